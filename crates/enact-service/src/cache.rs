//! The server's in-memory caches, each bounded (in bytes or entries, set on `serve`) by a
//! [`BoundedCache`] over `moka` (TinyLFU admission, LRU eviction) that also counts hits and
//! misses. `watch` clears the item-dependent ones when stored items change and logs the
//! figures.

use std::hash::Hash;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use bytes::Bytes;
use serde::Serialize;

use crate::store::items::StoredItem;

/// The bounds of the server's caches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CacheLimits {
    /// Item JSON and decoded items together, in bytes (half each).
    pub item_bytes: u64,
    /// Annotators' standings on items, in entries.
    pub standing_entries: u64,
    /// Datasets whose scoring targets are kept (each holds every item's signatures).
    pub target_datasets: u64,
    /// Datasets whose leaderboard is kept built.
    pub board_datasets: u64,
    /// Frame PNGs, in bytes.
    pub frame_bytes: u64,
    /// SQLite's page cache over all of a server's connections, in bytes (the OS caches the
    /// database file as well).
    pub db_page_cache_bytes: u64,
}

impl Default for CacheLimits {
    fn default() -> Self {
        CacheLimits {
            item_bytes: 32 * 1024 * 1024,
            standing_entries: 100_000,
            target_datasets: 8,
            board_datasets: 32,
            frame_bytes: 128 * 1024 * 1024,
            db_page_cache_bytes: 32 * 1024 * 1024,
        }
    }
}

/// What a cache says about itself.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CacheStats {
    pub name: &'static str,
    pub hits: u64,
    pub misses: u64,
    pub entries: u64,
    /// Bytes for caches bounded in bytes, else entries.
    pub weight: u64,
    pub capacity: u64,
}

impl CacheStats {
    pub fn hit_rate(&self) -> Option<f64> {
        let total = self.hits + self.misses;
        (total > 0).then(|| self.hits as f64 / total as f64)
    }
}

/// A concurrent cache with a bound, counting its hits and misses.
pub struct BoundedCache<K, V> {
    name: &'static str,
    capacity: u64,
    inner: moka::sync::Cache<K, V>,
    hits: AtomicU64,
    misses: AtomicU64,
}

impl<K, V> BoundedCache<K, V>
where
    K: Hash + Eq + Send + Sync + 'static,
    V: Clone + Send + Sync + 'static,
{
    /// At most `max_entries` entries.
    pub fn by_entries(name: &'static str, max_entries: u64) -> Self {
        BoundedCache::with(name, max_entries, moka::sync::Cache::new(max_entries))
    }

    /// At most `max_bytes` as `weigh` counts them (an entry heavier than `u32::MAX` bytes
    /// counts as that).
    pub fn by_bytes(name: &'static str, max_bytes: u64, weigh: fn(&K, &V) -> u64) -> Self {
        let inner = moka::sync::Cache::builder()
            .max_capacity(max_bytes)
            .weigher(move |k: &K, v: &V| u32::try_from(weigh(k, v)).unwrap_or(u32::MAX))
            .build();
        BoundedCache::with(name, max_bytes, inner)
    }

    fn with(name: &'static str, capacity: u64, inner: moka::sync::Cache<K, V>) -> Self {
        BoundedCache {
            name,
            capacity,
            inner,
            hits: AtomicU64::new(0),
            misses: AtomicU64::new(0),
        }
    }

    pub fn get(&self, key: &K) -> Option<V> {
        let found = self.inner.get(key);
        let counter = if found.is_some() {
            &self.hits
        } else {
            &self.misses
        };
        counter.fetch_add(1, Ordering::Relaxed);
        found
    }

    pub fn insert(&self, key: K, value: V) {
        self.inner.insert(key, value);
    }

    pub fn remove(&self, key: &K) {
        self.inner.invalidate(key);
    }

    pub fn clear(&self) {
        self.inner.invalidate_all();
    }

    pub fn stats(&self) -> CacheStats {
        // Counts are settled lazily; settle them so the figures are current.
        self.inner.run_pending_tasks();
        CacheStats {
            name: self.name,
            hits: self.hits.load(Ordering::Relaxed),
            misses: self.misses.load(Ordering::Relaxed),
            entries: self.inner.entry_count(),
            weight: self.inner.weighted_size(),
            capacity: self.capacity,
        }
    }
}

/// Key of an item: (dataset name, item id).
type ItemKey = (String, String);

fn key(dataset: &str, item_id: &str) -> ItemKey {
    (dataset.to_owned(), item_id.to_owned())
}

/// Bytes an item's decoded form holds, roughly: its strings and lists, and fixed overhead.
fn stored_weight(key: &ItemKey, item: &Arc<StoredItem>) -> u64 {
    let strings = item.summary.item_id.len()
        + item.summary.item_type.len()
        + item.summary.task_name.len()
        + item.question.len()
        + item.gt_answer.len()
        + item
            .key_frame_ids
            .iter()
            .map(|f| f.len() + 24)
            .sum::<usize>()
        + item.actions.iter().map(|a| a.len() + 24).sum::<usize>()
        + item
            .images
            .iter()
            .map(|i| i.path.len() + i.sha256.len() + 64)
            .sum::<usize>();
    (key.0.len() + key.1.len() + strings + 256) as u64
}

/// Items in memory, by (dataset name, item id): the public JSON view for the API, and the
/// decoded stored item for annotation pages. Both are cleared together.
pub struct ItemCache {
    json: BoundedCache<ItemKey, Bytes>,
    stored: BoundedCache<ItemKey, Arc<StoredItem>>,
}

impl ItemCache {
    /// At most `bytes` in all: half for JSON, half for decoded items.
    pub fn new(bytes: u64) -> ItemCache {
        ItemCache {
            json: BoundedCache::by_bytes("item_json", bytes / 2, |k, v| {
                (k.0.len() + k.1.len() + v.len() + 64) as u64
            }),
            stored: BoundedCache::by_bytes("item_stored", bytes / 2, stored_weight),
        }
    }

    pub fn json(&self, dataset: &str, item_id: &str) -> Option<Bytes> {
        // Tuple keys need owned strings; this allocation is far cheaper than a query.
        self.json.get(&key(dataset, item_id))
    }

    pub fn insert_json(&self, dataset: &str, item_id: &str, json: Bytes) {
        self.json.insert(key(dataset, item_id), json);
    }

    pub fn stored(&self, dataset: &str, item_id: &str) -> Option<Arc<StoredItem>> {
        self.stored.get(&key(dataset, item_id))
    }

    pub fn insert_stored(&self, dataset: &str, item_id: &str, item: Arc<StoredItem>) {
        self.stored.insert(key(dataset, item_id), item);
    }

    pub fn clear(&self) {
        self.json.clear();
        self.stored.clear();
    }

    pub fn stats(&self) -> [CacheStats; 2] {
        [self.json.stats(), self.stored.stats()]
    }
}

/// Frame PNGs by content hash. Frames never change, so entries never go stale; the bound is
/// only for memory.
pub struct FrameCache(BoundedCache<String, Bytes>);

impl FrameCache {
    pub fn new(bytes: u64) -> FrameCache {
        FrameCache(BoundedCache::by_bytes("frames", bytes, |k, v| {
            (k.len() + v.len() + 64) as u64
        }))
    }

    pub fn get(&self, sha256: &str) -> Option<Bytes> {
        self.0.get(&sha256.to_owned())
    }

    pub fn insert(&self, sha256: &str, png: Bytes) {
        self.0.insert(sha256.to_owned(), png);
    }

    pub fn stats(&self) -> CacheStats {
        self.0.stats()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_byte_bound_holds_and_hits_are_counted() {
        let cache = FrameCache::new(10_000);
        for i in 0..100 {
            cache.insert(&format!("{i:064}"), Bytes::from(vec![0u8; 1_000]));
        }
        let stats = cache.stats();
        assert!(stats.weight <= 10_000, "{stats:?}");
        assert!(stats.entries <= 10, "{stats:?}");
        let kept = (0..100)
            .filter(|i| cache.get(&format!("{i:064}")).is_some())
            .count();
        let stats = cache.stats();
        assert_eq!(stats.hits as usize, kept);
        assert_eq!(stats.misses as usize, 100 - kept);
        assert_eq!(stats.hit_rate(), Some(kept as f64 / 100.0));
    }

    #[test]
    fn an_entry_bound_holds_and_clearing_empties() {
        let cache: BoundedCache<u32, u32> = BoundedCache::by_entries("test", 50);
        for i in 0..1_000 {
            cache.insert(i, i);
        }
        assert!(cache.stats().entries <= 50);
        cache.clear();
        assert!((0..1_000).all(|i| cache.get(&i).is_none()));
    }
}
