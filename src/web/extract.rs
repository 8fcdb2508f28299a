//! The extractors handlers use, each refusing bad input with [`AppError`]'s JSON body (or
//! page) rather than axum's plain-text rejections: `Json`, `Query` and `Path` wrap axum's own,
//! and [`IdempotencyKey`] reads the header the submission route honours.

use axum::extract::rejection::{JsonRejection, PathRejection, QueryRejection};
use axum::extract::{FromRequest, FromRequestParts};
use axum::http::request::Parts;
use axum::response::{IntoResponse, Response};
use serde::Serialize;

use super::AppError;

/// A JSON body in, or a JSON body out.
#[derive(FromRequest)]
#[from_request(via(axum::Json), rejection(AppError))]
pub struct Json<T>(pub T);

impl<T: Serialize> IntoResponse for Json<T> {
    fn into_response(self) -> Response {
        axum::Json(self.0).into_response()
    }
}

/// Query parameters.
#[derive(FromRequestParts)]
#[from_request(via(axum::extract::Query), rejection(AppError))]
pub struct Query<T>(pub T);

/// Path parameters.
#[derive(FromRequestParts)]
#[from_request(via(axum::extract::Path), rejection(AppError))]
pub struct Path<T>(pub T);

impl From<JsonRejection> for AppError {
    fn from(rejection: JsonRejection) -> Self {
        let detail = rejection.body_text();
        if rejection.status() == axum::http::StatusCode::PAYLOAD_TOO_LARGE {
            return AppError::TooLarge(format!("the body is too large: {detail}"));
        }
        match rejection {
            JsonRejection::JsonDataError(_) => AppError::Rejected {
                message: format!("the JSON body does not fit this route: {detail}"),
                problems: Vec::new(),
            },
            JsonRejection::MissingJsonContentType(_) => AppError::UnsupportedFormat(
                "this route takes a JSON body: send `Content-Type: application/json`".to_owned(),
            ),
            _ => AppError::Invalid(format!("the body is not valid JSON: {detail}")),
        }
    }
}

impl From<QueryRejection> for AppError {
    fn from(rejection: QueryRejection) -> Self {
        AppError::Invalid(format!("query string: {}", rejection.body_text()))
    }
}

impl From<PathRejection> for AppError {
    fn from(rejection: PathRejection) -> Self {
        AppError::Invalid(format!("path: {}", rejection.body_text()))
    }
}

/// The `Idempotency-Key` header, when sent: 1 to 200 printable characters.
pub struct IdempotencyKey(pub Option<String>);

impl<S: Send + Sync> FromRequestParts<S> for IdempotencyKey {
    type Rejection = AppError;

    async fn from_request_parts(parts: &mut Parts, _: &S) -> Result<Self, AppError> {
        let Some(value) = parts.headers.get("idempotency-key") else {
            return Ok(IdempotencyKey(None));
        };
        value
            .to_str()
            .ok()
            .map(str::trim)
            .filter(|k| !k.is_empty() && k.len() <= 200)
            .map(|k| IdempotencyKey(Some(k.to_owned())))
            .ok_or_else(|| {
                AppError::Invalid(
                    "the Idempotency-Key header must be 1 to 200 printable characters".to_owned(),
                )
            })
    }
}
