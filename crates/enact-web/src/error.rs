//! The one error type at the HTTP boundary: a use case's [`AppError`] (defined with the use cases
//! in [`crate::app`], which know nothing of HTTP) answered as a JSON body ([`ApiError`]) or as a
//! page ([`PageError`]): its status codes, headers and rendering. Internal details go to the log
//! only.

use askama::Template;
use axum::Json;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{Html, IntoResponse, Response};
use serde::Serialize;

pub use crate::app::AppError;
use crate::app::refusal::{Refusal, RefusalKind};

use super::i18n::{Locale, Tr, msg};

/// The status an error is answered with.
pub fn status_of(error: &AppError) -> StatusCode {
    match error {
        AppError::Refused(r) => match r.kind() {
            RefusalKind::NotFound => StatusCode::NOT_FOUND,
            RefusalKind::Invalid => StatusCode::BAD_REQUEST,
            RefusalKind::Unauthenticated => StatusCode::UNAUTHORIZED,
            RefusalKind::NotPermitted => StatusCode::FORBIDDEN,
            RefusalKind::Conflict => StatusCode::CONFLICT,
            RefusalKind::LimitReached => StatusCode::TOO_MANY_REQUESTS,
        },
        AppError::NotFound(_) => StatusCode::NOT_FOUND,
        AppError::Invalid(_) => StatusCode::BAD_REQUEST,
        AppError::Unauthenticated(_) => StatusCode::UNAUTHORIZED,
        AppError::NotPermitted(_) => StatusCode::FORBIDDEN,
        AppError::Conflict(_) => StatusCode::CONFLICT,
        AppError::TooLarge(_) => StatusCode::PAYLOAD_TOO_LARGE,
        AppError::UnsupportedFormat(_) => StatusCode::UNSUPPORTED_MEDIA_TYPE,
        AppError::Rejected { .. } => StatusCode::UNPROCESSABLE_ENTITY,
        AppError::LimitReached { .. } => StatusCode::TOO_MANY_REQUESTS,
        AppError::Unavailable(_) => StatusCode::SERVICE_UNAVAILABLE,
        AppError::Internal(_) => StatusCode::INTERNAL_SERVER_ERROR,
    }
}

fn log_if_internal(error: &AppError) {
    match error {
        AppError::Internal(e) => tracing::error!(error = ?e, "request failed"),
        AppError::Unavailable(why) => tracing::error!(error = %why, "request failed"),
        _ => {}
    }
}

/// A use case's error answered as JSON: what every API handler returns. Anything a use case
/// returns converts with `?`.
#[derive(Debug)]
pub struct ApiError(pub AppError);

impl<E: Into<AppError>> From<E> for ApiError {
    fn from(e: E) -> Self {
        ApiError(e.into())
    }
}

impl ApiError {
    pub fn status(&self) -> StatusCode {
        status_of(&self.0)
    }
}

impl std::fmt::Display for ApiError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

/// A template rendered for a response; a template that fails to render is the server's fault.
pub trait RenderPage: Template {
    fn render_page(&self) -> Result<String, ApiError> {
        self.render()
            .map_err(|e| AppError::Internal(e.into()))
            .map_err(ApiError)
    }
}

impl<T: Template> RenderPage for T {}

#[derive(Serialize)]
struct ErrorBody<'a> {
    error: String,
    /// The reason's stable code ([`AppError::code`]).
    code: &'static str,
    /// The values a typed refusal names, by name (`item`, `dataset`, `limit`, ...).
    #[serde(skip_serializing_if = "Option::is_none")]
    details: Option<serde_json::Map<String, serde_json::Value>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    problems: Option<&'a [crate::core::submission::LineProblem]>,
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let ApiError(error) = self;
        log_if_internal(&error);
        let body = ErrorBody {
            error: error.to_string(),
            code: error.code(),
            details: match &error {
                AppError::Refused(r) => Some(
                    r.details()
                        .iter()
                        .map(|(name, d)| ((*name).to_owned(), d.into()))
                        .collect(),
                ),
                _ => None,
            },
            problems: match &error {
                AppError::Rejected { problems, .. } => Some(problems),
                _ => None,
            },
        };
        let status = status_of(&error);
        let mut response = (status, Json(body)).into_response();
        match &error {
            _ if status == StatusCode::UNAUTHORIZED => {
                response.headers_mut().insert(
                    header::WWW_AUTHENTICATE,
                    HeaderValue::from_static("Bearer realm=\"enact-hub\""),
                );
            }
            AppError::LimitReached {
                retry_after: Some(seconds),
                ..
            } => retry_after(&mut response, *seconds),
            AppError::Refused(r) => {
                if let Some(seconds) = r.retry_after() {
                    retry_after(&mut response, seconds);
                }
            }
            AppError::Unavailable(_) => retry_soon(&mut response),
            _ => {}
        }
        response
    }
}

/// Seconds a client is asked to wait before retrying a `503`: a busy database is free again
/// once the write holding its lock (one batch of an import, at most) commits.
const UNAVAILABLE_RETRY_AFTER: u64 = 1;

fn retry_soon(response: &mut Response) {
    retry_after(response, UNAVAILABLE_RETRY_AFTER);
}

/// `Retry-After: seconds`: when asking again may succeed.
fn retry_after(response: &mut Response, seconds: u64) {
    response
        .headers_mut()
        .insert(header::RETRY_AFTER, HeaderValue::from(seconds));
}

/// The same errors, shown as a page to people browsing the site.
#[derive(Debug)]
pub struct PageError(pub AppError);

impl<E: Into<AppError>> From<E> for PageError {
    fn from(e: E) -> Self {
        PageError(e.into())
    }
}

impl From<ApiError> for PageError {
    fn from(ApiError(e): ApiError) -> Self {
        PageError(e)
    }
}

#[derive(Template)]
#[template(path = "error.html")]
struct ErrorPage<'a> {
    tr: Tr,
    status: u16,
    reason: String,
    /// What the status means, in the page's language.
    explanation: String,
    /// The error's own message: in the page's language for a typed refusal, else in English
    /// as the use case wrote it (and marked so).
    message: &'a str,
    message_in_english: bool,
}

/// An error page waiting for its language: [`PageError`] leaves this on the response, and
/// [`localize_error_pages`], which sees the request, renders it.
#[derive(Clone)]
struct ErrorPageParts {
    status: StatusCode,
    message: String,
    refusal: Option<Refusal>,
}

impl ErrorPageParts {
    fn render(&self, tr: Tr) -> Response {
        let (reason, explanation) = status_keys(self.status);
        let localized = self.refusal.as_ref().map(|r| tr.refusal(r));
        let page = ErrorPage {
            status: self.status.as_u16(),
            reason: tr.t(reason),
            explanation: tr.t(explanation),
            message: localized.as_deref().unwrap_or(&self.message),
            message_in_english: localized.is_none(),
            tr,
        };
        match page.render() {
            Ok(html) => (self.status, Html(html)).into_response(),
            Err(_) => (self.status, self.message.clone()).into_response(),
        }
    }
}

/// The message keys of a page error's heading and explanation, for its status. Written out
/// (not built from the number) so that the catalogue check sees every key.
fn status_keys(status: StatusCode) -> (&'static str, &'static str) {
    match status.as_u16() {
        400 => (msg("error-reason-400"), msg("error-explain-400")),
        401 => (msg("error-reason-401"), msg("error-explain-401")),
        403 => (msg("error-reason-403"), msg("error-explain-403")),
        404 => (msg("error-reason-404"), msg("error-explain-404")),
        409 => (msg("error-reason-409"), msg("error-explain-409")),
        413 => (msg("error-reason-413"), msg("error-explain-413")),
        415 => (msg("error-reason-415"), msg("error-explain-415")),
        422 => (msg("error-reason-422"), msg("error-explain-422")),
        429 => (msg("error-reason-429"), msg("error-explain-429")),
        503 => (msg("error-reason-503"), msg("error-explain-503")),
        _ => (msg("error-reason-500"), msg("error-explain-500")),
    }
}

impl IntoResponse for PageError {
    fn into_response(self) -> Response {
        let error = self.0;
        log_if_internal(&error);
        let parts = ErrorPageParts {
            status: status_of(&error),
            message: error.to_string(),
            refusal: match &error {
                AppError::Refused(r) => Some(r.clone()),
                _ => None,
            },
        };
        // English until `localize_error_pages` renders it in the request's language.
        let mut response = parts.render(Tr::new(Locale::English));
        if matches!(error, AppError::Unavailable(_)) {
            retry_soon(&mut response);
        }
        response.extensions_mut().insert(parts);
        response
    }
}

/// Renders the error pages of the routes it wraps in the request's language, and marks every
/// page as varying with what chooses the language.
pub(super) async fn localize_error_pages(
    request: axum::extract::Request,
    next: axum::middleware::Next,
) -> Response {
    let tr = Tr::of_request(request.headers(), request.uri());
    let mut response = next.run(request).await;
    let html = response
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.starts_with("text/html"));
    if html {
        // A page's language follows these headers: caches must keep one copy per value.
        response.headers_mut().append(
            header::VARY,
            HeaderValue::from_static("accept-language, cookie"),
        );
    }
    match response.extensions().get::<ErrorPageParts>() {
        Some(parts) => {
            let mut localized = parts.render(tr);
            // Keep the headers the handler set (Retry-After, cookies), not its body.
            let (head, _) = response.into_parts();
            for (name, value) in &head.headers {
                if name != header::CONTENT_TYPE && name != header::CONTENT_LENGTH {
                    localized.headers_mut().append(name, value.clone());
                }
            }
            localized
        }
        _ => response,
    }
}
