//! Imports beside live traffic: while the command line imports a second dataset of 2,004
//! items and then replaces it, annotators save drafts and answers and a model submits, all
//! against the first dataset. No request fails, no write waits a second, every acknowledged
//! write is stored, and readers see the second dataset absent or whole.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use enact_hub::core::credentials::Role;
use reqwest::StatusCode;
use serde_json::{Value, json};

use crate::annotate::{annotator, assign, logged_in_on};
use crate::helpers::*;

/// What one stream of writes saw.
#[derive(Default)]
struct Stream {
    acknowledged: i64,
    failures: Vec<String>,
    slowest: Duration,
}

impl Stream {
    fn record(&mut self, what: &str, started: Instant, status: StatusCode, body: &str) -> bool {
        self.slowest = self.slowest.max(started.elapsed());
        if status.is_success() {
            self.acknowledged += 1;
            true
        } else {
            self.failures.push(format!("{what}: {status} {body}"));
            false
        }
    }
}

/// Runs the `enact-hub import` command to its end (failing with its stderr if it failed);
/// its report.
async fn cli_import(mut args: Vec<String>) -> Value {
    args.push("--json".to_owned());
    let out = tokio::task::spawn_blocking(move || enact_hub().args(&args).output())
        .await
        .expect("import task")
        .expect("spawn import");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("the report as JSON")
}

// Its 1 s bound is about the import's locking, so it runs alone: scripts/test.sh runs it with
// `--ignored` after the rest of the suite (`cargo test --test service -- --ignored live_import`).
#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
#[ignore = "runs alone, after the suite: cargo test --test service -- --ignored live_import"]
async fn answers_and_submissions_flow_while_a_2000_item_dataset_is_imported_and_replaced() {
    let (server, records) = spawn_serving_app_with_release().await;
    let server = Arc::new(server);
    let (_, token) = api_token(
        &server.pool,
        "modeler",
        Role::Submitter,
        Some(1_000_000),
        Some(1_000_000),
    )
    .await;
    let ids: Vec<String> = records
        .iter()
        .map(|r| r["id"].as_str().expect("id").to_owned())
        .collect();
    let refs: Vec<&str> = ids.iter().map(String::as_str).collect();
    let mut annotators = Vec::new();
    for name in ["ann0", "ann1", "ann2"] {
        let id = annotator(&server, name, false).await;
        assign(&server, id, &refs).await;
        annotators.push(logged_in_on(&server, name, "/annotate").await);
    }

    // The second dataset, and a second version of it (every question changed) beside it.
    let big = server.dir().join("big");
    let big_records = write_balanced_release(&big, &[3, 5, 8], 334);
    let items = big_records.len();
    assert!(items >= 2000);
    let changed = with_changed_questions(&big_records);
    let version_b = big.join("QA").join("version_b.jsonl");
    std::fs::write(&version_b, changed.join("\n") + "\n").expect("version b");

    let done = Arc::new(AtomicBool::new(false));
    // A model submitting again and again.
    let submitter = {
        let (server, done, token) = (server.clone(), done.clone(), token.clone());
        let body = answers(&records, &[]);
        tokio::spawn(async move {
            let mut stream = Stream::default();
            while !done.load(Ordering::SeqCst) {
                let started = Instant::now();
                let r = submit_to(&server, "mini", "model=m", &token, body.clone()).await;
                stream.record("submission", started, r.status, &r.text);
            }
            stream
        })
    };
    // Annotators saving drafts (each draft's placements count is its sequence number) and,
    // every few drafts, answering an item; the last item stays a draft.
    let mut annotating = Vec::new();
    for (mut browser, csrf) in annotators {
        let (done, records, ids) = (done.clone(), records.clone(), ids.clone());
        annotating.push(tokio::spawn(async move {
            let (mut drafts, mut answers) = (Stream::default(), Stream::default());
            let (mut item, mut seq) = (0usize, 0u32);
            let mut last_draft = None;
            while !done.load(Ordering::SeqCst) {
                seq += 1;
                let gt = records[item]["gt_answer"].as_array().expect("gt").clone();
                let path = format!("/annotate/mini/{}", ids[item]);
                let counts = json!({"placements": seq, "swaps": 0, "clears": 0, "undos": 0});
                let answer = seq % 8 == 0 && item + 1 < ids.len();
                let (action, slots) = if answer {
                    ("submit", Value::Array(gt))
                } else {
                    ("draft", Value::Array(vec![Value::Null; gt.len()]))
                };
                let started = Instant::now();
                let r = browser
                    .post_json(
                        &format!("{path}/{action}"),
                        Some(&csrf),
                        &json!({"slots": slots, "counts": counts}),
                    )
                    .await;
                let status = r.status();
                let text = r.text().await.unwrap_or_default();
                if answer {
                    if answers.record("answer", started, status, &text) {
                        item += 1;
                    }
                } else if drafts.record("draft", started, status, &text) {
                    last_draft = Some((ids[item].clone(), seq));
                }
                tokio::time::sleep(Duration::from_millis(20)).await;
            }
            (drafts, answers, last_draft)
        }));
    }
    // A reader: the second dataset is absent or whole, never part.
    let reader = {
        let (server, done) = (server.clone(), done.clone());
        tokio::spawn(async move {
            let mut seen = Vec::new();
            while !done.load(Ordering::SeqCst) {
                let (status, body) = server.get_json("/api/v1/datasets").await;
                assert_eq!(status, StatusCode::OK, "{body}");
                let listed = body["datasets"]
                    .as_array()
                    .expect("datasets")
                    .iter()
                    .find(|d| d["name"] == "big")
                    .map(|d| d["items"].as_i64().expect("items"));
                seen.push(listed);
                tokio::time::sleep(Duration::from_millis(10)).await;
            }
            seen
        })
    };

    let db = server.db_path().display().to_string();
    let started = Instant::now();
    let import = |from: &std::path::Path, replace: bool| {
        let mut args = vec![
            "import".to_owned(),
            from.display().to_string(),
            "--dataset".to_owned(),
            "big".to_owned(),
            "--db".to_owned(),
            db.clone(),
        ];
        if replace {
            args.push("--replace".to_owned());
        }
        args
    };
    let new = cli_import(import(&big, false)).await;
    let first = started.elapsed();
    let replacing = cli_import(import(&version_b, true)).await;
    let both = started.elapsed();
    done.store(true, Ordering::SeqCst);

    let submissions = submitter.await.expect("submitter");
    let mut all = vec![("submissions", &submissions)];
    let mut streams = Vec::new();
    for task in annotating {
        streams.push(task.await.expect("annotator"));
    }
    let seen = reader.await.expect("reader");
    for (drafts, answers, _) in &streams {
        all.push(("drafts", drafts));
        all.push(("answers", answers));
    }
    eprintln!(
        "imported {items} items in {first:?}, replaced them by {both:?}; {} submissions, {} \
         drafts, {} answers; slowest write {:?}; {} reads",
        submissions.acknowledged,
        streams.iter().map(|s| s.0.acknowledged).sum::<i64>(),
        streams.iter().map(|s| s.1.acknowledged).sum::<i64>(),
        all.iter().map(|(_, s)| s.slowest).max().unwrap_or_default(),
        seen.len()
    );
    for report in [&new, &replacing] {
        eprintln!(
            "import: longest transaction {} ms, cut-over {} ms",
            report["longest_transaction_ms"], report["cut_over_ms"]
        );
    }
    for (what, stream) in &all {
        assert!(stream.failures.is_empty(), "{what}: {:?}", stream.failures);
        assert!(
            stream.slowest < Duration::from_secs(1),
            "{what}: a write waited {:?}",
            stream.slowest
        );
    }
    assert!(submissions.acknowledged > 0);
    assert!(
        streams
            .iter()
            .all(|s| s.0.acknowledged > 0 && s.1.acknowledged > 0)
    );
    for listed in &seen {
        assert!(
            listed.is_none_or(|n| n == items as i64),
            "a reader saw {listed:?} of {items} items"
        );
    }

    // Every acknowledged write is stored.
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM submissions").await,
        submissions.acknowledged
    );
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM annotations").await,
        streams.iter().map(|s| s.1.acknowledged).sum::<i64>()
    );
    for (_, _, last) in &streams {
        let (item, seq) = last.as_ref().expect("a draft was saved");
        let stored = count(
            &server.pool,
            &format!(
                "SELECT count(*) FROM drafts d JOIN items i ON i.id = d.item \
                 WHERE i.item_id = '{item}' AND d.state LIKE '%\"placements\":{seq},%'"
            ),
        )
        .await;
        assert!(
            stored >= 1,
            "the last acknowledged draft ({item}, {seq}) is not stored"
        );
    }
    let new_version = count(
        &server.pool,
        "SELECT count(*) FROM items i JOIN datasets d ON d.id = i.dataset_id \
         WHERE d.name = 'big' AND i.question NOT LIKE '%Now please%'",
    )
    .await;
    assert_eq!(new_version, items as i64);
}
