//! Signatures of a diff (ENACT's `translate_diff_into_signatures`): one string per atomic
//! change, e.g. `node_add_the burner_ToggledOn`,
//! `edge_remove_the robot r1_the apple_RightGrasping`,
//! `node_transition_from_the apple_to_the half apple`. Two transitions are compared by
//! subset tests on these sets.

use std::collections::{BTreeMap, BTreeSet};

use serde::Serialize;

use crate::scene_graph::diff::{ChangeOp, StateDiff};
use crate::scene_graph::names::{NameError, format_object_name};

/// Whether a state belongs to one object or relates two.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StateArity {
    /// A node state ("open", "cooked").
    Unary,
    /// An edge state ("inside", "on top of and touching").
    Binary,
}

/// ENACT's `_state_templates`: the only states that produce signatures and sentences, with
/// the phrase used in sentences. Any other state (`LeftContact`, `Sliced`, ...) is ignored.
pub const STATE_PHRASES: [(&str, &str, StateArity); 26] = [
    ("Burnt", "burnt", StateArity::Unary),
    ("Cooked", "cooked", StateArity::Unary),
    ("Folded", "folded", StateArity::Unary),
    ("Unfolded", "unfolded", StateArity::Unary),
    ("Frozen", "frozen", StateArity::Unary),
    ("HeatSourceOrSink", "heat source or sink", StateArity::Unary),
    ("Heated", "heated", StateArity::Unary),
    ("OnFire", "on fire", StateArity::Unary),
    (
        "InFOVofRobot",
        "in field of view of robot",
        StateArity::Unary,
    ),
    ("Open", "open", StateArity::Unary),
    ("ToggledOn", "turned on", StateArity::Unary),
    ("AttachedTo", "attached to", StateArity::Binary),
    ("Contains", "containing", StateArity::Binary),
    ("Covered", "covered by", StateArity::Binary),
    ("Draped", "draped over", StateArity::Binary),
    ("Filled", "filled with", StateArity::Binary),
    ("Inside", "inside", StateArity::Binary),
    ("NextTo", "next to", StateArity::Binary),
    ("OnTop", "on top of and touching", StateArity::Binary),
    ("Overlaid", "overlaid on", StateArity::Binary),
    ("Saturated", "saturated with", StateArity::Binary),
    ("Touching", "touching", StateArity::Binary),
    ("Under", "under", StateArity::Binary),
    ("Grasping", "grasping", StateArity::Binary),
    (
        "LeftGrasping",
        "using the left gripper to grasp",
        StateArity::Binary,
    ),
    (
        "RightGrasping",
        "using the right gripper to grasp",
        StateArity::Binary,
    ),
];

/// The sentence phrase of a state, if ENACT describes it at all. ENACT uses one table for
/// nodes and edges, so a "binary" state on a node (or the reverse) is still described.
pub fn state_phrase(state: &str) -> Option<&'static str> {
    STATE_PHRASES
        .iter()
        .find(|(name, _, _)| *name == state)
        .map(|(_, phrase, _)| *phrase)
}

/// Which states a run describes (in sentences and signatures) and counts as a change.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StateVocabulary {
    /// ENACT's: the states of its template table; contact-only edges are not a change.
    #[default]
    Enact,
    /// ENACT's plus the robot's `LeftContact` and `RightContact`, and every edge change counts.
    WithContact,
}

impl StateVocabulary {
    /// The sentence phrase of a state, if this vocabulary describes it.
    pub fn phrase(self, state: &str) -> Option<&'static str> {
        state_phrase(state).or_else(|| match self {
            StateVocabulary::Enact => None,
            StateVocabulary::WithContact => crate::scene_graph::contact::CONTACT_PHRASES
                .iter()
                .find(|(name, _)| *name == state)
                .map(|(_, phrase)| *phrase),
        })
    }

    /// Whether a diff holds a change worth a transition (ENACT's `_has_meaningful_changes` for
    /// [`StateVocabulary::Enact`]; with contact, any node or edge entry).
    pub fn is_meaningful(self, diff: &StateDiff) -> bool {
        match self {
            StateVocabulary::Enact => diff.has_meaningful_change(),
            StateVocabulary::WithContact => ChangeOp::BOTH.iter().any(|&op| {
                let side = diff.side(op);
                !side.nodes.is_empty() || side.edges.iter().any(|e| !e.states.is_empty())
            }),
        }
    }
}

/// `node_{op}_{object}_{State}`.
pub fn node_signature(op: ChangeOp, object: &str, state: &str) -> String {
    format!("node_{}_{object}_{state}", op.as_str())
}

/// `edge_{op}_{from}_{to}_{State}`.
pub fn edge_signature(op: ChangeOp, from: &str, to: &str, state: &str) -> String {
    format!("edge_{}_{from}_{to}_{state}", op.as_str())
}

/// `node_transition_from_{sources}_to_{target}`; several sources are sorted and joined by `_`.
pub fn transition_signature(sources: &[&str], target: &str) -> String {
    let mut sorted = sources.to_vec();
    sorted.sort_unstable();
    format!("node_transition_from_{}_to_{target}", sorted.join("_"))
}

/// ENACT quirk: the signature of a cooked system whose uncooked self did not disappear names
/// the target with every "cooked " deleted (and ends in `_to_cooked`), while its sentence
/// deletes every "cooked" (see `sentence::cooked_sentence`).
pub fn cooked_transition_signature(target: &str) -> String {
    format!(
        "node_transition_from_{}_to_cooked",
        target.replace("cooked ", "")
    )
}

/// How a whole object's appearance is described: from which removed objects it came.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub enum ObjectTransition {
    /// `{sources} now becomes / now turn into {target}`. Sources are formatted names, sorted.
    From {
        sources: Vec<String>,
        target: String,
    },
    /// A cooked particle system appeared while its uncooked self did not disappear:
    /// "`{target without 'cooked'}` is now cooked".
    Cooked { target: String },
}

impl ObjectTransition {
    pub fn signature(&self) -> String {
        match self {
            ObjectTransition::From { sources, target } => {
                let refs: Vec<&str> = sources.iter().map(String::as_str).collect();
                transition_signature(&refs, target)
            }
            ObjectTransition::Cooked { target } => cooked_transition_signature(target),
        }
    }
}

/// The object transitions of a diff (ENACT's `process_object_add_and_remove*`), sorted.
///
/// ENACT quirk: appeared objects are keyed by their *formatted* name, so two that format
/// alike ("the half apple") collapse into one and the parent list of the last one processed
/// wins. ENACT's order there is Python set order; ours is the diff's (sorted by raw name).
pub fn object_transitions(diff: &StateDiff) -> Result<BTreeSet<ObjectTransition>, NameError> {
    let mut appeared: BTreeMap<String, &Option<Vec<String>>> = BTreeMap::new();
    for node in &diff.add.nodes {
        let name = format_object_name(&node.name)?;
        if node.is_whole_object() {
            appeared.insert(name, &node.parent);
        }
    }
    let mut disappeared: BTreeSet<String> = BTreeSet::new();
    for node in &diff.remove.nodes {
        let name = format_object_name(&node.name)?;
        if node.is_whole_object() {
            disappeared.insert(name);
        }
    }
    let mut out = BTreeSet::new();
    for (target, parent) in appeared {
        let Some(parent) = parent.as_ref().filter(|p| !p.is_empty()) else {
            continue;
        };
        let mut sources: BTreeSet<String> = BTreeSet::new();
        for p in parent {
            let p = format_object_name(p)?;
            if disappeared.contains(&p) {
                sources.insert(p);
            }
        }
        if !sources.is_empty() {
            out.insert(ObjectTransition::From {
                sources: sources.into_iter().collect(),
                target,
            });
        } else if target.to_lowercase().contains("cooked") {
            out.insert(ObjectTransition::Cooked { target });
        } else if let [only] = parent.as_slice() {
            out.insert(ObjectTransition::From {
                sources: vec![format_object_name(only)?],
                target,
            });
        }
    }
    Ok(out)
}

/// Every signature of a diff. An empty diff gives the empty set.
pub fn diff_signatures(diff: &StateDiff) -> Result<BTreeSet<String>, NameError> {
    diff_signatures_in(diff, StateVocabulary::Enact)
}

/// [`diff_signatures`] of the states `vocabulary` describes (contact runs add the grippers'
/// contact states).
pub fn diff_signatures_in(
    diff: &StateDiff,
    vocabulary: StateVocabulary,
) -> Result<BTreeSet<String>, NameError> {
    let mut out = BTreeSet::new();
    if diff.is_empty() {
        return Ok(out);
    }
    for op in ChangeOp::BOTH {
        let side = diff.side(op);
        for node in &side.nodes {
            // ENACT formats the name before looking at the states, so an unformattable name
            // fails even when no state would be described.
            let object = format_object_name(&node.name)?;
            for state in &node.states {
                if vocabulary.phrase(state).is_some() {
                    out.insert(node_signature(op, &object, state));
                }
            }
        }
        for edge in &side.edges {
            let from = format_object_name(&edge.from)?;
            let to = format_object_name(&edge.to)?;
            for state in &edge.states {
                if vocabulary.phrase(state).is_some() {
                    out.insert(edge_signature(op, &from, &to, state));
                }
            }
        }
    }
    out.extend(
        object_transitions(diff)?
            .iter()
            .map(ObjectTransition::signature),
    );
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_graph::diff::DiffSide;
    use crate::scene_graph::diff::tests::{edge_change as edge, node_change as change};

    fn sigs(add: DiffSide, remove: DiffSide) -> Vec<String> {
        diff_signatures(&StateDiff { add, remove })
            .unwrap()
            .into_iter()
            .collect()
    }

    #[test]
    fn node_and_edge_signatures_skip_unknown_states() {
        let add = DiffSide {
            nodes: vec![change("burner_tbgxvr_0", &["ToggledOn", "Unknown"], None)],
            edges: vec![edge(
                "robot_r1",
                "butter_cookie_3",
                &["LeftGrasping", "LeftContact"],
            )],
        };
        let remove = DiffSide {
            nodes: vec![change("fridge_petcxr_0", &["Open"], None)],
            edges: vec![edge("apple_1", "plate_2", &["OnTop"])],
        };
        assert_eq!(
            sigs(add, remove),
            [
                "edge_add_the robot r1_the butter cookie_LeftGrasping",
                "edge_remove_the apple_the plate_OnTop",
                "node_add_the burner_ToggledOn",
                "node_remove_the fridge_Open",
            ]
        );
        assert!(diff_signatures(&StateDiff::default()).unwrap().is_empty());
    }

    #[test]
    fn transition_from_one_removed_parent() {
        let add = DiffSide {
            nodes: vec![change("half_mushroom_2", &[], Some(&["mushroom_1"]))],
            edges: vec![],
        };
        let remove = DiffSide {
            nodes: vec![change("mushroom_1", &[], None)],
            edges: vec![],
        };
        assert_eq!(
            sigs(add, remove),
            ["node_transition_from_the mushroom_to_the half mushroom"]
        );
    }

    #[test]
    fn transition_from_several_removed_parents_is_sorted() {
        let add = DiffSide {
            nodes: vec![change(
                "diced__carrot",
                &[],
                Some(&["half_carrot_2", "half_carrot_1", "carrot_9"]),
            )],
            edges: vec![],
        };
        let remove = DiffSide {
            nodes: vec![
                change("half_carrot_1", &[], None),
                change("carrot_9", &[], None),
            ],
            edges: vec![],
        };
        assert_eq!(
            sigs(add, remove),
            ["node_transition_from_the carrot_the half carrot_to_the diced carrot"]
        );
    }

    #[test]
    fn cooked_transition_without_removed_parent() {
        let add = DiffSide {
            nodes: vec![change("cooked__diced__bacon", &[], Some(&["diced__bacon"]))],
            edges: vec![],
        };
        assert_eq!(
            sigs(add, DiffSide::default()),
            ["node_transition_from_the diced bacon_to_cooked"]
        );
    }

    #[test]
    fn single_parent_not_removed_and_no_parent() {
        let add = DiffSide {
            nodes: vec![
                change("half_apple_2", &[], Some(&["apple_1"])),
                change("dust", &[], Some(&[])),
                change("sliced_x_3", &[], Some(&["a_1", "b_2"])),
            ],
            edges: vec![],
        };
        assert_eq!(
            sigs(add, DiffSide::default()),
            ["node_transition_from_the apple_to_the half apple"]
        );
        // Whole objects disappearing produce nothing on their own.
        let remove = DiffSide {
            nodes: vec![change("apple_1", &[], None)],
            edges: vec![],
        };
        assert!(sigs(DiffSide::default(), remove).is_empty());
    }

    #[test]
    fn unformattable_names_are_errors() {
        let add = DiffSide {
            nodes: vec![change("_1", &["Weird"], None)],
            edges: vec![],
        };
        assert!(
            diff_signatures(&StateDiff {
                add,
                remove: DiffSide::default()
            })
            .is_err()
        );
    }

    #[test]
    fn only_the_contact_vocabulary_describes_gripper_contact() {
        assert_eq!(StateVocabulary::Enact.phrase("LeftContact"), None);
        assert_eq!(
            StateVocabulary::WithContact.phrase("RightContact"),
            Some("using the right gripper to touch")
        );
        assert_eq!(StateVocabulary::Enact.phrase("Touching"), Some("touching"));
        let contact_only = StateDiff {
            add: DiffSide {
                nodes: vec![],
                edges: vec![edge("robot_r1", "pan_1", &["RightContact"])],
            },
            remove: DiffSide::default(),
        };
        assert!(!StateVocabulary::Enact.is_meaningful(&contact_only));
        assert!(StateVocabulary::WithContact.is_meaningful(&contact_only));
    }
}
