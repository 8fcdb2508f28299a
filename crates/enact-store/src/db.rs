//! The two databases behind one type: SQLite (one file, the default) and PostgreSQL (shared by
//! many server instances). A pool, a pooled connection and a transaction are each an enum of
//! the two; store functions take [`Conn`] (either, pooled or in a transaction) and write each
//! query once, with `$1`-style placeholders that both understand, through [`on!`].

use std::time::Duration;

use sqlx::pool::PoolConnection;
use sqlx::postgres::{PgConnectOptions, PgPoolOptions, PgRow};
use sqlx::sqlite::SqliteRow;
use sqlx::{PgConnection, PgPool, Postgres, Sqlite, SqliteConnection, SqlitePool, Transaction};

/// A connection of either database, borrowed for one store call.
pub enum Handle<'c> {
    Sqlite(&'c mut SqliteConnection),
    Pg(&'c mut PgConnection),
}

/// Something a store function can run queries on: a pooled connection or a transaction.
pub trait Connection {
    fn handle(&mut self) -> Handle<'_>;
}

/// What store functions take.
pub type Conn = dyn Connection + Send;

impl Connection for SqliteConnection {
    fn handle(&mut self) -> Handle<'_> {
        Handle::Sqlite(self)
    }
}

impl Connection for PgConnection {
    fn handle(&mut self) -> Handle<'_> {
        Handle::Pg(self)
    }
}

impl Connection for PoolConnection<Sqlite> {
    fn handle(&mut self) -> Handle<'_> {
        Handle::Sqlite(self)
    }
}

impl Connection for PoolConnection<Postgres> {
    fn handle(&mut self) -> Handle<'_> {
        Handle::Pg(self)
    }
}

/// `on_db!(conn, |c| body)` (`on!` inside the store) runs `body` with `c` bound to the
/// connection of whichever database `conn` is on: the body is compiled once per database, so
/// it is written once. (It reads as a closure so rustfmt formats it; it is not one: `?` and
/// `return` act on the caller.)
#[macro_export]
macro_rules! on_db {
    ($conn:expr, |$c:ident| $body:expr) => {
        match $crate::db::Connection::handle($conn) {
            $crate::db::Handle::Sqlite($c) => $body,
            $crate::db::Handle::Pg($c) => $body,
        }
    };
}
pub(crate) use crate::on_db as on;

/// A pool of connections to one database.
#[derive(Clone, Debug)]
pub enum Pool {
    Sqlite(SqlitePool),
    Pg(PgPool),
}

impl From<SqlitePool> for Pool {
    fn from(pool: SqlitePool) -> Pool {
        Pool::Sqlite(pool)
    }
}

impl From<PgPool> for Pool {
    fn from(pool: PgPool) -> Pool {
        Pool::Pg(pool)
    }
}

/// A connection taken from a [`Pool`].
pub enum PooledConn {
    Sqlite(PoolConnection<Sqlite>),
    Pg(PoolConnection<Postgres>),
}

impl Connection for PooledConn {
    fn handle(&mut self) -> Handle<'_> {
        match self {
            PooledConn::Sqlite(c) => Handle::Sqlite(c),
            PooledConn::Pg(c) => Handle::Pg(c),
        }
    }
}

/// A connection the store's write functions take ([`WriteConn`]): only a transaction holding
/// this process's turn in the write gate ([`Tx`]), so a write outside the gate does not
/// compile. Reads take any [`Connection`], a write transaction included.
pub trait Writes: Connection {}

/// What store functions that write take.
pub type WriteConn = dyn Writes + Send;

/// A transaction begun outside the write gate ([`Pool::begin`], [`Pool::begin_snapshot`]):
/// it reads; to write, it takes this process's turn ([`PlainTx::holding`]). Rolled back when
/// dropped without [`PlainTx::commit`].
pub struct PlainTx(EitherTx);

/// A write transaction holding this process's turn in the write gate, given up once the
/// transaction has ended; rolled back when dropped without [`Tx::commit`].
pub struct Tx {
    // Declared first, so dropped first: the rollback is queued before the turn passes on.
    tx: EitherTx,
    turn: super::gate::WriteTurn,
}

enum EitherTx {
    Sqlite(Transaction<'static, Sqlite>),
    Pg(Transaction<'static, Postgres>),
}

impl EitherTx {
    fn handle(&mut self) -> Handle<'_> {
        match self {
            EitherTx::Sqlite(t) => Handle::Sqlite(t),
            EitherTx::Pg(t) => Handle::Pg(t),
        }
    }

    async fn commit(self) -> Result<(), sqlx::Error> {
        match self {
            EitherTx::Sqlite(t) => t.commit().await,
            EitherTx::Pg(t) => t.commit().await,
        }
    }

    async fn rollback(self) -> Result<(), sqlx::Error> {
        match self {
            EitherTx::Sqlite(t) => t.rollback().await,
            EitherTx::Pg(t) => t.rollback().await,
        }
    }
}

impl Connection for PlainTx {
    fn handle(&mut self) -> Handle<'_> {
        self.0.handle()
    }
}

impl Connection for Tx {
    fn handle(&mut self) -> Handle<'_> {
        self.tx.handle()
    }
}

impl Writes for Tx {}

impl PlainTx {
    /// The transaction as a write transaction, keeping `turn` until it commits or rolls back.
    pub fn holding(self, turn: super::gate::WriteTurn) -> Tx {
        Tx { tx: self.0, turn }
    }

    pub async fn commit(self) -> Result<(), sqlx::Error> {
        self.0.commit().await
    }

    pub async fn rollback(self) -> Result<(), sqlx::Error> {
        self.0.rollback().await
    }
}

impl Tx {
    pub async fn commit(self) -> Result<(), sqlx::Error> {
        let Tx { tx, turn } = self;
        let done = tx.commit().await;
        drop(turn);
        done
    }

    pub async fn rollback(self) -> Result<(), sqlx::Error> {
        let Tx { tx, turn } = self;
        let done = tx.rollback().await;
        drop(turn);
        done
    }
}

/// The key of the advisory lock every PostgreSQL write transaction takes (see [`Pool::begin`]).
const WRITE_LOCK: i64 = 0x454e_4143_5448_5542; // "ENACTHUB"

impl Pool {
    pub async fn acquire(&self) -> Result<PooledConn, sqlx::Error> {
        Ok(match self {
            Pool::Sqlite(p) => PooledConn::Sqlite(p.acquire().await?),
            Pool::Pg(p) => PooledConn::Pg(p.acquire().await?),
        })
    }

    /// A write transaction, serialised with every other one on the database. SQLite:
    /// `BEGIN IMMEDIATE` takes the write lock at once (a deferred transaction that read first
    /// and wrote after another writer's commit would fail with `database is locked` instead
    /// of queueing). PostgreSQL: a transaction-scoped advisory lock taken first (waiting at most
    /// as long as SQLite's busy timeout, then failing as [`is_busy`]), so the checks
    /// the use cases make before they write (quotas, idempotency keys, run-once rules,
    /// assignment) hold across every server instance exactly as they do in one SQLite process.
    pub async fn begin(&self) -> Result<PlainTx, sqlx::Error> {
        match self {
            Pool::Sqlite(p) => {
                let asked = std::time::Instant::now();
                loop {
                    match p.begin_with("BEGIN IMMEDIATE").await {
                        Ok(tx) => return Ok(PlainTx(EitherTx::Sqlite(tx))),
                        // A gate's connection gives up after `WRITE_POLL` and asks again;
                        // any other waited the whole `WRITE_WAIT` in SQLite already.
                        Err(e) if is_busy(&e) && asked.elapsed() < crate::WRITE_WAIT => {}
                        Err(e) => return Err(e),
                    }
                }
            }
            Pool::Pg(p) => {
                let mut tx = p.begin().await?;
                // The timeout first (left to right), for this transaction only.
                sqlx::query(
                    "SELECT set_config('lock_timeout', $2, true), pg_advisory_xact_lock($1)",
                )
                .bind(WRITE_LOCK)
                .bind(PG_LOCK_TIMEOUT)
                .execute(&mut *tx)
                .await?;
                Ok(PlainTx(EitherTx::Pg(tx)))
            }
        }
    }

    /// A transaction that reads one consistent snapshot of the database and takes no write
    /// lock, so writers carry on while it reads (a backup of a running server). SQLite: a
    /// deferred transaction, whose snapshot of the write-ahead log is fixed at its first read;
    /// PostgreSQL: `REPEATABLE READ READ ONLY`.
    pub async fn begin_snapshot(&self) -> Result<PlainTx, sqlx::Error> {
        Ok(match self {
            Pool::Sqlite(p) => PlainTx(EitherTx::Sqlite(p.begin_with("BEGIN DEFERRED").await?)),
            Pool::Pg(p) => PlainTx(EitherTx::Pg(
                p.begin_with("BEGIN ISOLATION LEVEL REPEATABLE READ READ ONLY")
                    .await?,
            )),
        })
    }

    pub async fn close(&self) {
        match self {
            Pool::Sqlite(p) => p.close().await,
            Pool::Pg(p) => p.close().await,
        }
    }

    pub fn is_closed(&self) -> bool {
        match self {
            Pool::Sqlite(p) => p.is_closed(),
            Pool::Pg(p) => p.is_closed(),
        }
    }

    /// The SQLite pool, for what only SQLite has (its file, backups with `VACUUM INTO`).
    pub fn sqlite(&self) -> Option<&SqlitePool> {
        match self {
            Pool::Sqlite(p) => Some(p),
            Pool::Pg(_) => None,
        }
    }
}

/// How a PostgreSQL pool of `max_connections` is built ([`open_postgres`]).
pub(crate) fn postgres_pool_options(max_connections: u32) -> PgPoolOptions {
    super::without_maintenance(PgPoolOptions::new())
        .max_connections(max_connections)
        .acquire_timeout(Duration::from_secs(15))
}

/// Connects to the PostgreSQL database at `url` and applies its migrations.
pub async fn open_postgres(url: &str, max_connections: u32) -> Result<PgPool, sqlx::Error> {
    let options: PgConnectOptions = url.parse()?;
    let pool = postgres_pool_options(max_connections)
        .connect_with(options)
        .await?;
    super::migrations::POSTGRES
        .migrator()
        .await?
        .run(&pool)
        .await?;
    Ok(pool)
}

/// A value a row column decodes to in both databases.
pub trait Field: Sized {
    fn from_sqlite(row: &SqliteRow, column: &str) -> Result<Self, sqlx::Error>;
    fn from_pg(row: &PgRow, column: &str) -> Result<Self, sqlx::Error>;
}

impl<T> Field for T
where
    T: for<'r> sqlx::Decode<'r, Sqlite>
        + sqlx::Type<Sqlite>
        + for<'r> sqlx::Decode<'r, Postgres>
        + sqlx::Type<Postgres>,
{
    fn from_sqlite(row: &SqliteRow, column: &str) -> Result<Self, sqlx::Error> {
        sqlx::Row::try_get(row, column)
    }

    fn from_pg(row: &PgRow, column: &str) -> Result<Self, sqlx::Error> {
        sqlx::Row::try_get(row, column)
    }
}

/// A row of either database, read by column name: what row-mapping helpers take.
pub trait Fields {
    fn try_get<T: Field>(&self, column: &str) -> Result<T, sqlx::Error>;
}

impl Fields for SqliteRow {
    fn try_get<T: Field>(&self, column: &str) -> Result<T, sqlx::Error> {
        T::from_sqlite(self, column)
    }
}

impl Fields for PgRow {
    fn try_get<T: Field>(&self, column: &str) -> Result<T, sqlx::Error> {
        T::from_pg(self, column)
    }
}

/// SQL that differs between the two databases, chosen by the connection a query runs on.
pub trait Dialect {
    /// The current UTC time as `2026-11-25T10:00:00Z` (how every timestamp column is written).
    fn utc_now(&self) -> &'static str;
    /// Midnight UTC today, in the same format.
    fn utc_today(&self) -> &'static str;
    /// A subquery of the integers in the JSON array bound as `$1`.
    fn json_ids(&self) -> &'static str;
}

impl Dialect for SqliteConnection {
    fn utc_now(&self) -> &'static str {
        "strftime('%Y-%m-%dT%H:%M:%SZ', 'now')"
    }

    fn utc_today(&self) -> &'static str {
        "strftime('%Y-%m-%dT00:00:00Z', 'now')"
    }

    fn json_ids(&self) -> &'static str {
        "SELECT value FROM json_each($1)"
    }
}

impl Dialect for PgConnection {
    fn utc_now(&self) -> &'static str {
        "to_char(now() AT TIME ZONE 'UTC', 'YYYY-MM-DD\"T\"HH24:MI:SS\"Z\"')"
    }

    fn utc_today(&self) -> &'static str {
        "to_char(now() AT TIME ZONE 'UTC', 'YYYY-MM-DD\"T00:00:00Z\"')"
    }

    fn json_ids(&self) -> &'static str {
        "SELECT value::bigint FROM json_array_elements_text($1::json)"
    }
}

/// The kind of constraint a refused write broke.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViolationKind {
    Unique,
    ForeignKey,
    NotNull,
    Check,
}

/// A write the database refused because it would break a constraint: the kind, and the
/// constraint's name where the database reports one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Violation {
    pub kind: ViolationKind,
    /// PostgreSQL names the constraint (`submissions_idempotency_key`, `studies_name_key`);
    /// SQLite never does (its extended result code says the kind, its message lists columns).
    pub constraint: Option<String>,
}

/// The constraint `e` broke, if it is a constraint violation. Read from the error's code
/// through sqlx's `DatabaseError::kind()` (SQLSTATE 23505/23503/23502/23514 on PostgreSQL,
/// the extended result codes `SQLITE_CONSTRAINT_UNIQUE`/`_PRIMARYKEY`/`_FOREIGNKEY`/… on
/// SQLite) and `constraint()`, never from the message text, which is neither stable across
/// versions nor the same on the two databases.
pub fn violation(e: &sqlx::Error) -> Option<Violation> {
    let sqlx::Error::Database(db) = e else {
        return None;
    };
    let kind = match db.kind() {
        sqlx::error::ErrorKind::UniqueViolation => ViolationKind::Unique,
        sqlx::error::ErrorKind::ForeignKeyViolation => ViolationKind::ForeignKey,
        sqlx::error::ErrorKind::NotNullViolation => ViolationKind::NotNull,
        sqlx::error::ErrorKind::CheckViolation => ViolationKind::Check,
        _ => return None,
    };
    Some(Violation {
        kind,
        constraint: db.constraint().map(str::to_owned),
    })
}

/// Whether `e` says the database is busy: a write that could not get the lock in time
/// (SQLite's `SQLITE_BUSY` and `SQLITE_LOCKED` codes and their extended forms after the busy
/// timeout; PostgreSQL's `lock_not_available`, 55P03, after the `lock_timeout`
/// [`Pool::begin`] sets), or no pooled connection free in time. Read from the error's code.
pub fn is_busy(e: &sqlx::Error) -> bool {
    match e {
        sqlx::Error::PoolTimedOut => true,
        sqlx::Error::Database(db) => {
            let code = db.code();
            let code = code.as_deref().unwrap_or("");
            if code == "55P03" {
                return true;
            }
            // SQLite reports its extended result code; the primary code is its low byte.
            code.parse::<i64>().is_ok_and(|n| matches!(n & 0xff, 5 | 6))
        }
        _ => false,
    }
}

/// How long a PostgreSQL write waits for the write lock before giving up as busy: as long as
/// SQLite's busy timeout (`store::open`).
const PG_LOCK_TIMEOUT: &str = "10s";

/// A unique key a use case tells apart from others: the table it is on and the name
/// PostgreSQL gives it (as the migrations declare it, or PostgreSQL's `<table>_<column>_key` /
/// `<table>_pkey` default).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UniqueKey {
    pub table: &'static str,
    pub constraint: &'static str,
}

impl UniqueKey {
    pub const SUBMISSION_IDEMPOTENCY_KEY: UniqueKey = UniqueKey {
        table: "submissions",
        constraint: "submissions_idempotency_key",
    };
    pub const ANNOTATOR_NAME: UniqueKey = UniqueKey {
        table: "annotators",
        constraint: "annotators_name_key",
    };
    pub const STUDY_NAME: UniqueKey = UniqueKey {
        table: "studies",
        constraint: "studies_name_key",
    };
    pub const AGREEMENT_ROUND: UniqueKey = UniqueKey {
        table: "agreement_rounds",
        constraint: "agreement_rounds_pkey",
    };
    pub const EPISODE_NAME: UniqueKey = UniqueKey {
        table: "episodes",
        constraint: "episodes_name_key",
    };
    pub const REPORTED_MODEL_SOURCE: UniqueKey = UniqueKey {
        table: "reported_results",
        constraint: "reported_results_model_source",
    };
    /// Every key a use case recognises; `store::tests` checks each against both schemas.
    pub const ALL: [UniqueKey; 6] = [
        UniqueKey::SUBMISSION_IDEMPOTENCY_KEY,
        UniqueKey::ANNOTATOR_NAME,
        UniqueKey::STUDY_NAME,
        UniqueKey::AGREEMENT_ROUND,
        UniqueKey::EPISODE_NAME,
        UniqueKey::REPORTED_MODEL_SOURCE,
    ];

    /// Whether `e`, returned by an INSERT into this key's table, is a duplicate of this key.
    ///
    /// PostgreSQL names the constraint, so the name decides. SQLite reports a UNIQUE or
    /// PRIMARY KEY violation by its extended result code only (no name; the message lists the
    /// columns, and matching text is what this replaces), so there the kind decides, which is
    /// exact because each of these tables has no other unique key an INSERT can collide with:
    /// the rest are generated ids or hashes of 32 random bytes (`annotators.invite_hash`).
    /// `store::tests::unique_keys_are_the_only_ones_on_their_tables` reads both schemas and
    /// fails when a migration adds another unique key to one of these tables.
    pub fn is_violated_by(self, e: &sqlx::Error) -> bool {
        match violation(e) {
            Some(Violation {
                kind: ViolationKind::Unique,
                constraint: Some(name),
            }) => name == self.constraint,
            Some(Violation {
                kind: ViolationKind::Unique,
                constraint: None,
            }) => true,
            _ => false,
        }
    }
}
