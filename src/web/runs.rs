//! Model runs worked by the server, over the JSON API (admins only): start one, list them,
//! read one with its live progress, and pause, resume or cancel it.

use axum::extract::State;
use axum::http::StatusCode;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::extract::{Json, Path};
use super::openapi::{ApiRoute, Verb};
use super::{AppError, AppState};
use crate::app::jobs::JobControl;
use crate::app::runs::{self, RunCalls, RunSpec, ServerRunView};
use crate::app::tokens::Caller;
use crate::core::credentials::Scope;
use crate::core::model_run::{GenerationParams, Prices};

pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Post,
            "/admin/runs",
            start_run,
            "Start a model run on the server",
        )
        .describe(
            "Finds or creates the run (by its name, or its dataset, endpoint, model and \
                 parameters) and queues it as a job that a serving instance works: every item \
                 not yet answered is asked, then the answers are submitted under `submit_as`. \
                 The API key is named by `key_variable`, an environment variable the server \
                 was started with (`serve --endpoint-key`); its value is never stored.",
        )
        .bearer(Scope::Admin)
        .body_json::<RunRequest>(
            "`dataset`, `endpoint` (an OpenAI-compatible base URL), `model`; optional \
                 `name`, `temperature`, `max_tokens`, `limit`, `retry_failed`, `submit_as`, \
                 `price_input` and `price_output` (USD per million tokens), `key_variable`, \
                 `concurrency`, `max_retries`, `timeout_s`.",
            "{\"dataset\": \"enact\", \"endpoint\": \"https://api.openai.com/v1\", \
                 \"model\": \"gpt-4o\", \"temperature\": 0, \"key_variable\": \
                 \"OPENAI_API_KEY\", \"submit_as\": \"GPT-4o\"}",
        )
        .responds_json::<RunStarted>(202, "The run's id and name, and its job's id (queued).")
        .errors(&[400, 401, 403, 404, 409, 415, 422]),
        ApiRoute::new(Verb::Get, "/admin/runs", list_runs, "List model runs")
            .describe("Every model run, newest first, with its newest job's state and progress.")
            .bearer(Scope::Admin)
            .responds_json::<Vec<ServerRunView>>(200, "The runs.")
            .errors(&[401, 403]),
        ApiRoute::new(
            Verb::Get,
            "/admin/runs/{run}",
            get_run,
            "A model run and its progress",
        )
        .describe(
            "The run with its job's state and progress (done, answered, failed, in flight, \
                 items/s, ETA, tokens, cost, recent errors), stored about once a second.",
        )
        .bearer(Scope::Admin)
        .responds_json::<ServerRunView>(200, "The run.")
        .errors(&[401, 403, 404]),
        ApiRoute::new(
            Verb::Post,
            "/admin/runs/{run}/{change}",
            change_run,
            "Pause, resume or cancel a model run",
        )
        .describe(
            "`{change}` is `pause` (it stops before its next item), `resume` (a paused or \
             failed run carries on where it stopped) or `cancel` (for good; what was asked \
             stays). Audited as the job's change.",
        )
        .bearer(Scope::Admin)
        .responds_json::<ServerRunView>(200, "The run as changed.")
        .errors(&[400, 401, 403, 404, 409]),
    ]
}

/// A run to start.
#[derive(Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct RunRequest {
    dataset: String,
    endpoint: String,
    model: String,
    name: Option<String>,
    temperature: Option<f64>,
    max_tokens: Option<u32>,
    limit: Option<usize>,
    #[serde(default)]
    retry_failed: bool,
    /// The leaderboard's model name; the model's when not given.
    submit_as: Option<String>,
    #[serde(default)]
    price_input: f64,
    #[serde(default)]
    price_output: f64,
    key_variable: Option<String>,
    concurrency: Option<usize>,
    max_retries: Option<u32>,
    timeout_s: Option<f64>,
}

#[derive(Serialize, JsonSchema)]
struct RunStarted {
    /// The run's id (`GET /api/v1/admin/runs/{run}` shows its progress) and name.
    run: i64,
    name: String,
    job: i64,
}

async fn start_run(
    State(state): State<AppState>,
    caller: Caller,
    Json(request): Json<RunRequest>,
) -> Result<(StatusCode, Json<RunStarted>), AppError> {
    for (field, price) in [
        ("price_input", request.price_input),
        ("price_output", request.price_output),
    ] {
        if !(price.is_finite() && price >= 0.0) {
            return Err(AppError::Invalid(format!(
                "{field} must be a price of 0 or more, not {price}"
            )));
        }
    }
    let defaults = RunCalls::default();
    let spec = RunSpec {
        dataset: request.dataset,
        endpoint: request.endpoint,
        submit_as: Some(request.submit_as.unwrap_or_else(|| request.model.clone())),
        model: request.model,
        name: request.name,
        params: GenerationParams {
            temperature: request.temperature,
            max_tokens: request.max_tokens,
        },
        limit: request.limit,
        retry_failed: request.retry_failed,
        prices: Prices {
            input_usd_per_mtok: request.price_input,
            output_usd_per_mtok: request.price_output,
        },
    };
    let calls = RunCalls {
        key_variable: request.key_variable,
        concurrency: request.concurrency.unwrap_or(defaults.concurrency),
        max_retries: request.max_retries.unwrap_or(defaults.max_retries),
        timeout_s: request.timeout_s.unwrap_or(defaults.timeout_s),
    };
    let (run, job) = runs::start(&state.hub, &caller.actor(), &spec, &calls).await?;
    Ok((
        StatusCode::ACCEPTED,
        Json(RunStarted {
            run: run.id,
            name: run.name,
            job: job.0,
        }),
    ))
}

async fn list_runs(State(state): State<AppState>) -> Result<Json<Vec<ServerRunView>>, AppError> {
    Ok(Json(runs::views(&state.hub).await?))
}

async fn get_run(
    State(state): State<AppState>,
    Path(run): Path<i64>,
) -> Result<Json<ServerRunView>, AppError> {
    Ok(Json(runs::view(&state.hub, run).await?))
}

async fn change_run(
    State(state): State<AppState>,
    Path((run, change)): Path<(i64, String)>,
    caller: Caller,
) -> Result<Json<ServerRunView>, AppError> {
    let change = match change.as_str() {
        "pause" => JobControl::Pause,
        "resume" => JobControl::Resume,
        "cancel" => JobControl::Cancel,
        other => {
            return Err(AppError::Invalid(format!(
                "{other:?} is not a change of a run: pause, resume or cancel"
            )));
        }
    };
    Ok(Json(
        runs::control(&state.hub, &caller.actor(), run, change).await?,
    ))
}
