//! The synthetic world's replays through the real pipeline and the importer: every generated
//! item is valid and gets transition signatures from the scene graphs.

use enact_hub::pipeline::{GenerateOptions, generate};
use enact_hub::world::{Activity, CameraRig, FrameImages, SimulateOptions, simulate};

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
}

#[tokio::test]
async fn the_demo_is_scored_from_its_scene_graphs() {
    let dir = tempfile::tempdir().unwrap();
    let pool = fresh_db(&dir).await;
    let report = enact_hub::cli::load_demo(&pool).await.unwrap();
    assert!(report.skipped.is_empty());
    assert!(report.rows >= 16, "{} rows", report.rows);
    assert_eq!(report.scene_graph_items, report.rows);
}
