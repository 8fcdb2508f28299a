//! Another hub's API as a run against it uses it (`enact-hub run --hub URL --token T`):
//! listing a dataset's items, reading each with its frames, reading a study, and posting the
//! answers, with retries while the hub is busy, restarting or behind a proxy that lost it.

use std::time::{Duration, SystemTime};

use bytes::Bytes;
use enact_core::model_run::{backoff, retry_after};
use enact_core::submission::SubmissionMetadata;
use enact_service::AppError;
use serde::Deserialize;

use crate::endpoint::CallSettings;

/// The hub a remote run reads its items from and submits to.
#[derive(Debug, Clone)]
pub struct RemoteHub {
    /// The hub's base URL (`http://host:port`, or with the path it is served under).
    pub url: String,
    /// A token with the submit scope; sent only to the hub, never stored.
    pub token: String,
}

impl RemoteHub {
    /// The hub's URL, checked: http or https, with a host, without a query or fragment.
    pub fn base(&self) -> Result<url::Url, AppError> {
        let bad = |why: &str| AppError::Invalid(format!("--hub {:?}: {why}", self.url));
        let url = url::Url::parse(self.url.trim()).map_err(|e| bad(&e.to_string()))?;
        if !matches!(url.scheme(), "http" | "https") || url.host_str().is_none() {
            return Err(bad("must be an http:// or https:// URL with a host"));
        }
        if url.query().is_some() || url.fragment().is_some() {
            return Err(bad("must not have a query or fragment"));
        }
        Ok(url)
    }
}

/// The hub's API as a run uses it, with retries for a busy or restarting hub.
pub struct HubClient {
    client: reqwest::Client,
    /// The base URL without its trailing slash.
    base: String,
    token: String,
    retries: u32,
    backoff_base: Duration,
}

/// Statuses after which the same request is sent again: the hub busy, restarting or behind
/// a proxy that lost it.
fn retried(status: u16) -> bool {
    matches!(status, 429 | 502 | 503 | 504)
}

impl HubClient {
    pub fn new(hub: &RemoteHub, settings: &CallSettings) -> Result<HubClient, AppError> {
        let base = hub.base()?;
        let client = reqwest::Client::builder()
            .timeout(settings.timeout.max(Duration::from_secs(60)))
            .user_agent(concat!("enact-hub/", env!("CARGO_PKG_VERSION")))
            .build()
            .map_err(|e| AppError::internal(format!("cannot build the HTTP client: {e}")))?;
        Ok(HubClient {
            client,
            base: base.as_str().trim_end_matches('/').to_owned(),
            token: hub.token.clone(),
            retries: settings.max_retries.max(3),
            backoff_base: settings.backoff_base.max(Duration::from_millis(200)),
        })
    }

    /// The URL of `segments` under the API, each segment escaped.
    fn api_url(&self, segments: &[&str]) -> Result<url::Url, AppError> {
        let mut url = url::Url::parse(&format!("{}/api/v1", self.base))
            .map_err(|e| AppError::internal(format!("the hub URL: {e}")))?;
        url.path_segments_mut()
            .map_err(|()| AppError::internal("the hub URL cannot have a path"))?
            .extend(segments);
        Ok(url)
    }

    /// The hub's base URL, without its trailing slash.
    pub fn base(&self) -> &str {
        &self.base
    }

    /// A path the hub gave (`/api/v1/…`) as a URL on this hub.
    fn hub_path(&self, path: &str) -> String {
        format!("{}{path}", self.base)
    }

    /// Sends the request `make` builds until the hub answers with something other than a
    /// busy status, or the retries are spent; an error status becomes the matching error
    /// with the hub's message.
    async fn send(
        &self,
        what: &str,
        make: impl Fn() -> reqwest::RequestBuilder,
    ) -> Result<reqwest::Response, AppError> {
        let mut attempt = 0;
        loop {
            attempt += 1;
            let (why, wait) = match make().send().await {
                Ok(reply) if reply.status().is_success() => return Ok(reply),
                Ok(reply) if retried(reply.status().as_u16()) && attempt <= self.retries => {
                    let wait = reply
                        .headers()
                        .get(reqwest::header::RETRY_AFTER)
                        .and_then(|v| v.to_str().ok())
                        .and_then(|v| retry_after(v, SystemTime::now()));
                    (format!("HTTP {}", reply.status().as_u16()), wait)
                }
                Ok(reply) => return Err(hub_error(what, reply).await),
                Err(e) if attempt <= self.retries && (e.is_connect() || e.is_timeout()) => {
                    (e.to_string(), None)
                }
                Err(e) => {
                    return Err(AppError::Unavailable(format!(
                        "{what}: the hub at {} cannot be reached: {e}",
                        self.base
                    )));
                }
            };
            let wait = wait.unwrap_or_else(|| {
                backoff(
                    attempt,
                    self.backoff_base,
                    Duration::from_secs(30),
                    rand::random::<f64>(),
                )
            });
            tracing::debug!(what, attempt, %why, ?wait, "the hub is busy; trying again");
            tokio::time::sleep(wait.min(Duration::from_secs(120))).await;
        }
    }

    async fn get_json<T: for<'de> Deserialize<'de>>(
        &self,
        what: &str,
        url: &str,
    ) -> Result<T, AppError> {
        let reply = self.send(what, || self.client.get(url)).await?;
        reply.json::<T>().await.map_err(|e| {
            AppError::Unavailable(format!("{what}: the hub's reply is unreadable: {e}"))
        })
    }

    /// The ids of `dataset`'s items in the hub's order.
    pub async fn item_ids(&self, dataset: &str) -> Result<Vec<String>, AppError> {
        #[derive(Deserialize)]
        struct Entry {
            id: String,
        }
        #[derive(Deserialize)]
        struct Page {
            items: Vec<Entry>,
            next: Option<String>,
        }
        let mut url = self.api_url(&["datasets", dataset, "items"])?;
        url.query_pairs_mut().append_pair("per_page", "500");
        let mut next = Some(url.to_string());
        let mut ids = Vec::new();
        let what = format!("listing the items of '{dataset}'");
        while let Some(url) = next {
            let page: Page = self.get_json(&what, &url).await?;
            ids.extend(page.items.into_iter().map(|e| e.id));
            next = page.next.map(|path| self.hub_path(&path));
        }
        Ok(ids)
    }

    /// An item's question and its images' labels and PNG bytes.
    pub async fn item(
        &self,
        dataset: &str,
        item: &str,
    ) -> Result<(String, Vec<(String, Bytes)>), AppError> {
        #[derive(Deserialize)]
        struct Image {
            label: String,
            url: String,
        }
        #[derive(Deserialize)]
        struct Item {
            question: String,
            images: Vec<Image>,
        }
        let what = format!("reading item '{item}' of '{dataset}'");
        let url = self.api_url(&["datasets", dataset, "items", item])?;
        let shown: Item = self.get_json(&what, url.as_str()).await?;
        let mut pngs = Vec::with_capacity(shown.images.len());
        for image in shown.images {
            let url = self.hub_path(&image.url);
            let reply = self.send(&what, || self.client.get(&url)).await?;
            let png = reply.bytes().await.map_err(|e| {
                AppError::Unavailable(format!("{what}: reading frame {}: {e}", image.url))
            })?;
            pngs.push((image.label, png));
        }
        Ok((shown.question, pngs))
    }

    /// The datasets of a study: its baseline, then each variant's.
    pub async fn study_datasets(&self, study: &str) -> Result<Vec<String>, AppError> {
        #[derive(Deserialize)]
        struct Variant {
            dataset: String,
        }
        #[derive(Deserialize)]
        struct Study {
            baseline: String,
            variants: Vec<Variant>,
        }
        let url = self.api_url(&["studies", study])?;
        let view: Study = self
            .get_json(&format!("reading study '{study}'"), url.as_str())
            .await?;
        Ok(std::iter::once(view.baseline)
            .chain(view.variants.into_iter().map(|v| v.dataset))
            .collect())
    }

    /// Posts a submission; returns its id.
    pub async fn submit(
        &self,
        dataset: &str,
        metadata: &SubmissionMetadata,
        key: &str,
        body: String,
    ) -> Result<i64, AppError> {
        #[derive(Deserialize)]
        struct Created {
            id: i64,
        }
        let mut url = self.api_url(&["datasets", dataset, "submissions"])?;
        let m = metadata;
        url.query_pairs_mut()
            .append_pair("model", &m.model)
            .append_pair("description", &m.description)
            .append_pair("prompt_version", &m.prompt_version)
            .append_pair("notes", &m.notes);
        let body = Bytes::from(body);
        let what = format!("submitting to '{dataset}'");
        let reply = self
            .send(&what, || {
                self.client
                    .post(url.clone())
                    .bearer_auth(&self.token)
                    .header("Idempotency-Key", key)
                    .header(reqwest::header::CONTENT_TYPE, "application/x-ndjson")
                    .body(body.clone())
            })
            .await?;
        let created: Created = reply.json().await.map_err(|e| {
            AppError::Unavailable(format!("{what}: the hub's reply is unreadable: {e}"))
        })?;
        Ok(created.id)
    }
}

/// An error reply of the hub as the error of the same kind, with its message and problems.
async fn hub_error(what: &str, reply: reqwest::Response) -> AppError {
    let status = reply.status().as_u16();
    let body: serde_json::Value = reply.json().await.unwrap_or(serde_json::Value::Null);
    let mut message = body
        .get("error")
        .and_then(serde_json::Value::as_str)
        .unwrap_or("(no message)")
        .to_owned();
    if let Some(problems) = body.get("problems").and_then(serde_json::Value::as_array) {
        for problem in problems.iter().take(5) {
            let line = problem.get("line").and_then(serde_json::Value::as_u64);
            let said = problem.get("message").and_then(serde_json::Value::as_str);
            if let (Some(line), Some(said)) = (line, said) {
                message.push_str(&format!("; line {line}: {said}"));
            }
        }
    }
    let message = format!("{what}: the hub answered {status}: {message}");
    match status {
        401 => AppError::Unauthenticated(message),
        403 => AppError::NotPermitted(message),
        404 => AppError::NotFound(message),
        409 => AppError::Conflict(message),
        413 => AppError::TooLarge(message),
        429 => AppError::LimitReached {
            message,
            retry_after: None,
        },
        400..=499 => AppError::Invalid(message),
        _ => AppError::Unavailable(message),
    }
}
