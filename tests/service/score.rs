//! `enact-hub score`: ENACT parity through the command line (scene graphs read from disk), and
//! the strict policy's failure accounting.

use std::path::Path;

use serde_json::{Value, json};

use crate::helpers::*;

fn run(args: &[&dyn AsRef<std::ffi::OsStr>]) -> (bool, String, String) {
    let out = enact_hub()
        .args(args.iter().map(|a| a.as_ref()))
        .output()
        .expect("run enact-hub");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn enact_policy_reproduces_enacts_evaluator_on_every_prediction_file() {
    let Some(fixtures) = fixtures_dir() else {
        return;
    };
    let parity = fixtures.join("enact-parity");
    let reference = parity.join("reference");
    let skipped: Value = serde_json::from_str(
        &std::fs::read_to_string(reference.join("skipped_items.json")).expect("skipped_items.json"),
    )
    .expect("json");
    let out = tempfile::tempdir().expect("tempdir");
    let mut models = 0;
    for entry in std::fs::read_dir(parity.join("predictions")).expect("predictions") {
        let path = entry.expect("entry").path();
        let name = path
            .file_name()
            .expect("name")
            .to_string_lossy()
            .into_owned();
        let Some(model) = name
            .strip_prefix("enact_ordering_")
            .and_then(|n| n.strip_suffix(".jsonl"))
        else {
            continue;
        };
        models += 1;
        let (ok, _, stderr) = run(&[
            &"score",
            &path,
            &"--data",
            &parity,
            &"--scene-graphs",
            &parity.join("replayed_activities"),
            &"--policy",
            &"enact",
            &"--out",
            &out.path(),
        ]);
        let expected_skips: Vec<(u64, String)> = skipped["plain"][model]["skipped"]
            .as_array()
            .expect("skipped list")
            .iter()
            .map(|s| {
                let reason = s["reason"].as_str().expect("reason");
                (
                    s["line_num"].as_u64().expect("line"),
                    reason.split(':').next().unwrap_or(reason).to_owned(),
                )
            })
            .collect();
        if model == "missingtype" {
            assert!(!ok, "ENACT crashes on {name}; we must refuse it");
            assert!(
                stderr.contains("line 4") && stderr.contains("`type` is missing"),
                "{stderr}"
            );
            assert!(!out.path().join(format!("meta_performance/{name}")).exists());
            continue;
        }
        assert!(ok, "{name}: {stderr}");
        let our_skips: Vec<(u64, String)> = stderr
            .lines()
            .filter_map(|l| l.trim().strip_prefix(&format!("{}: line ", path.display())))
            .map(|rest| {
                let (line, reason) = rest.split_once(": ").expect("line: reason");
                (
                    line.parse().expect("line number"),
                    reason.split(':').next().unwrap_or(reason).to_owned(),
                )
            })
            .collect();
        assert_eq!(our_skips, expected_skips, "{name}: skipped lines differ");

        let ours =
            std::fs::read_to_string(out.path().join("detailed_eval").join(&name)).expect("ours");
        let theirs =
            std::fs::read_to_string(reference.join("eval_plain/detailed_eval").join(&name))
                .expect("reference");
        assert_eq!(
            ours.lines().count(),
            theirs.lines().count(),
            "{name}: evaluated item count"
        );
        for (i, (a, b)) in ours.lines().zip(theirs.lines()).enumerate() {
            assert_detailed_line_eq(a, b, &format!("{name} detailed line {}", i + 1));
        }
        let meta = format!("{}.json", name.trim_end_matches(".jsonl"));
        let ours: Value = serde_json::from_str(
            &std::fs::read_to_string(out.path().join("meta_performance").join(&meta))
                .expect("ours"),
        )
        .expect("json");
        let theirs: Value = serde_json::from_str(
            &std::fs::read_to_string(reference.join("eval_plain/meta_performance").join(&meta))
                .expect("reference"),
        )
        .expect("json");
        assert_json_close(&ours, &theirs, &meta);
    }
    assert_eq!(
        models, 14,
        "every prediction file of the fixture was scored"
    );
}

/// Floats within 1e-12, everything else (including int vs float) exactly.
fn assert_json_close(a: &Value, b: &Value, at: &str) {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) if x.is_f64() && y.is_f64() => {
            let (x, y) = (x.as_f64().expect("f64"), y.as_f64().expect("f64"));
            assert!((x - y).abs() <= 1e-12, "{at}: {x} vs {y}");
        }
        (Value::Object(x), Value::Object(y)) => {
            assert_eq!(
                x.keys().collect::<Vec<_>>(),
                y.keys().collect::<Vec<_>>(),
                "{at}: keys"
            );
            for (k, v) in x {
                assert_json_close(v, &y[k], &format!("{at}.{k}"));
            }
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}: length");
            for (i, (v, w)) in x.iter().zip(y).enumerate() {
                assert_json_close(v, w, &format!("{at}[{i}]"));
            }
        }
        _ => assert_eq!(a, b, "{at}"),
    }
}

fn assert_detailed_line_eq(ours: &str, theirs: &str, at: &str) {
    let a: Value = serde_json::from_str(ours).expect("our line is JSON");
    let b: Value = serde_json::from_str(theirs).expect("reference line is JSON");
    assert_json_close(&a, &b, at);
}

fn write_predictions(path: &Path, lines: &[Value]) {
    let text: Vec<String> = lines.iter().map(Value::to_string).collect();
    std::fs::write(path, text.join("\n") + "\n").expect("write predictions");
}

#[test]
fn strict_policy_counts_every_failure_with_its_reason() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    // Items 0..6: forward and inverse for L = 3, 4, 5; every gt is [L-1, .., 1].
    let records = write_release(&root, &[3, 4, 5]);
    let id = |i: usize| records[i]["id"].clone();
    let predictions = dir.path().join("enact_ordering_mymodel.jsonl");
    write_predictions(
        &predictions,
        &[
            json!({"id": id(0), "answer": "[2, 1]"}),        // exact
            json!({"id": id(1), "answer": "I cannot tell"}), // garbage
            json!({"id": id(2), "answer": "[3, 2]"}),        // wrong length
            json!({"id": id(3), "answer": "[1, 1, 2]"}),     // repeated label
            json!({"id": id(4), "answer": "<think>[1,2,3,4]</think> [3, 2, 1, 0]"}), // 0-based
                                                             // id(5) missing
        ],
    );
    let out = dir.path().join("out");
    let (ok, stdout, stderr) = run(&[&"score", &predictions, &"--data", &root, &"--out", &out]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("model mymodel: 5 of 6 items answered"),
        "{stdout}"
    );
    assert!(stdout.contains("4 unparseable"), "{stdout}");
    assert!(stdout.contains("1 missing"), "{stdout}");
    let detailed = std::fs::read_to_string(out.join("detailed_eval/enact_ordering_mymodel.jsonl"))
        .expect("detailed");
    let lines: Vec<Value> = detailed
        .lines()
        .map(|l| serde_json::from_str(l).expect("json"))
        .collect();
    assert_eq!(lines.len(), 6, "every dataset item has a line");
    assert_eq!(lines[0]["outcome"], "scored");
    assert_eq!(lines[0]["eval_metrics"]["task_accuracy"], true);
    for (i, needle) in [
        (1, "no list"),
        (2, "wrong length"),
        (3, "repeated"),
        (4, "out of range"),
    ] {
        assert_eq!(lines[i]["outcome"], "unparseable", "item {i}");
        let reason = lines[i]["reason"].as_str().expect("reason");
        assert!(reason.contains(needle), "item {i}: {reason}");
        assert_eq!(lines[i]["eval_metrics"]["pairwise_accuracy"], 0.0);
    }
    assert_eq!(lines[5]["outcome"], "missing");
    let meta: Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("meta_performance/enact_ordering_mymodel.json"))
            .expect("meta"),
    )
    .expect("json");
    assert_eq!(meta["overall_performance"]["overall"]["count"], 6);
    let ta = meta["overall_performance"]["overall"]["task_accuracy"]
        .as_f64()
        .expect("ta");
    assert!((ta - 1.0 / 6.0).abs() < 1e-12, "{ta}");
}

#[test]
fn unknown_ids_are_errors_naming_file_and_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let records = write_release(&root, &[3]);
    let predictions = dir.path().join("p.jsonl");
    write_predictions(
        &predictions,
        &[
            json!({"id": records[0]["id"], "answer": "[2, 1]"}),
            json!({"id": "no_such_item", "answer": "[1, 2]"}),
        ],
    );
    let (ok, _, stderr) = run(&[&"score", &predictions, &"--data", &root]);
    assert!(!ok);
    assert!(
        stderr.contains("p.jsonl: line 2") && stderr.contains("no_such_item"),
        "{stderr}"
    );
}

#[test]
fn key_frame_missing_from_the_scene_graph_is_named() {
    let Some(fixtures) = fixtures_dir() else {
        return;
    };
    let parity = fixtures.join("enact-parity");
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    std::fs::create_dir_all(root.join("QA")).expect("mkdir");
    let first = std::fs::read_to_string(parity.join("QA/enact_ordering.jsonl")).expect("qa");
    let mut record: Value =
        serde_json::from_str(first.lines().next().expect("a line")).expect("json");
    record["key_frame_ids"][1] = json!("999999");
    std::fs::write(root.join("QA/enact_ordering.jsonl"), format!("{record}\n")).expect("write");
    let predictions = dir.path().join("p.jsonl");
    write_predictions(
        &predictions,
        &[json!({"id": record["id"], "answer": "[1, 2]"})],
    );
    let (ok, _, stderr) = run(&[
        &"score",
        &predictions,
        &"--data",
        &root,
        &"--scene-graphs",
        &parity.join("replayed_activities"),
    ]);
    assert!(!ok);
    assert!(
        stderr.contains("line 1")
            && stderr.contains("key_frame_ids[1]")
            && stderr.contains("frame 999999 is not in"),
        "{stderr}"
    );
}

#[test]
fn malformed_scene_graph_json_is_named_with_its_place() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let records = write_release(&root, &[3]);
    let task = records[0]["task_name"].as_str().expect("task");
    let replayed = dir.path().join("replayed");
    std::fs::create_dir_all(replayed.join(task)).expect("mkdir");
    std::fs::write(
        replayed.join(task).join("scene_graph_0.json"),
        "{\"0\": {\"type\": \"full\", \"nodes\": [}",
    )
    .expect("write");
    let predictions = dir.path().join("p.jsonl");
    write_predictions(
        &predictions,
        &[json!({"id": records[0]["id"], "answer": "[2, 1]"})],
    );
    let (ok, _, stderr) = run(&[
        &"score",
        &predictions,
        &"--data",
        &root,
        &"--scene-graphs",
        &replayed,
    ]);
    assert!(!ok);
    assert!(
        stderr.contains("scene_graph_0.json") && stderr.contains("invalid scene-graph JSON"),
        "{stderr}"
    );
    assert!(stderr.contains("line 1"), "{stderr}");
}

#[test]
fn strict_scores_agree_between_a_stored_dataset_and_the_release_on_disk() {
    let Some(fixtures) = fixtures_dir() else {
        return;
    };
    let parity = fixtures.join("enact-parity");
    let replayed = parity.join("replayed_activities");
    let dir = tempfile::tempdir().expect("tempdir");
    let db = dir.path().join("s.db");
    let (ok, _, stderr) = run(&[
        &"import",
        &parity,
        &"--db",
        &db,
        &"--dataset",
        &"parity",
        &"--scene-graphs",
        &replayed,
    ]);
    assert!(ok, "{stderr}");
    assert!(stderr.contains("96 from scene graphs"), "{stderr}");
    for model in ["random", "adjswap", "semequiv", "prose"] {
        let file = parity.join(format!("predictions/enact_ordering_{model}.jsonl"));
        let from_db = dir.path().join(format!("db-{model}"));
        let from_disk = dir.path().join(format!("disk-{model}"));
        let (ok, table_db, stderr) = run(&[
            &"score",
            &file,
            &"--db",
            &db,
            &"--dataset",
            &"parity",
            &"--out",
            &from_db,
        ]);
        assert!(ok, "{stderr}");
        let (ok, table_disk, stderr) = run(&[
            &"score",
            &file,
            &"--data",
            &parity,
            &"--scene-graphs",
            &replayed,
            &"--out",
            &from_disk,
        ]);
        assert!(ok, "{stderr}");
        assert_eq!(table_db, table_disk, "{model}");
        assert!(
            table_db.contains("96 items from scene graphs"),
            "{table_db}"
        );
        for sub in [
            format!("detailed_eval/enact_ordering_{model}.jsonl"),
            format!("meta_performance/enact_ordering_{model}.json"),
        ] {
            let a = std::fs::read_to_string(from_db.join(&sub)).expect("db output");
            let b = std::fs::read_to_string(from_disk.join(&sub)).expect("disk output");
            assert_eq!(a, b, "{model} {sub}");
        }
        // The enact policy reads the signatures stored at import just as well.
        let enact_db = dir.path().join(format!("enact-db-{model}"));
        let (ok, _, stderr) = run(&[
            &"score",
            &file,
            &"--db",
            &db,
            &"--dataset",
            &"parity",
            &"--policy",
            &"enact",
            &"--out",
            &enact_db,
        ]);
        assert!(ok, "{stderr}");
        let ours = std::fs::read_to_string(
            enact_db.join(format!("detailed_eval/enact_ordering_{model}.jsonl")),
        )
        .expect("ours");
        let reference = std::fs::read_to_string(parity.join(format!(
            "reference/eval_plain/detailed_eval/enact_ordering_{model}.jsonl"
        )))
        .expect("reference");
        assert_eq!(
            ours, reference,
            "{model}: enact policy from stored signatures"
        );
    }
}
