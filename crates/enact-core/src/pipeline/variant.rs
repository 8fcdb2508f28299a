//! A variant release that keeps a baseline's items: the paper's ablations ask the same
//! questions with other renderings (camera, realism, embodiment), so the variant's
//! `QA/enact_ordering.jsonl` is the baseline's, byte for byte, and only the images change:
//! each is drawn, with its label, from the variant replay's image of the same key frame.
//! With an [`ActionRewrite`] the action lines of the questions change too (another encoding,
//! perturbed deltas), computed from the baseline's own key-frame scene graphs; ids, frames and
//! answers stay.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::pipeline::actions::{ActionRewrite, rewrite_item};
use crate::pipeline::scene_graph_path;
use crate::scene_graph::{FrameSelection, SceneGraphTimeline};

use crate::dataset::{Direction, QaItem, parse_release_line};
use crate::pipeline::label::LabelFont;
use crate::pipeline::release::{
    LabelledTargets, copy_file, create_dir, same_dir, write_labelled_targets,
};
use crate::pipeline::{PipelineError, frame_image_path, task_names};
use crate::release::QA_FILE;

/// What [`items_from`] wrote.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VariantRelease {
    pub items: usize,
    pub tasks: usize,
    /// Item images written (each distinct frame and label drawn once, then copied).
    pub images: usize,
    /// Action texts that differ from the baseline's.
    pub actions_rewritten: usize,
    /// Predicates the perturbation dropped or swapped.
    pub predicates_perturbed: usize,
    pub jsonl_path: PathBuf,
}

/// Which key frame each of an item's images shows: inverse items list the states in time
/// order; a forward item's future states are shuffled, and `gt_answer[j]` is the position of
/// the image of key frame `j + 1`.
pub fn image_frames(item: &QaItem) -> Vec<&str> {
    let frames = &item.key_frame_ids;
    match item.direction {
        Direction::Inverse => frames.iter().map(String::as_str).collect(),
        Direction::Forward => {
            let mut shown = vec![frames[0].as_str(); frames.len()];
            for (j, &label) in item.gt_answer.iter().enumerate() {
                shown[usize::from(label)] = frames[j + 1].as_str();
            }
            shown
        }
    }
}

/// Writes into `out` the items of the release at `baseline` with their images taken from the
/// replays in `variant_replayed` (`{task}/external_sensor1/{frame:05}.png`). Refuses, before
/// writing anything, a baseline line that is not a valid item, a task the variant replay does
/// not have, and a key frame it has no image of.
pub fn items_from(
    variant_replayed: &Path,
    baseline: &Path,
    out: &Path,
    rewrite: &ActionRewrite,
) -> Result<VariantRelease, PipelineError> {
    if same_dir(out, baseline) {
        return Err(PipelineError::Options(format!(
            "--out {} is the baseline itself: write the variant somewhere else",
            out.display()
        )));
    }
    let qa_file = baseline.join(QA_FILE);
    let text = std::fs::read_to_string(&qa_file).map_err(|source| PipelineError::Read {
        path: qa_file.clone(),
        source,
    })?;
    let mut items = Vec::new();
    let mut lines = Vec::new();
    for (index, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let item = parse_release_line(line).map_err(|problems| PipelineError::Baseline {
            path: qa_file.clone(),
            line: index + 1,
            message: problems
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join("; "),
        })?;
        items.push(item);
        lines.push((index + 1, line));
    }
    if items.is_empty() {
        return Err(PipelineError::Options(format!(
            "{} holds no item",
            qa_file.display()
        )));
    }

    let available: BTreeSet<String> = task_names(variant_replayed)?.into_iter().collect();
    let tasks: BTreeSet<&str> = items.iter().map(|i| i.task_name.as_str()).collect();
    if let Some(task) = tasks.iter().find(|t| !available.contains(**t)) {
        return Err(PipelineError::TaskNotInVariant {
            task: (*task).to_owned(),
            dir: variant_replayed.to_path_buf(),
        });
    }
    // (task, frame, label) -> the images showing it.
    let mut targets = LabelledTargets::new();
    for item in &items {
        for (position, frame) in image_frames(item).into_iter().enumerate() {
            let source = frame_image_path(variant_replayed, &item.task_name, frame);
            if !source.is_file() {
                return Err(PipelineError::MissingKeyFrameImage {
                    task: item.task_name.clone(),
                    frame: frame.to_owned(),
                    path: source,
                });
            }
            targets
                .entry((&item.task_name, frame, QaItem::image_label(position)))
                .or_default()
                .push(out.join(&item.images[position]));
        }
    }

    // Rewritten before any image is written, so a baseline that cannot be rewritten leaves
    // nothing behind.
    let rewritten = if rewrite.is_identity() {
        None
    } else {
        Some(rewrite_lines(baseline, &qa_file, &items, &lines, rewrite)?)
    };
    let images = write_labelled_targets(variant_replayed, &targets, &LabelFont::load()?)?;
    let jsonl_path = out.join(QA_FILE);
    if let Some(dir) = jsonl_path.parent() {
        create_dir(dir)?;
    }
    let (actions_rewritten, predicates_perturbed) = match rewritten {
        Some(done) => {
            std::fs::write(&jsonl_path, done.text).map_err(|source| PipelineError::Write {
                path: jsonl_path.clone(),
                source,
            })?;
            (done.actions_rewritten, done.predicates_perturbed)
        }
        // The baseline's file itself: ids, questions, answers and their order stay exactly as
        // they were, so a variant's scores line up with the baseline's item by item.
        None => {
            copy_file(&qa_file, &jsonl_path)?;
            (0, 0)
        }
    };
    Ok(VariantRelease {
        items: items.len(),
        tasks: tasks.len(),
        images,
        actions_rewritten,
        predicates_perturbed,
        jsonl_path,
    })
}

/// A baseline's JSONL with its action lines rewritten.
struct RewrittenLines {
    text: String,
    actions_rewritten: usize,
    predicates_perturbed: usize,
}

/// Rewrites every item's action lines from the baseline's own key-frame scene graphs
/// (`replayed_activities/{task}/scene_graph_0.json`, which `generate` writes); an item whose
/// texts all stay keeps its line byte for byte.
fn rewrite_lines(
    baseline: &Path,
    qa_file: &Path,
    items: &[QaItem],
    lines: &[(usize, &str)],
    rewrite: &ActionRewrite,
) -> Result<RewrittenLines, PipelineError> {
    let graphs = baseline.join("replayed_activities");
    let mut frames: BTreeMap<&str, BTreeSet<String>> = BTreeMap::new();
    for item in items {
        frames
            .entry(&item.task_name)
            .or_default()
            .extend(item.key_frame_ids.iter().cloned());
    }
    let mut timelines: BTreeMap<&str, SceneGraphTimeline> = BTreeMap::new();
    for (task, frames) in frames {
        let path = scene_graph_path(&graphs, task);
        if !path.is_file() {
            return Err(PipelineError::MissingSceneGraph {
                task: task.to_owned(),
                path,
            });
        }
        let timeline =
            SceneGraphTimeline::load(&path, FrameSelection::Only(frames)).map_err(|source| {
                PipelineError::SceneGraph {
                    task: task.to_owned(),
                    source: Box::new(source),
                }
            })?;
        timelines.insert(task, timeline);
    }
    let mut out = RewrittenLines {
        text: String::with_capacity(lines.iter().map(|(_, l)| l.len() + 1).sum()),
        actions_rewritten: 0,
        predicates_perturbed: 0,
    };
    for (item, (number, line)) in items.iter().zip(lines) {
        let at_line = |message: String| PipelineError::Baseline {
            path: qa_file.to_path_buf(),
            line: *number,
            message: format!("item {}: {message}", item.id),
        };
        let timeline = &timelines[item.task_name.as_str()];
        let done = rewrite_item(item, timeline, rewrite).map_err(|e| at_line(e.to_string()))?;
        out.predicates_perturbed += done.changes.iter().map(Vec::len).sum::<usize>();
        out.actions_rewritten += done
            .actions
            .iter()
            .zip(&item.actions)
            .filter(|(new, old)| new != old)
            .count();
        match done.question {
            Some(question) => {
                let mut record: serde_json::Value =
                    serde_json::from_str(line).map_err(|e| at_line(e.to_string()))?;
                record["question"] = serde_json::Value::String(question);
                let written =
                    serde_json::to_string(&record).map_err(|source| PipelineError::Serialize {
                        what: format!("item {}", item.id),
                        source,
                    })?;
                out.text.push_str(&written);
            }
            None => out.text.push_str(line),
        }
        out.text.push('\n');
    }
    Ok(out)
}
