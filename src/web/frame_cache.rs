//! A bounded in-memory cache of frame PNGs.
//!
//! Frames are immutable and addressed by content hash, so entries never go stale; the cache only
//! bounds memory. Eviction is first-in first-out, which is enough for content that annotators and
//! clients request in dataset order.

use std::collections::{HashMap, VecDeque};
use std::sync::Mutex;

use axum::body::Bytes;

pub struct FrameCache {
    budget_bytes: usize,
    state: Mutex<CacheState>,
}

#[derive(Default)]
struct CacheState {
    entries: HashMap<String, Bytes>,
    order: VecDeque<String>,
    bytes: usize,
}

impl FrameCache {
    pub fn new(budget_bytes: usize) -> Self {
        FrameCache {
            budget_bytes,
            state: Mutex::new(CacheState::default()),
        }
    }

    pub fn get(&self, sha256: &str) -> Option<Bytes> {
        let state = self
            .state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        state.entries.get(sha256).cloned()
    }

    pub fn insert(&self, sha256: &str, png: Bytes) {
        if png.len() > self.budget_bytes {
            return;
        }
        let mut state = self
            .state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        if state.entries.contains_key(sha256) {
            return;
        }
        while state.bytes + png.len() > self.budget_bytes {
            let Some(oldest) = state.order.pop_front() else {
                break;
            };
            if let Some(evicted) = state.entries.remove(&oldest) {
                state.bytes -= evicted.len();
            }
        }
        state.bytes += png.len();
        state.order.push_back(sha256.to_owned());
        state.entries.insert(sha256.to_owned(), png);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evicts_oldest_entries_to_stay_within_budget() {
        let cache = FrameCache::new(10);
        cache.insert("a", Bytes::from_static(b"12345"));
        cache.insert("b", Bytes::from_static(b"12345"));
        cache.insert("c", Bytes::from_static(b"123"));
        assert!(cache.get("a").is_none());
        assert_eq!(cache.get("b").as_deref(), Some(&b"12345"[..]));
        assert_eq!(cache.get("c").as_deref(), Some(&b"123"[..]));
    }

    #[test]
    fn entries_larger_than_the_budget_are_not_kept() {
        let cache = FrameCache::new(4);
        cache.insert("big", Bytes::from_static(b"12345"));
        assert!(cache.get("big").is_none());
    }
}
