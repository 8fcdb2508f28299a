//! `ScoringPolicy::Strict`, the leaderboard default: every item of the dataset is scored,
//! answers are read strictly, and nothing in a prediction line but `id` and `answer` counts.
//!
//! Unlike ENACT's own loop, a missing or unreadable answer is wrong (TA 0 / PA 0) rather than
//! dropped from the denominator, and a submission cannot bring its own ground truth, type or
//! key frames: those come from the dataset.

use schemars::JsonSchema;
use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::verifier::answer::{
    Direction, ParsedAnswer, Permutation, StepLength, StrictParseFailure, parse_answer_strict,
};
use crate::verifier::pyjson::{PyValue, parse_python_json};
use crate::verifier::report::{PerformanceReport, ScoredEntry};
use crate::verifier::signatures::ItemSignatures;
use crate::verifier::unicode::py_strip;
use crate::verifier::verify::{PairwiseAccuracy, Verdict, VerifyError, verify};

/// How a prediction file is scored.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum ScoringPolicy {
    /// ENACT's own evaluator, quirks included (see `enact_policy`).
    Enact,
    /// Every dataset item counts; strict answers; only `id` and `answer` are read.
    #[default]
    Strict,
}

impl ScoringPolicy {
    pub fn as_str(self) -> &'static str {
        match self {
            ScoringPolicy::Enact => "enact",
            ScoringPolicy::Strict => "strict",
        }
    }

    pub fn parse(text: &str) -> Option<ScoringPolicy> {
        match text {
            "enact" => Some(ScoringPolicy::Enact),
            "strict" => Some(ScoringPolicy::Strict),
            _ => None,
        }
    }
}

/// One dataset item as the strict policy needs it.
#[derive(Debug, Clone, Copy)]
pub struct StrictItem<'a> {
    pub id: &'a str,
    pub direction: Direction,
    pub step_length: StepLength,
    pub ground_truth: &'a Permutation,
    /// `None` for an item without scene graphs: exact match only.
    pub signatures: Option<&'a ItemSignatures>,
}

/// What happened to one dataset item.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
pub enum StrictOutcome {
    Scored {
        answer: Permutation,
        verdict: Verdict,
    },
    /// An answer was given but is not a permutation of 1..L-1: scored TA 0 / PA 0.
    Unparseable { reason: StrictParseFailure },
    /// No prediction line for this item: scored TA 0 / PA 0.
    Missing,
}

/// The result for one dataset item, in dataset order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StrictItemResult {
    pub id: String,
    pub direction: Direction,
    pub step_length: StepLength,
    /// The prediction line used, if any.
    pub line: Option<usize>,
    pub outcome: StrictOutcome,
}

impl StrictItemResult {
    pub fn task_accuracy(&self) -> bool {
        matches!(&self.outcome, StrictOutcome::Scored { verdict, .. } if verdict.task_accuracy)
    }

    /// `None` only for an exact-only item whose answer is not exact.
    pub fn pairwise_accuracy(&self) -> Option<f64> {
        match &self.outcome {
            StrictOutcome::Scored { verdict, .. } => verdict.pairwise_accuracy.value(),
            StrictOutcome::Unparseable { .. } | StrictOutcome::Missing => Some(0.0),
        }
    }
}

/// A problem with one line of a submission; such lines do not score anything.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, thiserror::Error)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SubmissionProblem {
    #[error("line {line}: not valid JSON: {message}")]
    InvalidJson { line: usize, message: String },
    #[error("line {line}: not a JSON object")]
    NotAnObject { line: usize },
    #[error("line {line}: `id` is missing or not a non-empty string")]
    MissingId { line: usize },
    #[error("line {line}: item {id} is not in the dataset")]
    UnknownId { line: usize, id: String },
    #[error("line {line}: item {id} already answered on line {first_line}; this line is ignored")]
    DuplicateId {
        line: usize,
        id: String,
        first_line: usize,
    },
}

/// How much of the dataset the submission answered.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Coverage {
    pub dataset_items: usize,
    /// Items with a prediction line (readable or not).
    pub answered: usize,
    pub missing: usize,
    pub unparseable: usize,
    /// answered / dataset_items.
    pub coverage: f64,
    /// unparseable / answered (0 when nothing was answered).
    pub parse_failure_rate: f64,
    /// Items scored exact-only because they have no scene graphs.
    pub exact_only: usize,
}

/// The strict scoring of one submission.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StrictScoring {
    pub items: Vec<StrictItemResult>,
    pub report: PerformanceReport,
    pub coverage: Coverage,
    pub problems: Vec<SubmissionProblem>,
}

/// A dataset the strict policy cannot score with.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum StrictScoringError {
    #[error("dataset item {id} appears twice")]
    DuplicateDatasetItem { id: String },
    #[error(
        "dataset item {id}: ground truth has {labels} labels, step length {step_length} needs {expected}"
    )]
    GroundTruthLength {
        id: String,
        labels: usize,
        step_length: StepLength,
        expected: usize,
    },
    #[error("dataset item {id}: {source}")]
    Signatures { id: String, source: VerifyError },
}

/// Scores `lines` (line number, text) against every item of `dataset`.
pub fn score_strict_predictions<I, S>(
    dataset: &[StrictItem<'_>],
    lines: I,
) -> Result<StrictScoring, StrictScoringError>
where
    I: IntoIterator<Item = (usize, S)>,
    S: AsRef<str>,
{
    let mut index: HashMap<&str, usize> = HashMap::with_capacity(dataset.len());
    for (position, item) in dataset.iter().enumerate() {
        if index.insert(item.id, position).is_some() {
            return Err(StrictScoringError::DuplicateDatasetItem {
                id: item.id.to_owned(),
            });
        }
        if item.ground_truth.len() != item.step_length.actions() {
            return Err(StrictScoringError::GroundTruthLength {
                id: item.id.to_owned(),
                labels: item.ground_truth.len(),
                step_length: item.step_length,
                expected: item.step_length.actions(),
            });
        }
        if let Some(table) = item.signatures
            && table.key_frame_count() != item.step_length.states()
        {
            return Err(StrictScoringError::Signatures {
                id: item.id.to_owned(),
                source: VerifyError::FrameCountMismatch {
                    table: table.key_frame_count(),
                    item: item.step_length.states(),
                },
            });
        }
    }

    // First line per item wins; later ones are reported.
    let mut answers: Vec<Option<(usize, Option<PyValue>)>> = vec![None; dataset.len()];
    let mut problems = Vec::new();
    for (line, raw) in lines {
        let raw = py_strip(raw.as_ref());
        if raw.is_empty() {
            continue;
        }
        let record = match parse_python_json(raw) {
            Ok(record @ PyValue::Dict(_)) => record,
            Ok(_) => {
                problems.push(SubmissionProblem::NotAnObject { line });
                continue;
            }
            Err(error) => {
                problems.push(SubmissionProblem::InvalidJson {
                    line,
                    message: error.to_string(),
                });
                continue;
            }
        };
        let Some(id) = record
            .get("id")
            .and_then(PyValue::as_str)
            .filter(|s| !s.is_empty())
        else {
            problems.push(SubmissionProblem::MissingId { line });
            continue;
        };
        let Some(&position) = index.get(id) else {
            problems.push(SubmissionProblem::UnknownId {
                line,
                id: id.to_owned(),
            });
            continue;
        };
        match &answers[position] {
            Some((first_line, _)) => problems.push(SubmissionProblem::DuplicateId {
                line,
                id: id.to_owned(),
                first_line: *first_line,
            }),
            None => answers[position] = Some((line, record.get("answer").cloned())),
        }
    }

    let mut items = Vec::with_capacity(dataset.len());
    for (item, answer) in dataset.iter().zip(answers) {
        let (line, outcome) = match answer {
            None => (None, StrictOutcome::Missing),
            Some((line, value)) => {
                let outcome = match parse_answer_strict(value.as_ref(), item.step_length.actions())
                {
                    Err(reason) => StrictOutcome::Unparseable { reason },
                    Ok(answer) => {
                        let verdict = verify(
                            item.direction,
                            item.ground_truth,
                            &ParsedAnswer::from(&answer),
                            item.signatures,
                        )
                        .map_err(|source| {
                            StrictScoringError::Signatures {
                                id: item.id.to_owned(),
                                source,
                            }
                        })?;
                        StrictOutcome::Scored { answer, verdict }
                    }
                };
                (Some(line), outcome)
            }
        };
        items.push(StrictItemResult {
            id: item.id.to_owned(),
            direction: item.direction,
            step_length: item.step_length,
            line,
            outcome,
        });
    }

    let entries: Vec<ScoredEntry> = items
        .iter()
        .map(|r| ScoredEntry {
            group: Some(r.direction),
            states: r.step_length.states(),
            task_accuracy: r.task_accuracy(),
            pairwise_accuracy: r.pairwise_accuracy(),
        })
        .collect();
    let answered = items.iter().filter(|r| r.line.is_some()).count();
    let unparseable = items
        .iter()
        .filter(|r| matches!(r.outcome, StrictOutcome::Unparseable { .. }))
        .count();
    let exact_only = items
        .iter()
        .filter(|r| matches!(&r.outcome, StrictOutcome::Scored { verdict, .. } if !verdict.semantic_available))
        .count();
    let coverage = Coverage {
        dataset_items: dataset.len(),
        answered,
        missing: dataset.len() - answered,
        unparseable,
        coverage: if dataset.is_empty() {
            0.0
        } else {
            answered as f64 / dataset.len() as f64
        },
        parse_failure_rate: if answered == 0 {
            0.0
        } else {
            unparseable as f64 / answered as f64
        },
        exact_only,
    };
    Ok(StrictScoring {
        report: PerformanceReport::from_entries(&entries),
        items,
        coverage,
        problems,
    })
}

impl StrictOutcome {
    /// The pairwise accuracy with ENACT's int/float distinction, for display.
    pub fn pairwise(&self) -> PairwiseAccuracy {
        match self {
            StrictOutcome::Scored { verdict, .. } => verdict.pairwise_accuracy,
            StrictOutcome::Unparseable { .. } | StrictOutcome::Missing => {
                PairwiseAccuracy::Float(0.0)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;
    use crate::verifier::signatures::{View, VisibleCoverage};

    fn table() -> ItemSignatures {
        let frames: Vec<String> = ["10", "20", "30"].iter().map(|s| s.to_string()).collect();
        ItemSignatures::build(
            &frames,
            VisibleCoverage::Chronological,
            |from, to, _view: View| {
                let set: &[&str] = match (from, to) {
                    (f, t) if f == t => &[],
                    ("10", "20") => &["open"],
                    ("20", "30") => &["grasp"],
                    _ => &["far"],
                };
                Ok(set.iter().map(|s| s.to_string()).collect::<BTreeSet<_>>())
            },
        )
    }

    fn gt(labels: &[u8]) -> Permutation {
        Permutation::new(labels.to_vec()).expect("test permutation")
    }

    #[test]
    fn every_item_counts_and_problems_are_listed() {
        let (g1, g2) = (gt(&[2, 1]), gt(&[1, 2]));
        let t = table();
        let l3 = StepLength::new(3).expect("3");
        let dataset = [
            StrictItem {
                id: "f1",
                direction: Direction::Forward,
                step_length: l3,
                ground_truth: &g1,
                signatures: Some(&t),
            },
            StrictItem {
                id: "i1",
                direction: Direction::Inverse,
                step_length: l3,
                ground_truth: &g2,
                signatures: Some(&t),
            },
            StrictItem {
                id: "f2",
                direction: Direction::Forward,
                step_length: l3,
                ground_truth: &g1,
                signatures: None,
            },
            StrictItem {
                id: "i2",
                direction: Direction::Inverse,
                step_length: l3,
                ground_truth: &g2,
                signatures: None,
            },
            StrictItem {
                id: "f3",
                direction: Direction::Forward,
                step_length: l3,
                ground_truth: &g1,
                signatures: Some(&t),
            },
        ];
        let lines = [
            // A forged ground truth and type must not matter.
            r#"{"id": "f1", "answer": "[2, 1]", "gt_answer": [1, 2], "type": "inverse"}"#,
            r#"{"id": "i1", "answer": "garbage"}"#,
            r#"{"id": "f1", "answer": "[1, 2]"}"#,
            r#"{"id": "nope", "answer": "[1, 2]"}"#,
            "not json",
            r#"{"answer": "[1, 2]"}"#,
            r#"{"id": "f2", "answer": "[0, 1]"}"#,
            r#"{"id": "i2", "answer": "The order is [2, 1]."}"#,
            "",
        ];
        let scoring =
            score_strict_predictions(&dataset, lines.iter().enumerate().map(|(i, l)| (i + 1, *l)))
                .expect("scores");
        let outcome = |i: usize| &scoring.items[i].outcome;
        assert!(
            matches!(outcome(0), StrictOutcome::Scored { verdict, .. } if verdict.task_accuracy)
        );
        assert_eq!(
            outcome(1),
            &StrictOutcome::Unparseable {
                reason: StrictParseFailure::NoList
            }
        );
        assert_eq!(
            outcome(2),
            &StrictOutcome::Unparseable {
                reason: StrictParseFailure::OutOfRange {
                    label: "0".to_owned(),
                    max: 2
                }
            }
        );
        assert!(
            matches!(outcome(3), StrictOutcome::Scored { verdict, .. } if !verdict.task_accuracy && !verdict.semantic_available)
        );
        assert_eq!(outcome(4), &StrictOutcome::Missing);
        assert_eq!(
            scoring.problems,
            vec![
                SubmissionProblem::DuplicateId {
                    line: 3,
                    id: "f1".to_owned(),
                    first_line: 1
                },
                SubmissionProblem::UnknownId {
                    line: 4,
                    id: "nope".to_owned()
                },
                SubmissionProblem::InvalidJson {
                    line: 5,
                    message: "invalid JSON: Expecting value (char 0)".to_owned()
                },
                SubmissionProblem::MissingId { line: 6 },
            ]
        );
        let c = scoring.coverage;
        assert_eq!(
            (
                c.dataset_items,
                c.answered,
                c.missing,
                c.unparseable,
                c.exact_only
            ),
            (5, 4, 1, 2, 1)
        );
        assert_eq!(c.coverage, 0.8);
        assert_eq!(c.parse_failure_rate, 0.5);
        let overall = scoring.report.overall.as_ref().expect("overall");
        assert_eq!(overall.totals.count, 5);
        assert_eq!(overall.totals.task_accuracy, 0.2);
        // PA: f1 1, i1 0, f2 0, i2 unavailable, f3 0 → mean over four items.
        assert_eq!(overall.totals.pairwise_accuracy, Some(0.25));
        assert_eq!(overall.totals.pairwise_count, 4);
        let json = serde_json::to_value(&scoring).expect("serialises");
        assert_eq!(json["items"][2]["outcome"]["outcome"], "unparseable");
        assert_eq!(
            json["items"][2]["outcome"]["reason"]["kind"],
            "out_of_range"
        );
        assert_eq!(json["problems"][0]["kind"], "duplicate_id");
    }

    #[test]
    fn wrong_length_and_repeats_are_reasons() {
        let g = gt(&[2, 1, 3]);
        let l4 = StepLength::new(4).expect("4");
        let dataset = [
            StrictItem {
                id: "a",
                direction: Direction::Forward,
                step_length: l4,
                ground_truth: &g,
                signatures: None,
            },
            StrictItem {
                id: "b",
                direction: Direction::Forward,
                step_length: l4,
                ground_truth: &g,
                signatures: None,
            },
        ];
        let lines = [
            (1, r#"{"id": "a", "answer": "[2, 1]"}"#),
            (2, r#"{"id": "b", "answer": "[2, 2, 1]"}"#),
        ];
        let scoring = score_strict_predictions(&dataset, lines).expect("scores");
        let reasons: Vec<String> = scoring
            .items
            .iter()
            .map(|r| match &r.outcome {
                StrictOutcome::Unparseable { reason } => reason.to_string(),
                other => format!("{other:?}"),
            })
            .collect();
        assert_eq!(
            reasons,
            vec!["wrong length 2, expected 3", "label 2 repeated"]
        );
    }

    #[test]
    fn inconsistent_datasets_are_refused() {
        let g = gt(&[2, 1]);
        let l4 = StepLength::new(4).expect("4");
        let dataset = [StrictItem {
            id: "a",
            direction: Direction::Forward,
            step_length: l4,
            ground_truth: &g,
            signatures: None,
        }];
        let lines: [(usize, &str); 0] = [];
        assert!(matches!(
            score_strict_predictions(&dataset, lines),
            Err(StrictScoringError::GroundTruthLength { .. })
        ));
    }

    #[test]
    fn policies_are_read_by_the_names_they_are_written_with() {
        for policy in [ScoringPolicy::Enact, ScoringPolicy::Strict] {
            assert_eq!(ScoringPolicy::parse(policy.as_str()), Some(policy));
        }
        assert_eq!(ScoringPolicy::parse("Strict"), None);
        assert_eq!(ScoringPolicy::default(), ScoringPolicy::Strict);
    }
}
