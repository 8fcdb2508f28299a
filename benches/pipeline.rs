//! Benchmarks of the data pipeline: counting and sampling a million length-10 paths from a
//! long trajectory of the synthetic household world, and (once, printed) segmentation and generation on the parity
//! replays next to ENACT's timings.

use std::path::PathBuf;
use std::time::Instant;

use criterion::{Criterion, criterion_group};
use enact_hub::core::pipeline::{
    GenerateOptions, PathTable, TransitionGraph, sample_paths, segment_task, task_names,
};
use enact_hub::core::world::{Activity, CameraRig, FrameImages, SimulateOptions, simulate};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// One long trajectory of the synthetic household world: the cook_bacon script continued by
/// seeded random kitchen chores, 299 actions over about 92,000 frames, written as a replay,
/// segmented (300 key frames) and turned into its transition graph like any other task
/// (seed 7: 3,539 valid transitions, about 4·10^11 length-10 paths).
fn long_trajectory() -> TransitionGraph {
    let dir = tempfile::tempdir().expect("temp dir");
    let simulation = simulate(&SimulateOptions {
        seed: 7,
        activity: Activity::CookBacon,
        length: Some(299),
        camera: CameraRig {
            image_size: 64,
            ..CameraRig::default()
        },
    })
    .expect("simulate");
    simulation
        .write_replay(dir.path(), FrameImages::KeyFrames)
        .expect("write the replay");
    let task =
        segment_task(dir.path(), &simulation.task_name, &Default::default()).expect("segmentation");
    assert_eq!(
        task.segmentation.key_frames.len(),
        simulation.key_frames.len()
    );
    TransitionGraph::build(&task.key_frame_graphs, &task.segmentation.key_frames)
        .expect("transition graph")
}

fn sampling(c: &mut Criterion) {
    let graph = long_trajectory();
    let table = PathTable::count(&graph, 10).expect("no overflow");
    println!(
        "world trajectory: {} key frames, {} valid transitions, {} length-10 paths",
        graph.frames().len(),
        graph.edge_count(),
        table.total()
    );
    let mut group = c.benchmark_group("kfts");
    group.sample_size(10);
    group.bench_function("count_300_frames_L10", |b| {
        b.iter(|| PathTable::count(&graph, 10).expect("no overflow").total())
    });
    group.bench_function("count_and_sample_1M_paths_L10", |b| {
        b.iter(|| {
            let table = PathTable::count(&graph, 10).expect("no overflow");
            let mut rng = ChaCha8Rng::seed_from_u64(42);
            let paths = sample_paths(&graph, &table, 1_000_000, &mut rng);
            assert_eq!(paths.len(), 1_000_000);
            paths.len()
        })
    });
    group.finish();
}

#[path = "../tests/support/fixtures.rs"]
mod fixtures;

fn fixtures_dir() -> Option<PathBuf> {
    fixtures::shared_fixtures()
}

/// One timed run of segmentation alone and of the whole generation (`--num-to-sample 2`, as
/// ENACT's reference run), printed beside ENACT's medians (177.85 s segment, 176.24 s qa).
fn parity_timings() {
    let Some(replayed) = fixtures_dir()
        .map(|d| d.join("enact-parity/replayed_activities"))
        .filter(|d| d.is_dir())
    else {
        println!("fixtures not present, skipping the parity timings");
        return;
    };
    let tasks = task_names(&replayed).expect("task folders");
    let started = Instant::now();
    tasks.par_iter().for_each(|task| {
        segment_task(&replayed, task, &Default::default()).expect("segmentation");
    });
    let segment = started.elapsed();
    let out = tempfile::tempdir().expect("temp dir");
    let options = GenerateOptions {
        num_to_sample: 2,
        ..GenerateOptions::default()
    };
    let started = Instant::now();
    let summary = enact_hub::core::pipeline::generate(&replayed, out.path(), &options, &|_| {})
        .expect("generate");
    let generate = started.elapsed();
    println!(
        "parity replays ({} tasks): segmentation {:.2?}; segmentation + KFTS + {} items + {} images {:.2?} (ENACT: segment 177.85 s + qa 176.24 s)",
        tasks.len(),
        segment,
        summary.items,
        summary.images,
        generate
    );
}

criterion_group!(benches, sampling);

fn main() {
    benches();
    // `cargo test` runs this target too (each benchmark once, as a check that it works); the
    // parity timings are a minute of unoptimised segmentation there and time nothing: they run
    // under `cargo bench` only, which passes `--bench`.
    if std::env::args().any(|arg| arg == "--bench") {
        parity_timings();
    }
    Criterion::default().configure_from_args().final_summary();
}
