//! Contact relations (the paper's contact ablation, table `tab:contact_ablation`): which edge
//! states count as contact, the contact relations of a graph, and the phrases a contact run's
//! sentences give the grippers' contact states.
//!
//! ENACT's replays record three binary contact states on edges: `Touching` (two objects touch;
//! ENACT already describes it as "touching"), and the robot's `LeftContact` and `RightContact`
//! (a gripper touches an object; ENACT describes neither and does not count an edge holding only
//! them as a meaningful change). A run with contact key frames describes all three; a default
//! run keeps ENACT's vocabulary ([`crate::scene_graph::signature::StateVocabulary`]), so
//! its sentences and signatures stay ENACT's.

use std::collections::BTreeSet;

use crate::scene_graph::record::SceneGraph;

/// The edge states that are contact relations.
pub const CONTACT_STATES: [&str; 3] = ["Touching", "LeftContact", "RightContact"];

/// Phrases of the contact states ENACT's table lacks, in its "using the ... gripper to grasp"
/// style (`Touching` keeps ENACT's own "touching").
pub const CONTACT_PHRASES: [(&str, &str); 2] = [
    ("LeftContact", "using the left gripper to touch"),
    ("RightContact", "using the right gripper to touch"),
];

/// Whether an edge state is a contact relation.
pub fn is_contact_state(state: &str) -> bool {
    CONTACT_STATES.contains(&state)
}

/// The `(from, to, state)` contact relations of a graph.
pub fn contact_relations(graph: &SceneGraph) -> BTreeSet<(&str, &str, &str)> {
    graph
        .edges
        .iter()
        .flat_map(|e| {
            e.states
                .iter()
                .filter(|s| is_contact_state(s))
                .map(move |s| (e.from.as_str(), e.to.as_str(), s.as_str()))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_graph::diff::tests::{edge, node};

    #[test]
    fn contact_relations_are_the_three_contact_states_of_edges() {
        let graph = SceneGraph {
            nodes: vec![node("robot_r1", "agent", &[])],
            edges: vec![
                edge("robot_r1", "pan_1", &["LeftGrasping", "LeftContact"]),
                edge("apple_2", "table_3", &["OnTop", "Touching"]),
                edge("apple_2", "bowl_4", &["NextTo"]),
            ],
        };
        let found: Vec<_> = contact_relations(&graph).into_iter().collect();
        assert_eq!(
            found,
            [
                ("apple_2", "table_3", "Touching"),
                ("robot_r1", "pan_1", "LeftContact")
            ]
        );
    }
}
