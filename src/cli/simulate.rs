//! `enact-hub simulate`: its arguments and terminal output (the only part of the world that
//! talks to a terminal).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Args;

use crate::app;
use crate::core::world::{
    Activity, CameraRig, FrameImages, RecordMode, SimulateOptions, parse_colour,
};

#[derive(Args)]
pub struct SimulateArgs {
    /// Folder to write the replays into ({task}/scene_graph_0.json, {task}/external_sensor1/).
    #[arg(long, value_name = "REPLAYED_DIR")]
    pub out: PathBuf,
    /// Seed of the run: hands, timing, glitches and any actions beyond the script.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// put_dishes_away, make_tea, cook_bacon, slice_fruit, tidy_living_room, or all.
    #[arg(long, default_value = "all")]
    pub activity: String,
    /// Number of actions (default: the activity's script; longer runs continue with random
    /// possible actions in the same room).
    #[arg(long)]
    pub length: Option<usize>,
    /// Camera field of view in degrees.
    #[arg(long, default_value_t = CameraRig::default().fov_deg)]
    pub fov: f32,
    /// Camera height above the floor in metres.
    #[arg(long, default_value_t = CameraRig::default().height_m)]
    pub camera_height: f32,
    /// Robot colour: grey, white, black, red, green, blue, yellow, orange, purple, skin, or
    /// #rrggbb.
    #[arg(long, default_value = "grey")]
    pub robot_colour: String,
    /// Frame width and height in pixels.
    #[arg(long, default_value_t = CameraRig::default().image_size)]
    pub image_size: u32,
    /// Write every frame's image, not only the key frames' (the pipeline opens key frames
    /// only).
    #[arg(long)]
    pub all_frames: bool,
    /// How scene graphs are stored: `mixed` (a full record every 200 frames, diffs between)
    /// or `full` (every frame's record full, as ENACT's published replays; large).
    #[arg(long, default_value = "mixed", value_parser = ["mixed", "full"])]
    pub record_mode: String,
}

pub fn run(args: SimulateArgs) -> anyhow::Result<ExitCode> {
    let activities: Vec<Activity> = if args.activity == "all" {
        Activity::ALL.to_vec()
    } else {
        let names: Vec<&str> = Activity::ALL.iter().map(|a| a.name()).collect();
        let activity = Activity::from_name(&args.activity).with_context(|| {
            format!(
                "unknown activity {:?}; choose one of {} or all",
                args.activity,
                names.join(", ")
            )
        })?;
        vec![activity]
    };
    let robot_colour = parse_colour(&args.robot_colour).map_err(anyhow::Error::msg)?;
    let camera = CameraRig {
        fov_deg: args.fov,
        height_m: args.camera_height,
        robot_colour,
        image_size: args.image_size,
    };
    let images = if args.all_frames {
        FrameImages::All
    } else {
        FrameImages::KeyFrames
    };
    let mode = RecordMode::parse(&args.record_mode).context("--record-mode: mixed or full")?;
    let options = SimulateOptions {
        seed: args.seed,
        activity: activities[0],
        length: args.length,
        camera,
    };
    app::pipeline::simulate(
        &activities,
        &options,
        &args.out,
        images,
        mode,
        |simulation, written| {
            println!(
                "{}: {} actions over {} frames, {} key frames, {} glitches, {} images in {}",
                simulation.task_name,
                simulation.actions.len(),
                simulation.num_frames,
                simulation.key_frames.len(),
                simulation.flickers.len(),
                written.images,
                written.task_dir.display()
            );
        },
    )?;
    Ok(ExitCode::SUCCESS)
}
