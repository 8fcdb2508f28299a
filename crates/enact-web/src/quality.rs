//! Annotator quality control from the web: the admin API (`/api/v1/admin/annotators/quality`,
//! a dataset's gold set, exclusions) and the admin page `/admin/quality` (the gold set's form,
//! the sortable quality table with the annotators under a chosen bar highlighted, and
//! exclude/include buttons; the queues with their pause and handover forms, and the attention
//! checks, whose forms [`super::annotator_controls`] handles).

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::response::{Html, IntoResponse, Redirect, Response};
use axum::routing::{get, post};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::json;

use super::auth::TokenCaller;
use super::error::{ApiError, PageError, RenderPage};
use super::extract::{Json, MOST_WHOLE_NUMBER, Path, Query, required_whole_number};
use super::openapi::{ApiRoute, Verb};
use super::session::{Admin, Protected};
use super::{AppError, AppState};
use crate::app::gold::{GoldCleared, GoldQueues, GoldSet};
use crate::app::quality::QualityReport;
use crate::app::refusal::{Expected, Refusal};
use crate::app::{annotators, attention, controls, datasets, gold, quality};
use crate::core::annotation::Session;
use crate::core::credentials::Scope;
use crate::core::gold::{GoldChoice, GoldRate};
use crate::core::quality::{AnnotatorQuality, Interval};

pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Get,
            "/admin/annotators/quality",
            quality_api,
            "Each annotator's quality on a dataset",
        )
        .describe(
            "For every annotator who finished an item of the dataset: items done, gold items \
             answered, gold task and pairwise accuracy with 95% Wilson intervals, agreement \
             with the other annotators on shared items (mean pairwise Krippendorff's alpha on \
             whole answers, and exact agreement), median and lower-decile seconds per item, \
             the share answered in under `fast_seconds`, and skip and flag rates; with who is \
             excluded from the Human row.",
        )
        .bearer(Scope::Admin)
        .query("dataset", true, "The dataset's name.")
        .query_with(
            "fast_seconds",
            false,
            json!({"type": "number", "exclusiveMinimum": 0, "maximum": 3600}),
            "Items answered in under this many seconds count as fast: above 0, at most 3600 \
             (default 5).",
        )
        .responds_json::<QualityReport>(200, "The figures.")
        .errors(&[400, 401, 403, 404]),
        ApiRoute::new(
            Verb::Get,
            "/admin/datasets/{dataset}/gold",
            gold_api,
            "A dataset's gold set",
        )
        .describe(
            "How the gold items were chosen, the rate they are mixed in at, and their ids;              `gold` is null when the dataset has no gold set.",
        )
        .bearer(Scope::Admin)
        .responds_json::<GoldOfDataset>(200, "The gold set, or null.")
        .errors(&[401, 403, 404]),
        ApiRoute::new(
            Verb::Put,
            "/admin/datasets/{dataset}/gold",
            set_gold_api,
            "Choose a dataset's gold items",
        )
        .describe(
            "Replaces the dataset's gold set with `share` of its items drawn with `seed` (0 \
             when absent), or the listed `items`, and mixes them into every annotator's queue: \
             one in every `rate` items, unannounced. Gold answers are judged by the verifier, \
             count for the annotator's quality, and never count in the Human row or the \
             agreement report. Audited (`gold.set`).",
        )
        .bearer(Scope::Admin)
        .body_json::<GoldRequest>(
            "`rate` and either `share` (with an optional `seed`) or `items`.",
            "{\"rate\": 10, \"share\": 0.05, \"seed\": 7}",
        )
        .responds_json::<GoldChanged>(200, "The gold set as stored, and what changed in queues.")
        .errors(&[400, 401, 403, 404, 415, 422]),
        ApiRoute::new(
            Verb::Delete,
            "/admin/datasets/{dataset}/gold",
            clear_gold_api,
            "Remove a dataset's gold set",
        )
        .describe(
            "Unfinished gold items leave the queues; answers given stay, and count in the Human \
             row again. Audited (`gold.clear`). A dataset without a gold set is left as it is \
             (`cleared` false).",
        )
        .bearer(Scope::Admin)
        .responds_json::<GoldCleared>(200, "Whether there was a gold set, and what left queues.")
        .errors(&[401, 403, 404]),
        ApiRoute::new(
            Verb::Put,
            "/admin/datasets/{dataset}/exclusions/{annotator}",
            exclude_api,
            "Exclude an annotator from a dataset's Human row",
        )
        .describe(
            "The annotator's answers on the dataset leave its Human row and agreement report; \
             they stay stored, and DELETE on the same path counts them again. Audited \
             (`annotator.exclude`) when it changes anything (`changed`).",
        )
        .bearer(Scope::Admin)
        .responds_json::<ExclusionChanged>(200, "The annotator is excluded.")
        .errors(&[401, 403, 404]),
        ApiRoute::new(
            Verb::Delete,
            "/admin/datasets/{dataset}/exclusions/{annotator}",
            include_api,
            "Count an excluded annotator's answers again",
        )
        .describe(
            "Audited (`annotator.include`) when it changes anything (`changed`: false when the \
             annotator was not excluded).",
        )
        .bearer(Scope::Admin)
        .responds_json::<ExclusionChanged>(200, "The annotator is included.")
        .errors(&[401, 403, 404]),
    ]
}

/// The admin page and its forms (behind the admin pages' gate, `web::admin_pages`).
pub fn router() -> Router<AppState> {
    Router::new()
        .route("/admin/quality", get(quality_page))
        .route("/admin/quality/gold", post(set_gold_page))
        .route("/admin/quality/gold/clear", post(clear_gold_page))
        .route("/admin/quality/exclusion", post(exclusion_page))
}

#[derive(Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct QualityQuery {
    dataset: String,
    #[serde(default)]
    fast_seconds: Option<f64>,
}

async fn quality_api(
    State(state): State<AppState>,
    Query(query): Query<QualityQuery>,
) -> Result<axum::Json<QualityReport>, ApiError> {
    let fast = quality::fast_seconds(query.fast_seconds)?;
    Ok(axum::Json(
        quality::report(&state.hub, &query.dataset, fast).await?,
    ))
}

/// A dataset's gold set, if it has one.
#[derive(Serialize, JsonSchema)]
struct GoldOfDataset {
    dataset: String,
    gold: Option<GoldSet>,
}

async fn gold_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
) -> Result<axum::Json<GoldOfDataset>, ApiError> {
    let gold = gold::show(&state.hub, &dataset).await?;
    Ok(axum::Json(GoldOfDataset { dataset, gold }))
}

/// A gold set to choose: `rate` and either `share` (and `seed`) or `items`. The schema states
/// each field's own range; that `share` and `items` exclude each other, and that the items
/// must be the dataset's, are checked with a 400 naming the field.
#[derive(Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct GoldRequest {
    /// One gold item in every `rate` queue items (2 to 1000).
    #[serde(deserialize_with = "required_whole_number")]
    #[schemars(with = "i64", range(min = 2, max = GoldRate::MAX))]
    rate: i64,
    /// A share of the items, above 0 and below 1.
    #[serde(default)]
    #[schemars(extend("exclusiveMinimum" = 0, "exclusiveMaximum" = 1))]
    share: Option<f64>,
    /// The seed of the share's draw (0 when absent).
    #[serde(default, deserialize_with = "whole_seed")]
    #[schemars(with = "Option<u64>", range(max = u64::MAX))]
    seed: Option<u64>,
    /// Item ids, each once.
    #[serde(default)]
    #[schemars(length(min = 1), inner(regex(pattern = r"^[^#\s]\S*$")), extend("uniqueItems" = true))]
    items: Option<Vec<String>>,
}

/// A seed: a whole number from 0 to `u64::MAX`, or a whole float up to
/// [`MOST_WHOLE_NUMBER`] (`7.0` is a JSON Schema integer; schemathesis sent one and got 422).
pub(super) fn whole_seed<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    let Some(number) = Option::<serde_json::Number>::deserialize(d)? else {
        return Ok(None);
    };
    number
        .as_u64()
        .or_else(|| {
            number
                .as_f64()
                .filter(|f| f.fract() == 0.0 && (0.0..=MOST_WHOLE_NUMBER as f64).contains(f))
                .map(|f| f as u64)
        })
        .map(Some)
        .ok_or_else(|| {
            serde::de::Error::custom(format!(
                "{number} is not a seed (a whole number of 0 or more)"
            ))
        })
}

impl GoldRequest {
    fn choice(&self) -> Result<(GoldChoice, GoldRate), ApiError> {
        let rate = GoldRate::new(self.rate).map_err(|_| rate_refused(&self.rate.to_string()))?;
        let choice = match (self.share, &self.items) {
            (Some(share), None) => GoldChoice::share(share, self.seed.unwrap_or(0))
                .map_err(|_| Refusal::bad_value("share", share.to_string(), Expected::Fraction))?,
            (None, Some(items)) => {
                if self.seed.is_some() {
                    return Err(Refusal::NotWith {
                        field: "seed",
                        other: "items",
                    }
                    .into());
                }
                GoldChoice::list(&items.join("\n"))
                    .map_err(|e| AppError::Invalid(format!("`items`: {e}")))?
            }
            _ => {
                return Err(Refusal::ExactlyOneOf {
                    fields: vec!["share", "items"],
                }
                .into());
            }
        };
        Ok((choice, rate))
    }
}

#[derive(Serialize, JsonSchema)]
struct GoldChanged {
    gold: GoldSet,
    queues: GoldQueues,
}

async fn set_gold_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    TokenCaller(caller): TokenCaller,
    Json(request): Json<GoldRequest>,
) -> Result<axum::Json<GoldChanged>, ApiError> {
    let (choice, rate) = request.choice()?;
    let (gold, queues) = gold::set(&state.hub, &caller.actor(), &dataset, &choice, rate).await?;
    Ok(axum::Json(GoldChanged { gold, queues }))
}

async fn clear_gold_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    TokenCaller(caller): TokenCaller,
) -> Result<axum::Json<GoldCleared>, ApiError> {
    Ok(axum::Json(
        gold::clear(&state.hub, &caller.actor(), &dataset).await?,
    ))
}

#[derive(Serialize, JsonSchema)]
struct ExclusionChanged {
    dataset: String,
    annotator: String,
    excluded: bool,
    /// False when it was so already.
    changed: bool,
}

async fn exclude_api(
    State(state): State<AppState>,
    Path((dataset, annotator)): Path<(String, String)>,
    TokenCaller(caller): TokenCaller,
) -> Result<axum::Json<ExclusionChanged>, ApiError> {
    let changed = gold::exclude(&state.hub, &caller.actor(), &dataset, &annotator).await?;
    Ok(axum::Json(ExclusionChanged {
        dataset,
        annotator,
        excluded: true,
        changed,
    }))
}

async fn include_api(
    State(state): State<AppState>,
    Path((dataset, annotator)): Path<(String, String)>,
    TokenCaller(caller): TokenCaller,
) -> Result<axum::Json<ExclusionChanged>, ApiError> {
    let changed = gold::include(&state.hub, &caller.actor(), &dataset, &annotator).await?;
    Ok(axum::Json(ExclusionChanged {
        dataset,
        annotator,
        excluded: false,
        changed,
    }))
}

/// The columns the table sorts by, with their headings.
const COLUMNS: [(&str, &str); 12] = [
    ("name", "Annotator"),
    ("items_done", "Items done"),
    ("gold_answered", "Gold answered"),
    ("gold_ta", "Gold TA (95% interval)"),
    ("gold_pa", "Gold PA (95% interval)"),
    ("alpha", "Pairwise α"),
    ("exact", "Exact agreement"),
    ("median", "Median s/item"),
    ("p10", "Lower decile s/item"),
    ("fast", "Fast answers"),
    ("skip", "Skip rate"),
    ("flag", "Flag rate"),
];

/// The page's query: the dataset, the bar (in percent) under which gold TA is highlighted, the
/// fast-answer threshold, and the sort.
#[derive(Debug, Default, Deserialize)]
pub(super) struct PageQuery {
    #[serde(default)]
    dataset: String,
    #[serde(default)]
    bar: Option<f64>,
    #[serde(default)]
    fast_seconds: Option<f64>,
    #[serde(default)]
    sort: String,
    #[serde(default)]
    desc: bool,
}

impl PageQuery {
    /// The page of `dataset` with the default bar, threshold and order.
    pub(super) fn of(dataset: String) -> PageQuery {
        PageQuery {
            dataset,
            ..PageQuery::default()
        }
    }
}

struct Heading {
    label: &'static str,
    href: String,
    /// `ascending`, `descending` or `none`, for `aria-sort`.
    aria_sort: &'static str,
}

struct QualityRow {
    name: String,
    excluded: bool,
    below_bar: bool,
    cells: Vec<String>,
}

/// An annotator's queue with its controls (pause or resume, hand over).
struct QueueView {
    name: String,
    assigned: i64,
    finished: i64,
    /// Who paused it and when, when paused.
    paused: Option<(String, String)>,
}

/// One annotator's attention checks on the dataset.
struct ChecksView {
    name: String,
    passed: u64,
    failed: u64,
    pending: u64,
}

struct AttentionView {
    rate: i64,
    set_by: String,
    set_at: String,
    /// `ITEM_ID instruction` lines, as the form takes them.
    lines: String,
    items: usize,
}

struct GoldView {
    rate: i64,
    how: String,
    set_by: String,
    set_at: String,
    items: usize,
}

#[derive(Template)]
#[template(path = "admin_quality.html")]
struct QualityPage {
    name: String,
    csrf: String,
    datasets: Vec<String>,
    dataset: String,
    bar_percent: String,
    fast_seconds: String,
    sort: String,
    desc: bool,
    headings: Vec<Heading>,
    rows: Vec<QualityRow>,
    gold: Option<GoldView>,
    gold_items: i64,
    excluded: Vec<(String, String, String)>,
    queues: Vec<QueueView>,
    attention: Option<AttentionView>,
    attention_checks: i64,
    checks: Vec<ChecksView>,
    notice: Option<String>,
}

fn percent(value: Option<f64>) -> String {
    value.map_or_else(|| "–".to_owned(), |v| format!("{:.1}%", v * 100.0))
}

fn seconds(value: Option<f64>) -> String {
    value.map_or_else(|| "–".to_owned(), |v| format!("{v:.1}"))
}

fn with_interval(value: Option<f64>, interval: Option<Interval>) -> String {
    match (value, interval) {
        (Some(v), Some(i)) => format!(
            "{:.1}% ({:.1}–{:.1})",
            v * 100.0,
            i.low * 100.0,
            i.high * 100.0
        ),
        _ => "–".to_owned(),
    }
}

/// The value a column sorts by (missing values sort first ascending).
fn sort_key(a: &AnnotatorQuality, column: &str) -> Option<f64> {
    match column {
        "items_done" => Some(a.items_done as f64),
        "gold_answered" => Some(a.gold_answered as f64),
        "gold_ta" => a.gold_task_accuracy,
        "gold_pa" => a.gold_pairwise_accuracy,
        "alpha" => a.pairwise_alpha,
        "exact" => a.exact_agreement,
        "median" => a.median_seconds,
        "p10" => a.lower_decile_seconds,
        "fast" => a.fast_share,
        "skip" => a.skip_rate,
        "flag" => a.flag_rate,
        _ => None,
    }
}

fn sorted(
    mut annotators: Vec<AnnotatorQuality>,
    column: &str,
    desc: bool,
) -> Vec<AnnotatorQuality> {
    if column != "name" && COLUMNS.iter().any(|(key, _)| *key == column) {
        annotators.sort_by(|a, b| {
            let (x, y) = (sort_key(a, column), sort_key(b, column));
            match (x, y) {
                (Some(x), Some(y)) => x.total_cmp(&y),
                (x, y) => x.is_some().cmp(&y.is_some()),
            }
            .then_with(|| a.name.cmp(&b.name))
        });
    }
    if desc {
        annotators.reverse();
    }
    annotators
}

fn page_link(query: &PageQuery, bar: f64, sort: &str, desc: bool) -> String {
    let fast = query
        .fast_seconds
        .map(|f| f.to_string())
        .unwrap_or_default();
    format!(
        "/admin/quality?{}",
        serde_urlencoded::to_string([
            ("dataset", query.dataset.as_str()),
            ("bar", &bar.to_string()),
            ("fast_seconds", &fast),
            ("sort", sort),
            ("desc", if desc { "true" } else { "false" }),
        ])
        .unwrap_or_default()
    )
}

pub(super) async fn render(
    state: &AppState,
    session: Session,
    query: PageQuery,
    notice: Option<String>,
) -> Result<Html<String>, PageError> {
    let names: Vec<String> = datasets::overview(&state.hub)
        .await?
        .into_iter()
        .map(|d| d.dataset.name)
        .collect();
    let dataset = if query.dataset.trim().is_empty() {
        names.first().cloned().unwrap_or_default()
    } else {
        query.dataset.trim().to_owned()
    };
    let query = PageQuery { dataset, ..query };
    // In percent, as the form shows it.
    let bar = match query.bar {
        None => 80.0,
        Some(b) if b.is_finite() && (0.0..=100.0).contains(&b) => b,
        Some(b) => {
            return Err(Refusal::bad_value(
                "bar",
                b.to_string(),
                Expected::NumberBetween {
                    least: 0,
                    most: 100,
                },
            )
            .into());
        }
    };
    let fast = quality::fast_seconds(query.fast_seconds)?;
    let sort = if COLUMNS.iter().any(|(key, _)| *key == query.sort) {
        query.sort.clone()
    } else {
        "name".to_owned()
    };
    let pauses = controls::pauses(&state.hub).await?;
    let queues = annotators::with_progress(&state.hub)
        .await?
        .into_iter()
        .filter(|p| p.annotator.active)
        .map(|p| QueueView {
            paused: pauses
                .iter()
                .find(|x| x.annotator == p.annotator.name)
                .map(|x| (x.paused_by.clone(), x.paused_at.clone())),
            name: p.annotator.name,
            assigned: p.assigned,
            finished: p.finished,
        })
        .collect();
    let attention_view = if query.dataset.is_empty() {
        None
    } else {
        let set = attention::show(&state.hub, &query.dataset).await?;
        set.map(|a| AttentionView {
            rate: a.rate,
            set_by: a.set_by,
            set_at: a.set_at,
            items: a.checks.len(),
            lines: a
                .checks
                .iter()
                .map(|c| format!("{} {}", c.item_id, c.instruction.as_str()))
                .collect::<Vec<_>>()
                .join("\n"),
        })
    };
    let (rows, gold_view, gold_items, excluded, attention_checks, checks) = if query
        .dataset
        .is_empty()
    {
        (Vec::new(), None, 0, Vec::new(), 0, Vec::new())
    } else {
        let report = quality::report(&state.hub, &query.dataset, fast).await?;
        let gold_set = gold::show(&state.hub, &query.dataset).await?;
        let rows = sorted(report.annotators, &sort, query.desc)
            .into_iter()
            .map(|a| QualityRow {
                below_bar: a.gold_task_accuracy.is_some_and(|ta| ta * 100.0 < bar),
                cells: vec![
                    a.items_done.to_string(),
                    a.gold_answered.to_string(),
                    with_interval(a.gold_task_accuracy, a.gold_task_accuracy_interval),
                    with_interval(a.gold_pairwise_accuracy, a.gold_pairwise_accuracy_interval),
                    a.pairwise_alpha
                        .map_or_else(|| "–".to_owned(), |v| format!("{v:.3}")),
                    percent(a.exact_agreement),
                    seconds(a.median_seconds),
                    seconds(a.lower_decile_seconds),
                    percent(a.fast_share),
                    percent(a.skip_rate),
                    percent(a.flag_rate),
                ],
                name: a.name,
                excluded: a.excluded,
            })
            .collect();
        let gold_view = gold_set.map(|g| GoldView {
            rate: g.rate,
            how: match (g.share, g.seed) {
                (Some(share), Some(seed)) => format!("a share of {share} drawn with seed {seed}"),
                _ => "a list of items".to_owned(),
            },
            set_by: g.set_by,
            set_at: g.set_at,
            items: g.items.len(),
        });
        let excluded = report
            .exclusions
            .into_iter()
            .map(|e| (e.annotator, e.excluded_by, e.excluded_at))
            .collect();
        let checks = report
            .attention
            .into_iter()
            .map(|c| ChecksView {
                name: c.annotator,
                passed: c.tally.passed,
                failed: c.tally.failed,
                pending: c.tally.pending,
            })
            .collect();
        (
            rows,
            gold_view,
            report.gold_items,
            excluded,
            report.attention_checks,
            checks,
        )
    };
    let headings = COLUMNS
        .iter()
        .map(|(key, label)| {
            let current = *key == sort;
            Heading {
                label,
                // Clicking the sorted column again reverses it.
                href: page_link(&query, bar, key, current && !query.desc),
                aria_sort: match (current, query.desc) {
                    (false, _) => "none",
                    (true, false) => "ascending",
                    (true, true) => "descending",
                },
            }
        })
        .collect();
    let page = QualityPage {
        name: session.name,
        csrf: session.csrf_token,
        datasets: names,
        dataset: query.dataset.clone(),
        bar_percent: bar.to_string(),
        fast_seconds: fast.to_string(),
        sort,
        desc: query.desc,
        headings,
        rows,
        gold: gold_view,
        gold_items,
        excluded,
        queues,
        attention: attention_view,
        attention_checks,
        checks,
        notice,
    };
    Ok(Html(page.render_page()?))
}

async fn quality_page(
    State(state): State<AppState>,
    Admin(session): Admin,
    Query(query): Query<PageQuery>,
) -> Result<Html<String>, PageError> {
    render(&state, session, query, None).await
}

/// The gold form: `share` and `seed`, or `items` (one id per line), and `rate`.
#[derive(Deserialize)]
struct GoldForm {
    dataset: String,
    #[serde(default)]
    share: String,
    #[serde(default)]
    seed: String,
    #[serde(default)]
    items: String,
    #[serde(default)]
    rate: String,
}

/// A gold or attention rate that is not one item in every 2 to [`GoldRate::MAX`].
pub(super) fn rate_refused(rate: &str) -> Refusal {
    Refusal::bad_value(
        "rate",
        rate,
        Expected::WholeNumber {
            least: 2,
            most: GoldRate::MAX.into(),
        },
    )
}

fn form_number<T: std::str::FromStr>(field: &str, text: &str) -> Result<Option<T>, ApiError> {
    let text = text.trim();
    if text.is_empty() {
        return Ok(None);
    }
    text.parse()
        .map(Some)
        .map_err(|_| Refusal::bad_value(field, text, Expected::Number))
        .map_err(ApiError::from)
}

async fn set_gold_page(
    State(state): State<AppState>,
    request: Protected<GoldForm>,
) -> Result<Html<String>, PageError> {
    let form = request.body;
    let rate = form_number::<i64>("rate", &form.rate)?.ok_or_else(|| rate_refused(""))?;
    let share = form_number::<f64>("share", &form.share)?;
    let seed = form_number::<u64>("seed", &form.seed)?;
    let items = Some(form.items.trim())
        .filter(|t| !t.is_empty())
        .map(|t| t.lines().map(str::to_owned).collect());
    let request_body = GoldRequest {
        rate,
        share,
        seed: if share.is_some() { seed } else { None },
        items,
    };
    let (choice, rate) = request_body.choice()?;
    let (set, queues) = gold::set(
        &state.hub,
        &request.session.actor(),
        &form.dataset,
        &choice,
        rate,
    )
    .await?;
    let notice = format!(
        "Gold set of '{}': {} items, one in every {} queue items; {} added to queues, {} \
         unfinished ones of the earlier set taken out.",
        set.dataset,
        set.items.len(),
        set.rate,
        queues.added,
        queues.removed
    );
    let query = PageQuery {
        dataset: form.dataset,
        ..PageQuery::default()
    };
    render(&state, request.session, query, Some(notice)).await
}

#[derive(Deserialize)]
struct DatasetForm {
    dataset: String,
}

async fn clear_gold_page(
    State(state): State<AppState>,
    request: Protected<DatasetForm>,
) -> Result<Html<String>, PageError> {
    let cleared = gold::clear(&state.hub, &request.session.actor(), &request.body.dataset).await?;
    let notice = if cleared.cleared {
        format!(
            "Gold set of '{}' cleared; {} unfinished gold items taken out of queues.",
            request.body.dataset, cleared.removed
        )
    } else {
        format!("Dataset '{}' had no gold set.", request.body.dataset)
    };
    let query = PageQuery {
        dataset: request.body.dataset,
        ..PageQuery::default()
    };
    render(&state, request.session, query, Some(notice)).await
}

/// Exclude or include: `action` is `exclude` or `include`.
#[derive(Deserialize)]
struct ExclusionForm {
    dataset: String,
    annotator: String,
    action: String,
}

async fn exclusion_page(
    State(state): State<AppState>,
    request: Protected<ExclusionForm>,
) -> Result<Response, PageError> {
    let form = request.body;
    let actor = request.session.actor();
    // Already so (another admin, another tab): the page shows it as it is either way.
    match form.action.as_str() {
        "exclude" => {
            gold::exclude(&state.hub, &actor, &form.dataset, &form.annotator).await?;
        }
        "include" => {
            gold::include(&state.hub, &actor, &form.dataset, &form.annotator).await?;
        }
        other => {
            return Err(Refusal::bad_value(
                "action",
                other,
                Expected::OneOf(vec!["exclude", "include"]),
            )
            .into());
        }
    }
    // Back to the page (a reload does not send the form again).
    let query =
        serde_urlencoded::to_string([("dataset", form.dataset.as_str())]).unwrap_or_default();
    Ok(Redirect::to(&format!("/admin/quality?{query}")).into_response())
}
