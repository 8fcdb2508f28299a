//! Two leaderboard rows compared item by item (`app::compare`): the page
//! `/datasets/{dataset}/compare?a=&b=` (a form choosing the rows, then the comparison) and
//! `GET /api/v1/datasets/{dataset}/compare`. Public, as the leaderboard is; the lists of items
//! only one row gets right only where per-item verdicts are shown to the reader.

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::response::Html;
use axum::routing::get;
use serde::Deserialize;
use serde_json::json;

use super::AppState;
use super::error::{ApiError, PageError, RenderPage};
use super::extract::{Path, Query};
use super::i18n::Tr;
use super::openapi::{ApiRoute, Verb};
use super::session::ReaderIsAdmin;
use crate::app::compare::{self, DiscordantItem, RowComparison};
use crate::app::leaderboard;
use crate::app::refusal::{Expected, Refusal};
use crate::core::dataset::Direction;
use crate::core::leaderboard::{RowSource, one_per_model};
use crate::core::paired::{PairedCell, PairedConfig, Resampling};

pub fn page_router() -> Router<AppState> {
    Router::new().route("/datasets/{dataset}/compare", get(compare_page))
}

pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Get,
            "/datasets/{dataset}/compare",
            compare_api,
            "Compare two leaderboard rows",
        )
        .describe(
            "Two rows of the dataset's leaderboard compared on the items both were scored on: \
             each side's task and pairwise accuracy overall, per direction and per direction \
             and step length; the difference A − B with a paired percentile bootstrap interval \
             (items resampled together; by default whole activities, ENACT's `task_name`, \
             with their items); McNemar's exact test on task success (`mcnemar_p`); and the \
             items each gets right that the other does not (`a_only_items`, `b_only_items`: \
             null when the dataset's answers are hidden). A row is a model name (its board \
             row: the latest published submission of that model) or a published submission's \
             id. Rows scored under different metric versions are compared and marked \
             (`metric_versions_differ`).",
        )
        .query_with(
            "a",
            true,
            json!({"type": "string", "pattern": "\\S"}),
            "Row A: a model name or a submission id.",
        )
        .query_with(
            "b",
            true,
            json!({"type": "string", "pattern": "\\S"}),
            "Row B: a model name or a submission id (not row A).",
        )
        .query_with(
            "resample",
            false,
            json!({"enum": ["", "activities", "items"]}),
            "What the bootstrap resamples: `activities` (the default) or `items`.",
        )
        .responds_json::<RowComparison>(200, "The comparison.")
        .errors(&[400, 404, 503]),
    ]
}

/// The query parameter `resample`: what a bootstrap resamples, activities when absent.
pub(super) fn resample_param(value: Option<&str>) -> Result<Resampling, ApiError> {
    match value.unwrap_or_default().trim() {
        "" => Ok(Resampling::default()),
        other => Resampling::parse(other)
            .ok_or_else(|| {
                Refusal::bad_value(
                    "resample",
                    other,
                    Expected::OneOf(vec!["activities", "items"]),
                )
            })
            .map_err(ApiError::from),
    }
}

/// What a bootstrap resamples, in words.
pub(super) fn resampling_text(tr: &Tr, resampling: Resampling) -> String {
    tr.t(match resampling {
        Resampling::Activities => "intervals-resampling-activities",
        Resampling::Items => "intervals-resampling-items",
    })
}

/// The comparison's choices, as the form and the API send them.
#[derive(Debug, Default, Deserialize)]
struct CompareQuery {
    a: Option<String>,
    b: Option<String>,
    resample: Option<String>,
}

impl CompareQuery {
    fn config(&self) -> Result<PairedConfig, ApiError> {
        let resampling = resample_param(self.resample.as_deref())?;
        Ok(PairedConfig {
            resampling,
            ..PairedConfig::default()
        })
    }

    /// Both rows, when both are given.
    fn rows(&self) -> Option<(&str, &str)> {
        Some((given(&self.a)?, given(&self.b)?))
    }
}

/// A query value that holds more than blanks.
fn given(value: &Option<String>) -> Option<&str> {
    value.as_deref().map(str::trim).filter(|v| !v.is_empty())
}

async fn compare_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    Query(query): Query<CompareQuery>,
) -> Result<axum::Json<RowComparison>, ApiError> {
    let config = query.config()?;
    let Some((a, b)) = query.rows() else {
        return Err(Refusal::FieldsRequired {
            fields: vec!["a", "b"],
        }
        .into());
    };
    let comparison = compare::rows(&state.hub, &dataset, a, b, config, false).await?;
    Ok(axum::Json(comparison))
}

/// A choosable row in the form.
struct RowChoice {
    value: String,
    label: String,
}

/// One printed line of the table.
struct CellView {
    name: String,
    n: usize,
    a_ta: String,
    b_ta: String,
    difference: String,
    a_only: usize,
    b_only: usize,
    mcnemar_p: String,
    /// Whether McNemar's p is under 0.05.
    significant: bool,
    a_pa: String,
    b_pa: String,
    pairwise_difference: String,
    /// A direction's total (printed as a group heading line).
    total: bool,
}

struct ItemView {
    item: String,
    kind: String,
    activity: String,
}

struct ComparisonView {
    a: String,
    b: String,
    resampling: String,
    resamples: usize,
    level: String,
    cells: Vec<CellView>,
    unpaired_items: usize,
    metric_versions: Option<(u32, u32)>,
    /// The items only A gets right, then only B: a heading and the items, `None` where they
    /// are not shown.
    only: Vec<(String, Option<Vec<ItemView>>)>,
    /// This comparison as JSON (the API's address).
    json: String,
}

#[derive(Template)]
#[template(path = "compare.html")]
struct ComparePage {
    tr: Tr,
    dataset: String,
    choices: Vec<RowChoice>,
    a: String,
    b: String,
    resample: String,
    comparison: Option<ComparisonView>,
}

fn points(value: f64) -> String {
    format!("{:.2}", 100.0 * value)
}

fn signed(estimate: f64, low: f64, high: f64) -> String {
    format!(
        "{:+.2} [{:+.2}, {:+.2}]",
        100.0 * estimate,
        100.0 * low,
        100.0 * high
    )
}

fn cell_view(tr: &Tr, cell: &PairedCell) -> CellView {
    let name = match (cell.direction, cell.step_length) {
        (None, _) => tr.t("compare-overall"),
        (Some(Direction::Forward), None) => tr.t("compare-forward"),
        (Some(Direction::Inverse), None) => tr.t("compare-inverse"),
        (Some(_), Some(l)) => format!("L={}", l.get()),
    };
    let pa = |v: Option<f64>| v.map_or_else(|| "–".to_owned(), points);
    CellView {
        name,
        n: cell.n,
        a_ta: points(cell.a_task_accuracy),
        b_ta: points(cell.b_task_accuracy),
        difference: signed(
            cell.difference.estimate,
            cell.difference.low,
            cell.difference.high,
        ),
        a_only: cell.a_only,
        b_only: cell.b_only,
        mcnemar_p: if cell.mcnemar_p < 0.0001 {
            "< 0.0001".to_owned()
        } else {
            format!("{:.4}", cell.mcnemar_p)
        },
        significant: cell.mcnemar_p < 0.05,
        a_pa: pa(cell.a_pairwise_accuracy),
        b_pa: pa(cell.b_pairwise_accuracy),
        pairwise_difference: cell
            .pairwise_difference
            .map_or_else(|| "–".to_owned(), |d| signed(d.estimate, d.low, d.high)),
        total: cell.step_length.is_none(),
    }
}

fn item_views(items: &[DiscordantItem]) -> Vec<ItemView> {
    items
        .iter()
        .map(|i| ItemView {
            item: i.item.clone(),
            kind: format!("{} L={}", i.direction, i.step_length.get()),
            activity: i.activity.clone(),
        })
        .collect()
}

fn comparison_view(tr: &Tr, c: &RowComparison, query: &CompareQuery) -> ComparisonView {
    let label = |r: &compare::ComparedRow| format!("{} (#{})", r.model, r.submission);
    let mut pairs = vec![
        ("a", query.a.as_deref().unwrap_or_default()),
        ("b", query.b.as_deref().unwrap_or_default()),
    ];
    if let Some(r) = query.resample.as_deref().filter(|r| !r.is_empty()) {
        pairs.push(("resample", r));
    }
    let json = format!(
        "/api/v1/datasets/{}/compare?{}",
        c.dataset,
        serde_urlencoded::to_string(pairs).unwrap_or_default()
    );
    ComparisonView {
        a: label(&c.a),
        b: label(&c.b),
        resampling: resampling_text(tr, c.config.resampling),
        resamples: c.config.resamples,
        level: format!("{:.0}", 100.0 * c.config.level),
        cells: std::iter::once(&c.overall)
            .chain(&c.cells)
            .map(|cell| cell_view(tr, cell))
            .collect(),
        unpaired_items: c.unpaired_items,
        metric_versions: c
            .metric_versions_differ
            .then_some((c.a.metric_version, c.b.metric_version)),
        only: vec![
            (
                tr.t_s("compare-only-a", "row", label(&c.a)),
                c.a_only_items.as_deref().map(item_views),
            ),
            (
                tr.t_s("compare-only-b", "row", label(&c.b)),
                c.b_only_items.as_deref().map(item_views),
            ),
        ],
        json,
    }
}

async fn compare_page(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    Query(query): Query<CompareQuery>,
    ReaderIsAdmin(admin): ReaderIsAdmin,
    tr: Tr,
) -> Result<Html<String>, PageError> {
    let config = query.config()?;
    let board = leaderboard::board(&state.hub, &dataset).await?;
    let choices = one_per_model(&board.rows)
        .iter()
        .filter(|r| r.source == RowSource::Submission)
        .filter_map(|r| {
            let id = r.submission?;
            Some(RowChoice {
                value: id.to_string(),
                label: format!("{} (#{id}, {})", r.model, r.account),
            })
        })
        .collect();
    let comparison = match query.rows() {
        Some((a, b)) => {
            let c = compare::rows(&state.hub, &board.dataset.name, a, b, config, admin).await?;
            Some(comparison_view(&tr, &c, &query))
        }
        None => None,
    };
    let page = ComparePage {
        dataset: board.dataset.name.clone(),
        choices,
        a: query.a.clone().unwrap_or_default(),
        b: query.b.clone().unwrap_or_default(),
        resample: query.resample.clone().unwrap_or_default(),
        comparison,
        tr,
    };
    Ok(Html(page.render_page()?))
}
