//! Key frames a person marked (an exported real-world episode): the marker file beside a
//! task's scene graph and the segmentation `generate` takes from it instead of scanning.

use serde::{Deserialize, Serialize};

use crate::pipeline::segment::{KeyFrameCosine, Segmentation, SegmentedRecord, StateBag};
use crate::scene_graph::{GraphDelta, SceneGraph};

/// The file beside `scene_graph_0.json` that lists the key frames a person marked. ENACT's
/// own tools ignore it (they read `segmented_activities/`); `generate` takes these key frames
/// instead of scanning for them, so no similarity or stability filter can drop one.
pub const MARKED_KEY_FRAMES_FILE: &str = "marked_key_frames.json";

/// The content of [`MARKED_KEY_FRAMES_FILE`].
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct MarkedKeyFrames {
    /// Frame ids (decimal strings, as keys of `scene_graph_0.json`), increasing.
    pub key_frames: Vec<String>,
    /// Where the frames come from: `real` for a recorded episode.
    pub origin: String,
    /// The scene it was recorded in (may be empty).
    pub scene: String,
    /// The episode it was exported from.
    pub episode: String,
}

/// The segmentation of key frames a person marked: the first key frame's full graph, then each
/// later one's diff against the one before (an unchanged pair, which validation refuses, gets
/// an empty diff rather than being dropped).
pub fn marked_segmentation(key_frames: &[(String, SceneGraph)], num_frames: usize) -> Segmentation {
    let mut records = Vec::with_capacity(key_frames.len());
    let mut cosines = Vec::new();
    for (i, (frame, graph)) in key_frames.iter().enumerate() {
        match i.checked_sub(1).map(|p| &key_frames[p]) {
            None => records.push((frame.clone(), SegmentedRecord::Full(graph.clone()))),
            Some((prev_frame, prev)) => {
                cosines.push(KeyFrameCosine {
                    from_frame: prev_frame.clone(),
                    to_frame: frame.clone(),
                    cosine: StateBag::of(prev).cosine(&StateBag::of(graph)),
                });
                let delta = GraphDelta::between(prev, graph).unwrap_or_default();
                records.push((frame.clone(), SegmentedRecord::Diff(delta)));
            }
        }
    }
    Segmentation {
        num_frames,
        first_considered_frame: key_frames
            .first()
            .map(|(f, _)| f.clone())
            .unwrap_or_default(),
        key_frames: key_frames.iter().map(|(f, _)| f.clone()).collect(),
        records,
        consecutive_cosines: cosines,
    }
}
