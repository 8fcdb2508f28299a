//! The service every use case shares, and nothing of any one use case: [`Hub`], which holds
//! the database and what is kept in front of it, and the machinery around it.
//!
//! - [`Hub`]: the database (a pool for reading, a writer for the write gate), the caches of
//!   stored items and frames ([`cache`]), and what each use case keeps on it by type
//!   ([`kept`]: a leaderboard cache, a signing key, …), without naming any use case.
//! - [`write`]: the unit of work every write goes through: a lane of the write gate, the
//!   changes it announces, and what its commit does in this process.
//! - [`changes`] and [`watch`]: the changes processes on one database announce to each other,
//!   and following them (and the content generation) so that every cache stays honest.
//! - [`jobs`]: long work that survives restarts, claimed by one instance at a time; the kinds'
//!   handlers are registered where the server is assembled.
//! - [`heavy`]: the one bounded pool where CPU-heavy work runs; [`metrics`]: the instance's
//!   counters and their exposition; [`frames`]: where frame bytes live (the database or an
//!   object store); [`audit`]: the audit log written inside the transaction it records.
//! - [`AppError`] and [`refusal`]: what went wrong, with a typed reason for every refusal a
//!   person or client can act on; the sentence is made at the edge.
//!
//! It may use [`enact_core`] and [`enact_store`]; the use cases (`enact-app`) and the
//! adapters above them use it, and Cargo keeps it from naming them.

pub mod audit;
pub mod cache;
pub mod changes;
mod error;
pub mod frames;
pub mod heavy;
pub mod jobs;
pub mod kept;
pub mod metrics;
pub mod refusal;
pub mod watch;
mod write;

use std::path::Path;
use std::sync::Arc;

use sqlx::SqlitePool;

pub use error::AppError;
pub use kept::Kept;
pub use write::{Lane, Write};

/// The benchmark and the store, under the names the modules call them by (`crate::core::…`,
/// `crate::store::…`).
use enact_core as core;
use enact_store as store;
use store::Pool;

/// Where the database `location` names is (a SQLite file or a PostgreSQL server).
pub fn store_location(location: &Path) -> store::Location {
    store::Location::of(location)
}

/// The database `location` names, for messages and logs: a path, or a URL with its password
/// hidden.
pub fn describe_location(location: &Path) -> String {
    match store::Location::of(location) {
        store::Location::Postgres(url) => store::Location::redacted(&url),
        store::Location::Sqlite(path) => path.display().to_string(),
    }
}

/// What every use case works with: the store and the caches in front of it. Cheap to clone.
#[derive(Clone)]
pub struct Hub {
    pool: Pool,
    /// Where write transactions begin ([`Hub::begin_in`]): the pool itself, or on SQLite a
    /// connection of its own that polls for the write lock ([`store::open_serving_pools`],
    /// [`store::open_command_pools`]).
    writer: Pool,
    /// Whether [`Hub::watch_content`] also checkpoints the write-ahead log, which the writer's
    /// own connection then leaves to it.
    checkpoints_beside: bool,
    limits: cache::CacheLimits,
    items: Arc<cache::ItemCache>,
    frames: Arc<cache::FrameCache>,
    /// What the use cases keep on the hub, by type.
    kept: Arc<kept::KeptValues>,
    /// Where frame bytes are written, and read when the database does not hold them.
    frame_store: frames::FrameStore,
    /// Frames in an object store that signs URLs are answered with a redirect to a URL valid
    /// this long, when set.
    frame_redirect: Option<std::time::Duration>,
    /// Changes other instances announced, for caches outside the app layer.
    changes: tokio::sync::broadcast::Sender<changes::Change>,
    metrics: Arc<metrics::Metrics>,
    heavy: heavy::HeavyPool,
    /// The order this process's writers take the database's write lock in.
    gate: store::gate::WriteGate,
    /// This process's name in the change feed, so that a server skips its own announcements.
    origin: Arc<str>,
}

impl From<SqlitePool> for Hub {
    fn from(pool: SqlitePool) -> Hub {
        Hub::new(Pool::Sqlite(pool))
    }
}

impl From<Pool> for Hub {
    fn from(pool: Pool) -> Hub {
        Hub::new(pool)
    }
}

impl Hub {
    pub fn new(pool: Pool) -> Hub {
        let limits = cache::CacheLimits::default();
        let metrics = Arc::new(metrics::Metrics::default());
        let heavy = heavy::HeavyPool::new(heavy::HeavyLimits::default(), metrics.heavy());
        let gate = store::gate::WriteGate::observed({
            let metrics = metrics.clone();
            Arc::new(move |lane, held| metrics.write_held(lane, held))
        });
        Hub {
            writer: pool.clone(),
            checkpoints_beside: false,
            pool,
            items: Arc::new(cache::ItemCache::new(limits.item_bytes)),
            frames: Arc::new(cache::FrameCache::new(limits.frame_bytes)),
            limits,
            kept: Arc::default(),
            frame_store: frames::FrameStore::Database,
            frame_redirect: None,
            changes: tokio::sync::broadcast::channel(1024).0,
            metrics,
            heavy,
            gate,
            origin: changes::new_origin().into(),
        }
    }

    /// The hub with empty caches bounded by `limits`, its own and those the use cases keep on
    /// it (call before serving; what was set with [`Hub::with_kept`] stays).
    pub fn with_cache_limits(self, limits: &cache::CacheLimits) -> Hub {
        Hub {
            items: Arc::new(cache::ItemCache::new(limits.item_bytes)),
            frames: Arc::new(cache::FrameCache::new(limits.frame_bytes)),
            kept: Arc::new(self.kept.settings_only()),
            limits: *limits,
            ..self
        }
    }

    /// The limits the caches were built to, for the caches the use cases keep.
    pub fn cache_limits(&self) -> &cache::CacheLimits {
        &self.limits
    }

    /// The hub with `value` kept in place of what [`Kept::make`] would make (call before
    /// serving: a setting, such as the key statements are signed with).
    pub fn with_kept<T: Kept>(mut self, value: T) -> Hub {
        self.kept = Arc::new(self.kept.with(value));
        self
    }

    /// What the use case owning `T` keeps on this hub, made on first use.
    pub fn kept<T: Kept>(&self) -> Arc<T> {
        if let Some(found) = self.kept.get::<T>() {
            return found;
        }
        // Made outside the lock: making one may ask for another.
        self.kept.insert_made(T::make(self))
    }

    /// Opens (creating if missing) the database `location` names, migrated to this version:
    /// a SQLite file (a path, or `sqlite://path`), or a PostgreSQL database
    /// (`postgres://user:password@host/db`, which must exist).
    pub async fn open(location: &Path) -> anyhow::Result<Hub> {
        Hub::open_with(location, store::COMMAND_PAGE_CACHE_KIB).await
    }

    /// Opens the database for a server: every cache bounded by `limits`, SQLite's page cache
    /// (shared out over the connections) included. On SQLite the write transactions get a
    /// connection of their own beside the pool.
    pub async fn open_serving(location: &Path, limits: &cache::CacheLimits) -> anyhow::Result<Hub> {
        let cache_kib = limits.db_page_cache_bytes / 1024;
        let hub = match store::Location::of(location) {
            store::Location::Sqlite(path) => {
                let per_connection = cache_kib / u64::from(store::MAX_CONNECTIONS + 1);
                let (pool, writer) = store::open_serving_pools(&path, per_connection)
                    .await
                    .map_err(|e| anyhow::anyhow!("cannot open database {}: {e}", path.display()))?;
                Hub {
                    writer: Pool::Sqlite(writer),
                    checkpoints_beside: true,
                    ..Hub::new(Pool::Sqlite(pool))
                }
            }
            store::Location::Postgres(_) => {
                Hub::open_with(location, cache_kib / u64::from(store::MAX_CONNECTIONS)).await?
            }
        };
        Ok(hub.with_cache_limits(limits))
    }

    async fn open_with(location: &Path, page_cache_kib: u64) -> anyhow::Result<Hub> {
        let (pool, writer) = match store::Location::of(location) {
            store::Location::Postgres(url) => {
                let pool = store::db::open_postgres(&url, store::MAX_CONNECTIONS)
                    .await
                    .map_err(|e| {
                        anyhow::anyhow!(
                            "cannot open database {}: {e}",
                            store::Location::redacted(&url)
                        )
                    })?;
                (Pool::Pg(pool.clone()), Pool::Pg(pool))
            }
            store::Location::Sqlite(path) => {
                let (pool, writer) = store::open_command_pools(&path, page_cache_kib)
                    .await
                    .map_err(|e| anyhow::anyhow!("cannot open database {}: {e}", path.display()))?;
                (Pool::Sqlite(pool), Pool::Sqlite(writer))
            }
        };
        Ok(Hub {
            writer,
            ..Hub::new(pool)
        })
    }

    /// The hub writing new frames to `store` and reading there the frames the database does
    /// not hold; with `redirect`, frame requests for such frames are answered with a presigned
    /// URL valid that long (when the store can sign one).
    pub fn with_frame_store(
        mut self,
        store: frames::FrameStore,
        redirect: Option<std::time::Duration>,
    ) -> Hub {
        self.frame_store = store;
        self.frame_redirect = redirect;
        self
    }

    /// Where new frames are written.
    pub fn frame_store(&self) -> &frames::FrameStore {
        &self.frame_store
    }

    /// How long a presigned frame URL is valid, when frame requests are redirected.
    pub fn frame_redirect(&self) -> Option<std::time::Duration> {
        self.frame_redirect
    }

    /// The hub whose heavy work runs on a pool bounded by `limits` (call before serving).
    pub fn with_heavy_limits(mut self, limits: heavy::HeavyLimits) -> Hub {
        self.heavy = heavy::HeavyPool::new(limits, self.metrics.heavy());
        self
    }

    /// Where CPU-heavy work runs.
    pub fn heavy(&self) -> &heavy::HeavyPool {
        &self.heavy
    }

    /// The database's reading pool, for what the store reads outside a transaction of the
    /// hub's own (a health check, the schema's version, SQLite's files).
    pub fn pool(&self) -> &Pool {
        &self.pool
    }

    /// Folds the write-ahead log into the database and empties the log file, after work that
    /// wrote much in one transaction (an import's log is as large as its new frames, and
    /// pooled connections closing together may leave it on disk). Best effort: `false` when
    /// another process kept part of the log in use.
    pub async fn truncate_log(&self) -> bool {
        match store::truncate_wal(&self.pool).await {
            Ok(done) => done,
            Err(e) => {
                tracing::debug!(error = %e, "emptying the write-ahead log failed");
                false
            }
        }
    }

    /// Waits for the connections in use and closes the database.
    pub async fn close(&self) {
        self.writer.close().await;
        self.pool.close().await;
    }

    /// The item cache (hot read paths look here before the store).
    pub fn items(&self) -> &cache::ItemCache {
        &self.items
    }

    /// The frame cache.
    pub fn frames(&self) -> &cache::FrameCache {
        &self.frames
    }

    /// Whether the database answers.
    pub async fn healthy(&self) -> bool {
        match store::ping(&self.pool).await {
            Ok(()) => true,
            Err(e) => {
                tracing::error!(error = %e, "health check: database unavailable");
                false
            }
        }
    }

    /// Every cache of this hub: its own and those the use cases keep on it.
    fn caches(&self) -> watch::Caches {
        watch::Caches {
            items: self.items.clone(),
            frames: self.frames.clone(),
            kept: self.kept.clone(),
        }
    }

    /// Clears the caches whenever stored items change, also through another process's
    /// import, and whatever other processes announce: other instances on PostgreSQL, the
    /// command line on either database; and for a server on SQLite, checkpoints the
    /// write-ahead log. Runs until the database is closed.
    pub async fn watch_content(self) {
        let caches = self.caches();
        let checkpoints = async {
            if let (true, Some(pool)) = (self.checkpoints_beside, self.pool.sqlite()) {
                store::checkpoint_log(pool.clone()).await;
            }
        };
        tokio::join!(
            checkpoints,
            watch::watch_generation(self.pool.clone(), caches.clone()),
            watch::listen(
                self.pool.clone(),
                caches.clone(),
                self.changes.clone(),
                self.origin.clone()
            ),
            watch::follow_feed(
                self.pool.clone(),
                caches,
                self.changes.clone(),
                self.origin.clone()
            ),
        );
    }

    /// Changes other instances announce (their sessions ending, or everything after missed
    /// announcements), for caches kept outside the app layer.
    pub fn subscribe(&self) -> tokio::sync::broadcast::Receiver<changes::Change> {
        self.changes.subscribe()
    }

    /// Drops from this process's caches what `change` made stale: its own committed change
    /// ([`Write::commit`]), or one a test stands in for (the adapters' caches, such as the
    /// web's sessions, see to their own changes).
    pub fn forget_stale(&self, change: &changes::Change) {
        self.caches().forget(change);
    }

    /// Announces `change` to the other processes on the database (server instances, and
    /// servers beside a command-line process), when `conn`'s transaction commits.
    async fn publish(
        &self,
        conn: &mut store::Tx,
        change: &changes::Change,
    ) -> Result<(), AppError> {
        Ok(store::announce(conn, changes::CHANNEL, &self.origin, &change.payload()).await?)
    }

    /// A connection from the reading pool; the wait is counted in the metrics.
    pub async fn conn(&self) -> Result<store::PooledConn, AppError> {
        let asked = std::time::Instant::now();
        let conn = self.pool.acquire().await?;
        self.metrics.connection_waited(asked.elapsed());
        Ok(conn)
    }

    /// A bare write transaction in `lane`, announcing nothing: for an import's batches, which
    /// every process sees through the content generation instead. Everything else writes
    /// through [`Hub::write`]. A wait longer than the database's busy timeout fails as busy
    /// ([`store::db::is_busy`]).
    pub async fn begin_in(&self, lane: store::gate::Lane) -> Result<store::Tx, sqlx::Error> {
        let asked = std::time::Instant::now();
        // As long as the database's own busy timeout; then the same 503.
        let turn = tokio::time::timeout(store::WRITE_WAIT, self.gate.enter(lane))
            .await
            .map_err(|_| sqlx::Error::PoolTimedOut)?;
        let tx = self.writer.begin().await?.holding(turn);
        self.metrics.write_waited(lane, asked.elapsed());
        Ok(tx)
    }

    /// This instance's metrics ([`metrics::exposition`] writes them).
    pub fn metrics(&self) -> &metrics::Metrics {
        &self.metrics
    }
}
