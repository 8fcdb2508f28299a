//! Model runs worked by the server, over the JSON API (admins only): start one, list them,
//! read one with its live progress, and pause, resume or cancel it; and a run's answers as
//! ENACT's model-output JSONL (admins, or anyone for a dataset with public answers).

use axum::body::Body;
use axum::extract::State;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::auth::TokenCaller;
use super::error::ApiError;
use super::extract::{Json, Path, whole_number};
use super::openapi::{ApiRoute, Verb};
use super::session::ReaderIsAdmin;
use super::{AppError, AppState};
use crate::app::jobs::JobControl;
use crate::app::refusal::{Expected, Refusal};
use crate::app::runs::{self, Audience, RunCalls, RunOutput, RunSpec, ServerRunView};
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
        .errors(&[400, 401, 403, 404]),
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
        ApiRoute::new(
            Verb::Get,
            "/admin/runs/{run}/responses",
            admin_responses,
            "A model run's answers as ENACT model-output JSONL",
        )
        .describe(RESPONSES_DESCRIPTION)
        .bearer(Scope::Admin)
        .responds(200, Some(JSONL), "The answers, one JSON object a line.")
        .errors(&[400, 401, 403, 404]),
        ApiRoute::new(
            Verb::Get,
            "/runs/{run}/responses",
            public_responses,
            "A public model run's answers as ENACT model-output JSONL",
        )
        .describe(
            "The same file as `/admin/runs/{run}/responses`, for anyone, when the run's dataset \
             has public answers (404 otherwise).",
        )
        .responds(200, Some(JSONL), "The answers, one JSON object a line.")
        .errors(&[400, 404]),
        ApiRoute::new(
            Verb::Get,
            "/runs/{run}/stamp",
            run_stamp,
            "What a model run asked, and how",
        )
        .describe(
            "The stamp a leaderboard row of provenance `run` links to: the endpoint's host, the \
             model, the generation parameters, the prompt's version and SHA-256, the hub \
             version, token usage and cost, and the submission the replies became. Anyone may \
             read it once that submission is listed on its leaderboard (an admin always); no \
             answer is in it, so hidden datasets' runs show theirs too. 404 for a run that has \
             not submitted.",
        )
        .responds_json::<RunStampView>(200, "The run and its stamp.")
        .errors(&[400, 404]),
    ]
}

/// A run's stamp as the API gives it.
#[derive(Serialize, JsonSchema)]
struct RunStampView {
    run: i64,
    name: String,
    dataset: String,
    /// The submission its answers were filed as.
    submission: i64,
    /// As stored when the run submitted: `endpoint_host`, `model`, `params`, `prompt_version`,
    /// `prompt_hash`, `hub_version`, `usage`, `cost_usd`, `answered`, `failed` and the call
    /// settings.
    stamp: serde_json::Map<String, serde_json::Value>,
}

async fn run_stamp(
    State(state): State<AppState>,
    ReaderIsAdmin(admin): ReaderIsAdmin,
    Path(RunPath { run }): Path<RunPath>,
) -> Result<Json<RunStampView>, ApiError> {
    let audience = if admin {
        Audience::Admin
    } else {
        Audience::Public
    };
    let stamped = runs::stamp(&state.hub, run, audience).await?;
    let stamp = match stamped.stamp {
        serde_json::Value::Object(map) => map,
        other => {
            return Err(ApiError(AppError::internal(format!(
                "model run {run}: stored stamp is not an object: {other}"
            ))));
        }
    };
    Ok(Json(RunStampView {
        run: stamped.run.id,
        name: stamped.run.name,
        dataset: stamped.run.dataset,
        submission: stamped.submission,
        stamp,
    }))
}

const JSONL: &str = "application/x-ndjson";

const RESPONSES_DESCRIPTION: &str = "Every answered item of the run, streamed in dataset order, \
     as the file ENACT's `enact eval` reads: the item's QA fields with ground truth \
     (`key_frame_ids`, `gt_answer`) and `answer`, the model's raw reply as a string. Failed items \
     are left out (the hub scores them as unanswered). The suggested file name is \
     `enact_ordering_{model}.jsonl`, from which ENACT takes the model's name.";

/// A run's answers as a streamed JSONL download named as ENACT expects.
pub(super) fn responses_download(output: RunOutput) -> Response {
    let name = format!(
        "enact_ordering_{}.jsonl",
        super::file_name_safe(&output.run.model)
    );
    let mut response =
        Body::from_stream(tokio_stream::wrappers::ReceiverStream::new(output.chunks))
            .into_response();
    let headers = response.headers_mut();
    headers.insert(header::CONTENT_TYPE, HeaderValue::from_static(JSONL));
    if let Ok(v) = HeaderValue::from_str(&format!("attachment; filename=\"{name}\"")) {
        headers.insert(header::CONTENT_DISPOSITION, v);
    }
    response
}

async fn admin_responses(
    State(state): State<AppState>,
    Path(RunPath { run }): Path<RunPath>,
) -> Result<Response, ApiError> {
    let output = runs::output(&state.hub, run, Audience::Admin).await?;
    Ok(responses_download(output))
}

async fn public_responses(
    State(state): State<AppState>,
    Path(RunPath { run }): Path<RunPath>,
) -> Result<Response, ApiError> {
    let output = runs::output(&state.hub, run, Audience::Public).await?;
    Ok(responses_download(output))
}

/// A run's path: named fields, so a path that is not an id is refused naming `run`.
#[derive(Deserialize)]
struct RunPath {
    run: i64,
}

#[derive(Deserialize)]
struct RunChange {
    run: i64,
    change: String,
}

/// A run to start. The schema states every rule the server checks on its own (ranges,
/// non-blank names); what it cannot state is checked with a 400 naming the field: `endpoint`
/// must be an http(s) URL without credentials, query or fragment, and `key_variable` one the
/// server was started with. Counts are whole numbers, `5` or `5.0` (JSON Schema integers).
#[derive(Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub(super) struct RunRequest {
    pub(super) dataset: String,
    pub(super) endpoint: String,
    #[schemars(regex(pattern = r"\S"))]
    pub(super) model: String,
    /// 1 to 200 characters once trimmed.
    #[schemars(length(max = 200), regex(pattern = r"\S"))]
    pub(super) name: Option<String>,
    pub(super) temperature: Option<f64>,
    #[serde(default, deserialize_with = "whole_number")]
    #[schemars(with = "Option<i64>", range(min = 0, max = MOST_U32))]
    pub(super) max_tokens: Option<i64>,
    #[serde(default, deserialize_with = "whole_number")]
    #[schemars(with = "Option<i64>", range(min = 1, max = MOST_WHOLE))]
    pub(super) limit: Option<i64>,
    #[serde(default)]
    pub(super) retry_failed: bool,
    /// The leaderboard's model name; the model's when not given.
    #[schemars(regex(pattern = r"\S"))]
    pub(super) submit_as: Option<String>,
    #[serde(default)]
    #[schemars(range(min = 0))]
    pub(super) price_input: f64,
    #[serde(default)]
    #[schemars(range(min = 0))]
    pub(super) price_output: f64,
    pub(super) key_variable: Option<String>,
    #[serde(default, deserialize_with = "whole_number")]
    #[schemars(with = "Option<i64>", range(min = 1, max = MOST_CONCURRENCY))]
    pub(super) concurrency: Option<i64>,
    #[serde(default, deserialize_with = "whole_number")]
    #[schemars(with = "Option<i64>", range(min = 0, max = MOST_U32))]
    pub(super) max_retries: Option<i64>,
    /// Seconds, above 0 and at most 3600.
    #[schemars(range(max = 3600), extend("exclusiveMinimum" = 0))]
    pub(super) timeout_s: Option<f64>,
}

pub(super) const MOST_U32: i64 = u32::MAX as i64;
pub(super) const MOST_WHOLE: i64 = super::extract::MOST_WHOLE_NUMBER;
pub(super) const MOST_CONCURRENCY: i64 = runs::MOST_CONCURRENCY as i64;

/// What a count from `least` to `most` must be, as a refusal says it (every count's range
/// starts at 0 or more).
pub(super) fn whole(least: i64, most: i64) -> Expected {
    Expected::WholeNumber {
        least: least.max(0).unsigned_abs(),
        most: most.max(0).unsigned_abs(),
    }
}

/// `value` as the type a field is used as, or a 400 naming the field and the range.
fn counted<T: TryFrom<i64>>(
    field: &str,
    value: Option<i64>,
    least: i64,
    most: i64,
) -> Result<Option<T>, ApiError> {
    value
        .map(|v| {
            (least..=most)
                .contains(&v)
                .then(|| T::try_from(v).ok())
                .flatten()
                .ok_or_else(|| Refusal::bad_value(field, v.to_string(), whole(least, most)))
        })
        .transpose()
        .map_err(ApiError::from)
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
    TokenCaller(caller): TokenCaller,
    Json(request): Json<RunRequest>,
) -> Result<(StatusCode, Json<RunStarted>), ApiError> {
    let (spec, calls) = request.into_run()?;
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

impl RunRequest {
    /// The run asked for and how to call its endpoint; shared with the admin page's form.
    pub(super) fn into_run(self) -> Result<(RunSpec, RunCalls), ApiError> {
        let max_tokens = counted("max_tokens", self.max_tokens, 0, MOST_U32)?;
        let limit = counted("limit", self.limit, 1, MOST_WHOLE)?;
        let concurrency = counted("concurrency", self.concurrency, 1, MOST_CONCURRENCY)?;
        let max_retries = counted("max_retries", self.max_retries, 0, MOST_U32)?;
        let defaults = RunCalls::default();
        let spec = RunSpec {
            dataset: self.dataset,
            endpoint: self.endpoint,
            submit_as: Some(self.submit_as.unwrap_or_else(|| self.model.clone())),
            model: self.model,
            name: self.name,
            params: GenerationParams {
                temperature: self.temperature,
                max_tokens,
            },
            limit,
            retry_failed: self.retry_failed,
            prices: Prices {
                input_usd_per_mtok: self.price_input,
                output_usd_per_mtok: self.price_output,
            },
        };
        let calls = RunCalls {
            key_variable: self.key_variable,
            concurrency: concurrency.unwrap_or(defaults.concurrency),
            max_retries: max_retries.unwrap_or(defaults.max_retries),
            timeout_s: self.timeout_s.unwrap_or(defaults.timeout_s),
        };
        Ok((spec, calls))
    }
}

async fn list_runs(State(state): State<AppState>) -> Result<Json<Vec<ServerRunView>>, ApiError> {
    Ok(Json(runs::views(&state.hub).await?))
}

async fn get_run(
    State(state): State<AppState>,
    Path(RunPath { run }): Path<RunPath>,
) -> Result<Json<ServerRunView>, ApiError> {
    Ok(Json(runs::view(&state.hub, run).await?))
}

async fn change_run(
    State(state): State<AppState>,
    Path(RunChange { run, change }): Path<RunChange>,
    TokenCaller(caller): TokenCaller,
) -> Result<Json<ServerRunView>, ApiError> {
    let change = JobControl::parse(&change)?;
    Ok(Json(
        runs::control(&state.hub, &caller.actor(), run, change).await?,
    ))
}
