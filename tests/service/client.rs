//! clients/enact_client.py end to end: a real server with a small dataset, a fake
//! OpenAI-compatible endpoint (an axum server here) that checks each prompt and its images and
//! answers deterministically, and the client run by python3 in between, over the checkout's
//! `enact_hub` package (`python/`).

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;
use std::sync::{Arc, Mutex};

use axum::Json;
use axum::extract::State;
use axum::http::{HeaderMap, StatusCode};
use axum::response::{IntoResponse, Response};
use enact_hub::core::credentials::Role;
use enact_hub::store;
use serde_json::{Value, json};

use crate::helpers::*;

const API_KEY: &str = "fake-endpoint-key";

/// What the fake endpoint knows about each item, found by its question text.
struct Expected {
    images: usize,
    reply: String,
}

#[derive(Default)]
struct FakeLog {
    calls: usize,
    /// Problems with what the client sent; the test fails if any.
    problems: Vec<String>,
    answered: Vec<String>,
}

struct Fake {
    by_question: HashMap<String, Expected>,
    log: Mutex<FakeLog>,
}

/// One transient failure of each kind first (429, then 503), then answers.
async fn chat_completions(
    State(fake): State<Arc<Fake>>,
    headers: HeaderMap,
    Json(request): Json<Value>,
) -> Response {
    let mut log = fake.log.lock().expect("log");
    log.calls += 1;
    match log.calls {
        1 => {
            return (
                StatusCode::TOO_MANY_REQUESTS,
                [("retry-after", "0")],
                "slow down",
            )
                .into_response();
        }
        2 => return (StatusCode::SERVICE_UNAVAILABLE, "busy").into_response(),
        _ => {}
    }
    if headers.get("authorization").and_then(|v| v.to_str().ok())
        != Some(&format!("Bearer {API_KEY}"))
    {
        log.problems.push("missing or wrong API key".to_owned());
    }
    if request["model"] != "fake-vlm" {
        log.problems
            .push(format!("model is {}, not fake-vlm", request["model"]));
    }
    let parts = request["messages"][0]["content"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    let images = parts
        .iter()
        .filter(|p| p["type"] == "image_url")
        .filter(|p| {
            p["image_url"]["url"]
                .as_str()
                .is_some_and(|u| u.starts_with("data:image/png;base64,iVBOR"))
        })
        .count();
    let question = parts
        .iter()
        .rev()
        .find(|p| p["type"] == "text")
        .and_then(|p| p["text"].as_str())
        .unwrap_or_default();
    let Some(expected) = fake.by_question.get(question) else {
        log.problems
            .push(format!("a prompt the dataset does not have: {question:?}"));
        return (StatusCode::BAD_REQUEST, "unknown prompt").into_response();
    };
    if images != expected.images {
        log.problems.push(format!(
            "{images} PNG images sent, the item has {}",
            expected.images
        ));
    }
    log.answered.push(question.to_owned());
    Json(json!({
        "id": "chatcmpl-test",
        "object": "chat.completion",
        "choices": [{"index": 0, "message": {"role": "assistant", "content": expected.reply}, "finish_reason": "stop"}],
    }))
    .into_response()
}

fn python_with_requests() -> bool {
    Command::new("python3")
        .args(["-c", "import requests"])
        .output()
        .is_ok_and(|o| o.status.success())
}

async fn submitter_token(server: &TestServer) -> String {
    api_token(&server.pool, "team-a", Role::Submitter, None, None)
        .await
        .1
}

/// A fake chat endpoint for `records`. Items 0 and 1 get the right order, item 2 prose with no
/// order in it, item 3 the reversed order.
async fn spawn_fake(records: &[Value]) -> (Arc<Fake>, String, tokio::task::JoinHandle<()>) {
    let mut by_question = HashMap::new();
    for (i, r) in records.iter().enumerate() {
        let mut gt: Vec<u64> = r["gt_answer"]
            .as_array()
            .expect("gt")
            .iter()
            .map(|v| v.as_u64().expect("label"))
            .collect();
        let reply = match i {
            0 | 1 => format!("The order is {gt:?}."),
            2 => "I cannot tell from these pictures.".to_owned(),
            _ => {
                gt.reverse();
                format!("{gt:?}")
            }
        };
        by_question.insert(
            r["question"].as_str().expect("question").to_owned(),
            Expected {
                images: r["images"].as_array().expect("images").len(),
                reply,
            },
        );
    }
    let fake = Arc::new(Fake {
        by_question,
        log: Mutex::new(FakeLog::default()),
    });
    let app = axum::Router::new()
        .route(
            "/v1/chat/completions",
            axum::routing::post(chat_completions),
        )
        .with_state(fake.clone());
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0")
        .await
        .expect("bind fake endpoint");
    let fake_addr = listener.local_addr().expect("addr");
    let handle = tokio::spawn(async move {
        axum::serve(listener, app).await.expect("fake endpoint");
    });
    (fake, format!("http://{fake_addr}/v1"), handle)
}

/// Runs the client against the hub and the fake endpoint on dataset `mini`, with `extra`
/// arguments.
async fn run_client(
    server: &TestServer,
    model_url: &str,
    hub_token: &str,
    extra: &[&str],
) -> std::process::Output {
    run_client_on(server, ["--dataset", "mini"], model_url, hub_token, extra).await
}

/// Runs the client on `target` (`--dataset NAME` or `--study NAME`).
async fn run_client_on(
    server: &TestServer,
    target: [&str; 2],
    model_url: &str,
    hub_token: &str,
    extra: &[&str],
) -> std::process::Output {
    let checkout = Path::new(env!("CARGO_MANIFEST_DIR"));
    let script = checkout.join("clients/enact_client.py");
    let mut command = Command::new("python3");
    command
        .arg(script)
        // The example is written over the `enact_hub` package: the checkout's copy of it.
        .env("PYTHONPATH", checkout.join("python"))
        .args(["--hub", &server.url("")])
        .args(target)
        .args(["--model-url", model_url, "--model", "fake-vlm"])
        .args(["--name", "Fake VLM", "--retry-delay", "0.01"])
        .args(["--api-key-env", "FAKE_ENDPOINT_KEY"])
        .args(extra)
        .env("FAKE_ENDPOINT_KEY", API_KEY)
        .env("ENACT_HUB_TOKEN", hub_token);
    tokio::task::spawn_blocking(move || command.output().expect("run python3"))
        .await
        .expect("client task")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_example_client_answers_through_a_chat_endpoint_and_submits() {
    if !python_with_requests() {
        assert!(
            !crate::fixtures::must_not_skip(),
            "python3 with requests is missing in CI: scripts/test.sh installs it"
        );
        eprintln!("skipping: python3 with `requests` is absent (run scripts/test.sh)");
        return;
    }
    let (server, records) = spawn_app_with_release().await;
    let token = submitter_token(&server).await;
    let (fake, model_url, fake_server) = spawn_fake(&records).await;
    let output = run_client(&server, &model_url, &token, &[]).await;
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "client failed: {stderr}");
    assert!(
        stderr.contains("retrying"),
        "retries are reported: {stderr}"
    );

    {
        let log = fake.log.lock().expect("log");
        assert!(log.problems.is_empty(), "{:?}", log.problems);
        assert_eq!(log.answered.len(), records.len(), "each item asked once");
        assert_eq!(log.calls, records.len() + 2, "plus the 429 and the 503");
    }

    let printed: Value = serde_json::from_slice(&output.stdout).expect("client prints JSON");
    let id = printed["id"].as_i64().expect("submission id");
    let mut conn = server.pool.acquire().await.expect("conn");
    let row = store::submissions::by_id(&mut conn, id)
        .await
        .expect("query")
        .expect("stored");
    assert_eq!(row.model, "Fake VLM");
    let scores: Value = serde_json::to_value(&row.scores).expect("scores");
    assert_eq!(scores, printed["scores"]);
    let coverage = &scores["coverage"];
    assert_eq!(coverage["answered"], 4);
    assert_eq!(coverage["coverage"], 1.0);
    assert_eq!(coverage["unparseable"], 1);
    assert_eq!(coverage["parse_failure_rate"], 0.25);
    assert_eq!(scores["report"]["overall"]["task_accuracy"], 0.5);
    let verdicts = store::submissions::verdicts(&mut conn, id)
        .await
        .expect("verdicts");
    let correct: Vec<bool> = records
        .iter()
        .map(|r| {
            verdicts
                .iter()
                .find(|v| v.id == r["id"].as_str().expect("id"))
                .expect("a verdict per item")
                .task_accuracy
        })
        .collect();
    assert_eq!(correct, vec![true, true, false, false]);
    // The raw model text is what was stored, untouched.
    assert!(
        verdicts
            .iter()
            .any(|v| v.raw_answer.as_deref() == Some("\"I cannot tell from these pictures.\""))
    );
    drop(conn);
    fake_server.abort();
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_example_client_tries_a_few_items_and_names_a_refused_token() {
    if !python_with_requests() {
        eprintln!("skipping: python3 with `requests` is absent (run scripts/test.sh)");
        return;
    }
    let (server, records) = spawn_app_with_release().await;
    let (fake, model_url, fake_server) = spawn_fake(&records).await;

    let refused = run_client(
        &server,
        &model_url,
        "ehub_000000000000_nope",
        &["--limit", "2"],
    )
    .await;
    assert_eq!(refused.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(
        stderr.contains("posting the submission: HTTP 401") && stderr.contains("revoked"),
        "{stderr}"
    );

    let token = submitter_token(&server).await;
    let output = run_client(&server, &model_url, &token, &["--limit", "2"]).await;
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "client failed: {stderr}");
    let printed: Value = serde_json::from_slice(&output.stdout).expect("client prints JSON");
    let coverage = &printed["scores"]["coverage"];
    assert_eq!(coverage["answered"], 2);
    assert_eq!(coverage["missing"], 2);
    assert_eq!(coverage["coverage"], 0.5);
    assert_eq!(coverage["unparseable"], 0);
    // Two right answers out of four items: the unanswered ones score 0.
    assert_eq!(printed["scores"]["report"]["overall"]["task_accuracy"], 0.5);
    assert_eq!(
        fake.log.lock().expect("log").answered.len(),
        4,
        "two runs of two"
    );
    fake_server.abort();
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_example_client_stops_with_a_clear_message_when_the_model_endpoint_refuses() {
    if !python_with_requests() {
        eprintln!("skipping: python3 with `requests` is absent (run scripts/test.sh)");
        return;
    }
    let (server, _) = spawn_app_with_release().await;
    // The hub itself has no chat endpoint: a 404, which is not worth retrying.
    let model_url = server.url("/v1");
    let output = run_client(
        &server,
        &model_url,
        "ehub_000000000000_nope",
        &["--limit", "1"],
    )
    .await;
    assert_eq!(output.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("model endpoint") && stderr.contains("HTTP 404"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("retrying"),
        "a 404 is not retried: {stderr}"
    );
    let mut conn = server.pool.acquire().await.expect("conn");
    assert_eq!(
        store::submissions::counts(&mut conn)
            .await
            .expect("counts")
            .0,
        0
    );
    drop(conn);
    server.stop().await;
}

/// `--study`: the client answers the baseline and every variant of a study (the same questions
/// with other images), submits each, and prints the study report; the fake model answers by
/// question, so nothing changes between the datasets.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_example_client_runs_a_model_over_every_dataset_of_a_study() {
    if !python_with_requests() {
        eprintln!("skipping: python3 with `requests` is absent (run scripts/test.sh)");
        return;
    }
    let fov = enact_hub::core::world::CameraRig {
        image_size: 96,
        fov_deg: 30.0,
        ..Default::default()
    };
    let (server, records) = crate::studies::world_with_variants(&[("world-fov30", fov)]).await;
    let (_, admin) = api_token(&server.pool, "admin", Role::Admin, None, None).await;
    server
        .call(reqwest::Method::POST, "/api/v1/admin/studies")
        .bearer(&admin)
        .json(
            &json!({"name": "camera", "baseline": crate::studies::BASELINE,
                      "variants": ["Camera FOV/Aperture 30=world-fov30"]}),
        )
        .expect(201)
        .await;
    let token = submitter_token(&server).await;
    let (fake, model_url, fake_server) = spawn_fake(&records).await;
    let answers = tempfile::tempdir().expect("tempdir");
    let answers_dir = answers.path().join("answers");
    let output = run_client_on(
        &server,
        ["--study", "camera"],
        &model_url,
        &token,
        &["--answers-out", answers_dir.to_str().expect("utf-8 path")],
    )
    .await;
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "client failed: {stderr}");
    {
        let log = fake.log.lock().expect("log");
        assert!(log.problems.is_empty(), "{:?}", log.problems);
        assert_eq!(
            log.answered.len(),
            2 * records.len(),
            "each item of each dataset"
        );
    }
    let printed: Value = serde_json::from_slice(&output.stdout).expect("client prints JSON");
    let datasets: Vec<&str> = printed["submissions"]
        .as_array()
        .expect("submissions")
        .iter()
        .map(|s| s["dataset"].as_str().expect("dataset"))
        .collect();
    assert_eq!(datasets, [crate::studies::BASELINE, "world-fov30"]);
    for file in ["world.jsonl", "world-fov30.jsonl"] {
        assert!(answers_dir.join(file).is_file(), "{file}");
    }
    let report = &printed["report"];
    assert_eq!(report["stamp"]["row"], "Fake VLM");
    for cell in report["cells"].as_array().expect("cells") {
        assert_eq!(cell["delta"], 0.0, "the same answers: {cell}");
    }
    assert!(
        stderr.contains("Camera FOV/Aperture 30 forward: delta 0.0"),
        "{stderr}"
    );
    fake_server.abort();
    server.stop().await;
}
