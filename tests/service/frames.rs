//! Frames in the database, in a local folder (`file://`) and in S3 (a real S3-compatible server:
//! `scripts/test.sh` starts moto on loopback and exports `AWS_ENDPOINT`): import, serving with
//! ETags and 304s, archives, presigned redirects, and `frames migrate` out, between stores and
//! back, interrupted and resumed.

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

use enact_hub::app::Hub;
use enact_hub::app::frames::{self, FrameStore};
use enact_hub::app::import::import_release;
use enact_hub::store::Pool;
use enact_hub::web::WebConfig;
use reqwest::StatusCode;
use reqwest::header::{CACHE_CONTROL, CONTENT_SECURITY_POLICY, ETAG, IF_NONE_MATCH, LOCATION};
use serde_json::Value;
use sha2::{Digest, Sha256};
use tempfile::TempDir;

use crate::helpers::*;

#[derive(Debug, Clone, Copy)]
enum Backend {
    Database,
    Folder,
    S3,
}

const BACKENDS: [Backend; 3] = [Backend::Database, Backend::Folder, Backend::S3];

/// The S3 endpoint of the run, or `None` (the test is then skipped, unless the run must not
/// skip: under CI, by the one rule of [`crate::fixtures::must_not_skip`], or when
/// `ENACT_HUB_REQUIRE_S3` says so, as `scripts/test.sh` does after starting its S3 server).
fn s3_endpoint() -> Option<String> {
    match std::env::var("AWS_ENDPOINT") {
        Ok(endpoint) if !endpoint.is_empty() => Some(endpoint),
        _ => {
            assert!(
                !crate::fixtures::must_not_skip()
                    && std::env::var_os("ENACT_HUB_REQUIRE_S3").is_none(),
                "AWS_ENDPOINT is unset but this run must not skip (CI or ENACT_HUB_REQUIRE_S3 \
                 is set): no S3 server to test against (scripts/test.sh starts one)"
            );
            eprintln!("no S3 server (AWS_ENDPOINT unset; scripts/test.sh starts one): skipping S3");
            None
        }
    }
}

/// A new, empty bucket on the run's S3 server, as `s3://bucket/prefix`.
async fn new_bucket(endpoint: &str) -> String {
    static NEXT: AtomicU32 = AtomicU32::new(0);
    let bucket = format!(
        "enact-hub-test-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    );
    let r = reqwest::Client::new()
        .put(format!("{}/{bucket}", endpoint.trim_end_matches('/')))
        .send()
        .await
        .expect("create a bucket");
    assert!(r.status().is_success(), "create bucket: {}", r.status());
    format!("s3://{bucket}/frames")
}

/// The frame store of `backend` (a folder under `dir`, or a new bucket), or `None` when the
/// run has no S3 server.
async fn store_of(backend: Backend, dir: &Path) -> Option<FrameStore> {
    let url = match backend {
        Backend::Database => frames::DATABASE.to_owned(),
        Backend::Folder => format!("file://{}", dir.join("objects").display()),
        Backend::S3 => new_bucket(&s3_endpoint()?).await,
    };
    Some(FrameStore::parse(&url).unwrap_or_else(|e| panic!("{url}: {e}")))
}

/// Every image file of the release: `(path, bytes)`.
fn release_images(root: &Path, records: &[Value]) -> Vec<(String, Vec<u8>)> {
    records
        .iter()
        .flat_map(|r| r["images"].as_array().expect("images").clone())
        .map(|p| {
            let p = p.as_str().expect("path").to_owned();
            let bytes = std::fs::read(root.join(&p)).expect("read image");
            (p, bytes)
        })
        .collect()
}

fn sha256(bytes: &[u8]) -> String {
    hex::encode(Sha256::digest(bytes))
}

/// Checks that the server answers every image of the release with its bytes, a strong ETag,
/// a year's `immutable` caching, and a 304 to a request that has it.
async fn assert_serves(server: &TestServer, images: &[(String, Vec<u8>)], backend: Backend) {
    for (path, bytes) in images {
        let hash = sha256(bytes);
        let url = format!("/api/v1/frames/{hash}");
        let r = server.get(&url).await;
        assert_eq!(r.status(), StatusCode::OK, "{backend:?}: {path}");
        assert_eq!(r.headers()[ETAG], format!("\"{hash}\"").as_str());
        assert!(
            r.headers()[CACHE_CONTROL]
                .to_str()
                .expect("cache-control")
                .contains("immutable")
        );
        assert_eq!(
            r.bytes().await.expect("body").as_ref(),
            bytes.as_slice(),
            "{backend:?}: {path}"
        );
        let again = server
            .client
            .get(server.url(&url))
            .header(IF_NONE_MATCH, format!("\"{hash}\""))
            .send()
            .await
            .expect("conditional GET");
        assert_eq!(again.status(), StatusCode::NOT_MODIFIED, "{backend:?}");
    }
}

/// The release archive's files: path → bytes.
async fn archive_files(server: &TestServer, dataset: &str) -> HashMap<String, Vec<u8>> {
    let r = server
        .get(&format!("/api/v1/datasets/{dataset}/archive"))
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    let body = r.bytes().await.expect("archive");
    let mut files = HashMap::new();
    let mut archive = tar::Archive::new(body.as_ref());
    for entry in archive.entries().expect("a tar archive") {
        let mut entry = entry.expect("entry");
        let path = entry.path().expect("path").display().to_string();
        let mut bytes = Vec::new();
        entry.read_to_end(&mut bytes).expect("read entry");
        files.insert(path, bytes);
    }
    files
}

async fn counts(hub: &Hub) -> (u64, u64) {
    frames::count_by_place(hub).await.expect("count frames")
}

#[tokio::test]
async fn every_backend_imports_serves_and_archives_the_same_frames() {
    for backend in BACKENDS {
        let dir = tempfile::tempdir().expect("tempdir");
        let Some(store) = store_of(backend, dir.path()).await else {
            continue;
        };
        let pool = fresh_db(&dir).await;
        let hub = Hub::from(pool.clone()).with_frame_store(store.clone(), None);
        let root = dir.path().join("release");
        let records = write_release(&root, &[3, 4]);
        let report = import_release(&hub, &tester(), &root, &options("mini"))
            .await
            .unwrap_or_else(|e| panic!("{backend:?}: import failed: {e}"));
        let images = release_images(&root, &records);
        assert_eq!(report.new_frames, images.len());
        let held = counts(&hub).await;
        match store.objects() {
            None => assert_eq!(held, (images.len() as u64, 0), "{backend:?}"),
            Some(objects) => {
                assert_eq!(held, (0, images.len() as u64), "{backend:?}");
                for (_, bytes) in &images {
                    let stored = objects.get(&sha256(bytes)).await.expect("read object");
                    assert_eq!(stored.as_deref(), Some(bytes.as_slice()), "{backend:?}");
                }
            }
        }
        // Importing the same release again stores nothing new anywhere.
        let again = import_release(&hub, &tester(), &root, &options("mini"))
            .await
            .expect("re-import");
        assert_eq!(again.new_frames, 0);

        let server = serve_hub(hub, pool, dir, &WebConfig::default()).await;
        assert_serves(&server, &images, backend).await;
        let missing = format!("/api/v1/frames/{}", "0".repeat(64));
        assert_eq!(server.get(&missing).await.status(), StatusCode::NOT_FOUND);
        let archived = archive_files(&server, "mini").await;
        for (path, bytes) in &images {
            assert_eq!(
                archived.get(path).map(Vec::as_slice),
                Some(bytes.as_slice()),
                "{backend:?}: {path} in the archive"
            );
        }
        server.stop().await;
    }
}

/// Imports a release of 108 frames with the bytes in the database.
async fn database_with_release(dir: &TempDir) -> (Pool, Vec<(String, Vec<u8>)>) {
    let pool = fresh_db(dir).await;
    let root = dir.path().join("release");
    let records = write_balanced_release(&root, &[3, 4, 5, 6], 3);
    import(&pool, &root, &options("mini")).await;
    (pool, release_images(&root, &records))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_migration_interrupted_midway_serves_every_frame_and_resumes() {
    for backend in [Backend::Folder, Backend::S3] {
        let dir = tempfile::tempdir().expect("tempdir");
        let Some(target) = store_of(backend, dir.path()).await else {
            continue;
        };
        let (pool, images) = database_with_release(&dir).await;
        let total = images.len() as u64;
        let hub = Hub::from(pool.clone());
        assert_eq!(counts(&hub).await, (total, 0));

        // A crash after the first batch: its frames are moved, the rest are not.
        let (moving_hub, to) = (hub.clone(), target.clone());
        let crashed = tokio::spawn(async move {
            frames::migrate(&moving_hub, &FrameStore::Database, &to, |done, total| {
                assert!(done == 0 || done == total, "crash after {done} of {total}");
            })
            .await
        })
        .await;
        assert!(crashed.is_err(), "{backend:?}: the migration was to crash");
        let (here, elsewhere) = counts(&hub).await;
        assert!(
            here > 0 && elsewhere > 0,
            "{backend:?}: {here} / {elsewhere}"
        );
        assert_eq!(here + elsewhere, total);

        // In the middle, a server with the target configured serves every frame.
        let serving = hub.clone().with_frame_store(target.clone(), None);
        let server = serve_hub(
            serving,
            pool.clone(),
            tempfile::tempdir().expect("tempdir"),
            &WebConfig::default(),
        )
        .await;
        assert_serves(&server, &images, backend).await;
        server.stop().await;

        // Run again: it carries on, then has nothing left to do.
        let resumed = frames::migrate(&hub, &FrameStore::Database, &target, |_, _| {})
            .await
            .expect("resume");
        assert_eq!(resumed.moved, here, "{backend:?}");
        assert_eq!(resumed.already_there, elsewhere, "{backend:?}");
        assert_eq!(counts(&hub).await, (0, total));
        let idle = frames::migrate(&hub, &FrameStore::Database, &target, |_, _| {})
            .await
            .expect("run again");
        assert_eq!((idle.moved, idle.already_there), (0, total));

        // To another store, copying from this one; then back into the database.
        let other = FrameStore::parse(&format!(
            "file://{}",
            dir.path().join("other-objects").display()
        ))
        .expect("folder store");
        let copied = frames::migrate(&hub, &target, &other, |_, _| {})
            .await
            .expect("copy between stores");
        assert_eq!(copied.moved, total);
        let back = frames::migrate(&hub, &other, &FrameStore::Database, |_, _| {})
            .await
            .expect("back into the database");
        assert_eq!(back.moved, total);
        assert_eq!(counts(&hub).await, (total, 0));
        let server = serve_hub(
            hub,
            pool,
            tempfile::tempdir().expect("tempdir"),
            &WebConfig::default(),
        )
        .await;
        assert_serves(&server, &images, backend).await;
        server.stop().await;
        drop(dir);
    }
}

#[tokio::test]
async fn moving_back_without_naming_the_store_is_refused_with_what_to_do() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (pool, images) = database_with_release(&dir).await;
    let hub = Hub::from(pool);
    let folder = store_of(Backend::Folder, dir.path()).await.expect("folder");
    frames::migrate(&hub, &FrameStore::Database, &folder, |_, _| {})
        .await
        .expect("move out");
    let e = frames::migrate(
        &hub,
        &FrameStore::Database,
        &FrameStore::Database,
        |_, _| {},
    )
    .await
    .expect_err("no source");
    assert!(
        e.to_string().contains(&format!(
            "{} frames are held in object storage",
            images.len()
        )),
        "{e}"
    );
    assert!(e.to_string().contains("--from URL"), "{e}");

    // A frame missing from the store it is said to be in is named.
    let gone = sha256(&images[0].1);
    let objects = dir
        .path()
        .join("objects")
        .join(&gone[..2])
        .join(format!("{gone}.png"));
    std::fs::remove_file(&objects).expect("remove one object");
    let e = frames::migrate(&hub, &folder, &FrameStore::Database, |_, _| {})
        .await
        .expect_err("missing object");
    assert!(
        e.to_string()
            .contains(&format!("frame {gone} is missing from file://")),
        "{e}"
    );
}

#[tokio::test]
async fn a_frame_held_elsewhere_on_a_server_without_the_store_is_a_503_that_says_so() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (pool, images) = database_with_release(&dir).await;
    let hub = Hub::from(pool.clone());
    let folder = store_of(Backend::Folder, dir.path()).await.expect("folder");
    frames::migrate(&hub, &FrameStore::Database, &folder, |_, _| {})
        .await
        .expect("move out");
    let server = serve_hub(hub, pool, dir, &WebConfig::default()).await;
    let (status, body) = server
        .get_json(&format!("/api/v1/frames/{}", sha256(&images[0].1)))
        .await;
    assert_eq!(status, StatusCode::SERVICE_UNAVAILABLE);
    let error = body["error"].as_str().expect("error");
    assert!(error.contains("held in object storage"), "{error}");
    assert!(error.contains("ENACT_HUB_FRAMES"), "{error}");
    server.stop().await;
}

#[tokio::test]
async fn an_import_whose_frames_cannot_be_written_stores_nothing() {
    if s3_endpoint().is_none() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let pool = fresh_db(&dir).await;
    let missing = FrameStore::parse("s3://enact-hub-no-such-bucket/frames").expect("url");
    let hub = Hub::from(pool.clone()).with_frame_store(missing, None);
    let root = dir.path().join("release");
    write_release(&root, &[3]);
    let e = import_release(&hub, &tester(), &root, &options("mini"))
        .await
        .expect_err("the bucket does not exist");
    let message = e.to_string();
    assert!(
        message.contains("frame storage s3://enact-hub-no-such-bucket/frames"),
        "{message}"
    );
    assert!(message.contains("nothing was imported"), "{message}");
    let items = count(&pool, "SELECT count(*) FROM items").await;
    let frames = count(&pool, "SELECT count(*) FROM frames").await;
    assert_eq!((items, frames), (0, 0));
}

#[tokio::test]
async fn s3_frames_redirect_to_a_presigned_url_the_pages_allow() {
    let Some(endpoint) = s3_endpoint() else {
        return;
    };
    let dir = tempfile::tempdir().expect("tempdir");
    let store = store_of(Backend::S3, dir.path()).await.expect("s3");
    let pool = fresh_db(&dir).await;
    let hub = Hub::from(pool.clone()).with_frame_store(store, Some(Duration::from_secs(600)));
    let root = dir.path().join("release");
    let records = write_release(&root, &[3]);
    import_release(&hub, &tester(), &root, &options("mini"))
        .await
        .expect("import");
    let images = release_images(&root, &records);
    let server = serve_hub(hub, pool, dir, &WebConfig::default()).await;
    let no_follow = reqwest::Client::builder()
        .redirect(reqwest::redirect::Policy::none())
        .build()
        .expect("client");
    let (_, bytes) = &images[0];
    let hash = sha256(bytes);
    let r = no_follow
        .get(server.url(&format!("/api/v1/frames/{hash}")))
        .send()
        .await
        .expect("GET frame");
    assert_eq!(r.status(), StatusCode::TEMPORARY_REDIRECT);
    let location = r.headers()[LOCATION].to_str().expect("location").to_owned();
    let origin = endpoint.trim_end_matches('/');
    assert!(location.starts_with(origin), "{location}");
    assert!(location.contains("X-Amz-Signature="), "{location}");
    let cache = r.headers()[CACHE_CONTROL].to_str().expect("cc").to_owned();
    assert_eq!(cache, "private, max-age=300");
    let policy = r.headers()[CONTENT_SECURITY_POLICY]
        .to_str()
        .expect("csp")
        .to_owned();
    assert!(
        policy.contains(&format!("img-src 'self' data: {origin};")),
        "{policy}"
    );
    let fetched = no_follow
        .get(&location)
        .send()
        .await
        .expect("presigned GET");
    assert_eq!(fetched.status(), StatusCode::OK);
    assert_eq!(
        fetched.bytes().await.expect("body").as_ref(),
        bytes.as_slice()
    );
    // A client that has the frame still gets a 304 without a redirect.
    let r = no_follow
        .get(server.url(&format!("/api/v1/frames/{hash}")))
        .header(IF_NONE_MATCH, format!("\"{hash}\""))
        .send()
        .await
        .expect("conditional GET");
    assert_eq!(r.status(), StatusCode::NOT_MODIFIED);
    server.stop().await;
}

#[test]
fn the_command_line_reports_and_moves_frames_and_refuses_unknown_stores() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    write_release(&root, &[3, 5]);
    let db = dir.path().join("cli.db");
    let run = |args: &[&str]| {
        let out = enact_hub()
            .args(args)
            .arg("--db")
            .arg(&db)
            .env_remove("ENACT_HUB_FRAMES")
            .output()
            .expect("run enact-hub");
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let folder = format!("file://{}", dir.path().join("objects").display());
    let (ok, _, stderr) = run(&["import", root.to_str().expect("utf-8")]);
    assert!(ok, "{stderr}");
    let (ok, stdout, _) = run(&["frames", "status"]);
    assert!(ok);
    assert_eq!(
        stdout.trim(),
        "16 frames in the database, 0 in object storage"
    );
    let (ok, _, stderr) = run(&["frames", "migrate", "--to", &folder]);
    assert!(ok, "{stderr}");
    assert!(stderr.contains("moved 16 frames"), "{stderr}");
    assert!(stderr.contains(&format!("to {folder}")), "{stderr}");
    let (_, stdout, _) = run(&["frames", "status"]);
    assert_eq!(
        stdout.trim(),
        "0 frames in the database, 16 in object storage"
    );
    let (ok, _, stderr) = run(&["frames", "migrate", "--to", "ftp://example/x"]);
    assert!(!ok);
    assert!(stderr.contains("unknown scheme \"ftp\""), "{stderr}");
    let (ok, _, stderr) = run(&["frames", "migrate", "--to", "database", "--from", &folder]);
    assert!(ok, "{stderr}");
    let (_, stdout, _) = run(&["frames", "status"]);
    assert_eq!(
        stdout.trim(),
        "16 frames in the database, 0 in object storage"
    );
}
