//! Keeps a hub's caches honest: clears the item-dependent ones whenever the store's content
//! generation moves (imports may run in another process, so a replaced item is served stale
//! for at most one poll interval), and logs every cache's figures once a minute while they are
//! used.
//!
//! On PostgreSQL, several server instances share one database, and each keeps caches of what
//! the others change: an annotator's standing on an item, a leaderboard, a login session. Every
//! such change is [`published`](super::Hub::publish) on the database's `NOTIFY` channel inside
//! the transaction that makes it (so it is announced exactly when it commits), and every
//! instance [listens](listen) and drops what it cached. On SQLite the other writers are
//! command-line processes beside one server: the same announcements are rows of the change
//! feed, written in the same transactions, which the server [reads](follow_feed) twice a second.
//! Item changes keep the generation poll, which also catches imports by a command-line process.

use std::sync::Arc;
use std::time::Duration;

use super::cache::{CacheStats, FrameCache, ItemCache};
use super::changes::{CHANNEL, Change};
use super::kept::KeptValues;
use crate::store;
use crate::store::Pool;

/// How often running servers look for imports made by other processes.
pub const POLL_INTERVAL: Duration = Duration::from_millis(500);

/// How often cache statistics are logged (when a cache was used since the last time).
const STATS_INTERVAL: Duration = Duration::from_secs(60);

/// Every cache of a hub: its own, and those the use cases keep on it.
#[derive(Clone)]
pub struct Caches {
    pub(crate) items: Arc<ItemCache>,
    pub(crate) frames: Arc<FrameCache>,
    pub(crate) kept: Arc<KeptValues>,
}

impl Caches {
    /// Every cache's figures.
    pub fn stats(&self) -> Vec<CacheStats> {
        let mut all = self.items.stats().to_vec();
        all.extend(self.kept.stats());
        all.push(self.frames.stats());
        all
    }

    /// Drops what `change` made stale: for another process's change ([`apply`]), and for
    /// this process's own once its write commits ([`crate::Write::commit`]). Frames are
    /// addressed by their content and never go stale.
    pub(crate) fn forget(&self, change: &Change) {
        if *change == Change::Everything {
            self.items.clear();
        }
        self.kept.forget_stale(change);
    }
}

/// Logs each cache's figures when any was used since the last call; returns the lookups seen.
fn log_stats(stats: &[CacheStats], last_lookups: u64) -> u64 {
    let lookups: u64 = stats.iter().map(|s| s.hits + s.misses).sum();
    if lookups != last_lookups {
        for s in stats {
            tracing::info!(
                cache = s.name,
                hits = s.hits,
                misses = s.misses,
                hit_rate = s
                    .hit_rate()
                    .map_or_else(|| "-".to_owned(), |r| format!("{r:.3}")),
                entries = s.entries,
                weight = s.weight,
                capacity = s.capacity,
                "cache statistics"
            );
        }
    }
    lookups
}

/// Clears the item-dependent caches whenever the store's content generation changes, and logs
/// cache statistics once a minute. Runs until the pool closes.
pub async fn watch_generation(pool: Pool, caches: Caches) {
    let mut seen = None;
    let mut ticker = tokio::time::interval(POLL_INTERVAL);
    ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let mut last_stats = tokio::time::Instant::now();
    let mut lookups = 0;
    loop {
        ticker.tick().await;
        if pool.is_closed() {
            return;
        }
        if last_stats.elapsed() >= STATS_INTERVAL {
            last_stats = tokio::time::Instant::now();
            lookups = log_stats(&caches.stats(), lookups);
        }
        let current = match pool.acquire().await {
            Ok(mut conn) => store::content_generation(&mut conn).await,
            Err(e) => Err(e),
        };
        match current {
            Ok(generation) => {
                if seen.is_some_and(|s| s != generation) {
                    tracing::info!(generation, "stored items changed: item cache cleared");
                    caches.forget(&Change::Everything);
                }
                seen = Some(generation);
            }
            Err(e) => {
                // Serving stale items is worse than serving none: drop the cache.
                tracing::warn!(error = %e, "cannot read the content generation");
                caches.forget(&Change::Everything);
            }
        }
    }
}

/// Drops what another process's `change` makes stale from the caches, and passes it on to the
/// caches outside the app layer (the web's sessions).
fn apply(caches: &Caches, changes: &tokio::sync::broadcast::Sender<Change>, change: Change) {
    caches.forget(&change);
    let _ = changes.send(change);
}

/// How many announcements one read of the change feed takes at most.
const FEED_PAGE: i64 = 1000;

/// Applies what other processes wrote to the change feed (SQLite: the command line beside a
/// running server), within one poll interval, until the pool closes. A PostgreSQL database's
/// instances announce with `NOTIFY` instead ([`listen`]). Announcements this process wrote
/// itself (`origin`) were applied when they committed, and are skipped.
pub async fn follow_feed(
    pool: Pool,
    caches: Caches,
    changes: tokio::sync::broadcast::Sender<Change>,
    origin: Arc<str>,
) {
    if !matches!(pool, Pool::Sqlite(_)) {
        return;
    }
    // Where reading starts: what was announced before this server started is in no cache.
    let mut last = None;
    let mut ticker = tokio::time::interval(POLL_INTERVAL);
    ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        ticker.tick().await;
        if pool.is_closed() {
            return;
        }
        let read = async {
            let mut conn = pool.acquire().await?;
            let (oldest, newest) = store::change_feed_span(&mut conn).await?;
            let Some(after) = last else {
                return Ok::<_, sqlx::Error>((newest, Vec::new(), false));
            };
            // Rows pruned before this server read them: what they said is unknown.
            let missed = oldest > after + 1;
            let mut read = Vec::new();
            let mut from = after;
            loop {
                let page = store::announcements_after(&mut conn, from, FEED_PAGE).await?;
                let full = page.len() as i64 == FEED_PAGE;
                from = page.last().map_or(from, |a| a.id);
                read.extend(page);
                if !full {
                    break;
                }
            }
            Ok((from, read, missed))
        };
        match read.await {
            Ok((seen, announcements, missed)) => {
                if missed {
                    tracing::warn!("the change feed moved past this server: caches cleared");
                    apply(&caches, &changes, Change::Everything);
                }
                for announcement in announcements.iter().filter(|a| *a.origin != *origin) {
                    match Change::parse(&announcement.payload) {
                        Some(change) => apply(&caches, &changes, change),
                        None => tracing::warn!(
                            payload = announcement.payload,
                            "unknown change in the change feed"
                        ),
                    }
                }
                last = Some(seen);
            }
            Err(e) => {
                if pool.is_closed() {
                    return;
                }
                // Announcements may be missed meanwhile: serve nothing stale.
                tracing::warn!(error = %e, "cannot read the change feed");
                apply(&caches, &changes, Change::Everything);
            }
        }
    }
}

/// Applies the changes other instances announce, until the pool closes (PostgreSQL only; on
/// SQLite, [`follow_feed`]). What this process announced itself (`origin`) was applied when
/// it committed and is skipped: applied again on arrival, it would drop caches filled since.
/// Changes are also sent on `changes` for caches outside the app layer (the web's sessions).
/// When the connection drops, notifications may have been missed meanwhile: every cache is
/// cleared once listening again.
pub async fn listen(
    pool: Pool,
    caches: Caches,
    changes: tokio::sync::broadcast::Sender<Change>,
    origin: Arc<str>,
) {
    let Pool::Pg(pg) = &pool else {
        return;
    };
    let clear_all = |why: &str| {
        tracing::warn!(
            why,
            "cross-instance changes may have been missed: caches cleared"
        );
        apply(&caches, &changes, Change::Everything);
    };
    let Some(mut listener) = listening(&pool, pg).await else {
        return;
    };
    loop {
        match listener.try_recv().await {
            Ok(Some(notification)) => match store::notification_parts(notification.payload()) {
                (Some(from), _) if *from == *origin => {}
                (_, payload) => match Change::parse(payload) {
                    Some(change) => apply(&caches, &changes, change),
                    None => tracing::warn!(payload, "unknown change announced on {CHANNEL}"),
                },
            },
            // The connection was lost and is back (sqlx listens again before it says so).
            Ok(None) => clear_all("the listening connection was re-established"),
            // The connection was lost and could not be made again at once. The caches are
            // cleared once listening again, not before: a change committed while nobody
            // listened would otherwise stay unseen in a cache refilled meanwhile.
            Err(e) => {
                if pool.is_closed() {
                    return;
                }
                tracing::warn!(error = %e, "lost the connection listening for other instances' changes");
                tokio::time::sleep(POLL_INTERVAL).await;
                let Some(again) = listening(&pool, pg).await else {
                    return;
                };
                listener = again;
                clear_all(&format!("listening again after: {e}"));
            }
        }
    }
}

/// A connection listening on [`CHANNEL`], tried every [`POLL_INTERVAL`] until it is made;
/// `None` once the pool is closed.
async fn listening(pool: &Pool, pg: &sqlx::PgPool) -> Option<sqlx::postgres::PgListener> {
    loop {
        match sqlx::postgres::PgListener::connect_with(pg).await {
            Ok(mut listener) => match listener.listen(CHANNEL).await {
                Ok(()) => return Some(listener),
                Err(e) => tracing::warn!(error = %e, "cannot listen for other instances' changes"),
            },
            Err(e) => tracing::warn!(error = %e, "cannot listen for other instances' changes"),
        }
        if pool.is_closed() {
            return None;
        }
        tokio::time::sleep(POLL_INTERVAL).await;
    }
}
