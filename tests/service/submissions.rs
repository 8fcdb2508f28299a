//! Submissions over HTTP: tokens, validation, quotas, idempotency, visibility, the leaderboard,
//! and parity with `enact-hub score --policy strict` on ENACT's fixtures.

use std::collections::HashMap;

use enact_hub::core::credentials::Role;
use enact_hub::core::dataset::{AnswerVisibility, Direction};
use enact_hub::core::submission::Visibility;
use enact_hub::store;
use enact_hub::store::Pool;
use enact_hub::web::WebConfig;
use serde_json::{Value, json};

use crate::helpers::*;

/// A token for a fresh (or existing) account.
async fn make_token(pool: &Pool, name: &str, role: Role, daily: Option<i64>) -> String {
    api_token(pool, name, role, daily, None).await.1
}

pub(crate) async fn post(
    server: &TestServer,
    dataset: &str,
    query: &str,
    token: Option<&str>,
    body: impl Into<reqwest::Body>,
    idempotency_key: Option<&str>,
) -> (reqwest::StatusCode, reqwest::header::HeaderMap, Value) {
    let path = format!("/api/v1/datasets/{dataset}/submissions?{query}");
    let mut call = server.call(reqwest::Method::POST, &path).body(body);
    if let Some(t) = token {
        call = call.bearer(t);
    }
    if let Some(k) = idempotency_key {
        call = call.header("Idempotency-Key", k);
    }
    let reply = call.send().await;
    (reply.status, reply.headers.clone(), reply.json())
}

/// `post` of `body` to dataset "mini" as model "m", with `token` and no idempotency key.
async fn post_as(
    server: &TestServer,
    token: &str,
    body: impl Into<reqwest::Body>,
) -> (reqwest::StatusCode, reqwest::header::HeaderMap, Value) {
    post(server, "mini", "model=m", Some(token), body, None).await
}

async fn get_authed(server: &TestServer, path: &str, token: &str) -> (reqwest::StatusCode, Value) {
    let reply = server
        .call(reqwest::Method::GET, path)
        .bearer(token)
        .send()
        .await;
    (reply.status, reply.json())
}

async fn admin_json(
    server: &TestServer,
    method: reqwest::Method,
    path: &str,
    token: &str,
    body: Value,
) -> (reqwest::StatusCode, Value) {
    let reply = server
        .call(method, path)
        .bearer(token)
        .json(&body)
        .send()
        .await;
    (reply.status, reply.json())
}

/// An admin makes a dataset's ground truth and per-item verdicts public.
pub(crate) async fn make_answers_public(server: &TestServer, dataset: &str, admin: &str) {
    server
        .call(
            reqwest::Method::PUT,
            &format!("/api/v1/admin/datasets/{dataset}/answers"),
        )
        .bearer(admin)
        .json(&json!({"answers": "public"}))
        .expect(200)
        .await;
}

async fn stored_counts(pool: &Pool) -> (i64, i64) {
    let mut conn = pool.acquire().await.expect("conn");
    store::submissions::counts(&mut conn).await.expect("counts")
}

#[tokio::test]
async fn a_submission_is_scored_stored_and_readable_by_its_owner_only() {
    let (server, records) = spawn_app_with_release().await;
    let alice = make_token(&server.pool, "alice", Role::Submitter, None).await;
    let bob = make_token(&server.pool, "bob", Role::Submitter, None).await;
    let body = answers(&records, &[0]);
    let (status, headers, created) = post(
        &server,
        "mini",
        "model=m1&description=d",
        Some(&alice),
        body,
        None,
    )
    .await;
    assert_eq!(status, 201, "{created}");
    let id = created["id"].as_i64().expect("id");
    assert_eq!(
        headers["location"].to_str().expect("location"),
        format!("/api/v1/submissions/{id}")
    );
    let overall = &created["scores"]["report"]["overall"];
    assert_eq!(overall["count"], 4);
    assert_eq!(overall["task_accuracy"], 0.75);
    assert_eq!(created["scores"]["coverage"]["coverage"], 1.0);
    let ci = &created["scores"]["confidence"]["task_accuracy"];
    assert!(ci["low"].as_f64().expect("low") <= 0.75 && ci["high"].as_f64().expect("high") >= 0.75);
    assert_eq!(stored_counts(&server.pool).await, (1, 4));

    let path = format!("/api/v1/submissions/{id}");
    let (status, own) = get_authed(&server, &path, &alice).await;
    assert_eq!(status, 200);
    assert_eq!(own["scores"], created["scores"]);
    // Hidden by default: no per-item verdicts, no ground truth.
    assert!(own.get("items").is_none(), "{own}");
    assert!(
        own["items_withheld"]
            .as_str()
            .expect("note")
            .contains("hidden")
    );
    assert!(!own.to_string().contains("ground_truth"));

    let (status, other) = get_authed(&server, &path, &bob).await;
    assert_eq!(status, 404, "{other}");
    let (status, _) = get_authed(&server, "/api/v1/submissions/999", &alice).await;
    assert_eq!(status, 404);

    // An admin makes the answers public: the owner now sees verdicts and ground truth.
    let admin = make_token(&server.pool, "root", Role::Admin, None).await;
    make_answers_public(&server, "mini", &admin).await;
    let (_, own) = get_authed(&server, &path, &alice).await;
    let items = own["items"].as_array().expect("items");
    assert_eq!(items.len(), 4);
    assert_eq!(items[0]["task_accuracy"], false);
    assert_eq!(items[1]["task_accuracy"], true);
    assert_eq!(items[1]["ground_truth"], records[1]["gt_answer"]);
    assert_eq!(items[1]["line"], 2);
    let (status, _) = get_authed(&server, &path, &bob).await;
    assert_eq!(status, 404);
    // A submitter cannot use admin endpoints.
    let (status, _) = admin_json(
        &server,
        reqwest::Method::PUT,
        "/api/v1/admin/datasets/mini/answers",
        &alice,
        json!({"answers": "hidden"}),
    )
    .await;
    assert_eq!(status, 403);
    server.stop().await;
}

#[tokio::test]
async fn a_forged_ground_truth_changes_nothing() {
    let (server, records) = spawn_app_with_release().await;
    let token = make_token(&server.pool, "alice", Role::Submitter, None).await;
    let honest = answers(&records, &[0, 1]);
    let forged: String = honest
        .lines()
        .enumerate()
        .map(|(i, line)| {
            let mut record: Value = serde_json::from_str(line).expect("json");
            // Claim the submitted (reversed) answer is the truth, with a matching type.
            let answer: Vec<u64> =
                serde_json::from_str(record["answer"].as_str().expect("s")).expect("list");
            record["gt_answer"] = json!(answer);
            record["type"] = json!("forward_world_modeling_3_steps");
            record["key_frame_ids"] = json!(["1", "2", "3"]);
            let _ = i;
            record.to_string() + "\n"
        })
        .collect();
    let (s1, _, a) = post(&server, "mini", "model=honest", Some(&token), honest, None).await;
    let (s2, _, b) = post(&server, "mini", "model=forged", Some(&token), forged, None).await;
    assert_eq!((s1.as_u16(), s2.as_u16()), (201, 201), "{b}");
    assert_eq!(a["scores"], b["scores"]);
    assert_eq!(b["scores"]["report"]["overall"]["task_accuracy"], 0.5);
    server.stop().await;
}

#[tokio::test]
async fn tokens_missing_unknown_or_revoked_get_401() {
    let (server, records) = spawn_app_with_release().await;
    let token = make_token(&server.pool, "alice", Role::Submitter, None).await;
    let body = answers(&records, &[]);
    let (status, headers, error) = post(&server, "mini", "model=m", None, body.clone(), None).await;
    assert_eq!(status, 401);
    assert!(headers.contains_key("www-authenticate"));
    assert!(error["error"].as_str().expect("msg").contains("Bearer"));
    let (status, _, _) = post(
        &server,
        "mini",
        "model=m",
        Some("ehub_nope"),
        body.clone(),
        None,
    )
    .await;
    assert_eq!(status, 401);
    let (status, _, _) = post_as(&server, &token, body.clone()).await;
    assert_eq!(status, 201);
    let mut conn = write_tx(&server.pool).await;
    let prefix = enact_hub::core::credentials::lookup_prefix(&token);
    assert!(
        store::accounts::revoke_token(&mut conn, &prefix)
            .await
            .expect("revoke")
    );
    conn.commit().await.expect("commit");
    let (status, _, error) = post_as(&server, &token, body).await;
    assert_eq!(status, 401);
    assert!(error["error"].as_str().expect("msg").contains("revoked"));
    assert_eq!(stored_counts(&server.pool).await.0, 1);
    server.stop().await;
}

#[tokio::test]
async fn every_validation_problem_is_a_422_naming_its_line_and_nothing_is_stored() {
    let (server, records) = spawn_app_with_release().await;
    let token = make_token(&server.pool, "alice", Role::Submitter, None).await;
    let good = answers(&records, &[]);
    let first = good.lines().next().expect("line").to_owned();
    let cases: Vec<(String, &str, usize)> = vec![
        (format!("{first}\n{{\"id\": oops}}\n"), "invalid_json", 2),
        (
            format!("{first}\n{{\"id\":\"no_such_item\",\"answer\":\"[1,2]\"}}\n"),
            "unknown_id",
            2,
        ),
        (format!("{first}\n\n{first}\n"), "duplicate_id", 3),
        (
            format!("{first}\n{}\n", json!({"id": records[1]["id"]})),
            "missing_answer",
            2,
        ),
        (format!("{first}\n[1, 2]\n"), "not_an_object", 2),
        (
            format!("{first}\n{{\"answer\":\"[1]\"}}\n"),
            "missing_id",
            2,
        ),
        (
            format!(
                "{first}\n{}\n",
                json!({"id": records[1]["id"], "answer": {"order": [1, 2]}})
            ),
            "malformed_answer",
            2,
        ),
        ("".to_owned(), "empty_body", 1),
        (" \n\n".to_owned(), "empty_body", 1),
        ("[]".to_owned(), "empty_body", 1),
    ];
    for (body, kind, line) in cases {
        let (status, _, error) = post_as(&server, &token, body).await;
        assert_eq!(status, 422, "{kind}: {error}");
        let problems = error["problems"].as_array().expect("problems");
        assert_eq!(problems.len(), 1, "{error}");
        assert_eq!(problems[0]["kind"], kind);
        assert_eq!(problems[0]["line"], line);
        let message = error["error"].as_str().expect("message");
        assert!(message.contains(&format!("line {line}")), "{message}");
    }
    // A JSON array body names the line of its syntax error.
    let (status, _, error) = post_as(&server, &token, "[\n{\"id\": 1,\n}]").await;
    assert_eq!(status, 422, "{error}");
    assert_eq!(error["problems"][0]["line"], 3);
    // Not UTF-8.
    let (status, _, error) = post_as(&server, &token, vec![b'{', 0xff, b'}']).await;
    assert_eq!(status, 422);
    assert!(error["error"].as_str().expect("msg").contains("UTF-8"));
    // Missing metadata is a 400 that names the parameter.
    let (status, _, error) = post(&server, "mini", "", Some(&token), good, None).await;
    assert_eq!(status, 400);
    assert!(error["error"].as_str().expect("msg").contains("`model`"));
    assert_eq!(stored_counts(&server.pool).await, (0, 0));
    server.stop().await;
}

#[tokio::test]
async fn a_json_array_scores_like_jsonl_and_parse_failures_are_counted() {
    let (server, records) = spawn_app_with_release().await;
    let token = make_token(&server.pool, "alice", Role::Submitter, None).await;
    let mut lines: Vec<Value> = answers(&records, &[])
        .lines()
        .map(|l| serde_json::from_str(l).expect("json"))
        .collect();
    lines[0]["answer"] = json!("I cannot tell");
    lines[1]["answer"] = json!([2, 1]);
    let jsonl: String = lines.iter().map(|l| l.to_string() + "\n").collect();
    let array = Value::Array(lines).to_string();
    let (s1, _, a) = post(&server, "mini", "model=a", Some(&token), jsonl, None).await;
    let (s2, _, b) = post(&server, "mini", "model=b", Some(&token), array, None).await;
    assert_eq!((s1.as_u16(), s2.as_u16()), (201, 201), "{a} {b}");
    assert_eq!(a["scores"], b["scores"]);
    assert_eq!(a["scores"]["coverage"]["unparseable"], 1);
    assert_eq!(a["scores"]["coverage"]["parse_failure_rate"], 0.25);
    server.stop().await;
}

#[tokio::test]
async fn quotas_count_rejected_attempts_and_answer_429_with_retry_after() {
    let (server, records) = spawn_app_with_release().await;
    let token = make_token(&server.pool, "alice", Role::Submitter, Some(2)).await;
    let (status, _, _) = post_as(&server, &token, "{oops").await;
    assert_eq!(status, 422);
    let (status, _, _) = post_as(&server, &token, answers(&records, &[])).await;
    assert_eq!(status, 201);
    let (status, headers, error) = post_as(&server, &token, answers(&records, &[])).await;
    assert_eq!(status, 429, "{error}");
    let retry: u64 = headers["retry-after"]
        .to_str()
        .expect("text")
        .parse()
        .expect("seconds");
    assert!((1..=86_400).contains(&retry));
    assert!(
        error["error"]
            .as_str()
            .expect("msg")
            .contains("2 submissions for today")
    );
    // The reason is typed: the Retry-After header's seconds are in its details too.
    assert_eq!(error["code"], "daily_quota_used", "{error}");
    assert_eq!(error["details"]["limit"], 2, "{error}");
    assert_eq!(error["details"]["retry_after"], retry, "{error}");
    assert_eq!(stored_counts(&server.pool).await.0, 1);
    server.stop().await;
}

#[tokio::test]
async fn a_used_up_total_quota_answers_429_without_retry_after() {
    let (server, records) = spawn_app_with_release().await;
    // A generous daily quota, so the total is what runs out.
    let token = api_token(&server.pool, "carol", Role::Submitter, Some(50), Some(2))
        .await
        .1;
    let (status, _, _) = post_as(&server, &token, "{oops").await;
    assert_eq!(status, 422);
    let body = answers(&records, &[]);
    let (status, _, _) = post_as(&server, &token, body.clone()).await;
    assert_eq!(status, 201);
    let (status, headers, error) = post_as(&server, &token, body).await;
    assert_eq!(status, 429, "{error}");
    assert!(
        headers.get("retry-after").is_none(),
        "a used-up total quota must not suggest waiting: {headers:?}"
    );
    let message = error["error"].as_str().expect("msg");
    assert!(message.contains("2 of 2 submissions"), "{message}");
    assert!(message.contains("total quota"), "{message}");
    assert_eq!(stored_counts(&server.pool).await.0, 1);
    server.stop().await;
}

#[tokio::test]
async fn idempotency_keys_return_the_first_submission_and_refuse_another_body() {
    let (server, records) = spawn_app_with_release().await;
    let token = make_token(&server.pool, "alice", Role::Submitter, None).await;
    let body = answers(&records, &[]);
    let (s1, _, a) = post(
        &server,
        "mini",
        "model=m",
        Some(&token),
        body.clone(),
        Some("k1"),
    )
    .await;
    let (s2, _, b) = post(&server, "mini", "model=m", Some(&token), body, Some("k1")).await;
    assert_eq!((s1.as_u16(), s2.as_u16()), (201, 200));
    assert_eq!(a["id"], b["id"]);
    let (s3, _, c) = post(
        &server,
        "mini",
        "model=m",
        Some(&token),
        answers(&records, &[1]),
        Some("k1"),
    )
    .await;
    assert_eq!(s3, 409, "{c}");
    assert_eq!(stored_counts(&server.pool).await, (1, 4));
    server.stop().await;
}

/// Rounds of each race below: one lost race in ten is likely to show.
const RACES: usize = 10;

/// The statuses of two replies, lowest first.
fn both(a: &reqwest::StatusCode, b: &reqwest::StatusCode) -> [u16; 2] {
    let mut statuses = [a.as_u16(), b.as_u16()];
    statuses.sort_unstable();
    statuses
}

/// Twin requests (one body, one Idempotency-Key) sent at once: one is stored; one request
/// answers 201, the other 200 with the same submission.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn twin_requests_racing_with_one_idempotency_key_store_one_submission() {
    let (server, records) = spawn_app_with_release().await;
    // A twin that loses its race gives its attempt back: one attempt a round, however the
    // two interleave.
    let (token_id, token) =
        api_token(&server.pool, "alice", Role::Submitter, Some(1000), None).await;
    let body = answers(&records, &[]);
    for round in 0..RACES {
        let key = format!("race-{round}");
        let send = || {
            post(
                &server,
                "mini",
                "model=m",
                Some(&token),
                body.clone(),
                Some(&key),
            )
        };
        let (a, b) = tokio::join!(send(), send());
        assert_eq!(
            both(&a.0, &b.0),
            [200, 201],
            "round {round}: {} {}",
            a.2,
            b.2
        );
        assert_eq!((&a.2["id"], &a.2["scores"]), (&b.2["id"], &b.2["scores"]));
        let stored = count(
            &server.pool,
            &format!("SELECT count(*) FROM submissions WHERE idempotency_key = '{key}'"),
        )
        .await;
        assert_eq!(stored, 1, "round {round}");
    }
    assert_eq!(stored_counts(&server.pool).await.0, RACES as i64);
    let attempts = count(
        &server.pool,
        &format!("SELECT count(*) FROM submission_attempts WHERE token = {token_id}"),
    )
    .await;
    assert_eq!(attempts, RACES as i64, "a repeat is not paid for");
    server.stop().await;
}

/// Two submissions sent at once by a token with one submission left: one is stored (201), the
/// other refused with the quota's 429.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_submissions_racing_for_the_last_quota_slot_store_one() {
    let (server, records) = spawn_app_with_release().await;
    let body = answers(&records, &[]);
    for round in 0..RACES {
        let name = format!("racer-{round}");
        let (id, token) = api_token(&server.pool, &name, Role::Submitter, None, Some(1)).await;
        let send = |model| post(&server, "mini", model, Some(&token), body.clone(), None);
        let (a, b) = tokio::join!(send("model=a"), send("model=b"));
        assert_eq!(
            both(&a.0, &b.0),
            [201, 429],
            "round {round}: {} {}",
            a.2,
            b.2
        );
        let refusal = if a.0 == 429 { &a.2 } else { &b.2 };
        let message = refusal["error"].as_str().expect("a message");
        assert!(message.contains("total quota is used up"), "{message}");
        assert_eq!(refusal["code"], "total_quota_used", "{refusal}");
        let stored = count(
            &server.pool,
            &format!("SELECT count(*) FROM submissions WHERE token = {id}"),
        )
        .await;
        assert_eq!(stored, 1, "round {round}");
    }
    server.stop().await;
}

#[tokio::test]
async fn a_body_over_the_limit_is_refused_with_413() {
    let config = WebConfig {
        submission_body_limit: 300,
        ..WebConfig::default()
    };
    let records = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let shared = records.clone();
    let server = spawn_app_configured(config, |pool, dir| async move {
        let root = dir.join("release");
        *shared.lock().expect("lock") = write_release(&root, &[3, 4]);
        import(&pool, &root, &options("mini")).await;
    })
    .await;
    let records = records.lock().expect("lock").clone();
    let token = make_token(&server.pool, "alice", Role::Submitter, None).await;
    let body = answers(&records, &[]);
    assert!(body.len() > 300);
    let (status, _, error) = post_as(&server, &token, body).await;
    assert_eq!(status, 413, "{error}");
    assert!(error["error"].as_str().expect("msg").contains("300 bytes"));
    // Chunked, without a length: refused once the limit is passed.
    let status = chunked_post(&server, &token, &"x".repeat(100), 10).await;
    assert!(status.starts_with("HTTP/1.1 413"), "{status}");
    assert_eq!(stored_counts(&server.pool).await, (0, 0));
    server.stop().await;
}

/// POSTs `chunks` copies of `chunk` with chunked transfer encoding; returns the status line.
async fn chunked_post(server: &TestServer, token: &str, chunk: &str, chunks: usize) -> String {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let mut stream = tokio::net::TcpStream::connect(server.addr)
        .await
        .expect("connect");
    let head = format!(
        "POST /api/v1/datasets/mini/submissions?model=m HTTP/1.1\r\nHost: {}\r\n\
         Authorization: Bearer {token}\r\nTransfer-Encoding: chunked\r\nConnection: close\r\n\r\n",
        server.addr
    );
    stream.write_all(head.as_bytes()).await.expect("head");
    for _ in 0..chunks {
        let piece = format!("{:x}\r\n{chunk}\r\n", chunk.len());
        if stream.write_all(piece.as_bytes()).await.is_err() {
            break;
        }
    }
    let _ = stream.write_all(b"0\r\n\r\n").await;
    let mut response = Vec::new();
    let _ = stream.read_to_end(&mut response).await;
    String::from_utf8_lossy(&response)
        .lines()
        .next()
        .unwrap_or_default()
        .to_owned()
}

#[tokio::test]
async fn the_leaderboard_lists_published_rows_and_admins_curate_them() {
    let (server, records) = spawn_app_with_release().await;
    let alice = make_token(&server.pool, "alice", Role::Submitter, None).await;
    let admin = make_token(&server.pool, "root", Role::Admin, None).await;
    let (_, _, weak) = post(
        &server,
        "mini",
        "model=weak",
        Some(&alice),
        answers(&records, &[0, 1, 2]),
        None,
    )
    .await;
    let (_, _, strong) = post(
        &server,
        "mini",
        "model=strong",
        Some(&alice),
        answers(&records, &[]),
        None,
    )
    .await;
    let (status, board) = server.get_json("/api/v1/datasets/mini/leaderboard").await;
    assert_eq!(status, 200);
    let rows = board["rows"].as_array().expect("rows");
    let models: Vec<&str> = rows
        .iter()
        .map(|r| r["model"].as_str().expect("m"))
        .collect();
    assert_eq!(models, vec!["strong", "weak"]);
    assert_eq!(rows[0]["overall"]["task_accuracy"], 1.0);
    assert_eq!(rows[1]["overall"]["task_accuracy"], 0.25);
    assert_eq!(
        rows[0]["forward"]["per_step"][0],
        json!([3, {"task_accuracy": 1.0, "pairwise_accuracy": 1.0, "count": 1}])
    );
    assert_eq!(board["step_lengths"], json!([3, 4, 5, 6, 7, 8, 9, 10]));

    let page = server.get("/leaderboard/mini").await;
    assert_eq!(page.status(), 200);
    let html = page.text().await.expect("html");
    assert!(html.contains("strong") && html.contains("weak"));
    assert_eq!(
        html.matches("<polyline").count(),
        4,
        "two models × two panels"
    );
    assert!(html.contains("Forward world modeling") && html.contains("Inverse world modeling"));
    assert!(html.contains("L=10"));

    let weak_id = weak["id"].as_i64().expect("id");
    let (status, body) = admin_json(
        &server,
        reqwest::Method::PATCH,
        &format!("/api/v1/admin/submissions/{weak_id}"),
        &admin,
        json!({"baseline": true}),
    )
    .await;
    assert_eq!(status, 200, "{body}");
    let (_, board) = server.get_json("/api/v1/datasets/mini/leaderboard").await;
    assert_eq!(board["rows"][1]["baseline"], true);
    let strong_id = strong["id"].as_i64().expect("id");
    let (status, _) = admin_json(
        &server,
        reqwest::Method::PATCH,
        &format!("/api/v1/admin/submissions/{strong_id}"),
        &admin,
        json!({"visibility": "withdrawn"}),
    )
    .await;
    assert_eq!(status, 200);
    let (_, board) = server.get_json("/api/v1/datasets/mini/leaderboard").await;
    assert_eq!(board["rows"].as_array().expect("rows").len(), 1);
    let (status, error) = admin_json(
        &server,
        reqwest::Method::PATCH,
        &format!("/api/v1/admin/submissions/{strong_id}"),
        &admin,
        json!({"visibility": "gone"}),
    )
    .await;
    assert_eq!(status, 400, "{error}");
    let (status, _) = admin_json(
        &server,
        reqwest::Method::PATCH,
        &format!("/api/v1/admin/submissions/{strong_id}"),
        &alice,
        json!({"baseline": true}),
    )
    .await;
    assert_eq!(status, 403);
    let (status, _) = server.get_json("/api/v1/datasets/nope/leaderboard").await;
    assert_eq!(status, 404);
    server.stop().await;
}

#[tokio::test]
async fn the_demo_leaderboard_shows_table_and_chart() {
    let server = spawn_app_with(|pool, _| async move {
        enact_hub::app::demo::load(&pool.clone().into())
            .await
            .expect("demo");
    })
    .await;
    // A fresh demo already shows its chance baseline and the heuristic's row: a line per panel
    // each, marked as baselines.
    let (status, board) = server.get_json("/api/v1/datasets/demo/leaderboard").await;
    assert_eq!(status, 200, "{board}");
    let rows = board["rows"].as_array().expect("rows");
    assert_eq!(rows.len(), 2, "{board}");
    let row = |model: &str| {
        rows.iter()
            .find(|r| r["model"] == model)
            .unwrap_or_else(|| panic!("no row {model}: {board}"))
            .clone()
    };
    let chance = row(enact_hub::core::demo::CHANCE_BASELINE_MODEL);
    let heuristic = row(enact_hub::core::demo::GRASP_HEURISTIC_MODEL);
    assert_eq!(chance["baseline"], true);
    assert_eq!(heuristic["baseline"], true);
    // Its replies are text, read by the strict reader: every item answered, none unreadable.
    assert_eq!(heuristic["coverage"], 1.0, "{heuristic}");
    assert_eq!(heuristic["parse_failure_rate"], 0.0, "{heuristic}");
    let heuristic_id = heuristic["submission"].as_i64().expect("id");
    let mut conn = write_tx(&server.pool).await;
    let demo = store::datasets::by_name(&mut conn, "demo")
        .await
        .expect("q")
        .expect("demo");
    store::submissions::set_answer_visibility(&mut conn, demo.id, AnswerVisibility::Public)
        .await
        .expect("public");
    let first = store::items::scoring_items(&mut conn, demo.id)
        .await
        .expect("items")
        .into_iter()
        .find(|i| i.direction == Direction::Inverse)
        .expect("an inverse item")
        .item_id;
    conn.commit().await.expect("commit");
    let (status, item) = server
        .get_json(&format!("/api/v1/datasets/demo/items/{first}/answers"))
        .await;
    assert_eq!(status, 200, "{item}");
    let reply = item["models"]
        .as_array()
        .expect("models")
        .iter()
        .find(|m| m["submission"] == heuristic_id)
        .unwrap_or_else(|| panic!("no heuristic answer: {item}"))["answer"]
        .as_str()
        .expect("a text reply")
        .to_owned();
    assert!(reply.contains("Heuristic, not a model"), "{reply}");
    let html = server
        .get("/leaderboard/demo")
        .await
        .text()
        .await
        .expect("html");
    assert_eq!(html.matches("<polyline").count(), 4);
    // Loading the demo again (a restart on the same database) adds neither again.
    enact_hub::app::demo::load(&server.pool.clone().into())
        .await
        .expect("demo again");
    let (_, board) = server.get_json("/api/v1/datasets/demo/leaderboard").await;
    assert_eq!(board["rows"].as_array().expect("rows").len(), 2, "{board}");
    // Nor after an admin has hidden one: the hidden row is not filed again.
    let baseline_id = chance["submission"].as_i64().expect("submission id");
    let mut conn = write_tx(&server.pool).await;
    store::submissions::update_listing(&mut conn, baseline_id, None, Some(Visibility::Hidden))
        .await
        .expect("hide");
    conn.commit().await.expect("commit");
    enact_hub::app::demo::load(&server.pool.clone().into())
        .await
        .expect("demo a third time");
    let mut conn = write_tx(&server.pool).await;
    assert_eq!(
        store::submissions::counts(&mut conn)
            .await
            .expect("counts")
            .0,
        2
    );
    store::submissions::update_listing(&mut conn, baseline_id, None, Some(Visibility::Published))
        .await
        .expect("publish again");
    conn.commit().await.expect("commit");

    let token = make_token(&server.pool, "alice", Role::Submitter, None).await;
    let mut conn = server.pool.acquire().await.expect("conn");
    let dataset = store::datasets::by_name(&mut conn, "demo")
        .await
        .expect("q")
        .expect("demo");
    let items = store::items::scoring_items(&mut conn, dataset.id)
        .await
        .expect("items");
    drop(conn);
    // Right on every other item: a line per panel with values across all step lengths.
    let body: String = items
        .iter()
        .enumerate()
        .map(|(i, item)| {
            let mut answer = item.gt_answer.clone();
            if i % 2 == 1 {
                answer.reverse();
            }
            json!({"id": item.item_id, "answer": answer}).to_string() + "\n"
        })
        .collect();
    let (status, _, created) =
        post(&server, "demo", "model=demo-half", Some(&token), body, None).await;
    assert_eq!(status, 201, "{created}");
    assert_eq!(created["scores"]["coverage"]["coverage"], 1.0);
    let html = server
        .get("/leaderboard/demo")
        .await
        .text()
        .await
        .expect("html");
    assert!(html.contains("demo-half"));
    assert_eq!(
        html.matches("<polyline").count(),
        6,
        "two baselines and a model, two panels"
    );
    assert!(
        html.matches("<circle").count() >= 32,
        "a marker per step length and panel"
    );
    server.stop().await;
}

#[tokio::test]
async fn token_create_prints_the_token_last_and_revoke_takes_effect_at_once() {
    let (server, records) = spawn_app_with_release().await;
    let db = server.db_path();
    let out = enact_hub()
        .args([
            "token",
            "create",
            "--role",
            "submitter",
            "--name",
            "carol",
            "--db",
        ])
        .arg(&db)
        .output()
        .expect("run token create");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let token = stdout.lines().last().expect("a line").to_owned();
    assert!(
        token.starts_with("ehub_") && !token.contains(' '),
        "{stdout}"
    );
    let (status, _, _) = post_as(&server, &token, answers(&records, &[])).await;
    assert_eq!(status, 201);

    let list = enact_hub()
        .args(["token", "list", "--db"])
        .arg(&db)
        .output()
        .expect("list");
    let listing = String::from_utf8_lossy(&list.stdout);
    let prefix = enact_hub::core::credentials::lookup_prefix(&token);
    assert!(
        listing.contains(&prefix) && listing.contains("carol"),
        "{listing}"
    );
    assert!(!listing.contains(&token), "the secret must never be listed");

    let revoke = enact_hub()
        .args(["token", "revoke", &prefix, "--db"])
        .arg(&db)
        .output()
        .expect("revoke");
    assert!(revoke.status.success());
    let (status, _, _) = post_as(&server, &token, answers(&records, &[])).await;
    assert_eq!(status, 401);
    server.stop().await;
}

/// Lines of `file` whose record has no reply in `answer` (missing, null, or a JSON object): the
/// strict scorer counts them as unparseable, the API refuses them as the client's mistake.
fn lines_without_a_reply(text: &str) -> Vec<u64> {
    text.lines()
        .enumerate()
        .filter_map(|(i, line)| {
            let record: Value = serde_json::from_str(line).ok()?;
            let object = record.as_object()?;
            object.get("id")?.as_str().filter(|s| !s.is_empty())?;
            object
                .get("answer")
                .is_none_or(|a| a.is_null() || a.is_object())
                .then_some(i as u64 + 1)
        })
        .collect()
}

#[tokio::test]
async fn every_enact_prediction_file_scores_as_the_strict_command_does() {
    let Some(fixtures) = fixtures_dir() else {
        return;
    };
    let parity = fixtures.join("enact-parity");
    let server = spawn_app_with({
        let parity = parity.clone();
        |pool, _| async move {
            let mut opts = options("parity");
            opts.scene_graphs = Some(parity.join("replayed_activities"));
            import(&pool, &parity, &opts).await;
        }
    })
    .await;
    let token = make_token(&server.pool, "alice", Role::Admin, None).await;
    make_answers_public(&server, "parity", &token).await;
    let out = tempfile::tempdir().expect("tempdir");
    let mut accepted = Vec::new();
    let mut refused = Vec::new();
    let mut files: Vec<_> = std::fs::read_dir(parity.join("predictions"))
        .expect("predictions")
        .map(|e| e.expect("entry").path())
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("enact_ordering_"))
        })
        .collect();
    files.sort();
    for path in files {
        let name = path
            .file_name()
            .expect("name")
            .to_string_lossy()
            .into_owned();
        let model = name
            .trim_start_matches("enact_ordering_")
            .trim_end_matches(".jsonl")
            .to_owned();
        let text = std::fs::read_to_string(&path).expect("read");
        let cli = enact_hub()
            .arg("score")
            .arg(&path)
            .args([
                "--policy",
                "strict",
                "--dataset",
                "parity",
                "--model",
                &model,
                "--db",
            ])
            .arg(server.db_path())
            .arg("--out")
            .arg(out.path())
            .output()
            .expect("run score");
        let stderr = String::from_utf8_lossy(&cli.stderr).into_owned();
        // The lines the command refuses, and the lines without an answer.
        let mut expected: Vec<u64> = stderr
            .lines()
            .filter_map(|l| l.split(": line ").nth(1))
            .filter_map(|rest| rest.split(':').next()?.parse().ok())
            .collect();
        expected.extend(lines_without_a_reply(&text));
        expected.sort_unstable();
        expected.dedup();

        let (status, _, body) = post(
            &server,
            "parity",
            &format!("model={model}"),
            Some(&token),
            text,
            None,
        )
        .await;
        if !expected.is_empty() {
            assert_eq!(status, 422, "{name}: {body}");
            let mut lines: Vec<u64> = body["problems"]
                .as_array()
                .expect("problems")
                .iter()
                .map(|p| p["line"].as_u64().expect("line"))
                .collect();
            lines.dedup();
            assert_eq!(lines, expected, "{name}");
            refused.push(model);
            continue;
        }
        assert!(cli.status.success(), "{name}: {stderr}");
        assert_eq!(status, 201, "{name}: {body}");
        accepted.push(model.clone());
        // Tables: the same numbers as the command's meta_performance file.
        let meta: Value = serde_json::from_str(
            &std::fs::read_to_string(
                out.path()
                    .join("meta_performance")
                    .join(format!("enact_ordering_{model}.json")),
            )
            .expect("meta"),
        )
        .expect("meta json");
        let report = &body["scores"]["report"];
        for group in [
            "overall",
            "forward_world_modeling",
            "inverse_world_modeling",
        ] {
            let ours = &report[group];
            let theirs = &meta["overall_performance"][group];
            for key in ["count", "task_accuracy", "pairwise_accuracy"] {
                assert_eq!(ours[key], theirs[key], "{name} {group} {key}");
            }
            for l in 3..=10 {
                for key in ["count", "task_accuracy", "pairwise_accuracy"] {
                    assert_eq!(
                        ours["per_step"][l.to_string()][key],
                        theirs["per_step"][format!("{l}_steps")][key],
                        "{name} {group} L={l} {key}"
                    );
                }
            }
        }
        // Per-item verdicts: the same as the command's detailed_eval lines.
        let detailed = std::fs::read_to_string(
            out.path()
                .join("detailed_eval")
                .join(format!("enact_ordering_{model}.jsonl")),
        )
        .expect("detailed");
        let cli_items: HashMap<String, Value> = detailed
            .lines()
            .map(|l| {
                let v: Value = serde_json::from_str(l).expect("json");
                (v["id"].as_str().expect("id").to_owned(), v)
            })
            .collect();
        let (status, full) = get_authed(
            &server,
            &format!("/api/v1/submissions/{}", body["id"]),
            &token,
        )
        .await;
        assert_eq!(status, 200);
        let items = full["items"].as_array().expect("items");
        assert_eq!(items.len(), cli_items.len(), "{name}");
        for item in items {
            let theirs = &cli_items[item["id"].as_str().expect("id")];
            let metrics = &theirs["eval_metrics"];
            assert_eq!(item["outcome"], theirs["outcome"], "{name} {}", item["id"]);
            assert_eq!(item["line"], theirs["line"], "{name} {}", item["id"]);
            assert_eq!(
                item["exact_match"], metrics["exact_match"],
                "{name} {}",
                item["id"]
            );
            assert_eq!(
                item["semantic_match"], metrics["semantic_match"],
                "{name} {}",
                item["id"]
            );
            assert_eq!(
                item["task_accuracy"], metrics["task_accuracy"],
                "{name} {}",
                item["id"]
            );
            assert_eq!(
                item["pairwise_accuracy"].as_f64(),
                metrics["pairwise_accuracy"].as_f64(),
                "{name} {}",
                item["id"]
            );
            assert_eq!(
                item["permutation"], theirs["model_answer"],
                "{name} {}",
                item["id"]
            );
            assert_eq!(
                item["ground_truth"], theirs["ground_truth"],
                "{name} {}",
                item["id"]
            );
        }
    }
    for must_refuse in ["malformed", "dupids"] {
        assert!(
            refused.iter().any(|m| m == must_refuse),
            "{must_refuse} must be refused: {refused:?}"
        );
    }
    assert!(
        accepted.len() >= 10,
        "accepted {accepted:?}, refused {refused:?}"
    );
    eprintln!("accepted {accepted:?}; refused {refused:?}");
    // Only the accepted files are stored; the board shows them all.
    assert_eq!(
        stored_counts(&server.pool).await,
        (accepted.len() as i64, 96 * accepted.len() as i64)
    );
    let html = server
        .get("/leaderboard/parity")
        .await
        .text()
        .await
        .expect("html");
    for model in &accepted {
        assert!(
            html.contains(model.as_str()),
            "{model} missing from the page"
        );
    }
    // The chart draws the best ten models (one line in each of its two panels).
    let drawn = accepted.len().min(enact_hub::core::leaderboard::CHART_TOP);
    assert_eq!(html.matches("<polyline").count(), 2 * drawn);
    server.stop().await;
}
