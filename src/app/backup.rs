//! Online backup and restore of the database file.
//!
//! A backup is a consistent snapshot taken while the server runs (SQLite's `VACUUM INTO` in
//! one read transaction): every write committed before it began is in it, none after. It is
//! checked with `PRAGMA integrity_check` before it is reported done. A restore checks the
//! snapshot the same way, then puts it in place with a rename, so the target is never half
//! written; it refuses a database that exists unless told to move it aside.

use std::path::{Path, PathBuf};

use anyhow::Context;
use sqlx::Connection;
use sqlx::sqlite::SqliteConnectOptions;

use super::{AppError, Hub, audit};
use crate::core::audit::{Actor, AuditAction};
use crate::store;

/// What a backup or restore did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Snapshot {
    pub path: PathBuf,
    pub bytes: u64,
    pub submissions: i64,
    pub annotations: i64,
    pub items: i64,
}

/// Checks the database file at `path` and counts what it holds, without changing it.
async fn inspect(path: &Path) -> anyhow::Result<Snapshot> {
    let options = SqliteConnectOptions::new().filename(path).read_only(true);
    let mut conn = sqlx::SqliteConnection::connect_with(&options)
        .await
        .with_context(|| format!("cannot open {}", path.display()))?;
    let check = store::integrity_check(&mut conn).await?;
    if check != "ok" {
        anyhow::bail!("{} fails SQLite's integrity check: {check}", path.display());
    }
    let (submissions, annotations, items): (i64, i64, i64) = sqlx::query_as(
        "SELECT (SELECT count(*) FROM submissions), (SELECT count(*) FROM annotations), \
         (SELECT count(*) FROM items)",
    )
    .fetch_one(&mut conn)
    .await?;
    conn.close().await?;
    Ok(Snapshot {
        path: path.to_path_buf(),
        bytes: std::fs::metadata(path)?.len(),
        submissions,
        annotations,
        items,
    })
}

/// Snapshots the hub's database into `out`, which must not exist.
pub async fn backup(hub: &Hub, actor: &Actor, out: &Path) -> Result<Snapshot, AppError> {
    if out.exists() {
        return Err(AppError::Conflict(format!(
            "{} already exists: a backup never overwrites a file",
            out.display()
        )));
    }
    let mut conn = hub.conn().await?;
    let store::PooledConn::Sqlite(sqlite) = &mut conn else {
        return Err(AppError::BadRequest(
            "backup writes SQLite snapshots; back a PostgreSQL database up with pg_dump".into(),
        ));
    };
    store::backup_into(sqlite, out).await?;
    let snapshot = inspect(out).await?;
    // Written after the snapshot, so the log says what was taken, not what was attempted.
    audit::record(
        &mut conn,
        actor,
        AuditAction::BackupCreate,
        format!("file {}", out.display()),
        None,
        format!(
            "{} bytes: {} items, {} submissions, {} annotations",
            snapshot.bytes, snapshot.items, snapshot.submissions, snapshot.annotations
        ),
    )
    .await?;
    Ok(snapshot)
}

/// Puts the snapshot `from` in place as the database `db`. An existing `db` is refused unless
/// `replace`, which moves it (and its `-wal`/`-shm` files) aside to `{db}.before-restore`.
/// The server must not be running on `db`.
pub async fn restore(from: &Path, db: &Path, replace: bool) -> Result<Snapshot, AppError> {
    let snapshot = inspect(from).await?;
    let side = |suffix: &str| PathBuf::from(format!("{}{suffix}", db.display()));
    if db.exists() {
        if !replace {
            return Err(AppError::Conflict(format!(
                "{} exists: stop the server and give --replace to move it aside first",
                db.display()
            )));
        }
        let aside = side(".before-restore");
        if aside.exists() {
            return Err(AppError::Conflict(format!(
                "{} exists from an earlier restore: move it away first",
                aside.display()
            )));
        }
        std::fs::rename(db, &aside)
            .with_context(|| format!("cannot move {} aside", db.display()))?;
        for suffix in ["-wal", "-shm"] {
            let stale = side(suffix);
            if stale.exists() {
                std::fs::rename(&stale, side(&format!(".before-restore{suffix}")))
                    .with_context(|| format!("cannot move {} aside", stale.display()))?;
            }
        }
    }
    // Copy next to the target, then rename: the target is whole or absent, never half copied.
    let partial = side(".restoring");
    std::fs::copy(from, &partial)
        .with_context(|| format!("cannot copy {} to {}", from.display(), partial.display()))?;
    std::fs::rename(&partial, db).with_context(|| format!("cannot create {}", db.display()))?;
    Ok(Snapshot {
        path: db.to_path_buf(),
        ..snapshot
    })
}
