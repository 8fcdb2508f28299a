//! `ScoringPolicy::Enact`: ENACT's whole-file evaluator loop (`OrderingEvaluator.evaluate`) and
//! its output files, reproduced item for item.
//!
//! Every record is scored with its own `gt_answer`, `key_frame_ids` and `type`, in file order;
//! skipped lines leave the denominators, exactly as ENACT does. Use the strict policy for a
//! leaderboard; this one exists to give the same numbers as ENACT's own `enact eval`.

use std::borrow::Cow;
use std::collections::{HashMap, HashSet};
use std::fmt;

use crate::verifier::answer::{
    Direction, ParsedAnswer, enact_report_group, enact_verifier_direction, parse_answer_enact,
};
use crate::verifier::pyint::PyInt;
use crate::verifier::pyjson::{PyHashKey, PyJsonError, PyValue, parse_python_json};
use crate::verifier::report::{PerformanceReport, ScoredEntry, enact_meta_performance_json};
use crate::verifier::signatures::{ItemSignatures, VisibleCoverage};
use crate::verifier::unicode::py_strip;
use crate::verifier::verify::{
    GroundTruthView, KeyFrameShape, Verdict, VerifyError, verify_enact_record,
};

/// Where the Enact policy gets scene-graph signatures.
pub trait EnactSignatureSource {
    /// Whether ENACT could build a verifier for this task (its scene graphs exist).
    fn has_task(&self, task_name: &str) -> bool;

    /// The signature tables of a record's own key frames (`str()` of each element), with at
    /// least the visible `coverage` asked for. Only called for tasks with `has_task` true.
    /// Borrowed when the source holds the table already.
    fn item_signatures(
        &self,
        task_name: &str,
        key_frame_ids: &[String],
        coverage: VisibleCoverage,
    ) -> Cow<'_, ItemSignatures>;
}

/// ENACT's reasons for leaving a line out of every metric.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SkipReason {
    InvalidJsonFormat,
    MissingIdField,
    /// ENACT quirk: the id was already stored by an earlier, successfully evaluated line (an
    /// earlier line that was skipped does not count; ids compare as Python dict keys).
    AlreadyEvaluated,
    /// Missing task name, or a task without scene graphs.
    InvalidOrMissingTaskName,
    MissingGtAnswerOrKeyFrames,
    FailedToParseAnswer,
    /// A Python exception outside the verifier's try block, with its message.
    EvaluationError(String),
}

impl fmt::Display for SkipReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SkipReason::InvalidJsonFormat => f.write_str("invalid_json_format"),
            SkipReason::MissingIdField => f.write_str("missing_id_field"),
            SkipReason::AlreadyEvaluated => f.write_str("already_evaluated"),
            SkipReason::InvalidOrMissingTaskName => f.write_str("invalid_or_missing_task_name"),
            SkipReason::MissingGtAnswerOrKeyFrames => {
                f.write_str("missing_gt_answer_or_key_frames")
            }
            SkipReason::FailedToParseAnswer => f.write_str("failed_to_parse_answer"),
            SkipReason::EvaluationError(message) => write!(f, "evaluation_error: {message}"),
        }
    }
}

/// One entry of ENACT's `skipped_items` list (the values as ENACT records them).
#[derive(Debug, Clone)]
pub struct SkippedLine {
    pub line: usize,
    pub id: PyValue,
    pub reason: SkipReason,
    pub task_name: PyValue,
    pub task_type: PyValue,
    /// Only for `failed_to_parse_answer`.
    pub raw_answer: Option<PyValue>,
}

impl SkippedLine {
    /// The entry as ENACT builds it: `{id, line_num, reason, task_name, task_type[, raw_answer]}`.
    pub fn to_enact_value(&self) -> PyValue {
        let mut entries = vec![
            ("id".to_owned(), self.id.clone()),
            (
                "line_num".to_owned(),
                PyValue::Int(PyInt::Small(self.line as i64)),
            ),
            ("reason".to_owned(), PyValue::Str(self.reason.to_string())),
            ("task_name".to_owned(), self.task_name.clone()),
            ("task_type".to_owned(), self.task_type.clone()),
        ];
        if let Some(raw) = &self.raw_answer {
            entries.push(("raw_answer".to_owned(), raw.clone()));
        }
        PyValue::Dict(entries)
    }
}

/// One evaluated record, in ENACT's storage order.
#[derive(Debug, Clone)]
pub struct EvaluatedRecord {
    pub line: usize,
    pub id: PyValue,
    pub task_name: PyValue,
    pub task_type: PyValue,
    pub ground_truth: PyValue,
    pub model_answer: ParsedAnswer,
    pub raw_answer: PyValue,
    pub verdict: Verdict,
}

impl EvaluatedRecord {
    /// One line of ENACT's `detailed_eval` file, without the newline.
    pub fn detailed_eval_line(&self) -> String {
        let v = &self.verdict;
        let metrics = PyValue::Dict(vec![
            ("exact_match".to_owned(), PyValue::Bool(v.exact_match)),
            ("semantic_match".to_owned(), PyValue::Bool(v.semantic_match)),
            ("task_accuracy".to_owned(), PyValue::Bool(v.task_accuracy)),
            (
                "pairwise_accuracy".to_owned(),
                v.pairwise_accuracy.to_py_value(),
            ),
        ]);
        PyValue::Dict(vec![
            ("id".to_owned(), self.id.clone()),
            ("task_name".to_owned(), self.task_name.clone()),
            ("type".to_owned(), self.task_type.clone()),
            ("eval_metrics".to_owned(), metrics),
            ("ground_truth".to_owned(), self.ground_truth.clone()),
            (
                "model_answer".to_owned(),
                PyValue::List(self.model_answer.labels().to_vec()),
            ),
            ("raw_answer".to_owned(), self.raw_answer.clone()),
        ])
        .to_json(false)
    }
}

/// The outcome of ENACT's evaluator on one prediction file.
#[derive(Debug, Clone)]
pub struct EnactEvaluation {
    pub model_name: String,
    pub evaluated: Vec<EvaluatedRecord>,
    pub skipped: Vec<SkippedLine>,
    pub report: PerformanceReport,
}

impl EnactEvaluation {
    /// The bytes of `detailed_eval/enact_ordering_{model}.jsonl`.
    pub fn detailed_eval_jsonl(&self) -> String {
        let mut out = String::new();
        for record in &self.evaluated {
            out.push_str(&record.detailed_eval_line());
            out.push('\n');
        }
        out
    }

    /// The bytes of `meta_performance/enact_ordering_{model}.json`.
    pub fn meta_performance_json(&self) -> String {
        enact_meta_performance_json(&self.model_name, &self.report)
    }
}

/// Inputs on which ENACT's evaluator itself crashes: it writes nothing for the model.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EnactRunError {
    /// ENACT's first pass over the file (collecting task names) does not survive this line.
    #[error(
        "line {line}: ENACT's evaluator crashes on this line ({python_error}); it writes no results for the file"
    )]
    FirstPassCrash { line: usize, python_error: String },
    /// An evaluated record whose `type` is not a string crashes ENACT's report step.
    #[error(
        "line {line}: record {id} was evaluated but its `type` is {found}, not a string; ENACT's \
         report step crashes on it ({python_error}) and writes no results for the file"
    )]
    ReportCrash {
        line: usize,
        id: String,
        found: String,
        python_error: String,
    },
    /// The signature source returned a table that does not fit the record.
    #[error("line {line}: {source}")]
    Signatures { line: usize, source: VerifyError },
}

/// ENACT quirk: the model name ENACT derives from a prediction file name: the part between
/// `enact_ordering_` and `.jsonl` of the base name (possibly empty), else `"unknown"`.
pub fn enact_model_name(file_name: &str) -> String {
    let base = file_name
        .trim_end_matches('/')
        .rsplit('/')
        .next()
        .unwrap_or(file_name);
    base.strip_prefix("enact_ordering_")
        .and_then(|rest| rest.strip_suffix(".jsonl"))
        .map_or_else(|| "unknown".to_owned(), str::to_owned)
}

/// ENACT quirk: lines as Python's text-mode file iteration yields them (universal newlines: `\n`,
/// `\r\n` and a lone `\r` all end a line), numbered from 1, terminators removed.
pub fn python_text_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut rest = text;
    let mut number = 0;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        number += 1;
        let end = rest.find(['\n', '\r']).unwrap_or(rest.len());
        let line = &rest[..end];
        let after = &rest[end..];
        rest = match after.strip_prefix("\r\n") {
            Some(next) => next,
            None => after.get(1..).unwrap_or(""),
        };
        Some((number, line))
    })
}

fn text(s: &str) -> PyValue {
    PyValue::Str(s.to_owned())
}

/// ENACT's evaluator over one prediction file (plain mode, without `--analyze-wrong-cases`).
///
/// `lines` are (line number, text) pairs, e.g. from [`python_text_lines`]. ENACT reads the file
/// twice (task names first), so the lines are held in memory once parsed.
pub fn score_enact_predictions<I, S>(
    lines: I,
    model_name: &str,
    source: &dyn EnactSignatureSource,
) -> Result<EnactEvaluation, EnactRunError>
where
    I: IntoIterator<Item = (usize, S)>,
    S: AsRef<str>,
{
    let records: Vec<(usize, Result<PyValue, PyJsonError>)> = lines
        .into_iter()
        .map(|(line, raw)| (line, parse_python_json(py_strip(raw.as_ref()))))
        .collect();
    let verifiers = gather_verifiers(&records, source)?;
    let mut evaluation = EnactEvaluation {
        model_name: model_name.to_owned(),
        evaluated: Vec::new(),
        skipped: Vec::new(),
        report: PerformanceReport::default(),
    };
    if verifiers.is_empty() {
        // "No valid verifiers found. Evaluation aborted." (see `gather_verifiers`).
        return Ok(evaluation);
    }
    let mut stored: HashMap<PyHashKey, usize> = HashMap::new();
    for (serial, (line, parsed)) in records.iter().enumerate() {
        let line = *line;
        let Ok(record) = parsed else {
            evaluation.skipped.push(SkippedLine {
                line,
                id: text("unknown"),
                reason: SkipReason::InvalidJsonFormat,
                task_name: text("unknown"),
                task_type: text("unknown"),
                raw_answer: None,
            });
            continue;
        };
        match evaluate_record(line, serial, record, &verifiers, &stored, source)? {
            Ok(evaluated) => {
                if let Ok(key) = PyHashKey::of(&evaluated.id, serial) {
                    stored.insert(key, evaluation.evaluated.len());
                }
                evaluation.evaluated.push(evaluated);
            }
            Err(skipped) => evaluation.skipped.push(skipped),
        }
    }
    check_report_types(&evaluation.evaluated)?;
    let entries: Vec<ScoredEntry> = evaluation
        .evaluated
        .iter()
        .map(|r| ScoredEntry {
            group: r.task_type.as_str().and_then(enact_report_group),
            states: GroundTruthView::of(&r.ground_truth).map_or(1, |gt| gt.len() + 1),
            task_accuracy: r.verdict.task_accuracy,
            pairwise_accuracy: r.verdict.pairwise_accuracy.value(),
        })
        .collect();
    evaluation.report = PerformanceReport::from_entries(&entries);
    Ok(evaluation)
}

/// ENACT quirk: the first pass over the file collects the task names that get a verifier.
/// Lines `json.loads` rejects are passed over, but a line that is valid JSON and not an object,
/// or whose `task_name` is a non-empty list or dict, crashes the whole evaluation; and when no
/// task name has a verifier, ENACT evaluates nothing and records no skips at all.
fn gather_verifiers(
    records: &[(usize, Result<PyValue, PyJsonError>)],
    source: &dyn EnactSignatureSource,
) -> Result<HashSet<String>, EnactRunError> {
    let mut verifiers = HashSet::new();
    for (line, parsed) in records {
        let crash = |python_error: String| EnactRunError::FirstPassCrash {
            line: *line,
            python_error,
        };
        let record = match parsed {
            Ok(record) => record,
            Err(PyJsonError::Decode { .. }) => continue,
            Err(PyJsonError::Fatal { message }) => return Err(crash(message.clone())),
        };
        if !matches!(record, PyValue::Dict(_)) {
            return Err(crash(format!(
                "'{}' object has no attribute 'get'",
                record.type_name()
            )));
        }
        match record.get("task_name") {
            Some(name @ (PyValue::List(_) | PyValue::Dict(_))) if name.truthy() => {
                return Err(crash(format!("unhashable type: '{}'", name.type_name())));
            }
            Some(PyValue::Str(name)) if !name.is_empty() && source.has_task(name) => {
                verifiers.insert(name.clone());
            }
            _ => {}
        }
    }
    Ok(verifiers)
}

/// One line of ENACT's second pass: `Ok(Ok(record))` evaluated, `Ok(Err(skip))` skipped.
fn evaluate_record(
    line: usize,
    serial: usize,
    record: &PyValue,
    verifiers: &HashSet<String>,
    stored: &HashMap<PyHashKey, usize>,
    source: &dyn EnactSignatureSource,
) -> Result<Result<EvaluatedRecord, SkippedLine>, EnactRunError> {
    let get_or =
        |key: &str, default: &str| record.get(key).cloned().unwrap_or_else(|| text(default));
    let get = |key: &str| record.get(key).cloned().unwrap_or(PyValue::None);
    let skip =
        |id: PyValue, reason: SkipReason, task_name: PyValue, task_type: PyValue| SkippedLine {
            line,
            id,
            reason,
            task_name,
            task_type,
            raw_answer: None,
        };
    // An exception outside the verifier's try: ENACT re-reads the line for the entry.
    let evaluation_error = |message: String| {
        skip(
            get_or("id", "unknown"),
            SkipReason::EvaluationError(message),
            get_or("task_name", "unknown"),
            get_or("type", "unknown"),
        )
    };

    let id = get("id");
    if !id.truthy() {
        return Ok(Err(skip(
            text("unknown"),
            SkipReason::MissingIdField,
            get_or("task_name", "unknown"),
            get_or("type", "unknown"),
        )));
    }
    let key = match PyHashKey::of(&id, serial) {
        Ok(key) => key,
        Err(type_name) => {
            return Ok(Err(evaluation_error(format!(
                "unhashable type: '{type_name}'"
            ))));
        }
    };
    if stored.contains_key(&key) {
        return Ok(Err(skip(
            id,
            SkipReason::AlreadyEvaluated,
            get_or("task_name", "unknown"),
            get_or("type", "unknown"),
        )));
    }
    let task_name = get("task_name");
    let task_type = get("type");
    let key_frames = get_or_value(record, "key_frame_ids", PyValue::List(Vec::new()));
    let ground_truth = get_or_value(record, "gt_answer", PyValue::List(Vec::new()));
    let raw_answer = get_or_value(record, "answer", text(""));

    let known_task = match &task_name {
        PyValue::Str(name) => verifiers.contains(name),
        _ => false,
    };
    if !task_name.truthy() || !known_task {
        let shown = if task_name.truthy() {
            task_name
        } else {
            text("missing")
        };
        return Ok(Err(skip(
            id,
            SkipReason::InvalidOrMissingTaskName,
            shown,
            task_type,
        )));
    }
    if !ground_truth.truthy() || !key_frames.truthy() {
        return Ok(Err(skip(
            id,
            SkipReason::MissingGtAnswerOrKeyFrames,
            task_name,
            task_type,
        )));
    }
    let gt = match GroundTruthView::of(&ground_truth) {
        Ok(gt) => gt,
        Err(message) => return Ok(Err(evaluation_error(message))),
    };
    let Some(model_answer) = parse_answer_enact(&raw_answer, gt.len()) else {
        let mut skipped = skip(id, SkipReason::FailedToParseAnswer, task_name, task_type);
        skipped.raw_answer = Some(raw_answer);
        return Ok(Err(skipped));
    };
    let direction = match &task_type {
        PyValue::Str(t) => enact_verifier_direction(t),
        other if other.truthy() => {
            return Ok(Err(evaluation_error(format!(
                "'{}' object has no attribute 'lower'",
                other.type_name()
            ))));
        }
        _ => enact_verifier_direction(""),
    };
    let (shape, frames) = KeyFrameShape::of(&key_frames);
    let task = task_name.as_str().unwrap_or_default();
    let signatures = match shape {
        KeyFrameShape::Sequence(n) => {
            // A ground truth longer than L-1 makes ENACT chain visible sets off the
            // chronological path (forward only).
            let coverage = if direction == Direction::Forward && gt.len() + 1 > n {
                VisibleCoverage::AllPairs
            } else {
                VisibleCoverage::Chronological
            };
            source.item_signatures(task, &frames, coverage)
        }
        KeyFrameShape::Mapping(_) | KeyFrameShape::Unsized(_) => {
            Cow::Owned(ItemSignatures::empty())
        }
    };
    let verdict =
        match verify_enact_record(direction, shape, &gt, &model_answer, Some(&*signatures)) {
            Ok(verdict) => verdict,
            Err(VerifyError::Evaluation { message }) => return Ok(Err(evaluation_error(message))),
            Err(other) => {
                return Err(EnactRunError::Signatures {
                    line,
                    source: other,
                });
            }
        };
    Ok(Ok(EvaluatedRecord {
        line,
        id,
        task_name,
        task_type,
        ground_truth,
        model_answer,
        raw_answer,
        verdict,
    }))
}

fn get_or_value(record: &PyValue, key: &str, default: PyValue) -> PyValue {
    record.get(key).cloned().unwrap_or(default)
}

/// ENACT quirk: `report_overall_score` calls `type.lower()` on every stored record, so a
/// record without a string `type` (missing, null, or falsy like `0`) that was evaluated makes
/// ENACT crash after the loop, with no output for the file.
fn check_report_types(evaluated: &[EvaluatedRecord]) -> Result<(), EnactRunError> {
    match evaluated.iter().find(|r| r.task_type.as_str().is_none()) {
        None => Ok(()),
        Some(record) => Err(EnactRunError::ReportCrash {
            line: record.line,
            id: record.id.to_json(false),
            found: match &record.task_type {
                PyValue::None => "missing or null".to_owned(),
                other => other.to_json(false),
            },
            python_error: format!(
                "AttributeError: '{}' object has no attribute 'lower'",
                record.task_type.type_name()
            ),
        }),
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;
    use crate::verifier::verify::PairwiseAccuracy;

    /// One task, "kitchen", with frames 10, 20, 30 (10→20 opens, 20→30 grasps); every other
    /// pair shows an unrelated change; frame 99 is unknown.
    struct Kitchen;

    impl EnactSignatureSource for Kitchen {
        fn has_task(&self, task_name: &str) -> bool {
            task_name == "kitchen"
        }

        fn item_signatures(
            &self,
            _task: &str,
            key_frame_ids: &[String],
            coverage: VisibleCoverage,
        ) -> Cow<'_, ItemSignatures> {
            Cow::Owned(ItemSignatures::build(
                key_frame_ids,
                coverage,
                |from, to, view| {
                    let known = ["10", "20", "30"];
                    if !known.contains(&from) || !known.contains(&to) {
                        return Err(format!("'Frame ID {from} not found in scene graph data'"));
                    }
                    let set: &[&str] = match (from, to, view) {
                        (f, t, _) if f == t => &[],
                        ("10", "20", _) => &["open"],
                        ("20", "30", _) => &["grasp"],
                        _ => &["far"],
                    };
                    Ok(set.iter().map(|s| s.to_string()).collect::<BTreeSet<_>>())
                },
            ))
        }
    }

    fn line(id: &str, task_type: &str, gt: &str, answer: &str) -> String {
        format!(
            r#"{{"id": "{id}", "type": "{task_type}", "task_name": "kitchen", "key_frame_ids": ["10", "20", "30"], "gt_answer": {gt}, "answer": {answer}}}"#
        )
    }

    fn run(lines: &[String]) -> Result<EnactEvaluation, EnactRunError> {
        score_enact_predictions(
            lines.iter().enumerate().map(|(i, l)| (i + 1, l.as_str())),
            "toy",
            &Kitchen,
        )
    }

    #[test]
    fn skips_follow_enacts_order_and_reasons() {
        let lines = vec![
            line("a", "forward_world_modeling_3_steps", "[2, 1]", r#""[2, 1]""#),
            "{not json".to_owned(),
            r#"{"type": "x", "task_name": "kitchen"}"#.to_owned(),
            line("a", "forward_world_modeling_3_steps", "[2, 1]", r#""[1, 2]""#),
            r#"{"id": "b", "task_name": "garage", "type": "t", "gt_answer": [1, 2], "key_frame_ids": ["1"], "answer": "[1, 2]"}"#.to_owned(),
            r#"{"id": "c", "task_name": "kitchen", "type": "t", "gt_answer": [], "key_frame_ids": ["1"], "answer": "[1, 2]"}"#.to_owned(),
            line("d", "inverse_world_modeling_3_steps", "[1, 2]", r#""no digits""#),
            line("d", "inverse_world_modeling_3_steps", "[1, 2]", r#""[1, 2]""#),
            line("e", "inverse_world_modeling_3_steps", "[1, 2]", r#"["1", "2"]"#),
            line("f", "forward_world_modeling_3_steps", "[1, 1]", r#""[1, 2]""#),
        ];
        let evaluation = run(&lines).expect("runs");
        let reasons: Vec<(usize, String)> = evaluation
            .skipped
            .iter()
            .map(|s| (s.line, s.reason.to_string()))
            .collect();
        assert_eq!(
            reasons,
            vec![
                (2, "invalid_json_format".to_owned()),
                (3, "missing_id_field".to_owned()),
                (4, "already_evaluated".to_owned()),
                (5, "invalid_or_missing_task_name".to_owned()),
                (6, "missing_gt_answer_or_key_frames".to_owned()),
                (7, "failed_to_parse_answer".to_owned()),
                (9, "evaluation_error: unsupported operand type(s) for -: 'str' and 'int'".to_owned()),
                (
                    10,
                    "evaluation_error: Actual shuffled sequence is not fully reconstructed. Missing frame at index 2"
                        .to_owned()
                ),
            ]
        );
        // The unparseable first "d" was not stored, so the second "d" is evaluated.
        let ids: Vec<String> = evaluation.evaluated.iter().map(|r| r.id.py_str()).collect();
        assert_eq!(ids, vec!["a", "d"]);
        assert_eq!(
            evaluation.skipped[5]
                .raw_answer
                .as_ref()
                .map(|r| r.to_json(false))
                .as_deref(),
            Some("\"no digits\"")
        );
        let report = evaluation.report.overall.as_ref().expect("overall");
        assert_eq!(report.totals.count, 2);
    }

    #[test]
    fn detailed_lines_keep_python_types() {
        let lines = vec![
            line(
                "a",
                "forward_world_modeling_3_steps",
                "[2, 1]",
                "[2.0, 1.0]",
            ),
            line(
                "b",
                "forward_world_modeling_3_steps",
                "[2, 1]",
                r#""[1, 2]""#,
            ),
            line(
                "c",
                "forward_world_modeling_3_steps",
                "[2, 1]",
                r#""[2, 9]""#,
            ),
        ];
        let evaluation = run(&lines).expect("runs");
        let detailed = evaluation.detailed_eval_jsonl();
        let rows: Vec<&str> = detailed.lines().collect();
        assert_eq!(
            rows[0],
            r#"{"id": "a", "task_name": "kitchen", "type": "forward_world_modeling_3_steps", "eval_metrics": {"exact_match": true, "semantic_match": false, "task_accuracy": true, "pairwise_accuracy": 1}, "ground_truth": [2, 1], "model_answer": [2.0, 1.0], "raw_answer": [2.0, 1.0]}"#
        );
        // gt [2,1]: S = [10, 30, 20]. Answer [1, 2] chains 10→30→20: both far.
        assert!(
            rows[1].contains(r#""pairwise_accuracy": 0.0}"#),
            "{}",
            rows[1]
        );
        // '[2, 9]' is re-based to [1, 8]; 8 is out of range: the int 0.
        assert!(
            rows[2].contains(r#""pairwise_accuracy": 0}"#),
            "{}",
            rows[2]
        );
        assert!(
            rows[2].contains(r#""model_answer": [1, 8], "raw_answer": "[2, 9]""#),
            "{}",
            rows[2]
        );
        assert_eq!(
            evaluation.evaluated[1].verdict.pairwise_accuracy,
            PairwiseAccuracy::Float(0.0)
        );
    }

    /// A forward ground truth longer than L − 1 chains visible sets off the chronological
    /// path: here kf2 → kf2, whose (empty) set the table must hold.
    #[test]
    fn a_ground_truth_longer_than_the_key_frames_chains_off_the_path() {
        let lines = vec![line(
            "long",
            "forward_world_modeling_3_steps",
            "[2, 1, 1]",
            r#""[1, 2, 2]""#,
        )];
        let evaluation = run(&lines).expect("runs");
        let verdict = &evaluation.evaluated[0].verdict;
        assert!(!verdict.task_accuracy);
        // Of C = (open, grasp, ∅) only the empty set is within the predicted chain's changes.
        assert_eq!(
            verdict.pairwise_accuracy,
            PairwiseAccuracy::Float(1.0 / 3.0)
        );
    }

    /// The dataset's stored tables hold visible sets along the chronological path only, which is
    /// all a record whose ground truth has L − 1 labels needs.
    #[test]
    fn a_ground_truth_of_l_minus_1_labels_is_scored_from_chronological_tables() {
        // Like a stored dataset: chronological tables only, any other coverage is an error.
        struct ChronologicalOnly;
        impl EnactSignatureSource for ChronologicalOnly {
            fn has_task(&self, task_name: &str) -> bool {
                Kitchen.has_task(task_name)
            }
            fn item_signatures(
                &self,
                task: &str,
                key_frame_ids: &[String],
                coverage: VisibleCoverage,
            ) -> Cow<'_, ItemSignatures> {
                match coverage {
                    VisibleCoverage::Chronological => Cow::Owned(
                        Kitchen
                            .item_signatures(task, key_frame_ids, coverage)
                            .into_owned(),
                    ),
                    VisibleCoverage::AllPairs => {
                        Cow::Owned(ItemSignatures::build(key_frame_ids, coverage, |_, _, _| {
                            Err("not stored".to_owned())
                        }))
                    }
                }
            }
        }
        let stored = ChronologicalOnly;
        let lines = [line(
            "p",
            "forward_world_modeling_3_steps",
            "[1, 2]",
            r#""[1, 1]""#,
        )];
        let evaluation = score_enact_predictions(
            lines.iter().enumerate().map(|(i, l)| (i + 1, l.as_str())),
            "toy",
            &stored,
        )
        .expect("runs");
        // [1, 1] chains 10→20 (open ⊆ open) then 20→20 (grasp ⊄ ∅).
        assert_eq!(
            evaluation.evaluated[0].verdict.pairwise_accuracy,
            PairwiseAccuracy::Float(0.5)
        );
    }

    #[test]
    fn unknown_frames_and_neither_direction() {
        let lines = vec![
            r#"{"id": "u", "type": "forward_world_modeling_3_steps", "task_name": "kitchen", "key_frame_ids": ["10", "20", "99"], "gt_answer": [1, 2], "answer": "[1, 2]"}"#.to_owned(),
            r#"{"id": "v", "type": "ordering_3_steps", "task_name": "kitchen", "key_frame_ids": [10, 20, 30], "gt_answer": [1, 2], "answer": "[1, 2]"}"#.to_owned(),
        ];
        let evaluation = run(&lines).expect("runs");
        let u = &evaluation.evaluated[0].verdict;
        assert!(u.exact_match && !u.semantic_match && u.task_accuracy);
        let v = &evaluation.evaluated[1].verdict;
        assert!(
            v.semantic_match,
            "integer key frames are looked up by str()"
        );
        assert!(
            evaluation
                .report
                .forward_world_modeling
                .as_ref()
                .is_some_and(|g| g.totals.count == 1)
        );
        assert!(
            evaluation
                .report
                .overall
                .as_ref()
                .is_some_and(|g| g.totals.count == 2)
        );
    }

    /// A `type` that is truthy but not a string (a number) fails ENACT's `.lower()` on that line
    /// alone: its evaluator skips the line as an evaluation error with Python's message.
    #[test]
    fn a_truthy_type_that_is_not_a_string_skips_its_line_with_python_s_error() {
        let number_type = vec![
            line("a", "forward_world_modeling_3_steps", "[2, 1]", r#""[2, 1]""#),
            r#"{"id": "b", "type": 5, "task_name": "kitchen", "key_frame_ids": ["10", "20", "30"], "gt_answer": [1, 2], "answer": "[1, 2]"}"#.to_owned(),
        ];
        let evaluation = run(&number_type).expect("runs");
        assert_eq!(evaluation.evaluated.len(), 1);
        assert_eq!(evaluation.skipped.len(), 1);
        let skipped = &evaluation.skipped[0];
        assert_eq!(skipped.line, 2);
        assert_eq!(
            skipped.reason.to_string(),
            "evaluation_error: 'int' object has no attribute 'lower'"
        );
    }

    #[test]
    fn crashes_are_errors_naming_the_line() {
        let missing_type = vec![
            line("a", "forward_world_modeling_3_steps", "[2, 1]", r#""[2, 1]""#),
            r#"{"id": "b", "task_name": "kitchen", "key_frame_ids": ["10", "20", "30"], "gt_answer": [1, 2], "answer": "[1, 2]"}"#.to_owned(),
        ];
        match run(&missing_type) {
            Err(EnactRunError::ReportCrash {
                line, python_error, ..
            }) => {
                assert_eq!(line, 2);
                assert_eq!(
                    python_error,
                    "AttributeError: 'NoneType' object has no attribute 'lower'"
                );
            }
            other => panic!("expected a report crash, got {other:?}"),
        }
        let not_an_object = vec![line("a", "t", "[1, 2]", "\"[1, 2]\""), "[1, 2]".to_owned()];
        assert!(matches!(
            run(&not_an_object),
            Err(EnactRunError::FirstPassCrash { line: 2, .. })
        ));
        let list_task = vec![r#"{"id": "a", "task_name": ["kitchen"]}"#.to_owned()];
        assert!(matches!(
            run(&list_task),
            Err(EnactRunError::FirstPassCrash { line: 1, .. })
        ));
        // An empty list is falsy: ENACT never hashes it.
        let empty_list_task = vec![r#"{"id": "a", "task_name": []}"#.to_owned()];
        assert!(run(&empty_list_task).is_ok_and(|e| e.evaluated.is_empty()));
    }

    #[test]
    fn no_known_task_aborts_silently() {
        let lines = vec![
            r#"{"id": "a", "task_name": "garage", "answer": "x"}"#.to_owned(),
            "bad".to_owned(),
        ];
        let evaluation = run(&lines).expect("runs");
        assert!(evaluation.evaluated.is_empty() && evaluation.skipped.is_empty());
        assert_eq!(
            evaluation.meta_performance_json(),
            "{\n  \"model_name\": \"toy\",\n  \"overall_performance\": {}\n}"
        );
        assert_eq!(evaluation.detailed_eval_jsonl(), "");
    }

    #[test]
    fn numeric_ids_share_python_dict_identity() {
        let lines = vec![
            r#"{"id": 1, "type": "forward", "task_name": "kitchen", "key_frame_ids": ["10", "20", "30"], "gt_answer": [1, 2], "answer": "[1, 2]"}"#.to_owned(),
            r#"{"id": 1.0, "type": "forward", "task_name": "kitchen", "key_frame_ids": ["10", "20", "30"], "gt_answer": [1, 2], "answer": "[1, 2]"}"#.to_owned(),
            r#"{"id": [1], "type": "forward", "task_name": "kitchen", "key_frame_ids": ["10", "20", "30"], "gt_answer": [1, 2], "answer": "[1, 2]"}"#.to_owned(),
        ];
        let evaluation = run(&lines).expect("runs");
        assert_eq!(evaluation.evaluated.len(), 1);
        assert_eq!(evaluation.skipped[0].reason, SkipReason::AlreadyEvaluated);
        assert_eq!(
            evaluation.skipped[1].reason.to_string(),
            "evaluation_error: unhashable type: 'list'"
        );
    }

    #[test]
    fn model_names_and_lines() {
        assert_eq!(
            enact_model_name("preds/enact_ordering_gpt-4o.jsonl"),
            "gpt-4o"
        );
        assert_eq!(enact_model_name("enact_ordering_.jsonl"), "");
        assert_eq!(enact_model_name("gpt4o.jsonl"), "unknown");
        assert_eq!(enact_model_name("enact_ordering_x.json"), "unknown");
        let lines: Vec<(usize, &str)> = python_text_lines("a\r\nb\rc\n\nd").collect();
        assert_eq!(lines, vec![(1, "a"), (2, "b"), (3, "c"), (4, ""), (5, "d")]);
        assert_eq!(python_text_lines("a\n").count(), 1);
    }
}
