//! Real-world episodes: the key frames a curator marks in a recording and the scene graph
//! drawn for each, in the shape of the episode graphs file (`{"key_frames": [{"frame": 0,
//! "nodes": [...], "edges": [...], "visible": [...]}]}`).
//!
//! - [`validate`]: every problem of a graphs file, each naming the key frame and the field.
//! - [`describe`]: each transition between consecutive key frames as ENACT sees it: the
//!   state-centric diff, the action sentences and the signature components (visible and full).
//! - [`compare`]: where two curators' graphs of one episode differ, with agreement figures.
//!
//! A curator's graph becomes ENACT's scene graph through [`KeyFrameGraph::scene_graph`]:
//! ENACT decides what the camera sees from per-node sensor readings, so a node the curator
//! lists as visible gets a reading covering the whole image on `external_sensor1` (seen by any
//! threshold) and a node left out gets none (unseen). ENACT's visible and full views then come
//! out exactly as the curator said.

mod compare;
mod describe;
mod export;
mod validate;

use serde::{Deserialize, Serialize};

use crate::scene_graph::record::{SceneEdge, SceneGraph, SceneNode, Visibility};
use crate::scene_graph::visibility::EVALUATION_SENSORS;

pub use compare::{Comparison, ComponentCounts, KeyFrameDifference, TransitionDifference, compare};
pub use describe::{TransitionView, describe};
pub use export::{TaskExport, export_task};
pub use validate::{GraphProblem, validate};

/// The fewest key frames an export needs: the shortest step length ENACT asks (L = 3) needs
/// L + 1 key frames.
pub const MIN_EXPORT_KEY_FRAMES: usize = 4;

/// The key frames of one episode and the scene graph of each, in frame order.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EpisodeGraphs {
    pub key_frames: Vec<KeyFrameGraph>,
}

/// One key frame: its 0-based position in the episode's frame order and its scene graph.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyFrameGraph {
    pub frame: usize,
    #[serde(default)]
    pub nodes: Vec<EpisodeNode>,
    #[serde(default)]
    pub edges: Vec<SceneEdge>,
    /// The names of the nodes the camera sees; absent means every node.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub visible: Option<Vec<String>>,
}

/// An object as a curator draws it: ENACT's node without the sensor readings (those come
/// from the key frame's `visible` list).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EpisodeNode {
    pub name: String,
    pub category: String,
    #[serde(default)]
    pub states: Vec<String>,
    /// The objects this one was made from (slicing, dicing), as in ENACT's graphs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parent: Option<Vec<String>>,
}

/// The image size written into a visible node's sensor reading (ENACT's test only compares
/// the pixel share with a threshold, so a reading covering the whole image is seen whatever
/// the size).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FrameSize {
    pub width: u32,
    pub height: u32,
}

impl FrameSize {
    /// ENACT's rendered frames are 512 × 512; used where no image is at hand.
    pub const NOMINAL: FrameSize = FrameSize {
        width: 512,
        height: 512,
    };
}

impl KeyFrameGraph {
    /// Whether the camera sees the node `name` in this key frame.
    pub fn is_visible(&self, name: &str) -> bool {
        self.visible
            .as_ref()
            .is_none_or(|names| names.iter().any(|n| n == name))
    }

    /// ENACT's scene graph of this key frame: nodes with a whole-image reading on
    /// `external_sensor1` when visible and no reading otherwise.
    pub fn scene_graph(&self, size: FrameSize) -> SceneGraph {
        let nodes = self
            .nodes
            .iter()
            .map(|node| SceneNode {
                name: node.name.clone(),
                category: Some(node.category.clone()),
                states: node.states.clone(),
                visibility: if self.is_visible(&node.name) {
                    whole_image_reading(size)
                } else {
                    Visibility::new()
                },
                parent: node.parent.clone(),
            })
            .collect();
        SceneGraph {
            nodes,
            edges: self.edges.clone(),
        }
    }

    /// The curator's key frame read back from ENACT's scene graph (the inverse of
    /// [`KeyFrameGraph::scene_graph`]): a node is visible when its reading on
    /// `external_sensor1` is seen by ENACT's test; `visible` is left out when every node is.
    pub fn from_scene_graph(frame: usize, graph: &SceneGraph) -> KeyFrameGraph {
        let seen = |node: &SceneNode| {
            crate::scene_graph::visibility::node_is_visible(node, &EVALUATION_SENSORS)
                .unwrap_or(false)
        };
        let all_seen = graph.nodes.iter().all(seen);
        KeyFrameGraph {
            frame,
            nodes: graph
                .nodes
                .iter()
                .map(|node| EpisodeNode {
                    name: node.name.clone(),
                    category: node.category.clone().unwrap_or_default(),
                    states: node.states.clone(),
                    parent: node.parent.clone(),
                })
                .collect(),
            edges: graph.edges.clone(),
            visible: (!all_seen).then(|| {
                graph
                    .nodes
                    .iter()
                    .filter(|n| seen(n))
                    .map(|n| n.name.clone())
                    .collect()
            }),
        }
    }
}

/// `[pixels, xmin, ymin, xmax, ymax, height, width]` for an object filling the image.
fn whole_image_reading(size: FrameSize) -> Visibility {
    let (w, h) = (u64::from(size.width.max(1)), u64::from(size.height.max(1)));
    let reading: Vec<serde_json::Number> = [w * h, 0, 0, w - 1, h - 1, h, w]
        .into_iter()
        .map(serde_json::Number::from)
        .collect();
    EVALUATION_SENSORS
        .iter()
        .map(|sensor| (sensor.to_string(), reading.clone()))
        .collect()
}

#[cfg(test)]
pub(crate) mod tests;
