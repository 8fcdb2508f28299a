//! Agreement among annotators who answered ordering items: the named encodings that turn
//! permutation answers into reliability data, the exact-agreement rate, and the combined report.

use std::collections::HashSet;
use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::agreement::alpha::{
    MeasurementLevel, PairwiseAlpha, PreparedAlpha, mean_pairwise_alpha, pairwise_alphas,
};
use crate::agreement::bootstrap::{BootstrapAlpha, BootstrapConfig, BootstrapError};
use crate::agreement::reliability::{ReliabilityData, UnitItems};

/// How a permutation answer becomes reliability data. The choice moves alpha a lot (whole
/// answers as categories give far lower values than per-slot ordinal data), so every report
/// names the encoding it used.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OrderingEncoding {
    /// One unit per item; the whole permutation is one nominal category.
    Answer,
    /// One unit per (item, position); the value is the label placed at that position, ordinal.
    Position,
    /// One unit per (item, label); the value is the position given to that label, ordinal.
    Rank,
}

impl OrderingEncoding {
    pub const ALL: [OrderingEncoding; 3] = [
        OrderingEncoding::Answer,
        OrderingEncoding::Position,
        OrderingEncoding::Rank,
    ];

    pub fn name(self) -> &'static str {
        match self {
            OrderingEncoding::Answer => "answer",
            OrderingEncoding::Position => "position",
            OrderingEncoding::Rank => "rank",
        }
    }

    /// The level alpha is computed at for this encoding. Whole answers have no order among
    /// them, so `answer` is nominal whatever a paper calls it.
    pub fn level(self) -> MeasurementLevel {
        match self {
            OrderingEncoding::Answer => MeasurementLevel::Nominal,
            OrderingEncoding::Position | OrderingEncoding::Rank => MeasurementLevel::Ordinal,
        }
    }
}

/// ENACT quirk: the paper reports "ordinal" alpha = 0.83 without saying how an answer became a
/// value. Its figures (0.83 next to 76.7 % three-way exact agreement, pairwise alphas close to
/// the overall value) fit whole answers as categories and not per-slot ordinal values, which
/// come out near 0.94–0.99 for annotators this accurate. This is the default encoding, so a
/// figure from this service is comparable with the paper's; `rank` is the encoding to pick for
/// an ordinal reading, since positions are ordered while frame labels are shuffled indices.
pub const PAPER_COMPARABLE_ENCODING: OrderingEncoding = OrderingEncoding::Answer;

impl Default for OrderingEncoding {
    fn default() -> Self {
        PAPER_COMPARABLE_ENCODING
    }
}

impl fmt::Display for OrderingEncoding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An encoding name that is not one of answer, position, rank.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown ordering encoding {0:?}: expected answer, position or rank")]
pub struct UnknownOrderingEncoding(pub String);

impl FromStr for OrderingEncoding {
    type Err = UnknownOrderingEncoding;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        OrderingEncoding::ALL
            .into_iter()
            .find(|encoding| encoding.name() == text)
            .ok_or_else(|| UnknownOrderingEncoding(text.to_owned()))
    }
}

/// One ordering item and every annotator's answer to it (`None` where an annotator gave none).
/// An answer lists the labels 1..=k in the order the annotator chose.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct AnnotatedOrdering {
    pub item_id: String,
    pub answers: Vec<Option<Vec<u8>>>,
}

/// Why a set of annotated orderings was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum OrderingError {
    #[error("agreement needs at least one annotator")]
    NoAnnotators,
    #[error("item {item_id}: {found} answer slots for {expected} annotators")]
    AnswerCount {
        item_id: String,
        found: usize,
        expected: usize,
    },
    #[error("item {item_id} appears more than once")]
    DuplicateItem { item_id: String },
    #[error("item {item_id}, annotator {annotator}: {answer:?} is not a permutation of 1..={k}")]
    NotAPermutation {
        item_id: String,
        annotator: String,
        answer: Vec<u8>,
        k: usize,
    },
    #[error(
        "item {item_id}, annotator {annotator}: answer has {found} labels \
         but annotator {first_annotator} gave {expected}"
    )]
    LengthMismatch {
        item_id: String,
        annotator: String,
        found: usize,
        first_annotator: String,
        expected: usize,
    },
}

/// Validated orderings: every answer is a permutation of 1..=k, and all answers to one item
/// have the same k.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct OrderingAnnotations {
    annotators: Vec<String>,
    items: Vec<AnnotatedOrdering>,
}

impl OrderingAnnotations {
    pub fn new(
        annotators: Vec<String>,
        items: Vec<AnnotatedOrdering>,
    ) -> Result<Self, OrderingError> {
        if annotators.is_empty() {
            return Err(OrderingError::NoAnnotators);
        }
        let mut seen: HashSet<&str> = HashSet::new();
        for item in &items {
            if !seen.insert(&item.item_id) {
                return Err(OrderingError::DuplicateItem {
                    item_id: item.item_id.clone(),
                });
            }
            if item.answers.len() != annotators.len() {
                return Err(OrderingError::AnswerCount {
                    item_id: item.item_id.clone(),
                    found: item.answers.len(),
                    expected: annotators.len(),
                });
            }
            let mut first: Option<(usize, usize)> = None;
            for (annotator, answer) in item.answers.iter().enumerate() {
                let Some(answer) = answer else { continue };
                if !is_permutation(answer) {
                    return Err(OrderingError::NotAPermutation {
                        item_id: item.item_id.clone(),
                        annotator: annotators[annotator].clone(),
                        answer: answer.clone(),
                        k: answer.len(),
                    });
                }
                match first {
                    None => first = Some((annotator, answer.len())),
                    Some((first_annotator, expected)) if expected != answer.len() => {
                        return Err(OrderingError::LengthMismatch {
                            item_id: item.item_id.clone(),
                            annotator: annotators[annotator].clone(),
                            found: answer.len(),
                            first_annotator: annotators[first_annotator].clone(),
                            expected,
                        });
                    }
                    Some(_) => {}
                }
            }
        }
        Ok(Self { annotators, items })
    }

    pub fn annotators(&self) -> &[String] {
        &self.annotators
    }

    pub fn items(&self) -> &[AnnotatedOrdering] {
        &self.items
    }

    /// Reliability data for `encoding`, annotators as coders. Every item is kept, even one
    /// nobody answered, so the bootstrap draws from the full item set.
    pub fn encode(&self, encoding: OrderingEncoding) -> EncodedOrderings {
        let coders = self.annotators.len();
        let mut cells: Vec<Option<f64>> = Vec::new();
        let mut units: Vec<OrderingUnit> = Vec::new();
        match encoding {
            OrderingEncoding::Answer => {
                // Category numbers follow the sorted distinct answers, so they do not depend
                // on item order; nominal alpha ignores the numbers anyway.
                let mut categories: Vec<&[u8]> = self
                    .items
                    .iter()
                    .flat_map(|item| item.answers.iter().flatten().map(Vec::as_slice))
                    .collect();
                categories.sort_unstable();
                categories.dedup();
                for (item_index, item) in self.items.iter().enumerate() {
                    units.push(OrderingUnit {
                        item: item_index,
                        slot: UnitSlot::WholeAnswer,
                    });
                    cells.extend(item.answers.iter().map(|answer| {
                        answer.as_deref().map(|answer| {
                            (categories.partition_point(|&probe| probe < answer) + 1) as f64
                        })
                    }));
                }
            }
            OrderingEncoding::Position | OrderingEncoding::Rank => {
                for (item_index, item) in self.items.iter().enumerate() {
                    let k = item
                        .answers
                        .iter()
                        .flatten()
                        .map(Vec::len)
                        .next()
                        .unwrap_or(0);
                    // ranks[a][label − 1] = 1-based position annotator a gave to `label`.
                    let ranks: Vec<Option<Vec<u8>>> = item
                        .answers
                        .iter()
                        .map(|answer| answer.as_deref().map(ranks_of))
                        .collect();
                    for slot in 0..k {
                        let slot_number = (slot + 1) as u8;
                        units.push(OrderingUnit {
                            item: item_index,
                            slot: match encoding {
                                OrderingEncoding::Rank => UnitSlot::Label(slot_number),
                                _ => UnitSlot::Position(slot_number),
                            },
                        });
                        for annotator in 0..coders {
                            let value = match encoding {
                                OrderingEncoding::Rank => ranks[annotator]
                                    .as_ref()
                                    .map(|ranks| f64::from(ranks[slot])),
                                _ => item.answers[annotator]
                                    .as_ref()
                                    .map(|answer| f64::from(answer[slot])),
                            };
                            cells.push(value);
                        }
                    }
                }
            }
        }
        let item_of_unit = units.iter().map(|unit| unit.item).collect();
        let unit_items = UnitItems::new(item_of_unit, self.items.len())
            .expect("every unit was created from an item index below the item count");
        EncodedOrderings {
            encoding,
            level: encoding.level(),
            data: ReliabilityData::from_checked_unit_major(coders, units.len(), cells),
            units,
            unit_items,
        }
    }

    /// Among items answered by two or more annotators, how many got the identical permutation
    /// from every annotator who answered.
    pub fn exact_agreement(&self) -> ExactAgreement {
        let mut compared_items = 0;
        let mut agreeing_items = 0;
        for item in &self.items {
            let mut answers = item.answers.iter().flatten();
            let Some(first) = answers.next() else {
                continue;
            };
            let others: Vec<&Vec<u8>> = answers.collect();
            if others.is_empty() {
                continue;
            }
            compared_items += 1;
            if others.iter().all(|answer| *answer == first) {
                agreeing_items += 1;
            }
        }
        ExactAgreement {
            agreeing_items,
            compared_items,
            rate: (compared_items > 0).then(|| agreeing_items as f64 / compared_items as f64),
        }
    }
}

fn is_permutation(answer: &[u8]) -> bool {
    let k = answer.len();
    if k == 0 {
        return false;
    }
    let mut seen = vec![false; k];
    answer.iter().all(|&label| {
        let label = usize::from(label);
        (1..=k).contains(&label) && !std::mem::replace(&mut seen[label - 1], true)
    })
}

/// For a permutation of 1..=k, the 1-based position of each label.
fn ranks_of(answer: &[u8]) -> Vec<u8> {
    let mut ranks = vec![0u8; answer.len()];
    for (position, &label) in answer.iter().enumerate() {
        ranks[usize::from(label) - 1] = (position + 1) as u8;
    }
    ranks
}

/// What one unit of encoded orderings stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(tag = "slot", content = "index", rename_all = "snake_case")]
pub enum UnitSlot {
    /// The whole answer (encoding `answer`).
    WholeAnswer,
    /// The 1-based position in the answer (encoding `position`).
    Position(u8),
    /// The label 1..=k whose position is recorded (encoding `rank`).
    Label(u8),
}

/// A unit of encoded orderings: an index into the annotated items and the slot within it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct OrderingUnit {
    pub item: usize,
    pub slot: UnitSlot,
}

/// Orderings as reliability data, with what each unit stands for and which item it belongs to.
#[derive(Debug, Clone, PartialEq)]
pub struct EncodedOrderings {
    pub encoding: OrderingEncoding,
    pub level: MeasurementLevel,
    pub data: ReliabilityData,
    /// `units[u]` describes unit `u` of `data`.
    pub units: Vec<OrderingUnit>,
    pub unit_items: UnitItems,
}

/// The share of items on which every annotator who answered gave the same permutation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ExactAgreement {
    pub agreeing_items: usize,
    /// Items with answers from two or more annotators.
    pub compared_items: usize,
    /// `None` when no item has two answers.
    pub rate: Option<f64>,
}

/// Everything reported about agreement on a set of orderings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OrderingAgreement {
    pub encoding: OrderingEncoding,
    pub level: MeasurementLevel,
    pub annotators: Vec<String>,
    /// Alpha over all annotators with its bootstrap interval over items.
    pub alpha: BootstrapAlpha,
    pub pairwise: Vec<PairwiseAlpha>,
    pub mean_pairwise_alpha: Option<f64>,
    pub exact_agreement: ExactAgreement,
}

/// Alpha with an item bootstrap, pairwise alphas and exact agreement for `annotations`.
pub fn ordering_agreement(
    annotations: &OrderingAnnotations,
    encoding: OrderingEncoding,
    config: &BootstrapConfig,
) -> Result<OrderingAgreement, BootstrapError> {
    let encoded = annotations.encode(encoding);
    let alpha = PreparedAlpha::with_items(&encoded.data, encoded.level, &encoded.unit_items)?
        .bootstrap(config)?;
    let pairwise = pairwise_alphas(&encoded.data, encoded.level);
    Ok(OrderingAgreement {
        encoding,
        level: encoded.level,
        annotators: annotations.annotators.clone(),
        alpha,
        mean_pairwise_alpha: mean_pairwise_alpha(&pairwise),
        pairwise,
        exact_agreement: annotations.exact_agreement(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::agreement::alpha::krippendorff_alpha;

    fn item(id: &str, answers: &[Option<&[u8]>]) -> AnnotatedOrdering {
        AnnotatedOrdering {
            item_id: id.to_owned(),
            answers: answers
                .iter()
                .map(|answer| answer.map(<[u8]>::to_vec))
                .collect(),
        }
    }

    fn names(count: usize) -> Vec<String> {
        (0..count)
            .map(|index| format!("annotator-{index}"))
            .collect()
    }

    /// Three annotators on three items of lengths 3, 2 and 4.
    fn tiny() -> OrderingAnnotations {
        OrderingAnnotations::new(
            names(3),
            vec![
                item(
                    "q1",
                    &[Some(&[2, 1, 3]), Some(&[2, 1, 3]), Some(&[1, 2, 3])],
                ),
                item("q2", &[Some(&[2, 1]), Some(&[2, 1]), Some(&[2, 1])]),
                item(
                    "q3",
                    &[
                        Some(&[3, 1, 4, 2]),
                        Some(&[3, 4, 1, 2]),
                        Some(&[3, 1, 4, 2]),
                    ],
                ),
            ],
        )
        .unwrap()
    }

    fn rows(encoded: &EncodedOrderings) -> Vec<Vec<Option<f64>>> {
        encoded.data.coder_rows()
    }

    fn some(values: &[f64]) -> Vec<Option<f64>> {
        values.iter().copied().map(Some).collect()
    }

    #[test]
    fn an_encoding_is_written_as_its_name_and_read_back() {
        for (encoding, name) in [
            (OrderingEncoding::Answer, "answer"),
            (OrderingEncoding::Position, "position"),
            (OrderingEncoding::Rank, "rank"),
        ] {
            assert_eq!(encoding.to_string(), name);
            assert_eq!(name.parse::<OrderingEncoding>(), Ok(encoding));
        }
    }

    #[test]
    fn position_encoding_lists_labels_by_position() {
        let encoded = tiny().encode(OrderingEncoding::Position);
        assert_eq!(encoded.level, MeasurementLevel::Ordinal);
        assert_eq!(
            rows(&encoded)[1],
            some(&[2.0, 1.0, 3.0, 2.0, 1.0, 3.0, 4.0, 1.0, 2.0])
        );
        assert_eq!(
            encoded.unit_items.item_of_unit(),
            &[0, 0, 0, 1, 1, 2, 2, 2, 2]
        );
        assert_eq!(
            encoded.units[4],
            OrderingUnit {
                item: 1,
                slot: UnitSlot::Position(2)
            }
        );
    }

    #[test]
    fn rank_encoding_lists_positions_by_label() {
        let encoded = tiny().encode(OrderingEncoding::Rank);
        // [3, 4, 1, 2]: label 1 at position 3, label 2 at 4, label 3 at 1, label 4 at 2.
        assert_eq!(
            rows(&encoded)[1],
            some(&[2.0, 1.0, 3.0, 2.0, 1.0, 3.0, 4.0, 1.0, 2.0])
        );
        assert_eq!(
            rows(&encoded)[0],
            some(&[2.0, 1.0, 3.0, 2.0, 1.0, 2.0, 4.0, 1.0, 3.0])
        );
        assert_eq!(encoded.units[8].slot, UnitSlot::Label(4));
    }

    #[test]
    fn answer_encoding_gives_one_nominal_unit_per_item() {
        let encoded = tiny().encode(OrderingEncoding::Answer);
        assert_eq!(encoded.level, MeasurementLevel::Nominal);
        assert_eq!(encoded.data.units(), 3);
        let rows = rows(&encoded);
        assert_eq!(rows[0][0], rows[1][0]);
        assert_ne!(rows[0][0], rows[2][0]);
        assert_ne!(rows[0][2], rows[1][2]);
        // n = 9; Σ o_cc = 1 (q1) + 3 (q2) + 1 (q3) = 5; marginals 2, 1, 3, 2, 1 give
        // Σ n_c (n_c − 1) = 10; alpha = (8 · 5 − 10) / (9 · 8 − 10) = 30/62 = 15/31.
        let alpha = krippendorff_alpha(&encoded.data, encoded.level)
            .alpha
            .unwrap();
        assert!((alpha - 15.0 / 31.0).abs() < 1e-12);
    }

    #[test]
    fn missing_answers_and_unanswered_items() {
        let annotations = OrderingAnnotations::new(
            names(2),
            vec![
                item("q1", &[Some(&[1, 2]), None]),
                item("q2", &[None, None]),
                item("q3", &[Some(&[2, 1]), Some(&[2, 1])]),
            ],
        )
        .unwrap();
        assert_eq!(annotations.annotators(), names(2));
        assert_eq!(
            annotations
                .items()
                .iter()
                .map(|item| item.item_id.as_str())
                .collect::<Vec<_>>(),
            ["q1", "q2", "q3"]
        );
        let position = annotations.encode(OrderingEncoding::Position);
        // q2 has no answer, so no known length and no units, but it is still an item.
        assert_eq!(position.data.units(), 4);
        assert_eq!(position.unit_items.items(), 3);
        assert_eq!(position.data.value(1, 0), None);
        let answer = annotations.encode(OrderingEncoding::Answer);
        assert_eq!(answer.data.units(), 3);
        let agreement = annotations.exact_agreement();
        assert_eq!((agreement.agreeing_items, agreement.compared_items), (1, 1));
    }

    #[test]
    fn exact_agreement_counts_identical_permutations() {
        let agreement = tiny().exact_agreement();
        assert_eq!(agreement.agreeing_items, 1);
        assert_eq!(agreement.compared_items, 3);
        assert_eq!(agreement.rate, Some(1.0 / 3.0));
        let lonely =
            OrderingAnnotations::new(names(2), vec![item("q", &[Some(&[1]), None])]).unwrap();
        assert_eq!(lonely.exact_agreement().rate, None);
    }

    #[test]
    fn invalid_answers_are_refused_with_their_item() {
        let not_permutation =
            OrderingAnnotations::new(names(2), vec![item("q7", &[Some(&[1, 1]), None])])
                .unwrap_err();
        assert_eq!(
            not_permutation.to_string(),
            "item q7, annotator annotator-0: [1, 1] is not a permutation of 1..=2"
        );
        let zero_label =
            OrderingAnnotations::new(names(1), vec![item("q", &[Some(&[0, 1])])]).unwrap_err();
        assert!(matches!(zero_label, OrderingError::NotAPermutation { .. }));
        let empty = OrderingAnnotations::new(names(1), vec![item("q", &[Some(&[])])]);
        assert!(empty.is_err());
        let lengths = OrderingAnnotations::new(
            names(2),
            vec![item("q8", &[Some(&[1, 2]), Some(&[1, 2, 3])])],
        )
        .unwrap_err();
        assert!(matches!(
            lengths,
            OrderingError::LengthMismatch {
                found: 3,
                expected: 2,
                ..
            }
        ));
        let count = OrderingAnnotations::new(names(2), vec![item("q9", &[None])]).unwrap_err();
        assert!(
            count
                .to_string()
                .contains("item q9: 1 answer slots for 2 annotators")
        );
        let twice =
            OrderingAnnotations::new(names(1), vec![item("q", &[None]), item("q", &[None])])
                .unwrap_err();
        assert_eq!(
            twice,
            OrderingError::DuplicateItem {
                item_id: "q".into()
            }
        );
        assert_eq!(
            OrderingAnnotations::new(vec![], vec![]).unwrap_err(),
            OrderingError::NoAnnotators
        );
    }

    #[test]
    fn encodings_parse_and_default() {
        for encoding in OrderingEncoding::ALL {
            assert_eq!(
                encoding.name().parse::<OrderingEncoding>().unwrap(),
                encoding
            );
        }
        assert!("permutation".parse::<OrderingEncoding>().is_err());
        assert_eq!(OrderingEncoding::default(), OrderingEncoding::Answer);
    }

    #[test]
    fn report_names_encoding_and_bootstraps_items() {
        let report = ordering_agreement(
            &tiny(),
            OrderingEncoding::Position,
            &BootstrapConfig {
                replicates: 100,
                ..BootstrapConfig::default()
            },
        )
        .unwrap();
        assert_eq!(report.encoding, OrderingEncoding::Position);
        assert_eq!(report.alpha.items, 3);
        assert_eq!(report.alpha.estimate.units, 9);
        assert_eq!(report.pairwise.len(), 3);
        assert_eq!(report.exact_agreement.agreeing_items, 1);
        let json = serde_json::to_value(&report).unwrap();
        assert_eq!(json["encoding"], "position");
        assert_eq!(json["level"], "ordinal");
        // Stored reports read back unchanged, except the per-replicate alphas left out of JSON.
        let read_back: OrderingAgreement = serde_json::from_value(json).unwrap();
        assert!(read_back.alpha.replicate_alphas.is_empty());
        assert_eq!(read_back.alpha.ci_low, report.alpha.ci_low);
        assert_eq!(read_back.pairwise, report.pairwise);
    }
}
