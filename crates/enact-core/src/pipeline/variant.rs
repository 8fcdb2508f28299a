//! A variant release that keeps a baseline's items: the paper's ablations ask the same
//! questions with other renderings (camera, realism, embodiment), so the variant's
//! `QA/enact_ordering.jsonl` is the baseline's, byte for byte, and only the images change:
//! each is drawn, with its label, from the variant replay's image of the same key frame.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

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

    let images = write_labelled_targets(variant_replayed, &targets, &LabelFont::load()?)?;
    let jsonl_path = out.join(QA_FILE);
    if let Some(dir) = jsonl_path.parent() {
        create_dir(dir)?;
    }
    // The baseline's file itself: ids, questions, answers and their order stay exactly as they
    // were, so a variant's scores line up with the baseline's item by item.
    copy_file(&qa_file, &jsonl_path)?;
    Ok(VariantRelease {
        items: items.len(),
        tasks: tasks.len(),
        images,
        jsonl_path,
    })
}
