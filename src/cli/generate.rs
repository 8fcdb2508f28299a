//! `generate`: ENACT's data pipeline on replays (key-frame segmentation, then QA items), or a
//! variant of a release with the same items and another replay's images.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Args;

use crate::app;
use crate::core::pipeline::actions::{ActionEncoding, DeltaPerturbation};
use crate::core::pipeline::{
    GenerateOptions, GenerateProgress, KeyFrameTrigger, SegmentationParams, TypeNaming,
};

#[derive(Args)]
pub(super) struct GenerateArgs {
    /// Folder of replays: {task}/scene_graph_0.json and {task}/external_sensor1/{frame:05d}.png.
    replayed: PathBuf,
    /// Where to write the release (QA/, segmented_activities/, replayed_activities/,
    /// generation_summary.json).
    #[arg(long, value_name = "DATA_DIR")]
    out: PathBuf,
    /// Seed of path sampling, shuffles and sentence templates (with --items-from, only of
    /// --perturb-deltas's perturbation) [default: 42].
    #[arg(long)]
    seed: Option<u64>,
    /// Paths sampled per task, step length and direction.
    #[arg(long, default_value_t = 5)]
    num_to_sample: usize,
    /// Step lengths, as a range `3..10` or a list `3,5,7`.
    #[arg(long, default_value = "3..10")]
    steps: String,
    /// Segmentation constants: `enact-code` (ENACT's code: cosine 0.98, stability 10) or
    /// `paper` (the paper's text: cosine 0.97, stability 40).
    #[arg(long, default_value = "enact-code")]
    preset: String,
    /// Override the preset's cosine-similarity threshold.
    #[arg(long)]
    cosine_threshold: Option<f64>,
    /// Override the preset's minimum gap in frames between key frames.
    #[arg(long)]
    min_gap: Option<u64>,
    /// Override the preset's stability interval in frames.
    #[arg(long)]
    stability_frames: Option<u64>,
    /// Write type names as the released dataset does (`*_world_modeling_ordering_{L}_steps`)
    /// instead of ENACT's code (`*_world_modeling_{L}_steps`).
    #[arg(long)]
    ordering_type_names: bool,
    /// What triggers a key frame: `state` (ENACT's state changes) or `contact` (contact
    /// changes too: `Touching` and the robot's `LeftContact`/`RightContact` edges, which are
    /// then described in the actions and signatures).
    #[arg(long, default_value = "state", value_name = "state|contact")]
    key_frames: String,
    /// A variant of this release: its items unchanged (ids, questions, answers, key frames),
    /// each image drawn from the replay's frame instead. No segmentation or sampling is done.
    #[arg(
        long,
        value_name = "BASELINE_DATA_DIR",
        conflicts_with_all = [
            "num_to_sample", "steps", "preset", "cosine_threshold", "min_gap",
            "stability_frames", "ordering_type_names", "key_frames",
        ]
    )]
    items_from: Option<PathBuf>,
    /// With --items-from: the action texts written as `natural` (the baseline's sentences),
    /// `symbolic` (`add(Inside, apple_1, fridge_1)`, one predicate per change) or `emoji`.
    #[arg(
        long,
        requires = "items_from",
        default_value = "natural",
        value_name = "natural|symbolic|emoji"
    )]
    actions: String,
    /// With --items-from: perturb each transition's predicates with this probability (dropped
    /// or swapped for a wrong one, drawn from --seed) and write its action from the perturbed
    /// delta; the answers stay the baseline's.
    #[arg(long, requires = "items_from", value_name = "P")]
    perturb_deltas: Option<f64>,
}

/// `3..10`, `3..=10` or `3,5,7` into step lengths, each checked to lie in 3..10.
fn parse_steps(text: &str) -> anyhow::Result<Vec<usize>> {
    let number = |s: &str| -> anyhow::Result<usize> {
        let n: usize = s
            .trim()
            .parse()
            .with_context(|| format!("--steps: {s:?} is not a whole number"))?;
        anyhow::ensure!(
            (3..=10).contains(&n),
            "--steps: step length {n} is outside 3..10"
        );
        Ok(n)
    };
    let steps: Vec<usize> = match text.split_once("..") {
        Some((a, b)) => {
            let (a, b) = (number(a)?, number(b.trim_start_matches('='))?);
            anyhow::ensure!(a <= b, "--steps: empty range {text:?}");
            (a..=b).collect()
        }
        None => text.split(',').map(number).collect::<anyhow::Result<_>>()?,
    };
    Ok(steps)
}

/// `generate --items-from`: the baseline's items with the replay's images.
async fn generate_variant(args: &GenerateArgs, baseline: PathBuf) -> anyhow::Result<ExitCode> {
    let encoding = ActionEncoding::parse(&args.actions).with_context(|| {
        format!(
            "--actions: unknown encoding {:?} (use natural, symbolic or emoji)",
            args.actions
        )
    })?;
    let perturbation = args
        .perturb_deltas
        .map(|p| DeltaPerturbation::new(p, args.seed.unwrap_or(DEFAULT_SEED)))
        .transpose()
        .map_err(|e| anyhow::anyhow!("--perturb-deltas: {e}"))?;
    let baseline_graphs = app::pipeline::variant_scene_graphs(&baseline);
    let started = std::time::Instant::now();
    let done = app::pipeline::variant(
        args.replayed.clone(),
        baseline,
        args.out.clone(),
        encoding,
        perturbation,
    )
    .await?;
    eprintln!(
        "wrote {} items of {} tasks with {} images from {} into {} in {:.1} s \
         ({} action texts rewritten, {} predicates perturbed)",
        done.items,
        done.tasks,
        done.images,
        args.replayed.display(),
        args.out.display(),
        started.elapsed().as_secs_f64(),
        done.actions_rewritten,
        done.predicates_perturbed
    );
    eprintln!(
        "import it with: enact-hub import {} --dataset NAME --scene-graphs {}",
        args.out.display(),
        baseline_graphs.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// The seed when `--seed` is not given.
const DEFAULT_SEED: u64 = 42;

pub(super) async fn generate(args: GenerateArgs) -> anyhow::Result<ExitCode> {
    if let Some(baseline) = args.items_from.clone() {
        // A variant keeps the baseline's sampled items: a seed means something only for the
        // perturbation.
        if args.seed.is_some() && args.perturb_deltas.is_none() {
            anyhow::bail!(
                "--seed cannot be used with --items-from without --perturb-deltas: a variant \
                 keeps the baseline's sampled items"
            );
        }
        return generate_variant(&args, baseline).await;
    }
    let mut segmentation = SegmentationParams::preset(&args.preset).with_context(|| {
        format!(
            "--preset: unknown preset {:?} (use enact-code or paper)",
            args.preset
        )
    })?;
    if let Some(v) = args.cosine_threshold {
        segmentation.cosine_threshold = v;
    }
    if let Some(v) = args.min_gap {
        segmentation.min_gap = v;
    }
    if let Some(v) = args.stability_frames {
        segmentation.stability_frames = v;
    }
    segmentation.key_frames = KeyFrameTrigger::parse(&args.key_frames).with_context(|| {
        format!(
            "--key-frames: unknown trigger {:?} (use state or contact)",
            args.key_frames
        )
    })?;
    let options = GenerateOptions {
        seed: args.seed.unwrap_or(DEFAULT_SEED),
        num_to_sample: args.num_to_sample,
        step_lengths: parse_steps(&args.steps)?,
        segmentation,
        type_naming: if args.ordering_type_names {
            TypeNaming::Ordering
        } else {
            TypeNaming::Code
        },
    };
    let bar = if std::io::stderr().is_terminal() {
        indicatif::ProgressBar::new(0)
    } else {
        indicatif::ProgressBar::hidden()
    };
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{msg:>24} [{bar:40}] {pos}/{len} tasks")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    let started = std::time::Instant::now();
    let show = move |event| match event {
        GenerateProgress::Started { tasks } => bar.set_length(tasks as u64 * 3),
        GenerateProgress::Segmented { task, .. }
        | GenerateProgress::TransitionsBuilt { task, .. }
        | GenerateProgress::ImagesWritten { task, .. } => {
            bar.set_message(task);
            bar.inc(1);
        }
        GenerateProgress::Finished { .. } => bar.finish_and_clear(),
    };
    let summary =
        app::pipeline::generate(args.replayed.clone(), args.out.clone(), options, show).await?;
    eprintln!(
        "generated {} items ({} forward, {} inverse) and {} images from {} tasks into {} in {:.1} s",
        summary.items,
        summary.forward_items,
        summary.inverse_items,
        summary.images,
        summary.tasks.len(),
        args.out.display(),
        started.elapsed().as_secs_f64()
    );
    // Import finds the release's own replayed_activities/ by itself.
    eprintln!("import it with: enact-hub import {}", args.out.display());
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::parse_steps;

    #[test]
    fn step_lengths_are_read_as_ranges_or_lists_within_3_to_10() {
        assert_eq!(parse_steps("3..10").unwrap(), (3..=10).collect::<Vec<_>>());
        assert_eq!(parse_steps("4..=6").unwrap(), [4, 5, 6]);
        assert_eq!(parse_steps("3,5, 7").unwrap(), [3, 5, 7]);
        assert!(
            parse_steps("2..5")
                .unwrap_err()
                .to_string()
                .contains("outside 3..10")
        );
        assert!(
            parse_steps("6..4")
                .unwrap_err()
                .to_string()
                .contains("empty range")
        );
        assert!(
            parse_steps("x")
                .unwrap_err()
                .to_string()
                .contains("not a whole number")
        );
    }
}
