//! Model runs: the hub asks an OpenAI-compatible chat-completions endpoint every item of a
//! dataset itself, keeps every reply as it arrives, and submits the answers.
//!
//! A run is identified by its dataset, endpoint, model, generation parameters and prompt (or
//! by the name it was given). Each item's reply is committed as one row before the item
//! counts as done, so a run stopped anywhere (killed, crashed, its endpoint down) is resumed
//! by starting it again: items with a row are never asked again, and failed ones only when
//! asked to retry failures. A failure stays a failure: an item whose calls all failed, or
//! whose reply was empty or cut off, is stored as failed with its reason and submitted as
//! unanswered. When every item has a row, the answers go through the ordinary submission
//! use case ([`submissions::submit`]: quotas, scoring, audit) and the run is linked to the
//! submission with a stamp of everything that made it.

mod asker;
mod responses;
mod server;

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

use bytes::Bytes;
use serde::Serialize;
use sha2::{Digest, Sha256};
use tokio::task::JoinSet;

pub use asker::{ApiKey, CallSettings};
pub use responses::{
    Audience, RESPONSES_PER_PAGE, ResponsePage, RunOutput, output, public_runs, response_page,
    visible_run,
};
pub use server::{EndpointKeys, RunCalls, ServerRunView, control, start, view, views, work};

use super::submissions::{self, SubmissionRow, Submitted};
use super::tokens::{self, Caller};
use super::{AppError, Hub, datasets, frames, items};
use crate::core::audit::Actor;
use crate::core::credentials::{NewToken, Role};
pub use crate::core::model_run::{GenerationParams, Prices, Usage};
use crate::core::model_run::{
    PROMPT_VERSION, PromptImage, chat_request, prompt_template_hash, user_message,
};
use crate::core::submission::SubmissionMetadata;
use crate::store;
pub use crate::store::runs::{RunItemRow, RunRow};

/// The account model runs submit as (with one token whose secret nobody is shown).
pub const RUNS_ACCOUNT: &str = "model-runs";

/// What to run: the run's identity and what it does at the end.
#[derive(Debug, Clone)]
pub struct RunSpec {
    pub dataset: String,
    /// The endpoint's base URL (`…/v1`); its `/chat/completions` is called.
    pub endpoint: String,
    pub model: String,
    /// The run's name; made from its identity when not given.
    pub name: Option<String>,
    pub params: GenerationParams,
    /// Only the first `limit` items of the dataset (the rest are submitted unanswered).
    pub limit: Option<usize>,
    /// Ask the items that failed before again.
    pub retry_failed: bool,
    /// The leaderboard's model name to submit under; `None`: do not submit.
    pub submit_as: Option<String>,
    pub prices: Prices,
}

/// Where a run stands, as reported to the progress callback.
#[derive(Debug, Clone, Default, Serialize)]
pub struct RunProgress {
    /// Items this run covers (the limit applied).
    pub total: usize,
    /// Items with a row: answered or failed.
    pub done: usize,
    pub answered: usize,
    pub failed: usize,
    /// Asked in this process so far.
    pub asked_now: usize,
    pub in_flight: usize,
    pub usage: Usage,
    pub cost_usd: f64,
    pub requests: u64,
    pub refused: u64,
    pub elapsed_s: f64,
    /// The last few failures, newest last.
    pub recent_errors: Vec<String>,
}

/// How a run ended.
#[derive(Debug, Clone, Serialize)]
pub struct RunReport {
    pub run: String,
    pub run_id: i64,
    pub dataset: String,
    pub progress: RunProgress,
    /// Failure reasons and how many items each failed.
    pub failures: BTreeMap<String, usize>,
    /// The submission made (or found, when the same answers were submitted before).
    pub submission: Option<i64>,
    /// Whether items are left unasked (the run was stopped).
    pub stopped: bool,
}

/// The stamp a run's submission is made with.
#[derive(Debug, Clone, Serialize)]
pub struct RunStamp {
    pub run: String,
    pub endpoint_host: String,
    pub model: String,
    pub params: GenerationParams,
    pub limit: Option<usize>,
    pub concurrency: usize,
    pub max_retries: u32,
    pub timeout_s: f64,
    pub prompt_version: String,
    pub prompt_hash: String,
    pub hub_version: String,
    pub usage: Usage,
    pub prices: Prices,
    pub cost_usd: f64,
    pub answered: usize,
    pub failed: usize,
}

/// Errors in the endpoint URL are the caller's: a base URL over http(s), with no credentials
/// or query in it (keys go in the key's variable, never in the URL that is stored).
pub fn endpoint_url(endpoint: &str) -> Result<url::Url, AppError> {
    let bad = |why: &str| AppError::Invalid(format!("endpoint {endpoint:?}: {why}"));
    let url = url::Url::parse(endpoint.trim()).map_err(|e| bad(&e.to_string()))?;
    if !matches!(url.scheme(), "http" | "https") {
        return Err(bad("must be an http:// or https:// URL"));
    }
    if url.host_str().is_none() {
        return Err(bad("has no host"));
    }
    if !url.username().is_empty() || url.password().is_some() {
        return Err(bad(
            "must not hold credentials: give the key in an environment variable",
        ));
    }
    if url.query().is_some() || url.fragment().is_some() {
        return Err(bad(
            "must not have a query or fragment (a key in it would be stored)",
        ));
    }
    Ok(url)
}

/// The endpoint as stored: scheme, host, port and path, no trailing slash.
fn stored_endpoint(url: &url::Url) -> String {
    url.as_str().trim_end_matches('/').to_owned()
}

/// The name a run gets from its identity.
fn default_name(dataset: &str, endpoint: &str, model: &str, params: &str) -> String {
    let identity = format!(
        "{dataset}\n{endpoint}\n{model}\n{params}\n{PROMPT_VERSION}\n{}",
        prompt_template_hash()
    );
    let hash = hex::encode(Sha256::digest(identity.as_bytes()));
    format!("{model}@{dataset}-{}", &hash[..12])
}

/// The caller runs submit as: the runs account's token, created (its secret discarded) the
/// first time.
async fn runs_token(tx: &mut store::Tx) -> Result<i64, AppError> {
    let account = tokens::ensure_account(&mut *tx, RUNS_ACCOUNT, Role::Submitter).await?;
    if let Some(token) = store::runs::first_token_of(&mut *tx, account).await? {
        return Ok(token);
    }
    let token = NewToken::generate();
    Ok(
        store::accounts::insert_token(&mut *tx, account, Role::Submitter, &token, None, None)
            .await?,
    )
}

async fn run_caller(hub: &Hub, token: i64) -> Result<Caller, AppError> {
    let mut conn = hub.conn().await?;
    let t = store::runs::token_caller(&mut conn, token)
        .await?
        .ok_or_else(|| AppError::internal(format!("the token {token} of a model run vanished")))?;
    Ok(Caller {
        token_id: t.token_id,
        account_id: t.account_id,
        account_name: t.account_name,
        scopes: t.scopes,
        daily_quota: t.daily_quota,
        total_quota: t.total_quota,
    })
}

/// A run's identity as `spec` gives it, checked.
struct Identity {
    name: String,
    dataset_id: i64,
    dataset: String,
    endpoint: String,
    params: String,
    prompt_hash: String,
}

async fn identity(hub: &Hub, spec: &RunSpec) -> Result<Identity, AppError> {
    let dataset = datasets::by_name(hub, &spec.dataset).await?;
    let endpoint = stored_endpoint(&endpoint_url(&spec.endpoint)?);
    if spec.model.trim().is_empty() {
        return Err(AppError::Invalid("the model name is empty".to_owned()));
    }
    let params = serde_json::to_string(&spec.params)?;
    let name = match &spec.name {
        Some(n) if n.trim().is_empty() || n.chars().count() > 200 => {
            return Err(AppError::Invalid(
                "a run's name must be 1 to 200 characters".to_owned(),
            ));
        }
        Some(n) => n.trim().to_owned(),
        None => default_name(&dataset.name, &endpoint, &spec.model, &params),
    };
    Ok(Identity {
        name,
        dataset_id: dataset.id,
        dataset: dataset.name,
        endpoint,
        params,
        prompt_hash: prompt_template_hash(),
    })
}

/// The run `spec` names, found (its identity must match) or created on `tx`.
async fn find_or_create(
    tx: &mut store::Tx,
    actor: &Actor,
    spec: &RunSpec,
    id: &Identity,
) -> Result<RunRow, AppError> {
    let name = &id.name;
    if store::runs::by_name(&mut *tx, name).await?.is_none() {
        let token = runs_token(tx).await?;
        let new = store::runs::NewRun {
            name,
            dataset: id.dataset_id,
            endpoint: &id.endpoint,
            model: &spec.model,
            params: &id.params,
            prompt_version: PROMPT_VERSION,
            prompt_hash: &id.prompt_hash,
            token,
            created_by: &actor.to_string(),
        };
        // `None`: created meanwhile by another process; the identity check below applies.
        store::runs::insert(&mut *tx, &new).await?;
    }
    let run = store::runs::by_name(&mut *tx, name)
        .await?
        .ok_or_else(|| AppError::internal(format!("run '{name}' vanished")))?;
    let differs = [
        ("dataset", run.dataset.as_str(), id.dataset.as_str()),
        ("endpoint", &run.endpoint, &id.endpoint),
        ("model", &run.model, &spec.model),
        ("parameters", &run.params, &id.params),
        ("prompt version", &run.prompt_version, PROMPT_VERSION),
        ("prompt hash", &run.prompt_hash, &id.prompt_hash),
    ]
    .into_iter()
    .find(|(_, stored, given)| stored != given);
    match differs {
        None => Ok(run),
        Some((what, stored, given)) => Err(AppError::Conflict(format!(
            "run '{name}' exists with {what} {stored}, not {given}: \
             give another run name to start a new run"
        ))),
    }
}

/// The run `spec` names: found (its identity must match) or created.
pub async fn open(hub: &Hub, actor: &Actor, spec: &RunSpec) -> Result<RunRow, AppError> {
    let id = identity(hub, spec).await?;
    let mut tx = hub.begin().await?;
    let run = find_or_create(&mut tx, actor, spec, &id).await?;
    tx.commit().await?;
    Ok(run)
}

/// A run by name.
pub async fn by_name(hub: &Hub, name: &str) -> Result<RunRow, AppError> {
    let mut conn = hub.conn().await?;
    store::runs::by_name(&mut conn, name)
        .await?
        .ok_or_else(|| AppError::NotFound(format!("no model run '{name}'")))
}

/// Every run, newest first.
pub async fn list(hub: &Hub) -> Result<Vec<RunRow>, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::runs::list(&mut conn).await?)
}

/// A run's finished items, in dataset order.
pub async fn item_rows(hub: &Hub, run: &RunRow) -> Result<Vec<RunItemRow>, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::runs::items(&mut conn, run.id).await?)
}

/// What a progress callback is handed, as often as an item finishes.
pub type ProgressFn<'a> = &'a (dyn Fn(&RunProgress) + Send + Sync);

/// How many failures progress keeps.
const RECENT_ERRORS: usize = 5;

/// Asks every item of the run that is not done yet, keeping each reply as it arrives, then
/// (when every item is done and `spec.submit_as` is set) submits the answers. Stops between
/// items when `stop` returns true; what was done stays done.
pub async fn execute(
    hub: &Hub,
    actor: &Actor,
    spec: &RunSpec,
    settings: &CallSettings,
    progress: ProgressFn<'_>,
    stop: &(dyn Fn() -> bool + Send + Sync),
) -> Result<RunReport, AppError> {
    if settings.concurrency == 0 {
        return Err(AppError::Invalid(
            "concurrency must be at least 1".to_owned(),
        ));
    }
    if spec.limit == Some(0) {
        return Err(AppError::Invalid("limit must be at least 1".to_owned()));
    }
    let run = open(hub, actor, spec).await?;
    let params: GenerationParams = serde_json::from_str(&run.params)?;
    let asker =
        Arc::new(asker::Asker::new(&run.endpoint, settings.clone()).map_err(AppError::internal)?);
    let mut conn = hub.conn().await?;
    let states = store::runs::item_states(
        &mut conn,
        run.id,
        run.dataset_id,
        spec.limit.map(|l| i64::try_from(l).unwrap_or(i64::MAX)),
    )
    .await?;
    let rows = store::runs::items(&mut conn, run.id).await?;
    drop(conn);

    let mut state = RunProgress {
        total: states.len(),
        ..RunProgress::default()
    };
    let counted: std::collections::HashSet<&str> =
        states.iter().map(|s| s.item_id.as_str()).collect();
    for row in rows.iter().filter(|r| counted.contains(r.item_id.as_str())) {
        state.usage += Usage {
            prompt_tokens: row.prompt_tokens.max(0) as u64,
            completion_tokens: row.completion_tokens.max(0) as u64,
        };
        if row.answered {
            state.answered += 1;
        } else {
            state.failed += 1;
        }
    }
    drop(rows);
    state.done = state.answered + state.failed;
    state.cost_usd = spec.prices.cost(state.usage);
    progress(&state);

    // (item row, item id, whether it failed before)
    let pending: Vec<(i64, String, bool)> = states
        .into_iter()
        .filter_map(|s| match s.state.as_deref() {
            None => Some((s.item_row, s.item_id, false)),
            Some("failed") if spec.retry_failed => Some((s.item_row, s.item_id, true)),
            Some(_) => None,
        })
        .collect();
    let started = Instant::now();
    let mut tasks: JoinSet<Result<(RunItemRow, bool), AppError>> = JoinSet::new();
    let mut queue = pending.into_iter();
    let mut stopped = false;
    loop {
        // Items in hand are bounded by the concurrency: each holds one request's images.
        while tasks.len() < settings.concurrency && !stopped {
            if stop() {
                stopped = true;
                break;
            }
            let Some((item_row, item_id, failed_before)) = queue.next() else {
                break;
            };
            let (hub, asker, dataset) = (hub.clone(), asker.clone(), run.dataset.clone());
            let (model, params, run_id) = (run.model.clone(), params.clone(), run.id);
            tasks.spawn(async move {
                let body = request_body(&hub, &dataset, &item_id, &model, &params).await?;
                let asked = asker.ask(body).await;
                let row = RunItemRow {
                    item_id: item_id.clone(),
                    answered: asked.outcome.is_ok(),
                    response: asked.response,
                    finish_reason: asked.finish_reason,
                    prompt_tokens: asked.usage.prompt_tokens as i64,
                    completion_tokens: asked.usage.completion_tokens as i64,
                    latency_ms: asked.latency.as_millis() as i64,
                    attempts: i64::from(asked.attempts),
                    error: asked.outcome.err().or(asked.last_error),
                    done_at: String::new(),
                };
                // Durable before it counts: a crash after this never asks the item again.
                let mut tx = hub.begin().await?;
                store::runs::record_item(&mut tx, run_id, item_row, &row).await?;
                tx.commit().await?;
                Ok((row, failed_before))
            });
        }
        let Some(joined) = tasks.join_next().await else {
            break;
        };
        let (row, failed_before) = joined??;
        if failed_before {
            state.failed -= 1;
        }
        if row.answered {
            state.answered += 1;
        } else {
            state.failed += 1;
            let reason = row.error.as_deref().unwrap_or("failed");
            state
                .recent_errors
                .push(format!("{}: {reason}", row.item_id));
            if state.recent_errors.len() > RECENT_ERRORS {
                state.recent_errors.remove(0);
            }
        }
        state.asked_now += 1;
        state.done = state.answered + state.failed;
        state.usage += Usage {
            prompt_tokens: row.prompt_tokens as u64,
            completion_tokens: row.completion_tokens as u64,
        };
        state.cost_usd = spec.prices.cost(state.usage);
        state.in_flight = asker.in_flight();
        (state.requests, state.refused) = asker.requests();
        state.elapsed_s = started.elapsed().as_secs_f64();
        progress(&state);
    }
    stopped = stopped || queue.next().is_some();
    (state.requests, state.refused) = asker.requests();
    state.in_flight = 0;
    state.elapsed_s = started.elapsed().as_secs_f64();

    let mut conn = hub.conn().await?;
    let rows = store::runs::items(&mut conn, run.id).await?;
    drop(conn);
    let mut failures = BTreeMap::new();
    for row in rows.iter().filter(|r| !r.answered) {
        *failures
            .entry(failure_kind(row.error.as_deref()))
            .or_insert(0) += 1;
    }
    let mut report = RunReport {
        run: run.name.clone(),
        run_id: run.id,
        dataset: run.dataset.clone(),
        progress: state,
        failures,
        submission: None,
        stopped,
    };
    if !stopped && let Some(model) = &spec.submit_as {
        let row = submit(hub, &run, spec, settings, &rows, &report, model).await?;
        report.submission = Some(row.id);
    }
    progress(&report.progress);
    Ok(report)
}

/// A failure's reason without the item-specific detail, for counting reasons.
fn failure_kind(error: Option<&str>) -> String {
    let error = error.unwrap_or("failed");
    let short: String = error
        .split(": ")
        .take(2)
        .collect::<Vec<_>>()
        .join(": ")
        .chars()
        .take(120)
        .collect();
    short
}

/// The request body for one item: its images read from the frame store, encoded, and
/// dropped as soon as the body is written.
async fn request_body(
    hub: &Hub,
    dataset: &str,
    item_id: &str,
    model: &str,
    params: &GenerationParams,
) -> Result<Bytes, AppError> {
    let item = items::get(hub, dataset, item_id).await?;
    let mut pngs = Vec::with_capacity(item.images.len());
    for image in &item.images {
        pngs.push((image.label(), frames::png(hub, &image.sha256).await?));
    }
    let question = item.question.clone();
    let model = model.to_owned();
    let params = params.clone();
    // Base64 of up to ten 512×512 PNGs: off the async workers.
    tokio::task::spawn_blocking(move || {
        let images: Vec<PromptImage<'_>> = pngs
            .iter()
            .map(|(label, png)| PromptImage { label, png })
            .collect();
        let body = chat_request(&model, &params, user_message(&images, &question));
        serde_json::to_vec(&body).map(Bytes::from)
    })
    .await?
    .map_err(AppError::from)
}

/// Submits the run's answers (failed items left out, so they count as unanswered) and links
/// the submission to the run. The same answers submitted again find the first submission.
async fn submit(
    hub: &Hub,
    run: &RunRow,
    spec: &RunSpec,
    settings: &CallSettings,
    rows: &[RunItemRow],
    report: &RunReport,
    model: &str,
) -> Result<SubmissionRow, AppError> {
    let mut body = String::new();
    for row in rows.iter().filter(|r| r.answered) {
        let Some(answer) = &row.response else {
            continue;
        };
        body.push_str(&serde_json::to_string(
            &serde_json::json!({"id": row.item_id, "answer": answer}),
        )?);
        body.push('\n');
    }
    let usage = rows.iter().fold(Usage::default(), |mut u, r| {
        u += Usage {
            prompt_tokens: r.prompt_tokens.max(0) as u64,
            completion_tokens: r.completion_tokens.max(0) as u64,
        };
        u
    });
    let host = url::Url::parse(&run.endpoint)
        .ok()
        .and_then(|u| {
            u.host_str().map(|h| {
                u.port()
                    .map_or_else(|| h.to_owned(), |p| format!("{h}:{p}"))
            })
        })
        .unwrap_or_default();
    let stamp = RunStamp {
        run: run.name.clone(),
        endpoint_host: host.clone(),
        model: run.model.clone(),
        params: serde_json::from_str(&run.params)?,
        limit: spec.limit,
        concurrency: settings.concurrency,
        max_retries: settings.max_retries,
        timeout_s: settings.timeout.as_secs_f64(),
        prompt_version: run.prompt_version.clone(),
        prompt_hash: run.prompt_hash.clone(),
        hub_version: env!("CARGO_PKG_VERSION").to_owned(),
        usage,
        prices: spec.prices,
        cost_usd: spec.prices.cost(usage),
        answered: report.progress.answered,
        failed: report.progress.failed,
    };
    let stamp_json = serde_json::to_string(&stamp)?;
    let metadata = SubmissionMetadata {
        model: model.to_owned(),
        description: format!("model run '{}' of {} on {host}", run.name, run.model),
        url: String::new(),
        prompt_version: format!("{} ({})", run.prompt_version, &run.prompt_hash[..12]),
        notes: stamp_json.clone(),
    };
    let caller = run_caller(hub, run.token).await?;
    let key = format!(
        "model-run-{}-{}",
        run.id,
        &hex::encode(Sha256::digest(body.as_bytes()))[..16]
    );
    let bytes = body.into_bytes();
    let submitted = submissions::submit(
        hub,
        &caller,
        &run.dataset,
        metadata,
        Some(&key),
        async move { Ok(bytes) },
    )
    .await?;
    let row = match submitted {
        Submitted::Created(row) | Submitted::Repeated(row) => row,
    };
    let mut tx = hub.begin().await?;
    store::runs::set_submission(&mut tx, run.id, row.id, &stamp_json).await?;
    tx.commit().await?;
    Ok(row)
}
