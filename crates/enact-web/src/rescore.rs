//! Rescoring from the web: `POST /api/v1/admin/rescore` and the admin page's button queue a
//! rescore job (`app::rescore`), worked by the serving instances' job workers.

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
use super::extract::Json;
use super::openapi::{ApiRoute, Verb};
use super::session::Protected;
use crate::app::rescore;
use crate::core::credentials::Scope;
use crate::core::metric::METRIC_VERSION;

pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Post,
            "/admin/rescore",
            queue_rescore,
            "Rescore stored results under the current metric version",
        )
        .describe(
            "Queues a job that computes again, under this server's metric version, every stored \
             submission's scores and every human answer's verdict computed with an older one, \
             of one dataset or of all: one submission (or 500 answers) per short transaction, \
             results already current skipped, so it resumes after a restart. Leaderboard rows \
             stay marked `outdated` until their results are rescored; the job writes one audit \
             entry (`metric.rescore`) with its counts.",
        )
        .bearer(Scope::Admin)
        .body_json::<RescoreRequest>(
            "`dataset`: only this dataset (every dataset when absent or null).",
            "{\"dataset\": \"enact\"}",
        )
        .responds_json::<RescoreQueued>(202, "The job was queued.")
        .errors(&[400, 401, 403, 404, 415, 422]),
    ]
}

/// The admin page's form (behind the admin pages' gate, `web::admin_pages`).
pub fn router() -> Router<AppState> {
    Router::new().route("/admin/rescore", post(rescore_page))
}

/// What to rescore. Read from a JSON object only: serde's derive would also read it from an
/// array of its fields, and schemathesis found `[]` queued a rescore of every dataset.
#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
struct RescoreRequest {
    #[serde(default)]
    dataset: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RescoreFields {
    #[serde(default)]
    dataset: Option<String>,
}

impl<'de> Deserialize<'de> for RescoreRequest {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let object = serde_json::Map::<String, serde_json::Value>::deserialize(d)?;
        let RescoreFields { dataset } =
            RescoreFields::deserialize(serde_json::Value::Object(object))
                .map_err(serde::de::Error::custom)?;
        Ok(RescoreRequest { dataset })
    }
}

#[derive(Serialize, JsonSchema)]
struct RescoreQueued {
    /// The job's id.
    job: i64,
    /// The metric version results are brought to.
    metric_version: u32,
}

async fn queue_rescore(
    State(state): State<AppState>,
    TokenCaller(caller): TokenCaller,
    Json(request): Json<RescoreRequest>,
) -> Result<(StatusCode, axum::Json<RescoreQueued>), ApiError> {
    let job = rescore::request(&state.hub, &caller.actor(), request.dataset.as_deref()).await?;
    Ok((
        StatusCode::ACCEPTED,
        axum::Json(RescoreQueued {
            job: job.0,
            metric_version: METRIC_VERSION,
        }),
    ))
}

/// The admin page's form: `dataset` empty for every dataset.
#[derive(Deserialize)]
struct RescoreForm {
    #[serde(default)]
    dataset: String,
}

async fn rescore_page(
    State(state): State<AppState>,
    request: Protected<RescoreForm>,
) -> Result<Html<String>, PageError> {
    let dataset = Some(request.body.dataset.trim()).filter(|d| !d.is_empty());
    let job = rescore::request(&state.hub, &request.session.actor(), dataset).await?;
    render_admin(
        &state,
        request.session,
        Some(format!(
            "Queued {job}: {} rescored to metric version {METRIC_VERSION}; the audit log \
             gets its counts when it ends.",
            dataset.map_or_else(|| "every dataset".to_owned(), |d| format!("dataset '{d}'"))
        )),
        None,
    )
    .await
}
