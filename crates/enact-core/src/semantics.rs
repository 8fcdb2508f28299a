//! Transition signatures for dataset items: what the verifier needs for semantic matching.
//!
//! Two sources, in order of preference:
//! - **scene graphs** (`REPLAYED_DIR/{task}/scene_graph_0.json`): ENACT's own computation, for
//!   forward and inverse items alike;
//! - **action text**, for inverse items only when no scene graph exists: each `[Action k]`
//!   sentence is parsed back into signatures. The parsed set of the action that caused
//!   transition i stands in for both its visible set C_i and its full set F_i. Since ENACT
//!   accepts a chosen action when its visible set is a subset of F_i, and C_i ⊆ F_i, a verdict
//!   computed this way can only be stricter than ENACT's with scene graphs: a lower bound.
//!
//! Forward items without scene graphs are scored by exact match only.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::dataset::{Direction, FieldProblem, QaItem};
use crate::pipeline::release::release_vocabulary;
use crate::scene_graph::{
    FrameSelection, PairSignatureMemo, SceneGraphTimeline, StateVocabulary, TimelineError, View,
    parse_action,
};
use crate::verifier::{ItemSignatures, VisibleCoverage};

/// Where an item's signatures came from; reports count items by this.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SignatureSource {
    SceneGraph,
    ActionText,
}

impl SignatureSource {
    pub fn as_str(self) -> &'static str {
        match self {
            SignatureSource::SceneGraph => "scene_graph",
            SignatureSource::ActionText => "action_text",
        }
    }

    pub fn parse(s: &str) -> Option<SignatureSource> {
        match s {
            "scene_graph" => Some(SignatureSource::SceneGraph),
            "action_text" => Some(SignatureSource::ActionText),
            _ => None,
        }
    }
}

/// An item's signature table and its provenance.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ItemSemantics {
    pub source: SignatureSource,
    pub signatures: ItemSignatures,
}

/// An item's signature table, or what stops it being computed.
pub type SignaturesOrProblems = Result<ItemSignatures, Vec<FieldProblem>>;

/// The scene-graph file ENACT reads for a task.
pub fn scene_graph_path(replayed_dir: &Path, task_name: &str) -> PathBuf {
    replayed_dir.join(task_name).join("scene_graph_0.json")
}

/// Builds one item's table from a loaded timeline, reading pairs from `memo` (a task's pairs
/// computed once, see [`PairSignatureMemo`]). Pairs on which ENACT raises are kept as errors
/// inside the table (the verifier reproduces what ENACT does with them).
///
/// A forward item's table holds the visible sets of every ordered pair, not only the
/// chronological ones the verifier reads: the error analysis compares each step of a forward
/// answer with the visible change between the frames the answer put side by side.
pub fn item_signatures(
    memo: &PairSignatureMemo,
    timeline: &SceneGraphTimeline,
    key_frame_ids: &[String],
    direction: Direction,
) -> ItemSignatures {
    let coverage = match direction {
        Direction::Forward => VisibleCoverage::AllPairs,
        Direction::Inverse => VisibleCoverage::Chronological,
    };
    ItemSignatures::build(key_frame_ids, coverage, |from, to, view| {
        memo.signatures(timeline, from, to, view)
    })
}

/// Signatures from scene graphs for every item, in input order.
///
/// Problems name the field that points at the trouble: `task_name` when the task has no
/// readable scene graph (file missing, malformed JSON: the message names the file and the
/// place), `key_frame_ids[i]` when a key frame is not in the scene graph.
///
/// The scene graphs of a contact run (a `generate --key-frames contact` release's
/// `replayed_activities/`) give signatures of its contact changes too, as its actions describe
/// them; any other folder gives ENACT's.
pub fn from_scene_graphs(replayed_dir: &Path, items: &[&QaItem]) -> Vec<SignaturesOrProblems> {
    let vocabulary = replayed_dir
        .parent()
        .map_or(StateVocabulary::Enact, release_vocabulary);
    let mut by_task: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for (i, item) in items.iter().enumerate() {
        by_task.entry(item.task_name.as_str()).or_default().push(i);
    }
    let per_task: Vec<Vec<(usize, SignaturesOrProblems)>> = by_task
        .into_par_iter()
        .map(|(task, indexes)| {
            let path = scene_graph_path(replayed_dir, task);
            let frames: BTreeSet<String> = indexes
                .iter()
                .flat_map(|&i| items[i].key_frame_ids.iter().cloned())
                .collect();
            let timeline = if path.is_file() {
                SceneGraphTimeline::load(&path, FrameSelection::Only(frames))
            } else {
                Err(TimelineError::Io {
                    path: path.clone(),
                    source: std::io::Error::new(
                        std::io::ErrorKind::NotFound,
                        "no such file (is --scene-graphs the replayed_activities folder?)",
                    ),
                })
            };
            // Each distinct pair of the task once (in parallel), then the items' tables.
            let memo = match &timeline {
                Ok(tl) => PairSignatureMemo::compute_in(
                    tl,
                    indexes
                        .iter()
                        .flat_map(|&i| PairSignatureMemo::item_pairs(&items[i].key_frame_ids))
                        .collect(),
                    vocabulary,
                ),
                Err(_) => PairSignatureMemo::default(),
            };
            indexes
                .into_par_iter()
                .map(|i| {
                    let result = match &timeline {
                        Err(e) => Err(vec![FieldProblem::new("task_name", e.to_string())]),
                        Ok(tl) => {
                            let missing: Vec<FieldProblem> = items[i]
                                .key_frame_ids
                                .iter()
                                .enumerate()
                                .filter(|(_, f)| tl.scene_graph(f).is_err())
                                .map(|(k, f)| {
                                    FieldProblem::new(
                                        format!("key_frame_ids[{k}]"),
                                        format!("frame {f} is not in {}", path.display()),
                                    )
                                })
                                .collect();
                            if missing.is_empty() {
                                Ok(item_signatures(
                                    &memo,
                                    tl,
                                    &items[i].key_frame_ids,
                                    items[i].direction,
                                ))
                            } else {
                                Err(missing)
                            }
                        }
                    };
                    (i, result)
                })
                .collect()
        })
        .collect();
    let mut out: Vec<Option<SignaturesOrProblems>> = (0..items.len()).map(|_| None).collect();
    for (i, result) in per_task.into_iter().flatten() {
        out[i] = Some(result);
    }
    out.into_iter()
        .map(|r| r.unwrap_or_else(|| Err(vec![FieldProblem::new("", "not computed")])))
        .collect()
}

/// The text-derived table of an inverse item (see the module documentation), or `None` for a
/// forward item or when some action sentence cannot be parsed.
pub fn from_action_text(item: &QaItem) -> Option<ItemSignatures> {
    if item.direction != Direction::Inverse {
        return None;
    }
    let parsed: Vec<BTreeSet<String>> = item
        .actions
        .iter()
        .map(|text| parse_action(text).ok())
        .collect::<Option<_>>()?;
    // Transition i was caused by the action labelled gt[i].
    let mut by_transition: BTreeMap<(&str, &str), &BTreeSet<String>> = BTreeMap::new();
    for (i, label) in item.gt_answer.iter().enumerate() {
        let set = parsed.get(usize::from(*label).checked_sub(1)?)?;
        by_transition.insert(
            (
                item.key_frame_ids.get(i)?.as_str(),
                item.key_frame_ids.get(i + 1)?.as_str(),
            ),
            set,
        );
    }
    Some(ItemSignatures::build(
        &item.key_frame_ids,
        VisibleCoverage::Chronological,
        |from, to, _view: View| {
            by_transition
                .get(&(from, to))
                .map(|s| (*s).clone())
                .ok_or_else(|| {
                    "no scene graph: only transitions parsed from action text".to_owned()
                })
        },
    ))
}

/// The best table available for each item: scene graphs when `replayed_dir` is given (a
/// problem there is reported, not papered over), otherwise the action-text fallback.
pub fn for_items(
    replayed_dir: Option<&Path>,
    items: &[&QaItem],
) -> Vec<Result<Option<ItemSemantics>, Vec<FieldProblem>>> {
    match replayed_dir {
        Some(dir) => from_scene_graphs(dir, items)
            .into_iter()
            .map(|r| {
                r.map(|signatures| {
                    Some(ItemSemantics {
                        source: SignatureSource::SceneGraph,
                        signatures,
                    })
                })
            })
            .collect(),
        None => items
            .par_iter()
            .map(|item| {
                Ok(from_action_text(item).map(|signatures| ItemSemantics {
                    source: SignatureSource::ActionText,
                    signatures,
                }))
            })
            .collect(),
    }
}
