//! Parity with ENACT's own evaluator on the `enact-parity` fixtures: every prediction file is
//! scored with the Enact policy, signatures taken from ENACT's `pair_signatures.jsonl`, and
//! compared with ENACT's plain-mode output (`reference/eval_plain/`) and skip list
//! (`reference/skipped_items.json`, "plain").

use std::borrow::Cow;
use std::collections::{BTreeSet, HashMap, HashSet};
use std::fs;
use std::path::{Path, PathBuf};

use enact_core::verifier::{
    EnactEvaluation, EnactRunError, EnactSignatureSource, ItemSignatures, View, VisibleCoverage,
    enact_model_name, python_text_lines, score_enact_predictions,
};
use serde_json::Value;

#[path = "../../../tests/support/fixtures.rs"]
mod fixtures;

type PairSets = Result<(BTreeSet<String>, BTreeSet<String>), String>;

/// One task's key frames and ENACT's sets for every ordered pair of distinct key frames.
#[derive(Default)]
struct TaskScenes {
    frames: HashSet<String>,
    pairs: HashMap<(String, String), PairSets>,
}

/// ENACT's signature sets per task.
struct FixtureScenes {
    tasks: HashMap<String, TaskScenes>,
}

impl FixtureScenes {
    fn load(path: &Path) -> FixtureScenes {
        let text = fs::read_to_string(path).expect("pair_signatures.jsonl");
        let mut tasks: HashMap<String, TaskScenes> = HashMap::new();
        let as_set = |v: &Value| -> BTreeSet<String> {
            v.as_array()
                .expect("signature list")
                .iter()
                .map(|s| s.as_str().expect("signature string").to_owned())
                .collect()
        };
        for line in text.lines() {
            let row: Value = serde_json::from_str(line).expect("pair row");
            let task = row["task_name"].as_str().expect("task").to_owned();
            let from = row["from_frame"].as_str().expect("from").to_owned();
            let to = row["to_frame"].as_str().expect("to").to_owned();
            let sets = if row["visible"].is_null() || row["full"].is_null() {
                Err(row["error"].to_string())
            } else {
                Ok((as_set(&row["visible"]), as_set(&row["full"])))
            };
            let entry = tasks.entry(task).or_default();
            entry.frames.insert(from.clone());
            entry.frames.insert(to.clone());
            entry.pairs.insert((from, to), sets);
        }
        FixtureScenes { tasks }
    }
}

impl EnactSignatureSource for FixtureScenes {
    fn has_task(&self, task_name: &str) -> bool {
        self.tasks.contains_key(task_name)
    }

    fn item_signatures(
        &self,
        task_name: &str,
        key_frame_ids: &[String],
        coverage: VisibleCoverage,
    ) -> Cow<'_, ItemSignatures> {
        let TaskScenes { frames, pairs } = &self.tasks[task_name];
        Cow::Owned(ItemSignatures::build(
            key_frame_ids,
            coverage,
            |from, to, view| {
                for frame in [from, to] {
                    if !frames.contains(frame) {
                        return Err(format!("'Frame ID {frame} not found in scene graph data'"));
                    }
                }
                if from == to {
                    // ENACT's diff of a frame with itself is empty.
                    return Ok(BTreeSet::new());
                }
                match pairs.get(&(from.to_owned(), to.to_owned())) {
                    Some(Ok((visible, full))) => Ok(match view {
                        View::Visible => visible.clone(),
                        View::Full => full.clone(),
                    }),
                    Some(Err(error)) => Err(error.clone()),
                    None => Err(format!("pair ({from}, {to}) is not in the fixture")),
                }
            },
        ))
    }
}

/// Compares one detailed_eval line field by field; returns the differences.
fn compare_detailed(ours: &str, theirs: &str) -> Vec<String> {
    let a: Value = serde_json::from_str(ours).expect("our line is JSON");
    let b: Value = serde_json::from_str(theirs).expect("reference line is JSON");
    let mut problems = Vec::new();
    for key in [
        "id",
        "task_name",
        "type",
        "ground_truth",
        "model_answer",
        "raw_answer",
    ] {
        if a[key] != b[key] {
            problems.push(format!("{key}: ours {} vs ENACT {}", a[key], b[key]));
        }
    }
    let (ma, mb) = (&a["eval_metrics"], &b["eval_metrics"]);
    for key in ["exact_match", "semantic_match", "task_accuracy"] {
        if ma[key] != mb[key] || !mb[key].is_boolean() {
            problems.push(format!("{key}: ours {} vs ENACT {}", ma[key], mb[key]));
        }
    }
    let (pa, pb) = (&ma["pairwise_accuracy"], &mb["pairwise_accuracy"]);
    let same_kind = pa.is_f64() == pb.is_f64();
    let close = match (pa.as_f64(), pb.as_f64()) {
        (Some(x), Some(y)) => (x - y).abs() <= 1e-12,
        _ => false,
    };
    if !same_kind || !close {
        problems.push(format!("pairwise_accuracy: ours {pa} vs ENACT {pb}"));
    }
    let keys = |v: &Value| v.as_object().map(|o| o.keys().cloned().collect::<Vec<_>>());
    if keys(&a) != keys(&b) {
        problems.push(format!("keys: ours {:?} vs ENACT {:?}", keys(&a), keys(&b)));
    }
    problems
}

/// Compares meta_performance objects: same keys, counts and task accuracy exact, pairwise
/// accuracy within 1e-12.
fn compare_meta(ours: &Value, theirs: &Value, path: &str, problems: &mut Vec<String>) {
    match (ours, theirs) {
        (Value::Object(a), Value::Object(b)) => {
            let (ka, kb): (Vec<_>, Vec<_>) = (a.keys().collect(), b.keys().collect());
            if ka != kb {
                problems.push(format!("{path}: keys {ka:?} vs {kb:?}"));
                return;
            }
            for (key, value) in a {
                compare_meta(value, &b[key], &format!("{path}.{key}"), problems);
            }
        }
        (a, b) if path.ends_with("pairwise_accuracy") => {
            let close =
                matches!((a.as_f64(), b.as_f64()), (Some(x), Some(y)) if (x - y).abs() <= 1e-12);
            if !close {
                problems.push(format!("{path}: {a} vs {b}"));
            }
        }
        (a, b) => {
            if a != b {
                problems.push(format!("{path}: {a} vs {b}"));
            }
        }
    }
}

struct ModelOutcome {
    lines: String,
    problems: Vec<String>,
}

fn check_model(
    dir: &Path,
    file: &Path,
    scenes: &FixtureScenes,
    skipped_reference: &Value,
) -> ModelOutcome {
    let name = file
        .file_name()
        .and_then(|n| n.to_str())
        .expect("file name");
    let model = enact_model_name(name);
    let text = fs::read_to_string(file).expect("prediction file");
    let result = score_enact_predictions(python_text_lines(&text), &model, scenes);
    let expected = &skipped_reference["plain"][&model];
    let mut problems = Vec::new();

    if let Some(report_error) = expected["report_error"].as_str() {
        match result {
            Err(EnactRunError::ReportCrash {
                python_error, line, ..
            }) => {
                if python_error != report_error {
                    problems.push(format!(
                        "crash message {python_error:?} vs ENACT {report_error:?}"
                    ));
                }
                let meta = dir.join(format!(
                    "reference/eval_plain/meta_performance/enact_ordering_{model}.json"
                ));
                if meta.exists() {
                    problems.push("ENACT wrote a meta file for a crashing model?".to_owned());
                }
                return ModelOutcome {
                    lines: format!("ENACT crashes; we report line {line}: {python_error}"),
                    problems,
                };
            }
            other => {
                problems.push(format!(
                    "expected a report crash, got {:?}",
                    other.map(|e| e.evaluated.len())
                ));
                return ModelOutcome {
                    lines: String::new(),
                    problems,
                };
            }
        }
    }
    let evaluation: EnactEvaluation = match result {
        Ok(evaluation) => evaluation,
        Err(error) => {
            problems.push(format!("unexpected error: {error}"));
            return ModelOutcome {
                lines: String::new(),
                problems,
            };
        }
    };

    // Evaluated ids in order.
    let ids: Vec<Value> = evaluation
        .evaluated
        .iter()
        .map(|r| serde_json::from_str(&r.id.to_json(false)).expect("id"))
        .collect();
    let expected_ids = expected["evaluated_ids"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    if ids != expected_ids {
        problems.push(format!(
            "evaluated ids differ: {} ours vs {} ENACT",
            ids.len(),
            expected_ids.len()
        ));
    }

    // Skipped lines and reasons.
    let ours_skipped: Vec<Value> = evaluation
        .skipped
        .iter()
        .map(|s| serde_json::from_str(&s.to_enact_value().to_json(false)).expect("skip entry"))
        .collect();
    let theirs_skipped = expected["skipped"].as_array().cloned().unwrap_or_default();
    let skipped_matched = ours_skipped
        .iter()
        .zip(&theirs_skipped)
        .filter(|(a, b)| a == b)
        .count();
    if ours_skipped != theirs_skipped {
        for (a, b) in ours_skipped.iter().zip(&theirs_skipped) {
            if a != b {
                problems.push(format!("skip entry: ours {a} vs ENACT {b}"));
            }
        }
        if ours_skipped.len() != theirs_skipped.len() {
            problems.push(format!(
                "{} skips ours vs {} ENACT",
                ours_skipped.len(),
                theirs_skipped.len()
            ));
        }
    }

    // detailed_eval, line by line.
    let reference_detailed = fs::read_to_string(dir.join(format!(
        "reference/eval_plain/detailed_eval/enact_ordering_{model}.jsonl"
    )))
    .expect("reference detailed_eval");
    let ours_detailed = evaluation.detailed_eval_jsonl();
    let (ours_lines, theirs_lines): (Vec<&str>, Vec<&str>) = (
        ours_detailed.lines().collect(),
        reference_detailed.lines().collect(),
    );
    if ours_lines.len() != theirs_lines.len() {
        problems.push(format!(
            "{} detailed lines ours vs {} ENACT",
            ours_lines.len(),
            theirs_lines.len()
        ));
    }
    let mut matched = 0;
    let mut identical = 0;
    for (i, (a, b)) in ours_lines.iter().zip(&theirs_lines).enumerate() {
        let differences = compare_detailed(a, b);
        if differences.is_empty() {
            matched += 1;
        } else {
            problems.push(format!(
                "detailed line {}: {}",
                i + 1,
                differences.join("; ")
            ));
        }
        if a == b {
            identical += 1;
        }
    }
    if ours_detailed != reference_detailed {
        problems.push("detailed_eval file is not byte-identical".to_owned());
    }

    // meta_performance.
    let reference_meta = fs::read_to_string(dir.join(format!(
        "reference/eval_plain/meta_performance/enact_ordering_{model}.json"
    )))
    .expect("reference meta");
    let ours_meta = evaluation.meta_performance_json();
    let mut meta_problems = Vec::new();
    compare_meta(
        &serde_json::from_str(&ours_meta).expect("our meta"),
        &serde_json::from_str(&reference_meta).expect("reference meta"),
        "meta",
        &mut meta_problems,
    );
    let meta_identical = ours_meta == reference_meta;
    problems.extend(meta_problems.iter().cloned());
    if !meta_identical {
        problems.push("meta_performance file is not byte-identical".to_owned());
    }

    ModelOutcome {
        lines: format!(
            "{matched}/{} detailed lines match ({identical} byte-identical), {skipped_matched}/{} skips match, \
             meta {} ({})",
            theirs_lines.len(),
            theirs_skipped.len(),
            if meta_problems.is_empty() {
                "matches"
            } else {
                "DIFFERS"
            },
            if meta_identical {
                "byte-identical"
            } else {
                "not byte-identical"
            },
        ),
        problems,
    }
}

#[test]
fn enact_policy_matches_enacts_plain_evaluator() {
    let Some(dir) = fixtures::parity_dir() else {
        return;
    };
    let scenes = FixtureScenes::load(&dir.join("reference/pair_signatures.jsonl"));
    let skipped_reference: Value = serde_json::from_str(
        &fs::read_to_string(dir.join("reference/skipped_items.json")).expect("skipped_items"),
    )
    .expect("skipped_items JSON");
    let mut files: Vec<PathBuf> = fs::read_dir(dir.join("predictions"))
        .expect("predictions dir")
        .map(|e| e.expect("entry").path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("enact_ordering_") && n.ends_with(".jsonl"))
        })
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no prediction files found");
    let mut failures = Vec::new();
    for file in &files {
        let outcome = check_model(&dir, file, &scenes, &skipped_reference);
        let model = enact_model_name(file.to_str().unwrap_or_default());
        println!("{model:>12}: {}", outcome.lines);
        for problem in outcome.problems {
            failures.push(format!("{model}: {problem}"));
        }
    }
    for failure in &failures {
        println!("MISMATCH {failure}");
    }
    assert!(
        failures.is_empty(),
        "{} mismatches with ENACT",
        failures.len()
    );
}
