//! Annotators' standing on their assigned items (finished or not, and the draft) kept in memory
//! for the item page, which is read far more often than drafts are saved.
//!
//! Only this process writes drafts and answers, and every handler that writes one calls
//! [`StandingCache::forget`] after its commit. A reader stores what it read only if nothing was
//! forgotten while it was reading, so a slow read can never put back a state older than a write.
//! "Not assigned" is never stored, so new assignments need no notice. Imports, which may delete
//! items and reuse their row ids, clear the whole cache through the content-generation watcher.

use std::sync::Mutex;

use super::cache::{BoundedCache, CacheLimits, CacheStats};
use super::changes::Change;
use crate::core::annotation::AssignmentState;

pub struct StandingCache {
    /// By (annotator id, item row id).
    entries: BoundedCache<(i64, i64), AssignmentState>,
    /// Counts forgets; a reader's ticket is this count when it started reading the store. Held
    /// while remembering and forgetting, so a check and its insert are one step.
    forgets: Mutex<u64>,
}

impl Default for StandingCache {
    fn default() -> Self {
        StandingCache::new(CacheLimits::default().standing_entries)
    }
}

/// Taken before reading the store; [`StandingCache::remember`] refuses a stale one.
#[derive(Debug, Clone, Copy)]
pub struct ReadTicket(u64);

/// The item page's standings, dropped as drafts and answers are written here or announced
/// from elsewhere, and all of them when stored items change.
impl crate::Kept for StandingCache {
    fn make(hub: &crate::Hub) -> Self {
        StandingCache::new(hub.cache_limits().standing_entries)
    }

    fn forget_stale(&self, change: &Change) {
        match change {
            Change::Standing { annotator, item } => self.forget(*annotator, *item),
            Change::Everything => self.clear(),
            Change::Boards | Change::SessionEnded(_) => {}
        }
    }

    fn stats(&self) -> Vec<CacheStats> {
        vec![StandingCache::stats(self)]
    }
}

impl StandingCache {
    /// At most `max_entries` standings.
    pub fn new(max_entries: u64) -> StandingCache {
        StandingCache {
            entries: BoundedCache::by_entries("standings", max_entries),
            forgets: Mutex::new(0),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, u64> {
        self.forgets.lock().unwrap_or_else(|p| p.into_inner())
    }

    pub fn get(&self, annotator: i64, item: i64) -> Option<AssignmentState> {
        self.entries.get(&(annotator, item))
    }

    pub fn ticket(&self) -> ReadTicket {
        ReadTicket(*self.lock())
    }

    /// Stores a state read from the store after `ticket` was taken, unless something was
    /// forgotten since (the read may then predate a write).
    pub fn remember(&self, ticket: ReadTicket, annotator: i64, item: i64, state: AssignmentState) {
        let forgets = self.lock();
        if *forgets == ticket.0 {
            self.entries.insert((annotator, item), state);
        }
    }

    /// Drops what is known of one annotator's item; call after writing its draft or answer.
    pub fn forget(&self, annotator: i64, item: i64) {
        let mut forgets = self.lock();
        self.entries.remove(&(annotator, item));
        *forgets += 1;
    }

    pub fn clear(&self) {
        let mut forgets = self.lock();
        self.entries.clear();
        *forgets += 1;
    }

    pub fn stats(&self) -> CacheStats {
        self.entries.stats()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::annotation::Draft;
    use crate::core::annotation::StoredDraft;
    use crate::core::dataset::StepLength;

    fn state(started_at_ms: i64) -> AssignmentState {
        AssignmentState {
            finished: false,
            draft: Some(StoredDraft {
                draft: Draft::empty(StepLength::new(3).unwrap()),
                started_at_ms,
                first_placement_at_ms: None,
            }),
        }
    }

    fn started(cache: &StandingCache, annotator: i64, item: i64) -> Option<i64> {
        cache
            .get(annotator, item)
            .and_then(|s| s.draft)
            .map(|d| d.started_at_ms)
    }

    #[test]
    fn a_read_is_remembered_until_its_item_is_forgotten() {
        let cache = StandingCache::default();
        let ticket = cache.ticket();
        cache.remember(ticket, 1, 10, state(5));
        assert_eq!(started(&cache, 1, 10), Some(5));
        assert_eq!(started(&cache, 2, 10), None, "keyed by annotator too");
        cache.forget(1, 10);
        assert_eq!(started(&cache, 1, 10), None);
    }

    #[test]
    fn a_read_overtaken_by_a_write_is_not_remembered() {
        let cache = StandingCache::default();
        let slow_reader = cache.ticket();
        // A save commits and forgets while the reader still holds the old state.
        cache.forget(1, 10);
        cache.remember(slow_reader, 1, 10, state(1));
        assert_eq!(started(&cache, 1, 10), None);
        let fresh = cache.ticket();
        cache.remember(fresh, 1, 10, state(2));
        assert_eq!(started(&cache, 1, 10), Some(2));
    }

    #[test]
    fn clearing_drops_everything_and_outdates_tickets() {
        let cache = StandingCache::default();
        let ticket = cache.ticket();
        cache.remember(ticket, 1, 10, state(1));
        cache.clear();
        assert_eq!(started(&cache, 1, 10), None);
        cache.remember(ticket, 1, 11, state(1));
        assert_eq!(started(&cache, 1, 11), None);
    }
}
