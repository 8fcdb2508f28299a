//! Imports from the server's import folder (`POST /api/v1/admin/imports` and the admin page's
//! form), queued as jobs (`app::import_jobs`), and any job's state (`GET /api/v1/admin/jobs/{job}`,
//! `POST /api/v1/admin/jobs/{job}/{change}`).

use axum::Router;
use axum::extract::State;
use axum::http::StatusCode;
use axum::response::Html;
use axum::routing::post;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::AppState;
use super::admin::render_admin;
use super::auth::TokenCaller;
use super::error::{ApiError, PageError};
use super::extract::{Json, Path};
use super::openapi::{ApiRoute, Verb};
use super::session::Protected;
use crate::app::import_jobs::{self, ImportRequest};
use crate::app::jobs::{self, JobControl, JobId, JobView};
use crate::core::credentials::Scope;

pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Post,
            "/admin/imports",
            queue_import,
            "Import a release from the server's import folder",
        )
        .describe(
            "Queues a job that imports the ENACT release at `path` (relative to the folder the \
             server was started with, `serve --import-dir`) exactly as `enact-hub import` does: \
             staged, a batch per short transaction, invisible until one cut-over, resumed after \
             its last batch when the job is started again. Refused when the server has no import \
             folder, the path leaves it or holds no `QA/enact_ordering.jsonl`, or another import \
             into the dataset is unfinished. Follow it with `GET /api/v1/admin/jobs/{job}`: its \
             `progress.outcome` is `importing`, then `imported` (with the report), `refused` \
             (invalid lines or conflicts, with every problem) or `cancelled`.",
        )
        .bearer(Scope::Admin)
        .body_json::<ImportRequest>(
            "`path` under the import folder; `dataset` (default: the release folder's name), \
             `replace` and `skip_invalid` as the command line's flags.",
            "{\"path\": \"enact-release\", \"dataset\": \"enact\", \"replace\": false}",
        )
        .responds_json::<ImportQueued>(202, "The job was queued.")
        .errors(&[400, 401, 403, 404, 409, 415, 422]),
        ApiRoute::new(Verb::Get, "/admin/jobs/{job}", get_job, "A background job")
            .describe(
                "A job's kind, state, attempts, last error and the progress its code last \
                 stored (model runs, rescores and imports each write their own shape).",
            )
            .bearer(Scope::Admin)
            .responds_json::<JobView>(200, "The job.")
            .errors(&[400, 401, 403, 404]),
        ApiRoute::new(
            Verb::Post,
            "/admin/jobs/{job}/{change}",
            change_job,
            "Pause, resume or cancel a background job",
        )
        .describe(
            "`{change}` is `pause` (a running job stops at its next unit of work: an import \
             between batches, keeping them), `resume` (a paused or failed job carries on where \
             it stopped) or `cancel` (for good; a running import discards what it staged). \
             Audited.",
        )
        .bearer(Scope::Admin)
        .responds_json::<JobView>(200, "The job as changed.")
        .errors(&[400, 401, 403, 404, 409]),
    ]
}

/// The admin page's form (behind the admin pages' gate, `web::admin_pages`).
pub fn router() -> Router<AppState> {
    Router::new().route("/admin/imports", post(import_page))
}

#[derive(Serialize, JsonSchema)]
struct ImportQueued {
    /// The job's id.
    job: i64,
}

async fn queue_import(
    State(state): State<AppState>,
    TokenCaller(caller): TokenCaller,
    Json(request): Json<ImportRequest>,
) -> Result<(StatusCode, axum::Json<ImportQueued>), ApiError> {
    let job = import_jobs::request(&state.hub, &caller.actor(), &request).await?;
    Ok((
        StatusCode::ACCEPTED,
        axum::Json(ImportQueued { job: job.0 }),
    ))
}

/// A job's path, read through the JSON-error `Path` with named fields: a path that is not an
/// id is refused with the `Error` body naming `job` (axum's own extractor answered plain text).
#[derive(Deserialize)]
struct JobPath {
    job: i64,
}

#[derive(Deserialize)]
struct JobChange {
    job: i64,
    change: String,
}

async fn get_job(
    State(state): State<AppState>,
    Path(JobPath { job }): Path<JobPath>,
) -> Result<axum::Json<JobView>, ApiError> {
    Ok(axum::Json(jobs::view(&state.hub, JobId(job)).await?))
}

async fn change_job(
    State(state): State<AppState>,
    Path(JobChange { job, change }): Path<JobChange>,
    TokenCaller(caller): TokenCaller,
) -> Result<axum::Json<JobView>, ApiError> {
    let change = JobControl::parse(&change)?;
    let changed = jobs::control(&state.hub, &caller.actor(), JobId(job), change).await?;
    Ok(axum::Json(JobView::from(changed)))
}

/// The admin page's form: checkboxes arrive only when ticked.
#[derive(Deserialize)]
struct ImportForm {
    path: String,
    #[serde(default)]
    dataset: String,
    #[serde(default)]
    replace: Option<String>,
    #[serde(default)]
    skip_invalid: Option<String>,
}

async fn import_page(
    State(state): State<AppState>,
    request: Protected<ImportForm>,
) -> Result<Html<String>, PageError> {
    let form = request.body;
    let asked = ImportRequest {
        path: form.path,
        dataset: Some(form.dataset).filter(|d| !d.trim().is_empty()),
        replace: form.replace.is_some(),
        skip_invalid: form.skip_invalid.is_some(),
    };
    let job = import_jobs::request(&state.hub, &request.session.actor(), &asked).await?;
    render_admin(
        &state,
        request.session,
        Some(format!(
            "Queued {job}: importing {}; it is listed under Importing below.",
            asked.path
        )),
        None,
    )
    .await
}
