//! A dataset's leaderboard: a row per published submission and, once annotators have
//! answered, the Human row, scored by the same verifier. `core::leaderboard` cuts pages from
//! them (one row per account and model, ranks, sorts, filters).
//!
//! Boards are served from memory ([`board`]): built once, then shared until something that
//! changes them happens (a submission stored, a listing changed, an annotator's answer, here
//! or announced by another instance) or the stored items change (an import, seen by the
//! content watcher). Readers that miss at once share one build.

use std::collections::{BTreeMap, HashMap};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, RwLock};

use bytes::Bytes;

use super::cache::{BoundedCache, CacheLimits, CacheStats};
use super::challenge::ChallengeBoard;
use super::changes::Change;
use super::models::{self, ModelMetadata};
use super::reported::{self, ReportedResult};
use super::{AppError, Hub, datasets};
use crate::core::annotation::{self, HumanFigures};
use crate::core::explorer::Grid;
use crate::core::leaderboard::{LeaderboardRow, RowIdentity, rank};
use crate::core::verifier::PerformanceReport;
use crate::store;
use crate::store::datasets::Dataset;
use crate::store::submissions::SubmissionRow;

/// A submission's leaderboard row.
pub fn submission_row(s: &SubmissionRow) -> LeaderboardRow {
    LeaderboardRow::from_scores(
        &RowIdentity {
            submission: s.id,
            model: &s.model,
            account: &s.account,
            baseline: s.baseline,
            submitted_at: &s.created_at,
            metric_version: s.metric_version,
            provenance: s.provenance,
            run: s.run,
        },
        &s.scores,
    )
}

/// The Human row's figures on a dataset: every submitted answer's verdict, stored when the
/// answer was finished and scored as model answers are (the item's stored signatures, exact
/// match where there are none), by direction and step length, with the answers, items and
/// annotators it rests on, all read in one query. Answers on gold items and of excluded
/// annotators are left out ([`super::gold`]), and the coverage says how many of each. Answers finished before verdicts were stored
/// are judged here until a rescore stores theirs. `None` when nobody has answered an item yet.
/// Skipped and flagged items are not answers; an item answered by several annotators counts
/// once per answer.
pub async fn human_figures(
    hub: &Hub,
    dataset: &Dataset,
    dataset_items: usize,
) -> Result<Option<HumanFigures>, AppError> {
    let mut conn = hub.conn().await?;
    let answers = store::annotations::counted_answers(&mut conn, dataset.id).await?;
    // Attention checks are left out of the Human row as gold items are.
    let gold_items = store::gold::gold_count(&mut conn, dataset.id).await?
        + store::attention::attention_count(&mut conn, dataset.id).await?;
    let excluded = store::gold::exclusions(&mut conn, dataset.id).await?.len();
    drop(conn);
    let figures = annotation::human_figures(&answers, dataset_items).map_err(|e| {
        AppError::internal(format!(
            "dataset '{}': stored annotations: {e}",
            dataset.name
        ))
    })?;
    let gold_items = usize::try_from(gold_items).unwrap_or(0);
    Ok(figures.map(|f| HumanFigures {
        coverage: f.coverage.leaving_out(gold_items, excluded),
        ..f
    }))
}

/// Human performance on a dataset (see [`human_figures`]), `None` before the first answer.
pub async fn human_performance(
    hub: &Hub,
    dataset: &Dataset,
) -> Result<Option<PerformanceReport>, AppError> {
    Ok(human_figures(hub, dataset, 0).await?.map(|f| f.report))
}

/// The dataset's leaderboard rows, ranked.
pub async fn rows(hub: &Hub, dataset: &Dataset) -> Result<Vec<LeaderboardRow>, AppError> {
    Ok(rows_and_challenge(hub, dataset).await?.0)
}

/// The dataset's leaderboard rows, ranked, and on a split dataset its challenge with the
/// other part's rows, ranked too ([`super::challenge::on_board`]).
pub async fn rows_and_challenge(
    hub: &Hub,
    dataset: &Dataset,
) -> Result<(Vec<LeaderboardRow>, Option<ChallengeBoard>), AppError> {
    let mut conn = hub.conn().await?;
    let submissions = store::submissions::published(&mut conn, dataset.id).await?;
    let items = store::datasets::counts(&mut conn, dataset.id).await?.total;
    drop(conn);
    let mut rows: Vec<LeaderboardRow> = submissions.iter().map(submission_row).collect();
    let mut challenge =
        super::challenge::on_board(hub, dataset, &submissions, &mut rows, submission_row).await?;
    let dataset_items = usize::try_from(items).unwrap_or(0);
    if let Some(human) = human_figures(hub, dataset, dataset_items).await? {
        let human = LeaderboardRow::human(&human.report, human.coverage, human.stamp);
        if let Some(c) = &mut challenge {
            c.other.push(human.clone());
        }
        rows.push(human);
    }
    rank(&mut rows);
    if let Some(c) = &mut challenge {
        rank(&mut c.other);
    }
    Ok((rows, challenge))
}

/// The leaderboard of the dataset named `name`.
pub async fn of(hub: &Hub, name: &str) -> Result<(Dataset, Vec<LeaderboardRow>), AppError> {
    let dataset = datasets::by_name(hub, name).await?;
    let rows = rows(hub, &dataset).await?;
    Ok((dataset, rows))
}

/// A dataset's board as built from the store: every published submission's row and the Human
/// row. Pages, sorts and filters are cut from it per request, and what was cut and rendered is
/// kept with it (it goes when the board goes).
#[derive(Debug)]
pub struct Board {
    pub dataset: Dataset,
    pub rows: Vec<LeaderboardRow>,
    /// The hub's own models' metadata on the dataset, by model name.
    pub metadata: BTreeMap<String, ModelMetadata>,
    /// Results papers published for the dataset, shown beside the rows when asked for and
    /// never ranked with them.
    pub reported: Vec<ReportedResult>,
    /// A split dataset's challenge: what the rows are over, and the other part's rows.
    pub challenge: Option<ChallengeBoard>,
    /// Unique per build in this process: a response's entity tag starts with it.
    pub version: u64,
    views: RwLock<HashMap<String, Bytes>>,
    /// The explorer's grid of this board's rows' verdicts (`super::explore`), built by its
    /// first reader: it goes when the board goes, so whatever changes the board changes it.
    pub explorer: tokio::sync::OnceCell<Arc<Grid>>,
}

/// Rendered views kept per board; past this the board starts over (each renders in a few ms).
const MAX_VIEWS: usize = 256;

impl Board {
    /// Whether this board was built before its challenge's deadline, which has now passed: it
    /// must be built again (and the reveal recorded) rather than served.
    pub fn reveal_due(&self) -> bool {
        self.challenge
            .as_ref()
            .is_some_and(ChallengeBoard::reveal_due)
    }

    /// A view rendered before under `key` (a format and the normalized request).
    pub fn view(&self, key: &str) -> Option<Bytes> {
        self.views
            .read()
            .unwrap_or_else(|p| p.into_inner())
            .get(key)
            .cloned()
    }

    /// Keeps a rendered view for the next request with the same `key`.
    pub fn keep_view(&self, key: String, view: Bytes) {
        let mut views = self.views.write().unwrap_or_else(|p| p.into_inner());
        if views.len() >= MAX_VIEWS {
            views.clear();
        }
        views.insert(key, view);
    }
}

/// Built boards by dataset name, and a count of the changes that outdate them.
pub struct BoardCache {
    boards: BoundedCache<String, Arc<Board>>,
    /// Bumped by every change; a build stores its board only if no change came in between.
    /// Held while storing and while dropping, so a check and its insert are one step.
    changes: Mutex<u64>,
    builds: AtomicU64,
    /// The build under way per dataset: readers that miss together wait for one build instead
    /// of each reading every submission again (after each answer, under load, many do).
    flights: Mutex<HashMap<String, Arc<Flight>>>,
}

/// One build of a board, shared by the readers that asked for it before any change since it
/// began.
struct Flight {
    /// The change count when it began: it reads everything committed before.
    ticket: u64,
    board: tokio::sync::OnceCell<Arc<Board>>,
}

impl Default for BoardCache {
    fn default() -> Self {
        BoardCache::new(CacheLimits::default().board_datasets)
    }
}

/// Every board is dropped when something boards show changes, or stored items do.
impl crate::Kept for BoardCache {
    fn make(hub: &Hub) -> Self {
        BoardCache::new(hub.cache_limits().board_datasets)
    }

    fn forget_stale(&self, change: &Change) {
        match change {
            Change::Boards | Change::Everything => self.changed(),
            Change::Standing { .. } | Change::SessionEnded(_) => {}
        }
    }

    fn stats(&self) -> Vec<CacheStats> {
        vec![BoardCache::stats(self)]
    }
}

/// How many leaderboards `hub` has built (each cache miss that read the store).
pub fn board_builds(hub: &Hub) -> u64 {
    hub.kept::<BoardCache>().builds()
}

impl BoardCache {
    /// At most `datasets` boards.
    pub fn new(datasets: u64) -> BoardCache {
        BoardCache {
            boards: BoundedCache::by_entries("boards", datasets),
            changes: Mutex::new(0),
            builds: AtomicU64::new(0),
            flights: Mutex::default(),
        }
    }

    /// The build of `dataset` to wait for: the one under way if no change came since it
    /// began, else a new one.
    fn flight(&self, dataset: &str) -> Arc<Flight> {
        let ticket = *self.changes();
        let mut flights = self.flights.lock().unwrap_or_else(|p| p.into_inner());
        match flights.get(dataset) {
            Some(flight) if flight.ticket == ticket => flight.clone(),
            _ => {
                let flight = Arc::new(Flight {
                    ticket,
                    board: tokio::sync::OnceCell::new(),
                });
                flights.insert(dataset.to_owned(), flight.clone());
                flight
            }
        }
    }

    /// Forgets `flight` once it is done (a newer one may have replaced it).
    fn landed(&self, dataset: &str, flight: &Arc<Flight>) {
        let mut flights = self.flights.lock().unwrap_or_else(|p| p.into_inner());
        if flights.get(dataset).is_some_and(|f| Arc::ptr_eq(f, flight)) {
            flights.remove(dataset);
        }
    }

    /// Changes seen so far ([`BoardCache::changed`]).
    pub fn change_count(&self) -> u64 {
        *self.changes()
    }

    /// Boards built so far (each build's version is the count at its end).
    pub fn builds(&self) -> u64 {
        self.builds.load(Ordering::SeqCst)
    }

    fn changes(&self) -> std::sync::MutexGuard<'_, u64> {
        self.changes.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Something that boards show has changed: drop them all (they rebuild in milliseconds).
    pub fn changed(&self) {
        let mut changes = self.changes();
        *changes += 1;
        self.boards.clear();
    }

    fn get(&self, dataset: &str) -> Option<Arc<Board>> {
        self.boards.get(&dataset.to_owned())
    }

    pub fn stats(&self) -> CacheStats {
        self.boards.stats()
    }
}

/// Builds every dataset's board into the cache, as a server starts: the first build of a
/// full-size board takes about a second and a half, which its first readers would otherwise
/// wait out (measured: the slowest reads of the mixed load were exactly those). A board that
/// fails to build is logged and left to its first reader. Returns how many were built.
pub async fn warm(hub: &Hub) -> Result<usize, AppError> {
    let mut built = 0;
    for overview in super::datasets::overview(hub).await? {
        match board(hub, &overview.dataset.name).await {
            Ok(_) => built += 1,
            Err(e) => tracing::warn!(
                dataset = %overview.dataset.name,
                error = %e,
                "building a leaderboard at start failed; its first reader builds it"
            ),
        }
    }
    Ok(built)
}

/// The board of the dataset named `name`, from memory when nothing changed since it was built.
/// Readers that miss at once share one build (see [`BoardCache`]).
pub async fn board(hub: &Hub, name: &str) -> Result<Arc<Board>, AppError> {
    let cache = &hub.kept::<BoardCache>();
    // A board kept from before its challenge's deadline is built again (and the reveal made).
    if let Some(board) = cache.get(name).filter(|b| !b.reveal_due()) {
        return Ok(board);
    }
    let flight = Landing {
        cache,
        dataset: name,
        flight: cache.flight(name),
    };
    // One reader builds; the others wait for it. A failed build is tried again by the next
    // waiter (each then gets its own error), as is one whose reader went away.
    flight
        .flight
        .board
        .get_or_try_init(|| build(hub, name, flight.flight.ticket))
        .await
        .cloned()
}

/// Forgets its flight when dropped, even when the request waiting on it is cancelled, so no
/// flight outlives its readers.
struct Landing<'a> {
    cache: &'a BoardCache,
    dataset: &'a str,
    flight: Arc<Flight>,
}

impl Drop for Landing<'_> {
    fn drop(&mut self) {
        self.cache.landed(self.dataset, &self.flight);
    }
}

/// Reads and ranks the board of `name`; keeps it when no change came since `ticket`.
async fn build(hub: &Hub, name: &str, ticket: u64) -> Result<Arc<Board>, AppError> {
    let cache = &hub.kept::<BoardCache>();
    // Kept by a build that landed between this reader's miss and its flight.
    if let Some(board) = cache.get(name).filter(|b| !b.reveal_due()) {
        return Ok(board);
    }
    let dataset = datasets::by_name(hub, name).await?;
    let (rows, challenge) = rows_and_challenge(hub, &dataset).await?;
    let metadata = models::of_dataset(hub, &dataset.name)
        .await?
        .into_iter()
        .map(|(model, entry)| (model, entry.metadata))
        .collect();
    let reported = reported::list(hub, &dataset.name).await?;
    let board = Arc::new(Board {
        dataset,
        rows,
        metadata,
        reported,
        challenge,
        version: cache.builds.fetch_add(1, Ordering::SeqCst) + 1,
        views: RwLock::default(),
        explorer: tokio::sync::OnceCell::new(),
    });
    let changes = cache.changes();
    // A change during the build may predate what was read: serve this board, keep none.
    if *changes == ticket {
        cache.boards.insert(name.to_owned(), board.clone());
    }
    drop(changes);
    Ok(board)
}
