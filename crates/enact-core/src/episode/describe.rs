//! Each transition of an episode as ENACT will see it, for the curator to check while
//! drawing: the diff, the action text an inverse item will carry and the signature
//! components the verifier compares.

use serde::Serialize;

use crate::episode::{EpisodeGraphs, FrameSize};
use crate::scene_graph::sentence::render_diff_first_templates;
use crate::scene_graph::visibility::EVALUATION_SENSORS;
use crate::scene_graph::{StateDiff, View, diff_signatures, restrict_to_view, state_centric_diff};

/// The change from one key frame to the next.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TransitionView {
    /// Indices into `key_frames`.
    pub from_key_frame: usize,
    pub to_key_frame: usize,
    /// Positions in the episode's frame order.
    pub from_frame: usize,
    pub to_frame: usize,
    /// The diff over every object the camera sees in either key frame (ENACT's full view).
    pub full_diff: StateDiff,
    /// The diff restricted to what the camera sees in both key frames (ENACT's visible view,
    /// the one items are made from).
    pub visible_diff: StateDiff,
    /// The action text of the visible diff with every sentence in its first template ("now
    /// becomes", "is no longer"); the pipeline picks each verb at random among its templates,
    /// which changes the wording but not the signatures. `None` when the change has nothing
    /// ENACT can describe.
    pub action: Option<String>,
    /// Signature components of the visible diff (ENACT's C sets), sorted.
    pub visible_signatures: Vec<String>,
    /// Signature components of the full diff (ENACT's F sets), sorted.
    pub full_signatures: Vec<String>,
    /// Why the transition could not be described (an unformattable name, a half object
    /// without a parent, ...); every other field is then empty.
    pub error: Option<String>,
}

/// Every transition between consecutive key frames, in order. Works on graphs that do not
/// validate too (the editor shows it while the curator types): a transition that cannot be
/// computed carries its `error`.
pub fn describe(graphs: &EpisodeGraphs) -> Vec<TransitionView> {
    graphs
        .key_frames
        .windows(2)
        .enumerate()
        .map(|(index, pair)| {
            let mut view = TransitionView {
                from_key_frame: index,
                to_key_frame: index + 1,
                from_frame: pair[0].frame,
                to_frame: pair[1].frame,
                full_diff: StateDiff::default(),
                visible_diff: StateDiff::default(),
                action: None,
                visible_signatures: Vec::new(),
                full_signatures: Vec::new(),
                error: None,
            };
            let a = pair[0].scene_graph(FrameSize::NOMINAL);
            let b = pair[1].scene_graph(FrameSize::NOMINAL);
            let described = (|| -> Result<(), String> {
                let full = state_centric_diff(&a, &b).map_err(|e| e.to_string())?;
                let visible = restrict_to_view(&a, &b, &full, View::Visible, &EVALUATION_SENSORS)
                    .map_err(|e| e.to_string())?;
                let full_view = restrict_to_view(&a, &b, &full, View::Full, &EVALUATION_SENSORS)
                    .map_err(|e| e.to_string())?;
                view.action = render_diff_first_templates(&visible).map_err(|e| e.to_string())?;
                view.visible_signatures = diff_signatures(&visible)
                    .map_err(|e| e.to_string())?
                    .into_iter()
                    .collect();
                view.full_signatures = diff_signatures(&full_view)
                    .map_err(|e| e.to_string())?
                    .into_iter()
                    .collect();
                view.full_diff = full_view;
                view.visible_diff = visible;
                Ok(())
            })();
            if let Err(error) = described {
                view = TransitionView {
                    action: None,
                    visible_signatures: Vec::new(),
                    full_signatures: Vec::new(),
                    full_diff: StateDiff::default(),
                    visible_diff: StateDiff::default(),
                    error: Some(error),
                    ..view
                };
            }
            view
        })
        .collect()
}
