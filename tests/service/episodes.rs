//! Real-world episodes through the command line: import recorded frames, set a curator's
//! graphs (refused with the key frame and field named), export, `generate` keeping every
//! marked key frame, and the items' action texts and ground truth checked by the verifier.

use std::path::Path;

use enact_hub::app::refusal::Refusal;
use enact_hub::core::dataset::{Direction, parse_release_line};
use enact_hub::core::episode::{EpisodeGraphs, describe};
use enact_hub::core::scene_graph::parse_action;
use enact_hub::core::verifier::{Permutation, parse_answer_enact, parse_python_json, verify};
use serde_json::{Value, json};

use crate::helpers::{count, db, enact_hub, fresh_db_located, tester};

fn run(args: &[&str]) -> (bool, String, String) {
    let out = enact_hub()
        .env("ENACT_HUB_OPERATOR", "curator-ann")
        .args(args)
        .output()
        .expect("enact-hub runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Twelve distinct frames named so that only natural order puts them right (`frame_2` before
/// `frame_10`); one is a JPEG.
fn write_frames(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    for n in 1..=12u32 {
        let image = image::RgbImage::from_fn(64, 48, |x, y| {
            image::Rgb([(n * 20) as u8, (x * 4) as u8, (y * 5) as u8])
        });
        let format = if n == 5 {
            image::ImageFormat::Jpeg
        } else {
            image::ImageFormat::Png
        };
        let ext = if n == 5 { "jpg" } else { "png" };
        image
            .save_with_format(dir.join(format!("frame_{n}.{ext}")), format)
            .unwrap();
    }
}

/// `episode import FRAMES --db DB --name kitchen_real` with `extra` arguments.
fn import_frames(frames: &Path, db: &str, extra: &[&str]) -> (bool, String, String) {
    let mut args = vec!["episode", "import", frames.to_str().unwrap(), "--db", db];
    args.extend_from_slice(&["--name", "kitchen_real"]);
    args.extend_from_slice(extra);
    run(&args)
}

/// `episode COMMAND kitchen_real --db DB` with `args`.
fn episode(db: &str, command: &str, args: &[&str]) -> (bool, String, String) {
    let mut all = vec!["episode", command, "kitchen_real", "--db", db];
    all.extend_from_slice(args);
    run(&all)
}

fn node(name: &str, category: &str, states: &[&str]) -> Value {
    json!({"name": name, "category": category, "states": states})
}

/// Five key frames: the fridge opens, the robot takes the apple out, puts it on the table and
/// turns the stove on, then closes the fridge.
fn graphs() -> Value {
    let frame = |frame: u32, fridge: &[&str], stove: &[&str], edges: Value| {
        json!({"frame": frame, "nodes": [
            node("robot_r1", "agent", &[]),
            node("fridge_1", "fridge", fridge),
            node("apple_2", "apple", &[]),
            node("table_3", "table", &[]),
            node("stove_4", "stove", stove),
        ], "edges": edges})
    };
    json!({"key_frames": [
        frame(0, &[], &[], json!([{"from": "apple_2", "to": "fridge_1", "states": ["Inside"]}])),
        frame(3, &["Open"], &[], json!([{"from": "apple_2", "to": "fridge_1", "states": ["Inside"]}])),
        frame(6, &["Open"], &[], json!([{"from": "robot_r1", "to": "apple_2", "states": ["LeftGrasping"]}])),
        frame(9, &["Open"], &["ToggledOn"], json!([{"from": "apple_2", "to": "table_3", "states": ["OnTop"]}])),
        frame(11, &[], &["ToggledOn"], json!([{"from": "apple_2", "to": "table_3", "states": ["OnTop"]}])),
    ]})
}

#[tokio::test]
async fn an_episode_becomes_items_whose_actions_are_the_curators_transitions() {
    let dir = tempfile::tempdir().unwrap();
    let (pool, db) = fresh_db_located(&dir).await;
    let db = db.to_str().unwrap();
    let frames = dir.path().join("frames");
    write_frames(&frames);

    // Anything but a frame in the folder is refused by name, and nothing is stored.
    std::fs::write(frames.join("notes.txt"), "x").unwrap();
    let (ok, _, err) = import_frames(&frames, db, &[]);
    assert!(
        !ok && err.contains("notes.txt") && err.contains("only PNG and JPEG"),
        "{err}"
    );
    std::fs::remove_file(frames.join("notes.txt")).unwrap();
    std::fs::write(frames.join("frame_13.png"), b"not a png").unwrap();
    let (ok, _, err) = import_frames(&frames, db, &[]);
    assert!(
        !ok && err.contains("frame_13.png") && err.contains("cannot decode"),
        "{err}"
    );
    std::fs::remove_file(frames.join("frame_13.png")).unwrap();
    assert_eq!(count(&pool, "SELECT COUNT(*) FROM episodes").await, 0);

    let (ok, out, err) = import_frames(&frames, db, &["--scene", "kitchen"]);
    assert!(ok, "{err}");
    assert!(out.contains("12 frames imported (scene kitchen)"), "{out}");
    // Twelve frames and twelve filmstrip copies.
    assert_eq!(
        count(&pool, "SELECT COUNT(*) FROM episode_frames").await,
        12
    );
    assert_eq!(count(&pool, "SELECT COUNT(*) FROM frames").await, 24);
    let (ok, _, err) = import_frames(&frames, db, &[]);
    assert!(!ok && err.contains("exists already"), "{err}");

    // A graph with mistakes is refused whole, each problem with its key frame and field.
    let mut bad = graphs();
    bad["key_frames"][2]["nodes"][1]["states"] = json!(["Opn"]);
    bad["key_frames"][3]["edges"][0]["to"] = json!("shelf_9");
    let bad_file = dir.path().join("bad.json");
    std::fs::write(&bad_file, bad.to_string()).unwrap();
    let (ok, _, err) = episode(db, "graphs", &["--set", bad_file.to_str().unwrap()]);
    assert!(!ok, "{err}");
    assert!(
        err.contains("key frame 2 (frame 6), nodes[1].states[0]: unknown predicate \"Opn\""),
        "{err}"
    );
    assert!(
        err.contains("key frame 3 (frame 9), edges[0].to: \"shelf_9\" is not an object"),
        "{err}"
    );
    assert_eq!(count(&pool, "SELECT COUNT(*) FROM episode_graphs").await, 0);

    let file = dir.path().join("graphs.json");
    std::fs::write(&file, graphs().to_string()).unwrap();
    let (ok, out, err) = episode(db, "graphs", &["--set", file.to_str().unwrap()]);
    assert!(
        ok && out.contains("graphs of curator curator-ann set (5 key frames)"),
        "{out}{err}"
    );
    let back = dir.path().join("back.json");
    let (ok, _, err) = episode(db, "graphs", &["--get", back.to_str().unwrap()]);
    assert!(ok, "{err}");
    let stored: EpisodeGraphs = serde_json::from_slice(&std::fs::read(&back).unwrap()).unwrap();
    let sent: EpisodeGraphs = serde_json::from_value(graphs()).unwrap();
    assert_eq!(stored, sent);
    let (ok, out, _) = run(&["episode", "list", "--db", db]);
    assert!(
        ok && out.contains("kitchen_real\t12 frames\tscene kitchen\tcurators: curator-ann"),
        "{out}"
    );
    assert_eq!(
        count(
            &pool,
            "SELECT COUNT(*) FROM audit_log WHERE action LIKE 'episode.%'"
        )
        .await,
        2
    );

    // Export, then generate: every marked key frame is kept.
    let export = dir.path().join("export");
    let (ok, out, err) = episode(db, "export", &["--out", export.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(
        out.contains("12 frames and 5 key frames (0, 3, 6, 9, 11)"),
        "{out}"
    );
    let replayed = export.join("replayed_activities");
    for n in 0..12 {
        let png = replayed.join(format!("kitchen_real/external_sensor1/{n:05}.png"));
        let image = image::open(&png).unwrap_or_else(|e| panic!("{}: {e}", png.display()));
        assert_eq!((image.width(), image.height()), (64, 48));
    }
    // Natural order: frame_2 is position 1, frame_10 position 9 (its red channel says which).
    let red = |n: u32| {
        image::open(replayed.join(format!("kitchen_real/external_sensor1/{n:05}.png")))
            .unwrap()
            .to_rgb8()
            .get_pixel(0, 0)[0]
    };
    assert_eq!((red(1), red(9)), (40, 200));
    assert!(
        export
            .join("segmented_activities/kitchen_real/segmented_scene_graph_0.json")
            .is_file()
    );

    let data = dir.path().join("data");
    let (ok, _, err) = run(&[
        "generate",
        replayed.to_str().unwrap(),
        "--out",
        data.to_str().unwrap(),
        "--steps",
        "3,4",
    ]);
    assert!(ok, "{err}");
    let summary: Value =
        serde_json::from_slice(&std::fs::read(data.join("generation_summary.json")).unwrap())
            .unwrap();
    assert_eq!(
        summary["tasks"][0]["key_frames"],
        json!(["0", "3", "6", "9", "11"])
    );

    // The items' action texts say what the curator's transitions say, and the verifier
    // accepts the ground truth and refuses a wrong answer.
    let described = describe(&sent);
    let by_pair: std::collections::BTreeMap<(String, String), Vec<String>> = described
        .iter()
        .map(|t| {
            (
                (t.from_frame.to_string(), t.to_frame.to_string()),
                t.visible_signatures.clone(),
            )
        })
        .collect();
    let text = std::fs::read_to_string(data.join("QA/enact_ordering.jsonl")).unwrap();
    let items: Vec<_> = text
        .lines()
        .map(|l| parse_release_line(l).expect("a valid item"))
        .collect();
    assert!(items.len() >= 4, "{} items", items.len());
    let refs: Vec<_> = items.iter().collect();
    let signatures =
        enact_hub::core::semantics::from_scene_graphs(&data.join("replayed_activities"), &refs);
    let mut inverse_checked = 0;
    for (item, signatures) in items.iter().zip(&signatures) {
        let signatures = signatures
            .as_ref()
            .expect("signatures from the exported graphs");
        let gt = Permutation::new(item.gt_answer.clone()).expect("a permutation");
        let answer = |labels: &[u8]| {
            let text = serde_json::to_string(labels).unwrap();
            parse_answer_enact(&parse_python_json(&text).unwrap(), labels.len()).unwrap()
        };
        let right = verify(item.direction, &gt, &answer(gt.labels()), Some(signatures)).unwrap();
        assert!(right.task_accuracy, "{}", item.id);
        let mut wrong: Vec<u8> = gt.labels().to_vec();
        wrong.reverse();
        let wrong = verify(item.direction, &gt, &answer(&wrong), Some(signatures)).unwrap();
        assert!(
            !wrong.task_accuracy,
            "{}: reversed answer accepted",
            item.id
        );
        if item.direction == Direction::Inverse {
            // Each action line, read back, is the transition it describes.
            let frames = &item.key_frame_ids;
            // `gt_answer[step]` is the label of the action of transition `step`.
            for (step, &label) in item.gt_answer.iter().enumerate() {
                let action = &item.actions[usize::from(label) - 1];
                let pair = (frames[step].clone(), frames[step + 1].clone());
                if let Some(expected) = by_pair.get(&pair) {
                    let parsed: Vec<String> = parse_action(action).unwrap().into_iter().collect();
                    assert_eq!(&parsed, expected, "{}: step {step}", item.id);
                    inverse_checked += 1;
                }
            }
        }
    }
    assert!(inverse_checked > 0);

    // The release imports with every item's signatures from the exported scene graphs.
    let (ok, _, err) = run(&[
        "import",
        data.to_str().unwrap(),
        "--db",
        db,
        "--dataset",
        "kitchen-real",
    ]);
    assert!(ok, "{err}");
    let stored = count(&pool, "SELECT COUNT(*) FROM items").await;
    assert_eq!(stored, items.len() as i64);
    assert_eq!(
        count(&pool, "SELECT COUNT(*) FROM item_signatures").await,
        stored
    );
    // ... and says where its items come from.
    let overview = enact_hub::app::datasets::overview(&pool.clone().into())
        .await
        .unwrap();
    let dataset = &overview[0].dataset;
    assert_eq!(
        (dataset.origin.as_str(), dataset.scene.as_str()),
        ("real", "kitchen")
    );

    // A second curator who saw the right gripper: the comparison counts the difference, an
    // export waits for an admin to choose, and then exports the chosen graphs.
    let mut other = graphs();
    other["key_frames"][2]["edges"][0]["states"] = json!(["RightGrasping"]);
    let other_file = dir.path().join("bob.json");
    std::fs::write(&other_file, other.to_string()).unwrap();
    let (ok, _, err) = episode(
        db,
        "graphs",
        &["--set", other_file.to_str().unwrap(), "--curator", "bob"],
    );
    assert!(ok, "{err}");
    let (ok, out, err) = episode(db, "compare", &["--curators", "curator-ann,bob", "--json"]);
    assert!(ok, "{err}");
    let comparison: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        comparison["key_frames"][2]["only_a"],
        json!(["robot_r1 -> apple_2: LeftGrasping"])
    );
    assert_eq!(
        comparison["key_frames"][2]["only_b"],
        json!(["robot_r1 -> apple_2: RightGrasping"])
    );
    // Transitions 3->6 and 6->9 each differ by the grasp on both sides; 2 of 4 are the same.
    assert_eq!(
        comparison["transition_components"],
        json!({"shared": 5, "only_a": 2, "only_b": 2})
    );
    let (ok, _, err) = episode(db, "export", &["--out", export.to_str().unwrap()]);
    assert!(
        !ok && err.contains("graphs from several curators (bob, curator-ann)")
            && err.contains("enact-hub episode resolve kitchen_real --curator NAME"),
        "{err}"
    );
    let (ok, _, err) = episode(db, "resolve", &["--curator", "bob"]);
    assert!(ok, "{err}");
    let again = dir.path().join("again");
    let (ok, _, err) = episode(db, "export", &["--out", again.to_str().unwrap()]);
    assert!(ok, "{err}");
    let segmented = std::fs::read_to_string(
        again.join("segmented_activities/kitchen_real/segmented_scene_graph_0.json"),
    )
    .unwrap();
    assert!(segmented.contains("RightGrasping") && !segmented.contains("LeftGrasping"));
    assert_eq!(
        count(
            &pool,
            "SELECT COUNT(*) FROM audit_log WHERE action LIKE 'episode.%'"
        )
        .await,
        4
    );
}

#[tokio::test]
async fn an_incomplete_episode_is_hidden_and_the_next_import_of_its_name_replaces_it() {
    use enact_hub::app::{AppError, Hub, episodes};
    let dir = tempfile::tempdir().unwrap();
    let (pool, _) = fresh_db_located(&dir).await;
    let hub = Hub::from(pool.clone());
    let frames = dir.path().join("frames");
    write_frames(&frames);
    // What a killed import leaves: the episode row and a first batch of frames, never marked
    // complete, with its claim on the name still running for a minute.
    let now = enact_hub::app::annotators::now_ms();
    let mut tx = crate::helpers::write_tx(&pool).await;
    let left =
        enact_hub::store::episodes::insert(&mut tx, "kitchen_real", "", "killed", now + 60_000)
            .await
            .unwrap();
    let frame = enact_hub::store::frames::insert(&mut tx, &"ab".repeat(32), 4, 4, b"png")
        .await
        .unwrap();
    enact_hub::store::episodes::insert_frame(&mut tx, left, 0, "frame_1.png", frame, frame)
        .await
        .unwrap();
    tx.commit().await.unwrap();

    assert!(episodes::list(&hub).await.unwrap().is_empty());
    assert!(matches!(
        episodes::get(&hub, "kitchen_real").await,
        Err(AppError::Refused(Refusal::NoEpisode { .. }))
    ));

    // While the claim runs, the import that holds it might be alive: the next is refused, and
    // nothing is touched.
    let refused = episodes::import(&hub, &tester(), &frames, "kitchen_real", "kitchen").await;
    match refused {
        Err(AppError::Refused(refusal @ Refusal::EpisodeImporting { .. })) => {
            let message = refusal.to_string();
            assert!(
                message.starts_with("episode 'kitchen_real' is being imported since ")
                    && message.contains("(by killed)")
                    && message.contains("lapses in 60 s"),
                "{message}"
            );
            assert_eq!(refusal.code(), "episode_importing");
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
    assert_eq!(count(&pool, "SELECT count(*) FROM episode_frames").await, 1);
    // Once it has lapsed, the import that held it is taken for dead.
    db!(
        pool,
        execute,
        sqlx::query("UPDATE episodes SET import_alive_until_ms = $1 WHERE id = $2")
            .bind(now - 1)
            .bind(left)
    )
    .expect("lapse the claim");
    let summary = episodes::import(&hub, &tester(), &frames, "kitchen_real", "kitchen")
        .await
        .expect("the incomplete episode gives way");
    assert_eq!(summary.frame_count, 12);
    assert_eq!(episodes::list(&hub).await.unwrap().len(), 1);
    assert_eq!(count(&pool, "SELECT count(*) FROM episodes").await, 1);
    // The killed import's frame went with it; every frame left is the new episode's.
    let killed = format!(
        "SELECT count(*) FROM frames WHERE sha256 = '{}'",
        "ab".repeat(32)
    );
    assert_eq!(count(&pool, &killed).await, 0);
    let used = "SELECT count(*) FROM (SELECT frame AS f FROM episode_frames \
                UNION SELECT thumbnail FROM episode_frames) u";
    assert_eq!(
        count(&pool, "SELECT count(*) FROM frames").await,
        count(&pool, used).await
    );
    assert_eq!(
        count(&pool, "SELECT count(*) FROM episode_frames").await,
        12
    );
}

/// `n` distinct PNG frames in `dir`.
fn write_many_frames(dir: &Path, n: u32) {
    std::fs::create_dir_all(dir).unwrap();
    for k in 0..n {
        let image = image::RgbImage::from_fn(64, 48, |x, y| {
            image::Rgb([
                (k % 256) as u8,
                (k / 256) as u8 + (x * 4) as u8,
                (y * 5) as u8,
            ])
        });
        image
            .save_with_format(dir.join(format!("frame_{k}.png")), image::ImageFormat::Png)
            .unwrap();
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_second_import_of_a_name_being_imported_is_refused_and_the_first_finishes() {
    use enact_hub::app::{AppError, Hub, episodes};
    let dir = tempfile::tempdir().unwrap();
    let (pool, _) = fresh_db_located(&dir).await;
    // Two hubs: like the server and a command-line import, they share only the database.
    let (first_hub, second_hub) = (Hub::from(pool.clone()), Hub::from(pool.clone()));
    let (long, short) = (dir.path().join("long"), dir.path().join("short"));
    write_many_frames(&long, 96);
    write_many_frames(&short, 1);

    let first = tokio::spawn(async move {
        episodes::import(&first_hub, &tester(), &long, "kitchen_real", "kitchen").await
    });
    // The second starts once the first has claimed the name, with 96 frames (12 batches) to
    // write.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    while count(&pool, "SELECT count(*) FROM episodes WHERE complete = 0").await == 0 {
        assert!(
            std::time::Instant::now() < deadline,
            "the first import never claimed the name"
        );
        tokio::time::sleep(std::time::Duration::from_millis(1)).await;
    }
    let second = episodes::import(&second_hub, &tester(), &short, "kitchen_real", "").await;
    let first = first.await.unwrap();

    match second {
        Err(AppError::Refused(refusal @ Refusal::EpisodeImporting { .. })) => {
            let message = refusal.to_string();
            assert!(
                message.starts_with("episode 'kitchen_real' is being imported since ")
                    && message.contains("(by operator tests)"),
                "{message}"
            );
        }
        other => panic!("the second import was not refused: {other:?}"),
    }
    let summary = first.expect("the first import finishes");
    assert_eq!(summary.frame_count, 96);
    assert_eq!(count(&pool, "SELECT count(*) FROM episodes").await, 1);
    assert_eq!(
        count(&pool, "SELECT count(*) FROM episode_frames").await,
        96
    );
    assert_eq!(
        count(
            &pool,
            "SELECT count(*) FROM episodes WHERE import_alive_until_ms IS NULL AND complete = 1"
        )
        .await,
        1,
        "a finished import leaves no claim"
    );
}
