//! Submissions over HTTP: posting a prediction file, reading its scores, and the admin's
//! controls (tokens, dataset answer visibility, leaderboard rows).

use std::collections::HashMap;
use std::pin::Pin;
use std::sync::{Arc, Mutex};

use axum::Json;
use axum::body::{Body, HttpBody};
use axum::extract::{Path, Query, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use sha2::{Digest, Sha256};

use super::auth::require;
use super::openapi::{ApiRoute, Verb};
use super::{AppError, AppState, dataset_or_404};
use crate::core::credentials::{NewToken, Role, Scope};
use crate::core::scoring::{self, ScoringTarget};
use crate::core::submission::{SubmissionError, score_submission};
use crate::store;
use crate::store::accounts::{AttemptQuota, Caller};
use crate::store::submissions::{
    AnswerVisibility, NewSubmission, SubmissionMetadata, SubmissionRow,
};

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
        .bearer("submit")
        .query("model", true, "The model's name on the leaderboard (1 to 200 characters).")
        .query("description", false, "Free text about the model or run.")
        .query("url", false, "A link to the model or paper.")
        .query("prompt_version", false, "Which prompt produced the answers.")
        .query("notes", false, "Anything else worth recording.")
        .header(
            "Idempotency-Key",
            "1 to 200 characters. Repeating a request with the same key and body returns the \
             first submission (200) instead of storing another; a different body is 409.",
        )
        .body(
            &["application/x-ndjson", "application/json", "text/plain"],
            "One JSON object per line, or one JSON array. The body limit is the server's \
             `--submission-body-limit` (64 MiB by default, enough for a full ENACT file).",
            Some(
                "{\"id\": \"cook_bacon_..._forward_world_modeling_ordering_3_steps_...\", \"answer\": \"[2, 1]\"}\n\
                 {\"id\": \"...\", \"answer\": [1, 3, 2]}",
            ),
        )
        .responds(201, Some("application/json"), "Stored and scored: the submission with its `id`, `href` and `scores`; `Location` names it.")
        .responds(200, Some("application/json"), "A repeat with the same `Idempotency-Key` and body: the first submission.")
        .errors(&[400, 401, 403, 404, 409, 413, 422, 429]),
        ApiRoute::new(Verb::Get, "/submissions/{id}", get_submission, "A submission's scores")
            .describe(
                "Status; TA and PA overall, forward, inverse and per step length; coverage and \
                 parse-failure rate; 95% bootstrap intervals on overall TA and PA. Per-item \
                 verdicts (`items`) only to the owner (or an admin) and only if the dataset's \
                 answers are public; otherwise `items_withheld` says why.",
            )
            .bearer("read_own")
            .responds(200, Some("application/json"), "The submission.")
            .errors(&[401, 403, 404]),
        ApiRoute::new(
            Verb::Patch,
            "/admin/submissions/{id}",
            update_listing,
            "Change a submission's leaderboard listing",
        )
        .describe("Mark a baseline, or hide, publish or withdraw a leaderboard row.")
        .bearer("admin")
        .body(
            &["application/json"],
            "`baseline` (bool) and/or `visibility`: `published`, `hidden` or `withdrawn`.",
            Some("{\"baseline\": true, \"visibility\": \"published\"}"),
        )
        .responds(200, Some("application/json"), "The submission as changed.")
        .errors(&[400, 401, 403, 404, 422]),
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
        .bearer("admin")
        .body(&["application/json"], "`{\"answers\": \"public\" | \"hidden\"}`.", Some("{\"answers\": \"public\"}"))
        .responds(200, Some("application/json"), "The dataset's setting.")
        .errors(&[400, 401, 403, 404, 422]),
        ApiRoute::new(Verb::Post, "/admin/tokens", create_token, "Create an API token")
            .describe(
                "Creates the account if it is new, and a token for it. The token's secret is in \
                 this response only; the server keeps its SHA-256.",
            )
            .bearer("admin")
            .body(
                &["application/json"],
                "`name` (1 to 100 characters), `role` (`submitter`, the default, or `admin`), \
                 optional `daily_quota` and `total_quota` (else the server's defaults).",
                Some("{\"name\": \"team-a\", \"role\": \"submitter\", \"daily_quota\": 5}"),
            )
            .responds(201, Some("application/json"), "`id`, `prefix`, `account`, `role`, and `token`, the secret.")
            .errors(&[400, 401, 403, 409, 422]),
        ApiRoute::new(Verb::Get, "/admin/tokens", list_tokens, "List API tokens")
            .describe("Every token with its account, role, scopes, quotas, creation, last use and revocation; never a secret.")
            .bearer("admin")
            .responds(200, Some("application/json"), "The tokens.")
            .errors(&[401, 403]),
        ApiRoute::new(Verb::Delete, "/admin/tokens/{token}", revoke_token, "Revoke an API token")
            .describe("Takes effect at once: the next request with the token gets 401.")
            .bearer("admin")
            .responds(204, None, "Revoked.")
            .errors(&[401, 403, 404]),
    ]
}

/// A dataset's scoring targets and their `items` row ids, in dataset order.
pub struct DatasetTargets {
    pub targets: Vec<ScoringTarget>,
    pub item_rows: Vec<i64>,
}

/// Scoring targets per dataset, kept until the stored items change: deserialising the
/// signature tables of a full dataset costs more than scoring a submission against them.
#[derive(Default)]
pub struct TargetCache {
    entries: Mutex<HashMap<i64, (i64, Arc<DatasetTargets>)>>,
}

impl TargetCache {
    fn get(&self, dataset: i64, generation: i64) -> Option<Arc<DatasetTargets>> {
        let entries = self.entries.lock().ok()?;
        entries
            .get(&dataset)
            .filter(|(g, _)| *g == generation)
            .map(|(_, t)| t.clone())
    }

    fn put(&self, dataset: i64, generation: i64, targets: Arc<DatasetTargets>) {
        if let Ok(mut entries) = self.entries.lock() {
            entries.insert(dataset, (generation, targets));
        }
    }
}

pub async fn dataset_targets(
    state: &AppState,
    dataset: i64,
) -> Result<Arc<DatasetTargets>, AppError> {
    let mut conn = state.pool.acquire().await?;
    let generation = store::content_generation(&mut conn).await?;
    if let Some(t) = state.targets.get(dataset, generation) {
        return Ok(t);
    }
    let rows = store::items::scoring_items(&mut conn, dataset).await?;
    drop(conn);
    let targets = tokio::task::spawn_blocking(move || {
        let item_rows = rows.iter().map(|r| r.row_id).collect();
        scoring::targets_from_stored(rows).map(|targets| DatasetTargets { targets, item_rows })
    })
    .await
    .map_err(|e| AppError::Internal(e.into()))?
    .map_err(|e| AppError::Internal(anyhow::anyhow!(e)))?;
    let targets = Arc::new(targets);
    state.targets.put(dataset, generation, targets.clone());
    Ok(targets)
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

impl SubmitQuery {
    fn metadata(self) -> Result<SubmissionMetadata, AppError> {
        let model = self
            .model
            .map(|m| m.trim().to_owned())
            .filter(|m| !m.is_empty())
            .ok_or_else(|| {
                AppError::BadRequest(
                    "query parameter `model` is required (the model's name for the leaderboard)"
                        .to_owned(),
                )
            })?;
        if model.chars().count() > 200 {
            return Err(AppError::BadRequest(
                "query parameter `model` is longer than 200 characters".to_owned(),
            ));
        }
        Ok(SubmissionMetadata {
            model,
            description: self.description.unwrap_or_default(),
            url: self.url.unwrap_or_default(),
            prompt_version: self.prompt_version.unwrap_or_default(),
            notes: self.notes.unwrap_or_default(),
        })
    }
}

/// Seconds until the next UTC midnight, when daily quotas reset.
fn seconds_until_utc_midnight() -> u64 {
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    86_400 - now % 86_400
}

/// Reads the body frame by frame, refusing it as soon as it passes `limit`.
async fn read_body(mut body: Body, headers: &HeaderMap, limit: usize) -> Result<Vec<u8>, AppError> {
    let too_large = || {
        AppError::PayloadTooLarge(format!(
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
    let mut bytes = Vec::with_capacity(declared.unwrap_or(0));
    while let Some(frame) = std::future::poll_fn(|cx| Pin::new(&mut body).poll_frame(cx)).await {
        let frame = frame.map_err(|e| {
            AppError::BadRequest(format!("the request body could not be read: {e}"))
        })?;
        if let Ok(data) = frame.into_data() {
            if bytes.len() + data.len() > limit {
                return Err(too_large());
            }
            bytes.extend_from_slice(&data);
        }
    }
    Ok(bytes)
}

/// What the API says about a submission.
#[derive(Serialize)]
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
    status: String,
    policy: String,
    visibility: String,
    baseline: bool,
    created_at: String,
    scores: Value,
    /// Per-item verdicts: only for the owner, and only if the dataset's answers are public.
    #[serde(skip_serializing_if = "Option::is_none")]
    items: Option<Vec<ItemVerdictView>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    items_withheld: Option<String>,
}

#[derive(Serialize)]
struct ItemVerdictView {
    id: String,
    direction: String,
    step_length: i64,
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

impl SubmissionView {
    fn new(row: SubmissionRow) -> Result<SubmissionView, AppError> {
        let scores = serde_json::from_str(&row.scores).map_err(|e| {
            AppError::Internal(anyhow::anyhow!(
                "submission {}: scores unreadable: {e}",
                row.id
            ))
        })?;
        Ok(SubmissionView {
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
            created_at: row.created_at,
            scores,
            items: None,
            items_withheld: None,
        })
    }
}

async fn submit(
    State(state): State<AppState>,
    Path(dataset_name): Path<String>,
    Query(query): Query<SubmitQuery>,
    caller: Caller,
    headers: HeaderMap,
    body: Body,
) -> Result<Response, AppError> {
    require(&caller, Scope::Submit)?;
    let dataset = dataset_or_404(&state.pool, &dataset_name).await?;
    let metadata = query.metadata()?;
    let idempotency_key = match headers.get("idempotency-key") {
        None => None,
        Some(v) => Some(
            v.to_str()
                .ok()
                .map(str::trim)
                .filter(|k| !k.is_empty() && k.len() <= 200)
                .ok_or_else(|| {
                    AppError::BadRequest(
                        "the Idempotency-Key header must be 1 to 200 printable characters"
                            .to_owned(),
                    )
                })?
                .to_owned(),
        ),
    };
    if let Some(key) = &idempotency_key {
        let mut conn = state.pool.acquire().await?;
        if let Some(existing) =
            store::submissions::by_idempotency_key(&mut conn, caller.token_id, key).await?
        {
            drop(conn);
            let bytes = read_body(body, &headers, state.submission_body_limit).await?;
            return idempotent_repeat(existing, &bytes);
        }
    }

    // Every authenticated attempt counts against the quota, refused ones too.
    let exempt = caller.has(Scope::Admin);
    if !exempt {
        let mut conn = state.pool.acquire().await?;
        let daily = caller.daily_quota.unwrap_or(state.daily_quota);
        let total = caller.total_quota.unwrap_or(state.total_quota);
        match store::accounts::record_attempt(&mut conn, caller.token_id, daily, total).await? {
            AttemptQuota::Granted => {}
            AttemptQuota::DailyExhausted { limit } => {
                let retry_after = seconds_until_utc_midnight();
                return Err(AppError::TooManyRequests {
                    message: format!(
                        "this token has used its {limit} submissions for today (UTC); \
                         try again in {retry_after} s"
                    ),
                    retry_after: Some(retry_after),
                });
            }
            AttemptQuota::TotalExhausted { used, limit } => {
                // No Retry-After: the total never refills, so waiting would not help.
                return Err(AppError::TooManyRequests {
                    message: format!(
                        "this token's total quota is used up: {used} of {limit} submissions \
                         made; waiting will not help, ask an admin for a new token or a larger \
                         total quota"
                    ),
                    retry_after: None,
                });
            }
        }
    }

    let bytes = read_body(body, &headers, state.submission_body_limit).await?;
    let targets = dataset_targets(&state, dataset.id).await?;
    let scored = tokio::task::spawn_blocking({
        let targets = targets.clone();
        let dataset_name = dataset.name.clone();
        move || {
            let body_sha256 = hex::encode(Sha256::digest(&bytes));
            let text = std::str::from_utf8(&bytes).map_err(|e| {
                let line = bytes[..e.valid_up_to()]
                    .iter()
                    .filter(|b| **b == b'\n')
                    .count()
                    + 1;
                AppError::Unprocessable {
                    message: format!(
                        "line {line}: the body is not UTF-8 text (byte {} is invalid)",
                        e.valid_up_to()
                    ),
                    problems: Vec::new(),
                }
            })?;
            let scored = match score_submission(&targets.targets, text) {
                Ok(s) => s,
                Err(SubmissionError::Rejected(problems)) => {
                    let first: Vec<String> =
                        problems.iter().take(5).map(|p| p.message.clone()).collect();
                    return Err(AppError::Unprocessable {
                        message: format!(
                            "{} problems; nothing was stored: {}{}",
                            problems.len(),
                            first.join("; "),
                            if problems.len() > 5 { "; …" } else { "" }
                        ),
                        problems,
                    });
                }
                Err(SubmissionError::Dataset(e)) => {
                    return Err(AppError::Internal(anyhow::anyhow!(
                        "dataset {dataset_name} cannot be scored: {e}"
                    )));
                }
            };
            let scores_json =
                serde_json::to_string(&scored.scores).map_err(|e| AppError::Internal(e.into()))?;
            Ok((body_sha256, scored, scores_json))
        }
    })
    .await
    .map_err(|e| AppError::Internal(e.into()))??;
    let (body_sha256, scored, scores_json) = scored;

    let mut tx = state.pool.begin().await?;
    let new = NewSubmission {
        dataset: dataset.id,
        account: caller.account_id,
        token: caller.token_id,
        idempotency_key: idempotency_key.as_deref(),
        body_sha256: &body_sha256,
        metadata: &metadata,
        scores_json: &scores_json,
    };
    let Some(id) = store::submissions::insert(&mut tx, &new).await? else {
        // A twin request with the same key committed first.
        tx.rollback().await?;
        let mut conn = state.pool.acquire().await?;
        let key = idempotency_key.as_deref().unwrap_or_default();
        let existing = store::submissions::by_idempotency_key(&mut conn, caller.token_id, key)
            .await?
            .ok_or_else(|| AppError::Internal(anyhow::anyhow!("idempotent twin vanished")))?;
        return respond(existing, StatusCode::OK);
    };
    store::submissions::insert_items(&mut tx, id, &targets.item_rows, &scored.items).await?;
    tx.commit().await?;
    tracing::info!(
        submission = id,
        dataset = %dataset.name,
        account = %caller.account_name,
        model = %metadata.model,
        "submission scored"
    );
    let mut conn = state.pool.acquire().await?;
    let row = store::submissions::by_id(&mut conn, id)
        .await?
        .ok_or_else(|| AppError::Internal(anyhow::anyhow!("submission {id} vanished")))?;
    respond(row, StatusCode::CREATED)
}

fn idempotent_repeat(existing: SubmissionRow, bytes: &[u8]) -> Result<Response, AppError> {
    if hex::encode(Sha256::digest(bytes)) != existing.body_sha256 {
        return Err(AppError::Conflict(format!(
            "this Idempotency-Key was used for submission {} with a different body",
            existing.id
        )));
    }
    respond(existing, StatusCode::OK)
}

fn respond(row: SubmissionRow, status: StatusCode) -> Result<Response, AppError> {
    let location = format!("/api/v1/submissions/{}", row.id);
    let view = SubmissionView::new(row)?;
    Ok((status, [(header::LOCATION, location)], Json(view)).into_response())
}

fn parse_submission_id(raw: &str) -> Result<i64, AppError> {
    raw.parse::<i64>()
        .map_err(|_| AppError::NotFound(format!("no submission {raw}")))
}

async fn get_submission(
    State(state): State<AppState>,
    Path(raw_id): Path<String>,
    caller: Caller,
) -> Result<Json<SubmissionView>, AppError> {
    if !caller.has(Scope::ReadOwn) && !caller.has(Scope::Admin) {
        return Err(AppError::Forbidden(
            "this token lacks the `read_own` scope".to_owned(),
        ));
    }
    let id = parse_submission_id(&raw_id)?;
    let mut conn = state.pool.acquire().await?;
    let row = store::submissions::by_id(&mut conn, id)
        .await?
        // Another account's submission is answered like a missing one: ids reveal nothing.
        .filter(|r| r.account_id == caller.account_id || caller.has(Scope::Admin))
        .ok_or_else(|| AppError::NotFound(format!("no submission {raw_id}")))?;
    let visibility = store::submissions::answer_visibility(&mut conn, row.dataset_id).await?;
    let owner = row.account_id == caller.account_id;
    let mut view = SubmissionView::new(row)?;
    if visibility == AnswerVisibility::Public && (owner || caller.has(Scope::Admin)) {
        let verdicts = store::submissions::verdicts(&mut conn, id).await?;
        view.items = Some(
            verdicts
                .into_iter()
                .map(|v| ItemVerdictView {
                    answer: parse_json_column(v.raw_answer.as_deref()),
                    permutation: parse_json_column(v.permutation.as_deref()),
                    ground_truth: parse_json_column(Some(&v.gt_answer)).unwrap_or(Value::Null),
                    id: v.id,
                    direction: v.direction,
                    step_length: v.step_length,
                    line: v.line,
                    outcome: v.outcome,
                    failure: v.failure,
                    exact_match: v.exact_match,
                    semantic_match: v.semantic_match,
                    task_accuracy: v.task_accuracy,
                    pairwise_accuracy: v.pairwise_accuracy,
                })
                .collect(),
        );
    } else {
        view.items_withheld = Some(format!(
            "per-item verdicts are not shown: the answers of dataset '{}' are {}",
            view.dataset,
            visibility.as_str()
        ));
    }
    Ok(Json(view))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ListingChange {
    baseline: Option<bool>,
    visibility: Option<String>,
}

async fn update_listing(
    State(state): State<AppState>,
    Path(raw_id): Path<String>,
    caller: Caller,
    Json(change): Json<ListingChange>,
) -> Result<Json<SubmissionView>, AppError> {
    require(&caller, Scope::Admin)?;
    let id = parse_submission_id(&raw_id)?;
    if let Some(v) = change.visibility.as_deref()
        && !matches!(v, "published" | "hidden" | "withdrawn")
    {
        return Err(AppError::BadRequest(format!(
            "visibility must be 'published', 'hidden' or 'withdrawn', not {v:?}"
        )));
    }
    let mut conn = state.pool.acquire().await?;
    if !store::submissions::update_listing(
        &mut conn,
        id,
        change.baseline,
        change.visibility.as_deref(),
    )
    .await?
    {
        return Err(AppError::NotFound(format!("no submission {raw_id}")));
    }
    let row = store::submissions::by_id(&mut conn, id)
        .await?
        .ok_or_else(|| AppError::NotFound(format!("no submission {raw_id}")))?;
    Ok(Json(SubmissionView::new(row)?))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AnswersChange {
    answers: AnswerVisibility,
}

#[derive(Serialize)]
struct AnswersView {
    dataset: String,
    answers: AnswerVisibility,
}

async fn set_answers(
    State(state): State<AppState>,
    Path(dataset_name): Path<String>,
    caller: Caller,
    Json(change): Json<AnswersChange>,
) -> Result<Json<AnswersView>, AppError> {
    require(&caller, Scope::Admin)?;
    let dataset = dataset_or_404(&state.pool, &dataset_name).await?;
    let mut conn = state.pool.acquire().await?;
    store::submissions::set_answer_visibility(&mut conn, dataset.id, change.answers).await?;
    Ok(Json(AnswersView {
        dataset: dataset.name,
        answers: change.answers,
    }))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TokenRequest {
    name: String,
    role: Option<String>,
    daily_quota: Option<i64>,
    total_quota: Option<i64>,
}

#[derive(Serialize)]
pub(super) struct CreatedToken {
    pub id: i64,
    pub prefix: String,
    pub account: String,
    pub role: &'static str,
    /// The secret, shown this once.
    pub token: String,
}

async fn create_token(
    State(state): State<AppState>,
    caller: Caller,
    Json(request): Json<TokenRequest>,
) -> Result<(StatusCode, Json<CreatedToken>), AppError> {
    require(&caller, Scope::Admin)?;
    let role = match request.role.as_deref() {
        None => Role::Submitter,
        Some(r) => parse_role(r)?,
    };
    let created = issue_token(
        &state,
        &request.name,
        role,
        request.daily_quota,
        request.total_quota,
    )
    .await?;
    Ok((StatusCode::CREATED, Json(created)))
}

pub(super) fn parse_role(text: &str) -> Result<Role, AppError> {
    Role::parse(text).ok_or_else(|| {
        AppError::BadRequest(format!("role must be 'submitter' or 'admin', not {text:?}"))
    })
}

/// Creates a token (and its account if new) for the JSON API and the admin page alike.
pub(super) async fn issue_token(
    state: &AppState,
    name: &str,
    role: Role,
    daily_quota: Option<i64>,
    total_quota: Option<i64>,
) -> Result<CreatedToken, AppError> {
    let name = name.trim();
    if name.is_empty() || name.chars().count() > 100 {
        return Err(AppError::BadRequest(
            "`name` must be 1 to 100 characters".to_owned(),
        ));
    }
    for (field, quota) in [("daily_quota", daily_quota), ("total_quota", total_quota)] {
        if quota.is_some_and(|q| q < 0) {
            return Err(AppError::BadRequest(format!(
                "`{field}` must not be negative"
            )));
        }
    }
    let token = NewToken::generate();
    let mut tx = state.pool.begin().await?;
    let account = store::accounts::ensure_account(&mut tx, name, role)
        .await?
        .map_err(AppError::Conflict)?;
    let id =
        store::accounts::insert_token(&mut tx, account, role, &token, daily_quota, total_quota)
            .await?;
    tx.commit().await?;
    Ok(CreatedToken {
        id,
        prefix: token.prefix.clone(),
        account: name.to_owned(),
        role: role.as_str(),
        token: token.token,
    })
}

async fn list_tokens(
    State(state): State<AppState>,
    caller: Caller,
) -> Result<Json<Vec<store::accounts::TokenListing>>, AppError> {
    require(&caller, Scope::Admin)?;
    let mut conn = state.pool.acquire().await?;
    Ok(Json(store::accounts::list_tokens(&mut conn).await?))
}

async fn revoke_token(
    State(state): State<AppState>,
    Path(which): Path<String>,
    caller: Caller,
) -> Result<StatusCode, AppError> {
    require(&caller, Scope::Admin)?;
    let mut conn = state.pool.acquire().await?;
    if store::accounts::revoke_token(&mut conn, &which).await? {
        Ok(StatusCode::NO_CONTENT)
    } else {
        Err(AppError::NotFound(format!(
            "no live token with id or prefix {which:?}"
        )))
    }
}
