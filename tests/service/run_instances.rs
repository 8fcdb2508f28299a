//! Server-side model runs worked by real `enact-hub serve` processes: a run survives its
//! server's SIGKILL and restart; with two instances on one PostgreSQL database, the other
//! takes over the run of the one killed; and the endpoint key's value is in no table, log line,
//! page, API reply or backup.

use std::collections::HashMap;
use std::path::Path;
use std::time::{Duration, Instant};

use enact_hub::core::credentials::Role;
use enact_hub::store::Pool;
use reqwest::StatusCode;
use serde_json::{Value, json};

use crate::annotate::{Browser, PASSWORD, annotator_on};
use crate::helpers::*;
use crate::instances::Instance;
use crate::runs::{
    SECRET_KEY, answer_text, run_fixture_located, scripts, stored_submission, task_accuracy,
};
use crate::standin::{ItemCalls, StandIn, StandInConfig, Step};

use crate::server_runs::KEY_VARIABLE;

/// Items answered wrong by the stand-in (by index), so the scores are not all right.
const WRONG: [usize; 3] = [1, 5, 9];

/// Requests in flight per run: at most this many items can be answered twice across a kill
/// (answered by the stand-in, the server killed before the reply was committed).
const CONCURRENCY: usize = 2;

/// `serve` on `db` allowing the stand-in's key variable, with a 2-second job lease.
fn instance(db: &str) -> Instance {
    Instance::start_with(
        db,
        &["--endpoint-key", KEY_VARIABLE, "--job-lease", "2"],
        &[(KEY_VARIABLE, SECRET_KEY)],
    )
}

async fn standin(root: &Path, records: &[Value]) -> StandIn {
    StandIn::start(StandInConfig {
        scripts: scripts(root, records, |i, r| {
            vec![Step::Answer(answer_text(r, !WRONG.contains(&i)))]
        }),
        latency: Duration::from_millis(150),
        tokens_per_image: 85,
        ..StandInConfig::default()
    })
    .await
}

/// What the tests keep of every reply, to search for the key at the end.
#[derive(Default)]
struct Seen(Vec<String>);

impl Seen {
    async fn get(&mut self, client: &reqwest::Client, url: &str, token: &str) -> Value {
        let r = client
            .get(url)
            .bearer_auth(token)
            .send()
            .await
            .expect("GET");
        assert_eq!(r.status(), StatusCode::OK, "{url}");
        let text = r.text().await.expect("a body");
        self.0.push(text.clone());
        serde_json::from_str(&text).expect("JSON")
    }
}

async fn start_run(
    client: &reqwest::Client,
    on: &Instance,
    token: &str,
    standin: &StandIn,
    seen: &mut Seen,
) -> i64 {
    let r = client
        .post(on.url("/api/v1/admin/runs"))
        .bearer_auth(token)
        .json(&json!({
            "dataset": "mini", "endpoint": standin.endpoint(), "model": "standin-vl",
            "name": "served", "temperature": 0, "key_variable": KEY_VARIABLE,
            "concurrency": CONCURRENCY, "max_retries": 2, "timeout_s": 10,
            "price_input": 2.5, "price_output": 10, "submit_as": "Stand-in VL",
        }))
        .send()
        .await
        .expect("POST a run");
    assert_eq!(r.status(), StatusCode::ACCEPTED);
    let text = r.text().await.expect("a body");
    seen.0.push(text.clone());
    let started: Value = serde_json::from_str(&text).expect("JSON");
    started["run"].as_i64().expect("a run id")
}

async fn stored_rows(pool: &Pool) -> usize {
    count(pool, "SELECT count(*) FROM model_run_items").await as usize
}

async fn stored_items(pool: &Pool) -> Vec<String> {
    db!(
        pool,
        fetch_all,
        sqlx::query_scalar::<_, String>(
            "SELECT i.item_id FROM model_run_items r JOIN items i ON i.id = r.item"
        )
    )
    .expect("stored items")
}

/// Waits until at least `rows` items are stored, and checks that the API shows the run's
/// progress meanwhile.
async fn wait_for_rows(pool: &Pool, rows: usize, records: usize) {
    let deadline = Instant::now() + Duration::from_secs(60);
    while stored_rows(pool).await < rows {
        assert!(Instant::now() < deadline, "the run made no progress");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    assert!(
        stored_rows(pool).await < records,
        "the run finished before it could be killed"
    );
}

/// Polls the run over the API until its job is done.
async fn wait_done(
    client: &reqwest::Client,
    on: &Instance,
    token: &str,
    run: i64,
    seen: &mut Seen,
) -> Value {
    let deadline = Instant::now() + Duration::from_secs(90);
    loop {
        let shown = seen
            .get(client, &on.url(&format!("/api/v1/admin/runs/{run}")), token)
            .await;
        if shown["state"] == "done" {
            return shown;
        }
        assert!(Instant::now() < deadline, "the run never finished: {shown}");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

/// After a kill part-way: an item stored before the kill was never asked again, every item
/// was answered, and only items in flight at the kill were answered twice.
fn assert_asked_once(
    records: &[Value],
    stored_at_kill: &[String],
    at_kill: &HashMap<String, ItemCalls>,
    calls: &HashMap<String, ItemCalls>,
) {
    for id in stored_at_kill {
        assert_eq!(
            calls[id].requests, at_kill[id].requests,
            "{id} was asked again after it was stored"
        );
    }
    for r in records {
        let id = r["id"].as_str().expect("id");
        assert!(calls[id].answered >= 1, "{id} never answered: {calls:?}");
        if !at_kill.contains_key(id) {
            // Not yet asked at the kill: asked by the instance that took over only, once.
            assert_eq!(calls[id].requests, 1, "{id} asked twice: {calls:?}");
        }
    }
    let twice = calls.values().filter(|c| c.answered > 1).count();
    assert!(
        twice <= CONCURRENCY,
        "{twice} items answered twice (at most the {CONCURRENCY} in flight at the kill may be)"
    );
}

/// The final state, submission and scores of a run over `records` that the stand-in answered.
async fn assert_finished(pool: &Pool, shown: &Value, records: &[Value]) {
    assert_eq!(shown["progress"]["stage"], "submitted", "{shown}");
    assert_eq!(shown["progress"]["answered"], records.len(), "{shown}");
    assert_eq!(shown["progress"]["failed"], 0, "{shown}");
    let submission = shown["submission"].as_i64().expect("a submission");
    let stored = stored_submission(pool, submission).await;
    assert_eq!(stored.scores.coverage.answered, records.len());
    let expected = (records.len() - WRONG.len()) as f64 / records.len() as f64;
    assert!((task_accuracy(&stored) - expected).abs() < 1e-9);
}

/// The run's admin pages and downloads, read as an admin would in a browser: the list, the
/// run's page with its progress and responses, the progress its script polls, and the
/// model-output JSONL. The public side hides the run (the dataset's answers are hidden).
async fn read_pages(pool: &Pool, on: &Instance, run: i64, records: &[Value], seen: &mut Seen) {
    annotator_on(pool, "boss", true).await;
    let mut browser = Browser::at(&on.base);
    let r = browser.login("boss", PASSWORD).await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);
    let (status, list) = browser.text("/admin/runs").await;
    assert_eq!(status, StatusCode::OK);
    assert!(
        list.contains("served") && list.contains(KEY_VARIABLE),
        "{list}"
    );
    let (status, page) = browser.text(&format!("/admin/runs/{run}")).await;
    assert_eq!(status, StatusCode::OK);
    assert!(page.contains("done (submitted)"), "{page}");
    assert!(
        page.contains(&format!("{} of {}", records.len(), records.len())),
        "{page}"
    );
    assert!(page.contains("/static/run_progress.js"), "{page}");
    let (status, progress) = browser.text(&format!("/admin/runs/{run}/progress")).await;
    assert_eq!(status, StatusCode::OK);
    let progress: Value = serde_json::from_str(&progress).expect("JSON progress");
    assert_eq!(progress["progress"]["done"], records.len());
    let (status, jsonl) = browser
        .text(&format!("/admin/runs/{run}/responses.jsonl"))
        .await;
    assert_eq!(status, StatusCode::OK);
    let lines: Vec<Value> = jsonl
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect();
    assert_eq!(lines.len(), records.len());
    let by_id: HashMap<&str, &Value> = records
        .iter()
        .map(|r| (r["id"].as_str().expect("id"), r))
        .collect();
    for line in &lines {
        let record = by_id[line["id"].as_str().expect("id")];
        assert_eq!(line["gt_answer"], record["gt_answer"]);
        assert_eq!(line["key_frame_ids"], record["key_frame_ids"]);
        assert!(line["answer"].is_string(), "{line}");
        assert!(line["type"].is_string() && line["task_name"].is_string());
    }
    let (status, _) = browser.text(&format!("/runs/{run}")).await;
    assert_eq!(
        status,
        StatusCode::NOT_FOUND,
        "a hidden dataset's run is public"
    );
    seen.0.extend([list, page, jsonl]);
}

/// Every value of every table, hex-encoded and lower-cased (so any column type can be
/// searched the same way on SQLite and PostgreSQL).
async fn dump_tables(pool: &Pool) -> String {
    let mut dump = String::new();
    for table in enact_hub::store::copy::TABLES {
        let sql = match pool {
            Pool::Sqlite(_) => {
                let columns: Vec<String> = table
                    .columns()
                    .map(|c| format!("coalesce(lower(hex(\"{c}\")), '')"))
                    .collect();
                format!("SELECT {} FROM {}", columns.join(" || ',' || "), table.name)
            }
            Pool::Pg(_) => {
                let columns: Vec<String> = table
                    .columns()
                    .map(|c| {
                        format!("coalesce(encode(convert_to(\"{c}\"::text, 'UTF8'), 'hex'), '')")
                    })
                    .collect();
                format!("SELECT {} FROM {}", columns.join(" || ',' || "), table.name)
            }
        };
        let rows: Vec<String> = db!(pool, fetch_all, sqlx::query_scalar::<_, String>(&sql))
            .unwrap_or_else(|e| panic!("{sql}: {e}"));
        assert!(
            table.name != "model_runs" || !rows.is_empty(),
            "the dump missed the runs"
        );
        for row in rows {
            dump.push_str(&row);
            dump.push('\n');
        }
    }
    dump
}

/// The key's value is in no table, no log line of any instance, no page or API reply, and
/// no backup (`enact-hub backup`, a real process).
async fn assert_key_nowhere(
    pool: &Pool,
    db: &str,
    dir: &Path,
    instances: &[&Instance],
    seen: &Seen,
) {
    let dump = dump_tables(pool).await;
    assert!(
        dump.contains(&hex::encode("standin-vl")),
        "the dump holds the run"
    );
    assert!(
        !dump.contains(&hex::encode(SECRET_KEY)),
        "the key is in a table"
    );
    for instance in instances {
        let log = instance.log();
        assert!(
            log.iter().any(|l| l.contains("job worker started")),
            "the log was not captured: {log:?}"
        );
        assert!(
            log.iter().all(|l| !l.contains(SECRET_KEY)),
            "the key is in a log line"
        );
    }
    assert!(
        seen.0.iter().all(|r| !r.contains(SECRET_KEY)),
        "the key is in a reply"
    );
    let backup = dir.join("after-run.backup.db");
    let out = enact_hub()
        .args(["backup", "--db", db, "--out"])
        .arg(&backup)
        .output()
        .expect("enact-hub backup");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&backup).expect("the backup");
    assert!(bytes.len() > 4096, "an empty backup");
    assert!(
        !bytes
            .windows(SECRET_KEY.len())
            .any(|w| w == SECRET_KEY.as_bytes()),
        "the key is in the backup"
    );
    for output in [&out.stdout, &out.stderr] {
        assert!(!String::from_utf8_lossy(output).contains(SECRET_KEY));
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_server_run_survives_a_sigkill_and_finishes_when_the_server_starts_again() {
    let (dir, pool, records, db) = run_fixture_located(2).await;
    let db = db.to_str().expect("a UTF-8 location").to_owned();
    let standin = standin(&dir.path().join("release"), &records).await;
    let (_, admin) = api_token(&pool, "root", Role::Admin, None, None).await;
    let client = reqwest::Client::new();
    let mut seen = Seen::default();

    let mut first = instance(&db);
    let run = start_run(&client, &first, &admin, &standin, &mut seen).await;
    wait_for_rows(&pool, 4, records.len()).await;
    let shown = seen
        .get(
            &client,
            &first.url(&format!("/api/v1/admin/runs/{run}")),
            &admin,
        )
        .await;
    assert_eq!(shown["state"], "running", "{shown}");
    assert!(shown["progress"]["total"] == records.len(), "{shown}");
    first.kill();
    let stored_at_kill = stored_items(&pool).await;
    let at_kill = standin.calls();
    assert!(stored_at_kill.len() < records.len(), "killed too late");

    // The restarted server takes the run over once the dead one's lease has run out.
    let second = instance(&db);
    let shown = wait_done(&client, &second, &admin, run, &mut seen).await;
    assert_finished(&pool, &shown, &records).await;
    assert_asked_once(&records, &stored_at_kill, &at_kill, &standin.calls());
    assert!(standin.problems().is_empty(), "{:?}", standin.problems());
    read_pages(&pool, &second, run, &records, &mut seen).await;
    assert_key_nowhere(&pool, &db, dir.path(), &[&first, &second], &seen).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn with_two_instances_on_postgres_the_other_takes_over_the_run_of_the_one_killed() {
    if postgres_server().is_none() {
        eprintln!("no PostgreSQL server (ENACT_HUB_TEST_POSTGRES unset): skipping");
        return;
    }
    let (dir, pool, records, db) = run_fixture_located(2).await;
    let db = db.to_str().expect("a URL").to_owned();
    let standin = standin(&dir.path().join("release"), &records).await;
    let (_, admin) = api_token(&pool, "root", Role::Admin, None, None).await;
    let client = reqwest::Client::new();
    let mut seen = Seen::default();

    let mut a = instance(&db);
    let mut b = instance(&db);
    let run = start_run(&client, &a, &admin, &standin, &mut seen).await;
    wait_for_rows(&pool, 4, records.len()).await;
    // The instance holding the run's lease is the one killed.
    let owner: String = db!(
        pool,
        fetch_one,
        sqlx::query_scalar::<_, String>(
            "SELECT j.lease_owner FROM jobs j JOIN model_runs r ON r.job = j.id WHERE r.id = $1"
        )
        .bind(run)
    )
    .expect("the run's job has an owner");
    let working_is_a = owner.contains(&format!(":{}:", a.pid()));
    assert!(
        working_is_a || owner.contains(&format!(":{}:", b.pid())),
        "{owner} is neither instance"
    );
    let (dead, survivor) = if working_is_a {
        (&mut a, &b)
    } else {
        (&mut b, &a)
    };
    dead.kill();
    let stored_at_kill = stored_items(&pool).await;
    let at_kill = standin.calls();
    assert!(stored_at_kill.len() < records.len(), "killed too late");

    let shown = wait_done(&client, survivor, &admin, run, &mut seen).await;
    assert_finished(&pool, &shown, &records).await;
    assert_asked_once(&records, &stored_at_kill, &at_kill, &standin.calls());
    let attempts = count(
        &pool,
        &format!(
            "SELECT attempts FROM jobs WHERE id = (SELECT job FROM model_runs WHERE id = {run})"
        ),
    )
    .await;
    assert_eq!(attempts, 2, "worked once by each instance");
    read_pages(&pool, survivor, run, &records, &mut seen).await;
    assert_key_nowhere(&pool, &db, dir.path(), &[&a, &b], &seen).await;
}
