//! The agreement report of a dataset, without I/O: inter-annotator agreement on the items that
//! several annotators answered (alpha with an item bootstrap, every annotator pair, exact
//! agreement, counts by direction × step length), the TA/PA tables of the published submissions
//! and the Human row, and Welch comparisons on per-item pairwise accuracy.
//!
//! [`heatmap`] lays out the comparison figure and [`export`] writes the bundle's files; the
//! store gathers the inputs and the web and command line call [`build_report`].

pub mod export;
pub mod heatmap;

use std::collections::{BTreeMap, BTreeSet};

use serde::Serialize;
use sha2::{Digest, Sha256};

use crate::agreement::protocol::AssignmentKind;
use crate::agreement::{
    AnnotatedOrdering, BootstrapAlpha, BootstrapConfig, BootstrapError, ExactAgreement,
    MeasurementLevel, OrderingAnnotations, OrderingEncoding, OrderingError, PreparedAlpha,
    WelchComparison, mean_pairwise_alpha, pairwise_alphas, welch_t_test,
};
use crate::annotation::{HumanAnswer, human_entries, mean_by_item};
use crate::dataset::{Direction, StepLength};
use crate::leaderboard::{HumanCoverage, LeaderboardRow};
use crate::metric::MetricStamp;
use crate::verifier::PerformanceReport;
use crate::version::{HubBuild, THIS_BUILD};

/// Names what the numbers of a report mean. Bump it when a definition changes (which answers
/// count, how an encoding or a comparison is computed), so stamped files say which rules made
/// them.
pub const REPORT_METRIC_VERSION: &str = "enact-hub-agreement-report/1";

/// A stable fingerprint of a dataset's content: sha256 over `item_id TAB content_hash LF`
/// lines sorted by item id. Two stores holding the same items give the same hash.
pub fn dataset_content_hash<'a>(items: impl IntoIterator<Item = (&'a str, &'a str)>) -> String {
    let mut lines: Vec<(&str, &str)> = items.into_iter().collect();
    lines.sort_unstable();
    let mut hasher = Sha256::new();
    for (item_id, content_hash) in lines {
        hasher.update(item_id.as_bytes());
        hasher.update(b"\t");
        hasher.update(content_hash.as_bytes());
        hasher.update(b"\n");
    }
    hex::encode(hasher.finalize())
}

/// One annotator's submitted answer to one item, with what scoring it needs.
#[derive(Debug, Clone)]
pub struct AnnotatorAnswer {
    pub annotator_id: i64,
    pub annotator: String,
    pub item_id: String,
    pub kind: AssignmentKind,
    pub human: HumanAnswer,
}

/// An annotator as reports name them.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct AnnotatorRef {
    pub id: i64,
    pub name: String,
}

/// The items answered by two or more annotators, as orderings ready for agreement.
#[derive(Debug, Clone)]
pub struct OverlapSet {
    pub annotations: OrderingAnnotations,
    /// Coder order of `annotations`: by annotator id.
    pub annotators: Vec<AnnotatorRef>,
    /// Direction and step length of each item of `annotations`, in the same order.
    pub kinds: Vec<(Direction, StepLength)>,
    /// Answers on the overlapping items.
    pub answers: usize,
}

/// Why agreement could not be computed on stored answers.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AgreementUnavailable {
    #[error(
        "no item has answers from two or more annotators ({answers} answers on {items} items); \
         run the agreement protocol and let the annotators finish their items first"
    )]
    NoOverlap { answers: usize, items: usize },
    #[error(
        "encoding `answer` treats whole permutations as unordered categories, so only the \
         nominal level applies (got {0})"
    )]
    AnswerEncodingLevel(MeasurementLevel),
    #[error(transparent)]
    Ordering(#[from] OrderingError),
    #[error(transparent)]
    Bootstrap(#[from] BootstrapError),
}

/// Groups answers by item and keeps the items answered by two or more annotators.
pub fn overlapping_answers(
    answers: &[AnnotatorAnswer],
) -> Result<OverlapSet, AgreementUnavailable> {
    let mut by_item: BTreeMap<&str, Vec<&AnnotatorAnswer>> = BTreeMap::new();
    for answer in answers {
        by_item.entry(&answer.item_id).or_default().push(answer);
    }
    by_item.retain(|_, answers| {
        answers
            .iter()
            .map(|a| a.annotator_id)
            .collect::<BTreeSet<_>>()
            .len()
            >= 2
    });
    if by_item.is_empty() {
        let items = answers
            .iter()
            .map(|a| a.item_id.as_str())
            .collect::<BTreeSet<_>>()
            .len();
        return Err(AgreementUnavailable::NoOverlap {
            answers: answers.len(),
            items,
        });
    }
    let mut annotators: BTreeMap<i64, &str> = BTreeMap::new();
    for answer in by_item.values().flatten() {
        annotators.insert(answer.annotator_id, &answer.annotator);
    }
    let coder_of: BTreeMap<i64, usize> = annotators
        .keys()
        .enumerate()
        .map(|(coder, id)| (*id, coder))
        .collect();
    let mut items = Vec::with_capacity(by_item.len());
    let mut kinds = Vec::with_capacity(by_item.len());
    let mut count = 0;
    for (item_id, answers) in &by_item {
        let mut row: Vec<Option<Vec<u8>>> = vec![None; annotators.len()];
        for answer in answers {
            row[coder_of[&answer.annotator_id]] = Some(answer.human.answer.labels().to_vec());
            count += 1;
        }
        kinds.push((answers[0].human.direction, answers[0].human.step_length));
        items.push(AnnotatedOrdering {
            item_id: (*item_id).to_owned(),
            answers: row,
        });
    }
    let refs: Vec<AnnotatorRef> = annotators
        .iter()
        .map(|(id, name)| AnnotatorRef {
            id: *id,
            name: (*name).to_owned(),
        })
        .collect();
    let annotations =
        OrderingAnnotations::new(refs.iter().map(|a| a.name.clone()).collect(), items)?;
    Ok(OverlapSet {
        annotations,
        annotators: refs,
        kinds,
        answers: count,
    })
}

/// Alpha of one annotator pair, named.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AnnotatorPairAlpha {
    pub a: AnnotatorRef,
    pub b: AnnotatorRef,
    pub alpha: Option<f64>,
    /// Why alpha is undefined, when it is.
    pub reason: Option<String>,
    /// Units both annotators coded (items for `answer`, item slots otherwise).
    pub shared_units: usize,
}

/// Items, answers and all-agree items in one direction × step length cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct CellCount {
    pub direction: Direction,
    pub step_length: StepLength,
    pub items: usize,
    pub answers: usize,
    pub all_agree: usize,
}

/// Inter-annotator agreement on the overlapping items.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AgreementSection {
    pub encoding: OrderingEncoding,
    pub level: MeasurementLevel,
    pub annotators: Vec<AnnotatorRef>,
    pub items: usize,
    pub answers: usize,
    /// Alpha over all annotators with its percentile bootstrap interval over items.
    pub alpha: BootstrapAlpha,
    pub pairwise: Vec<AnnotatorPairAlpha>,
    pub mean_pairwise_alpha: Option<f64>,
    pub exact_agreement: ExactAgreement,
    /// Every direction × step length with at least one overlapping item, forward first.
    pub counts: Vec<CellCount>,
}

/// Agreement on `overlap`: `level` overrides the encoding's own level (`answer` allows only
/// nominal, its categories having no order).
pub fn agreement_section(
    overlap: &OverlapSet,
    encoding: OrderingEncoding,
    level: Option<MeasurementLevel>,
    config: &BootstrapConfig,
) -> Result<AgreementSection, AgreementUnavailable> {
    let level = level.unwrap_or(encoding.level());
    if encoding == OrderingEncoding::Answer && level != MeasurementLevel::Nominal {
        return Err(AgreementUnavailable::AnswerEncodingLevel(level));
    }
    let encoded = overlap.annotations.encode(encoding);
    let prepared = PreparedAlpha::with_items(&encoded.data, level, &encoded.unit_items)
        .map_err(BootstrapError::from)?;
    let alpha = if config.replicates == 0 {
        // No interval asked for: the estimate alone, with nothing resampled.
        BootstrapAlpha {
            estimate: prepared.estimate(),
            items: prepared.items(),
            replicates: 0,
            undefined_replicates: 0,
            confidence_level: config.confidence_level,
            ci_low: None,
            ci_high: None,
            replicate_mean: None,
            replicate_sd: None,
            seed: None,
            rng: None,
            replicate_alphas: Vec::new(),
        }
    } else {
        prepared.bootstrap(config)?
    };
    let pairs = pairwise_alphas(&encoded.data, level);
    let pairwise = pairs
        .iter()
        .map(|pair| AnnotatorPairAlpha {
            a: overlap.annotators[pair.coder_a].clone(),
            b: overlap.annotators[pair.coder_b].clone(),
            alpha: pair.result.alpha,
            reason: pair.result.reason.as_ref().map(ToString::to_string),
            shared_units: pair.result.units_used,
        })
        .collect();
    let mut cells: BTreeMap<(Direction, StepLength), CellCount> = BTreeMap::new();
    for (item, &(direction, step_length)) in overlap.annotations.items().iter().zip(&overlap.kinds)
    {
        let cell = cells.entry((direction, step_length)).or_insert(CellCount {
            direction,
            step_length,
            items: 0,
            answers: 0,
            all_agree: 0,
        });
        let answers: Vec<&Vec<u8>> = item.answers.iter().flatten().collect();
        cell.items += 1;
        cell.answers += answers.len();
        if answers.windows(2).all(|pair| pair[0] == pair[1]) {
            cell.all_agree += 1;
        }
    }
    Ok(AgreementSection {
        encoding,
        level,
        annotators: overlap.annotators.clone(),
        items: overlap.annotations.items().len(),
        answers: overlap.answers,
        alpha,
        mean_pairwise_alpha: mean_pairwise_alpha(&pairs),
        pairwise,
        exact_agreement: overlap.annotations.exact_agreement(),
        counts: cells.into_values().collect(),
    })
}

/// One published submission as the report uses it: its leaderboard row and per-item scores.
#[derive(Debug, Clone)]
pub struct SubmissionInput {
    pub row: LeaderboardRow,
    pub item_scores: Vec<ItemScore>,
}

/// A submission's pairwise accuracy on one item (`None` where it has none).
#[derive(Debug, Clone, PartialEq)]
pub struct ItemScore {
    pub item_id: String,
    pub direction: Direction,
    pub step_length: StepLength,
    pub pairwise_accuracy: Option<f64>,
}

/// The protocol round behind the agreement items, when there was one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct ProtocolStamp {
    pub items_per_cell: i64,
    pub seed: u64,
}

/// Everything a report is built from.
#[derive(Debug, Clone)]
pub struct ReportInputs {
    pub dataset: String,
    pub dataset_hash: String,
    pub dataset_items: usize,
    pub answers: Vec<AnnotatorAnswer>,
    /// Published submissions, in any order.
    pub submissions: Vec<SubmissionInput>,
    /// Two submission ids to compare with each other (a − b), chosen by the admin.
    pub chosen_pair: Option<(i64, i64)>,
    pub encoding: OrderingEncoding,
    pub level: Option<MeasurementLevel>,
    pub bootstrap: BootstrapConfig,
    pub protocol: Option<ProtocolStamp>,
}

/// What every exported file carries, so a number can be traced to the data and rules behind it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportStamp {
    pub dataset: String,
    pub dataset_hash: String,
    /// The report's rules and the metric version of its figures (the oldest among its rows).
    pub metric_version: String,
    /// The enact-hub build that computed the report.
    pub hub: HubBuild,
    pub encoding: OrderingEncoding,
    pub level: MeasurementLevel,
    pub bootstrap_seed: u64,
    pub bootstrap_replicates: usize,
    pub confidence_level: f64,
    pub bootstrap_rng: &'static str,
    /// Published submissions in the tables and comparisons, ascending.
    pub submission_ids: Vec<i64>,
    /// Annotators whose answers the report uses, ascending.
    pub annotator_ids: Vec<i64>,
    pub protocol: Option<ProtocolStamp>,
}

/// One side of a comparison.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ComparisonSide {
    pub label: String,
    /// `None` for the Human side.
    pub submission: Option<i64>,
}

/// Welch's test in one direction × step length.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CellComparison {
    pub direction: Direction,
    pub step_length: StepLength,
    pub welch: WelchComparison,
}

/// Per-item pairwise accuracy of `a` against `b` over the items both have a value for:
/// Δ = mean(a) − mean(b), Welch's two-sided test, overall and in each of the 16 cells.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    pub a: ComparisonSide,
    pub b: ComparisonSide,
    /// Items compared (both sides have a pairwise accuracy for each).
    pub items: usize,
    pub overall: WelchComparison,
    /// Forward 3..10, then inverse 3..10.
    pub cells: Vec<CellComparison>,
}

/// The report of one dataset.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AgreementReport {
    pub stamp: ReportStamp,
    /// `None` with `agreement_unavailable` set while no item has two answers.
    pub agreement: Option<AgreementSection>,
    pub agreement_unavailable: Option<String>,
    /// Table 1 / Table 3 rows: published submissions (best overall TA first), then Human.
    pub rows: Vec<LeaderboardRow>,
    pub comparisons: Vec<Comparison>,
}

/// Why a report could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReportError {
    #[error("submission {0} is not a published submission of this dataset")]
    UnknownSubmission(i64),
    #[error("answer of annotator {annotator} to item {item_id}: {reason}")]
    Unscorable {
        annotator: String,
        item_id: String,
        reason: String,
    },
    #[error(transparent)]
    Agreement(#[from] AgreementUnavailable),
    #[error("comparison {a} vs {b}: {reason}")]
    Comparison {
        a: String,
        b: String,
        reason: String,
    },
}

/// Pairwise accuracy per item: `(direction, step length, value)` by item id.
type ItemValues = BTreeMap<String, (Direction, StepLength, f64)>;

/// The label of the Human row and comparison side.
pub const HUMAN_LABEL: &str = "Human";

fn submission_label(row: &LeaderboardRow) -> String {
    match row.submission {
        Some(id) => format!("{} (#{id})", row.model),
        None => row.model.clone(),
    }
}

/// Builds the report: agreement on the overlapping items, the tables, and the comparisons.
pub fn build_report(inputs: &ReportInputs) -> Result<AgreementReport, ReportError> {
    // Human answers scored like model answers: the Human row, and per-item means for Welch.
    let mut entries = Vec::with_capacity(inputs.answers.len());
    for answer in &inputs.answers {
        let scored = human_entries(std::slice::from_ref(&answer.human)).map_err(|reason| {
            ReportError::Unscorable {
                annotator: answer.annotator.clone(),
                item_id: answer.item_id.clone(),
                reason,
            }
        })?;
        entries.extend(scored);
    }
    // An item answered by several annotators is one human observation: their mean.
    let human_items: ItemValues = mean_by_item(
        inputs
            .answers
            .iter()
            .map(|a| &a.human)
            .zip(entries.iter().map(|e| e.pairwise_accuracy)),
    );

    let mut submissions: Vec<&SubmissionInput> = inputs.submissions.iter().collect();
    submissions.sort_by_key(|s| s.row.submission);
    let mut rows: Vec<LeaderboardRow> = submissions.iter().map(|s| s.row.clone()).collect();
    crate::leaderboard::rank(&mut rows);
    if !entries.is_empty() {
        rows.push(LeaderboardRow::human(
            &PerformanceReport::from_entries(&entries),
            HumanCoverage::of_answers(
                inputs
                    .answers
                    .iter()
                    .map(|a| (a.annotator_id, a.item_id.as_str())),
                inputs.dataset_items,
            ),
            // Judged just now, under the current rules.
            MetricStamp::current(),
        ));
    }

    let values = |s: &SubmissionInput| -> ItemValues {
        s.item_scores
            .iter()
            .filter_map(|score| {
                score.pairwise_accuracy.map(|value| {
                    (
                        score.item_id.clone(),
                        (score.direction, score.step_length, value),
                    )
                })
            })
            .collect()
    };
    let side_of = |s: &SubmissionInput| ComparisonSide {
        label: submission_label(&s.row),
        submission: s.row.submission,
    };
    let human_side = ComparisonSide {
        label: HUMAN_LABEL.to_owned(),
        submission: None,
    };
    let mut comparisons = Vec::new();
    if !human_items.is_empty() {
        for s in &submissions {
            comparisons.push(compare(
                side_of(s),
                &values(s),
                human_side.clone(),
                &human_items,
            )?);
        }
    }
    if let Some((a, b)) = inputs.chosen_pair {
        let find = |id: i64| {
            submissions
                .iter()
                .find(|s| s.row.submission == Some(id))
                .ok_or(ReportError::UnknownSubmission(id))
        };
        let (a, b) = (find(a)?, find(b)?);
        comparisons.push(compare(side_of(a), &values(a), side_of(b), &values(b))?);
    }

    let (agreement, agreement_unavailable, level) = match overlapping_answers(&inputs.answers) {
        Ok(overlap) => {
            let section =
                agreement_section(&overlap, inputs.encoding, inputs.level, &inputs.bootstrap)?;
            let level = section.level;
            (Some(section), None, level)
        }
        Err(unavailable @ AgreementUnavailable::NoOverlap { .. }) => (
            None,
            Some(unavailable.to_string()),
            inputs.level.unwrap_or(inputs.encoding.level()),
        ),
        Err(other) => return Err(other.into()),
    };
    let annotator_ids: BTreeSet<i64> = inputs.answers.iter().map(|a| a.annotator_id).collect();
    Ok(AgreementReport {
        stamp: ReportStamp {
            dataset: inputs.dataset.clone(),
            dataset_hash: inputs.dataset_hash.clone(),
            metric_version: MetricStamp::oldest(rows.iter().map(|r| r.metric.metric_version))
                .with_report(REPORT_METRIC_VERSION),
            hub: THIS_BUILD,
            encoding: inputs.encoding,
            level,
            bootstrap_seed: inputs.bootstrap.seed,
            bootstrap_replicates: inputs.bootstrap.replicates,
            confidence_level: inputs.bootstrap.confidence_level,
            bootstrap_rng: crate::agreement::BOOTSTRAP_RNG,
            submission_ids: submissions
                .iter()
                .filter_map(|s| s.row.submission)
                .collect(),
            annotator_ids: annotator_ids.into_iter().collect(),
            protocol: inputs.protocol,
        },
        agreement,
        agreement_unavailable,
        rows,
        comparisons,
    })
}

/// Welch's test of `a` against `b` on the items both have, overall and per cell.
fn compare(
    a: ComparisonSide,
    a_items: &ItemValues,
    b: ComparisonSide,
    b_items: &ItemValues,
) -> Result<Comparison, ReportError> {
    let shared: Vec<(Direction, StepLength, f64, f64)> = a_items
        .iter()
        .filter_map(|(id, &(direction, length, va))| {
            b_items
                .get(id)
                .map(|&(_, _, vb)| (direction, length, va, vb))
        })
        .collect();
    let test = |keep: &dyn Fn(Direction, StepLength) -> bool| {
        let (xs, ys): (Vec<f64>, Vec<f64>) = shared
            .iter()
            .filter(|(d, l, _, _)| keep(*d, *l))
            .map(|&(_, _, x, y)| (x, y))
            .unzip();
        welch_t_test(&xs, &ys).map_err(|e| ReportError::Comparison {
            a: a.label.clone(),
            b: b.label.clone(),
            reason: e.to_string(),
        })
    };
    let overall = test(&|_, _| true)?;
    let mut cells = Vec::with_capacity(16);
    for direction in Direction::ALL {
        for step_length in StepLength::all() {
            cells.push(CellComparison {
                direction,
                step_length,
                welch: test(&|d, l| d == direction && l == step_length)?,
            });
        }
    }
    Ok(Comparison {
        items: shared.len(),
        a,
        b,
        overall,
        cells,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leaderboard::{AccuracyCell, DirectionColumns, RowSource};
    use crate::verifier::Permutation;

    fn l(n: usize) -> StepLength {
        StepLength::new(n).unwrap()
    }

    fn answer(annotator: i64, item: &str, labels: &[u8]) -> AnnotatorAnswer {
        AnnotatorAnswer {
            annotator_id: annotator,
            annotator: format!("a{annotator}"),
            item_id: item.to_owned(),
            kind: AssignmentKind::Primary,
            human: HumanAnswer {
                item_id: item.to_owned(),
                // Inverse items are scored by exact match here (no signatures): PA 1 or 0.
                direction: Direction::Inverse,
                step_length: l(4),
                ground_truth: Permutation::new(vec![3, 2, 1]).unwrap(),
                answer: Permutation::new(labels.to_vec()).unwrap(),
                signatures: None,
            },
        }
    }

    fn submission(id: i64, values: &[(&str, f64)]) -> SubmissionInput {
        let columns = DirectionColumns {
            total: AccuracyCell::default(),
            per_step: Vec::new(),
        };
        SubmissionInput {
            row: LeaderboardRow {
                rank: None,
                attempts: 1,
                account_submissions: None,
                standing: None,
                source: RowSource::Submission,
                provenance: None,
                run: None,
                submission: Some(id),
                model: format!("m{id}"),
                account: "team".into(),
                baseline: false,
                submitted_at: String::new(),
                overall: AccuracyCell::default(),
                overall_task_accuracy_ci: None,
                overall_pairwise_accuracy_ci: None,
                interval_resampling: None,
                item_intervals: None,
                forward: columns.clone(),
                inverse: columns,
                coverage: 1.0,
                parse_failure_rate: 0.0,
                human: None,
                metric: MetricStamp::current(),
            },
            item_scores: values
                .iter()
                .map(|(item, pa)| ItemScore {
                    item_id: (*item).to_owned(),
                    direction: Direction::Inverse,
                    step_length: l(4),
                    pairwise_accuracy: Some(*pa),
                })
                .collect(),
        }
    }

    fn inputs() -> ReportInputs {
        ReportInputs {
            dataset: "d".into(),
            dataset_hash: dataset_content_hash([("q1", "h1"), ("q2", "h2")]),
            dataset_items: 3,
            answers: vec![
                answer(1, "q1", &[3, 2, 1]),
                answer(2, "q1", &[3, 2, 1]),
                answer(1, "q2", &[3, 2, 1]),
                answer(2, "q2", &[1, 2, 3]),
                answer(1, "q3", &[3, 2, 1]),
            ],
            submissions: vec![
                submission(7, &[("q1", 0.5), ("q2", 0.0), ("q3", 1.0)]),
                submission(4, &[("q1", 1.0), ("q2", 0.5)]),
            ],
            chosen_pair: Some((7, 4)),
            encoding: OrderingEncoding::Answer,
            level: None,
            bootstrap: BootstrapConfig {
                replicates: 50,
                ..BootstrapConfig::default()
            },
            protocol: None,
        }
    }

    #[test]
    fn report_has_agreement_tables_and_item_paired_comparisons() {
        let report = build_report(&inputs()).unwrap();
        let agreement = report.agreement.as_ref().unwrap();
        assert_eq!(agreement.items, 2, "q3 has one answer");
        assert_eq!(agreement.answers, 4, "q1's and q2's");
        assert_eq!(agreement.exact_agreement.agreeing_items, 1);
        assert_eq!(agreement.pairwise.len(), 1);
        assert_eq!(agreement.pairwise[0].a.name, "a1");
        // One cell (inverse, 4 steps): q1 and q2 with two answers each, q1's alike.
        assert_eq!(agreement.counts.len(), 1);
        let counts = &agreement.counts[0];
        assert_eq!(
            (counts.direction, counts.step_length),
            (Direction::Inverse, l(4))
        );
        assert_eq!((counts.items, counts.answers, counts.all_agree), (2, 4, 1));
        assert_eq!(report.stamp.submission_ids, vec![4, 7]);
        assert_eq!(report.stamp.annotator_ids, vec![1, 2]);
        assert_eq!(report.rows.last().unwrap().source, RowSource::Human);
        // Two submissions vs Human, then the chosen pair.
        assert_eq!(report.comparisons.len(), 3);
        let vs_human = report
            .comparisons
            .iter()
            .find(|c| c.a.submission == Some(7) && c.b.submission.is_none())
            .unwrap();
        // Without signatures only an exact answer has a pairwise accuracy (1.0), so every
        // item's human mean is 1.0 here, q2's from its one exact answer.
        assert_eq!(vs_human.items, 3);
        assert_eq!(vs_human.overall.mean_b, Some(1.0));
        assert_eq!(vs_human.overall.mean_a, Some(0.5));
        let chosen = report.comparisons.last().unwrap();
        assert_eq!(
            (chosen.a.submission, chosen.b.submission),
            (Some(7), Some(4))
        );
        assert_eq!(chosen.items, 2, "only items both submissions scored");
        assert_eq!(chosen.overall.delta, Some(0.25 - 0.75));
        let cell = chosen
            .cells
            .iter()
            .find(|c| c.direction == Direction::Inverse && c.step_length == l(4))
            .unwrap();
        assert_eq!(cell.welch.n_a, 2);
        assert_eq!(chosen.cells.len(), 16);
        // A cell holds the items of its direction and its step length, not of either.
        for (direction, step_length) in [(Direction::Inverse, l(3)), (Direction::Forward, l(4))] {
            let other = chosen
                .cells
                .iter()
                .find(|c| c.direction == direction && c.step_length == step_length)
                .unwrap();
            assert_eq!(other.welch.n_a, 0, "{direction} {step_length}");
        }
    }

    /// The interval is resampled when replicates are asked for, and the estimate stands alone
    /// (no interval, nothing drawn) when none are.
    #[test]
    fn the_agreement_interval_is_resampled_only_when_replicates_are_asked_for() {
        let with = |replicates| ReportInputs {
            bootstrap: BootstrapConfig {
                replicates,
                ..BootstrapConfig::default()
            },
            ..inputs()
        };
        let alpha = |replicates| {
            build_report(&with(replicates))
                .unwrap()
                .agreement
                .unwrap()
                .alpha
        };
        let resampled = alpha(50);
        assert_eq!(resampled.replicates, 50);
        assert!(resampled.replicate_mean.is_some(), "{resampled:?}");
        let alone = alpha(0);
        assert_eq!(alone.replicates, 0);
        assert_eq!((alone.ci_low, alone.ci_high), (None, None));
        assert_eq!(alone.replicate_mean, None);
        assert_eq!(alone.estimate, resampled.estimate);
    }

    #[test]
    fn only_the_answer_encoding_is_held_to_the_nominal_level() {
        let with = |encoding, level| ReportInputs {
            encoding,
            level: Some(level),
            ..inputs()
        };
        // Whole answers are unordered categories: no ordinal or interval reading of them.
        for level in [MeasurementLevel::Ordinal, MeasurementLevel::Interval] {
            assert!(matches!(
                build_report(&with(OrderingEncoding::Answer, level)),
                Err(ReportError::Agreement(
                    AgreementUnavailable::AnswerEncodingLevel(l)
                )) if l == level
            ));
        }
        let nominal = build_report(&with(OrderingEncoding::Answer, MeasurementLevel::Nominal));
        assert_eq!(
            nominal.unwrap().agreement.unwrap().level,
            MeasurementLevel::Nominal
        );
        // Positions and ranks are ordered: any level is theirs to ask for.
        for encoding in [OrderingEncoding::Position, OrderingEncoding::Rank] {
            let report = build_report(&with(encoding, MeasurementLevel::Interval)).unwrap();
            assert_eq!(
                report.agreement.unwrap().level,
                MeasurementLevel::Interval,
                "{encoding}"
            );
        }
    }

    #[test]
    fn an_item_counts_as_all_agreeing_only_when_every_answer_is_alike() {
        let mut alike = inputs();
        // q2's second answer now matches its first: both overlapping items agree.
        alike.answers[3] = answer(2, "q2", &[3, 2, 1]);
        let report = build_report(&alike).unwrap();
        let counts = &report.agreement.as_ref().unwrap().counts[0];
        assert_eq!((counts.items, counts.all_agree), (2, 2));
        // Three answers where the first and last agree but the middle one does not.
        let mut split = inputs();
        split.answers[3] = answer(2, "q2", &[3, 2, 1]);
        split.answers.push(answer(3, "q2", &[1, 2, 3]));
        split.answers.push(answer(4, "q2", &[3, 2, 1]));
        let report = build_report(&split).unwrap();
        let counts = &report.agreement.as_ref().unwrap().counts[0];
        assert_eq!((counts.items, counts.answers, counts.all_agree), (2, 6, 1));
    }

    #[test]
    fn missing_overlap_and_unknown_submissions() {
        let mut only_one = inputs();
        only_one.answers.retain(|a| a.annotator_id == 1);
        let report = build_report(&only_one).unwrap();
        assert!(report.agreement.is_none());
        assert!(
            report
                .agreement_unavailable
                .unwrap()
                .contains("no item has answers from two or more annotators")
        );
        let mut unknown = inputs();
        unknown.chosen_pair = Some((7, 99));
        assert_eq!(
            build_report(&unknown).unwrap_err(),
            ReportError::UnknownSubmission(99)
        );
    }

    #[test]
    fn dataset_hash_ignores_order() {
        assert_eq!(
            dataset_content_hash([("b", "2"), ("a", "1")]),
            dataset_content_hash([("a", "1"), ("b", "2")])
        );
        assert_ne!(
            dataset_content_hash([("a", "1")]),
            dataset_content_hash([("a", "2")])
        );
    }

    #[test]
    fn error_files_hold_each_row_and_are_stamped() {
        let report = build_report(&inputs()).unwrap();
        let analysis = crate::error_analysis::analyse(std::iter::empty());
        let rows = [
            export::ErrorRow {
                label: "model-a".into(),
                submission: Some(7),
                analysis: &analysis,
            },
            export::ErrorRow {
                label: "Human".into(),
                submission: None,
                analysis: &analysis,
            },
        ];
        let files = export::error_files(&report.stamp, &rows).unwrap();
        let names: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["errors.json", "errors.csv"]);
        let json: serde_json::Value = serde_json::from_slice(&files[0].bytes).unwrap();
        let labels: Vec<(&str, Option<i64>)> = json["rows"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| (r["label"].as_str().unwrap(), r["submission"].as_i64()))
            .collect();
        assert_eq!(labels, [("model-a", Some(7)), ("Human", None)]);
        let csv = String::from_utf8(files[1].bytes.clone()).unwrap();
        assert!(
            csv.contains("\nmodel-a,") && csv.contains("\nHuman,"),
            "{csv}"
        );
        for file in &files {
            let text = String::from_utf8(file.bytes.clone()).unwrap();
            assert!(text.contains(&report.stamp.dataset_hash), "{}", file.name);
        }
    }

    #[test]
    fn bundle_files_are_stamped() {
        let report = build_report(&inputs()).unwrap();
        let files = export::bundle_files(&report).unwrap();
        let names: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "report.json",
                "agreement.csv",
                "agreement_counts.csv",
                "accuracy.csv",
                "comparisons.csv",
                "report.md",
                "tables.tex",
                "heatmap.svg",
                "task_accuracy.svg"
            ]
        );
        for file in &files {
            let text = String::from_utf8(file.bytes.clone()).unwrap();
            assert!(text.contains(&report.stamp.dataset_hash), "{}", file.name);
            assert!(text.contains(REPORT_METRIC_VERSION), "{}", file.name);
            // The JSON holds the stamp as an object, the other files as `hub:` lines.
            assert!(
                text.contains(crate::version::VERSION) && text.contains(crate::version::COMMIT),
                "{}",
                file.name
            );
        }
        // The agreement table: alpha over everyone, then each pair of annotators.
        let agreement_csv = String::from_utf8(files[1].bytes.clone()).unwrap();
        assert!(
            agreement_csv.contains("\nall annotators,"),
            "{agreement_csv}"
        );
        assert!(agreement_csv.contains("\na1,a2,"), "{agreement_csv}");
        // The comparisons: each row's Welch figures, here the chosen pair over both items they
        // scored (m7: 0.5 and 0.0; m4: 1.0 and 0.5).
        let comparisons_csv = String::from_utf8(files[4].bytes.clone()).unwrap();
        assert!(
            comparisons_csv.contains(",all,all,2,0.2500,0.7500,-0.5000,"),
            "{comparisons_csv}"
        );
        let tex = String::from_utf8(files[6].bytes.clone()).unwrap();
        assert!(tex.contains("\\toprule") && tex.contains("Human Performance"));
        // Only the Human row is bold: a model's row is printed as it is.
        let model_rows: Vec<&str> = tex
            .lines()
            .filter(|l| l.starts_with("m4 &") || l.starts_with("m7 &"))
            .collect();
        assert_eq!(model_rows.len(), 4, "{tex}");
        assert!(model_rows.iter().all(|l| !l.contains("\\textbf")), "{tex}");
        let human_rows: Vec<&str> = tex
            .lines()
            .filter(|l| l.starts_with("\\textbf{Human Performance} &"))
            .collect();
        assert_eq!(human_rows.len(), 2, "{tex}");
        // The chosen pair's overall Welch row, in both table formats.
        let chosen = report.comparisons.last().unwrap();
        let delta = format!("{:.4}", chosen.overall.delta.unwrap());
        let md = String::from_utf8(files[5].bytes.clone()).unwrap();
        let md_row = format!("| {} | {} | 2 | {delta} |", chosen.a.label, chosen.b.label);
        assert!(md.contains(&md_row), "{md}");
        let tex_label = |label: &str| label.replace('#', "\\#");
        let tex_row = format!(
            "{} & {} & 2 & {delta} &",
            tex_label(&chosen.a.label),
            tex_label(&chosen.b.label)
        );
        assert!(tex.contains(&tex_row), "{tex}");
        let svg = String::from_utf8(files[7].bytes.clone()).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("m7 (#7) − Human"));
        let archive = crate::bundle::tar_archive("bundle", &files).unwrap();
        let mut reader = tar::Archive::new(archive.as_slice());
        let entries: Vec<String> = reader
            .entries()
            .unwrap()
            .map(|e| e.unwrap().path().unwrap().display().to_string())
            .collect();
        assert_eq!(entries[0], "bundle/report.json");
        assert_eq!(entries.len(), files.len());
    }

    /// Each step length's figure sits in its own column, and a Human figure on enough answers
    /// (exactly the minimum here) is not marked.
    #[test]
    fn the_markdown_export_puts_each_cell_in_its_column() {
        let report = build_report(&inputs()).unwrap();
        let markdown = export::markdown(&report);
        let human = markdown
            .lines()
            .find(|line| line.starts_with("| Human |"))
            .expect("a Human row");
        let cells: Vec<&str> = human
            .trim_matches('|')
            .split('|')
            .map(str::trim)
            .skip(1)
            .collect();
        assert_eq!(cells.len(), 16, "{human}");
        // Five answers, every one inverse with 4 images, four of them exact: column I4 only.
        let filled: Vec<(usize, &str)> = cells
            .iter()
            .enumerate()
            .filter(|(_, c)| !c.is_empty())
            .map(|(i, c)| (i, *c))
            .collect();
        assert_eq!(filled, [(8 + 1, "80.00")], "{human}");
        assert!(!human.contains('†'), "{human}");
    }

    /// The Markdown export names each row (a model, or Human) with submitters' text escaped.
    #[test]
    fn the_markdown_export_names_rows_with_their_text_escaped() {
        let mut inputs = inputs();
        // A literal "&lt;" must stay text: '&' is escaped too.
        inputs.submissions[0].row.model = "<b>m7</b> | *best* &lt;".to_owned();
        // Four human answers remain: one fewer than a Human figure needs.
        inputs.answers.pop();
        let report = build_report(&inputs).unwrap();
        let markdown = export::markdown(&report);
        assert!(
            markdown.contains("| &lt;b&gt;m7&lt;/b&gt; \\| \\*best\\* &amp;lt; |"),
            "{markdown}"
        );
        assert!(markdown.contains("| Human |"), "{markdown}");
        assert!(!markdown.contains("<b>"), "{markdown}");
        // Human cells resting on fewer answers than a figure needs are marked, model cells not.
        let human = markdown
            .lines()
            .find(|line| line.starts_with("| Human |"))
            .expect("a Human row");
        assert!(human.contains('†'), "{human}");
        let model = markdown
            .lines()
            .find(|line| line.starts_with("| &lt;b&gt;"))
            .expect("the model's row");
        assert!(!model.contains('†'), "{model}");
    }
}
