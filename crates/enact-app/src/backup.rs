//! Online backup and restore.
//!
//! A backup is a consistent snapshot in one SQLite file, taken while the server runs: every
//! write committed before it began is in it, none after. From SQLite it is `VACUUM INTO` in one
//! read transaction; from PostgreSQL it is the database copied table by table into a new SQLite
//! file (the copy holds the write lock, so writers wait for it). It is checked with
//! `PRAGMA integrity_check` before it is reported done. A restore checks the snapshot the same
//! way, then puts it in place with a rename, so the target is never half written; it refuses a
//! database that exists unless told to move it aside. Into PostgreSQL, a restore copies the
//! snapshot into an empty database in one transaction.
//!
//! A snapshot never holds the statement-signing key's secret: it lives in a key file outside the
//! database ([`super::signing`]), and only the public keys and the signed statements are
//! tables. A database restored without its key file makes a new key at its next signing, listed
//! beside the old ones, so every statement stays verifiable.

use std::path::{Path, PathBuf};

use anyhow::Context;
use sqlx::Connection;
use sqlx::sqlite::SqliteConnectOptions;

use super::{AppError, Hub, audit, migrate_db};
use crate::Lane;
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
    match &mut conn {
        store::PooledConn::Sqlite(sqlite) => store::backup_into(sqlite, out).await?,
        store::PooledConn::Pg(_) => copy_into_file(hub, out).await?,
    }
    drop(conn);
    let snapshot = inspect(out).await?;
    // Written after the snapshot, so the log says what was taken, not what was attempted.
    let mut tx = hub.write(Lane::Interactive).await?;
    audit::record(
        &mut tx,
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
    tx.commit().await?;
    Ok(snapshot)
}

/// A side file of `path`: `path` with `suffix` appended.
fn beside(path: &Path, suffix: &str) -> PathBuf {
    PathBuf::from(format!("{}{suffix}", path.display()))
}

/// Removes the SQLite file `path` and its log files, if there.
fn remove_database_file(path: &Path) {
    for suffix in ["", "-wal", "-shm"] {
        let _ = std::fs::remove_file(beside(path, suffix));
    }
}

/// Copies the hub's whole database into a new SQLite file `out` (written beside it, then
/// renamed, so `out` is whole or absent).
async fn copy_into_file(hub: &Hub, out: &Path) -> Result<(), AppError> {
    let partial = beside(out, ".partial");
    if partial.exists() {
        return Err(AppError::Conflict(format!(
            "{} exists from an interrupted backup: remove it first",
            partial.display()
        )));
    }
    let copied = async {
        let file = Hub::open(&partial).await?;
        let copied = migrate_db::migrate_db(hub, &file, |_, _| {}).await;
        file.truncate_log().await;
        file.close().await;
        copied
    }
    .await;
    match copied {
        Ok(_) => {
            std::fs::rename(&partial, out)
                .with_context(|| format!("cannot create {}", out.display()))?;
            remove_database_file(&partial);
            Ok(())
        }
        Err(e) => {
            remove_database_file(&partial);
            Err(e)
        }
    }
}

/// Puts the snapshot `from` in place as the database `db`. An existing `db` is refused unless
/// `replace`, which moves it (and its `-wal`/`-shm` files) aside to `{db}.before-restore`.
/// The server must not be running on `db`.
pub async fn restore(from: &Path, db: &Path, replace: bool) -> Result<Snapshot, AppError> {
    let snapshot = inspect(from).await?;
    if !store::Location::of(db).is_file() {
        return restore_into_database(from, db, replace, snapshot).await;
    }
    let side = |suffix: &str| beside(db, suffix);
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

/// Copies the snapshot `from` into `db`, an empty PostgreSQL database.
async fn restore_into_database(
    from: &Path,
    db: &Path,
    replace: bool,
    snapshot: Snapshot,
) -> Result<Snapshot, AppError> {
    if replace {
        return Err(AppError::Invalid(
            "--replace moves a SQLite file aside; a PostgreSQL restore goes into an empty \
             database: create one (createdb) and restore into it"
                .into(),
        ));
    }
    // Opening a database brings its schema up to date: done on a scratch copy, so the
    // snapshot itself is never changed.
    let scratch = tempfile::Builder::new()
        .prefix("enact-hub-restore-")
        .suffix(".db")
        .tempfile()
        .context("cannot create a scratch file for the restore")?
        .into_temp_path();
    std::fs::copy(from, &scratch)
        .with_context(|| format!("cannot copy {} to {}", from.display(), scratch.display()))?;
    let copied: Result<_, AppError> = async {
        let source = Hub::open(&scratch).await?;
        let copied = async {
            let target = Hub::open(db).await?;
            let copied = migrate_db::migrate_db(&source, &target, |_, _| {}).await;
            target.close().await;
            copied
        }
        .await;
        source.close().await;
        copied
    }
    .await;
    remove_database_file(&scratch);
    copied?;
    Ok(Snapshot {
        path: PathBuf::from(super::describe_location(db)),
        ..snapshot
    })
}
