//! The extractors handlers use, each refusing bad input with [`ApiError`]'s JSON body (or
//! page) rather than axum's plain-text rejections: `Json`, `Query` and `Path` wrap axum's own,
//! and [`IdempotencyKey`] reads the header the submission route honours.

use axum::extract::rejection::{JsonRejection, PathRejection, QueryRejection};
use axum::extract::{FromRequest, FromRequestParts, Request};
use axum::http::request::Parts;
use axum::response::{IntoResponse, Response};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::AppError;
use super::error::ApiError;
use crate::app::refusal::{Expected, Refusal};

/// A JSON body in, or a JSON body out.
pub struct Json<T>(pub T);

impl<T: DeserializeOwned, S: Send + Sync> FromRequest<S> for Json<T> {
    type Rejection = ApiError;

    async fn from_request(request: Request, state: &S) -> Result<Self, ApiError> {
        match axum::Json::<T>::from_request(request, state).await {
            Ok(axum::Json(value)) => Ok(Json(value)),
            Err(rejection) => Err(ApiError(json_refused(rejection))),
        }
    }
}

impl<T: Serialize> IntoResponse for Json<T> {
    fn into_response(self) -> Response {
        axum::Json(self.0).into_response()
    }
}

/// Query parameters.
pub struct Query<T>(pub T);

impl<T: DeserializeOwned, S: Send + Sync> FromRequestParts<S> for Query<T> {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, state: &S) -> Result<Self, ApiError> {
        match axum::extract::Query::<T>::from_request_parts(parts, state).await {
            Ok(axum::extract::Query(value)) => Ok(Query(value)),
            Err(rejection) => Err(ApiError(query_refused(rejection))),
        }
    }
}

/// Path parameters.
pub struct Path<T>(pub T);

impl<T: DeserializeOwned + Send, S: Send + Sync> FromRequestParts<S> for Path<T> {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, state: &S) -> Result<Self, ApiError> {
        match axum::extract::Path::<T>::from_request_parts(parts, state).await {
            Ok(axum::extract::Path(value)) => Ok(Path(value)),
            Err(rejection) => Err(ApiError(path_refused(rejection))),
        }
    }
}

/// What a body that is not the route's JSON is refused as.
fn json_refused(rejection: JsonRejection) -> AppError {
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

fn query_refused(rejection: QueryRejection) -> AppError {
    AppError::Invalid(format!("query string: {}", rejection.body_text()))
}

fn path_refused(rejection: PathRejection) -> AppError {
    AppError::Invalid(format!("path: {}", rejection.body_text()))
}

/// The `Idempotency-Key` header, when sent: 1 to 200 printable characters.
pub struct IdempotencyKey(pub Option<String>);

impl<S: Send + Sync> FromRequestParts<S> for IdempotencyKey {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, _: &S) -> Result<Self, ApiError> {
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
                ApiError(AppError::Invalid(
                    "the Idempotency-Key header must be 1 to 200 printable characters".to_owned(),
                ))
            })
    }
}

/// The largest whole number [`whole_number`] reads from a float: beyond it, floats skip whole
/// numbers.
pub const MOST_WHOLE_NUMBER: i64 = 9_000_000_000_000_000;

/// A JSON number that is a whole number: `5` or `5.0`, both JSON Schema integers (serde's
/// `i64` alone would refuse the second).
pub fn whole_number<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<i64>, D::Error> {
    let Some(number) = Option::<serde_json::Number>::deserialize(d)? else {
        return Ok(None);
    };
    number
        .as_i64()
        .or_else(|| {
            number
                .as_f64()
                .filter(|f| f.fract() == 0.0 && f.abs() <= MOST_WHOLE_NUMBER as f64)
                .map(|f| f as i64)
        })
        .map(Some)
        .ok_or_else(|| serde::de::Error::custom(format!("{number} is not a whole number")))
}

/// A query parameter's or form field's `text` (trimmed) as a whole number from `least` to
/// `most`, or the refusal that names `field` and the range.
pub fn whole_number_between(
    field: &str,
    text: &str,
    least: u64,
    most: u64,
) -> Result<u64, Refusal> {
    let text = text.trim();
    text.parse::<u64>()
        .ok()
        .filter(|n| (least..=most).contains(n))
        .ok_or_else(|| Refusal::bad_value(field, text, Expected::WholeNumber { least, most }))
}

/// A required [`whole_number`].
pub fn required_whole_number<'de, D: serde::Deserializer<'de>>(d: D) -> Result<i64, D::Error> {
    whole_number(d)?.ok_or_else(|| serde::de::Error::custom("null is not a whole number"))
}
