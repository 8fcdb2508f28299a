//! ENACT's transient ("oscillation") filter: removes states, nodes and edges that flicker for
//! fewer than ten frames, and restores ones that drop out briefly (`SceneGraphReader(...,
//! filter_transients=True)`, used by segmentation only).
//!
//! Windows start every [`STRIDE`] frames; each start `i` looks at the windows ending at
//! `i+2 ..= i+9` (never past the last frame). In a window, the first frame is the base, the
//! last the end, and the frames between are the middle. Windows run in order and each reads
//! graphs earlier windows already changed, so the result for one frame depends on all frames
//! before it. Positions are indices into the numerically sorted frame list, not frame numbers.
//!
//! The filter runs on an interned copy of the graphs (names, states and edge keys as small
//! integers, other node fields referenced rather than copied) because it visits every frame
//! about forty times.

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::ops::Deref;

use crate::scene_graph::record::{FrameRecord, SceneEdge, SceneGraph, SceneNode, apply_delta_to};

/// How a filtered node refers to the record entry that carries its other fields: a reference
/// into records held in memory, or a shared copy when records are read as a stream.
pub(crate) trait Fields: Clone + Deref<Target = SceneNode> {}

impl<T: Clone + Deref<Target = SceneNode>> Fields for T {}

/// A change shorter than this many frames is treated as a glitch (ENACT's
/// `TRANSIENT_FRAME_THRESHOLD`); windows span at most this many frames minus one.
pub const TRANSIENT_FRAME_THRESHOLD: usize = 10;
/// Distance between window starts (half the threshold, as in ENACT).
pub const STRIDE: usize = TRANSIENT_FRAME_THRESHOLD / 2;

#[derive(Debug, Clone)]
struct Node<R> {
    name: u32,
    /// As stored until the filter rewrites them; then a set (sorted, no repeats).
    states: Vec<u32>,
    rewritten: bool,
    /// The record entry whose other fields (category, visibility, parent) this node carries.
    fields: R,
}

#[derive(Debug, Clone)]
struct Edge {
    key: u32,
    states: Vec<u32>,
    rewritten: bool,
}

#[derive(Debug, Clone)]
struct Frame<R> {
    nodes: Vec<Node<R>>,
    edges: Vec<Edge>,
}

#[derive(Default)]
struct Interner {
    ids: HashMap<String, u32>,
    strings: Vec<String>,
}

impl Interner {
    fn id(&mut self, s: &str) -> u32 {
        if let Some(&id) = self.ids.get(s) {
            return id;
        }
        let id = self.strings.len() as u32;
        self.strings.push(s.to_string());
        self.ids.insert(s.to_string(), id);
        id
    }
}

/// Every frame's graph after ENACT's transient filter, in numeric order. `Err(frame)` names
/// the first frame with no `full` record at or before it (ENACT fails there too).
#[cfg(test)]
pub(crate) fn filtered_graphs(
    records: &BTreeMap<u64, FrameRecord>,
) -> Result<Vec<(u64, SceneGraph)>, u64> {
    let mut out = Vec::with_capacity(records.len());
    for_each_filtered_graph(records, |id, graph| out.push((id, graph)))?;
    Ok(out)
}

/// Calls `emit` with every frame's graph after ENACT's transient filter, in numeric order,
/// building one graph at a time so a caller can keep only what it needs. `Err(frame)` names
/// the first frame with no `full` record at or before it (ENACT fails there too).
pub(crate) fn for_each_filtered_graph(
    records: &BTreeMap<u64, FrameRecord>,
    mut emit: impl FnMut(u64, SceneGraph),
) -> Result<(), u64> {
    let mut windows = Windows::default();
    // Reconstruction on references: each frame is a list of record entries.
    let mut current: Option<(Vec<&SceneNode>, Vec<&SceneEdge>)> = None;
    for (&id, record) in records {
        match record {
            FrameRecord::Full(g) => {
                current = Some((g.nodes.iter().collect(), g.edges.iter().collect()))
            }
            FrameRecord::Diff(delta) => {
                if let Some((nodes, edges)) = current.as_mut() {
                    apply_delta_to(nodes, edges, delta);
                }
            }
            FrameRecord::Empty => {}
        }
        let (nodes, edges) = current.as_ref().ok_or(id)?;
        windows.push(id, nodes.iter().copied(), edges.iter().copied(), &mut emit);
    }
    windows.finish(&mut emit);
    Ok(())
}

/// ENACT's transient filter fed one frame at a time. Window starts come every [`STRIDE`]
/// frames and reach [`TRANSIENT_FRAME_THRESHOLD`] − 1 frames ahead; a start runs as soon as
/// its widest window's frames are in. A window changes only frames after its start, so once a
/// start has run, every frame before the next start is final: it is emitted and dropped. Memory
/// holds about two windows of frames, whatever the length of the replay.
pub(crate) struct Windows<R> {
    words: Interner,
    edge_ids: HashMap<(u32, u32), u32>,
    edge_keys: Vec<(u32, u32)>,
    /// Frames not yet emitted; `frames[0]` has index `first` in the whole replay.
    frames: VecDeque<(u64, Frame<R>)>,
    first: usize,
    /// Frames pushed so far.
    total: usize,
    /// The next window start to run (a multiple of STRIDE).
    next_start: usize,
    scratch: Scratch,
}

impl<R> Default for Windows<R> {
    fn default() -> Self {
        Windows {
            words: Interner::default(),
            edge_ids: HashMap::new(),
            edge_keys: Vec::new(),
            frames: VecDeque::new(),
            first: 0,
            total: 0,
            next_start: 0,
            scratch: Scratch::new(0, 0),
        }
    }
}

impl<R: Fields> Windows<R> {
    /// Adds the next frame's reconstructed (unfiltered) graph, and emits what became final.
    pub(crate) fn push<'e>(
        &mut self,
        id: u64,
        nodes: impl Iterator<Item = R>,
        edges: impl Iterator<Item = &'e SceneEdge>,
        emit: &mut impl FnMut(u64, SceneGraph),
    ) {
        let words = &mut self.words;
        let nodes = nodes
            .map(|n| Node {
                name: words.id(&n.name),
                states: n.states.iter().map(|s| words.id(s)).collect(),
                rewritten: false,
                fields: n,
            })
            .collect();
        let edges = edges
            .map(|e| {
                let pair = (words.id(&e.from), words.id(&e.to));
                let key = *self.edge_ids.entry(pair).or_insert_with(|| {
                    self.edge_keys.push(pair);
                    self.edge_keys.len() as u32 - 1
                });
                Edge {
                    key,
                    states: e.states.iter().map(|s| words.id(s)).collect(),
                    rewritten: false,
                }
            })
            .collect();
        self.frames.push_back((id, Frame { nodes, edges }));
        self.total += 1;
        // A start's widest window ends TRANSIENT_FRAME_THRESHOLD − 1 frames after it.
        while self.total >= self.next_start + TRANSIENT_FRAME_THRESHOLD {
            self.run_start(TRANSIENT_FRAME_THRESHOLD - 1, emit);
        }
    }

    /// Runs the windows of `next_start` up to `widest`, then emits and drops the frames that
    /// no later window changes or reads.
    fn run_start(&mut self, widest: usize, emit: &mut impl FnMut(u64, SceneGraph)) {
        self.scratch
            .grow(self.words.strings.len(), self.edge_keys.len());
        let start = self.next_start - self.first;
        let frames = self.frames.make_contiguous();
        for window in 2..=widest {
            let (head, tail) = frames.split_at_mut(start + 1);
            let (middle, rest) = tail.split_at_mut(window - 1);
            let (base, end) = (&head[start].1, &rest[0].1);
            self.scratch.fix_nodes(base, end, middle);
            self.scratch.fix_edges(base, end, middle);
        }
        self.next_start += STRIDE;
        // Windows of later starts change only frames after those starts and read from them on.
        while self.first < self.next_start.min(self.total) {
            let (id, frame) = self
                .frames
                .pop_front()
                .expect("a frame before the next start");
            emit(id, rebuild(&frame, &self.words.strings, &self.edge_keys));
            self.first += 1;
        }
    }

    /// Runs the starts left once the last frame is in, and emits every remaining frame.
    pub(crate) fn finish(mut self, emit: &mut impl FnMut(u64, SceneGraph)) {
        while self.next_start < self.total {
            // ENACT: `range(2, min(THRESHOLD, n - start))`, so the end index stays below n.
            let widest = (TRANSIENT_FRAME_THRESHOLD - 1).min(self.total - self.next_start - 1);
            self.run_start(widest, emit);
        }
        for (id, frame) in self.frames.drain(..) {
            emit(id, rebuild(&frame, &self.words.strings, &self.edge_keys));
        }
    }
}

fn strings(ids: &[u32], rewritten: bool, words: &[String]) -> Vec<String> {
    let mut out: Vec<String> = ids.iter().map(|&i| words[i as usize].clone()).collect();
    if rewritten {
        out.sort_unstable();
    }
    out
}

fn rebuild<R: Fields>(frame: &Frame<R>, words: &[String], edge_keys: &[(u32, u32)]) -> SceneGraph {
    SceneGraph {
        nodes: frame
            .nodes
            .iter()
            .map(|n| SceneNode {
                name: words[n.name as usize].clone(),
                category: n.fields.category.clone(),
                states: strings(&n.states, n.rewritten, words),
                visibility: n.fields.visibility.clone(),
                parent: n.fields.parent.clone(),
            })
            .collect(),
        edges: frame
            .edges
            .iter()
            .map(|e| {
                let (from, to) = edge_keys[e.key as usize];
                SceneEdge {
                    from: words[from as usize].clone(),
                    to: words[to as usize].clone(),
                    states: strings(&e.states, e.rewritten, words),
                }
            })
            .collect(),
    }
}

/// A small state set: sorted, without repeats.
fn state_set(states: &[u32]) -> Vec<u32> {
    let mut set = states.to_vec();
    set.sort_unstable();
    set.dedup();
    set
}

fn intersect(a: &[u32], b: &[u32]) -> Vec<u32> {
    a.iter().copied().filter(|s| b.contains(s)).collect()
}

/// `(current ∪ stable) ∩ (base ∪ end)`: brief drop-outs of stable states are restored and
/// states present in neither the base nor the end are removed. Since stable ⊆ base ∪ end this
/// is `(current ∩ (base ∪ end)) ∪ stable`.
fn repaired_states(current: &[u32], base: &[u32], end: &[u32], stable: &[u32]) -> Vec<u32> {
    let mut out: Vec<u32> = current
        .iter()
        .copied()
        .filter(|s| base.contains(s) || end.contains(s))
        .chain(stable.iter().copied())
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// ENACT quirk: a node restored by the transient filter gets its name and stable states, but
/// every other field (category, visibility, parent) is copied from the *first node of the base
/// frame* (`base_graph['nodes'][0]`, normally the robot), not from the node itself. It is also
/// appended to middle frames that still had the node, which duplicates it there.
fn restored_node<R: Fields>(first_of_base: &Node<R>, name: u32, stable: &[u32]) -> Node<R> {
    Node {
        name,
        states: stable.to_vec(),
        rewritten: true,
        fields: first_of_base.fields.clone(),
    }
}

/// Per-window lookup tables indexed by interned id, reused across windows. A slot is valid
/// for the current window only when its stamp equals the window's stamp.
struct Scratch {
    stamp: u32,
    base_stamp: Vec<u32>,
    base_states: Vec<Vec<u32>>,
    end_stamp: Vec<u32>,
    end_states: Vec<Vec<u32>>,
    holders: Vec<u32>,
    seen_stamp: Vec<u32>,
    seen: u32,
    edge_base_stamp: Vec<u32>,
    edge_base: Vec<Vec<u32>>,
    edge_end_stamp: Vec<u32>,
    edge_end: Vec<Vec<u32>>,
    edge_last: Vec<usize>,
    edge_last_stamp: Vec<u32>,
}

impl Scratch {
    fn new(words: usize, edges: usize) -> Self {
        Scratch {
            stamp: 0,
            base_stamp: vec![0; words],
            base_states: vec![Vec::new(); words],
            end_stamp: vec![0; words],
            end_states: vec![Vec::new(); words],
            holders: vec![0; words],
            seen_stamp: vec![0; words],
            seen: 0,
            edge_base_stamp: vec![0; edges],
            edge_base: vec![Vec::new(); edges],
            edge_end_stamp: vec![0; edges],
            edge_end: vec![Vec::new(); edges],
            edge_last: vec![0; edges],
            edge_last_stamp: vec![0; edges],
        }
    }

    /// Makes room for `words` interned strings and `edges` edge keys (new slots are unstamped).
    fn grow(&mut self, words: usize, edges: usize) {
        if words > self.base_stamp.len() {
            self.base_stamp.resize(words, 0);
            self.base_states.resize(words, Vec::new());
            self.end_stamp.resize(words, 0);
            self.end_states.resize(words, Vec::new());
            self.holders.resize(words, 0);
            self.seen_stamp.resize(words, 0);
        }
        if edges > self.edge_base_stamp.len() {
            self.edge_base_stamp.resize(edges, 0);
            self.edge_base.resize(edges, Vec::new());
            self.edge_end_stamp.resize(edges, 0);
            self.edge_end.resize(edges, Vec::new());
            self.edge_last.resize(edges, 0);
            self.edge_last_stamp.resize(edges, 0);
        }
    }

    fn fix_nodes<R: Fields>(
        &mut self,
        base: &Frame<R>,
        end: &Frame<R>,
        middle: &mut [(u64, Frame<R>)],
    ) {
        self.stamp += 1;
        let stamp = self.stamp;
        // The last entry with a name gives its states (a dict comprehension in ENACT).
        for n in &base.nodes {
            let i = n.name as usize;
            self.base_stamp[i] = stamp;
            self.base_states[i] = state_set(&n.states);
            self.holders[i] = 0;
        }
        for n in &end.nodes {
            let i = n.name as usize;
            self.end_stamp[i] = stamp;
            self.end_states[i] = state_set(&n.states);
            self.holders[i] = 0;
        }
        let empty: Vec<u32> = Vec::new();
        for (_, frame) in middle.iter_mut() {
            // Nodes in neither the base nor the end frame are transient: dropped everywhere.
            frame.nodes.retain(|n| {
                let i = n.name as usize;
                self.base_stamp[i] == stamp || self.end_stamp[i] == stamp
            });
            // Only the first entry with a name is repaired (ENACT stops at the first match).
            self.seen += 1;
            for node in frame.nodes.iter_mut() {
                let i = node.name as usize;
                if self.seen_stamp[i] == self.seen {
                    continue;
                }
                self.seen_stamp[i] = self.seen;
                self.holders[i] += 1;
                let b = if self.base_stamp[i] == stamp {
                    &self.base_states[i]
                } else {
                    &empty
                };
                let e = if self.end_stamp[i] == stamp {
                    &self.end_states[i]
                } else {
                    &empty
                };
                let stable = intersect(b, e);
                node.states = repaired_states(&node.states, b, e, &stable);
                node.rewritten = true;
            }
        }
        // A node with stable states missing from some middle frame is appended to every
        // middle frame (also to those that still have it).
        let Some(first) = base.nodes.first() else {
            return;
        };
        self.seen += 1;
        for n in &base.nodes {
            let i = n.name as usize;
            if self.end_stamp[i] != stamp
                || (self.holders[i] as usize) >= middle.len()
                || self.seen_stamp[i] == self.seen
            {
                continue;
            }
            // A name repeated in the base frame is handled once.
            self.seen_stamp[i] = self.seen;
            let stable = intersect(&self.base_states[i], &self.end_states[i]);
            if stable.is_empty() {
                continue;
            }
            let restored = restored_node(first, n.name, &stable);
            for (_, frame) in middle.iter_mut() {
                frame.nodes.push(restored.clone());
            }
        }
    }

    fn fix_edges<R>(&mut self, base: &Frame<R>, end: &Frame<R>, middle: &mut [(u64, Frame<R>)]) {
        self.stamp += 1;
        let stamp = self.stamp;
        // The last entry with a key gives its states.
        let mut keys: Vec<u32> = Vec::with_capacity(base.edges.len() + end.edges.len());
        for e in &base.edges {
            let k = e.key as usize;
            self.edge_base_stamp[k] = stamp;
            self.edge_base[k] = state_set(&e.states);
            keys.push(e.key);
        }
        for e in &end.edges {
            let k = e.key as usize;
            self.edge_end_stamp[k] = stamp;
            self.edge_end[k] = state_set(&e.states);
            keys.push(e.key);
        }
        keys.sort_unstable();
        keys.dedup();
        let empty: Vec<u32> = Vec::new();
        let plans: Vec<(u32, Vec<u32>)> = keys
            .iter()
            .map(|&k| {
                let b = if self.edge_base_stamp[k as usize] == stamp {
                    &self.edge_base[k as usize]
                } else {
                    &empty
                };
                let e = if self.edge_end_stamp[k as usize] == stamp {
                    &self.edge_end[k as usize]
                } else {
                    &empty
                };
                (k, intersect(b, e))
            })
            .collect();
        for (_, frame) in middle.iter_mut() {
            // Edges in neither the base nor the end frame are transient: dropped everywhere.
            frame.edges.retain(|e| {
                let k = e.key as usize;
                self.edge_base_stamp[k] == stamp || self.edge_end_stamp[k] == stamp
            });
            // ENACT looks edges up through a dict, so the *last* entry with a key is repaired.
            self.seen += 1;
            for (i, e) in frame.edges.iter().enumerate() {
                let k = e.key as usize;
                self.edge_last[k] = i;
                self.edge_last_stamp[k] = self.seen;
            }
            for (k, stable) in &plans {
                let ku = *k as usize;
                if self.edge_last_stamp[ku] == self.seen {
                    let b = if self.edge_base_stamp[ku] == stamp {
                        &self.edge_base[ku]
                    } else {
                        &empty
                    };
                    let e = if self.edge_end_stamp[ku] == stamp {
                        &self.edge_end[ku]
                    } else {
                        &empty
                    };
                    let edge = &mut frame.edges[self.edge_last[ku]];
                    edge.states = repaired_states(&edge.states, b, e, stable);
                    edge.rewritten = true;
                } else if !stable.is_empty() {
                    // An edge with stable states that is missing here is put back.
                    frame.edges.push(Edge {
                        key: *k,
                        states: stable.clone(),
                        rewritten: true,
                    });
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_graph::record::Visibility;

    fn node(name: &str, category: &str, states: &[&str]) -> SceneNode {
        SceneNode {
            name: name.to_string(),
            category: Some(category.to_string()),
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

    /// Twelve identical frames (robot first, a fridge, a plate on a table); `change` edits
    /// some of them.
    fn frames(change: impl Fn(usize, &mut SceneGraph)) -> Vec<(u64, SceneGraph)> {
        (0..12)
            .map(|i| {
                let mut g = SceneGraph {
                    nodes: vec![
                        node("robot_r1", "agent", &[]),
                        node("fridge_1", "fridge", &["Open"]),
                        node("plate_2", "plate", &[]),
                        node("table_3", "table", &[]),
                    ],
                    edges: vec![edge("plate_2", "table_3", &["OnTop", "Touching"])],
                };
                change(i, &mut g);
                (i as u64, g)
            })
            .collect()
    }

    fn filtered(g: Vec<(u64, SceneGraph)>) -> Vec<(u64, SceneGraph)> {
        let records: BTreeMap<u64, FrameRecord> = g
            .into_iter()
            .map(|(i, g)| (i, FrameRecord::Full(g)))
            .collect();
        filtered_graphs(&records).unwrap()
    }

    #[test]
    fn flickering_node_state_is_restored_and_spurious_one_removed() {
        let out = filtered(frames(|i, g| {
            if (3..5).contains(&i) {
                g.nodes[1].states.clear(); // "Open" drops out for two frames
            }
            if i == 7 {
                g.nodes[2].states.push("Frozen".into()); // one-frame glitch
            }
        }));
        for (i, g) in &out {
            assert_eq!(g.nodes[1].states, ["Open"], "frame {i}");
            assert!(g.nodes[2].states.is_empty(), "frame {i}");
        }
    }

    #[test]
    fn lasting_change_survives() {
        let out = filtered(frames(|i, g| {
            if i >= 4 {
                g.nodes[1].states.clear();
            }
        }));
        for (i, g) in &out {
            assert_eq!(g.nodes[1].states.is_empty(), *i >= 4, "frame {i}");
        }
    }

    #[test]
    fn transient_node_and_edge_are_removed() {
        let out = filtered(frames(|i, g| {
            if (5..7).contains(&i) {
                g.nodes.push(node("dust", "System", &[]));
                g.edges.push(edge("table_3", "dust", &["Covered"]));
            }
        }));
        for (i, g) in &out {
            assert!(!g.nodes.iter().any(|n| n.name == "dust"), "frame {i}");
            assert_eq!(g.edges.len(), 1, "frame {i}");
        }
    }

    #[test]
    fn edge_dropout_and_edge_state_dropout_are_restored() {
        let out = filtered(frames(|i, g| {
            if i == 2 {
                g.edges.clear();
            }
            if i == 8 {
                g.edges[0].states = vec!["Touching".into(), "Inside".into()];
            }
        }));
        for (i, g) in &out {
            assert_eq!(
                g.edges,
                vec![edge("plate_2", "table_3", &["OnTop", "Touching"])],
                "frame {i}"
            );
        }
    }

    #[test]
    fn stateless_node_dropout_is_not_repaired() {
        let out = filtered(frames(|i, g| {
            if i == 6 {
                g.nodes.retain(|n| n.name != "plate_2");
            }
        }));
        assert!(!out[6].1.nodes.iter().any(|n| n.name == "plate_2"));
        assert!(out[5].1.nodes.iter().any(|n| n.name == "plate_2"));
    }

    #[test]
    fn node_with_states_dropping_out_is_duplicated_with_robot_fields() {
        let mut robot_vis = Visibility::new();
        robot_vis.insert("external_sensor1".into(), vec![15000.into(), 0.into()]);
        let out = filtered(frames(|i, g| {
            g.nodes[0].visibility = robot_vis.clone();
            if i == 6 {
                g.nodes.retain(|n| n.name != "fridge_1");
            }
        }));
        // The first window with frame 6 in its middle and the fridge at both ends is base 0,
        // end 7: the copy goes to every middle frame 1..=6, so frames 1..=5, which still had
        // the fridge, now hold it twice. Later windows find frame 6's copy and add nothing.
        let fridges = |g: &SceneGraph| -> Vec<SceneNode> {
            g.nodes
                .iter()
                .filter(|n| n.name == "fridge_1")
                .cloned()
                .collect()
        };
        let copy_ok = |n: &SceneNode| {
            n.category.as_deref() == Some("agent")
                && n.visibility == robot_vis
                && n.states == ["Open"]
        };
        let at6 = fridges(&out[6].1);
        assert_eq!(at6.len(), 1);
        assert!(copy_ok(&at6[0]));
        for (frame, graph) in &out[1..=5] {
            let both = fridges(graph);
            assert_eq!(both.len(), 2, "frame {frame}");
            assert_eq!(both[0].category.as_deref(), Some("fridge"));
            assert!(copy_ok(&both[1]));
        }
        for frame in [0, 7, 11] {
            assert_eq!(fridges(&out[frame].1).len(), 1, "frame {frame}");
        }
    }

    #[test]
    fn diff_records_are_applied_before_filtering() {
        use crate::scene_graph::record::{DeltaSide, GraphDelta};
        let base = frames(|_, _| {}).remove(0).1;
        let open_fridge = GraphDelta {
            update: Some(DeltaSide {
                nodes: vec![node("fridge_1", "fridge", &[])],
                edges: vec![],
            }),
            ..GraphDelta::default()
        };
        let mut records = BTreeMap::new();
        records.insert(0, FrameRecord::Full(base.clone()));
        for i in 1..12 {
            let rec = if i == 4 {
                FrameRecord::Diff(open_fridge.clone())
            } else {
                FrameRecord::Empty
            };
            records.insert(i, rec);
        }
        let out = filtered_graphs(&records).unwrap();
        assert_eq!(out.len(), 12);
        for (i, g) in &out {
            assert_eq!(g.nodes[1].states.is_empty(), *i >= 4, "frame {i}");
            assert_eq!(g.nodes.len(), 4);
        }
        records.insert(0, FrameRecord::Empty);
        assert_eq!(filtered_graphs(&records).unwrap_err(), 0);
    }

    #[test]
    fn short_timelines_do_not_panic() {
        for len in 0..4 {
            let g: Vec<(u64, SceneGraph)> = (0..len)
                .map(|i| (i as u64, SceneGraph::default()))
                .collect();
            assert_eq!(filtered(g).len(), len);
        }
    }
}
