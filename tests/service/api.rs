//! The JSON read API: datasets, item lists with filters and pages, items, frames with ETags.

use enact_hub::core::credentials::Role;
use reqwest::StatusCode;
use reqwest::header::{CACHE_CONTROL, CONTENT_TYPE, ETAG, IF_NONE_MATCH};
use serde_json::Value;

use crate::helpers::*;

#[tokio::test]
async fn healthz_is_ok() {
    let server = spawn_app_with(|_, _| async {}).await;
    assert_eq!(server.get("/healthz").await.status(), StatusCode::OK);
    server.stop().await;
}

/// The highest `NNNN_` number among a migrations folder's files.
fn highest_migration(backend: &str) -> i64 {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("migrations")
        .join(backend);
    std::fs::read_dir(&dir)
        .expect("migrations folder")
        .filter_map(|e| {
            let name = e.expect("entry").file_name().into_string().ok()?;
            name.split('_').next()?.parse::<i64>().ok()
        })
        .max()
        .expect("a migration")
}

#[tokio::test]
async fn version_names_the_build_and_the_schema_its_database_is_at() {
    use enact_hub::core::version::{COMMIT, VERSION};
    use enact_hub::store::{POSTGRES_SCHEMA, SQLITE_SCHEMA};
    let server = spawn_app_with(|_, _| async {}).await;
    let (status, body) = server.get_json("/api/v1/version").await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(body["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(body["version"], VERSION);
    assert_eq!(body["commit"], COMMIT);
    let database = &body["database"];
    let backend = database["backend"].as_str().expect("backend");
    let known = match backend {
        "sqlite" => SQLITE_SCHEMA,
        "postgres" => POSTGRES_SCHEMA,
        other => panic!("backend {other}"),
    };
    assert_eq!(
        known,
        highest_migration(backend),
        "build.rs read the folder"
    );
    assert_eq!(database["expected"], known);
    assert_eq!(database["applied"], known, "a fresh database is migrated");
    server.stop().await;
}

#[tokio::test]
async fn datasets_list_counts_by_direction_and_step_length() {
    let (server, _) = spawn_app_with_release().await;
    let (status, body) = server.get_json("/api/v1/datasets").await;
    assert_eq!(status, StatusCode::OK);
    let d = &body["datasets"][0];
    assert_eq!(d["name"], "mini");
    assert_eq!(d["items"], 4);
    assert_eq!(d["forward"], 2);
    assert_eq!(d["by_step_length"]["inverse"]["4"], 1);
    let (status, one) = server.get_json("/api/v1/datasets/mini").await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(one["tasks"], 1);
    server.stop().await;
}

#[tokio::test]
async fn item_list_filters_and_paginates() {
    let (server, _) = spawn_app_with_release().await;
    let (_, all) = server.get_json("/api/v1/datasets/mini/items").await;
    assert_eq!(all["total"], 4);
    assert!(all["next"].is_null());

    let (_, fwd) = server
        .get_json("/api/v1/datasets/mini/items?direction=forward&step_length=4")
        .await;
    assert_eq!(fwd["total"], 1);
    assert_eq!(fwd["items"][0]["direction"], "forward");
    assert_eq!(fwd["items"][0]["step_length"], 4);

    let (_, page1) = server
        .get_json("/api/v1/datasets/mini/items?per_page=3")
        .await;
    assert_eq!(page1["items"].as_array().map(Vec::len), Some(3));
    let next = page1["next"].as_str().expect("a next page").to_owned();
    let (_, page2) = server.get_json(&next).await;
    assert_eq!(page2["items"].as_array().map(Vec::len), Some(1));
    assert!(page2["next"].is_null());

    let (_, task) = server
        .get_json("/api/v1/datasets/mini/items?task=nope")
        .await;
    assert_eq!(task["total"], 0);
    server.stop().await;
}

#[tokio::test]
async fn bad_queries_and_unknown_names_get_clear_errors() {
    let (server, _) = spawn_app_with_release().await;
    let (status, body) = server
        .get_json("/api/v1/datasets/mini/items?step_length=12")
        .await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    assert!(
        body["error"]
            .as_str()
            .expect("message")
            .contains("step_length"),
        "{body}"
    );
    // Each bad value names its field, what was given and what it must be, with a code per
    // kind of value expected.
    assert_eq!(body["code"], "bad_value_whole_number", "{body}");
    assert_eq!(
        body["details"],
        serde_json::json!({"field": "step_length", "value": "12", "least": 3, "most": 10})
    );
    assert_eq!(
        body["error"],
        "step_length: \"12\" is not a whole number from 3 to 10"
    );
    let (status, body) = server
        .get_json("/api/v1/datasets/mini/items?direction=sideways")
        .await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    assert_eq!(body["code"], "bad_value_one_of", "{body}");
    assert_eq!(
        body["details"],
        serde_json::json!({"field": "direction", "value": "sideways", "choices": "forward, inverse"})
    );
    let (status, body) = server
        .get_json("/api/v1/datasets/mini/leaderboard?chart=7,x")
        .await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    assert_eq!(body["code"], "bad_value_submission_id", "{body}");
    assert_eq!(body["details"]["value"], "x", "{body}");
    // A page says it in the reader's language.
    let (status, page) = crate::annotate::Browser::new(&server)
        .in_language("zh-CN")
        .text("/datasets/mini?per_page=0")
        .await;
    assert_eq!(status, 400);
    assert!(page.contains("per_page：“0”不是 1 到 "), "{page}");
    let (status, body) = server.get_json("/api/v1/datasets/nope/items").await;
    assert_eq!(status, StatusCode::NOT_FOUND);
    assert!(
        body["error"].as_str().expect("message").contains("nope"),
        "{body}"
    );
    let (status, _) = server.get_json("/api/v1/datasets/mini/items/nope").await;
    assert_eq!(status, StatusCode::NOT_FOUND);
    server.stop().await;
}

#[tokio::test]
async fn item_shows_prompt_actions_and_images_in_order() {
    let (server, records) = spawn_app_with_release().await;
    let rec = &records[3]; // inverse, L = 4
    let id = rec["id"].as_str().expect("id");
    let (status, item) = server
        .get_json(&format!("/api/v1/datasets/mini/items/{id}"))
        .await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(item["direction"], "inverse");
    assert_eq!(item["question"], rec["question"]);
    assert_eq!(item["actions"].as_array().map(Vec::len), Some(3));
    assert_eq!(item["actions"][0]["label"], 1);
    let images = item["images"].as_array().expect("images");
    assert_eq!(images.len(), 4);
    assert_eq!(images[0]["label"], "Current State");
    assert_eq!(images[3]["label"], "Next State 3");
    server.stop().await;
}

/// Walks a JSON value and fails if any key names ground truth.
fn assert_no_ground_truth(value: &Value, path: &str) {
    match value {
        Value::Object(map) => {
            for (k, v) in map {
                assert!(
                    !["gt_answer", "ground_truth", "answer", "key_frame_ids"].contains(&k.as_str()),
                    "{path}.{k} must not be served"
                );
                assert_no_ground_truth(v, &format!("{path}.{k}"));
            }
        }
        Value::Array(list) => list.iter().for_each(|v| assert_no_ground_truth(v, path)),
        _ => {}
    }
}

#[tokio::test]
async fn no_read_endpoint_returns_ground_truth() {
    let (server, records) = spawn_app_with_release().await;
    let mut paths = vec![
        "/api/v1/datasets".to_owned(),
        "/api/v1/datasets/mini".to_owned(),
        "/api/v1/datasets/mini/items".to_owned(),
    ];
    for r in &records {
        paths.push(format!(
            "/api/v1/datasets/mini/items/{}",
            r["id"].as_str().expect("id")
        ));
    }
    for path in paths {
        let text = server.get(&path).await.text().await.expect("body");
        let value: Value = serde_json::from_str(&text).expect("json");
        assert_no_ground_truth(&value, &path);
        assert!(!text.contains("gt_answer"), "{path} mentions gt_answer");
    }
    server.stop().await;
}

#[tokio::test]
async fn frames_are_png_with_strong_etag_immutable_and_304() {
    let (server, records) = spawn_app_with_release().await;
    let id = records[0]["id"].as_str().expect("id");
    let (_, item) = server
        .get_json(&format!("/api/v1/datasets/mini/items/{id}"))
        .await;
    let url = item["images"][1]["url"].as_str().expect("url").to_owned();

    let r = server.get(&url).await;
    assert_eq!(r.status(), StatusCode::OK);
    assert_eq!(r.headers()[CONTENT_TYPE], "image/png");
    let etag = r.headers()[ETAG].to_str().expect("etag").to_owned();
    assert!(
        etag.starts_with('"') && !etag.starts_with("W/"),
        "strong ETag: {etag}"
    );
    assert!(
        r.headers()[CACHE_CONTROL]
            .to_str()
            .expect("cc")
            .contains("immutable")
    );
    let bytes = r.bytes().await.expect("body");
    // records[0] is item n = 1; its image 1 shows key frame 1000 + 211 (see write_record).
    assert_eq!(bytes.as_ref(), png_bytes(1211, 1).as_slice());

    let r = server
        .client
        .get(server.url(&url))
        .header(IF_NONE_MATCH, &etag)
        .send()
        .await
        .expect("conditional GET");
    assert_eq!(r.status(), StatusCode::NOT_MODIFIED);
    assert_eq!(r.headers()[ETAG].to_str().expect("etag"), etag);
    assert!(r.bytes().await.expect("body").is_empty());

    let r = server
        .client
        .get(server.url(&url))
        .header(IF_NONE_MATCH, "\"something-else\"")
        .send()
        .await
        .expect("conditional GET");
    assert_eq!(r.status(), StatusCode::OK);

    let missing = format!("/api/v1/frames/{}", "0".repeat(64));
    assert_eq!(server.get(&missing).await.status(), StatusCode::NOT_FOUND);
    assert_eq!(
        server.get("/api/v1/frames/xyz").await.status(),
        StatusCode::NOT_FOUND
    );
    server.stop().await;
}

#[tokio::test]
async fn item_json_follows_a_replacing_import_made_while_serving() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let mut records = write_release(&root, &[3]);
    let server = {
        let root = root.clone();
        spawn_app_with(|pool, _| async move {
            import(&pool, &root, &options("mini")).await;
        })
        .await
    };
    let id = records[0]["id"].as_str().expect("id").to_owned();
    let path = format!("/api/v1/datasets/mini/items/{id}");
    let (_, before) = server.get_json(&path).await;
    assert!(before["question"].as_str().expect("q").contains("object 1"));

    let q = records[0]["question"]
        .as_str()
        .expect("q")
        .replace("object 1", "object one");
    records[0]["question"] = Value::String(q);
    write_qa_file(
        &root,
        &records.iter().map(Value::to_string).collect::<Vec<_>>(),
    );
    let mut replace = options("mini");
    replace.replace = true;
    let report = import(&server.pool, &root, &replace).await;
    assert_eq!(report.replaced_items, 1);

    // The cache is dropped within one poll interval of the content generation changing.
    let mut updated = false;
    for _ in 0..40 {
        let (_, now) = server.get_json(&path).await;
        if now["question"].as_str().expect("q").contains("object one") {
            updated = true;
            break;
        }
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    }
    assert!(updated, "item JSON still stale after 4 s");
    server.stop().await;
}

#[tokio::test]
async fn a_replacing_import_removes_the_replaced_items_verdicts_and_keeps_the_others() {
    let (server, records) = spawn_app_with_release().await;
    let (_, token) = api_token(&server.pool, "modeller", Role::Submitter, None, None).await;
    let id = submit_to(
        &server,
        "mini",
        "model=oracle",
        &token,
        ground_truth_answers(&records),
    )
    .await
    .id();
    let verdicts = format!("SELECT count(*) FROM submission_items WHERE submission = {id}");
    let all = records.len() as i64;
    assert_eq!(count(&server.pool, &verdicts).await, all);

    // Two items change; the release is imported again over them.
    let root = server.dir().join("release");
    let mut lines: Vec<String> = records.iter().map(Value::to_string).collect();
    let changed = with_changed_questions(&records[..2]);
    lines[..2].clone_from_slice(&changed);
    write_qa_file(&root, &lines);
    let mut replace = options("mini");
    replace.replace = true;
    let report = import(&server.pool, &root, &replace).await;
    assert_eq!(report.replaced_items, 2);

    assert_eq!(count(&server.pool, &verdicts).await, all - 2);
    let orphans = "SELECT count(*) FROM submission_items v \
                   WHERE NOT EXISTS (SELECT 1 FROM items i WHERE i.id = v.item)";
    assert_eq!(count(&server.pool, orphans).await, 0);
    server.stop().await;
}
