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

mod remote;
mod responses;
mod server;

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

use bytes::Bytes;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use tokio::task::JoinSet;

/// The model endpoint's client, from the outbound clients' crate.
use enact_outbound::endpoint as asker;
pub use enact_outbound::endpoint::{ApiKey, CallSettings};
pub use enact_outbound::hub::RemoteHub;
pub use remote::{default_cache, execute_remote, study_datasets};
pub use responses::{
    Audience, RESPONSES_PER_PAGE, ResponsePage, RunOutput, StampedRun, output, public_runs,
    response_page, stamp, visible_run,
};
pub use server::{
    EndpointKeys, MOST_CONCURRENCY, RunCalls, RunJobProgress, RunStage, ServerRunView, control,
    start, view, views, work,
};

use super::refusal::Refusal;
use super::submissions::{self, Submitted};
use super::tokens::{self, Caller};
use super::{AppError, Hub, datasets, frames, items};
use crate::Lane;
use crate::core::audit::{Actor, AuditAction};
use crate::core::credentials::{NewToken, Role};
pub use crate::core::model_run::{GenerationParams, ItemOutcome, Prices, RunFailure, Usage};
use crate::core::model_run::{
    PROMPT_VERSION, PromptImage, chat_request, prompt_template_hash, user_message,
};
use crate::core::submission::{Provenance, SubmissionMetadata};
use crate::store;
pub use crate::store::runs::{RunItemRow, RunRow};

/// The caches a command-line run keeps: a run reads each item once, so the server's defaults
/// (128 MiB of frames among them) would only hold memory that grows with the dataset's frames.
pub const CACHE_LIMITS: super::cache::CacheLimits = super::cache::CacheLimits {
    item_bytes: 4 * 1024 * 1024,
    standing_entries: 1_000,
    target_datasets: 1,
    board_datasets: 1,
    frame_bytes: 16 * 1024 * 1024,
    db_page_cache_bytes: 8 * 1024 * 1024,
};

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
    /// The run's row in the hub's database (none for a run against a remote hub).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub run_id: Option<i64>,
    pub dataset: String,
    pub progress: RunProgress,
    /// How many items failed with each kind of failure (keyed by the kind's code).
    pub failures: BTreeMap<RunFailure, usize>,
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
    store::runs::token_caller(&mut conn, token)
        .await?
        .ok_or_else(|| AppError::internal(format!("the token {token} of a model run vanished")))
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

/// What identifies a run of `dataset` besides the dataset, checked: the endpoint as stored,
/// the parameters as JSON, and the run's name (given, or made from the rest).
struct Named {
    endpoint: String,
    params: String,
    name: String,
}

fn named(dataset: &str, spec: &RunSpec) -> Result<Named, AppError> {
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
        None => default_name(dataset, &endpoint, &spec.model, &params),
    };
    Ok(Named {
        endpoint,
        params,
        name,
    })
}

async fn identity(hub: &Hub, spec: &RunSpec) -> Result<Identity, AppError> {
    let dataset = datasets::by_name(hub, &spec.dataset).await?;
    let Named {
        endpoint,
        params,
        name,
    } = named(&dataset.name, spec)?;
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
    let mut tx = hub.write(Lane::Interactive).await?;
    let run = find_or_create(&mut tx, actor, spec, &id).await?;
    tx.commit().await?;
    Ok(run)
}

/// A run by name.
pub async fn by_name(hub: &Hub, name: &str) -> Result<RunRow, AppError> {
    let mut conn = hub.conn().await?;
    store::runs::by_name(&mut conn, name).await?.ok_or_else(|| {
        AppError::from(Refusal::NoRun {
            run: name.to_owned(),
        })
    })
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

/// Asked between items: whether to stop (what was done stays done).
pub type StopFn<'a> = &'a (dyn Fn() -> bool + Send + Sync);

/// How many failures progress keeps.
const RECENT_ERRORS: usize = 5;

/// An item still to ask.
#[derive(Debug, Clone)]
struct Pending {
    /// Where the ledger finds the item (the item's row id; its place in a remote dataset).
    key: i64,
    item_id: String,
    /// Whether it failed before (asked again with `retry_failed`).
    failed_before: bool,
}

/// Where a run finds its items and keeps its replies: the hub's own database, or (for a
/// run against a remote hub) the hub's API and a cache file. The rest of a run is the same.
trait Ledger: Send + Sync + 'static {
    /// The question of `item` and its images, each with its label.
    fn item(&self, item: &Pending) -> impl Future<Output = Result<Asked, AppError>> + Send;

    /// Keeps `row` durably (committed or fsynced) before the item counts as done.
    fn record(
        &self,
        item: &Pending,
        row: &RunItemRow,
    ) -> impl Future<Output = Result<(), AppError>> + Send;

    /// Every reply kept for the run's items, in the items' order.
    fn rows(&self) -> impl Future<Output = Result<Vec<RunItemRow>, AppError>> + Send;

    /// What the run's submission is stamped with.
    fn head(&self) -> &RunHead;

    /// What names the run in its submission's idempotency key ([`submission_key`]).
    fn run_key(&self) -> String;

    /// Submits `body`, the run's answers, `stamped`, under the idempotency key `key`; the
    /// submission's id.
    fn send(
        &self,
        stamped: Stamped,
        key: &str,
        body: String,
    ) -> impl Future<Output = Result<i64, AppError>> + Send;
}

/// An item as a model is asked it: its question, and its images' labels and PNG bytes.
type Asked = (String, Vec<(String, Bytes)>);

/// What a run's tail ([`ask_and_report`]) is told besides its ledger.
struct Tail<'a> {
    dataset: String,
    model: &'a str,
    run: String,
    /// The run's row, for a run kept in this hub's database.
    run_id: Option<i64>,
    params: &'a GenerationParams,
    spec: &'a RunSpec,
    settings: &'a CallSettings,
}

/// The end every run shares, kept here or against another hub: asks the items `todo` holds,
/// reads back every reply the ledger keeps and reports them; when the run was not stopped and
/// `spec.submit_as` names a model, submits the answers first.
async fn ask_and_report<L: Ledger>(
    ledger: Arc<L>,
    asker: Arc<asker::Asker>,
    tail: Tail<'_>,
    todo: Vec<Pending>,
    mut state: RunProgress,
    progress: ProgressFn<'_>,
    stop: StopFn<'_>,
) -> Result<RunReport, AppError> {
    let stopped = ask_pending(
        ledger.clone(),
        asker,
        tail.model,
        tail.params,
        todo,
        &mut state,
        tail.spec.prices,
        tail.settings.concurrency,
        progress,
        stop,
    )
    .await?;
    let rows = ledger.rows().await?;
    let mut report = RunReport {
        run: tail.run,
        run_id: tail.run_id,
        dataset: tail.dataset,
        progress: state,
        failures: failures(&rows),
        submission: None,
        stopped,
    };
    if !stopped && let Some(model) = &tail.spec.submit_as {
        let body = answers_jsonl(&rows)?;
        let stamped = stamped(
            ledger.head(),
            tail.spec,
            tail.settings,
            &rows,
            &report,
            model,
        )?;
        let key = submission_key(&ledger.run_key(), &body);
        report.submission = Some(ledger.send(stamped, &key, body).await?);
    }
    progress(&report.progress);
    Ok(report)
}

/// The replies of a run's items that are stored already, counted.
fn tally<'a>(rows: impl IntoIterator<Item = &'a RunItemRow>, prices: Prices) -> RunProgress {
    let mut state = RunProgress::default();
    for row in rows {
        state.usage += row_usage(row);
        if row.outcome.is_answered() {
            state.answered += 1;
        } else {
            state.failed += 1;
        }
    }
    state.done = state.answered + state.failed;
    state.cost_usd = prices.cost(state.usage);
    state
}

fn row_usage(row: &RunItemRow) -> Usage {
    Usage {
        prompt_tokens: row.prompt_tokens.max(0) as u64,
        completion_tokens: row.completion_tokens.max(0) as u64,
    }
}

/// The kinds of failure of `rows` and how many items failed with each.
fn failures<'a>(rows: impl IntoIterator<Item = &'a RunItemRow>) -> BTreeMap<RunFailure, usize> {
    let mut failures = BTreeMap::new();
    for failure in rows.into_iter().filter_map(|r| r.outcome.failure()) {
        *failures.entry(failure).or_insert(0) += 1;
    }
    failures
}

/// The pending items of a run whose stored states are `states` (`None`: not asked yet).
fn pending<'a>(
    states: impl IntoIterator<Item = (i64, &'a str, Option<bool>)>,
    retry_failed: bool,
) -> Vec<Pending> {
    states
        .into_iter()
        .filter_map(|(key, item_id, answered)| match answered {
            None => Some((key, item_id, false)),
            Some(false) if retry_failed => Some((key, item_id, true)),
            Some(_) => None,
        })
        .map(|(key, item_id, failed_before)| Pending {
            key,
            item_id: item_id.to_owned(),
            failed_before,
        })
        .collect()
}

/// Asks every pending item, at most `concurrency` at once, keeping each reply in `ledger`
/// as it arrives and counting it into `state`. Returns whether it stopped before the end.
#[allow(clippy::too_many_arguments)]
async fn ask_pending<L: Ledger>(
    ledger: Arc<L>,
    asker: Arc<asker::Asker>,
    model: &str,
    params: &GenerationParams,
    pending: Vec<Pending>,
    state: &mut RunProgress,
    prices: Prices,
    concurrency: usize,
    progress: ProgressFn<'_>,
    stop: StopFn<'_>,
) -> Result<bool, AppError> {
    let started = Instant::now();
    let mut tasks: JoinSet<Result<(RunItemRow, bool), AppError>> = JoinSet::new();
    let mut queue = pending.into_iter().peekable();
    let mut stopped = false;
    loop {
        // Items in hand are bounded by the concurrency: each holds one request's images.
        while tasks.len() < concurrency && !stopped && queue.peek().is_some() {
            if stop() {
                stopped = true;
                break;
            }
            let Some(item) = queue.next() else {
                break;
            };
            let (ledger, asker) = (ledger.clone(), asker.clone());
            let (model, params) = (model.to_owned(), params.clone());
            tasks.spawn(async move {
                let (question, pngs) = ledger.item(&item).await?;
                let body = request_body(pngs, question, &model, &params).await?;
                let asked = asker.ask(body).await;
                let (outcome, error) = match asked.outcome {
                    Ok(_) => (ItemOutcome::Answered, asked.last_error),
                    Err((failure, message)) => (ItemOutcome::Failed(failure), Some(message)),
                };
                let row = RunItemRow {
                    item_id: item.item_id.clone(),
                    outcome,
                    response: asked.response,
                    finish_reason: asked.finish_reason,
                    prompt_tokens: asked.usage.prompt_tokens as i64,
                    completion_tokens: asked.usage.completion_tokens as i64,
                    latency_ms: asked.latency.as_millis() as i64,
                    attempts: i64::from(asked.attempts),
                    error,
                    done_at: String::new(),
                };
                // Durable before it counts: a crash after this never asks the item again.
                ledger.record(&item, &row).await?;
                Ok((row, item.failed_before))
            });
        }
        let Some(joined) = tasks.join_next().await else {
            break;
        };
        let (row, failed_before) = joined??;
        if failed_before {
            state.failed -= 1;
        }
        if let Some(failure) = row.outcome.failure() {
            state.failed += 1;
            let reason = match &row.error {
                Some(words) => words.clone(),
                None => failure.to_string(),
            };
            state
                .recent_errors
                .push(format!("{}: {reason}", row.item_id));
            if state.recent_errors.len() > RECENT_ERRORS {
                state.recent_errors.remove(0);
            }
        } else {
            state.answered += 1;
        }
        state.asked_now += 1;
        state.done = state.answered + state.failed;
        state.usage += row_usage(&row);
        state.cost_usd = prices.cost(state.usage);
        state.in_flight = asker.in_flight();
        (state.requests, state.refused) = asker.requests();
        state.elapsed_s = started.elapsed().as_secs_f64();
        progress(state);
    }
    (state.requests, state.refused) = asker.requests();
    state.in_flight = 0;
    state.elapsed_s = started.elapsed().as_secs_f64();
    Ok(stopped || queue.next().is_some())
}

/// A run kept in the hub's own database: items and frames from the store, one row per reply.
struct StoreLedger {
    hub: Hub,
    run: RunRow,
    head: RunHead,
}

impl Ledger for StoreLedger {
    async fn item(&self, item: &Pending) -> Result<Asked, AppError> {
        let stored = items::get(&self.hub, &self.run.dataset, &item.item_id).await?;
        let mut pngs = Vec::with_capacity(stored.images.len());
        for image in &stored.images {
            pngs.push((image.label(), frames::png(&self.hub, &image.sha256).await?));
        }
        Ok((stored.question.clone(), pngs))
    }

    async fn record(&self, item: &Pending, row: &RunItemRow) -> Result<(), AppError> {
        let mut tx = self.hub.write(Lane::Bulk).await?;
        store::runs::record_item(&mut tx, self.run.id, item.key, row).await?;
        tx.commit().await?;
        Ok(())
    }

    async fn rows(&self) -> Result<Vec<RunItemRow>, AppError> {
        let mut conn = self.hub.conn().await?;
        Ok(store::runs::items(&mut conn, self.run.id).await?)
    }

    fn head(&self) -> &RunHead {
        &self.head
    }

    fn run_key(&self) -> String {
        self.run.id.to_string()
    }

    /// Submits through the submission use case, as the run's token (quotas, scoring, audit),
    /// and links the submission to the run.
    async fn send(&self, stamped: Stamped, key: &str, body: String) -> Result<i64, AppError> {
        let Stamped { stamp, metadata } = stamped;
        let caller = run_caller(&self.hub, self.run.token).await?;
        let bytes = body.into_bytes();
        let submitted = submissions::submit(
            &self.hub,
            &caller,
            &self.run.dataset,
            metadata,
            Provenance::Run,
            Some(key),
            async move { Ok(bytes) },
        )
        .await?;
        let (Submitted::Created(row) | Submitted::Repeated(row)) = submitted;
        let mut tx = self.hub.write(Lane::Bulk).await?;
        store::runs::set_submission(&mut tx, self.run.id, row.id, &stamp).await?;
        tx.commit().await?;
        Ok(row.id)
    }
}

/// Asks every item of the run that is not done yet, keeping each reply as it arrives, then
/// (when every item is done and `spec.submit_as` is set) submits the answers. Stops between
/// items when `stop` returns true; what was done stays done.
pub async fn execute(
    hub: &Hub,
    actor: &Actor,
    spec: &RunSpec,
    settings: &CallSettings,
    progress: ProgressFn<'_>,
    stop: StopFn<'_>,
) -> Result<RunReport, AppError> {
    check_settings(spec, settings)?;
    let run = {
        let id = identity(hub, spec).await?;
        let mut tx = hub.write(Lane::Bulk).await?;
        let run = find_or_create(&mut tx, actor, spec, &id).await?;
        // A server's run was audited when it was started (`server::start`); one started at
        // the command line is audited each time it is started or resumed.
        if *actor != Actor::Server {
            super::audit::record(
                &mut tx,
                actor,
                AuditAction::RunStart,
                format!("run {}", run.name),
                Some(&run.dataset),
                format!("command line: {} at {}", run.model, run.endpoint),
            )
            .await?;
        }
        tx.commit().await?;
        run
    };
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

    let counted: std::collections::HashSet<&str> =
        states.iter().map(|s| s.item_id.as_str()).collect();
    let mut state = tally(
        rows.iter().filter(|r| counted.contains(r.item_id.as_str())),
        spec.prices,
    );
    state.total = states.len();
    drop(rows);
    progress(&state);

    let todo = pending(
        states.iter().map(|s| {
            let answered = s.state.map(ItemOutcome::is_answered);
            (s.item_row, s.item_id.as_str(), answered)
        }),
        spec.retry_failed,
    );
    drop(states);
    let tail = Tail {
        dataset: run.dataset.clone(),
        model: &run.model,
        run: run.name.clone(),
        run_id: Some(run.id),
        params: &params,
        spec,
        settings,
    };
    let ledger = Arc::new(StoreLedger {
        hub: hub.clone(),
        head: RunHead::of_row(&run),
        run: run.clone(),
    });
    ask_and_report(ledger, asker, tail, todo, state, progress, stop).await
}

/// What every run checks before it starts.
fn check_settings(spec: &RunSpec, settings: &CallSettings) -> Result<(), AppError> {
    spec.check()?;
    if settings.concurrency == 0 {
        return Err(AppError::Invalid(
            "concurrency must be at least 1".to_owned(),
        ));
    }
    Ok(())
}

impl RunSpec {
    /// Refuses a run no one can start, the same way wherever it was asked for (the API, the
    /// admin page's form, the command line): a limit of 0, an empty model to submit as, a
    /// price below 0 or not a number.
    pub fn check(&self) -> Result<(), AppError> {
        if self.limit == Some(0) {
            return Err(AppError::Invalid("limit must be at least 1".to_owned()));
        }
        if let Some(model) = &self.submit_as
            && model.trim().is_empty()
        {
            return Err(AppError::Invalid("submit_as is empty".to_owned()));
        }
        for (field, price) in [
            ("price_input", self.prices.input_usd_per_mtok),
            ("price_output", self.prices.output_usd_per_mtok),
        ] {
            if !(price.is_finite() && price >= 0.0) {
                return Err(AppError::from(Refusal::RunPrice {
                    field: field.to_owned(),
                    price: price.to_string(),
                }));
            }
        }
        Ok(())
    }
}

/// The request body for one item from its images' labels and PNG bytes (dropped as soon as
/// the body is written) and its question.
async fn request_body(
    pngs: Vec<(String, Bytes)>,
    question: String,
    model: &str,
    params: &GenerationParams,
) -> Result<Bytes, AppError> {
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

/// The answers of `rows` as compact submission JSONL: failed items left out, so that they
/// count as unanswered.
fn answers_jsonl(rows: &[RunItemRow]) -> Result<String, AppError> {
    let mut body = String::new();
    for row in rows.iter().filter(|r| r.outcome.is_answered()) {
        let Some(answer) = &row.response else {
            continue;
        };
        body.push_str(&serde_json::to_string(
            &serde_json::json!({"id": row.item_id, "answer": answer}),
        )?);
        body.push('\n');
    }
    Ok(body)
}

/// An endpoint's host and port, as a stamp names it (never its path or a key).
fn endpoint_host(endpoint: &str) -> String {
    url::Url::parse(endpoint)
        .ok()
        .and_then(|u| {
            u.host_str().map(|h| {
                u.port()
                    .map_or_else(|| h.to_owned(), |p| format!("{h}:{p}"))
            })
        })
        .unwrap_or_default()
}

/// What a run's submission is stamped with, and its leaderboard metadata.
struct Stamped {
    stamp: String,
    metadata: SubmissionMetadata,
}

/// The parts of a run that its stamp names: a run's row holds them, a remote run's cache
/// file keeps them in its header.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct RunHead {
    run: String,
    endpoint: String,
    model: String,
    /// The generation parameters as JSON.
    params: String,
    prompt_version: String,
    prompt_hash: String,
}

impl RunHead {
    fn of_row(run: &RunRow) -> RunHead {
        RunHead {
            run: run.name.clone(),
            endpoint: run.endpoint.clone(),
            model: run.model.clone(),
            params: run.params.clone(),
            prompt_version: run.prompt_version.clone(),
            prompt_hash: run.prompt_hash.clone(),
        }
    }
}

fn stamped(
    of: &RunHead,
    spec: &RunSpec,
    settings: &CallSettings,
    rows: &[RunItemRow],
    report: &RunReport,
    submit_as: &str,
) -> Result<Stamped, AppError> {
    let usage = tally(rows, spec.prices).usage;
    let host = endpoint_host(&of.endpoint);
    let stamp = RunStamp {
        run: of.run.clone(),
        endpoint_host: host.clone(),
        model: of.model.clone(),
        params: serde_json::from_str(&of.params)?,
        limit: spec.limit,
        concurrency: settings.concurrency,
        max_retries: settings.max_retries,
        timeout_s: settings.timeout.as_secs_f64(),
        prompt_version: of.prompt_version.clone(),
        prompt_hash: of.prompt_hash.clone(),
        hub_version: crate::core::version::BUILD.to_owned(),
        usage,
        prices: spec.prices,
        cost_usd: spec.prices.cost(usage),
        answered: report.progress.answered,
        failed: report.progress.failed,
    };
    let stamp = serde_json::to_string(&stamp)?;
    let metadata = SubmissionMetadata {
        model: submit_as.to_owned(),
        description: format!("model run '{}' of {} on {host}", of.run, of.model),
        url: String::new(),
        prompt_version: format!(
            "{} ({})",
            of.prompt_version,
            of.prompt_hash.get(..12).unwrap_or(&of.prompt_hash)
        ),
        notes: stamp.clone(),
    };
    Ok(Stamped { stamp, metadata })
}

/// The idempotency key of a run's submission (`run` names the run: its row id here, a hash
/// of its name for a remote hub): the same answers of the same run submitted again find the
/// first submission.
fn submission_key(run: &str, body: &str) -> String {
    format!(
        "model-run-{run}-{}",
        &hex::encode(Sha256::digest(body.as_bytes()))[..16]
    )
}
