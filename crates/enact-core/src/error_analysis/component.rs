//! Signatures parsed into components (the paper's `c ::= (γ, e1, ρ, e2) | (γ, e, ρ) |
//! (transition, e, ρ_from → ρ_to)`), the unit every error count is made of.
//!
//! The grammar is the one the scene-graph code writes (`scene_graph::signature`):
//! `edge_{add|remove}_{from}_{to}_{State}`, `node_{add|remove}_{object}_{State}` and
//! `node_transition_from_{sources joined by _}_to_{target}`. Formatted object names never hold
//! an underscore (ENACT joins name parts with spaces), so `_` splits fields unambiguously.

use std::fmt;

use serde::Serialize;

use crate::scene_graph::signature::state_phrase;

/// What a component changes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ComponentKind {
    /// A relation between two objects (`Inside`, `LeftGrasping`, ...).
    Edge,
    /// A state of one object (`Open`, `Cooked`, ...).
    Node,
    /// An object turning into another (sliced, diced, cooked particles).
    Transition,
}

/// How it changes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Operation {
    Add,
    Remove,
    Transition,
}

/// One atomic state change.
///
/// For a transition, `entities` are the sources (sorted, as ENACT writes them) and `predicate`
/// is the target: "the apple → the half apple" has entity "the apple" and predicate
/// "the half apple", so a wrong result is a predicate substitution and a wrong source an
/// entity substitution.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub struct Component {
    pub kind: ComponentKind,
    pub operation: Operation,
    pub entities: Vec<String>,
    pub predicate: String,
}

/// A signature outside the grammar.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{0}` is not a state-change signature")]
pub struct ComponentParseError(pub String);

impl Component {
    /// Parses one signature string.
    pub fn parse(signature: &str) -> Result<Component, ComponentParseError> {
        let bad = || ComponentParseError(signature.to_owned());
        if let Some(rest) = signature.strip_prefix("node_transition_from_") {
            // Sources are names ("the ..."), so a field that is exactly "to" is the separator.
            let fields: Vec<&str> = rest.split('_').collect();
            let to = fields.iter().rposition(|f| *f == "to").ok_or_else(bad)?;
            let (sources, target) = (&fields[..to], &fields[to + 1..]);
            if sources.is_empty() || target.len() != 1 || fields.iter().any(|s| s.is_empty()) {
                return Err(bad());
            }
            return Ok(Component {
                kind: ComponentKind::Transition,
                operation: Operation::Transition,
                entities: sources.iter().map(|s| (*s).to_owned()).collect(),
                predicate: target[0].to_owned(),
            });
        }
        let fields: Vec<&str> = signature.split('_').collect();
        let operation = match fields.get(1) {
            Some(&"add") => Operation::Add,
            Some(&"remove") => Operation::Remove,
            _ => return Err(bad()),
        };
        let (kind, arity) = match fields[0] {
            "node" => (ComponentKind::Node, 1),
            "edge" => (ComponentKind::Edge, 2),
            _ => return Err(bad()),
        };
        if fields.len() != arity + 3 || fields.iter().any(|f| f.is_empty()) {
            return Err(bad());
        }
        Ok(Component {
            kind,
            operation,
            entities: fields[2..2 + arity]
                .iter()
                .map(|s| (*s).to_owned())
                .collect(),
            predicate: fields[2 + arity].to_owned(),
        })
    }

    /// The hand a grasping component names, if any.
    pub fn hand(&self) -> Option<Hand> {
        match (self.kind, self.predicate.as_str()) {
            (ComponentKind::Edge | ComponentKind::Node, "LeftGrasping") => Some(Hand::Left),
            (ComponentKind::Edge | ComponentKind::Node, "RightGrasping") => Some(Hand::Right),
            _ => None,
        }
    }

    /// The change as an English sentence, in the words of ENACT's action templates ("The
    /// fridge is no longer open.").
    pub fn sentence(&self) -> String {
        let phrase = state_phrase(&self.predicate).unwrap_or(&self.predicate);
        let text = match (self.kind, self.operation) {
            (ComponentKind::Transition, _) if self.predicate == "cooked" => {
                format!("{} is now cooked", self.entities.join(", "))
            }
            (ComponentKind::Transition, _) => {
                format!(
                    "{} now becomes {}",
                    and_list(&self.entities),
                    self.predicate
                )
            }
            (ComponentKind::Node, Operation::Remove) => {
                format!("{} is no longer {phrase}", self.entities[0])
            }
            (ComponentKind::Node, _) => format!("{} becomes {phrase}", self.entities[0]),
            (ComponentKind::Edge, Operation::Remove) => format!(
                "{} is no longer {phrase} {}",
                self.entities[0], self.entities[1]
            ),
            (ComponentKind::Edge, _) => {
                format!("{} becomes {phrase} {}", self.entities[0], self.entities[1])
            }
        };
        let mut chars = text.chars();
        match chars.next() {
            Some(first) => format!("{}{}.", first.to_uppercase(), chars.as_str()),
            None => text,
        }
    }
}

fn and_list(names: &[String]) -> String {
    match names {
        [] => String::new(),
        [one] => one.clone(),
        [init @ .., last] => format!("{}, and {last}", init.join(", ")),
    }
}

impl fmt::Display for Component {
    /// Back to the signature string it was parsed from.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.kind {
            ComponentKind::Transition => write!(
                f,
                "node_transition_from_{}_to_{}",
                self.entities.join("_"),
                self.predicate
            ),
            kind => {
                let kind = if kind == ComponentKind::Edge {
                    "edge"
                } else {
                    "node"
                };
                let op = if self.operation == Operation::Add {
                    "add"
                } else {
                    "remove"
                };
                write!(
                    f,
                    "{kind}_{op}_{}_{}",
                    self.entities.join("_"),
                    self.predicate
                )
            }
        }
    }
}

/// A robot gripper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Hand {
    Left,
    Right,
}

impl Hand {
    pub const BOTH: [Hand; 2] = [Hand::Left, Hand::Right];

    pub fn other(self) -> Hand {
        match self {
            Hand::Left => Hand::Right,
            Hand::Right => Hand::Left,
        }
    }

    pub fn as_str(self) -> &'static str {
        match self {
            Hand::Left => "left",
            Hand::Right => "right",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_three_shapes_and_prints_them_back() {
        for (signature, kind, operation, entities, predicate) in [
            (
                "edge_remove_the robot r1_the apple_RightGrasping",
                ComponentKind::Edge,
                Operation::Remove,
                vec!["the robot r1", "the apple"],
                "RightGrasping",
            ),
            (
                "node_add_the burner_ToggledOn",
                ComponentKind::Node,
                Operation::Add,
                vec!["the burner"],
                "ToggledOn",
            ),
            (
                "node_transition_from_the apple_to_the half apple",
                ComponentKind::Transition,
                Operation::Transition,
                vec!["the apple"],
                "the half apple",
            ),
            (
                "node_transition_from_the bread_the butter_to_the sandwich",
                ComponentKind::Transition,
                Operation::Transition,
                vec!["the bread", "the butter"],
                "the sandwich",
            ),
            (
                "node_transition_from_the diced bacon_to_cooked",
                ComponentKind::Transition,
                Operation::Transition,
                vec!["the diced bacon"],
                "cooked",
            ),
        ] {
            let c = Component::parse(signature).unwrap();
            assert_eq!(c.kind, kind, "{signature}");
            assert_eq!(c.operation, operation, "{signature}");
            assert_eq!(c.entities, entities, "{signature}");
            assert_eq!(c.predicate, predicate, "{signature}");
            assert_eq!(c.to_string(), signature);
        }
    }

    #[test]
    fn refuses_what_is_outside_the_grammar() {
        for bad in [
            "",
            "edge_add_the a_Inside",
            "node_flip_the a_Open",
            "node_add_the a_the b_Open",
            "node_transition_from__to_the b",
            "node_transition_from_the a_to_",
            // No source, or a target of two fields: a transition has one of each at least.
            "node_transition_from_to_the b",
            "node_transition_from_the a_to_the b_the c",
            "thing_add_the a_Open",
        ] {
            assert!(Component::parse(bad).is_err(), "{bad:?} was accepted");
        }
    }

    #[test]
    fn sentences_use_the_action_templates() {
        let s = |sig: &str| Component::parse(sig).unwrap().sentence();
        assert_eq!(
            s("node_remove_the fridge_Open"),
            "The fridge is no longer open."
        );
        assert_eq!(
            s("edge_add_the robot r1_the apple_LeftGrasping"),
            "The robot r1 becomes using the left gripper to grasp the apple."
        );
        assert_eq!(
            s("node_transition_from_the apple_to_the half apple"),
            "The apple now becomes the half apple."
        );
        assert_eq!(
            s("node_transition_from_the diced bacon_to_cooked"),
            "The diced bacon is now cooked."
        );
    }

    #[test]
    fn only_grasping_names_a_hand() {
        let hand = |sig: &str| Component::parse(sig).unwrap().hand();
        assert_eq!(
            hand("edge_add_the robot r1_the a_LeftGrasping"),
            Some(Hand::Left)
        );
        assert_eq!(
            hand("edge_add_the robot r1_the a_RightGrasping"),
            Some(Hand::Right)
        );
        assert_eq!(hand("edge_add_the robot r1_the a_Grasping"), None);
        assert_eq!(hand("edge_add_the a_the b_Inside"), None);
    }
}
