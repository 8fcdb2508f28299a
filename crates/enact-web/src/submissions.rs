//! Submissions over HTTP: posting a prediction file, reading its scores, and the admin's
//! controls (tokens, dataset answer visibility, leaderboard rows).

use axum::body::Body;
use axum::extract::State;
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use super::auth::TokenCaller;
use super::error::ApiError;
use super::extract::{IdempotencyKey, Json, Path, Query, whole_number};
use super::openapi::{ApiRoute, Verb};
use super::{AppError, AppState};
use crate::app::refusal::{Expected, Refusal};
use crate::app::submissions::{self, StoredVerdict, SubmissionRow, Submitted};
use crate::app::tokens::{self, CreatedToken, TokenListing};
use crate::app::{challenge, datasets};
use crate::core::credentials::{Role, Scope};
use crate::core::dataset::AnswerVisibility;
use crate::core::metric::MetricStamp;
use crate::core::submission::{
    Provenance, SubmissionMetadata, SubmissionScores, SubmissionStatus, Visibility,
};
use crate::core::verifier::ScoringPolicy;

/// Submitting, reading scores, and the admin's controls (see [`super::openapi`]).
pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Post,
            "/datasets/{dataset}/submissions",
            submit,
            "Submit a model's answers",
        )
        .describe(
            "Scores a prediction file against every item of the dataset and stores it, all or \
             nothing. The body is ENACT's model-output JSONL (each QA record plus `answer`), \
             compact JSONL (`{\"id\", \"answer\"}` per line), or a JSON array of such objects. \
             Only `id` and `answer` are read: a submitted `gt_answer`, `type` or `key_frame_ids` \
             never influences scoring. `answer` may be the model's raw text or a list; an \
             answer that cannot be parsed is scored as a failure and counted, not refused. \
             Every dataset item counts: unanswered items score 0. Each attempt (refused ones \
             too) counts against the token's daily and total quotas; admin tokens are exempt.",
        )
        .bearer(Scope::Submit)
        .query_with(
            "model",
            true,
            json!({"type": "string", "maxLength": 200, "pattern": "\\S"}),
            "The model's name on the leaderboard (1 to 200 characters).",
        )
        .query("description", false, "Free text about the model or run.")
        .query("url", false, "A link to the model or paper.")
        .query("prompt_version", false, "Which prompt produced the answers.")
        .query("notes", false, "Anything else worth recording.")
        .header(
            "Idempotency-Key",
            json!({"type": "string", "pattern": "^[!-~]([ -~]{0,198}[!-~])?$"}),
            "1 to 200 printable ASCII characters. Repeating a request with the same key and body returns the \
             first submission (200) instead of storing another; a different body is 409.",
        )
        .body(
            &["text/plain"],
            "One JSON object per line (sent as `text/plain`, `application/x-ndjson` or \
             anything else), or one JSON array (`application/json` too). The body limit is the server's \
             `--submission-body-limit` (64 MiB by default, enough for a full ENACT file).",
            Some(
                "{\"id\": \"cook_bacon_..._forward_world_modeling_ordering_3_steps_...\", \"answer\": \"[2, 1]\"}\n\
                 {\"id\": \"...\", \"answer\": [1, 3, 2]}",
            ),
        )
        .responds_json::<SubmissionView>(201, "Stored and scored: the submission with its `id`, `href` and `scores`; `Location` names it.")
        .responds_json::<SubmissionView>(200, "A repeat with the same `Idempotency-Key` and body: the first submission.")
        .errors(&[400, 401, 403, 404, 409, 413, 422, 429]),
        ApiRoute::new(Verb::Get, "/submissions/{id}", get_submission, "A submission's scores")
            .describe(
                "Status; TA and PA overall, forward, inverse and per step length; coverage and \
                 parse-failure rate; 95% bootstrap intervals on overall TA and PA. Per-item \
                 verdicts (`items`) only to the owner (or an admin) and only if the dataset's \
                 answers are public; otherwise `items_withheld` says why. On a dataset split for \
                 a challenge, until its private part is revealed, `scores` are over the public \
                 part only (to anyone but an admin), as they are when the submission is posted.",
            )
            .bearer(Scope::ReadOwn)
            .responds_json::<SubmissionView>(200, "The submission.")
            .errors(&[401, 403, 404]),
        ApiRoute::new(
            Verb::Patch,
            "/admin/submissions/{id}",
            update_listing,
            "Change a submission's leaderboard listing",
        )
        .describe("Mark a baseline, or hide, publish or withdraw a leaderboard row.")
        .bearer(Scope::Admin)
        .body_json::<ListingChange>(
            "`baseline` (bool) and/or `visibility`: `published`, `hidden` or `withdrawn`.",
            "{\"baseline\": true, \"visibility\": \"published\"}",
        )
        .responds_json::<SubmissionView>(200, "The submission as changed.")
        .errors(&[400, 401, 403, 404, 415, 422]),
        ApiRoute::new(
            Verb::Put,
            "/admin/datasets/{dataset}/answers",
            set_answers,
            "Set whether a dataset's answers are public",
        )
        .describe(
            "`hidden` (the default) never shows ground truth or per-item correctness to \
             submitters, and leaves ground truth out of the dataset archive; `public` shows \
             both.",
        )
        .bearer(Scope::Admin)
        .body_json::<AnswersChange>(
            "`{\"answers\": \"public\" | \"hidden\"}`.",
            "{\"answers\": \"public\"}",
        )
        .responds_json::<AnswersView>(200, "The dataset's setting.")
        .errors(&[400, 401, 403, 404, 415, 422]),
        ApiRoute::new(Verb::Post, "/admin/tokens", create_token, "Create an API token")
            .describe(
                "Creates the account if it is new, and a token for it. The token's secret is in \
                 this response only; the server keeps its SHA-256.",
            )
            .bearer(Scope::Admin)
            .body_json::<TokenRequest>(
                "`name` (1 to 100 characters), `role` (`submitter`, the default, or `admin`), \
                 optional `daily_quota` and `total_quota` (else the server's defaults).",
                "{\"name\": \"team-a\", \"role\": \"submitter\", \"daily_quota\": 5}",
            )
            .responds_json::<CreatedToken>(201, "`id`, `prefix`, `account`, `role`, and `token`, the secret.")
            .errors(&[400, 401, 403, 409, 415, 422]),
        ApiRoute::new(Verb::Get, "/admin/tokens", list_tokens, "List API tokens")
            .describe("Every token with its account, role, scopes, quotas, creation, last use and revocation; never a secret.")
            .bearer(Scope::Admin)
            .responds_json::<Vec<TokenListing>>(200, "The tokens.")
            .errors(&[401, 403]),
        ApiRoute::new(Verb::Delete, "/admin/tokens/{token_id_or_prefix}", revoke_token, "Revoke an API token")
            .describe("Takes effect at once: the next request with the token gets 401.")
            .bearer(Scope::Admin)
            .responds(204, None, "Revoked.")
            .errors(&[401, 403, 404]),
    ]
}

/// Metadata of a submission, as query parameters.
#[derive(Debug, Default, Deserialize)]
struct SubmitQuery {
    model: Option<String>,
    description: Option<String>,
    url: Option<String>,
    prompt_version: Option<String>,
    notes: Option<String>,
}

impl From<SubmitQuery> for SubmissionMetadata {
    fn from(q: SubmitQuery) -> Self {
        SubmissionMetadata {
            model: q.model.unwrap_or_default(),
            description: q.description.unwrap_or_default(),
            url: q.url.unwrap_or_default(),
            prompt_version: q.prompt_version.unwrap_or_default(),
            notes: q.notes.unwrap_or_default(),
        }
    }
}

/// Reads a submission body up to `limit` bytes: a declared length over the limit is refused
/// before reading, and a body that grows past it as soon as it does.
async fn read_body(body: Body, headers: &HeaderMap, limit: usize) -> Result<Vec<u8>, AppError> {
    let too_large = || {
        AppError::TooLarge(format!(
            "the submission body is larger than the limit of {limit} bytes"
        ))
    };
    let declared = headers
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.parse::<usize>().ok());
    if declared.is_some_and(|n| n > limit) {
        return Err(too_large());
    }
    match axum::body::to_bytes(body, limit).await {
        Ok(bytes) => Ok(bytes.into()),
        Err(e) if is_length_limit(&e) => Err(too_large()),
        Err(e) => Err(AppError::Invalid(format!(
            "the request body could not be read: {e}"
        ))),
    }
}

/// Whether a body error is `to_bytes` stopping at its limit.
fn is_length_limit(e: &axum::Error) -> bool {
    let mut source: Option<&(dyn std::error::Error + 'static)> = Some(e);
    while let Some(s) = source {
        if s.is::<http_body_util::LengthLimitError>() {
            return true;
        }
        source = s.source();
    }
    false
}

/// What the API says about a submission.
#[derive(Serialize, JsonSchema)]
struct SubmissionView {
    id: i64,
    href: String,
    dataset: String,
    account: String,
    model: String,
    description: String,
    url: String,
    prompt_version: String,
    notes: String,
    status: SubmissionStatus,
    policy: ScoringPolicy,
    visibility: Visibility,
    baseline: bool,
    /// `run` when this hub asked the model itself (then `run` names the model run), else
    /// `submitted`.
    provenance: Provenance,
    #[serde(skip_serializing_if = "Option::is_none")]
    run: Option<i64>,
    created_at: String,
    scores: SubmissionScores,
    /// The metric version `scores` and the verdicts were computed with, and whether it is
    /// older than the server's (then they are not comparable with current rows until rescored).
    #[serde(flatten)]
    metric: MetricStamp,
    /// The enact-hub build that computed `scores` (`version+commit`; empty for submissions
    /// scored before builds were recorded).
    scored_by: String,
    /// Per-item verdicts: only for the owner, and only if the dataset's answers are public.
    #[serde(skip_serializing_if = "Option::is_none")]
    items: Option<Vec<ItemVerdictView>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    items_withheld: Option<String>,
}

#[derive(Serialize, JsonSchema)]
struct ItemVerdictView {
    id: String,
    direction: String,
    step_length: u8,
    line: Option<i64>,
    outcome: String,
    answer: Option<Value>,
    permutation: Option<Value>,
    failure: Option<String>,
    exact_match: bool,
    semantic_match: bool,
    task_accuracy: bool,
    pairwise_accuracy: Option<f64>,
    ground_truth: Value,
}

fn parse_json_column(text: Option<&str>) -> Option<Value> {
    text.and_then(|t| serde_json::from_str(t).ok())
}

impl From<StoredVerdict> for ItemVerdictView {
    fn from(v: StoredVerdict) -> Self {
        ItemVerdictView {
            answer: parse_json_column(v.raw_answer.as_deref()),
            permutation: parse_json_column(v.permutation.as_deref()),
            ground_truth: parse_json_column(Some(&v.gt_answer)).unwrap_or(Value::Null),
            id: v.id,
            direction: v.direction.as_str().to_owned(),
            step_length: v.step_length.get(),
            line: v.line,
            outcome: v.outcome.as_str().to_owned(),
            failure: v.failure,
            exact_match: v.exact_match,
            semantic_match: v.semantic_match,
            task_accuracy: v.task_accuracy,
            pairwise_accuracy: v.pairwise_accuracy,
        }
    }
}

impl From<SubmissionRow> for SubmissionView {
    fn from(row: SubmissionRow) -> Self {
        SubmissionView {
            href: format!("/api/v1/submissions/{}", row.id),
            id: row.id,
            dataset: row.dataset,
            account: row.account,
            model: row.model,
            description: row.description,
            url: row.url,
            prompt_version: row.prompt_version,
            notes: row.notes,
            status: row.status,
            policy: row.policy,
            visibility: row.visibility,
            baseline: row.baseline,
            provenance: row.provenance,
            run: row.run,
            created_at: row.created_at,
            scores: row.scores,
            metric: MetricStamp::of(row.metric_version),
            scored_by: row.scored_by.clone(),
            items: None,
            items_withheld: None,
        }
    }
}

async fn submit(
    State(state): State<AppState>,
    // First, so a caller without a valid token hears 401 whatever else is wrong.
    TokenCaller(caller): TokenCaller,
    Path(dataset): Path<String>,
    Query(query): Query<SubmitQuery>,
    IdempotencyKey(key): IdempotencyKey,
    headers: HeaderMap,
    body: Body,
) -> Result<Response, ApiError> {
    let limit = state.submission_body_limit;
    let read = read_body(body, &headers, limit);
    let submitted = submissions::submit(
        &state.hub,
        &caller,
        &dataset,
        query.into(),
        // An upload, whatever its metadata claims: only the hub's own runs are `run`.
        Provenance::Submitted,
        key.as_deref(),
        read,
    )
    .await?;
    let (status, row) = match submitted {
        Submitted::Created(row) => (StatusCode::CREATED, row),
        Submitted::Repeated(row) => (StatusCode::OK, row),
    };
    let row = challenge::as_shown_to(&state.hub, &caller, row).await?;
    let location = format!("/api/v1/submissions/{}", row.id);
    Ok((
        status,
        [(header::LOCATION, location)],
        Json(SubmissionView::from(row)),
    )
        .into_response())
}

async fn get_submission(
    State(state): State<AppState>,
    Path(id): Path<String>,
    TokenCaller(caller): TokenCaller,
) -> Result<Json<SubmissionView>, ApiError> {
    let detail = submissions::read(&state.hub, &caller, &id).await?;
    let row = challenge::as_shown_to(&state.hub, &caller, detail.row).await?;
    let mut view = SubmissionView::from(row);
    match detail.verdicts {
        Ok(verdicts) => {
            view.items = Some(verdicts.into_iter().map(ItemVerdictView::from).collect());
        }
        Err(withheld) => view.items_withheld = Some(withheld),
    }
    Ok(Json(view))
}

#[derive(Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct ListingChange {
    baseline: Option<bool>,
    /// Read as text so a wrong value gets this API's own message.
    #[schemars(with = "Option<Visibility>")]
    visibility: Option<String>,
}

async fn update_listing(
    State(state): State<AppState>,
    Path(id): Path<String>,
    TokenCaller(caller): TokenCaller,
    Json(change): Json<ListingChange>,
) -> Result<Json<SubmissionView>, ApiError> {
    let row = submissions::update_listing(
        &state.hub,
        &caller.actor(),
        &id,
        change.baseline,
        change.visibility.as_deref(),
    )
    .await?;
    Ok(Json(row.into()))
}

#[derive(Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct AnswersChange {
    answers: AnswerVisibility,
}

#[derive(Serialize, JsonSchema)]
struct AnswersView {
    dataset: String,
    answers: AnswerVisibility,
}

async fn set_answers(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    TokenCaller(caller): TokenCaller,
    Json(change): Json<AnswersChange>,
) -> Result<Json<AnswersView>, ApiError> {
    let dataset =
        datasets::set_answer_visibility(&state.hub, &caller.actor(), &dataset, change.answers)
            .await?;
    Ok(Json(AnswersView {
        dataset: dataset.name,
        answers: change.answers,
    }))
}

#[derive(Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct TokenRequest {
    /// The account: 1 to 100 characters once trimmed.
    #[schemars(length(max = 100), regex(pattern = r"\S"))]
    name: String,
    #[schemars(with = "Option<Role>")]
    role: Option<String>,
    #[serde(default, deserialize_with = "whole_number")]
    #[schemars(with = "Option<i64>", range(min = 0))]
    daily_quota: Option<i64>,
    #[serde(default, deserialize_with = "whole_number")]
    #[schemars(with = "Option<i64>", range(min = 0))]
    total_quota: Option<i64>,
}

async fn create_token(
    State(state): State<AppState>,
    TokenCaller(caller): TokenCaller,
    Json(request): Json<TokenRequest>,
) -> Result<(StatusCode, Json<CreatedToken>), ApiError> {
    let role = match request.role.as_deref() {
        None => Role::Submitter,
        Some(r) => parse_role(r)?,
    };
    let created = tokens::issue(
        &state.hub,
        &caller.actor(),
        &request.name,
        role,
        request.daily_quota,
        request.total_quota,
    )
    .await?;
    Ok((StatusCode::CREATED, Json(created)))
}

pub(super) fn parse_role(text: &str) -> Result<Role, ApiError> {
    Role::parse(text)
        .ok_or_else(|| {
            Refusal::bad_value("role", text, Expected::OneOf(vec!["submitter", "admin"]))
        })
        .map_err(ApiError::from)
}

async fn list_tokens(State(state): State<AppState>) -> Result<Json<Vec<TokenListing>>, ApiError> {
    Ok(Json(tokens::list(&state.hub).await?))
}

async fn revoke_token(
    State(state): State<AppState>,
    Path(which): Path<String>,
    TokenCaller(caller): TokenCaller,
) -> Result<StatusCode, ApiError> {
    tokens::revoke(&state.hub, &caller.actor(), &which).await?;
    Ok(StatusCode::NO_CONTENT)
}
