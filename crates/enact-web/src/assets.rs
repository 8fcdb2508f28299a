//! Static files, embedded in the binary so the service is one file with no external requests.

use axum::Router;
use axum::http::{HeaderValue, header};
use axum::response::IntoResponse;
use axum::routing::get;

use super::AppState;

const APP_CSS: &str = include_str!("../../../static/app.css");
const ANNOTATE_JS: &str = include_str!("../../../static/annotate.js");
const RUN_PROGRESS_JS: &str = include_str!("../../../static/run_progress.js");
const EPISODE_JS: &str = include_str!("../../../static/episode.js");
const EPISODE_CSS: &str = include_str!("../../../static/episode.css");
const FAVICON_SVG: &str = include_str!("../../../static/favicon.svg");

pub fn router() -> Router<AppState> {
    Router::new()
        .route(
            "/static/app.css",
            get(|| asset("text/css; charset=utf-8", APP_CSS)),
        )
        .route(
            "/static/annotate.js",
            get(|| asset("text/javascript; charset=utf-8", ANNOTATE_JS)),
        )
        .route(
            "/static/run_progress.js",
            get(|| asset("text/javascript; charset=utf-8", RUN_PROGRESS_JS)),
        )
        .route(
            "/static/episode.js",
            get(|| asset("text/javascript; charset=utf-8", EPISODE_JS)),
        )
        .route(
            "/static/episode.css",
            get(|| asset("text/css; charset=utf-8", EPISODE_CSS)),
        )
        .route(
            "/static/favicon.svg",
            get(|| asset("image/svg+xml", FAVICON_SVG)),
        )
        // Browsers ask for /favicon.ico whatever the page says; the SVG answers it too.
        .route("/favicon.ico", get(|| asset("image/svg+xml", FAVICON_SVG)))
}

async fn asset(content_type: &'static str, body: &'static str) -> impl IntoResponse {
    (
        [
            (header::CONTENT_TYPE, HeaderValue::from_static(content_type)),
            (
                header::CACHE_CONTROL,
                HeaderValue::from_static("public, max-age=3600"),
            ),
        ],
        body,
    )
}
