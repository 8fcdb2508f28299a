//! The one error type at the HTTP boundary, [`AppError`] (defined with the use cases in
//! [`crate::app`]), as a JSON body or as a page: its status codes, headers and rendering.
//! Internal details go to the log only.

use askama::Template;
use axum::Json;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{Html, IntoResponse, Response};
use serde::Serialize;

pub use crate::app::AppError;

impl AppError {
    pub fn status(&self) -> StatusCode {
        match self {
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

    fn log_if_internal(&self) {
        match self {
            AppError::Internal(e) => tracing::error!(error = ?e, "request failed"),
            AppError::Unavailable(why) => tracing::error!(error = %why, "request failed"),
            _ => {}
        }
    }
}

impl From<askama::Error> for AppError {
    fn from(e: askama::Error) -> Self {
        AppError::Internal(e.into())
    }
}

#[derive(Serialize)]
struct ErrorBody<'a> {
    error: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    problems: Option<&'a [crate::core::submission::LineProblem]>,
}

impl IntoResponse for AppError {
    fn into_response(self) -> Response {
        self.log_if_internal();
        let body = ErrorBody {
            error: self.to_string(),
            problems: match &self {
                AppError::Rejected { problems, .. } => Some(problems),
                _ => None,
            },
        };
        let mut response = (self.status(), Json(body)).into_response();
        match &self {
            AppError::Unauthenticated(_) => {
                response.headers_mut().insert(
                    header::WWW_AUTHENTICATE,
                    HeaderValue::from_static("Bearer realm=\"enact-hub\""),
                );
            }
            AppError::LimitReached {
                retry_after: Some(retry_after),
                ..
            } => {
                response
                    .headers_mut()
                    .insert(header::RETRY_AFTER, HeaderValue::from(*retry_after));
            }
            AppError::Unavailable(_) => retry_soon(&mut response),
            _ => {}
        }
        response
    }
}

/// Seconds a client is asked to wait before retrying a `503`: a busy database is free again
/// once the write holding its lock (one batch of an import, at most) commits.
const UNAVAILABLE_RETRY_AFTER: u32 = 1;

fn retry_soon(response: &mut Response) {
    response.headers_mut().insert(
        header::RETRY_AFTER,
        HeaderValue::from(UNAVAILABLE_RETRY_AFTER),
    );
}

/// The same errors, shown as a page to people browsing the site.
#[derive(Debug)]
pub struct PageError(pub AppError);

impl<E: Into<AppError>> From<E> for PageError {
    fn from(e: E) -> Self {
        PageError(e.into())
    }
}

#[derive(Template)]
#[template(path = "error.html")]
struct ErrorPage<'a> {
    status: u16,
    reason: &'a str,
    message: String,
}

impl IntoResponse for PageError {
    fn into_response(self) -> Response {
        let error = self.0;
        error.log_if_internal();
        let status = error.status();
        let page = ErrorPage {
            status: status.as_u16(),
            reason: status.canonical_reason().unwrap_or("Error"),
            message: error.to_string(),
        };
        let mut response = match page.render() {
            Ok(html) => (status, Html(html)).into_response(),
            Err(_) => (status, error.to_string()).into_response(),
        };
        if matches!(error, AppError::Unavailable(_)) {
            retry_soon(&mut response);
        }
        response
    }
}
