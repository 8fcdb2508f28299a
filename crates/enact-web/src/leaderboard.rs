//! The leaderboard as JSON (`/api/v1/datasets/{dataset}/leaderboard`) and as a page with its
//! chart (`/leaderboard/{dataset}`): one row per account and model (or every submission),
//! ranked with ties, sorted by any column and paged, from the board kept in memory.

use schemars::JsonSchema;
use serde_json::json;
use std::hash::{Hash, Hasher};

use askama::Template;
use axum::Router;
use axum::body::Bytes;
use axum::extract::{RawQuery, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use serde::Serialize;

use super::api::matches_etag;
use super::error::{ApiError, PageError, RenderPage};
use super::extract::{Path, whole_number_between};
use super::i18n::{Tr, msg};
use super::openapi::{ApiRoute, Verb};
use super::session::ReaderIsAdmin;
use super::{AppError, AppState};
use crate::app::challenge::BoardChallenge;
use crate::app::leaderboard::{self, Board};
use crate::app::models::ModelMetadata;
use crate::app::refusal::{Expected, Refusal};
use crate::app::reported::ReportedResult;
use crate::core::challenge::Part;
use crate::core::dataset::{Direction, StepLength};
use crate::core::leaderboard::{
    AccuracyCell, AccuracyChart, BoardPage, BoardQuery, ColumnGroup, Interval, LeaderboardRow,
    MIN_HUMAN_ANSWERS, RowSource, SortKey, board_page, chart_rows,
};
use crate::core::metric::METRIC_VERSION;
use crate::core::paper::{CellKey, Metric};
use crate::core::submission::Provenance;
use crate::core::verifier::Resampling;

/// Rows a page may ask for at once.
const MAX_PER_PAGE: usize = 1000;

pub fn api_routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Get,
            "/datasets/{dataset}/leaderboard",
            leaderboard_json,
            "The leaderboard",
        )
        .describe(
            "One row per account and model (its latest published submission, with `attempts` \
             and a `history` link), ranked by `sort` (overall TA by default): rows whose value \
             is equal as shown (a percentage to one decimal) share a rank, and the next rank \
             skips. TA and PA overall, forward, inverse and per step length 3..10, 95% \
             bootstrap intervals (resampling activities, ENACT's `task_name`, with their items \
             unless `resample=items`; each row's `interval_resampling` says which), coverage \
             and date. The Human row (when annotations exist) \
             and baselines are on every page, unranked. Strong `ETag`; `If-None-Match` gives \
             304. The HTML page is /leaderboard/{dataset}.",
        )
        .query_with(
            "sort",
            false,
            json!({"type": "string", "pattern": "^(overall_(ta|pa)|(forward|inverse)_(ta|pa)(_([3-9]|10))?)?$"}),
            "overall_ta (default), overall_pa, forward_ta, forward_pa, inverse_ta, inverse_pa, \
             or a step length: forward_ta_5, inverse_pa_10, ….",
        )
        .query_with(
            "resample",
            false,
            json!({"type": "string", "enum": ["activities", "items", ""]}),
            "What the intervals' bootstrap resamples: `activities` (the default) or `items`.",
        )
        .query_with(
            "page",
            false,
            // An empty value is the default, as the page's own filter form sends it.
            json!({"anyOf": [{"type": "integer", "minimum": 1, "maximum": 1_000_000}, {"const": ""}]}),
            "1-based page of ranked rows (default 1).",
        )
        .query_with(
            "per_page",
            false,
            json!({"anyOf": [{"type": "integer", "minimum": 1, "maximum": MAX_PER_PAGE}, {"const": ""}]}),
            "Ranked rows per page, 1 to 1000 (default 50).",
        )
        .query_with(
            "all",
            false,
            json!({"enum": ["", "0", "1", "false", "true"]}),
            "`1` lists every published submission instead of one row per account and model.",
        )
        .query("model", false, "Only this model (exact name).")
        .query("account", false, "Only this account (exact name).")
        .query_with(
            "provenance",
            false,
            json!({"enum": ["", "run", "submitted", "reported"]}),
            "Only rows whose answers came this way: `run` (this hub asked the model), \
             `submitted` (uploaded) or `reported` (a paper's published numbers; shows them).",
        )
        .query_with(
            "reported",
            false,
            json!({"enum": ["", "0", "1", "false", "true"]}),
            "`1` adds `reported`: the results papers published for the dataset (values in \
             percent as printed), never ranked against the hub's rows.",
        )
        .query_with(
            "part",
            false,
            json!({"enum": ["", "public", "private"]}),
            "On a dataset split for a challenge (`challenge` says so): whose items the figures \
             are over. By default the public part until the reveal, then the private part, \
             whose rows are each account's selected submissions (or its latest) with their \
             `standing`: rank over each part and the change. Before the reveal `private` (the \
             final ranking as a reveal now would make it) is for admins: 403 otherwise. \
             Ignored on a dataset that is not split. Every row's `account_submissions` counts \
             its account's submissions to the dataset, listed or not.",
        )
        .responds_json::<LeaderboardView<'static>>(
            200,
            "The page of rows, with `next` and `prev` links.",
        )
        .responds(
            304,
            None,
            "Unchanged since the `ETag` sent in `If-None-Match`.",
        )
        .errors(&[400, 403, 404, 503]),
    ]
}

pub fn page_router() -> Router<AppState> {
    Router::new().route("/leaderboard/{dataset}", get(leaderboard_page))
}

/// A board request as typed in a URL.
struct BoardRequest {
    query: BoardQuery,
    /// Show the results papers published beside the hub's rows.
    reported: bool,
    /// Submission ids the reader picked for the chart.
    chart: Option<Vec<i64>>,
    /// On a split dataset, the part whose figures to show (`super::challenge`).
    part: Option<Part>,
}

impl BoardRequest {
    fn parse(raw: Option<&str>) -> Result<BoardRequest, ApiError> {
        let pairs: Vec<(String, String)> = serde_urlencoded::from_str(raw.unwrap_or(""))
            .map_err(|e| AppError::Invalid(format!("query string: {e}")))?;
        let mut query = BoardQuery::default();
        let mut chart: Option<Vec<i64>> = None;
        let mut reported = false;
        let mut part = None;
        let number = |name: &str, text: &str, max: usize| {
            whole_number_between(name, text, 1, max as u64).map(|n| n as usize)
        };
        let switch = |name: &str, value: &str| match value {
            "1" | "true" => Ok(true),
            "0" | "false" => Ok(false),
            other => Err(AppError::from(Refusal::bad_value(
                name,
                other,
                Expected::OneOf(vec!["1", "0"]),
            ))),
        };
        for (key, value) in &pairs {
            let value = value.trim();
            match key.as_str() {
                _ if value.is_empty() => {}
                "sort" => query.sort = SortKey::parse(value).map_err(AppError::Invalid)?,
                "page" => query.page = number("page", value, 1_000_000)?,
                "per_page" => query.per_page = number("per_page", value, MAX_PER_PAGE)?,
                "all" => query.every_submission = switch("all", value)?,
                "resample" => query.intervals = super::compare::resample_param(Some(value))?,
                "reported" => reported = switch("reported", value)?,
                "part" => part = Some(super::challenge::parse_part(value)?),
                "model" => query.model = Some(value.to_owned()),
                "account" => query.account = Some(value.to_owned()),
                "provenance" => {
                    let p = Provenance::parse(value).ok_or_else(|| {
                        Refusal::bad_value(
                            "provenance",
                            value,
                            Expected::OneOf(vec!["run", "submitted", "reported"]),
                        )
                    })?;
                    // A paper's numbers are the reported rows: asking for them shows them.
                    reported |= p == Provenance::Reported;
                    query.provenance = Some(p);
                }
                "chart" => {
                    for part in value.split(',').filter(|p| !p.trim().is_empty()) {
                        let id = part.trim().parse().map_err(|_| {
                            Refusal::bad_value("chart", part.trim(), Expected::SubmissionId)
                        })?;
                        chart.get_or_insert_with(Vec::new).push(id);
                    }
                }
                // Unknown parameters are ignored, as links from elsewhere may carry some.
                _ => {}
            }
        }
        Ok(BoardRequest {
            query,
            reported,
            chart,
            part,
        })
    }

    /// The query string of this request with `page` and other changes applied by `edit`.
    fn link(&self, dataset_path: &str, edit: impl FnOnce(&mut BoardQuery)) -> String {
        let mut q = self.query.clone();
        edit(&mut q);
        format!("{dataset_path}?{}", self.query_string(&q, self.reported))
    }

    /// `q` as a query string, with the reported rows' switch and the part asked for.
    fn query_string(&self, q: &BoardQuery, reported: bool) -> String {
        let mut text = query_string(q);
        if reported {
            text.push_str("&reported=1");
        }
        if let Some(part) = self.part {
            text.push_str("&part=");
            text.push_str(part.as_str());
        }
        text
    }

    /// What this request asks for in `kind` (json or page), normalized: the key of its
    /// rendered view.
    fn key(&self, kind: &str) -> String {
        format!(
            "{kind}?{}&chart={:?}",
            self.query_string(&self.query, self.reported),
            self.chart
        )
    }

    /// An entity tag for this request's answer from `board`: it changes when the board is
    /// rebuilt or the request asks for something else.
    fn etag(&self, board: &Board, kind: &str) -> String {
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        self.key(kind).hash(&mut hasher);
        format!("\"lb{}-{:016x}\"", board.version, hasher.finish())
    }

    /// The view of `board` this request asks for in `kind`, rendered by `render` the first
    /// time and kept with the board after that.
    fn view(
        &self,
        board: &Board,
        kind: &str,
        render: impl FnOnce() -> Result<Vec<u8>, ApiError>,
    ) -> Result<Bytes, ApiError> {
        let key = self.key(kind);
        if let Some(view) = board.view(&key) {
            return Ok(view);
        }
        let view = Bytes::from(render()?);
        board.keep_view(key, view.clone());
        Ok(view)
    }
}

/// A query string that reads back as `q`.
fn query_string(q: &BoardQuery) -> String {
    let mut pairs: Vec<(&str, String)> = vec![("sort", q.sort.name())];
    if q.every_submission {
        pairs.push(("all", "1".to_owned()));
    }
    if q.intervals != Resampling::default() {
        pairs.push(("resample", q.intervals.as_str().to_owned()));
    }
    if let Some(m) = &q.model {
        pairs.push(("model", m.clone()));
    }
    if let Some(a) = &q.account {
        pairs.push(("account", a.clone()));
    }
    if let Some(p) = q.provenance {
        pairs.push(("provenance", p.as_str().to_owned()));
    }
    pairs.push(("page", q.page.to_string()));
    pairs.push(("per_page", q.per_page.to_string()));
    serde_urlencoded::to_string(pairs).unwrap_or_default()
}

/// The link to every published submission of a row's account and model.
fn history(base: &str, row: &LeaderboardRow) -> Option<String> {
    (row.source == RowSource::Submission).then(|| {
        let q = BoardQuery {
            every_submission: true,
            model: Some(row.model.clone()),
            account: Some(row.account.clone()),
            ..BoardQuery::default()
        };
        format!("{base}?{}", query_string(&q))
    })
}

/// 304 when the client holds `etag`, else `response` with it; boards are revalidated, never
/// served stale from a cache.
fn with_etag(headers: &HeaderMap, etag: &str, response: impl IntoResponse) -> Response {
    let mut response = if matches_etag(headers, etag) {
        StatusCode::NOT_MODIFIED.into_response()
    } else {
        response.into_response()
    };
    let h = response.headers_mut();
    if let Ok(v) = HeaderValue::from_str(etag) {
        h.insert(header::ETAG, v);
    }
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-cache"));
    response
}

#[derive(Serialize, JsonSchema)]
struct RowView {
    #[serde(flatten)]
    row: LeaderboardRow,
    /// Every published submission of this account and model.
    history: Option<String>,
    /// The model's category, family, size and link on this dataset, when set.
    #[serde(skip_serializing_if = "Option::is_none")]
    metadata: Option<ModelMetadata>,
}

#[derive(Serialize, JsonSchema)]
struct LeaderboardView<'a> {
    dataset: &'a str,
    policy: &'static str,
    /// The metric version this server computes with; a row whose `metric_version` is older is
    /// `outdated` until an admin rescores it.
    metric_version: u32,
    sort: String,
    every_submission: bool,
    page: usize,
    per_page: usize,
    pages: usize,
    /// Ranked rows matching the filters, on all pages.
    entries: usize,
    step_lengths: Vec<u8>,
    rows: Vec<RowView>,
    /// With `reported=1`: the results papers published for the dataset (values in percent as
    /// printed), never ranked against `rows` (a paper's numbers, no interval, no per-item data).
    #[serde(skip_serializing_if = "Option::is_none")]
    reported: Option<&'a [ReportedResult]>,
    /// On a dataset split for a challenge: the part the rows' figures are over, the parts'
    /// sizes, the deadline and the reveal.
    #[serde(skip_serializing_if = "Option::is_none")]
    challenge: Option<BoardChallenge>,
    next: Option<String>,
    prev: Option<String>,
}

/// The links to the pages before and after this one.
fn neighbours(
    request: &BoardRequest,
    path: &str,
    page: &BoardPage,
) -> (Option<String>, Option<String>) {
    let current = request.query.page;
    let prev = (current > 1).then(|| request.link(path, |q| q.page = current - 1));
    let next = (current < page.pages).then(|| request.link(path, |q| q.page = current + 1));
    (prev, next)
}

async fn leaderboard_json(
    State(state): State<AppState>,
    Path(name): Path<String>,
    RawQuery(raw): RawQuery,
    headers: HeaderMap,
    ReaderIsAdmin(admin): ReaderIsAdmin,
) -> Result<Response, ApiError> {
    let request = BoardRequest::parse(raw.as_deref())?;
    let board = leaderboard::board(&state.hub, &name).await?;
    // Refused before anything is served, a kept view or a 304 included.
    let (rows, challenge) = super::challenge::board_rows(&board, request.part, admin)?;
    let etag = request.etag(&board, "json");
    if matches_etag(&headers, &etag) {
        return Ok(with_etag(&headers, &etag, ()));
    }
    let json = request.view(&board, "json", || {
        Ok(serde_json::to_vec(&leaderboard_view(
            &board, rows, challenge, &request,
        ))?)
    })?;
    let body = ([(header::CONTENT_TYPE, "application/json")], json);
    Ok(with_etag(&headers, &etag, body))
}

/// The JSON of the page `request` asks for, cut from `rows` (the part asked for).
fn leaderboard_view<'a>(
    board: &'a Board,
    rows: &[LeaderboardRow],
    challenge: Option<BoardChallenge>,
    request: &BoardRequest,
) -> LeaderboardView<'a> {
    let path = format!("/api/v1/datasets/{}/leaderboard", board.dataset.name);
    let page = board_page(rows, &request.query);
    let (prev, next) = neighbours(request, &path, &page);
    LeaderboardView {
        dataset: &board.dataset.name,
        policy: "strict",
        metric_version: METRIC_VERSION,
        sort: request.query.sort.name(),
        every_submission: request.query.every_submission,
        page: request.query.page,
        per_page: request.query.per_page,
        pages: page.pages,
        entries: page.matching,
        step_lengths: StepLength::all().map(StepLength::get).collect(),
        rows: page
            .rows
            .into_iter()
            .map(|row| RowView {
                history: history(&path, &row),
                metadata: (row.source == RowSource::Submission)
                    .then(|| board.metadata.get(&row.model).cloned())
                    .flatten(),
                row,
            })
            .collect(),
        reported: request.reported.then_some(board.reported.as_slice()),
        challenge,
        next,
        prev,
    }
}

/// One TA/PA pair as the table prints it.
struct CellText {
    ta: String,
    pa: String,
    /// Set on a Human cell resting on too few answers: what it rests on.
    few: Option<String>,
}

/// A cell's text; Human cells with fewer than [`MIN_HUMAN_ANSWERS`] answers are marked.
fn cell_text(tr: &Tr, c: &AccuracyCell, human: bool) -> CellText {
    let few = (human && c.count > 0 && c.count < MIN_HUMAN_ANSWERS).then(|| {
        tr.t_nn(
            "leaderboard-few-answers",
            "count",
            c.count,
            "minimum",
            MIN_HUMAN_ANSWERS,
        )
    });
    CellText {
        few,
        ta: tr.percent_figure(c.task_accuracy),
        pa: tr.percent_figure(c.pairwise_accuracy),
    }
}

fn interval_text(tr: &Tr, i: Option<Interval>) -> String {
    i.map_or_else(String::new, |i| {
        format!(
            "{}–{}",
            tr.percent_figure(Some(i.low)),
            tr.percent_figure(Some(i.high))
        )
    })
}

/// A sort column as the page names it: "overall TA", "forward PA at L=5".
fn sort_label(tr: &Tr, key: &SortKey) -> String {
    let group = tr.t(match key.group {
        ColumnGroup::Overall => msg("leaderboard-group-overall"),
        ColumnGroup::Forward => msg("leaderboard-group-forward"),
        ColumnGroup::Inverse => msg("leaderboard-group-inverse"),
    });
    let metric = if key.pairwise { "PA" } else { "TA" };
    match key.step {
        None => tr.t_args("leaderboard-sort", &[("group", &group), ("metric", metric)]),
        Some(l) => tr.t_args(
            "leaderboard-sort-step",
            &[
                ("group", &group),
                ("metric", metric),
                ("step", &l.to_string()),
            ],
        ),
    }
}

struct RowText {
    /// The rank, or a dash for reference rows.
    rank: String,
    model: String,
    account: String,
    baseline: bool,
    human: bool,
    attempts: usize,
    history: Option<String>,
    /// The submission id, for the chart's checkbox.
    submission: Option<i64>,
    drawn: bool,
    submitted_on: String,
    overall: CellText,
    ta_ci: String,
    pa_ci: String,
    /// The intervals resample something other than the page says (scores stored before the
    /// hub clustered its intervals resample items).
    ci_differs: bool,
    forward: CellText,
    inverse: CellText,
    forward_steps: Vec<CellText>,
    inverse_steps: Vec<CellText>,
    coverage: String,
    parse_failures: String,
    /// The Human row: answers, items and annotators it rests on.
    human_note: Option<String>,
    /// Set when the row was computed with an older metric version: which, and what to do.
    outdated: Option<String>,
    /// A reported row (a paper's published numbers): where they were published.
    reported: Option<String>,
    /// A hub row's provenance badge: `run` (with the link to the run's stamp) or `submitted`.
    provenance: Option<ProvenanceBadge>,
    /// How many submissions the row's account made to the dataset, listed or not.
    account_submissions: Option<String>,
    /// A challenge's final row: its rank over each part and the change.
    standing: Option<String>,
    /// The model's category, family and size, as the hub's metadata or the paper gives them.
    about: Option<String>,
    /// The model's link, from its metadata.
    link: Option<String>,
}

/// A submission row's provenance as the page shows it.
struct ProvenanceBadge {
    label: String,
    /// What the badge means, for its title and screen readers.
    meaning: String,
    /// A run's stamp (endpoint host, model, parameters, prompt version and hash).
    stamp: Option<String>,
}

fn provenance_badge(tr: &Tr, r: &LeaderboardRow) -> Option<ProvenanceBadge> {
    let badge = match r.provenance? {
        Provenance::Run => ProvenanceBadge {
            label: tr.t("leaderboard-provenance-run"),
            meaning: tr.t("leaderboard-provenance-run-meaning"),
            stamp: r.run.map(|run| format!("/api/v1/runs/{run}/stamp")),
        },
        Provenance::Submitted => ProvenanceBadge {
            label: tr.t("leaderboard-provenance-submitted"),
            meaning: tr.t("leaderboard-provenance-submitted-meaning"),
            stamp: None,
        },
        Provenance::Reported => return None,
    };
    Some(badge)
}

/// A column header that sorts the board by its column.
struct SortLink {
    href: String,
    active: bool,
}

/// The TA and PA sort links of one group of columns.
struct SortPair {
    ta: SortLink,
    pa: SortLink,
}

#[derive(Template)]
#[template(path = "leaderboard.html")]
struct LeaderboardPage {
    tr: Tr,
    dataset: String,
    metric_version: u32,
    step_lengths: Vec<u8>,
    rows: Vec<RowText>,
    chart: AccuracyChart,
    picked: bool,
    sort_label: String,
    overall: SortPair,
    forward: SortPair,
    inverse: SortPair,
    forward_steps: Vec<SortPair>,
    inverse_steps: Vec<SortPair>,
    every_submission: bool,
    toggle: String,
    /// The reported rows (when shown), after the hub's rows.
    reported_rows: Vec<RowText>,
    /// How many reported rows the dataset has, shown or not.
    reported_count: usize,
    show_reported: bool,
    /// The page with the reported rows shown if hidden, hidden if shown.
    reported_toggle: String,
    filter: Option<String>,
    unfiltered: String,
    page: usize,
    pages: usize,
    entries: usize,
    prev: Option<String>,
    next: Option<String>,
    /// The request's parameters but the chart's, for the chart form.
    hidden: Vec<(String, String)>,
    /// What the intervals resample, in words, and the page resampling the other way.
    resampling: String,
    resampling_toggle: String,
    resampling_items: bool,
    /// Some row's intervals resample items where the page's resample activities.
    any_ci_differs: bool,
    /// Links narrowing the board to one provenance, and back to every row.
    provenance_links: Vec<FilterLink>,
    /// On a split dataset: which part the figures are over, and the other part's board.
    challenge: Option<super::challenge::ChallengeNote>,
}

/// A link that narrows a board, marked when it is the board shown.
struct FilterLink {
    label: String,
    href: String,
    active: bool,
}

impl LeaderboardPage {
    /// The page of `rows` (the part asked for, see `super::challenge::board_rows`).
    fn new(
        tr: Tr,
        board: &Board,
        (rows, challenge): (&[LeaderboardRow], Option<BoardChallenge>),
        admin: bool,
        request: &BoardRequest,
    ) -> LeaderboardPage {
        let name = &board.dataset.name;
        let path = format!("/leaderboard/{name}");
        let query = &request.query;
        let page = board_page(rows, query);
        let drawn = chart_rows(rows, query, request.chart.as_deref());
        let drawn_ids: Vec<i64> = drawn.iter().filter_map(|r| r.submission).collect();
        let sort = |key: SortKey| SortLink {
            href: request.link(&path, |q| {
                q.sort = key;
                q.page = 1;
            }),
            active: key == query.sort,
        };
        let pair = |group: ColumnGroup, step: Option<StepLength>| SortPair {
            ta: sort(SortKey {
                group,
                step,
                pairwise: false,
            }),
            pa: sort(SortKey {
                group,
                step,
                pairwise: true,
            }),
        };
        let steps = |group| StepLength::all().map(|l| pair(group, Some(l))).collect();
        let (prev, next) = neighbours(request, &path, &page);
        let filter = match (&query.model, &query.account) {
            (None, None) => None,
            (Some(m), None) => Some(tr.t_s("leaderboard-only-model", "model", m)),
            (None, Some(a)) => Some(tr.t_s("leaderboard-only-account", "account", a)),
            (Some(m), Some(a)) => Some(tr.t_args(
                "leaderboard-only-model-of-account",
                &[("model", m), ("account", a)],
            )),
        };
        LeaderboardPage {
            dataset: name.clone(),
            metric_version: METRIC_VERSION,
            step_lengths: StepLength::all().map(StepLength::get).collect(),
            rows: page
                .rows
                .iter()
                .map(|r| {
                    let mut text = row_text(&tr, r, history(&path, r), &drawn_ids, query.intervals);
                    if let Some(m) = (r.source == RowSource::Submission)
                        .then(|| board.metadata.get(&r.model))
                        .flatten()
                    {
                        text.about = about(
                            m.category.as_deref(),
                            m.family.as_deref(),
                            m.size.as_deref(),
                        );
                        text.link.clone_from(&m.link);
                    }
                    text
                })
                .collect(),
            reported_rows: if request.reported {
                board
                    .reported
                    .iter()
                    .map(|r| reported_text(&tr, r))
                    .collect()
            } else {
                Vec::new()
            },
            reported_count: board.reported.len(),
            show_reported: request.reported,
            reported_toggle: format!("{path}?{}", request.query_string(query, !request.reported)),
            chart: AccuracyChart::task_accuracy_by_step_length(&drawn),
            picked: request.chart.is_some(),
            sort_label: sort_label(&tr, &query.sort),
            overall: pair(ColumnGroup::Overall, None),
            forward: pair(ColumnGroup::Forward, None),
            inverse: pair(ColumnGroup::Inverse, None),
            forward_steps: steps(ColumnGroup::Forward),
            inverse_steps: steps(ColumnGroup::Inverse),
            every_submission: query.every_submission,
            toggle: request.link(&path, |q| {
                q.every_submission = !q.every_submission;
                q.page = 1;
            }),
            filter,
            unfiltered: request.link(&path, |q| {
                q.model = None;
                q.account = None;
                q.page = 1;
            }),
            page: query.page,
            pages: page.pages,
            entries: page.matching,
            prev,
            next,
            hidden: serde_urlencoded::from_str(&request.query_string(query, request.reported))
                .unwrap_or_default(),
            resampling: super::compare::resampling_text(&tr, query.intervals),
            resampling_toggle: request.link(&path, |q| {
                q.intervals = match q.intervals {
                    Resampling::Activities => Resampling::Items,
                    Resampling::Items => Resampling::Activities,
                };
            }),
            resampling_items: query.intervals == Resampling::Items,
            any_ci_differs: page.rows.iter().any(|r| {
                r.interval_resampling
                    .is_some_and(|stored| stored != query.intervals)
            }),
            provenance_links: provenance_links(&tr, request, &path),
            challenge: challenge.map(|c| {
                let other = match c.part {
                    Part::Public => Part::Private,
                    Part::Private => Part::Public,
                };
                let mut q = query.clone();
                q.page = 1;
                let href = format!("{path}?{}&part={}", query_string(&q), other.as_str());
                super::challenge::note(&tr, &c, admin, href)
            }),
            tr,
        }
    }
}

/// One link per provenance, and one to rows of any provenance.
fn provenance_links(tr: &Tr, request: &BoardRequest, path: &str) -> Vec<FilterLink> {
    let link = |label: String, provenance: Option<Provenance>| {
        let mut href = request.link(path, |q| {
            q.provenance = provenance;
            q.page = 1;
        });
        if provenance == Some(Provenance::Reported) && !request.reported {
            href.push_str("&reported=1");
        }
        FilterLink {
            label,
            href,
            active: request.query.provenance == provenance,
        }
    };
    vec![
        link(tr.t("leaderboard-provenance-run"), Some(Provenance::Run)),
        link(
            tr.t("leaderboard-provenance-submitted"),
            Some(Provenance::Submitted),
        ),
        link(
            tr.t("leaderboard-reported-badge"),
            Some(Provenance::Reported),
        ),
        link(tr.t("leaderboard-provenance-all"), None),
    ]
}

/// `resampling`: what the page's intervals resample.
fn row_text(
    tr: &Tr,
    r: &LeaderboardRow,
    history: Option<String>,
    drawn: &[i64],
    resampling: Resampling,
) -> RowText {
    let human = r.source == RowSource::Human;
    RowText {
        human_note: r.human.map(|h| {
            let mut note = format!(
                "{}, {}, {}",
                tr.t_nn(
                    "leaderboard-human-items",
                    "items",
                    h.items,
                    "total",
                    h.dataset_items
                ),
                tr.t_n("leaderboard-human-annotators", "count", h.annotators),
                tr.t_n("leaderboard-human-answers", "count", h.answers),
            );
            if h.gold_items > 0 {
                note.push_str(&tr.t_n("leaderboard-human-gold", "count", h.gold_items));
            }
            if h.excluded_annotators > 0 {
                note.push_str(&tr.t_n(
                    "leaderboard-human-excluded",
                    "count",
                    h.excluded_annotators,
                ));
            }
            note.push_str(&tr.t("leaderboard-human-unranked"));
            note
        }),
        rank: r.rank.map_or_else(|| "–".to_owned(), |k| k.to_string()),
        model: r.model.clone(),
        account: r.account.clone(),
        baseline: r.baseline,
        human,
        attempts: r.attempts,
        history,
        submission: r.submission,
        drawn: r.submission.is_some_and(|id| drawn.contains(&id)),
        submitted_on: tr.date(&r.submitted_at),
        overall: cell_text(tr, &r.overall, human),
        ta_ci: interval_text(tr, r.overall_task_accuracy_ci),
        pa_ci: interval_text(tr, r.overall_pairwise_accuracy_ci),
        ci_differs: r
            .interval_resampling
            .is_some_and(|stored| stored != resampling),
        forward: cell_text(tr, &r.forward.total, human),
        inverse: cell_text(tr, &r.inverse.total, human),
        forward_steps: r
            .forward
            .per_step
            .iter()
            .map(|(_, c)| cell_text(tr, c, human))
            .collect(),
        inverse_steps: r
            .inverse
            .per_step
            .iter()
            .map(|(_, c)| cell_text(tr, c, human))
            .collect(),
        coverage: tr.percent(r.coverage),
        parse_failures: tr.percent(r.parse_failure_rate),
        outdated: r.metric.outdated.then(|| {
            tr.t_nn(
                "leaderboard-outdated",
                "version",
                r.metric.metric_version,
                "current",
                METRIC_VERSION,
            )
        }),
        reported: None,
        provenance: provenance_badge(tr, r),
        account_submissions: super::challenge::submissions_text(tr, r),
        standing: super::challenge::standing_text(tr, r.standing.as_ref()),
        about: None,
        link: None,
    }
}

/// "open-weight · Qwen2.5-VL · 7B", from what is known.
fn about(category: Option<&str>, family: Option<&str>, size: Option<&str>) -> Option<String> {
    let known: Vec<&str> = [category, family, size].into_iter().flatten().collect();
    (!known.is_empty()).then(|| known.join(" · "))
}

/// A reported row as the table prints it: its per-step cells (the paper's percentages), no
/// totals (the paper's appendix tables give none), no interval, no rank.
fn reported_text(tr: &Tr, r: &ReportedResult) -> RowText {
    let m = &r.reported;
    let value = |metric: Metric, key: CellKey| m.values(metric).get(&key).map(|v| v / 100.0);
    let steps = |direction| {
        CellKey::all()
            .filter(|k| k.direction == direction)
            .map(|k| CellText {
                ta: tr.percent_figure(value(Metric::TaskAccuracy, k)),
                pa: tr.percent_figure(value(Metric::PairwiseAccuracy, k)),
                few: None,
            })
            .collect()
    };
    let none = || CellText {
        ta: tr.percent_figure(None),
        pa: tr.percent_figure(None),
        few: None,
    };
    RowText {
        rank: String::new(),
        model: m.model.clone(),
        account: String::new(),
        baseline: false,
        human: false,
        attempts: 0,
        history: None,
        submission: None,
        drawn: false,
        submitted_on: String::new(),
        overall: none(),
        ta_ci: String::new(),
        pa_ci: String::new(),
        ci_differs: false,
        forward: none(),
        inverse: none(),
        forward_steps: steps(Direction::Forward),
        inverse_steps: steps(Direction::Inverse),
        coverage: String::new(),
        parse_failures: String::new(),
        human_note: None,
        outdated: None,
        reported: Some(m.source.clone()),
        provenance: None,
        account_submissions: None,
        standing: None,
        about: about(
            Some(m.category.as_str()),
            m.family.as_deref(),
            m.size.as_deref(),
        ),
        link: None,
    }
}

async fn leaderboard_page(
    State(state): State<AppState>,
    Path(name): Path<String>,
    RawQuery(raw): RawQuery,
    headers: HeaderMap,
    ReaderIsAdmin(admin): ReaderIsAdmin,
    tr: Tr,
) -> Result<Response, PageError> {
    let request = BoardRequest::parse(raw.as_deref())?;
    let board = leaderboard::board(&state.hub, &name).await?;
    let shown = super::challenge::board_rows(&board, request.part, admin)?;
    // One rendering per language and kind of reader (admins see a link to the preview); the
    // switch's return path is the request's own.
    let kind = format!("page.{}.{}.{admin}", tr.lang(), tr.here());
    let etag = request.etag(&board, &kind);
    if matches_etag(&headers, &etag) {
        return Ok(with_etag(&headers, &etag, ()));
    }
    let html = request.view(&board, &kind, || {
        Ok(LeaderboardPage::new(tr, &board, shown, admin, &request)
            .render_page()?
            .into_bytes())
    })?;
    let body = ([(header::CONTENT_TYPE, "text/html; charset=utf-8")], html);
    Ok(with_etag(&headers, &etag, body))
}
