//! One step's comparison: the paper's "Action-level Parsing of Signatures Data" (matched,
//! missing, hallucinated components) and "Action-level Structural and Semantic Error
//! Categorization".
//!
//! Rules where the paper leaves a choice (also in the README, "Error analysis"):
//! - Pairs are found class by class in the paper's order (polarity inversion, then predicate
//!   substitution, then entity substitution); each pair consumes one missing and one
//!   hallucinated component. Missing components are visited in sorted order; among the
//!   hallucinated ones that fit, the one in the same semantic category wins, then the first in
//!   sorted order. So a pairing never depends on input order.
//! - Within a class, the closest pairs are made first: all pairs with no entity different,
//!   then those with one, then two (a one-end entity substitution of an edge is paired before
//!   a both-ends one, whichever missing component sorts first).
//! - Entity substitution is the paper's: the predicate is right but applied to the wrong
//!   object(s) (section 3.5), "entities differ while other fields match" (appendix D). Same
//!   kind, operation and predicate, any entity different: both ends of an edge may be wrong,
//!   and a transition may have other sources.
//! - A transition "A → B" has entity A and predicate B: "A → C" is a predicate substitution,
//!   "C → B" an entity substitution, and "B → A" a polarity inversion.
//! - A paired error is labelled with the semantic category of its true component (what the
//!   answer got wrong about the world); a hallucination with that of its predicted one.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::component::{Component, ComponentKind};
use super::semantic::{SemanticCategory, category};

/// The paper's structural error classes, in classification order.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum StructuralClass {
    PolarityInversion,
    PredicateSubstitution,
    EntitySubstitution,
    Omission,
    Hallucination,
}

impl StructuralClass {
    pub const ALL: [StructuralClass; 5] = [
        StructuralClass::PolarityInversion,
        StructuralClass::PredicateSubstitution,
        StructuralClass::EntitySubstitution,
        StructuralClass::Omission,
        StructuralClass::Hallucination,
    ];

    /// The classes that pair a true component with a predicted one, in the order they are
    /// looked for.
    const PAIRED: [StructuralClass; 3] = [
        StructuralClass::PolarityInversion,
        StructuralClass::PredicateSubstitution,
        StructuralClass::EntitySubstitution,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            StructuralClass::PolarityInversion => "polarity_inversion",
            StructuralClass::PredicateSubstitution => "predicate_substitution",
            StructuralClass::EntitySubstitution => "entity_substitution",
            StructuralClass::Omission => "omission",
            StructuralClass::Hallucination => "hallucination",
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            StructuralClass::PolarityInversion => "Polarity inversion",
            StructuralClass::PredicateSubstitution => "Predicate substitution",
            StructuralClass::EntitySubstitution => "Entity substitution",
            StructuralClass::Omission => "Omission",
            StructuralClass::Hallucination => "Hallucination",
        }
    }

    pub fn index(self) -> usize {
        self as usize
    }

    /// Whether `predicted` is this class's kind of mistake for `truth`.
    fn fits(self, truth: &Component, predicted: &Component) -> bool {
        if truth.kind != predicted.kind {
            return false;
        }
        match self {
            StructuralClass::PolarityInversion if truth.kind == ComponentKind::Transition => {
                truth.entities.len() == 1
                    && predicted.entities.len() == 1
                    && truth.entities[0] == predicted.predicate
                    && predicted.entities[0] == truth.predicate
            }
            StructuralClass::PolarityInversion => {
                truth.operation != predicted.operation
                    && truth.entities == predicted.entities
                    && truth.predicate == predicted.predicate
            }
            StructuralClass::PredicateSubstitution => {
                truth.operation == predicted.operation
                    && truth.entities == predicted.entities
                    && truth.predicate != predicted.predicate
            }
            StructuralClass::EntitySubstitution => {
                truth.operation == predicted.operation
                    && truth.predicate == predicted.predicate
                    && truth.entities != predicted.entities
            }
            StructuralClass::Omission | StructuralClass::Hallucination => false,
        }
    }
}

/// How many entities of `predicted` are not `truth`'s in the same place (an entity one has and
/// the other lacks counts as different): the closeness of two components that fit a class.
fn entities_differing(truth: &Component, predicted: &Component) -> usize {
    let in_place = truth
        .entities
        .iter()
        .zip(&predicted.entities)
        .filter(|(a, b)| a != b)
        .count();
    in_place + truth.entities.len().abs_diff(predicted.entities.len())
}

/// One wrong component (or pair of them).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct StructuralError {
    pub class: StructuralClass,
    /// The true component: absent for a hallucination.
    pub truth: Option<Component>,
    /// The predicted component: absent for an omission.
    pub predicted: Option<Component>,
    pub category: Option<SemanticCategory>,
}

/// How one predicted step's components compare with the true step's.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct StepComparison {
    pub matched: Vec<Component>,
    /// In the truth only (before pairing).
    pub missing: Vec<Component>,
    /// In the prediction only (before pairing).
    pub hallucinated: Vec<Component>,
    pub errors: Vec<StructuralError>,
}

/// Compares two component sets (duplicates are ignored).
pub fn compare_step(truth: &[Component], predicted: &[Component]) -> StepComparison {
    let sorted = |v: &[Component]| {
        let mut v = v.to_vec();
        v.sort();
        v.dedup();
        v
    };
    let (truth, predicted) = (sorted(truth), sorted(predicted));
    let contains = |set: &[Component], c: &Component| set.binary_search(c).is_ok();
    let matched: Vec<Component> = truth
        .iter()
        .filter(|c| contains(&predicted, c))
        .cloned()
        .collect();
    let missing: Vec<Component> = truth
        .iter()
        .filter(|c| !contains(&predicted, c))
        .cloned()
        .collect();
    let hallucinated: Vec<Component> = predicted
        .iter()
        .filter(|c| !contains(&truth, c))
        .cloned()
        .collect();

    let mut missing_left: Vec<bool> = vec![true; missing.len()];
    let mut hallucinated_left: Vec<bool> = vec![true; hallucinated.len()];
    let mut errors = Vec::new();
    for class in StructuralClass::PAIRED {
        // Closest pairs first, over all missing components: every one-end entity substitution
        // is paired before any two-end one, so a far pair never takes a near pair's component.
        let mut rounds: Vec<usize> = missing
            .iter()
            .flat_map(|t| {
                hallucinated
                    .iter()
                    .filter(|p| class.fits(t, p))
                    .map(|p| entities_differing(t, p))
            })
            .collect();
        rounds.sort_unstable();
        rounds.dedup();
        for distance in rounds {
            for (m, truth_c) in missing.iter().enumerate() {
                if !missing_left[m] {
                    continue;
                }
                let truth_category = category(truth_c);
                let fitting = || {
                    hallucinated.iter().enumerate().filter(|&(h, p)| {
                        hallucinated_left[h]
                            && class.fits(truth_c, p)
                            && entities_differing(truth_c, p) == distance
                    })
                };
                let chosen = fitting()
                    .find(|(_, p)| category(p) == truth_category)
                    .or_else(|| fitting().next())
                    .map(|(h, _)| h);
                if let Some(h) = chosen {
                    missing_left[m] = false;
                    hallucinated_left[h] = false;
                    errors.push(StructuralError {
                        class,
                        truth: Some(truth_c.clone()),
                        predicted: Some(hallucinated[h].clone()),
                        category: truth_category,
                    });
                }
            }
        }
    }
    for (m, c) in missing.iter().enumerate() {
        if !missing_left[m] {
            continue;
        }
        errors.push(StructuralError {
            class: StructuralClass::Omission,
            truth: Some(c.clone()),
            predicted: None,
            category: category(c),
        });
    }
    for (h, c) in hallucinated.iter().enumerate() {
        if hallucinated_left[h] {
            errors.push(StructuralError {
                class: StructuralClass::Hallucination,
                truth: None,
                predicted: Some(c.clone()),
                category: category(c),
            });
        }
    }
    StepComparison {
        matched,
        missing,
        hallucinated,
        errors,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(sigs: &[&str]) -> Vec<Component> {
        sigs.iter().map(|s| Component::parse(s).unwrap()).collect()
    }

    fn classes(truth: &[&str], predicted: &[&str]) -> Vec<(StructuralClass, String, String)> {
        compare_step(&parse(truth), &parse(predicted))
            .errors
            .into_iter()
            .map(|e| {
                (
                    e.class,
                    e.truth.map(|c| c.to_string()).unwrap_or_default(),
                    e.predicted.map(|c| c.to_string()).unwrap_or_default(),
                )
            })
            .collect()
    }

    use StructuralClass::*;

    #[test]
    fn each_structural_class() {
        let inside = "edge_add_the apple_the fridge_Inside";
        assert_eq!(
            classes(&[inside], &["edge_remove_the apple_the fridge_Inside"]),
            [(
                PolarityInversion,
                inside.into(),
                "edge_remove_the apple_the fridge_Inside".into()
            )]
        );
        assert_eq!(
            classes(&[inside], &["edge_add_the apple_the fridge_OnTop"]),
            [(
                PredicateSubstitution,
                inside.into(),
                "edge_add_the apple_the fridge_OnTop".into()
            )]
        );
        assert_eq!(
            classes(&[inside], &["edge_add_the pear_the fridge_Inside"]),
            [(
                EntitySubstitution,
                inside.into(),
                "edge_add_the pear_the fridge_Inside".into()
            )]
        );
        assert_eq!(
            classes(&[inside], &[]),
            [(Omission, inside.into(), String::new())]
        );
        assert_eq!(
            classes(&[], &[inside]),
            [(Hallucination, String::new(), inside.into())]
        );
        assert_eq!(classes(&[inside], &[inside]), []);
    }

    #[test]
    fn entity_substitution_is_any_entity_wrong_under_the_right_predicate() {
        let inside = "edge_add_the apple_the fridge_Inside";
        // One end, either one.
        for predicted in [
            "edge_add_the pear_the fridge_Inside",
            "edge_add_the apple_the sink_Inside",
        ] {
            assert_eq!(
                classes(&[inside], &[predicted]),
                [(EntitySubstitution, inside.into(), predicted.into())]
            );
        }
        // Both ends (the paper's "wrong object(s)"), and the two ends swapped.
        for predicted in [
            "edge_add_the pear_the sink_Inside",
            "edge_add_the fridge_the apple_Inside",
        ] {
            assert_eq!(
                classes(&[inside], &[predicted]),
                [(EntitySubstitution, inside.into(), predicted.into())]
            );
        }
        // A node's one entity.
        assert_eq!(
            classes(
                &["node_add_the fridge_Open"],
                &["node_add_the cabinet_Open"]
            )[0]
            .0,
            EntitySubstitution
        );
        // A transition to the right result from other sources, even a different number.
        assert_eq!(
            classes(
                &["node_transition_from_the apple_the pear_to_the fruit salad"],
                &["node_transition_from_the apple_to_the fruit salad"]
            )[0]
            .0,
            EntitySubstitution
        );
        // Another predicate or operation as well is not an entity substitution.
        assert_eq!(
            classes(&[inside], &["edge_add_the pear_the sink_OnTop"]),
            [
                (Omission, inside.into(), String::new()),
                (
                    Hallucination,
                    String::new(),
                    "edge_add_the pear_the sink_OnTop".into()
                )
            ]
        );
        assert_eq!(
            classes(&[inside], &["edge_remove_the pear_the sink_Inside"]).len(),
            2
        );
    }

    #[test]
    fn competing_entity_substitutions_pair_the_closest_first() {
        // "the a … the b" sorts first and fits the prediction with both ends wrong, but "the
        // c … the d" fits it with one end wrong: the closer pair is made.
        let truth = ["edge_add_the a_the b_Inside", "edge_add_the c_the d_Inside"];
        assert_eq!(
            classes(&truth, &["edge_add_the c_the x_Inside"]),
            [
                (
                    EntitySubstitution,
                    "edge_add_the c_the d_Inside".into(),
                    "edge_add_the c_the x_Inside".into()
                ),
                (
                    Omission,
                    "edge_add_the a_the b_Inside".into(),
                    String::new()
                ),
            ]
        );
        // With a second prediction both are paired, the far one last; input order does not
        // matter.
        let predicted = ["edge_add_the y_the z_Inside", "edge_add_the c_the x_Inside"];
        let errors = classes(&truth, &predicted);
        assert_eq!(
            errors,
            [
                (
                    EntitySubstitution,
                    "edge_add_the c_the d_Inside".into(),
                    "edge_add_the c_the x_Inside".into()
                ),
                (
                    EntitySubstitution,
                    "edge_add_the a_the b_Inside".into(),
                    "edge_add_the y_the z_Inside".into()
                ),
            ]
        );
        let (mut t, mut p) = (truth, predicted);
        t.reverse();
        p.reverse();
        assert_eq!(classes(&t, &p), errors);
        // Equally close candidates: the first in sorted order.
        assert_eq!(
            classes(
                &["edge_add_the a_the b_Inside"],
                &["edge_add_the a_the z_Inside", "edge_add_the a_the c_Inside"]
            )[0]
            .2,
            "edge_add_the a_the c_Inside"
        );
    }

    #[test]
    fn transitions_have_entity_predicate_and_polarity() {
        let t = "node_transition_from_the apple_to_the half apple";
        assert_eq!(
            classes(&[t], &["node_transition_from_the half apple_to_the apple"])[0].0,
            PolarityInversion
        );
        assert_eq!(
            classes(&[t], &["node_transition_from_the apple_to_the diced apple"])[0].0,
            PredicateSubstitution
        );
        assert_eq!(
            classes(&[t], &["node_transition_from_the pear_to_the half apple"])[0].0,
            EntitySubstitution
        );
        // A node and a transition never pair.
        assert_eq!(classes(&[t], &["node_add_the apple_Cooked"]).len(), 2);
        // Inverted needs both ends swapped: starting from the true end state is not enough.
        let half = classes(
            &[t],
            &["node_transition_from_the half apple_to_the diced apple"],
        );
        assert_eq!(
            half.iter().map(|e| e.0).collect::<Vec<_>>(),
            [Omission, Hallucination]
        );
    }

    #[test]
    fn polarity_is_looked_for_before_substitutions() {
        // The removed Inside could also be read as a predicate substitution of nothing here,
        // but the add/remove pair on the same fact is found first.
        let errors = classes(
            &[
                "edge_add_the apple_the fridge_Inside",
                "edge_add_the apple_the fridge_OnTop",
            ],
            &[
                "edge_remove_the apple_the fridge_Inside",
                "edge_add_the apple_the fridge_Under",
            ],
        );
        assert_eq!(errors[0].0, PolarityInversion);
        assert_eq!(errors[0].1, "edge_add_the apple_the fridge_Inside");
        assert_eq!(errors[1].0, PredicateSubstitution);
        assert_eq!(errors[1].1, "edge_add_the apple_the fridge_OnTop");
        assert_eq!(errors.len(), 2);
    }

    #[test]
    fn predicate_substitution_comes_before_entity_substitution() {
        // The prediction fits the first truth as a predicate substitution and the second as an
        // entity substitution: predicate substitution is looked for first.
        let errors = classes(
            &["edge_add_the a_the b_Inside", "edge_add_the c_the b_OnTop"],
            &["edge_add_the a_the b_OnTop"],
        );
        assert_eq!(
            errors[0],
            (
                PredicateSubstitution,
                "edge_add_the a_the b_Inside".into(),
                "edge_add_the a_the b_OnTop".into()
            )
        );
        assert_eq!(errors[1].0, Omission);
    }

    #[test]
    fn ties_go_to_the_same_category_then_sorted_order() {
        // Two predicate substitutions fit the left-hand grasp: the other hand (same category)
        // wins over Inside, which sorts first.
        let errors = classes(
            &["edge_add_the robot r1_the a_LeftGrasping"],
            &[
                "edge_add_the robot r1_the a_Inside",
                "edge_add_the robot r1_the a_RightGrasping",
            ],
        );
        assert_eq!(errors[0].0, PredicateSubstitution);
        assert_eq!(errors[0].2, "edge_add_the robot r1_the a_RightGrasping");
        assert_eq!(errors[1].0, Hallucination);
        // No same-category candidate: the first in sorted order.
        let errors = classes(
            &["edge_add_the a_the b_Inside"],
            &["edge_add_the a_the b_Under", "edge_add_the a_the b_OnTop"],
        );
        assert_eq!(errors[0].2, "edge_add_the a_the b_OnTop");
        // Input order does not matter.
        let again = classes(
            &["edge_add_the a_the b_Inside"],
            &["edge_add_the a_the b_OnTop", "edge_add_the a_the b_Under"],
        );
        assert_eq!(errors, again);
    }

    #[test]
    fn empty_sets() {
        assert_eq!(compare_step(&[], &[]), StepComparison::default());
        let only = parse(&["node_add_the a_Open"]);
        let c = compare_step(&only, &only);
        assert_eq!(c.matched, only);
        assert!(c.errors.is_empty() && c.missing.is_empty() && c.hallucinated.is_empty());
    }

    #[test]
    fn errors_are_labelled_by_the_true_component() {
        let c = compare_step(
            &parse(&["edge_add_the robot r1_the a_LeftGrasping"]),
            &parse(&["edge_add_the robot r1_the a_Inside"]),
        );
        assert_eq!(
            c.errors[0].category,
            Some(SemanticCategory::AgentInteraction)
        );
        let c = compare_step(&[], &parse(&["edge_add_the a_the b_Inside"]));
        assert_eq!(
            c.errors[0].category,
            Some(SemanticCategory::SpatialRelations)
        );
    }

    /// Random sets over a small vocabulary, so that every class of near miss is common.
    fn random_set(rng: &mut impl rand::Rng) -> Vec<Component> {
        const NAMES: [&str; 4] = ["the robot r1", "the apple", "the fridge", "the half apple"];
        const EDGE: [&str; 5] = [
            "Inside",
            "OnTop",
            "LeftGrasping",
            "RightGrasping",
            "Touching",
        ];
        const NODE: [&str; 3] = ["Open", "Cooked", "ToggledOn"];
        let n = rng.random_range(0..7);
        (0..n)
            .map(|_| {
                let op = if rng.random_bool(0.5) {
                    "add"
                } else {
                    "remove"
                };
                let sig = match rng.random_range(0..3) {
                    0 => format!(
                        "edge_{op}_{}_{}_{}",
                        NAMES[rng.random_range(0..4)],
                        NAMES[rng.random_range(0..4)],
                        EDGE[rng.random_range(0..EDGE.len())]
                    ),
                    1 => format!(
                        "node_{op}_{}_{}",
                        NAMES[rng.random_range(0..4)],
                        NODE[rng.random_range(0..3)]
                    ),
                    _ => format!(
                        "node_transition_from_{}_to_{}",
                        NAMES[rng.random_range(0..4)],
                        NAMES[rng.random_range(0..4)]
                    ),
                };
                Component::parse(&sig).unwrap()
            })
            .collect()
    }

    #[test]
    fn components_are_conserved_on_random_sets() {
        use rand::SeedableRng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
        for _ in 0..20_000 {
            let truth = random_set(&mut rng);
            let predicted = random_set(&mut rng);
            let c = compare_step(&truth, &predicted);
            let count =
                |class: StructuralClass| c.errors.iter().filter(|e| e.class == class).count();
            let paired =
                count(PolarityInversion) + count(PredicateSubstitution) + count(EntitySubstitution);
            let distinct = |v: &[Component]| {
                let mut v = v.to_vec();
                v.sort();
                v.dedup();
                v.len()
            };
            assert_eq!(c.matched.len() + paired + count(Omission), distinct(&truth));
            assert_eq!(
                c.matched.len() + paired + count(Hallucination),
                distinct(&predicted)
            );
            // Every paired error really is of its class, and consumed components are distinct.
            for e in &c.errors {
                if let (Some(t), Some(p)) = (&e.truth, &e.predicted) {
                    assert!(e.class.fits(t, p), "{e:?}");
                }
            }
            // Nothing left over is an entity substitution: an omission and a hallucination
            // never share kind, operation and predicate.
            for o in c.errors.iter().filter(|e| e.class == Omission) {
                for h in c.errors.iter().filter(|e| e.class == Hallucination) {
                    let (Some(t), Some(p)) = (&o.truth, &h.predicted) else {
                        unreachable!("omissions have a truth, hallucinations a prediction")
                    };
                    assert!(!EntitySubstitution.fits(t, p), "{t} / {p}");
                }
            }
            // A perfect answer has no errors.
            let perfect = compare_step(&truth, &truth);
            assert!(perfect.errors.is_empty());
            assert_eq!(perfect.matched.len(), distinct(&truth));
        }
    }

    /// The names written into reports and the API are the serialised names.
    #[test]
    fn each_class_is_named_as_it_is_serialised() {
        for class in StructuralClass::ALL {
            assert_eq!(
                serde_json::to_value(class).expect("serialise"),
                class.as_str(),
                "{class:?}"
            );
        }
    }
}
