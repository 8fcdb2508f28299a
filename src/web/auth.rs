//! Bearer-token authentication: the `Caller` extractor.

use axum::extract::FromRequestParts;
use axum::http::header;
use axum::http::request::Parts;

use super::{AppError, AppState};
use crate::app::tokens::{self, Caller};

impl FromRequestParts<AppState> for Caller {
    type Rejection = AppError;

    async fn from_request_parts(parts: &mut Parts, state: &AppState) -> Result<Self, AppError> {
        let header = parts
            .headers
            .get(header::AUTHORIZATION)
            .ok_or_else(|| {
                AppError::Unauthenticated(
                    "this endpoint needs an API token: send `Authorization: Bearer TOKEN`"
                        .to_owned(),
                )
            })?
            .to_str()
            .map_err(|_| {
                AppError::Unauthenticated("the Authorization header is not text".to_owned())
            })?;
        let token = header
            .strip_prefix("Bearer ")
            .or_else(|| header.strip_prefix("bearer "))
            .map(str::trim)
            .filter(|t| !t.is_empty())
            .ok_or_else(|| {
                AppError::Unauthenticated(
                    "the Authorization header must read `Bearer TOKEN`".to_owned(),
                )
            })?;
        tokens::authenticate(&state.hub, token).await
    }
}
