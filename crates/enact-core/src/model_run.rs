//! Asking a model an item, without the asking: the chat-completions request an item becomes
//! (its prompt, versioned), what a reply means (an answer, or a failure with its reason), how
//! long to wait before trying again, and how many requests may be in flight.
//!
//! The prompt is the one `clients/enact_client.py` has always sent: one user message whose
//! parts are, for each image, a text part with its label and a colon ("Current State:",
//! "Next State 1:", …) followed by the image as a base64 `data:image/png` URL, then ENACT's
//! question text. [`PROMPT_VERSION`] names it and [`prompt_template_hash`] pins it, so a run's
//! stamp says exactly what the model was shown.

use std::time::{Duration, SystemTime};

use base64::Engine as _;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use sha2::{Digest, Sha256};

use crate::verifier::{Permutation, StrictParseFailure, parse_answer_text_strict};

/// The prompt's version, stamped on every run and submission it makes. Bump it whenever
/// [`user_message`] changes what a model is shown.
pub const PROMPT_VERSION: &str = "enact-hub-run/1";

/// One image of an item as the model sees it.
pub struct PromptImage<'a> {
    /// "Current State", "Next State 1", …
    pub label: &'a str,
    pub png: &'a [u8],
}

/// The `data:image/png;base64,…` URL of a PNG.
pub fn png_data_url(png: &[u8]) -> String {
    let mut url = String::with_capacity(22 + png.len().div_ceil(3) * 4);
    url.push_str("data:image/png;base64,");
    base64::engine::general_purpose::STANDARD.encode_string(png, &mut url);
    url
}

/// The content parts of the one user message an item becomes.
pub fn user_message(images: &[PromptImage<'_>], question: &str) -> Value {
    let parts: Vec<Value> = images
        .iter()
        .flat_map(|image| {
            [
                json!({"type": "text", "text": format!("{}:", image.label)}),
                json!({"type": "image_url", "image_url": {"url": png_data_url(image.png)}}),
            ]
        })
        .chain(std::iter::once(json!({"type": "text", "text": question})))
        .collect();
    json!({"role": "user", "content": parts})
}

/// The prompt template's SHA-256 (hex): the message built from placeholders instead of an
/// item, so any change to the message's layout changes the hash even if the version was not
/// bumped.
pub fn prompt_template_hash() -> String {
    let message = user_message(
        &[PromptImage {
            label: "{label}",
            png: b"{png}",
        }],
        "{question}",
    );
    let text = format!("{PROMPT_VERSION}\n{message}");
    hex::encode(Sha256::digest(text.as_bytes()))
}

/// What a run sends besides the message: part of the run's identity.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct GenerationParams {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub temperature: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_tokens: Option<u32>,
}

/// The body of `POST {endpoint}/chat/completions` for one item.
pub fn chat_request(model: &str, params: &GenerationParams, message: Value) -> Value {
    let mut body = json!({"model": model, "messages": [message]});
    if let Some(t) = params.temperature {
        body["temperature"] = json!(t);
    }
    if let Some(n) = params.max_tokens {
        body["max_tokens"] = json!(n);
    }
    body
}

/// Tokens an endpoint reported for one call (0 when it reported none).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Usage {
    pub prompt_tokens: u64,
    pub completion_tokens: u64,
}

impl std::ops::AddAssign for Usage {
    fn add_assign(&mut self, other: Usage) {
        self.prompt_tokens += other.prompt_tokens;
        self.completion_tokens += other.completion_tokens;
    }
}

/// Prices in US dollars per million tokens.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Prices {
    pub input_usd_per_mtok: f64,
    pub output_usd_per_mtok: f64,
}

impl Prices {
    /// What `usage` costs, in US dollars.
    pub fn cost(&self, usage: Usage) -> f64 {
        (usage.prompt_tokens as f64 * self.input_usd_per_mtok
            + usage.completion_tokens as f64 * self.output_usd_per_mtok)
            / 1_000_000.0
    }
}

/// A successful chat-completions reply, read.
#[derive(Debug, Clone, PartialEq)]
pub struct Completion {
    /// `choices[0].message.content` (content parts joined), `None` when absent or null.
    pub text: Option<String>,
    pub finish_reason: Option<String>,
    pub usage: Usage,
}

#[derive(Deserialize)]
struct ReplyBody {
    #[serde(default)]
    choices: Vec<ReplyChoice>,
    #[serde(default)]
    usage: Option<ReplyUsage>,
}

#[derive(Deserialize)]
struct ReplyChoice {
    #[serde(default)]
    message: Option<ReplyMessage>,
    #[serde(default)]
    finish_reason: Option<String>,
}

#[derive(Deserialize)]
struct ReplyMessage {
    #[serde(default)]
    content: Option<Value>,
}

#[derive(Deserialize)]
struct ReplyUsage {
    #[serde(default)]
    prompt_tokens: Option<u64>,
    #[serde(default)]
    completion_tokens: Option<u64>,
}

/// Reads a chat-completions reply body; an error says what is wrong with it.
pub fn read_completion(body: &[u8]) -> Result<Completion, String> {
    let reply: ReplyBody = serde_json::from_slice(body)
        .map_err(|e| format!("the reply is not a chat completion: {e}"))?;
    let usage = reply
        .usage
        .map(|u| Usage {
            prompt_tokens: u.prompt_tokens.unwrap_or(0),
            completion_tokens: u.completion_tokens.unwrap_or(0),
        })
        .unwrap_or_default();
    let Some(choice) = reply.choices.into_iter().next() else {
        return Err("the reply has no choices".to_owned());
    };
    // Some servers answer with content parts; their text is the answer.
    let text = match choice.message.and_then(|m| m.content) {
        Some(Value::String(s)) => Some(s),
        Some(Value::Array(parts)) => Some(
            parts
                .iter()
                .filter_map(|p| p.get("text").and_then(Value::as_str))
                .collect(),
        ),
        _ => None,
    };
    Ok(Completion {
        text,
        finish_reason: choice.finish_reason,
        usage,
    })
}

/// Why a reply that arrived is not an answer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum NotAnAnswer {
    /// No text, or only whitespace.
    Empty,
    /// `finish_reason: "length"`: the model was cut off at `max_tokens`.
    Cut,
}

impl std::fmt::Display for NotAnAnswer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NotAnAnswer::Empty => f.write_str("empty response"),
            NotAnAnswer::Cut => f.write_str("response cut off (finish_reason: length)"),
        }
    }
}

/// The answer text of a reply, or why it is not one: an empty or cut reply is a failure,
/// never an answer (a cut reply may end in a list that is not the model's last word).
pub fn answer_text(completion: &Completion) -> Result<&str, NotAnAnswer> {
    if completion.finish_reason.as_deref() == Some("length") {
        return Err(NotAnAnswer::Cut);
    }
    match completion.text.as_deref() {
        Some(text) if !text.trim().is_empty() => Ok(text),
        _ => Err(NotAnAnswer::Empty),
    }
}

/// How the hub will read an answer text for an item with `actions` labels: the verifier's
/// strict parser, the one submissions are scored with.
pub fn read_answer(text: &str, actions: usize) -> Result<Permutation, StrictParseFailure> {
    parse_answer_text_strict(text, actions)
}

/// How a failed call is handled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CallFailure {
    /// 429: wait (Retry-After when given) and send fewer requests at once.
    RateLimited,
    /// 5xx, 408, 409, a timeout or a connection error: try again after a backoff.
    Transient,
    /// Any other 4xx: the request itself is wrong; trying again would not help.
    Permanent,
}

impl CallFailure {
    /// The class of an HTTP error status.
    pub fn of_status(status: u16) -> CallFailure {
        match status {
            429 => CallFailure::RateLimited,
            408 | 409 => CallFailure::Transient,
            400..=499 => CallFailure::Permanent,
            _ => CallFailure::Transient,
        }
    }
}

/// Why an item of a run has no answer: what its last call met. Kept with the item
/// (`model_run_items.failure`, a remote run's cache file) by its [`code`](RunFailure::code),
/// and what a run's report counts failures by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum RunFailure {
    /// No reply: the request timed out, or the connection failed.
    NoReply,
    /// An error status other than 429.
    Status(u16),
    /// 429 more often than an item may meet.
    RateLimited,
    /// A reply that is not a chat completion.
    Unreadable,
    /// An empty reply.
    Empty,
    /// A reply cut off at `max_tokens`.
    Cut,
    /// Failed before the hub kept a failure's kind: only its text tells why.
    Unrecorded,
}

impl RunFailure {
    /// The stable code a failure is stored and reported by: `no_reply`, `http_503`,
    /// `rate_limited`, `unreadable`, `empty`, `cut`, `unrecorded`.
    pub fn code(self) -> String {
        match self {
            RunFailure::NoReply => "no_reply".to_owned(),
            RunFailure::Status(status) => format!("http_{status}"),
            RunFailure::RateLimited => "rate_limited".to_owned(),
            RunFailure::Unreadable => "unreadable".to_owned(),
            RunFailure::Empty => "empty".to_owned(),
            RunFailure::Cut => "cut".to_owned(),
            RunFailure::Unrecorded => "unrecorded".to_owned(),
        }
    }

    /// The failure a [`code`](RunFailure::code) names; `None` for any other text.
    pub fn from_code(code: &str) -> Option<RunFailure> {
        Some(match code {
            "no_reply" => RunFailure::NoReply,
            "rate_limited" => RunFailure::RateLimited,
            "unreadable" => RunFailure::Unreadable,
            "empty" => RunFailure::Empty,
            "cut" => RunFailure::Cut,
            "unrecorded" => RunFailure::Unrecorded,
            _ => {
                let status = code.strip_prefix("http_")?;
                // Three digits, as `code` writes them: "http_+99" or "http_0503" is not one.
                if status.len() != 3 || !status.bytes().all(|b| b.is_ascii_digit()) {
                    return None;
                }
                RunFailure::Status(status.parse().ok()?)
            }
        })
    }

    /// How a call that failed so is handled: `None` for what ends the item at once (an empty
    /// or cut reply is final; `Unrecorded` only describes stored rows).
    pub fn handling(self) -> Option<CallFailure> {
        match self {
            RunFailure::NoReply | RunFailure::Unreadable => Some(CallFailure::Transient),
            RunFailure::Status(status) => Some(CallFailure::of_status(status)),
            RunFailure::RateLimited => Some(CallFailure::RateLimited),
            RunFailure::Empty | RunFailure::Cut | RunFailure::Unrecorded => None,
        }
    }
}

impl From<NotAnAnswer> for RunFailure {
    fn from(not: NotAnAnswer) -> RunFailure {
        match not {
            NotAnAnswer::Empty => RunFailure::Empty,
            NotAnAnswer::Cut => RunFailure::Cut,
        }
    }
}

impl std::fmt::Display for RunFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunFailure::NoReply => f.write_str("no reply (timed out or no connection)"),
            RunFailure::Status(status) => write!(f, "HTTP {status}"),
            RunFailure::RateLimited => f.write_str("rate limited (429) too often"),
            RunFailure::Unreadable => f.write_str("a reply that is not a chat completion"),
            RunFailure::Empty => NotAnAnswer::Empty.fmt(f),
            RunFailure::Cut => NotAnAnswer::Cut.fmt(f),
            RunFailure::Unrecorded => f.write_str("failed (kind not recorded)"),
        }
    }
}

/// Reports count failures in a map keyed by [`RunFailure::code`].
impl Serialize for RunFailure {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(&self.code())
    }
}

/// How an item of a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ItemOutcome {
    /// The model replied with an answer, which was kept.
    Answered,
    /// No answer: every attempt failed, or the reply ended the item without one.
    Failed(RunFailure),
}

impl ItemOutcome {
    pub fn is_answered(self) -> bool {
        self == ItemOutcome::Answered
    }

    /// Why the item has no answer; `None` when answered.
    pub fn failure(self) -> Option<RunFailure> {
        match self {
            ItemOutcome::Answered => None,
            ItemOutcome::Failed(failure) => Some(failure),
        }
    }
}

/// A `Retry-After` header's delay from `now`: delta-seconds or an HTTP date (a date in the
/// past is no delay). `None` when the header reads as neither.
pub fn retry_after(header: &str, now: SystemTime) -> Option<Duration> {
    let header = header.trim();
    if let Ok(seconds) = header.parse::<u64>() {
        return Some(Duration::from_secs(seconds));
    }
    let at = httpdate::parse_http_date(header).ok()?;
    Some(at.duration_since(now).unwrap_or(Duration::ZERO))
}

/// The wait before retry `attempt` (1 for the first retry): exponential from `base`, capped at
/// `cap`, with full jitter (`jitter` drawn uniformly from [0, 1)) so that failed requests do
/// not come back together.
pub fn backoff(attempt: u32, base: Duration, cap: Duration, jitter: f64) -> Duration {
    let exponential = base.saturating_mul(1u32 << attempt.saturating_sub(1).min(20));
    exponential.min(cap).mul_f64(jitter.clamp(0.0, 1.0))
}

/// How many requests a run keeps in flight: additive increase, multiplicative decrease.
///
/// It starts small and doubles every window of replies (a slow start) until the first 429 or
/// the ceiling; a 429 halves it; then it grows back by a quarter of a request per window of
/// replies, slowly, because a server that refused at some level will refuse there again.
/// Only a refusal of a request sent since the last decrease lowers the limit again: the
/// requests already in flight when it was lowered were sent under the old limit.
#[derive(Debug, Clone)]
pub struct ConcurrencyWindow {
    limit: f64,
    ceiling: f64,
    slow_start: bool,
    /// Counts decreases; a request remembers the epoch it was sent in.
    epoch: u64,
}

/// Requests a window starts with (or the ceiling, when lower).
const INITIAL_WINDOW: f64 = 2.0;
/// Growth per window of replies once a server has refused.
const ADDITIVE_INCREASE: f64 = 0.25;

impl ConcurrencyWindow {
    /// A window that never exceeds `ceiling` (at least 1) requests in flight.
    pub fn new(ceiling: usize) -> ConcurrencyWindow {
        let ceiling = ceiling.max(1) as f64;
        ConcurrencyWindow {
            limit: INITIAL_WINDOW.min(ceiling),
            ceiling,
            slow_start: true,
            epoch: 0,
        }
    }

    /// Requests that may be in flight now (at least 1).
    pub fn limit(&self) -> usize {
        (self.limit.floor() as usize).max(1)
    }

    /// The epoch to remember with a request sent now.
    pub fn epoch(&self) -> u64 {
        self.epoch
    }

    /// A reply that was not a 429.
    pub fn on_reply(&mut self) {
        let step = if self.slow_start {
            1.0
        } else {
            ADDITIVE_INCREASE / self.limit
        };
        self.limit = (self.limit + step).min(self.ceiling);
    }

    /// A 429 for a request sent in `sent_epoch`; whether the limit was lowered.
    pub fn on_refused(&mut self, sent_epoch: u64) -> bool {
        if sent_epoch != self.epoch {
            return false;
        }
        self.slow_start = false;
        self.limit = (self.limit / 2.0).max(1.0);
        self.epoch += 1;
        true
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_failure_code_reads_back_as_the_failure_and_nothing_else_reads_as_one() {
        let every = [
            RunFailure::NoReply,
            RunFailure::Status(400),
            RunFailure::Status(503),
            RunFailure::RateLimited,
            RunFailure::Unreadable,
            RunFailure::Empty,
            RunFailure::Cut,
            RunFailure::Unrecorded,
        ];
        for failure in every {
            assert_eq!(
                RunFailure::from_code(&failure.code()),
                Some(failure),
                "{failure}"
            );
            assert_eq!(
                serde_json::to_value(failure).expect("code"),
                json!(failure.code())
            );
        }
        assert_eq!(RunFailure::Status(503).code(), "http_503");
        for other in [
            "",
            "http_",
            "http_50",
            "http_5034",
            "http_+99",
            "HTTP 503",
            "failed",
        ] {
            assert_eq!(RunFailure::from_code(other), None, "{other:?}");
        }
    }

    #[test]
    fn a_failure_is_handled_as_its_kind_says() {
        assert_eq!(RunFailure::NoReply.handling(), Some(CallFailure::Transient));
        assert_eq!(
            RunFailure::Unreadable.handling(),
            Some(CallFailure::Transient)
        );
        assert_eq!(
            RunFailure::Status(503).handling(),
            Some(CallFailure::Transient)
        );
        assert_eq!(
            RunFailure::Status(400).handling(),
            Some(CallFailure::Permanent)
        );
        assert_eq!(
            RunFailure::RateLimited.handling(),
            Some(CallFailure::RateLimited)
        );
        assert_eq!(RunFailure::Empty.handling(), None);
        assert_eq!(RunFailure::Cut.handling(), None);
        assert_eq!(RunFailure::Unrecorded.handling(), None);
        assert_eq!(RunFailure::from(NotAnAnswer::Cut), RunFailure::Cut);
        assert_eq!(
            RunFailure::Empty.to_string(),
            NotAnAnswer::Empty.to_string(),
            "the words a stored row has always had"
        );
    }

    use super::*;

    fn images() -> Vec<(String, Vec<u8>)> {
        vec![
            ("Current State".to_owned(), vec![0x89, b'P', b'N', b'G']),
            ("Next State 1".to_owned(), vec![1, 2, 3]),
        ]
    }

    #[test]
    fn the_message_is_the_example_clients() {
        let images = images();
        let prompt: Vec<PromptImage<'_>> = images
            .iter()
            .map(|(label, png)| PromptImage { label, png })
            .collect();
        let message = user_message(&prompt, "Order the states.");
        assert_eq!(
            message,
            json!({"role": "user", "content": [
                {"type": "text", "text": "Current State:"},
                {"type": "image_url", "image_url": {"url": "data:image/png;base64,iVBORw=="}},
                {"type": "text", "text": "Next State 1:"},
                {"type": "image_url", "image_url": {"url": "data:image/png;base64,AQID"}},
                {"type": "text", "text": "Order the states."},
            ]})
        );
        let body = chat_request(
            "m",
            &GenerationParams {
                temperature: Some(0.0),
                max_tokens: Some(64),
            },
            message,
        );
        assert_eq!(body["model"], "m");
        assert_eq!(body["temperature"], json!(0.0));
        assert_eq!(body["max_tokens"], 64);
        assert_eq!(body["messages"].as_array().map(Vec::len), Some(1));
        let bare = chat_request("m", &GenerationParams::default(), json!({}));
        assert!(bare.get("temperature").is_none() && bare.get("max_tokens").is_none());
    }

    #[test]
    fn the_template_hash_is_stable_and_hex() {
        let hash = prompt_template_hash();
        assert_eq!(hash.len(), 64);
        assert!(hash.bytes().all(|b| b.is_ascii_hexdigit()));
        assert_eq!(hash, prompt_template_hash());
    }

    #[test]
    fn replies_are_read_with_usage_and_content_parts() {
        let body = br#"{"choices":[{"message":{"content":"[2, 1]"},"finish_reason":"stop"}],
            "usage":{"prompt_tokens":1200,"completion_tokens":7,"total_tokens":1207}}"#;
        let c = read_completion(body).unwrap();
        assert_eq!(c.text.as_deref(), Some("[2, 1]"));
        assert_eq!(c.finish_reason.as_deref(), Some("stop"));
        assert_eq!(
            c.usage,
            Usage {
                prompt_tokens: 1200,
                completion_tokens: 7
            }
        );
        assert_eq!(answer_text(&c), Ok("[2, 1]"));

        let parts = br#"{"choices":[{"message":{"content":[{"type":"text","text":"[1,"},{"type":"text","text":" 2]"}]}}]}"#;
        let c = read_completion(parts).unwrap();
        assert_eq!(c.text.as_deref(), Some("[1, 2]"));
        assert_eq!(c.usage, Usage::default());

        assert!(
            read_completion(b"{\"choices\":[]}")
                .unwrap_err()
                .contains("no choices")
        );
        assert!(
            read_completion(b"<html>")
                .unwrap_err()
                .contains("not a chat completion")
        );
    }

    #[test]
    fn empty_and_cut_replies_are_failures() {
        let reply = |text: Option<&str>, finish: &str| Completion {
            text: text.map(str::to_owned),
            finish_reason: Some(finish.to_owned()),
            usage: Usage::default(),
        };
        assert_eq!(answer_text(&reply(None, "stop")), Err(NotAnAnswer::Empty));
        assert_eq!(
            answer_text(&reply(Some("  \n"), "stop")),
            Err(NotAnAnswer::Empty)
        );
        assert_eq!(
            answer_text(&reply(Some("[1, 2]"), "length")),
            Err(NotAnAnswer::Cut)
        );
        assert!(NotAnAnswer::Cut.to_string().contains("length"));
    }

    #[test]
    fn answers_are_read_by_the_verifiers_parser() {
        assert_eq!(
            read_answer("<think>[1]</think> so [2, 1]", 2)
                .unwrap()
                .labels(),
            &[2, 1]
        );
        assert!(read_answer("no idea", 2).is_err());
    }

    #[test]
    fn statuses_are_classed() {
        assert_eq!(CallFailure::of_status(429), CallFailure::RateLimited);
        for s in [408, 409, 500, 502, 503] {
            assert_eq!(CallFailure::of_status(s), CallFailure::Transient, "{s}");
        }
        for s in [400, 401, 403, 404, 422] {
            assert_eq!(CallFailure::of_status(s), CallFailure::Permanent, "{s}");
        }
    }

    #[test]
    fn retry_after_reads_seconds_and_dates() {
        let now = SystemTime::UNIX_EPOCH + Duration::from_secs(1_700_000_000);
        assert_eq!(retry_after("3", now), Some(Duration::from_secs(3)));
        let later = httpdate::fmt_http_date(now + Duration::from_secs(5));
        assert_eq!(retry_after(&later, now), Some(Duration::from_secs(5)));
        let earlier = httpdate::fmt_http_date(now - Duration::from_secs(5));
        assert_eq!(retry_after(&earlier, now), Some(Duration::ZERO));
        assert_eq!(retry_after("soon", now), None);
    }

    #[test]
    fn backoff_grows_is_capped_and_jittered() {
        let base = Duration::from_millis(100);
        let cap = Duration::from_secs(1);
        assert_eq!(backoff(1, base, cap, 1.0), Duration::from_millis(100));
        assert_eq!(backoff(3, base, cap, 1.0), Duration::from_millis(400));
        assert_eq!(backoff(30, base, cap, 1.0), cap);
        assert_eq!(backoff(3, base, cap, 0.5), Duration::from_millis(200));
        assert_eq!(backoff(3, base, cap, 0.0), Duration::ZERO);
    }

    #[test]
    fn cost_is_tokens_times_prices() {
        let prices = Prices {
            input_usd_per_mtok: 2.5,
            output_usd_per_mtok: 10.0,
        };
        let usage = Usage {
            prompt_tokens: 2_000_000,
            completion_tokens: 100_000,
        };
        assert!((prices.cost(usage) - 6.0).abs() < 1e-12);
    }

    #[test]
    fn the_window_starts_slow_halves_on_refusal_and_grows_back() {
        let mut w = ConcurrencyWindow::new(32);
        assert_eq!(w.limit(), 2);
        for _ in 0..6 {
            w.on_reply();
        }
        assert_eq!(w.limit(), 8);
        let epoch = w.epoch();
        assert!(w.on_refused(epoch));
        assert_eq!(w.limit(), 4);
        // Requests sent before the decrease do not lower it again.
        assert!(!w.on_refused(epoch));
        assert_eq!(w.limit(), 4);
        // Growth is now slow: a quarter request per window.
        for _ in 0..4 {
            w.on_reply();
        }
        assert_eq!(w.limit(), 4);
        for _ in 0..100 {
            w.on_reply();
        }
        assert!(w.limit() > 4);
        for _ in 0..100_000 {
            w.on_reply();
        }
        assert_eq!(w.limit(), 32);
        // Never below one.
        let mut w = ConcurrencyWindow::new(1);
        assert!(w.on_refused(w.epoch()));
        assert_eq!(w.limit(), 1);
    }
}
