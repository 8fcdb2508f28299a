//! The admins' agreement pages: the cross-annotation protocol action, and the dataset report
//! (page, JSON and the downloadable bundle).

use askama::Template;
use axum::Router;
use axum::extract::{RawQuery, State};
use axum::response::{Html, Response};
use axum::routing::{get, post};
use serde::Deserialize;

use super::admin::render_admin;
use super::error::{ApiError, PageError, RenderPage};
use super::extract::{Json, Path, whole_number_between};
use super::session::{Admin, Protected};
use super::{AppError, AppState};
use crate::app::agreement::{self, ReportSettings};
use crate::app::refusal::{Expected, Refusal};
use crate::core::agreement::protocol::DEFAULT_ITEMS_PER_CELL;
use crate::core::agreement::report::heatmap::comparison_heatmap;
use crate::core::agreement::report::{AgreementReport, AgreementSection};
use crate::core::agreement::{
    BootstrapConfig, DEFAULT_BOOTSTRAP_SEED, DEFAULT_CONFIDENCE_LEVEL, DEFAULT_REPLICATES,
    MeasurementLevel, OrderingEncoding, PAPER_COMPARABLE_ENCODING, WelchComparison,
};
use crate::core::bundle::BundleFile;
use crate::core::dataset::{Direction, StepLength};
use crate::core::heatmap::Heatmap;
use crate::core::leaderboard::{AccuracyChart, LeaderboardRow, RowSource};

pub fn router() -> Router<AppState> {
    Router::new()
        .route(
            "/admin/datasets/{dataset}/agreement-protocol",
            post(run_protocol),
        )
        .route("/admin/datasets/{dataset}/report", get(report_page))
        .route("/admin/datasets/{dataset}/report.json", get(report_json))
        .route("/admin/datasets/{dataset}/report.tar", get(report_bundle))
}

/// The protocol form: k and an optional seed (a fresh random one, recorded, when empty).
#[derive(Deserialize)]
struct ProtocolForm {
    #[serde(default)]
    items_per_cell: String,
    #[serde(default)]
    seed: String,
}

fn parse_field<T: std::str::FromStr>(name: &str, text: &str, default: T) -> Result<T, ApiError> {
    let text = text.trim();
    if text.is_empty() {
        return Ok(default);
    }
    text.parse()
        .map_err(|_| Refusal::bad_value(name, text, Expected::WholeNumberFrom { least: 0 }))
        .map_err(ApiError::from)
}

async fn run_protocol(
    State(state): State<AppState>,
    Path(name): Path<String>,
    request: Protected<ProtocolForm>,
) -> Result<Html<String>, PageError> {
    let items_per_cell = parse_field(
        "items_per_cell",
        &request.body.items_per_cell,
        DEFAULT_ITEMS_PER_CELL,
    )?;
    let seed = parse_field("seed", &request.body.seed, rand::random::<u64>())?;
    let run = agreement::run_protocol(
        &state.hub,
        &request.session.actor(),
        &name,
        items_per_cell,
        seed,
        Some(request.session.annotator),
    )
    .await?;
    let short = if run.plan.shortfalls.is_empty() {
        String::new()
    } else {
        format!(
            " {} annotator × direction × step length cells had fewer than {items_per_cell} \
             completed items and were taken whole.",
            run.plan.shortfalls.len()
        )
    };
    let notice = format!(
        "Agreement protocol on '{}': drew {} items (k = {items_per_cell}, seed = {seed}) from \
         the completed primary items of {} annotators and added {} assignments.{short}",
        run.dataset,
        run.plan.samples.len(),
        run.annotators.len(),
        run.assignments_added,
    );
    render_admin(&state, request.session, Some(notice), None).await
}

/// The report's query string: every field optional, empty fields as absent.
#[derive(Deserialize, Default)]
struct ReportQuery {
    #[serde(default)]
    encoding: String,
    #[serde(default)]
    level: String,
    #[serde(default)]
    bootstrap: String,
    #[serde(default)]
    seed: String,
    #[serde(default)]
    confidence: String,
    /// Two published submission ids to compare (a − b).
    #[serde(default)]
    a: String,
    #[serde(default)]
    b: String,
}

/// The most bootstrap replicates a report page computes.
const MOST_REPLICATES: usize = 20_000;

/// The query parameter `name`, when given, as `expected` describes it.
fn optional<T: std::str::FromStr>(
    name: &str,
    text: &str,
    expected: Expected,
) -> Result<Option<T>, ApiError> {
    let text = text.trim();
    if text.is_empty() {
        return Ok(None);
    }
    text.parse()
        .map(Some)
        .map_err(|_| Refusal::bad_value(name, text, expected))
        .map_err(ApiError::from)
}

impl ReportQuery {
    fn parse(raw: Option<&str>) -> Result<ReportQuery, ApiError> {
        serde_urlencoded::from_str(raw.unwrap_or(""))
            .map_err(|e| AppError::Invalid(format!("query string: {e}")))
            .map_err(ApiError)
    }

    fn settings(&self) -> Result<ReportSettings, ApiError> {
        let chosen_pair = match (
            optional::<i64>("a", &self.a, Expected::SubmissionId)?,
            optional::<i64>("b", &self.b, Expected::SubmissionId)?,
        ) {
            (Some(a), Some(b)) => Some((a, b)),
            (None, None) => None,
            _ => {
                return Err(Refusal::BothOrNeither { fields: ["a", "b"] }.into());
            }
        };
        let confidence_level = optional::<f64>("confidence", &self.confidence, Expected::Fraction)?
            .unwrap_or(DEFAULT_CONFIDENCE_LEVEL);
        if !(confidence_level > 0.0 && confidence_level < 1.0) {
            return Err(Refusal::bad_value(
                "confidence",
                confidence_level.to_string(),
                Expected::Fraction,
            )
            .into());
        }
        // A page request must stay bounded; the command line has no such limit.
        let replicates = match self.bootstrap.trim() {
            "" => DEFAULT_REPLICATES,
            text => whole_number_between("bootstrap", text, 0, MOST_REPLICATES as u64)? as usize,
        };
        Ok(ReportSettings {
            encoding: optional::<OrderingEncoding>(
                "encoding",
                &self.encoding,
                Expected::OneOf(OrderingEncoding::ALL.map(OrderingEncoding::name).to_vec()),
            )?
            .unwrap_or(PAPER_COMPARABLE_ENCODING),
            level: optional::<MeasurementLevel>(
                "level",
                &self.level,
                Expected::OneOf(MeasurementLevel::ALL.map(MeasurementLevel::name).to_vec()),
            )?,
            bootstrap: BootstrapConfig {
                replicates,
                confidence_level,
                seed: optional::<u64>("seed", &self.seed, Expected::WholeNumberFrom { least: 0 })?
                    .unwrap_or(DEFAULT_BOOTSTRAP_SEED),
            },
            chosen_pair,
        })
    }
}

/// Gathers the inputs and builds the report off the async workers (the bootstrap is CPU work).
async fn dataset_report(
    state: &AppState,
    name: &str,
    raw: Option<&str>,
) -> Result<(AgreementReport, ReportSettings), ApiError> {
    let settings = ReportQuery::parse(raw)?.settings()?;
    let report = agreement::report(&state.hub, name, &settings).await?;
    Ok((report, settings))
}

/// The report's bundle: its files and the error analyses of the leaderboard's rows.
async fn dataset_bundle(
    state: &AppState,
    name: &str,
    raw: Option<&str>,
) -> Result<(AgreementReport, Vec<BundleFile>), ApiError> {
    let settings = ReportQuery::parse(raw)?.settings()?;
    agreement::report_bundle(&state.hub, name, &settings)
        .await
        .map_err(ApiError)
}

async fn report_json(
    State(state): State<AppState>,
    Admin(_): Admin,
    Path(name): Path<String>,
    RawQuery(raw): RawQuery,
) -> Result<Json<AgreementReport>, ApiError> {
    Ok(Json(dataset_report(&state, &name, raw.as_deref()).await?.0))
}

async fn report_bundle(
    State(state): State<AppState>,
    Admin(_): Admin,
    Path(name): Path<String>,
    RawQuery(raw): RawQuery,
) -> Result<Response, PageError> {
    let (report, files) = dataset_bundle(&state, &name, raw.as_deref()).await?;
    let folder = bundle_folder(&report);
    Ok(super::archive::bundle_download(&folder, &files)?)
}

/// `enact-hub-report-{dataset}-{first 12 hex digits of its hash}`, with anything outside
/// `[A-Za-z0-9._-]` in the name replaced, so it is a safe file name and header value.
pub fn bundle_folder(report: &AgreementReport) -> String {
    let name = super::file_name_safe(&report.stamp.dataset);
    let hash = report.stamp.dataset_hash.get(..12).unwrap_or("");
    format!("enact-hub-report-{name}-{hash}")
}

struct PairText {
    a: String,
    b: String,
    alpha: String,
    shared_units: usize,
}

struct CountText {
    direction: &'static str,
    step_length: u8,
    items: usize,
    answers: usize,
    all_agree: usize,
}

struct AgreementText {
    encoding: String,
    level: String,
    alpha: String,
    ci: String,
    items: usize,
    answers: usize,
    annotators: String,
    exact: String,
    pairs: Vec<PairText>,
    counts: Vec<CountText>,
}

struct TableRowText {
    label: String,
    human: bool,
    /// Forward 3..10 then inverse 3..10.
    cells: Vec<String>,
}

struct ComparisonText {
    a: String,
    b: String,
    items: usize,
    delta: String,
    se: String,
    t: String,
    df: String,
    p: String,
}

struct SubmissionChoice {
    id: i64,
    label: String,
    as_a: bool,
    as_b: bool,
}

#[derive(Template)]
#[template(path = "agreement_report.html")]
struct ReportPage {
    dataset: String,
    query: String,
    stamp: String,
    stamp_lines: Vec<String>,
    agreement: Option<AgreementText>,
    agreement_unavailable: Option<String>,
    step_lengths: Vec<u8>,
    /// Pairwise accuracy (Table 1 layout), then task accuracy (Table 3 layout).
    tables: Vec<(&'static str, Vec<TableRowText>)>,
    comparisons: Vec<ComparisonText>,
    heatmap: Heatmap,
    chart: AccuracyChart,
    submissions: Vec<SubmissionChoice>,
    encodings: Vec<(&'static str, bool)>,
    seed: u64,
    bootstrap: usize,
    /// What the report leaves out: answers on gold items, annotators an admin excluded.
    left_out: Vec<String>,
}

/// A figure with `decimals` places, or a dash where there is none.
pub(super) fn fixed(value: Option<f64>, decimals: usize) -> String {
    value.map_or_else(|| "–".to_owned(), |v| format!("{v:.decimals$}"))
}

fn percent(value: Option<f64>) -> String {
    value.map_or_else(|| "–".to_owned(), |v| format!("{:.2}", v * 100.0))
}

fn table_rows(rows: &[LeaderboardRow], task: bool) -> Vec<TableRowText> {
    rows.iter()
        .map(|row| TableRowText {
            label: match row.source {
                RowSource::Human => "Human".to_owned(),
                RowSource::Submission => format!(
                    "{} (#{})",
                    row.model,
                    row.submission.map_or_else(String::new, |id| id.to_string())
                ),
            },
            human: row.source == RowSource::Human,
            cells: Direction::ALL
                .iter()
                .flat_map(|direction| {
                    let columns = match direction {
                        Direction::Forward => &row.forward,
                        Direction::Inverse => &row.inverse,
                    };
                    columns.per_step.iter().map(|(_, cell)| {
                        percent(if task {
                            cell.task_accuracy
                        } else {
                            cell.pairwise_accuracy
                        })
                    })
                })
                .collect(),
        })
        .collect()
}

fn comparison_text(a: &str, b: &str, items: usize, w: &WelchComparison) -> ComparisonText {
    ComparisonText {
        a: a.to_owned(),
        b: b.to_owned(),
        items,
        delta: w
            .delta
            .map_or_else(|| "–".to_owned(), |d| format!("{d:+.4}")),
        se: fixed(w.se, 4),
        t: fixed(w.t, 3),
        df: fixed(w.df, 1),
        p: w.p.map_or_else(
            || {
                w.reason
                    .as_ref()
                    .map_or_else(|| "–".to_owned(), ToString::to_string)
            },
            |p| format!("{p:.3e}"),
        ),
    }
}

async fn report_page(
    State(state): State<AppState>,
    Admin(_): Admin,
    Path(name): Path<String>,
    RawQuery(raw): RawQuery,
) -> Result<Html<String>, PageError> {
    let (report, settings) = dataset_report(&state, &name, raw.as_deref()).await?;
    let mut page = ReportPage::new(&report, &settings, raw.as_deref().unwrap_or_default());
    if let Some(gold) = crate::app::gold::show(&state.hub, &name).await? {
        page.left_out.push(format!(
            "answers on the {} gold items (they judge annotators: see Annotator quality)",
            gold.items.len()
        ));
    }
    for e in crate::app::gold::exclusions(&state.hub, &name).await? {
        page.left_out.push(format!(
            "every answer of {}, excluded by {} at {}",
            e.annotator, e.excluded_by, e.excluded_at
        ));
    }
    Ok(Html(page.render_page()?))
}

impl AgreementText {
    fn new(a: &AgreementSection, seed: u64) -> AgreementText {
        AgreementText {
            encoding: a.encoding.to_string(),
            level: a.level.to_string(),
            alpha: fixed(a.alpha.estimate.alpha, 4),
            ci: format!(
                "{}% CI [{}, {}] ({} resamples of {} items, seed {})",
                a.alpha.confidence_level * 100.0,
                fixed(a.alpha.ci_low, 4),
                fixed(a.alpha.ci_high, 4),
                a.alpha.replicates,
                a.alpha.items,
                seed
            ),
            items: a.items,
            answers: a.answers,
            annotators: a
                .annotators
                .iter()
                .map(|r| format!("{} (#{})", r.name, r.id))
                .collect::<Vec<_>>()
                .join(", "),
            exact: format!(
                "{} of {} items ({}%)",
                a.exact_agreement.agreeing_items,
                a.exact_agreement.compared_items,
                percent(a.exact_agreement.rate)
            ),
            pairs: a
                .pairwise
                .iter()
                .map(|p| PairText {
                    a: p.a.name.clone(),
                    b: p.b.name.clone(),
                    alpha: p.alpha.map_or_else(
                        || format!("undefined: {}", p.reason.clone().unwrap_or_default()),
                        |v| format!("{v:.4}"),
                    ),
                    shared_units: p.shared_units,
                })
                .collect(),
            counts: a
                .counts
                .iter()
                .map(|c| CountText {
                    direction: c.direction.as_str(),
                    step_length: c.step_length.get(),
                    items: c.items,
                    answers: c.answers,
                    all_agree: c.all_agree,
                })
                .collect(),
        }
    }
}

impl ReportPage {
    fn new(report: &AgreementReport, settings: &ReportSettings, query: &str) -> ReportPage {
        let agreement = report
            .agreement
            .as_ref()
            .map(|a| AgreementText::new(a, settings.bootstrap.seed));
        ReportPage {
            dataset: report.stamp.dataset.clone(),
            query: if query.is_empty() {
                String::new()
            } else {
                format!("?{query}")
            },
            stamp: crate::core::bundle::stamp_text(&report.stamp),
            stamp_lines: crate::core::bundle::stamp_lines(&report.stamp),
            agreement,
            agreement_unavailable: report.agreement_unavailable.clone(),
            step_lengths: StepLength::all().map(StepLength::get).collect(),
            left_out: Vec::new(),
            tables: vec![
                (
                    "Pairwise accuracy (%), Table 1 layout",
                    table_rows(&report.rows, false),
                ),
                (
                    "Task accuracy (%), Table 3 layout",
                    table_rows(&report.rows, true),
                ),
            ],
            comparisons: report
                .comparisons
                .iter()
                .map(|c| comparison_text(&c.a.label, &c.b.label, c.items, &c.overall))
                .collect(),
            heatmap: comparison_heatmap(&report.comparisons),
            chart: AccuracyChart::task_accuracy_by_step_length(&report.rows),
            submissions: report
                .rows
                .iter()
                .filter_map(|r| {
                    r.submission.map(|id| SubmissionChoice {
                        id,
                        label: format!("{} (#{id})", r.model),
                        as_a: settings.chosen_pair.is_some_and(|(a, _)| a == id),
                        as_b: settings.chosen_pair.is_some_and(|(_, b)| b == id),
                    })
                })
                .collect(),
            encodings: OrderingEncoding::ALL
                .iter()
                .map(|e| (e.name(), *e == settings.encoding))
                .collect(),
            seed: settings.bootstrap.seed,
            bootstrap: settings.bootstrap.replicates,
        }
    }
}
