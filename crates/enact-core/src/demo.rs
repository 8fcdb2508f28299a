//! The built-in demo dataset, so that `enact-hub serve --demo` works without downloading
//! anything: the synthetic household world ([`crate::world`]) plays four activities, and the
//! real data pipeline ([`crate::pipeline::generate`]) segments the replays and writes forward
//! and inverse items for every L in 3..=10 in ENACT's release layout, with the scene graphs
//! the importer reads for semantic scoring.
//!
//! [`write_demo_release`] writes the dataset; [`chance_baseline`] and [`grasp_heuristic`] are
//! the leaderboard rows the demo starts with.

use std::path::{Path, PathBuf};

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

use crate::dataset::Direction;
use crate::pipeline::{GenerateOptions, PipelineError, TypeNaming, generate};
use crate::world::{Activity, CameraRig, FrameImages, SimulateOptions, WorldError, simulate};

/// What [`write_demo_release`] wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DemoSummary {
    /// `out_dir/QA/enact_ordering.jsonl`.
    pub jsonl_path: PathBuf,
    /// `out_dir/replayed_activities`: the key frames' scene graphs, for `--scene-graphs`.
    pub replayed_dir: PathBuf,
    /// JSONL rows written.
    pub items: usize,
    pub forward_items: usize,
    pub inverse_items: usize,
    /// Labelled PNG files the items name.
    pub images: usize,
    /// Task names (`{activity}_{16 digits}`) the items come from.
    pub task_names: Vec<String>,
}

/// Why the demo release could not be written.
#[derive(Debug, thiserror::Error)]
pub enum DemoError {
    #[error("demo world: {0}")]
    World(#[from] WorldError),
    #[error("demo pipeline: {0}")]
    Pipeline(#[from] PipelineError),
}

/// The seed `serve --demo` uses, so every demo start shows the same dataset.
pub const DEFAULT_SEED: u64 = 42;

/// The demo's activities: between them every predicate class the world has but `Contains`
/// (make_tea, left out to keep the demo start short).
const DEMO_ACTIVITIES: [Activity; 4] = [
    Activity::PutDishesAway,
    Activity::CookBacon,
    Activity::SliceFruit,
    Activity::TidyLivingRoom,
];

/// Items per (task, step length, direction): with four activities, four items of each kind.
const ITEMS_PER_TASK: usize = 1;

/// Writes the demo release under `out_dir` (created if missing; files already there are
/// overwritten): the simulated replays in `out_dir/simulated/`, then the pipeline's release
/// (`QA/`, `segmented_activities/`, `replayed_activities/`, `generation_summary.json`). The
/// same seed always gives byte-identical files.
pub fn write_demo_release(out_dir: &Path, seed: u64) -> Result<DemoSummary, DemoError> {
    let simulated = out_dir.join("simulated");
    let mut task_names = Vec::new();
    for activity in DEMO_ACTIVITIES {
        let simulation = simulate(&SimulateOptions {
            seed,
            activity,
            length: None,
            camera: CameraRig::default(),
        })?;
        simulation.write_replay(&simulated, FrameImages::KeyFrames)?;
        task_names.push(simulation.task_name);
    }
    task_names.sort();
    let options = GenerateOptions {
        seed,
        num_to_sample: ITEMS_PER_TASK,
        type_naming: TypeNaming::Ordering,
        ..GenerateOptions::default()
    };
    let summary = generate(&simulated, out_dir, &options, &|_| {})?;
    Ok(DemoSummary {
        jsonl_path: summary.jsonl_path,
        replayed_dir: out_dir.join("replayed_activities"),
        items: summary.items,
        forward_items: summary.forward_items,
        inverse_items: summary.inverse_items,
        images: summary.images,
        task_names,
    })
}

/// The model name of the demo's chance baseline on the leaderboard.
pub const CHANCE_BASELINE_MODEL: &str = "chance (uniformly random order)";

/// The demo leaderboard's baseline, as a compact submission (one `{"id", "answer"}` line per
/// item): every item answered with a uniformly random ordering of its `labels` (1-based, as
/// ENACT's answers are), seeded. Scored like any submission, it shows what chance earns at
/// each step length, which is the floor every model on the board should clear.
pub fn chance_baseline<'a>(items: impl IntoIterator<Item = (&'a str, usize)>, seed: u64) -> String {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut body = String::new();
    for (id, labels) in items {
        let mut answer: Vec<usize> = (1..=labels).collect();
        answer.shuffle(&mut rng);
        body.push_str(&serde_json::json!({ "id": id, "answer": answer }).to_string());
        body.push('\n');
    }
    body
}

/// The model name of the demo's heuristic row on the leaderboard.
pub const GRASP_HEURISTIC_MODEL: &str = "heuristic: grasp before release (not a model)";

/// The heuristic's answer to one item: for an inverse item, its shuffled actions ordered so
/// that an action in which the robot comes to grasp an object precedes every action in which
/// it lets go of that object, the listed order otherwise; for a forward item (whose options
/// are images, which the heuristic cannot see), the listed order. 1-based labels, `labels` of
/// them.
pub fn grasp_heuristic_order(direction: Direction, question: &str, labels: usize) -> Vec<usize> {
    if direction == Direction::Forward {
        return (1..=labels).collect();
    }
    // (grasped, released) object names per action, by label.
    let mut grasps: Vec<(Vec<String>, Vec<String>)> = vec![Default::default(); labels];
    for line in question.lines() {
        let Some(rest) = line.trim().strip_prefix("[Action ") else {
            continue;
        };
        let Some((number, text)) = rest.split_once(']') else {
            continue;
        };
        let Some(index) = number
            .trim()
            .parse::<usize>()
            .ok()
            .filter(|n| (1..=labels).contains(n))
        else {
            continue;
        };
        for sentence in text.split('.') {
            let Some((_, object)) = sentence.split_once("grasp the ") else {
                continue;
            };
            let object = object.trim().to_owned();
            if sentence.contains("no longer") || sentence.contains("stopped being") {
                grasps[index - 1].1.push(object);
            } else {
                grasps[index - 1].0.push(object);
            }
        }
    }
    // Kahn's order, the lowest label first among those free; a cycle (an object grasped,
    // released and grasped again) is broken by taking the lowest label left.
    let before = |a: usize, b: usize| grasps[a].0.iter().any(|o| grasps[b].1.contains(o));
    let mut left: Vec<usize> = (0..labels).collect();
    let mut order = Vec::with_capacity(labels);
    while !left.is_empty() {
        let free = left
            .iter()
            .position(|&b| !left.iter().any(|&a| a != b && before(a, b)))
            .unwrap_or(0);
        order.push(left.remove(free) + 1);
    }
    order
}

/// The heuristic's replies as a submission (one `{"id", "answer"}` line per item, the answer a
/// model-like reply text): what ordering by a single rule of ENACT's sentences earns, beside
/// chance. `items`: id, direction, question and number of labels.
pub fn grasp_heuristic<'a>(
    items: impl IntoIterator<Item = (&'a str, Direction, &'a str, usize)>,
) -> String {
    let mut body = String::new();
    for (id, direction, question, labels) in items {
        let order = grasp_heuristic_order(direction, question, labels);
        let why = match direction {
            Direction::Forward => "the images in the order listed (the heuristic cannot see them)",
            Direction::Inverse => {
                "each object grasped before it is released, otherwise the order listed"
            }
        };
        let reply = format!("Heuristic, not a model: {why}. Answer: {order:?}");
        body.push_str(&serde_json::json!({ "id": id, "answer": reply }).to_string());
        body.push('\n');
    }
    body
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_heuristic_puts_a_grasp_before_the_release_of_the_same_object() {
        let question = "## Shuffled Actions\n\
            [Action 1] The robot r1 is no longer using the right gripper to grasp the plate.\n\
            [Action 2] The fridge transitions to be open.\n\
            [Action 3] The robot r1 now becomes using the right gripper to grasp the plate. \
            The plate is no longer on top of the table.\n\
            [Action 4] The robot r1 stopped being using the right gripper to grasp the cup.\n\
            [Action 5] The robot r1 changes to be using the right gripper to grasp the cup.\n";
        assert_eq!(
            grasp_heuristic_order(Direction::Inverse, question, 5),
            vec![2, 3, 1, 5, 4]
        );
        // Forward items list images: the listed order.
        assert_eq!(
            grasp_heuristic_order(Direction::Forward, question, 5),
            vec![1, 2, 3, 4, 5]
        );
        // Grasped, released and grasped again: the cycle is broken, every label appears once.
        let cycle = "[Action 1] The robot r1 now becomes using the right gripper to grasp the cup.\n\
            [Action 2] The robot r1 is no longer using the right gripper to grasp the cup.\n\
            [Action 3] The robot r1 changes to be using the right gripper to grasp the cup.\n";
        let mut order = grasp_heuristic_order(Direction::Inverse, cycle, 3);
        order.sort_unstable();
        assert_eq!(order, vec![1, 2, 3]);
    }

    #[test]
    fn the_heuristic_replies_as_a_model_would_and_the_strict_reader_reads_them() {
        let question = "[Action 1] The robot r1 is no longer using the right gripper to grasp the plate.\n\
            [Action 2] The robot r1 now becomes using the right gripper to grasp the plate.\n";
        let body = grasp_heuristic([("i", Direction::Inverse, question, 2)]);
        let line: serde_json::Value = serde_json::from_str(body.trim()).unwrap();
        assert_eq!(line["id"], "i");
        let reply = line["answer"].as_str().unwrap();
        assert!(reply.starts_with("Heuristic, not a model"), "{reply}");
        let read = crate::verifier::parse_answer_text_strict(reply, 2).unwrap();
        assert_eq!(read.labels(), &[2, 1]);
    }

    #[test]
    fn the_chance_baseline_answers_every_item_with_a_seeded_permutation() {
        let items = [("a", 2), ("b", 9), ("c", 9)];
        let body = chance_baseline(items, 7);
        let lines: Vec<serde_json::Value> = body
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        assert_eq!(lines.len(), 3);
        for (line, (id, labels)) in lines.iter().zip(items) {
            assert_eq!(line["id"], id);
            let mut answer: Vec<u64> = line["answer"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_u64().unwrap())
                .collect();
            answer.sort_unstable();
            assert_eq!(answer, (1..=labels as u64).collect::<Vec<_>>());
        }
        assert_ne!(lines[1]["answer"], lines[2]["answer"], "shuffled per item");
        assert_eq!(body, chance_baseline(items, 7));
        assert_ne!(body, chance_baseline(items, 8));
    }
}
