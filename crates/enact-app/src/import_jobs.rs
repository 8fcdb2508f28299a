//! Imports worked as jobs: an admin asks the hub (API or admin page) to import a release that
//! sits in the server's import folder (`serve --import-dir`), and the serving instances' job
//! workers run the same staged import as the command line. Started again after a crash, a
//! restart or a takeover, the job resumes after the import's last committed batch; paused, it
//! stops between batches and keeps them; cancelled, it discards what it staged.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use serde::{Deserialize, Serialize};
use tokio::sync::watch;

use super::import::{
    BATCH_LINES, ImportError, ImportObserver, ImportOptions, ImportProgress, ImportStop,
    ReleaseLocation, abandon, default_dataset_name, import_release,
};
use super::jobs::{self, JobContext, JobId, JobKind, JobState};
use super::refusal::{ImportPathProblem, Refusal};
use super::{AppError, Hub};
use crate::Lane;
use crate::core::audit::Actor;
use crate::store;

/// What an admin asks for: a release under the import folder, and the command line's options.
#[derive(Debug, Clone, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ImportRequest {
    /// The release folder (or its `QA/*.jsonl` file), relative to the server's import folder.
    pub path: String,
    /// The dataset to import into; the release folder's name when absent.
    #[serde(default)]
    pub dataset: Option<String>,
    /// Overwrite stored items whose content differs (`import --replace`).
    #[serde(default)]
    pub replace: bool,
    /// Import the valid lines and list the others (`import --skip-invalid`).
    #[serde(default)]
    pub skip_invalid: bool,
}

/// The job's payload: the request as resolved when it was queued, and who asked.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct ImportPayload {
    /// Relative to the import folder, as asked.
    path: String,
    dataset: String,
    replace: bool,
    skip_invalid: bool,
    actor_kind: String,
    actor: String,
}

/// What a queued import's progress says, for pages and `GET /api/v1/admin/jobs/{id}`: written
/// and read only as this enum.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
enum ImportOutcome {
    /// Still going: how far it has read.
    Importing {
        dataset: String,
        qa_bytes_read: u64,
        qa_bytes: u64,
        rows: usize,
    },
    /// Imported: the import's report (as `import --json` prints it).
    Imported {
        dataset: String,
        report: Box<super::import::ImportReport>,
    },
    /// Refused for what the release holds (invalid lines, conflicts): retrying cannot help,
    /// so the job ends here with the reasons.
    Refused {
        dataset: String,
        error: String,
        details: Vec<String>,
    },
    /// Cancelled by an admin: what it had staged is discarded.
    Cancelled { dataset: String },
}

/// The refusal of `path`, the release an admin asked for, for `problem`.
fn path_refused(path: &str, problem: ImportPathProblem) -> AppError {
    AppError::Refused(Refusal::ImportPath {
        path: path.to_owned(),
        problem,
    })
}

/// Where `path` (relative to `root`) is, refused when it leaves `root` (`..`, a symbolic link
/// out) or is not there.
fn under(root: &Path, path: &str) -> Result<PathBuf, AppError> {
    let root = std::fs::canonicalize(root)
        .map_err(|e| AppError::internal(format!("the import folder {}: {e}", root.display())))?;
    let refused = |problem| path_refused(path, problem);
    let asked = Path::new(path.trim());
    if asked.as_os_str().is_empty() || asked.is_absolute() {
        return Err(refused(ImportPathProblem::NotRelative));
    }
    let resolved =
        std::fs::canonicalize(root.join(asked)).map_err(|_| refused(ImportPathProblem::Missing))?;
    if !resolved.starts_with(&root) {
        return Err(refused(ImportPathProblem::LeavesFolder));
    }
    Ok(resolved)
}

/// The release at `path` under `root`: its QA file must be JSON lines and the release folder
/// (the images' base) must lie inside `root` too.
fn release_under(root: &Path, path: &str) -> Result<(PathBuf, ReleaseLocation), AppError> {
    let resolved = under(root, path)?;
    let location =
        ReleaseLocation::resolve(&resolved).map_err(|e| AppError::Invalid(format!("path: {e}")))?;
    let refused = |problem| path_refused(path, problem);
    if location.qa_file.extension().and_then(|e| e.to_str()) != Some("jsonl") {
        return Err(refused(ImportPathProblem::NotARelease));
    }
    let inside = std::fs::canonicalize(&location.root)
        .ok()
        .zip(std::fs::canonicalize(root).ok())
        .is_some_and(|(release, root)| release.starts_with(root));
    if !inside {
        return Err(refused(ImportPathProblem::ReleaseLeavesFolder));
    }
    Ok((resolved, location))
}

/// The folder import jobs read releases from (`serve --import-dir`); none: refused.
#[derive(Debug, Clone, Default)]
pub struct ImportDir(pub Option<PathBuf>);

impl crate::Kept for ImportDir {
    fn make(_hub: &Hub) -> Self {
        ImportDir(None)
    }
}

/// The folder import jobs on `hub` read releases from, when this instance has one.
pub fn folder(hub: &Hub) -> Option<PathBuf> {
    hub.kept::<ImportDir>().0.clone()
}

/// The import folder of this instance, or the refusal an admin reads.
fn import_dir(hub: &Hub) -> Result<PathBuf, AppError> {
    folder(hub).ok_or(AppError::Refused(Refusal::ImportFolderUnset))
}

/// Queues an import of the release at `request.path` under the import folder. The release's
/// location is checked now (its `QA/enact_ordering.jsonl` found); its lines are checked by the
/// job. Refused while another import job into the same dataset is unfinished.
pub async fn request(hub: &Hub, actor: &Actor, request: &ImportRequest) -> Result<JobId, AppError> {
    let (path, _) = release_under(&import_dir(hub)?, &request.path)?;
    let dataset = request
        .dataset
        .as_deref()
        .map(str::trim)
        .filter(|d| !d.is_empty())
        .map_or_else(|| default_dataset_name(&path), str::to_owned);
    let payload = ImportPayload {
        path: request.path.trim().to_owned(),
        dataset,
        replace: request.replace,
        skip_invalid: request.skip_invalid,
        actor_kind: actor.kind().to_owned(),
        actor: actor.name().to_owned(),
    };
    let mut tx = hub.write(Lane::Interactive).await?;
    for job in store::jobs::unfinished(&mut tx, JobKind::Import).await? {
        let other: Option<ImportPayload> = serde_json::from_str(&job.payload).ok();
        if other.is_some_and(|o| o.dataset == payload.dataset) {
            return Err(AppError::Conflict(format!(
                "job {} is already importing into dataset '{}' ({})",
                job.id,
                payload.dataset,
                job.state.as_str()
            )));
        }
    }
    let id = jobs::enqueue(&mut tx, JobKind::Import, &serde_json::json!(payload), actor).await?;
    tx.commit().await?;
    Ok(id)
}

/// How often a running import's progress is written.
const PROGRESS_EVERY: Duration = Duration::from_secs(2);

/// Works a queued import: the staged import of the command line, resumed where an earlier
/// start of the job stopped, its progress stored every few seconds. A refusal for the
/// release's content ends the job with the reasons in its progress (no retry); a database or
/// disk error fails it, to be retried.
pub async fn work(hub: &Hub, job: &Arc<JobContext>) -> Result<(), AppError> {
    let payload: ImportPayload = serde_json::from_value(job.payload.clone())
        .map_err(|e| AppError::internal(format!("import job: unreadable payload: {e}")))?;
    let actor = Actor::from_parts(&payload.actor_kind, &payload.actor).ok_or_else(|| {
        AppError::internal(format!(
            "import job: unknown actor kind {:?}",
            payload.actor_kind
        ))
    })?;
    let (path, location) = release_under(&import_dir(hub)?, &payload.path)?;
    let latest: Arc<Mutex<Option<ImportProgress>>> = Arc::default();
    let noted = Arc::clone(&latest);
    let stopping = Arc::clone(job);
    let options = ImportOptions {
        dataset: payload.dataset.clone(),
        skip_invalid: payload.skip_invalid,
        replace: payload.replace,
        progress: Some(ImportObserver(Arc::new(move |p: &ImportProgress| {
            *noted.lock().unwrap_or_else(|p| p.into_inner()) = Some(*p);
        }))),
        scene_graphs: location.own_scene_graphs(),
        batch_lines: BATCH_LINES,
        stop: Some(ImportStop(Arc::new(move || {
            stopping.stop_requested().is_some()
        }))),
    };
    // The progress is written beside the import, never in its place: awaited while the import
    // waits unpolled, a write would wait for the lock of the batch transaction the import holds
    // open (SQLite's single writer), and both would wait out the busy timeout.
    let (finished, mut ended) = watch::channel(false);
    let importing = async {
        let result = import_release(hub, &actor, &path, &options).await;
        finished.send_replace(true);
        result
    };
    let writer = async {
        let mut tick = tokio::time::interval(PROGRESS_EVERY);
        loop {
            tokio::select! {
                _ = tick.tick() => {
                    let seen = latest.lock().unwrap_or_else(|p| p.into_inner()).take();
                    if let Some(p) = seen {
                        let outcome = ImportOutcome::Importing {
                            dataset: payload.dataset.clone(),
                            qa_bytes_read: p.qa_bytes_read,
                            qa_bytes: p.qa_bytes,
                            rows: p.rows,
                        };
                        if let Err(e) = job.progress(hub, &outcome).await {
                            tracing::warn!(job = job.id.0, error = %e, "storing an import's progress failed");
                        }
                    }
                }
                _ = ended.changed() => break,
            }
        }
    };
    let (result, ()) = tokio::join!(importing, writer);
    let dataset = payload.dataset.clone();
    let outcome = match result {
        Ok(report) => {
            if report.new_frames > 0 {
                hub.truncate_log().await;
            }
            ImportOutcome::Imported {
                dataset,
                report: Box::new(report),
            }
        }
        Err(ImportError::Stopped { .. }) => {
            if job.stop_requested() != Some(JobState::Cancelled) {
                // Paused, or the instance is stopping: the batches stay for the next start.
                return Ok(());
            }
            abandon(hub, &actor, &payload.dataset)
                .await
                .map_err(|e| AppError::Internal(e.into()))?;
            ImportOutcome::Cancelled { dataset }
        }
        Err(
            e @ (ImportError::Invalid { .. }
            | ImportError::Conflict { .. }
            | ImportError::Location(_)
            | ImportError::ImageChanged { .. }),
        ) => ImportOutcome::Refused {
            dataset,
            error: e.to_string(),
            details: e.details(),
        },
        Err(e) => return Err(AppError::Internal(e.into())),
    };
    job.progress(hub, &outcome).await
}

/// An import job as the admin page lists it.
#[derive(Debug, Clone, Serialize)]
pub struct ImportJobSummary {
    pub id: i64,
    pub state: &'static str,
    pub dataset: String,
    pub path: String,
    /// Where it stands, in a sentence.
    pub outcome: String,
    pub updated_at: String,
}

/// The newest import jobs, at most `limit`.
pub async fn recent(hub: &Hub, limit: u32) -> Result<Vec<ImportJobSummary>, AppError> {
    let jobs = jobs::list(hub, Some(JobKind::Import), limit).await?;
    Ok(jobs
        .into_iter()
        .map(|job| {
            let payload: Option<ImportPayload> = serde_json::from_str(&job.payload).ok();
            let progress: Option<ImportOutcome> = job
                .progress
                .as_deref()
                .and_then(|p| serde_json::from_str(p).ok());
            ImportJobSummary {
                id: job.id,
                state: job.state.as_str(),
                dataset: payload
                    .as_ref()
                    .map(|p| p.dataset.clone())
                    .unwrap_or_default(),
                path: payload.map(|p| p.path).unwrap_or_default(),
                outcome: describe(job.state, progress.as_ref(), job.last_error.as_deref()),
                updated_at: job.updated_at,
            }
        })
        .collect())
}

/// A sentence for an import job's state and stored progress.
fn describe(state: JobState, progress: Option<&ImportOutcome>, error: Option<&str>) -> String {
    match progress {
        Some(ImportOutcome::Importing {
            qa_bytes_read,
            qa_bytes,
            rows,
            ..
        }) => {
            let share = if *qa_bytes == 0 {
                0.0
            } else {
                100.0 * *qa_bytes_read as f64 / *qa_bytes as f64
            };
            format!("{rows} lines read ({share:.0} % of the QA file)")
        }
        Some(ImportOutcome::Imported { report, .. }) => report.summary_line(),
        Some(ImportOutcome::Refused { error, .. }) => error.clone(),
        Some(ImportOutcome::Cancelled { .. }) => {
            "cancelled; what it had staged was discarded".to_owned()
        }
        None => match (state, error) {
            (JobState::Queued, Some(e)) => format!("waiting to retry after: {e}"),
            (JobState::Failed, Some(e)) => format!("failed: {e}"),
            (JobState::Queued, None) => "waiting for a job worker".to_owned(),
            (state, _) => state.as_str().to_owned(),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What the job stored, read back as the admin page reads it.
    fn described(outcome: &ImportOutcome, state: JobState) -> String {
        let stored = serde_json::to_string(outcome).expect("serialised");
        let read: ImportOutcome = serde_json::from_str(&stored).expect("read back");
        describe(state, Some(&read), None)
    }

    #[test]
    fn each_stored_outcome_reads_back_as_its_sentence() {
        let dataset = "main".to_owned();
        let importing = ImportOutcome::Importing {
            dataset: dataset.clone(),
            qa_bytes_read: 250,
            qa_bytes: 1000,
            rows: 12,
        };
        assert_eq!(
            described(&importing, JobState::Running),
            "12 lines read (25 % of the QA file)"
        );
        let report = super::super::import::ImportReport {
            dataset: dataset.clone(),
            new_items: 3,
            ..Default::default()
        };
        let imported = ImportOutcome::Imported {
            dataset: dataset.clone(),
            report: Box::new(report.clone()),
        };
        assert_eq!(described(&imported, JobState::Done), report.summary_line());
        let refused = ImportOutcome::Refused {
            dataset: dataset.clone(),
            error: "line 3: not JSON".to_owned(),
            details: vec!["line 3".to_owned()],
        };
        assert_eq!(described(&refused, JobState::Done), "line 3: not JSON");
        assert_eq!(
            described(&ImportOutcome::Cancelled { dataset }, JobState::Cancelled),
            "cancelled; what it had staged was discarded"
        );
        // Nothing stored yet: the job's state says it.
        assert_eq!(
            describe(JobState::Queued, None, Some("busy")),
            "waiting to retry after: busy"
        );
    }
}
