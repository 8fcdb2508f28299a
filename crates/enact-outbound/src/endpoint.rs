//! Sending one item's request to the endpoint until it is answered or has failed for good:
//! retries with backoff, `Retry-After`, and the in-flight window shared by a run's requests.

use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant, SystemTime};

use bytes::Bytes;
use tokio::sync::Notify;

use enact_core::model_run::{
    CallFailure, Completion, ConcurrencyWindow, RunFailure, Usage, answer_text, backoff,
    read_completion, retry_after,
};

/// An API key, kept out of every `Debug` and `Display` so it cannot reach a log line.
#[derive(Clone)]
pub struct ApiKey(String);

impl ApiKey {
    /// `None` for an empty value.
    pub fn new(value: impl Into<String>) -> Option<ApiKey> {
        let value = value.into();
        let trimmed = value.trim();
        (!trimmed.is_empty()).then(|| ApiKey(trimmed.to_owned()))
    }
}

impl std::fmt::Debug for ApiKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ApiKey(…)")
    }
}

/// How a run calls its endpoint; none of it is part of the run's identity.
#[derive(Debug, Clone)]
pub struct CallSettings {
    /// Requests in flight at most (the window grows back up to this after a 429).
    pub concurrency: usize,
    /// Retries after 5xx, 408, 409, timeouts, connection errors and unreadable replies.
    pub max_retries: u32,
    /// Per request, reading the reply included.
    pub timeout: Duration,
    /// The first retry's backoff (doubled per retry, with jitter, capped at a minute).
    pub backoff_base: Duration,
    pub api_key: Option<ApiKey>,
}

impl Default for CallSettings {
    fn default() -> Self {
        CallSettings {
            concurrency: 8,
            max_retries: 5,
            timeout: Duration::from_secs(120),
            backoff_base: Duration::from_secs(1),
            api_key: None,
        }
    }
}

/// 429s an item may meet before it fails, whatever `max_retries` is: a rate limit is the
/// server asking to wait, not the request failing, so it gets more patience.
const RATE_LIMITED_TRIES: u32 = 50;
/// The longest wait before a retry, `Retry-After` included.
const LONGEST_WAIT: Duration = Duration::from_secs(300);

/// How an item's calls ended.
#[derive(Debug)]
pub struct Asked {
    /// The answer text, or why there is none: the failure's kind and what was said.
    pub outcome: Result<String, (RunFailure, String)>,
    /// The last reply's text when it was not an answer (a cut reply), or the answer.
    pub response: Option<String>,
    pub finish_reason: Option<String>,
    pub usage: Usage,
    pub attempts: u32,
    pub latency: Duration,
    /// What the last failed call said, when one failed.
    pub last_error: Option<String>,
}

/// Requests in flight and the window that bounds them.
struct Window {
    state: Mutex<(ConcurrencyWindow, usize)>,
    changed: Notify,
}

/// A request's place in the window, given back when dropped.
struct Slot<'a> {
    window: &'a Window,
    epoch: u64,
}

impl Window {
    async fn acquire(&self) -> Slot<'_> {
        loop {
            let notified = self.changed.notified();
            tokio::pin!(notified);
            // Registered before the check, so a release between the check and the wait is
            // not missed.
            notified.as_mut().enable();
            {
                let mut state = self.lock();
                let (window, in_flight) = &mut *state;
                if *in_flight < window.limit() {
                    *in_flight += 1;
                    return Slot {
                        window: self,
                        epoch: window.epoch(),
                    };
                }
            }
            notified.await;
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, (ConcurrencyWindow, usize)> {
        // The state is two numbers updated together; a panic elsewhere cannot leave it torn.
        self.state
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }
}

impl Drop for Slot<'_> {
    fn drop(&mut self) {
        self.window.lock().1 -= 1;
        self.window.changed.notify_waiters();
    }
}

/// Calls one endpoint for a run; shared by the run's items.
pub struct Asker {
    client: reqwest::Client,
    url: String,
    settings: CallSettings,
    window: Window,
    requests: AtomicU64,
    refused: AtomicU64,
}

impl Asker {
    /// An asker of `endpoint` (its `/chat/completions` is called).
    pub fn new(endpoint: &str, settings: CallSettings) -> Result<Asker, String> {
        let client = reqwest::Client::builder()
            .timeout(settings.timeout)
            .user_agent(concat!("enact-hub/", env!("CARGO_PKG_VERSION")))
            .build()
            .map_err(|e| format!("cannot build the HTTP client: {e}"))?;
        Ok(Asker {
            client,
            url: format!("{}/chat/completions", endpoint.trim_end_matches('/')),
            window: Window {
                state: Mutex::new((ConcurrencyWindow::new(settings.concurrency), 0)),
                changed: Notify::new(),
            },
            settings,
            requests: AtomicU64::new(0),
            refused: AtomicU64::new(0),
        })
    }

    /// Requests sent so far, and how many of them were refused with 429.
    pub fn requests(&self) -> (u64, u64) {
        (
            self.requests.load(Ordering::Relaxed),
            self.refused.load(Ordering::Relaxed),
        )
    }

    /// Requests in flight now.
    pub fn in_flight(&self) -> usize {
        self.window.lock().1
    }

    /// Sends `body` until it is answered, fails for good, or the retries are spent.
    pub async fn ask(&self, body: Bytes) -> Asked {
        let mut asked = Asked {
            outcome: Err((RunFailure::NoReply, String::new())),
            response: None,
            finish_reason: None,
            usage: Usage::default(),
            attempts: 0,
            latency: Duration::ZERO,
            last_error: None,
        };
        let (mut retries, mut rate_limited) = (0u32, 0u32);
        loop {
            let (failure, message, wait) = match self.call(&body, &mut asked).await {
                Ok(()) => return asked,
                Err(e) => e,
            };
            let wait = match failure.handling() {
                None | Some(CallFailure::Permanent) => {
                    asked.outcome = Err((failure, message));
                    return asked;
                }
                Some(CallFailure::RateLimited) => {
                    rate_limited += 1;
                    if rate_limited >= RATE_LIMITED_TRIES {
                        asked.outcome = Err((
                            failure,
                            format!("gave up after {rate_limited} rate-limited calls: {message}"),
                        ));
                        return asked;
                    }
                    wait.unwrap_or_else(|| self.backoff(rate_limited))
                }
                Some(CallFailure::Transient) => {
                    retries += 1;
                    if retries > self.settings.max_retries {
                        asked.outcome = Err((
                            failure,
                            format!("gave up after {} attempts: {message}", asked.attempts),
                        ));
                        return asked;
                    }
                    self.backoff(retries)
                }
            };
            asked.last_error = Some(message);
            tokio::time::sleep(wait.min(LONGEST_WAIT)).await;
        }
    }

    fn backoff(&self, attempt: u32) -> Duration {
        backoff(
            attempt,
            self.settings.backoff_base,
            Duration::from_secs(60),
            rand::random::<f64>(),
        )
    }

    /// One call. `Ok` when the item is done (answered, or a reply that is final: empty or
    /// cut); otherwise how it failed, what was said, and the wait the server asked for.
    async fn call(
        &self,
        body: &Bytes,
        asked: &mut Asked,
    ) -> Result<(), (RunFailure, String, Option<Duration>)> {
        let slot = self.window.acquire().await;
        asked.attempts += 1;
        self.requests.fetch_add(1, Ordering::Relaxed);
        let started = Instant::now();
        let mut request = self
            .client
            .post(&self.url)
            .header(reqwest::header::CONTENT_TYPE, "application/json")
            .body(body.clone());
        if let Some(key) = &self.settings.api_key {
            request = request.bearer_auth(&key.0);
        }
        let reply = request.send().await;
        let reply = match reply {
            Ok(r) => r,
            Err(e) => return Err((RunFailure::NoReply, describe(&e), None)),
        };
        let status = reply.status();
        let wait = reply
            .headers()
            .get(reqwest::header::RETRY_AFTER)
            .and_then(|v| v.to_str().ok())
            .and_then(|v| retry_after(v, SystemTime::now()));
        let text = reply.bytes().await;
        asked.latency = started.elapsed();
        let text = match text {
            Ok(t) => t,
            Err(e) => return Err((RunFailure::NoReply, describe(&e), None)),
        };
        if status.as_u16() == 429 {
            self.refused.fetch_add(1, Ordering::Relaxed);
            self.window.lock().0.on_refused(slot.epoch);
            return Err((
                RunFailure::RateLimited,
                format!("HTTP 429: {}", error_message(&text)),
                wait,
            ));
        }
        self.window.lock().0.on_reply();
        drop(slot);
        if !status.is_success() {
            return Err((
                RunFailure::Status(status.as_u16()),
                format!("HTTP {}: {}", status.as_u16(), error_message(&text)),
                None,
            ));
        }
        let completion: Completion = read_completion(&text)
            .map_err(|e| (RunFailure::Unreadable, format!("HTTP {status}: {e}"), None))?;
        asked.usage += completion.usage;
        asked.finish_reason = completion.finish_reason.clone();
        asked.response = completion.text.clone();
        asked.outcome = match answer_text(&completion) {
            Ok(text) => Ok(text.to_owned()),
            Err(not) => Err((RunFailure::from(not.clone()), not.to_string())),
        };
        Ok(())
    }
}

/// A transport error in words: a timeout, a refused connection, or what reqwest says.
fn describe(e: &reqwest::Error) -> String {
    if e.is_timeout() {
        "timed out".to_owned()
    } else if e.is_connect() {
        format!("cannot connect: {e}")
    } else {
        format!("request failed: {e}")
    }
}

/// The message of an error reply: OpenAI's `error.message` (or `error` when a string, or
/// `message`), else the start of the body.
fn error_message(body: &[u8]) -> String {
    if let Ok(value) = serde_json::from_slice::<serde_json::Value>(body) {
        let message = value
            .pointer("/error/message")
            .or_else(|| value.get("error").filter(|e| e.is_string()))
            .or_else(|| value.get("message"))
            .and_then(serde_json::Value::as_str);
        if let Some(m) = message {
            return m.to_owned();
        }
    }
    let text = String::from_utf8_lossy(body);
    let text = text.trim();
    match text.char_indices().nth(300) {
        Some((cut, _)) => format!("{}…", &text[..cut]),
        None if text.is_empty() => "(empty body)".to_owned(),
        None => text.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_messages_come_from_the_body() {
        assert_eq!(
            error_message(br#"{"error":{"message":"bad model","type":"invalid"}}"#),
            "bad model"
        );
        assert_eq!(error_message(br#"{"error":"nope"}"#), "nope");
        assert_eq!(error_message(b""), "(empty body)");
        assert_eq!(error_message(b"plain words"), "plain words");
        assert!(error_message("x".repeat(400).as_bytes()).ends_with('…'));
    }

    #[test]
    fn keys_do_not_print() {
        let key = ApiKey::new("sk-secret").unwrap();
        assert!(!format!("{key:?}").contains("secret"));
        let settings = CallSettings {
            api_key: Some(key),
            ..CallSettings::default()
        };
        assert!(!format!("{settings:?}").contains("secret"));
        assert!(ApiKey::new("  ").is_none());
    }
}
