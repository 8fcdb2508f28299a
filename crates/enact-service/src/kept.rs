//! What the use cases keep on a hub: their caches (a leaderboard, an annotator's standings,
//! scoring targets) and their settings (a signing key, the endpoint keys a model run may use),
//! each a type of the use case's own, one of each per hub and shared by its clones.
//!
//! The hub does not name them: a use case asks for its own type ([`crate::Hub::kept`]), which
//! is made on first use ([`Kept::make`]), or set before serving ([`crate::Hub::with_kept`]).
//! Every kept value hears each change this process commits or another announces
//! ([`Kept::forget_stale`]), so a cache kept here is cleared exactly as the hub's own are.

use std::any::{Any, TypeId};
use std::collections::HashMap;
use std::sync::{Arc, RwLock};

use crate::Hub;
use crate::cache::CacheStats;
use crate::changes::Change;

/// State a use case keeps on the hub.
pub trait Kept: Any + Send + Sync {
    /// The value a hub starts with, made from its settings (its cache limits, its database)
    /// the first time it is asked for.
    fn make(hub: &Hub) -> Self
    where
        Self: Sized;

    /// Drops what `change` made stale: a change this process committed, one another process
    /// announced, or [`Change::Everything`] when stored items changed or announcements were
    /// missed.
    fn forget_stale(&self, _change: &Change) {}

    /// The figures of the caches it holds, for the log and the metrics.
    fn stats(&self) -> Vec<CacheStats> {
        Vec::new()
    }
}

struct Entry {
    value: Arc<dyn Kept>,
    /// Set before serving ([`crate::Hub::with_kept`]) rather than made on first use: kept when
    /// the caches are rebuilt to new limits.
    set: bool,
}

/// Every kept value of a hub, by type.
#[derive(Default)]
pub(crate) struct KeptValues {
    by_type: RwLock<HashMap<TypeId, Entry>>,
}

impl KeptValues {
    fn read(&self) -> std::sync::RwLockReadGuard<'_, HashMap<TypeId, Entry>> {
        self.by_type.read().unwrap_or_else(|p| p.into_inner())
    }

    fn write(&self) -> std::sync::RwLockWriteGuard<'_, HashMap<TypeId, Entry>> {
        self.by_type.write().unwrap_or_else(|p| p.into_inner())
    }

    pub(crate) fn get<T: Kept>(&self) -> Option<Arc<T>> {
        let value = self.read().get(&TypeId::of::<T>())?.value.clone();
        Some(downcast(value))
    }

    /// `made`, unless another caller put one first (then theirs, so that every clone of the
    /// hub shares one).
    pub(crate) fn insert_made<T: Kept>(&self, made: T) -> Arc<T> {
        let mut by_type = self.write();
        let entry = by_type.entry(TypeId::of::<T>()).or_insert_with(|| Entry {
            value: Arc::new(made),
            set: false,
        });
        downcast(entry.value.clone())
    }

    /// A copy holding what this holds, with `value` set in place of any `T`.
    pub(crate) fn with<T: Kept>(&self, value: T) -> KeptValues {
        let mut copy = self.copy(|_| true);
        copy.by_type
            .get_mut()
            .unwrap_or_else(|p| p.into_inner())
            .insert(
                TypeId::of::<T>(),
                Entry {
                    value: Arc::new(value),
                    set: true,
                },
            );
        copy
    }

    /// A copy holding only what was set: what is made on first use is made again.
    pub(crate) fn settings_only(&self) -> KeptValues {
        self.copy(|entry| entry.set)
    }

    fn copy(&self, keep: impl Fn(&Entry) -> bool) -> KeptValues {
        let by_type = self
            .read()
            .iter()
            .filter(|(_, entry)| keep(entry))
            .map(|(id, entry)| {
                let entry = Entry {
                    value: entry.value.clone(),
                    set: entry.set,
                };
                (*id, entry)
            })
            .collect();
        KeptValues {
            by_type: RwLock::new(by_type),
        }
    }

    pub(crate) fn forget_stale(&self, change: &Change) {
        for entry in self.read().values() {
            entry.value.forget_stale(change);
        }
    }

    pub(crate) fn stats(&self) -> Vec<CacheStats> {
        let mut all: Vec<CacheStats> = self
            .read()
            .values()
            .flat_map(|entry| entry.value.stats())
            .collect();
        // The map's order is arbitrary; the log's and the metrics' is not.
        all.sort_by(|a, b| a.name.cmp(b.name));
        all
    }
}

fn downcast<T: Kept>(value: Arc<dyn Kept>) -> Arc<T> {
    let any: Arc<dyn Any + Send + Sync> = value;
    match any.downcast::<T>() {
        Ok(value) => value,
        // Entries are stored under their own type's id.
        Err(_) => unreachable!("a kept value is stored under another type's id"),
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicU64, Ordering};

    use super::*;

    #[derive(Default)]
    struct Counter {
        forgotten: AtomicU64,
        made_with: u64,
    }

    impl Kept for Counter {
        fn make(hub: &Hub) -> Self {
            Counter {
                forgotten: AtomicU64::new(0),
                made_with: hub.cache_limits().board_datasets,
            }
        }

        fn forget_stale(&self, _change: &Change) {
            self.forgotten.fetch_add(1, Ordering::SeqCst);
        }
    }

    struct Setting(&'static str);

    impl Kept for Setting {
        fn make(_hub: &Hub) -> Self {
            Setting("made")
        }
    }

    async fn hub() -> (tempfile::TempDir, Hub) {
        let dir = tempfile::tempdir().expect("tempdir");
        let hub = Hub::open(&dir.path().join("hub.db")).await.expect("open");
        (dir, hub)
    }

    #[tokio::test]
    async fn a_kept_value_is_made_once_and_shared_by_every_clone() {
        let (_dir, hub) = hub().await;
        let clone = hub.clone();
        let first = hub.kept::<Counter>();
        assert!(Arc::ptr_eq(&first, &clone.kept::<Counter>()));
        assert_eq!(
            first.made_with,
            crate::cache::CacheLimits::default().board_datasets
        );
        hub.forget_stale(&Change::Boards);
        assert_eq!(clone.kept::<Counter>().forgotten.load(Ordering::SeqCst), 1);
    }

    #[tokio::test]
    async fn a_set_value_outlives_new_cache_limits_and_a_made_one_is_made_again() {
        let (_dir, hub) = hub().await;
        let made = hub.kept::<Counter>();
        let limits = crate::cache::CacheLimits {
            board_datasets: 3,
            ..Default::default()
        };
        let hub = hub.with_kept(Setting("set")).with_cache_limits(&limits);
        assert_eq!(hub.kept::<Setting>().0, "set");
        let remade = hub.kept::<Counter>();
        assert!(!Arc::ptr_eq(&made, &remade));
        assert_eq!(remade.made_with, 3);
    }
}
