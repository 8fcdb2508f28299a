//! The order in which one process's writers take the database's single write lock.
//!
//! SQLite has one write lock and hands it out by polling: a writer that finds it taken sleeps
//! 1, 2, 5, 10 … up to 100 ms between tries, on a pooled connection it keeps the whole time.
//! Under load that turns a 60 ms wait into 80 ms or more, the sleepers hold connections that
//! readers need, and a bulk write (a full-size submission's verdicts, an import batch) is as
//! likely to get the lock next as an annotator's answer. The gate queues this process's
//! writers before they take a connection: the lock passes from one to the next at once, and an
//! [`Lane::Interactive`] writer waiting goes before every [`Lane::Bulk`] one, so an annotator
//! waits for at most the one write holding the lock. Other processes (a command-line import)
//! still meet at the database's own lock, which the gate does not replace.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use tokio::sync::oneshot;

/// Which queue a writer waits in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lane {
    /// A request someone is waiting on: an answer, a draft, a quota count, an admin's change.
    Interactive,
    /// Many rows at once, where a few more milliseconds do not matter: a submission's
    /// verdicts, rescoring, an import's batches and cut-over.
    Bulk,
}

/// Told how long each turn to write was held, and in which lane.
pub type HeldObserver = Arc<dyn Fn(Lane, Duration) + Send + Sync>;

/// The gate; clones share it.
#[derive(Clone, Default)]
pub struct WriteGate {
    state: Arc<Mutex<State>>,
    observer: Option<HeldObserver>,
}

/// Invariant: when `held` is false both queues are empty (a release hands the turn to the
/// first waiter still there, or clears `held`).
#[derive(Default)]
struct State {
    held: bool,
    interactive: VecDeque<oneshot::Sender<()>>,
    bulk: VecDeque<oneshot::Sender<()>>,
}

/// The right to write, until dropped.
#[must_use]
pub struct WriteTurn {
    gate: WriteGate,
    lane: Lane,
    since: Instant,
}

impl Drop for WriteTurn {
    fn drop(&mut self) {
        self.gate.pass_on();
        if let Some(observer) = &self.gate.observer {
            observer(self.lane, self.since.elapsed());
        }
    }
}

/// A writer in a queue. Dropped before its turn came (a timeout, a cancelled request), it
/// leaves the queue; dropped after the turn was handed to it but before it saw it, it passes
/// the turn on, so no turn is ever lost.
struct Waiting<'g> {
    gate: &'g WriteGate,
    turn: Option<oneshot::Receiver<()>>,
}

impl Drop for Waiting<'_> {
    fn drop(&mut self) {
        if let Some(mut turn) = self.turn.take() {
            turn.close();
            if turn.try_recv().is_ok() {
                self.gate.pass_on();
            } else {
                let mut state = self.gate.lock();
                state.interactive.retain(|s| !s.is_closed());
                state.bulk.retain(|s| !s.is_closed());
            }
        }
    }
}

impl WriteGate {
    /// A gate that tells `observer` how long each turn was held.
    pub fn observed(observer: HeldObserver) -> WriteGate {
        WriteGate {
            observer: Some(observer),
            ..WriteGate::default()
        }
    }

    fn turn(&self, lane: Lane) -> WriteTurn {
        WriteTurn {
            gate: self.clone(),
            lane,
            since: Instant::now(),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, State> {
        // The state is a flag and two queues, consistent after every statement.
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Waits for this process's turn to write in `lane`.
    pub async fn enter(&self, lane: Lane) -> WriteTurn {
        let receiver = {
            let mut state = self.lock();
            if !state.held {
                state.held = true;
                return self.turn(lane);
            }
            let (sender, receiver) = oneshot::channel();
            match lane {
                Lane::Interactive => state.interactive.push_back(sender),
                Lane::Bulk => state.bulk.push_back(sender),
            }
            receiver
        };
        let mut waiting = Waiting {
            gate: self,
            turn: Some(receiver),
        };
        let receiver = waiting.turn.as_mut().expect("set above");
        // The sender is only dropped unsent by `pass_on` when this receiver is gone, so the
        // wait ends with the turn.
        let _ = receiver.await;
        waiting.turn = None;
        self.turn(lane)
    }

    /// Writers waiting, (interactive, bulk).
    pub fn waiting(&self) -> (usize, usize) {
        let state = self.lock();
        (state.interactive.len(), state.bulk.len())
    }

    /// Hands the turn to the first interactive writer still waiting, else the first bulk one,
    /// else frees the gate.
    fn pass_on(&self) {
        let mut state = self.lock();
        loop {
            let next = match state.interactive.pop_front() {
                Some(next) => next,
                None => match state.bulk.pop_front() {
                    Some(next) => next,
                    None => {
                        state.held = false;
                        return;
                    }
                },
            };
            if next.send(()).is_ok() {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    async fn settle() {
        for _ in 0..10 {
            tokio::task::yield_now().await;
        }
    }

    #[tokio::test]
    async fn an_interactive_writer_goes_before_bulk_writers_that_waited_longer() {
        let gate = WriteGate::default();
        let first = gate.enter(Lane::Bulk).await;
        let order = Arc::new(Mutex::new(Vec::new()));
        let mut tasks = Vec::new();
        for (name, lane) in [
            ("bulk 1", Lane::Bulk),
            ("bulk 2", Lane::Bulk),
            ("answer", Lane::Interactive),
        ] {
            let (gate, order) = (gate.clone(), order.clone());
            tasks.push(tokio::spawn(async move {
                let _turn = gate.enter(lane).await;
                order.lock().unwrap().push(name);
            }));
            settle().await;
        }
        assert_eq!(gate.waiting(), (1, 2));
        drop(first);
        for task in tasks {
            task.await.unwrap();
        }
        assert_eq!(*order.lock().unwrap(), ["answer", "bulk 1", "bulk 2"]);
        assert_eq!(gate.waiting(), (0, 0));
        let _again = gate.enter(Lane::Bulk).await;
    }

    #[tokio::test]
    async fn a_writer_that_gives_up_waiting_loses_no_turn() {
        let gate = WriteGate::default();
        let held = gate.enter(Lane::Interactive).await;
        let gave_up =
            tokio::time::timeout(Duration::from_millis(20), gate.enter(Lane::Interactive)).await;
        assert!(gave_up.is_err(), "the gate was held");
        assert_eq!(gate.waiting(), (0, 0), "the one who gave up left the queue");
        drop(held);
        // Free again: the next writer gets in at once.
        let _next = tokio::time::timeout(Duration::from_millis(500), gate.enter(Lane::Bulk))
            .await
            .expect("the gate was passed on, not lost");
    }

    #[tokio::test]
    async fn a_turn_handed_to_a_writer_dropped_before_it_looked_is_passed_on() {
        let gate = WriteGate::default();
        let held = gate.enter(Lane::Interactive).await;
        let mut first = Box::pin(gate.enter(Lane::Interactive));
        // Polled once: queued.
        assert!(futures_poll_once(first.as_mut()).await.is_none());
        let second = tokio::spawn({
            let gate = gate.clone();
            async move { gate.enter(Lane::Bulk).await }
        });
        settle().await;
        drop(held); // hands the turn to `first`, which never looks
        drop(first); // its drop must pass the turn to `second`
        let _turn = tokio::time::timeout(Duration::from_millis(500), second)
            .await
            .expect("the turn reached the second writer")
            .unwrap();
    }

    async fn futures_poll_once<F: std::future::Future + Unpin>(fut: F) -> Option<F::Output> {
        let mut fut = fut;
        std::future::poll_fn(|cx| {
            std::task::Poll::Ready(match std::pin::Pin::new(&mut fut).poll(cx) {
                std::task::Poll::Ready(v) => Some(v),
                std::task::Poll::Pending => None,
            })
        })
        .await
    }
}
