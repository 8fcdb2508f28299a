//! The HTTP service: application state, the router, and the server's life cycle. Handlers
//! parse a request, call one use case of [`crate::app`] and render its result.
//!
//! `api` serves JSON under `/api/v1`, `pages` the HTML site, `assets` the embedded CSS and
//! scripts; `auth` checks API tokens (before the handler, for every route whose table entry
//! asks for one), `session` logs annotators in (and gates the admin pages), `annotate` is
//! their side of human annotation and `admin`, `admin_tokens` and `admin_audit` the admins';
//! `error_analysis` serves the error taxonomy as JSON and pages; `challenge` hidden datasets
//! split into a public and a private part (the admin API and page, submitters' selections);
//! `episodes` the curators' pages for real-world episodes (key frames, the scene-graph editor,
//! comparison and resolution); `statements` a submission's signed statement, the hub's public
//! keys and their rotation.
//! Each page module exposes one `router()`; they are merged once in [`router`], the admin
//! pages behind one gate ([`admin_pages`]). The JSON routes are one table instead ([`api_routes`]): the `/api/v1`
//! router, its authorization and the OpenAPI document (`openapi`) are all built from it.
//! `extract` holds the extractors whose rejections are the JSON error body; `i18n` the pages'
//! languages (message catalogues, the request's locale), `locale_switch` the switch.

/// The benchmark and the use cases, named as the handlers call them.
use enact_app as app;
use enact_core as core;

mod admin;
mod admin_audit;
mod admin_tokens;
mod agreement;
mod annotate;
mod annotator_controls;
mod api;
mod archive;
mod assets;
mod auth;
mod challenge;
mod compare;
mod cookies;
mod episodes;
pub mod error;
mod error_analysis;
mod explore;
mod extract;
pub mod forwarded;
pub mod i18n;
mod imports;
mod leaderboard;
mod locale_switch;
mod metrics;
pub mod openapi;
mod pages;
mod paper;
mod quality;
mod red_flags;
mod reported;
mod rescore;
mod run_pages;
mod runs;
pub mod session;
mod statements;
mod studies;
mod submissions;

use std::future::Future;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use axum::Router;
use axum::extract::{DefaultBodyLimit, MatchedPath, Request};
use axum::http::{HeaderValue, StatusCode};
use tokio::net::TcpListener;
use tower_http::request_id::{MakeRequestUuid, PropagateRequestIdLayer, SetRequestIdLayer};
use tower_http::timeout::TimeoutLayer;
use tower_http::trace::TraceLayer;

pub use error::{ApiError, AppError};

use crate::app::Hub;

/// Settings of a running server that handlers may need.
#[derive(Debug, Clone)]
pub struct WebConfig {
    /// Largest request body accepted, in bytes.
    pub body_limit: usize,
    /// A request taking longer than this is answered with 408.
    pub request_timeout: Duration,
    /// Largest submission body accepted, in bytes (other routes use `body_limit`).
    pub submission_body_limit: usize,
    /// Reverse proxies whose `X-Forwarded-For` names the client (none by default).
    pub trusted_proxies: Vec<forwarded::TrustedProxy>,
    /// A bearer token `GET /metrics` accepts besides admin tokens (for a Prometheus scraper).
    pub metrics_token: Option<String>,
}

impl Default for WebConfig {
    fn default() -> Self {
        WebConfig {
            body_limit: 2 * 1024 * 1024,
            request_timeout: Duration::from_secs(30),
            // A full ENACT-format file (8,972 QA records with answers) is about 27 MB.
            submission_body_limit: 64 * 1024 * 1024,
            trusted_proxies: Vec::new(),
            metrics_token: None,
        }
    }
}

/// What handlers share: the use cases' [`Hub`], and what only HTTP needs.
#[derive(Clone)]
pub struct AppState {
    pub hub: Hub,
    submission_body_limit: usize,
    logins: Arc<session::LoginLimiter>,
    sessions: Arc<session::SessionCache>,
    trusted_proxies: Arc<[forwarded::TrustedProxy]>,
    /// SHA-256 of `WebConfig::metrics_token`, compared as API tokens are.
    metrics_token_hash: Option<Arc<str>>,
}

impl AppState {
    pub fn new(hub: Hub, config: &WebConfig) -> Self {
        AppState {
            hub,
            submission_body_limit: config.submission_body_limit,
            logins: Arc::new(session::LoginLimiter::default()),
            sessions: Arc::new(session::SessionCache::default()),
            trusted_proxies: config.trusted_proxies.clone().into(),
            metrics_token_hash: config
                .metrics_token
                .as_deref()
                .map(|t| Arc::from(crate::core::credentials::token_hash(t))),
        }
    }
}

async fn healthz(axum::extract::State(state): axum::extract::State<AppState>) -> StatusCode {
    if state.hub.healthy().await {
        StatusCode::OK
    } else {
        StatusCode::SERVICE_UNAVAILABLE
    }
}

async fn version(
    axum::extract::State(state): axum::extract::State<AppState>,
) -> Result<extract::Json<crate::app::version::BuildReport>, ApiError> {
    Ok(extract::Json(
        crate::app::version::describe(&state.hub).await?,
    ))
}

/// Every route of the JSON API, in the order the document lists them.
pub fn api_routes() -> Vec<openapi::ApiRoute> {
    let mut routes = vec![
        openapi::ApiRoute::new(openapi::Verb::Get, "/version", version, "This build")
            .describe(
                "The version and git commit the server was built from (what `enact-hub \
                 --version` prints) and its database's backend and schema version: the highest \
                 migration applied, and the highest this build knows.",
            )
            .responds_json::<crate::app::version::BuildReport>(200, "The build and its schema.")
            .errors(&[]),
    ];
    routes.extend(api::routes());
    routes.extend(archive::routes());
    routes.extend(submissions::routes());
    routes.extend(statements::routes());
    routes.extend(leaderboard::api_routes());
    routes.extend(challenge::routes());
    routes.extend(error_analysis::routes());
    routes.extend(studies::routes());
    routes.extend(imports::routes());
    routes.extend(rescore::routes());
    routes.extend(runs::routes());
    routes.extend(quality::routes());
    routes.extend(annotator_controls::routes());
    routes.extend(reported::routes());
    routes.extend(red_flags::routes());
    routes.extend(compare::routes());
    routes.extend(explore::routes());
    routes.push(
        openapi::ApiRoute::new(
            openapi::Verb::Get,
            "/openapi.json",
            openapi::openapi_json,
            "This document",
        )
        .describe(
            "The OpenAPI 3.1 description of every route under /api/v1, built from the same \
                 table the router is built from. Rendered as HTML at /api/docs.",
        )
        .responds(200, Some("application/json"), "The OpenAPI document."),
    );
    routes
}

/// `text` with anything outside `[A-Za-z0-9._-]` replaced by `_`: safe as a file name and
/// inside a quoted `Content-Disposition` header.
fn file_name_safe(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The policy every response carries: scripts, styles and images from this origin only (no
/// inline script or style anywhere), no framing, no plugins. Images may also come from
/// `frame_origin`, where frame requests are redirected to presigned object-store URLs.
fn content_security_policy(frame_origin: Option<&str>) -> HeaderValue {
    let img_src = match frame_origin {
        Some(origin) => format!("'self' data: {origin}"),
        None => "'self' data:".to_owned(),
    };
    HeaderValue::from_str(&format!(
        "default-src 'self'; img-src {img_src}; style-src 'self'; script-src 'self'; \
         object-src 'none'; base-uri 'none'; form-action 'self'; frame-ancestors 'none'"
    ))
    .unwrap_or_else(|_| HeaderValue::from_static("default-src 'self'"))
}

/// Security headers on every response (a handler's own value wins).
async fn security_headers(
    policy: HeaderValue,
    mut response: axum::response::Response,
) -> axum::response::Response {
    use axum::http::{HeaderName, header};
    let headers = response.headers_mut();
    headers
        .entry(header::CONTENT_SECURITY_POLICY)
        .or_insert(policy);
    let set: [(HeaderName, &'static str); 3] = [
        (header::X_CONTENT_TYPE_OPTIONS, "nosniff"),
        (header::X_FRAME_OPTIONS, "DENY"),
        // Invite and login links carry their secret in the path: never send it on.
        (header::REFERRER_POLICY, "no-referrer"),
    ];
    for (name, value) in set {
        headers
            .entry(name)
            .or_insert(HeaderValue::from_static(value));
    }
    response
}

/// Every admin page, behind one gate ([`session::admin_only`]) that refuses anyone but a
/// logged-in admin before a handler runs, so before a form is read.
fn admin_pages(state: &AppState) -> Router<AppState> {
    Router::new()
        .merge(admin::router())
        .merge(agreement::router())
        .merge(admin_tokens::router())
        .merge(admin_audit::router())
        .merge(studies::admin_router())
        .merge(reported::admin_router())
        .merge(red_flags::admin_router())
        .merge(imports::router())
        .merge(rescore::router())
        .merge(quality::router())
        .merge(annotator_controls::router())
        .merge(challenge::admin_router())
        .merge(run_pages::admin_router())
        .merge(episodes::admin_router())
        .route_layer(axum::middleware::from_fn_with_state(
            state.clone(),
            session::admin_only,
        ))
}

/// The whole application with its middleware; `frame_origin` is where frame requests may be
/// redirected ([`crate::app::frames::redirect_origin`]).
pub fn router(state: AppState, config: &WebConfig, frame_origin: Option<&str>) -> Router {
    let policy = content_security_policy(frame_origin);
    let trace = TraceLayer::new_for_http().make_span_with(|request: &Request| {
        let route = request
            .extensions()
            .get::<MatchedPath>()
            .map(MatchedPath::as_str)
            .unwrap_or("unmatched");
        // Set by the request-id layer outside this one (or by a proxy in front), echoed in
        // the response: a log line can be found from the id a user reports.
        let request_id = request
            .headers()
            .get("x-request-id")
            .and_then(|v| v.to_str().ok())
            .unwrap_or("");
        tracing::info_span!(
            "request",
            method = %request.method(),
            route,
            uri = %request.uri(),
            request_id
        )
    });
    Router::new()
        .route("/healthz", axum::routing::get(healthz))
        .merge(pages::router())
        .merge(leaderboard::page_router())
        .merge(error_analysis::page_router())
        .merge(session::router())
        .merge(annotate::router())
        .merge(episodes::router())
        .merge(admin_pages(&state))
        .merge(studies::page_router())
        .merge(paper::page_router())
        .merge(compare::page_router())
        .merge(explore::page_router())
        .merge(run_pages::page_router())
        .merge(assets::router())
        .merge(openapi::page_router())
        .merge(metrics::router(&state))
        .merge(locale_switch::router())
        .nest(
            openapi::API_PREFIX,
            openapi::api_router(api_routes(), &state),
        )
        // Inside the router, so the route's pattern is known when it counts.
        .route_layer(axum::middleware::from_fn_with_state(
            state.clone(),
            metrics::count_requests,
        ))
        .with_state(state)
        .layer(axum::middleware::from_fn(error::localize_error_pages))
        .layer(axum::middleware::map_response(move |response| {
            security_headers(policy.clone(), response)
        }))
        .layer(DefaultBodyLimit::max(config.body_limit))
        .layer(TimeoutLayer::with_status_code(
            StatusCode::REQUEST_TIMEOUT,
            config.request_timeout,
        ))
        .layer(trace)
        .layer(PropagateRequestIdLayer::x_request_id())
        .layer(SetRequestIdLayer::x_request_id(MakeRequestUuid))
}

/// A bound server, ready to run. Binding is separate from running so tests can ask for port 0
/// and learn the address.
pub struct Server {
    listener: TcpListener,
    app: Router,
    state: AppState,
}

impl Server {
    pub async fn bind(addr: SocketAddr, hub: Hub, config: &WebConfig) -> std::io::Result<Server> {
        let frame_origin = crate::app::frames::redirect_origin(&hub).await;
        let state = AppState::new(hub, config);
        let listener = TcpListener::bind(addr).await?;
        Ok(Server {
            listener,
            app: router(state.clone(), config, frame_origin.as_deref()),
            state,
        })
    }

    pub fn local_addr(&self) -> std::io::Result<SocketAddr> {
        self.listener.local_addr()
    }

    /// Serves until `shutdown` completes, then finishes the requests in flight.
    pub async fn run(
        self,
        shutdown: impl Future<Output = ()> + Send + 'static,
    ) -> std::io::Result<()> {
        let watcher = tokio::spawn(self.state.hub.clone().watch_content());
        let sessions = self.state.sessions.clone();
        let changes = self.state.hub.subscribe();
        let follower = tokio::spawn(async move { sessions.follow(changes).await });
        // The first login with an unknown name must not pay for the hash it is checked against.
        tokio::spawn(async {
            if let Err(e) = crate::app::annotators::prepare_login().await {
                tracing::warn!(error = %e, "the hash unknown login names are checked against");
            }
        });
        // Connection info gives the login rate limit the client's address.
        let result = axum::serve(
            self.listener,
            self.app.into_make_service_with_connect_info::<SocketAddr>(),
        )
        .with_graceful_shutdown(shutdown)
        .await;
        watcher.abort();
        follower.abort();
        result
    }
}

/// Completes on SIGINT (Ctrl-C) or SIGTERM.
pub async fn shutdown_signal() {
    let ctrl_c = async {
        if let Err(e) = tokio::signal::ctrl_c().await {
            tracing::error!(error = %e, "cannot listen for Ctrl-C");
            std::future::pending::<()>().await;
        }
    };
    #[cfg(unix)]
    let terminate = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut signal) => {
                signal.recv().await;
            }
            Err(e) => {
                tracing::error!(error = %e, "cannot listen for SIGTERM");
                std::future::pending::<()>().await;
            }
        }
    };
    #[cfg(not(unix))]
    let terminate = std::future::pending::<()>();
    tokio::select! {
        () = ctrl_c => {},
        () = terminate => {},
    }
    tracing::info!("shutting down: finishing requests in flight");
}
