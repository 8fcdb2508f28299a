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
