//! A leaderboard submission: reading its body, refusing it line by line, and scoring it under
//! the strict policy with bootstrap intervals (pure; the web layer stores the result).
//!
//! Only `id` and `answer` are read from each record; a `gt_answer`, `type` or `key_frame_ids`
//! in the body is ignored, since everything but the answer comes from the dataset.

use schemars::JsonSchema;
use std::collections::HashMap;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::value::RawValue;

use crate::scoring::ScoringTarget;
use crate::verifier::{
    BOOTSTRAP_LEVEL, BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED, ConfidenceInterval, Coverage,
    PerformanceReport, Resampling, ScoringPolicy, StrictItem, StrictOutcome, StrictParseFailure,
    StrictScoring, StrictScoringError, SubmissionProblem, cluster_ids, leaderboard_ci,
    parse_python_json, python_text_lines, score_strict_predictions,
};

/// Why one line (or array element) of a body was refused.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct LineProblem {
    /// 1-based line of a JSONL body, or 1-based element of a JSON array body.
    pub line: usize,
    /// `empty_body`, `invalid_json`, `not_an_object`, `missing_id`, `unknown_id`,
    /// `duplicate_id`, `missing_answer`, `malformed_answer`.
    pub kind: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub item: Option<String>,
    pub message: String,
}

impl LineProblem {
    fn from_strict(problem: &SubmissionProblem) -> LineProblem {
        let (line, kind, item) = match problem {
            SubmissionProblem::InvalidJson { line, .. } => (*line, "invalid_json", None),
            SubmissionProblem::NotAnObject { line } => (*line, "not_an_object", None),
            SubmissionProblem::MissingId { line } => (*line, "missing_id", None),
            SubmissionProblem::UnknownId { line, id } => (*line, "unknown_id", Some(id.clone())),
            SubmissionProblem::DuplicateId { line, id, .. } => {
                (*line, "duplicate_id", Some(id.clone()))
            }
        };
        LineProblem {
            line,
            kind,
            item,
            message: problem.to_string(),
        }
    }
}

/// The records of a body as (position, JSON text): JSONL lines, or the elements of a JSON
/// array. A body whose first non-blank character is `[` is an array.
pub fn submission_records(text: &str) -> Result<Vec<(usize, String)>, Vec<LineProblem>> {
    let trimmed = text.trim_start();
    if trimmed.starts_with('[') {
        let elements: Vec<Box<RawValue>> = serde_json::from_str(text).map_err(|e| {
            vec![LineProblem {
                line: e.line(),
                kind: "invalid_json",
                item: None,
                message: format!(
                    "line {}, column {}: the body is not a valid JSON array: {e}",
                    e.line(),
                    e.column()
                ),
            }]
        })?;
        return Ok(elements
            .into_iter()
            .enumerate()
            .map(|(i, raw)| (i + 1, raw.get().to_owned()))
            .collect());
    }
    Ok(python_text_lines(text)
        .map(|(line, s)| (line, s.to_owned()))
        .collect())
}

/// Bootstrap intervals on the overall means.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ConfidenceIntervals {
    pub level: f64,
    pub resamples: usize,
    pub seed: u64,
    /// What the bootstrap resampled: activities with their items (the default) or items one
    /// by one. Scores stored before the hub clustered its intervals resampled items.
    #[serde(default = "Resampling::before_clustering")]
    pub resampling: Resampling,
    pub task_accuracy: Option<ConfidenceInterval>,
    pub pairwise_accuracy: Option<ConfidenceInterval>,
    /// The item bootstrap's intervals beside the clustered ones, for readers who ask for
    /// them; absent when `resampling` is already `items`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub by_items: Option<ItemIntervals>,
}

/// Intervals from resampling items one by one.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ItemIntervals {
    pub task_accuracy: Option<ConfidenceInterval>,
    pub pairwise_accuracy: Option<ConfidenceInterval>,
}

/// What a submission's scores are, as stored and served.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SubmissionScores {
    pub policy: ScoringPolicy,
    pub report: PerformanceReport,
    pub coverage: Coverage,
    pub confidence: ConfidenceIntervals,
}

/// Metadata given with a submission.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SubmissionMetadata {
    pub model: String,
    pub description: String,
    pub url: String,
    pub prompt_version: String,
    pub notes: String,
}

impl SubmissionMetadata {
    /// The metadata with its model name trimmed and checked (1 to 200 characters).
    pub fn checked(mut self) -> Result<SubmissionMetadata, String> {
        self.model = self.model.trim().to_owned();
        if self.model.is_empty() {
            return Err("`model` is required (the model's name for the leaderboard)".to_owned());
        }
        if self.model.chars().count() > 200 {
            return Err("`model` is longer than 200 characters".to_owned());
        }
        Ok(self)
    }
}

/// Where a submission stands on its dataset's leaderboard; admins change it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Visibility {
    /// Listed (the state every submission starts in).
    Published,
    /// Kept but not listed, until an admin publishes it again.
    Hidden,
    /// Taken back by its submitter or an admin.
    Withdrawn,
}

impl Visibility {
    pub const ALL: [Visibility; 3] = [
        Visibility::Published,
        Visibility::Hidden,
        Visibility::Withdrawn,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            Visibility::Published => "published",
            Visibility::Hidden => "hidden",
            Visibility::Withdrawn => "withdrawn",
        }
    }

    pub fn parse(text: &str) -> Option<Visibility> {
        Visibility::ALL.into_iter().find(|v| v.as_str() == text)
    }
}

/// Where a leaderboard row's answers came from, so a reader can tell what the hub itself
/// witnessed from what it was handed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Provenance {
    /// A model run of this hub (on the server, or by the CLI on its database): the hub sent
    /// every prompt and kept every reply it scored.
    Run,
    /// Answers uploaded by a submitter (including a CLI run against a remote hub, which the
    /// hub only sees as an upload).
    Submitted,
    /// A number a paper published, copied in; never scored by the hub.
    Reported,
}

impl Provenance {
    pub const ALL: [Provenance; 3] = [Provenance::Run, Provenance::Submitted, Provenance::Reported];

    pub fn as_str(self) -> &'static str {
        match self {
            Provenance::Run => "run",
            Provenance::Submitted => "submitted",
            Provenance::Reported => "reported",
        }
    }

    pub fn parse(text: &str) -> Option<Provenance> {
        Provenance::ALL.into_iter().find(|p| p.as_str() == text)
    }
}

/// What has happened to a submission. Scoring is synchronous, so a stored submission is
/// always scored; the state is kept so that queued scoring can be added without a new column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum SubmissionStatus {
    Scored,
}

impl SubmissionStatus {
    pub fn as_str(self) -> &'static str {
        match self {
            SubmissionStatus::Scored => "scored",
        }
    }

    pub fn parse(text: &str) -> Option<SubmissionStatus> {
        (text == "scored").then_some(SubmissionStatus::Scored)
    }
}

/// What became of one item's answer, as the `submission_items.outcome` column spells it: the
/// kind of a [`StrictOutcome`] without its data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VerdictOutcome {
    Scored,
    Unparseable,
    Missing,
}

impl VerdictOutcome {
    pub const ALL: [VerdictOutcome; 3] = [
        VerdictOutcome::Scored,
        VerdictOutcome::Unparseable,
        VerdictOutcome::Missing,
    ];

    pub fn of(outcome: &StrictOutcome) -> VerdictOutcome {
        match outcome {
            StrictOutcome::Scored { .. } => VerdictOutcome::Scored,
            StrictOutcome::Unparseable { .. } => VerdictOutcome::Unparseable,
            StrictOutcome::Missing => VerdictOutcome::Missing,
        }
    }

    pub fn as_str(self) -> &'static str {
        match self {
            VerdictOutcome::Scored => "scored",
            VerdictOutcome::Unparseable => "unparseable",
            VerdictOutcome::Missing => "missing",
        }
    }

    pub fn parse(text: &str) -> Option<VerdictOutcome> {
        VerdictOutcome::ALL.into_iter().find(|o| o.as_str() == text)
    }
}

/// How one answer fared, as the item page and its API name it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum AnswerVerdict {
    /// The true order.
    Exact,
    /// Another order whose state changes the verifier accepts as the truth's.
    Equivalent,
    /// Read, and not accepted.
    Wrong,
    /// Not a reading of the item's labels.
    Unparseable,
    /// No answer to the item.
    Missing,
}

impl AnswerVerdict {
    pub fn of(outcome: VerdictOutcome, exact_match: bool, task_accuracy: bool) -> AnswerVerdict {
        match outcome {
            VerdictOutcome::Missing => AnswerVerdict::Missing,
            VerdictOutcome::Unparseable => AnswerVerdict::Unparseable,
            VerdictOutcome::Scored if exact_match => AnswerVerdict::Exact,
            VerdictOutcome::Scored if task_accuracy => AnswerVerdict::Equivalent,
            VerdictOutcome::Scored => AnswerVerdict::Wrong,
        }
    }

    pub fn as_str(self) -> &'static str {
        match self {
            AnswerVerdict::Exact => "exact",
            AnswerVerdict::Equivalent => "equivalent",
            AnswerVerdict::Wrong => "wrong",
            AnswerVerdict::Unparseable => "unparseable",
            AnswerVerdict::Missing => "missing",
        }
    }
}

/// One dataset item's verdict, with the answer as submitted.
#[derive(Debug, Clone, PartialEq)]
pub struct ItemVerdict {
    /// Index into the dataset's targets.
    pub target: usize,
    pub line: Option<usize>,
    /// The `answer` value as JSON text, as submitted.
    pub raw_answer: Option<String>,
    pub outcome: StrictOutcome,
    pub task_accuracy: bool,
    pub pairwise_accuracy: Option<f64>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct ScoredSubmission {
    pub scores: SubmissionScores,
    pub items: Vec<ItemVerdict>,
}

#[derive(Debug, thiserror::Error)]
pub enum SubmissionError {
    /// The body is refused; nothing is scored.
    #[error("{} problems in the submission", .0.len())]
    Rejected(Vec<LineProblem>),
    /// The stored dataset cannot be scored (our side).
    #[error(transparent)]
    Dataset(#[from] StrictScoringError),
}

/// Reads and scores a body against every item of a dataset.
pub fn score_submission(
    targets: &[ScoringTarget],
    body: &str,
) -> Result<ScoredSubmission, SubmissionError> {
    let records = submission_records(body).map_err(SubmissionError::Rejected)?;
    if records.iter().all(|(_, record)| record.trim().is_empty()) {
        // Scoring nothing would store a row of zeros: almost surely a client that sent the
        // wrong file, or none.
        return Err(SubmissionError::Rejected(vec![LineProblem {
            line: 1,
            kind: "empty_body",
            item: None,
            message: "line 1: the body holds no record; send one JSON object per line (or a \
                      JSON array of them), each with `id` and `answer`"
                .to_owned(),
        }]));
    }
    let items: Vec<StrictItem<'_>> = targets.iter().map(ScoringTarget::strict_item).collect();
    let scoring = score_strict_predictions(&items, records.iter().map(|(l, s)| (*l, s.as_str())))?;
    let mut problems: Vec<LineProblem> = scoring
        .problems
        .iter()
        .map(LineProblem::from_strict)
        .collect();
    for result in &scoring.items {
        let (Some(line), StrictOutcome::Unparseable { reason }) = (result.line, &result.outcome)
        else {
            continue;
        };
        // A model's reply is text or a list; a missing answer or an object is the client's
        // mistake, refused rather than scored as the model's failure.
        let (kind, what) = match reason {
            StrictParseFailure::Missing => ("missing_answer", "is missing or null"),
            StrictParseFailure::NotText { found: "dict" } => (
                "malformed_answer",
                "is a JSON object; send the model's reply as text or a list of labels",
            ),
            _ => continue,
        };
        problems.push(LineProblem {
            line,
            kind,
            item: Some(result.id.clone()),
            message: format!("line {line}: item {}: `answer` {what}", result.id),
        });
    }
    if !problems.is_empty() {
        problems.sort_by_key(|p| p.line);
        return Err(SubmissionError::Rejected(problems));
    }
    let text_by_line: HashMap<usize, &str> =
        records.iter().map(|(l, s)| (*l, s.as_str())).collect();
    let raw_answers: Vec<Option<String>> = scoring
        .items
        .par_iter()
        .map(|r| {
            r.line
                .and_then(|l| text_by_line.get(&l))
                .and_then(|t| raw_answer(t))
        })
        .collect();
    Ok(assemble(scoring, raw_answers, &activity_clusters(targets)))
}

/// An answer a stored submission gave: its item, the body's line (or array element) it came
/// from, and the `answer` value as submitted (JSON text).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StoredAnswer {
    pub item_id: String,
    pub line: usize,
    pub raw_answer: String,
}

/// Scores a stored submission's answers again against `targets` as they are now, under the
/// current metric: each answer is read and judged as if its line were submitted again, and
/// items it did not answer count as missing, as at submission. With nothing changed (rules,
/// items, signatures) the result equals the stored one, bit for bit.
pub fn rescore_submission(
    targets: &[ScoringTarget],
    answers: &[StoredAnswer],
) -> Result<ScoredSubmission, SubmissionError> {
    let records: Vec<(usize, String)> = answers
        .iter()
        .map(|a| {
            // serde_json writes a string as a valid JSON string; it cannot fail.
            let id = serde_json::Value::String(a.item_id.clone());
            (
                a.line,
                format!("{{\"id\":{id},\"answer\":{}}}", a.raw_answer),
            )
        })
        .collect();
    let items: Vec<StrictItem<'_>> = targets.iter().map(ScoringTarget::strict_item).collect();
    let scoring = score_strict_predictions(&items, records.iter().map(|(l, s)| (*l, s.as_str())))?;
    if !scoring.problems.is_empty() {
        return Err(SubmissionError::Rejected(
            scoring
                .problems
                .iter()
                .map(LineProblem::from_strict)
                .collect(),
        ));
    }
    let by_line: HashMap<usize, &str> = answers
        .iter()
        .map(|a| (a.line, a.raw_answer.as_str()))
        .collect();
    let raw_answers = scoring
        .items
        .iter()
        .map(|r| {
            r.line
                .and_then(|l| by_line.get(&l))
                .map(|a| (*a).to_owned())
        })
        .collect();
    Ok(assemble(scoring, raw_answers, &activity_clusters(targets)))
}

/// Each target's activity (`task_name`) as a cluster number, in the targets' order.
fn activity_clusters(targets: &[ScoringTarget]) -> Vec<u32> {
    cluster_ids(targets.iter().map(|t| t.task_name.as_str()))
}

/// The `answer` value of a record, as compact JSON.
fn raw_answer(record: &str) -> Option<String> {
    #[derive(serde::Deserialize)]
    struct AnswerOnly<'a> {
        #[serde(borrow)]
        answer: Option<&'a RawValue>,
    }
    match serde_json::from_str::<AnswerOnly<'_>>(record) {
        Ok(r) => r.answer.map(|a| a.get().to_owned()),
        // Python's JSON (NaN, duplicate keys: the last wins) where serde refuses it.
        Err(_) => parse_python_json(record.trim())
            .ok()
            .and_then(|v| v.get("answer").map(|a| a.to_json(false))),
    }
}

/// The submission's overall intervals: resampling activities (`clusters`: each scored item's
/// activity, in order), and items one by one beside them.
fn intervals(scoring: &StrictScoring, clusters: &[u32]) -> ConfidenceIntervals {
    let ta: Vec<(u32, f64)> = scoring
        .items
        .iter()
        .zip(clusters)
        .map(|(r, c)| (*c, f64::from(u8::from(r.task_accuracy()))))
        .collect();
    let pa: Vec<(u32, f64)> = scoring
        .items
        .iter()
        .zip(clusters)
        .filter_map(|(r, c)| r.pairwise_accuracy().map(|p| (*c, p)))
        .collect();
    let ci = leaderboard_ci;
    let ((ta_ci, pa_ci), (ta_items, pa_items)) = rayon::join(
        || {
            (
                ci(&ta, Resampling::Activities),
                ci(&pa, Resampling::Activities),
            )
        },
        || rayon::join(|| ci(&ta, Resampling::Items), || ci(&pa, Resampling::Items)),
    );
    ConfidenceIntervals {
        level: BOOTSTRAP_LEVEL,
        resamples: BOOTSTRAP_RESAMPLES,
        seed: BOOTSTRAP_SEED,
        resampling: Resampling::Activities,
        task_accuracy: ta_ci,
        pairwise_accuracy: pa_ci,
        by_items: Some(ItemIntervals {
            task_accuracy: ta_items,
            pairwise_accuracy: pa_items,
        }),
    }
}

/// `clusters`: each target's activity as a number, in the targets' order.
fn assemble(
    scoring: StrictScoring,
    raw_answers: Vec<Option<String>>,
    clusters: &[u32],
) -> ScoredSubmission {
    let confidence = intervals(&scoring, clusters);
    let items = scoring
        .items
        .into_iter()
        .zip(raw_answers)
        .enumerate()
        .map(|(target, (r, raw_answer))| ItemVerdict {
            target,
            line: r.line,
            raw_answer,
            task_accuracy: r.task_accuracy(),
            pairwise_accuracy: r.pairwise_accuracy(),
            outcome: r.outcome,
        })
        .collect();
    ScoredSubmission {
        scores: SubmissionScores {
            policy: ScoringPolicy::Strict,
            report: scoring.report,
            coverage: scoring.coverage,
            confidence,
        },
        items,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_verdict_outcome_is_spelled_as_its_column_checks() {
        for outcome in VerdictOutcome::ALL {
            assert_eq!(VerdictOutcome::parse(outcome.as_str()), Some(outcome));
        }
        assert_eq!(
            VerdictOutcome::of(&StrictOutcome::Missing),
            VerdictOutcome::Missing
        );
        assert_eq!(VerdictOutcome::parse("skipped"), None);
    }
    use crate::dataset::{Direction, StepLength};
    use crate::verifier::Permutation;

    fn targets() -> Vec<ScoringTarget> {
        (0..4)
            .map(|i| ScoringTarget {
                id: format!("item{i}"),
                item_type: "forward_world_modeling_3_steps".to_owned(),
                task_name: "task".to_owned(),
                direction: Direction::Forward,
                step_length: StepLength::new(3).expect("3"),
                ground_truth: Permutation::new(vec![2, 1]).expect("perm"),
                semantics: None,
            })
            .collect()
    }

    #[test]
    fn forged_ground_truth_is_ignored() {
        let body = "{\"id\":\"item0\",\"answer\":\"[1, 2]\",\"gt_answer\":[1,2]}\n\
                    {\"id\":\"item1\",\"answer\":[2,1]}\n";
        let scored = score_submission(&targets(), body).expect("scored");
        assert!(!scored.items[0].task_accuracy);
        assert!(scored.items[1].task_accuracy);
        assert_eq!(scored.items[0].raw_answer.as_deref(), Some("\"[1, 2]\""));
        assert_eq!(scored.scores.coverage.answered, 2);
        assert_eq!(scored.scores.coverage.missing, 2);
    }

    #[test]
    fn arrays_and_lines_score_alike_and_parse_failures_count() {
        let lines =
            "{\"id\":\"item0\",\"answer\":\"[2,1]\"}\n{\"id\":\"item1\",\"answer\":\"no idea\"}\n";
        let array =
            "[{\"id\":\"item0\",\"answer\":\"[2,1]\"},{\"id\":\"item1\",\"answer\":\"no idea\"}]";
        let a = score_submission(&targets(), lines).expect("lines");
        let b = score_submission(&targets(), array).expect("array");
        assert_eq!(a.scores, b.scores);
        assert_eq!(a.scores.coverage.unparseable, 1);
        assert_eq!(a.scores.coverage.parse_failure_rate, 0.5);
        let ci = a.scores.confidence.task_accuracy.expect("ci");
        assert!(ci.low <= 0.25 && 0.25 <= ci.high);
    }

    #[test]
    fn every_problem_is_reported_with_its_line() {
        let body = "{\"id\":\"item0\",\"answer\":\"[2,1]\"}\n\
                    {oops\n\
                    {\"id\":\"nope\",\"answer\":\"[2,1]\"}\n\
                    {\"id\":\"item0\",\"answer\":\"[1,2]\"}\n\
                    {\"id\":\"item1\"}\n";
        let Err(SubmissionError::Rejected(problems)) = score_submission(&targets(), body) else {
            panic!("must be rejected");
        };
        let kinds: Vec<(usize, &str)> = problems.iter().map(|p| (p.line, p.kind)).collect();
        assert_eq!(
            kinds,
            vec![
                (2, "invalid_json"),
                (3, "unknown_id"),
                (4, "duplicate_id"),
                (5, "missing_answer")
            ]
        );
        assert!(problems[3].message.contains("line 5"), "{:?}", problems[3]);
    }

    #[test]
    fn rescoring_stored_answers_gives_the_same_result() {
        let body = "{\"id\":\"item0\",\"answer\":\"[2, 1]\"}\n\
                    {\"id\":\"item2\",\"answer\":[1,2]}\n\
                    {\"id\":\"item3\",\"answer\":\"I cannot tell\"}\n";
        let scored = score_submission(&targets(), body).expect("scored");
        let ids: Vec<String> = targets().iter().map(|t| t.id.clone()).collect();
        let answers: Vec<StoredAnswer> = scored
            .items
            .iter()
            .filter_map(|v| {
                Some(StoredAnswer {
                    item_id: ids[v.target].clone(),
                    line: v.line?,
                    raw_answer: v.raw_answer.clone()?,
                })
            })
            .collect();
        assert_eq!(answers.len(), 3);
        let again = rescore_submission(&targets(), &answers).expect("rescored");
        assert_eq!(again, scored);
        assert_eq!(
            serde_json::to_string(&again.scores).expect("json"),
            serde_json::to_string(&scored.scores).expect("json")
        );
        // Judged against the items as they are now: a changed ground truth changes the verdict.
        let mut changed = targets();
        changed[2].ground_truth = Permutation::new(vec![1, 2]).expect("perm");
        let rejudged = rescore_submission(&changed, &answers).expect("rescored");
        assert!(!scored.items[2].task_accuracy);
        assert!(rejudged.items[2].task_accuracy);
    }

    #[test]
    fn a_broken_array_names_its_line() {
        let Err(SubmissionError::Rejected(problems)) =
            score_submission(&targets(), "[\n{\"id\":\"item0\",\n\"answer\" 1}]")
        else {
            panic!("must be rejected");
        };
        assert_eq!(problems[0].line, 3);
    }
}
