//! Scene graphs of replayed tasks and what changed between two frames, bit-exact with ENACT:
//! records and reconstruction ([`timeline`]), the transient filter ([`transient`]), the
//! state-centric diff ([`diff`]), what the camera sees ([`visibility`]), object names
//! ([`names`]), signatures ([`signature`]) and action sentences ([`sentence`]); [`contact`]
//! names the contact relations a contact run also describes.
//!
//! Start with [`SceneGraphTimeline::load`] and [`pair_signatures`] /
//! [`transition_signatures`]: the evaluator's C (visible) and F (full) sets.

pub mod contact;
pub mod diff;
pub mod names;
pub mod record;
pub mod sentence;
pub mod signature;
mod split;
pub mod timeline;
pub mod transient;
pub mod visibility;

use std::borrow::Cow;
use std::collections::{BTreeSet, HashMap};
use std::path::PathBuf;

use rayon::prelude::*;

pub use contact::{CONTACT_STATES, contact_relations};
pub use diff::{
    ChangeOp, DiffFault, DiffSide, EdgeChange, GraphIndex, NodeChange, StateDiff,
    state_centric_diff, state_centric_diff_indexed,
};
pub use names::{NameError, format_object_name};
pub use record::{FrameRecord, GraphDelta, SceneEdge, SceneGraph, SceneNode};
pub use sentence::{
    SentenceParseError, parse_action, render_diff, render_diff_first_templates, render_diff_in,
    sentence_count, sentence_count_in,
};
pub use signature::{StateVocabulary, diff_signatures, diff_signatures_in};
pub use timeline::{FrameSelection, SceneGraphTimeline, TimelineError, TransientFilter};
pub use visibility::{EVALUATION_SENSORS, View, restrict_to_view, restrict_to_view_indexed};

/// Why the change between two frames could not be computed.
#[derive(Debug, thiserror::Error)]
pub enum DiffError {
    /// A frame is missing or its graph cannot be rebuilt.
    #[error(transparent)]
    Timeline(#[from] TimelineError),
    /// ENACT raises (or exits) on this pair, e.g. a backward pair across cooking.
    #[error("{file}: frames {from} -> {to}: {fault}")]
    Pair {
        file: PathBuf,
        from: String,
        to: String,
        #[source]
        fault: Box<DiffFault>,
    },
}

/// The diff from `from` to `to` in both views, computed from one state-centric diff.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PairDiffs {
    /// ENACT's `get_visible_full_diff(..., partial_diff=True)`.
    pub visible: StateDiff,
    /// ENACT's `get_visible_full_diff(..., partial_diff=False)`.
    pub full: StateDiff,
}

/// Wraps a fault with the pair it happened on (allocating only when there is one).
fn pair_fault<'a>(
    timeline: &'a SceneGraphTimeline,
    from: &'a str,
    to: &'a str,
) -> impl Fn(DiffFault) -> DiffError + 'a {
    move |fault| DiffError::Pair {
        file: timeline.source().to_path_buf(),
        from: from.to_string(),
        to: to.to_string(),
        fault: Box::new(fault),
    }
}

/// ENACT's `get_visible_full_diff(from, to, ["external_sensor1"], partial_diff)` with
/// `partial_diff = (view == View::Visible)`.
pub fn visible_diff(
    timeline: &SceneGraphTimeline,
    from: &str,
    to: &str,
    view: View,
) -> Result<StateDiff, DiffError> {
    let (a, b) = (timeline.scene_graph(from)?, timeline.scene_graph(to)?);
    visible_diff_indexed(
        timeline,
        from,
        to,
        &GraphIndex::new(&a),
        &GraphIndex::new(&b),
        view,
    )
}

/// [`visible_diff`] over the two frames' graphs, already indexed (`a` is `from`'s).
pub fn visible_diff_indexed(
    timeline: &SceneGraphTimeline,
    from: &str,
    to: &str,
    a: &GraphIndex<'_>,
    b: &GraphIndex<'_>,
    view: View,
) -> Result<StateDiff, DiffError> {
    let fault = pair_fault(timeline, from, to);
    let full = state_centric_diff_indexed(a, b).map_err(&fault)?;
    restrict_to_view_indexed(a, b, &full, view, &EVALUATION_SENSORS).map_err(fault)
}

/// Both views of the change from `from` to `to`. Fails if either view fails in ENACT.
pub fn pair_diffs(
    timeline: &SceneGraphTimeline,
    from: &str,
    to: &str,
) -> Result<PairDiffs, DiffError> {
    let fault = pair_fault(timeline, from, to);
    let (a, b) = (timeline.scene_graph(from)?, timeline.scene_graph(to)?);
    let full = state_centric_diff(&a, &b).map_err(&fault)?;
    Ok(PairDiffs {
        visible: restrict_to_view(&a, &b, &full, View::Visible, &EVALUATION_SENSORS)
            .map_err(&fault)?,
        full: restrict_to_view(&a, &b, &full, View::Full, &EVALUATION_SENSORS).map_err(&fault)?,
    })
}

/// The signature set of the change from `from` to `to` in `view` (ENACT's
/// `translate_diff_into_signatures(get_visible_full_diff(...))`). `from == to` gives the
/// empty set, as in ENACT (identical graphs have an empty diff).
pub fn pair_signatures(
    timeline: &SceneGraphTimeline,
    from: &str,
    to: &str,
    view: View,
) -> Result<BTreeSet<String>, DiffError> {
    pair_signatures_in(timeline, from, to, view, StateVocabulary::Enact)
}

/// [`pair_signatures`] of the states `vocabulary` describes.
pub fn pair_signatures_in(
    timeline: &SceneGraphTimeline,
    from: &str,
    to: &str,
    view: View,
    vocabulary: StateVocabulary,
) -> Result<BTreeSet<String>, DiffError> {
    let diff = visible_diff(timeline, from, to, view)?;
    diff_signatures_in(&diff, vocabulary)
        .map_err(|e| pair_fault(timeline, from, to)(DiffFault::Name(e)))
}

/// Both views' signature sets of the change from `from` to `to`, from one state-centric diff:
/// each view fails (or not) exactly as [`pair_signatures`] would for it alone.
pub fn pair_signature_views(
    timeline: &SceneGraphTimeline,
    from: &str,
    to: &str,
) -> [Result<BTreeSet<String>, String>; 2] {
    pair_signature_views_in(timeline, from, to, StateVocabulary::Enact)
}

/// [`pair_signature_views`] of the states `vocabulary` describes.
fn pair_signature_views_in(
    timeline: &SceneGraphTimeline,
    from: &str,
    to: &str,
    vocabulary: StateVocabulary,
) -> [Result<BTreeSet<String>, String>; 2] {
    let graphs = timeline
        .scene_graph(from)
        .and_then(|a| Ok((a, timeline.scene_graph(to)?)));
    match graphs {
        Ok((a, b)) => indexed_signature_views(
            timeline,
            from,
            to,
            &GraphIndex::new(&a),
            &GraphIndex::new(&b),
            vocabulary,
        ),
        Err(e) => {
            let message = DiffError::from(e).to_string();
            [Err(message.clone()), Err(message)]
        }
    }
}

/// [`pair_signature_views`] over the two frames' graphs, already indexed.
fn indexed_signature_views(
    timeline: &SceneGraphTimeline,
    from: &str,
    to: &str,
    a: &GraphIndex<'_>,
    b: &GraphIndex<'_>,
    vocabulary: StateVocabulary,
) -> ViewSets {
    let fault = pair_fault(timeline, from, to);
    let full = match state_centric_diff_indexed(a, b) {
        Ok(full) => full,
        Err(e) => {
            let message = fault(e).to_string();
            return [Err(message.clone()), Err(message)];
        }
    };
    [View::Visible, View::Full].map(|view| {
        restrict_to_view_indexed(a, b, &full, view, &EVALUATION_SENSORS)
            .map_err(&fault)
            .and_then(|diff| {
                diff_signatures_in(&diff, vocabulary).map_err(|e| fault(DiffFault::Name(e)))
            })
            .map_err(|e| e.to_string())
    })
}

/// One pair's signature sets: visible, then full; an `Err` is the message of what ENACT raises.
type ViewSets = [Result<BTreeSet<String>, String>; 2];

/// The signature sets of many frame pairs of one timeline, each pair diffed once.
///
/// Items of one task share most of their pairs (an ENACT task yields up to 16 items over a few
/// dozen key frames), and each pair's two views come from one state-centric diff, so a task's
/// distinct pairs are computed once, in parallel, and items read their tables from here.
#[derive(Debug, Default)]
pub struct PairSignatureMemo {
    sets: HashMap<(String, String), ViewSets>,
    vocabulary: StateVocabulary,
}

impl PairSignatureMemo {
    /// Computes both views of every pair in `pairs`.
    pub fn compute(timeline: &SceneGraphTimeline, pairs: BTreeSet<(String, String)>) -> Self {
        Self::compute_in(timeline, pairs, StateVocabulary::Enact)
    }

    /// [`PairSignatureMemo::compute`] with the signatures of the states `vocabulary` describes
    /// (a contact run's items signal their contact changes too).
    pub fn compute_in(
        timeline: &SceneGraphTimeline,
        pairs: BTreeSet<(String, String)>,
        vocabulary: StateVocabulary,
    ) -> Self {
        // Each frame's graph is indexed once for all the pairs it is in.
        let frames: BTreeSet<&str> = pairs
            .iter()
            .flat_map(|(from, to)| [from.as_str(), to.as_str()])
            .collect();
        let graphs: Vec<(&str, Cow<'_, SceneGraph>)> = frames
            .into_iter()
            .filter_map(|f| Some((f, timeline.scene_graph(f).ok()?)))
            .collect();
        let indexes: HashMap<&str, GraphIndex<'_>> = graphs
            .par_iter()
            .map(|(f, graph)| (*f, GraphIndex::new(graph)))
            .collect();
        let sets = pairs
            .par_iter()
            .map(|(from, to)| {
                let sets = match (indexes.get(from.as_str()), indexes.get(to.as_str())) {
                    (Some(a), Some(b)) => {
                        indexed_signature_views(timeline, from, to, a, b, vocabulary)
                    }
                    // A frame that cannot be rebuilt: the same error as for the pair alone.
                    _ => pair_signature_views_in(timeline, from, to, vocabulary),
                };
                ((from.clone(), to.clone()), sets)
            })
            .collect();
        PairSignatureMemo { sets, vocabulary }
    }

    /// Every ordered pair of `key_frame_ids`, the diagonal included: what an item's table
    /// asks for (see [`crate::verifier::ItemSignatures::build`]).
    pub fn item_pairs(key_frame_ids: &[String]) -> impl Iterator<Item = (String, String)> + '_ {
        key_frame_ids.iter().flat_map(move |from| {
            key_frame_ids
                .iter()
                .map(move |to| (from.clone(), to.clone()))
        })
    }

    /// The set of `from -> to` in `view`: from the memo, or computed now for a pair it lacks.
    pub fn signatures(
        &self,
        timeline: &SceneGraphTimeline,
        from: &str,
        to: &str,
        view: View,
    ) -> Result<BTreeSet<String>, String> {
        let slot = match view {
            View::Visible => 0,
            View::Full => 1,
        };
        match self.sets.get(&(from.to_owned(), to.to_owned())) {
            Some(sets) => sets[slot].clone(),
            None => pair_signatures_in(timeline, from, to, view, self.vocabulary)
                .map_err(|e| e.to_string()),
        }
    }
}

/// The C (visible) and F (full) signature sets of one transition.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TransitionSignatureSets {
    pub visible: BTreeSet<String>,
    pub full: BTreeSet<String>,
}

/// The signature sets of each consecutive transition `key_frame_ids[i] -> key_frame_ids[i+1]`
/// (chronological for a QA item). Fewer than two frames give no transition.
pub fn transition_signatures(
    timeline: &SceneGraphTimeline,
    key_frame_ids: &[String],
) -> Result<Vec<TransitionSignatureSets>, DiffError> {
    key_frame_ids
        .windows(2)
        .map(|pair| {
            let (from, to) = (pair[0].as_str(), pair[1].as_str());
            let diffs = pair_diffs(timeline, from, to)?;
            let fault = pair_fault(timeline, from, to);
            Ok(TransitionSignatureSets {
                visible: diff_signatures(&diffs.visible).map_err(|e| fault(DiffFault::Name(e)))?,
                full: diff_signatures(&diffs.full).map_err(|e| fault(DiffFault::Name(e)))?,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_graph::diff::tests::{edge, node, with_parent};

    fn seen(mut n: SceneNode, pixels: u64) -> SceneNode {
        n.visibility.insert(
            "external_sensor1".into(),
            vec![
                pixels.into(),
                0.into(),
                0.into(),
                5.into(),
                5.into(),
                512.into(),
                512.into(),
            ],
        );
        n
    }

    /// Frame 0: bacon on the pan; 1: the robot grasps the pan while the oven opens out of
    /// view (10 px); 2: the bacon is diced; 3: the diced bacon is cooked.
    fn kitchen() -> SceneGraphTimeline {
        let robot = seen(node("robot_r1", "agent", &[]), 5000);
        let pan = seen(node("frying_pan_7", "frying_pan", &[]), 900);
        let oven = |states: &[&str], px| seen(node("oven_2", "oven", states), px);
        let bacon = seen(node("bacon_4", "bacon", &[]), 300);
        let diced = seen(
            with_parent(node("diced__bacon", "System", &[]), &["bacon_4"]),
            300,
        );
        let cooked = seen(
            with_parent(
                node("cooked__diced__bacon", "System", &[]),
                &["diced__bacon"],
            ),
            300,
        );
        let g0 = SceneGraph {
            nodes: vec![robot.clone(), pan.clone(), oven(&[], 10), bacon.clone()],
            edges: vec![edge("bacon_4", "frying_pan_7", &["OnTop"])],
        };
        let g1 = SceneGraph {
            nodes: vec![robot.clone(), pan.clone(), oven(&["Open"], 10), bacon],
            edges: vec![
                edge("bacon_4", "frying_pan_7", &["OnTop"]),
                edge("robot_r1", "frying_pan_7", &["LeftGrasping", "LeftContact"]),
            ],
        };
        let g2 = SceneGraph {
            nodes: vec![robot.clone(), pan.clone(), oven(&["Open"], 10), diced],
            edges: vec![edge(
                "robot_r1",
                "frying_pan_7",
                &["LeftGrasping", "LeftContact"],
            )],
        };
        let g3 = SceneGraph {
            nodes: vec![robot, pan, oven(&["Open"], 10), cooked],
            edges: vec![],
        };
        SceneGraphTimeline::from_records(
            "kitchen.json",
            [g0, g1, g2, g3]
                .into_iter()
                .enumerate()
                .map(|(i, g)| (i as u64, FrameRecord::Full(g))),
        )
    }

    fn ids(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    fn set(v: &[&str]) -> BTreeSet<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn same_frame_gives_empty_set() {
        let t = kitchen();
        for view in [View::Visible, View::Full] {
            assert!(pair_signatures(&t, "2", "2", view).unwrap().is_empty());
        }
    }

    #[test]
    fn transitions_of_a_chain() {
        let t = kitchen();
        let sets = transition_signatures(&t, &ids(&["0", "1", "2", "3"])).unwrap();
        assert_eq!(sets.len(), 3);
        assert_eq!(
            sets[0].visible,
            set(&["edge_add_the robot r1_the frying pan_LeftGrasping"])
        );
        // The oven is at 10 px: invisible in both views.
        assert_eq!(sets[0].full, sets[0].visible);
        assert_eq!(
            sets[1].visible,
            set(&[
                "edge_remove_the bacon_the frying pan_OnTop",
                "node_transition_from_the bacon_to_the diced bacon",
            ])
        );
        assert_eq!(
            sets[2].visible,
            set(&[
                "edge_remove_the robot r1_the frying pan_LeftGrasping",
                "node_transition_from_the diced bacon_to_the cooked diced bacon",
            ])
        );
        assert!(transition_signatures(&t, &ids(&["0"])).unwrap().is_empty());
        assert_eq!(
            pair_signatures(&t, "0", "1", View::Visible).unwrap(),
            sets[0].visible
        );
    }

    #[test]
    fn backward_across_cooking_is_a_typed_error() {
        let t = kitchen();
        let err = pair_signatures(&t, "3", "2", View::Visible).unwrap_err();
        match &err {
            DiffError::Pair {
                from, to, fault, ..
            } => {
                assert_eq!((from.as_str(), to.as_str()), ("3", "2"));
                assert!(matches!(**fault, DiffFault::SystemParentNotRemoved { .. }));
            }
            other => panic!("unexpected {other:?}"),
        }
        assert!(err.to_string().contains("kitchen.json: frames 3 -> 2"));
        assert!(transition_signatures(&t, &ids(&["0", "3", "2"])).is_err());
        // Forward over the same step is fine.
        assert!(pair_signatures(&t, "2", "3", View::Full).is_ok());
    }

    #[test]
    fn unknown_frame_is_a_typed_error() {
        let t = kitchen();
        let err = pair_signatures(&t, "0", "77", View::Full).unwrap_err();
        assert!(matches!(
            err,
            DiffError::Timeline(TimelineError::FrameNotInSceneGraph { ref frame, .. }) if frame == "77"
        ));
    }
}
