//! A curator's episode in a real browser (tests/browser/episode.mjs): 12 frames uploaded, 5
//! key frames marked, the first graph built and the next four edited by keyboard and by mouse,
//! saved. Then the command line exports the episode and generates items from the export: the
//! inverse items' action texts are the transitions the page showed, the ground truth scores
//! full marks and a wrong answer does not.

use std::collections::BTreeSet;
use std::path::Path;

use enact_hub::core::credentials::{random_token as new_token, token_hash};
use enact_hub::core::dataset::action_lines;
use enact_hub::core::scene_graph::parse_action;
use enact_hub::store;
use serde_json::{Value, json};

use crate::browser::{CHROMIUM, browser_available, run_node};
use crate::helpers::*;

/// Twelve 160×120 PNG frames, each a different shade, named in order.
fn write_frames(dir: &Path) -> Vec<String> {
    std::fs::create_dir_all(dir).expect("frames dir");
    (0u8..12)
        .map(|i| {
            let image = image::RgbImage::from_fn(160, 120, |x, y| {
                image::Rgb([i * 20, (x % 256) as u8, (y * 2 % 256) as u8])
            });
            let path = dir.join(format!("{:05}.png", i + 1));
            image.save(&path).expect("write frame");
            path.to_string_lossy().into_owned()
        })
        .collect()
}

fn cli(args: &[&std::ffi::OsStr]) -> String {
    let out = enact_hub().args(args).output().expect("run enact-hub");
    assert!(
        out.status.success(),
        "enact-hub {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn jsonl(path: &Path) -> Vec<Value> {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON line"))
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_curator_draws_an_episode_in_chromium_and_its_items_verify() {
    if !browser_available() {
        return;
    }
    let server = spawn_app_with(|_, _| async {}).await;
    let token = new_token();
    {
        let mut tx = write_tx(&server.pool).await;
        store::annotations::create_annotator(&mut tx, "curator", true, &token_hash(&token))
            .await
            .expect("insert");
        tx.commit().await.expect("commit");
    }
    let frames = write_frames(&server.dir().join("frames"));
    let found = run_node(
        "episode.mjs",
        json!({
            "mode": "e2e",
            "base": server.url(""),
            "invite": format!("/invite/{token}"),
            "episode": "kitchen",
            "frames": frames,
            "objects": [["robot_r1", "robot"], ["apple_1", "apple"], ["fridge_1", "fridge"], ["table_1", "table"]],
            "axe": ["/episodes", "/episodes/kitchen", "/admin/episodes/new"],
            "chromium": CHROMIUM,
            "failure_dir": env!("CARGO_TARGET_TMPDIR"),
            // scripts/screenshots-episode.sh: the README's pictures of the editor.
            "screenshots": std::env::var("ENACT_HUB_SCREENSHOTS").ok(),
        }),
    )
    .await;
    assert_eq!(found["console_errors"], 0, "{found}");
    assert_eq!(found["axe"], json!([]), "{found}");
    // Flagged before saving: a copied key frame (no change) and an edge to a removed object.
    assert!(
        found["unchanged"].to_string().contains("change"),
        "no change was not flagged: {found}"
    );
    assert!(
        found["dangling"].to_string().contains("table_1"),
        "the edge to the removed table was not flagged: {found}"
    );
    let transitions = found["transitions"].as_array().expect("transitions");
    assert_eq!(transitions.len(), 4, "{found}");
    let shown: Vec<BTreeSet<String>> = transitions
        .iter()
        .map(|t| {
            assert_eq!(t["problems"], json!([]), "{t}");
            t["components"]
                .as_array()
                .expect("components")
                .iter()
                .map(|c| c.as_str().expect("component").to_owned())
                .collect()
        })
        .collect();
    // What each transition says, as the page showed it.
    let sentences = |i: usize| transitions[i]["sentences"].to_string();
    assert!(sentences(0).contains("grasp"), "{}", sentences(0));
    assert!(sentences(0).contains("on top of"), "{}", sentences(0));
    assert!(sentences(1).contains("open"), "{}", sentences(1));
    assert!(sentences(2).contains("inside"), "{}", sentences(2));
    assert!(sentences(3).contains("open"), "{}", sentences(3));
    assert_eq!(
        found["after_reload"]["components"],
        transitions[3]["components"]
    );

    // Export and generate, as a maintainer would.
    let export = server.dir().join("export");
    let data = server.dir().join("data");
    let db = server.db_path();
    cli(&[
        "episode".as_ref(),
        "export".as_ref(),
        "kitchen".as_ref(),
        "--db".as_ref(),
        db.as_os_str(),
        "--out".as_ref(),
        export.as_os_str(),
    ]);
    let replayed = export.join("replayed_activities");
    cli(&[
        "generate".as_ref(),
        "--out".as_ref(),
        data.as_os_str(),
        replayed.as_os_str(),
    ]);
    let records = jsonl(&data.join("QA/enact_ordering.jsonl"));
    assert!(!records.is_empty(), "generate made no item");
    // Every inverse item's actions are what the curator saw, in ENACT's wording: between two
    // neighbouring key frames exactly the transition shown; across skipped key frames
    // (shorter items choose among the five) a part of the transitions in between.
    let key_frame_ids = |r: &Value| -> Vec<u64> {
        r["key_frame_ids"]
            .as_array()
            .expect("key_frame_ids")
            .iter()
            .map(|v| v.as_str().expect("id").parse().expect("a number"))
            .collect()
    };
    let marked: Vec<u64> = records
        .iter()
        .flat_map(key_frame_ids)
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    assert_eq!(
        marked.len(),
        5,
        "items use the five key frames marked: {marked:?}"
    );
    let index = |id: u64| {
        marked
            .iter()
            .position(|m| *m == id)
            .expect("a marked frame")
    };
    let mut inverse = 0;
    let mut neighbours = 0;
    for record in &records {
        if !record["type"]
            .as_str()
            .expect("type")
            .starts_with("inverse")
        {
            continue;
        }
        inverse += 1;
        let question = record["question"].as_str().expect("question");
        let actions = action_lines(question);
        let ids = key_frame_ids(record);
        let gt = record["gt_answer"].as_array().expect("gt_answer");
        assert_eq!(actions.len(), gt.len(), "{question}");
        for (j, label) in gt.iter().enumerate() {
            let label = usize::try_from(label.as_u64().expect("label")).expect("small");
            let text = &actions[label - 1].1;
            let parsed = parse_action(text).expect("an action ENACT can parse");
            let (from, to) = (index(ids[j]), index(ids[j + 1]));
            if to == from + 1 {
                neighbours += 1;
                assert_eq!(parsed, shown[from], "action {text:?} of transition {from}");
            } else {
                let spanned: BTreeSet<String> = shown[from..to].iter().flatten().cloned().collect();
                assert!(
                    parsed.is_subset(&spanned),
                    "action {text:?} of key frames {from}..{to} is not what was shown"
                );
            }
        }
    }
    assert!(inverse > 0 && neighbours > 0, "{inverse} inverse items");

    // The ground truth scores full marks; the reverse of it does not.
    let predictions = server.dir().join("enact_ordering_curated.jsonl");
    let lines: Vec<String> = records
        .iter()
        .map(|r| json!({"id": r["id"], "answer": r["gt_answer"].to_string()}).to_string())
        .collect();
    std::fs::write(&predictions, lines.join("\n") + "\n").expect("predictions");
    let scored = server.dir().join("scored");
    let score = |out: &Path| {
        cli(&[
            "score".as_ref(),
            predictions.as_os_str(),
            "--data".as_ref(),
            data.as_os_str(),
            "--scene-graphs".as_ref(),
            replayed.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
        ]);
        jsonl(&out.join("detailed_eval/enact_ordering_curated.jsonl"))
    };
    for line in score(&scored) {
        assert_eq!(line["eval_metrics"]["task_accuracy"], true, "{line}");
    }
    let wrong: Vec<String> = records
        .iter()
        .map(|r| {
            let mut answer: Vec<i64> = r["gt_answer"]
                .as_array()
                .expect("gt_answer")
                .iter()
                .map(|v| v.as_i64().expect("label"))
                .collect();
            answer.reverse();
            json!({"id": r["id"], "answer": format!("{answer:?}")}).to_string()
        })
        .collect();
    std::fs::write(&predictions, wrong.join("\n") + "\n").expect("predictions");
    for line in score(&server.dir().join("scored-wrong")) {
        assert_eq!(line["eval_metrics"]["task_accuracy"], false, "{line}");
    }
    server.stop().await;
}
