//! `enact-hub run --hub URL`: a model run against a hub over its API, its replies in a cache
//! file, killed part-way and run again, and its answers submitted under the caller's token.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use enact_hub::core::credentials::Role;
use serde_json::Value;

use crate::helpers::*;
use crate::runs::{
    SECRET_KEY, answer_text, finished, json_summary, scripts, stored_submission, task_accuracy,
};
use crate::standin::{StandIn, StandInConfig, Step};

/// A hub serving `mini` (`per_cell` items per direction × L in 3, 4, 5) and the records.
async fn hub_with_release(per_cell: u32) -> (TestServer, Vec<Value>) {
    let written = Arc::new(Mutex::new(Vec::new()));
    let shared = written.clone();
    let server = spawn_app_with(|pool, dir| async move {
        let root = dir.join("release");
        let records = write_balanced_release(&root, &[3, 4, 5], per_cell);
        import(&pool, &root, &options("mini")).await;
        *shared.lock().expect("lock") = records;
    })
    .await;
    let records = written.lock().expect("lock").clone();
    (server, records)
}

/// Complete lines of the cache file (the header included), 0 when it is not there yet.
fn cache_lines(path: &std::path::Path) -> usize {
    std::fs::read(path).map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count())
}

/// Killed with SIGKILL part-way and run again: an item whose reply is in the cache is never
/// asked again, every item ends up answered, and the submission (under the caller's token)
/// scores what the stand-in answered. Neither the endpoint's key nor the hub's token is in
/// the cache or the output.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_remote_run_keeps_replies_in_its_cache_and_goes_on_after_a_kill() {
    let (server, records) = hub_with_release(5).await;
    let root = server.dir().join("release");
    let (_, token) = api_token(&server.pool, "team-remote", Role::Submitter, None, None).await;
    let wrong = [0usize, 3, 8, 13, 21];
    let standin = StandIn::start(StandInConfig {
        scripts: scripts(&root, &records, |i, r| {
            // One item fails once with a 500 before it is answered: retried, not failed.
            let answer = Step::Answer(answer_text(r, !wrong.contains(&i)));
            if i == 5 {
                vec![Step::Status(500, "overloaded".into()), answer]
            } else {
                vec![answer]
            }
        }),
        latency: Duration::from_millis(150),
        tokens_per_image: 85,
        ..StandInConfig::default()
    })
    .await;
    let work = tempfile::tempdir().expect("tempdir");
    let cache = work.path().join("replies.jsonl");
    let hub_url = server.url("");
    let command = || {
        let mut c = enact_hub();
        c.args(["run", "mini", "--hub", &hub_url, "--endpoint"])
            .arg(standin.endpoint())
            .args(["--model", "standin-vl", "--submit-as", "Remote VL"])
            .args(["--concurrency", "2", "--retry-delay", "0.01"])
            .args(["--api-key-env", "STANDIN_API_KEY", "--price-input", "1"])
            .arg("--cache")
            .arg(&cache)
            .arg("--json")
            .current_dir(work.path())
            .env("STANDIN_API_KEY", SECRET_KEY)
            .env("ENACT_HUB_TOKEN", &token)
            .env("RUST_LOG", "debug")
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped());
        c
    };
    let mut first = command().spawn().expect("start enact-hub run --hub");
    let deadline = Instant::now() + Duration::from_secs(60);
    while cache_lines(&cache) < 1 + 8 {
        assert!(Instant::now() < deadline, "the run made no progress");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    first.kill().expect("SIGKILL");
    let killed = tokio::task::spawn_blocking(move || first.wait_with_output())
        .await
        .expect("joined")
        .expect("the killed run");
    let done_at_kill = cache_lines(&cache) - 1;
    assert!(
        done_at_kill < records.len(),
        "killed too late to test resuming"
    );
    let calls_at_kill = standin.calls();
    let cached_at_kill: Vec<String> = std::fs::read_to_string(&cache)
        .expect("the cache")
        .lines()
        .skip(1)
        .map(|l| {
            let line: Value = serde_json::from_str(l).expect("a cache line");
            line["item"].as_str().expect("item").to_owned()
        })
        .collect();

    let (second, report) = json_summary(command()).await;
    assert_eq!(report["progress"]["answered"], records.len(), "{report}");
    assert_eq!(report["progress"]["failed"], 0);
    assert_eq!(
        report["progress"]["asked_now"],
        records.len() - done_at_kill
    );
    assert!(report.get("run_id").is_none(), "a remote run has no row id");

    let calls = standin.calls();
    for id in &cached_at_kill {
        assert_eq!(
            calls[id].requests, calls_at_kill[id].requests,
            "{id} asked again"
        );
    }
    let twice = calls.values().filter(|c| c.answered > 1).count();
    assert!(twice <= 2, "{twice} items answered twice");
    // Usage is what the stand-in reported for the answers kept: every item's images, once.
    let images: u64 = records
        .iter()
        .map(|r| r["images"].as_array().expect("images").len() as u64)
        .sum();
    let prompt_tokens = report["progress"]["usage"]["prompt_tokens"]
        .as_u64()
        .expect("prompt tokens");
    assert!(
        prompt_tokens >= images * 85,
        "{prompt_tokens} < {}",
        images * 85
    );

    // The submission is the caller's, stamped with the run, and scores 5 wrong of 30.
    let submission = report["submission"].as_i64().expect("submitted");
    let stored = stored_submission(&server.pool, submission).await;
    assert_eq!(stored.model, "Remote VL");
    assert_eq!(stored.account, "team-remote");
    let expected = (records.len() - wrong.len()) as f64 / records.len() as f64;
    assert!((task_accuracy(&stored) - expected).abs() < 1e-9);
    assert_eq!(stored.scores.coverage.missing, 0);
    let stamp: Value = serde_json::from_str(&stored.notes).expect("a JSON stamp");
    assert_eq!(stamp["model"], "standin-vl");
    assert_eq!(stamp["answered"], records.len());
    assert!(stamp["prompt_hash"].as_str().is_some_and(|h| h.len() == 64));
    // The build that ran the model and the one that scored it: here the same.
    assert_eq!(stamp["hub_version"], enact_hub::core::version::BUILD);
    assert_eq!(stored.scored_by, enact_hub::core::version::BUILD);
    let view = server
        .call(
            reqwest::Method::GET,
            &format!("/api/v1/submissions/{submission}"),
        )
        .bearer(&token)
        .expect(200)
        .await
        .json();
    assert_eq!(view["scored_by"], enact_hub::core::version::BUILD, "{view}");

    // Run a third time: nothing is asked, the same submission is found.
    let before = standin.total_requests();
    let (_, report3) = json_summary(command()).await;
    assert_eq!(report3["progress"]["asked_now"], 0);
    assert_eq!(report3["submission"], submission);
    assert_eq!(standin.total_requests(), before);

    let kept = std::fs::read_to_string(&cache).expect("the cache");
    for text in [
        kept.as_str(),
        &String::from_utf8_lossy(&killed.stdout),
        &String::from_utf8_lossy(&killed.stderr),
        &String::from_utf8_lossy(&second.stdout),
        &String::from_utf8_lossy(&second.stderr),
    ] {
        assert!(!text.contains(SECRET_KEY), "the endpoint's key was written");
        assert!(!text.contains(&token), "the hub's token was written");
    }
    server.stop().await;
}

/// A hub serving `mini` (one item per direction × L), its records, a submitter's token, and a
/// stand-in answering every item right.
async fn hub_and_a_right_model() -> (TestServer, Vec<Value>, String, StandIn) {
    let (server, records) = hub_with_release(1).await;
    let root = server.dir().join("release");
    let (_, token) = api_token(&server.pool, "team-remote", Role::Submitter, None, None).await;
    let standin = StandIn::start(StandInConfig {
        scripts: scripts(&root, &records, |_, r| {
            vec![Step::Answer(answer_text(r, true))]
        }),
        ..StandInConfig::default()
    })
    .await;
    (server, records, token, standin)
}

/// A cache made by another run is refused, naming the file and the run it holds; a hub that
/// does not have the dataset is a clear error; neither asks the endpoint anything.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_remote_run_refuses_another_runs_cache_and_an_unknown_dataset() {
    let (server, records, token, standin) = hub_and_a_right_model().await;
    let work = tempfile::tempdir().expect("tempdir");
    let cache = work.path().join("replies.jsonl");
    let hub_url = server.url("");
    let run = |dataset: &str, model: &str| {
        let mut c = enact_hub();
        c.args([
            "run",
            dataset,
            "--hub",
            &hub_url,
            "--token",
            &token,
            "--endpoint",
        ])
        .arg(standin.endpoint())
        .args(["--model", model, "--no-submit", "--cache"])
        .arg(&cache)
        .current_dir(work.path());
        c
    };
    let first = finished(run("mini", "model-a")).await;
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    assert!(String::from_utf8_lossy(&first.stderr).contains("not submitted"));
    let asked = standin.total_requests();
    assert_eq!(asked, records.len());

    let other = finished(run("mini", "model-b")).await;
    assert!(!other.status.success());
    let said = String::from_utf8_lossy(&other.stderr);
    assert!(
        said.contains("replies.jsonl") && said.contains("model-a"),
        "{said}"
    );

    let missing = finished(run("no-such-dataset", "model-a")).await;
    assert!(!missing.status.success());
    let said = String::from_utf8_lossy(&missing.stderr);
    assert!(
        said.contains("no-such-dataset") && said.contains("404"),
        "{said}"
    );
    assert_eq!(standin.total_requests(), asked);
    server.stop().await;
}

/// A reply the hub proxy gives instead of the hub's.
#[derive(Clone)]
struct Fault {
    method: reqwest::Method,
    /// What the request's path (and query) starts with.
    path: String,
    status: u16,
    retry_after: Option<u64>,
    /// The hub gets the request first and does what it asks; its reply is lost.
    after_the_hub: bool,
    /// Requests it answers (`usize::MAX`: all).
    times: usize,
}

impl Fault {
    fn new(method: reqwest::Method, path: &str, status: u16) -> Fault {
        Fault {
            method,
            path: path.to_owned(),
            status,
            retry_after: None,
            after_the_hub: false,
            times: 1,
        }
    }
}

/// A request as the proxy answered it.
#[derive(Debug, Clone)]
struct Passed {
    method: reqwest::Method,
    path: String,
    status: u16,
    at: Instant,
}

struct ProxyState {
    hub: String,
    client: reqwest::Client,
    faults: Mutex<Vec<Fault>>,
    passed: Mutex<Vec<Passed>>,
}

/// Real HTTP on 127.0.0.1:0 in front of a hub: every request goes to the hub, except those
/// a [`Fault`] answers instead, in the order the faults are listed.
struct HubProxy {
    addr: std::net::SocketAddr,
    state: Arc<ProxyState>,
    task: tokio::task::JoinHandle<()>,
}

impl Drop for HubProxy {
    fn drop(&mut self) {
        self.task.abort();
    }
}

impl HubProxy {
    async fn start(hub: &TestServer, faults: Vec<Fault>) -> HubProxy {
        let state = Arc::new(ProxyState {
            hub: hub.url(""),
            client: reqwest::Client::new(),
            faults: Mutex::new(faults),
            passed: Mutex::default(),
        });
        let app = axum::Router::new()
            .fallback(proxy_pass)
            .with_state(state.clone());
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0")
            .await
            .expect("bind the proxy");
        let addr = listener.local_addr().expect("the proxy's address");
        let task = tokio::spawn(async move {
            axum::serve(listener, app).await.expect("the proxy serves");
        });
        HubProxy { addr, state, task }
    }

    fn url(&self) -> String {
        format!("http://{}", self.addr)
    }

    /// The statuses the requests `method path…` were answered with, and when.
    fn passed(&self, method: &reqwest::Method, path: &str) -> Vec<(u16, Instant)> {
        let passed = self.state.passed.lock().expect("the proxy's log");
        passed
            .iter()
            .filter(|p| p.method == method && p.path.starts_with(path))
            .map(|p| (p.status, p.at))
            .collect()
    }
}

async fn proxy_pass(
    axum::extract::State(proxy): axum::extract::State<Arc<ProxyState>>,
    method: reqwest::Method,
    uri: axum::http::Uri,
    mut headers: reqwest::header::HeaderMap,
    body: bytes::Bytes,
) -> axum::response::Response {
    use axum::response::IntoResponse;
    let path = uri.path_and_query().map_or("/", |p| p.as_str()).to_owned();
    let fault = {
        let mut faults = proxy.faults.lock().expect("the faults");
        faults
            .iter_mut()
            .find(|f| f.times > 0 && f.method == method && path.starts_with(&f.path))
            .map(|f| {
                f.times -= 1;
                f.clone()
            })
    };
    let log = |status: u16| {
        proxy.passed.lock().expect("the proxy's log").push(Passed {
            method: method.clone(),
            path: path.clone(),
            status,
            at: Instant::now(),
        });
    };
    let mut reply = None;
    if fault.as_ref().is_none_or(|f| f.after_the_hub) {
        headers.remove(reqwest::header::HOST);
        let r = proxy
            .client
            .request(method.clone(), format!("{}{path}", proxy.hub))
            .headers(headers)
            .body(body)
            .send()
            .await
            .expect("the hub answers the proxy");
        let status = r.status();
        let kind = r.headers().get(reqwest::header::CONTENT_TYPE).cloned();
        reply = Some((status, kind, r.bytes().await.expect("the hub's reply")));
    }
    match (fault, reply) {
        (Some(fault), _) => {
            log(fault.status);
            let status = reqwest::StatusCode::from_u16(fault.status).expect("a status");
            let mut response = (status, "the proxy says no").into_response();
            if let Some(seconds) = fault.retry_after {
                response
                    .headers_mut()
                    .insert(reqwest::header::RETRY_AFTER, seconds.into());
            }
            response
        }
        (None, Some((status, kind, bytes))) => {
            log(status.as_u16());
            let mut response = (status, bytes).into_response();
            if let Some(kind) = kind {
                response
                    .headers_mut()
                    .insert(reqwest::header::CONTENT_TYPE, kind);
            }
            response
        }
        (None, None) => unreachable!("a request without a fault went to the hub"),
    }
}

/// `enact-hub run mini --hub` through `proxy`, with the stand-in answering every item right,
/// retrying three times at most; its output.
async fn run_through(
    proxy: &HubProxy,
    standin: &StandIn,
    token: &str,
    work: &std::path::Path,
) -> std::process::Output {
    let mut c = enact_hub();
    c.args(["run", "mini", "--hub", &proxy.url(), "--endpoint"])
        .arg(standin.endpoint())
        .args(["--model", "standin-vl", "--max-retries", "3"])
        .args(["--retry-delay", "0.01", "--json"])
        .current_dir(work)
        .env("ENACT_HUB_TOKEN", token);
    finished(c).await
}

/// A hub behind a proxy that answers 429, 502, 503 and 504 now and then (the submission's
/// 503 after the hub stored it): the run asks again, waits as `Retry-After` says, answers
/// every item once and stores one submission.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_remote_run_rides_out_a_busy_hub_and_honours_retry_after() {
    use reqwest::Method;
    let (server, records, token, standin) = hub_and_a_right_model().await;
    let listing = "/api/v1/datasets/mini/items?";
    let item = format!(
        "/api/v1/datasets/mini/items/{}",
        records[0]["id"].as_str().expect("id")
    );
    let frame = "/api/v1/frames/";
    let submit = "/api/v1/datasets/mini/submissions";
    let proxy = HubProxy::start(
        &server,
        vec![
            Fault {
                retry_after: Some(1),
                ..Fault::new(Method::GET, listing, 429)
            },
            Fault::new(Method::GET, &item, 502),
            Fault::new(Method::GET, &item, 504),
            Fault::new(Method::GET, frame, 503),
            Fault {
                retry_after: Some(1),
                after_the_hub: true,
                ..Fault::new(Method::POST, submit, 503)
            },
        ],
    )
    .await;
    let work = tempfile::tempdir().expect("tempdir");
    let out = run_through(&proxy, &standin, &token, work.path()).await;
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value = serde_json::from_slice(&out.stdout).expect("a JSON summary");
    assert_eq!(report["progress"]["answered"], records.len(), "{report}");
    assert_eq!(report["progress"]["failed"], 0, "{report}");
    let calls = standin.calls();
    assert_eq!(calls.len(), records.len());
    for (id, c) in &calls {
        assert_eq!((c.requests, c.answered), (1, 1), "{id}");
    }

    let statuses = |method: &Method, path: &str| -> Vec<u16> {
        proxy.passed(method, path).iter().map(|p| p.0).collect()
    };
    assert_eq!(statuses(&Method::GET, listing), [429, 200]);
    assert_eq!(statuses(&Method::GET, &item), [502, 504, 200]);
    let refused_frame = {
        let passed = proxy.state.passed.lock().expect("the proxy's log");
        let refused = passed.iter().find(|p| p.path.starts_with(frame));
        refused.expect("a frame was asked for").path.clone()
    };
    assert_eq!(statuses(&Method::GET, &refused_frame), [503, 200]);
    // The hub stored the submission whose reply was lost; asked again with the same key, it
    // answers with that one (200).
    assert_eq!(statuses(&Method::POST, submit), [503, 200]);
    for path in [listing, submit] {
        let method = if path == submit {
            Method::POST
        } else {
            Method::GET
        };
        let passed = proxy.passed(&method, path);
        let waited = passed[1].1 - passed[0].1;
        assert!(
            waited >= Duration::from_secs(1),
            "{method} {path}: asked again after {waited:?}, not the second Retry-After said"
        );
    }
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM submissions").await,
        1
    );
    let stored: i64 = count(&server.pool, "SELECT min(id) FROM submissions").await;
    assert_eq!(report["submission"], stored, "{report}");
    server.stop().await;
}

/// A hub that keeps answering 502 is asked once and three times again (`--max-retries 3`),
/// then the run stops with an error naming the status, having asked the model nothing.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_remote_run_gives_up_on_a_hub_that_stays_down_and_names_the_status() {
    let (server, _, token, standin) = hub_and_a_right_model().await;
    let listing = "/api/v1/datasets/mini/items?";
    let proxy = HubProxy::start(
        &server,
        vec![Fault {
            times: usize::MAX,
            ..Fault::new(reqwest::Method::GET, listing, 502)
        }],
    )
    .await;
    let work = tempfile::tempdir().expect("tempdir");
    let out = run_through(&proxy, &standin, &token, work.path()).await;
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("listing the items of 'mini': the hub answered 502"),
        "{stderr}"
    );
    assert_eq!(proxy.passed(&reqwest::Method::GET, listing).len(), 4);
    assert_eq!(standin.total_requests(), 0);
    server.stop().await;
}
