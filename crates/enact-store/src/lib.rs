//! enact-hub's storage in SQLite or PostgreSQL: connection setup, migrations, the write gate,
//! and the queries the use cases run. It may name the benchmark's types (`enact-core`) and the
//! codecs of columns stored as text, and decides nothing: what to write, and when, is the use
//! cases' (the hub's `app`), which this crate cannot name.
//!
//! Functions take a [`Conn`] (a pooled connection or an open transaction of either database),
//! so a caller that writes several rows decides where the transaction begins and ends. Each
//! query is written once, with `$1` placeholders, for both databases ([`db`]).

pub mod accounts;
pub mod agreement;
pub mod annotations;
pub mod attention;
pub mod audit;
pub mod challenges;
pub mod controls;
pub mod copy;
pub mod datasets;
pub mod db;
pub mod episode_drafts;
pub mod episodes;
pub mod frames;
pub mod gate;
pub mod gold;
pub mod items;
pub mod jobs;
pub mod migrations;
pub mod model_metadata;
pub mod red_flags;
pub mod reported;
pub mod runs;
pub mod staged;
pub mod statements;
pub mod studies;
pub mod submissions;

use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Duration;

pub use db::{Conn, PlainTx, Pool, PooledConn, Tx, WriteConn, Writes};
use db::{Fields, on};
use sqlx::SqlitePool;
use sqlx::sqlite::{SqliteConnectOptions, SqliteJournalMode, SqlitePoolOptions, SqliteSynchronous};

/// The highest SQLite migration this build applies (counted by `build.rs`).
pub const SQLITE_SCHEMA: i64 = decimal(env!("ENACT_HUB_SCHEMA_SQLITE"));

/// The highest PostgreSQL migration this build applies.
pub const POSTGRES_SCHEMA: i64 = decimal(env!("ENACT_HUB_SCHEMA_POSTGRES"));

/// A build script's decimal number, read at compile time (a stray character fails the build).
const fn decimal(text: &str) -> i64 {
    let bytes = text.as_bytes();
    assert!(!bytes.is_empty(), "an empty schema version");
    let mut value = 0;
    let mut i = 0;
    while i < bytes.len() {
        assert!(
            bytes[i].is_ascii_digit(),
            "a schema version that is not a number"
        );
        value = value * 10 + (bytes[i] - b'0') as i64;
        i += 1;
    }
    value
}

/// How long a write waits for the database's write lock before it is refused as busy.
pub const WRITE_WAIT: Duration = Duration::from_secs(10);

/// Connections in a pool.
pub const MAX_CONNECTIONS: u32 = 8;

/// SQLite's page cache per connection for commands (imports and scoring read and write much
/// in one transaction), in KiB.
pub const COMMAND_PAGE_CACHE_KIB: u64 = 64 * 1024;

/// How large the write-ahead log file is left after a checkpoint resets it.
pub const JOURNAL_SIZE_LIMIT_BYTES: u64 = 64 * 1024 * 1024;

/// Opens (creating if missing) the database at `path` and applies the embedded migrations,
/// with the page cache of commands.
pub async fn open(path: &Path) -> Result<SqlitePool, sqlx::Error> {
    open_with_page_cache(path, COMMAND_PAGE_CACHE_KIB).await
}

/// [`open`] with `page_cache_kib` of SQLite page cache per connection (a server keeps
/// [`MAX_CONNECTIONS`] of them; the OS caches the file beneath).
pub async fn open_with_page_cache(
    path: &Path,
    page_cache_kib: u64,
) -> Result<SqlitePool, sqlx::Error> {
    let pool = sqlite_pool(path, page_cache_kib, MAX_CONNECTIONS, PoolRole::Shared).await?;
    migrations::SQLITE.migrator().await?.run(&pool).await?;
    Ok(pool)
}

/// A command's pools on the SQLite file at `path` (migrated): [`MAX_CONNECTIONS`] for reads
/// and one for the write gate's transactions, which takes the write lock as a server's does
/// ([`WRITE_POLL`]) and copies the write-ahead log into the database when a commit fills it.
pub async fn open_command_pools(
    path: &Path,
    page_cache_kib: u64,
) -> Result<(SqlitePool, SqlitePool), sqlx::Error> {
    let pool = open_with_page_cache(path, page_cache_kib).await?;
    let writer = sqlite_pool(path, page_cache_kib, 1, PoolRole::CommandGate).await?;
    Ok((pool, writer))
}

/// A server's pools on the SQLite file at `path` (migrated): [`MAX_CONNECTIONS`] for reads
/// and for writes outside the write gate, and one more, the gate's own, which only the writer
/// holding the gate's turn uses. A writer given the turn then never waits for a connection
/// that readers hold, with the turn (and every writer behind it) held meanwhile. Nor does it
/// copy the write-ahead log into the database when its commit fills the log (SQLite's
/// automatic checkpoint, tens of milliseconds after a few submissions): [`checkpoint_log`]
/// does that beside it.
pub async fn open_serving_pools(
    path: &Path,
    page_cache_kib: u64,
) -> Result<(SqlitePool, SqlitePool), sqlx::Error> {
    let pool = sqlite_pool(path, page_cache_kib, MAX_CONNECTIONS, PoolRole::Shared).await?;
    migrations::SQLITE.migrator().await?.run(&pool).await?;
    let writer = sqlite_pool(path, page_cache_kib, 1, PoolRole::ServerGate).await?;
    Ok((pool, writer))
}

/// How often a server copies the write-ahead log into the database ([`checkpoint_log`]).
pub const CHECKPOINT_INTERVAL: Duration = Duration::from_millis(250);

/// Copies what the write-ahead log holds into the database every [`CHECKPOINT_INTERVAL`], on
/// one of `pool`'s connections, without waiting for readers or the writer (a passive
/// checkpoint: what readers still use is copied at a later pass), until the pool is closed.
/// For the gate's connection, which checkpoints nothing itself ([`open_serving_pools`]).
pub async fn checkpoint_log(pool: SqlitePool) {
    let mut ticker = tokio::time::interval(CHECKPOINT_INTERVAL);
    ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        ticker.tick().await;
        if pool.is_closed() {
            return;
        }
        if let Err(e) = sqlx::query("PRAGMA wal_checkpoint(PASSIVE)")
            .execute(&pool)
            .await
        {
            tracing::debug!(error = %e, "checkpointing the write-ahead log failed");
        }
    }
}

/// `options` with none of sqlx's pool maintenance: no idle timeout, no lifetime and no
/// minimum, so every connection a pool opens stays open (the first is opened as the pool is)
/// and sqlx runs no background task over them.
///
/// The idle sweep (sqlx 0.8, launchbadge/sqlx#3645) can read the idle count after a race has
/// wrapped it below zero and then loop without ever yielding: one runtime thread spins for
/// good, and a task left in that thread's slot (a job worker's next look at the queue, seen
/// here) never runs again. Without a sweep, a minimum would be kept by a task started beside
/// the pool's first connection, which on a new SQLite file could open a second connection
/// while the first sets up the write-ahead log. A local file's connection does not go stale,
/// and a PostgreSQL pool is bounded by its size either way.
pub fn without_maintenance<DB: sqlx::Database>(
    options: sqlx::pool::PoolOptions<DB>,
) -> sqlx::pool::PoolOptions<DB> {
    options
        .idle_timeout(None)
        .max_lifetime(None)
        .min_connections(0)
}

/// How long a write gate's connection lets SQLite wait for the write lock before
/// [`db::Pool::begin`] asks again.
///
/// SQLite hands its lock out by polling: a connection that finds it taken sleeps 1, 2, 5, 10 …
/// then 100 ms between tries. Against another process's stream of transactions (a
/// command-line import's batches, a few milliseconds apart) such a sleeper wakes inside the
/// next batch again and again: a server's writes waited 130, 230 … 630 ms, in steps of 100,
/// for batches of about 100 ms. At this bound SQLite tries at 0, 1, 3 and 5 ms and gives up,
/// and the pool begins again at once, so a writer waits about one transaction of the other
/// process, up to [`WRITE_WAIT`] in all.
pub const WRITE_POLL: Duration = Duration::from_millis(5);

/// What a pool's connections are for, which decides how they wait for the write lock and
/// whether their commits copy the write-ahead log into the database.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PoolRole {
    /// Readers and writes outside the gate: a write lock is waited for in SQLite, up to
    /// [`WRITE_WAIT`]; a commit that fills the log copies it (SQLite's default).
    Shared,
    /// A command's write gate connection: the lock is asked for by [`WRITE_POLL`]; commits
    /// copy the log as `Shared` ones do.
    CommandGate,
    /// A server's write gate connection: the lock is asked for by [`WRITE_POLL`]; commits copy
    /// nothing ([`checkpoint_log`] does it beside).
    ServerGate,
}

/// `connections` to the file at `path`, for `role`.
async fn sqlite_pool(
    path: &Path,
    page_cache_kib: u64,
    connections: u32,
    role: PoolRole,
) -> Result<SqlitePool, sqlx::Error> {
    // A negative cache_size is in KiB.
    let cache_size = format!("-{}", page_cache_kib.max(1));
    let options = SqliteConnectOptions::from_str("sqlite://")?
        .filename(path)
        .create_if_missing(true)
        .journal_mode(SqliteJournalMode::Wal)
        // WAL + NORMAL is durable across application crashes; only an OS crash can lose the
        // last transactions, never corrupt the file.
        .synchronous(SqliteSynchronous::Normal)
        .foreign_keys(true)
        .busy_timeout(match role {
            PoolRole::Shared => WRITE_WAIT,
            PoolRole::CommandGate | PoolRole::ServerGate => WRITE_POLL,
        })
        .pragma("cache_size", cache_size)
        .pragma("temp_store", "memory")
        // One import is one transaction, so the write-ahead log grows to the size of its new
        // frames. SQLite reuses the log file from the start after a checkpoint but keeps its
        // size; this limit makes it cut the file back once the log is reset.
        .pragma("journal_size_limit", JOURNAL_SIZE_LIMIT_BYTES.to_string());
    let options = if role == PoolRole::ServerGate {
        options.pragma("wal_autocheckpoint", "0")
    } else {
        options
    };
    without_maintenance(SqlitePoolOptions::new())
        .max_connections(connections)
        .acquire_timeout(Duration::from_secs(15))
        // A local file connection does not go stale; pinging it on every acquire would cost a
        // round trip to its worker thread on every request.
        .test_before_acquire(false)
        .connect_with(options)
        .await
}

/// Where a database is, as a command line or the environment names it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Location {
    /// A SQLite file: a plain path, or `sqlite://path`.
    Sqlite(PathBuf),
    /// A PostgreSQL URL: `postgres://` or `postgresql://`.
    Postgres(String),
}

impl Location {
    pub fn of(location: &Path) -> Location {
        let text = location.to_string_lossy();
        if text.starts_with("postgres://") || text.starts_with("postgresql://") {
            Location::Postgres(text.into_owned())
        } else if let Some(path) = text.strip_prefix("sqlite://") {
            Location::Sqlite(PathBuf::from(path))
        } else {
            Location::Sqlite(location.to_path_buf())
        }
    }

    /// A PostgreSQL URL with its password replaced by `***`, for messages and logs.
    pub fn redacted(url: &str) -> String {
        match url::Url::parse(url) {
            Ok(mut parsed) if parsed.password().is_some() => {
                let _ = parsed.set_password(Some("***"));
                parsed.to_string()
            }
            _ => url.to_owned(),
        }
    }

    /// Whether the database is a file that can be looked for on disk.
    pub fn is_file(&self) -> bool {
        matches!(self, Location::Sqlite(_))
    }
}

/// The content generation: changes whenever stored items change.
pub async fn content_generation(conn: &mut Conn) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar("SELECT value FROM content_generation WHERE id = 1")
            .fetch_one(&mut *c)
            .await
    })
}

/// How many announcements the SQLite change feed keeps: servers read it twice a second, so a
/// reader can only miss rows pruned from under it after thousands of changes in half a second
/// (and then drops everything it cached).
pub const CHANGE_FEED_KEPT: i64 = 4096;

/// A `NOTIFY` text: the announcing process's origin, a tab, the payload. The origin lets a
/// listener skip what it announced itself, which it applied when it committed.
pub fn notification_text(origin: &str, payload: &str) -> String {
    format!("{origin}\t{payload}")
}

/// A `NOTIFY` text's origin and payload; a text without an origin (from a hub before origins
/// were sent) is all payload.
pub fn notification_parts(text: &str) -> (Option<&str>, &str) {
    match text.split_once('\t') {
        Some((origin, payload)) => (Some(origin), payload),
        None => (None, text),
    }
}

/// Announces `payload` from `origin` to the other processes on the database, delivered when the
/// transaction `conn` is in commits (at once outside one): PostgreSQL's `NOTIFY` on `channel`
/// (its text framed by [`notification_text`]); on SQLite a row of `change_feed`, which running
/// servers read ([`announcements_after`]).
pub async fn announce(
    conn: &mut WriteConn,
    channel: &str,
    origin: &str,
    payload: &str,
) -> Result<(), sqlx::Error> {
    match db::Connection::handle(conn) {
        db::Handle::Sqlite(c) => {
            let id: i64 = sqlx::query_scalar(
                "INSERT INTO change_feed (origin, payload) VALUES ($1, $2) RETURNING id",
            )
            .bind(origin)
            .bind(payload)
            .fetch_one(&mut *c)
            .await?;
            sqlx::query("DELETE FROM change_feed WHERE id <= $1")
                .bind(id - CHANGE_FEED_KEPT)
                .execute(&mut *c)
                .await?;
            Ok(())
        }
        db::Handle::Pg(c) => {
            sqlx::query("SELECT pg_notify($1, $2)")
                .bind(channel)
                .bind(notification_text(origin, payload))
                .execute(c)
                .await?;
            Ok(())
        }
    }
}

/// An announcement of the change feed: its id, the announcing process and the payload.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Announcement {
    pub id: i64,
    pub origin: String,
    pub payload: String,
}

impl<'r, R: sqlx::Row> sqlx::FromRow<'r, R> for Announcement
where
    &'static str: sqlx::ColumnIndex<R>,
    i64: sqlx::Decode<'r, R::Database> + sqlx::Type<R::Database>,
    String: sqlx::Decode<'r, R::Database> + sqlx::Type<R::Database>,
{
    fn from_row(row: &'r R) -> Result<Self, sqlx::Error> {
        Ok(Self {
            id: row.try_get("id")?,
            origin: row.try_get("origin")?,
            payload: row.try_get("payload")?,
        })
    }
}

/// The change feed's announcements after `after`, oldest first (at most `limit`).
pub async fn announcements_after(
    conn: &mut Conn,
    after: i64,
    limit: i64,
) -> Result<Vec<Announcement>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_as(
            "SELECT id, origin, payload FROM change_feed WHERE id > $1 ORDER BY id LIMIT $2",
        )
        .bind(after)
        .bind(limit)
        .fetch_all(&mut *c)
        .await
    })
}

/// The oldest and newest announcement ids the change feed still holds (0 and 0 when empty).
pub async fn change_feed_span(conn: &mut Conn) -> Result<(i64, i64), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_as("SELECT COALESCE(MIN(id), 0), COALESCE(MAX(id), 0) FROM change_feed")
            .fetch_one(&mut *c)
            .await
    })
}

/// Marks stored items as changed; call inside the transaction that changes them.
pub async fn bump_content_generation(conn: &mut WriteConn) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("UPDATE content_generation SET value = value + 1 WHERE id = 1")
            .execute(&mut *c)
            .await?;
        Ok(())
    })
}

/// A column that holds something this version cannot read, as a decode error naming it.
pub fn corrupt(column: &str, detail: impl std::fmt::Display) -> sqlx::Error {
    sqlx::Error::ColumnDecode {
        index: column.to_owned(),
        source: detail.to_string().into(),
    }
}

/// The `direction` and `step_length` columns of an item row.
pub fn kind_from_row(
    row: &impl Fields,
) -> Result<
    (
        enact_core::dataset::Direction,
        enact_core::dataset::StepLength,
    ),
    sqlx::Error,
> {
    let direction: String = row.try_get("direction")?;
    let step_length: i64 = row.try_get("step_length")?;
    Ok((
        enact_core::dataset::Direction::parse(&direction)
            .ok_or_else(|| corrupt("direction", format!("unknown direction {direction:?}")))?,
        usize::try_from(step_length)
            .ok()
            .and_then(enact_core::dataset::StepLength::new)
            .ok_or_else(|| corrupt("step_length", format!("bad step length {step_length}")))?,
    ))
}

/// Copies the write-ahead log into the database and cuts the log file to nothing (waiting,
/// under the busy timeout, for readers still using it). Returns whether it could; PostgreSQL
/// has no such file and always can.
pub async fn truncate_wal(pool: &Pool) -> Result<bool, sqlx::Error> {
    let Some(pool) = pool.sqlite() else {
        return Ok(true);
    };
    // The row is (busy, pages in the log, pages checkpointed); busy = 1 when it could not.
    let (busy, _, _): (i64, i64, i64) = sqlx::query_as("PRAGMA wal_checkpoint(TRUNCATE)")
        .fetch_one(pool)
        .await?;
    Ok(busy == 0)
}

/// A SQLite database's file and its write-ahead log.
#[derive(Debug, Clone)]
pub struct SqliteFiles {
    pub database: std::path::PathBuf,
    pub wal: std::path::PathBuf,
}

/// Where a SQLite database lives on disk; `None` for PostgreSQL or an in-memory database.
pub async fn sqlite_files(pool: &Pool) -> Result<Option<SqliteFiles>, sqlx::Error> {
    let Some(pool) = pool.sqlite() else {
        return Ok(None);
    };
    // Rows of (seq, name, file); `file` is empty for an in-memory database.
    let rows: Vec<(i64, String, String)> = sqlx::query_as("PRAGMA database_list")
        .fetch_all(pool)
        .await?;
    Ok(rows
        .into_iter()
        .find(|(_, name, file)| name == "main" && !file.is_empty())
        .map(|(_, _, file)| SqliteFiles {
            wal: std::path::PathBuf::from(format!("{file}-wal")),
            database: file.into(),
        }))
}

/// SQLite's `PRAGMA quick_check`: the problems it found (none when the file is sound), or
/// `None` for PostgreSQL.
pub async fn quick_check(pool: &Pool) -> Result<Option<Vec<String>>, sqlx::Error> {
    let Some(pool) = pool.sqlite() else {
        return Ok(None);
    };
    let rows: Vec<String> = sqlx::query_scalar("PRAGMA quick_check")
        .fetch_all(pool)
        .await?;
    Ok(Some(rows.into_iter().filter(|r| r != "ok").collect()))
}

/// One round trip to the database.
pub async fn ping(pool: &Pool) -> Result<(), sqlx::Error> {
    let mut conn = pool.acquire().await?;
    on!(&mut conn, |c| {
        sqlx::query("SELECT 1").execute(&mut *c).await?;
    });
    Ok(())
}

/// Which backend a database is and the highest migration applied to it.
pub async fn schema_version(pool: &Pool) -> Result<(&'static str, i64), sqlx::Error> {
    let backend = match pool {
        Pool::Sqlite(_) => "sqlite",
        Pool::Pg(_) => "postgres",
    };
    let mut conn = pool.acquire().await?;
    let applied: i64 = on!(&mut conn, |c| {
        sqlx::query_scalar("SELECT COALESCE(MAX(version), 0) FROM _sqlx_migrations WHERE success")
            .fetch_one(&mut *c)
            .await?
    });
    Ok((backend, applied))
}

enact_core::text_columns!(jobs::JobState);

/// Writes a consistent copy of the whole SQLite database to `out` (`VACUUM INTO`): one read
/// transaction, so writers carry on and the copy holds exactly what was committed when it
/// began. `out` must not exist.
pub async fn backup_into(conn: &mut sqlx::SqliteConnection, out: &Path) -> Result<(), sqlx::Error> {
    let target = out
        .to_str()
        .ok_or_else(|| sqlx::Error::Protocol(format!("{} is not a UTF-8 path", out.display())))?;
    sqlx::query("VACUUM INTO $1")
        .bind(target)
        .execute(conn)
        .await
        .map(|_| ())
}

/// SQLite's own consistency check of the database `conn` is on: `ok`, or what is wrong.
pub async fn integrity_check(conn: &mut sqlx::SqliteConnection) -> Result<String, sqlx::Error> {
    let lines: Vec<String> = sqlx::query_scalar("PRAGMA integrity_check")
        .fetch_all(conn)
        .await?;
    Ok(lines.join("; "))
}

#[cfg(test)]
mod tests {
    use super::*;

    async fn autocheckpoint(pool: &SqlitePool) -> i64 {
        sqlx::query_scalar("PRAGMA wal_autocheckpoint")
            .fetch_one(pool)
            .await
            .unwrap()
    }

    async fn busy_timeout(pool: &SqlitePool) -> i64 {
        sqlx::query_scalar("PRAGMA busy_timeout")
            .fetch_one(pool)
            .await
            .unwrap()
    }

    /// A gate's connection lets SQLite wait only [`WRITE_POLL`] for the write lock, then
    /// [`db::Pool::begin`] asks again: a lock held twenty times as long is waited out, not
    /// answered as busy. Other connections wait in SQLite for the whole [`WRITE_WAIT`].
    #[tokio::test]
    async fn a_gate_connection_asks_for_the_write_lock_again_until_it_is_free() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("hub.db");
        let (pool, writer) = open_serving_pools(&path, 1024).await.unwrap();
        let (command_pool, command_writer) = open_command_pools(&path, 1024).await.unwrap();
        let poll = i64::try_from(WRITE_POLL.as_millis()).unwrap();
        let wait = i64::try_from(WRITE_WAIT.as_millis()).unwrap();
        assert_eq!(busy_timeout(&writer).await, poll);
        assert_eq!(busy_timeout(&command_writer).await, poll);
        assert_eq!(busy_timeout(&pool).await, wait);
        assert_eq!(busy_timeout(&command_pool).await, wait);
        // A command's writer checkpoints as it commits; it has nothing beside it to do so.
        assert_eq!(autocheckpoint(&command_writer).await, 1000);

        for gate in [writer, command_writer] {
            let holder = pool.begin_with("BEGIN IMMEDIATE").await.unwrap();
            let released = tokio::spawn(async move {
                tokio::time::sleep(WRITE_POLL * 20).await;
                holder.commit().await.unwrap();
            });
            let tx = db::Pool::Sqlite(gate.clone())
                .begin()
                .await
                .expect("the write lock, once the holder committed");
            tx.rollback().await.unwrap();
            released.await.unwrap();
        }
    }

    /// No pool runs sqlx's maintenance ([`without_maintenance`]): every pool a server or a
    /// command opens keeps its connections without a timeout, a lifetime or a minimum.
    #[tokio::test]
    async fn no_pool_runs_sqlx_maintenance() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("hub.db");
        let (pool, writer) = open_serving_pools(&path, 1024).await.unwrap();
        let (command_pool, command_writer) = open_command_pools(&path, 1024).await.unwrap();
        for pool in [pool, writer, command_pool, command_writer] {
            assert_maintains_nothing(pool.options());
            // The first connection, opened with the pool, stays.
            assert!(pool.size() >= 1);
        }
        assert_maintains_nothing(&db::postgres_pool_options(8));
    }

    fn assert_maintains_nothing<DB: sqlx::Database>(options: &sqlx::pool::PoolOptions<DB>) {
        assert_eq!(options.get_idle_timeout(), None);
        assert_eq!(options.get_max_lifetime(), None);
        assert_eq!(options.get_min_connections(), 0);
    }

    /// The gate's connection leaves the write-ahead log to [`checkpoint_log`], which copies it
    /// into the database: without it, the database file would stay as the migrations left it.
    #[tokio::test]
    async fn the_writer_checkpoints_nothing_and_the_checkpointer_copies_the_log() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("hub.db");
        let (pool, writer) = open_serving_pools(&path, 1024).await.unwrap();
        assert_eq!(autocheckpoint(&writer).await, 0);
        assert_eq!(autocheckpoint(&pool).await, 1000);
        sqlx::query("PRAGMA wal_checkpoint(TRUNCATE)")
            .execute(&pool)
            .await
            .unwrap();
        let before = std::fs::metadata(&path).unwrap().len();

        // About 2,500 pages: past the 1,000 at which a connection of the pool would checkpoint.
        let mut tx = writer.begin().await.unwrap();
        sqlx::query("CREATE TABLE filler (bytes BLOB)")
            .execute(&mut *tx)
            .await
            .unwrap();
        for _ in 0..2500 {
            sqlx::query("INSERT INTO filler VALUES (randomblob(3000))")
                .execute(&mut *tx)
                .await
                .unwrap();
        }
        tx.commit().await.unwrap();
        assert_eq!(
            std::fs::metadata(&path).unwrap().len(),
            before,
            "the writer's commit copied the log into the database"
        );

        let checkpointer = tokio::spawn(checkpoint_log(pool.clone()));
        let deadline = tokio::time::Instant::now() + Duration::from_secs(30);
        while std::fs::metadata(&path).unwrap().len() < before + 2500 * 3000 {
            assert!(
                tokio::time::Instant::now() < deadline,
                "the checkpointer did not copy the log within 30 s"
            );
            tokio::time::sleep(CHECKPOINT_INTERVAL).await;
        }
        pool.close().await;
        writer.close().await;
        checkpointer.await.unwrap();
    }
}
