//! A write that cannot get the database's lock in time: `503 Service Unavailable` with
//! `Retry-After` and a message saying the database is busy, on the API and on pages, on
//! both databases; nothing is half-written and the same request succeeds once the lock is free.

use std::future::Future;
use std::time::{Duration, Instant};

use enact_hub::core::credentials::Role;
use enact_hub::store::WRITE_WAIT;
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
    let draft_path = format!("/annotate/mini/{item}/draft");
    let ((submission, submission_waited), (saved, saved_waited), (login, login_waited)) = tokio::join!(
        timed(submit_to(&server, "mini", "model=m", &token, body.clone())),
        timed(alice.post_json(&draft_path, Some(&csrf), &draft)),
        timed(bob.login("bob", PASSWORD)),
    );
    // Each refused write waited out the lock first (SQLite's busy timeout, PostgreSQL's
    // lock_timeout, both WRITE_WAIT) rather than giving up at once; a tenth of it is left to
    // the timers' granularity.
    let waited_out = WRITE_WAIT - WRITE_WAIT / 10;
    assert!(
        submission_waited >= waited_out,
        "the submission was refused after {submission_waited:?}, not after waiting out the lock"
    );
    assert!(
        saved_waited >= waited_out,
        "the draft was refused after {saved_waited:?}, not after waiting out the lock"
    );
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
    // The login form is a page: the error page says the same. The session is a write like any
    // other (in the interactive lane), so on PostgreSQL too it waits for the write lock.
    assert!(
        login_waited >= waited_out,
        "login refused after {login_waited:?}"
    );
    assert_eq!(login.status(), StatusCode::SERVICE_UNAVAILABLE);
    assert_eq!(login.headers()["retry-after"], "1");
    let page = login.text().await.expect("page");
    assert!(page.contains("the database is busy"), "{page}");
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

    // Retried while the lock is held for a moment, the submission waits for it and succeeds
    // once it is free.
    let held = server.pool.begin().await.expect("the write lock");
    let hold = Duration::from_secs(1);
    let release = async {
        tokio::time::sleep(hold).await;
        held.rollback().await.expect("released");
    };
    let ((submission, waited), ()) = tokio::join!(
        timed(submit_to(&server, "mini", "model=m", &token, body)),
        release
    );
    assert!(submission.status.is_success(), "{}", submission.text);
    assert!(
        waited >= hold,
        "the submission was answered after {waited:?}, while the lock was still held"
    );
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

/// `request`'s answer and how long it took.
async fn timed<T>(request: impl Future<Output = T>) -> (T, Duration) {
    let started = Instant::now();
    let answer = request.await;
    (answer, started.elapsed())
}
