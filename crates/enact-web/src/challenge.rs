//! Hidden test sets split for a challenge, from the web: the admin API (split, settings,
//! reveal, status), the submitters' selections for the final ranking, the admin page
//! `/admin/challenges`, and what the leaderboard (JSON and page) shows of a challenge: which
//! part its figures are over, each row's submission count and standing, and the admins'
//! preview of the private part.

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{Html, IntoResponse, Redirect, Response};
use axum::routing::{get, post};
use schemars::JsonSchema;
use serde::Deserialize;

use super::AppState;
use super::auth::TokenCaller;
use super::error::{ApiError, PageError, RenderPage};
use super::extract::{Json, MOST_WHOLE_NUMBER, Path, Query};
use super::i18n::{Tr, msg};
use super::openapi::{ApiRoute, Verb};
use super::session::{Admin, Protected};
use crate::app::challenge::{
    self, BoardChallenge, ChallengeView, MAX_SELECTION_LIMIT, SelectionView, SettingsChange,
};
use crate::app::datasets;
use crate::app::leaderboard::Board;
use crate::app::refusal::{Expected, Refusal};
use crate::core::challenge::{Part, Standing};
use crate::core::credentials::Scope;
use crate::core::dataset::AnswerVisibility;
use crate::core::leaderboard::LeaderboardRow;

/// The challenge routes of the API (see [`super::openapi`]), in the order an admin and a
/// submitter use them: split, settings, selections, reveal.
pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Post,
            "/admin/datasets/{dataset}/challenge/split",
            split_api,
            "Split a hidden dataset into a public and a private part",
        )
        .describe(
            "Draws `share` of each stratum (direction × step length) of the dataset's items \
             into the public part, the rest into the private part, by a seeded shuffle: the \
             same items, share and seed always give the same split (the rule is documented \
             with `enact_core::challenge::draw_split`). A stratum of two or more items has at \
             least one item in each part. From then on the leaderboard's figures are over the \
             public part until the private part is revealed (at `reveal_at`, or by hand), and \
             submitters see their own scores over the public part only. Only a dataset whose \
             answers are hidden can be split (409 otherwise), and only once: a split is final \
             (409). Audited.",
        )
        .bearer(Scope::Admin)
        .body_json::<SplitRequest>(
            "`share` (above 0 and below 1) and an optional `seed` (0 when absent).",
            "{\"share\": 0.5, \"seed\": 7}",
        )
        .responds_json::<ChallengeView>(
            201,
            "The split: counts per part and stratum, and the public part's item ids.",
        )
        .errors(&[400, 401, 403, 404, 409, 415, 422]),
        ApiRoute::new(
            Verb::Get,
            "/admin/datasets/{dataset}/challenge",
            status_api,
            "A split dataset's challenge",
        )
        .describe(
            "The split (seed, share, counts per part and stratum, the public part's item ids), \
             the deadline, the reveal and the selection limit. 409 when the dataset is not \
             split.",
        )
        .bearer(Scope::Admin)
        .responds_json::<ChallengeView>(200, "The challenge.")
        .errors(&[401, 403, 404, 409]),
        ApiRoute::new(
            Verb::Patch,
            "/admin/datasets/{dataset}/challenge",
            settings_api,
            "Set a challenge's deadline and selection limit",
        )
        .describe(
            "`reveal_at`: when the private part is revealed by itself (RFC 3339, kept to the \
             second in UTC; `null` clears it). No timer is involved: the first leaderboard read \
             after it records the reveal (audited as the server), so a time in the past \
             reveals it at the next read. `selection_limit`: how many submissions an account \
             may select for the final ranking (1 to 1000; `null`: no limit). A field left out \
             stays as it is. Refused with 409 when the dataset is not split or its private \
             part was revealed (both are fixed then). Audited.",
        )
        .bearer(Scope::Admin)
        .body_json::<SettingsRequest>(
            "`reveal_at` and/or `selection_limit`, each nullable.",
            "{\"reveal_at\": \"2026-07-01T12:00:00Z\", \"selection_limit\": 2}",
        )
        .responds_json::<ChallengeView>(200, "The challenge as it now stands.")
        .errors(&[400, 401, 403, 404, 409, 415, 422]),
        ApiRoute::new(
            Verb::Get,
            "/datasets/{dataset}/selection",
            selection_api,
            "Your selections for a challenge's final ranking",
        )
        .describe(
            "The caller's account's published submissions selected for the split dataset's \
             final ranking, the selection limit, and `counted`: the submissions that make its \
             final rows now (those it selected, or its latest submission when it selected \
             none). 409 when the dataset is not split.",
        )
        .bearer(Scope::ReadOwn)
        .responds_json::<SelectionView>(200, "The account's selections.")
        .errors(&[401, 403, 404, 409]),
        ApiRoute::new(
            Verb::Put,
            "/submissions/{id}/selection",
            select_api,
            "Select a submission for the final ranking",
        )
        .describe(
            "After the reveal, the final ranking is over the private part and its rows are \
             the submissions each account selected (or its latest, when it selected none). \
             Only the submission's account (or an admin) selects it; only a published \
             submission of a split dataset, before the reveal, and no more than the dataset's \
             `selection_limit` per account (409 naming the limit and the ones selected). \
             Selecting a selected submission changes nothing. Audited.",
        )
        .bearer(Scope::Submit)
        .responds_json::<SelectionView>(200, "The account's selections now.")
        .errors(&[401, 403, 404, 409]),
        ApiRoute::new(
            Verb::Delete,
            "/submissions/{id}/selection",
            unselect_api,
            "Take a submission out of the final ranking",
        )
        .describe(
            "The inverse of selecting it, before the reveal; taking out one not selected \
             changes nothing. Audited.",
        )
        .bearer(Scope::Submit)
        .responds_json::<SelectionView>(200, "The account's selections now.")
        .errors(&[401, 403, 404, 409]),
        ApiRoute::new(
            Verb::Post,
            "/admin/datasets/{dataset}/challenge/reveal",
            reveal_api,
            "Reveal a challenge's private part now",
        )
        .describe(
            "The leaderboard's figures are over the private part from then on: its rows are \
             each account's selected submissions (or its latest), and each shows its rank over \
             the public part, over the private part, and the change. The final ranking, the \
             settings and the selections are fixed. 409 when the dataset is not split or was \
             revealed before. Audited.",
        )
        .bearer(Scope::Admin)
        .responds_json::<ChallengeView>(200, "The challenge, revealed.")
        .errors(&[401, 403, 404, 409]),
    ]
}

/// A split: the public part's share of each stratum, and the draw's seed.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct SplitRequest {
    /// The share of each stratum's items drawn into the public part: above 0 and below 1.
    #[schemars(extend("exclusiveMinimum" = 0, "exclusiveMaximum" = 1))]
    share: f64,
    /// The seed of the draw (0 when absent).
    #[serde(default, deserialize_with = "super::quality::whole_seed")]
    #[schemars(with = "Option<u64>", range(max = u64::MAX))]
    seed: Option<u64>,
}

/// A change of settings; a field left out stays as it is, `null` clears it.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct SettingsRequest {
    /// When the private part is revealed by itself: RFC 3339 (`2026-07-01T12:00:00Z`).
    #[serde(default, deserialize_with = "present")]
    #[schemars(
        with = "Option<String>",
        regex(pattern = r"^[0-9]{4}-[0-9]{2}-[0-9]{2}[Tt ][0-9]{2}:[0-9]{2}:[0-9]{2}(\.[0-9]+)?([Zz]|[+-][0-9]{2}:[0-9]{2})$"),
        extend("format" = "date-time")
    )]
    reveal_at: Option<Option<String>>,
    /// How many submissions an account may select for the final ranking.
    #[serde(default, deserialize_with = "present_whole_number")]
    #[schemars(with = "Option<i64>", range(min = 1, max = MAX_SELECTION_LIMIT))]
    selection_limit: Option<Option<i64>>,
}

/// A field that is present: `Some(None)` for `null`, so that a missing field (`None`, by
/// `default`) and a cleared one differ.
fn present<'de, D, T>(d: D) -> Result<Option<Option<T>>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    Option::<T>::deserialize(d).map(Some)
}

/// [`present`] for a whole number (`2` or `2.0`, both JSON Schema integers).
fn present_whole_number<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<Option<i64>>, D::Error> {
    let Some(number) = Option::<serde_json::Number>::deserialize(d)? else {
        return Ok(Some(None));
    };
    number
        .as_i64()
        .or_else(|| {
            number
                .as_f64()
                .filter(|f| f.fract() == 0.0 && f.abs() <= MOST_WHOLE_NUMBER as f64)
                .map(|f| f as i64)
        })
        .map(|n| Some(Some(n)))
        .ok_or_else(|| serde::de::Error::custom(format!("{number} is not a whole number")))
}

impl From<SettingsRequest> for SettingsChange {
    fn from(r: SettingsRequest) -> SettingsChange {
        SettingsChange {
            reveal_at: r.reveal_at,
            selection_limit: r.selection_limit,
        }
    }
}

async fn split_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    TokenCaller(caller): TokenCaller,
    Json(request): Json<SplitRequest>,
) -> Result<(StatusCode, Json<ChallengeView>), ApiError> {
    let view = challenge::split(
        &state.hub,
        &caller.actor(),
        &dataset,
        request.share,
        request.seed.unwrap_or(0),
    )
    .await?;
    Ok((StatusCode::CREATED, Json(view)))
}

async fn status_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
) -> Result<Json<ChallengeView>, ApiError> {
    Ok(Json(challenge::status(&state.hub, &dataset).await?))
}

async fn settings_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    TokenCaller(caller): TokenCaller,
    Json(request): Json<SettingsRequest>,
) -> Result<Json<ChallengeView>, ApiError> {
    let change = SettingsChange::from(request);
    Ok(Json(
        challenge::configure(&state.hub, &caller.actor(), &dataset, &change).await?,
    ))
}

async fn reveal_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    TokenCaller(caller): TokenCaller,
) -> Result<Json<ChallengeView>, ApiError> {
    Ok(Json(
        challenge::reveal(&state.hub, &caller.actor(), &dataset).await?,
    ))
}

async fn selection_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    TokenCaller(caller): TokenCaller,
) -> Result<Json<SelectionView>, ApiError> {
    Ok(Json(
        challenge::selection(&state.hub, &caller, &dataset).await?,
    ))
}

async fn select_api(
    State(state): State<AppState>,
    Path(id): Path<String>,
    TokenCaller(caller): TokenCaller,
) -> Result<Json<SelectionView>, ApiError> {
    Ok(Json(
        challenge::set_selected(&state.hub, &caller, &id, true).await?,
    ))
}

async fn unselect_api(
    State(state): State<AppState>,
    Path(id): Path<String>,
    TokenCaller(caller): TokenCaller,
) -> Result<Json<SelectionView>, ApiError> {
    Ok(Json(
        challenge::set_selected(&state.hub, &caller, &id, false).await?,
    ))
}

/// The leaderboard's `part` parameter.
pub(super) fn parse_part(value: &str) -> Result<Part, ApiError> {
    Part::parse(value)
        .ok_or_else(|| {
            Refusal::bad_value("part", value, Expected::OneOf(vec!["public", "private"]))
        })
        .map_err(ApiError::from)
}

/// The rows a leaderboard request for `part` (the default part when `None`) reads, and what
/// the board says of its challenge. A dataset that is not split has one part, all its items:
/// `part` changes nothing there. Before the reveal, the private part is for admins.
pub(super) fn board_rows(
    board: &Board,
    part: Option<Part>,
    admin: bool,
) -> Result<(&[LeaderboardRow], Option<BoardChallenge>), ApiError> {
    let Some(challenge) = &board.challenge else {
        return Ok((&board.rows, None));
    };
    let part = part.unwrap_or(challenge.shown.part);
    if part == Part::Private && challenge.shown.revealed_at.is_none() && !admin {
        return Err(ApiError(
            Refusal::PrivatePartHidden {
                dataset: board.dataset.name.clone(),
                reveal_at: challenge.shown.reveal_at.clone(),
            }
            .into(),
        ));
    }
    let rows = challenge.rows_over(part).unwrap_or(&board.rows);
    Ok((rows, Some(challenge.showing(part))))
}

/// What the leaderboard page says of a challenge, with a link to the other part's board
/// (when the reader may see it).
pub(super) struct ChallengeNote {
    pub text: String,
    pub other: Option<(String, String)>,
}

/// The page's note on the part shown; `other_href` is this page showing the other part.
pub(super) fn note(tr: &Tr, c: &BoardChallenge, admin: bool, other_href: String) -> ChallengeNote {
    let total = c.public_items + c.private_items;
    let revealed = c.revealed_at.as_deref();
    let parts = [
        ("public", c.public_items),
        ("private", c.private_items),
        ("total", total),
    ];
    let text = match (c.part, revealed) {
        (Part::Public, None) => match c.reveal_at.as_deref() {
            Some(at) => say(
                tr,
                msg("leaderboard-challenge-public"),
                &parts,
                &[("deadline", at)],
            ),
            None => say(
                tr,
                msg("leaderboard-challenge-public-no-deadline"),
                &parts,
                &[],
            ),
        },
        (Part::Public, Some(at)) => say(
            tr,
            msg("leaderboard-challenge-public-after"),
            &parts,
            &[("revealed", &tr.date(at))],
        ),
        (Part::Private, Some(at)) => say(
            tr,
            msg("leaderboard-challenge-private"),
            &parts,
            &[("revealed", &tr.date(at))],
        ),
        (Part::Private, None) => say(tr, msg("leaderboard-challenge-preview"), &parts, &[]),
    };
    let other = match (c.part, revealed.is_some()) {
        (Part::Public, false) if admin => Some(tr.t("leaderboard-challenge-show-preview")),
        (Part::Public, false) => None,
        (Part::Public, true) => Some(tr.t("leaderboard-challenge-show-final")),
        (Part::Private, _) => Some(tr.t("leaderboard-challenge-show-public")),
    };
    ChallengeNote {
        text,
        other: other.map(|label| (other_href, label)),
    }
}

/// `key` with counts (written as numbers, so its text says "N of M" rather than choosing a
/// plural form) and texts.
fn say(tr: &Tr, key: &str, counts: &[(&str, usize)], texts: &[(&str, &str)]) -> String {
    let counts: Vec<(&str, String)> = counts.iter().map(|(k, n)| (*k, n.to_string())).collect();
    let mut vars: Vec<(&str, &str)> = counts.iter().map(|(k, v)| (*k, v.as_str())).collect();
    vars.extend_from_slice(texts);
    tr.t_args(key, &vars)
}

/// A row's submission count, as the page prints it beside the account.
pub(super) fn submissions_text(tr: &Tr, row: &LeaderboardRow) -> Option<String> {
    row.account_submissions
        .map(|n| tr.t_n("leaderboard-account-submissions", "count", n))
}

/// A final row's ranks over each part and the change, as the page prints it.
pub(super) fn standing_text(tr: &Tr, standing: Option<&Standing>) -> Option<String> {
    let s = standing?;
    let rank = |r: Option<usize>| r.map_or_else(|| "–".to_owned(), |r| r.to_string());
    let change = match s.rank_change {
        None => String::new(),
        Some(0) => tr.t("leaderboard-rank-same"),
        Some(up) if up > 0 => tr.t_n("leaderboard-rank-up", "places", up),
        Some(down) => tr.t_n("leaderboard-rank-down", "places", -down),
    };
    Some(tr.t_args(
        "leaderboard-standing",
        &[
            ("public", &rank(s.public_rank)),
            ("private", &rank(s.private_rank)),
            ("change", &change),
        ],
    ))
}

/// The admin page's routes (behind the admin gate, see [`super::admin_pages`]).
pub fn admin_router() -> Router<AppState> {
    Router::new()
        .route("/admin/challenges", get(challenges_page))
        .route("/admin/challenges/split", post(split_form))
        .route("/admin/challenges/settings", post(settings_form))
        .route("/admin/challenges/reveal", post(reveal_form))
}

struct DatasetLine {
    name: String,
    answers: &'static str,
    state: String,
}

#[derive(Template)]
#[template(path = "admin_challenges.html")]
struct ChallengesPage {
    name: String,
    csrf: String,
    datasets: Vec<DatasetLine>,
    /// The dataset shown in detail ("" for none).
    dataset: String,
    hidden: bool,
    challenge: Option<ChallengeView>,
    max_limit: i64,
}

#[derive(Debug, Default, Deserialize)]
struct PageQuery {
    #[serde(default)]
    dataset: String,
}

async fn challenges_page(
    State(state): State<AppState>,
    Admin(session): Admin,
    Query(query): Query<PageQuery>,
) -> Result<Html<String>, PageError> {
    let mut lines = Vec::new();
    let mut detail = None;
    for o in datasets::overview(&state.hub).await? {
        let answers = datasets::answer_visibility(&state.hub, &o.dataset).await?;
        let challenge = challenge::find(&state.hub, &o.dataset.name).await?;
        let state_text = match &challenge {
            None => "not split".to_owned(),
            Some(c) => match (&c.revealed_at, &c.reveal_at) {
                (Some(at), _) => format!("revealed at {at}"),
                (None, Some(at)) => format!("split; reveals at {at}"),
                (None, None) => "split; no deadline".to_owned(),
            },
        };
        if o.dataset.name == query.dataset {
            detail = Some((answers == AnswerVisibility::Hidden, challenge));
        }
        lines.push(DatasetLine {
            name: o.dataset.name,
            answers: answers.as_str(),
            state: state_text,
        });
    }
    let (hidden, challenge, dataset) = match detail {
        Some((hidden, challenge)) => (hidden, challenge, query.dataset),
        None => (false, None, String::new()),
    };
    let page = ChallengesPage {
        name: session.name,
        csrf: session.csrf_token,
        datasets: lines,
        dataset,
        hidden,
        challenge,
        max_limit: MAX_SELECTION_LIMIT,
    };
    Ok(Html(page.render_page()?))
}

/// Back to the page of `dataset` (a reload does not send the form again).
fn back_to(dataset: &str) -> Response {
    let query = serde_urlencoded::to_string([("dataset", dataset)]).unwrap_or_default();
    Redirect::to(&format!("/admin/challenges?{query}")).into_response()
}

fn form_dataset(dataset: &str) -> Result<&str, ApiError> {
    let dataset = dataset.trim();
    if dataset.is_empty() {
        return Err(Refusal::FieldsRequired {
            fields: vec!["dataset"],
        }
        .into());
    }
    Ok(dataset)
}

#[derive(Deserialize)]
struct SplitForm {
    #[serde(default)]
    dataset: String,
    #[serde(default)]
    share: String,
    #[serde(default)]
    seed: String,
}

async fn split_form(
    State(state): State<AppState>,
    request: Protected<SplitForm>,
) -> Result<Response, PageError> {
    let form = request.body;
    let dataset = form_dataset(&form.dataset)?;
    let share = form
        .share
        .trim()
        .parse::<f64>()
        .map_err(|_| Refusal::bad_value("share", form.share.trim(), Expected::Fraction))?;
    let seed = match form.seed.trim() {
        "" => 0,
        text => text.parse::<u64>().map_err(|_| {
            Refusal::bad_value("seed", text, Expected::WholeNumberFrom { least: 0 })
        })?,
    };
    challenge::split(&state.hub, &request.session.actor(), dataset, share, seed).await?;
    Ok(back_to(dataset))
}

#[derive(Deserialize)]
struct SettingsForm {
    #[serde(default)]
    dataset: String,
    #[serde(default)]
    reveal_at: String,
    #[serde(default)]
    selection_limit: String,
}

async fn settings_form(
    State(state): State<AppState>,
    request: Protected<SettingsForm>,
) -> Result<Response, PageError> {
    let form = request.body;
    let dataset = form_dataset(&form.dataset)?;
    // The form shows both as they are: an empty field clears it.
    let reveal_at = Some(form.reveal_at.trim())
        .filter(|t| !t.is_empty())
        .map(str::to_owned);
    let selection_limit = match form.selection_limit.trim() {
        "" => None,
        text => Some(text.parse::<i64>().map_err(|_| {
            Refusal::bad_value(
                "selection_limit",
                text,
                Expected::WholeNumber {
                    least: 1,
                    most: MAX_SELECTION_LIMIT as u64,
                },
            )
        })?),
    };
    let change = SettingsChange {
        reveal_at: Some(reveal_at),
        selection_limit: Some(selection_limit),
    };
    challenge::configure(&state.hub, &request.session.actor(), dataset, &change).await?;
    Ok(back_to(dataset))
}

#[derive(Deserialize)]
struct DatasetForm {
    #[serde(default)]
    dataset: String,
}

async fn reveal_form(
    State(state): State<AppState>,
    request: Protected<DatasetForm>,
) -> Result<Response, PageError> {
    let dataset = form_dataset(&request.body.dataset)?;
    challenge::reveal(&state.hub, &request.session.actor(), dataset).await?;
    Ok(back_to(dataset))
}
