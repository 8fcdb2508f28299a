//! What an operator watches, in Prometheus' text format (`GET /metrics`): counters and
//! histograms each instance keeps in memory from its start (requests by route and status,
//! their latency, waits for a database connection and for a write transaction, how long write
//! transactions held the turn to write, submissions scored, annotator answers, failed logins),
//! and gauges read when scraped (the caches' sizes and hit counts, jobs by kind and state, and
//! the items done by each running job).
//!
//! Each [`Hub`] has its own registry, so servers in one process (tests) never count each
//! other's requests.

use std::time::Duration;

use prometheus_client::encoding::EncodeLabelSet;
use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::{Histogram, exponential_buckets};
use prometheus_client::registry::Registry;

use super::{AppError, Hub};
use crate::store;

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct RequestLabels {
    method: String,
    route: String,
    status: u16,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct RouteLabels {
    method: String,
    route: String,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct KindLabels {
    kind: String,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct LaneLabels {
    lane: String,
}

fn lane_labels(lane: store::gate::Lane) -> LaneLabels {
    let lane = match lane {
        store::gate::Lane::Interactive => "interactive",
        store::gate::Lane::Bulk => "bulk",
    };
    LaneLabels {
        lane: lane.to_owned(),
    }
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct JobLabels {
    kind: String,
    state: String,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct RunningJobLabels {
    job: String,
    kind: String,
}

#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
struct CacheLabels {
    cache: String,
}

/// How a login failed: a wrong annotator password, or an unknown or revoked API token.
#[derive(Debug, Clone, Copy)]
pub enum LoginFailure {
    Password,
    Token,
}

/// The heavy-work pool's gauges and counters, shared with the pool ([`super::heavy`]).
#[derive(Clone, Default)]
pub struct HeavyMetrics {
    pub(super) queued: Gauge,
    pub(super) running: Gauge,
    pub(super) refused: Counter,
    pub(super) done: Counter,
}

/// One instance's metrics.
pub struct Metrics {
    registry: Registry,
    requests: Family<RequestLabels, Counter>,
    latency: Family<RouteLabels, Histogram>,
    connection_wait: Histogram,
    write_wait: Family<LaneLabels, Histogram>,
    write_held: Family<LaneLabels, Histogram>,
    submissions_scored: Counter,
    annotator_answers: Counter,
    login_failures: Family<KindLabels, Counter>,
    jobs: Family<JobLabels, Gauge>,
    job_items_done: Family<RunningJobLabels, Gauge>,
    cache_entries: Family<CacheLabels, Gauge>,
    cache_hits: Family<CacheLabels, Gauge>,
    cache_misses: Family<CacheLabels, Gauge>,
    heavy: HeavyMetrics,
}

/// Seconds from 0.5 ms to about 16 s, doubling.
fn seconds_buckets() -> impl Iterator<Item = f64> {
    exponential_buckets(0.0005, 2.0, 16)
}

impl Default for Metrics {
    fn default() -> Self {
        let mut registry = Registry::with_prefix("enact_hub");
        let requests = Family::<RequestLabels, Counter>::default();
        registry.register(
            "http_requests",
            "HTTP requests answered, by method, route and status",
            requests.clone(),
        );
        let latency = Family::<RouteLabels, Histogram>::new_with_constructor(|| {
            Histogram::new(seconds_buckets())
        });
        registry.register(
            "http_request_duration_seconds",
            "Time to answer an HTTP request, by method and route",
            latency.clone(),
        );
        let connection_wait = Histogram::new(seconds_buckets());
        registry.register(
            "db_connection_wait_seconds",
            "Time a use case waited for a database connection from the pool",
            connection_wait.clone(),
        );
        let write_wait = Family::<LaneLabels, Histogram>::new_with_constructor(|| {
            Histogram::new(seconds_buckets())
        });
        registry.register(
            "db_write_wait_seconds",
            "Time to begin a write transaction (this instance's turn to write, a connection, then \
             the database's write lock), by lane: a bulk writer's wait is bounded by the write \
             gate's ageing",
            write_wait.clone(),
        );
        let write_held = Family::<LaneLabels, Histogram>::new_with_constructor(|| {
            Histogram::new(seconds_buckets())
        });
        registry.register(
            "db_write_held_seconds",
            "Time a write transaction kept this instance's turn to write (from the turn to its \
             commit or rollback), by lane: interactive (answers, drafts, quota counts, admin changes) \
             or bulk (submissions' verdicts, rescoring, import batches)",
            write_held.clone(),
        );
        let submissions_scored = Counter::default();
        registry.register(
            "submissions_scored",
            "Model submissions stored with their scores",
            submissions_scored.clone(),
        );
        let annotator_answers = Counter::default();
        registry.register(
            "annotator_answers",
            "Items finished by annotators",
            annotator_answers.clone(),
        );
        let login_failures = Family::<KindLabels, Counter>::default();
        registry.register(
            "login_failures",
            "Refused credentials: kind=password (an annotator's login), kind=token (an API token)",
            login_failures.clone(),
        );
        let jobs = Family::<JobLabels, Gauge>::default();
        registry.register(
            "jobs",
            "Background jobs (model runs, rescoring) by kind and state, as stored",
            jobs.clone(),
        );
        let job_items_done = Family::<RunningJobLabels, Gauge>::default();
        registry.register(
            "job_items_done",
            "Items done by each running job, from its stored progress",
            job_items_done.clone(),
        );
        let cache_entries = Family::<CacheLabels, Gauge>::default();
        registry.register(
            "cache_entries",
            "Entries held by each cache",
            cache_entries.clone(),
        );
        let cache_hits = Family::<CacheLabels, Gauge>::default();
        registry.register(
            "cache_hits",
            "Lookups each cache answered since the start",
            cache_hits.clone(),
        );
        let cache_misses = Family::<CacheLabels, Gauge>::default();
        registry.register(
            "cache_misses",
            "Lookups each cache could not answer since the start",
            cache_misses.clone(),
        );
        let heavy = HeavyMetrics::default();
        for (name, help, gauge) in [
            (
                "heavy_queued",
                "Heavy work (scoring, analyses, reports, imports' validation) waiting for a pool thread",
                &heavy.queued,
            ),
            (
                "heavy_running",
                "Heavy work running on the pool's threads",
                &heavy.running,
            ),
        ] {
            registry.register(name, help, gauge.clone());
        }
        for (name, help, counter) in [
            (
                "heavy_refused",
                "Heavy work refused with 503 because every place in the pool was taken",
                &heavy.refused,
            ),
            ("heavy_done", "Heavy work the pool finished", &heavy.done),
        ] {
            registry.register(name, help, counter.clone());
        }
        Metrics {
            registry,
            requests,
            latency,
            connection_wait,
            write_wait,
            write_held,
            submissions_scored,
            annotator_answers,
            login_failures,
            jobs,
            job_items_done,
            cache_entries,
            cache_hits,
            cache_misses,
            heavy,
        }
    }
}

impl Metrics {
    /// Counts an answered request (`route`: the route's pattern, never the raw path, so the
    /// label's values stay few).
    pub fn request(&self, method: &str, route: &str, status: u16, took: Duration) {
        self.requests
            .get_or_create(&RequestLabels {
                method: method.to_owned(),
                route: route.to_owned(),
                status,
            })
            .inc();
        self.latency
            .get_or_create(&RouteLabels {
                method: method.to_owned(),
                route: route.to_owned(),
            })
            .observe(took.as_secs_f64());
    }

    /// The heavy-work pool's gauges and counters, for the pool to move.
    pub(super) fn heavy(&self) -> HeavyMetrics {
        self.heavy.clone()
    }

    pub(super) fn connection_waited(&self, took: Duration) {
        self.connection_wait.observe(took.as_secs_f64());
    }

    pub(super) fn write_waited(&self, lane: store::gate::Lane, took: Duration) {
        self.write_wait
            .get_or_create(&lane_labels(lane))
            .observe(took.as_secs_f64());
    }

    pub(super) fn write_held(&self, lane: store::gate::Lane, took: Duration) {
        self.write_held
            .get_or_create(&lane_labels(lane))
            .observe(took.as_secs_f64());
    }

    pub fn submission_scored(&self) {
        self.submissions_scored.inc();
    }

    pub fn annotator_answered(&self) {
        self.annotator_answers.inc();
    }

    pub fn login_failed(&self, how: LoginFailure) {
        let kind = match how {
            LoginFailure::Password => "password",
            LoginFailure::Token => "token",
        };
        self.login_failures
            .get_or_create(&KindLabels {
                kind: kind.to_owned(),
            })
            .inc();
    }
}

/// Every metric in Prometheus' text format, the gauges read now.
pub async fn exposition(hub: &Hub) -> Result<String, AppError> {
    let metrics: &Metrics = hub.metrics();
    let mut conn = hub.conn().await?;
    let counts = store::jobs::counts(&mut conn).await?;
    let running = store::jobs::running(&mut conn).await?;
    drop(conn);
    metrics.jobs.clear();
    for (kind, state, n) in counts {
        metrics
            .jobs
            .get_or_create(&JobLabels { kind, state })
            .set(n);
    }
    metrics.job_items_done.clear();
    for job in running {
        let done = job
            .progress
            .as_deref()
            .and_then(|p| serde_json::from_str::<serde_json::Value>(p).ok())
            .and_then(|p| p.get("done").and_then(serde_json::Value::as_i64));
        if let Some(done) = done {
            metrics
                .job_items_done
                .get_or_create(&RunningJobLabels {
                    job: job.id.to_string(),
                    kind: job.kind.as_str().to_owned(),
                })
                .set(done);
        }
    }
    for stats in hub.caches().stats() {
        let labels = CacheLabels {
            cache: stats.name.to_owned(),
        };
        let gauge = |n: u64| i64::try_from(n).unwrap_or(i64::MAX);
        metrics
            .cache_entries
            .get_or_create(&labels)
            .set(gauge(stats.entries));
        metrics
            .cache_hits
            .get_or_create(&labels)
            .set(gauge(stats.hits));
        metrics
            .cache_misses
            .get_or_create(&labels)
            .set(gauge(stats.misses));
    }
    let mut text = String::new();
    prometheus_client::encoding::text::encode(&mut text, &metrics.registry)
        .map_err(|e| AppError::internal(format!("writing the metrics: {e}")))?;
    Ok(text)
}
