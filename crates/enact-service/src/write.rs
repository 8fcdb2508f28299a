//! The unit of work every write goes through ([`Hub::write`]): one transaction in a lane of the
//! write gate, the changes it announces, and what its commit does in this process.
//!
//! The lane is always the caller's choice, there is no default: [`Lane::Interactive`] for a
//! request someone is waiting on (an annotator's save, a login), [`Lane::Bulk`] for many rows at
//! once or for background work (a submission's verdicts, a model run's replies, a job's
//! progress, an import's batches), which lets every waiting interactive write go first.

use std::ops::{Deref, DerefMut};

pub use crate::store::gate::Lane;

use crate::changes::Change;
use crate::store::db::{Connection, Handle};
use crate::{AppError, Hub, store};

/// A write transaction holding this process's turn in one lane of the write gate, and the
/// changes it announces. Store functions take it as they take any connection.
///
/// A change is announced inside the transaction ([`Write::announce`]: the change feed's row on
/// SQLite, `NOTIFY` on PostgreSQL, both delivered only if it commits), and applied to this
/// process's caches by [`Write::commit`] once the rows are durable: a change can neither be
/// seen before it is stored nor be stored without its announcement. Dropped without a commit,
/// it rolls back and announces nothing.
#[must_use = "a write is rolled back unless it is committed"]
pub struct Write {
    hub: Hub,
    tx: store::Tx,
    announced: Vec<Change>,
}

impl Hub {
    /// A write transaction in `lane`, serialised with every other writer of the database. A
    /// wait longer than the database's busy timeout fails as busy (503).
    pub async fn write(&self, lane: Lane) -> Result<Write, AppError> {
        let tx = self.begin_in(lane).await?;
        Ok(Write {
            hub: self.clone(),
            tx,
            announced: Vec::new(),
        })
    }
}

impl Write {
    /// Announces `change` to every instance and process (once, however often it is asked), and
    /// applies it to this process's caches when the write commits.
    pub async fn announce(&mut self, change: Change) -> Result<(), AppError> {
        if !self.announced.contains(&change) {
            self.hub.publish(&mut self.tx, &change).await?;
            self.announced.push(change);
        }
        Ok(())
    }

    /// Commits, then drops from this process's caches what the announced changes made stale.
    pub async fn commit(self) -> Result<(), AppError> {
        let Write { hub, tx, announced } = self;
        tx.commit().await?;
        for change in announced {
            hub.forget_stale(&change);
        }
        Ok(())
    }

    /// Rolls back: nothing is stored and nothing announced.
    pub async fn rollback(self) -> Result<(), AppError> {
        self.tx.rollback().await?;
        Ok(())
    }
}

impl Connection for Write {
    fn handle(&mut self) -> Handle<'_> {
        self.tx.handle()
    }
}

/// The store's write functions take a unit of work as they take its transaction.
impl store::Writes for Write {}

impl Deref for Write {
    type Target = store::Tx;

    fn deref(&self) -> &store::Tx {
        &self.tx
    }
}

impl DerefMut for Write {
    fn deref_mut(&mut self) -> &mut store::Tx {
        &mut self.tx
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicU64, Ordering};

    use super::*;
    use crate::Kept;

    /// Counts the board changes this process applied, as the leaderboard's cache would.
    #[derive(Default)]
    struct BoardChanges(AtomicU64);

    impl Kept for BoardChanges {
        fn make(_hub: &Hub) -> Self {
            BoardChanges::default()
        }

        fn forget_stale(&self, change: &Change) {
            if *change == Change::Boards {
                self.0.fetch_add(1, Ordering::SeqCst);
            }
        }
    }

    fn board_changes(hub: &Hub) -> u64 {
        hub.kept::<BoardChanges>().0.load(Ordering::SeqCst)
    }

    async fn hub() -> (tempfile::TempDir, Hub) {
        let dir = tempfile::tempdir().expect("tempdir");
        let hub = Hub::open(&dir.path().join("hub.db")).await.expect("open");
        (dir, hub)
    }

    /// What the change feed holds (SQLite's announcements to other processes).
    async fn feed(hub: &Hub) -> Vec<String> {
        let mut conn = hub.conn().await.expect("conn");
        store::announcements_after(&mut conn, 0, 100)
            .await
            .expect("feed")
            .into_iter()
            .map(|a| a.payload)
            .collect()
    }

    #[tokio::test]
    async fn a_committed_write_announces_each_change_once_and_applies_it_here_after_commit() {
        let (_dir, hub) = hub().await;
        let before = board_changes(&hub);
        let mut write = hub.write(Lane::Interactive).await.expect("write");
        write.announce(Change::Boards).await.expect("announce");
        write
            .announce(Change::Boards)
            .await
            .expect("announce again");
        write
            .announce(Change::Standing {
                annotator: 3,
                item: 17,
            })
            .await
            .expect("announce a standing");
        assert_eq!(board_changes(&hub), before, "applied before commit");
        write.commit().await.expect("commit");
        assert_eq!(feed(&hub).await, ["boards", "standing 3 17"]);
        assert_eq!(board_changes(&hub), before + 1);
    }

    #[tokio::test]
    async fn a_write_dropped_or_rolled_back_announces_nothing_and_gives_its_turn_back() {
        let (_dir, hub) = hub().await;
        let before = board_changes(&hub);
        {
            let mut dropped = hub.write(Lane::Bulk).await.expect("write");
            dropped.announce(Change::Boards).await.expect("announce");
        }
        let mut rolled_back = hub.write(Lane::Interactive).await.expect("write");
        rolled_back
            .announce(Change::Boards)
            .await
            .expect("announce");
        rolled_back.rollback().await.expect("rollback");
        assert!(feed(&hub).await.is_empty());
        assert_eq!(board_changes(&hub), before);
        // Neither kept the gate: the next writer gets in at once.
        let next = tokio::time::timeout(
            std::time::Duration::from_secs(5),
            hub.write(Lane::Interactive),
        )
        .await
        .expect("the gate was given back")
        .expect("write");
        next.commit().await.expect("commit");
    }
}
