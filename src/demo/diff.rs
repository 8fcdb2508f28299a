//! Scene graphs of the demo world and the state-centric diff between two of them, shaped like
//! ENACT's visible diff (added/removed node states, edge states and whole objects).

use std::collections::{BTreeMap, BTreeSet};

use crate::demo::world::{Gripper, Placement, Thing, WorldState};

/// Unary predicates, named as in OmniGibson.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum NodeState {
    Cooked,
    Open,
    ToggledOn,
}

/// Binary predicates, named as in OmniGibson.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum EdgeState {
    Inside,
    OnTop,
    LeftGrasping,
    RightGrasping,
}

/// One key frame's scene graph: the objects with their unary states, and the relations.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct SceneGraph {
    nodes: BTreeMap<Thing, BTreeSet<NodeState>>,
    edges: BTreeMap<(Thing, Thing), BTreeSet<EdgeState>>,
    parents: BTreeMap<Thing, Thing>,
}

impl SceneGraph {
    pub(crate) fn of(state: &WorldState) -> SceneGraph {
        let mut nodes: BTreeMap<Thing, BTreeSet<NodeState>> = Thing::FIXED
            .iter()
            .chain(state.placements.keys())
            .map(|t| (*t, BTreeSet::new()))
            .collect();
        let mut mark = |thing: Thing, node_state: NodeState| {
            if let Some(states) = nodes.get_mut(&thing) {
                states.insert(node_state);
            }
        };
        if state.fridge_open {
            mark(Thing::Fridge, NodeState::Open);
        }
        if state.stove_on {
            mark(Thing::Stove, NodeState::ToggledOn);
        }
        for food in &state.cooked {
            mark(*food, NodeState::Cooked);
        }
        let mut edges: BTreeMap<(Thing, Thing), BTreeSet<EdgeState>> = BTreeMap::new();
        for (thing, placement) in &state.placements {
            let (key, relation) = match placement {
                Placement::OnTop(support) => ((*thing, *support), EdgeState::OnTop),
                Placement::Inside(container) => ((*thing, *container), EdgeState::Inside),
                Placement::HeldBy(Gripper::Left) => {
                    ((Thing::Robot, *thing), EdgeState::LeftGrasping)
                }
                Placement::HeldBy(Gripper::Right) => {
                    ((Thing::Robot, *thing), EdgeState::RightGrasping)
                }
            };
            edges.entry(key).or_default().insert(relation);
        }
        SceneGraph {
            nodes,
            edges,
            parents: state.parents.clone(),
        }
    }
}

/// A node entry of a diff. Empty `states` means the whole object appeared or disappeared.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct NodeChange {
    pub(crate) thing: Thing,
    pub(crate) states: Vec<NodeState>,
    pub(crate) parent: Option<Thing>,
}

/// An edge entry of a diff: relations from `from` to `to` that appeared or disappeared.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct EdgeChange {
    pub(crate) from: Thing,
    pub(crate) to: Thing,
    pub(crate) states: Vec<EdgeState>,
}

/// The added or the removed half of a diff.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct DiffSide {
    pub(crate) nodes: Vec<NodeChange>,
    pub(crate) edges: Vec<EdgeChange>,
}

/// What changed between two key frames.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct StateDiff {
    pub(crate) add: DiffSide,
    pub(crate) remove: DiffSide,
}

/// An object created from another one (an apple becoming halves).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Transition {
    pub(crate) from: Thing,
    pub(crate) to: Thing,
}

impl StateDiff {
    /// The diff from graph `a` to graph `b`, after ENACT's ambiguity filter.
    pub(crate) fn between(a: &SceneGraph, b: &SceneGraph) -> StateDiff {
        let mut diff = StateDiff::default();
        let names: BTreeSet<Thing> = a.nodes.keys().chain(b.nodes.keys()).copied().collect();
        for thing in names {
            match (a.nodes.get(&thing), b.nodes.get(&thing)) {
                (Some(_), None) => diff.remove.nodes.push(NodeChange {
                    thing,
                    states: Vec::new(),
                    parent: a.parents.get(&thing).copied(),
                }),
                (None, Some(_)) => diff.add.nodes.push(NodeChange {
                    thing,
                    states: Vec::new(),
                    parent: b.parents.get(&thing).copied(),
                }),
                (Some(before), Some(after)) => {
                    let parent = b.parents.get(&thing).copied();
                    let gained: Vec<NodeState> = after.difference(before).copied().collect();
                    let lost: Vec<NodeState> = before.difference(after).copied().collect();
                    if !gained.is_empty() {
                        diff.add.nodes.push(NodeChange {
                            thing,
                            states: gained,
                            parent,
                        });
                    }
                    if !lost.is_empty() {
                        diff.remove.nodes.push(NodeChange {
                            thing,
                            states: lost,
                            parent,
                        });
                    }
                }
                (None, None) => {}
            }
        }
        let keys: BTreeSet<(Thing, Thing)> =
            a.edges.keys().chain(b.edges.keys()).copied().collect();
        let none = BTreeSet::new();
        for (from, to) in keys {
            let before = a.edges.get(&(from, to)).unwrap_or(&none);
            let after = b.edges.get(&(from, to)).unwrap_or(&none);
            let gained: Vec<EdgeState> = after.difference(before).copied().collect();
            let lost: Vec<EdgeState> = before.difference(after).copied().collect();
            if !gained.is_empty() {
                diff.add.edges.push(EdgeChange {
                    from,
                    to,
                    states: gained,
                });
            }
            if !lost.is_empty() {
                diff.remove.edges.push(EdgeChange {
                    from,
                    to,
                    states: lost,
                });
            }
        }
        diff.drop_ambiguous();
        diff
    }

    /// ENACT quirk: when two changed objects share a category (the two apple halves), their
    /// relations cannot be told apart in text, so ENACT's visible diff drops those edges and keeps
    /// only "half" node entries. We apply the same rule so our action text reads like theirs.
    fn drop_ambiguous(&mut self) {
        let mut active: BTreeSet<Thing> = BTreeSet::new();
        for side in [&self.add, &self.remove] {
            active.extend(side.nodes.iter().map(|n| n.thing));
            active.extend(side.edges.iter().flat_map(|e| [e.from, e.to]));
        }
        let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
        for thing in &active {
            *counts.entry(thing.category()).or_default() += 1;
        }
        let ambiguous = |thing: Thing| counts.get(thing.category()).copied().unwrap_or(0) > 1;
        for side in [&mut self.add, &mut self.remove] {
            side.nodes
                .retain(|n| !ambiguous(n.thing) || (n.thing.is_half() && n.parent.is_some()));
            side.edges
                .retain(|e| !ambiguous(e.from) && !ambiguous(e.to));
        }
    }

    /// ENACT quirk: transition sentences are collected in a set of formatted names, so the two
    /// halves of one apple give a single "the apple now becomes the half apple". Returns the
    /// objects that appeared with a parent, each (parent, child phrase) once.
    pub(crate) fn transitions(&self) -> Vec<Transition> {
        let mut seen: Vec<Transition> = Vec::new();
        for node in self.add.nodes.iter().filter(|n| n.states.is_empty()) {
            let Some(parent) = node.parent else { continue };
            let repeated = seen
                .iter()
                .any(|t| t.from == parent && t.to.phrase() == node.thing.phrase());
            if !repeated {
                seen.push(Transition {
                    from: parent,
                    to: node.thing,
                });
            }
        }
        seen
    }

    /// How many sentences the action text of this diff has (one per changed predicate, one per
    /// transition), independent of which phrasing template is picked.
    pub(crate) fn sentence_count(&self) -> usize {
        let per_side = |side: &DiffSide| {
            side.nodes.iter().map(|n| n.states.len()).sum::<usize>()
                + side.edges.iter().map(|e| e.states.len()).sum::<usize>()
        };
        per_side(&self.add) + per_side(&self.remove) + self.transitions().len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::world::Step;

    fn graph(state: &WorldState) -> SceneGraph {
        SceneGraph::of(state)
    }

    fn start() -> WorldState {
        let mut placements = BTreeMap::new();
        placements.insert(Thing::Apple, Placement::OnTop(Thing::Counter));
        placements.insert(Thing::Knife, Placement::OnTop(Thing::Counter));
        WorldState {
            placements,
            fridge_open: false,
            stove_on: false,
            cooked: BTreeSet::new(),
            parents: BTreeMap::new(),
        }
    }

    #[test]
    fn grasping_adds_a_grasp_edge_and_removes_the_support_edge() {
        let a = start();
        let b = a.apply(Step::Grasp(Gripper::Left, Thing::Apple)).unwrap();
        let diff = StateDiff::between(&graph(&a), &graph(&b));
        assert_eq!(
            diff.add.edges,
            vec![EdgeChange {
                from: Thing::Robot,
                to: Thing::Apple,
                states: vec![EdgeState::LeftGrasping]
            }]
        );
        assert_eq!(
            diff.remove.edges,
            vec![EdgeChange {
                from: Thing::Apple,
                to: Thing::Counter,
                states: vec![EdgeState::OnTop]
            }]
        );
        assert!(diff.add.nodes.is_empty() && diff.remove.nodes.is_empty());
        assert_eq!(diff.sentence_count(), 2);
    }

    #[test]
    fn identical_states_have_an_empty_diff() {
        let a = start();
        let diff = StateDiff::between(&graph(&a), &graph(&a));
        assert_eq!(diff, StateDiff::default());
        assert_eq!(diff.sentence_count(), 0);
    }

    #[test]
    fn slicing_keeps_one_transition_and_drops_edges_of_the_halves() {
        let a = start()
            .apply(Step::Grasp(Gripper::Left, Thing::Apple))
            .and_then(|s| {
                s.apply(Step::Place(
                    Gripper::Left,
                    Placement::OnTop(Thing::CuttingBoard),
                ))
            })
            .and_then(|s| s.apply(Step::Grasp(Gripper::Right, Thing::Knife)))
            .unwrap();
        let b = a.apply(Step::SliceApple).unwrap();
        let diff = StateDiff::between(&graph(&a), &graph(&b));
        assert_eq!(
            diff.transitions(),
            vec![Transition {
                from: Thing::Apple,
                to: Thing::HalfApple1
            }]
        );
        assert!(diff.add.edges.is_empty(), "{:?}", diff.add.edges);
        // The apple's own relation to the board disappears and is still described.
        assert_eq!(diff.remove.edges.len(), 1);
        assert_eq!(diff.sentence_count(), 2);
    }

    #[test]
    fn turning_on_the_stove_is_one_node_state() {
        let a = start();
        let b = a.apply(Step::TurnOnStove).unwrap();
        let diff = StateDiff::between(&graph(&a), &graph(&b));
        assert_eq!(
            diff.add.nodes,
            vec![NodeChange {
                thing: Thing::Stove,
                states: vec![NodeState::ToggledOn],
                parent: None
            }]
        );
        let back = StateDiff::between(&graph(&b), &graph(&a));
        assert_eq!(back.remove.nodes.len(), 1);
        assert_eq!(back.sentence_count(), 1);
    }
}
