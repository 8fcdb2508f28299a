//! Two leaderboard rows compared item by item: `GET /api/v1/datasets/{d}/compare`, the page
//! `/datasets/{d}/compare` and `enact-hub compare`, their figures recomputed here.

use std::collections::BTreeSet;

use enact_hub::core::credentials::Role;
use enact_hub::core::dataset::AnswerVisibility;
use serde_json::Value;

use crate::helpers::*;
use crate::submissions::{make_answers_public, post};

/// Twelve items: two activities × forward and inverse × L = 3, 4, 5 (in that order): 0–2 cook
/// forward, 3–5 cook inverse, 6–8 wash forward, 9–11 wash inverse.
pub(crate) async fn server_with_two_activities() -> (TestServer, Vec<Value>) {
    let records = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let shared = records.clone();
    let server = spawn_app_with(|pool, dir| async move {
        let root = dir.join("release");
        let mut written = Vec::new();
        let mut n = 1;
        for task in ["cook_bacon", "wash_dishes"] {
            for forward in [true, false] {
                for l in [3, 4, 5] {
                    written.push(write_record(&root, task, forward, l, n));
                    n += 1;
                }
            }
        }
        let lines: Vec<String> = written.iter().map(Value::to_string).collect();
        write_qa_file(&root, &lines);
        import(&pool, &root, &options("mini")).await;
        *shared.lock().expect("lock") = written;
    })
    .await;
    let records = records.lock().expect("lock").clone();
    (server, records)
}

/// McNemar's exact two-sided p-value, by exact integer arithmetic.
fn mcnemar(a_only: u32, b_only: u32) -> f64 {
    let n = a_only + b_only;
    if n == 0 {
        return 1.0;
    }
    let choose =
        |n: u32, k: u32| (0..k).fold(1u128, |c, i| c * u128::from(n - i) / u128::from(i + 1));
    let tail: u128 = (0..=a_only.min(b_only)).map(|k| choose(n, k)).sum();
    (2.0 * tail as f64 / 2f64.powi(n as i32)).min(1.0)
}

fn ids(records: &[Value], at: &[usize]) -> BTreeSet<String> {
    at.iter()
        .map(|&i| records[i]["id"].as_str().expect("id").to_owned())
        .collect()
}

fn listed(items: &Value) -> BTreeSet<String> {
    items
        .as_array()
        .unwrap_or_else(|| panic!("a list of items: {items}"))
        .iter()
        .map(|i| i["item"].as_str().expect("item").to_owned())
        .collect()
}

#[tokio::test]
async fn two_rows_are_compared_item_by_item_as_computed_here() {
    let (server, records) = server_with_two_activities().await;
    let (_, alice) = api_token(&server.pool, "alice", Role::Submitter, None, None).await;
    let (_, bob) = api_token(&server.pool, "bob", Role::Submitter, None, None).await;
    // A is wrong on 0, 1, 2 and 9; B on 3, 4, 5, 6, 7 and 9.
    let wrong_a = [0, 1, 2, 9];
    let wrong_b = [3, 4, 5, 6, 7, 9];
    let a = submit_to(
        &server,
        "mini",
        "model=Alpha",
        &alice,
        answers(&records, &wrong_a),
    )
    .await;
    assert_eq!(a.status, 201, "{}", a.text);
    let b = submit_to(
        &server,
        "mini",
        "model=Beta",
        &bob,
        answers(&records, &wrong_b),
    )
    .await;
    assert_eq!(b.status, 201, "{}", b.text);

    let (status, c) = server
        .get_json("/api/v1/datasets/mini/compare?a=Alpha&b=Beta")
        .await;
    assert_eq!(status, 200, "{c}");
    assert_eq!(c["a"]["model"], "Alpha");
    assert_eq!(c["a"]["submission"], a.id());
    assert_eq!(c["b"]["submission"], b.id());
    assert_eq!(c["config"]["resampling"], "activities");
    let o = &c["overall"];
    assert_eq!(o["n"], 12);
    assert_eq!(o["activities"], 2);
    // A right where B is wrong: 3..=7 (5 items); B right where A is wrong: 0, 1, 2.
    assert_eq!(
        (o["a_only"].as_u64(), o["b_only"].as_u64()),
        (Some(5), Some(3))
    );
    assert_eq!(
        (o["both"].as_u64(), o["neither"].as_u64()),
        (Some(3), Some(1))
    );
    assert_eq!(o["a_task_accuracy"].as_f64(), Some(8.0 / 12.0));
    assert_eq!(o["b_task_accuracy"].as_f64(), Some(6.0 / 12.0));
    let p = o["mcnemar_p"].as_f64().expect("p");
    assert!((p - mcnemar(5, 3)).abs() < 1e-12, "{p}");
    let d = &o["difference"];
    let estimate = d["estimate"].as_f64().expect("estimate");
    assert!((estimate - 2.0 / 12.0).abs() < 1e-12, "{d}");
    assert!(
        d["low"].as_f64() <= Some(estimate) && Some(estimate) <= d["high"].as_f64(),
        "{d}"
    );

    // Per direction, then per step length: forward holds items 0..=2 and 6..=8.
    let cells = c["cells"].as_array().expect("cells");
    let forward = cells
        .iter()
        .find(|c| c["direction"] == "forward" && c["step_length"].is_null())
        .expect("forward");
    assert_eq!(forward["n"], 6);
    assert_eq!(
        (forward["a_only"].as_u64(), forward["b_only"].as_u64()),
        (Some(2), Some(3))
    );
    assert!((forward["mcnemar_p"].as_f64().expect("p") - mcnemar(2, 3)).abs() < 1e-12);
    let inverse_5 = cells
        .iter()
        .find(|c| c["direction"] == "inverse" && c["step_length"] == 5)
        .expect("inverse L=5");
    // Items 5 (cook) and 11 (wash): B wrong on 5 only.
    assert_eq!(inverse_5["n"], 2);
    assert_eq!(inverse_5["activities"], 2);
    assert_eq!(
        (inverse_5["a_only"].as_u64(), inverse_5["b_only"].as_u64()),
        (Some(1), Some(0))
    );
    assert_eq!(
        cells.len(),
        2 + 2 * 3,
        "two directions and three step lengths each"
    );

    // The dataset's answers are hidden: no per-item lists for anyone on the API.
    assert!(
        c["a_only_items"].is_null() && c["b_only_items"].is_null(),
        "{c}"
    );
    set_mini_answers(&server.pool, AnswerVisibility::Public).await;
    let (_, c) = server
        .get_json("/api/v1/datasets/mini/compare?a=Alpha&b=Beta&resample=items")
        .await;
    assert_eq!(c["config"]["resampling"], "items");
    assert_eq!(listed(&c["a_only_items"]), ids(&records, &[3, 4, 5, 6, 7]));
    assert_eq!(listed(&c["b_only_items"]), ids(&records, &[0, 1, 2]));
    // By submission id, the same rows.
    let (_, by_id) = server
        .get_json(&format!(
            "/api/v1/datasets/mini/compare?a={}&b={}&resample=items",
            a.id(),
            b.id()
        ))
        .await;
    assert_eq!(by_id, c);

    // The command line prints the same comparison (with the lists: it is the operator's).
    let out = enact_hub()
        .args([
            "compare",
            "Alpha",
            "Beta",
            "--dataset",
            "mini",
            "--json",
            "--resample",
            "items",
        ])
        .arg("--db")
        .arg(server.db_path())
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let cli: Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(cli, c);
    let out = enact_hub()
        .args(["compare", "Alpha", "Beta", "--dataset", "mini"])
        .arg("--db")
        .arg(server.db_path())
        .output()
        .expect("runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("A: Alpha (submission") && text.contains("resamples of activities"),
        "{text}"
    );
    assert!(text.contains("A right, B wrong (5):"), "{text}");

    // The page, in both languages.
    let (status, html) = server
        .page_in("/datasets/mini/compare?a=Alpha&b=Beta", "en")
        .await;
    assert_eq!(status, 200);
    assert!(
        html.contains("Alpha (#") && html.contains("McNemar p"),
        "{html}"
    );
    for id in ids(&records, &[3, 4, 5, 6, 7]) {
        assert!(
            html.contains(&format!("/datasets/mini/items/{id}")),
            "{id} linked"
        );
    }
    let (status, html) = server.page_in("/datasets/mini/compare", "zh-CN").await;
    assert_eq!(status, 200);
    assert!(
        html.contains("比较两行") && html.contains("Alpha (#"),
        "{html}"
    );
    server.stop().await;
}

#[tokio::test]
async fn comparisons_that_cannot_be_made_are_refused_with_the_reason() {
    let (server, records) = server_with_two_activities().await;
    let (_, alice) = api_token(&server.pool, "alice", Role::Submitter, None, None).await;
    let (_, bob) = api_token(&server.pool, "bob", Role::Submitter, None, None).await;
    for token in [&alice, &bob] {
        let r = submit_to(
            &server,
            "mini",
            "model=Alpha",
            token,
            answers(&records, &[1]),
        )
        .await;
        assert_eq!(r.status, 201, "{}", r.text);
    }
    let r = submit_to(&server, "mini", "model=Beta", &bob, answers(&records, &[2])).await;
    let beta = r.id();
    let refused = |query: &str, status: u16, says: &'static str| {
        let server = &server;
        let query = query.to_owned();
        async move {
            let (got, body) = server
                .get_json(&format!("/api/v1/datasets/mini/compare?{query}"))
                .await;
            assert_eq!(got.as_u16(), status, "{query}: {body}");
            let error = body["error"].as_str().unwrap_or_default();
            assert!(error.contains(says), "{query}: {error}");
        }
    };
    refused("a=Beta", 400, "this request needs a and b").await;
    refused("a=Human&b=Beta", 400, "the Human row pools").await;
    refused(
        "a=Gamma&b=Beta",
        404,
        "no published row of model 'Gamma' (its models: Alpha, Beta)",
    )
    .await;
    refused(
        "a=Alpha&b=Beta",
        400,
        "model 'Alpha' has rows of 2 accounts",
    )
    .await;
    refused(&format!("a={beta}&b=Beta"), 400, "the same row").await;
    refused("a=999&b=Beta", 404, "no published submission 999").await;
    refused(
        "a=Beta&b=1&resample=episodes",
        400,
        "resample: \"episodes\" is not one of: activities, items",
    )
    .await;
    let (got, _) = server
        .get_json("/api/v1/datasets/nope/compare?a=1&b=2")
        .await;
    assert_eq!(got, 404);
    // The page says the same in its own words.
    let page = server.get("/datasets/mini/compare?a=Human&b=Beta").await;
    assert_eq!(page.status(), 400);
    server.stop().await;
}

/// The items ENACT's own evaluator counts as task successes in its per-item output for
/// `model` (`reference/{mode}/detailed_eval`); an item it skipped is not one.
fn enact_successes(parity: &std::path::Path, mode: &str, model: &str) -> BTreeSet<String> {
    let path = parity.join(format!(
        "reference/{mode}/detailed_eval/enact_ordering_{model}.jsonl"
    ));
    std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).expect("a detailed_eval line"))
        .filter(|v| v["eval_metrics"]["task_accuracy"] == true)
        .map(|v| v["id"].as_str().expect("id").to_owned())
        .collect()
}

#[tokio::test]
async fn comparing_two_parity_prediction_files_agrees_with_enacts_own_verdicts() {
    let Some(parity) = crate::fixtures::parity_dir() else {
        return;
    };
    let server = spawn_app_with({
        let parity = parity.clone();
        |pool, _| async move {
            let mut opts = options("parity");
            opts.scene_graphs = Some(parity.join("replayed_activities"));
            import(&pool, &parity, &opts).await;
        }
    })
    .await;
    let (_, token) = api_token(&server.pool, "alice", Role::Admin, None, None).await;
    make_answers_public(&server, "parity", &token).await;
    // Well-formed files the strict policy takes as they are: random answers, answers
    // equivalent to the truth without being it, and the truth with one adjacent pair swapped.
    let models = ["random", "semequiv", "adjswap"];
    for model in models {
        let text = std::fs::read_to_string(
            parity.join(format!("predictions/enact_ordering_{model}.jsonl")),
        )
        .expect("predictions");
        let (status, _, body) = post(
            &server,
            "parity",
            &format!("model={model}"),
            Some(&token),
            text,
            None,
        )
        .await;
        assert_eq!(status, 201, "{model}: {body}");
    }
    for (a, b) in [
        ("random", "semequiv"),
        ("semequiv", "adjswap"),
        ("random", "adjswap"),
    ] {
        let (status, c) = server
            .get_json(&format!("/api/v1/datasets/parity/compare?a={a}&b={b}"))
            .await;
        assert_eq!(status, 200, "{c}");
        let right_a = enact_successes(&parity, "eval_plain", a);
        let right_b = enact_successes(&parity, "eval_plain", b);
        let a_only: BTreeSet<String> = right_a.difference(&right_b).cloned().collect();
        let b_only: BTreeSet<String> = right_b.difference(&right_a).cloned().collect();
        assert_eq!(listed(&c["a_only_items"]), a_only, "{a} right, {b} wrong");
        assert_eq!(listed(&c["b_only_items"]), b_only, "{b} right, {a} wrong");
        assert_eq!(c["overall"]["n"], 96, "{c}");
        assert_eq!(c["overall"]["a_only"], a_only.len(), "{c}");
        assert_eq!(c["overall"]["b_only"], b_only.len(), "{c}");
        let both = right_a.intersection(&right_b).count() as f64;
        let a_ta = c["overall"]["a_task_accuracy"].as_f64().expect("a TA");
        assert!(
            (a_ta - (both + a_only.len() as f64) / 96.0).abs() < 1e-9,
            "{a}: {a_ta}"
        );
    }
    server.stop().await;
}

#[tokio::test]
async fn the_leaderboards_intervals_resample_activities_unless_asked_and_say_which() {
    let (server, records) = server_with_two_activities().await;
    let (_, token) = api_token(&server.pool, "alice", Role::Submitter, None, None).await;
    // Right on every item of cook_bacon, wrong on every item of wash_dishes.
    let wrong: Vec<usize> = (6..12).collect();
    let reply = submit_to(
        &server,
        "mini",
        "model=split",
        &token,
        answers(&records, &wrong),
    )
    .await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    let stored = reply.json()["scores"]["confidence"].clone();
    assert_eq!(stored["resampling"], "activities", "{stored}");
    // By hand: a resample draws two activities, (1, 1), (1, 0), (0, 1) or (0, 0), so its task
    // accuracy is 1, 1/2 or 0, each end with probability 1/4: the 95 % interval is [0, 1].
    // Resampling the twelve items one by one draws Binomial(12, 1/2) / 12: far narrower.
    assert_eq!(
        stored["task_accuracy"],
        serde_json::json!({"low": 0.0, "high": 1.0})
    );
    let by_items = stored["by_items"]["task_accuracy"].clone();
    assert!(
        by_items["low"].as_f64().expect("low") > 0.1
            && by_items["high"].as_f64().expect("high") < 0.9,
        "{by_items}"
    );

    let (status, board) = server.get_json("/api/v1/datasets/mini/leaderboard").await;
    assert_eq!(status, 200, "{board}");
    let row = &board["rows"][0];
    assert_eq!(row["interval_resampling"], "activities", "{row}");
    assert_eq!(
        row["overall_task_accuracy_ci"], stored["task_accuracy"],
        "{row}"
    );
    let (status, board) = server
        .get_json("/api/v1/datasets/mini/leaderboard?resample=items")
        .await;
    assert_eq!(status, 200, "{board}");
    let row = &board["rows"][0];
    assert_eq!(row["interval_resampling"], "items", "{row}");
    assert_eq!(row["overall_task_accuracy_ci"], by_items, "{row}");
    let (status, refused) = server
        .get_json("/api/v1/datasets/mini/leaderboard?resample=episodes")
        .await;
    assert_eq!(status, 400, "{refused}");
    assert!(refused.to_string().contains("resample"), "{refused}");

    // The page says which, in both languages, and links to the other.
    let (status, html) = server.page_in("/leaderboard/mini", "en").await;
    assert_eq!(status, 200);
    assert!(
        html.contains("resampling whole activities with their items"),
        "{html}"
    );
    assert!(html.contains("resample=items"), "{html}");
    let (_, html) = server
        .page_in("/leaderboard/mini?resample=items", "zh-CN")
        .await;
    assert!(html.contains("重抽样单位为逐个题目"), "{html}");
    server.stop().await;
}
