//! The heavy-work pool (scoring and the like): when every place is taken a submission is
//! answered `503` with `Retry-After` and a message at once, rather than waiting; work already
//! admitted still completes; `/metrics` shows the pool's queue and what it refused.

use std::time::Duration;

use enact_hub::app::Hub;
use enact_hub::app::heavy::HeavyLimits;
use enact_hub::core::credentials::Role;
use enact_hub::web::WebConfig;
use reqwest::StatusCode;

use crate::helpers::*;
use crate::metrics::Scrape;

const METRICS_TOKEN: &str = "scrape-heavy-5e0a71c3";

/// Scrapes until `name` reads `value` (the pool moves on its own threads); fails after 10 s.
async fn until_gauge(server: &TestServer, name: &str, value: f64) -> Scrape {
    for _ in 0..200 {
        let scrape = Scrape::of(server, METRICS_TOKEN).await;
        if scrape.value(name, &[]) == value {
            return scrape;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    panic!("{name} never reached {value}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_full_pool_answers_503_with_retry_after_and_admitted_work_completes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (pool, _) = fresh_db_located(&dir).await;
    let root = dir.path().join("release");
    let records = write_release(&root, &[3, 4]);
    import(&pool, &root, &options("mini")).await;
    let hub = Hub::from(pool.clone()).with_heavy_limits(
        HeavyLimits {
            threads: 1,
            queue: 1,
            nice: 0,
        }
        .checked()
        .expect("limits"),
    );
    let config = WebConfig {
        metrics_token: Some(METRICS_TOKEN.to_owned()),
        ..WebConfig::default()
    };
    let server = serve_hub(hub.clone(), pool, dir, &config).await;
    let (_, token) = api_token(&server.pool, "modeler", Role::Submitter, None, None).await;
    let body = answers(&records, &[1]);

    // The one thread is taken by work that waits for the test's word.
    let (release, blocked) = std::sync::mpsc::channel::<()>();
    let blocker = tokio::spawn({
        let hub = hub.clone();
        async move { hub.heavy().run(move || blocked.recv().is_ok()).await }
    });
    until_gauge(&server, "enact_hub_heavy_running", 1.0).await;

    // A first submission takes the one waiting place...
    let waiting = tokio::spawn({
        let server_url = server.url("/api/v1/datasets/mini/submissions?model=first");
        let (client, token, body) = (server.client.clone(), token.clone(), body.clone());
        async move {
            client
                .post(server_url)
                .bearer_auth(token)
                .body(body)
                .send()
                .await
                .expect("POST")
        }
    });
    until_gauge(&server, "enact_hub_heavy_queued", 1.0).await;

    // ...so a second one is refused at once, saying why and when to come back.
    let refused = submit_to(&server, "mini", "model=second", &token, body.clone()).await;
    assert_eq!(
        refused.status,
        StatusCode::SERVICE_UNAVAILABLE,
        "{}",
        refused.text
    );
    assert_eq!(refused.headers["retry-after"], "1");
    assert_eq!(
        refused.error(),
        "the server is busy with heavy work (1 running, 1 waiting, the most it takes); nothing was done, retry in a moment"
    );
    let full = Scrape::of(&server, METRICS_TOKEN).await;
    assert_eq!(full.value("enact_hub_heavy_refused_total", &[]), 1.0);
    assert_eq!(full.value("enact_hub_heavy_running", &[]), 1.0);
    assert_eq!(full.value("enact_hub_heavy_queued", &[]), 1.0);
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM submissions").await,
        0
    );
    // The refused attempt is not counted against the token's quota: only the waiting one is.
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM submission_attempts").await,
        1
    );

    // Once the thread is free the waiting submission is scored and stored, and the refused
    // one succeeds when sent again.
    release.send(()).expect("the blocked work listens");
    assert!(blocker.await.expect("task").expect("admitted"));
    let first = waiting.await.expect("task");
    assert_eq!(first.status(), StatusCode::CREATED);
    let again = submit_to(&server, "mini", "model=second", &token, body).await;
    assert_eq!(again.status, StatusCode::CREATED, "{}", again.text);
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM submissions").await,
        2
    );
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM submission_attempts").await,
        2
    );
    let after = until_gauge(&server, "enact_hub_heavy_running", 0.0).await;
    assert_eq!(after.value("enact_hub_heavy_queued", &[]), 0.0);
    assert_eq!(after.value("enact_hub_heavy_refused_total", &[]), 1.0);
    // The blocker, the dataset's scoring targets (built once, then cached) and two scorings.
    assert_eq!(after.value("enact_hub_heavy_done_total", &[]), 4.0);
    server.stop().await;
}
