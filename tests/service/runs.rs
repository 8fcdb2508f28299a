//! Model runs against the stand-in OpenAI-compatible server (tests/support/standin.rs): every
//! reply kept, failures stored as failures, rate limits, usage and cost, resuming, and the
//! submission the run makes.

use std::collections::HashMap;
use std::path::Path;
use std::time::Duration;

use enact_hub::app::Hub;
use enact_hub::app::runs::{self, ApiKey, CallSettings, RunSpec};
use enact_hub::core::model_run::{GenerationParams, ItemOutcome, Prices, RunFailure};
use serde_json::Value;
use tempfile::TempDir;

use crate::helpers::*;
use crate::standin::{StandIn, StandInConfig, Step, item_key};

pub const SECRET_KEY: &str = "sk-standin-7f3a9c51e2d84b60a1c0";

/// A fresh database with `mini` imported: `per_cell` items per direction × L in 3, 4, 5.
pub async fn run_fixture(per_cell: u32) -> (TempDir, enact_hub::store::Pool, Vec<Value>) {
    let (dir, pool, records, _) = run_fixture_located(per_cell).await;
    (dir, pool, records)
}

/// [`run_fixture`], and the database as `--db` takes it.
pub async fn run_fixture_located(
    per_cell: u32,
) -> (
    TempDir,
    enact_hub::store::Pool,
    Vec<Value>,
    std::path::PathBuf,
) {
    let dir = TempDir::new().expect("tempdir");
    let root = dir.path().join("release");
    let records = write_balanced_release(&root, &[3, 4, 5], per_cell);
    let (pool, location) = fresh_db_located(&dir).await;
    import(&pool, &root, &options("mini")).await;
    (dir, pool, records, location)
}

/// The ground truth of a record as a model writes it, or reversed (wrong).
pub fn answer_text(record: &Value, right: bool) -> String {
    let mut gt: Vec<u64> = record["gt_answer"]
        .as_array()
        .expect("gt")
        .iter()
        .map(|v| v.as_u64().expect("label"))
        .collect();
    if !right {
        gt.reverse();
    }
    format!("The order is {gt:?}")
}

/// Scripts keyed as the stand-in recognises items, from a step list per record.
pub fn scripts(
    root: &Path,
    records: &[Value],
    script: impl Fn(usize, &Value) -> Vec<Step>,
) -> HashMap<String, (String, Vec<Step>)> {
    records
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let first = root.join(r["images"][0].as_str().expect("image path"));
            let png = std::fs::read(&first).expect("the first image");
            (
                item_key(&png),
                (r["id"].as_str().expect("id").to_owned(), script(i, r)),
            )
        })
        .collect()
}

/// Scripts answering every record right at once.
fn all_right(root: &Path, records: &[Value]) -> HashMap<String, (String, Vec<Step>)> {
    scripts(root, records, |_, r| {
        vec![Step::Answer(answer_text(r, true))]
    })
}

/// A stored submission, read from the database.
pub async fn stored_submission(
    pool: &enact_hub::store::Pool,
    id: i64,
) -> enact_hub::store::submissions::SubmissionRow {
    let mut conn = pool.acquire().await.expect("conn");
    enact_hub::store::submissions::by_id(&mut conn, id)
        .await
        .expect("read")
        .expect("stored")
}

/// A stored submission's overall task accuracy.
pub fn task_accuracy(stored: &enact_hub::store::submissions::SubmissionRow) -> f64 {
    stored
        .scores
        .report
        .overall
        .as_ref()
        .expect("overall")
        .totals
        .task_accuracy
}

/// Runs `command` to its end off the runtime's thread (the stand-in answers on it).
pub async fn finished(mut command: std::process::Command) -> std::process::Output {
    tokio::task::spawn_blocking(move || command.output())
        .await
        .expect("joined")
        .expect("the command ran")
}

/// `command`'s `--json` summary; fails with its standard error unless it succeeded.
pub async fn json_summary(command: std::process::Command) -> (std::process::Output, Value) {
    let output = finished(command).await;
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let summary = serde_json::from_slice(&output.stdout).expect("a JSON summary");
    (output, summary)
}

pub fn spec(standin: &StandIn, name: &str) -> RunSpec {
    RunSpec {
        dataset: "mini".to_owned(),
        endpoint: standin.endpoint(),
        model: "standin-vl".to_owned(),
        name: Some(name.to_owned()),
        params: GenerationParams {
            temperature: Some(0.0),
            max_tokens: Some(256),
        },
        limit: None,
        retry_failed: false,
        submit_as: Some("Stand-in VL".to_owned()),
        prices: Prices {
            input_usd_per_mtok: 2.5,
            output_usd_per_mtok: 10.0,
        },
    }
}

fn settings(concurrency: usize) -> CallSettings {
    CallSettings {
        concurrency,
        max_retries: 3,
        // Long enough that a prompt reply is never timed out on a loaded two-core machine
        // (attempt counts are asserted exactly), short enough that the 6 s slow reply always is.
        timeout: Duration::from_secs(2),
        backoff_base: Duration::from_millis(10),
        api_key: ApiKey::new(SECRET_KEY),
    }
}

async fn execute(hub: &Hub, spec: &RunSpec, settings: &CallSettings) -> runs::RunReport {
    runs::execute(hub, &tester(), spec, settings, &|_| {}, &|| false)
        .await
        .unwrap_or_else(|e| panic!("the run failed: {e}"))
}

#[tokio::test]
async fn a_run_keeps_every_reply_stores_failures_as_failures_and_submits_its_scores() {
    let (dir, pool, records) = run_fixture(3).await;
    let root = dir.path().join("release");
    // 18 items: by index, a plan per item; the rest answer right or wrong.
    let plan = |i: usize, r: &Value| -> Vec<Step> {
        let right = Step::Answer(answer_text(r, true));
        match i {
            0 => vec![Step::Status(500, "boom".into()), right],
            1 => vec![Step::RetryAfterSeconds(1), right],
            2 => vec![Step::RetryAfterDate(1), right],
            3 => vec![Step::Slow(Duration::from_secs(6), "[1, 2]".into()), right],
            4 => vec![Step::Cut(answer_text(r, true))],
            5 => vec![Step::Empty],
            6 => vec![Step::Status(400, "image too large for this model".into())],
            7 => vec![Step::Status(503, "overloaded".into())],
            8..=10 => vec![Step::Answer(answer_text(r, false))],
            _ => vec![right],
        }
    };
    let standin = StandIn::start(StandInConfig {
        scripts: scripts(&root, &records, plan),
        tokens_per_image: 85,
        ..StandInConfig::default()
    })
    .await;
    let hub = Hub::from(pool.clone());
    let spec = spec(&standin, "first");
    let report = execute(&hub, &spec, &settings(4)).await;
    assert!(standin.problems().is_empty(), "{:?}", standin.problems());
    assert_eq!(report.progress.total, 18);
    assert_eq!(report.progress.answered, 14, "{report:?}");
    assert_eq!(report.progress.failed, 4, "{report:?}");
    assert!(!report.stopped);
    // Failures counted by kind, not by their words (which name attempts and messages).
    assert_eq!(
        report
            .failures
            .iter()
            .map(|(f, n)| (*f, *n))
            .collect::<Vec<_>>(),
        [
            (RunFailure::Status(400), 1),
            (RunFailure::Status(503), 1),
            (RunFailure::Empty, 1),
            (RunFailure::Cut, 1),
        ],
        "{report:?}"
    );
    assert_eq!(
        serde_json::to_value(&report.failures).expect("JSON"),
        serde_json::json!({"http_400": 1, "http_503": 1, "empty": 1, "cut": 1})
    );

    // Each item's row says what happened.
    let run = runs::by_name(&hub, "first").await.expect("the run");
    let rows: HashMap<String, runs::RunItemRow> = runs::item_rows(&hub, &run)
        .await
        .expect("rows")
        .into_iter()
        .map(|r| (r.item_id.clone(), r))
        .collect();
    let row = |i: usize| &rows[records[i]["id"].as_str().expect("id")];
    let answered = ItemOutcome::Answered;
    assert!(row(0).outcome == answered && row(0).attempts == 2);
    assert!(row(0).error.as_deref().is_some_and(|e| e.contains("500")));
    assert!(row(1).outcome == answered && row(1).attempts == 2);
    assert!(row(2).outcome == answered && row(2).attempts == 2);
    assert_eq!(row(3).outcome, answered, "{:?}", row(3));
    assert!(
        row(3)
            .error
            .as_deref()
            .is_some_and(|e| e.contains("timed out"))
    );
    assert_eq!(row(4).outcome, ItemOutcome::Failed(RunFailure::Cut));
    assert_eq!(row(4).finish_reason.as_deref(), Some("length"));
    assert!(
        row(4)
            .error
            .as_deref()
            .is_some_and(|e| e.contains("cut off"))
    );
    assert_eq!(
        row(4).response.as_deref(),
        Some(answer_text(&records[4], true).as_str())
    );
    assert_eq!(row(5).outcome, ItemOutcome::Failed(RunFailure::Empty));
    assert_eq!(row(5).error.as_deref(), Some("empty response"));
    assert_eq!(row(6).outcome, ItemOutcome::Failed(RunFailure::Status(400)));
    assert!(row(6).attempts == 1, "a 400 is not retried");
    assert!(
        row(6)
            .error
            .as_deref()
            .is_some_and(|e| e.contains("image too large"))
    );
    assert_eq!(row(7).outcome, ItemOutcome::Failed(RunFailure::Status(503)));
    assert!(row(7).attempts == 4, "{:?}", row(7));
    assert!(
        row(7)
            .error
            .as_deref()
            .is_some_and(|e| e.contains("gave up after 4"))
    );
    assert!(row(8).outcome == answered && row(8).attempts == 1);

    // Every answered item was asked successfully exactly once.
    let calls = standin.calls();
    for (i, r) in records.iter().enumerate() {
        let id = r["id"].as_str().expect("id");
        let expected = usize::from(![4, 5, 6, 7].contains(&i));
        assert_eq!(calls[id].answered, expected, "item {i}");
    }

    // The submission: scored from the stand-in's answers, failed items unanswered.
    let submission = report.submission.expect("submitted");
    let stored = stored_submission(&pool, submission).await;
    assert_eq!(stored.model, "Stand-in VL");
    assert_eq!(stored.account, runs::RUNS_ACCOUNT);
    let coverage = &stored.scores.coverage;
    assert_eq!((coverage.answered, coverage.missing), (14, 4));
    // 14 answered, of which 3 wrong: 11 right of 18.
    assert!((task_accuracy(&stored) - 11.0 / 18.0).abs() < 1e-9);
    let run = runs::by_name(&hub, "first").await.expect("the run");
    assert_eq!(run.submission, Some(submission));
    let stamp: Value = serde_json::from_str(run.stamp.as_deref().expect("a stamp")).expect("json");
    assert_eq!(
        stamp["endpoint_host"],
        format!("127.0.0.1:{}", standin.addr.port())
    );
    assert_eq!(stamp["model"], "standin-vl");
    assert_eq!(stamp["params"]["max_tokens"], 256);
    assert_eq!(
        stamp["prompt_version"],
        enact_hub::core::model_run::PROMPT_VERSION
    );
    assert_eq!(
        stamp["prompt_hash"],
        enact_hub::core::model_run::prompt_template_hash()
    );

    // Usage and cost are the stand-in's tokens times the prices.
    let (prompt, completion) = standin.tokens();
    assert!(prompt > 0 && completion > 0);
    assert_eq!(stamp["usage"]["prompt_tokens"], prompt);
    assert_eq!(stamp["usage"]["completion_tokens"], completion);
    let cost = (prompt as f64 * 2.5 + completion as f64 * 10.0) / 1e6;
    assert!((stamp["cost_usd"].as_f64().expect("cost") - cost).abs() < 1e-12);
    assert!((report.progress.cost_usd - cost).abs() < 1e-12);

    // The key went to the endpoint and nowhere else.
    assert!(
        standin
            .authorizations()
            .iter()
            .all(|a| a == &format!("Bearer {SECRET_KEY}"))
    );
    assert_key_stored_nowhere(&hub, dir.path()).await;

    // Again: nothing is asked, the same submission is found.
    let before = standin.total_requests();
    let again = execute(&hub, &spec, &settings(4)).await;
    assert_eq!(standin.total_requests(), before);
    assert_eq!(again.progress.asked_now, 0);
    assert_eq!(again.submission, Some(submission));

    // --retry-failed asks only the failed ones.
    let retry = RunSpec {
        retry_failed: true,
        ..spec.clone()
    };
    let retried = execute(&hub, &retry, &settings(4)).await;
    assert_eq!(retried.progress.asked_now, 4);
    assert_eq!(standin.total_requests(), before + 1 + 1 + 1 + 4);
    assert_eq!(retried.progress.failed, 4);
    assert_ne!(retried.submission, None);

    // Another identity under the same name is refused.
    let other = RunSpec {
        model: "other".to_owned(),
        ..spec.clone()
    };
    let refused = runs::execute(&hub, &tester(), &other, &settings(4), &|_| {}, &|| false)
        .await
        .expect_err("a name is one identity");
    assert!(
        refused.to_string().contains("exists with model"),
        "{refused}"
    );
}

/// The key's value in no table and no file of the database (backups are copies of it).
pub async fn assert_key_stored_nowhere(hub: &Hub, dir: &Path) {
    let snapshot = dir.join("snapshot.db");
    enact_hub::app::backup::backup(hub, &tester(), &snapshot)
        .await
        .expect("a backup");
    for entry in std::fs::read_dir(dir).expect("the test folder") {
        let path = entry.expect("an entry").path();
        if path.is_file() {
            let bytes = std::fs::read(&path).expect("read");
            assert!(
                !bytes
                    .windows(SECRET_KEY.len())
                    .any(|w| w == SECRET_KEY.as_bytes()),
                "the key is in {}",
                path.display()
            );
        }
    }
}

#[tokio::test]
async fn a_run_at_concurrency_32_against_a_server_taking_4_is_rarely_refused() {
    let (dir, pool, records) = run_fixture(40).await;
    let root = dir.path().join("release");
    let standin = StandIn::start(StandInConfig {
        scripts: all_right(&root, &records),
        latency: Duration::from_millis(20),
        max_in_flight: Some(4),
        tokens_per_image: 10,
        ..StandInConfig::default()
    })
    .await;
    let hub = Hub::from(pool);
    let mut settings = settings(32);
    settings.max_retries = 10;
    let report = execute(&hub, &spec(&standin, "throttled"), &settings).await;
    assert_eq!(report.progress.answered, records.len(), "{report:?}");
    let (total, refused) = (standin.total_requests(), standin.total_refused());
    assert_eq!(report.progress.requests as usize, total);
    assert!(
        (refused as f64) < 0.10 * total as f64,
        "{refused} of {total} requests refused"
    );
}

#[tokio::test]
async fn a_limited_run_submits_the_rest_as_unanswered_and_a_stop_leaves_it_resumable() {
    let (dir, pool, records) = run_fixture(2).await;
    let root = dir.path().join("release");
    let standin = StandIn::start(StandInConfig {
        scripts: all_right(&root, &records),
        ..StandInConfig::default()
    })
    .await;
    let hub = Hub::from(pool.clone());
    let stop_after = std::sync::atomic::AtomicUsize::new(0);
    let stopping = runs::RunSpec {
        submit_as: Some("m".into()),
        ..spec(&standin, "stopped")
    };
    // Stops once 5 items have been handed out.
    let report = runs::execute(&hub, &tester(), &stopping, &settings(1), &|_| {}, &|| {
        stop_after.fetch_add(1, std::sync::atomic::Ordering::SeqCst) >= 5
    })
    .await
    .expect("stopped run");
    assert!(report.stopped);
    assert_eq!(report.submission, None, "a stopped run does not submit");
    assert_eq!(report.progress.done, 5);
    let report = execute(&hub, &stopping, &settings(2)).await;
    assert_eq!(report.progress.asked_now, records.len() - 5);
    assert!(standin.calls().values().all(|c| c.requests == 1));
    assert!(report.submission.is_some());

    let limited = RunSpec {
        limit: Some(4),
        ..spec(&standin, "limited")
    };
    let report = execute(&hub, &limited, &settings(2)).await;
    assert_eq!(report.progress.total, 4);
    let stored = stored_submission(&pool, report.submission.expect("submitted")).await;
    assert_eq!(stored.scores.coverage.answered, 4);
    assert_eq!(stored.scores.coverage.missing, records.len() - 4);
}

/// A price below 0 is refused by the run's own check, which the API and the admin form share;
/// the command line names its flag, and nothing is asked or stored.
#[tokio::test]
async fn a_negative_price_is_refused_naming_the_flag() {
    let (_dir, pool, _records, db) = run_fixture_located(5).await;
    let out = enact_hub()
        .args(["run", "mini", "--endpoint", "http://127.0.0.1:9/v1"])
        .args(["--model", "m", "--price-output=-0.5", "--db"])
        .arg(&db)
        .output()
        .expect("run enact-hub run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("--price-output must be a price of 0 or more, not -0.5"),
        "{stderr}"
    );
    assert_eq!(count(&pool, "SELECT count(*) FROM model_runs").await, 0);
}

/// `enact-hub run` killed with SIGKILL part-way, then run again: no item with a stored reply
/// is asked again, every item ends up answered, and the submission scores what the stand-in
/// answered. The key is in no output and no file.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_run_killed_part_way_goes_on_where_it_stopped() {
    let (dir, pool, records, db) = run_fixture_located(5).await;
    let root = dir.path().join("release");
    let wrong = [1usize, 4, 7, 12, 20, 25];
    let standin = StandIn::start(StandInConfig {
        scripts: scripts(&root, &records, |i, r| {
            vec![Step::Answer(answer_text(r, !wrong.contains(&i)))]
        }),
        latency: Duration::from_millis(150),
        tokens_per_image: 85,
        ..StandInConfig::default()
    })
    .await;
    let command = || {
        let mut c = enact_hub();
        c.args(["run", "mini", "--endpoint"])
            .arg(standin.endpoint())
            .args([
                "--model",
                "standin-vl",
                "--concurrency",
                "2",
                "--retry-delay",
                "0.01",
            ])
            .args([
                "--api-key-env",
                "STANDIN_API_KEY",
                "--price-input",
                "1",
                "--json",
            ])
            .arg("--db")
            .arg(&db)
            .env("STANDIN_API_KEY", SECRET_KEY)
            .env("RUST_LOG", "debug")
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped());
        c
    };
    let mut first = command().spawn().expect("start enact-hub run");
    let rows = || async { count(&pool, "SELECT count(*) FROM model_run_items").await };
    let deadline = std::time::Instant::now() + Duration::from_secs(60);
    while rows().await < 8 {
        assert!(
            std::time::Instant::now() < deadline,
            "the run made no progress"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    first.kill().expect("SIGKILL");
    let killed = tokio::task::spawn_blocking(move || first.wait_with_output())
        .await
        .expect("joined")
        .expect("the killed run");
    let done_at_kill = rows().await as usize;
    assert!(
        done_at_kill < records.len(),
        "killed too late to test resuming"
    );
    let calls_at_kill = standin.calls();
    let stored_at_kill: Vec<String> = db!(
        pool,
        fetch_all,
        sqlx::query_scalar::<_, String>(
            "SELECT i.item_id FROM model_run_items r JOIN items i ON i.id = r.item"
        )
    )
    .expect("stored items");

    let (second, report) = json_summary(command()).await;
    assert_eq!(report["progress"]["answered"], records.len());
    assert_eq!(
        report["progress"]["asked_now"],
        records.len() - done_at_kill
    );

    // An item stored before the kill was never asked again; every item was answered, and
    // at most the requests in flight at the kill (2) were answered twice.
    let calls = standin.calls();
    for id in &stored_at_kill {
        assert_eq!(
            calls[id].requests, calls_at_kill[id].requests,
            "{id} asked again"
        );
    }
    let twice = calls.values().filter(|c| c.answered > 1).count();
    assert!(twice <= 2, "{twice} items answered twice");
    assert!(
        records
            .iter()
            .all(|r| calls[r["id"].as_str().expect("id")].answered >= 1)
    );

    // The scores are the stand-in's answers': 6 wrong of 30.
    let submission = report["submission"].as_i64().expect("submitted");
    let stored = stored_submission(&pool, submission).await;
    let expected = (records.len() - wrong.len()) as f64 / records.len() as f64;
    assert!((task_accuracy(&stored) - expected).abs() < 1e-9);
    assert_eq!(stored.scores.coverage.missing, 0);

    for output in [
        &killed.stdout,
        &killed.stderr,
        &second.stdout,
        &second.stderr,
    ] {
        assert!(
            !String::from_utf8_lossy(output).contains(SECRET_KEY),
            "the key was printed"
        );
    }
    // Each start at the command line is audited, by the operator.
    let starts = count(
        &pool,
        "SELECT count(*) FROM audit_log WHERE action = 'run.start' AND actor_kind = 'operator'",
    )
    .await;
    assert_eq!(starts, 2);
    assert_key_stored_nowhere(&Hub::from(pool.clone()), dir.path()).await;
}

/// The migration that gave run items a failure kind (SQLite 0032, PostgreSQL 0024) reads the
/// kind of each older failed row from its words, in every form the hub wrote them.
#[tokio::test]
async fn older_failed_items_get_the_failure_kind_their_words_name() {
    let (dir, pool, records) = run_fixture(2).await;
    let root = dir.path().join("release");
    let standin = StandIn::start(StandInConfig {
        scripts: scripts(&root, &records, |_, _| vec![Step::Status(400, "no".into())]),
        ..StandInConfig::default()
    })
    .await;
    let hub = Hub::from(pool.clone());
    let spec = RunSpec {
        submit_as: None,
        ..spec(&standin, "legacy")
    };
    let report = execute(&hub, &spec, &settings(4)).await;
    let legacy = [
        ("empty response", RunFailure::Empty),
        ("response cut off (finish_reason: length)", RunFailure::Cut),
        (
            "gave up after 50 rate-limited calls: HTTP 429: slow down",
            RunFailure::RateLimited,
        ),
        (
            "gave up after 4 attempts: HTTP 200 OK: not a chat completion: missing field `choices`",
            RunFailure::Unreadable,
        ),
        ("HTTP 400: image too large", RunFailure::Status(400)),
        (
            "HTTP 404: gave up after 3 attempts",
            RunFailure::Status(404),
        ),
        (
            "gave up after 4 attempts: HTTP 503: overloaded",
            RunFailure::Status(503),
        ),
        ("gave up after 6 attempts: timed out", RunFailure::NoReply),
        (
            "gave up after 2 attempts: cannot connect: error sending request",
            RunFailure::NoReply,
        ),
        ("a reply nobody wrote", RunFailure::Unrecorded),
    ];
    assert!(report.progress.failed > legacy.len(), "{report:?}");
    let run = runs::by_name(&hub, "legacy").await.expect("the run");
    let rows = runs::item_rows(&hub, &run).await.expect("rows");
    let mut expected = HashMap::new();
    for ((words, kind), row) in legacy.iter().zip(&rows) {
        db!(
            pool,
            execute,
            sqlx::query(
                "UPDATE model_run_items SET error = $1, failure = NULL WHERE run = $2 AND item = \
                 (SELECT id FROM items WHERE item_id = $3)"
            )
            .bind(*words)
            .bind(run.id)
            .bind(&row.item_id)
        )
        .expect("make the row as an older hub wrote it");
        expected.insert(row.item_id.clone(), ItemOutcome::Failed(*kind));
    }
    // One answered row: the migration leaves it without a kind.
    let answered = &rows[legacy.len()].item_id;
    db!(
        pool,
        execute,
        sqlx::query(
            "UPDATE model_run_items SET state = 'answered', error = NULL, failure = NULL \
             WHERE run = $1 AND item = (SELECT id FROM items WHERE item_id = $2)"
        )
        .bind(run.id)
        .bind(answered)
    )
    .expect("an answered row");
    expected.insert(answered.clone(), ItemOutcome::Answered);

    // The migration's backfill, as the file has it, on this backend.
    let (migrations, number) = if on_sqlite() {
        (enact_hub::store::migrations::SQLITE, "0032_")
    } else {
        (enact_hub::store::migrations::POSTGRES, "0024_")
    };
    let (_, sql) = migrations
        .0
        .iter()
        .find(|(name, _)| name.starts_with(number))
        .expect("the migration");
    let backfill = &sql[sql.find("UPDATE model_run_items").expect("its backfill")..];
    db!(pool, execute, sqlx::query(backfill)).expect("the backfill runs");

    let rows = runs::item_rows(&hub, &run).await.expect("rows");
    for row in &rows {
        let want = expected
            .get(&row.item_id)
            .copied()
            .unwrap_or(ItemOutcome::Failed(RunFailure::Status(400)));
        assert_eq!(row.outcome, want, "{row:?}");
    }
}
