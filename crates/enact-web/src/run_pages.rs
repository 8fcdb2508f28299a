//! The admin pages of model runs: `/admin/runs` lists every run (started on the server or by
//! the CLI) with a form to start one; `/admin/runs/{run}` shows a run's progress, kept live by
//! `static/run_progress.js` polling `/admin/runs/{run}/progress` (the run's API view, for the
//! session's admin), its pause, resume and cancel buttons, and its per-item responses a page
//! at a time. `/runs/{run}` shows the responses to anyone when the run's dataset has public
//! answers. Both offer the answers as ENACT's model-output JSONL.

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::response::{Html, IntoResponse, Redirect, Response};
use axum::routing::{get, post};
use serde::Deserialize;

use super::AppState;
use super::error::{ApiError, PageError, RenderPage};
use super::extract::{Path, Query};
use super::runs::{MOST_CONCURRENCY, MOST_U32, MOST_WHOLE, RunRequest, responses_download, whole};
use super::session::{Admin, Protected};
use crate::app::datasets;
use crate::app::jobs::JobControl;
use crate::app::refusal::{Expected, Refusal};
use crate::app::runs::{self, Audience, ResponsePage, RunItemRow, ServerRunView};
use crate::core::annotation::Session;

/// The admin pages (behind the admin pages' gate, `web::admin_pages`).
pub fn admin_router() -> Router<AppState> {
    Router::new()
        .route("/admin/runs", get(runs_page).post(start))
        .route("/admin/runs/{run}", get(run_page))
        .route("/admin/runs/{run}/progress", get(progress))
        .route("/admin/runs/{run}/control", post(control))
        .route("/admin/runs/{run}/responses.jsonl", get(admin_download))
}

/// The public pages.
pub fn page_router() -> Router<AppState> {
    Router::new()
        .route("/runs/{run}", get(public_page))
        .route("/runs/{run}/responses.jsonl", get(public_download))
}

/// A run's row in the list.
struct RunListed {
    id: i64,
    name: String,
    dataset: String,
    model: String,
    endpoint: String,
    state: String,
    done: String,
    created_at: String,
}

#[derive(Template)]
#[template(path = "admin_runs.html")]
struct RunsPage {
    name: String,
    csrf: String,
    runs: Vec<RunListed>,
    datasets: Vec<String>,
    /// The environment variables a run may take its key from (names only).
    key_variables: Vec<String>,
    notice: Option<String>,
}

/// What the page shows of a job's progress, formatted as `run_progress.js` formats it.
struct ProgressShown {
    stage: String,
    done: String,
    answered: String,
    failed: String,
    in_flight: String,
    items_per_s: String,
    eta: String,
    tokens: String,
    cost: String,
    recent_errors: Vec<String>,
}

/// Seconds as "1 h 02 min", "3 min 05 s" or "12 s".
fn duration(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    match (s / 3600, s % 3600 / 60, s % 60) {
        (0, 0, s) => format!("{s} s"),
        (0, m, s) => format!("{m} min {s:02} s"),
        (h, m, _) => format!("{h} h {m:02} min"),
    }
}

fn progress_shown(view: &ServerRunView) -> ProgressShown {
    let p = view.progress.clone().unwrap_or_default();
    ProgressShown {
        stage: match (&view.state, &view.progress) {
            (Some(state), Some(p)) if p.stage.as_str() != state => {
                format!("{state} ({})", p.stage.as_str())
            }
            (Some(state), _) => state.clone(),
            (None, _) => "not started on the server".to_owned(),
        },
        done: format!("{} of {}", p.done, p.total),
        answered: p.answered.to_string(),
        failed: p.failed.to_string(),
        in_flight: p.in_flight.to_string(),
        items_per_s: format!("{:.2}", p.items_per_s),
        eta: p.eta_s.map_or_else(|| "–".to_owned(), duration),
        tokens: format!("{} in, {} out", p.prompt_tokens, p.completion_tokens),
        cost: format!("${:.4}", p.cost_usd),
        recent_errors: p.recent_errors,
    }
}

/// A response's row in the table.
struct ResponseShown {
    item: String,
    outcome: &'static str,
    /// Why a failed item failed, in words; empty when answered.
    failure: String,
    finish_reason: String,
    tokens: String,
    latency_ms: i64,
    attempts: i64,
    error: String,
    response: String,
}

fn responses_shown(rows: &[RunItemRow]) -> Vec<ResponseShown> {
    rows.iter()
        .map(|r| ResponseShown {
            item: r.item_id.clone(),
            outcome: if r.outcome.is_answered() {
                "answered"
            } else {
                "failed"
            },
            failure: r
                .outcome
                .failure()
                .map(|f| f.to_string())
                .unwrap_or_default(),
            finish_reason: r.finish_reason.clone().unwrap_or_default(),
            tokens: format!("{} / {}", r.prompt_tokens, r.completion_tokens),
            latency_ms: r.latency_ms,
            attempts: r.attempts,
            error: r.error.clone().unwrap_or_default(),
            response: r.response.clone().unwrap_or_default(),
        })
        .collect()
}

#[derive(Template)]
#[template(path = "admin_run.html")]
struct RunPage {
    name: String,
    csrf: String,
    run: ServerRunView,
    progress: ProgressShown,
    /// Which of pause, resume and cancel apply to the run's job now.
    can_pause: bool,
    can_resume: bool,
    can_cancel: bool,
    responses: Vec<ResponseShown>,
    /// This page's path, for the pager.
    base: String,
    page: i64,
    pages: i64,
    total: i64,
    notice: Option<String>,
}

#[derive(Template)]
#[template(path = "run_responses.html")]
struct PublicRunPage {
    run: crate::app::runs::RunRow,
    responses: Vec<ResponseShown>,
    base: String,
    page: i64,
    pages: i64,
    total: i64,
}

#[derive(Deserialize)]
struct PageQuery {
    #[serde(default)]
    page: Option<i64>,
}

async fn render_list(
    state: &AppState,
    session: Session,
    notice: Option<String>,
) -> Result<Html<String>, PageError> {
    let views = runs::views(&state.hub).await?;
    let datasets = datasets::overview(&state.hub)
        .await?
        .into_iter()
        .map(|o| o.dataset.name)
        .collect();
    let page = RunsPage {
        name: session.name,
        csrf: session.csrf_token,
        runs: views
            .iter()
            .map(|v| RunListed {
                id: v.id,
                name: v.name.clone(),
                dataset: v.dataset.clone(),
                model: v.model.clone(),
                endpoint: v.endpoint.clone(),
                state: match (&v.state, v.submission) {
                    (Some(state), _) => state.clone(),
                    (None, Some(s)) => format!("submitted (submission {s})"),
                    (None, None) => "CLI run".to_owned(),
                },
                done: progress_shown(v).done,
                created_at: v.created_at.clone(),
            })
            .collect(),
        datasets,
        key_variables: state
            .hub
            .kept::<crate::app::runs::EndpointKeys>()
            .names()
            .map(str::to_owned)
            .collect(),
        notice,
    };
    Ok(Html(page.render_page()?))
}

async fn runs_page(
    State(state): State<AppState>,
    Admin(session): Admin,
) -> Result<Html<String>, PageError> {
    render_list(&state, session, None).await
}

/// The start form: every field as text, empty meaning the default.
#[derive(Deserialize)]
struct StartForm {
    #[serde(default)]
    dataset: String,
    #[serde(default)]
    endpoint: String,
    #[serde(default)]
    model: String,
    #[serde(default)]
    name: String,
    #[serde(default)]
    temperature: String,
    #[serde(default)]
    max_tokens: String,
    #[serde(default)]
    limit: String,
    #[serde(default)]
    submit_as: String,
    #[serde(default)]
    price_input: String,
    #[serde(default)]
    price_output: String,
    #[serde(default)]
    key_variable: String,
    #[serde(default)]
    concurrency: String,
    #[serde(default)]
    max_retries: String,
    #[serde(default)]
    timeout_s: String,
    #[serde(default)]
    retry_failed: Option<String>,
}

/// A form field's number, `None` when left empty.
fn optional<T: std::str::FromStr>(
    field: &str,
    text: &str,
    expected: Expected,
) -> Result<Option<T>, ApiError> {
    let text = text.trim();
    if text.is_empty() {
        return Ok(None);
    }
    text.parse()
        .map(Some)
        .map_err(|_| Refusal::bad_value(field, text, expected))
        .map_err(ApiError::from)
}

fn text(value: &str) -> Option<String> {
    Some(value.trim().to_owned()).filter(|v| !v.is_empty())
}

impl StartForm {
    fn request(self) -> Result<RunRequest, ApiError> {
        Ok(RunRequest {
            temperature: optional("temperature", &self.temperature, Expected::Number)?,
            max_tokens: optional("max tokens", &self.max_tokens, whole(0, MOST_U32))?,
            limit: optional("limit", &self.limit, whole(1, MOST_WHOLE))?,
            price_input: optional("input price", &self.price_input, Expected::Number)?
                .unwrap_or(0.0),
            price_output: optional("output price", &self.price_output, Expected::Number)?
                .unwrap_or(0.0),
            concurrency: optional("concurrency", &self.concurrency, whole(1, MOST_CONCURRENCY))?,
            max_retries: optional("max retries", &self.max_retries, whole(0, MOST_U32))?,
            timeout_s: optional("timeout", &self.timeout_s, Expected::Number)?,
            dataset: self.dataset.trim().to_owned(),
            endpoint: self.endpoint.trim().to_owned(),
            model: self.model.trim().to_owned(),
            name: text(&self.name),
            submit_as: text(&self.submit_as),
            key_variable: text(&self.key_variable),
            retry_failed: self.retry_failed.is_some(),
        })
    }
}

async fn start(
    State(state): State<AppState>,
    request: Protected<StartForm>,
) -> Result<Response, PageError> {
    let (spec, calls) = request.body.request()?.into_run()?;
    let (run, _) = runs::start(&state.hub, &request.session.actor(), &spec, &calls).await?;
    Ok(Redirect::to(&format!("/admin/runs/{}", run.id)).into_response())
}

async fn render_run(
    state: &AppState,
    session: Session,
    id: i64,
    page: i64,
    notice: Option<String>,
) -> Result<Html<String>, PageError> {
    let view = runs::view(&state.hub, id).await?;
    let responses: ResponsePage =
        runs::response_page(&state.hub, id, Audience::Admin, page).await?;
    let state_is = |states: &[&str]| view.state.as_deref().is_some_and(|s| states.contains(&s));
    let page = RunPage {
        name: session.name,
        csrf: session.csrf_token,
        progress: progress_shown(&view),
        can_pause: state_is(&["queued", "running"]),
        can_resume: state_is(&["paused", "failed"]),
        can_cancel: state_is(&["queued", "running", "paused"]),
        base: format!("/admin/runs/{}", view.id),
        run: view,
        responses: responses_shown(&responses.rows),
        page: responses.page,
        pages: responses.pages,
        total: responses.total,
        notice,
    };
    Ok(Html(page.render_page()?))
}

async fn run_page(
    State(state): State<AppState>,
    Admin(session): Admin,
    Path(id): Path<i64>,
    Query(query): Query<PageQuery>,
) -> Result<Html<String>, PageError> {
    render_run(&state, session, id, query.page.unwrap_or(1), None).await
}

/// The run as the API shows it, for the page's script.
async fn progress(
    State(state): State<AppState>,
    Path(id): Path<i64>,
) -> Result<axum::Json<ServerRunView>, ApiError> {
    Ok(axum::Json(runs::view(&state.hub, id).await?))
}

#[derive(Deserialize)]
struct ControlForm {
    #[serde(default)]
    change: String,
}

async fn control(
    State(state): State<AppState>,
    Path(id): Path<i64>,
    request: Protected<ControlForm>,
) -> Result<Html<String>, PageError> {
    let (change, done) = match request.body.change.as_str() {
        "pause" => (JobControl::Pause, "Paused: it stops before its next item."),
        "resume" => (
            JobControl::Resume,
            "Resumed: it carries on where it stopped.",
        ),
        "cancel" => (JobControl::Cancel, "Cancelled: what was asked stays."),
        other => {
            return Err(Refusal::bad_value(
                "change",
                other,
                Expected::OneOf(vec!["pause", "resume", "cancel"]),
            )
            .into());
        }
    };
    runs::control(&state.hub, &request.session.actor(), id, change).await?;
    render_run(&state, request.session, id, 1, Some(done.to_owned())).await
}

async fn admin_download(
    State(state): State<AppState>,
    Path(id): Path<i64>,
) -> Result<Response, PageError> {
    Ok(responses_download(
        runs::output(&state.hub, id, Audience::Admin).await?,
    ))
}

async fn public_page(
    State(state): State<AppState>,
    Path(id): Path<i64>,
    Query(query): Query<PageQuery>,
) -> Result<Html<String>, PageError> {
    let responses =
        runs::response_page(&state.hub, id, Audience::Public, query.page.unwrap_or(1)).await?;
    let page = PublicRunPage {
        responses: responses_shown(&responses.rows),
        base: format!("/runs/{}", responses.run.id),
        run: responses.run,
        page: responses.page,
        pages: responses.pages,
        total: responses.total,
    };
    Ok(Html(page.render_page()?))
}

async fn public_download(
    State(state): State<AppState>,
    Path(id): Path<i64>,
) -> Result<Response, PageError> {
    Ok(responses_download(
        runs::output(&state.hub, id, Audience::Public).await?,
    ))
}
