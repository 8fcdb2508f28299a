//! Two `enact-hub serve` processes on one PostgreSQL database and one frame store behave as
//! one server: requests alternate between them and each sees what the other did. Runs in the
//! suite's PostgreSQL pass (`ENACT_HUB_TEST_POSTGRES`); the frames are in S3 when the run has
//! one (`AWS_ENDPOINT`), else in a shared folder.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use enact_hub::core::credentials::Role;
use enact_hub::store::{self, Pool};
use reqwest::StatusCode;
use serde_json::{Value, json};
use sha2::{Digest, Sha256};

use crate::annotate::{Browser, PASSWORD, annotator_on, assign_on};
use crate::helpers::*;

/// A server process; killed when dropped.
pub(crate) struct Instance {
    child: Child,
    pub(crate) base: String,
    /// Every line it wrote to standard output and standard error so far.
    log: Arc<Mutex<Vec<String>>>,
}

impl Instance {
    /// Starts `enact-hub serve` on `db` and `frames`, on a port of its own choosing.
    fn start(db: &str, frames: &str) -> Instance {
        Instance::start_with(db, &["--frames", frames], &[])
    }

    /// Starts `enact-hub serve --db db` with `args` and `env` besides, logging at `info`.
    pub(crate) fn start_with(db: &str, args: &[&str], env: &[(&str, &str)]) -> Instance {
        let mut child = Command::new(env!("CARGO_BIN_EXE_enact-hub"))
            .args(["serve", "--db", db, "--addr", "127.0.0.1:0"])
            .args(args)
            .envs(env.iter().copied())
            .env("RUST_LOG", "info")
            .env("NO_COLOR", "1")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start enact-hub serve");
        let log = Arc::new(Mutex::new(Vec::new()));
        // Standard output is read to the end, so the server never blocks on a full pipe.
        let stdout = BufReader::new(child.stdout.take().expect("stdout")).lines();
        let kept = log.clone();
        std::thread::spawn(move || {
            for line in stdout.map_while(Result::ok) {
                kept.lock().expect("the log").push(line);
            }
        });
        let mut lines = BufReader::new(child.stderr.take().expect("stderr")).lines();
        let base = loop {
            let line = lines
                .next()
                .expect("the server stopped before listening")
                .expect("read the server's log");
            log.lock().expect("the log").push(line.clone());
            if let Some(at) = line.find("listening on http://") {
                let address = &line[at + "listening on ".len()..];
                let end = address["http://".len()..]
                    .find('/')
                    .map_or(address.len(), |i| i + "http://".len());
                break address[..end].to_owned();
            }
        };
        let kept = log.clone();
        std::thread::spawn(move || {
            for line in lines.map_while(Result::ok) {
                kept.lock().expect("the log").push(line);
            }
        });
        Instance { child, base, log }
    }

    /// Its process id (which its job worker's lease owner names).
    pub(crate) fn pid(&self) -> u32 {
        self.child.id()
    }

    /// The lines it logged so far.
    pub(crate) fn log(&self) -> Vec<String> {
        self.log.lock().expect("the log").clone()
    }

    pub(crate) fn url(&self, path: &str) -> String {
        format!("{}{path}", self.base)
    }

    /// Sends `signal` (as `kill -s` names it: `INT`, `TERM`) to the process.
    pub(crate) fn signal(&self, signal: &str) {
        let sent = Command::new("kill")
            .args(["-s", signal, &self.pid().to_string()])
            .status()
            .expect("run kill");
        assert!(sent.success(), "kill -s {signal} {}", self.pid());
    }

    /// Waits up to `limit` for the process to end by itself: how it ended.
    pub(crate) async fn exit_within(&mut self, limit: Duration) -> std::process::ExitStatus {
        let deadline = Instant::now() + limit;
        loop {
            if let Some(status) = self.child.try_wait().expect("poll the server process") {
                return status;
            }
            assert!(
                Instant::now() < deadline,
                "the server still runs {limit:?} later; its log: {:#?}",
                self.log()
            );
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    }

    /// Stops the process at once, as a crash would (SIGKILL).
    pub(crate) fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        self.kill();
    }
}

/// Retries `check` for up to five seconds: announcements between instances arrive within
/// milliseconds, item changes within one poll (half a second).
async fn eventually<F, Fut>(what: &str, mut check: F)
where
    F: FnMut() -> Fut,
    Fut: std::future::Future<Output = bool>,
{
    let deadline = Instant::now() + Duration::from_secs(5);
    while !check().await {
        assert!(Instant::now() < deadline, "never happened: {what}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

/// Reloads `page` until it contains `needle` (for up to five seconds).
async fn page_shows(browser: &mut Browser, page: &str, needle: &str) {
    let deadline = Instant::now() + Duration::from_secs(5);
    loop {
        let (status, html) = browser.text(page).await;
        if status == StatusCode::OK && html.contains(needle) {
            return;
        }
        assert!(
            Instant::now() < deadline,
            "{page} never showed {needle}: {html}"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

async fn submit(
    client: &reqwest::Client,
    on: &Instance,
    token: &str,
    body: &str,
    key: Option<&str>,
) -> (StatusCode, Value) {
    let mut request = client
        .post(on.url("/api/v1/datasets/mini/submissions?model=m"))
        .bearer_auth(token)
        .body(body.to_owned());
    if let Some(key) = key {
        request = request.header("Idempotency-Key", key);
    }
    let r = request.send().await.expect("POST a submission");
    let status = r.status();
    (status, r.json().await.unwrap_or(Value::Null))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_instances_on_one_database_and_bucket_behave_as_one_server() {
    let Some(server) = postgres_server() else {
        eprintln!("no PostgreSQL server (ENACT_HUB_TEST_POSTGRES unset): skipping");
        return;
    };
    let dir = tempfile::tempdir().expect("tempdir");
    let db = new_postgres_database(&server).await;
    let pool = Pool::Pg(store::db::open_postgres(&db, 4).await.expect("migrate"));
    let frames = match std::env::var("AWS_ENDPOINT") {
        Ok(endpoint) if !endpoint.is_empty() => {
            let bucket = format!("enact-hub-instances-{}", std::process::id());
            let r = reqwest::Client::new()
                .put(format!("{}/{bucket}", endpoint.trim_end_matches('/')))
                .send()
                .await
                .expect("create a bucket");
            assert!(r.status().is_success());
            format!("s3://{bucket}/frames")
        }
        _ => format!("file://{}", dir.path().join("objects").display()),
    };

    // The operator imports a release, frames into the shared store, then starts two servers.
    let root = dir.path().join("release");
    let records = write_release(&root, &[3, 4]);
    let out = enact_hub()
        .arg("import")
        .arg(&root)
        .args(["--dataset", "mini", "--db", &db, "--frames", &frames])
        .output()
        .expect("import");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut a = Instance::start(&db, &frames);
    let b = Instance::start(&db, &frames);
    let client = reqwest::Client::new();

    // Frames are served by both, from the shared store.
    let image =
        std::fs::read(root.join(records[0]["images"][1].as_str().expect("path"))).expect("image");
    let hash = hex::encode(Sha256::digest(&image));
    for instance in [&a, &b] {
        let r = client
            .get(instance.url(&format!("/api/v1/frames/{hash}")))
            .send()
            .await
            .expect("GET frame");
        assert_eq!(r.status(), StatusCode::OK);
        assert_eq!(r.bytes().await.expect("bytes").as_ref(), image.as_slice());
    }

    // A session started on one instance works on the other.
    let alice = annotator_on(&pool, "alice", false).await;
    let ids: Vec<String> = records
        .iter()
        .map(|r| r["id"].as_str().expect("id").to_owned())
        .collect();
    let refs: Vec<&str> = ids.iter().map(String::as_str).collect();
    assign_on(&pool, "mini", alice, &refs).await;
    let mut browser = Browser::at(&a.base);
    let r = browser.login("alice", PASSWORD).await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);
    browser.switch_to(&b.base);
    let csrf = browser.csrf("/annotate").await;

    // A draft saved on A is resumed on B, though B read the item (and kept its standing) first.
    let item = &ids[0];
    let page = format!("/annotate/mini/{item}");
    // Read twice: the first opening creates the draft, the second leaves B holding her standing.
    browser.get(&page).await;
    let (status, html) = browser.text(&page).await;
    assert_eq!(status, StatusCode::OK);
    assert!(html.contains("&#34;slots&#34;:[null,null]"), "{html}");
    browser.switch_to(&a.base);
    let counts = json!({"placements": 1, "swaps": 0, "clears": 0, "undos": 0});
    let r = browser
        .post_json(
            &format!("{page}/draft"),
            Some(&csrf),
            &json!({"slots": [null, 1], "counts": counts}),
        )
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    browser.switch_to(&b.base);
    page_shows(&mut browser, &page, "&#34;slots&#34;:[null,1]").await;

    // An answer finished on A is refused as a draft on B.
    browser.switch_to(&a.base);
    let r = browser
        .post_json(
            &format!("{page}/submit"),
            Some(&csrf),
            &json!({"slots": [2, 1], "counts": counts}),
        )
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    browser.switch_to(&b.base);
    let r = browser
        .post_json(
            &format!("{page}/draft"),
            Some(&csrf),
            &json!({"slots": [1, null], "counts": counts}),
        )
        .await;
    assert_eq!(r.status(), StatusCode::CONFLICT);

    // A logout on A ends the session on B, which had it in memory.
    assert_eq!(browser.get("/annotate").await.status(), StatusCode::OK);
    let cookie = browser.cookie_header();
    browser.switch_to(&a.base);
    let csrf_now = browser.csrf("/annotate").await;
    let r = browser.post_form("/logout", &[("csrf", &csrf_now)]).await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);
    let no_redirects = reqwest::Client::builder()
        .redirect(reqwest::redirect::Policy::none())
        .build()
        .expect("client");
    eventually("B refuses the session ended on A", || {
        let request = no_redirects
            .get(b.url("/annotate"))
            .header("cookie", cookie.clone());
        async move {
            let r = request.send().await.expect("GET /annotate");
            r.status() == StatusCode::SEE_OTHER
                && r.headers()["location"]
                    .to_str()
                    .is_ok_and(|l| l.starts_with("/login"))
        }
    })
    .await;

    let empty_board = client
        .get(b.url("/api/v1/datasets/mini/leaderboard"))
        .send()
        .await
        .expect("GET leaderboard");
    assert_eq!(empty_board.status(), StatusCode::OK);

    // A token's quota is shared: two submissions a day, one on each instance, then 429.
    let (_, token) = api_token(&pool, "team", Role::Submitter, Some(2), None).await;
    let body = answers(&records, &[]);
    let (first, one) = submit(&client, &a, &token, &body, Some("k1")).await;
    assert_eq!(first, StatusCode::CREATED, "{one}");
    // The idempotent repeat on B returns A's submission (and counts no attempt).
    let (again, same) = submit(&client, &b, &token, &body, Some("k1")).await;
    assert_eq!(again, StatusCode::OK, "{same}");
    assert_eq!(same["id"], one["id"]);
    let (second, _) = submit(&client, &b, &token, &body, None).await;
    assert_eq!(second, StatusCode::CREATED);
    let (third, refusal) = submit(&client, &a, &token, &body, None).await;
    assert_eq!(third, StatusCode::TOO_MANY_REQUESTS, "{refusal}");

    // B's leaderboard, read (and kept) before, shows the team's two submissions, made on A
    // and on B.
    eventually("B's leaderboard counts both submissions", || {
        let url = b.url("/api/v1/datasets/mini/leaderboard");
        let client = client.clone();
        async move {
            let board: Value = client
                .get(url)
                .send()
                .await
                .expect("GET leaderboard")
                .json()
                .await
                .expect("json");
            board["rows"].as_array().is_some_and(|rows| {
                rows.iter()
                    .any(|r| r["account"] == "team" && r["attempts"] == 2)
            })
        }
    })
    .await;

    // An import made while both run is served by both.
    let other = dir.path().join("other");
    write_release(&other, &[5]);
    let out = enact_hub()
        .arg("import")
        .arg(&other)
        .args(["--dataset", "other", "--db", &db, "--frames", &frames])
        .output()
        .expect("import");
    assert!(out.status.success());
    for instance in [&a, &b] {
        let url = instance.url("/api/v1/datasets/other/items");
        eventually("the new dataset is served", || {
            let (client, url) = (client.clone(), url.clone());
            async move { client.get(url).send().await.expect("GET").status() == StatusCode::OK }
        })
        .await;
    }

    // Killing A with writes in flight loses nothing it acknowledged and leaves nothing
    // half-written: a writer posts to A without pause, A is killed once it has acknowledged
    // three, and B serves every submission A answered 201 to, each with all its verdicts.
    let (_, token) = api_token(&pool, "crash", Role::Submitter, None, None).await;
    let last_before = count(&pool, "SELECT coalesce(max(id), 0) FROM submissions").await;
    let (acked, mut acknowledgements) = tokio::sync::mpsc::unbounded_channel();
    let writer = {
        let (client, url, token, body) = (
            client.clone(),
            a.url("/api/v1/datasets/mini/submissions?model=m"),
            token.clone(),
            body.clone(),
        );
        tokio::spawn(async move {
            let mut sent = 0_i64;
            loop {
                sent += 1;
                let reply = client.post(&url).bearer_auth(&token).body(body.clone());
                // A refused connection or a cut reply is the kill; any other status is not.
                let Ok(reply) = reply.send().await else { break };
                assert_eq!(reply.status(), StatusCode::CREATED, "submission {sent}");
                let Ok(json) = reply.json::<Value>().await else {
                    break;
                };
                if acked.send(json["id"].clone()).is_err() {
                    break;
                }
            }
            sent
        })
    };
    let mut acknowledged = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(60);
    while acknowledged.len() < 3 {
        let id = tokio::time::timeout_at(deadline.into(), acknowledgements.recv())
            .await
            .expect("A acknowledged three submissions within a minute")
            .expect("the writer stopped before A was killed");
        acknowledged.push(id);
    }
    a.kill();
    let sent = writer.await.expect("the writer");
    while let Ok(id) = acknowledgements.try_recv() {
        acknowledged.push(id);
    }
    for id in &acknowledged {
        let r = client
            .get(b.url(&format!("/api/v1/submissions/{id}")))
            .bearer_auth(&token)
            .send()
            .await
            .expect("GET submission");
        assert_eq!(r.status(), StatusCode::OK, "submission {id}");
    }
    // The write the kill cut landed whole or not at all.
    let since = format!("FROM submissions s WHERE s.id > {last_before}");
    let stored = count(&pool, &format!("SELECT count(*) {since}")).await;
    let acknowledged = acknowledged.len() as i64;
    assert!(
        (acknowledged..=sent).contains(&stored),
        "{stored} submissions stored, {acknowledged} acknowledged, {sent} sent"
    );
    assert_eq!(
        count(
            &pool,
            &format!(
                "SELECT count(*) {since} AND (SELECT count(*) FROM submission_items i \
                 WHERE i.submission = s.id) != (SELECT count(*) FROM items i \
                 WHERE i.dataset_id = s.dataset)"
            )
        )
        .await,
        0,
        "a submission without all its verdicts"
    );
    drop(b);
}

/// The backend of the connection this database's change feed listens on (`LISTEN`), other
/// than `not`, once there is one (for up to five seconds).
async fn listening_backend(pool: &Pool, not: Option<i32>) -> i32 {
    let deadline = Instant::now() + Duration::from_secs(5);
    loop {
        let found: Option<i32> = db!(
            pool,
            fetch_optional,
            sqlx::query_scalar(
                "SELECT pid FROM pg_stat_activity WHERE datname = current_database() \
                 AND query ILIKE 'LISTEN%' AND pid IS DISTINCT FROM $1"
            )
            .bind(not)
        )
        .expect("read pg_stat_activity");
        if let Some(pid) = found {
            return pid;
        }
        assert!(Instant::now() < deadline, "no listening connection");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}

/// When the connection an instance listens for announcements on drops, announcements may have
/// been lost meanwhile, so it clears every cache; then it listens again.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_dropped_listening_connection_clears_every_cache_and_listening_resumes() {
    if postgres_server().is_none() {
        eprintln!("no PostgreSQL server (ENACT_HUB_TEST_POSTGRES unset): skipping");
        return;
    }
    let (server, records) = spawn_app_with_release().await;
    let (_, token) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let item = records[0]["id"].as_str().expect("id");
    let shown = async |server: &TestServer| {
        let board = server.get_json("/api/v1/datasets/mini/leaderboard").await.1;
        let models: Vec<String> = board["rows"]
            .as_array()
            .expect("rows")
            .iter()
            .filter_map(|r| r["model"].as_str().map(str::to_owned))
            .collect();
        let item = server
            .get_json(&format!("/api/v1/datasets/mini/items/{item}"))
            .await
            .1;
        (
            models,
            item["question"].as_str().expect("question").to_owned(),
        )
    };
    let body = answers(&records, &[]);
    submit_to(&server, "mini", "model=first", &token, body.clone())
        .await
        .id();
    let (models, question) = shown(&server).await;
    assert_eq!(models, ["first"]);
    let listener = listening_backend(&server.pool, None).await;

    // Changed without an announcement (as when one is lost) or a new content generation: the
    // cached board and item stay as they were.
    db!(
        server.pool,
        execute,
        sqlx::query("UPDATE submissions SET model = 'renamed'")
    )
    .expect("rename behind the server's back");
    db!(
        server.pool,
        execute,
        sqlx::query("UPDATE items SET question = question || ' Edited.' WHERE item_id = $1")
            .bind(item)
    )
    .expect("edit behind the server's back");
    assert_eq!(shown(&server).await, (models, question.clone()));

    let killed: bool = db!(
        server.pool,
        fetch_one,
        sqlx::query_scalar("SELECT pg_terminate_backend($1)").bind(listener)
    )
    .expect("terminate the listening backend");
    assert!(killed);
    eventually("both caches are cleared", || async {
        shown(&server).await == (vec!["renamed".to_owned()], format!("{question} Edited."))
    })
    .await;

    // Listening again: what another instance announces reaches this one.
    listening_backend(&server.pool, Some(listener)).await;
    let dir = tempfile::tempdir().expect("tempdir");
    let other = enact_hub::app::Hub::from(server.pool.clone());
    let other = serve_hub(other, server.pool.clone(), dir, &Default::default()).await;
    submit_to(&other, "mini", "model=second", &token, body)
        .await
        .id();
    eventually("the other instance's submission is shown", || async {
        shown(&server).await.0.contains(&"second".to_owned())
    })
    .await;
    other.stop().await;
    server.stop().await;
}
