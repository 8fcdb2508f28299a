//! The synthetic household world, checked through the project's own scene-graph and pipeline
//! code on the replays it writes: predicate classes, visibility, determinism, rendering
//! variants, and key frames recovered by ENACT's segmentation.

use std::collections::BTreeSet;
use std::path::Path;

use enact_hub::core::pipeline::{SegmentationParams, segment_key_frames, segment_task};
use enact_hub::core::scene_graph::visibility::node_is_visible;
use enact_hub::core::scene_graph::{
    EVALUATION_SENSORS, FrameSelection, SceneGraphTimeline, transition_signatures,
};
use enact_hub::core::world::{
    Activity, CameraRig, FrameImages, SimulateOptions, Simulation, parse_colour, simulate,
};

fn options(activity: Activity, seed: u64) -> SimulateOptions {
    SimulateOptions {
        seed,
        activity,
        length: None,
        camera: CameraRig {
            image_size: 160,
            ..CameraRig::default()
        },
    }
}

fn write(dir: &Path, options: &SimulateOptions) -> Simulation {
    let simulation = simulate(options).unwrap();
    simulation
        .write_replay(dir, FrameImages::KeyFrames)
        .unwrap();
    simulation
}

fn timeline(dir: &Path, simulation: &Simulation) -> SceneGraphTimeline {
    SceneGraphTimeline::load(
        &dir.join(&simulation.task_name).join("scene_graph_0.json"),
        FrameSelection::All,
    )
    .unwrap()
}

fn frames(simulation: &Simulation) -> Vec<String> {
    simulation
        .key_frames
        .iter()
        .map(|f| f.to_string())
        .collect()
}

/// The predicate named by a signature: the last `_` field of node/edge signatures, and
/// "Transition" for object transitions.
fn predicate(signature: &str) -> String {
    if signature.starts_with("node_transition_from_") {
        return "Transition".into();
    }
    signature.rsplit('_').next().unwrap_or_default().to_string()
}

#[test]
fn the_activities_emit_every_predicate_class_in_view() {
    let dir = tempfile::tempdir().unwrap();
    let mut seen = BTreeSet::new();
    for activity in Activity::ALL {
        for seed in [1, 2] {
            let simulation = write(dir.path(), &options(activity, seed));
            let timeline = timeline(dir.path(), &simulation);
            let sets = transition_signatures(&timeline, &frames(&simulation)).unwrap();
            assert_eq!(sets.len(), simulation.actions.len());
            for (step, set) in sets.iter().enumerate() {
                // Every action of a script changes something the camera sees.
                assert!(
                    !set.visible.is_empty(),
                    "{} step {step} ({}) shows no visible change",
                    simulation.task_name,
                    simulation.actions[step].action
                );
                assert!(set.visible.is_subset(&set.full));
                seen.extend(set.visible.iter().map(|s| predicate(s)));
            }
        }
    }
    for class in [
        "OnTop",
        "Inside",
        "Under",
        "Contains",
        "Covered",
        "Open",
        "ToggledOn",
        "Cooked",
        "LeftGrasping",
        "RightGrasping",
        "Transition",
    ] {
        assert!(
            seen.contains(class),
            "no visible {class} change; saw {seen:?}"
        );
    }
}

#[test]
fn a_closed_cabinet_hides_its_contents_and_opening_shows_them() {
    let dir = tempfile::tempdir().unwrap();
    let simulation = write(dir.path(), &options(Activity::PutDishesAway, 4));
    assert!(
        simulation.actions[0]
            .action
            .starts_with("open top_cabinet_0")
    );
    let timeline = timeline(dir.path(), &simulation);
    let visible = |frame: u64, name: &str| {
        let graph = timeline.scene_graph(&frame.to_string()).unwrap();
        let node = graph.nodes.iter().find(|n| n.name == name).unwrap();
        node_is_visible(node, &EVALUATION_SENSORS).unwrap()
    };
    let [closed, opened] = [simulation.key_frames[0], simulation.key_frames[1]];
    assert!(!visible(closed, "mug_0"), "the mug shows through the door");
    assert!(visible(opened, "mug_0"), "the open cabinet hides the mug");
    assert!(visible(closed, "top_cabinet_0") && visible(closed, "robot_r1"));
    // The living room is out of the kitchen camera's view.
    assert!(!visible(closed, "sofa_0"));
}

#[test]
fn a_narrow_field_of_view_loses_objects_at_the_edges() {
    let wide = simulate(&options(Activity::CookBacon, 1)).unwrap();
    let mut narrow_options = options(Activity::CookBacon, 1);
    narrow_options.camera.fov_deg = 30.0;
    let narrow = simulate(&narrow_options).unwrap();
    let seen = |s: &Simulation| -> BTreeSet<String> {
        s.scene_graph(59)
            .nodes
            .iter()
            .filter(|n| node_is_visible(n, &EVALUATION_SENSORS).unwrap())
            .map(|n| n.name.clone())
            .collect()
    };
    let (w, n) = (seen(&wide), seen(&narrow));
    assert!(
        n.is_subset(&w) && n.len() < w.len(),
        "wide {w:?}, narrow {n:?}"
    );
}

#[test]
fn the_same_seed_gives_the_same_bytes_and_another_seed_another_run() {
    let read = |seed: u64| {
        let dir = tempfile::tempdir().unwrap();
        let simulation = write(dir.path(), &options(Activity::SliceFruit, seed));
        let task = dir.path().join(&simulation.task_name);
        (
            std::fs::read(task.join("scene_graph_0.json")).unwrap(),
            std::fs::read(task.join("external_sensor1/00059.png")).unwrap(),
        )
    };
    let (a, a_png) = read(9);
    let (b, b_png) = read(9);
    assert!(a == b, "same seed, different scene graphs");
    assert_eq!(a_png, b_png);
    let (c, _) = read(10);
    assert!(a != c, "seeds 9 and 10 gave the same scene graph");
}

#[test]
fn rendering_variants_change_the_pixels() {
    let base = options(Activity::TidyLivingRoom, 3);
    let picture = |o: &SimulateOptions| simulate(o).unwrap().image(59).clone();
    let reference = picture(&base);
    let mut variants = Vec::new();
    let mut fov = base.clone();
    fov.camera.fov_deg = 80.0;
    variants.push(("fov", fov));
    let mut height = base.clone();
    height.camera.height_m = 1.1;
    variants.push(("camera height", height));
    let mut colour = base.clone();
    colour.camera.robot_colour = parse_colour("white").unwrap();
    variants.push(("robot colour", colour));
    for (what, variant) in variants {
        let other = picture(&variant);
        let changed = reference
            .pixels()
            .zip(other.pixels())
            .filter(|(a, b)| a != b)
            .count();
        assert!(changed > 500, "{what}: only {changed} pixels differ");
    }
    assert_eq!(parse_colour("#0a0B0c").unwrap(), [10, 11, 12]);
    assert!(parse_colour("mauve").unwrap_err().contains("#rrggbb"));
}

#[test]
fn segmentation_finds_exactly_the_intended_key_frames() {
    let dir = tempfile::tempdir().unwrap();
    let mut glitch_mattered = false;
    for activity in Activity::ALL {
        for (seed, length) in [(1, None), (5, Some(18))] {
            let mut o = options(activity, seed);
            o.length = length;
            o.camera.image_size = 64;
            let simulation = write(dir.path(), &o);
            assert!(!simulation.flickers.is_empty());
            let segmented = segment_task(dir.path(), &simulation.task_name, &Default::default())
                .unwrap_or_else(|e| panic!("{}: {e}", simulation.task_name));
            assert_eq!(
                segmented.segmentation.key_frames,
                frames(&simulation),
                "{}",
                simulation.task_name
            );
            // Without ENACT's transient filter, the glitches would move or add key frames.
            let raw = timeline(dir.path(), &simulation);
            let unfiltered = segment_key_frames(&raw, &SegmentationParams::default()).unwrap();
            glitch_mattered |= unfiltered.key_frames != frames(&simulation);
        }
    }
    assert!(glitch_mattered, "no glitch would have fooled segmentation");
}

#[test]
fn the_written_records_rebuild_every_frame_as_simulated() {
    let dir = tempfile::tempdir().unwrap();
    let mut o = options(Activity::MakeTea, 6);
    o.camera.image_size = 64;
    let simulation = write(dir.path(), &o);
    let timeline = timeline(dir.path(), &simulation);
    assert_eq!(timeline.frame_ids().count() as u64, simulation.num_frames);
    let sorted = |mut g: enact_hub::core::scene_graph::SceneGraph| {
        g.nodes.sort_by(|a, b| a.name.cmp(&b.name));
        g.edges
            .sort_by(|a, b| (&a.from, &a.to).cmp(&(&b.from, &b.to)));
        g
    };
    for frame in 0..simulation.num_frames {
        let rebuilt = timeline
            .scene_graph(&frame.to_string())
            .unwrap()
            .into_owned();
        assert_eq!(
            sorted(rebuilt),
            sorted(simulation.scene_graph(frame)),
            "frame {frame}"
        );
    }
}

/// `(xmin, ymin, xmax, ymax)` of a node as the head camera sees it, if it is seen.
fn bbox(graph: &enact_hub::core::scene_graph::SceneGraph, name: &str) -> Option<[f64; 4]> {
    let node = graph.nodes.iter().find(|n| n.name == name)?;
    let reading = node.visibility.get("external_sensor1")?;
    let v: Vec<f64> = reading.iter().filter_map(|n| n.as_f64()).collect();
    (v.len() == 7 && v[0] > 0.0).then(|| [v[1], v[2], v[3], v[4]])
}

/// Objects whose recorded state changed between two graphs: a node's states, a node appearing
/// or disappearing, or a relation (both of its objects), counting only states ENACT describes.
fn changed_objects(
    a: &enact_hub::core::scene_graph::SceneGraph,
    b: &enact_hub::core::scene_graph::SceneGraph,
) -> BTreeSet<String> {
    use enact_hub::core::scene_graph::signature::state_phrase;
    let described = |states: &[String]| -> BTreeSet<String> {
        states
            .iter()
            .filter(|s| state_phrase(s).is_some())
            .cloned()
            .collect()
    };
    let mut changed = BTreeSet::new();
    let names: BTreeSet<&str> = a
        .nodes
        .iter()
        .chain(&b.nodes)
        .map(|n| n.name.as_str())
        .collect();
    for name in names {
        let states = |g: &enact_hub::core::scene_graph::SceneGraph| {
            g.nodes
                .iter()
                .find(|n| n.name == name)
                .map(|n| described(&n.states))
        };
        if states(a) != states(b) {
            changed.insert(name.to_owned());
        }
    }
    let edges = |g: &enact_hub::core::scene_graph::SceneGraph| {
        g.edges
            .iter()
            .map(|e| ((e.from.clone(), e.to.clone()), described(&e.states)))
            .filter(|(_, s)| !s.is_empty())
            .collect::<std::collections::BTreeMap<_, _>>()
    };
    let (ea, eb) = (edges(a), edges(b));
    for key in ea.keys().chain(eb.keys()) {
        if ea.get(key) != eb.get(key) {
            changed.insert(key.0.clone());
            changed.insert(key.1.clone());
        }
    }
    changed
}

/// Every state change a key frame records is visible at thumbnail size, and every object an
/// activity touches is drawn at least 24 px across in a 512 px frame.
#[test]
fn key_frame_changes_are_visible_at_thumbnail_size() {
    use image::imageops::{FilterType, resize};
    let mut report = Vec::new();
    for activity in Activity::ALL {
        for seed in [3, 11] {
            let simulation = simulate(&SimulateOptions {
                seed,
                activity,
                length: None,
                camera: CameraRig::default(),
            })
            .unwrap();
            let frames = &simulation.key_frames;
            let mut touched: BTreeSet<String> = BTreeSet::new();
            let mut largest: std::collections::BTreeMap<String, f64> = Default::default();
            for pair in frames.windows(2) {
                let (a, b) = (
                    simulation.scene_graph(pair[0]),
                    simulation.scene_graph(pair[1]),
                );
                let small = |f: u64| resize(simulation.image(f), 256, 256, FilterType::Triangle);
                let (ia, ib) = (small(pair[0]), small(pair[1]));
                let differs = |x: u32, y: u32| {
                    let (p, q) = (ia.get_pixel(x, y).0, ib.get_pixel(x, y).0);
                    (0..3).any(|c| p[c].abs_diff(q[c]) > 24)
                };
                let changed_pixels = (0..256)
                    .flat_map(|y| (0..256).map(move |x| (x, y)))
                    .filter(|&(x, y)| differs(x, y))
                    .count();
                let share = changed_pixels as f64 / (256.0 * 256.0);
                let what = format!(
                    "{} seed {seed}, key frames {} → {}",
                    activity.name(),
                    pair[0],
                    pair[1]
                );
                if share < 0.005 {
                    report.push(format!(
                        "{what}: only {:.2}% of pixels change ({:?})",
                        share * 100.0,
                        changed_objects(&a, &b)
                    ));
                }
                for name in changed_objects(&a, &b) {
                    if name.starts_with("robot") {
                        continue;
                    }
                    // Where the object is in either frame, at 256 px.
                    let boxes: Vec<[f64; 4]> = [bbox(&a, &name), bbox(&b, &name)]
                        .into_iter()
                        .flatten()
                        .collect();
                    if boxes.is_empty() {
                        continue; // not seen in either frame: ENACT does not describe it
                    }
                    touched.insert(name.clone());
                    let seen = boxes.iter().any(|[x0, y0, x1, y1]| {
                        let r = |v: f64| ((v / 2.0).floor().max(0.0) as u32).min(255);
                        (r(*y0)..=r(*y1)).any(|y| (r(*x0)..=r(*x1)).any(|x| differs(x, y)))
                    });
                    if !seen {
                        report.push(format!("{what}: {name} changes but no pixel of it does"));
                    }
                }
                for g in [&a, &b] {
                    for n in &g.nodes {
                        if let Some([x0, y0, x1, y1]) = bbox(g, &n.name) {
                            let across = (x1 - x0).max(y1 - y0);
                            let e = largest.entry(n.name.clone()).or_default();
                            *e = e.max(across);
                        }
                    }
                }
            }
            for name in &touched {
                let across = largest.get(name).copied().unwrap_or(0.0);
                if across < 24.0 {
                    report.push(format!(
                        "{} seed {seed}: {name} is at most {across} px across",
                        activity.name()
                    ));
                }
            }
        }
    }
    assert!(
        report.is_empty(),
        "{} problems:\n{}",
        report.len(),
        report.join("\n")
    );
}

fn enact_hub(args: &[&std::ffi::OsStr]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_enact-hub"))
        .args(args)
        .output()
        .unwrap()
}

/// `enact-hub generate REPLAY --out RELEASE --steps STEPS`, which must succeed.
fn generate(replay: &Path, release: &Path, steps: &str) {
    let out = enact_hub(&[
        "generate".as_ref(),
        replay.as_os_str(),
        "--out".as_ref(),
        release.as_os_str(),
        "--steps".as_ref(),
        steps.as_ref(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The paper's camera ablation in small: the same activity and seed rendered with a 30° field
/// of view keeps every item of the baseline (the same QA file, byte for byte) with images of
/// its own; a variant missing a key frame or replaying other tasks is refused by name.
#[test]
fn a_variant_release_keeps_the_baseline_items_with_its_own_images() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    let mut baseline = options(Activity::SliceFruit, 3);
    baseline.camera.image_size = 96;
    let simulation = write(&path("base-replay"), &baseline);
    let mut narrow = baseline.clone();
    narrow.camera.fov_deg = 30.0;
    write(&path("fov-replay"), &narrow);

    generate(&path("base-replay"), &path("base"), "3..4");
    let variant = |replay: &str, out: &str| {
        enact_hub(&[
            "generate".as_ref(),
            path(replay).as_os_str(),
            "--out".as_ref(),
            path(out).as_os_str(),
            "--items-from".as_ref(),
            path("base").as_os_str(),
        ])
    };
    let out = variant("fov-replay", "fov");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The hint imports the variant with the baseline's scene graphs, not the replay's.
    let hint = String::from_utf8_lossy(&out.stderr).into_owned();
    let baseline_graphs = path("base").join("replayed_activities");
    assert!(
        hint.contains(&format!("--scene-graphs {}", baseline_graphs.display())),
        "{hint}"
    );

    let qa = |release: &str| std::fs::read(path(release).join("QA/enact_ordering.jsonl")).unwrap();
    assert_eq!(qa("fov"), qa("base"), "the variant changes no item");
    let text = String::from_utf8(qa("base")).unwrap();
    let (mut images, mut differing) = (0, 0);
    for line in text.lines() {
        let item: serde_json::Value = serde_json::from_str(line).unwrap();
        for image in item["images"].as_array().unwrap() {
            let image = image.as_str().unwrap();
            images += 1;
            differing += usize::from(
                std::fs::read(path("base").join(image)).unwrap()
                    != std::fs::read(path("fov").join(image)).unwrap(),
            );
        }
    }
    assert!(images > 0);
    assert_eq!(
        differing, images,
        "every image is the variant's own rendering"
    );

    // A key frame the variant has no image of is named.
    let frame = simulation.key_frames[1].to_string();
    let missing = path("fov-replay")
        .join(&simulation.task_name)
        .join("external_sensor1")
        .join(format!("{:05}.png", simulation.key_frames[1]));
    std::fs::remove_file(&missing).unwrap();
    let out = variant("fov-replay", "fov-missing");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(&format!("key frame {frame} has no image")),
        "{stderr}"
    );
    assert!(
        !path("fov-missing").exists(),
        "nothing written before the refusal"
    );

    // Another seed replays other tasks.
    write(&path("other-replay"), &options(Activity::SliceFruit, 4));
    let out = variant("other-replay", "other");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(&simulation.task_name) && stderr.contains("same tasks"),
        "{stderr}"
    );

    // Sampling options mean nothing for a variant.
    let out = enact_hub(&[
        "generate".as_ref(),
        path("fov-replay").as_os_str(),
        "--out".as_ref(),
        path("x").as_os_str(),
        "--items-from".as_ref(),
        path("base").as_os_str(),
        "--seed".as_ref(),
        "7".as_ref(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot be used with"));
}

/// ENACT's download layout (QA/ beside replayed_activities/) imports with one command: the
/// scene graphs are found and every item is scored from them; `--no-scene-graphs` skips them.
#[test]
fn a_release_with_its_replays_imports_them_without_being_told() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    let mut o = options(Activity::MakeTea, 2);
    o.camera.image_size = 96;
    write(&path("replay"), &o);
    generate(&path("replay"), &path("release"), "3");
    let (release, db) = (path("release"), path("hub.db"));
    let import = |dataset: &str, extra: &[&str]| {
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "import".as_ref(),
            release.as_os_str(),
            "--db".as_ref(),
            db.as_os_str(),
            "--dataset".as_ref(),
            dataset.as_ref(),
            "--json".as_ref(),
        ];
        args.extend(extra.iter().map(|a| std::ffi::OsStr::new(*a)));
        let out = enact_hub(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        (report, String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let (found, stderr) = import("found", &[]);
    let items = found["rows"].as_u64().unwrap();
    assert!(items > 0);
    assert_eq!(found["scene_graph_items"], items, "{found}");
    assert!(
        stderr.contains("replayed_activities (the release's own"),
        "{stderr}"
    );
    let (skipped, _) = import("skipped", &["--no-scene-graphs"]);
    assert_eq!(skipped["scene_graph_items"], 0, "{skipped}");
    assert_eq!(skipped["rows"], items);
}

/// BEHAVIOR's writer stores either every frame's record `full` (ENACT's published replays) or a
/// `full` record every 200 frames with diffs between: the same run written both ways gives the
/// same key frames, path counts, items and signatures.
#[test]
fn full_and_mixed_record_replays_give_the_same_items() {
    use enact_hub::core::pipeline::{GenerateOptions, generate};
    use enact_hub::core::world::RecordMode;

    let dir = tempfile::tempdir().unwrap();
    let mut options = options(Activity::MakeTea, 4);
    options.camera.image_size = 96;
    let simulation = simulate(&options).unwrap();
    let mut sizes = Vec::new();
    let mut summaries = Vec::new();
    for (name, mode) in [("mixed", RecordMode::Mixed), ("full", RecordMode::Full)] {
        let replay = dir.path().join(format!("{name}-replay"));
        simulation
            .write_replay_with(&replay, FrameImages::KeyFrames, mode)
            .unwrap();
        let graph = replay
            .join(&simulation.task_name)
            .join("scene_graph_0.json");
        sizes.push(std::fs::metadata(&graph).unwrap().len());
        let out = dir.path().join(name);
        let mut summary = generate(
            &replay,
            &out,
            &GenerateOptions {
                num_to_sample: 2,
                step_lengths: vec![3, 4, 6],
                ..GenerateOptions::default()
            },
            &|_| {},
        )
        .unwrap();
        summary.jsonl_path = Default::default();
        let signatures =
            transition_signatures(&timeline(&replay, &simulation), &frames(&simulation)).unwrap();
        let qa = std::fs::read(out.join("QA/enact_ordering.jsonl")).unwrap();
        summaries.push((summary, signatures, qa));
    }
    assert!(
        sizes[1] > 20 * sizes[0],
        "a full record per frame is far larger: {sizes:?}"
    );
    let (mixed, full) = (&summaries[0], &summaries[1]);
    assert_eq!(
        full.0.tasks[0].key_frames,
        frames(&simulation),
        "segmentation finds the intended key frames"
    );
    assert_eq!(mixed.0, full.0, "key frames, path counts and items");
    assert_eq!(mixed.1, full.1, "signatures at the key frames");
    assert_eq!(mixed.2, full.2, "the same QA file");
}

/// Large replays are read as a stream through the transient filter (one window of frames in
/// memory): on a full-record replay with glitches, every filtered frame equals the in-memory
/// filter's, and segmentation on it finds the intended key frames.
#[test]
fn a_streamed_filtered_replay_equals_the_in_memory_one() {
    use enact_hub::core::scene_graph::TransientFilter;
    use enact_hub::core::world::RecordMode;

    let dir = tempfile::tempdir().unwrap();
    let mut options = options(Activity::SliceFruit, 6);
    options.camera.image_size = 64;
    let simulation = simulate(&options).unwrap();
    assert!(!simulation.flickers.is_empty());
    simulation
        .write_replay_with(dir.path(), FrameImages::KeyFrames, RecordMode::Full)
        .unwrap();
    let path = dir
        .path()
        .join(&simulation.task_name)
        .join("scene_graph_0.json");
    let in_memory =
        SceneGraphTimeline::load_with(&path, FrameSelection::All, TransientFilter::Enact).unwrap();
    let streamed =
        SceneGraphTimeline::load_streamed(&path, &FrameSelection::All, TransientFilter::Enact)
            .unwrap()
            .expect("frame ids in order");
    let ids: Vec<String> = in_memory.frame_ids().collect();
    assert_eq!(ids, streamed.frame_ids().collect::<Vec<_>>());
    for f in &ids {
        assert_eq!(
            *in_memory.scene_graph(f).unwrap(),
            *streamed.scene_graph(f).unwrap(),
            "frame {f}"
        );
    }
    let segmented = segment_key_frames(&streamed, &SegmentationParams::default()).unwrap();
    assert_eq!(segmented.key_frames, frames(&simulation));
}

/// Every key frame of every activity, under the default rig and three variants, hashed with the
/// visibility each object reads in it: drawing code may be reorganised, but a change here is a
/// change to every released image and must be meant (then record the new digest).
#[test]
fn rendered_frames_are_unchanged() {
    use sha2::{Digest, Sha256};
    let mut rigs = vec![CameraRig {
        image_size: 160,
        ..CameraRig::default()
    }];
    rigs.push(CameraRig {
        fov_deg: 30.0,
        ..rigs[0]
    });
    rigs.push(CameraRig {
        height_m: 1.1,
        image_size: 97,
        ..rigs[0]
    });
    rigs.push(CameraRig {
        robot_colour: parse_colour("white").unwrap(),
        fov_deg: 90.0,
        ..rigs[0]
    });
    let mut digest = Sha256::new();
    for rig in &rigs {
        for activity in Activity::ALL {
            let simulation = simulate(&SimulateOptions {
                seed: 5,
                activity,
                length: None,
                camera: *rig,
            })
            .unwrap();
            for &frame in &simulation.key_frames {
                let image = simulation.image(frame);
                digest.update(image.width().to_le_bytes());
                digest.update(image.as_raw());
                for node in &simulation.scene_graph(frame).nodes {
                    digest.update(node.name.as_bytes());
                    digest.update(serde_json::to_vec(&node.visibility).unwrap());
                }
            }
        }
    }
    assert_eq!(
        hex::encode(digest.finalize()),
        "a46d758ccff8f988bc75e018b4ba76c54151d43e6606f60dc789a8e8232121c9",
        "the rendered frames changed"
    );
}
