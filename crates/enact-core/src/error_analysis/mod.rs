//! Error analysis (the paper's section 3.5 and appendix D): how answers are wrong, not only how
//! often.
//!
//! For every analysed answer and step, the true step's state changes are compared with the
//! predicted step's ([`steps`]), each signature parsed into a [`Component`]. Components are
//! matched, then wrong ones classified structurally (polarity inversion, predicate
//! substitution, entity substitution, omission, hallucination: [`classify`]) and semantically
//! ([`semantic`]). Hand use is scored by precision, recall and the paper's left/right mixing
//! rate ([`handedness`]), and semantically accepted steps that still omit part of the true
//! change are counted ("accepted but incomplete").
//!
//! Pure: answers and signature tables come in, one [`ErrorAnalysis`] goes out.

pub mod chart;
pub mod classify;
pub mod component;
pub mod handedness;
pub mod present;
pub mod semantic;
pub mod steps;
pub mod why;

use schemars::JsonSchema;
use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

pub use classify::{StepComparison, StructuralClass, StructuralError, compare_step};
pub use component::{Component, ComponentKind, ComponentParseError, Hand, Operation};
pub use handedness::{HandFigures, HandTally};
pub use semantic::{PREDICATE_CATEGORIES, SemanticCategory};
pub use steps::{StepSets, StepsUnavailable, answer_steps};

use crate::verifier::{
    Direction, Permutation, StrictItem, StrictOutcome, StrictParseFailure, StrictScoring,
};

/// The analysis's version, stored with every result: a stored result of another version is
/// recomputed. The analysis is part of the metric, so this is the metric's version: raise
/// [`crate::metric::METRIC_VERSION`] whenever a rule here changes what is counted.
pub const ANALYSIS_VERSION: u32 = crate::metric::METRIC_VERSION;

/// Examples kept per semantic category × structural class.
pub const EXAMPLES_PER_CELL: usize = 3;

/// What was read from an answer, as far as the analysis cares.
#[derive(Debug, Clone, Copy)]
pub enum Reading<'a> {
    /// A permutation of the right length, with the verifier's task accuracy for it.
    Answer {
        answer: &'a Permutation,
        task_accuracy: bool,
    },
    /// A list of integers of another length than the truth's.
    WrongLength,
    /// Any other answer that is not a permutation of the item's labels.
    Unreadable,
    /// No answer.
    Missing,
}

impl<'a> Reading<'a> {
    /// What the strict reader made of an answer.
    pub fn of_strict(outcome: &'a StrictOutcome) -> Reading<'a> {
        match outcome {
            StrictOutcome::Scored { answer, verdict } => Reading::Answer {
                answer,
                task_accuracy: verdict.task_accuracy,
            },
            StrictOutcome::Unparseable {
                reason: StrictParseFailure::WrongLength { .. },
            } => Reading::WrongLength,
            StrictOutcome::Unparseable { .. } => Reading::Unreadable,
            StrictOutcome::Missing => Reading::Missing,
        }
    }
}

/// One answer to analyse.
#[derive(Debug, Clone, Copy)]
pub struct AnsweredItem<'a> {
    pub item: StrictItem<'a>,
    pub reading: Reading<'a>,
}

/// Counts gathered over answers.
#[derive(Debug, Clone, Default, PartialEq)]
struct Tally {
    answers: usize,
    steps: usize,
    excluded_unequal_length: usize,
    excluded_unreadable: usize,
    excluded_missing: usize,
    excluded_without_signatures: usize,
    truth: usize,
    predicted: usize,
    matched: usize,
    structural: [usize; 5],
    semantic: [[usize; 5]; 4],
    hands: [HandTally; 2],
    accepted_answers: usize,
    incomplete_answers: usize,
    accepted_steps: usize,
    incomplete_steps: usize,
}

/// Why an answer is not analysed.
#[derive(Debug, Clone, Copy)]
enum Exclusion {
    UnequalLength,
    Unreadable,
    Missing,
    WithoutSignatures,
}

impl Tally {
    fn exclude(&mut self, why: Exclusion) {
        *match why {
            Exclusion::UnequalLength => &mut self.excluded_unequal_length,
            Exclusion::Unreadable => &mut self.excluded_unreadable,
            Exclusion::Missing => &mut self.excluded_missing,
            Exclusion::WithoutSignatures => &mut self.excluded_without_signatures,
        } += 1;
    }

    fn add_step(&mut self, comparison: &StepComparison) {
        self.steps += 1;
        self.truth += comparison.matched.len() + comparison.missing.len();
        self.predicted += comparison.matched.len() + comparison.hallucinated.len();
        self.matched += comparison.matched.len();
        for e in &comparison.errors {
            self.structural[e.class.index()] += 1;
            if let Some(c) = e.category {
                self.semantic[c.index()][e.class.index()] += 1;
            }
        }
        for hand in Hand::BOTH {
            self.hands[hand as usize].add(hand, comparison);
        }
    }

    fn figures(&self) -> ErrorFigures {
        let classes = |row: &[usize; 5]| ClassCounts {
            polarity_inversion: row[StructuralClass::PolarityInversion.index()],
            predicate_substitution: row[StructuralClass::PredicateSubstitution.index()],
            entity_substitution: row[StructuralClass::EntitySubstitution.index()],
            omission: row[StructuralClass::Omission.index()],
            hallucination: row[StructuralClass::Hallucination.index()],
        };
        let category = |c: SemanticCategory| {
            let row = &self.semantic[c.index()];
            CategoryCounts {
                classes: classes(row),
                total: row.iter().sum(),
            }
        };
        ErrorFigures {
            analysed_answers: self.answers,
            analysed_steps: self.steps,
            excluded_unequal_length: self.excluded_unequal_length,
            excluded_unreadable: self.excluded_unreadable,
            excluded_missing: self.excluded_missing,
            excluded_without_signatures: self.excluded_without_signatures,
            components: ComponentCounts {
                truth: self.truth,
                predicted: self.predicted,
                matched: self.matched,
            },
            errors: self.structural.iter().sum(),
            structural: classes(&self.structural),
            semantic: SemanticCounts {
                spatial_relations: category(SemanticCategory::SpatialRelations),
                functional_states: category(SemanticCategory::FunctionalStates),
                material_states: category(SemanticCategory::MaterialStates),
                agent_interaction: category(SemanticCategory::AgentInteraction),
            },
            handedness: Handedness {
                left: self.hands[Hand::Left as usize].figures(),
                right: self.hands[Hand::Right as usize].figures(),
            },
            accepted_incomplete: AcceptedIncomplete {
                accepted_answers: self.accepted_answers,
                incomplete_answers: self.incomplete_answers,
                data_level: ratio(self.incomplete_answers, self.accepted_answers),
                accepted_steps: self.accepted_steps,
                incomplete_steps: self.incomplete_steps,
                pair_level: ratio(self.incomplete_steps, self.accepted_steps),
            },
        }
    }
}

fn ratio(part: usize, whole: usize) -> Option<f64> {
    (whole > 0).then(|| part as f64 / whole as f64)
}

/// Component totals: the identities `matched + paired + omissions = truth` and
/// `matched + paired + hallucinations = predicted` hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct ComponentCounts {
    pub truth: usize,
    pub predicted: usize,
    pub matched: usize,
}

/// Left- and right-hand figures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Handedness {
    pub left: HandFigures,
    pub right: HandFigures,
}

/// The paper's table of semantically accepted answers that omit parts of transitions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct AcceptedIncomplete {
    /// Analysed answers the verifier accepts (task accuracy).
    pub accepted_answers: usize,
    /// Of those, answers with a step whose predicted change is a strict subset of the truth's.
    pub incomplete_answers: usize,
    /// incomplete_answers / accepted_answers (data-level mismatch rate).
    pub data_level: Option<f64>,
    /// Steps of analysed answers that pass the verifier's per-step test.
    pub accepted_steps: usize,
    /// Of those, steps whose predicted change is a strict subset of the truth's.
    pub incomplete_steps: usize,
    /// incomplete_steps / accepted_steps (pair-level mismatch rate).
    pub pair_level: Option<f64>,
}

/// A count per structural class.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct ClassCounts {
    pub polarity_inversion: usize,
    pub predicate_substitution: usize,
    pub entity_substitution: usize,
    pub omission: usize,
    pub hallucination: usize,
}

impl ClassCounts {
    pub fn get(&self, class: StructuralClass) -> usize {
        match class {
            StructuralClass::PolarityInversion => self.polarity_inversion,
            StructuralClass::PredicateSubstitution => self.predicate_substitution,
            StructuralClass::EntitySubstitution => self.entity_substitution,
            StructuralClass::Omission => self.omission,
            StructuralClass::Hallucination => self.hallucination,
        }
    }
}

/// One semantic category's errors by structural class, and their total.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct CategoryCounts {
    #[serde(flatten)]
    pub classes: ClassCounts,
    pub total: usize,
}

/// Errors per semantic category.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct SemanticCounts {
    pub spatial_relations: CategoryCounts,
    pub functional_states: CategoryCounts,
    pub material_states: CategoryCounts,
    pub agent_interaction: CategoryCounts,
}

impl SemanticCounts {
    pub fn get(&self, category: SemanticCategory) -> &CategoryCounts {
        match category {
            SemanticCategory::SpatialRelations => &self.spatial_relations,
            SemanticCategory::FunctionalStates => &self.functional_states,
            SemanticCategory::MaterialStates => &self.material_states,
            SemanticCategory::AgentInteraction => &self.agent_interaction,
        }
    }
}

/// The figures of one group of answers (all, or one direction).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ErrorFigures {
    pub analysed_answers: usize,
    pub analysed_steps: usize,
    pub excluded_unequal_length: usize,
    pub excluded_unreadable: usize,
    pub excluded_missing: usize,
    /// Answers on items whose signature table cannot give the needed sets (forward items
    /// without scene graphs, pairs on which ENACT raises).
    pub excluded_without_signatures: usize,
    pub components: ComponentCounts,
    /// Structural errors in all: the sum of `structural`.
    pub errors: usize,
    pub structural: ClassCounts,
    pub semantic: SemanticCounts,
    pub handedness: Handedness,
    pub accepted_incomplete: AcceptedIncomplete,
}

impl ErrorFigures {
    pub fn structural_count(&self, class: StructuralClass) -> usize {
        self.structural.get(class)
    }
}

/// One wrong component, as shown to people.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ErrorExample {
    pub item: String,
    pub direction: Direction,
    /// 1-based.
    pub step: usize,
    pub class: StructuralClass,
    pub category: Option<SemanticCategory>,
    pub truth: Option<ExampleChange>,
    pub predicted: Option<ExampleChange>,
}

/// A component as signature and sentence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ExampleChange {
    pub signature: String,
    pub sentence: String,
}

impl ExampleChange {
    fn of(component: &Component) -> ExampleChange {
        ExampleChange {
            signature: component.to_string(),
            sentence: component.sentence(),
        }
    }
}

/// The whole analysis of a set of answers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ErrorAnalysis {
    pub version: u32,
    #[serde(flatten)]
    pub overall: ErrorFigures,
    pub by_direction: ByDirection,
    /// Up to [`EXAMPLES_PER_CELL`] per semantic category × structural class, in answer order.
    /// Callers remove them where the truth must stay hidden.
    pub examples: Vec<ErrorExample>,
}

/// The figures of each direction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ByDirection {
    pub forward: ErrorFigures,
    pub inverse: ErrorFigures,
}

impl ErrorAnalysis {
    pub fn direction(&self, direction: Direction) -> &ErrorFigures {
        match direction {
            Direction::Forward => &self.by_direction.forward,
            Direction::Inverse => &self.by_direction.inverse,
        }
    }
}

/// Analyses a strictly scored prediction file: `items` are the dataset's, in the order
/// `scoring` lists its results.
pub fn analyse_strict(items: &[StrictItem<'_>], scoring: &StrictScoring) -> ErrorAnalysis {
    analyse(
        items
            .iter()
            .zip(&scoring.items)
            .map(|(item, result)| AnsweredItem {
                item: *item,
                reading: Reading::of_strict(&result.outcome),
            }),
    )
}

/// Analyses answers, in the order given (which decides only which examples are kept).
pub fn analyse<'a>(answers: impl IntoIterator<Item = AnsweredItem<'a>>) -> ErrorAnalysis {
    let mut overall = Tally::default();
    let mut by_direction = [Tally::default(), Tally::default()];
    let mut examples = Vec::new();
    let mut kept = BTreeMap::<(Option<SemanticCategory>, StructuralClass), usize>::new();
    for AnsweredItem { item, reading } in answers {
        let d = match item.direction {
            Direction::Forward => 0,
            Direction::Inverse => 1,
        };
        let excluded = match reading {
            Reading::Answer { .. } => None,
            Reading::WrongLength => Some(Exclusion::UnequalLength),
            Reading::Unreadable => Some(Exclusion::Unreadable),
            Reading::Missing => Some(Exclusion::Missing),
        };
        // A table that cannot give the sets (no scene graphs, a pair ENACT raises on) excludes
        // the answer too.
        let steps = match (reading, item.signatures) {
            (Reading::Answer { answer, .. }, Some(table)) => {
                answer_steps(item.direction, item.ground_truth, answer, table).ok()
            }
            _ => None,
        };
        let (Some(steps), None) = (steps, excluded) else {
            let why = excluded.unwrap_or(Exclusion::WithoutSignatures);
            overall.exclude(why);
            by_direction[d].exclude(why);
            continue;
        };
        let task_accuracy = matches!(
            reading,
            Reading::Answer {
                task_accuracy: true,
                ..
            }
        );
        let mut incomplete_steps = 0;
        let mut accepted_steps = 0;
        for t in [&mut overall, &mut by_direction[d]] {
            t.answers += 1;
        }
        for (k, step) in steps.iter().enumerate() {
            let comparison = compare_step(&step.truth, &step.predicted);
            overall.add_step(&comparison);
            by_direction[d].add_step(&comparison);
            if step.accepted {
                accepted_steps += 1;
                // A strict subset: nothing hallucinated, something missing.
                if comparison.hallucinated.is_empty() && !comparison.missing.is_empty() {
                    incomplete_steps += 1;
                }
            }
            for e in &comparison.errors {
                let count = kept.entry((e.category, e.class)).or_default();
                if *count < EXAMPLES_PER_CELL {
                    *count += 1;
                    examples.push(ErrorExample {
                        item: item.id.to_owned(),
                        direction: item.direction,
                        step: k + 1,
                        class: e.class,
                        category: e.category,
                        truth: e.truth.as_ref().map(ExampleChange::of),
                        predicted: e.predicted.as_ref().map(ExampleChange::of),
                    });
                }
            }
        }
        for t in [&mut overall, &mut by_direction[d]] {
            t.accepted_steps += accepted_steps;
            t.incomplete_steps += incomplete_steps;
            if task_accuracy {
                t.accepted_answers += 1;
                t.incomplete_answers += usize::from(incomplete_steps > 0);
            }
        }
    }
    ErrorAnalysis {
        version: ANALYSIS_VERSION,
        overall: overall.figures(),
        by_direction: ByDirection {
            forward: by_direction[0].figures(),
            inverse: by_direction[1].figures(),
        },
        examples,
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;
    use crate::verifier::{ItemSignatures, Permutation, StepLength, View, VisibleCoverage};

    const INSIDE: &str = "edge_add_the apple_the fridge_Inside";
    const OPEN: &str = "node_add_the fridge_Open";

    /// An inverse item of three states whose transitions change `first` then `second`, each
    /// transition's full change being both.
    fn table(first: &[&str], second: &[&str]) -> ItemSignatures {
        let ids: Vec<String> = (0..3).map(|i| format!("f{i}")).collect();
        let both: BTreeSet<String> = first
            .iter()
            .chain(second)
            .map(|s| (*s).to_owned())
            .collect();
        ItemSignatures::build(&ids, VisibleCoverage::Chronological, |from, to, view| {
            Ok(match (view, from, to) {
                (View::Visible, "f0", "f1") => first.iter().map(|s| (*s).to_owned()).collect(),
                (View::Visible, "f1", "f2") => second.iter().map(|s| (*s).to_owned()).collect(),
                _ => both.clone(),
            })
        })
    }

    fn item<'a>(id: &'a str, truth: &'a Permutation, table: &'a ItemSignatures) -> StrictItem<'a> {
        StrictItem {
            id,
            direction: Direction::Inverse,
            step_length: StepLength::new(3).expect("3 states"),
            ground_truth: truth,
            signatures: Some(table),
        }
    }

    #[test]
    fn components_errors_and_accepted_but_incomplete_answers_are_counted() {
        let truth = Permutation::new(vec![1, 2]).expect("a permutation");
        let swapped = Permutation::new(vec![2, 1]).expect("a permutation");
        // The first transition changes more than the second: the swapped answer's first step
        // names a strict subset of what happened, its second step one change too many.
        let nested = table(&[INSIDE, OPEN], &[OPEN]);
        let apart = table(&[INSIDE], &[OPEN]);
        let answers = [
            // Right: two steps, every component matched.
            (
                item("right", &truth, &apart),
                Reading::Answer {
                    answer: &truth,
                    task_accuracy: true,
                },
            ),
            // Accepted (each chosen change is within the full change) but incomplete.
            (
                item("nested", &truth, &nested),
                Reading::Answer {
                    answer: &swapped,
                    task_accuracy: true,
                },
            ),
            (item("short", &truth, &apart), Reading::WrongLength),
            (item("garbled", &truth, &apart), Reading::Unreadable),
            (item("silent", &truth, &apart), Reading::Missing),
        ];
        let analysis = analyse(answers.iter().map(|(item, reading)| AnsweredItem {
            item: *item,
            reading: *reading,
        }));
        let figures = &analysis.overall;
        assert_eq!(figures.analysed_answers, 2);
        assert_eq!(figures.analysed_steps, 4);
        assert_eq!(
            (
                figures.excluded_unequal_length,
                figures.excluded_unreadable,
                figures.excluded_missing,
                figures.excluded_without_signatures
            ),
            (1, 1, 1, 0)
        );
        // Right: 1 + 1 matched. Nested, swapped: step 1 predicts {open} of {inside, open}
        // (1 matched, 1 missing); step 2 predicts {inside, open} of {open} (1 matched, 1 extra).
        assert_eq!(
            figures.components,
            ComponentCounts {
                truth: 2 + 3,
                predicted: 2 + 3,
                matched: 2 + 2
            }
        );
        assert_eq!(figures.structural.omission, 1);
        assert_eq!(figures.structural.hallucination, 1);
        assert_eq!(figures.errors, 2);
        assert_eq!(
            figures
                .semantic
                .get(SemanticCategory::SpatialRelations)
                .total,
            2,
            "{:?}",
            figures.semantic
        );
        let incomplete = &figures.accepted_incomplete;
        assert_eq!(
            (incomplete.accepted_answers, incomplete.incomplete_answers),
            (2, 1)
        );
        assert_eq!(incomplete.data_level, Some(0.5));
        assert_eq!(
            (incomplete.accepted_steps, incomplete.incomplete_steps),
            (4, 1)
        );
        assert_eq!(incomplete.pair_level, Some(0.25));
        // Every answer here is inverse.
        assert_eq!(analysis.direction(Direction::Inverse), figures);
        assert_eq!(analysis.direction(Direction::Forward).analysed_answers, 0);
        assert_eq!(
            analysis
                .direction(Direction::Forward)
                .accepted_incomplete
                .data_level,
            None
        );
        assert_eq!(analysis.examples.len(), 2);
        assert!(analysis.examples.iter().all(|e| e.item == "nested"));
        assert_eq!(
            analysis
                .examples
                .iter()
                .map(|e| (e.step, e.class))
                .collect::<Vec<_>>(),
            [
                (1, StructuralClass::Omission),
                (2, StructuralClass::Hallucination)
            ]
        );
    }

    #[test]
    fn examples_stop_at_their_cap_per_category_and_class() {
        let truth = Permutation::new(vec![1, 2]).expect("a permutation");
        let swapped = Permutation::new(vec![2, 1]).expect("a permutation");
        let nested = table(&[INSIDE, OPEN], &[OPEN]);
        let ids: Vec<String> = (0..EXAMPLES_PER_CELL + 2)
            .map(|i| format!("item{i}"))
            .collect();
        let analysis = analyse(ids.iter().map(|id| AnsweredItem {
            item: item(id, &truth, &nested),
            reading: Reading::Answer {
                answer: &swapped,
                task_accuracy: true,
            },
        }));
        assert_eq!(analysis.overall.structural.omission, EXAMPLES_PER_CELL + 2);
        let omissions: Vec<&str> = analysis
            .examples
            .iter()
            .filter(|e| e.class == StructuralClass::Omission)
            .map(|e| e.item.as_str())
            .collect();
        // The first answers' examples, in answer order.
        assert_eq!(
            omissions,
            ids[..EXAMPLES_PER_CELL]
                .iter()
                .map(String::as_str)
                .collect::<Vec<_>>()
        );
        assert_eq!(analysis.examples.len(), 2 * EXAMPLES_PER_CELL);
    }

    #[test]
    fn errors_are_counted_under_their_own_semantic_category() {
        let truth = Permutation::new(vec![1, 2]).expect("a permutation");
        let swapped = Permutation::new(vec![2, 1]).expect("a permutation");
        // As the first test's nested item, with the fridge's opening as the change the swapped
        // answer leaves out of step 1 and adds to step 2: a functional state, not a spatial one.
        let nested = table(&[OPEN, INSIDE], &[INSIDE]);
        let analysis = analyse([AnsweredItem {
            item: item("nested", &truth, &nested),
            reading: Reading::Answer {
                answer: &swapped,
                task_accuracy: true,
            },
        }]);
        let semantic = &analysis.overall.semantic;
        let totals = SemanticCategory::ALL.map(|c| semantic.get(c).total);
        assert_eq!(totals, [0, 2, 0, 0], "{semantic:?}");
        let functional = semantic.get(SemanticCategory::FunctionalStates);
        assert_eq!(
            (
                functional.classes.omission,
                functional.classes.hallucination
            ),
            (1, 1)
        );
    }
}
