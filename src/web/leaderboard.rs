//! The leaderboard as JSON (`/api/v1/datasets/{dataset}/leaderboard`) and as a page with its
//! chart (`/leaderboard/{dataset}`).

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::response::Html;
use axum::routing::get;
use serde::Serialize;

use super::error::PageError;
use super::extract::{Json, Path};
use super::openapi::{ApiRoute, Verb};
use super::{AppError, AppState};
use crate::app::leaderboard;
use crate::core::dataset::StepLength;
use crate::core::leaderboard::{AccuracyCell, AccuracyChart, Interval, LeaderboardRow};

pub fn api_routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Get,
            "/datasets/{dataset}/leaderboard",
            leaderboard_json,
            "The leaderboard",
        )
        .describe(
            "One row per published submission, best overall TA first: TA and PA overall, \
             forward, inverse and per step length 3..10, 95% bootstrap intervals, coverage and \
             date; a Human row when annotations exist. The HTML page is /leaderboard/{dataset}.",
        )
        .responds(200, Some("application/json"), "The rows.")
        .errors(&[404]),
    ]
}

pub fn page_router() -> Router<AppState> {
    Router::new().route("/leaderboard/{dataset}", get(leaderboard_page))
}

#[derive(Serialize)]
struct LeaderboardView {
    dataset: String,
    policy: &'static str,
    step_lengths: Vec<u8>,
    rows: Vec<LeaderboardRow>,
}

async fn leaderboard_json(
    State(state): State<AppState>,
    Path(name): Path<String>,
) -> Result<Json<LeaderboardView>, AppError> {
    let (dataset, rows) = leaderboard::of(&state.hub, &name).await?;
    Ok(Json(LeaderboardView {
        dataset: dataset.name,
        policy: "strict",
        step_lengths: StepLength::all().map(StepLength::get).collect(),
        rows,
    }))
}

/// One TA/PA pair as the table prints it.
struct CellText {
    ta: String,
    pa: String,
}

fn percent(v: Option<f64>) -> String {
    v.map_or_else(|| "–".to_owned(), |v| format!("{:.1}", v * 100.0))
}

fn cell_text(c: &AccuracyCell) -> CellText {
    CellText {
        ta: percent(c.task_accuracy),
        pa: percent(c.pairwise_accuracy),
    }
}

fn interval_text(i: Option<Interval>) -> String {
    i.map_or_else(String::new, |i| {
        format!("{:.1}–{:.1}", i.low * 100.0, i.high * 100.0)
    })
}

struct RowText {
    rank: usize,
    model: String,
    account: String,
    baseline: bool,
    submitted_on: String,
    overall: CellText,
    ta_ci: String,
    pa_ci: String,
    forward: CellText,
    inverse: CellText,
    forward_steps: Vec<CellText>,
    inverse_steps: Vec<CellText>,
    coverage: String,
    parse_failures: String,
}

#[derive(Template)]
#[template(path = "leaderboard.html")]
struct LeaderboardPage {
    dataset: String,
    step_lengths: Vec<u8>,
    rows: Vec<RowText>,
    chart: AccuracyChart,
}

async fn leaderboard_page(
    State(state): State<AppState>,
    Path(name): Path<String>,
) -> Result<Html<String>, PageError> {
    let (dataset, rows) = leaderboard::of(&state.hub, &name).await?;
    let chart = AccuracyChart::task_accuracy_by_step_length(&rows);
    let texts = rows
        .iter()
        .enumerate()
        .map(|(i, r)| RowText {
            rank: i + 1,
            model: r.model.clone(),
            account: r.account.clone(),
            baseline: r.baseline,
            submitted_on: r
                .submitted_at
                .get(..10)
                .unwrap_or(&r.submitted_at)
                .to_owned(),
            overall: cell_text(&r.overall),
            ta_ci: interval_text(r.overall_task_accuracy_ci),
            pa_ci: interval_text(r.overall_pairwise_accuracy_ci),
            forward: cell_text(&r.forward.total),
            inverse: cell_text(&r.inverse.total),
            forward_steps: r
                .forward
                .per_step
                .iter()
                .map(|(_, c)| cell_text(c))
                .collect(),
            inverse_steps: r
                .inverse
                .per_step
                .iter()
                .map(|(_, c)| cell_text(c))
                .collect(),
            coverage: format!("{:.1}%", r.coverage * 100.0),
            parse_failures: format!("{:.1}%", r.parse_failure_rate * 100.0),
        })
        .collect();
    let page = LeaderboardPage {
        dataset: dataset.name,
        step_lengths: StepLength::all().map(StepLength::get).collect(),
        rows: texts,
        chart,
    };
    Ok(Html(page.render()?))
}
