//! Model runs the server works as jobs: started by an admin, worked by whichever serving
//! instance holds the job's lease, resumed after a restart or a takeover.
//!
//! A run's API key is named only by the environment variable that holds it, and only a
//! variable the server was started with (`serve --endpoint-key VAR`) may be named: otherwise
//! an admin could have the server send any secret in its environment (the database password)
//! to an endpoint of their choosing. The allowed variables are read when the server starts and
//! kept in memory only: never in the run, the job's payload, its progress, the audit log or a log
//! line.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Duration;

use serde::{Deserialize, Serialize};
use tokio::sync::watch;

use super::{ApiKey, CallSettings, Prices, RunProgress, RunRow, RunSpec, execute};
use crate::Lane;
use crate::core::audit::{Actor, AuditAction};
use crate::core::model_run::GenerationParams;
use crate::jobs::{self, JobContext, JobId, JobKind};
use crate::refusal::Refusal;
use crate::store;
use crate::{AppError, Hub, audit};

/// The environment variables a server-side run may take its API key from, with their
/// values as read when the server started (kept in memory only).
#[derive(Debug, Clone, Default)]
pub struct EndpointKeys(Arc<BTreeMap<String, ApiKey>>);

/// A hub's model runs take no key from its environment unless its operator names the
/// variables (`serve --endpoint-key`).
impl crate::Kept for EndpointKeys {
    fn make(_hub: &crate::Hub) -> Self {
        EndpointKeys::default()
    }
}

impl EndpointKeys {
    /// The allowlist of `names`, each an environment variable's name, read from this
    /// process's environment now: a name that is not set (or empty) is refused.
    pub fn from_env(names: impl IntoIterator<Item = String>) -> Result<EndpointKeys, AppError> {
        let mut pairs = Vec::new();
        for name in names {
            let name = name.trim().to_owned();
            let value = std::env::var(&name).unwrap_or_default();
            pairs.push((name, value));
        }
        EndpointKeys::from_pairs(pairs)
    }

    /// The allowlist of these variables' names with their values.
    pub fn from_pairs(
        pairs: impl IntoIterator<Item = (String, String)>,
    ) -> Result<EndpointKeys, AppError> {
        let mut keys = BTreeMap::new();
        for (name, value) in pairs {
            if !is_variable_name(&name) {
                return Err(AppError::Invalid(format!(
                    "endpoint key variable {name:?} is not an environment variable's name \
                     (letters, digits and _, not starting with a digit)"
                )));
            }
            let key = ApiKey::new(value).ok_or_else(|| {
                AppError::Invalid(format!(
                    "endpoint key variable {name} is not set (or empty) in the environment"
                ))
            })?;
            keys.insert(name, key);
        }
        Ok(EndpointKeys(Arc::new(keys)))
    }

    /// The allowed names, sorted.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.0.keys().map(String::as_str)
    }

    /// The key held by `variable`, refused when the server was not started with that name.
    pub fn key(&self, variable: &str) -> Result<ApiKey, AppError> {
        self.0.get(variable).cloned().ok_or_else(|| {
            let allowed = if self.0.is_empty() {
                "the server allows none (its operator names them in ENACT_HUB_ENDPOINT_KEYS)"
                    .to_owned()
            } else {
                format!(
                    "the server allows {}",
                    self.names().collect::<Vec<_>>().join(", ")
                )
            };
            AppError::Invalid(format!(
                "key_variable {variable:?} is not one a run may use: {allowed}"
            ))
        })
    }
}

fn is_variable_name(name: &str) -> bool {
    let mut chars = name.chars();
    chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// How a server-side run calls its endpoint (not part of the run's identity).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunCalls {
    /// The environment variable holding the API key (on the server's allowlist); `None`: the
    /// endpoint takes no key.
    pub key_variable: Option<String>,
    pub concurrency: usize,
    pub max_retries: u32,
    pub timeout_s: f64,
}

impl Default for RunCalls {
    fn default() -> Self {
        let defaults = CallSettings::default();
        RunCalls {
            key_variable: None,
            concurrency: defaults.concurrency,
            max_retries: defaults.max_retries,
            timeout_s: defaults.timeout.as_secs_f64(),
        }
    }
}

/// The most requests in flight a server-side run may ask for.
pub const MOST_CONCURRENCY: usize = 256;

impl RunCalls {
    fn check(&self, hub: &Hub) -> Result<(), AppError> {
        if !(1..=MOST_CONCURRENCY).contains(&self.concurrency) {
            return Err(AppError::Invalid(format!(
                "concurrency must be 1 to {MOST_CONCURRENCY}, not {}",
                self.concurrency
            )));
        }
        if !(self.timeout_s.is_finite() && self.timeout_s > 0.0 && self.timeout_s <= 3600.0) {
            return Err(AppError::Invalid(format!(
                "timeout_s must be more than 0 and at most 3600, not {}",
                self.timeout_s
            )));
        }
        if let Some(variable) = &self.key_variable {
            hub.kept::<EndpointKeys>().key(variable)?;
        }
        Ok(())
    }

    fn settings(&self, hub: &Hub) -> Result<CallSettings, AppError> {
        let api_key = match &self.key_variable {
            Some(variable) => Some(hub.kept::<EndpointKeys>().key(variable)?),
            None => None,
        };
        Ok(CallSettings {
            concurrency: self.concurrency,
            max_retries: self.max_retries,
            timeout: Duration::from_secs_f64(self.timeout_s),
            api_key,
            ..CallSettings::default()
        })
    }
}

/// A model-run job's payload: the run and how to work it. Holds no secret.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct RunJob {
    run_id: i64,
    run: String,
    dataset: String,
    endpoint: String,
    model: String,
    params: GenerationParams,
    limit: Option<usize>,
    retry_failed: bool,
    submit_as: Option<String>,
    prices: Prices,
    calls: RunCalls,
}

impl RunJob {
    fn spec(&self) -> RunSpec {
        RunSpec {
            dataset: self.dataset.clone(),
            endpoint: self.endpoint.clone(),
            model: self.model.clone(),
            name: Some(self.run.clone()),
            params: self.params.clone(),
            limit: self.limit,
            retry_failed: self.retry_failed,
            submit_as: self.submit_as.clone(),
            prices: self.prices,
        }
    }
}

/// Starts `spec` on the server: the run is found or created and its job enqueued in one
/// transaction, audited. Refused when the run already has a job that has not ended.
pub async fn start(
    hub: &Hub,
    actor: &Actor,
    spec: &RunSpec,
    calls: &RunCalls,
) -> Result<(RunRow, JobId), AppError> {
    calls.check(hub)?;
    spec.check()?;
    let identity = super::identity(hub, spec).await?;
    let mut tx = hub.write(Lane::Interactive).await?;
    let run = super::find_or_create(&mut tx, actor, spec, &identity).await?;
    if let Some(job) = unfinished_job(&mut tx, &run).await? {
        return Err(AppError::Conflict(format!(
            "run '{}' already has job {} ({}): pause, resume or cancel that one",
            run.name,
            job.id,
            job.state.as_str()
        )));
    }
    let payload = RunJob {
        run_id: run.id,
        run: run.name.clone(),
        dataset: run.dataset.clone(),
        endpoint: run.endpoint.clone(),
        model: run.model.clone(),
        params: spec.params.clone(),
        limit: spec.limit,
        retry_failed: spec.retry_failed,
        submit_as: spec.submit_as.clone(),
        prices: spec.prices,
        calls: calls.clone(),
    };
    let job = jobs::enqueue(
        &mut tx,
        JobKind::ModelRun,
        &serde_json::to_value(&payload)?,
        actor,
    )
    .await?;
    store::runs::set_job(&mut tx, run.id, job.0).await?;
    audit::record(
        &mut tx,
        actor,
        AuditAction::RunStart,
        format!("run {}", run.name),
        Some(&run.dataset),
        format!("{job}: {} at {}", run.model, run.endpoint),
    )
    .await?;
    tx.commit().await?;
    Ok((run, job))
}

/// The job of `run` that has not ended, if there is one.
async fn unfinished_job(
    conn: &mut store::Conn,
    run: &RunRow,
) -> Result<Option<jobs::JobRow>, AppError> {
    let Some(job) = run.job else {
        return Ok(None);
    };
    let job = store::jobs::get(conn, job).await?;
    Ok(job.filter(|j| !j.state.is_final()))
}

/// How often a running job's progress is written at most.
const PROGRESS_EVERY: Duration = Duration::from_secs(1);

/// Works a model-run job: asks every item not asked yet (a restarted job skips what is
/// stored), reports progress, stops at the next item when the job is paused, cancelled or
/// released, and submits when every item is done.
pub async fn work(hub: &Hub, job: &JobContext) -> Result<(), AppError> {
    let payload: RunJob = serde_json::from_value(job.payload.clone())
        .map_err(|e| AppError::internal(format!("{} has a bad payload: {e}", job.id)))?;
    let settings = payload.calls.settings(hub)?;
    let spec = payload.spec();
    let (shown, mut seen) = watch::channel(None::<RunProgress>);
    let stop = || job.stop_requested().is_some();
    let ran = async {
        let progress = move |p: &RunProgress| {
            shown.send_replace(Some(p.clone()));
        };
        // `progress`, the sender, is dropped when the run returns: that ends the writer.
        execute(hub, &Actor::Server, &spec, &settings, &progress, &stop).await
    };
    // Progress is written from here, at most once a PROGRESS_EVERY, not from the callback
    // (which is synchronous and called as often as an item finishes). The writer is never
    // dropped mid-write, so no late write lands after the last one below.
    let writer = async {
        while seen.changed().await.is_ok() {
            let current = seen.borrow_and_update().clone();
            if let Some(p) = current
                && let Err(e) = job
                    .progress(hub, &RunJobProgress::of(&p, RunStage::Running))
                    .await
            {
                tracing::warn!(job = job.id.0, error = %e, "storing a run's progress failed");
            }
            tokio::time::sleep(PROGRESS_EVERY).await;
        }
    };
    let (report, ()) = tokio::join!(ran, writer);
    let report = report?;
    let stage = if report.stopped {
        RunStage::Stopped
    } else if report.submission.is_some() {
        RunStage::Submitted
    } else {
        RunStage::Finished
    };
    let mut last = RunJobProgress::of(&report.progress, stage);
    last.submission = report.submission;
    last.failures = report
        .failures
        .iter()
        .map(|(failure, n)| (failure.code(), *n))
        .collect();
    job.progress(hub, &last).await
}

/// Where a run's job has got.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum RunStage {
    /// Asking items.
    #[default]
    Running,
    /// Stopped (paused, cancelled or released) with items left.
    Stopped,
    /// Every item done and the answers submitted.
    Submitted,
    /// Every item done, not submitted (the run submits under no name).
    Finished,
}

impl RunStage {
    pub fn as_str(self) -> &'static str {
        match self {
            RunStage::Running => "running",
            RunStage::Stopped => "stopped",
            RunStage::Submitted => "submitted",
            RunStage::Finished => "finished",
        }
    }
}

/// A run job's progress, as the job stores it and the API and the run's page show it: the
/// run's counts with the rate and the time left and, once it ended, the submission and the
/// failures by kind. Written and read only as this struct.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct RunJobProgress {
    pub stage: RunStage,
    /// Items the run covers.
    pub total: usize,
    /// Items with a row: answered or failed.
    pub done: usize,
    pub answered: usize,
    pub failed: usize,
    pub in_flight: usize,
    /// Items asked per second by this job so far.
    pub items_per_s: f64,
    /// Seconds left at that rate; none before the first item.
    pub eta_s: Option<f64>,
    pub prompt_tokens: u64,
    pub completion_tokens: u64,
    pub cost_usd: f64,
    pub requests: u64,
    /// Requests refused with 429.
    pub refused: u64,
    /// The last few failures, newest last.
    pub recent_errors: Vec<String>,
    /// The submission made, once the run ended submitted.
    pub submission: Option<i64>,
    /// Items failed by kind (`RunFailure` codes: `http_503`, `no_reply`, …), once ended.
    pub failures: BTreeMap<String, usize>,
}

impl RunJobProgress {
    fn of(p: &RunProgress, stage: RunStage) -> RunJobProgress {
        let rate = if p.elapsed_s > 0.0 {
            p.asked_now as f64 / p.elapsed_s
        } else {
            0.0
        };
        let left = p.total.saturating_sub(p.done);
        RunJobProgress {
            stage,
            total: p.total,
            done: p.done,
            answered: p.answered,
            failed: p.failed,
            in_flight: p.in_flight,
            items_per_s: rate,
            eta_s: (rate > 0.0).then(|| left as f64 / rate),
            prompt_tokens: p.usage.prompt_tokens,
            completion_tokens: p.usage.completion_tokens,
            cost_usd: p.cost_usd,
            requests: p.requests,
            refused: p.refused,
            recent_errors: p.recent_errors.clone(),
            submission: None,
            failures: BTreeMap::new(),
        }
    }
}

/// A server-side run as the API shows it: the run, its newest job and that job's progress.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub struct ServerRunView {
    pub id: i64,
    pub name: String,
    pub dataset: String,
    pub endpoint: String,
    pub model: String,
    /// The generation parameters.
    pub params: serde_json::Value,
    pub prompt_version: String,
    /// The submission made, once every item was done.
    pub submission: Option<i64>,
    pub created_by: String,
    pub created_at: String,
    /// Its newest job's id and state (`queued`, `running`, `paused`, `done`, `failed`,
    /// `cancelled`), when it was started on the server.
    pub job: Option<i64>,
    pub state: Option<String>,
    /// The job's last error, when it failed.
    pub last_error: Option<String>,
    /// What the job last reported; none before it was started on the server.
    pub progress: Option<RunJobProgress>,
}

fn view_of(run: &RunRow, job: Option<&jobs::JobRow>) -> ServerRunView {
    ServerRunView {
        id: run.id,
        name: run.name.clone(),
        dataset: run.dataset.clone(),
        endpoint: run.endpoint.clone(),
        model: run.model.clone(),
        params: serde_json::from_str(&run.params).unwrap_or(serde_json::Value::Null),
        prompt_version: run.prompt_version.clone(),
        submission: run.submission,
        created_by: run.created_by.clone(),
        created_at: run.created_at.clone(),
        job: job.map(|j| j.id),
        state: job.map(|j| j.state.as_str().to_owned()),
        last_error: job.and_then(|j| j.last_error.clone()),
        progress: job.and_then(|j| {
            let stored = j.progress.as_deref()?;
            // Written by this code's job only; an older build's wording is shown as none,
            // and said in the log rather than failing the page.
            serde_json::from_str(stored)
                .inspect_err(|e| {
                    tracing::warn!(run = %run.name, job = j.id, error = %e, "a run job's stored progress is unreadable");
                })
                .ok()
        }),
    }
}

/// Every run, newest first, with the job it was last started with.
pub async fn views(hub: &Hub) -> Result<Vec<ServerRunView>, AppError> {
    let mut conn = hub.conn().await?;
    let runs = store::runs::list(&mut conn).await?;
    let mut views = Vec::with_capacity(runs.len());
    for run in &runs {
        views.push(view_with_job(&mut conn, run).await?);
    }
    Ok(views)
}

async fn view_with_job(conn: &mut store::Conn, run: &RunRow) -> Result<ServerRunView, AppError> {
    let job = match run.job {
        Some(job) => store::jobs::get(conn, job).await?,
        None => None,
    };
    Ok(view_of(run, job.as_ref()))
}

/// One run by id with the job it was last started with.
pub async fn view(hub: &Hub, id: i64) -> Result<ServerRunView, AppError> {
    let mut conn = hub.conn().await?;
    let run = store::runs::by_id(&mut conn, id).await?.ok_or_else(|| {
        AppError::from(Refusal::NoRun {
            run: id.to_string(),
        })
    })?;
    view_with_job(&mut conn, &run).await
}

/// Pauses, resumes or cancels run `id`'s newest job (audited as the job's change).
pub async fn control(
    hub: &Hub,
    actor: &Actor,
    id: i64,
    change: jobs::JobControl,
) -> Result<ServerRunView, AppError> {
    let shown = view(hub, id).await?;
    let job = shown.job.ok_or_else(|| {
        AppError::Conflict(format!(
            "model run {id} was never started on the server: it has no job"
        ))
    })?;
    jobs::control(hub, actor, JobId(job), change).await?;
    view(hub, id).await
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_progress_a_job_stored_before_the_struct_reads_back_whole() {
        // As 0.1's `shown_progress` wrote an ended run's progress, failures keyed by words.
        let stored = r#"{"stage":"submitted","total":18,"done":18,"answered":14,"failed":4,
            "in_flight":0,"items_per_s":3.5,"eta_s":null,"prompt_tokens":1000,
            "completion_tokens":200,"cost_usd":0.0045,"requests":23,"refused":2,
            "recent_errors":["a: HTTP 400: no"],"submission":7,
            "failures":{"gave up after 4 attempts: HTTP 503":1}}"#;
        let read: RunJobProgress = serde_json::from_str(stored).expect("reads");
        assert_eq!(read.stage, RunStage::Submitted);
        assert_eq!(
            (read.total, read.done, read.answered, read.failed),
            (18, 18, 14, 4)
        );
        assert_eq!(
            (read.requests, read.refused, read.submission),
            (23, 2, Some(7))
        );
        assert_eq!(read.eta_s, None);
        assert_eq!(read.failures["gave up after 4 attempts: HTTP 503"], 1);
        // A running job's progress had neither the submission nor the failures.
        let running: RunJobProgress =
            serde_json::from_str(r#"{"stage":"running","total":5,"done":1,"eta_s":12.0}"#)
                .expect("reads");
        assert_eq!(running.stage, RunStage::Running);
        assert_eq!((running.done, running.eta_s), (1, Some(12.0)));
        assert!(running.failures.is_empty() && running.submission.is_none());
        let again: RunJobProgress =
            serde_json::from_value(serde_json::json!(read.clone())).expect("round trip");
        assert_eq!(again, read);
    }

    #[test]
    fn a_run_s_progress_counts_its_rate_and_time_left() {
        let progress = RunProgress {
            total: 100,
            done: 40,
            answered: 30,
            failed: 10,
            asked_now: 20,
            elapsed_s: 10.0,
            ..RunProgress::default()
        };
        let shown = RunJobProgress::of(&progress, RunStage::Running);
        assert_eq!(shown.items_per_s, 2.0);
        assert_eq!(shown.eta_s, Some(30.0), "60 items left at 2 a second");
        let idle = RunJobProgress::of(&RunProgress::default(), RunStage::Running);
        assert_eq!((idle.items_per_s, idle.eta_s), (0.0, None));
    }
}
