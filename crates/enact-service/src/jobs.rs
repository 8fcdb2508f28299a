//! Long work that must survive restarts and be worked by one instance at a time: model runs,
//! rescoring, and imports from the server's import folder. One mechanism for all of them, in
//! the shape of crates.io's worker:
//!
//! - a job is a row (`jobs`): its kind, a JSON payload, its state and progress. [`enqueue`]
//!   writes it on the caller's transaction, so the job exists exactly when the change that asks
//!   for it does;
//! - each serving instance runs a [`Worker`] that claims the oldest due job by taking its lease
//!   (an owner and an expiry, in a write transaction, so two instances never take the same
//!   job), renews the lease while the job's code works, and lets go when it returns;
//! - an instance that dies stops renewing: once the lease has run out, another instance's
//!   worker (or the same one, restarted) takes the job over. A graceful stop releases its jobs
//!   at once. The code of a job is therefore resumable and idempotent: started again from the
//!   top, it skips what is already durably done;
//! - a failure is retried after 1 min × 2^(attempts − 1) (capped at an hour) until
//!   [`JobSettings::max_attempts`]; an admin can pause, resume and cancel a job.
//!
//! On PostgreSQL every write transaction takes the same advisory lock (`store::Pool::begin`),
//! so a claim is serialised across instances as SQLite's single writer serialises it; no
//! `SKIP LOCKED` is needed. Leases are in milliseconds of the instances' clocks, which are
//! assumed to agree to well within a lease.

use std::collections::HashMap;
use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use tokio::sync::watch;
use tokio::task::JoinSet;

use super::{AppError, Hub, Lane, audit};
use crate::core::audit::{Actor, AuditAction};
use crate::refusal::Refusal;
use crate::store;
pub use crate::store::jobs::{JobKind, JobRow, JobState};

/// A job's row id.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(transparent)]
pub struct JobId(pub i64);

impl std::fmt::Display for JobId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "job {}", self.0)
    }
}

/// Milliseconds since the epoch on this instance's clock.
pub fn now_ms() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_millis()).unwrap_or(i64::MAX))
}

fn millis(d: Duration) -> i64 {
    i64::try_from(d.as_millis()).unwrap_or(i64::MAX)
}

/// Enqueues a job of `kind` with `payload`, asked for by `actor`, on `conn`: call it inside
/// the transaction of the change that asks for the job, so both commit or neither does. The
/// payload is stored as it is: never put a secret in it.
pub async fn enqueue(
    conn: &mut store::Tx,
    kind: JobKind,
    payload: &serde_json::Value,
    actor: &Actor,
) -> Result<JobId, AppError> {
    let id = store::jobs::insert(conn, kind, &payload.to_string(), actor.name()).await?;
    Ok(JobId(id))
}

/// One job, if there is one with that id.
pub async fn get(hub: &Hub, id: JobId) -> Result<Option<JobRow>, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::jobs::get(&mut conn, id.0).await?)
}

/// A job as the API shows it: its state, attempts and the progress its code last stored.
#[derive(Debug, Clone, serde::Serialize, schemars::JsonSchema)]
pub struct JobView {
    pub id: i64,
    /// `model_run`, `rescore` or `import`.
    pub kind: String,
    /// `queued`, `running`, `paused`, `done`, `failed` or `cancelled`.
    pub state: String,
    pub attempts: i64,
    /// Why the last attempt failed, if it did.
    pub last_error: Option<String>,
    /// What the job's code last reported (its shape depends on the kind), or null.
    pub progress: serde_json::Value,
    pub created_by: String,
    pub created_at: String,
    pub updated_at: String,
    pub finished_at: Option<String>,
}

impl From<JobRow> for JobView {
    fn from(job: JobRow) -> JobView {
        JobView {
            id: job.id,
            kind: job.kind.as_str().to_owned(),
            state: job.state.as_str().to_owned(),
            attempts: job.attempts,
            last_error: job.last_error,
            progress: job
                .progress
                .as_deref()
                .and_then(|p| serde_json::from_str(p).ok())
                .unwrap_or(serde_json::Value::Null),
            created_by: job.created_by,
            created_at: job.created_at,
            updated_at: job.updated_at,
            finished_at: job.finished_at,
        }
    }
}

/// The job `id` as the API shows it.
pub async fn view(hub: &Hub, id: JobId) -> Result<JobView, AppError> {
    get(hub, id).await?.map(JobView::from).ok_or_else(|| {
        AppError::from(Refusal::NoJob {
            job: id.0.to_string(),
        })
    })
}

/// The newest jobs (of one kind when given), newest first.
pub async fn list(hub: &Hub, kind: Option<JobKind>, limit: u32) -> Result<Vec<JobRow>, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::jobs::list(&mut conn, kind, i64::from(limit)).await?)
}

/// An admin's change of a job's state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JobControl {
    /// Stop working it (a running job stops at its next unit of work) until resumed.
    Pause,
    /// Queue a paused or failed job again; it carries on where it stopped.
    Resume,
    /// Stop it for good; what it did so far is kept.
    Cancel,
}

impl JobControl {
    /// `pause`, `resume` or `cancel`, as paths and forms spell them; anything else is refused
    /// saying what is allowed.
    pub fn parse(text: &str) -> Result<JobControl, AppError> {
        match text {
            "pause" => Ok(JobControl::Pause),
            "resume" => Ok(JobControl::Resume),
            "cancel" => Ok(JobControl::Cancel),
            other => Err(AppError::Invalid(format!(
                "change: {other:?} is not pause, resume or cancel"
            ))),
        }
    }

    /// The state a job moves to, if it may from `from`.
    fn target(self, from: JobState) -> Option<JobState> {
        match (self, from) {
            (JobControl::Pause, JobState::Queued | JobState::Running) => Some(JobState::Paused),
            (JobControl::Resume, JobState::Paused | JobState::Failed) => Some(JobState::Queued),
            (JobControl::Cancel, s) if !s.is_final() => Some(JobState::Cancelled),
            _ => None,
        }
    }

    fn verb(self) -> &'static str {
        match self {
            JobControl::Pause => "paused",
            JobControl::Resume => "resumed",
            JobControl::Cancel => "cancelled",
        }
    }

    fn audit_action(self) -> AuditAction {
        match self {
            JobControl::Pause => AuditAction::JobPause,
            JobControl::Resume => AuditAction::JobResume,
            JobControl::Cancel => AuditAction::JobCancel,
        }
    }
}

/// Pauses, resumes or cancels a job, audited. A job already in a state the change does not
/// apply to is refused with its state named. Returns the job as it is afterwards.
pub async fn control(
    hub: &Hub,
    actor: &Actor,
    id: JobId,
    change: JobControl,
) -> Result<JobRow, AppError> {
    let mut tx = hub.write(Lane::Interactive).await?;
    let job = store::jobs::get(&mut tx, id.0).await?.ok_or_else(|| {
        AppError::from(Refusal::NoJob {
            job: id.0.to_string(),
        })
    })?;
    let to = change.target(job.state).ok_or_else(|| {
        AppError::Conflict(format!(
            "{id} is {}: it cannot be {}",
            job.state.as_str(),
            change.verb()
        ))
    })?;
    store::jobs::set_state(&mut tx, id.0, to).await?;
    audit::record(
        &mut tx,
        actor,
        change.audit_action(),
        id.to_string(),
        None,
        format!("{} job, was {}", job.kind.as_str(), job.state.as_str()),
    )
    .await?;
    let job = store::jobs::get(&mut tx, id.0)
        .await?
        .ok_or_else(|| AppError::internal(format!("{id} vanished in its own transaction")))?;
    tx.commit().await?;
    Ok(job)
}

/// What the worker hands the code of a job while it works it.
pub struct JobContext {
    pub id: JobId,
    pub kind: JobKind,
    /// The payload it was enqueued with.
    pub payload: serde_json::Value,
    /// How many times it has been started, this time included (more than one after a failure,
    /// a restart or a takeover).
    pub attempt: i64,
    stop: watch::Receiver<Option<JobState>>,
}

impl JobContext {
    /// Whether the job should stop at its next unit of work, and why: `Paused` or `Cancelled`
    /// by an admin, or `Queued` when the instance is shutting down or lost the lease (the job
    /// will be resumed, here or elsewhere). The job's code returns `Ok(())` when it sees one.
    pub fn stop_requested(&self) -> Option<JobState> {
        *self.stop.borrow()
    }

    /// Waits until a stop is requested (for `tokio::select!` around a long wait).
    pub async fn stopped(&self) -> JobState {
        let mut stop = self.stop.clone();
        loop {
            if let Some(state) = *stop.borrow_and_update() {
                return state;
            }
            if stop.changed().await.is_err() {
                return JobState::Queued;
            }
        }
    }

    /// Stores the job's progress, for pages and the API (in the bulk lane: annotators' writes
    /// go first): each kind's own struct, serialised here only and read back as that struct
    /// by its kind's code. Its `done` field, when it has one, is the count the metrics show
    /// as the job's items done. Never call it while holding a [`crate::Write`]: the gate lets
    /// one writer in at a time.
    pub async fn progress<P: serde::Serialize>(
        &self,
        hub: &Hub,
        progress: &P,
    ) -> Result<(), AppError> {
        let stored = serde_json::to_string(progress).map_err(|e| {
            AppError::internal(format!("writing job {}'s progress: {e}", self.id.0))
        })?;
        let mut tx = hub.write(Lane::Bulk).await?;
        store::jobs::set_progress(&mut tx, self.id.0, &stored).await?;
        tx.commit().await?;
        Ok(())
    }
}

/// The future a job's code returns.
pub type JobFuture = Pin<Box<dyn Future<Output = Result<(), AppError>> + Send>>;

/// The code of one kind of job: given the hub and the job, the future that works it.
type JobCode = Arc<dyn Fn(Hub, Arc<JobContext>) -> JobFuture + Send + Sync>;

/// The code that works each kind of job.
#[derive(Clone, Default)]
pub struct JobHandlers {
    handlers: HashMap<JobKind, JobCode>,
}

impl JobHandlers {
    /// `work` works every job of `kind`.
    pub fn with(
        mut self,
        kind: JobKind,
        work: impl Fn(Hub, Arc<JobContext>) -> JobFuture + Send + Sync + 'static,
    ) -> JobHandlers {
        self.handlers.insert(kind, Arc::new(work));
        self
    }

    fn kinds(&self) -> Vec<JobKind> {
        let mut kinds: Vec<JobKind> = self.handlers.keys().copied().collect();
        kinds.sort_by_key(|k| k.as_str());
        kinds
    }
}

/// How a worker works.
#[derive(Debug, Clone, Copy)]
pub struct JobSettings {
    /// How long a lease lasts unless renewed; another instance takes a job over this long
    /// after its instance died.
    pub lease: Duration,
    /// How often the queue is looked at when there was nothing to do.
    pub poll: Duration,
    /// Jobs worked at once by one instance.
    pub max_running: usize,
    /// Starts after which a failing job is left failed.
    pub max_attempts: i64,
    /// The first retry's wait; each further one doubles it, up to an hour.
    pub retry_base: Duration,
}

impl Default for JobSettings {
    fn default() -> Self {
        JobSettings {
            lease: Duration::from_secs(30),
            poll: Duration::from_secs(1),
            max_running: 4,
            max_attempts: 5,
            retry_base: Duration::from_secs(60),
        }
    }
}

impl JobSettings {
    fn retry_delay(&self, attempts: i64) -> Duration {
        let doublings = u32::try_from((attempts - 1).clamp(0, 16)).unwrap_or(16);
        self.retry_base
            .saturating_mul(2u32.saturating_pow(doublings))
            .min(Duration::from_secs(3600))
    }
}

/// A running worker; [`Worker::stop`] lets go of its jobs and waits for them.
pub struct Worker {
    shutdown: watch::Sender<bool>,
    task: tokio::task::JoinHandle<()>,
    owner: String,
}

impl Worker {
    /// Starts working the queue on `hub` with `handlers`: only jobs of the kinds they have
    /// code for are claimed (a newer instance's kinds are left to it).
    pub fn spawn(hub: Hub, handlers: JobHandlers, settings: JobSettings) -> Worker {
        let owner = format!(
            "{}:{}:{:08x}",
            std::env::var("HOSTNAME").unwrap_or_else(|_| "enact-hub".to_owned()),
            std::process::id(),
            rand::random::<u32>()
        );
        let (shutdown, stopping) = watch::channel(false);
        let task = tokio::spawn(work_queue(
            hub,
            Arc::new(handlers),
            settings,
            owner.clone(),
            stopping,
        ));
        Worker {
            shutdown,
            task,
            owner,
        }
    }

    /// The name its leases carry.
    pub fn owner(&self) -> &str {
        &self.owner
    }

    /// Stops claiming, asks the running jobs to stop, and waits for them to let go of their
    /// leases (so another instance, or this one restarted, takes them at once).
    pub async fn stop(self) {
        let _ = self.shutdown.send(true);
        if let Err(e) = self.task.await {
            tracing::error!(error = %e, "the job worker failed");
        }
    }
}

async fn work_queue(
    hub: Hub,
    handlers: Arc<JobHandlers>,
    settings: JobSettings,
    owner: String,
    mut stopping: watch::Receiver<bool>,
) {
    let kinds = handlers.kinds();
    if kinds.is_empty() {
        return;
    }
    let mut running: JoinSet<()> = JoinSet::new();
    // The jobs this worker works, by task: never claimed again while their code runs, even
    // when their lease ran out (renewals held up on a busy database) and the queue offers them.
    let mut working: HashMap<tokio::task::Id, i64> = HashMap::new();
    tracing::info!(%owner, kinds = ?kinds.iter().map(|k| k.as_str()).collect::<Vec<_>>(), "job worker started");
    loop {
        if *stopping.borrow() {
            break;
        }
        while let Some(ended) = running.try_join_next_with_id() {
            working.remove(&ended.map_or_else(|e| e.id(), |(id, ())| id));
        }
        let claimed = if running.len() < settings.max_running {
            let ids: Vec<i64> = working.values().copied().collect();
            claim(&hub, &owner, &kinds, &settings, &ids).await
        } else {
            None
        };
        if let Some(job) = claimed {
            let id = job.id;
            let task = running.spawn(work_one(
                hub.clone(),
                Arc::clone(&handlers),
                settings,
                owner.clone(),
                job,
                stopping.clone(),
            ));
            working.insert(task.id(), id);
            continue;
        }
        tokio::select! {
            _ = tokio::time::sleep(settings.poll) => {}
            _ = stopping.changed() => {}
            Some(ended) = running.join_next_with_id(), if !running.is_empty() => {
                working.remove(&ended.map_or_else(|e| e.id(), |(id, ())| id));
            }
        }
    }
    while running.join_next().await.is_some() {}
    tracing::info!(%owner, "job worker stopped");
}

/// The next due job of a kind this worker has code for and is not working already, leased to
/// `owner`.
async fn claim(
    hub: &Hub,
    owner: &str,
    kinds: &[JobKind],
    settings: &JobSettings,
    working: &[i64],
) -> Option<JobRow> {
    let claimed = async {
        let mut tx = hub.write(Lane::Interactive).await?;
        let now = now_ms();
        let until = now + millis(settings.lease);
        let job = store::jobs::claim(&mut tx, kinds, owner, now, until, working).await?;
        tx.commit().await?;
        Ok::<_, AppError>(job)
    };
    match claimed.await {
        Ok(job) => job,
        Err(e) => {
            tracing::warn!(error = %e, "claiming a job failed; trying again later");
            None
        }
    }
}

/// Works one claimed job to its end, renewing its lease meanwhile, and lets go of it.
async fn work_one(
    hub: Hub,
    handlers: Arc<JobHandlers>,
    settings: JobSettings,
    owner: String,
    job: JobRow,
    mut stopping: watch::Receiver<bool>,
) {
    let id = JobId(job.id);
    let Some(handler) = handlers.handlers.get(&job.kind).cloned() else {
        return;
    };
    let payload = match serde_json::from_str(&job.payload) {
        Ok(payload) => payload,
        Err(e) => {
            let error = format!("the payload is not JSON: {e}");
            finish(&hub, id, &owner, JobState::Failed, 0, Some(&error)).await;
            return;
        }
    };
    let (stop, stop_seen) = watch::channel(None);
    let context = Arc::new(JobContext {
        id,
        kind: job.kind,
        payload,
        attempt: job.attempts,
        stop: stop_seen,
    });
    tracing::info!(
        job = id.0,
        kind = job.kind.as_str(),
        attempt = job.attempts,
        "job started"
    );

    // The job's code runs as its own task, so that a panic in it is a failure of the job.
    let mut work = tokio::spawn(handler(hub.clone(), Arc::clone(&context)));
    let mut renew = tokio::time::interval(settings.lease / 3);
    renew.tick().await;
    let mut lost = false;
    let outcome = loop {
        tokio::select! {
            done = &mut work => break done,
            _ = renew.tick() => {
                let until = now_ms() + millis(settings.lease);
                match renew_lease(&hub, id, &owner, until).await {
                    Ok(Some(JobState::Running)) => {}
                    Ok(Some(state)) => { let _ = stop.send(Some(state)); }
                    Ok(None) => {
                        lost = true;
                        tracing::warn!(job = id.0, "lost the lease of a job; stopping it");
                        let _ = stop.send(Some(JobState::Queued));
                    }
                    Err(e) => tracing::warn!(job = id.0, error = %e, "renewing a lease failed"),
                }
            }
            _ = stopping.changed() => {
                if *stopping.borrow() {
                    let _ = stop.send(Some(JobState::Queued));
                }
            }
        }
    };
    if lost {
        return;
    }
    let shutting_down = *stopping.borrow();
    match outcome {
        Ok(Ok(())) if context.stop_requested() == Some(JobState::Queued) || shutting_down => {
            // Released for another worker (or this one, restarted); resumed at once.
            finish(&hub, id, &owner, JobState::Queued, 0, None).await;
            tracing::info!(job = id.0, "job released");
        }
        Ok(Ok(())) => {
            // A job an admin paused or cancelled keeps that state (`release` leaves it).
            finish(&hub, id, &owner, JobState::Done, 0, None).await;
            tracing::info!(job = id.0, "job finished");
        }
        Ok(Err(e)) => {
            let error = match &e {
                AppError::Internal(inner) => format!("{inner:#}"),
                other => other.to_string(),
            };
            fail(&hub, &settings, id, &owner, job.attempts, &error).await;
        }
        Err(panicked) => {
            let error = format!("the job's code panicked: {panicked}");
            fail(&hub, &settings, id, &owner, job.attempts, &error).await;
        }
    }
}

async fn renew_lease(
    hub: &Hub,
    id: JobId,
    owner: &str,
    until: i64,
) -> Result<Option<JobState>, AppError> {
    let mut tx = hub.write(Lane::Interactive).await?;
    let state = store::jobs::renew(&mut tx, id.0, owner, until).await?;
    tx.commit().await?;
    Ok(state)
}

/// A failed start: retried later, or failed for good after the last attempt.
async fn fail(
    hub: &Hub,
    settings: &JobSettings,
    id: JobId,
    owner: &str,
    attempts: i64,
    error: &str,
) {
    if attempts >= settings.max_attempts {
        tracing::error!(job = id.0, attempts, error, "job failed for good");
        finish(hub, id, owner, JobState::Failed, 0, Some(error)).await;
    } else {
        let wait = settings.retry_delay(attempts);
        tracing::warn!(
            job = id.0,
            attempts,
            error,
            retry_in_s = wait.as_secs(),
            "job failed; retrying later"
        );
        finish(
            hub,
            id,
            owner,
            JobState::Queued,
            now_ms() + millis(wait),
            Some(error),
        )
        .await;
    }
}

/// Lets go of a job's lease, leaving it in `state`; a failure to write is logged (the lease
/// then runs out and the job is taken again, which its code tolerates).
async fn finish(
    hub: &Hub,
    id: JobId,
    owner: &str,
    state: JobState,
    run_after_ms: i64,
    error: Option<&str>,
) {
    let released = async {
        let mut tx = hub.write(Lane::Interactive).await?;
        let held = store::jobs::release(&mut tx, id.0, owner, state, run_after_ms, error).await?;
        tx.commit().await?;
        Ok::<_, AppError>(held)
    };
    match released.await {
        Ok(true) => {}
        Ok(false) => tracing::warn!(job = id.0, "a job's lease was taken over before it let go"),
        Err(e) => tracing::warn!(job = id.0, error = %e, "releasing a job failed"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn admin_changes_apply_only_where_they_mean_something() {
        use JobControl::*;
        use JobState::*;
        assert_eq!(Pause.target(Running), Some(Paused));
        assert_eq!(Pause.target(Queued), Some(Paused));
        assert_eq!(Pause.target(Done), None);
        assert_eq!(Resume.target(Paused), Some(Queued));
        assert_eq!(Resume.target(Failed), Some(Queued));
        assert_eq!(Resume.target(Running), None);
        assert_eq!(Cancel.target(Paused), Some(Cancelled));
        assert_eq!(Cancel.target(Cancelled), None);
        assert_eq!(Cancel.target(Done), None);
    }

    #[test]
    fn retries_wait_longer_each_time_up_to_an_hour() {
        let s = JobSettings::default();
        assert_eq!(s.retry_delay(1), Duration::from_secs(60));
        assert_eq!(s.retry_delay(2), Duration::from_secs(120));
        assert_eq!(s.retry_delay(3), Duration::from_secs(240));
        assert_eq!(s.retry_delay(40), Duration::from_secs(3600));
    }
}
