//! The synthetic world's replays through the real pipeline and the importer: every generated
//! item is valid and gets transition signatures from the scene graphs.

use enact_hub::core::pipeline::{GenerateOptions, generate};
use enact_hub::core::world::{Activity, CameraRig, FrameImages, SimulateOptions, simulate};

use crate::helpers::{fresh_db, import, options};

#[tokio::test]
async fn simulated_replays_generate_items_that_import_with_scene_graph_semantics() {
    let dir = tempfile::tempdir().unwrap();
    let replayed = dir.path().join("simulated");
    for (activity, seed) in [(Activity::MakeTea, 8), (Activity::SliceFruit, 9)] {
        let simulation = simulate(&SimulateOptions {
            seed,
            activity,
            length: Some(12),
            camera: CameraRig {
                image_size: 128,
                ..CameraRig::default()
            },
        })
        .unwrap();
        simulation
            .write_replay(&replayed, FrameImages::KeyFrames)
            .unwrap();
    }
    let data = dir.path().join("data");
    let summary = generate(
        &replayed,
        &data,
        &GenerateOptions {
            num_to_sample: 2,
            ..GenerateOptions::default()
        },
        &|_| {},
    )
    .unwrap();
    assert_eq!(summary.tasks.len(), 2);
    for task in &summary.tasks {
        // 12 actions: 13 key frames, so every L in 3..=10 has paths.
        assert_eq!(task.key_frames.len(), 13, "{}", task.task_name);
        assert!(
            task.steps
                .iter()
                .all(|s| s.valid_paths > 0 && s.forward_items > 0)
        );
    }

    let pool = fresh_db(&dir).await;
    let mut import_options = options("world");
    import_options.scene_graphs = Some(data.join("replayed_activities"));
    let report = import(&pool, &data, &import_options).await;
    assert!(report.skipped.is_empty(), "{:?}", report.skipped);
    assert_eq!(report.rows, summary.items);
    assert_eq!(report.new_items, summary.items);
    assert_eq!(report.scene_graph_items, summary.items);
    let overview = enact_hub::app::datasets::overview(&pool.clone().into())
        .await
        .unwrap();
    assert_eq!(overview[0].dataset.origin, "simulation");
}

#[tokio::test]
async fn the_demo_is_scored_from_its_scene_graphs() {
    let dir = tempfile::tempdir().unwrap();
    let pool = fresh_db(&dir).await;
    let report = enact_hub::app::demo::load(&pool.clone().into())
        .await
        .unwrap();
    assert!(report.skipped.is_empty());
    assert!(report.rows >= 16, "{} rows", report.rows);
    assert_eq!(report.scene_graph_items, report.rows);
}

#[test]
fn simulate_writes_replays_that_generate_reads_and_refuses_bad_options() {
    let dir = tempfile::tempdir().unwrap();
    let replayed = dir.path().join("replayed");
    let out = crate::helpers::enact_hub()
        .args(["simulate", "--activity", "cook_bacon", "--length", "4"])
        .args([
            "--fov",
            "45",
            "--camera-height",
            "1.3",
            "--robot-colour",
            "#ffffff",
        ])
        .args(["--image-size", "96", "--seed", "3", "--out"])
        .arg(&replayed)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("cook_bacon_1700000000000003: 4 actions"),
        "{stdout}"
    );
    let task = replayed.join("cook_bacon_1700000000000003");
    assert!(task.join("scene_graph_0.json").is_file());
    assert!(task.join("external_sensor1/00059.png").is_file());
    let generated = crate::helpers::enact_hub()
        .args(["generate", "--steps", "3..5", "--out"])
        .arg(dir.path().join("data"))
        .arg(&replayed)
        .output()
        .unwrap();
    assert!(
        generated.status.success(),
        "{}",
        String::from_utf8_lossy(&generated.stderr)
    );

    for (args, complaint) in [
        (["--activity", "juggling"], "unknown activity \"juggling\""),
        (["--robot-colour", "mauve"], "#rrggbb"),
        (["--fov", "400"], "field of view 400"),
    ] {
        let out = crate::helpers::enact_hub()
            .arg("simulate")
            .args(args)
            .arg("--out")
            .arg(dir.path().join("bad"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success());
        assert!(stderr.contains(complaint), "{stderr}");
    }
}
