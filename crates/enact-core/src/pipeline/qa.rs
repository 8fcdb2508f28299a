//! Forward and inverse ordering items built from sampled key-frame paths: ids, type names,
//! action texts, label shuffles and ground truth, and the images each item shows.

use rand::Rng;
use rand::seq::SliceRandom;
use serde::Serialize;
use sha2::{Digest, Sha256};

use crate::dataset::{Direction, QaItem};
use crate::pipeline::prompt::{forward_question, inverse_question};
use crate::scene_graph::sentence::NO_MEANINGFUL_CHANGE_TEXT;
use crate::scene_graph::{SceneGraphTimeline, StateVocabulary, View, render_diff_in, visible_diff};

use crate::pipeline::kfts::KftsError;

/// How the `type` field names an item.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TypeNaming {
    /// `{direction}_world_modeling_{L}_steps`, what ENACT's public code emits.
    #[default]
    Code,
    /// `{direction}_world_modeling_ordering_{L}_steps`, what the released dataset says.
    Ordering,
}

/// The `type` of an item.
pub fn qa_type(direction: Direction, length: usize, naming: TypeNaming) -> String {
    match naming {
        TypeNaming::Code => format!("{direction}_world_modeling_{length}_steps"),
        TypeNaming::Ordering => format!("{direction}_world_modeling_ordering_{length}_steps"),
    }
}

/// ENACT's item id: `{task}_{type}_{sha256("_".join(key_frame_ids))[:8]}`.
pub fn item_id(task_name: &str, qa_type: &str, key_frame_ids: &[String]) -> String {
    let digest = Sha256::digest(key_frame_ids.join("_").as_bytes());
    let hex = hex::encode(digest);
    format!("{task_name}_{qa_type}_{}", &hex[..8])
}

/// The inverse generator keeps at most this many items per (task, L), in random order.
pub const INVERSE_ITEMS_CAP: usize = 25;

/// One image of an item: which key frame, the label drawn on it, and where it goes
/// (relative to the release root).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LabelledImage {
    pub frame: String,
    pub label: String,
    pub path: String,
}

/// A generated QA item, serialised as one line of `QA/enact_ordering.jsonl`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct GeneratedItem {
    pub id: String,
    #[serde(rename = "type")]
    pub qa_type: String,
    pub task_name: String,
    pub key_frame_ids: Vec<String>,
    pub images: Vec<String>,
    pub question: String,
    pub options: Vec<String>,
    pub gt_answer: Vec<usize>,
    /// Which frame each image shows, with its label (not part of the JSONL line).
    #[serde(skip)]
    pub labelled_images: Vec<LabelledImage>,
}

/// The action text of every transition of a chronological path: ENACT's sentence rendering
/// of the visible diff, templates chosen with `rng`; a diff without sentences gets ENACT's
/// "No meaningful change is observed.".
pub fn action_texts<R: Rng + ?Sized>(
    timeline: &SceneGraphTimeline,
    path: &[String],
    rng: &mut R,
) -> Result<Vec<String>, KftsError> {
    action_texts_in(timeline, path, StateVocabulary::Enact, rng)
}

/// [`action_texts`] describing the states of `vocabulary`.
pub fn action_texts_in<R: Rng + ?Sized>(
    timeline: &SceneGraphTimeline,
    path: &[String],
    vocabulary: StateVocabulary,
    rng: &mut R,
) -> Result<Vec<String>, KftsError> {
    path.windows(2)
        .map(|pair| {
            let diff = visible_diff(timeline, &pair[0], &pair[1], View::Visible)?;
            let text =
                render_diff_in(&diff, vocabulary, rng).map_err(|source| KftsError::Name {
                    file: timeline.source().display().to_string(),
                    from: pair[0].clone(),
                    to: pair[1].clone(),
                    source,
                })?;
            Ok(text.unwrap_or_else(|| NO_MEANINGFUL_CHANGE_TEXT.to_string()))
        })
        .collect()
}

fn image_path(qa_type: &str, task_name: &str, id: &str, position: usize) -> String {
    let file = if position == 0 {
        format!("{id}_cur_state.png")
    } else {
        format!("{id}_next_state_{position}.png")
    };
    format!("QA/images/{qa_type}/{task_name}/{file}")
}

/// The current state first, then `next` in the order given, labelled and placed.
fn labelled_images(
    qa_type: &str,
    task_name: &str,
    id: &str,
    current: &str,
    next: &[String],
) -> Vec<LabelledImage> {
    std::iter::once(current)
        .chain(next.iter().map(String::as_str))
        .enumerate()
        .map(|(position, frame)| LabelledImage {
            frame: frame.to_string(),
            label: QaItem::image_label(position),
            path: image_path(qa_type, task_name, id, position),
        })
        .collect()
}

/// A forward item: the actions in time order, the future states shuffled; `gt_answer[j]` is
/// the label of the (j+1)-th chronological future state.
pub fn forward_item<R: Rng + ?Sized>(
    task_name: &str,
    qa_type: &str,
    path: &[String],
    actions: &[String],
    rng: &mut R,
) -> GeneratedItem {
    let id = item_id(task_name, qa_type, path);
    let mut shuffled = path[1..].to_vec();
    shuffled.shuffle(rng);
    let gt_answer = path[1..]
        .iter()
        .map(|frame| {
            shuffled
                .iter()
                .position(|s| s == frame)
                .map_or(0, |i| i + 1)
        })
        .collect();
    let labelled = labelled_images(qa_type, task_name, &id, &path[0], &shuffled);
    GeneratedItem {
        images: labelled.iter().map(|l| l.path.clone()).collect(),
        id,
        qa_type: qa_type.to_string(),
        task_name: task_name.to_string(),
        key_frame_ids: path.to_vec(),
        question: forward_question(actions),
        options: Vec::new(),
        gt_answer,
        labelled_images: labelled,
    }
}

/// ENACT quirk: when two actions of an inverse item have the same text, each transition takes
/// the first label with that text not used by an earlier transition.
pub fn inverse_ground_truth(chronological: &[String], shuffled: &[String]) -> Vec<usize> {
    let mut used = vec![false; shuffled.len()];
    chronological
        .iter()
        .filter_map(|action| {
            let at = (0..shuffled.len()).find(|&i| !used[i] && shuffled[i] == *action)?;
            used[at] = true;
            Some(at + 1)
        })
        .collect()
}

/// An inverse item: the images in time order, the actions shuffled; `gt_answer[j]` is the
/// label of the action of transition j.
pub fn inverse_item<R: Rng + ?Sized>(
    task_name: &str,
    qa_type: &str,
    path: &[String],
    actions: &[String],
    rng: &mut R,
) -> GeneratedItem {
    let id = item_id(task_name, qa_type, path);
    let mut shuffled = actions.to_vec();
    shuffled.shuffle(rng);
    let gt_answer = inverse_ground_truth(actions, &shuffled);
    let labelled = labelled_images(qa_type, task_name, &id, &path[0], &path[1..]);
    GeneratedItem {
        images: labelled.iter().map(|l| l.path.clone()).collect(),
        id,
        qa_type: qa_type.to_string(),
        task_name: task_name.to_string(),
        key_frame_ids: path.to_vec(),
        question: inverse_question(&shuffled),
        options: Vec::new(),
        gt_answer,
        labelled_images: labelled,
    }
}

/// ENACT quirk: the inverse generator returns `random.sample(items, min(25, n))`, which both
/// caps and reorders the items.
pub fn cap_inverse_items<R: Rng + ?Sized>(items: &mut Vec<GeneratedItem>, rng: &mut R) {
    items.shuffle(rng);
    items.truncate(INVERSE_ITEMS_CAP);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::parse_release_line;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn strings(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn ids_and_types() {
        let t = qa_type(Direction::Forward, 3, TypeNaming::Code);
        assert_eq!(t, "forward_world_modeling_3_steps");
        assert_eq!(
            qa_type(Direction::Inverse, 10, TypeNaming::Ordering),
            "inverse_world_modeling_ordering_10_steps"
        );
        // sha256("1061_8095_9327") starts with ffe68db8 (the released cook_bacon item).
        let id = item_id("cook_bacon_1", &t, &strings(&["1061", "8095", "9327"]));
        assert_eq!(id, "cook_bacon_1_forward_world_modeling_3_steps_ffe68db8");
    }

    #[test]
    fn forward_ground_truth_lists_labels_in_time_order() {
        let path = strings(&["10", "20", "30", "40"]);
        let actions = strings(&["A.", "B.", "C."]);
        for seed in 0..20 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let item = forward_item(
                "task_1",
                "forward_world_modeling_4_steps",
                &path,
                &actions,
                &mut rng,
            );
            // Image i (i ≥ 1) shows the state labelled "Next State i"; gt[j] is the label of
            // path[j+1], so the images listed in gt order are chronological.
            for (j, &label) in item.gt_answer.iter().enumerate() {
                assert_eq!(item.labelled_images[label].frame, path[j + 1]);
                assert_eq!(
                    item.labelled_images[label].label,
                    format!("Next State {label}")
                );
            }
            assert_eq!(item.labelled_images[0].frame, "10");
            assert_eq!(item.labelled_images[0].label, "Current State");
            assert!(
                item.question
                    .contains("[Action 1] A.\n[Action 2] B.\n[Action 3] C.")
            );
            assert!(item.images[2].ends_with(&format!("{}_next_state_2.png", item.id)));
        }
    }

    #[test]
    fn inverse_ground_truth_takes_first_unused_label_for_repeated_text() {
        let chronological = strings(&["Open.", "Close.", "Open."]);
        let shuffled = strings(&["Open.", "Open.", "Close."]);
        assert_eq!(
            inverse_ground_truth(&chronological, &shuffled),
            vec![1, 3, 2]
        );
        let shuffled = strings(&["Close.", "Open.", "Open."]);
        assert_eq!(
            inverse_ground_truth(&chronological, &shuffled),
            vec![2, 1, 3]
        );
    }

    #[test]
    fn inverse_items_keep_images_in_time_order() {
        let path = strings(&["1", "2", "3", "4"]);
        let actions = strings(&["A.", "B.", "C."]);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let item = inverse_item(
            "t_1",
            "inverse_world_modeling_4_steps",
            &path,
            &actions,
            &mut rng,
        );
        let frames: Vec<&str> = item
            .labelled_images
            .iter()
            .map(|l| l.frame.as_str())
            .collect();
        assert_eq!(frames, vec!["1", "2", "3", "4"]);
        let lines = crate::dataset::action_lines(&item.question);
        for (j, &label) in item.gt_answer.iter().enumerate() {
            let (n, text) = &lines[label - 1];
            assert_eq!(*n as usize, label);
            assert_eq!(*text, actions[j]);
        }
    }

    #[test]
    fn items_parse_as_release_lines() {
        let path = strings(&["59", "270", "517"]);
        let actions = strings(&["The apple is now on the table.", "The fridge is open."]);
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for (direction, item) in [
            (
                Direction::Forward,
                forward_item(
                    "slicing_1749141358356841",
                    &qa_type(Direction::Forward, 3, TypeNaming::Code),
                    &path,
                    &actions,
                    &mut rng,
                ),
            ),
            (
                Direction::Inverse,
                inverse_item(
                    "slicing_1749141358356841",
                    &qa_type(Direction::Inverse, 3, TypeNaming::Ordering),
                    &path,
                    &actions,
                    &mut rng,
                ),
            ),
        ] {
            let line = serde_json::to_string(&item).unwrap();
            assert!(line.starts_with("{\"id\":"));
            let parsed = parse_release_line(&line).unwrap();
            assert_eq!(parsed.direction, direction);
            assert_eq!(parsed.key_frame_ids, path);
        }
    }

    #[test]
    fn inverse_cap_keeps_25() {
        let path = strings(&["1", "2", "3"]);
        let actions = strings(&["A.", "B."]);
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut items: Vec<GeneratedItem> = (0..40)
            .map(|_| {
                inverse_item(
                    "t_1",
                    "inverse_world_modeling_3_steps",
                    &path,
                    &actions,
                    &mut rng,
                )
            })
            .collect();
        cap_inverse_items(&mut items, &mut rng);
        assert_eq!(items.len(), INVERSE_ITEMS_CAP);
    }
}
