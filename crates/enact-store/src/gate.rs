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
//!
//! Bulk writes age, so that an unbroken stream of interactive writes cannot starve them into
//! the 503 of a 10 s wait. **The bound**: the bulk writer at the front of its queue gets the
//! turn at the first hand-over at least [`BULK_AGE`] after both it joined the queue and the
//! previous bulk turn ended; that is, within `BULK_AGE` plus the one interactive turn under
//! way then. The other side of it: while interactive writers wait, bulk turns start at least
//! `BULK_AGE` after the previous bulk turn ended, so an annotator's write waits for at most one
//! bulk turn (the one under way, or one that came due) and interactive writes keep at least
//! `BULK_AGE / (BULK_AGE + longest bulk turn)` of the time when both lanes are full.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use tokio::sync::oneshot;

/// How long the bulk writer at the front of its queue lets interactive writers go first,
/// counted from when it joined or the previous bulk turn ended, whichever is later. A bulk
/// turn (a full-size submission's verdicts, an import batch) holds the lock for about 60 ms;
/// at this age a full interactive lane keeps about three quarters of the time or more, and a
/// bulk writer at the front waits a fifth of a second, not the 10 s that end in a 503.
pub const BULK_AGE: Duration = Duration::from_millis(200);

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
#[derive(Clone)]
pub struct WriteGate {
    state: Arc<Mutex<State>>,
    observer: Option<HeldObserver>,
    bulk_age: Duration,
}

impl Default for WriteGate {
    fn default() -> WriteGate {
        WriteGate {
            state: Arc::default(),
            observer: None,
            bulk_age: BULK_AGE,
        }
    }
}

/// Invariant: when `held` is false both queues are empty (a release hands the turn to the
/// first waiter still there, or clears `held`).
#[derive(Default)]
struct State {
    held: bool,
    interactive: VecDeque<oneshot::Sender<()>>,
    /// Bulk writers with the time each joined the queue.
    bulk: VecDeque<(Instant, oneshot::Sender<()>)>,
    /// When the last bulk turn ended: the front bulk writer's age counts from here at the
    /// earliest.
    bulk_ended: Option<Instant>,
}

impl State {
    /// Whether the front bulk writer has let interactive writers go first for `age`.
    fn bulk_due(&self, now: Instant, age: Duration) -> bool {
        self.bulk.front().is_some_and(|(joined, _)| {
            let since = self.bulk_ended.map_or(*joined, |ended| ended.max(*joined));
            now.saturating_duration_since(since) >= age
        })
    }
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
        self.gate.pass_on(Some(self.lane));
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
                // A turn never used: no bulk write held it.
                self.gate.pass_on(None);
            } else {
                let mut state = self.gate.lock();
                state.interactive.retain(|s| !s.is_closed());
                state.bulk.retain(|(_, s)| !s.is_closed());
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

    /// This gate with bulk writers ageing after `age` instead of [`BULK_AGE`].
    pub fn with_bulk_age(self, age: Duration) -> WriteGate {
        WriteGate {
            bulk_age: age,
            ..self
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
                Lane::Bulk => state.bulk.push_back((Instant::now(), sender)),
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

    /// Hands the turn on, when a turn of `ended` (none: a turn handed to a writer that had
    /// gone) is over: to the front bulk writer if it has aged ([`BULK_AGE`]), else to the first
    /// interactive writer still waiting, else to the first bulk one, else frees the gate.
    fn pass_on(&self, ended: Option<Lane>) {
        let mut state = self.lock();
        let now = Instant::now();
        if ended == Some(Lane::Bulk) {
            state.bulk_ended = Some(now);
        }
        loop {
            let next = if state.bulk_due(now, self.bulk_age) {
                state.bulk.pop_front().map(|(_, next)| next)
            } else {
                None
            };
            let next = match next.or_else(|| state.interactive.pop_front()) {
                Some(next) => next,
                None => match state.bulk.pop_front() {
                    Some((_, next)) => next,
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

    /// Writers queued one after the other, each noting its name when its turn comes.
    struct Queued {
        order: Arc<Mutex<Vec<&'static str>>>,
        tasks: Vec<tokio::task::JoinHandle<()>>,
    }

    impl Queued {
        /// The order the writers had their turns in, once all have.
        async fn order(self) -> Vec<&'static str> {
            for task in self.tasks {
                task.await.unwrap();
            }
            self.order.lock().unwrap().clone()
        }
    }

    async fn queue_up<const N: usize>(
        gate: &WriteGate,
        writers: [(&'static str, Lane); N],
    ) -> Queued {
        let order = Arc::new(Mutex::new(Vec::new()));
        let mut tasks = Vec::new();
        for (name, lane) in writers {
            let (gate, order) = (gate.clone(), order.clone());
            tasks.push(tokio::spawn(async move {
                let _turn = gate.enter(lane).await;
                order.lock().unwrap().push(name);
            }));
            settle().await;
        }
        Queued { order, tasks }
    }

    /// Long enough that no bulk writer ages during a test that does not mean it to.
    const NEVER: Duration = Duration::from_secs(3600);

    #[tokio::test]
    async fn an_interactive_writer_goes_before_bulk_writers_that_waited_longer() {
        let gate = WriteGate::default().with_bulk_age(NEVER);
        let first = gate.enter(Lane::Bulk).await;
        let queued = queue_up(
            &gate,
            [
                ("bulk 1", Lane::Bulk),
                ("bulk 2", Lane::Bulk),
                ("answer", Lane::Interactive),
            ],
        )
        .await;
        assert_eq!(gate.waiting(), (1, 2));
        drop(first);
        assert_eq!(queued.order().await, ["answer", "bulk 1", "bulk 2"]);
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

    #[tokio::test]
    async fn a_bulk_writer_that_has_aged_goes_before_interactive_ones() {
        let age = Duration::from_millis(30);
        let gate = WriteGate::default().with_bulk_age(age);
        let held = gate.enter(Lane::Interactive).await;
        let queued = queue_up(
            &gate,
            [
                ("bulk 1", Lane::Bulk),
                ("answer", Lane::Interactive),
                ("bulk 2", Lane::Bulk),
            ],
        )
        .await;
        assert_eq!(gate.waiting(), (1, 2));
        tokio::time::sleep(age * 2).await;
        drop(held);
        // The first bulk writer had aged; the second's age counts from the end of the first's
        // turn, so the answer goes before it.
        assert_eq!(queued.order().await, ["bulk 1", "answer", "bulk 2"]);
    }

    /// What an unbroken stream of interactive writes did while a bulk writer waited.
    struct Stream {
        /// When each interactive turn was seen to start.
        starts: Vec<Instant>,
        /// When the bulk writer asked for its turn, when it had certainly joined its queue,
        /// and when its turn started.
        bulk_asked: Instant,
        bulk_joined_by: Instant,
        bulk_started: Option<Instant>,
    }

    /// Interactive writers, each queued while the one before holds the turn (so the interactive
    /// queue is never empty at a hand-over), each holding it 1 ms; a bulk writer joins after
    /// a few turns. Runs until the bulk writer has had its turn and a few more interactive turns
    /// went, or until `deadline`.
    async fn stream_with_one_bulk_writer(gate: &WriteGate, deadline: Duration) -> Stream {
        let started = Instant::now();
        let mut starts = Vec::new();
        let mut turn = gate.enter(Lane::Interactive).await;
        let mut bulk: Option<tokio::task::JoinHandle<Instant>> = None;
        let (mut bulk_asked, mut bulk_joined_by) = (started, started);
        let mut bulk_started = None;
        let mut after_bulk = 0;
        while started.elapsed() < deadline && after_bulk < 5 {
            starts.push(Instant::now());
            let next = tokio::spawn({
                let gate = gate.clone();
                async move { gate.enter(Lane::Interactive).await }
            });
            while gate.waiting().0 == 0 {
                tokio::task::yield_now().await;
            }
            if starts.len() == 5 {
                bulk_asked = Instant::now();
                bulk = Some(tokio::spawn({
                    let gate = gate.clone();
                    async move {
                        let _turn = gate.enter(Lane::Bulk).await;
                        let started = Instant::now();
                        tokio::time::sleep(Duration::from_millis(1)).await;
                        started
                    }
                }));
                while gate.waiting().1 == 0 {
                    tokio::task::yield_now().await;
                }
                bulk_joined_by = Instant::now();
            }
            tokio::time::sleep(Duration::from_millis(1)).await;
            drop(turn);
            turn = next.await.unwrap();
            if let Some(task) = bulk.as_mut().filter(|t| t.is_finished()) {
                bulk_started = Some(task.await.unwrap());
                bulk = None;
            }
            if bulk_started.is_some() {
                after_bulk += 1;
            }
        }
        if let Some(task) = bulk {
            task.abort();
        }
        Stream {
            starts,
            bulk_asked,
            bulk_joined_by,
            bulk_started,
        }
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn under_an_unbroken_stream_of_interactive_writes_a_bulk_writer_gets_its_turn_within_the_bound()
     {
        let gate = WriteGate::default();
        let stream = stream_with_one_bulk_writer(&gate, Duration::from_secs(10)).await;
        let bulk_started = stream.bulk_started.unwrap_or_else(|| {
            panic!(
                "the bulk writer was starved: no turn in 10 s of {} interactive turns",
                stream.starts.len()
            )
        });
        // Not before its age: interactive writers went first meanwhile ...
        let waited = bulk_started - stream.bulk_asked;
        assert!(
            waited >= BULK_AGE,
            "the bulk writer went after {waited:?}, before it had aged {BULK_AGE:?}"
        );
        assert!(
            stream
                .starts
                .iter()
                .filter(|s| **s > stream.bulk_joined_by && **s < bulk_started)
                .count()
                > 1,
            "interactive writers went first while it aged"
        );
        // ... and at the first hand-over after it: at most one interactive turn (the one
        // handed over just before it came due) starts after it came due.
        let due = stream.bulk_joined_by + BULK_AGE;
        let late = stream
            .starts
            .iter()
            .filter(|s| **s > due && **s < bulk_started)
            .count();
        assert!(
            late <= 1,
            "{late} interactive turns started after the bulk writer came due ({waited:?} wait)"
        );
        // The stream went on after it.
        assert!(stream.starts.iter().any(|s| *s > bulk_started));
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn without_ageing_the_same_stream_starves_the_bulk_writer() {
        // The rig of the test above can fail: with bulk writers that never age, the stream
        // keeps the turn for as long as it runs.
        let gate = WriteGate::default().with_bulk_age(NEVER);
        let stream = stream_with_one_bulk_writer(&gate, Duration::from_secs(1)).await;
        assert!(stream.bulk_started.is_none());
        assert!(stream.starts.len() > 10, "{} turns", stream.starts.len());
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
