//! The use cases: one function each, called alike by the web handlers and the command line.
//! They own the transactions and the decisions; [`enact_store`] only maps rows, and
//! [`enact_core`] holds the benchmark's logic. Neither may name this crate; the adapters (the
//! hub's `web` and `cli`) call it.
//!
//! - [`Hub`]: the database and the in-memory caches every use case shares ([`cache`],
//!   [`standings`]; [`watch`] keeps them current), and the quotas submissions count against.
//! - [`datasets`] and [`items`]: reading what is stored, frames and release archives included;
//!   [`import`]: an ENACT release read from disk, all or nothing.
//! - [`scoring`]: a prediction file scored against a stored dataset or a release folder.
//! - [`submissions`]: submit, read and list a leaderboard submission; [`leaderboard`] builds
//!   the rows, the Human row included, and keeps each dataset's board in memory;
//!   [`challenge`]: a hidden dataset split into a public and a private part, its deadline,
//!   reveal and selections, and what the board shows of it.
//! - [`tokens`]: API tokens and the accounts behind them; [`annotators`]: annotator accounts,
//!   invites and login sessions.
//! - [`annotation`]: assignments, the queue, drafts, answers, skips and flags; [`gold`]: gold
//!   items mixed into the queues, and annotators excluded from the Human row; [`attention`]:
//!   attention checks mixed in like gold items and judged against their instruction;
//!   [`controls`]: pausing an annotator's queue and handing their unfinished items to others;
//!   [`quality`]: each annotator's figures on a dataset.
//! - [`agreement`]: the cross-annotation protocol, agreement statistics and the report.
//! - [`explore`]: the explorer's grid of every item × every leaderboard row's verdict, kept
//!   with the board, and the views cut from it.
//! - [`error_analysis`]: the paper's error taxonomy of a submission, the Human row, a file, or
//!   a whole leaderboard.
//! - [`studies`]: ablation studies (a baseline and variant datasets) and their reports.
//! - [`rescore`]: stored results (submissions' scores, human verdicts) computed again under
//!   the current metric version, in the foreground or as a job.
//! - [`heavy`]: the one bounded pool, at a lower priority, where CPU-heavy work runs (scoring,
//!   analyses, reports, imports' validation), so that interactive requests keep a core.
//! - [`audit`]: the audit log every audited use case writes in its own transaction.
//! - [`demo`]: the built-in demo dataset, its chance baseline and its login link.
//! - [`backup`]: online snapshots of the database, and restoring one.
//! - [`signing`]: the hub's statement-signing key (in a key file, never in the database),
//!   made on first need and rotated; [`statements`]: each scored submission's signed
//!   statement, and checking one offline.
//! - [`jobs`]: long work that survives restarts, worked by one instance at a time (model runs,
//!   rescoring); [`pipeline`]: new items from replays, and simulated replays.
//! - [`runs`]: model runs: the hub asks an OpenAI-compatible endpoint every item, keeps each
//!   reply as it arrives, resumes where it stopped, and submits the answers.
//!
//! Errors are [`AppError`]: each kind says what was wrong, in words a person can act on.

pub mod agreement;
pub mod annotation;
pub mod annotators;
pub mod attention;
pub mod audit;
pub mod backup;
pub mod cache;
pub mod challenge;
pub mod changes;
pub mod compare;
pub mod controls;
pub mod datasets;
pub mod demo;
pub mod doctor;
pub mod episode_curation;
pub mod episodes;
mod error;
pub mod error_analysis;
pub mod explore;
pub mod frames;
pub mod gold;
pub mod heavy;
pub mod import;
pub mod import_jobs;
pub mod item_answers;
pub mod items;
pub mod jobs;
pub mod leaderboard;
pub mod metrics;
pub mod migrate_db;
pub mod models;
pub mod paper;
pub mod pipeline;
pub mod quality;
pub mod red_flags;
pub mod refusal;
pub mod reported;
pub mod rescore;
pub mod runs;
pub mod scoring;
pub mod signing;
pub mod standings;
pub mod statements;
pub mod studies;
pub mod submissions;
pub mod tokens;
pub mod version;
pub mod watch;
mod write;

use std::path::Path;
use std::sync::Arc;

use sqlx::SqlitePool;

pub use error::AppError;
pub use write::{Lane, Write};

/// The benchmark and the store, under the names every use case calls them by (`crate::core::…`,
/// `crate::store::…`).
use enact_core as core;
use enact_store as store;
use store::Pool;

/// Submission attempts a token may make, unless the token sets its own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Quotas {
    /// Per UTC day.
    pub daily: i64,
    /// In total.
    pub total: i64,
}

impl Default for Quotas {
    fn default() -> Self {
        Quotas {
            daily: 20,
            total: 1000,
        }
    }
}

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

/// The code of every kind of job this version knows, as a serving instance's worker runs it
/// (here, above both the job mechanism and the modules owning each kind, so neither uses the
/// other both ways). A model run's key comes from the hub's allowlist (`serve
/// --endpoint-key`), so the hub it is handed is enough.
pub fn job_handlers() -> jobs::JobHandlers {
    jobs::JobHandlers::default()
        .with(jobs::JobKind::Rescore, |hub, job| {
            Box::pin(async move { rescore::work(&hub, &job).await })
        })
        .with(jobs::JobKind::ModelRun, |hub, job| {
            Box::pin(async move { runs::work(&hub, &job).await })
        })
        .with(jobs::JobKind::Import, |hub, job| {
            Box::pin(async move { import_jobs::work(&hub, &job).await })
        })
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
    items: Arc<cache::ItemCache>,
    standings: Arc<standings::StandingCache>,
    targets: Arc<submissions::TargetCache>,
    boards: Arc<leaderboard::BoardCache>,
    frames: Arc<cache::FrameCache>,
    /// Where frame bytes are written, and read when the database does not hold them.
    frame_store: frames::FrameStore,
    /// Frames in an object store that signs URLs are answered with a redirect to a URL valid
    /// this long, when set.
    frame_redirect: Option<std::time::Duration>,
    /// Changes other instances announced, for caches outside the app layer.
    changes: tokio::sync::broadcast::Sender<changes::Change>,
    quotas: Quotas,
    /// The environment variables a server-side model run may take its API key from.
    endpoint_keys: runs::EndpointKeys,
    /// The folder import jobs read releases from (`serve --import-dir`); none: refused.
    import_dir: Option<Arc<std::path::PathBuf>>,
    metrics: Arc<metrics::Metrics>,
    heavy: heavy::HeavyPool,
    /// The order this process's writers take the database's write lock in.
    gate: store::gate::WriteGate,
    /// This process's name in the change feed, so that a server skips its own announcements.
    origin: Arc<str>,
    /// The key statements are signed with, and the hub they name.
    signer: Arc<signing::Signer>,
    item_digests: Arc<statements::ItemDigests>,
}

impl From<SqlitePool> for Hub {
    fn from(pool: SqlitePool) -> Hub {
        Hub::new(Pool::Sqlite(pool), Quotas::default())
    }
}

impl From<Pool> for Hub {
    fn from(pool: Pool) -> Hub {
        Hub::new(pool, Quotas::default())
    }
}

impl Hub {
    pub fn new(pool: Pool, quotas: Quotas) -> Hub {
        let caches = watch::Caches::new(&cache::CacheLimits::default());
        let metrics = Arc::new(metrics::Metrics::default());
        let heavy = heavy::HeavyPool::new(heavy::HeavyLimits::default(), metrics.heavy());
        let gate = store::gate::WriteGate::observed({
            let metrics = metrics.clone();
            Arc::new(move |lane, held| metrics.write_held(lane, held))
        });
        let signer = Arc::new(signing::Signer::new(
            signing::KeySource::beside(&pool),
            None,
        ));
        Hub {
            writer: pool.clone(),
            checkpoints_beside: false,
            pool,
            items: caches.items,
            standings: caches.standings,
            targets: caches.targets,
            boards: caches.boards,
            frames: caches.frames,
            frame_store: frames::FrameStore::Database,
            frame_redirect: None,
            changes: tokio::sync::broadcast::channel(1024).0,
            quotas,
            endpoint_keys: runs::EndpointKeys::default(),
            import_dir: None,
            metrics,
            heavy,
            gate,
            origin: changes::new_origin().into(),
            signer,
            item_digests: Arc::default(),
        }
    }

    /// The hub signing its statements with the key in `key_file` (made there on first need)
    /// instead of the one beside a SQLite database (`--signing-key`, `ENACT_HUB_SIGNING_KEY`),
    /// naming itself by `public_url` in them (`--public-url`, `ENACT_HUB_PUBLIC_URL`).
    pub fn with_signing(
        mut self,
        key_file: Option<std::path::PathBuf>,
        public_url: Option<String>,
    ) -> Hub {
        let source = match key_file {
            Some(path) => signing::KeySource::File(path),
            None => signing::KeySource::beside(&self.pool),
        };
        self.signer = Arc::new(signing::Signer::new(source, public_url));
        self
    }

    /// The hub with empty caches bounded by `limits` (call before serving).
    pub fn with_cache_limits(self, limits: &cache::CacheLimits) -> Hub {
        let caches = watch::Caches::new(limits);
        Hub {
            items: caches.items,
            standings: caches.standings,
            targets: caches.targets,
            boards: caches.boards,
            frames: caches.frames,
            ..self
        }
    }

    fn caches(&self) -> watch::Caches {
        watch::Caches {
            items: self.items.clone(),
            standings: self.standings.clone(),
            targets: self.targets.clone(),
            boards: self.boards.clone(),
            frames: self.frames.clone(),
        }
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
                    ..Hub::new(Pool::Sqlite(pool), Quotas::default())
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
            ..Hub::new(pool, Quotas::default())
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

    pub fn with_quotas(mut self, quotas: Quotas) -> Hub {
        self.quotas = quotas;
        self
    }

    /// The hub whose model runs may take their API keys from `keys` (`serve --endpoint-key`).
    pub fn with_endpoint_keys(mut self, keys: runs::EndpointKeys) -> Hub {
        self.endpoint_keys = keys;
        self
    }

    /// The hub whose import jobs read releases from under `dir` (`serve --import-dir`).
    pub fn with_import_dir(mut self, dir: Option<std::path::PathBuf>) -> Hub {
        self.import_dir = dir.map(Arc::new);
        self
    }

    /// The folder import jobs read releases from, when this instance has one.
    pub fn import_dir(&self) -> Option<&std::path::Path> {
        self.import_dir.as_deref().map(std::path::PathBuf::as_path)
    }

    /// The environment variables a server-side model run may take its API key from.
    pub fn endpoint_keys(&self) -> &runs::EndpointKeys {
        &self.endpoint_keys
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

    /// How many leaderboards this hub has built (each cache miss that read the store).
    pub fn board_builds(&self) -> u64 {
        self.boards.builds()
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

    /// Drops from this process's caches what its own committed `change` made stale (the
    /// adapters' caches, such as the web's sessions, see to their own changes).
    fn apply_committed(&self, change: changes::Change) {
        watch::forget(&self.caches(), &change);
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

    async fn conn(&self) -> Result<store::PooledConn, AppError> {
        let asked = std::time::Instant::now();
        let conn = self.pool.acquire().await?;
        self.metrics.connection_waited(asked.elapsed());
        Ok(conn)
    }

    /// A write transaction in `lane`; a wait longer than the database's busy timeout fails
    /// as busy ([`store::db::is_busy`]).
    async fn begin_in(&self, lane: store::gate::Lane) -> Result<store::Tx, sqlx::Error> {
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
