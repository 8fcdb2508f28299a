//! The one place CPU-heavy work runs: scoring submissions and files, building scoring targets,
//! rescoring, error analyses, agreement and study reports, quality figures and an import's
//! validation and hashing. A dedicated rayon pool of a few threads (the core's own parallel
//! loops run on it too, not on rayon's global pool), in front of it a bounded number of places.
//!
//! Why: on a small machine a handful of 8,972-line submissions keep every core busy, and the
//! annotators' page loads and answers, which need a millisecond of CPU each, wait behind them.
//! On Linux each pool thread lowers its own scheduling priority (`nice`, 10 by default), so
//! heavy work still uses every core when nothing else runs but the request threads get a core
//! as soon as they wake. Work asked for by a request is refused with `503` and `Retry-After`
//! when every place is taken ([`HeavyPool::run`]), rather than queueing without end and making
//! every submitter wait longer; long work that must go on (an import's batches, a job) waits
//! for a place instead ([`HeavyPool::run_waiting`]).

use std::panic::AssertUnwindSafe;
use std::sync::{Arc, OnceLock};

use tokio::sync::{OwnedSemaphorePermit, Semaphore};

use super::metrics::HeavyMetrics;

/// How large the heavy-work pool is (`serve --heavy-threads`, `--heavy-queue`, `--heavy-nice`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HeavyLimits {
    /// Threads doing heavy work at once.
    pub threads: usize,
    /// Pieces of work waiting for a thread beyond those running; one more is refused.
    pub queue: usize,
    /// The pool threads' `nice` value on Linux (0 to 19; 0 leaves them at the server's
    /// priority). Ignored elsewhere.
    pub nice: i32,
}

impl Default for HeavyLimits {
    fn default() -> Self {
        HeavyLimits {
            threads: std::thread::available_parallelism().map_or(2, usize::from),
            queue: 32,
            nice: 10,
        }
    }
}

impl HeavyLimits {
    /// The limits, or what is wrong with them.
    pub fn checked(self) -> Result<HeavyLimits, String> {
        if self.threads == 0 {
            return Err("the heavy-work pool needs at least one thread".into());
        }
        if !(0..=19).contains(&self.nice) {
            return Err(format!(
                "the heavy-work threads' nice value must be 0 to 19, not {}",
                self.nice
            ));
        }
        Ok(self)
    }
}

/// Work refused because every place in the pool is taken.
#[derive(Debug, thiserror::Error)]
#[error(
    "the server is busy with heavy work ({running} running, {queued} waiting, the most it takes); nothing was done, retry in a moment"
)]
pub struct HeavyBusy {
    running: i64,
    queued: i64,
}

/// The pool, shared by every clone of a hub.
#[derive(Clone)]
pub struct HeavyPool {
    inner: Arc<Inner>,
}

struct Inner {
    limits: HeavyLimits,
    /// Built at the first piece of work: most hubs a test or a command opens never need it.
    pool: OnceLock<Result<rayon::ThreadPool, String>>,
    /// One permit per place: `threads` running plus `queue` waiting.
    places: Arc<Semaphore>,
    metrics: HeavyMetrics,
}

impl HeavyPool {
    pub fn new(limits: HeavyLimits, metrics: HeavyMetrics) -> HeavyPool {
        HeavyPool {
            inner: Arc::new(Inner {
                limits,
                pool: OnceLock::new(),
                places: Arc::new(Semaphore::new(limits.threads + limits.queue)),
                metrics,
            }),
        }
    }

    pub fn limits(&self) -> HeavyLimits {
        self.inner.limits
    }

    /// Runs `work` on the pool and returns its result (a panic in it is resumed here, as a
    /// direct call would). Refused at once when every place is taken.
    pub async fn run<T, F>(&self, work: F) -> Result<T, HeavyBusy>
    where
        T: Send + 'static,
        F: FnOnce() -> T + Send + 'static,
    {
        let place = match self.inner.places.clone().try_acquire_owned() {
            Ok(place) => place,
            Err(_) => {
                self.inner.metrics.refused.inc();
                return Err(HeavyBusy {
                    running: self.inner.metrics.running.get(),
                    queued: self.inner.metrics.queued.get(),
                });
            }
        };
        Ok(self.start(place, work).await)
    }

    /// Runs `work` on the pool, first waiting for a place when every one is taken: for long
    /// work that has already begun and must not fail halfway (an import's next batch, a job).
    pub async fn run_waiting<T, F>(&self, work: F) -> T
    where
        T: Send + 'static,
        F: FnOnce() -> T + Send + 'static,
    {
        match self.inner.places.clone().acquire_owned().await {
            Ok(place) => self.start(place, work).await,
            // The semaphore is never closed; should it be, the work still runs.
            Err(_) => work(),
        }
    }

    async fn start<T, F>(&self, place: OwnedSemaphorePermit, work: F) -> T
    where
        T: Send + 'static,
        F: FnOnce() -> T + Send + 'static,
    {
        let pool = match self.pool() {
            Ok(pool) => pool,
            Err(e) => {
                // Threads could not be made (a resource limit): the work runs where it was
                // asked for rather than not at all.
                tracing::warn!(error = %e, "no heavy-work pool; running on a blocking thread");
                drop(place);
                return match tokio::task::spawn_blocking(work).await {
                    Ok(done) => done,
                    Err(e) => std::panic::resume_unwind(e.into_panic()),
                };
            }
        };
        let metrics = self.inner.metrics.clone();
        metrics.queued.inc();
        let (sender, receiver) = tokio::sync::oneshot::channel();
        pool.spawn(move || {
            metrics.queued.dec();
            metrics.running.inc();
            let outcome = std::panic::catch_unwind(AssertUnwindSafe(work));
            metrics.running.dec();
            metrics.done.inc();
            // The place is free before the caller hears, so a caller that goes on to ask
            // again finds it free. Dropped even if the caller stopped waiting (its request
            // timed out or was cancelled): the work itself ran to its end.
            drop(place);
            let _ = sender.send(outcome);
        });
        match receiver.await {
            Ok(Ok(done)) => done,
            Ok(Err(panic)) => std::panic::resume_unwind(panic),
            // The closure always sends unless the pool dropped it unrun, which rayon does
            // not do while the pool is alive (this hub holds it).
            Err(_) => panic!("the heavy-work pool dropped a piece of work"),
        }
    }

    fn pool(&self) -> Result<&rayon::ThreadPool, &str> {
        let limits = self.inner.limits;
        self.inner
            .pool
            .get_or_init(|| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(limits.threads)
                    .thread_name(|i| format!("enact-heavy-{i}"))
                    .start_handler(move |_| lower_priority(limits.nice))
                    .build()
                    .map_err(|e| e.to_string())
            })
            .as_ref()
            .map_err(String::as_str)
    }
}

/// Lowers the calling thread's scheduling priority to `nice` (Linux gives each thread its own
/// nice value; raising it needs no privilege).
#[cfg(target_os = "linux")]
fn lower_priority(nice: i32) {
    if nice == 0 {
        return;
    }
    let thread = rustix::thread::gettid();
    if let Err(e) = rustix::process::setpriority_process(Some(thread), nice) {
        tracing::warn!(nice, error = %e, "cannot lower a heavy-work thread's priority");
    }
}

#[cfg(not(target_os = "linux"))]
fn lower_priority(_nice: i32) {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_are_checked() {
        let ok = HeavyLimits {
            threads: 1,
            queue: 0,
            nice: 19,
        };
        assert_eq!(ok.checked(), Ok(ok));
        assert!(
            HeavyLimits { threads: 0, ..ok }
                .checked()
                .unwrap_err()
                .contains("at least one thread")
        );
        assert!(
            HeavyLimits { nice: 20, ..ok }
                .checked()
                .unwrap_err()
                .contains("0 to 19")
        );
    }

    #[cfg(target_os = "linux")]
    #[tokio::test]
    async fn pool_threads_run_at_the_lower_priority() {
        let pool = HeavyPool::new(
            HeavyLimits {
                threads: 1,
                queue: 0,
                nice: 7,
            },
            HeavyMetrics::default(),
        );
        let nice = pool
            .run(|| rustix::process::getpriority_process(Some(rustix::thread::gettid())))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(nice, 7);
    }

    #[tokio::test]
    async fn a_full_pool_refuses_and_frees_its_places() {
        let metrics = HeavyMetrics::default();
        let pool = HeavyPool::new(
            HeavyLimits {
                threads: 1,
                queue: 1,
                nice: 0,
            },
            metrics.clone(),
        );
        let (release, blocked) = std::sync::mpsc::channel::<()>();
        let (started_tx, started) = tokio::sync::oneshot::channel();
        let running = tokio::spawn({
            let pool = pool.clone();
            async move {
                pool.run(move || {
                    let _ = started_tx.send(());
                    blocked.recv().is_ok()
                })
                .await
            }
        });
        started.await.unwrap();
        let waiting = tokio::spawn({
            let pool = pool.clone();
            async move { pool.run(|| 2).await }
        });
        while metrics.queued.get() < 1 {
            tokio::task::yield_now().await;
        }
        let refused = pool.run(|| 3).await.unwrap_err();
        assert_eq!(
            refused.to_string(),
            "the server is busy with heavy work (1 running, 1 waiting, the most it takes); nothing was done, retry in a moment"
        );
        assert_eq!(metrics.refused.get(), 1);
        release.send(()).unwrap();
        assert!(running.await.unwrap().unwrap());
        assert_eq!(waiting.await.unwrap().unwrap(), 2);
        assert_eq!(pool.run(|| 4).await.unwrap(), 4);
        assert_eq!(metrics.done.get(), 3);
        assert_eq!((metrics.running.get(), metrics.queued.get()), (0, 0));
    }
}
