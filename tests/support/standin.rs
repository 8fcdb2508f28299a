//! A stand-in OpenAI-compatible chat-completions server for the model-run tests: real HTTP on
//! 127.0.0.1:0, scripted per item (found by its first image, see [`item_key`]), counting every
//! request per item, successful or not.
//!
//! Each item has a script: the replies to its first, second, … call; the last step repeats.
//! Besides, the server can refuse with 429 any request beyond N in flight, answer after a
//! fixed latency, and reports `usage` tokens on every 200 it sends (and sums them).

#![allow(dead_code)]

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, SystemTime};

use axum::Json;
use axum::Router;
use axum::extract::State;
use axum::http::{HeaderMap, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::routing::post;
use serde_json::{Value, json};

/// One reply of an item's script.
#[derive(Debug, Clone)]
pub enum Step {
    /// 200 with this text and `finish_reason: "stop"`.
    Answer(String),
    /// 200 with this text and `finish_reason: "length"`.
    Cut(String),
    /// 200 with empty content.
    Empty,
    /// This status with an OpenAI-style error body.
    Status(u16, String),
    /// 429 with `Retry-After` in seconds.
    RetryAfterSeconds(u64),
    /// 429 with `Retry-After` as an HTTP date this many seconds ahead.
    RetryAfterDate(u64),
    /// Sleeps this long before answering with the text (past the client's timeout).
    Slow(Duration, String),
}

/// What happened to an item, as the server saw it.
#[derive(Debug, Clone, Default)]
pub struct ItemCalls {
    /// Every request for the item.
    pub requests: usize,
    /// 200 replies with an answer (`finish_reason: stop`, non-empty).
    pub answered: usize,
    /// 429s sent because too many requests were in flight.
    pub refused: usize,
}

#[derive(Default)]
struct Log {
    per_item: HashMap<String, ItemCalls>,
    /// Requests whose question matched no item.
    unknown: usize,
    prompt_tokens: u64,
    completion_tokens: u64,
    authorizations: Vec<String>,
    problems: Vec<String>,
}

/// The settings and scripts of a stand-in.
#[derive(Clone, Default)]
pub struct StandInConfig {
    /// By [`item_key`]: (item id, its script).
    pub scripts: HashMap<String, (String, Vec<Step>)>,
    /// Wait before every reply.
    pub latency: Duration,
    /// Refuse with 429 (no Retry-After) when more than this many requests are in flight.
    pub max_in_flight: Option<usize>,
    /// Prompt tokens reported per image of the request (completion tokens: the reply's
    /// characters).
    pub tokens_per_image: u64,
    /// When set, every request takes one permit before it is answered (and never gives it
    /// back): a test lets a run go as far as it wants it, whatever the machine's speed.
    pub gate: Option<Arc<tokio::sync::Semaphore>>,
}

struct Shared {
    config: StandInConfig,
    in_flight: AtomicUsize,
    log: Mutex<Log>,
}

/// A running stand-in; stops when dropped.
pub struct StandIn {
    pub addr: SocketAddr,
    shared: Arc<Shared>,
    task: tokio::task::JoinHandle<()>,
}

impl Drop for StandIn {
    fn drop(&mut self) {
        self.task.abort();
    }
}

impl StandIn {
    pub async fn start(config: StandInConfig) -> StandIn {
        let shared = Arc::new(Shared {
            config,
            in_flight: AtomicUsize::new(0),
            log: Mutex::new(Log::default()),
        });
        let app = Router::new()
            .route("/v1/chat/completions", post(chat_completions))
            .with_state(shared.clone());
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0")
            .await
            .expect("bind the stand-in");
        let addr = listener.local_addr().expect("the stand-in's address");
        let task = tokio::spawn(async move {
            axum::serve(listener, app)
                .await
                .expect("the stand-in serves");
        });
        StandIn { addr, shared, task }
    }

    /// The base URL a run is given (`…/v1`).
    pub fn endpoint(&self) -> String {
        format!("http://{}/v1", self.addr)
    }

    /// What the server saw of each item, by item id.
    pub fn calls(&self) -> HashMap<String, ItemCalls> {
        self.log().per_item.clone()
    }

    pub fn total_requests(&self) -> usize {
        let log = self.log();
        log.per_item.values().map(|c| c.requests).sum::<usize>() + log.unknown
    }

    pub fn total_refused(&self) -> usize {
        self.log().per_item.values().map(|c| c.refused).sum()
    }

    /// Tokens reported in every 200 sent: (prompt, completion).
    pub fn tokens(&self) -> (u64, u64) {
        let log = self.log();
        (log.prompt_tokens, log.completion_tokens)
    }

    /// Every Authorization header received.
    pub fn authorizations(&self) -> Vec<String> {
        self.log().authorizations.clone()
    }

    /// What was wrong with requests (a prompt not built as specified, an unknown item).
    pub fn problems(&self) -> Vec<String> {
        self.log().problems.clone()
    }

    fn log(&self) -> std::sync::MutexGuard<'_, Log> {
        self.shared.log.lock().expect("the stand-in's log")
    }
}

/// Gives back its in-flight place however the handler ends (a client timing out drops it).
struct InFlight<'a>(&'a AtomicUsize);

impl Drop for InFlight<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

/// How the stand-in recognises an item: the SHA-256 (hex) of its first image's PNG bytes
/// (questions repeat across items; frames do not).
pub fn item_key(first_png: &[u8]) -> String {
    use sha2::Digest;
    hex::encode(sha2::Sha256::digest(first_png))
}

/// The key of the item a request asks (see [`item_key`]) and its image count, checking the
/// prompt is built as the example client builds it.
fn read_prompt(request: &Value) -> Result<(String, usize), String> {
    use base64::Engine;
    let parts = request
        .pointer("/messages/0/content")
        .and_then(Value::as_array)
        .ok_or("no messages[0].content list")?;
    let (question, images) = parts.split_last().ok_or("empty content")?;
    if images.len() % 2 != 0 {
        return Err("images are not label + image pairs".into());
    }
    for (i, pair) in images.chunks(2).enumerate() {
        let label = if i == 0 {
            "Current State:".to_owned()
        } else {
            format!("Next State {i}:")
        };
        if pair[0]["text"] != json!(label) {
            return Err(format!("part {} is not the label {label:?}", 2 * i));
        }
        let url = pair[1]["image_url"]["url"].as_str().unwrap_or("");
        if !url.starts_with("data:image/png;base64,iVBOR") {
            return Err(format!("image {i} is not a base64 PNG data URL"));
        }
    }
    if !question["text"].is_string() {
        return Err("no question text last".into());
    }
    let first = images
        .get(1)
        .and_then(|p| p["image_url"]["url"].as_str())
        .and_then(|u| u.strip_prefix("data:image/png;base64,"))
        .ok_or("no first image")?;
    let png = base64::engine::general_purpose::STANDARD
        .decode(first)
        .map_err(|e| format!("the first image is not base64: {e}"))?;
    Ok((item_key(&png), images.len() / 2))
}

fn completion(text: &str, finish: &str, prompt_tokens: u64) -> Value {
    json!({
        "id": "chatcmpl-standin",
        "object": "chat.completion",
        "choices": [{"index": 0, "message": {"role": "assistant", "content": text},
                     "finish_reason": finish}],
        "usage": {"prompt_tokens": prompt_tokens, "completion_tokens": text.len(),
                  "total_tokens": prompt_tokens + text.len() as u64},
    })
}

async fn chat_completions(
    State(shared): State<Arc<Shared>>,
    headers: HeaderMap,
    Json(request): Json<Value>,
) -> Response {
    let now = shared.in_flight.fetch_add(1, Ordering::SeqCst) + 1;
    let _place = InFlight(&shared.in_flight);
    let config = &shared.config;
    let (key, images) = match read_prompt(&request) {
        Ok(p) => p,
        Err(problem) => {
            let mut log = shared.log.lock().expect("log");
            log.unknown += 1;
            log.problems.push(problem.clone());
            return (
                StatusCode::BAD_REQUEST,
                Json(json!({"error": {"message": problem}})),
            )
                .into_response();
        }
    };
    let Some((item, script)) = config.scripts.get(&key) else {
        let mut log = shared.log.lock().expect("log");
        log.unknown += 1;
        log.problems
            .push(format!("unknown item with first image {key}"));
        return (
            StatusCode::BAD_REQUEST,
            Json(json!({"error": {"message": "unknown item"}})),
        )
            .into_response();
    };
    let step = {
        let mut log = shared.log.lock().expect("log");
        if let Some(a) = headers.get("authorization").and_then(|v| v.to_str().ok()) {
            log.authorizations.push(a.to_owned());
        }
        let calls = log.per_item.entry(item.clone()).or_default();
        calls.requests += 1;
        if config.max_in_flight.is_some_and(|max| now > max) {
            calls.refused += 1;
            return (
                StatusCode::TOO_MANY_REQUESTS,
                Json(json!({"error": {"message": "too many requests in flight"}})),
            )
                .into_response();
        }
        let index = (calls.requests - calls.refused - 1).min(script.len().saturating_sub(1));
        script.get(index).cloned()
    };
    if let Some(gate) = &config.gate {
        gate.acquire().await.expect("the gate stays open").forget();
    }
    tokio::time::sleep(config.latency).await;
    let prompt_tokens = config.tokens_per_image * images as u64;
    let (status, body, finish) = match step {
        None => return (StatusCode::INTERNAL_SERVER_ERROR, "no script").into_response(),
        Some(Step::Status(status, message)) => {
            let status = StatusCode::from_u16(status).expect("a status");
            return (status, Json(json!({"error": {"message": message}}))).into_response();
        }
        Some(Step::RetryAfterSeconds(s)) => {
            return (
                StatusCode::TOO_MANY_REQUESTS,
                [("retry-after", s.to_string())],
                "rate limited",
            )
                .into_response();
        }
        Some(Step::RetryAfterDate(s)) => {
            let at = httpdate::fmt_http_date(SystemTime::now() + Duration::from_secs(s));
            return (
                StatusCode::TOO_MANY_REQUESTS,
                [("retry-after", at)],
                "rate limited",
            )
                .into_response();
        }
        Some(Step::Slow(wait, text)) => {
            tokio::time::sleep(wait).await;
            (StatusCode::OK, text, "stop")
        }
        Some(Step::Answer(text)) => (StatusCode::OK, text, "stop"),
        Some(Step::Cut(text)) => (StatusCode::OK, text, "length"),
        Some(Step::Empty) => (StatusCode::OK, String::new(), "stop"),
    };
    let mut log = shared.log.lock().expect("log");
    log.prompt_tokens += prompt_tokens;
    log.completion_tokens += body.len() as u64;
    if finish == "stop" && !body.is_empty() {
        log.per_item.entry(item.clone()).or_default().answered += 1;
    }
    (status, Json(completion(&body, finish, prompt_tokens))).into_response()
}
