//! The paper's cross-annotation protocol (ENACT appendix B.1.2), without I/O: from each
//! annotator's completed primary answers, draw k items per direction × step length and give each
//! to every other annotator, so the sampled items end up with one answer per annotator.

use std::collections::BTreeMap;

use rand::SeedableRng;
use rand::seq::IndexedRandom;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::dataset::{Direction, StepLength};

/// The paper samples five items per annotator, direction and step length.
pub const DEFAULT_ITEMS_PER_CELL: usize = 5;
/// Seed used when the admin gives none; recorded with the round either way.
pub const DEFAULT_PROTOCOL_SEED: u64 = 0;

/// Why an annotator has an item in their queue. Only admins and reports see this: the
/// annotator's pages are the same for both kinds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AssignmentKind {
    /// Dealt out by a split or an id list: the annotator's own share of the dataset.
    Primary,
    /// Given by the agreement protocol: another annotator's item, answered again for agreement.
    Agreement,
}

impl AssignmentKind {
    pub fn as_str(self) -> &'static str {
        match self {
            AssignmentKind::Primary => "primary",
            AssignmentKind::Agreement => "agreement",
        }
    }

    pub fn parse(text: &str) -> Option<AssignmentKind> {
        match text {
            "primary" => Some(AssignmentKind::Primary),
            "agreement" => Some(AssignmentKind::Agreement),
            _ => None,
        }
    }
}

/// One completed primary answer: the item (store id) and who answered it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PrimaryAnswer {
    pub item: i64,
    pub annotator: i64,
    pub direction: Direction,
    pub step_length: StepLength,
}

/// An item drawn for agreement, with the annotator whose primary answer it was.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct SampledItem {
    pub item: i64,
    pub source_annotator: i64,
    pub direction: Direction,
    pub step_length: StepLength,
}

/// A cell where an annotator had fewer completed items than asked for: all of them were taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Shortfall {
    pub annotator: i64,
    pub direction: Direction,
    pub step_length: StepLength,
    pub available: usize,
    pub wanted: usize,
}

/// What one run of the protocol does.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ProtocolPlan {
    pub items_per_cell: usize,
    pub seed: u64,
    /// Sorted by item.
    pub samples: Vec<SampledItem>,
    /// `(annotator, item)`: every sampled item for every annotator but its source, sorted.
    pub assignments: Vec<(i64, i64)>,
    pub shortfalls: Vec<Shortfall>,
}

/// Why the protocol cannot run.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ProtocolError {
    #[error("the protocol needs k ≥ 1 items per annotator, direction and step length")]
    NoItemsPerCell,
    #[error(
        "the protocol needs at least two annotators with primary assignments; this dataset has {0}"
    )]
    TooFewAnnotators(usize),
    #[error("no annotator has completed a primary item of this dataset yet")]
    NothingCompleted,
    #[error("annotator {0} answered an item but is not among the annotators given")]
    UnknownAnnotator(i64),
}

/// Draws `items_per_cell` items from each annotator's completed primary answers in every
/// direction × step length (all of them where fewer exist) and assigns each to every other
/// annotator in `annotators`.
///
/// The draw depends only on the seed and the set of answers: candidates are sorted by item
/// before a ChaCha8 generator seeded with `seed` picks among them, cell by cell in a fixed
/// order. An item answered by two annotators as primary is drawn at most once.
pub fn plan_cross_assignments(
    answers: &[PrimaryAnswer],
    annotators: &[i64],
    items_per_cell: usize,
    seed: u64,
) -> Result<ProtocolPlan, ProtocolError> {
    if items_per_cell == 0 {
        return Err(ProtocolError::NoItemsPerCell);
    }
    let mut annotators: Vec<i64> = annotators.to_vec();
    annotators.sort_unstable();
    annotators.dedup();
    if annotators.len() < 2 {
        return Err(ProtocolError::TooFewAnnotators(annotators.len()));
    }
    if answers.is_empty() {
        return Err(ProtocolError::NothingCompleted);
    }
    type Cell = (i64, Direction, StepLength);
    let mut cells: BTreeMap<Cell, Vec<i64>> = BTreeMap::new();
    for answer in answers {
        if annotators.binary_search(&answer.annotator).is_err() {
            return Err(ProtocolError::UnknownAnnotator(answer.annotator));
        }
        cells
            .entry((answer.annotator, answer.direction, answer.step_length))
            .or_default()
            .push(answer.item);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut taken: BTreeMap<i64, SampledItem> = BTreeMap::new();
    let mut shortfalls = Vec::new();
    for ((annotator, direction, step_length), mut items) in cells {
        items.sort_unstable();
        items.dedup();
        // Items another annotator's cell already gave are not drawn twice.
        items.retain(|item| !taken.contains_key(item));
        if items.len() < items_per_cell {
            shortfalls.push(Shortfall {
                annotator,
                direction,
                step_length,
                available: items.len(),
                wanted: items_per_cell,
            });
        }
        let chosen: Vec<i64> = items
            .choose_multiple(&mut rng, items_per_cell)
            .copied()
            .collect();
        for item in chosen {
            taken.insert(
                item,
                SampledItem {
                    item,
                    source_annotator: annotator,
                    direction,
                    step_length,
                },
            );
        }
    }
    let samples: Vec<SampledItem> = taken.into_values().collect();
    let mut assignments: Vec<(i64, i64)> = samples
        .iter()
        .flat_map(|sample| {
            annotators
                .iter()
                .filter(move |&&annotator| annotator != sample.source_annotator)
                .map(move |&annotator| (annotator, sample.item))
        })
        .collect();
    assignments.sort_unstable();
    Ok(ProtocolPlan {
        items_per_cell,
        seed,
        samples,
        assignments,
        shortfalls,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l(n: usize) -> StepLength {
        StepLength::new(n).unwrap()
    }

    /// Three annotators, each with `per_cell` completed items in forward/inverse × L 3..4.
    fn balanced(per_cell: i64) -> Vec<PrimaryAnswer> {
        let mut answers = Vec::new();
        let mut item = 0;
        for annotator in [1, 2, 3] {
            for direction in Direction::ALL {
                for length in [3, 4] {
                    for _ in 0..per_cell {
                        item += 1;
                        answers.push(PrimaryAnswer {
                            item,
                            annotator,
                            direction,
                            step_length: l(length),
                        });
                    }
                }
            }
        }
        answers
    }

    #[test]
    fn samples_k_per_annotator_and_cell_and_assigns_to_the_others() {
        let answers = balanced(7);
        let plan = plan_cross_assignments(&answers, &[3, 1, 2], 5, 11).unwrap();
        assert_eq!(plan.samples.len(), 3 * 2 * 2 * 5);
        assert!(plan.shortfalls.is_empty());
        for annotator in [1, 2, 3] {
            for direction in Direction::ALL {
                for length in [3, 4] {
                    let n = plan
                        .samples
                        .iter()
                        .filter(|s| {
                            s.source_annotator == annotator
                                && s.direction == direction
                                && s.step_length == l(length)
                        })
                        .count();
                    assert_eq!(n, 5);
                }
            }
        }
        // Each sample goes to the two annotators who did not answer it, never to its source.
        assert_eq!(plan.assignments.len(), plan.samples.len() * 2);
        for sample in &plan.samples {
            let owners: Vec<i64> = plan
                .assignments
                .iter()
                .filter(|(_, item)| *item == sample.item)
                .map(|(who, _)| *who)
                .collect();
            assert_eq!(owners.len(), 2);
            assert!(!owners.contains(&sample.source_annotator));
            let source = answers.iter().find(|a| a.item == sample.item).unwrap();
            assert_eq!(source.annotator, sample.source_annotator);
        }
    }

    #[test]
    fn the_draw_depends_on_the_seed_only() {
        let answers = balanced(9);
        let mut shuffled = answers.clone();
        shuffled.reverse();
        let a = plan_cross_assignments(&answers, &[1, 2, 3], 5, 3).unwrap();
        let b = plan_cross_assignments(&shuffled, &[2, 3, 1], 5, 3).unwrap();
        assert_eq!(a, b, "input order must not matter");
        let c = plan_cross_assignments(&answers, &[1, 2, 3], 5, 4).unwrap();
        assert_ne!(a.samples, c.samples, "another seed draws other items");
    }

    #[test]
    fn a_cell_of_exactly_k_items_is_no_shortfall() {
        let plan = plan_cross_assignments(&balanced(5), &[1, 2, 3], 5, 0).unwrap();
        assert!(plan.shortfalls.is_empty(), "{:?}", plan.shortfalls);
        assert_eq!(plan.samples.len(), 3 * 2 * 2 * 5);
    }

    #[test]
    fn assignment_kinds_read_back_what_they_write() {
        for kind in [AssignmentKind::Primary, AssignmentKind::Agreement] {
            assert_eq!(AssignmentKind::parse(kind.as_str()), Some(kind));
        }
        assert_eq!(AssignmentKind::parse("Primary"), None);
    }

    #[test]
    fn small_cells_are_taken_whole_and_reported() {
        let answers = balanced(2);
        let plan = plan_cross_assignments(&answers, &[1, 2, 3], 5, 0).unwrap();
        assert_eq!(plan.samples.len(), answers.len());
        assert_eq!(plan.shortfalls.len(), 12);
        assert_eq!(plan.shortfalls[0].available, 2);
        assert_eq!(plan.shortfalls[0].wanted, 5);
    }

    #[test]
    fn an_item_answered_twice_is_drawn_once() {
        let mut answers = balanced(1);
        let twin = PrimaryAnswer {
            annotator: 2,
            ..answers[0]
        };
        answers.push(twin);
        let plan = plan_cross_assignments(&answers, &[1, 2, 3], 1, 0).unwrap();
        let first = plan
            .samples
            .iter()
            .filter(|s| s.item == answers[0].item)
            .count();
        assert_eq!(first, 1);
    }

    #[test]
    fn refusals_say_why() {
        let answers = balanced(1);
        assert_eq!(
            plan_cross_assignments(&answers, &[1, 2, 3], 0, 0),
            Err(ProtocolError::NoItemsPerCell)
        );
        assert_eq!(
            plan_cross_assignments(&answers, &[1], 5, 0),
            Err(ProtocolError::TooFewAnnotators(1))
        );
        assert_eq!(
            plan_cross_assignments(&[], &[1, 2], 5, 0),
            Err(ProtocolError::NothingCompleted)
        );
        assert_eq!(
            plan_cross_assignments(&answers, &[1, 2], 5, 0),
            Err(ProtocolError::UnknownAnnotator(3))
        );
        assert_eq!(
            AssignmentKind::parse("agreement"),
            Some(AssignmentKind::Agreement)
        );
        assert_eq!(AssignmentKind::Primary.as_str(), "primary");
    }
}
