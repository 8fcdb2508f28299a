//! `GET /metrics`: who may read it, and that its counters move by exactly the requests,
//! submission, answer and refused logins made between two scrapes (parsed with a Prometheus
//! text-format parser, not by string matching).

use enact_hub::core::credentials::Role;
use enact_hub::web::WebConfig;
use reqwest::{Method, StatusCode};
use serde_json::json;

use crate::annotate::{annotator, assign, logged_in_on};
use crate::helpers::*;

const METRICS_TOKEN: &str = "scrape-4d1c9e07b2a8";

/// One scrape, parsed.
pub struct Scrape(prometheus_parse::Scrape);

impl Scrape {
    pub async fn of(server: &TestServer, token: &str) -> Scrape {
        let reply = server
            .client
            .get(server.url("/metrics"))
            .bearer_auth(token)
            .send()
            .await
            .expect("GET /metrics");
        assert_eq!(reply.status(), StatusCode::OK);
        let content_type = reply.headers()["content-type"]
            .to_str()
            .expect("text")
            .to_owned();
        assert!(content_type.starts_with("application/openmetrics-text"));
        let text = reply.text().await.expect("text");
        let lines = text.lines().map(|l| Ok(l.to_owned()));
        Scrape(prometheus_parse::Scrape::parse(lines).expect("Prometheus text format"))
    }

    /// The value of the sample `name` whose labels include `labels` (0 when there is none).
    pub fn value(&self, name: &str, labels: &[(&str, &str)]) -> f64 {
        self.0
            .samples
            .iter()
            .filter(|s| s.metric == name)
            .filter(|s| labels.iter().all(|(k, v)| s.labels.get(k) == Some(*v)))
            .map(|s| match &s.value {
                prometheus_parse::Value::Counter(v)
                | prometheus_parse::Value::Gauge(v)
                | prometheus_parse::Value::Untyped(v) => *v,
                prometheus_parse::Value::Histogram(h) => {
                    h.iter().map(|b| b.count).fold(0.0, f64::max)
                }
                prometheus_parse::Value::Summary(_) => panic!("{name} is a summary"),
            })
            .sum()
    }
}

#[tokio::test]
async fn metrics_move_by_exactly_the_requests_submission_answer_and_refused_logins_made() {
    let config = WebConfig {
        metrics_token: Some(METRICS_TOKEN.to_owned()),
        ..WebConfig::default()
    };
    let written = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let shared = written.clone();
    let server = spawn_app_configured(config, |pool, dir| async move {
        let root = dir.join("release");
        let records = write_release(&root, &[3, 4]);
        import(&pool, &root, &options("mini")).await;
        *shared.lock().expect("lock") = records;
    })
    .await;
    let records = written.lock().expect("lock").clone();
    let (_, admin) = api_token(&server.pool, "ops", Role::Admin, None, None).await;
    let (_, submitter) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let first_item = records[0]["id"].as_str().expect("id").to_owned();
    let bob = annotator(&server, "bob", false).await;
    assign(&server, bob, &[&first_item]).await;

    // Who may read it: the metrics token and admin tokens; no one else.
    let status = |token: Option<&'static str>| {
        let server = &server;
        async move {
            let mut request = server.client.get(server.url("/metrics"));
            if let Some(token) = token {
                request = request.bearer_auth(token);
            }
            request.send().await.expect("GET /metrics").status()
        }
    };
    assert_eq!(status(None).await, StatusCode::UNAUTHORIZED);
    assert_eq!(status(Some("scrape-wrong")).await, StatusCode::UNAUTHORIZED);
    let refused = server
        .client
        .get(server.url("/metrics"))
        .bearer_auth(&submitter)
        .send()
        .await
        .expect("GET /metrics");
    assert_eq!(refused.status(), StatusCode::FORBIDDEN);

    let before = Scrape::of(&server, METRICS_TOKEN).await;
    for _ in 0..3 {
        server.get("/api/v1/datasets").await;
    }
    server.get("/api/v1/datasets/no-such").await;
    server
        .call(Method::POST, "/api/v1/datasets/mini/submissions?model=m")
        .bearer(&submitter)
        .body(answers(&records, &[]))
        .expect(201)
        .await;
    server
        .call(Method::GET, "/api/v1/submissions/1")
        .bearer("ehub_000000000000_not-a-token")
        .expect(401)
        .await;
    let (mut browser, csrf) = logged_in_on(&server, "bob", "/annotate").await;
    let bad = browser.login("bob", "not the password").await;
    assert_ne!(bad.status(), StatusCode::SEE_OTHER);
    let gt = records[0]["gt_answer"].clone();
    let r = browser
        .post_json(
            &format!("/annotate/mini/{first_item}/submit"),
            Some(&csrf),
            &json!({"slots": gt, "counts": {"placements": 2, "swaps": 0, "clears": 0, "undos": 0}}),
        )
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    let after = Scrape::of(&server, &admin).await;

    let moved = |name: &str, labels: &[(&str, &str)]| {
        after.value(name, labels) - before.value(name, labels)
    };
    let requests = "enact_hub_http_requests_total";
    let datasets = [("method", "GET"), ("route", "/api/v1/datasets")];
    assert_eq!(
        moved(requests, &[datasets[0], datasets[1], ("status", "200")]),
        3.0
    );
    let one = [("route", "/api/v1/datasets/:dataset"), ("status", "404")];
    assert_eq!(moved(requests, &one), 1.0);
    let submit = [
        ("method", "POST"),
        ("route", "/api/v1/datasets/:dataset/submissions"),
        ("status", "201"),
    ];
    assert_eq!(moved(requests, &submit), 1.0);
    // The first scrape was counted once it was answered.
    assert_eq!(
        moved(requests, &[("route", "/metrics"), ("status", "200")]),
        1.0
    );
    assert_eq!(
        moved("enact_hub_http_request_duration_seconds_count", &datasets),
        3.0
    );
    assert_eq!(moved("enact_hub_submissions_scored_total", &[]), 1.0);
    assert_eq!(moved("enact_hub_annotator_answers_total", &[]), 1.0);
    assert_eq!(
        moved("enact_hub_login_failures_total", &[("kind", "token")]),
        1.0
    );
    assert_eq!(
        moved("enact_hub_login_failures_total", &[("kind", "password")]),
        1.0
    );
    assert!(after.value("enact_hub_db_connection_wait_seconds_count", &[]) > 0.0);
    // The submission's verdicts were the one bulk write; its counted attempt, the annotator's
    // login (the session stored) and answer the three interactive ones (a refused login writes
    // nothing): each waited for its turn and held it, in its lane.
    for family in [
        "enact_hub_db_write_wait_seconds_count",
        "enact_hub_db_write_held_seconds_count",
    ] {
        assert_eq!(moved(family, &[("lane", "bulk")]), 1.0, "{family}");
        assert_eq!(moved(family, &[("lane", "interactive")]), 3.0, "{family}");
    }
    assert!(after.value("enact_hub_cache_entries", &[("cache", "items")]) >= 0.0);
    server.stop().await;
}

/// Jobs by kind and state are read from the database when scraped.
#[tokio::test]
async fn jobs_are_counted_by_kind_and_state_when_scraped() {
    let config = WebConfig {
        metrics_token: Some(METRICS_TOKEN.to_owned()),
        ..WebConfig::default()
    };
    let server = spawn_app_configured(config, |_, _| async {}).await;
    let hub = enact_hub::app::Hub::from(server.pool.clone());
    let (_, admin) = api_token(&server.pool, "ops", Role::Admin, None, None).await;
    let empty = Scrape::of(&server, METRICS_TOKEN).await;
    assert_eq!(empty.value("enact_hub_jobs", &[]), 0.0);
    server
        .call(Method::POST, "/api/v1/admin/rescore")
        .bearer(&admin)
        .json(&json!({}))
        .send()
        .await;
    let jobs = enact_hub::app::jobs::list(&hub, None, 10)
        .await
        .expect("jobs");
    assert_eq!(
        jobs.len(),
        1,
        "the rescore job is queued (no worker runs here)"
    );
    let scraped = Scrape::of(&server, METRICS_TOKEN).await;
    assert_eq!(scraped.value("enact_hub_jobs", &[]), jobs.len() as f64);
    for job in &jobs {
        assert!(
            scraped.value(
                "enact_hub_jobs",
                &[("kind", job.kind.as_str()), ("state", job.state.as_str())]
            ) >= 1.0
        );
    }
    server.stop().await;
}
