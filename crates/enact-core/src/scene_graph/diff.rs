//! The state-centric diff between two scene graphs (ENACT's `generate_state_centric_diff`):
//! which states each object and relation gained or lost, and which objects appeared or
//! disappeared as a whole.

use std::collections::BTreeSet;

use rustc_hash::FxHashMap;
use serde::Serialize;

use crate::scene_graph::names::NameError;
use crate::scene_graph::record::{SceneGraph, SceneNode};

/// Whether a change entry gains or loses states.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ChangeOp {
    Add,
    Remove,
}

impl ChangeOp {
    /// Both operations in ENACT's processing order.
    pub const BOTH: [ChangeOp; 2] = [ChangeOp::Add, ChangeOp::Remove];

    /// The word used in signatures (`node_add_…`, `edge_remove_…`).
    pub fn as_str(self) -> &'static str {
        match self {
            ChangeOp::Add => "add",
            ChangeOp::Remove => "remove",
        }
    }
}

/// A node entry of a diff. With `states` empty it is a whole object appearing (add) or
/// disappearing (remove); otherwise it lists the states gained or lost.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct NodeChange {
    pub name: String,
    pub states: Vec<String>,
    pub category: Option<String>,
    /// For an object that appeared, the objects it came from (normalised for particle
    /// systems, see [`state_centric_diff`]); otherwise the node's `parent` field as stored.
    pub parent: Option<Vec<String>>,
}

impl NodeChange {
    /// Whether this entry is a whole object appearing or disappearing.
    pub fn is_whole_object(&self) -> bool {
        self.states.is_empty()
    }
}

/// An edge entry of a diff: the relation states `from -> to` gained or lost.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct EdgeChange {
    pub from: String,
    pub to: String,
    pub states: Vec<String>,
}

/// One side of a diff.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct DiffSide {
    pub nodes: Vec<NodeChange>,
    pub edges: Vec<EdgeChange>,
}

impl DiffSide {
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty() && self.edges.is_empty()
    }
}

/// A state-centric diff. Entries are in a deterministic order (whole objects first, then
/// state changes, each sorted by name; edges sorted by `(from, to)`; states sorted) where
/// ENACT's order comes from Python set iteration. An empty diff is ENACT's `{"type": "empty"}`.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct StateDiff {
    pub add: DiffSide,
    pub remove: DiffSide,
}

impl StateDiff {
    pub fn is_empty(&self) -> bool {
        self.add.is_empty() && self.remove.is_empty()
    }

    pub fn side(&self, op: ChangeOp) -> &DiffSide {
        match op {
            ChangeOp::Add => &self.add,
            ChangeOp::Remove => &self.remove,
        }
    }

    /// ENACT's `_has_meaningful_changes` (QA generation): any node entry at all, or an edge
    /// entry with a state that is not a `*Contact*` state.
    pub fn has_meaningful_change(&self) -> bool {
        ChangeOp::BOTH.iter().any(|&op| {
            let side = self.side(op);
            !side.nodes.is_empty()
                || side
                    .edges
                    .iter()
                    .any(|e| e.states.iter().any(|s| !s.contains("Contact")))
        })
    }

    /// The names of every object the diff touches: node entries and both ends of every edge
    /// entry (ENACT's `get_active_objects`).
    pub fn active_objects(&self) -> BTreeSet<&str> {
        let mut active = BTreeSet::new();
        for op in ChangeOp::BOTH {
            let side = self.side(op);
            active.extend(side.nodes.iter().map(|n| n.name.as_str()));
            for e in &side.edges {
                active.insert(e.from.as_str());
                active.insert(e.to.as_str());
            }
        }
        active
    }

    /// Names of objects that appeared or disappeared as a whole (entries with no states).
    pub fn created_or_deleted(&self) -> BTreeSet<&str> {
        ChangeOp::BOTH
            .iter()
            .flat_map(|&op| self.side(op).nodes.iter())
            .filter(|n| n.is_whole_object())
            .map(|n| n.name.as_str())
            .collect()
    }
}

/// Why a diff between two graphs could not be computed the way ENACT computes it. Each of
/// these is an exception in ENACT (caught by the evaluator's try/except where it has one).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DiffFault {
    #[error("particle system {node} appeared with an empty parent list")]
    SystemParentMissing { node: String },
    #[error(
        "particle system {node} appeared but no removed object matches its parent {parent} \
         (ENACT: \"Added node {node} has no corresponding parent\")"
    )]
    SystemParentNotRemoved { node: String, parent: String },
    #[error("object {object}: visibility reading for {sensor} is malformed: {problem}")]
    MalformedVisibility {
        object: String,
        sensor: String,
        problem: String,
    },
    #[error("visible object {object} has no category")]
    MissingCategory { object: String },
    #[error("object {node} changed state, has 'half' in its name and no parent list")]
    HalfNodeWithoutParent { node: String },
    #[error(transparent)]
    Name(#[from] NameError),
}

fn state_set(node_states: &[String]) -> BTreeSet<&str> {
    node_states.iter().map(String::as_str).collect()
}

fn owned(states: impl IntoIterator<Item = impl AsRef<str>>) -> Vec<String> {
    states.into_iter().map(|s| s.as_ref().to_string()).collect()
}

/// ENACT quirk: the parent recorded for an object that appeared. A particle system (category
/// `System`) with a parent is re-pointed at what was actually removed: a cooked system at its
/// uncooked self (`cooked__diced__x` -> `diced__x`), any other system at the removed objects
/// whose names contain `half_<parent>`, else `<parent>`. ENACT asserts that such an object
/// exists; going backwards across cooking (`diced__x` "appears" while only
/// `cooked__diced__x` "disappears") it does not, which we report as an error.
fn appeared_parent(node: &SceneNode, removed: &[&str]) -> Result<Option<Vec<String>>, DiffFault> {
    let Some(parent) = &node.parent else {
        return Ok(Some(Vec::new()));
    };
    if node.category.as_deref() != Some("System") {
        return Ok(Some(parent.clone()));
    }
    if node.name.to_lowercase().contains("cooked") {
        return Ok(Some(vec![node.name.replace("cooked__", "")]));
    }
    let first = parent
        .first()
        .ok_or_else(|| DiffFault::SystemParentMissing {
            node: node.name.clone(),
        })?;
    let half = format!("half_{first}");
    let mut matches: Vec<String> = owned(removed.iter().filter(|r| r.contains(half.as_str())));
    if matches.is_empty() {
        matches = owned(removed.iter().filter(|r| r.contains(first.as_str())));
    }
    if matches.is_empty() {
        return Err(DiffFault::SystemParentNotRemoved {
            node: node.name.clone(),
            parent: first.clone(),
        });
    }
    Ok(Some(matches))
}

/// A scene graph's lookups, built once per frame and shared by every pair the frame is in
/// (a task's key frames take part in dozens of pairs each).
#[derive(Debug)]
pub struct GraphIndex<'a> {
    pub graph: &'a SceneGraph,
    /// Each name's last node: ENACT's diff builds dicts, so a repeated name's last entry counts.
    last_node: FxHashMap<&'a str, &'a SceneNode>,
    /// Each name's first node: ENACT's visibility lookups scan the list and stop at the first.
    first_node: FxHashMap<&'a str, &'a SceneNode>,
    /// Each relation's states, the last entry winning for a repeated `(from, to)`.
    edges: FxHashMap<(&'a str, &'a str), &'a [String]>,
}

impl<'a> GraphIndex<'a> {
    pub fn new(graph: &'a SceneGraph) -> Self {
        let mut last_node =
            FxHashMap::with_capacity_and_hasher(graph.nodes.len(), Default::default());
        let mut first_node =
            FxHashMap::with_capacity_and_hasher(graph.nodes.len(), Default::default());
        for n in &graph.nodes {
            last_node.insert(n.name.as_str(), n);
            first_node.entry(n.name.as_str()).or_insert(n);
        }
        let edges = graph
            .edges
            .iter()
            .map(|e| ((e.from.as_str(), e.to.as_str()), e.states.as_slice()))
            .collect();
        GraphIndex {
            graph,
            last_node,
            first_node,
            edges,
        }
    }

    /// The first node named `name`, as ENACT's visibility lookups find it.
    pub fn first_node(&self, name: &str) -> Option<&'a SceneNode> {
        self.first_node.get(name).copied()
    }
}

/// The state-centric diff from `prev` to `next`. When a name or `(from, to)` pair occurs more
/// than once in a graph, its last entry counts (ENACT builds dicts).
pub fn state_centric_diff(prev: &SceneGraph, next: &SceneGraph) -> Result<StateDiff, DiffFault> {
    state_centric_diff_indexed(&GraphIndex::new(prev), &GraphIndex::new(next))
}

/// [`state_centric_diff`] over graphs already indexed.
pub fn state_centric_diff_indexed(
    prev: &GraphIndex<'_>,
    next: &GraphIndex<'_>,
) -> Result<StateDiff, DiffFault> {
    let (prev_nodes, next_nodes) = (&prev.last_node, &next.last_node);
    let mut diff = StateDiff::default();

    let mut removed: Vec<&str> = prev_nodes
        .keys()
        .copied()
        .filter(|n| !next_nodes.contains_key(n))
        .collect();
    removed.sort_unstable();
    for name in &removed {
        let node = prev_nodes[name];
        diff.remove.nodes.push(NodeChange {
            name: node.name.clone(),
            states: Vec::new(),
            category: node.category.clone(),
            parent: node.parent.clone(),
        });
    }

    let mut added: Vec<&str> = next_nodes
        .keys()
        .copied()
        .filter(|n| !prev_nodes.contains_key(n))
        .collect();
    added.sort_unstable();
    for name in added {
        let node = next_nodes[name];
        diff.add.nodes.push(NodeChange {
            name: node.name.clone(),
            states: Vec::new(),
            category: node.category.clone(),
            parent: appeared_parent(node, &removed)?,
        });
    }

    // Most objects keep their states between two key frames: equal lists cannot differ as
    // sets, so only the others are compared (and sorted).
    let mut changed: Vec<(&str, &SceneNode, &SceneNode)> = prev_nodes
        .iter()
        .filter_map(|(&name, &old)| {
            let new = *next_nodes.get(name)?;
            (old.states != new.states).then_some((name, old, new))
        })
        .collect();
    changed.sort_unstable_by_key(|&(name, _, _)| name);
    for (name, old, new) in changed {
        let (old_states, new_states) = (state_set(&old.states), state_set(&new.states));
        let gained: Vec<String> = owned(new_states.difference(&old_states));
        if !gained.is_empty() {
            diff.add.nodes.push(NodeChange {
                name: name.to_string(),
                states: gained,
                category: old.category.clone(),
                parent: new.parent.clone(),
            });
        }
        let lost: Vec<String> = owned(old_states.difference(&new_states));
        if !lost.is_empty() {
            diff.remove.nodes.push(NodeChange {
                name: name.to_string(),
                states: lost,
                category: old.category.clone(),
                parent: old.parent.clone(),
            });
        }
    }

    // Relations present on one side only, or with other states; an absent relation has none.
    let (prev_edges, next_edges) = (&prev.edges, &next.edges);
    let mut keys: Vec<(&str, &str)> = prev_edges
        .iter()
        .filter(|(key, states)| next_edges.get(*key).copied().unwrap_or_default() != **states)
        .map(|(key, _)| *key)
        .chain(
            next_edges
                .iter()
                .filter(|(key, states)| !prev_edges.contains_key(*key) && !states.is_empty())
                .map(|(key, _)| *key),
        )
        .collect();
    keys.sort_unstable();
    for key in keys {
        let old = state_set(prev_edges.get(&key).copied().unwrap_or_default());
        let new = state_set(next_edges.get(&key).copied().unwrap_or_default());
        let gained: Vec<String> = owned(new.difference(&old));
        if !gained.is_empty() {
            diff.add.edges.push(EdgeChange {
                from: key.0.to_string(),
                to: key.1.to_string(),
                states: gained,
            });
        }
        let lost: Vec<String> = owned(old.difference(&new));
        if !lost.is_empty() {
            diff.remove.edges.push(EdgeChange {
                from: key.0.to_string(),
                to: key.1.to_string(),
                states: lost,
            });
        }
    }
    Ok(diff)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::scene_graph::record::{SceneEdge, Visibility};

    pub(crate) fn node(name: &str, category: &str, states: &[&str]) -> SceneNode {
        SceneNode {
            name: name.to_string(),
            category: Some(category.to_string()),
            states: owned(states),
            visibility: Visibility::new(),
            parent: None,
        }
    }

    pub(crate) fn with_parent(mut n: SceneNode, parent: &[&str]) -> SceneNode {
        n.parent = Some(owned(parent));
        n
    }

    pub(crate) fn edge(from: &str, to: &str, states: &[&str]) -> SceneEdge {
        SceneEdge {
            from: from.to_string(),
            to: to.to_string(),
            states: owned(states),
        }
    }

    /// A node change as the diff reports it, for tests of what consumes diffs.
    pub(crate) fn node_change(name: &str, states: &[&str], parent: Option<&[&str]>) -> NodeChange {
        NodeChange {
            name: name.into(),
            states: owned(states),
            category: Some("x".into()),
            parent: parent.map(owned),
        }
    }

    /// An edge change as the diff reports it, for tests of what consumes diffs.
    pub(crate) fn edge_change(from: &str, to: &str, states: &[&str]) -> EdgeChange {
        EdgeChange {
            from: from.into(),
            to: to.into(),
            states: owned(states),
        }
    }

    fn graph(nodes: Vec<SceneNode>, edges: Vec<SceneEdge>) -> SceneGraph {
        SceneGraph { nodes, edges }
    }

    #[test]
    fn identical_graphs_give_an_empty_diff() {
        let g = graph(
            vec![node("a", "x", &["Open"]), node("a", "x", &["Cooked"])],
            vec![edge("a", "b", &["OnTop"])],
        );
        let d = state_centric_diff(&g, &g).unwrap();
        assert!(d.is_empty());
        assert!(!d.has_meaningful_change());
    }

    #[test]
    fn node_add_remove_and_state_changes() {
        let prev = graph(
            vec![
                node("fridge_1", "fridge", &["Open", "Frozen"]),
                node("apple_2", "apple", &[]),
            ],
            vec![],
        );
        let next = graph(
            vec![
                node("fridge_1", "fridge", &["Frozen", "ToggledOn"]),
                with_parent(node("half_apple_3", "half_apple", &[]), &["apple_2"]),
            ],
            vec![],
        );
        let d = state_centric_diff(&prev, &next).unwrap();
        assert_eq!(d.remove.nodes.len(), 2);
        assert_eq!(d.remove.nodes[0].name, "apple_2");
        assert!(d.remove.nodes[0].is_whole_object());
        assert_eq!(d.remove.nodes[1].states, ["Open"]);
        assert_eq!(d.add.nodes[0].name, "half_apple_3");
        assert_eq!(d.add.nodes[0].parent, Some(vec!["apple_2".to_string()]));
        assert_eq!(d.add.nodes[1].states, ["ToggledOn"]);
        assert_eq!(
            d.created_or_deleted(),
            BTreeSet::from(["apple_2", "half_apple_3"])
        );
        assert!(d.has_meaningful_change());
    }

    #[test]
    fn appeared_object_without_parent_gets_empty_parent_list() {
        let next = graph(vec![node("dust", "System", &[])], vec![]);
        let d = state_centric_diff(&SceneGraph::default(), &next).unwrap();
        assert_eq!(d.add.nodes[0].parent, Some(vec![]));
    }

    #[test]
    fn edge_updates_over_union_of_keys() {
        let prev = graph(
            vec![],
            vec![
                edge("a", "b", &["OnTop", "Touching"]),
                edge("r", "a", &["LeftGrasping"]),
            ],
        );
        let next = graph(
            vec![],
            vec![
                edge("a", "b", &["Touching", "Inside"]),
                edge("c", "d", &["RightContact"]),
            ],
        );
        let d = state_centric_diff(&prev, &next).unwrap();
        assert_eq!(
            d.add.edges,
            vec![
                edge_change("a", "b", &["Inside"]),
                edge_change("c", "d", &["RightContact"])
            ]
        );
        assert_eq!(
            d.remove.edges,
            vec![
                edge_change("a", "b", &["OnTop"]),
                edge_change("r", "a", &["LeftGrasping"])
            ]
        );
        assert_eq!(
            d.active_objects(),
            BTreeSet::from(["a", "b", "c", "d", "r"])
        );
        // Only a Contact edge: not meaningful.
        let only_contact = graph(vec![], vec![edge("c", "d", &["RightContact"])]);
        let d = state_centric_diff(&SceneGraph::default(), &only_contact).unwrap();
        assert!(!d.has_meaningful_change());
    }

    #[test]
    fn duplicate_names_use_the_last_entry() {
        let prev = graph(vec![node("a", "x", &["Open"]), node("a", "x", &[])], vec![]);
        let next = graph(vec![node("a", "x", &[])], vec![]);
        assert!(state_centric_diff(&prev, &next).unwrap().is_empty());
    }

    #[test]
    fn system_parents_are_normalised() {
        // Cooked system: parent is its uncooked name, whatever was stored.
        let prev = graph(vec![node("diced__bacon", "System", &[])], vec![]);
        let next = graph(
            vec![
                node("diced__bacon", "System", &[]),
                with_parent(node("cooked__diced__bacon", "System", &[]), &["something"]),
            ],
            vec![],
        );
        let d = state_centric_diff(&prev, &next).unwrap();
        assert_eq!(
            d.add.nodes[0].parent,
            Some(vec!["diced__bacon".to_string()])
        );

        // Diced system: the removed half object wins over the removed whole object.
        let prev = graph(
            vec![
                node("half_carrot_1", "half_carrot", &[]),
                node("carrot_1", "carrot", &[]),
            ],
            vec![],
        );
        let next = graph(
            vec![with_parent(
                node("diced__carrot", "System", &[]),
                &["carrot_1"],
            )],
            vec![],
        );
        let d = state_centric_diff(&prev, &next).unwrap();
        assert_eq!(
            d.add.nodes[0].parent,
            Some(vec!["half_carrot_1".to_string()])
        );
        let prev = graph(vec![node("carrot_1", "carrot", &[])], vec![]);
        let d = state_centric_diff(&prev, &next).unwrap();
        assert_eq!(d.add.nodes[0].parent, Some(vec!["carrot_1".to_string()]));
    }

    #[test]
    fn backward_across_cooking_is_an_error() {
        let cooked = graph(vec![node("cooked__diced__bacon", "System", &[])], vec![]);
        let raw = graph(
            vec![with_parent(
                node("diced__bacon", "System", &[]),
                &["bacon_1"],
            )],
            vec![],
        );
        assert!(state_centric_diff(&raw, &cooked).is_ok());
        let err = state_centric_diff(&cooked, &raw).unwrap_err();
        assert_eq!(
            err,
            DiffFault::SystemParentNotRemoved {
                node: "diced__bacon".into(),
                parent: "bacon_1".into()
            }
        );
        let empty_parent = graph(
            vec![with_parent(node("diced__bacon", "System", &[]), &[])],
            vec![],
        );
        assert!(matches!(
            state_centric_diff(&SceneGraph::default(), &empty_parent),
            Err(DiffFault::SystemParentMissing { .. })
        ));
    }
}
