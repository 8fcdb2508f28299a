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

use crate::agreement::{
    AnnotatedOrdering, BootstrapAlpha, BootstrapConfig, BootstrapError, ExactAgreement,
    MeasurementLevel, OrderingAnnotations, OrderingEncoding, OrderingError, PreparedAlpha,
    WelchComparison, mean_pairwise_alpha, pairwise_alphas, welch_t_test,
};
use crate::agreement_protocol::AssignmentKind;
use crate::annotation::{HumanAnswer, human_entries};
use crate::dataset::{Direction, StepLength};
use crate::leaderboard::LeaderboardRow;
use crate::verifier::PerformanceReport;

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
