//! Agreement on stored annotations: `enact-hub agreement --db`, the cross-annotation protocol,
//! and the report over HTTP and on the command line, checked against the pure core.

use enact_hub::agreement::{
    AnnotatedOrdering, BootstrapConfig, OrderingAnnotations, OrderingEncoding, ordering_agreement,
};
use enact_hub::annotation::{new_token, token_hash};
use enact_hub::store;
use enact_hub::store::annotations::{Outcome, Telemetry};
use enact_hub::verifier::Permutation;
use serde_json::Value;

use crate::annotate::{Browser, PASSWORD, annotator};
use crate::helpers::*;

const TELEMETRY: Telemetry = Telemetry {
    time_on_item_ms: 1000,
    time_to_first_placement_ms: Some(10),
    placements: 2,
    swaps: 0,
    clears: 0,
    undos: 0,
};

/// A database with dataset "mini" (one forward and one inverse item for L = 3, 4, 5) and
/// answers stored directly: `answers[a][i]` is annotator `a`'s answer to item `i`.
async fn stored_answers(
    dir: &tempfile::TempDir,
    answers: &[Vec<Option<Vec<u8>>>],
) -> (std::path::PathBuf, Vec<String>) {
    let pool = fresh_db(dir).await;
    let root = dir.path().join("release");
    let records = write_release(&root, &[3, 4, 5]);
    import(&pool, &root, &options("mini")).await;
    let ids: Vec<String> = records
        .iter()
        .map(|r| r["id"].as_str().expect("id").to_owned())
        .collect();
    let mut conn = pool.acquire().await.expect("conn");
    let dataset = store::datasets::by_name(&mut conn, "mini")
        .await
        .expect("query")
        .expect("mini");
    let rows = store::annotations::item_rowids(&mut conn, dataset.id, &ids)
        .await
        .expect("query")
        .expect("ids");
    for (a, row) in answers.iter().enumerate() {
        let annotator = store::annotations::create_annotator(
            &mut conn,
            &format!("coder{a}"),
            false,
            &token_hash(&new_token()),
        )
        .await
        .expect("insert")
        .expect("new");
        for (item, answer) in row.iter().enumerate() {
            let Some(answer) = answer else { continue };
            let outcome = Outcome::Answered(Permutation::new(answer.clone()).expect("perm"));
            store::annotations::finish(&mut conn, annotator, rows[item], &outcome, &TELEMETRY)
                .await
                .expect("finish");
        }
    }
    drop(conn);
    pool.close().await;
    (dir.path().join("test.db"), ids)
}

fn run_json(args: &[&str]) -> (bool, Value, String) {
    let out = enact_hub().args(args).output().expect("run enact-hub");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let json = if out.status.success() {
        serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("not JSON: {e}: {stdout}"))
    } else {
        Value::Null
    };
    (out.status.success(), json, stderr)
}

fn close(a: &Value, b: Option<f64>) {
    match (a.as_f64(), b) {
        (Some(a), Some(b)) => assert!((a - b).abs() < 1e-12, "{a} != {b}"),
        (None, None) => {}
        (a, b) => panic!("{a:?} != {b:?}"),
    }
}

#[tokio::test]
async fn agreement_on_stored_annotations_matches_the_core() {
    let dir = tempfile::tempdir().expect("tempdir");
    // Items in release order: F3, I3, F4, I4, F5, I5 (answer lengths 2, 2, 3, 3, 4, 4).
    let some = |v: &[u8]| Some(v.to_vec());
    let answers = vec![
        vec![
            some(&[2, 1]),
            some(&[1, 2]),
            some(&[3, 2, 1]),
            some(&[1, 2, 3]),
            some(&[4, 3, 2, 1]),
            None,
        ],
        vec![
            some(&[2, 1]),
            some(&[2, 1]),
            some(&[3, 2, 1]),
            some(&[1, 3, 2]),
            None,
            some(&[1, 2, 3, 4]),
        ],
        vec![
            some(&[2, 1]),
            some(&[1, 2]),
            None,
            some(&[1, 2, 3]),
            some(&[4, 3, 1, 2]),
            None,
        ],
    ];
    let (db, ids) = stored_answers(&dir, &answers).await;
    let db = db.to_str().expect("utf-8 path");

    // The same data through the pure core: items answered by two or more, sorted by id.
    let mut items: Vec<AnnotatedOrdering> = ids
        .iter()
        .enumerate()
        .map(|(i, id)| AnnotatedOrdering {
            item_id: id.clone(),
            answers: answers.iter().map(|row| row[i].clone()).collect(),
        })
        .filter(|item| item.answers.iter().flatten().count() >= 2)
        .collect();
    items.sort_by(|a, b| a.item_id.cmp(&b.item_id));
    assert_eq!(items.len(), 5, "I5 has one answer only");
    let names = vec!["coder0".into(), "coder1".into(), "coder2".into()];
    let core = OrderingAnnotations::new(names, items).expect("valid");

    for encoding in OrderingEncoding::ALL {
        let (ok, json, stderr) = run_json(&[
            "agreement",
            "--db",
            db,
            "--dataset",
            "mini",
            "--encoding",
            encoding.name(),
            "--bootstrap",
            "300",
            "--seed",
            "9",
            "--confidence",
            "0.9",
        ]);
        assert!(ok, "{stderr}");
        let config = BootstrapConfig {
            replicates: 300,
            confidence_level: 0.9,
            seed: 9,
        };
        let expected = ordering_agreement(&core, encoding, &config).expect("core");
        assert_eq!(json["encoding"], encoding.name());
        assert_eq!(json["level"], expected.level.name());
        assert_eq!(json["metric_version"], "enact-hub-agreement-report/1");
        assert_eq!(json["dataset_hash"].as_str().expect("hash").len(), 64);
        close(&json["alpha"], expected.alpha.estimate.alpha);
        close(&json["ci"]["low"], expected.alpha.ci_low);
        close(&json["ci"]["high"], expected.alpha.ci_high);
        assert_eq!(json["ci"]["seed"], 9);
        assert_eq!(json["ci"]["replicates"], 300);
        assert_eq!(json["ci"]["confidence_level"], 0.9);
        let pairs = json["pairwise"].as_array().expect("pairs");
        assert_eq!(pairs.len(), 3);
        for (pair, want) in pairs.iter().zip(&expected.pairwise) {
            close(&pair["alpha"], want.result.alpha);
            assert_eq!(pair["a"]["name"], format!("coder{}", want.coder_a));
            assert_eq!(pair["b"]["name"], format!("coder{}", want.coder_b));
        }
        // F3 and I4 agree all round; I3, F4, F5 do not.
        assert_eq!(json["exact_agreement"]["agreeing_items"], 2);
        assert_eq!(json["exact_agreement"]["compared_items"], 5);
        assert_eq!(json["counts"]["items"], 5);
        assert_eq!(json["counts"]["answers"], 13);
        assert_eq!(json["counts"]["annotators"], 3);
    }

    // Without an interval the CI is null; a level the encoding cannot take is refused.
    let (ok, json, _) = run_json(&[
        "agreement",
        "--db",
        db,
        "--dataset",
        "mini",
        "--encoding",
        "rank",
        "--bootstrap",
        "0",
        "--level",
        "interval",
    ]);
    assert!(ok);
    assert_eq!(json["level"], "interval");
    assert!(json["ci"].is_null());
    let (ok, _, stderr) = run_json(&[
        "agreement",
        "--db",
        db,
        "--dataset",
        "mini",
        "--encoding",
        "answer",
        "--level",
        "ordinal",
    ]);
    assert!(!ok);
    assert!(
        stderr.contains("only the nominal level applies"),
        "{stderr}"
    );
    let (ok, _, stderr) = run_json(&["agreement", "--db", db, "--dataset", "nope"]);
    assert!(!ok);
    assert!(stderr.contains("no dataset named 'nope'"), "{stderr}");
}

#[tokio::test]
async fn agreement_without_overlapping_answers_says_so() {
    let dir = tempfile::tempdir().expect("tempdir");
    let answers = vec![vec![Some(vec![2, 1]), None], vec![None, Some(vec![1, 2])]];
    let (db, _) = stored_answers(&dir, &answers).await;
    let (ok, _, stderr) = run_json(&[
        "agreement",
        "--db",
        db.to_str().expect("utf-8"),
        "--dataset",
        "mini",
    ]);
    assert!(!ok);
    assert!(
        stderr.contains("no item has answers from two or more annotators (2 answers on 2 items)"),
        "{stderr}"
    );
}

/// A release with `per_cell` items in every direction × L in `lengths`, imported as "mini".
pub fn write_balanced_release(
    root: &std::path::Path,
    lengths: &[usize],
    per_cell: u32,
) -> Vec<Value> {
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

async fn logged_in(server: &TestServer, name: &str) -> (Browser, String) {
    let mut browser = Browser::new(server);
    let r = browser.login(name, PASSWORD).await;
    assert_eq!(
        r.status(),
        reqwest::StatusCode::SEE_OTHER,
        "login of {name}"
    );
    let csrf = browser.csrf("/annotate").await;
    (browser, csrf)
}

async fn kinds(server: &TestServer) -> Vec<(i64, String, String)> {
    sqlx::query_as(
        "SELECT g.annotator, i.item_id, g.kind FROM assignments g JOIN items i ON i.id = g.item \
         ORDER BY g.annotator, i.item_id",
    )
    .fetch_all(&server.pool)
    .await
    .expect("assignments")
}

#[tokio::test]
async fn the_protocol_runs_once_with_csrf_and_cross_assigns_blind() {
    let server = spawn_app_with(|pool, dir| async move {
        let root = dir.join("release");
        write_balanced_release(&root, &[3, 4], 4);
        import(&pool, &root, &options("mini")).await;
    })
    .await;
    annotator(&server, "root", true).await;
    let ids: Vec<i64> = [
        annotator(&server, "ann", false).await,
        annotator(&server, "bob", false).await,
    ]
    .to_vec();
    let (mut admin, csrf) = logged_in(&server, "root").await;
    let mut fields = vec![
        ("csrf", csrf.as_str()),
        ("dataset", "mini"),
        ("mode", "split"),
    ];
    let id_text: Vec<String> = ids.iter().map(i64::to_string).collect();
    for id in &id_text {
        fields.push(("annotator", id));
    }
    assert_eq!(
        admin.post_form("/admin/assign", &fields).await.status(),
        200
    );
    // Each answers their whole primary share (ground truth is the reversed order).
    for name in ["ann", "bob"] {
        let (mut browser, token) = logged_in(&server, name).await;
        let queue = store::annotations::queue(
            &mut server.pool.acquire().await.expect("conn"),
            ids[usize::from(name == "bob")],
        )
        .await
        .expect("queue");
        assert_eq!(queue.len(), 8);
        for entry in queue {
            let slots: Vec<u8> = (1..entry.step_length.get()).rev().collect();
            let path = format!("/annotate/mini/{}", entry.item_id);
            browser.get(&path).await;
            let r = browser
                .post_json(
                    &format!("{path}/submit"),
                    Some(&token),
                    &serde_json::json!({"slots": slots, "counts": {"placements": 1, "swaps": 0, "clears": 0, "undos": 0}}),
                )
                .await;
            assert_eq!(r.status(), 200);
        }
    }
    let path = "/admin/datasets/mini/agreement-protocol";
    let r = admin
        .post_form(path, &[("items_per_cell", "1"), ("seed", "5")])
        .await;
    assert_eq!(r.status(), 403, "no CSRF token, no protocol");
    let r = admin
        .post_form(
            path,
            &[("csrf", &csrf), ("items_per_cell", "1"), ("seed", "5")],
        )
        .await;
    assert_eq!(r.status(), 200);
    let html = r.text().await.expect("body");
    assert!(
        html.contains("drew 8 items (k = 1, seed = 5) from the completed primary items of 2 annotators and added 8 assignments"),
        "{html}"
    );
    let stored = kinds(&server).await;
    let cross: Vec<&(i64, String, String)> = stored
        .iter()
        .filter(|(_, _, kind)| kind == "agreement")
        .collect();
    assert_eq!(cross.len(), 8);
    assert_eq!(stored.len(), 16 + 8);
    // Each cross-assigned item is the other annotator's primary item.
    for (who, item, _) in &cross {
        assert!(
            stored
                .iter()
                .any(|(other, it, kind)| other != who && it == item && kind == "primary")
        );
    }
    // The annotator's queue and item page look like any other assignment.
    let (mut ann, _) = logged_in(&server, "ann").await;
    let (_, queue) = ann.text("/annotate").await;
    assert!(!queue.to_lowercase().contains("agreement"), "{queue}");
    let theirs = cross
        .iter()
        .find(|(who, _, _)| *who == ids[0])
        .expect("ann has one");
    let (status, page) = ann.text(&format!("/annotate/mini/{}", theirs.1)).await;
    assert_eq!(status, 200);
    assert!(!page.to_lowercase().contains("agreement"), "{page}");
    // A second run is refused and changes nothing, over HTTP and on the command line.
    let r = admin
        .post_form(path, &[("csrf", &csrf), ("items_per_cell", "2")])
        .await;
    assert_eq!(r.status(), 409);
    assert!(
        r.text()
            .await
            .expect("body")
            .contains("already ran on this dataset")
    );
    let out = enact_hub()
        .args(["agreement-protocol", "--dataset", "mini", "--db"])
        .arg(server.db_path())
        .output()
        .expect("run");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("seed = 5"));
    assert_eq!(kinds(&server).await, stored);
    server.stop().await;
}
