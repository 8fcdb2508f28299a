//! Serialised item JSON kept in memory, so the hot read path does no database work.
//!
//! Items change only through imports, which may run in another process. A background task
//! watches the store's content generation and clears the cache when it moves, so a replaced
//! item is served stale for at most one poll interval.

use std::collections::HashMap;
use std::sync::RwLock;
use std::time::Duration;

use axum::body::Bytes;
use sqlx::SqlitePool;

use crate::store;

/// How often running servers look for imports made by other processes.
pub const POLL_INTERVAL: Duration = Duration::from_millis(500);

/// Entries kept at most; past this the cache starts over (items are small and cheap to rebuild).
const MAX_ENTRIES: usize = 50_000;

#[derive(Default)]
pub struct ItemCache {
    entries: RwLock<HashMap<(String, String), Bytes>>,
}

impl ItemCache {
    pub fn get(&self, dataset: &str, item_id: &str) -> Option<Bytes> {
        let entries = self.entries.read().unwrap_or_else(|p| p.into_inner());
        // Tuple keys need owned strings; this allocation is far cheaper than a query.
        entries
            .get(&(dataset.to_owned(), item_id.to_owned()))
            .cloned()
    }

    pub fn insert(&self, dataset: &str, item_id: &str, json: Bytes) {
        let mut entries = self.entries.write().unwrap_or_else(|p| p.into_inner());
        if entries.len() >= MAX_ENTRIES {
            entries.clear();
        }
        entries.insert((dataset.to_owned(), item_id.to_owned()), json);
    }

    pub fn clear(&self) {
        self.entries
            .write()
            .unwrap_or_else(|p| p.into_inner())
            .clear();
    }
}

/// Clears `cache` whenever the store's content generation changes. Runs until the pool closes.
pub async fn watch_generation(pool: SqlitePool, cache: std::sync::Arc<ItemCache>) {
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
                }
                seen = Some(generation);
            }
            Err(e) => {
                // Serving stale items is worse than serving none: drop the cache.
                tracing::warn!(error = %e, "cannot read the content generation");
                cache.clear();
            }
        }
    }
}
