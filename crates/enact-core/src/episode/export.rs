//! An episode written as one task of ENACT's replay layout: `scene_graph_0.json` with a full
//! record per key frame, `segmented_scene_graph_0.json` as ENACT's segmentation writes it, and
//! the marker that tells `generate` to take the curator's key frames as they are.

use serde_json::{Map, Value};

use crate::episode::{EpisodeGraphs, FrameSize};
use crate::pipeline::marked::{MarkedKeyFrames, marked_segmentation};

/// One task's files, in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskExport {
    /// `scene_graph_0.json`: frame id → `full` record, one per key frame.
    pub scene_graph: Value,
    /// `segmented_scene_graph_0.json`.
    pub segmented: Value,
    pub marked: MarkedKeyFrames,
}

/// The files of episode `episode` with its (validated) `graphs`; `size_of(frame)` gives each
/// key frame's image size for the visibility readings. Frame ids are the frames' positions.
pub fn export_task(
    episode: &str,
    scene: &str,
    graphs: &EpisodeGraphs,
    size_of: impl Fn(usize) -> FrameSize,
) -> TaskExport {
    let scene_graphs: Vec<(String, crate::scene_graph::SceneGraph)> = graphs
        .key_frames
        .iter()
        .map(|k| (k.frame.to_string(), k.scene_graph(size_of(k.frame))))
        .collect();
    let mut records = Map::new();
    for (frame, graph) in &scene_graphs {
        records.insert(
            frame.clone(),
            serde_json::json!({"type": "full", "nodes": graph.nodes, "edges": graph.edges}),
        );
    }
    TaskExport {
        scene_graph: Value::Object(records),
        segmented: marked_segmentation(&scene_graphs, scene_graphs.len()).segmented_scene_graph(),
        marked: MarkedKeyFrames {
            key_frames: scene_graphs.iter().map(|(f, _)| f.clone()).collect(),
            origin: "real".into(),
            scene: scene.into(),
            episode: episode.into(),
        },
    }
}
