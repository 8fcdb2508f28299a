//! Bearer-token authorization of the JSON API: [`require_scope`], the layer that
//! [`super::openapi::api_router`] puts in front of every route the table marks
//! [`Access::Bearer`](super::openapi::Access), and the [`Caller`] extractor through which
//! handlers learn who passed it.

use axum::extract::{FromRequestParts, Request, State};
use axum::http::request::Parts;
use axum::http::{HeaderMap, header};
use axum::middleware::Next;
use axum::response::Response;

use super::{ApiError, AppError, AppState};
use crate::app::refusal::Refusal;
use crate::app::tokens::{self, Caller};
use crate::core::credentials::Scope;

/// What [`require_scope`] needs: the use cases, and the scope the route's table entry names.
#[derive(Clone)]
pub(super) struct ScopeGuard {
    pub state: AppState,
    pub scope: Scope,
}

/// Refuses a request without a live token holding the route's scope (401 or 403), before the
/// handler reads anything; lets the rest through with their [`Caller`].
pub(super) async fn require_scope(
    State(guard): State<ScopeGuard>,
    mut request: Request,
    next: Next,
) -> Result<Response, ApiError> {
    let token = bearer_token(request.headers())?.to_owned();
    let caller = tokens::authorize(&guard.state.hub, &token, guard.scope).await?;
    request.extensions_mut().insert(caller);
    Ok(next.run(request).await)
}

/// The token of an `Authorization: Bearer TOKEN` header.
pub(super) fn bearer_token(headers: &HeaderMap) -> Result<&str, ApiError> {
    let header = headers
        .get(header::AUTHORIZATION)
        .ok_or(Refusal::TokenMissing)?
        .to_str()
        .map_err(|_| Refusal::AuthorizationMalformed)?;
    header
        .strip_prefix("Bearer ")
        .or_else(|| header.strip_prefix("bearer "))
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .ok_or(Refusal::AuthorizationMalformed)
        .map_err(ApiError::from)
}

/// The caller [`require_scope`] let through. A handler that asks for one on a route the table
/// calls public is a mistake in the table, answered with 500 (the authorization tests call
/// every route).
pub struct TokenCaller(pub Caller);

impl<S: Send + Sync> FromRequestParts<S> for TokenCaller {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, _: &S) -> Result<Self, ApiError> {
        let caller = parts.extensions.get::<Caller>().cloned().map(TokenCaller);
        caller.ok_or_else(|| {
            ApiError(AppError::internal(format!(
                "{} {} reads its caller, but its route table entry asks for no token",
                parts.method,
                parts.uri.path()
            )))
        })
    }
}
