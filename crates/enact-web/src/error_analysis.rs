//! Error analysis over HTTP: a submission's analysis as JSON (owner or admin), the published
//! rows of a dataset side by side as JSON, and the two pages (all rows compared; one row with
//! its examples).

use crate::core::error_analysis::ErrorAnalysis;
use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::response::Html;
use axum::routing::get;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::json;

use super::auth::TokenCaller;
use super::error::{ApiError, PageError, RenderPage};
use super::extract::{Json, Path, Query};
use super::i18n::{Tr, msg};
use super::openapi::{ApiRoute, Verb};
use super::session::ReaderIsAdmin;
use super::{AppError, AppState};
use crate::app::error_analysis::{self, Analysed, ComparedRow};
use crate::app::refusal::{Expected, Refusal};
use crate::core::credentials::Scope;
use crate::core::error_analysis::chart::{self, BarChart, ChartNames};
use crate::core::error_analysis::{
    ErrorExample, ErrorFigures, Hand, HandFigures, SemanticCategory, StructuralClass,
};
use crate::core::verifier::Direction;

/// Rows compared by default: the top of the board, as on its chart.
const DEFAULT_ROWS: usize = 8;

pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Get,
            "/submissions/{id}/errors",
            submission_errors,
            "A submission's error analysis",
        )
        .describe(
            "The paper's error analysis of the submission's answers: per step, the predicted \
             state changes against the true ones, components matched or classed as polarity \
             inversion, predicate substitution, entity substitution, omission or \
             hallucination (`structural`), by semantic category (`semantic`), left- and \
             right-hand precision, recall and mixing with standard errors (`handedness`), \
             accepted-but-incomplete rates, and the same `by_direction`. Only answers of the \
             right length are analysed; `excluded_*` count the others. `examples` (true and \
             predicted changes as sentences) only when the dataset's answers are public; \
             otherwise `examples_withheld` says why. Same JSON as `enact-hub errors --json`.",
        )
        .bearer(Scope::ReadOwn)
        .responds_json::<AnalysisJson>(200, "The analysis.")
        .errors(&[401, 403, 404]),
        ApiRoute::new(
            Verb::Get,
            "/datasets/{dataset}/errors",
            dataset_errors,
            "Error analyses of a leaderboard",
        )
        .describe(
            "The error analysis of each published leaderboard row in board order (the top 8 \
             by default), then the Human row once annotators have answered. Examples only for \
             datasets whose answers are public. The page is /leaderboard/{dataset}/errors.",
        )
        .query_with(
            "top",
            false,
            json!({"type": "integer", "minimum": 1, "maximum": 50}),
            "How many ranked rows, 1 to 50 (default 8).",
        )
        .query_with(
            "pick",
            false,
            json!({"type": "string", "pattern": "^([0-9]{1,18}(,[0-9]{1,18})*)?$"}),
            "Comma-separated submission ids to compare instead.",
        )
        .responds_json::<ComparisonJson>(200, "`dataset` and `rows`.")
        .errors(&[400, 404]),
    ]
}

pub fn page_router() -> Router<AppState> {
    Router::new()
        .route("/leaderboard/{dataset}/errors", get(comparison_page))
        .route("/leaderboard/{dataset}/errors/{entry}", get(row_page))
}

/// The analysis as served, with `examples_withheld` when examples were removed.
#[derive(Serialize, JsonSchema)]
struct AnalysisJson {
    #[serde(flatten)]
    analysis: ErrorAnalysis,
    #[serde(skip_serializing_if = "Option::is_none")]
    examples_withheld: Option<String>,
}

impl From<&Analysed> for AnalysisJson {
    fn from(analysed: &Analysed) -> Self {
        AnalysisJson {
            analysis: analysed.analysis.clone(),
            examples_withheld: analysed.withheld.clone(),
        }
    }
}

async fn submission_errors(
    State(state): State<AppState>,
    Path(id): Path<String>,
    TokenCaller(caller): TokenCaller,
) -> Result<Json<AnalysisJson>, ApiError> {
    let (_, analysed) = error_analysis::of_submission(&state.hub, &caller, &id).await?;
    Ok(Json(AnalysisJson::from(&analysed)))
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct CompareQuery {
    top: Option<usize>,
    pick: Option<String>,
    direction: Option<String>,
}

impl CompareQuery {
    fn top(&self) -> Result<usize, ApiError> {
        match self.top {
            None => Ok(DEFAULT_ROWS),
            Some(n @ 1..=50) => Ok(n),
            Some(n) => Err(Refusal::bad_value(
                "top",
                n.to_string(),
                Expected::WholeNumber { least: 1, most: 50 },
            )
            .into()),
        }
    }

    fn picked(&self) -> Result<Vec<i64>, AppError> {
        let Some(text) = self.pick.as_deref().filter(|t| !t.is_empty()) else {
            return Ok(Vec::new());
        };
        text.split(',')
            .map(|id| {
                id.trim().parse().map_err(|_| {
                    AppError::from(Refusal::bad_value(
                        "pick",
                        id.trim(),
                        Expected::SubmissionId,
                    ))
                })
            })
            .collect()
    }

    fn direction(&self) -> Result<Option<Direction>, ApiError> {
        match self.direction.as_deref() {
            None | Some("" | "overall") => Ok(None),
            Some("forward") => Ok(Some(Direction::Forward)),
            Some("inverse") => Ok(Some(Direction::Inverse)),
            Some(other) => Err(Refusal::bad_value(
                "direction",
                other,
                Expected::OneOf(vec!["overall", "forward", "inverse"]),
            )
            .into()),
        }
    }
}

#[derive(Serialize, JsonSchema)]
struct ComparedJson {
    submission: Option<i64>,
    label: String,
    account: String,
    baseline: bool,
    analysis: AnalysisJson,
}

#[derive(Serialize, JsonSchema)]
struct ComparisonJson {
    dataset: String,
    rows: Vec<ComparedJson>,
}

async fn dataset_errors(
    State(state): State<AppState>,
    Path(name): Path<String>,
    Query(query): Query<CompareQuery>,
) -> Result<Json<ComparisonJson>, ApiError> {
    let (dataset, rows) =
        error_analysis::comparison(&state.hub, &name, query.top()?, &query.picked()?, false)
            .await?;
    let rows: Vec<ComparedJson> = rows
        .iter()
        .map(|r| ComparedJson {
            submission: r.submission,
            label: r.label.clone(),
            account: r.account.clone(),
            baseline: r.baseline,
            analysis: AnalysisJson::from(&r.analysis),
        })
        .collect();
    Ok(Json(ComparisonJson {
        dataset: dataset.name,
        rows,
    }))
}

/// One table line of figures.
struct FigureRow {
    label: String,
    href: Option<String>,
    analysed: usize,
    excluded: usize,
    errors: usize,
    /// Per structural class: "12.4% (37)".
    structural: Vec<String>,
    /// Per semantic category.
    semantic: Vec<String>,
    /// Left precision, recall, mixing, then right: "0.812 ± 0.021".
    hands: Vec<String>,
    data_level: String,
    pair_level: String,
}

fn share(n: usize, of: usize) -> String {
    if of == 0 {
        "–".to_owned()
    } else {
        format!("{:.1}% ({n})", 100.0 * n as f64 / of as f64)
    }
}

fn rate(value: Option<f64>) -> String {
    value.map_or("–".to_owned(), |v| format!("{:.2}%", v * 100.0))
}

fn figure_row(label: String, href: Option<String>, f: &ErrorFigures) -> FigureRow {
    let hand = |h: &HandFigures| {
        [
            (h.precision, h.precision_se),
            (h.recall, h.recall_se),
            (h.mixing, h.mixing_se),
        ]
        .map(|(v, se)| match (v, se) {
            (Some(v), Some(se)) => format!("{v:.3} ± {se:.3}"),
            _ => "–".to_owned(),
        })
    };
    let mut hands = hand(&f.handedness.left).to_vec();
    hands.extend(hand(&f.handedness.right));
    FigureRow {
        label,
        href,
        analysed: f.analysed_answers,
        excluded: f.excluded_unequal_length
            + f.excluded_unreadable
            + f.excluded_missing
            + f.excluded_without_signatures,
        errors: f.errors,
        structural: StructuralClass::ALL
            .iter()
            .map(|c| share(f.structural.get(*c), f.errors))
            .collect(),
        semantic: SemanticCategory::ALL
            .iter()
            .map(|c| share(f.semantic.get(*c).total, f.errors))
            .collect(),
        hands,
        data_level: rate(f.accepted_incomplete.data_level),
        pair_level: rate(f.accepted_incomplete.pair_level),
    }
}

fn figures(analysed: &Analysed, direction: Option<Direction>) -> &ErrorFigures {
    match direction {
        None => &analysed.analysis.overall,
        Some(d) => analysed.analysis.direction(d),
    }
}

/// The message key of a structural class (the paper's taxonomy).
fn structural_key(class: StructuralClass) -> &'static str {
    match class {
        StructuralClass::PolarityInversion => msg("errors-polarity-inversion"),
        StructuralClass::PredicateSubstitution => msg("errors-predicate-substitution"),
        StructuralClass::EntitySubstitution => msg("errors-entity-substitution"),
        StructuralClass::Omission => msg("errors-omission"),
        StructuralClass::Hallucination => msg("errors-hallucination"),
    }
}

/// The message key of a semantic category.
fn semantic_key(category: SemanticCategory) -> &'static str {
    match category {
        SemanticCategory::SpatialRelations => msg("errors-spatial-relations"),
        SemanticCategory::FunctionalStates => msg("errors-functional-states"),
        SemanticCategory::MaterialStates => msg("errors-material-states"),
        SemanticCategory::AgentInteraction => msg("errors-agent-interaction"),
    }
}

/// The names of the classes, categories and hand measures in the reader's language: the
/// tables' column headings and the charts' labels and legends.
fn headings(tr: &Tr) -> ChartNames {
    let mut hands = Vec::new();
    for h in Hand::BOTH {
        let hand = tr.t(match h {
            Hand::Left => msg("errors-hand-left"),
            Hand::Right => msg("errors-hand-right"),
        });
        for m in [
            msg("errors-precision"),
            msg("errors-recall"),
            msg("errors-mixing"),
        ] {
            hands.push(format!("{hand} {}", tr.t(m)));
        }
    }
    ChartNames {
        structural: StructuralClass::ALL
            .iter()
            .map(|c| tr.t(structural_key(*c)))
            .collect(),
        semantic: SemanticCategory::ALL
            .iter()
            .map(|c| tr.t(semantic_key(*c)))
            .collect(),
        hands,
    }
}

/// The message key of a direction link, or of the rows of all directions.
fn direction_link_key(direction: &str) -> &'static str {
    match direction {
        "forward" => msg("direction-forward"),
        "inverse" => msg("direction-inverse"),
        _ => msg("errors-overall"),
    }
}

#[derive(Template)]
#[template(path = "errors.html")]
struct ComparisonPage {
    tr: Tr,
    dataset: String,
    direction: String,
    links: Vec<(String, String, bool)>,
    headings: ChartNames,
    rows: Vec<FigureRow>,
    structural: BarChart,
    semantic: BarChart,
    hands: BarChart,
    withheld: Option<String>,
}

fn direction_name(direction: Option<Direction>) -> &'static str {
    direction.map_or("overall", Direction::as_str)
}

async fn comparison_page(
    State(state): State<AppState>,
    Path(name): Path<String>,
    Query(query): Query<CompareQuery>,
    ReaderIsAdmin(admin): ReaderIsAdmin,
    tr: Tr,
) -> Result<Html<String>, PageError> {
    let direction = query.direction()?;
    let (dataset, rows) =
        error_analysis::comparison(&state.hub, &name, query.top()?, &query.picked()?, admin)
            .await?;
    let base = format!("/leaderboard/{}/errors", dataset.name);
    let label = |r: &ComparedRow| match r.submission {
        Some(id) => format!("{} (#{id})", r.label),
        None => r.label.clone(),
    };
    let entry = |r: &ComparedRow| {
        r.submission
            .map_or_else(|| "human".to_owned(), |id| id.to_string())
    };
    let labels: Vec<String> = rows.iter().map(label).collect();
    let drawn: Vec<(&str, &ErrorFigures)> = rows
        .iter()
        .zip(&labels)
        .map(|(r, l)| (l.as_str(), figures(&r.analysis, direction)))
        .collect();
    let keep = |d: &str| {
        let mut q = vec![format!("direction={d}")];
        if let Some(top) = query.top {
            q.push(format!("top={top}"));
        }
        if let Some(pick) = &query.pick {
            q.push(format!("pick={pick}"));
        }
        format!("{base}?{}", q.join("&"))
    };
    let headings = headings(&tr);
    let page = ComparisonPage {
        dataset: dataset.name.clone(),
        direction: tr.t(direction_link_key(direction_name(direction))),
        links: ["overall", "forward", "inverse"]
            .into_iter()
            .map(|d| {
                (
                    tr.t(direction_link_key(d)),
                    keep(d),
                    d == direction_name(direction),
                )
            })
            .collect(),
        rows: rows
            .iter()
            .zip(&labels)
            .map(|(r, l)| {
                figure_row(
                    l.clone(),
                    Some(format!("{base}/{}", entry(r))),
                    figures(&r.analysis, direction),
                )
            })
            .collect(),
        structural: chart::structural_chart(&drawn, &headings),
        semantic: chart::semantic_chart(&drawn, &headings),
        hands: chart::hand_chart(&drawn, &headings),
        headings,
        withheld: rows
            .iter()
            .any(|r| r.analysis.withheld.is_some())
            .then(|| tr.t_s("errors-examples-withheld", "dataset", &dataset.name)),
        tr,
    };
    Ok(Html(page.render_page()?))
}

/// Examples of one semantic category, per structural class.
struct ExampleGroup {
    category: String,
    examples: Vec<ExampleLine>,
}

struct ExampleLine {
    class: String,
    item: String,
    href: String,
    direction: String,
    step: usize,
    truth: String,
    predicted: String,
}

#[derive(Template)]
#[template(path = "errors_row.html")]
struct RowPage {
    tr: Tr,
    dataset: String,
    label: String,
    headings: ChartNames,
    rows: Vec<FigureRow>,
    structural: BarChart,
    semantic: BarChart,
    hands: BarChart,
    examples: Vec<ExampleGroup>,
    withheld: Option<String>,
}

fn example_groups(tr: &Tr, dataset: &str, examples: &[ErrorExample]) -> Vec<ExampleGroup> {
    let mut groups: Vec<ExampleGroup> = SemanticCategory::ALL
        .iter()
        .map(|c| ExampleGroup {
            category: tr.t(semantic_key(*c)),
            examples: Vec::new(),
        })
        .collect();
    for e in examples {
        let Some(category) = e.category else { continue };
        groups[category.index()].examples.push(ExampleLine {
            class: tr.t(structural_key(e.class)),
            item: e.item.clone(),
            href: format!("/datasets/{dataset}/items/{}", e.item),
            direction: tr.t(super::annotate::direction_key(e.direction)),
            step: e.step,
            truth: e
                .truth
                .as_ref()
                .map_or("–".to_owned(), |c| c.sentence.clone()),
            predicted: e
                .predicted
                .as_ref()
                .map_or("–".to_owned(), |c| c.sentence.clone()),
        });
    }
    groups.retain(|g| !g.examples.is_empty());
    groups
}

async fn row_page(
    State(state): State<AppState>,
    Path((name, entry)): Path<(String, String)>,
    ReaderIsAdmin(admin): ReaderIsAdmin,
    tr: Tr,
) -> Result<Html<String>, PageError> {
    let picked: Vec<i64> = match entry.as_str() {
        "human" => Vec::new(),
        id => vec![id.parse().map_err(|_| {
            AppError::NotFound(format!(
                "no published row {id} on the leaderboard of '{name}': use a submission id \
                 or `human`"
            ))
        })?],
    };
    let (dataset, rows) = error_analysis::comparison(&state.hub, &name, 0, &picked, admin).await?;
    let row = rows
        .into_iter()
        .find(|r| match (entry.as_str(), r.submission) {
            ("human", None) => true,
            (_, Some(id)) => picked.contains(&id),
            _ => false,
        })
        .ok_or_else(|| {
            AppError::NotFound(format!(
                "no published row {entry} on the leaderboard of '{}'{}",
                dataset.name,
                if entry == "human" {
                    " (nobody has answered yet)"
                } else {
                    ""
                }
            ))
        })?;
    let label = match row.submission {
        Some(id) => format!("{} (#{id})", row.label),
        None => row.label.clone(),
    };
    let a = &row.analysis.analysis;
    let groups = [
        ("overall", &a.overall),
        ("forward", &a.by_direction.forward),
        ("inverse", &a.by_direction.inverse),
    ];
    let directions: Vec<String> = groups[1..]
        .iter()
        .map(|(g, _)| tr.t(direction_link_key(g)))
        .collect();
    let drawn: Vec<(&str, &ErrorFigures)> = directions
        .iter()
        .zip(&groups[1..])
        .map(|(name, (_, f))| (name.as_str(), *f))
        .collect();
    let headings = headings(&tr);
    let page = RowPage {
        dataset: dataset.name.clone(),
        label,
        rows: groups
            .iter()
            .map(|(g, f)| figure_row(tr.t(direction_link_key(g)), None, f))
            .collect(),
        structural: chart::structural_chart(&drawn, &headings),
        semantic: chart::semantic_chart(&drawn, &headings),
        hands: chart::hand_chart(&drawn, &headings),
        headings,
        examples: example_groups(&tr, &dataset.name, &a.examples),
        // The API's English reason, in the reader's language.
        withheld: row
            .analysis
            .withheld
            .as_ref()
            .map(|_| tr.t_s("errors-examples-withheld", "dataset", &dataset.name)),
        tr,
    };
    Ok(Html(page.render_page()?))
}
