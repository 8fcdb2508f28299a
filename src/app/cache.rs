//! Items kept in memory (the API's JSON and the annotation pages' decoded items), so hot read
//! paths do no database work for item content.
//!
//! Items change only through imports, which may run in another process. A background task
//! watches the store's content generation and clears the cache when it moves, so a replaced
//! item is served stale for at most one poll interval.

use std::collections::HashMap;
use std::sync::{Arc, RwLock};
use std::time::Duration;

use bytes::Bytes;
use sqlx::SqlitePool;

use super::leaderboard::BoardCache;
use super::standings::StandingCache;
use crate::store;
use crate::store::items::StoredItem;

/// How often running servers look for imports made by other processes.
pub const POLL_INTERVAL: Duration = Duration::from_millis(500);

/// Entries kept at most per map; past this the map starts over (items are cheap to rebuild).
const MAX_ENTRIES: usize = 50_000;

/// Items in memory, by (dataset name, item id): the public JSON view for the API, and the
/// decoded stored item for annotation pages. Both are cleared together.
#[derive(Default)]
pub struct ItemCache {
    json: KeyedCache<Bytes>,
    stored: KeyedCache<Arc<StoredItem>>,
}

impl ItemCache {
    pub fn json(&self, dataset: &str, item_id: &str) -> Option<Bytes> {
        self.json.get(dataset, item_id)
    }

    pub fn insert_json(&self, dataset: &str, item_id: &str, json: Bytes) {
        self.json.insert(dataset, item_id, json);
    }

    pub fn stored(&self, dataset: &str, item_id: &str) -> Option<Arc<StoredItem>> {
        self.stored.get(dataset, item_id)
    }

    pub fn insert_stored(&self, dataset: &str, item_id: &str, item: Arc<StoredItem>) {
        self.stored.insert(dataset, item_id, item);
    }

    pub fn clear(&self) {
        self.json.clear();
        self.stored.clear();
    }
}

struct KeyedCache<V> {
    entries: RwLock<HashMap<(String, String), V>>,
}

impl<V> Default for KeyedCache<V> {
    fn default() -> Self {
        KeyedCache {
            entries: RwLock::default(),
        }
    }
}

impl<V: Clone> KeyedCache<V> {
    fn get(&self, dataset: &str, item_id: &str) -> Option<V> {
        let entries = self.entries.read().unwrap_or_else(|p| p.into_inner());
        // Tuple keys need owned strings; this allocation is far cheaper than a query.
        entries
            .get(&(dataset.to_owned(), item_id.to_owned()))
            .cloned()
    }

    fn insert(&self, dataset: &str, item_id: &str, value: V) {
        let mut entries = self.entries.write().unwrap_or_else(|p| p.into_inner());
        if entries.len() >= MAX_ENTRIES {
            entries.clear();
        }
        entries.insert((dataset.to_owned(), item_id.to_owned()), value);
    }

    fn clear(&self) {
        self.entries
            .write()
            .unwrap_or_else(|p| p.into_inner())
            .clear();
    }
}

/// Clears `cache`, `standings` and `boards` whenever the store's content generation changes.
/// Runs until the pool closes.
pub async fn watch_generation(
    pool: SqlitePool,
    cache: Arc<ItemCache>,
    standings: Arc<StandingCache>,
    boards: Arc<BoardCache>,
) {
    let mut seen = None;
    let mut ticker = tokio::time::interval(POLL_INTERVAL);
    ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        ticker.tick().await;
        if pool.is_closed() {
            return;
        }
        let current = match pool.acquire().await {
            Ok(mut conn) => store::content_generation(&mut conn).await,
            Err(e) => Err(e),
        };
        match current {
            Ok(generation) => {
                if seen.is_some_and(|s| s != generation) {
                    tracing::info!(generation, "stored items changed: item cache cleared");
                    cache.clear();
                    standings.clear();
                    boards.changed();
                }
                seen = Some(generation);
            }
            Err(e) => {
                // Serving stale items is worse than serving none: drop the cache.
                tracing::warn!(error = %e, "cannot read the content generation");
                cache.clear();
                standings.clear();
                boards.changed();
            }
        }
    }
}
