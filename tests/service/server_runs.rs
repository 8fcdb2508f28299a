//! Model runs started on the server: worked as jobs by the serving instance's worker, with
//! the API key named only by an allowed environment variable.

use std::time::{Duration, Instant};

use enact_hub::app::jobs::{self, JobControl, JobId, JobSettings, JobState, Worker};
use enact_hub::app::runs::{self, EndpointKeys, RunCalls};
use enact_hub::app::{AppError, Hub};
use enact_hub::core::credentials::Role;
use reqwest::Method;
use serde_json::{Value, json};

use crate::helpers::*;
use crate::runs::{
    SECRET_KEY, answer_text, assert_key_stored_nowhere, run_fixture, scripts, spec,
    stored_submission, task_accuracy,
};
use crate::standin::{StandIn, StandInConfig, Step};

pub const KEY_VARIABLE: &str = "STANDIN_API_KEY";

pub fn fast() -> JobSettings {
    JobSettings {
        lease: Duration::from_millis(900),
        poll: Duration::from_millis(20),
        max_running: 2,
        max_attempts: 3,
        retry_base: Duration::from_millis(50),
    }
}

pub fn keyed(hub: Hub) -> Hub {
    let keys = EndpointKeys::from_pairs([(KEY_VARIABLE.to_owned(), SECRET_KEY.to_owned())])
        .expect("an allowlist");
    hub.with_kept(keys)
}

fn calls(concurrency: usize) -> RunCalls {
    RunCalls {
        key_variable: Some(KEY_VARIABLE.to_owned()),
        concurrency,
        max_retries: 3,
        timeout_s: 5.0,
    }
}

/// How long a wait for the job or the endpoint may take before the test fails, saying what
/// it waited for: far beyond what any step needs on a loaded two-core machine.
const DEADLINE: Duration = Duration::from_secs(60);

/// Starts the run `name` of "mini" over the API against `standin` (as submitter "Stand-in")
/// and works it until it has submitted: the run's id and its submission's.
pub async fn run_to_submission(
    server: &TestServer,
    hub: &Hub,
    admin: &str,
    standin: &StandIn,
    name: &str,
) -> (i64, i64) {
    let started = server
        .call(Method::POST, "/api/v1/admin/runs")
        .bearer(admin)
        .json(&json!({
            "dataset": "mini", "endpoint": standin.endpoint(), "model": "standin-vl",
            "name": name, "temperature": 0, "key_variable": KEY_VARIABLE,
            "concurrency": 2, "timeout_s": 5, "submit_as": "Stand-in",
        }))
        .expect(202)
        .await
        .json();
    let run = started["run"].as_i64().expect("a run id");
    let worker = Worker::spawn(hub.clone(), enact_hub::app::job_handlers(), fast());
    let mut submission = None;
    for _ in 0..1500 {
        let shown = server
            .call(Method::GET, &format!("/api/v1/admin/runs/{run}"))
            .bearer(admin)
            .expect(200)
            .await
            .json();
        if shown["state"] == "done" {
            submission = shown["submission"].as_i64();
            break;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    worker.stop().await;
    (run, submission.expect("the run submitted"))
}

async fn wait_until(hub: &Hub, id: JobId, what: &str, done: impl Fn(&jobs::JobRow) -> bool) {
    let deadline = Instant::now() + DEADLINE;
    while Instant::now() < deadline {
        let job = jobs::get(hub, id).await.expect("read").expect("the job");
        if done(&job) {
            return;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    let job = jobs::get(hub, id).await.expect("read").expect("the job");
    panic!(
        "{id} never got {what} within {DEADLINE:?}: {job:?} {:?}",
        job.progress
    );
}

/// Waits until the stand-in has been asked `n` times in all.
async fn asked_at_least(standin: &StandIn, n: usize) {
    let deadline = Instant::now() + DEADLINE;
    while standin.total_requests() < n {
        assert!(
            Instant::now() < deadline,
            "the endpoint was asked {} times within {DEADLINE:?}, not {n}",
            standin.total_requests()
        );
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
}

async fn progress(hub: &Hub, id: JobId) -> Value {
    let job = jobs::get(hub, id).await.expect("read").expect("the job");
    serde_json::from_str(job.progress.as_deref().unwrap_or("null")).expect("json progress")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_run_started_on_the_server_is_worked_as_a_job_and_submits_what_the_endpoint_answered() {
    let (dir, pool, records) = run_fixture(2).await;
    let root = dir.path().join("release");
    // Every third item answered wrong: the scores must be the stand-in's, not all right.
    let standin = StandIn::start(StandInConfig {
        scripts: scripts(&root, &records, |i, r| {
            vec![Step::Answer(answer_text(r, i % 3 != 0))]
        }),
        ..StandInConfig::default()
    })
    .await;
    let hub = keyed(Hub::from(pool.clone()));
    let (run, job) = runs::start(&hub, &tester(), &spec(&standin, "served"), &calls(4))
        .await
        .expect("started");
    assert_eq!(run.name, "served");
    // A second start while the job has not ended is refused, naming the job.
    match runs::start(&hub, &tester(), &spec(&standin, "served"), &calls(4)).await {
        Err(AppError::Conflict(m)) => assert!(m.contains(&format!("job {}", job.0)), "{m}"),
        other => panic!("a second start was not refused: {other:?}"),
    }

    let worker = Worker::spawn(hub.clone(), enact_hub::app::job_handlers(), fast());
    wait_until(&hub, job, "done", |j| j.state == JobState::Done).await;
    worker.stop().await;

    let shown = progress(&hub, job).await;
    assert_eq!(shown["stage"], "submitted", "{shown}");
    assert_eq!(shown["done"], records.len());
    assert_eq!(shown["failed"], 0);
    let submission = shown["submission"].as_i64().expect("a submission");
    let run = runs::by_name(&hub, "served").await.expect("the run");
    assert_eq!(run.submission, Some(submission));
    let stored = stored_submission(&pool, submission).await;
    assert_eq!(stored.scores.coverage.answered, records.len());
    let right = (0..records.len()).filter(|i| i % 3 != 0).count();
    assert!((task_accuracy(&stored) - right as f64 / records.len() as f64).abs() < 1e-9);
    assert!(standin.calls().values().all(|c| c.requests == 1));
    assert!(
        standin
            .authorizations()
            .iter()
            .all(|a| a == &format!("Bearer {SECRET_KEY}"))
    );
    let audit = enact_hub::app::audit::list(
        &hub,
        enact_hub::core::audit::AuditFilter {
            action: Some("run".to_owned()),
            limit: 50,
            ..Default::default()
        },
    )
    .await
    .expect("the audit log");
    assert!(
        audit.iter().any(|e| e.action == "run.start"),
        "the start is audited"
    );
    assert_key_stored_nowhere(&hub, dir.path()).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_server_run_stopped_paused_and_resumed_never_asks_an_answered_item_again() {
    let (dir, pool, records) = run_fixture(4).await;
    let root = dir.path().join("release");
    let standin = StandIn::start(StandInConfig {
        scripts: scripts(&root, &records, |_, r| {
            vec![Step::Answer(answer_text(r, true))]
        }),
        latency: Duration::from_millis(60),
        ..StandInConfig::default()
    })
    .await;
    let hub = keyed(Hub::from(pool.clone()));
    let (_, job) = runs::start(&hub, &tester(), &spec(&standin, "resumed"), &calls(1))
        .await
        .expect("started");

    // The first instance stops gracefully part-way: the job is released, not failed.
    let first = Worker::spawn(hub.clone(), enact_hub::app::job_handlers(), fast());
    asked_at_least(&standin, 4).await;
    first.stop().await;
    let released = jobs::get(&hub, job).await.expect("read").expect("job");
    assert_eq!(released.state, JobState::Queued, "{released:?}");
    let asked = standin.total_requests();
    assert!(asked < records.len(), "the run was not stopped part-way");

    // A second instance on the same database carries on; an admin pauses and resumes it.
    let second = Worker::spawn(hub.clone(), enact_hub::app::job_handlers(), fast());
    asked_at_least(&standin, asked + 4).await;
    jobs::control(&hub, &tester(), job, JobControl::Pause)
        .await
        .expect("paused");
    wait_until(&hub, job, "paused and let go", |j| {
        j.state == JobState::Paused && j.lease_owner.is_none()
    })
    .await;
    let paused_at = standin.total_requests();
    tokio::time::sleep(Duration::from_millis(300)).await;
    assert_eq!(standin.total_requests(), paused_at, "asked while paused");
    assert!(paused_at < records.len(), "the pause came too late to test");
    jobs::control(&hub, &tester(), job, JobControl::Resume)
        .await
        .expect("resumed");
    wait_until(&hub, job, "done", |j| j.state == JobState::Done).await;
    second.stop().await;

    let calls = standin.calls();
    assert_eq!(calls.len(), records.len());
    assert!(
        calls.values().all(|c| c.requests == 1),
        "an item was asked twice: {calls:?}"
    );
    let shown = progress(&hub, job).await;
    assert_eq!(shown["stage"], "submitted", "{shown}");
    assert_eq!(shown["answered"], records.len());
    drop(dir);
}

#[tokio::test]
async fn a_key_variable_not_on_the_allowlist_is_refused_and_nothing_is_started() {
    let (_dir, pool, _) = run_fixture(1).await;
    let standin = StandIn::start(StandInConfig::default()).await;
    let hub = keyed(Hub::from(pool));
    let mut asked = calls(1);
    asked.key_variable = Some("ENACT_HUB_DATABASE_URL".to_owned());
    match runs::start(&hub, &tester(), &spec(&standin, "refused"), &asked).await {
        Err(AppError::Invalid(m)) => {
            assert!(
                m.contains("key_variable") && m.contains("ENACT_HUB_DATABASE_URL"),
                "{m}"
            );
            assert!(
                m.contains(KEY_VARIABLE),
                "the allowed names are listed: {m}"
            );
        }
        other => panic!("not refused: {other:?}"),
    }
    assert!(runs::list(&hub).await.expect("runs").is_empty());
    assert!(jobs::list(&hub, None, 10).await.expect("jobs").is_empty());
    assert_eq!(standin.total_requests(), 0);

    // The allowlist itself: names must be variables' names, and set.
    let unset = EndpointKeys::from_pairs([("EMPTY_KEY".to_owned(), String::new())]);
    assert!(matches!(unset, Err(AppError::Invalid(m)) if m.contains("EMPTY_KEY")));
    let bad = EndpointKeys::from_pairs([("1-KEY".to_owned(), "x".to_owned())]);
    assert!(matches!(bad, Err(AppError::Invalid(m)) if m.contains("1-KEY")));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_run_started_over_the_api_finishes_and_its_errors_name_the_field() {
    let (dir, pool, records) = run_fixture(1).await;
    let root = dir.path().join("release");
    let standin = StandIn::start(StandInConfig {
        scripts: scripts(&root, &records, |_, r| {
            vec![Step::Answer(answer_text(r, true))]
        }),
        ..StandInConfig::default()
    })
    .await;
    let hub = keyed(Hub::from(pool.clone()));
    let server = serve_hub(hub.clone(), pool.clone(), dir, &Default::default()).await;
    let (_, admin) = api_token(&pool, "root", Role::Admin, None, None).await;
    let body = |change: Value| {
        let mut body = json!({
            "dataset": "mini", "endpoint": standin.endpoint(), "model": "standin-vl",
            "name": "over-api", "temperature": 0, "key_variable": KEY_VARIABLE,
            "concurrency": 2, "timeout_s": 5, "submit_as": "Stand-in (API)",
        });
        for (k, v) in change.as_object().expect("an object") {
            body[k] = v.clone();
        }
        body
    };
    let mut replies = Vec::new();
    for (change, status, named) in [
        (
            json!({"key_variable": "ENACT_HUB_DATABASE_URL"}),
            400,
            "key_variable",
        ),
        (json!({"dataset": "nowhere"}), 404, "nowhere"),
        (json!({"endpoint": "ftp://example.org/v1"}), 400, "endpoint"),
        (json!({"concurrency": 0}), 400, "concurrency"),
        (json!({"price_input": -1}), 400, "price_input"),
    ] {
        let reply = server
            .call(Method::POST, "/api/v1/admin/runs")
            .bearer(&admin)
            .json(&body(change))
            .expect(status)
            .await;
        assert!(reply.text.contains(named), "{named}: {}", reply.text);
        replies.push(reply.text);
    }
    assert!(runs::list(&hub).await.expect("runs").is_empty());
    let priced: Value = serde_json::from_str(&replies[4]).expect("JSON");
    assert_eq!(priced["code"], "run_price", "{priced}");
    assert_eq!(priced["details"]["field"], "price_input", "{priced}");

    let started = server
        .call(Method::POST, "/api/v1/admin/runs")
        .bearer(&admin)
        .json(&body(json!({})))
        .expect(202)
        .await
        .json();
    let run = started["run"].as_i64().expect("a run id");
    assert_eq!(started["name"], "over-api");
    let worker = Worker::spawn(hub.clone(), enact_hub::app::job_handlers(), fast());
    let path = format!("/api/v1/admin/runs/{run}");
    let mut shown = Value::Null;
    for _ in 0..1500 {
        let reply = server
            .call(Method::GET, &path)
            .bearer(&admin)
            .expect(200)
            .await;
        replies.push(reply.text.clone());
        shown = reply.json();
        if shown["state"] == "done" {
            break;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    worker.stop().await;
    assert_eq!(shown["state"], "done", "{shown}");
    assert_eq!(shown["progress"]["stage"], "submitted", "{shown}");
    assert_eq!(shown["progress"]["answered"], records.len());
    assert!(shown["submission"].is_i64(), "{shown}");
    let listed = server
        .call(Method::GET, "/api/v1/admin/runs")
        .bearer(&admin)
        .expect(200)
        .await;
    assert!(
        listed
            .json()
            .as_array()
            .expect("a list")
            .iter()
            .any(|r| r["id"] == run)
    );
    replies.push(listed.text);
    // A finished run cannot be paused; an unknown change is named.
    let refused = server
        .call(Method::POST, &format!("{path}/pause"))
        .bearer(&admin)
        .expect(409)
        .await;
    assert!(refused.text.contains("done"), "{}", refused.text);
    let unknown = server
        .call(Method::POST, &format!("{path}/explode"))
        .bearer(&admin)
        .expect(400)
        .await;
    assert!(unknown.text.contains("explode"), "{}", unknown.text);
    // The key reached the endpoint and no reply.
    assert!(!standin.authorizations().is_empty());
    assert!(replies.iter().all(|r| !r.contains(SECRET_KEY)));
    server.stop().await;
}

/// The parameter `name` of `method path` in the OpenAPI document.
fn documented_param<'a>(doc: &'a Value, path: &str, method: &str, name: &str) -> &'a Value {
    doc["paths"][path][method]["parameters"]
        .as_array()
        .and_then(|ps| ps.iter().find(|p| p["name"] == name))
        .unwrap_or_else(|| panic!("{method} {path} documents no parameter {name}"))
}

/// Found by scripts/schemathesis.sh: run and job ids were documented as any string, so
/// `/admin/runs/abc` drew an undocumented 400 (and `/admin/jobs/abc` a plain-text one, from
/// axum's own extractor); `{change}` was any string; and a count sent as `3.0`, an integer to
/// JSON Schema, was refused with 422. Now the document says what the handlers read, a path
/// that is not an id is refused with the JSON `Error` body naming the parameter, and whole
/// floats are counts.
#[tokio::test]
async fn run_and_job_paths_and_counts_are_read_as_the_document_says() {
    let (dir, pool, _) = run_fixture(1).await;
    let hub = keyed(Hub::from(pool.clone()));
    let server = serve_hub(hub.clone(), pool.clone(), dir, &Default::default()).await;
    let (_, admin) = api_token(&pool, "root", Role::Admin, None, None).await;
    let doc = server
        .call(Method::GET, "/api/v1/openapi.json")
        .expect(200)
        .await
        .json();

    for (path, method, id) in [
        ("/api/v1/admin/runs/{run}", "get", "run"),
        ("/api/v1/admin/runs/{run}/responses", "get", "run"),
        ("/api/v1/runs/{run}/responses", "get", "run"),
        ("/api/v1/admin/runs/{run}/{change}", "post", "run"),
        ("/api/v1/admin/jobs/{job}", "get", "job"),
        ("/api/v1/admin/jobs/{job}/{change}", "post", "job"),
    ] {
        let schema = &documented_param(&doc, path, method, id)["schema"];
        assert_eq!(schema["type"], "integer", "{method} {path}: {schema}");
        assert!(
            doc["paths"][path][method]["responses"]["400"].is_object(),
            "{method} {path} documents its 400"
        );
        if method == "post" {
            let change = &documented_param(&doc, path, method, "change")["schema"];
            assert_eq!(
                change["enum"],
                json!(["pause", "resume", "cancel"]),
                "{path}"
            );
        }
    }
    for (method, path, named) in [
        (Method::GET, "/api/v1/admin/runs/abc", "`run`"),
        (Method::GET, "/api/v1/admin/runs/abc/responses", "`run`"),
        (Method::GET, "/api/v1/runs/abc/responses", "`run`"),
        (Method::POST, "/api/v1/admin/runs/abc/pause", "`run`"),
        (Method::GET, "/api/v1/admin/jobs/abc", "`job`"),
        (Method::POST, "/api/v1/admin/jobs/abc/pause", "`job`"),
    ] {
        let reply = server
            .call(method.clone(), path)
            .bearer(&admin)
            .expect(400)
            .await;
        assert_eq!(
            reply.headers["content-type"], "application/json",
            "{method} {path}: {}",
            reply.text
        );
        let error = reply.json()["error"]
            .as_str()
            .unwrap_or_default()
            .to_owned();
        assert!(error.contains(named), "{method} {path}: {error}");
    }

    let body = |change: Value| {
        let mut body = json!({
            "dataset": "mini", "endpoint": "http://127.0.0.1:9/v1", "model": "standin-vl",
            "name": "whole-floats", "key_variable": KEY_VARIABLE,
        });
        for (k, v) in change.as_object().expect("an object") {
            body[k] = v.clone();
        }
        body
    };
    for (change, status, named) in [
        (json!({"concurrency": 1.5}), 422, "concurrency"),
        (json!({"max_retries": -1}), 400, "max_retries"),
        (json!({"limit": 0.0}), 400, "limit"),
        (json!({"name": " "}), 400, "name"),
    ] {
        let reply = server
            .call(Method::POST, "/api/v1/admin/runs")
            .bearer(&admin)
            .json(&body(change))
            .expect(status)
            .await;
        assert!(reply.text.contains(named), "{named}: {}", reply.text);
    }
    let started = server
        .call(Method::POST, "/api/v1/admin/runs")
        .bearer(&admin)
        .json(&body(json!({
            "concurrency": 2.0, "max_retries": 3.0, "limit": 1.0, "max_tokens": 64.0,
        })))
        .expect(202)
        .await
        .json();
    let job = started["job"].as_i64().expect("a job id");
    let row = jobs::get(&hub, JobId(job))
        .await
        .expect("read the job")
        .expect("the job");
    let payload: Value = serde_json::from_str(&row.payload).expect("a JSON payload");
    assert_eq!(payload["calls"]["concurrency"], 2, "{payload}");
    assert_eq!(payload["calls"]["max_retries"], 3, "{payload}");
    assert_eq!(payload["limit"], 1, "{payload}");
    assert_eq!(payload["params"]["max_tokens"], 64, "{payload}");
}
