//! The paper's semantic error categories, from one predicate → category table.
//!
//! Every state ENACT's sentence templates know (`scene_graph::signature::STATE_PHRASES`) is in
//! [`PREDICATE_CATEGORIES`]; a unit test fails when one is missing. Object transitions
//! (slicing, dicing, cooking into a new object) change what an object is made of, so they are
//! material states.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::component::{Component, ComponentKind};

/// What kind of world knowledge a wrong component is about.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum SemanticCategory {
    /// Where objects are relative to each other.
    SpatialRelations,
    /// What an object is doing or set to (open, switched on, burning).
    FunctionalStates,
    /// What an object is made of or its physical condition (cooked, frozen, sliced, soaked).
    MaterialStates,
    /// What the robot's grippers hold.
    AgentInteraction,
}

impl SemanticCategory {
    pub const ALL: [SemanticCategory; 4] = [
        SemanticCategory::SpatialRelations,
        SemanticCategory::FunctionalStates,
        SemanticCategory::MaterialStates,
        SemanticCategory::AgentInteraction,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            SemanticCategory::SpatialRelations => "spatial_relations",
            SemanticCategory::FunctionalStates => "functional_states",
            SemanticCategory::MaterialStates => "material_states",
            SemanticCategory::AgentInteraction => "agent_interaction",
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            SemanticCategory::SpatialRelations => "Spatial relations",
            SemanticCategory::FunctionalStates => "Functional states",
            SemanticCategory::MaterialStates => "Material states",
            SemanticCategory::AgentInteraction => "Agent interaction",
        }
    }

    pub fn index(self) -> usize {
        self as usize
    }
}

/// Predicate → category, for every state that produces a signature.
pub const PREDICATE_CATEGORIES: [(&str, SemanticCategory); 26] = {
    use SemanticCategory::*;
    [
        ("Inside", SpatialRelations),
        ("OnTop", SpatialRelations),
        ("NextTo", SpatialRelations),
        ("Under", SpatialRelations),
        ("Touching", SpatialRelations),
        ("AttachedTo", SpatialRelations),
        ("Covered", SpatialRelations),
        ("Draped", SpatialRelations),
        ("Overlaid", SpatialRelations),
        ("Contains", SpatialRelations),
        ("Open", FunctionalStates),
        ("ToggledOn", FunctionalStates),
        ("OnFire", FunctionalStates),
        ("HeatSourceOrSink", FunctionalStates),
        ("InFOVofRobot", FunctionalStates),
        ("Cooked", MaterialStates),
        ("Burnt", MaterialStates),
        ("Frozen", MaterialStates),
        ("Heated", MaterialStates),
        ("Folded", MaterialStates),
        ("Unfolded", MaterialStates),
        ("Filled", MaterialStates),
        ("Saturated", MaterialStates),
        ("Grasping", AgentInteraction),
        ("LeftGrasping", AgentInteraction),
        ("RightGrasping", AgentInteraction),
    ]
};

/// The category of a component, `None` for a predicate outside the table (which no signature
/// ENACT writes has).
pub fn category(component: &Component) -> Option<SemanticCategory> {
    if component.kind == ComponentKind::Transition {
        return Some(SemanticCategory::MaterialStates);
    }
    PREDICATE_CATEGORIES
        .iter()
        .find(|(p, _)| *p == component.predicate)
        .map(|(_, c)| *c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_graph::signature::STATE_PHRASES;

    #[test]
    fn every_state_enact_describes_has_a_category() {
        for (state, _, _) in STATE_PHRASES {
            assert!(
                PREDICATE_CATEGORIES.iter().any(|(p, _)| *p == state),
                "state {state} has no semantic category"
            );
        }
        for (p, _) in PREDICATE_CATEGORIES {
            assert!(
                STATE_PHRASES.iter().any(|(s, _, _)| *s == p),
                "{p} is not a state ENACT describes"
            );
        }
    }

    #[test]
    fn each_category_has_its_predicates() {
        let c = |sig: &str| category(&Component::parse(sig).unwrap()).unwrap();
        assert_eq!(
            c("edge_add_the apple_the fridge_Inside"),
            SemanticCategory::SpatialRelations
        );
        assert_eq!(
            c("node_remove_the fridge_Open"),
            SemanticCategory::FunctionalStates
        );
        assert_eq!(
            c("node_add_the bacon_Cooked"),
            SemanticCategory::MaterialStates
        );
        assert_eq!(
            c("node_transition_from_the apple_to_the half apple"),
            SemanticCategory::MaterialStates
        );
        assert_eq!(
            c("edge_add_the robot r1_the apple_LeftGrasping"),
            SemanticCategory::AgentInteraction
        );
        assert_eq!(
            category(&Component::parse("node_add_the a_Sliced").unwrap()),
            None
        );
    }
}
