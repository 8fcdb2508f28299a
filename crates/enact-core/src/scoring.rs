//! Scoring whole prediction files: the sources of items and signatures each policy needs, the
//! TA/PA table, and ENACT's output files. The verdicts themselves come from [`crate::verifier`].

use std::borrow::Cow;
use std::collections::{BTreeSet, HashMap};
use std::fmt::Write as _;
use std::path::Path;

use rayon::prelude::*;
use serde_json::Value;

use crate::dataset::{Direction, QaItem, StepLength};
use crate::scene_graph::{FrameSelection, PairSignatureMemo, SceneGraphTimeline, TimelineError};
use crate::semantics::{self, ItemSemantics, SignatureSource};
use crate::verifier::{
    EnactSignatureSource, ItemSignatures, PerformanceReport, Permutation, StepPerformance,
    StrictItem, StrictItemResult, StrictOutcome, StrictScoring, VisibleCoverage,
};

/// ENACT's evaluator reads signatures from the scene graphs of the tasks a prediction file
/// names, at the key frames its records carry.
pub struct SceneGraphSignatures {
    tasks: HashMap<String, TaskSignatures>,
}

/// A task's timeline, the pairs its records need, and each record's table at the coverage
/// nearly every record asks for, all computed ahead in parallel (ENACT's evaluator loop is
/// sequential; the signatures need not be).
struct TaskSignatures {
    timeline: SceneGraphTimeline,
    memo: PairSignatureMemo,
    tables: HashMap<Vec<String>, ItemSignatures>,
}

impl SceneGraphSignatures {
    /// Loads, for every task the prediction lines name, the frames they use, and computes the
    /// tables of each line's key frames. A task without a scene graph is left out (ENACT skips
    /// its lines); an unreadable one is an error.
    pub fn for_predictions<'a>(
        replayed_dir: &Path,
        lines: impl IntoIterator<Item = &'a str>,
    ) -> Result<SceneGraphSignatures, TimelineError> {
        // Per task: each line's key frames as ENACT looks them up (`str(id)`).
        let mut frames: HashMap<String, BTreeSet<Vec<String>>> = HashMap::new();
        for line in lines {
            let Ok(Value::Object(record)) = serde_json::from_str::<Value>(line) else {
                continue;
            };
            let Some(Value::String(task)) = record.get("task_name") else {
                continue;
            };
            let entry = frames.entry(task.clone()).or_default();
            if let Some(Value::Array(ids)) = record.get("key_frame_ids") {
                let ids: Vec<String> = ids
                    .iter()
                    .filter_map(|id| match id {
                        Value::String(s) => Some(s.clone()),
                        Value::Number(n) => Some(n.to_string()),
                        _ => None,
                    })
                    .collect();
                entry.insert(ids);
            }
        }
        let loaded: Vec<Result<Option<(String, TaskSignatures)>, TimelineError>> = frames
            .into_par_iter()
            .map(|(task, lines)| {
                let path = semantics::scene_graph_path(replayed_dir, &task);
                if !path.is_file() {
                    return Ok(None);
                }
                let selected = lines.iter().flatten().cloned().collect();
                let timeline = SceneGraphTimeline::load(&path, FrameSelection::Only(selected))?;
                let pairs = lines
                    .iter()
                    .flat_map(|ids| PairSignatureMemo::item_pairs(ids))
                    .collect();
                // A contact run's scene graphs signal contact changes too (see `semantics`).
                let vocabulary = replayed_dir.parent().map_or_else(
                    Default::default,
                    crate::pipeline::release::release_vocabulary,
                );
                let memo = PairSignatureMemo::compute_in(&timeline, pairs, vocabulary);
                let tables = lines
                    .into_par_iter()
                    .map(|ids| {
                        let table = ItemSignatures::build(
                            &ids,
                            VisibleCoverage::Chronological,
                            |from, to, view| memo.signatures(&timeline, from, to, view),
                        );
                        (ids, table)
                    })
                    .collect();
                let signatures = TaskSignatures {
                    timeline,
                    memo,
                    tables,
                };
                Ok(Some((task, signatures)))
            })
            .collect();
        let mut tasks = HashMap::new();
        for entry in loaded {
            if let Some((task, signatures)) = entry? {
                tasks.insert(task, signatures);
            }
        }
        Ok(SceneGraphSignatures { tasks })
    }
}

impl EnactSignatureSource for SceneGraphSignatures {
    fn has_task(&self, task_name: &str) -> bool {
        self.tasks.contains_key(task_name)
    }

    fn item_signatures(
        &self,
        task_name: &str,
        key_frame_ids: &[String],
        coverage: VisibleCoverage,
    ) -> Cow<'_, ItemSignatures> {
        let task = self.tasks.get(task_name);
        if let (Some(task), VisibleCoverage::Chronological) = (task, coverage)
            && let Some(table) = task.tables.get(key_frame_ids)
        {
            return Cow::Borrowed(table);
        }
        Cow::Owned(ItemSignatures::build(
            key_frame_ids,
            coverage,
            |from, to, view| {
                let task = task.ok_or_else(|| format!("no scene graph for task {task_name}"))?;
                task.memo.signatures(&task.timeline, from, to, view)
            },
        ))
    }
}

/// ENACT's evaluator over a stored dataset: signatures computed at import, looked up by the
/// record's task and key frames. A record whose key frames are not those of a stored item (or
/// whose ground truth needs pairs a stored table does not cover) gets a table of errors, so it
/// scores as ENACT scores an item whose diffs raise: exact match only. Against a release on
/// disk with `--scene-graphs`, every pair is computed instead.
pub struct StoredSignatures {
    tables: HashMap<(String, Vec<String>), ItemSignatures>,
    tasks: BTreeSet<String>,
}

impl StoredSignatures {
    /// From `(task, key frames, table)` of the stored items that have scene-graph signatures.
    pub fn new(items: impl IntoIterator<Item = (String, Vec<String>, ItemSignatures)>) -> Self {
        let mut tables = HashMap::new();
        let mut tasks = BTreeSet::new();
        for (task, frames, table) in items {
            tasks.insert(task.clone());
            tables.insert((task, frames), table);
        }
        StoredSignatures { tables, tasks }
    }
}

impl EnactSignatureSource for StoredSignatures {
    fn has_task(&self, task_name: &str) -> bool {
        self.tasks.contains(task_name)
    }

    fn item_signatures(
        &self,
        task_name: &str,
        key_frame_ids: &[String],
        coverage: VisibleCoverage,
    ) -> Cow<'_, ItemSignatures> {
        let key = (task_name.to_owned(), key_frame_ids.to_vec());
        match (self.tables.get(&key), coverage) {
            (Some(table), VisibleCoverage::Chronological) => Cow::Borrowed(table),
            _ => Cow::Owned(ItemSignatures::build(key_frame_ids, coverage, |_, _, _| {
                Err("these key frames are not a stored item of the dataset".to_owned())
            })),
        }
    }
}

/// One dataset item as the strict policy scores it.
#[derive(Debug, Clone)]
pub struct ScoringTarget {
    pub id: String,
    pub item_type: String,
    pub task_name: String,
    pub direction: Direction,
    pub step_length: StepLength,
    pub ground_truth: Permutation,
    pub semantics: Option<ItemSemantics>,
}

impl ScoringTarget {
    pub fn from_item(item: &QaItem, semantics: Option<ItemSemantics>) -> Result<Self, String> {
        Ok(ScoringTarget {
            id: item.id.clone(),
            item_type: item.item_type.clone(),
            task_name: item.task_name.clone(),
            direction: item.direction,
            step_length: item.step_length,
            ground_truth: Permutation::new(item.gt_answer.clone())
                .map_err(|e| format!("item {}: gt_answer: {e}", item.id))?,
            semantics,
        })
    }

    pub fn strict_item(&self) -> StrictItem<'_> {
        StrictItem {
            id: &self.id,
            direction: self.direction,
            step_length: self.step_length,
            ground_truth: &self.ground_truth,
            signatures: self.semantics.as_ref().map(|s| &s.signatures),
        }
    }
}

/// How many items of a dataset can be judged semantically, by source.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct SemanticCoverage {
    pub scene_graph: usize,
    pub action_text: usize,
    pub exact_only: usize,
}

impl SemanticCoverage {
    pub fn of(targets: &[ScoringTarget]) -> Self {
        let mut c = SemanticCoverage::default();
        for t in targets {
            match t.semantics.as_ref().map(|s| s.source) {
                Some(SignatureSource::SceneGraph) => c.scene_graph += 1,
                Some(SignatureSource::ActionText) => c.action_text += 1,
                None => c.exact_only += 1,
            }
        }
        c
    }

    pub fn describe(&self) -> String {
        format!(
            "semantic matching: {} items from scene graphs, {} from action text (lower bound), \
             {} exact-only",
            self.scene_graph, self.action_text, self.exact_only
        )
    }
}

fn percent(v: f64) -> String {
    format!("{:.2}", v * 100.0)
}

fn cell(step: Option<&StepPerformance>) -> (String, String) {
    match step {
        None => ("-".to_owned(), "-".to_owned()),
        Some(s) => (
            percent(s.task_accuracy),
            s.pairwise_accuracy
                .map_or_else(|| "n/a".to_owned(), percent),
        ),
    }
}

/// The TA/PA table (percent), by direction and step length, as printed by `score`.
pub fn performance_table(report: &PerformanceReport) -> String {
    let groups = [
        ("overall", report.overall.as_ref()),
        ("forward", report.forward_world_modeling.as_ref()),
        ("inverse", report.inverse_world_modeling.as_ref()),
    ];
    let mut out = String::new();
    let _ = write!(out, "{:<9} {:>6} {:>7} {:>7}", "", "count", "TA", "PA");
    for l in StepLength::all() {
        let _ = write!(out, " {:>15}", format!("L={l} TA/PA"));
    }
    out.push('\n');
    for (name, group) in groups {
        let Some(g) = group else {
            continue;
        };
        let (ta, pa) = cell(Some(&g.totals));
        let _ = write!(out, "{name:<9} {:>6} {ta:>7} {pa:>7}", g.totals.count);
        for l in StepLength::all() {
            let (ta, pa) = cell(g.per_step.get(&l.states()));
            let _ = write!(out, " {:>15}", format!("{ta}/{pa}"));
        }
        out.push('\n');
    }
    if report.overall.is_none() {
        out.push_str("(no item was scored)\n");
    }
    out
}

/// `detailed_eval` lines for a strict scoring: ENACT's fields, plus the outcome and, for
/// answers that could not be read, the reason.
pub fn strict_detailed_jsonl(targets: &[ScoringTarget], scoring: &StrictScoring) -> String {
    let by_id: HashMap<&str, &ScoringTarget> = targets.iter().map(|t| (t.id.as_str(), t)).collect();
    let mut out = String::new();
    for result in &scoring.items {
        let line = strict_detailed_line(by_id.get(result.id.as_str()).copied(), result);
        out.push_str(&line.to_string());
        out.push('\n');
    }
    out
}

fn strict_detailed_line(target: Option<&ScoringTarget>, result: &StrictItemResult) -> Value {
    let (outcome, answer, metrics, reason) = match &result.outcome {
        StrictOutcome::Scored { answer, verdict } => (
            "scored",
            serde_json::to_value(answer).unwrap_or(Value::Null),
            serde_json::json!({
                "exact_match": verdict.exact_match,
                "semantic_match": verdict.semantic_match,
                "task_accuracy": verdict.task_accuracy,
                "pairwise_accuracy": result.pairwise_accuracy(),
            }),
            None,
        ),
        StrictOutcome::Unparseable { reason } => (
            "unparseable",
            Value::Null,
            failed_metrics(),
            Some(reason.to_string()),
        ),
        StrictOutcome::Missing => ("missing", Value::Null, failed_metrics(), None),
    };
    serde_json::json!({
        "id": result.id,
        "task_name": target.map(|t| t.task_name.as_str()),
        "type": target.map(|t| t.item_type.as_str()),
        "eval_metrics": metrics,
        "ground_truth": target.map(|t| &t.ground_truth),
        "model_answer": answer,
        "line": result.line,
        "outcome": outcome,
        "reason": reason,
    })
}

fn failed_metrics() -> Value {
    serde_json::json!({
        "exact_match": false,
        "semantic_match": false,
        "task_accuracy": false,
        "pairwise_accuracy": 0.0,
    })
}

/// Everything scoring needs of a stored item: its ground truth and, as stored, its signatures.
#[derive(Debug, Clone)]
pub struct ScoringItem {
    /// The row id in `items`.
    pub row_id: i64,
    pub item_id: String,
    pub item_type: String,
    pub direction: Direction,
    pub step_length: StepLength,
    pub task_name: String,
    pub key_frame_ids: Vec<String>,
    pub gt_answer: Vec<u8>,
    /// `(source, ItemSignatures JSON)`.
    pub semantics: Option<(String, String)>,
}

/// Scoring targets from stored items, in dataset order.
pub fn targets_from_stored(rows: Vec<ScoringItem>) -> Result<Vec<ScoringTarget>, String> {
    let mut targets = Vec::with_capacity(rows.len());
    for row in rows {
        let semantics = match &row.semantics {
            None => None,
            Some((source, json)) => Some(ItemSemantics {
                source: SignatureSource::parse(source).ok_or_else(|| {
                    format!("item {}: unknown signature source {source:?}", row.item_id)
                })?,
                signatures: serde_json::from_str(json).map_err(|e| {
                    format!(
                        "item {}: stored signatures are unreadable: {e}",
                        row.item_id
                    )
                })?,
            }),
        };
        let item = QaItem {
            id: row.item_id,
            item_type: row.item_type,
            direction: row.direction,
            step_length: row.step_length,
            task_name: row.task_name,
            key_frame_ids: row.key_frame_ids,
            images: Vec::new(),
            question: String::new(),
            actions: Vec::new(),
            gt_answer: row.gt_answer,
        };
        targets.push(ScoringTarget::from_item(&item, semantics)?);
    }
    Ok(targets)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::verifier::{View, score_strict_predictions};

    fn frames(n: usize) -> Vec<String> {
        (0..n).map(|i| format!("f{i}")).collect()
    }

    /// A table of `n` key frames whose every pair changes `change`.
    fn table(n: usize, change: &str) -> ItemSignatures {
        ItemSignatures::build(&frames(n), VisibleCoverage::Chronological, |_, _, _| {
            Ok(BTreeSet::from([change.to_owned()]))
        })
    }

    fn target(
        id: &str,
        direction: Direction,
        truth: &[u8],
        source: Option<SignatureSource>,
    ) -> ScoringTarget {
        let step_length = StepLength::new(truth.len() + 1).expect("3 to 10 states");
        ScoringTarget {
            id: id.to_owned(),
            item_type: format!("{direction}_world_modeling"),
            task_name: "task".to_owned(),
            direction,
            step_length,
            ground_truth: Permutation::new(truth.to_vec()).expect("a permutation"),
            semantics: source.map(|source| ItemSemantics {
                source,
                signatures: table(truth.len() + 1, "open(door)"),
            }),
        }
    }

    #[test]
    fn stored_signatures_lend_a_stored_table_and_make_any_other_one_of_errors() {
        let stored = StoredSignatures::new([("task".to_owned(), frames(3), table(3, "a"))]);
        assert!(stored.has_task("task"));
        assert!(!stored.has_task("other"));
        let found = stored.item_signatures("task", &frames(3), VisibleCoverage::Chronological);
        assert!(matches!(found, Cow::Borrowed(_)));
        assert_eq!(
            found.signature_set(View::Visible, 0, 1),
            Some(Ok(vec!["a"]))
        );
        // All pairs, another task, other key frames: not what was stored.
        for (task, ids, coverage) in [
            ("task", frames(3), VisibleCoverage::AllPairs),
            ("other", frames(3), VisibleCoverage::Chronological),
            ("task", frames(4), VisibleCoverage::Chronological),
        ] {
            let made = stored.item_signatures(task, &ids, coverage);
            assert!(matches!(made, Cow::Owned(_)), "{task} {ids:?} {coverage:?}");
            assert_eq!(made.key_frame_ids(), &ids[..]);
            assert_eq!(made.visible_coverage(), coverage);
            assert_eq!(
                made.signature_set(View::Full, 0, 1),
                Some(Err("these key frames are not a stored item of the dataset"))
            );
        }
    }

    #[test]
    fn a_task_without_a_scene_graph_is_left_out_and_its_pairs_raise() {
        let replayed = tempfile::tempdir().expect("tempdir");
        let lines = [
            r#"{"task_name": "t", "key_frame_ids": [1, "2", null]}"#,
            "not json",
            r#"{"key_frame_ids": [1, 2]}"#,
            "[1, 2]",
        ];
        let signatures = SceneGraphSignatures::for_predictions(replayed.path(), lines)
            .expect("a missing scene graph is no error");
        assert!(!signatures.has_task("t"));
        let made = signatures.item_signatures("t", &frames(3), VisibleCoverage::Chronological);
        assert_eq!(
            made.signature_set(View::Full, 0, 1),
            Some(Err("no scene graph for task t"))
        );
        // A scene graph that is there but unreadable is an error, not a skip.
        let task = replayed.path().join("t");
        std::fs::create_dir(&task).expect("task folder");
        std::fs::write(task.join("scene_graph_0.json"), "{ not json").expect("write");
        assert!(SceneGraphSignatures::for_predictions(replayed.path(), lines).is_err());
    }

    #[test]
    fn a_task_with_a_scene_graph_lends_its_signatures() {
        let replayed = tempfile::tempdir().expect("tempdir");
        let task = replayed.path().join("t");
        std::fs::create_dir(&task).expect("task folder");
        std::fs::write(
            task.join("scene_graph_0.json"),
            r#"{
  "0": {"nodes": [{"name": "robot_r1", "category": "agent", "states": [], "visibility": {"external_sensor1": [900, 0, 0, 30, 30, 512, 512]}},
                  {"name": "apple_1", "category": "apple", "states": [],
                   "visibility": {"external_sensor1": [900, 0, 0, 30, 30, 512, 512]}}],
        "edges": [], "type": "full"},
  "2": {"type": "diff",
        "add": {"nodes": [],
                "edges": [{"from": "robot_r1", "to": "apple_1", "states": ["LeftGrasping"]}]},
        "remove": {"nodes": [], "edges": []}, "update": {"nodes": [], "edges": []}},
  "3": {"type": "diff", "add": {"nodes": [], "edges": []}, "remove": {"nodes": [], "edges": []},
        "update": {"nodes": [{"name": "apple_1", "category": "apple", "states": ["Cooked"],
                   "visibility": {"external_sensor1": [900, 0, 0, 30, 30, 512, 512]}}], "edges": []}}
}"#,
        )
        .expect("write");
        let ids: Vec<String> = ["0", "2", "3"].map(str::to_owned).to_vec();
        // Key frames named by strings or by numbers: ENACT looks both up as `str(id)`.
        for line in [
            r#"{"task_name": "t", "key_frame_ids": ["0", "2", "3"]}"#,
            r#"{"task_name": "t", "key_frame_ids": [0, 2, 3]}"#,
        ] {
            let signatures = SceneGraphSignatures::for_predictions(replayed.path(), [line])
                .expect("a readable scene graph");
            assert!(signatures.has_task("t"));
            assert!(!signatures.has_task("u"));
            let made = signatures.item_signatures("t", &ids, VisibleCoverage::Chronological);
            assert!(
                matches!(made, Cow::Borrowed(_)),
                "{line}: computed for the line"
            );
            // The grasp between the first two key frames is a change the verifier can compare.
            assert!(
                matches!(made.signature_set(View::Full, 0, 1), Some(Ok(set)) if !set.is_empty()),
                "{line}: {:?}",
                made.signature_set(View::Full, 0, 1)
            );
        }
    }

    #[test]
    fn semantic_coverage_counts_items_by_source_and_says_so() {
        let targets = [
            target(
                "a",
                Direction::Forward,
                &[2, 1],
                Some(SignatureSource::SceneGraph),
            ),
            target(
                "b",
                Direction::Inverse,
                &[1, 2],
                Some(SignatureSource::ActionText),
            ),
            target("c", Direction::Inverse, &[1, 2], None),
            target("d", Direction::Forward, &[1, 3, 2], None),
        ];
        let coverage = SemanticCoverage::of(&targets);
        assert_eq!(
            coverage,
            SemanticCoverage {
                scene_graph: 1,
                action_text: 1,
                exact_only: 2
            }
        );
        assert_eq!(
            coverage.describe(),
            "semantic matching: 1 items from scene graphs, 1 from action text (lower bound), \
             2 exact-only"
        );
    }

    fn scored(targets: &[ScoringTarget], lines: &[&str]) -> StrictScoring {
        let items: Vec<StrictItem<'_>> = targets.iter().map(ScoringTarget::strict_item).collect();
        score_strict_predictions(&items, lines.iter().enumerate().map(|(i, l)| (i + 1, *l)))
            .expect("a valid dataset")
    }

    #[test]
    fn the_performance_table_has_a_row_per_direction_and_a_cell_per_step_length() {
        let targets = [
            target("a", Direction::Forward, &[2, 1], None),
            target("b", Direction::Inverse, &[1, 3, 2], None),
            target(
                "c",
                Direction::Inverse,
                &[1, 2],
                Some(SignatureSource::SceneGraph),
            ),
        ];
        let scoring = scored(
            &targets,
            &[
                r#"{"id": "a", "answer": [2, 1]}"#,
                r#"{"id": "b", "answer": [1, 2, 3]}"#,
                r#"{"id": "c", "answer": [2, 1]}"#,
            ],
        );
        let table = performance_table(&scoring.report);
        let rows: Vec<&str> = table.lines().collect();
        assert_eq!(rows.len(), 4, "{table}");
        let cells = |row: &str| {
            row.split_whitespace()
                .map(str::to_owned)
                .collect::<Vec<_>>()
        };
        assert_eq!(cells(rows[0])[..4], ["count", "TA", "PA", "L=3"]);
        // Forward: one item of 3 states, right. Exact-only items have no partial credit.
        let forward = cells(rows[2]);
        assert_eq!(
            forward[..5],
            ["forward", "1", "100.00", "100.00", "100.00/100.00"]
        );
        assert_eq!(forward[5], "-/-");
        // Inverse: of 4 states, wrong and exact-only (n/a); of 3 states, a semantic match
        // (every transition changes the same thing).
        let inverse = cells(rows[3]);
        assert_eq!(inverse[..3], ["inverse", "2", "50.00"]);
        assert_eq!(inverse[4], "100.00/100.00");
        assert_eq!(inverse[5], "0.00/n/a");
        assert_eq!(cells(rows[1])[..3], ["overall", "3", "66.67"]);
        assert!(!table.contains("no item was scored"));

        let nothing = performance_table(&scored(&[], &[]).report);
        assert_eq!(nothing.lines().count(), 2, "{nothing}");
        assert!(nothing.ends_with("(no item was scored)\n"));
    }

    #[test]
    fn detailed_lines_say_how_each_item_was_scored_and_why_not() {
        let targets = [
            target("a", Direction::Forward, &[2, 1], None),
            target("b", Direction::Inverse, &[1, 2], None),
            target("c", Direction::Inverse, &[2, 1], None),
        ];
        let scoring = scored(
            &targets,
            &[
                r#"{"id": "a", "answer": [2, 1]}"#,
                r#"{"id": "b", "answer": "first"}"#,
            ],
        );
        let text = strict_detailed_jsonl(&targets, &scoring);
        let lines: Vec<Value> = text
            .lines()
            .map(|l| serde_json::from_str(l).expect("a JSON line"))
            .collect();
        assert_eq!(lines.len(), 3);
        let [a, b, c] = &lines[..] else {
            unreachable!()
        };
        assert_eq!(a["id"], "a");
        assert_eq!(a["task_name"], "task");
        assert_eq!(a["type"], "forward_world_modeling");
        assert_eq!(a["outcome"], "scored");
        assert_eq!(a["line"], 1);
        assert_eq!(a["ground_truth"], serde_json::json!([2, 1]));
        assert_eq!(a["model_answer"], serde_json::json!([2, 1]));
        assert_eq!(a["reason"], Value::Null);
        assert_eq!(a["eval_metrics"]["exact_match"], true);
        assert_eq!(a["eval_metrics"]["task_accuracy"], true);
        assert_eq!(a["eval_metrics"]["pairwise_accuracy"], 1.0);

        assert_eq!(b["outcome"], "unparseable");
        assert_eq!(b["line"], 2);
        assert_eq!(b["model_answer"], Value::Null);
        assert!(b["reason"].as_str().is_some_and(|r| !r.is_empty()), "{b}");
        for failed in [b, c] {
            assert_eq!(
                failed["eval_metrics"],
                serde_json::json!({"exact_match": false, "semantic_match": false,
                                   "task_accuracy": false, "pairwise_accuracy": 0.0})
            );
        }
        assert_eq!(c["outcome"], "missing");
        assert_eq!(c["line"], Value::Null);
        assert_eq!(c["ground_truth"], serde_json::json!([2, 1]));
    }

    fn stored_row(semantics: Option<(&str, String)>, truth: Vec<u8>) -> ScoringItem {
        ScoringItem {
            row_id: 7,
            item_id: "i1".to_owned(),
            item_type: "inverse_world_modeling".to_owned(),
            direction: Direction::Inverse,
            step_length: StepLength::new(3).expect("3 states"),
            task_name: "task".to_owned(),
            key_frame_ids: frames(3),
            gt_answer: truth,
            semantics: semantics.map(|(source, json)| (source.to_owned(), json)),
        }
    }

    #[test]
    fn stored_items_become_targets_and_a_bad_one_is_named() {
        let json = serde_json::to_string(&table(3, "a")).expect("serialise");
        let targets = targets_from_stored(vec![
            stored_row(Some(("scene_graph", json.clone())), vec![2, 1]),
            stored_row(None, vec![1, 2]),
        ])
        .expect("valid rows");
        assert_eq!(targets.len(), 2);
        assert_eq!(targets[0].id, "i1");
        assert_eq!(targets[0].ground_truth.labels(), &[2, 1]);
        let semantics = targets[0].semantics.as_ref().expect("signatures");
        assert_eq!(semantics.source, SignatureSource::SceneGraph);
        assert_eq!(semantics.signatures, table(3, "a"));
        assert!(targets[1].semantics.is_none());

        let unknown = targets_from_stored(vec![stored_row(Some(("graph", json)), vec![2, 1])]);
        assert_eq!(
            unknown.err().as_deref(),
            Some("item i1: unknown signature source \"graph\"")
        );
        let unreadable = targets_from_stored(vec![stored_row(
            Some(("scene_graph", "{".to_owned())),
            vec![2, 1],
        )])
        .expect_err("refused");
        assert!(
            unreadable.starts_with("item i1: stored signatures are unreadable: "),
            "{unreadable}"
        );
        let not_a_permutation =
            targets_from_stored(vec![stored_row(None, vec![2, 2])]).expect_err("refused");
        assert!(
            not_a_permutation.starts_with("item i1: gt_answer: "),
            "{not_a_permutation}"
        );
    }
}
