//! Builds the demo items (forward and inverse, 3..=10 states) from the activities' key frames
//! with ENACT's id, path and answer rules, and writes them out as an ENACT release.

use std::collections::{BTreeMap, HashSet};
use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder, RgbImage};
use rand::Rng;
use rand::seq::SliceRandom;
use serde::Serialize;
use sha2::{Digest, Sha256};

use crate::demo::diff::{SceneGraph, StateDiff};
use crate::demo::kitchen::{FRAME_SIZE, Kitchen};
use crate::demo::label::{LabelFont, Overlay};
use crate::demo::narration::action_text;
use crate::demo::prompt::{forward_question, inverse_question};
use crate::demo::world::{Activity, WorldState};
use crate::demo::{DemoError, DemoSummary};

/// Shortest and longest items, counted in states (ENACT's L).
pub(crate) const STEP_LENGTHS: std::ops::RangeInclusive<usize> = 3..=10;
/// Items per (direction, L).
pub(crate) const ITEMS_PER_TYPE: usize = 2;
/// ENACT keeps a transition in a sequence only if it changes 1 to 5 things.
const MAX_SENTENCES: usize = 5;
/// Where the JSONL goes, relative to the release root.
pub(crate) const JSONL_PATH: &str = "QA/enact_ordering.jsonl";

/// Which way an item asks to order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Direction {
    /// Order shuffled future frames given the actions in order.
    Forward,
    /// Order shuffled actions given the frames in order.
    Inverse,
}

impl Direction {
    /// ENACT quirk: the released data names its types `*_world_modeling_ordering_{L}_steps`,
    /// while ENACT's public generator code emits `*_world_modeling_{L}_steps`; we follow the data.
    pub(crate) fn type_name(self, steps: usize) -> String {
        match self {
            Direction::Forward => format!("forward_world_modeling_ordering_{steps}_steps"),
            Direction::Inverse => format!("inverse_world_modeling_ordering_{steps}_steps"),
        }
    }
}

/// One JSONL row, fields in the order ENACT's `QAPair.to_dict` emits them.
#[derive(Clone, Debug, Serialize)]
pub(crate) struct QaRecord {
    pub(crate) id: String,
    #[serde(rename = "type")]
    pub(crate) qa_type: String,
    pub(crate) task_name: String,
    pub(crate) key_frame_ids: Vec<String>,
    pub(crate) images: Vec<String>,
    pub(crate) question: String,
    pub(crate) options: Vec<String>,
    pub(crate) gt_answer: Vec<u32>,
}

/// An item and, for each of its images, the key-frame state shown and the label drawn on it.
pub(crate) struct DemoItem {
    pub(crate) record: QaRecord,
    pub(crate) run: usize,
    pub(crate) frames: Vec<(usize, String)>,
}

/// One recorded run of an activity: its states and their frame ids.
pub(crate) struct TaskRun {
    pub(crate) task_name: String,
    pub(crate) states: Vec<WorldState>,
    pub(crate) frame_ids: Vec<u64>,
    graphs: Vec<SceneGraph>,
    /// `usable[i][j]`: going from key frame i straight to key frame j changes 1..=5 things.
    usable: Vec<Vec<bool>>,
}

impl TaskRun {
    pub(crate) fn record<R: Rng + ?Sized>(
        activity: &Activity,
        rng: &mut R,
    ) -> Result<TaskRun, DemoError> {
        let states = activity
            .states()
            .map_err(|(step, rejected)| DemoError::Script {
                activity: activity.name,
                step,
                reason: rejected.to_string(),
            })?;
        // A 16-digit microsecond timestamp, as in BEHAVIOR task names.
        let stamp: u64 = rng.random_range(1_700_000_000_000_000..1_760_000_000_000_000);
        let mut frame = rng.random_range(30..400u64);
        let mut frame_ids = Vec::with_capacity(states.len());
        for _ in &states {
            frame_ids.push(frame);
            frame += rng.random_range(120..1800u64);
        }
        let graphs: Vec<SceneGraph> = states.iter().map(SceneGraph::of).collect();
        let n = states.len();
        let usable = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| {
                        j > i
                            && (1..=MAX_SENTENCES).contains(
                                &StateDiff::between(&graphs[i], &graphs[j]).sentence_count(),
                            )
                    })
                    .collect()
            })
            .collect();
        Ok(TaskRun {
            task_name: format!("{}_{stamp}", activity.name),
            states,
            frame_ids,
            graphs,
            usable,
        })
    }

    fn diff(&self, from: usize, to: usize) -> StateDiff {
        StateDiff::between(&self.graphs[from], &self.graphs[to])
    }

    /// `paths[l][i]`: how many usable sequences of `l` key frames start at key frame `i`.
    fn path_counts(&self, longest: usize) -> Vec<Vec<u64>> {
        let n = self.states.len();
        let mut paths = vec![vec![0u64; n]; longest + 1];
        if longest >= 1 {
            paths[1] = vec![1; n];
        }
        for l in 2..=longest {
            for i in 0..n {
                paths[l][i] = (i + 1..n)
                    .filter(|j| self.usable[i][*j])
                    .map(|j| paths[l - 1][j])
                    .sum();
            }
        }
        paths
    }

    /// A usable sequence of `length` key frames, uniformly among all of them.
    pub(crate) fn sample_sequence<R: Rng + ?Sized>(
        &self,
        length: usize,
        rng: &mut R,
    ) -> Option<Vec<usize>> {
        let paths = self.path_counts(length);
        let pick = |candidates: Vec<(usize, u64)>, rng: &mut R| {
            let total: u64 = candidates.iter().map(|(_, w)| w).sum();
            if total == 0 {
                return None;
            }
            let mut ticket = rng.random_range(0..total);
            for (index, weight) in candidates {
                if ticket < weight {
                    return Some(index);
                }
                ticket -= weight;
            }
            None
        };
        let starts = (0..self.states.len())
            .map(|i| (i, paths[length][i]))
            .collect();
        let mut sequence = vec![pick(starts, rng)?];
        for remaining in (1..length).rev() {
            let last = sequence[sequence.len() - 1];
            let next = (last + 1..self.states.len())
                .filter(|j| self.usable[last][*j])
                .map(|j| (j, paths[remaining][j]))
                .collect();
            sequence.push(pick(next, rng)?);
        }
        Some(sequence)
    }
}

/// `{task_name}_{type}_{first 8 hex digits of sha256 of the frame ids joined by "_"}`.
pub(crate) fn item_id(task_name: &str, qa_type: &str, key_frame_ids: &[String]) -> String {
    let digest = Sha256::digest(key_frame_ids.join("_").as_bytes());
    let hash = hex::encode(digest);
    format!("{task_name}_{qa_type}_{}", &hash[..8])
}

/// Image path of an item relative to the release root (always with `/`).
pub(crate) fn image_path(qa_type: &str, task_name: &str, id: &str, slot: usize) -> String {
    let file = if slot == 0 {
        format!("{id}_cur_state.png")
    } else {
        format!("{id}_next_state_{slot}.png")
    };
    format!("QA/images/{qa_type}/{task_name}/{file}")
}

/// Forward answer: for each future state in chronological order, its label among the shuffled
/// next-state images.
pub(crate) fn forward_answer(chronological: &[usize], shuffled: &[usize]) -> Vec<u32> {
    chronological
        .iter()
        .filter_map(|frame| shuffled.iter().position(|s| s == frame))
        .map(|p| p as u32 + 1)
        .collect()
}

/// ENACT quirk: the inverse answer matches actions by their text, so when two transitions have
/// identical text each chronological position takes the first label not used yet.
pub(crate) fn inverse_answer(chronological: &[String], shuffled: &[String]) -> Vec<u32> {
    let mut used = vec![false; shuffled.len()];
    let mut answer = Vec::with_capacity(chronological.len());
    for text in chronological {
        if let Some(p) = (0..shuffled.len()).find(|p| !used[*p] && shuffled[*p] == *text) {
            used[p] = true;
            answer.push(p as u32 + 1);
        }
    }
    answer
}

/// Builds one item over the key frames `sequence` of `run`.
pub(crate) fn build_item<R: Rng + ?Sized>(
    runs: &[TaskRun],
    run_index: usize,
    sequence: &[usize],
    direction: Direction,
    rng: &mut R,
) -> Result<DemoItem, DemoError> {
    let run = &runs[run_index];
    let qa_type = direction.type_name(sequence.len());
    let key_frame_ids: Vec<String> = sequence
        .iter()
        .map(|i| run.frame_ids[*i].to_string())
        .collect();
    let id = item_id(&run.task_name, &qa_type, &key_frame_ids);
    let mut actions = Vec::with_capacity(sequence.len() - 1);
    for pair in sequence.windows(2) {
        let text =
            action_text(&run.diff(pair[0], pair[1]), rng).ok_or_else(|| DemoError::Unchanged {
                id: id.clone(),
                from: pair[0],
                to: pair[1],
            })?;
        actions.push(text);
    }
    let (shown, question, gt_answer) = match direction {
        Direction::Forward => {
            let mut shuffled = sequence[1..].to_vec();
            shuffled.shuffle(rng);
            let answer = forward_answer(&sequence[1..], &shuffled);
            (shuffled, forward_question(&actions), answer)
        }
        Direction::Inverse => {
            let mut shuffled = actions.clone();
            shuffled.shuffle(rng);
            let answer = inverse_answer(&actions, &shuffled);
            (sequence[1..].to_vec(), inverse_question(&shuffled), answer)
        }
    };
    let mut frames = vec![(sequence[0], "Current State".to_string())];
    frames.extend(
        shown
            .iter()
            .enumerate()
            .map(|(i, state)| (*state, format!("Next State {}", i + 1))),
    );
    let images = (0..frames.len())
        .map(|slot| image_path(&qa_type, &run.task_name, &id, slot))
        .collect();
    Ok(DemoItem {
        record: QaRecord {
            id,
            qa_type,
            task_name: run.task_name.clone(),
            key_frame_ids,
            images,
            question,
            options: Vec::new(),
            gt_answer,
        },
        run: run_index,
        frames,
    })
}

/// All demo items: `ITEMS_PER_TYPE` forward and inverse items per L, spread over the runs, no
/// sequence used twice for one (task, direction).
pub(crate) fn build_items<R: Rng + ?Sized>(
    runs: &[TaskRun],
    rng: &mut R,
) -> Result<Vec<DemoItem>, DemoError> {
    let mut taken: HashSet<(usize, Direction, Vec<usize>)> = HashSet::new();
    let mut items = Vec::new();
    for steps in STEP_LENGTHS {
        for (d, direction) in [Direction::Forward, Direction::Inverse]
            .into_iter()
            .enumerate()
        {
            for k in 0..ITEMS_PER_TYPE {
                let first = steps + k + d;
                let mut placed = false;
                'runs: for offset in 0..runs.len() {
                    let run_index = (first + offset) % runs.len();
                    for _ in 0..64 {
                        let Some(sequence) = runs[run_index].sample_sequence(steps, rng) else {
                            continue 'runs;
                        };
                        if taken.insert((run_index, direction, sequence.clone())) {
                            items.push(build_item(runs, run_index, &sequence, direction, rng)?);
                            placed = true;
                            break 'runs;
                        }
                    }
                }
                if !placed {
                    return Err(DemoError::NotEnoughSequences {
                        qa_type: direction.type_name(steps),
                    });
                }
            }
        }
    }
    Ok(items)
}

/// ENACT quirk: ENACT writes its JSONL with Python's `json.dump(..., ensure_ascii=False)`, whose
/// separators are ", " and ": "; the demo file uses the same bytes as a released one.
struct PythonJsonFormatter;

impl serde_json::ser::Formatter for PythonJsonFormatter {
    fn begin_array_value<W: ?Sized + io::Write>(
        &mut self,
        writer: &mut W,
        first: bool,
    ) -> io::Result<()> {
        if first {
            Ok(())
        } else {
            writer.write_all(b", ")
        }
    }

    fn begin_object_key<W: ?Sized + io::Write>(
        &mut self,
        writer: &mut W,
        first: bool,
    ) -> io::Result<()> {
        if first {
            Ok(())
        } else {
            writer.write_all(b", ")
        }
    }

    fn begin_object_value<W: ?Sized + io::Write>(&mut self, writer: &mut W) -> io::Result<()> {
        writer.write_all(b": ")
    }
}

/// One JSONL line (without the newline) in Python's `json.dump` layout.
pub(crate) fn jsonl_line(record: &QaRecord) -> Result<String, DemoError> {
    let mut bytes = Vec::new();
    let mut serializer = serde_json::Serializer::with_formatter(&mut bytes, PythonJsonFormatter);
    record
        .serialize(&mut serializer)
        .map_err(|source| DemoError::Serialize {
            id: record.id.clone(),
            source,
        })?;
    String::from_utf8(bytes).map_err(|e| DemoError::Serialize {
        id: record.id.clone(),
        source: serde::ser::Error::custom(e),
    })
}

fn encode_png(image: &RgbImage, path: &Path) -> Result<Vec<u8>, DemoError> {
    let mut bytes = Vec::new();
    PngEncoder::new_with_quality(&mut bytes, CompressionType::Fast, FilterType::Paeth)
        .write_image(
            image.as_raw(),
            image.width(),
            image.height(),
            ExtendedColorType::Rgb8,
        )
        .map_err(|source| DemoError::EncodePng {
            path: path.to_path_buf(),
            source,
        })?;
    Ok(bytes)
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<(), DemoError> {
    if let Some(parent) = path.parent() {
        fs::create_dir_all(parent).map_err(|source| DemoError::Io {
            path: parent.to_path_buf(),
            source,
        })?;
    }
    fs::write(path, bytes).map_err(|source| DemoError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes the JSONL and every labelled image of `items` under `out_dir`.
pub(crate) fn write_release(
    out_dir: &Path,
    runs: &[TaskRun],
    items: &[DemoItem],
    font: &LabelFont,
) -> Result<DemoSummary, DemoError> {
    let kitchen = Kitchen::new();
    let mut frames: BTreeMap<(usize, usize), RgbImage> = BTreeMap::new();
    let mut labels: BTreeMap<String, Overlay> = BTreeMap::new();
    let mut jsonl = String::new();
    let mut image_count = 0;
    for item in items {
        for ((state, label), relative) in item.frames.iter().zip(&item.record.images) {
            let run = &runs[item.run];
            let base = frames
                .entry((item.run, *state))
                .or_insert_with(|| kitchen.render(&run.states[*state], font));
            let overlay = labels
                .entry(label.clone())
                .or_insert_with(|| font.state_label(label, FRAME_SIZE));
            let mut image = base.clone();
            overlay.apply(&mut image);
            let path: PathBuf = out_dir.join(relative);
            write_file(&path, &encode_png(&image, &path)?)?;
            image_count += 1;
        }
        jsonl.push_str(&jsonl_line(&item.record)?);
        jsonl.push('\n');
    }
    let jsonl_path = out_dir.join(JSONL_PATH);
    write_file(&jsonl_path, jsonl.as_bytes())?;
    let forward_items = items
        .iter()
        .filter(|i| i.record.qa_type.starts_with("forward"))
        .count();
    Ok(DemoSummary {
        jsonl_path,
        items: items.len(),
        forward_items,
        inverse_items: items.len() - forward_items,
        images: image_count,
        task_names: runs.iter().map(|r| r.task_name.clone()).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::prompt::{FORWARD_PROMPT_TEMPLATE, INVERSE_PROMPT_TEMPLATE, action_block};
    use crate::demo::world::activities;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Action text with every phrasing template reduced to one form.
    fn canonical(text: &str) -> String {
        text.replace(" now becomes ", " becomes ")
            .replace(" changes to be ", " becomes ")
            .replace(" transitions to be ", " becomes ")
            .replace(" stopped being ", " is no longer ")
    }

    fn runs(seed: u64) -> (Vec<TaskRun>, ChaCha8Rng) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let runs = activities()
            .iter()
            .map(|a| TaskRun::record(a, &mut rng).unwrap())
            .collect();
        (runs, rng)
    }

    #[test]
    fn ids_hash_the_joined_frame_ids() {
        // sha256("1061_8095_9327") starts with ffe68db8 (a real cook_bacon item).
        let frames: Vec<String> = ["1061", "8095", "9327"].map(String::from).to_vec();
        assert_eq!(
            item_id(
                "cook_bacon_1",
                "forward_world_modeling_ordering_3_steps",
                &frames
            ),
            "cook_bacon_1_forward_world_modeling_ordering_3_steps_ffe68db8"
        );
        assert_eq!(
            image_path("t", "task", "x", 0),
            "QA/images/t/task/x_cur_state.png"
        );
        assert_eq!(
            image_path("t", "task", "x", 4),
            "QA/images/t/task/x_next_state_4.png"
        );
    }

    #[test]
    fn forward_answer_lists_labels_in_chronological_order() {
        // Future frames 5, 7, 9 shown as [9, 5, 7] → 5 is label 2, 7 is label 3, 9 is label 1.
        assert_eq!(forward_answer(&[5, 7, 9], &[9, 5, 7]), vec![2, 3, 1]);
    }

    #[test]
    fn inverse_answer_gives_repeated_texts_the_first_unused_label() {
        let s = |v: &[&str]| v.iter().map(|t| t.to_string()).collect::<Vec<_>>();
        assert_eq!(
            inverse_answer(&s(&["a", "b", "c"]), &s(&["c", "a", "b"])),
            vec![2, 3, 1]
        );
        assert_eq!(
            inverse_answer(&s(&["a", "b", "a"]), &s(&["a", "a", "b"])),
            vec![1, 3, 2]
        );
    }

    #[test]
    fn python_layout_json_lines() {
        let record = QaRecord {
            id: "x".into(),
            qa_type: "t".into(),
            task_name: "k".into(),
            key_frame_ids: vec!["1".into(), "2".into()],
            images: vec![],
            question: "a\nb".into(),
            options: vec![],
            gt_answer: vec![2, 1],
        };
        assert_eq!(
            jsonl_line(&record).unwrap(),
            r#"{"id": "x", "type": "t", "task_name": "k", "key_frame_ids": ["1", "2"], "images": [], "question": "a\nb", "options": [], "gt_answer": [2, 1]}"#
        );
    }

    #[test]
    fn sampled_sequences_are_increasing_and_every_hop_is_usable() {
        let (runs, mut rng) = runs(7);
        for run in &runs {
            for length in STEP_LENGTHS {
                let sequence = run.sample_sequence(length, &mut rng).unwrap();
                assert_eq!(sequence.len(), length);
                for pair in sequence.windows(2) {
                    assert!(pair[0] < pair[1]);
                    let n = run.diff(pair[0], pair[1]).sentence_count();
                    assert!((1..=MAX_SENTENCES).contains(&n));
                }
            }
        }
    }

    #[test]
    fn items_follow_enact_rules_and_cover_every_length_both_ways() {
        let (runs, mut rng) = runs(42);
        let items = build_items(&runs, &mut rng).unwrap();
        assert_eq!(items.len(), STEP_LENGTHS.count() * 2 * ITEMS_PER_TYPE);
        for item in &items {
            let r = &item.record;
            let steps = r.key_frame_ids.len();
            let run = &runs[item.run];
            assert!(r.qa_type.ends_with(&format!("_ordering_{steps}_steps")));
            assert_eq!(r.id, item_id(&r.task_name, &r.qa_type, &r.key_frame_ids));
            assert_eq!(r.images.len(), steps);
            let mut sorted = r.gt_answer.clone();
            sorted.sort();
            assert_eq!(sorted, (1..steps as u32).collect::<Vec<_>>());
            // Rebuild the sequence from the frame ids and check the answer against the frames.
            let sequence: Vec<usize> = r
                .key_frame_ids
                .iter()
                .map(|f| {
                    run.frame_ids
                        .iter()
                        .position(|g| g.to_string() == *f)
                        .unwrap()
                })
                .collect();
            let lines: Vec<&str> = r
                .question
                .lines()
                .filter(|l| l.starts_with("[Action "))
                .collect();
            assert_eq!(lines.len(), steps - 1);
            let texts: Vec<String> = lines
                .iter()
                .enumerate()
                .map(|(i, l)| {
                    l.strip_prefix(&format!("[Action {}] ", i + 1))
                        .unwrap()
                        .to_string()
                })
                .collect();
            if r.qa_type.starts_with("forward") {
                assert_eq!(
                    r.question,
                    FORWARD_PROMPT_TEMPLATE.replace("{STATE_CHANGES}", &action_block(&texts))
                );
                for (j, text) in texts.iter().enumerate() {
                    let diff = run.diff(sequence[j], sequence[j + 1]);
                    let expected = action_text(&diff, &mut ChaCha8Rng::seed_from_u64(0)).unwrap();
                    assert_eq!(canonical(text), canonical(&expected));
                }
                for (j, label) in r.gt_answer.iter().enumerate() {
                    // The image labelled `label` shows the (j+1)-th future key frame.
                    assert_eq!(item.frames[*label as usize].0, sequence[j + 1]);
                    assert_eq!(
                        item.frames[*label as usize].1,
                        format!("Next State {label}")
                    );
                }
            } else {
                assert_eq!(
                    r.question,
                    INVERSE_PROMPT_TEMPLATE.replace("{SHUFFLED_ACTIONS}", &action_block(&texts))
                );
                for (j, frame) in item.frames.iter().enumerate() {
                    assert_eq!(frame.0, sequence[j]);
                }
                for (j, label) in r.gt_answer.iter().enumerate() {
                    // The action labelled `label` describes transition j (up to phrasing).
                    let diff = run.diff(sequence[j], sequence[j + 1]);
                    let expected = action_text(&diff, &mut ChaCha8Rng::seed_from_u64(0)).unwrap();
                    assert_eq!(canonical(&texts[*label as usize - 1]), canonical(&expected));
                }
            }
        }
        for steps in STEP_LENGTHS {
            for direction in [Direction::Forward, Direction::Inverse] {
                let name = direction.type_name(steps);
                assert!(items.iter().any(|i| i.record.qa_type == name), "{name}");
            }
        }
    }
}
