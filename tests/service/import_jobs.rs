//! Imports queued over the API from the server's import folder and worked by a job worker:
//! the dataset arrives as `enact-hub import` would write it, a refusal for the release's
//! content ends the job with every problem, paths outside the folder are refused, and a job
//! started again after an interruption resumes after the last committed batch.

use std::sync::Arc;
use std::time::Duration;

use enact_hub::app::import::{ImportObserver, ImportOptions, ImportProgress, import_release};
use enact_hub::app::jobs::{self, JobId, JobSettings, JobState, Worker};
use enact_hub::app::{self, AppError, Hub};
use enact_hub::core::credentials::Role;
use enact_hub::web::WebConfig;
use serde_json::{Value, json};

use crate::helpers::*;

/// Waits until job `id` has ended (done, failed or cancelled) and returns its view.
async fn ended(hub: &Hub, id: JobId) -> jobs::JobView {
    for _ in 0..1500 {
        let job = jobs::view(hub, id).await.expect("the job");
        if ["done", "failed", "cancelled"].contains(&job.state.as_str()) {
            return job;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    panic!("{id} never ended: {:?}", jobs::view(hub, id).await);
}

fn worker(hub: &Hub) -> Worker {
    Worker::spawn(
        hub.clone(),
        app::job_handlers(),
        JobSettings {
            poll: Duration::from_millis(20),
            ..JobSettings::default()
        },
    )
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_admin_imports_a_release_from_the_import_folder_as_a_job() {
    let dir = tempfile::tempdir().expect("tempdir");
    let folder = dir.path().join("imports");
    let records = write_balanced_release(&folder.join("release"), &[3, 4], 30);
    std::fs::write(folder.join("not-a-release.txt"), "hello").expect("a stray file");
    let outside = dir.path().join("elsewhere");
    write_balanced_release(&outside, &[3], 10);
    let (pool, _) = fresh_db_located(&dir).await;
    let hub = Hub::from(pool.clone())
        .with_kept(enact_hub::app::import_jobs::ImportDir(Some(folder.clone())));
    let server_dir = tempfile::tempdir().expect("tempdir");
    let server = serve_hub(hub.clone(), pool.clone(), server_dir, &WebConfig::default()).await;
    let (_, submitter) = api_token(&pool, "team", Role::Submitter, None, None).await;
    let (_, admin) = api_token(&pool, "root", Role::Admin, None, None).await;
    let queue = |token: &str, body: Value| {
        server
            .call(reqwest::Method::POST, "/api/v1/admin/imports")
            .bearer(token)
            .json(&body)
    };

    queue(&submitter, json!({"path": "release"}))
        .expect(403)
        .await;
    let escape = queue(&admin, json!({"path": "../elsewhere"}))
        .expect(400)
        .await;
    assert!(
        escape.error().contains("leaves the server's import folder"),
        "{}",
        escape.text
    );
    assert_eq!(escape.json()["code"], "import_path_leaves_folder");
    assert_eq!(escape.json()["details"]["path"], "../elsewhere");
    let absolute = queue(&admin, json!({"path": outside.display().to_string()}))
        .expect(400)
        .await;
    assert!(absolute.error().contains("relative"), "{}", absolute.text);
    assert_eq!(absolute.json()["code"], "import_path_not_relative");
    let missing = queue(&admin, json!({"path": "nope"})).expect(404).await;
    assert!(missing.error().contains("nope"), "{}", missing.text);
    assert_eq!(missing.json()["code"], "import_path_missing");
    let stray = queue(&admin, json!({"path": "not-a-release.txt"}))
        .expect(400)
        .await;
    assert!(stray.error().starts_with("path:"), "{}", stray.text);
    queue(&admin, json!({"path": "release", "colour": 1}))
        .expect(422)
        .await;

    let queued = queue(&admin, json!({"path": "release", "dataset": "queued"}))
        .expect(202)
        .await
        .json();
    let id = JobId(queued["job"].as_i64().expect("a job id"));
    let again = queue(&admin, json!({"path": "release", "dataset": "queued"}))
        .expect(409)
        .await;
    assert!(
        again.error().contains("already importing"),
        "{}",
        again.text
    );

    let working = worker(&hub);
    let job = ended(&hub, id).await;
    working.stop().await;
    assert_eq!(job.state, "done", "{job:?}");
    assert_eq!(job.kind, "import");
    assert_eq!(job.progress["outcome"], "imported", "{}", job.progress);
    assert_eq!(job.progress["report"]["items_written"], records.len());
    assert_eq!(
        count(&pool, "SELECT count(*) FROM items i JOIN datasets d ON d.id = i.dataset_id WHERE d.name = 'queued'").await,
        records.len() as i64
    );
    // The same release through the command line's path gives the same dataset.
    import(&pool, &folder.join("release"), &options("by-hand")).await;
    assert_eq!(
        dataset_digest(&pool, "queued").await,
        dataset_digest(&pool, "by-hand").await
    );
    let shown = server
        .call(
            reqwest::Method::GET,
            &format!("/api/v1/admin/jobs/{}", id.0),
        )
        .bearer(&admin)
        .expect(200)
        .await
        .json();
    assert_eq!(shown["progress"]["dataset"], "queued");
    server
        .call(reqwest::Method::GET, "/api/v1/admin/jobs/999999")
        .bearer(&admin)
        .expect(404)
        .await;

    // Invalid lines: the job ends with every problem in its progress, nothing imported.
    let broken = folder.join("broken");
    let mut lines: Vec<String> = write_balanced_release(&broken, &[3], 10)
        .iter()
        .map(Value::to_string)
        .collect();
    lines[2] = "{not json".to_owned();
    write_qa_file(&broken, &lines);
    let queued = queue(&admin, json!({"path": "broken"}))
        .expect(202)
        .await
        .json();
    let refused_id = JobId(queued["job"].as_i64().expect("a job id"));
    let working = worker(&hub);
    let refused = ended(&hub, refused_id).await;
    working.stop().await;
    assert_eq!(refused.state, "done", "not retried: {refused:?}");
    assert_eq!(
        refused.progress["outcome"], "refused",
        "{}",
        refused.progress
    );
    assert!(
        refused.progress["details"].to_string().contains("line 3"),
        "{}",
        refused.progress
    );
    assert_eq!(
        count(&pool, "SELECT count(*) FROM datasets WHERE name = 'broken'").await,
        0
    );
    assert_eq!(count(&pool, "SELECT count(*) FROM staged_imports").await, 0);

    // Without an import folder, a server refuses, saying how to turn it on.
    let bare = Hub::from(pool.clone());
    let refused = app::import_jobs::request(
        &bare,
        &tester(),
        &app::import_jobs::ImportRequest {
            path: "release".into(),
            dataset: None,
            replace: false,
            skip_invalid: false,
        },
    )
    .await
    .expect_err("no import folder");
    assert!(
        refused.to_string().contains("ENACT_HUB_IMPORT_DIR"),
        "{refused}"
    );
    assert!(
        matches!(
            refused,
            AppError::Refused(app::refusal::Refusal::ImportFolderUnset)
        ),
        "{refused:?}"
    );
}

/// An import interrupted after some batches (a killed server), then queued as a job: the job
/// resumes after the committed batches and the dataset is the one an uninterrupted import makes.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_import_job_resumes_after_the_committed_batches() {
    let dir = tempfile::tempdir().expect("tempdir");
    let folder = dir.path().join("imports");
    let root = folder.join("release");
    write_balanced_release(&root, &[3, 5], 40);
    let (pool, _) = fresh_db_located(&dir).await;
    let hub = Hub::from(pool.clone())
        .with_kept(enact_hub::app::import_jobs::ImportDir(Some(folder.clone())));

    // The first run stops (as a paused job does) after three batches of 8 lines.
    let batches = Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let seen = Arc::clone(&batches);
    let stopping = ImportOptions {
        batch_lines: 8,
        progress: Some(ImportObserver(Arc::new(move |p: &ImportProgress| {
            if !p.finished {
                seen.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
            }
        }))),
        stop: Some(enact_hub::app::import::ImportStop(Arc::new(move || {
            batches.load(std::sync::atomic::Ordering::SeqCst) > 3
        }))),
        ..crate::helpers::options("resumed")
    };
    let stopped = import_release(&hub, &tester(), &root, &stopping)
        .await
        .expect_err("stopped");
    assert!(
        stopped.to_string().contains("run it again to resume"),
        "{stopped}"
    );
    assert_eq!(count(&pool, "SELECT count(*) FROM staged_imports").await, 1);

    // The job runs the same file with the command line's default batch size: a resume needs
    // the same options, so it is asked with the same dataset and flags.
    let job = app::import_jobs::request(
        &hub,
        &tester(),
        &app::import_jobs::ImportRequest {
            path: "release".into(),
            dataset: Some("resumed".into()),
            replace: false,
            skip_invalid: false,
        },
    )
    .await
    .expect("queued");
    let working = worker(&hub);
    let done = ended(&hub, job).await;
    working.stop().await;
    assert_eq!(done.state, JobState::Done.as_str(), "{done:?}");
    assert_eq!(done.progress["outcome"], "imported", "{}", done.progress);
    let resumed = done.progress["report"]["resumed_rows"]
        .as_u64()
        .unwrap_or(0);
    assert!(
        resumed >= 16,
        "resumed after {resumed} rows: {}",
        done.progress
    );
    import(&pool, &root, &options("whole")).await;
    assert_eq!(
        dataset_digest(&pool, "resumed").await,
        dataset_digest(&pool, "whole").await
    );
}
