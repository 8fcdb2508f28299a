//! The built-in demo dataset, so that `enact-hub serve --demo` works without downloading
//! anything: the synthetic household world ([`crate::world`]) plays four activities, and the
//! real data pipeline ([`crate::pipeline::generate`]) segments the replays and writes forward
//! and inverse items for every L in 3..=10 in ENACT's release layout, with the scene graphs
//! the importer reads for semantic scoring.
//!
//! [`write_demo_release`] writes the dataset; [`chance_baseline`] is the leaderboard row the
//! demo starts with.

use std::path::{Path, PathBuf};

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

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

#[cfg(test)]
mod tests {
    use super::*;

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
