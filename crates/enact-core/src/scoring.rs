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
