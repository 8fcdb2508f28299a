//! `GET /metrics` (Prometheus' text format, [`crate::app::metrics`]) and the middleware that
//! counts every request by its route's pattern and status.
//!
//! The page is not public: it answers a scraper that presents the token the server was
//! started with (`serve --metrics-token`, or `ENACT_HUB_METRICS_TOKEN`) and any admin API
//! token; anyone else gets 401.

use std::time::Instant;

use axum::Router;
use axum::extract::{MatchedPath, Request, State};
use axum::http::{HeaderValue, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use super::error::ApiError;
use super::{AppState, auth};
use crate::app;
use crate::core::credentials::{self, Scope};

/// The content type of Prometheus' text format as `prometheus-client` writes it (OpenMetrics).
const CONTENT_TYPE: &str = "application/openmetrics-text; version=1.0.0; charset=utf-8";

pub(super) fn router(state: &AppState) -> Router<AppState> {
    Router::new()
        .route("/metrics", axum::routing::get(metrics))
        .route_layer(axum::middleware::from_fn_with_state(
            state.clone(),
            scraper_only,
        ))
}

async fn metrics(State(state): State<AppState>) -> Result<Response, ApiError> {
    let text = app::metrics::exposition(&state.hub).await?;
    let mut response = text.into_response();
    response
        .headers_mut()
        .insert(header::CONTENT_TYPE, HeaderValue::from_static(CONTENT_TYPE));
    Ok(response)
}

/// Lets through the metrics token or an admin token; 401 or 403 otherwise.
async fn scraper_only(
    State(state): State<AppState>,
    request: Request,
    next: Next,
) -> Result<Response, ApiError> {
    let presented = auth::bearer_token(request.headers())?;
    let is_metrics_token = state
        .metrics_token_hash
        .as_deref()
        .is_some_and(|hash| credentials::token_matches(presented, hash));
    if !is_metrics_token {
        app::tokens::authorize(&state.hub, presented, Scope::Admin).await?;
    }
    Ok(next.run(request).await)
}

/// Counts the request under its route's pattern (`unmatched` for a path no route has), its
/// method and the status answered, with the time taken.
pub(super) async fn count_requests(
    State(state): State<AppState>,
    request: Request,
    next: Next,
) -> Response {
    let started = Instant::now();
    let method = request.method().as_str().to_owned();
    let route = request
        .extensions()
        .get::<MatchedPath>()
        .map_or_else(|| "unmatched".to_owned(), |p| route_label(p.as_str()));
    let response = next.run(request).await;
    state.hub.metrics().request(
        &method,
        &route,
        response.status().as_u16(),
        started.elapsed(),
    );
    response
}

/// A route's pattern as a label value: `{name}` written `:name`, since braces inside label
/// values trip some text-format parsers.
fn route_label(pattern: &str) -> String {
    pattern.replace('{', ":").replace('}', "")
}

#[cfg(test)]
mod tests {
    use super::route_label;

    #[test]
    fn route_labels_name_parameters_with_colons() {
        assert_eq!(
            route_label("/api/v1/datasets/{dataset}/items/{item_id}"),
            "/api/v1/datasets/:dataset/items/:item_id"
        );
    }
}
