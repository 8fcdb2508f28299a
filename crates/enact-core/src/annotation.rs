//! Human annotation, the parts without HTTP or SQL: the balanced split of a dataset over
//! annotators, the draft an annotator is working on, where each assigned item stands, the
//! telemetry of a finished item, and the scoring of submitted answers into the same report
//! models get. Passwords and tokens are in [`crate::credentials`].

use crate::audit::Actor;
use std::collections::{BTreeMap, HashMap, HashSet};

use serde::{Deserialize, Serialize};

use crate::dataset::{Direction, StepLength};
use crate::error_analysis::{self, AnsweredItem, ErrorAnalysis, Reading};
use crate::leaderboard::HumanCoverage;
use crate::metric::{METRIC_VERSION, MetricStamp};
use crate::verifier::{
    ItemSignatures, ParsedAnswer, PerformanceReport, Permutation, ScoredEntry, StrictItem,
    VerifyError, verify,
};

/// An item to deal out: its store id and its kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SplitItem {
    pub item: i64,
    pub direction: Direction,
    pub step_length: StepLength,
}

/// Up to `per_kind` items of each direction × step length, in rounds: the first item of every
/// kind (step lengths ascending, forward before inverse), then the second, and so on, so that
/// a short session already sees both directions and every length.
pub fn balanced_sample(items: &[SplitItem], per_kind: usize) -> Vec<i64> {
    let mut by_kind: BTreeMap<(StepLength, Direction), Vec<i64>> = BTreeMap::new();
    for it in items {
        by_kind
            .entry((it.step_length, it.direction))
            .or_default()
            .push(it.item);
    }
    (0..per_kind)
        .flat_map(|round| {
            by_kind
                .values()
                .filter_map(move |ids| ids.get(round).copied())
                .collect::<Vec<_>>()
        })
        .collect()
}

/// Deals `items` over `annotators` disjointly so that every annotator gets the same number of
/// items of each direction × step length, ±1, and the same total, ±1. Items keep their order
/// within a kind; returns `(annotator, item)` pairs.
pub fn balanced_split(items: &[SplitItem], annotators: &[i64]) -> Vec<(i64, i64)> {
    if annotators.is_empty() {
        return Vec::new();
    }
    let mut by_kind: BTreeMap<(Direction, StepLength), Vec<i64>> = BTreeMap::new();
    for it in items {
        by_kind
            .entry((it.direction, it.step_length))
            .or_default()
            .push(it.item);
    }
    // One running counter across kinds: each kind's remainder goes to the annotators who got
    // the fewest so far, which keeps the totals balanced too.
    let mut next = 0usize;
    let mut out = Vec::with_capacity(items.len());
    for kind_items in by_kind.values() {
        for &item in kind_items {
            out.push((annotators[next % annotators.len()], item));
            next += 1;
        }
    }
    out
}

/// Deals an annotator's unfinished `items` over `recipients` for a handover: kind by kind
/// (direction × step length, in the order of [`balanced_split`]), each item goes to the
/// recipient who has received the fewest so far (the earliest in `recipients` on a tie) among
/// those who do not hold it already (`held`: annotator → items in their queue), so the totals
/// stay within one of each other whenever nobody holds the items. Returns the `(recipient,
/// item)` pairs and the items every recipient holds already (nobody can take them).
pub fn handover_split(
    items: &[SplitItem],
    recipients: &[i64],
    held: &HashMap<i64, HashSet<i64>>,
) -> (Vec<(i64, i64)>, Vec<i64>) {
    let mut by_kind: BTreeMap<(Direction, StepLength), Vec<i64>> = BTreeMap::new();
    for it in items {
        by_kind
            .entry((it.direction, it.step_length))
            .or_default()
            .push(it.item);
    }
    let mut given = vec![0usize; recipients.len()];
    let mut pairs = Vec::with_capacity(items.len());
    let mut left = Vec::new();
    for kind_items in by_kind.values() {
        for &item in kind_items {
            let takes = recipients
                .iter()
                .enumerate()
                .filter(|(_, r)| !held.get(r).is_some_and(|h| h.contains(&item)))
                .min_by_key(|(index, _)| (given[*index], *index));
            match takes {
                Some((index, &recipient)) => {
                    given[index] += 1;
                    pairs.push((recipient, item));
                }
                None => left.push(item),
            }
        }
    }
    (pairs, left)
}

/// Interaction counts the item page reports with each change.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct InteractionCounts {
    pub placements: u32,
    pub swaps: u32,
    pub clears: u32,
    pub undos: u32,
}

/// The half-placed answer of an item: one slot per transition, each a label or empty.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Draft {
    pub slots: Vec<Option<u8>>,
    pub counts: InteractionCounts,
    /// Earlier slot states, oldest first, so undo survives a reload.
    #[serde(default)]
    pub history: Vec<Vec<Option<u8>>>,
}

/// Undo steps kept per item.
pub const MAX_HISTORY: usize = 200;

impl Draft {
    pub fn empty(step_length: StepLength) -> Draft {
        Draft {
            slots: vec![None; step_length.actions()],
            counts: InteractionCounts::default(),
            history: Vec::new(),
        }
    }

    /// Checks a draft sent by the page against the item: L-1 slots, labels in 1..L-1, none twice.
    pub fn check(&self, step_length: StepLength) -> Result<(), DraftProblem> {
        let n = step_length.actions();
        check_slots("slots", &self.slots, n)?;
        if self.history.len() > MAX_HISTORY {
            return Err(DraftProblem::HistoryTooLong {
                entries: self.history.len(),
                most: MAX_HISTORY,
            });
        }
        for (i, h) in self.history.iter().enumerate() {
            check_slots(&format!("history[{i}]"), h, n)?;
        }
        Ok(())
    }

    pub fn has_placement(&self) -> bool {
        self.slots.iter().any(Option::is_some)
    }

    /// The answer, when every slot is filled.
    pub fn answer(&self) -> Option<Permutation> {
        let labels: Option<Vec<u8>> = self.slots.iter().copied().collect();
        labels.and_then(|l| Permutation::new(l).ok())
    }
}

/// What is wrong with a draft the page sent, and where: `field` is `slots` (what is placed now)
/// or `history[i]` (an undo step); `slot` counts from 0, as the field's index does.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DraftProblem {
    /// The field has `given` slots; the item has `expected` (its transitions).
    SlotCount {
        field: String,
        given: usize,
        expected: usize,
    },
    /// A slot holds a label the item has no card for (its cards are 1..=`labels`).
    LabelOutOfRange {
        field: String,
        slot: usize,
        label: u8,
        labels: usize,
    },
    /// A label is placed a second time, in `slot`.
    PlacedTwice {
        field: String,
        slot: usize,
        label: u8,
    },
    /// More undo steps than are kept.
    HistoryTooLong { entries: usize, most: usize },
}

impl std::fmt::Display for DraftProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DraftProblem::SlotCount {
                field,
                given,
                expected,
            } => write!(f, "{field}: {given} slots given, this item has {expected}"),
            DraftProblem::LabelOutOfRange {
                field,
                slot,
                label,
                labels,
            } => write!(f, "{field}[{slot}]: label {label} is not in 1..{labels}"),
            DraftProblem::PlacedTwice { field, slot, label } => {
                write!(f, "{field}[{slot}]: label {label} is placed twice")
            }
            DraftProblem::HistoryTooLong { entries, most } => {
                write!(f, "history: {entries} entries; at most {most}")
            }
        }
    }
}

fn check_slots(field: &str, slots: &[Option<u8>], n: usize) -> Result<(), DraftProblem> {
    if slots.len() != n {
        return Err(DraftProblem::SlotCount {
            field: field.to_owned(),
            given: slots.len(),
            expected: n,
        });
    }
    let mut seen = vec![false; n + 1];
    for (i, label) in slots.iter().enumerate() {
        let Some(label) = label else { continue };
        let index = usize::from(*label);
        if index == 0 || index > n {
            return Err(DraftProblem::LabelOutOfRange {
                field: field.to_owned(),
                slot: i,
                label: *label,
                labels: n,
            });
        }
        if seen[index] {
            return Err(DraftProblem::PlacedTwice {
                field: field.to_owned(),
                slot: i,
                label: *label,
            });
        }
        seen[index] = true;
    }
    Ok(())
}

/// One submitted human answer with what scoring needs of its item.
#[derive(Debug, Clone)]
pub struct HumanAnswer {
    pub item_id: String,
    pub direction: Direction,
    pub step_length: StepLength,
    pub ground_truth: Permutation,
    pub answer: Permutation,
    pub signatures: Option<ItemSignatures>,
}

/// Scores human answers with the verifier models are scored with. Every answer is one entry (an
/// item answered by two people counts twice); an answer the verifier cannot judge is an error
/// naming its position.
pub fn human_entries(answers: &[HumanAnswer]) -> Result<Vec<ScoredEntry>, String> {
    answers
        .iter()
        .enumerate()
        .map(|(i, a)| {
            let verdict = human_verdict(a).map_err(|e| format!("answer {i}: {e}"))?;
            Ok(verdict.entry(a.direction, a.step_length))
        })
        .collect()
}

/// A human answer's verdict, as stored with the answer (the figures a submission line keeps).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HumanVerdict {
    pub exact_match: bool,
    pub semantic_match: bool,
    pub task_accuracy: bool,
    pub pairwise_accuracy: Option<f64>,
}

impl HumanVerdict {
    /// The answer's entry in a performance report.
    pub fn entry(&self, direction: Direction, step_length: StepLength) -> ScoredEntry {
        ScoredEntry {
            group: Some(direction),
            states: step_length.states(),
            task_accuracy: self.task_accuracy,
            pairwise_accuracy: self.pairwise_accuracy,
        }
    }
}

/// Judges one human answer with the verifier models are judged with, under the current metric.
pub fn human_verdict(a: &HumanAnswer) -> Result<HumanVerdict, VerifyError> {
    let verdict = verify(
        a.direction,
        &a.ground_truth,
        &ParsedAnswer::from(&a.answer),
        a.signatures.as_ref(),
    )?;
    Ok(HumanVerdict {
        exact_match: verdict.exact_match,
        semantic_match: verdict.semantic_match,
        task_accuracy: verdict.task_accuracy,
        pairwise_accuracy: verdict.pairwise_accuracy.value(),
    })
}

/// One answer the Human row counts: who gave it on which item, and its verdict as stored, or
/// the answer itself when no verdict is stored yet (answers finished before verdicts were
/// stored, until a rescore computes theirs).
#[derive(Debug, Clone)]
pub struct CountedAnswer {
    pub annotator: i64,
    pub item: i64,
    pub direction: Direction,
    pub step_length: StepLength,
    pub verdict: CountedVerdict,
}

#[derive(Debug, Clone)]
pub enum CountedVerdict {
    Stored {
        verdict: HumanVerdict,
        metric_version: u32,
    },
    Unscored(Box<HumanAnswer>),
}

/// The Human row's figures: its report, what it rests on, and the oldest metric version among
/// its verdicts.
#[derive(Debug, Clone, PartialEq)]
pub struct HumanFigures {
    pub report: PerformanceReport,
    pub coverage: HumanCoverage,
    pub stamp: MetricStamp,
}

/// The Human row from its answers (`dataset_items`: the dataset's size, for coverage): stored
/// verdicts as they are, missing ones judged now under the current metric. `None` before the
/// first answer; an answer the verifier cannot judge is an error naming its item.
pub fn human_figures(
    answers: &[CountedAnswer],
    dataset_items: usize,
) -> Result<Option<HumanFigures>, String> {
    if answers.is_empty() {
        return Ok(None);
    }
    let mut entries = Vec::with_capacity(answers.len());
    let mut versions = Vec::with_capacity(answers.len());
    for a in answers {
        let (verdict, version) = match &a.verdict {
            CountedVerdict::Stored {
                verdict,
                metric_version,
            } => (*verdict, *metric_version),
            CountedVerdict::Unscored(answer) => (
                human_verdict(answer).map_err(|e| format!("item {}: {e}", answer.item_id))?,
                METRIC_VERSION,
            ),
        };
        entries.push(verdict.entry(a.direction, a.step_length));
        versions.push(version);
    }
    Ok(Some(HumanFigures {
        report: PerformanceReport::from_entries(&entries),
        coverage: HumanCoverage::of_answers(
            answers.iter().map(|a| (a.annotator, a.item)),
            dataset_items,
        ),
        stamp: MetricStamp::oldest(versions),
    }))
}

/// Each answered item's mean pairwise accuracy over its human answers (an item answered by
/// several annotators is one observation), by item id; answers without a value are left out.
pub fn mean_by_item<'a>(
    scored: impl IntoIterator<Item = (&'a HumanAnswer, Option<f64>)>,
) -> std::collections::BTreeMap<String, (Direction, StepLength, f64)> {
    let mut sums: std::collections::BTreeMap<&str, (Direction, StepLength, f64, usize)> =
        std::collections::BTreeMap::new();
    for (answer, value) in scored {
        let Some(value) = value else { continue };
        let sum =
            sums.entry(&answer.item_id)
                .or_insert((answer.direction, answer.step_length, 0.0, 0));
        sum.2 += value;
        sum.3 += 1;
    }
    sums.into_iter()
        .map(|(id, (direction, length, sum, n))| {
            (id.to_owned(), (direction, length, sum / n as f64))
        })
        .collect()
}

/// The error analysis of human answers, each read like a model's (an item answered by two
/// people counts twice), with the verifier's task accuracy for it.
pub fn human_error_analysis(answers: &[HumanAnswer]) -> Result<ErrorAnalysis, String> {
    let mut verdicts = Vec::with_capacity(answers.len());
    for (i, a) in answers.iter().enumerate() {
        let verdict = verify(
            a.direction,
            &a.ground_truth,
            &ParsedAnswer::from(&a.answer),
            a.signatures.as_ref(),
        )
        .map_err(|e| format!("answer {i} (item {}): {e}", a.item_id))?;
        verdicts.push(verdict.task_accuracy);
    }
    Ok(error_analysis::analyse(answers.iter().zip(verdicts).map(
        |(a, task_accuracy)| AnsweredItem {
            item: StrictItem {
                id: &a.item_id,
                direction: a.direction,
                step_length: a.step_length,
                ground_truth: &a.ground_truth,
                signatures: a.signatures.as_ref(),
            },
            reading: Reading::Answer {
                answer: &a.answer,
                task_accuracy,
            },
        },
    )))
}

/// An annotator logged in: who, and the CSRF token their forms must carry.
#[derive(Debug, Clone)]
pub struct Session {
    pub annotator: i64,
    pub name: String,
    pub is_admin: bool,
    pub csrf_token: String,
}

impl Session {
    /// Who this session is in the audit log.
    pub fn actor(&self) -> Actor {
        Actor::Annotator(self.name.clone())
    }
}

/// Where an assigned item stands for its annotator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum QueueStatus {
    Todo,
    /// A draft exists: the annotator has opened the item.
    Started,
    Answered,
    Skipped,
    Flagged,
}

impl QueueStatus {
    /// Where an item stands given how it was finished, if it was, and whether a draft of it
    /// exists (a finished item keeps none).
    pub fn of(finished: Option<OutcomeKind>, started: bool) -> QueueStatus {
        match finished {
            Some(OutcomeKind::Answered) => QueueStatus::Answered,
            Some(OutcomeKind::Skipped) => QueueStatus::Skipped,
            Some(OutcomeKind::Flagged) => QueueStatus::Flagged,
            None if started => QueueStatus::Started,
            None => QueueStatus::Todo,
        }
    }

    pub fn as_str(self) -> &'static str {
        match self {
            QueueStatus::Todo => "to do",
            QueueStatus::Started => "in progress",
            QueueStatus::Answered => "answered",
            QueueStatus::Skipped => "skipped",
            QueueStatus::Flagged => "flagged",
        }
    }

    pub fn is_done(self) -> bool {
        matches!(
            self,
            QueueStatus::Answered | QueueStatus::Skipped | QueueStatus::Flagged
        )
    }
}

#[derive(Debug, Clone)]
pub struct QueueEntry {
    pub dataset: String,
    pub item_id: String,
    pub direction: Direction,
    pub step_length: StepLength,
    pub status: QueueStatus,
}

/// The item an annotator should work on next: one already started, else the first to do.
pub fn next_in_queue(queue: &[QueueEntry]) -> Option<&QueueEntry> {
    queue
        .iter()
        .find(|e| e.status == QueueStatus::Started)
        .or_else(|| queue.iter().find(|e| e.status == QueueStatus::Todo))
}

/// An annotator's standing on one item: whether it is finished, and the draft if one exists.
#[derive(Debug, Clone)]
pub struct AssignmentState {
    pub finished: bool,
    pub draft: Option<StoredDraft>,
}

/// A stored draft with its timing.
#[derive(Debug, Clone)]
pub struct StoredDraft {
    pub draft: Draft,
    pub started_at_ms: i64,
    pub first_placement_at_ms: Option<i64>,
}

/// How an item was finished.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    Answered(Permutation),
    Skipped(String),
    Flagged(String),
}

impl Outcome {
    pub fn kind(&self) -> OutcomeKind {
        match self {
            Outcome::Answered(_) => OutcomeKind::Answered,
            Outcome::Skipped(_) => OutcomeKind::Skipped,
            Outcome::Flagged(_) => OutcomeKind::Flagged,
        }
    }
}

/// How an item was finished, without the answer or reason: the `annotations.outcome` column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutcomeKind {
    Answered,
    Skipped,
    Flagged,
}

impl OutcomeKind {
    pub const ALL: [OutcomeKind; 3] = [
        OutcomeKind::Answered,
        OutcomeKind::Skipped,
        OutcomeKind::Flagged,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            OutcomeKind::Answered => "answered",
            OutcomeKind::Skipped => "skipped",
            OutcomeKind::Flagged => "flagged",
        }
    }

    pub fn parse(text: &str) -> Option<OutcomeKind> {
        OutcomeKind::ALL.into_iter().find(|o| o.as_str() == text)
    }
}

/// Telemetry stored with each finished item.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Telemetry {
    pub time_on_item_ms: i64,
    pub time_to_first_placement_ms: Option<i64>,
    pub placements: u32,
    pub swaps: u32,
    pub clears: u32,
    pub undos: u32,
}

impl Telemetry {
    /// An item finished without ever being opened.
    pub fn none() -> Telemetry {
        Telemetry {
            time_on_item_ms: 0,
            time_to_first_placement_ms: None,
            placements: 0,
            swaps: 0,
            clears: 0,
            undos: 0,
        }
    }

    /// Times run from the item's first opening to `now_ms`.
    pub fn of(draft: &StoredDraft, now_ms: i64) -> Telemetry {
        Telemetry {
            time_on_item_ms: (now_ms - draft.started_at_ms).max(0),
            time_to_first_placement_ms: draft
                .first_placement_at_ms
                .map(|t| (t - draft.started_at_ms).max(0)),
            placements: draft.draft.counts.placements,
            swaps: draft.draft.counts.swaps,
            clears: draft.draft.counts.clears,
            undos: draft.draft.counts.undos,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_queued_item_stands_where_its_outcome_or_its_draft_puts_it() {
        for kind in OutcomeKind::ALL {
            let status = QueueStatus::of(Some(kind), false);
            assert_eq!(status.as_str(), kind.as_str());
            assert!(status.is_done());
            // A finished item keeps no draft, but a stray one would not reopen it.
            assert_eq!(QueueStatus::of(Some(kind), true), status);
            assert_eq!(OutcomeKind::parse(kind.as_str()), Some(kind));
        }
        assert_eq!(QueueStatus::of(None, true), QueueStatus::Started);
        assert_eq!(QueueStatus::of(None, false), QueueStatus::Todo);
        assert_eq!(OutcomeKind::parse("done"), None);
    }

    #[test]
    fn an_outcome_is_of_its_kind() {
        let answered = Outcome::Answered(Permutation::new(vec![2, 1, 3]).expect("a permutation"));
        assert_eq!(answered.kind(), OutcomeKind::Answered);
        assert_eq!(Outcome::Skipped("x".into()).kind(), OutcomeKind::Skipped);
        assert_eq!(Outcome::Flagged("x".into()).kind(), OutcomeKind::Flagged);
    }

    fn l(n: usize) -> StepLength {
        StepLength::new(n).expect("valid L")
    }

    #[test]
    fn split_is_disjoint_and_balanced_per_kind() {
        let mut items = Vec::new();
        let mut id = 0;
        for (direction, n, count) in [
            (Direction::Forward, 3, 5),
            (Direction::Inverse, 3, 4),
            (Direction::Forward, 10, 3),
        ] {
            for _ in 0..count {
                id += 1;
                items.push(SplitItem {
                    item: id,
                    direction,
                    step_length: l(n),
                });
            }
        }
        let pairs = balanced_split(&items, &[100, 200]);
        assert_eq!(pairs.len(), items.len());
        let mut seen: Vec<i64> = pairs.iter().map(|p| p.1).collect();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), items.len(), "an item was dealt twice");
        let kind = |item: i64| {
            let it = items.iter().find(|i| i.item == item).expect("item");
            (it.direction, it.step_length)
        };
        for k in [
            (Direction::Forward, l(3)),
            (Direction::Inverse, l(3)),
            (Direction::Forward, l(10)),
        ] {
            let per: Vec<usize> = [100, 200]
                .iter()
                .map(|a| {
                    pairs
                        .iter()
                        .filter(|(who, item)| who == a && kind(*item) == k)
                        .count()
                })
                .collect();
            assert!(per[0].abs_diff(per[1]) <= 1, "{k:?}: {per:?}");
        }
        let totals: Vec<usize> = [100, 200]
            .iter()
            .map(|a| pairs.iter().filter(|(who, _)| who == a).count())
            .collect();
        assert_eq!(totals, vec![6, 6]);
        assert!(balanced_split(&items, &[]).is_empty());
    }

    #[test]
    fn a_handover_is_balanced_and_never_gives_an_item_twice() {
        let items: Vec<SplitItem> = (1..=7)
            .map(|item| SplitItem {
                item,
                direction: if item % 2 == 0 {
                    Direction::Forward
                } else {
                    Direction::Inverse
                },
                step_length: l(3),
            })
            .collect();
        let (pairs, left) = handover_split(&items, &[100, 200], &HashMap::new());
        assert!(left.is_empty());
        let count = |pairs: &[(i64, i64)], who: i64| pairs.iter().filter(|p| p.0 == who).count();
        assert_eq!((count(&pairs, 100), count(&pairs, 200)), (4, 3));
        // 200 holds item 2 already, and both hold item 5: 5 stays where it was.
        let held: HashMap<i64, HashSet<i64>> = [(200, [2, 5].into()), (100, [5].into())].into();
        let (pairs, left) = handover_split(&items, &[100, 200], &held);
        assert_eq!(left, vec![5]);
        assert!(pairs.contains(&(100, 2)));
        assert!(!pairs.iter().any(|p| p.1 == 5));
        assert!(count(&pairs, 100).abs_diff(count(&pairs, 200)) <= 1);
        assert_eq!(pairs.len(), 6);
        assert!(handover_split(&items, &[], &HashMap::new()).0.is_empty());
    }

    #[test]
    fn drafts_are_checked_against_the_item() {
        let mut d = Draft::empty(l(4));
        assert_eq!(d.check(l(4)), Ok(()));
        assert!(d.answer().is_none());
        d.slots = vec![Some(2), None, Some(2)];
        assert_eq!(
            d.check(l(4)).expect_err("repeat").to_string(),
            "slots[2]: label 2 is placed twice"
        );
        d.slots = vec![Some(4), None, None];
        assert_eq!(
            d.check(l(4)).expect_err("range").to_string(),
            "slots[0]: label 4 is not in 1..3"
        );
        d.slots = vec![None, None];
        assert_eq!(
            d.check(l(4)).expect_err("length").to_string(),
            "slots: 2 slots given, this item has 3"
        );
        d.slots = vec![None; 3];
        d.history = vec![vec![None, Some(0), None]];
        assert_eq!(
            d.check(l(4)).expect_err("history"),
            DraftProblem::LabelOutOfRange {
                field: "history[0]".to_owned(),
                slot: 1,
                label: 0,
                labels: 3
            }
        );
        d.history = vec![vec![None; 3]; MAX_HISTORY + 1];
        assert_eq!(
            d.check(l(4)).expect_err("long").to_string(),
            format!(
                "history: {} entries; at most {MAX_HISTORY}",
                MAX_HISTORY + 1
            )
        );
        d.slots = vec![Some(3), Some(1), Some(2)];
        assert_eq!(d.answer().expect("full").labels(), &[3, 1, 2]);
    }

    #[test]
    fn human_answers_are_scored_like_model_answers() {
        let gt = Permutation::new(vec![2, 1]).expect("gt");
        let answers = [
            HumanAnswer {
                item_id: "a".to_owned(),
                direction: Direction::Forward,
                step_length: l(3),
                ground_truth: gt.clone(),
                answer: gt.clone(),
                signatures: None,
            },
            HumanAnswer {
                item_id: "b".to_owned(),
                direction: Direction::Inverse,
                step_length: l(3),
                ground_truth: gt.clone(),
                answer: Permutation::new(vec![1, 2]).expect("answer"),
                signatures: None,
            },
        ];
        let entries = human_entries(&answers).expect("scored");
        assert!(entries[0].task_accuracy);
        assert_eq!(entries[0].pairwise_accuracy, Some(1.0));
        assert!(!entries[1].task_accuracy);
        let report = crate::verifier::PerformanceReport::from_entries(&entries);
        assert_eq!(report.overall.expect("overall").totals.task_accuracy, 0.5);
    }

    #[test]
    fn a_balanced_sample_has_every_kind_in_rounds() {
        let items: Vec<SplitItem> = (0..40)
            .map(|i| SplitItem {
                item: i,
                direction: if i % 2 == 0 {
                    Direction::Forward
                } else {
                    Direction::Inverse
                },
                step_length: l(3 + (i as usize / 2) % 4),
            })
            .collect();
        let sample = balanced_sample(&items, 2);
        assert_eq!(sample.len(), 16);
        // The first round holds one item of each of the 8 kinds, lengths ascending.
        assert_eq!(&sample[..8], &[0, 1, 2, 3, 4, 5, 6, 7]);
        assert_eq!(&sample[8..], &[8, 9, 10, 11, 12, 13, 14, 15]);
        assert!(balanced_sample(&items, 0).is_empty());
        assert_eq!(balanced_sample(&items[..3], 5), vec![0, 1, 2]);
    }
}
