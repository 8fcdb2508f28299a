//! Per-annotator quality on a dataset, without I/O: accuracy on gold items with Wilson
//! intervals, agreement with the other annotators on shared items (pairwise Krippendorff's
//! alpha on whole answers and exact agreement, from [`crate::agreement`]), time per item
//! from the telemetry, and skip and flag rates.

use std::collections::{BTreeMap, HashMap};

use schemars::JsonSchema;
use serde::Serialize;

use super::agreement::{
    AnnotatedOrdering, OrderingAnnotations, PAPER_COMPARABLE_ENCODING, pairwise_alphas, percentile,
};
use super::annotation::{HumanAnswer, HumanVerdict, OutcomeKind, human_verdict};
pub use super::leaderboard::Interval;

/// The z of a two-sided 95% interval.
const Z_95: f64 = 1.959_963_984_540_054;

/// Items answered faster than this many seconds count as fast, unless the admin picks another.
pub const DEFAULT_FAST_SECONDS: f64 = 5.0;

/// One finished item of one annotator.
#[derive(Debug, Clone)]
pub struct FinishedItem {
    /// The item's store id (what "shared" compares).
    pub item: i64,
    pub gold: bool,
    pub outcome: OutcomeKind,
    /// The answer with what judging it needs, when answered.
    pub answer: Option<HumanAnswer>,
    /// The verdict stored when it was answered, if any (judged here otherwise).
    pub verdict: Option<HumanVerdict>,
    pub time_on_item_ms: i64,
}

/// An annotator and everything they finished on the dataset.
#[derive(Debug, Clone)]
pub struct AnnotatorWork {
    pub name: String,
    /// Excluded from the dataset's Human row and agreement report.
    pub excluded: bool,
    pub items: Vec<FinishedItem>,
}

/// Wilson's score interval at 95% for `successes` out of `n` (a mean of values in [0, 1] is
/// taken as `successes`), `None` for no trials.
pub fn wilson(successes: f64, n: usize) -> Option<Interval> {
    if n == 0 {
        return None;
    }
    let n = n as f64;
    let p = successes / n;
    let z2 = Z_95 * Z_95;
    let denominator = 1.0 + z2 / n;
    let centre = (p + z2 / (2.0 * n)) / denominator;
    let half = Z_95 * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt() / denominator;
    Some(Interval {
        low: (centre - half).max(0.0),
        high: (centre + half).min(1.0),
    })
}

/// One annotator's figures.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct AnnotatorQuality {
    pub name: String,
    pub excluded: bool,
    /// Items finished: answered, skipped or flagged, gold items included.
    pub items_done: usize,
    pub answered: usize,
    /// Gold items answered.
    pub gold_answered: usize,
    /// Share of gold answers the verifier accepts (exact or state-change consistent).
    pub gold_task_accuracy: Option<f64>,
    pub gold_task_accuracy_interval: Option<Interval>,
    /// Mean pairwise accuracy of the gold answers.
    pub gold_pairwise_accuracy: Option<f64>,
    /// Wilson's interval with the gold answers as trials (the mean taken as the success share).
    pub gold_pairwise_accuracy_interval: Option<Interval>,
    /// Items this annotator and at least one other answered.
    pub shared_items: usize,
    /// Mean of the pairwise Krippendorff's alphas (whole answers, nominal) with each other
    /// annotator, over the items each pair shares; `None` when none is defined.
    pub pairwise_alpha: Option<f64>,
    /// Share of (other annotator, shared item) pairs where both gave the same answer.
    pub exact_agreement: Option<f64>,
    /// Median seconds on an item (finished items, from first opening to finishing).
    pub median_seconds: Option<f64>,
    /// The 10th percentile of seconds on an item.
    pub lower_decile_seconds: Option<f64>,
    /// Share of answered items answered in under `fast_seconds`.
    pub fast_share: Option<f64>,
    /// Skipped items per finished item.
    pub skip_rate: Option<f64>,
    /// Flagged items per finished item.
    pub flag_rate: Option<f64>,
}

fn share(count: usize, of: usize) -> Option<f64> {
    (of > 0).then(|| count as f64 / of as f64)
}

/// Every annotator's figures, in the order given. `fast_seconds` is the bar of
/// [`AnnotatorQuality::fast_share`]. An answer the verifier cannot judge is an error naming it.
pub fn annotator_quality(
    work: &[AnnotatorWork],
    fast_seconds: f64,
) -> Result<Vec<AnnotatorQuality>, String> {
    let agreement = agreement_with_others(work);
    work.iter()
        .zip(agreement)
        .map(
            |(annotator, (shared_items, pairwise_alpha, exact_agreement))| {
                one(
                    annotator,
                    fast_seconds,
                    shared_items,
                    pairwise_alpha,
                    exact_agreement,
                )
            },
        )
        .collect()
}

fn one(
    annotator: &AnnotatorWork,
    fast_seconds: f64,
    shared_items: usize,
    pairwise_alpha: Option<f64>,
    exact_agreement: Option<f64>,
) -> Result<AnnotatorQuality, String> {
    let finished = annotator.items.len();
    let count = |kind: OutcomeKind| annotator.items.iter().filter(|i| i.outcome == kind).count();
    let answered = count(OutcomeKind::Answered);
    let mut accepted = 0usize;
    let mut pairwise: Vec<f64> = Vec::new();
    let mut gold_answered = 0usize;
    for item in annotator.items.iter().filter(|i| i.gold) {
        let Some(answer) = &item.answer else { continue };
        gold_answered += 1;
        let verdict = match item.verdict {
            Some(verdict) => verdict,
            None => human_verdict(answer).map_err(|e| format!("item {}: {e}", answer.item_id))?,
        };
        accepted += usize::from(verdict.task_accuracy);
        // An answer without a pairwise accuracy (a one-step item) has no pair to count.
        if let Some(pa) = verdict.pairwise_accuracy {
            pairwise.push(pa);
        }
    }
    let mut seconds: Vec<f64> = annotator
        .items
        .iter()
        .map(|i| i.time_on_item_ms as f64 / 1000.0)
        .collect();
    seconds.sort_by(f64::total_cmp);
    let fast = annotator
        .items
        .iter()
        .filter(|i| i.outcome == OutcomeKind::Answered)
        .filter(|i| (i.time_on_item_ms as f64 / 1000.0) < fast_seconds)
        .count();
    let pa_sum: f64 = pairwise.iter().sum();
    Ok(AnnotatorQuality {
        name: annotator.name.clone(),
        excluded: annotator.excluded,
        items_done: finished,
        answered,
        gold_answered,
        gold_task_accuracy: share(accepted, gold_answered),
        gold_task_accuracy_interval: wilson(accepted as f64, gold_answered),
        gold_pairwise_accuracy: (!pairwise.is_empty()).then(|| pa_sum / pairwise.len() as f64),
        gold_pairwise_accuracy_interval: wilson(pa_sum, pairwise.len()),
        shared_items,
        pairwise_alpha,
        exact_agreement,
        median_seconds: percentile(&seconds, 0.5),
        lower_decile_seconds: percentile(&seconds, 0.1),
        fast_share: share(fast, answered),
        skip_rate: share(count(OutcomeKind::Skipped), finished),
        flag_rate: share(count(OutcomeKind::Flagged), finished),
    })
}

/// Each answered item (by store id): every annotator's labels on it, in `work`'s order.
type AnswersByItem = BTreeMap<i64, Vec<Option<Vec<u8>>>>;

/// Per annotator (in `work`'s order): items shared with someone, mean pairwise alpha with the
/// others and exact agreement with them.
fn agreement_with_others(work: &[AnnotatorWork]) -> Vec<(usize, Option<f64>, Option<f64>)> {
    // Every answered item: each annotator's labels on it.
    let mut by_item: AnswersByItem = BTreeMap::new();
    for (index, annotator) in work.iter().enumerate() {
        for item in &annotator.items {
            let Some(answer) = &item.answer else { continue };
            let entry = by_item
                .entry(item.item)
                .or_insert_with(|| vec![None; work.len()]);
            entry[index] = Some(answer.answer.labels().to_vec());
        }
    }
    let shared: Vec<&Vec<Option<Vec<u8>>>> = by_item
        .values()
        .filter(|answers| answers.iter().flatten().count() >= 2)
        .collect();
    let mut result = Vec::with_capacity(work.len());
    let mut pair_matches: HashMap<usize, (usize, usize)> = HashMap::new();
    let mut shared_items: HashMap<usize, usize> = HashMap::new();
    for answers in &shared {
        for (a, mine) in answers.iter().enumerate() {
            let Some(mine) = mine else { continue };
            *shared_items.entry(a).or_default() += 1;
            for (b, theirs) in answers.iter().enumerate() {
                if a == b {
                    continue;
                }
                if let Some(theirs) = theirs {
                    let tally = pair_matches.entry(a).or_default();
                    tally.0 += usize::from(mine == theirs);
                    tally.1 += 1;
                }
            }
        }
    }
    let alphas = pairwise_alpha_means(work, &by_item);
    for index in 0..work.len() {
        let (same, pairs) = pair_matches.get(&index).copied().unwrap_or((0, 0));
        result.push((
            shared_items.get(&index).copied().unwrap_or(0),
            alphas.get(index).copied().flatten(),
            share(same, pairs),
        ));
    }
    result
}

/// Each annotator's mean of the defined pairwise alphas with the others, on whole answers.
fn pairwise_alpha_means(work: &[AnnotatorWork], by_item: &AnswersByItem) -> Vec<Option<f64>> {
    let none = vec![None; work.len()];
    if work.len() < 2 {
        return none;
    }
    let names: Vec<String> = (0..work.len()).map(|i| format!("annotator-{i}")).collect();
    // Keyed by store id, so two items sharing a display id never collide.
    let items: Vec<AnnotatedOrdering> = by_item
        .iter()
        .map(|(item, answers)| AnnotatedOrdering {
            item_id: item.to_string(),
            answers: answers.clone(),
        })
        .collect();
    let Ok(annotations) = OrderingAnnotations::new(names, items) else {
        // Stored answers are permutations of their item's labels; nothing to compare if not.
        return none;
    };
    let encoded = annotations.encode(PAPER_COMPARABLE_ENCODING);
    let mut sums: Vec<(f64, usize)> = vec![(0.0, 0); work.len()];
    for pair in pairwise_alphas(&encoded.data, encoded.level) {
        if let Some(alpha) = pair.result.alpha {
            for coder in [pair.coder_a, pair.coder_b] {
                sums[coder].0 += alpha;
                sums[coder].1 += 1;
            }
        }
    }
    sums.into_iter()
        .map(|(sum, n)| (n > 0).then(|| sum / n as f64))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::{Direction, StepLength};
    use crate::verifier::Permutation;

    fn answer(item: i64, gt: &[u8], given: &[u8]) -> HumanAnswer {
        HumanAnswer {
            item_id: format!("item-{item}"),
            direction: Direction::Forward,
            step_length: StepLength::new(gt.len() + 1).unwrap(),
            ground_truth: Permutation::new(gt.to_vec()).unwrap(),
            answer: Permutation::new(given.to_vec()).unwrap(),
            signatures: None,
        }
    }

    fn answered(item: i64, gold: bool, gt: &[u8], given: &[u8], ms: i64) -> FinishedItem {
        FinishedItem {
            item,
            gold,
            outcome: OutcomeKind::Answered,
            answer: Some(answer(item, gt, given)),
            verdict: None,
            time_on_item_ms: ms,
        }
    }

    fn skipped(item: i64, kind: OutcomeKind, ms: i64) -> FinishedItem {
        FinishedItem {
            item,
            gold: false,
            outcome: kind,
            answer: None,
            verdict: None,
            time_on_item_ms: ms,
        }
    }

    #[test]
    fn wilson_matches_the_textbook_values() {
        // 8 of 10: (0.4902, 0.9433).
        let i = wilson(8.0, 10).unwrap();
        assert!((i.low - 0.4902).abs() < 1e-4, "{i:?}");
        assert!((i.high - 0.9433).abs() < 1e-4, "{i:?}");
        let all = wilson(5.0, 5).unwrap();
        assert!((all.high - 1.0).abs() < 1e-12 && all.low > 0.5);
        assert!(wilson(0.0, 0).is_none());
    }

    #[test]
    fn gold_accuracy_time_and_rates_come_from_the_annotator_s_own_items() {
        let careful = AnnotatorWork {
            name: "careful".into(),
            excluded: false,
            items: vec![
                answered(1, true, &[1, 2, 3], &[1, 2, 3], 20_000),
                answered(2, true, &[2, 1, 3], &[2, 1, 3], 30_000),
                answered(3, false, &[1, 2], &[1, 2], 10_000),
                skipped(4, OutcomeKind::Skipped, 4_000),
                skipped(5, OutcomeKind::Flagged, 6_000),
            ],
        };
        let careless = AnnotatorWork {
            name: "careless".into(),
            excluded: true,
            items: vec![
                answered(1, true, &[1, 2, 3], &[3, 2, 1], 2_000),
                answered(2, true, &[2, 1, 3], &[2, 1, 3], 2_000),
                answered(3, false, &[1, 2], &[2, 1], 2_000),
            ],
        };
        let q = annotator_quality(&[careful, careless], 5.0).unwrap();
        let (a, b) = (&q[0], &q[1]);
        assert_eq!((a.items_done, a.answered, a.gold_answered), (5, 3, 2));
        assert_eq!(a.gold_task_accuracy, Some(1.0));
        assert_eq!(a.gold_pairwise_accuracy, Some(1.0));
        assert_eq!(a.skip_rate, Some(0.2));
        assert_eq!(a.flag_rate, Some(0.2));
        // Seconds 4, 6, 10, 20, 30: median 10, lower decile 4 + 0.4 × 2.
        assert_eq!(a.median_seconds, Some(10.0));
        assert!((a.lower_decile_seconds.unwrap() - 4.8).abs() < 1e-9);
        assert_eq!(a.fast_share, Some(0.0));
        assert_eq!(b.gold_task_accuracy, Some(0.5));
        assert_eq!(b.fast_share, Some(1.0));
        assert!(b.excluded);
        // Items 1, 2, 3 shared; same answer on item 2 only.
        assert_eq!((a.shared_items, b.shared_items), (3, 3));
        assert_eq!(a.exact_agreement, Some(1.0 / 3.0));
        assert_eq!(b.exact_agreement, Some(1.0 / 3.0));
        assert_eq!(a.pairwise_alpha, b.pairwise_alpha);
    }

    #[test]
    fn an_annotator_alone_has_no_agreement_and_no_gold_figures_without_gold() {
        let alone = AnnotatorWork {
            name: "alone".into(),
            excluded: false,
            items: vec![answered(1, false, &[1, 2], &[1, 2], 1_000)],
        };
        let q = annotator_quality(&[alone], 5.0).unwrap();
        assert_eq!(q[0].shared_items, 0);
        assert_eq!(q[0].pairwise_alpha, None);
        assert_eq!(q[0].exact_agreement, None);
        assert_eq!(q[0].gold_task_accuracy, None);
        assert_eq!(q[0].gold_task_accuracy_interval, None);
    }
}
