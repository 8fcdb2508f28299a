//! Rescoring: stored results computed again under the current metric version
//! ([`METRIC_VERSION`]), so that leaderboards never mix results of different rules silently.
//!
//! A submission is rescored from its stored answers (each read and judged again as if its line
//! were submitted again, against the dataset's items as they are now); a human answer's
//! verdict is judged again from the answer. Work goes in small units, each its own short
//! transaction: one submission (its scores and every verdict row together), or a batch of
//! human answers. Results already at the current version are skipped, so a rescore stopped
//! anywhere (a crash, a paused job) resumes by starting again from the top, and writers are
//! never held up for longer than one unit. A unit that an import changed under it (the content
//! generation moved) is computed again.
//!
//! [`rescore`] runs in the foreground (the command line); [`work`] is the same work carried by
//! the job mechanism (the admin page and API enqueue it). Each run writes one audit entry with
//! its counts.

use std::sync::Mutex;
use std::time::Duration;

use serde::{Deserialize, Serialize};

use super::changes::Change;
use super::jobs::{self, JobContext, JobId, JobKind};
use super::{AppError, Hub, audit, datasets, statements, submissions};
use crate::Lane;
use crate::core::annotation::human_verdict;
use crate::core::audit::{Actor, AuditAction};
use crate::core::metric::METRIC_VERSION;
use crate::core::submission::{StoredAnswer, SubmissionError, rescore_submission};
use crate::core::version::BUILD;
use crate::store;
use crate::store::datasets::Dataset;

/// Human answers judged per transaction.
const HUMAN_BATCH: i64 = 500;

/// Attempts at one unit that imports keep changing under it before it is reported as failed.
const ATTEMPTS: usize = 3;

/// What a rescore is doing, reported after every unit.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct RescoreProgress {
    pub dataset: String,
    pub stage: RescoreStage,
    /// Units of this stage of this dataset done (submissions, or human answers).
    pub done: usize,
    /// Units of this stage of this dataset found below the current version at its start.
    pub total: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RescoreStage {
    Submissions,
    HumanAnswers,
}

impl RescoreStage {
    pub fn as_str(self) -> &'static str {
        match self {
            RescoreStage::Submissions => "submissions",
            RescoreStage::HumanAnswers => "human answers",
        }
    }
}

/// What a rescore did.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct RescoreSummary {
    /// The version results were brought to.
    pub metric_version: u32,
    /// Datasets looked at.
    pub datasets: usize,
    /// Submissions brought to the current version, and how many of them scored differently.
    pub submissions: usize,
    pub submissions_changed: usize,
    /// Human answers brought to the current version, and how many were judged differently.
    pub human_answers: usize,
    pub human_answers_changed: usize,
    /// Results left at their version, each with why (the rescore goes on without them).
    pub failures: Vec<String>,
    /// Stopped before the end (a paused or cancelled job); starting again resumes.
    pub stopped: bool,
}

impl RescoreSummary {
    /// The audit entry's detail.
    fn detail(&self) -> String {
        format!(
            "to metric version {}: {} datasets, {} submissions ({} changed), {} human answers \
             ({} changed), {} failed{}",
            self.metric_version,
            self.datasets,
            self.submissions,
            self.submissions_changed,
            self.human_answers,
            self.human_answers_changed,
            self.failures.len(),
            if self.stopped {
                "; stopped before the end"
            } else {
                ""
            }
        )
    }
}

/// Rescores the stored submissions and human answers of the dataset named `dataset`, or of
/// every dataset, under the current metric version, reporting progress after each unit. Writes
/// one audit entry by `actor` with the counts.
pub async fn rescore(
    hub: &Hub,
    actor: &Actor,
    dataset: Option<&str>,
    progress: &dyn Fn(RescoreProgress),
) -> Result<RescoreSummary, AppError> {
    run(hub, actor, dataset, progress, &|| false).await
}

/// What a queued rescore asks for: the dataset (all when `None`) and who asked, for the audit
/// entry.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RescorePayload {
    pub dataset: Option<String>,
    pub actor_kind: String,
    pub actor: String,
}

impl RescorePayload {
    pub fn new(dataset: Option<&str>, actor: &Actor) -> RescorePayload {
        RescorePayload {
            dataset: dataset.map(str::to_owned),
            actor_kind: actor.kind().to_owned(),
            actor: actor.name().to_owned(),
        }
    }

    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!(self)
    }
}

/// What the work of a queued rescore needs of the job carrying it: [`JobContext`] for the job
/// mechanism (`stop_requested`: paused, cancelled, or the instance stopping).
pub trait RescoreJob: Sync {
    fn payload(&self) -> &serde_json::Value;
    fn stop_requested(&self) -> bool;
    fn progress(
        &self,
        hub: &Hub,
        progress: &RescoreJobProgress,
    ) -> impl Future<Output = Result<(), AppError>> + Send;
}

/// A rescore job's stored progress: how far it has got while it runs, then what it did.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum RescoreJobProgress {
    Running(RescoreProgress),
    Ended(RescoreSummary),
}

impl RescoreJob for JobContext {
    fn payload(&self) -> &serde_json::Value {
        &self.payload
    }

    fn stop_requested(&self) -> bool {
        JobContext::stop_requested(self).is_some()
    }

    fn progress(
        &self,
        hub: &Hub,
        progress: &RescoreJobProgress,
    ) -> impl Future<Output = Result<(), AppError>> + Send {
        JobContext::progress(self, hub, progress)
    }
}

/// Queues a rescore of the dataset named `dataset`, or of every dataset, for the serving
/// instances' job workers; the rescore's audit entry names `actor`. An unknown dataset is
/// refused here rather than failing in the job.
pub async fn request(hub: &Hub, actor: &Actor, dataset: Option<&str>) -> Result<JobId, AppError> {
    if let Some(name) = dataset {
        datasets::by_name(hub, name).await?;
    }
    let payload = RescorePayload::new(dataset, actor).to_json();
    let mut tx = hub.write(Lane::Interactive).await?;
    let id = jobs::enqueue(&mut tx, JobKind::Rescore, &payload, actor).await?;
    tx.commit().await?;
    Ok(id)
}

/// How often a job's progress is written while it runs.
const PROGRESS_EVERY: Duration = Duration::from_secs(2);

/// Works a queued rescore (see [`RescorePayload`]): the same work as [`rescore`], stopping
/// between units when the job is paused or cancelled, its progress stored every few seconds.
/// Started again after a crash or a takeover, it resumes where the results stand.
pub async fn work(hub: &Hub, job: &JobContext) -> Result<(), AppError> {
    work_on(hub, job).await
}

/// [`work`] on any carrier of a rescore job.
pub async fn work_on(hub: &Hub, job: &impl RescoreJob) -> Result<(), AppError> {
    let payload: RescorePayload = serde_json::from_value(job.payload().clone())
        .map_err(|e| AppError::internal(format!("rescore job: unreadable payload: {e}")))?;
    let actor = Actor::from_parts(&payload.actor_kind, &payload.actor).ok_or_else(|| {
        AppError::internal(format!(
            "rescore job: unknown actor kind {:?}",
            payload.actor_kind
        ))
    })?;
    let latest: Mutex<Option<RescoreProgress>> = Mutex::new(None);
    let note = |p: RescoreProgress| {
        *latest.lock().unwrap_or_else(|p| p.into_inner()) = Some(p);
    };
    let stop = || job.stop_requested();
    // The progress is written beside the rescore, never in its place: awaited while the
    // rescore waits unpolled, a write would wait for the lock of the unit's transaction the
    // rescore holds open (SQLite's single writer), and both would wait out the busy timeout.
    let (finished, mut ended) = tokio::sync::watch::channel(false);
    let running = async {
        let summary = run(hub, &actor, payload.dataset.as_deref(), &note, &stop).await;
        finished.send_replace(true);
        summary
    };
    let writer = async {
        let mut tick = tokio::time::interval(PROGRESS_EVERY);
        loop {
            tokio::select! {
                _ = tick.tick() => {
                    let value = latest.lock().unwrap_or_else(|p| p.into_inner()).take();
                    if let Some(p) = value
                        && let Err(e) = job.progress(hub, &RescoreJobProgress::Running(p)).await
                    {
                        tracing::warn!(error = %e, "storing a rescore's progress failed");
                    }
                }
                _ = ended.changed() => break,
            }
        }
    };
    let (summary, ()) = tokio::join!(running, writer);
    let summary = summary?;
    job.progress(hub, &RescoreJobProgress::Ended(summary)).await
}

async fn run<P, S>(
    hub: &Hub,
    actor: &Actor,
    dataset: Option<&str>,
    progress: &P,
    stop: &S,
) -> Result<RescoreSummary, AppError>
where
    P: Fn(RescoreProgress) + ?Sized,
    S: Fn() -> bool + ?Sized,
{
    let targets: Vec<Dataset> = match dataset {
        Some(name) => vec![datasets::by_name(hub, name).await?],
        None => {
            let mut conn = hub.conn().await?;
            store::datasets::overview(&mut conn)
                .await?
                .into_iter()
                .map(|o| o.dataset)
                .collect()
        }
    };
    let mut summary = RescoreSummary {
        metric_version: METRIC_VERSION,
        ..RescoreSummary::default()
    };
    for dataset in &targets {
        summary.datasets += 1;
        rescore_submissions(hub, dataset, progress, stop, &mut summary).await?;
        if summary.stopped {
            break;
        }
        rescore_human_answers(hub, dataset, progress, stop, &mut summary).await?;
        if summary.stopped {
            break;
        }
    }
    let mut tx = hub.write(Lane::Bulk).await?;
    if summary.submissions + summary.human_answers > 0 {
        // Running servers drop what they keep in memory (boards above all) when the content
        // generation moves: a rescore run from the command line reaches them as an import does.
        store::bump_content_generation(&mut tx).await?;
    }
    audit::record(
        &mut tx,
        actor,
        AuditAction::MetricRescore,
        match dataset {
            Some(name) => format!("dataset {name}"),
            None => "every dataset".to_owned(),
        },
        dataset,
        summary.detail(),
    )
    .await?;
    tx.commit().await?;
    tracing::info!(detail = %summary.detail(), "rescore");
    Ok(summary)
}

async fn rescore_submissions<P, S>(
    hub: &Hub,
    dataset: &Dataset,
    progress: &P,
    stop: &S,
    summary: &mut RescoreSummary,
) -> Result<(), AppError>
where
    P: Fn(RescoreProgress) + ?Sized,
    S: Fn() -> bool + ?Sized,
{
    let mut conn = hub.conn().await?;
    let ids = store::submissions::below_version(&mut conn, dataset.id, METRIC_VERSION).await?;
    drop(conn);
    for (done, id) in ids.iter().enumerate() {
        if stop() {
            summary.stopped = true;
            return Ok(());
        }
        match rescore_one_submission(hub, *id).await? {
            Unit::Rescored { changed } => {
                summary.submissions += 1;
                summary.submissions_changed += usize::from(changed);
            }
            Unit::Current => {}
            Unit::Failed(why) => summary.failures.push(format!(
                "dataset '{}': submission {id}: {why}",
                dataset.name
            )),
        }
        progress(RescoreProgress {
            dataset: dataset.name.clone(),
            stage: RescoreStage::Submissions,
            done: done + 1,
            total: ids.len(),
        });
    }
    Ok(())
}

/// How one unit ended.
enum Unit {
    Rescored {
        changed: bool,
    },
    /// Already at the current version (another rescore did it), or gone.
    Current,
    Failed(String),
}

async fn rescore_one_submission(hub: &Hub, id: i64) -> Result<Unit, AppError> {
    for _ in 0..ATTEMPTS {
        let mut conn = hub.conn().await?;
        let generation = store::content_generation(&mut conn).await?;
        let Some(row) = store::submissions::by_id(&mut conn, id).await? else {
            return Ok(Unit::Current);
        };
        if row.metric_version >= METRIC_VERSION {
            return Ok(Unit::Current);
        }
        let old_scores = store::submissions::scores_json(&mut conn, id).await?;
        let verdicts = store::submissions::verdicts(&mut conn, id).await?;
        drop(conn);
        let mut answers = Vec::with_capacity(verdicts.len());
        for v in verdicts {
            let (Some(line), Some(raw_answer)) = (v.line, v.raw_answer) else {
                continue; // no answer: counted missing again
            };
            let Ok(line) = usize::try_from(line) else {
                return Ok(Unit::Failed(format!("item {}: stored line {line}", v.id)));
            };
            answers.push(StoredAnswer {
                item_id: v.id,
                line,
                raw_answer,
            });
        }
        let targets = submissions::dataset_targets(hub, row.dataset_id).await?;
        let scoring = targets.clone();
        // Rescoring is long work already under way: it waits for a place on the pool.
        let scored = hub
            .heavy()
            .run_waiting(move || rescore_submission(&scoring.targets, &answers))
            .await;
        let scored = match scored {
            Ok(scored) => scored,
            Err(SubmissionError::Rejected(problems)) => {
                let first: Vec<&str> = problems
                    .iter()
                    .take(3)
                    .map(|p| p.message.as_str())
                    .collect();
                return Ok(Unit::Failed(format!(
                    "its stored answers are refused under the current rules: {}",
                    first.join("; ")
                )));
            }
            Err(SubmissionError::Dataset(e)) => {
                return Ok(Unit::Failed(format!("the dataset cannot be scored: {e}")));
            }
        };
        let new_scores = serde_json::to_string(&scored.scores)?;
        let verdicts = statements::scored_verdicts(&targets.targets, &scored.items);
        let mut tx = hub.write(Lane::Bulk).await?;
        if store::content_generation(&mut tx).await? != generation {
            // An import changed the items meanwhile: score against what it left.
            tx.rollback().await?;
            continue;
        }
        let written = store::submissions::replace_scores(
            &mut tx,
            id,
            &scored.scores,
            METRIC_VERSION,
            BUILD,
            &targets.item_rows,
            &scored.items,
        )
        .await?;
        if !written {
            tx.rollback().await?;
            return Ok(Unit::Current);
        }
        statements::record(hub, &mut tx, id, verdicts).await?;
        tx.announce(Change::Boards).await?;
        tx.commit().await?;
        return Ok(Unit::Rescored {
            changed: old_scores.as_deref() != Some(new_scores.as_str()),
        });
    }
    Ok(Unit::Failed(format!(
        "imports changed the dataset {ATTEMPTS} times while it was rescored; run the rescore again"
    )))
}

async fn rescore_human_answers<P, S>(
    hub: &Hub,
    dataset: &Dataset,
    progress: &P,
    stop: &S,
    summary: &mut RescoreSummary,
) -> Result<(), AppError>
where
    P: Fn(RescoreProgress) + ?Sized,
    S: Fn() -> bool + ?Sized,
{
    let mut conn = hub.conn().await?;
    let total =
        store::annotations::count_below_version(&mut conn, dataset.id, METRIC_VERSION).await?;
    drop(conn);
    let total = usize::try_from(total).unwrap_or(0);
    let mut cursor = (i64::MIN, i64::MIN);
    let mut done = 0;
    let mut attempts = 0;
    loop {
        if stop() {
            summary.stopped = true;
            return Ok(());
        }
        let mut conn = hub.conn().await?;
        let generation = store::content_generation(&mut conn).await?;
        let batch = store::annotations::answers_below_version(
            &mut conn,
            dataset.id,
            METRIC_VERSION,
            cursor,
            HUMAN_BATCH,
        )
        .await?;
        drop(conn);
        let Some(last) = batch.last() else {
            return Ok(());
        };
        let next_cursor = (last.item, last.annotator);
        let judged: Vec<_> = batch
            .iter()
            .map(|a| (a, human_verdict(&a.answer)))
            .collect();
        let mut tx = hub.write(Lane::Bulk).await?;
        if store::content_generation(&mut tx).await? != generation {
            tx.rollback().await?;
            attempts += 1;
            if attempts < ATTEMPTS {
                continue; // the same batch again, judged against what the import left
            }
            summary.failures.push(format!(
                "dataset '{}': {} human answers: imports changed the dataset {ATTEMPTS} times \
                 while they were rescored; run the rescore again",
                dataset.name,
                batch.len()
            ));
            attempts = 0;
            cursor = next_cursor;
            continue;
        }
        let mut rescored = 0;
        let mut changed = 0;
        for (a, verdict) in &judged {
            match verdict {
                Ok(verdict) => {
                    if store::annotations::set_verdict(
                        &mut tx,
                        a.annotator,
                        a.item,
                        verdict,
                        METRIC_VERSION,
                    )
                    .await?
                    {
                        rescored += 1;
                        changed += usize::from(a.verdict.is_some_and(|old| old != *verdict));
                    }
                }
                Err(e) => summary.failures.push(format!(
                    "dataset '{}': item {}: a human answer cannot be judged: {e}",
                    dataset.name, a.answer.item_id
                )),
            }
        }
        tx.announce(Change::Boards).await?;
        tx.commit().await?;
        summary.human_answers += rescored;
        summary.human_answers_changed += changed;
        attempts = 0;
        cursor = next_cursor;
        done += batch.len();
        progress(RescoreProgress {
            dataset: dataset.name.clone(),
            stage: RescoreStage::HumanAnswers,
            done,
            // Answers finished during the rescore may add to what it found at the start.
            total: total.max(done),
        });
    }
}

/// Judges the annotator's answer on `item` and stores its verdict, inside the transaction that
/// finished it. An answer the verifier cannot judge (the item's signature table does not cover
/// it) keeps no verdict: the Human row judges it again when read and says what is wrong.
pub(crate) async fn judge_answer(
    conn: &mut store::Tx,
    annotator: i64,
    item: i64,
) -> Result<(), AppError> {
    let Some(answer) = store::annotations::answer_to_judge(conn, annotator, item).await? else {
        return Ok(());
    };
    match human_verdict(&answer.answer) {
        Ok(verdict) => {
            store::annotations::set_verdict(conn, annotator, item, &verdict, METRIC_VERSION)
                .await?;
        }
        Err(e) => tracing::warn!(
            item = %answer.answer.item_id,
            error = %e,
            "a human answer cannot be judged; its verdict is left to be computed"
        ),
    }
    Ok(())
}

/// Judges again every answer on a dataset whose items' signatures changed, inside the import
/// that changed them, so the Human row never reads a verdict of old signatures. Returns how
/// many verdicts were stored; answers that cannot be judged keep none (see [`judge_answer`]).
pub(crate) async fn rejudge_dataset(
    conn: &mut store::Tx,
    dataset_id: i64,
) -> Result<usize, sqlx::Error> {
    store::annotations::forget_verdicts(conn, dataset_id).await?;
    let mut cursor = (i64::MIN, i64::MIN);
    let mut stored = 0;
    loop {
        let batch = store::annotations::answers_below_version(
            conn,
            dataset_id,
            METRIC_VERSION,
            cursor,
            HUMAN_BATCH,
        )
        .await?;
        let Some(last) = batch.last() else {
            return Ok(stored);
        };
        cursor = (last.item, last.annotator);
        for a in &batch {
            if let Ok(verdict) = human_verdict(&a.answer)
                && store::annotations::set_verdict(
                    conn,
                    a.annotator,
                    a.item,
                    &verdict,
                    METRIC_VERSION,
                )
                .await?
            {
                stored += 1;
            }
        }
    }
}
