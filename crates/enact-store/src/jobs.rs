//! Rows of the job queue: enqueuing, claiming by lease, renewing, finishing, and the admin's
//! state changes. Times of leases and retries are milliseconds since the epoch, given by the
//! caller (the application's clock decides; the rows only record).

use super::db::{Conn, Fields, WriteConn, on};

/// Which code works a job.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum JobKind {
    /// A model run: every item of a dataset asked of an OpenAI-compatible endpoint.
    ModelRun,
    /// Stored results re-scored under the current metric version.
    Rescore,
    /// A release imported from the server's import folder (staged, as the command line does).
    Import,
}

impl JobKind {
    pub const ALL: [JobKind; 3] = [JobKind::ModelRun, JobKind::Rescore, JobKind::Import];

    pub fn as_str(self) -> &'static str {
        match self {
            JobKind::ModelRun => "model_run",
            JobKind::Rescore => "rescore",
            JobKind::Import => "import",
        }
    }

    pub fn parse(text: &str) -> Option<JobKind> {
        JobKind::ALL.into_iter().find(|k| k.as_str() == text)
    }
}

/// Where a job is in its life.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum JobState {
    /// Waiting for an instance (new, resumed, released at shutdown, or waiting to retry).
    Queued,
    /// Held by the instance named in its lease.
    Running,
    /// Stopped by an admin until resumed; its work so far is kept.
    Paused,
    Done,
    /// Failed more often than it is retried; `last_error` says why.
    Failed,
    Cancelled,
}

impl JobState {
    pub const ALL: [JobState; 6] = [
        JobState::Queued,
        JobState::Running,
        JobState::Paused,
        JobState::Done,
        JobState::Failed,
        JobState::Cancelled,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            JobState::Queued => "queued",
            JobState::Running => "running",
            JobState::Paused => "paused",
            JobState::Done => "done",
            JobState::Failed => "failed",
            JobState::Cancelled => "cancelled",
        }
    }

    pub fn parse(text: &str) -> Option<JobState> {
        JobState::ALL.into_iter().find(|s| s.as_str() == text)
    }

    /// Whether the job will never run again.
    pub fn is_final(self) -> bool {
        matches!(
            self,
            JobState::Done | JobState::Failed | JobState::Cancelled
        )
    }
}

/// A job as stored.
#[derive(Debug, Clone, serde::Serialize)]
pub struct JobRow {
    pub id: i64,
    pub kind: JobKind,
    /// The job's parameters, as JSON text.
    #[serde(skip)]
    pub payload: String,
    pub state: JobState,
    /// What the job's code last reported, as JSON text.
    #[serde(skip)]
    pub progress: Option<String>,
    pub attempts: i64,
    pub last_error: Option<String>,
    pub lease_owner: Option<String>,
    pub lease_until_ms: Option<i64>,
    pub created_by: String,
    pub created_at: String,
    pub updated_at: String,
    pub finished_at: Option<String>,
}

const COLUMNS: &str = "id, kind, payload, state, progress, attempts, last_error, lease_owner, \
                       lease_until_ms, created_by, created_at, updated_at, finished_at";

fn job_from_row(row: &impl Fields) -> Result<JobRow, sqlx::Error> {
    let kind: String = row.try_get("kind")?;
    Ok(JobRow {
        id: row.try_get("id")?,
        kind: JobKind::parse(&kind)
            .ok_or_else(|| super::corrupt("kind", format!("unknown job kind {kind:?}")))?,
        payload: row.try_get("payload")?,
        state: row.try_get("state")?,
        progress: row.try_get("progress")?,
        attempts: row.try_get("attempts")?,
        last_error: row.try_get("last_error")?,
        lease_owner: row.try_get("lease_owner")?,
        lease_until_ms: row.try_get("lease_until_ms")?,
        created_by: row.try_get("created_by")?,
        created_at: row.try_get("created_at")?,
        updated_at: row.try_get("updated_at")?,
        finished_at: row.try_get("finished_at")?,
    })
}

/// Adds a queued job; call inside the transaction of the change that asks for it.
pub async fn insert(
    conn: &mut WriteConn,
    kind: JobKind,
    payload: &str,
    created_by: &str,
) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
            "INSERT INTO jobs (kind, payload, created_by) VALUES ($1, $2, $3) RETURNING id",
        )
        .bind(kind.as_str())
        .bind(payload)
        .bind(created_by)
        .fetch_one(&mut *c)
        .await
    })
}

/// Takes the lease of the oldest job of one of `kinds` that is queued and due, or running on a
/// lease that ran out before `now_ms` (its instance died), for `owner` until `lease_until_ms`.
/// Run it in a write transaction: two instances then never take the same job. A job paused
/// and resumed while its code was still working keeps that lease until the code has stopped
/// (or the lease ran out), so the job's code never runs twice at once. Jobs in `working` (the
/// claiming worker's own, still running: their lease ran out because its renewals were held
/// up) are left alone, for the same reason.
pub async fn claim(
    conn: &mut WriteConn,
    kinds: &[JobKind],
    owner: &str,
    now_ms: i64,
    lease_until_ms: i64,
    working: &[i64],
) -> Result<Option<JobRow>, sqlx::Error> {
    // `,model_run,rescore,`: one parameter both databases can match a kind against.
    let kinds: String = kinds.iter().fold(",".to_owned(), |mut list, kind| {
        list.push_str(kind.as_str());
        list.push(',');
        list
    });
    // `,4,7,`: the jobs the claiming worker still works, the same way.
    let working: String = working.iter().fold(",".to_owned(), |mut list, id| {
        list.push_str(&id.to_string());
        list.push(',');
        list
    });
    on!(conn, |c| {
        let sql = format!(
            "UPDATE jobs SET state = 'running', lease_owner = $1, lease_until_ms = $2, \
                    attempts = attempts + 1, updated_at = {now} \
             WHERE id = (SELECT id FROM jobs \
                         WHERE ((state = 'queued' AND run_after_ms <= $3 \
                                 AND (lease_owner IS NULL OR lease_until_ms < $3)) \
                                OR (state = 'running' AND lease_until_ms < $3)) \
                           AND $4 LIKE '%,' || kind || ',%' \
                           AND $5 NOT LIKE '%,' || CAST(id AS TEXT) || ',%' \
                         ORDER BY id LIMIT 1) \
             RETURNING {COLUMNS}",
            now = super::db::Dialect::utc_now(&*c),
        );
        let row = sqlx::query(&sql)
            .bind(owner)
            .bind(lease_until_ms)
            .bind(now_ms)
            .bind(kinds)
            .bind(working)
            .fetch_optional(&mut *c)
            .await?;
        row.as_ref().map(job_from_row).transpose()
    })
}

/// Extends `owner`'s lease of a job to `lease_until_ms`. Returns the job's state when `owner`
/// still holds it (an admin may have paused or cancelled it meanwhile: the lease then stays
/// `owner`'s until it lets go), `None` when the lease was lost.
pub async fn renew(
    conn: &mut WriteConn,
    id: i64,
    owner: &str,
    lease_until_ms: i64,
) -> Result<Option<JobState>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
            "UPDATE jobs SET lease_until_ms = $3 WHERE id = $1 AND lease_owner = $2 \
             RETURNING state",
        )
        .bind(id)
        .bind(owner)
        .bind(lease_until_ms)
        .fetch_optional(&mut *c)
        .await
    })
}

/// `owner` lets go of a job: it becomes `state` (`Queued` to be taken again at `run_after_ms`,
/// or a final state), with `error` recorded when given. A job an admin paused or cancelled
/// meanwhile keeps that state. Returns whether `owner` still held it.
pub async fn release(
    conn: &mut WriteConn,
    id: i64,
    owner: &str,
    state: JobState,
    run_after_ms: i64,
    error: Option<&str>,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let sql = format!(
            "UPDATE jobs SET \
                 state = CASE WHEN state = 'running' THEN $3 ELSE state END, \
                 run_after_ms = $4, last_error = COALESCE($5, last_error), \
                 lease_owner = NULL, lease_until_ms = NULL, updated_at = {now}, \
                 finished_at = CASE WHEN state = 'running' AND $3 IN ('done', 'failed', 'cancelled') \
                                    THEN {now} ELSE finished_at END \
             WHERE id = $1 AND lease_owner = $2",
            now = super::db::Dialect::utc_now(&*c),
        );
        let done = sqlx::query(&sql)
            .bind(id)
            .bind(owner)
            .bind(state)
            .bind(run_after_ms)
            .bind(error)
            .execute(&mut *c)
            .await?;
        Ok(done.rows_affected() == 1)
    })
}

/// Puts a job in state `to` (an admin's pause, resume or cancel, decided by the caller from
/// the state it read in the same write transaction); a queued job is due at once.
pub async fn set_state(conn: &mut WriteConn, id: i64, to: JobState) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        let sql = format!(
            "UPDATE jobs SET state = $2, run_after_ms = 0, updated_at = {now}, \
                 finished_at = CASE WHEN $2 IN ('done', 'failed', 'cancelled') THEN {now} \
                                    ELSE NULL END \
             WHERE id = $1",
            now = super::db::Dialect::utc_now(&*c),
        );
        sqlx::query(&sql).bind(id).bind(to).execute(&mut *c).await?;
        Ok(())
    })
}

/// Records what the job's code reports of its progress (JSON text).
pub async fn set_progress(
    conn: &mut WriteConn,
    id: i64,
    progress: &str,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("UPDATE jobs SET progress = $2 WHERE id = $1")
            .bind(id)
            .bind(progress)
            .execute(&mut *c)
            .await?;
        Ok(())
    })
}

/// One job.
pub async fn get(conn: &mut Conn, id: i64) -> Result<Option<JobRow>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(&format!("SELECT {COLUMNS} FROM jobs WHERE id = $1"))
            .bind(id)
            .fetch_optional(&mut *c)
            .await?;
        row.as_ref().map(job_from_row).transpose()
    })
}

/// The newest jobs, of one kind when given, at most `limit`.
pub async fn list(
    conn: &mut Conn,
    kind: Option<JobKind>,
    limit: i64,
) -> Result<Vec<JobRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "SELECT {COLUMNS} FROM jobs WHERE ($1 IS NULL OR kind = $1) ORDER BY id DESC LIMIT $2"
        ))
        .bind(kind.map(JobKind::as_str))
        .bind(limit)
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(job_from_row).collect()
    })
}

/// The jobs of `kind` that have not ended (queued, running or paused), oldest first.
pub async fn unfinished(conn: &mut Conn, kind: JobKind) -> Result<Vec<JobRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "SELECT {COLUMNS} FROM jobs WHERE kind = $1 \
             AND state IN ('queued', 'running', 'paused') ORDER BY id"
        ))
        .bind(kind.as_str())
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(job_from_row).collect()
    })
}

/// How many jobs there are of each kind in each state.
pub async fn counts(conn: &mut Conn) -> Result<Vec<(String, String, i64)>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_as(
            "SELECT kind, state, count(*) FROM jobs GROUP BY kind, state ORDER BY kind, state",
        )
        .fetch_all(&mut *c)
        .await
    })
}

/// The newest failed jobs, at most `limit`.
pub async fn failed(conn: &mut Conn, limit: i64) -> Result<Vec<JobRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "SELECT {COLUMNS} FROM jobs WHERE state = 'failed' ORDER BY id DESC LIMIT $1"
        ))
        .bind(limit)
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(job_from_row).collect()
    })
}

/// The running jobs, oldest first.
pub async fn running(conn: &mut Conn) -> Result<Vec<JobRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "SELECT {COLUMNS} FROM jobs WHERE state = 'running' ORDER BY id"
        ))
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(job_from_row).collect()
    })
}
