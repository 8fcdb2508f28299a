//! The scene-graph record reader (`scene_graph_0.json`), with and without ENACT's transient
//! filter, and the diff and signatures of consecutive frames of whatever it accepts.
#![no_main]

use std::collections::BTreeSet;
use std::path::Path;

use enact_hub::core::scene_graph::diff::state_centric_diff;
use enact_hub::core::scene_graph::signature::diff_signatures;
use enact_hub::core::scene_graph::timeline::{FrameSelection, SceneGraphTimeline, TransientFilter};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let source = Path::new("fuzz/scene_graph_0.json");
    for filter in [TransientFilter::Off, TransientFilter::Enact] {
        let Ok(timeline) =
            SceneGraphTimeline::from_json_slice(data, source, FrameSelection::All, filter)
        else {
            continue;
        };
        let frames: Vec<String> = timeline.frame_ids().take(16).collect();
        let graphs: Vec<_> = frames
            .iter()
            .filter_map(|frame| timeline.scene_graph(frame).ok())
            .collect();
        for pair in graphs.windows(2) {
            if let Ok(diff) = state_centric_diff(&pair[0], &pair[1]) {
                let _ = diff_signatures(&diff);
            }
        }
        // Reading only some frames must agree with reading them all.
        if filter == TransientFilter::Off && !frames.is_empty() {
            let middle = frames[frames.len() / 2].clone();
            let only = SceneGraphTimeline::from_json_slice(
                data,
                source,
                FrameSelection::Only(BTreeSet::from([middle.clone()])),
                filter,
            )
            .expect("a file read whole reads in part");
            assert_eq!(
                only.scene_graph(&middle).ok().map(|g| g.into_owned()),
                timeline.scene_graph(&middle).ok().map(|g| g.into_owned()),
                "frame {middle} differs when read alone"
            );
        }
    }
});
