//! Making new items: ENACT's data pipeline over replays (`generate`), a variant release that
//! keeps a baseline's items with another replay's images or other action texts, and replays simulated in the built-in
//! household world. The work is [`enact_core`]'s and runs on a blocking thread; these use
//! cases are what the command line calls.

use std::path::{Path, PathBuf};

use crate::core::pipeline::PipelineError;
use crate::core::pipeline::actions::{ActionEncoding, ActionRewrite, DeltaPerturbation};
use crate::core::pipeline::variant::{self, VariantRelease};
use crate::core::pipeline::{self, GenerateOptions, GenerateProgress, GenerationSummary};
use crate::core::world::{
    self, Activity, FrameImages, RecordMode, SimulateOptions, Simulation, WorldError, WrittenReplay,
};

/// The result of a blocking task; a panic in it is resumed here, as a direct call would.
async fn on_blocking_thread<T: Send + 'static>(work: impl FnOnce() -> T + Send + 'static) -> T {
    match tokio::task::spawn_blocking(work).await {
        Ok(done) => done,
        Err(e) => std::panic::resume_unwind(e.into_panic()),
    }
}

/// Segments the replays in `replayed` into key frames and writes forward and inverse items in
/// ENACT's release layout under `out`. `progress` hears of each task's steps.
pub async fn generate(
    replayed: PathBuf,
    out: PathBuf,
    options: GenerateOptions,
    progress: impl Fn(GenerateProgress) + Send + Sync + 'static,
) -> Result<GenerationSummary, PipelineError> {
    on_blocking_thread(move || pipeline::generate(&replayed, &out, &options, &progress)).await
}

/// Writes under `out` the items of the release `baseline` (ids, answers, key frames), each image
/// drawn from the replay in `replayed`, the action texts in `encoding` and, with a
/// `perturbation`, written from perturbed deltas (the baseline's own texts when neither
/// changes them).
pub async fn variant(
    replayed: PathBuf,
    baseline: PathBuf,
    out: PathBuf,
    encoding: ActionEncoding,
    perturbation: Option<DeltaPerturbation>,
) -> Result<VariantRelease, PipelineError> {
    on_blocking_thread(move || {
        let rewrite = ActionRewrite {
            encoding,
            perturbation,
            vocabulary: crate::core::pipeline::release::release_vocabulary(&baseline),
        };
        variant::items_from(&replayed, &baseline, &out, &rewrite)
    })
    .await
}

/// The scene graphs a variant made by [`variant`] is to be imported with: the baseline's, so
/// that answers are judged as on the baseline and only the images differ (a replay's own graphs
/// record what its camera sees).
pub fn variant_scene_graphs(baseline: &Path) -> PathBuf {
    baseline.join("replayed_activities")
}

/// Simulates each of `activities` with `options` (its `activity` replaced by each in turn) and
/// writes their replays under `out`; `written` hears of each replay as it is written.
pub fn simulate(
    activities: &[Activity],
    options: &SimulateOptions,
    out: &Path,
    images: FrameImages,
    mode: RecordMode,
    mut written: impl FnMut(&Simulation, &WrittenReplay),
) -> Result<(), WorldError> {
    for &activity in activities {
        let options = SimulateOptions {
            activity,
            ..options.clone()
        };
        let simulation = world::simulate(&options)?;
        let replay = simulation.write_replay_with(out, images, mode)?;
        written(&simulation, &replay);
    }
    Ok(())
}
