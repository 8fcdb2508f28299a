//! Per-frame scene-graph records as BEHAVIOR-1K's `SceneGraphWriter` stores them: nodes, edges,
//! and the `full` / `diff` / `empty` record kinds of `scene_graph_0.json`.

use std::collections::{BTreeMap, HashMap};

use serde::{Deserialize, Deserializer, Serialize};

/// One object (or particle system) in a frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneNode {
    pub name: String,
    /// `"System"` for particle systems. Optional because the reader never requires it; the
    /// visibility filter reports a missing category as an error, like ENACT's assertion.
    #[serde(default)]
    pub category: Option<String>,
    #[serde(default, deserialize_with = "null_as_default")]
    pub states: Vec<String>,
    /// Sensor name -> `[pixel_count, xmin, ymin, xmax, ymax, img_h, img_w]`; `{}` when unseen.
    #[serde(default, deserialize_with = "null_as_default")]
    pub visibility: Visibility,
    /// Objects this one was created from (slicing, dicing, cooking). Absent and `null` mean the
    /// same to ENACT (`node.get('parent', None)`), so both become `None`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parent: Option<Vec<String>>,
}

/// Per-sensor visibility readings of one node. Numbers are kept as written (integers stay
/// integers when a graph is written back out).
pub type Visibility = BTreeMap<String, SensorReading>;

/// `[pixel_count, xmin, ymin, xmax, ymax, img_h, img_w]` as stored; an empty list (or `null`)
/// means "not seen by this sensor".
pub type SensorReading = Vec<serde_json::Number>;

/// A directed relation between two nodes (`from` is the subject).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneEdge {
    pub from: String,
    pub to: String,
    #[serde(default, deserialize_with = "null_as_default")]
    pub states: Vec<String>,
}

/// The scene graph of one frame. List order is kept: ENACT looks nodes up by "first with this
/// name" in some places and "last with this name" in others, which only differ when a name
/// occurs twice (the transient filter can cause that).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SceneGraph {
    pub nodes: Vec<SceneNode>,
    pub edges: Vec<SceneEdge>,
}

/// One side (`add`, `remove` or `update`) of an old-style `diff` record.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct DeltaSide {
    #[serde(default, deserialize_with = "null_as_default")]
    pub nodes: Vec<SceneNode>,
    #[serde(default, deserialize_with = "null_as_default")]
    pub edges: Vec<SceneEdge>,
}

/// An old-style `diff` record: whole nodes/edges added, removed (matched by name or by
/// `(from, to)`), or replaced by their new complete value.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct GraphDelta {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub add: Option<DeltaSide>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub remove: Option<DeltaSide>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub update: Option<DeltaSide>,
}

/// A record of `scene_graph_0.json`, keyed there by frame id.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", try_from = "RawFrameRecord")]
pub enum FrameRecord {
    Full(SceneGraph),
    Diff(GraphDelta),
    /// `{"type": "empty"}`; also any record whose `type` is missing or unknown, because
    /// ENACT's reader only acts on `full` and `diff` and skips everything else.
    Empty,
}

/// The record as written, before its `type` decides which fields matter.
#[derive(Deserialize)]
struct RawFrameRecord {
    #[serde(rename = "type", default)]
    kind: Option<String>,
    #[serde(default)]
    nodes: Option<Vec<SceneNode>>,
    #[serde(default)]
    edges: Option<Vec<SceneEdge>>,
    #[serde(default)]
    add: Option<DeltaSide>,
    #[serde(default)]
    remove: Option<DeltaSide>,
    #[serde(default)]
    update: Option<DeltaSide>,
}

impl TryFrom<RawFrameRecord> for FrameRecord {
    type Error = String;

    fn try_from(raw: RawFrameRecord) -> Result<Self, Self::Error> {
        match raw.kind.as_deref() {
            Some("full") => {
                let nodes = raw
                    .nodes
                    .ok_or_else(|| "a `full` record has no `nodes` list".to_string())?;
                let edges = raw
                    .edges
                    .ok_or_else(|| "a `full` record has no `edges` list".to_string())?;
                Ok(FrameRecord::Full(SceneGraph { nodes, edges }))
            }
            Some("diff") => Ok(FrameRecord::Diff(GraphDelta {
                add: raw.add,
                remove: raw.remove,
                update: raw.update,
            })),
            _ => Ok(FrameRecord::Empty),
        }
    }
}

/// Treats JSON `null` like an absent field.
fn null_as_default<'de, D, T>(deserializer: D) -> Result<T, D::Error>
where
    D: Deserializer<'de>,
    T: Default + Deserialize<'de>,
{
    Ok(Option::<T>::deserialize(deserializer)?.unwrap_or_default())
}

impl SceneGraph {
    /// Applies one old-style diff record in place, with ENACT's order and matching rules:
    /// adds first (skipped when the name or `(from, to)` is already present), then removals
    /// (every entry with that name or key), then updates (the first entry with that name or key
    /// is replaced; an update for an absent entry does nothing).
    pub fn apply_delta(&mut self, delta: &GraphDelta) {
        apply_delta_to(&mut self.nodes, &mut self.edges, delta);
    }
}

/// A node as held by a graph under reconstruction: owned, or borrowed from the records (the
/// transient filter rebuilds every frame and must not copy them all).
pub(crate) trait NodeEntry<'a> {
    fn from_record(node: &'a SceneNode) -> Self;
    fn name(&self) -> &str;
}

/// An edge as held by a graph under reconstruction, see [`NodeEntry`].
pub(crate) trait EdgeEntry<'a> {
    fn from_record(edge: &'a SceneEdge) -> Self;
    fn key(&self) -> (&str, &str);
}

impl<'a> NodeEntry<'a> for SceneNode {
    fn from_record(node: &'a SceneNode) -> Self {
        node.clone()
    }
    fn name(&self) -> &str {
        &self.name
    }
}

impl<'a> NodeEntry<'a> for &'a SceneNode {
    fn from_record(node: &'a SceneNode) -> Self {
        node
    }
    fn name(&self) -> &str {
        &self.name
    }
}

impl<'a> NodeEntry<'a> for std::sync::Arc<SceneNode> {
    fn from_record(node: &'a SceneNode) -> Self {
        std::sync::Arc::new(node.clone())
    }
    fn name(&self) -> &str {
        &self.name
    }
}

impl<'a> EdgeEntry<'a> for SceneEdge {
    fn from_record(edge: &'a SceneEdge) -> Self {
        edge.clone()
    }
    fn key(&self) -> (&str, &str) {
        (&self.from, &self.to)
    }
}

impl<'a> EdgeEntry<'a> for &'a SceneEdge {
    fn from_record(edge: &'a SceneEdge) -> Self {
        edge
    }
    fn key(&self) -> (&str, &str) {
        (&self.from, &self.to)
    }
}

/// ENACT's `_apply_diff_to_graph` on any node/edge representation (see
/// [`SceneGraph::apply_delta`] for the rules).
pub(crate) fn apply_delta_to<'a, N: NodeEntry<'a>, E: EdgeEntry<'a>>(
    nodes: &mut Vec<N>,
    edges: &mut Vec<E>,
    delta: &'a GraphDelta,
) {
    let edge_key = |e: &'a SceneEdge| (e.from.as_str(), e.to.as_str());
    if let Some(add) = &delta.add {
        for node in &add.nodes {
            if !nodes.iter().any(|n| n.name() == node.name) {
                nodes.push(N::from_record(node));
            }
        }
        for edge in &add.edges {
            if !edges.iter().any(|e| e.key() == edge_key(edge)) {
                edges.push(E::from_record(edge));
            }
        }
    }
    if let Some(remove) = &delta.remove {
        for node in &remove.nodes {
            nodes.retain(|n| n.name() != node.name);
        }
        for edge in &remove.edges {
            edges.retain(|e| e.key() != edge_key(edge));
        }
    }
    if let Some(update) = &delta.update {
        for node in &update.nodes {
            if let Some(slot) = nodes.iter_mut().find(|n| n.name() == node.name) {
                *slot = N::from_record(node);
            }
        }
        for edge in &update.edges {
            if let Some(slot) = edges.iter_mut().find(|e| e.key() == edge_key(edge)) {
                *slot = E::from_record(edge);
            }
        }
    }
}

impl GraphDelta {
    /// The old-style diff from `prev` to `next` (ENACT's `generate_scene_graph_diff`, used when
    /// segmentation writes key frames after the first): whole added and removed nodes/edges,
    /// and an update carrying the new state list wherever the state *lists* differ (order
    /// counts there, as in ENACT). `None` when nothing differs (ENACT's `{"type": "empty"}`).
    /// Entries come out sorted by name / key so the output is deterministic.
    pub fn between(prev: &SceneGraph, next: &SceneGraph) -> Option<GraphDelta> {
        // Later duplicates win, as in ENACT's dict comprehension.
        let prev_nodes: HashMap<&str, &SceneNode> =
            prev.nodes.iter().map(|n| (n.name.as_str(), n)).collect();
        let next_nodes: HashMap<&str, &SceneNode> =
            next.nodes.iter().map(|n| (n.name.as_str(), n)).collect();
        let prev_edges: HashMap<(&str, &str), &SceneEdge> = prev
            .edges
            .iter()
            .map(|e| ((e.from.as_str(), e.to.as_str()), e))
            .collect();
        let next_edges: HashMap<(&str, &str), &SceneEdge> = next
            .edges
            .iter()
            .map(|e| ((e.from.as_str(), e.to.as_str()), e))
            .collect();

        let mut add = DeltaSide::default();
        let mut remove = DeltaSide::default();
        let mut update = DeltaSide::default();

        let mut next_names: Vec<&str> = next_nodes.keys().copied().collect();
        next_names.sort_unstable();
        for name in &next_names {
            let new = next_nodes[name];
            match prev_nodes.get(name) {
                None => add.nodes.push(new.clone()),
                Some(old) if old.states != new.states => update.nodes.push(SceneNode {
                    name: new.name.clone(),
                    states: new.states.clone(),
                    // Fields other than name/states are taken from the previous frame.
                    category: old.category.clone(),
                    visibility: old.visibility.clone(),
                    parent: old.parent.clone(),
                }),
                Some(_) => {}
            }
        }
        let mut prev_names: Vec<&str> = prev_nodes.keys().copied().collect();
        prev_names.sort_unstable();
        for name in prev_names {
            if !next_nodes.contains_key(name) {
                remove.nodes.push(prev_nodes[name].clone());
            }
        }

        let mut next_keys: Vec<(&str, &str)> = next_edges.keys().copied().collect();
        next_keys.sort_unstable();
        for key in next_keys {
            let new = next_edges[&key];
            match prev_edges.get(&key) {
                None => add.edges.push(new.clone()),
                Some(old) if old.states != new.states => update.edges.push(SceneEdge {
                    from: new.from.clone(),
                    to: new.to.clone(),
                    states: new.states.clone(),
                }),
                Some(_) => {}
            }
        }
        let mut prev_keys: Vec<(&str, &str)> = prev_edges.keys().copied().collect();
        prev_keys.sort_unstable();
        for key in prev_keys {
            if !next_edges.contains_key(&key) {
                remove.edges.push(prev_edges[&key].clone());
            }
        }

        let is_empty = |s: &DeltaSide| s.nodes.is_empty() && s.edges.is_empty();
        if is_empty(&add) && is_empty(&remove) && is_empty(&update) {
            return None;
        }
        Some(GraphDelta {
            add: Some(add),
            remove: Some(remove),
            update: Some(update),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(name: &str, states: &[&str]) -> SceneNode {
        SceneNode {
            name: name.to_string(),
            category: Some("thing".to_string()),
            states: states.iter().map(|s| s.to_string()).collect(),
            visibility: Visibility::new(),
            parent: None,
        }
    }

    fn edge(from: &str, to: &str, states: &[&str]) -> SceneEdge {
        SceneEdge {
            from: from.to_string(),
            to: to.to_string(),
            states: states.iter().map(|s| s.to_string()).collect(),
        }
    }

    #[test]
    fn record_kinds_parse_and_unknown_types_are_empty() {
        let full: FrameRecord = serde_json::from_str(
            r#"{"nodes":[{"name":"a","category":"c","states":["Open"],"visibility":{}}],"edges":[],"type":"full"}"#,
        )
        .unwrap();
        assert!(matches!(full, FrameRecord::Full(ref g) if g.nodes[0].states == ["Open"]));
        let diff: FrameRecord =
            serde_json::from_str(r#"{"type":"diff","add":{"nodes":[],"edges":[]}}"#).unwrap();
        assert!(matches!(diff, FrameRecord::Diff(ref d) if d.add.is_some() && d.remove.is_none()));
        for text in [r#"{"type":"empty"}"#, r#"{"type":"weird"}"#, r#"{}"#] {
            let rec: FrameRecord = serde_json::from_str(text).unwrap();
            assert_eq!(rec, FrameRecord::Empty);
        }
        let bad = serde_json::from_str::<FrameRecord>(r#"{"type":"full","edges":[]}"#);
        assert!(bad.unwrap_err().to_string().contains("no `nodes`"));
    }

    #[test]
    fn null_fields_read_as_absent_and_integers_round_trip() {
        let n: SceneNode = serde_json::from_str(
            r#"{"name":"a","category":null,"states":null,"visibility":{"external_sensor1":[14,1,2,3,4,512,512]},"parent":null}"#,
        )
        .unwrap();
        assert!(n.states.is_empty() && n.category.is_none() && n.parent.is_none());
        let out = serde_json::to_string(&n).unwrap();
        assert!(out.contains("[14,1,2,3,4,512,512]"), "{out}");
        let full = FrameRecord::Full(SceneGraph::default());
        assert_eq!(
            serde_json::to_string(&full).unwrap(),
            r#"{"type":"full","nodes":[],"edges":[]}"#
        );
    }

    #[test]
    fn apply_delta_follows_add_remove_update_order() {
        let mut g = SceneGraph {
            nodes: vec![node("a", &[]), node("b", &["Open"])],
            edges: vec![edge("a", "b", &["OnTop"])],
        };
        let delta = GraphDelta {
            // "a" is already present: not added again. "c" is added and then removed by the
            // removal pass of the same record.
            add: Some(DeltaSide {
                nodes: vec![node("a", &["Cooked"]), node("c", &[])],
                edges: vec![edge("a", "b", &["Inside"]), edge("b", "a", &["Under"])],
            }),
            remove: Some(DeltaSide {
                nodes: vec![node("c", &[])],
                edges: vec![edge("a", "b", &[])],
            }),
            update: Some(DeltaSide {
                nodes: vec![node("b", &[]), node("zzz", &["Open"])],
                edges: vec![edge("b", "a", &["Under", "Touching"])],
            }),
        };
        g.apply_delta(&delta);
        let names: Vec<&str> = g.nodes.iter().map(|n| n.name.as_str()).collect();
        assert_eq!(names, ["a", "b"]);
        assert!(g.nodes[0].states.is_empty() && g.nodes[1].states.is_empty());
        assert_eq!(g.edges, vec![edge("b", "a", &["Under", "Touching"])]);
    }

    #[test]
    fn delta_between_round_trips() {
        let prev = SceneGraph {
            nodes: vec![node("a", &["Open"]), node("b", &[])],
            edges: vec![edge("a", "b", &["OnTop"]), edge("b", "a", &["Under"])],
        };
        let next = SceneGraph {
            nodes: vec![node("a", &[]), node("c", &["Cooked"])],
            edges: vec![edge("a", "b", &["OnTop", "Touching"]), edge("c", "a", &[])],
        };
        assert_eq!(GraphDelta::between(&prev, &prev), None);
        let delta = GraphDelta::between(&prev, &next).unwrap();
        assert_eq!(delta.add.as_ref().unwrap().nodes[0].name, "c");
        assert_eq!(delta.remove.as_ref().unwrap().nodes[0].name, "b");
        assert_eq!(delta.update.as_ref().unwrap().nodes[0].name, "a");
        let mut rebuilt = prev.clone();
        rebuilt.apply_delta(&delta);
        let mut want = next.clone();
        rebuilt.nodes.sort_by(|x, y| x.name.cmp(&y.name));
        want.nodes.sort_by(|x, y| x.name.cmp(&y.name));
        rebuilt
            .edges
            .sort_by(|x, y| (&x.from, &x.to).cmp(&(&y.from, &y.to)));
        want.edges
            .sort_by(|x, y| (&x.from, &x.to).cmp(&(&y.from, &y.to)));
        assert_eq!(rebuilt, want);
    }
}
