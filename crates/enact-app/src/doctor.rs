//! `enact-hub doctor`: what an operator should look at in a hub's database before it bites,
//! each finding with what to do about it. Reads only, unless asked to remove stale imports.

use serde::Serialize;

use super::{AppError, Hub};
use crate::core::audit::Actor;
use crate::store;

/// How long an unfinished import waits untouched before it counts as abandoned: a killed
/// import is normally run again within minutes.
pub const STALE_IMPORT_HOURS: u32 = 24;

/// A write-ahead log this much larger than the database (and over [`WAL_FLOOR_BYTES`]) means
/// checkpoints are not keeping up: a long reader holds the log, or writes never pause.
const WAL_SHARE_WARNING: f64 = 0.10;
const WAL_FLOOR_BYTES: u64 = 64 * 1024 * 1024;

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Level {
    /// Nothing to do.
    Ok,
    /// Worth knowing; nothing is wrong.
    Notice,
    /// Needs an operator's action.
    Warning,
}

#[derive(Debug, Clone, Serialize)]
pub struct Finding {
    /// What was checked: `schema`, `imports`, `jobs`, `write-ahead log`, `integrity`.
    pub check: &'static str,
    pub level: Level,
    pub detail: String,
    /// The command or step that deals with it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fix: Option<String>,
}

impl Finding {
    fn new(check: &'static str, level: Level, detail: String, fix: Option<String>) -> Finding {
        Finding {
            check,
            level,
            detail,
            fix,
        }
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct Checkup {
    pub findings: Vec<Finding>,
}

impl Checkup {
    /// The most serious level found.
    pub fn worst(&self) -> Level {
        self.findings
            .iter()
            .map(|f| f.level)
            .max()
            .unwrap_or(Level::Ok)
    }
}

/// What `examine` does besides reading.
#[derive(Debug, Clone, Copy, Default)]
pub struct Options {
    /// Discard the unfinished imports untouched for [`STALE_IMPORT_HOURS`] (audited).
    pub remove_stale_imports: bool,
    /// Run SQLite's `PRAGMA quick_check` (reads every page: minutes on a full-size database).
    pub integrity: bool,
    /// Fold SQLite's write-ahead log into the database and cut the log file back.
    pub truncate_log: bool,
}

/// Examines the hub's database: its schema against this build, unfinished imports, jobs whose
/// instance died or that failed, the SQLite write-ahead log's size and, when asked, the
/// database file's integrity.
pub async fn examine(hub: &Hub, actor: &Actor, options: Options) -> Result<Checkup, AppError> {
    let mut findings = vec![schema(hub).await?];
    findings.extend(imports(hub, actor, options.remove_stale_imports).await?);
    findings.extend(jobs(hub).await?);
    if options.truncate_log && !hub.truncate_log().await {
        findings.push(Finding::new(
            "write-ahead log",
            Level::Warning,
            "the log could not be emptied: another connection still reads from it".into(),
            Some("end long readers (an open `sqlite3` shell, a stuck backup), then again".into()),
        ));
    }
    if let Some(f) = write_ahead_log(hub).await? {
        findings.push(f);
    }
    if options.integrity {
        findings.push(integrity(hub).await?);
    }
    Ok(Checkup { findings })
}

async fn schema(hub: &Hub) -> Result<Finding, AppError> {
    let build = super::version::describe(hub).await?;
    let db = &build.database;
    Ok(if db.applied > db.expected {
        Finding::new(
            "schema",
            Level::Warning,
            format!(
                "the {} database is at migration {}, newer than this build's {} ({}): another \
                 instance was upgraded",
                db.backend, db.applied, db.expected, build.version
            ),
            Some("run the newer enact-hub build against this database".into()),
        )
    } else {
        Finding::new(
            "schema",
            Level::Ok,
            format!(
                "{} database at migration {} (this build: {} {})",
                db.backend, db.applied, build.version, build.commit
            ),
            None,
        )
    })
}

async fn imports(hub: &Hub, actor: &Actor, remove_stale: bool) -> Result<Vec<Finding>, AppError> {
    let unfinished = {
        let mut conn = hub.pool().acquire().await?;
        store::staged::all(&mut conn).await?
    };
    let stale: Vec<String> = super::import::stale(hub, STALE_IMPORT_HOURS)
        .await
        .map_err(|e| AppError::Internal(e.into()))?
        .into_iter()
        .map(|s| s.dataset)
        .collect();
    if unfinished.is_empty() {
        return Ok(vec![Finding::new(
            "imports",
            Level::Ok,
            "no unfinished import".into(),
            None,
        )]);
    }
    let mut findings = Vec::new();
    for s in &unfinished {
        let what = format!(
            "unfinished import into dataset '{}': {} records written, started {}, last batch {}",
            s.dataset, s.rows_done, s.started_at, s.updated_at
        );
        if !stale.contains(&s.dataset) {
            findings.push(Finding::new(
                "imports",
                Level::Notice,
                format!("{what} (running, or killed: readers do not see it)"),
                Some(
                    "run the same import again to resume it, or `enact-hub import --abandon \
                     DATASET`"
                        .into(),
                ),
            ));
        } else if remove_stale {
            super::import::abandon(hub, actor, &s.dataset)
                .await
                .map_err(|e| AppError::Internal(e.into()))?;
            findings.push(Finding::new(
                "imports",
                Level::Notice,
                format!("{what}: removed (untouched for {STALE_IMPORT_HOURS} hours)"),
                None,
            ));
        } else {
            findings.push(Finding::new(
                "imports",
                Level::Warning,
                format!("{what}: untouched for {STALE_IMPORT_HOURS} hours, its rows take space"),
                Some(format!(
                    "`enact-hub import --abandon {}`, or `enact-hub doctor --remove-stale`",
                    s.dataset
                )),
            ));
        }
    }
    Ok(findings)
}

async fn jobs(hub: &Hub) -> Result<Vec<Finding>, AppError> {
    let mut conn = hub.pool().acquire().await?;
    let running = store::jobs::running(&mut conn).await?;
    let failed = store::jobs::failed(&mut conn, 20).await?;
    drop(conn);
    let now = super::jobs::now_ms();
    let mut findings = Vec::new();
    for job in running {
        let expired = job.lease_until_ms.is_none_or(|until| until < now);
        if expired {
            findings.push(Finding::new(
                "jobs",
                Level::Warning,
                format!(
                    "job {} ({}) is running under {}'s lease, which has expired: that \
                     instance stopped mid-job",
                    job.id,
                    job.kind.as_str(),
                    job.lease_owner.as_deref().unwrap_or("no instance"),
                ),
                Some(
                    "start `enact-hub serve` on this database: its job worker takes the job \
                     over where it stopped"
                        .into(),
                ),
            ));
        }
    }
    for job in failed {
        findings.push(Finding::new(
            "jobs",
            Level::Notice,
            format!(
                "job {} ({}) failed after {} attempts, {}: {}",
                job.id,
                job.kind.as_str(),
                job.attempts,
                job.finished_at.as_deref().unwrap_or(&job.updated_at),
                job.last_error.as_deref().unwrap_or("no error recorded"),
            ),
            None,
        ));
    }
    if findings.is_empty() {
        findings.push(Finding::new(
            "jobs",
            Level::Ok,
            "no job stuck or failed".into(),
            None,
        ));
    }
    Ok(findings)
}

async fn write_ahead_log(hub: &Hub) -> Result<Option<Finding>, AppError> {
    let Some(files) = store::sqlite_files(hub.pool()).await? else {
        return Ok(None);
    };
    let size = |path: &std::path::Path| std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    let (database, wal) = (size(&files.database), size(&files.wal));
    let mib = |bytes: u64| bytes as f64 / (1024.0 * 1024.0);
    let detail = format!(
        "{}: {:.1} MiB, write-ahead log {:.1} MiB",
        files.database.display(),
        mib(database),
        mib(wal)
    );
    let swollen = wal > WAL_FLOOR_BYTES && wal as f64 > WAL_SHARE_WARNING * database as f64;
    Ok(Some(if swollen {
        Finding::new(
            "write-ahead log",
            Level::Warning,
            format!("{detail}: checkpoints are not keeping up (a long-running reader?)"),
            Some(
                "end long readers (an open `sqlite3` shell, a stuck backup), then \
                 `enact-hub doctor --truncate-log`"
                    .into(),
            ),
        )
    } else {
        Finding::new("write-ahead log", Level::Ok, detail, None)
    }))
}

async fn integrity(hub: &Hub) -> Result<Finding, AppError> {
    Ok(match store::quick_check(hub.pool()).await? {
        None => Finding::new(
            "integrity",
            Level::Notice,
            "PostgreSQL checks its own pages; use amcheck or pg_checksums for a full check".into(),
            None,
        ),
        Some(problems) if problems.is_empty() => Finding::new(
            "integrity",
            Level::Ok,
            "PRAGMA quick_check: ok".into(),
            None,
        ),
        Some(problems) => Finding::new(
            "integrity",
            Level::Warning,
            format!(
                "PRAGMA quick_check found {} problems: {}",
                problems.len(),
                problems.join("; ")
            ),
            Some("restore the last backup (`enact-hub restore`)".into()),
        ),
    })
}
