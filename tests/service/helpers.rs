//! Shared test set-up: fresh databases, releases written on the fly, a running server.

#![allow(dead_code)]

use std::net::SocketAddr;
use std::path::{Path, PathBuf};

use enact_hub::app::Hub;
use enact_hub::app::import::{BATCH_LINES, ImportOptions, ImportReport, import_release};
use enact_hub::core::audit::Actor;
use enact_hub::core::credentials::Role;
use enact_hub::store;
use enact_hub::store::Pool;
use enact_hub::web::{Server, WebConfig};
use serde_json::{Value, json};
use tempfile::TempDir;
use tokio::sync::oneshot;

pub use crate::fixtures::{fixtures_dir, shared_fixtures};

/// Runs a sqlx query (`$1` placeholders) on the test database, SQLite or PostgreSQL:
/// `db!(pool, fetch_one, sqlx::query_scalar::<_, i64>("SELECT …"))`.
macro_rules! db {
    // Each database has its own result type for a statement: only success is kept.
    ($pool:expr, execute, $query:expr) => {{
        let mut conn = $pool.acquire().await.expect("a database connection");
        enact_hub::store::on_db!(&mut conn, |c| $query.execute(&mut *c).await.map(|_| ()))
    }};
    ($pool:expr, $method:ident, $query:expr) => {{
        let mut conn = $pool.acquire().await.expect("a database connection");
        enact_hub::store::on_db!(&mut conn, |c| $query.$method(&mut *c).await)
    }};
}
pub(crate) use db;

/// A fresh, migrated database: a SQLite file in `dir`, or, when `ENACT_HUB_TEST_POSTGRES`
/// names a PostgreSQL server (`postgres://user@host:port`), a new database on it. The whole
/// suite runs once each way (`scripts/test.sh`).
pub async fn fresh_db(dir: &TempDir) -> Pool {
    fresh_db_located(dir).await.0
}

/// [`fresh_db`], and where it is as the command line's `--db` takes it (a file or a URL).
pub async fn fresh_db_located(dir: &TempDir) -> (Pool, PathBuf) {
    match postgres_server() {
        Some(server) => {
            let url = new_postgres_database(&server).await;
            let pool = store::db::open_postgres(&url, 4)
                .await
                .expect("open a fresh PostgreSQL database");
            (Pool::Pg(pool), PathBuf::from(url))
        }
        None => {
            let path = dir.path().join("test.db");
            let pool = store::open(&path).await.expect("open a fresh database");
            (Pool::Sqlite(pool), path)
        }
    }
}

/// The PostgreSQL server the suite runs against, if it does.
pub fn postgres_server() -> Option<String> {
    std::env::var("ENACT_HUB_TEST_POSTGRES")
        .ok()
        .filter(|url| !url.is_empty())
}

/// Creates an empty database on `server` and returns its URL.
pub async fn new_postgres_database(server: &str) -> String {
    use sqlx::Connection;
    static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let name = format!(
        "enact_test_{}_{}_{}",
        std::process::id(),
        NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos())
    );
    let server = server.trim_end_matches('/');
    let mut admin = sqlx::PgConnection::connect(&format!("{server}/postgres"))
        .await
        .expect("connect to the test PostgreSQL server");
    sqlx::query(&format!("CREATE DATABASE {name}"))
        .execute(&mut admin)
        .await
        .expect("create a test database");
    admin.close().await.ok();
    format!("{server}/{name}")
}

/// The database is SQLite (some tests check what only SQLite has: its file, `VACUUM INTO`).
pub fn on_sqlite() -> bool {
    postgres_server().is_none()
}

pub fn options(dataset: &str) -> ImportOptions {
    ImportOptions {
        dataset: dataset.to_owned(),
        skip_invalid: false,
        replace: false,
        progress: None,
        scene_graphs: None,
        batch_lines: BATCH_LINES,
        stop: None,
    }
}

/// The actor the tests' own setup steps are logged under.
pub fn tester() -> Actor {
    Actor::Operator("tests".to_owned())
}

pub async fn import(pool: &Pool, path: &Path, options: &ImportOptions) -> ImportReport {
    import_release(&Hub::from(pool.clone()), &tester(), path, options)
        .await
        .unwrap_or_else(|e| {
            panic!(
                "import of {} failed: {e}: {:?}",
                path.display(),
                e.details()
            )
        })
}

/// A tiny, distinct PNG for key frame `frame` with label `label` "drawn" as a colour.
pub fn png_bytes(frame: u32, label: usize) -> Vec<u8> {
    let img = image::RgbImage::from_fn(8, 8, |x, y| {
        image::Rgb([
            (frame % 251) as u8,
            (label * 20) as u8,
            ((x + y) * 10) as u8,
        ])
    });
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .expect("encode png");
    out.into_inner()
}

/// One valid QA record of an ENACT release, as a JSON object, with its image files written
/// under `root`. `n` makes ids and frames distinct.
pub fn write_record(root: &Path, task: &str, forward: bool, l: usize, n: u32) -> Value {
    let kind = if forward { "forward" } else { "inverse" };
    let item_type = format!("{kind}_world_modeling_ordering_{l}_steps");
    let id = format!("{task}_{item_type}_{n:08x}");
    let key_frame_ids: Vec<String> = (0..l)
        .map(|i| (n * 1000 + i as u32 * 211).to_string())
        .collect();
    let dir = format!("QA/images/{item_type}/{task}");
    std::fs::create_dir_all(root.join(&dir)).expect("create image dir");
    let mut images = Vec::new();
    for i in 0..l {
        let name = if i == 0 {
            format!("{dir}/{id}_cur_state.png")
        } else {
            format!("{dir}/{id}_next_state_{i}.png")
        };
        std::fs::write(root.join(&name), png_bytes(n * 1000 + i as u32 * 211, i))
            .expect("write png");
        images.push(name);
    }
    let heading = if forward {
        "## Actions in Order"
    } else {
        "## Shuffled Actions"
    };
    let mut question = format!("You are a capable agent.\n\n{heading}\n");
    for k in 1..l {
        question.push_str(&format!(
            "[Action {k}] The robot r1 becomes touching the object {k}.\n"
        ));
    }
    question.push_str("\nNow please provide your answer in the requested format.\n");
    let gt: Vec<usize> = (1..l).rev().collect();
    json!({
        "id": id,
        "type": item_type,
        "task_name": task,
        "key_frame_ids": key_frame_ids,
        "images": images,
        "question": question,
        "options": [],
        "gt_answer": gt,
    })
}

/// Writes `records` as `root/QA/enact_ordering.jsonl` (one raw line each) and returns its path.
pub fn write_qa_file(root: &Path, lines: &[String]) -> PathBuf {
    std::fs::create_dir_all(root.join("QA")).expect("create QA dir");
    let path = root.join("QA").join("enact_ordering.jsonl");
    std::fs::write(&path, lines.join("\n") + "\n").expect("write jsonl");
    path
}

/// A valid release with one forward and one inverse item for each L in `lengths`.
pub fn write_release(root: &Path, lengths: &[usize]) -> Vec<Value> {
    write_balanced_release(root, lengths, 1)
}

/// A release with `per_cell` items in every direction × L in `lengths`.
pub fn write_balanced_release(root: &Path, lengths: &[usize], per_cell: u32) -> Vec<Value> {
    let mut records = Vec::new();
    let mut n = 1;
    for &l in lengths {
        for forward in [true, false] {
            for _ in 0..per_cell {
                records.push(write_record(
                    root,
                    "cook_bacon_1749678308264596",
                    forward,
                    l,
                    n,
                ));
                n += 1;
            }
        }
    }
    let lines: Vec<String> = records.iter().map(Value::to_string).collect();
    write_qa_file(root, &lines);
    records
}

pub struct TestServer {
    pub addr: SocketAddr,
    pub pool: Pool,
    db: PathBuf,
    pub client: reqwest::Client,
    shutdown: Option<oneshot::Sender<()>>,
    handle: Option<tokio::task::JoinHandle<()>>,
    _dir: TempDir,
}

impl TestServer {
    /// The server's temporary folder (releases written by `setup` are here).
    pub fn dir(&self) -> &Path {
        self._dir.path()
    }

    /// The database the server runs on, as the command line's `--db` takes it.
    pub fn db_path(&self) -> PathBuf {
        self.db.clone()
    }

    pub fn url(&self, path: &str) -> String {
        format!("http://{}{}", self.addr, path)
    }

    pub async fn get(&self, path: &str) -> reqwest::Response {
        self.client
            .get(self.url(path))
            .send()
            .await
            .unwrap_or_else(|e| panic!("GET {path}: {e}"))
    }

    pub async fn get_json(&self, path: &str) -> (reqwest::StatusCode, Value) {
        let r = self.get(path).await;
        let status = r.status();
        let body = r
            .json::<Value>()
            .await
            .unwrap_or_else(|e| panic!("GET {path}: not JSON: {e}"));
        (status, body)
    }

    pub async fn stop(mut self) {
        if let Some(tx) = self.shutdown.take() {
            let _ = tx.send(());
        }
        if let Some(h) = self.handle.take() {
            h.await.expect("server task");
        }
    }
}

/// A server on 127.0.0.1:0 over a fresh database, with `setup` run on the database first.
pub async fn spawn_app_with<F, Fut>(setup: F) -> TestServer
where
    F: FnOnce(Pool, PathBuf) -> Fut,
    Fut: std::future::Future<Output = ()>,
{
    spawn_app_configured(WebConfig::default(), setup).await
}

/// [`spawn_app_with`] with a server configuration of the test's choosing.
pub async fn spawn_app_configured<F, Fut>(config: WebConfig, setup: F) -> TestServer
where
    F: FnOnce(Pool, PathBuf) -> Fut,
    Fut: std::future::Future<Output = ()>,
{
    let dir = tempfile::tempdir().expect("tempdir");
    let (pool, db) = fresh_db_located(&dir).await;
    setup(pool.clone(), dir.path().to_path_buf()).await;
    // The test's folder is also the folder import jobs may read releases from.
    let hub = Hub::from(pool.clone()).with_kept(enact_hub::app::import_jobs::ImportDir(Some(
        dir.path().to_path_buf(),
    )));
    let mut server = serve_hub(hub, pool, dir, &config).await;
    server.db = db;
    server
}

/// A server on 127.0.0.1:0 running `hub` (over `pool`, a database in `dir`).
pub async fn serve_hub(hub: Hub, pool: Pool, dir: TempDir, config: &WebConfig) -> TestServer {
    let server = Server::bind("127.0.0.1:0".parse().expect("addr"), hub, config)
        .await
        .expect("bind");
    let addr = server.local_addr().expect("local addr");
    let (tx, rx) = oneshot::channel();
    let handle = tokio::spawn(async move {
        server
            .run(async {
                let _ = rx.await;
            })
            .await
            .expect("server run");
    });
    TestServer {
        addr,
        pool,
        db: dir.path().join("test.db"),
        client: reqwest::Client::new(),
        shutdown: Some(tx),
        handle: Some(handle),
        _dir: dir,
    }
}

/// A server whose database holds a small generated release as dataset "mini" (L = 3 and 4).
pub async fn spawn_app_with_release() -> (TestServer, Vec<Value>) {
    spawn_app_with_release_as(&["mini"]).await
}

/// [`spawn_app_with_release`] with the release imported once under each of `datasets`.
pub async fn spawn_app_with_release_as(datasets: &[&str]) -> (TestServer, Vec<Value>) {
    let records = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let shared = records.clone();
    let server = spawn_app_with(|pool, dir| async move {
        *shared.lock().expect("lock") = import_small_release(&pool, &dir, datasets).await;
    })
    .await;
    let records = records.lock().expect("lock").clone();
    (server, records)
}

/// [`spawn_app_with_release`], the server's hub opened as `enact-hub serve` opens it: on
/// SQLite with the write gate's own connection, which polls for the write lock, and the
/// write-ahead log checkpointed beside it. (Other tests' servers write on the test's pool.)
pub async fn spawn_serving_app_with_release() -> (TestServer, Vec<Value>) {
    let dir = tempfile::tempdir().expect("tempdir");
    let (pool, db) = fresh_db_located(&dir).await;
    let records = import_small_release(&pool, dir.path(), &["mini"]).await;
    let hub = Hub::open_serving(&db, &enact_hub::app::cache::CacheLimits::default())
        .await
        .expect("open the database as a server does")
        .with_kept(enact_hub::app::import_jobs::ImportDir(Some(
            dir.path().to_path_buf(),
        )));
    let mut server = serve_hub(hub, pool, dir, &WebConfig::default()).await;
    server.db = db;
    (server, records)
}

/// Writes the small generated release (L = 3 and 4) into `dir` and imports it once under
/// each of `datasets`; its records.
async fn import_small_release(pool: &Pool, dir: &Path, datasets: &[&str]) -> Vec<Value> {
    let root = dir.join("release");
    let written = write_release(&root, &[3, 4]);
    for dataset in datasets {
        import(pool, &root, &options(dataset)).await;
    }
    written
}

impl TestServer {
    /// A page asked for in `language` (an `Accept-Language` value): its status and text.
    pub async fn page_in(&self, path: &str, language: &str) -> (reqwest::StatusCode, String) {
        let page = self
            .client
            .get(self.url(path))
            .header("accept-language", language)
            .send()
            .await
            .unwrap_or_else(|e| panic!("GET {path}: {e}"));
        let status = page.status();
        (status, page.text().await.expect("a page's text"))
    }
}

/// A request to the test server, built step by step and sent once.
pub struct Call {
    what: String,
    request: reqwest::RequestBuilder,
}

/// A response read whole: status, headers and body.
pub struct Reply {
    pub status: reqwest::StatusCode,
    pub headers: reqwest::header::HeaderMap,
    pub text: String,
}

impl TestServer {
    /// `method path`, relative to the server; add a token, headers and a body, then send.
    pub fn call(&self, method: reqwest::Method, path: &str) -> Call {
        Call {
            what: format!("{method} {path}"),
            request: self.client.request(method, self.url(path)),
        }
    }
}

impl Call {
    pub fn bearer(self, token: &str) -> Call {
        Call {
            request: self.request.bearer_auth(token),
            ..self
        }
    }

    pub fn header(self, name: &str, value: &str) -> Call {
        Call {
            request: self.request.header(name, value),
            ..self
        }
    }

    pub fn json(self, body: &Value) -> Call {
        Call {
            request: self.request.json(body),
            ..self
        }
    }

    pub fn body(self, body: impl Into<reqwest::Body>) -> Call {
        Call {
            request: self.request.body(body),
            ..self
        }
    }

    pub async fn send(self) -> Reply {
        let response = self
            .request
            .send()
            .await
            .unwrap_or_else(|e| panic!("{}: {e}", self.what));
        Reply {
            status: response.status(),
            headers: response.headers().clone(),
            text: response.text().await.unwrap_or_default(),
        }
    }

    /// Sends and checks the status, naming the request and showing the body when it differs.
    pub async fn expect(self, status: u16) -> Reply {
        let what = self.what.clone();
        let reply = self.send().await;
        assert_eq!(reply.status, status, "{what}: {}", reply.text);
        reply
    }
}

impl Reply {
    /// The body as JSON (`null` when it is not JSON).
    pub fn json(&self) -> Value {
        serde_json::from_str(&self.text).unwrap_or(Value::Null)
    }

    /// The `id` of the JSON body.
    pub fn id(&self) -> i64 {
        self.json()["id"].as_i64().expect("an id in the body")
    }

    /// The `error` message of a JSON error body.
    pub fn error(&self) -> String {
        self.json()["error"]
            .as_str()
            .unwrap_or_else(|| panic!("not an error body: {}", self.text))
            .to_owned()
    }
}

/// Posts a submission body to `dataset` as `token`; `query` carries the model and metadata.
pub async fn submit_to(
    server: &TestServer,
    dataset: &str,
    query: &str,
    token: &str,
    body: impl Into<reqwest::Body>,
) -> Reply {
    server
        .call(
            reqwest::Method::POST,
            &format!("/api/v1/datasets/{dataset}/submissions?{query}"),
        )
        .bearer(token)
        .body(body)
        .send()
        .await
}

/// Compact lines answering every record of a release with its ground truth written as text
/// (`"[2, 1]"`, as models answer), reversed for the records at the indices in `wrong`.
pub fn answers(records: &[Value], wrong: &[usize]) -> String {
    records
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let mut gt: Vec<u64> = r["gt_answer"]
                .as_array()
                .expect("gt")
                .iter()
                .map(|v| v.as_u64().expect("label"))
                .collect();
            if wrong.contains(&i) {
                gt.reverse();
            }
            json!({"id": r["id"], "answer": format!("{gt:?}")}).to_string() + "\n"
        })
        .collect()
}

/// Compact answers (`{"id", "answer"}` lines) equal to each record's ground truth.
pub fn ground_truth_answers(records: &[Value]) -> String {
    records
        .iter()
        .map(|r| json!({"id": r["id"], "answer": r["gt_answer"]}).to_string() + "\n")
        .collect()
}

/// A new API token for the account `name` (created with `role` if new), as the admin
/// endpoints issue them: its id and secret.
pub async fn api_token(
    pool: &Pool,
    name: &str,
    role: Role,
    daily_quota: Option<i64>,
    total_quota: Option<i64>,
) -> (i64, String) {
    let created = enact_hub::app::tokens::issue(
        &Hub::from(pool.clone()),
        &tester(),
        name,
        role,
        daily_quota,
        total_quota,
    )
    .await
    .expect("token issued");
    (created.id, created.token)
}

/// The `enact-hub` binary built for these tests.
pub fn enact_hub() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_enact-hub"))
}

/// Creates the study `name` over `mini` (from [`spawn_app_with_release`]) with one variant:
/// the same release imported again as `mini-copy` (on first use).
pub async fn mini_study(server: &TestServer, name: &str) {
    let hub = Hub::from(server.pool.clone());
    if enact_hub::app::datasets::by_name(&hub, "mini-copy")
        .await
        .is_err()
    {
        let root = server.dir().join("release");
        import(&server.pool, &root, &options("mini-copy")).await;
    }
    let copy =
        enact_hub::core::study::VariantSpec::new("Copy", "same", "mini-copy").expect("variant");
    enact_hub::app::studies::create(&hub, &tester(), name, "mini", &[copy])
        .await
        .expect("study created");
}

/// `SELECT count(*) …` (or any one integer) on the test database.
pub async fn count(pool: &Pool, sql: &str) -> i64 {
    db!(pool, fetch_one, sqlx::query_scalar::<_, i64>(sql)).unwrap_or_else(|e| panic!("{sql}: {e}"))
}

/// A write transaction for a test's own rows. The store's write functions take only a
/// transaction holding a turn of a write gate; a test writing beside a server takes one of its
/// own gate (the database's lock still serialises it with the server's writers).
pub async fn write_tx(pool: &Pool) -> store::Tx {
    let turn = store::gate::WriteGate::default()
        .enter(store::gate::Lane::Bulk)
        .await;
    pool.begin()
        .await
        .expect("a write transaction")
        .holding(turn)
}

/// Makes dataset `mini`'s ground truth and per-item verdicts public, or hides them again.
pub async fn set_mini_answers(pool: &Pool, answers: enact_hub::core::dataset::AnswerVisibility) {
    let mut tx = write_tx(pool).await;
    let dataset = store::datasets::by_name(&mut tx, "mini")
        .await
        .expect("query")
        .expect("mini");
    store::submissions::set_answer_visibility(&mut tx, dataset.id, answers)
        .await
        .expect("set answers");
    tx.commit().await.expect("commit");
}

/// The lines of a second version of a release: every question with another last line.
pub fn with_changed_questions(records: &[Value]) -> Vec<String> {
    records
        .iter()
        .map(|r| {
            let mut r = r.clone();
            let q = r["question"]
                .as_str()
                .expect("question")
                .replace("Now please", "Please");
            r["question"] = Value::String(q);
            r.to_string()
        })
        .collect()
}

/// sha256 over everything a dataset's items hold: fields, images, frames and signatures (not
/// row ids), to compare what two imports stored.
pub async fn dataset_digest(pool: &Pool, dataset: &str) -> String {
    use sha2::{Digest, Sha256};
    let rows: Vec<(String, String, i64, String, String)> = db!(
        pool,
        fetch_all,
        sqlx::query_as(
            "SELECT i.item_id, i.content_hash, i.source_line, i.question || i.gt_answer, \
             coalesce((SELECT s.source || s.signatures FROM item_signatures s \
             WHERE s.item = i.id), '') FROM items i JOIN datasets d ON d.id = i.dataset_id \
             WHERE d.name = $1 ORDER BY i.item_id"
        )
        .bind(dataset)
    )
    .expect("items");
    let images: Vec<(String, i64, String, String)> = db!(
        pool,
        fetch_all,
        sqlx::query_as(
            "SELECT i.item_id, ii.position, ii.path, f.sha256 FROM item_images ii \
             JOIN items i ON i.id = ii.item JOIN frames f ON f.id = ii.frame \
             JOIN datasets d ON d.id = i.dataset_id WHERE d.name = $1 \
             ORDER BY i.item_id, ii.position"
        )
        .bind(dataset)
    )
    .expect("images");
    hex::encode(Sha256::digest(format!("{rows:?}{images:?}").as_bytes()))
}
