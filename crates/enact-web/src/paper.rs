//! The paper's tables as a page (`/datasets/{dataset}/paper`): ENACT's result tables with the
//! hub's rows beside the published ones, their figures, the reproduction check, and the
//! folder `enact-hub paper` writes, as a tar (`/datasets/{dataset}/paper.tar`) or file by file
//! (`/datasets/{dataset}/paper/files/{file}`). Public, as the leaderboard is: every figure in
//! it is an aggregate of published rows.

use askama::Template;
use axum::Router;
use axum::extract::{RawQuery, State};
use axum::http::{HeaderValue, header};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::get;
use serde::Deserialize;

use super::AppState;
use super::error::{ApiError, PageError, RenderPage};
use super::extract::{Path, Query};
use super::i18n::Tr;
use crate::app::paper::{self, Paper, PaperOptions};
use crate::app::refusal::{Expected, Refusal};
use crate::core::dataset::StepLength;
use crate::core::paper::export::study_heatmap_names;
use crate::core::paper::hub::ReproducedCell;
use crate::core::paper::write::grouped;
use crate::core::paper::{Category, CellKey, Mark, Metric, PaperTable};

pub fn page_router() -> Router<AppState> {
    Router::new()
        .route("/datasets/{dataset}/paper", get(paper_page))
        .route("/datasets/{dataset}/paper.tar", get(paper_tar))
        .route("/datasets/{dataset}/paper/files/{file}", get(paper_file))
}

/// The page's choices, as its form sends them (every field optional).
#[derive(Debug, Default, Deserialize)]
struct PaperQuery {
    /// Comma-separated model names, in order.
    models: Option<String>,
    /// `ta`, `pa`, or empty for both.
    metric: Option<String>,
    intervals: Option<String>,
    /// `activities` (the default) or `items`.
    resample: Option<String>,
}

impl PaperQuery {
    fn options(&self) -> Result<PaperOptions, ApiError> {
        let models: Vec<String> = self
            .models
            .as_deref()
            .unwrap_or_default()
            .split(',')
            .map(str::trim)
            .filter(|m| !m.is_empty())
            .map(str::to_owned)
            .collect();
        let metrics = match self.metric.as_deref().unwrap_or_default() {
            "" => Metric::ALL.to_vec(),
            "ta" => vec![Metric::TaskAccuracy],
            "pa" => vec![Metric::PairwiseAccuracy],
            other => {
                return Err(
                    Refusal::bad_value("metric", other, Expected::OneOf(vec!["ta", "pa"])).into(),
                );
            }
        };
        Ok(PaperOptions {
            models: (!models.is_empty()).then_some(models),
            metrics,
            intervals: self.intervals.as_deref().is_some_and(|v| !v.is_empty()),
            resampling: super::compare::resample_param(self.resample.as_deref())?,
        })
    }
}

/// A printed cell.
struct CellView {
    value: String,
    interval: String,
    /// `first`, `second` or empty.
    mark: &'static str,
}

struct RowView {
    model: String,
    source: String,
    family: String,
    size: String,
    cells: Vec<CellView>,
}

struct GroupView {
    heading: String,
    rows: Vec<RowView>,
}

struct TableView {
    metric: &'static str,
    title: String,
    /// How the printed intervals were drawn; empty without intervals.
    intervals_note: String,
    groups: Vec<GroupView>,
    figure: String,
    figure_png: String,
}

/// A study's heat map on the page.
struct StudyFigureView {
    study: String,
    /// The row it is reported for.
    row: String,
    svg: String,
    png: String,
}

struct ReproductionView {
    model: String,
    metric: String,
    cell: String,
    reported: String,
    hub: String,
    difference: String,
    interval: String,
    /// `inside`, `outside` or empty (no interval).
    inside: &'static str,
    submission: Option<i64>,
}

#[derive(Template)]
#[template(path = "paper.html")]
struct PaperPage {
    tr: Tr,
    dataset: String,
    models: String,
    metric: String,
    intervals: bool,
    resample: String,
    /// The page's query, for the downloads and figures (empty or starting with `?`).
    query: String,
    step_lengths: Vec<u8>,
    tables: Vec<TableView>,
    /// The error-analysis figure's SVG and PNG addresses; `None` when no hub row is chosen.
    error_figure: Option<(String, String)>,
    studies: Vec<StudyFigureView>,
    reproduction: Vec<ReproductionView>,
}

fn heading(tr: &Tr, category: &Category) -> String {
    match category {
        Category::Proprietary => tr.t("paper-category-proprietary"),
        Category::OpenWeight => tr.t("paper-category-open-weight"),
        Category::Human => tr.t("paper-category-human"),
        Category::Named(name) => name.clone(),
    }
}

fn metric_title(tr: &Tr, metric: Metric) -> String {
    match metric {
        Metric::TaskAccuracy => tr.t("paper-task-accuracy"),
        Metric::PairwiseAccuracy => tr.t("paper-pairwise-accuracy"),
    }
}

fn table_view(tr: &Tr, dataset: &str, query: &str, table: &PaperTable) -> TableView {
    let groups = grouped(table)
        .into_iter()
        .map(|(category, rows)| GroupView {
            heading: heading(tr, category),
            rows: rows
                .into_iter()
                .map(|row| RowView {
                    model: row.model.clone(),
                    source: row.source.clone(),
                    family: row.family.clone().unwrap_or_default(),
                    size: row.size.clone().unwrap_or_default(),
                    cells: CellKey::all()
                        .map(|key| {
                            let cell = row.cells.get(&key);
                            CellView {
                                value: cell
                                    .and_then(|c| c.value)
                                    .map_or_else(|| "–".to_owned(), |v| format!("{v:.2}")),
                                interval: cell
                                    .and_then(|c| c.interval)
                                    .map_or_else(String::new, |(low, high)| {
                                        format!("[{low:.2}, {high:.2}]")
                                    }),
                                mark: match cell.and_then(|c| c.mark) {
                                    Some(Mark::First) => "first",
                                    Some(Mark::Second) => "second",
                                    None => "",
                                },
                            }
                        })
                        .collect(),
                })
                .collect(),
        })
        .collect();
    let base = format!(
        "/datasets/{}/paper/files/{}_by_step_length",
        // Dataset names are letters, digits, `.`, `_` and `-`: safe in a path as they are.
        dataset,
        table.metric.as_str()
    );
    let printed = table
        .rows
        .iter()
        .any(|r| r.cells.values().any(|c| c.interval.is_some()));
    TableView {
        intervals_note: match table.intervals {
            Some(resampling) if printed => tr.t_s(
                "intervals-note",
                "resampling",
                super::compare::resampling_text(tr, resampling),
            ),
            _ => String::new(),
        },
        metric: table.metric.as_str(),
        title: metric_title(tr, table.metric),
        groups,
        figure: format!("{base}.svg{query}"),
        figure_png: format!("{base}.png{query}"),
    }
}

fn reproduction_view(tr: &Tr, cell: &ReproducedCell) -> ReproductionView {
    ReproductionView {
        model: cell.model.clone(),
        metric: metric_title(tr, cell.metric),
        cell: cell.cell.to_string(),
        reported: format!("{:.2}", cell.reported),
        hub: format!("{:.2}", cell.hub),
        difference: format!("{:+.2}", cell.difference),
        interval: cell
            .interval
            .map_or_else(String::new, |(low, high)| format!("[{low:.2}, {high:.2}]")),
        inside: match cell.inside {
            Some(true) => "inside",
            Some(false) => "outside",
            None => "",
        },
        submission: cell.submission,
    }
}

fn page_query(raw: Option<&str>) -> String {
    raw.filter(|q| !q.is_empty())
        .map_or_else(String::new, |q| format!("?{q}"))
}

async fn made(state: &AppState, dataset: &str, query: &PaperQuery) -> Result<Paper, ApiError> {
    paper::paper(&state.hub, dataset, &query.options()?)
        .await
        .map_err(ApiError)
}

async fn paper_page(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    Query(query): Query<PaperQuery>,
    RawQuery(raw): RawQuery,
    tr: Tr,
) -> Result<Html<String>, PageError> {
    let paper = made(&state, &dataset, &query).await?;
    let query_text = page_query(raw.as_deref());
    let page = PaperPage {
        tables: paper
            .tables
            .iter()
            .map(|t| table_view(&tr, &paper.dataset, &query_text, &t.table))
            .collect(),
        reproduction: paper
            .reproduction
            .iter()
            .map(|c| reproduction_view(&tr, c))
            .collect(),
        error_figure: (!paper.error_analyses.is_empty()).then(|| {
            let base = format!("/datasets/{}/paper/files/error_analysis", paper.dataset);
            (
                format!("{base}.svg{query_text}"),
                format!("{base}.png{query_text}"),
            )
        }),
        studies: paper
            .studies
            .iter()
            .map(|f| {
                let [svg, png] = study_heatmap_names(&f.study);
                let base = format!("/datasets/{}/paper/files", paper.dataset);
                StudyFigureView {
                    study: f.study.clone(),
                    row: f.report.stamp.row.clone(),
                    svg: format!("{base}/{svg}{query_text}"),
                    png: format!("{base}/{png}{query_text}"),
                }
            })
            .collect(),
        step_lengths: StepLength::all().map(StepLength::get).collect(),
        models: query.models.clone().unwrap_or_default(),
        metric: query.metric.clone().unwrap_or_default(),
        intervals: query.intervals.as_deref().is_some_and(|v| !v.is_empty()),
        resample: query.resample.clone().unwrap_or_default(),
        query: query_text,
        dataset: paper.dataset,
        tr,
    };
    Ok(Html(page.render_page()?))
}

/// `enact-hub-paper-{dataset}`, safe as a file name and header value.
fn folder(dataset: &str) -> String {
    format!("enact-hub-paper-{}", super::file_name_safe(dataset))
}

async fn paper_tar(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    Query(query): Query<PaperQuery>,
) -> Result<Response, ApiError> {
    let paper = made(&state, &dataset, &query).await?;
    let folder = folder(&paper.dataset);
    super::archive::bundle_download(&folder, &paper.files(true)?)
}

fn media_type(file: &str) -> &'static str {
    match file.rsplit_once('.').map(|(_, ext)| ext) {
        Some("svg") => "image/svg+xml",
        Some("png") => "image/png",
        Some("json") => "application/json",
        Some("csv") => "text/csv; charset=utf-8",
        Some("md") => "text/markdown; charset=utf-8",
        Some("tex") => "application/x-tex; charset=utf-8",
        _ => "application/octet-stream",
    }
}

async fn paper_file(
    State(state): State<AppState>,
    Path((dataset, file)): Path<(String, String)>,
    Query(query): Query<PaperQuery>,
) -> Result<Response, ApiError> {
    let paper = made(&state, &dataset, &query).await?;
    let files = paper.files(true)?;
    let names: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
    let Some(found) = files.iter().find(|f| f.name == file) else {
        return Err(Refusal::NoPaperFile {
            dataset: paper.dataset.clone(),
            file,
            files: names.join(", "),
        }
        .into());
    };
    Ok((
        [(
            header::CONTENT_TYPE,
            HeaderValue::from_static(media_type(&found.name)),
        )],
        found.bytes.clone(),
    )
        .into_response())
}
