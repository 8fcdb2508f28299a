//! A write that cannot get the database's lock in time: `503 Service Unavailable` with
//! `Retry-After` and a message saying the database is busy, on the API and on pages, on
//! both databases; nothing is half-written and the same request succeeds once the lock is free.

use enact_hub::core::credentials::Role;
use reqwest::StatusCode;
use serde_json::json;

use crate::annotate::{Browser, PASSWORD, annotator, assign, logged_in_on};
use crate::helpers::*;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn writes_wait_out_the_lock_then_answer_503_with_retry_after() {
    let (server, records) = spawn_app_with_release().await;
    let (_, token) = api_token(&server.pool, "modeler", Role::Submitter, None, None).await;
    let alice = annotator(&server, "alice", false).await;
    annotator(&server, "bob", false).await;
    let item = records[0]["id"].as_str().expect("id").to_owned();
    assign(&server, alice, &[&item]).await;
    let (mut alice, csrf) = logged_in_on(&server, "alice", "/annotate").await;
    alice.get(&format!("/annotate/mini/{item}")).await;
    let mut bob = Browser::new(&server);
    let body = answers(&records, &[]);
    let draft = json!({"slots": [null, 1], "counts": {"placements": 1, "swaps": 0,
        "clears": 0, "undos": 0}});

    // Another writer holds the write lock (SQLite's, or PostgreSQL's advisory one) past the
    // busy timeout.
    let draft_rows = "SELECT count(*) FROM drafts WHERE slots LIKE '%1%'";
    assert_eq!(count(&server.pool, draft_rows).await, 0);
    let held = server.pool.begin().await.expect("the write lock");
    let started = std::time::Instant::now();
    let draft_path = format!("/annotate/mini/{item}/draft");
    let (submission, saved, login) = tokio::join!(
        submit_to(&server, "mini", "model=m", &token, body.clone()),
        alice.post_json(&draft_path, Some(&csrf), &draft),
        bob.login("bob", PASSWORD),
    );
    eprintln!("refused after {:?}", started.elapsed());
    assert_eq!(
        submission.status,
        StatusCode::SERVICE_UNAVAILABLE,
        "{}",
        submission.text
    );
    assert_eq!(submission.headers["retry-after"], "1");
    assert!(
        submission.error().contains("the database is busy"),
        "{}",
        submission.text
    );
    assert_eq!(saved.status(), StatusCode::SERVICE_UNAVAILABLE);
    assert_eq!(saved.headers()["retry-after"], "1");
    let saved: serde_json::Value = saved.json().await.expect("json");
    assert!(
        saved["error"]
            .as_str()
            .is_some_and(|e| e.contains("database is busy"))
    );
    // The login form is a page: the error page says the same. (On PostgreSQL a session is
    // written without the write lock, which serialises only the use cases' checked writes,
    // so a login does not wait there.)
    if on_sqlite() {
        assert_eq!(login.status(), StatusCode::SERVICE_UNAVAILABLE);
        assert_eq!(login.headers()["retry-after"], "1");
        let page = login.text().await.expect("page");
        assert!(page.contains("the database is busy"), "{page}");
    } else {
        assert_eq!(login.status(), StatusCode::SEE_OTHER);
        bob = Browser::new(&server);
    }
    held.rollback().await.expect("released");
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM submissions").await,
        0
    );
    assert_eq!(
        count(&server.pool, draft_rows).await,
        0,
        "the refused draft was not saved"
    );

    // Retried once the lock is free, each succeeds.
    let submission = submit_to(&server, "mini", "model=m", &token, body).await;
    assert!(submission.status.is_success(), "{}", submission.text);
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM submissions").await,
        1
    );
    let saved = alice.post_json(&draft_path, Some(&csrf), &draft).await;
    assert_eq!(saved.status(), StatusCode::OK);
    assert_eq!(
        bob.login("bob", PASSWORD).await.status(),
        StatusCode::SEE_OTHER
    );
}
