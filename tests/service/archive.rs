//! The dataset archive: an ENACT release that imports back to the same items, streamed, with
//! ground truth only for public datasets.

use std::collections::HashMap;
use std::path::Path;

use enact_hub::core::dataset::AnswerVisibility;
use enact_hub::store;

use crate::helpers::*;

async fn set_answers(server: &TestServer, answers: AnswerVisibility) {
    set_mini_answers(&server.pool, answers).await;
}

async fn content_hashes(pool: &enact_hub::store::Pool, dataset: &str) -> HashMap<String, String> {
    let mut conn = pool.acquire().await.expect("conn");
    let dataset = store::datasets::by_name(&mut conn, dataset)
        .await
        .expect("query")
        .expect("dataset");
    store::items::content_hashes(&mut conn, dataset.id)
        .await
        .expect("hashes")
}

/// Downloads the archive of "mini" and unpacks it into `into`; returns the raw bytes.
async fn download(server: &TestServer, into: &Path) -> (reqwest::header::HeaderMap, Vec<u8>) {
    let r = server.get("/api/v1/datasets/mini/archive").await;
    assert_eq!(r.status(), 200);
    let headers = r.headers().clone();
    assert_eq!(headers["content-type"], "application/x-tar");
    assert_eq!(
        headers["content-disposition"],
        "attachment; filename=\"mini.tar\""
    );
    assert!(
        headers.get("content-length").is_none(),
        "the archive is streamed, not built whole"
    );
    let bytes = r.bytes().await.expect("body").to_vec();
    tar::Archive::new(bytes.as_slice())
        .unpack(into)
        .expect("a valid tar archive");
    (headers, bytes)
}

#[tokio::test]
async fn a_public_dataset_archive_imports_back_to_the_same_items() {
    let (server, records) = spawn_app_with_release().await;
    set_answers(&server, AnswerVisibility::Public).await;
    let out = tempfile::tempdir().expect("tempdir");
    let (headers, _) = download(&server, out.path()).await;
    assert_eq!(headers["x-enact-ground-truth"], "included");

    let lines = std::fs::read_to_string(out.path().join("QA/enact_ordering.jsonl")).expect("QA");
    let lines: Vec<serde_json::Value> = lines
        .lines()
        .map(|l| serde_json::from_str(l).expect("json line"))
        .collect();
    assert_eq!(lines.len(), records.len());
    for (line, record) in lines.iter().zip(&records) {
        assert_eq!(line, record, "the record as it was imported, in file order");
    }

    assert_reimports_identically(&server, out.path()).await;
    server.stop().await;
}

#[tokio::test]
async fn a_hidden_dataset_archive_has_no_ground_truth_anywhere() {
    let (server, records) = spawn_app_with_release().await;
    // Hidden is the default; say it anyway.
    set_answers(&server, AnswerVisibility::Hidden).await;
    let out = tempfile::tempdir().expect("tempdir");
    let (headers, bytes) = download(&server, out.path()).await;
    assert_eq!(headers["x-enact-ground-truth"], "omitted");
    let raw = String::from_utf8_lossy(&bytes);
    assert!(!raw.contains("gt_answer") && !raw.contains("key_frame_ids"));
    let qa = std::fs::read_to_string(out.path().join("QA/enact_ordering.jsonl")).expect("QA");
    assert_eq!(qa.lines().count(), records.len());
    for (line, record) in qa.lines().zip(&records) {
        let line: serde_json::Value = serde_json::from_str(line).expect("json");
        assert_eq!(line["id"], record["id"]);
        assert_eq!(line["question"], record["question"]);
        assert_eq!(line["images"], record["images"]);
        for image in line["images"].as_array().expect("images") {
            assert!(out.path().join(image.as_str().expect("path")).is_file());
        }
    }
    // Without ground truth the importer refuses the file, as documented.
    let import = enact_hub()
        .arg("import")
        .arg(out.path())
        .arg("--db")
        .arg(out.path().join("copy.db"))
        .output()
        .expect("run enact-hub import");
    assert!(!import.status.success());
    server.stop().await;
}

#[tokio::test]
async fn an_unknown_dataset_has_no_archive() {
    let (server, _) = spawn_app_with_release().await;
    let (status, body) = server.get_json("/api/v1/datasets/nope/archive").await;
    assert_eq!(status, 404);
    assert!(body["error"].as_str().expect("msg").contains("nope"));
    let html = server
        .get("/datasets/mini")
        .await
        .text()
        .await
        .expect("page");
    assert!(html.contains("href=\"/api/v1/datasets/mini/archive\""));
    server.stop().await;
}

#[tokio::test]
async fn the_enact_sample_round_trips_through_its_archive() {
    let Some(fixtures) = fixtures_dir() else {
        return;
    };
    let sample = fixtures.join("enact-sample");
    let server = spawn_app_with(|pool, _| async move {
        import(&pool, &sample, &options("mini")).await;
    })
    .await;
    set_answers(&server, AnswerVisibility::Public).await;
    let out = tempfile::tempdir().expect("tempdir");
    download(&server, out.path()).await;
    // Line for line the release's own records (ENACT's field order and values).
    let original = std::fs::read_to_string(fixtures.join("enact-sample/QA/enact_ordering.jsonl"))
        .expect("sample QA");
    let written = std::fs::read_to_string(out.path().join("QA/enact_ordering.jsonl")).expect("QA");
    let parse = |text: &str| -> Vec<serde_json::Value> {
        text.lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| serde_json::from_str(l).expect("json"))
            .collect()
    };
    assert_eq!(parse(&written), parse(&original));
    assert_reimports_identically(&server, out.path()).await;
    server.stop().await;
}

/// Imports the extracted archive in `dir` into a new database with the enact-hub binary and
/// checks its items are those served (content hashes cover every field and every image byte).
async fn assert_reimports_identically(server: &TestServer, dir: &std::path::Path) {
    let db = dir.join("copy.db");
    let import = enact_hub()
        .arg("import")
        .arg(dir)
        .arg("--db")
        .arg(&db)
        .arg("--dataset")
        .arg("mini")
        .output()
        .expect("run enact-hub import");
    assert!(
        import.status.success(),
        "{}",
        String::from_utf8_lossy(&import.stderr)
    );
    let copy = store::Pool::Sqlite(store::open(&db).await.expect("open copy"));
    assert_eq!(
        content_hashes(&copy, "mini").await,
        content_hashes(&server.pool, "mini").await
    );
}
