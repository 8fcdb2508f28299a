//! Key-frame segmentation (ENACT's `FrameSegmentManager`): the bag-of-states features of a
//! frame, their cosine similarity, the candidate-then-stability scan over the
//! transient-filtered timeline, and the `segmented_scene_graph_0.json` it writes.

use std::collections::HashMap;

use serde_json::{Map, Value};

use crate::scene_graph::{
    GraphDelta, SceneGraph, SceneGraphTimeline, StateVocabulary, TimelineError, contact_relations,
};

/// The constants of the key-frame scan. Every field can be overridden; the presets are
/// [`SegmentationParams::enact_code`] (the default) and [`SegmentationParams::paper`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SegmentationParams {
    /// Frames dropped from the start of the numerically sorted ids before anything else.
    pub skip_first_frames: usize,
    /// The first key frame is the `warmup_frames`-th remaining frame (ENACT's
    /// `SKIPPING_FRAMES`, 50: index 49).
    pub warmup_frames: usize,
    /// A frame differs enough when its cosine similarity to the last key frame is below this.
    pub cosine_threshold: f64,
    /// ... and it is more than this many frame numbers after the last key frame.
    pub min_gap: u64,
    /// A differing frame is only a candidate; the saved one is the first differing frame at
    /// least this many frame numbers after the candidate (ENACT's `SKIPPING_SAVED_INTERVAL`).
    pub stability_frames: u64,
    /// What makes a frame differ: ENACT's state bags only, or contact changes too. Left out
    /// of `generation_summary.json` for ENACT's own, so a default run writes what it always did.
    #[serde(skip_serializing_if = "KeyFrameTrigger::is_state")]
    pub key_frames: KeyFrameTrigger,
}

/// What triggers a key frame (`generate --key-frames`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum KeyFrameTrigger {
    /// ENACT's: the cosine similarity of the state bags drops below the threshold.
    #[default]
    State,
    /// The paper's contact ablation: that, or a contact relation (see
    /// [`crate::scene_graph::contact`]) appeared or disappeared since the last key frame.
    /// Contact changes are then described in sentences and signatures too.
    Contact,
}

impl KeyFrameTrigger {
    /// `state` or `contact`.
    pub fn parse(name: &str) -> Option<KeyFrameTrigger> {
        match name {
            "state" => Some(KeyFrameTrigger::State),
            "contact" => Some(KeyFrameTrigger::Contact),
            _ => None,
        }
    }

    fn is_state(&self) -> bool {
        *self == KeyFrameTrigger::State
    }

    /// The states the run's transitions describe.
    pub fn vocabulary(self) -> StateVocabulary {
        match self {
            KeyFrameTrigger::State => StateVocabulary::Enact,
            KeyFrameTrigger::Contact => StateVocabulary::WithContact,
        }
    }
}

impl Default for SegmentationParams {
    fn default() -> Self {
        Self::enact_code()
    }
}

impl SegmentationParams {
    /// The constants of ENACT's public code (which its released data matches).
    pub const fn enact_code() -> Self {
        SegmentationParams {
            skip_first_frames: 10,
            warmup_frames: 50,
            cosine_threshold: 0.98,
            min_gap: 200,
            stability_frames: 10,
            key_frames: KeyFrameTrigger::State,
        }
    }

    /// The values the paper's appendix quotes: cosine 0.97 and 40 stability frames; the
    /// paper names no other constant, so the rest stay as in the code.
    pub const fn paper() -> Self {
        SegmentationParams {
            cosine_threshold: 0.97,
            stability_frames: 40,
            ..Self::enact_code()
        }
    }

    /// A preset by name: `enact-code` or `paper`.
    pub fn preset(name: &str) -> Option<Self> {
        match name {
            "enact-code" => Some(Self::enact_code()),
            "paper" => Some(Self::paper()),
            _ => None,
        }
    }
}

/// The multiset of `node:{name}:{state}` and `edge:{from}->{to}:{state}` strings of a graph.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct StateBag {
    counts: HashMap<String, u64>,
    /// Σ count², kept so the norm of the bag is computed once.
    square_sum: u64,
}

impl StateBag {
    pub fn of(graph: &SceneGraph) -> StateBag {
        let mut counts: HashMap<String, u64> = HashMap::new();
        for node in &graph.nodes {
            for state in &node.states {
                *counts
                    .entry(format!("node:{}:{state}", node.name))
                    .or_default() += 1;
            }
        }
        for edge in &graph.edges {
            for state in &edge.states {
                *counts
                    .entry(format!("edge:{}->{}:{state}", edge.from, edge.to))
                    .or_default() += 1;
            }
        }
        let square_sum = counts.values().map(|c| c * c).sum();
        StateBag { counts, square_sum }
    }

    /// ENACT's `_cosine_similarity`: 1.0 when either bag is empty. The sums are exact integers
    /// and each norm is one `sqrt` of an integer, as in Python, so the value is bit-identical.
    pub fn cosine(&self, other: &StateBag) -> f64 {
        let (small, large) = if self.counts.len() <= other.counts.len() {
            (self, other)
        } else {
            (other, self)
        };
        let dot: u64 = small
            .counts
            .iter()
            .filter_map(|(k, a)| large.counts.get(k).map(|b| a * b))
            .sum();
        let norms = (self.square_sum as f64).sqrt() * (other.square_sum as f64).sqrt();
        if norms == 0.0 {
            1.0
        } else {
            dot as f64 / norms
        }
    }
}

/// Why a timeline could not be segmented.
#[derive(Debug, thiserror::Error)]
pub enum SegmentationError {
    #[error(transparent)]
    Timeline(#[from] TimelineError),
    #[error(
        "{path}: {frames} frames, but segmentation needs at least {needed} (it skips {skip} and starts at the {warmup}th of the rest)"
    )]
    TooFewFrames {
        path: String,
        frames: usize,
        needed: usize,
        skip: usize,
        warmup: usize,
    },
    /// ENACT asserts that a saved frame differs from the previous key frame.
    #[error("{path}: frame {frame} has the same scene graph as key frame {previous}")]
    UnchangedKeyFrame {
        path: String,
        frame: String,
        previous: String,
    },
}

/// The cosine similarity between two consecutive key frames (on the scanned graphs).
#[derive(Debug, Clone, PartialEq)]
pub struct KeyFrameCosine {
    pub from_frame: String,
    pub to_frame: String,
    pub cosine: f64,
}

/// What the scan found for one task.
#[derive(Debug, Clone, PartialEq)]
pub struct Segmentation {
    /// Frames in the timeline (before skipping).
    pub num_frames: usize,
    /// The first frame left after the skip.
    pub first_considered_frame: String,
    /// Key frame ids in numeric order; the first is the initial key frame.
    pub key_frames: Vec<String>,
    /// The first key frame's graph, then the old-style diff of each later key frame against
    /// the previous one (ENACT's `segmented_scene_graph_0.json` records).
    pub records: Vec<(String, SegmentedRecord)>,
    pub consecutive_cosines: Vec<KeyFrameCosine>,
}

/// One record of `segmented_scene_graph_0.json`.
#[derive(Debug, Clone, PartialEq)]
pub enum SegmentedRecord {
    Full(SceneGraph),
    Diff(GraphDelta),
}

/// Scans a timeline (normally loaded with `TransientFilter::Enact`) for key frames.
///
/// ENACT quirk: the scan starts with the frame at index `warmup_frames - 1` (after the skip)
/// as the first key frame, then never looks at index `warmup_frames` nor at the last frame
/// (`range(50, len - 1)` with `continue` on 50). A frame qualifies when its cosine to the
/// last key frame is below the threshold and it is more than `min_gap` after it; the first
/// qualifying frame becomes a candidate, and the first qualifying frame at least
/// `stability_frames` after the candidate is saved instead (the candidate is dropped). A
/// candidate still pending at the end is saved itself.
pub fn segment_key_frames(
    timeline: &SceneGraphTimeline,
    params: &SegmentationParams,
) -> Result<Segmentation, SegmentationError> {
    let path = timeline.source().display().to_string();
    let all: Vec<String> = timeline.frame_ids().collect();
    let ids = all.get(params.skip_first_frames..).unwrap_or(&[]);
    if params.warmup_frames == 0 || ids.len() < params.warmup_frames {
        return Err(SegmentationError::TooFewFrames {
            path,
            frames: all.len(),
            needed: params.skip_first_frames + params.warmup_frames.max(1),
            skip: params.skip_first_frames,
            warmup: params.warmup_frames,
        });
    }
    let number = |id: &str| id.parse::<u64>().unwrap_or_default();

    let mut prev = ids[params.warmup_frames - 1].clone();
    let first = timeline.scene_graph(&prev)?.into_owned();
    let mut prev_bag = StateBag::of(&first);
    let mut prev_graph = first.clone();
    let mut records = vec![(prev.clone(), SegmentedRecord::Full(first))];
    let mut cosines = Vec::new();
    // (frame, its diff against `prev`, its cosine, earliest frame number that may replace it)
    let mut candidate: Option<(String, GraphDelta, f64, u64)> = None;

    let end = ids.len().saturating_sub(1);
    for current in ids.iter().take(end).skip(params.warmup_frames + 1) {
        let graph = timeline.scene_graph(current)?;
        let bag = StateBag::of(&graph);
        let cosine = prev_bag.cosine(&bag);
        let cur_n = number(current);
        let differs = cosine < params.cosine_threshold
            || (params.key_frames == KeyFrameTrigger::Contact
                && contact_relations(&graph) != contact_relations(&prev_graph));
        if !(differs && cur_n.saturating_sub(number(&prev)) > params.min_gap) {
            continue;
        }
        let delta = GraphDelta::between(&prev_graph, &graph).ok_or_else(|| {
            SegmentationError::UnchangedKeyFrame {
                path: path.clone(),
                frame: current.clone(),
                previous: prev.clone(),
            }
        })?;
        match &candidate {
            Some((_, _, _, min_save)) if cur_n >= *min_save => {
                cosines.push(KeyFrameCosine {
                    from_frame: prev.clone(),
                    to_frame: current.clone(),
                    cosine,
                });
                records.push((current.clone(), SegmentedRecord::Diff(delta)));
                prev = current.clone();
                prev_graph = graph.into_owned();
                prev_bag = bag;
                candidate = None;
            }
            Some(_) => {}
            None => {
                candidate = Some((
                    current.clone(),
                    delta,
                    cosine,
                    cur_n.saturating_add(params.stability_frames),
                ))
            }
        }
    }
    if let Some((frame, delta, cosine, _)) = candidate {
        cosines.push(KeyFrameCosine {
            from_frame: prev.clone(),
            to_frame: frame.clone(),
            cosine,
        });
        records.push((frame, SegmentedRecord::Diff(delta)));
    }
    Ok(Segmentation {
        num_frames: all.len(),
        first_considered_frame: ids[0].clone(),
        key_frames: records.iter().map(|(id, _)| id.clone()).collect(),
        records,
        consecutive_cosines: cosines,
    })
}

impl Segmentation {
    /// The `segmented_scene_graph_0.json` document: frame id → record, first `full`, then
    /// `diff` records (ENACT writes it with `indent=2`).
    pub fn segmented_scene_graph(&self) -> Value {
        let mut doc = Map::new();
        for (frame, record) in &self.records {
            let value = match record {
                SegmentedRecord::Full(graph) => serde_json::json!({
                    "type": "full",
                    "nodes": graph.nodes,
                    "edges": graph.edges,
                }),
                SegmentedRecord::Diff(delta) => {
                    let side = |s: &Option<crate::scene_graph::record::DeltaSide>| {
                        let s = s.clone().unwrap_or_default();
                        serde_json::json!({"nodes": s.nodes, "edges": s.edges})
                    };
                    serde_json::json!({
                        "type": "diff",
                        "add": side(&delta.add),
                        "remove": side(&delta.remove),
                        "update": side(&delta.update),
                    })
                }
            };
            doc.insert(frame.clone(), value);
        }
        Value::Object(doc)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_graph::{FrameRecord, SceneEdge, SceneNode};

    fn node(name: &str, states: &[&str]) -> SceneNode {
        SceneNode {
            name: name.into(),
            category: Some("thing".into()),
            states: states.iter().map(|s| s.to_string()).collect(),
            visibility: Default::default(),
            parent: None,
        }
    }

    fn graph(open: bool, on_top: bool) -> SceneGraph {
        let mut nodes = vec![node("robot_r1", &[]), node("fridge_1", &[])];
        if open {
            nodes[1].states.push("Open".into());
        }
        nodes.push(node("apple_2", &["Cold"]));
        nodes.push(node("table_3", &["Clean"]));
        let mut edges = vec![SceneEdge {
            from: "table_3".into(),
            to: "floor_0".into(),
            states: vec!["OnTop".into()],
        }];
        if on_top {
            edges.push(SceneEdge {
                from: "apple_2".into(),
                to: "table_3".into(),
                states: vec!["OnTop".into()],
            });
        }
        SceneGraph { nodes, edges }
    }

    /// A timeline whose graph at frame n is `world(n)`.
    fn timeline(frames: u64, world: impl Fn(u64) -> SceneGraph) -> SceneGraphTimeline {
        SceneGraphTimeline::from_records(
            "hand.json",
            (0..frames).map(|n| (n, FrameRecord::Full(world(n)))),
        )
    }

    fn small() -> SegmentationParams {
        SegmentationParams {
            skip_first_frames: 2,
            warmup_frames: 3,
            cosine_threshold: 0.98,
            min_gap: 10,
            stability_frames: 4,
            key_frames: KeyFrameTrigger::State,
        }
    }

    #[test]
    fn cosine_matches_hand_computation() {
        let a = StateBag::of(&graph(false, true));
        let b = StateBag::of(&graph(true, true));
        // a = {Cold, Clean, table OnTop, apple OnTop}, b = a + {Open}: 4 / (2 * sqrt 5).
        assert_eq!(a.cosine(&b), 4.0 / (2.0 * 5f64.sqrt()));
        assert_eq!(a.cosine(&a), 1.0);
        let empty = StateBag::of(&SceneGraph::default());
        assert_eq!(empty.cosine(&a), 1.0);
        assert_eq!(a.cosine(&empty), 1.0);
        // Duplicated features count twice.
        let mut g = graph(false, false);
        g.nodes.push(node("apple_2", &["Cold"]));
        let dup = StateBag::of(&g);
        assert_eq!(dup.square_sum, 4 + 1 + 1);
    }

    #[test]
    fn frame_handling_start_skip_and_last() {
        // Frames 0..40; after skipping 2 the ids are 2..39, the initial key frame is index 2
        // (frame 4), index 3 (frame 5) is never examined and neither is the last frame (39).
        let t = timeline(40, |n| graph(n >= 20, true));
        let s = segment_key_frames(&t, &small()).unwrap();
        assert_eq!(s.first_considered_frame, "2");
        // Frame 20 differs and is > 10 after 4: candidate; 24 is the first >= 20 + 4.
        assert_eq!(s.key_frames, vec!["4", "24"]);
        assert_eq!(s.num_frames, 40);
        assert!(matches!(s.records[0].1, SegmentedRecord::Full(_)));
        assert!(matches!(s.records[1].1, SegmentedRecord::Diff(_)));
        assert_eq!(s.consecutive_cosines.len(), 1);
        assert!(s.consecutive_cosines[0].cosine < 0.98);
    }

    #[test]
    fn change_at_the_skipped_index_is_seen_only_through_later_frames() {
        // The world changes at frame 5 (index 3, never examined) but frames 6.. show it.
        let t = timeline(30, |n| graph(n >= 5, true));
        let s = segment_key_frames(&t, &small()).unwrap();
        // 15 is the first frame > 4 + 10; candidate 15, saved 19.
        assert_eq!(s.key_frames, vec!["4", "19"]);
    }

    #[test]
    fn pending_candidate_is_saved_at_the_end() {
        // The change comes so late that no frame >= candidate + 4 is examined: the last frame
        // (29) is never looked at, so the candidate 26 is saved itself.
        let t = timeline(30, |n| graph(n >= 26, true));
        let s = segment_key_frames(&t, &small()).unwrap();
        assert_eq!(s.key_frames, vec!["4", "26"]);
        // A change only in the last frame is never seen.
        let t = timeline(30, |n| graph(n >= 29, true));
        assert_eq!(
            segment_key_frames(&t, &small()).unwrap().key_frames,
            vec!["4"]
        );
    }

    #[test]
    fn a_reverting_change_drops_the_candidate_only_when_a_later_frame_qualifies() {
        // Frames 20..21 differ (candidate 20), then the world reverts: nothing else qualifies,
        // so the candidate is saved at the end.
        let t = timeline(60, |n| graph((20..22).contains(&n), true));
        let s = segment_key_frames(&t, &small()).unwrap();
        assert_eq!(s.key_frames, vec!["4", "20"]);
    }

    /// 40 steady node states, the robot's left gripper touching the apple from frame 20 (one
    /// feature: too small a change for the cosine), the fridge opening with the apple inside it
    /// from frame 40 (three features).
    fn contact_world(n: u64) -> SceneGraph {
        let mut nodes: Vec<SceneNode> = (0..40)
            .map(|k| node(&format!("thing_{k}"), &["Clean"]))
            .collect();
        nodes.push(node("robot_r1", &[]));
        nodes.push(node("apple_1", &[]));
        nodes.push(node("fridge_2", if n >= 40 { &["Open"] } else { &[] }));
        let mut edges = Vec::new();
        if n >= 20 {
            edges.push(SceneEdge {
                from: "robot_r1".into(),
                to: "apple_1".into(),
                states: vec!["LeftContact".into()],
            });
        }
        if n >= 40 {
            edges.push(SceneEdge {
                from: "apple_1".into(),
                to: "fridge_2".into(),
                states: vec!["Inside".into(), "Touching".into()],
            });
        }
        SceneGraph { nodes, edges }
    }

    #[test]
    fn contact_changes_trigger_key_frames_only_in_contact_runs() {
        let t = timeline(60, contact_world);
        let state = segment_key_frames(&t, &small()).unwrap();
        assert_eq!(state.key_frames, vec!["4", "44"]);
        let contact = KeyFrameTrigger::parse("contact").unwrap();
        let params = SegmentationParams {
            key_frames: contact,
            ..small()
        };
        let with_contact = segment_key_frames(&t, &params).unwrap();
        // The contact at 20 is a candidate, saved after the same stability interval.
        assert_eq!(with_contact.key_frames, vec!["4", "24", "44"]);
        let relations = |f: &str| {
            let g = t.scene_graph(f).unwrap().into_owned();
            contact_relations(&g)
                .into_iter()
                .map(|(a, b, s)| format!("{a}->{b}:{s}"))
                .collect::<Vec<_>>()
        };
        assert_ne!(relations("24"), relations("4"));
        // A state run's summary says nothing of the trigger; a contact run's does.
        let json = |p: &SegmentationParams| serde_json::to_string(p).unwrap();
        assert!(!json(&small()).contains("key_frames"));
        assert!(json(&params).contains("\"key_frames\":\"contact\""));
        assert_eq!(KeyFrameTrigger::parse("touch"), None);
    }

    #[test]
    fn gap_is_strict_and_counts_from_the_last_key_frame() {
        // Change at 14: 14 - 4 = 10 is not > 10, so 15 is the candidate, 19 saved; then a second
        // change at 40 is compared with frame 19's graph.
        let t = timeline(60, |n| graph(n >= 14, n < 40));
        let s = segment_key_frames(&t, &small()).unwrap();
        assert_eq!(s.key_frames, vec!["4", "19", "44"]);
    }
}
