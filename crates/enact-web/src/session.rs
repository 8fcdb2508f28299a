//! Annotator accounts at the HTTP boundary: invites, login and logout, the session cookie, the
//! CSRF check every state-changing request passes, and the login rate limit.
//!
//! Sessions are opaque random tokens in an HttpOnly, SameSite=Strict cookie (Secure when the
//! request came over TLS through a proxy that says so with `X-Forwarded-Proto: https`); the
//! store keeps only their sha256. Each session has a synchronizer CSRF token that forms carry in
//! a hidden `csrf` field and scripts in the `X-CSRF-Token` header; [`Protected`] is the only way
//! a handler gets a request body, so no state-changing handler can skip the check. The login
//! and invite forms come before any session and use a double-submit cookie instead.
//!
//! The admin pages are all mounted behind [`admin_only`] (see [`super::router`]), which refuses
//! anyone but a logged-in admin before the handler runs, so before a form is read.

use std::collections::{HashMap, VecDeque};
use std::net::{IpAddr, SocketAddr};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use askama::Template;
use axum::Router;
use axum::body::Bytes;
use axum::extract::{ConnectInfo, FromRequest, FromRequestParts, Path, Request, State};
use axum::http::request::Parts;
use axum::http::{HeaderMap, HeaderValue, Method, header};
use axum::response::{AppendHeaders, Html, IntoResponse, Redirect, Response};
use axum::routing::{get, post};
use serde::Deserialize;
use serde::de::DeserializeOwned;

use super::cookies::cookie;
use super::error::{ApiError, PageError, RenderPage};
use super::i18n::{Locale, Tr, locale_cookie};
use super::{AppError, AppState};
use crate::app::annotators::{self, SESSION_LIFETIME, now_ms};
use crate::app::cache::BoundedCache;
use crate::app::changes::Change;
use crate::app::refusal::Refusal;
use crate::app::tokens;
use crate::core::annotation::Session;
use crate::core::credentials::{
    MIN_PASSWORD_CHARS, Scope, constant_time_eq, random_token, token_hash,
};

pub const SESSION_COOKIE: &str = "enact_session";
const LOGIN_CSRF_COOKIE: &str = "enact_login_csrf";
/// Failed logins allowed per window: per account, and per client address.
const ACCOUNT_FAILURES: usize = 5;
const ADDRESS_FAILURES: usize = 20;
const FAILURE_WINDOW: Duration = Duration::from_secs(15 * 60);

pub fn router() -> Router<AppState> {
    Router::new()
        .route("/login", get(login_page).post(login))
        .route("/logout", post(logout))
        .route("/invite/{token}", get(invite_page).post(accept_invite))
        .route("/login/link/{token}", get(follow_login_link))
}

/// Failed login attempts in a sliding window, per account and per client address.
#[derive(Default)]
pub struct LoginLimiter {
    failures: Mutex<HashMap<String, VecDeque<Instant>>>,
}

/// The client an address counts as for the address limit. An IPv6 host is usually given a
/// whole /64 network, so one client could try a fresh address for every attempt: IPv6
/// addresses count by their /64. An IPv4 address written as IPv6 (`::ffff:a.b.c.d`, as a
/// dual-stack socket reports it) counts as the IPv4 address.
fn address_key(address: Option<IpAddr>) -> String {
    match address {
        None => "?".to_owned(),
        Some(IpAddr::V4(v4)) => v4.to_string(),
        Some(IpAddr::V6(v6)) => match v6.to_ipv4_mapped() {
            Some(v4) => v4.to_string(),
            None => {
                let network = u128::from(v6) & !(u128::MAX >> 64);
                format!("{}/64", std::net::Ipv6Addr::from(network))
            }
        },
    }
}

impl LoginLimiter {
    fn keys(account: &str, address: Option<IpAddr>) -> [(String, usize); 2] {
        [
            (format!("account:{account}"), ACCOUNT_FAILURES),
            (
                format!("address:{}", address_key(address)),
                ADDRESS_FAILURES,
            ),
        ]
    }

    /// `Err` with a message saying what is blocked and for how long.
    pub fn check(&self, account: &str, address: Option<IpAddr>) -> Result<(), ApiError> {
        let now = Instant::now();
        let mut failures = self.failures.lock().unwrap_or_else(|p| p.into_inner());
        for (i, (key, limit)) in Self::keys(account, address).into_iter().enumerate() {
            let Some(times) = failures.get_mut(&key) else {
                continue;
            };
            while times
                .front()
                .is_some_and(|t| now.duration_since(*t) > FAILURE_WINDOW)
            {
                times.pop_front();
            }
            if times.len() >= limit {
                let wait = times
                    .front()
                    .map_or(FAILURE_WINDOW, |t| FAILURE_WINDOW - now.duration_since(*t));
                let minutes = wait.as_secs().div_ceil(60).max(1);
                let what = if i == 0 {
                    format!("account '{account}'")
                } else {
                    "your address".to_owned()
                };
                return Err(ApiError(AppError::LimitReached {
                    message: format!(
                        "too many failed logins for {what} ({limit} in {} minutes); try again in \
                         {minutes} minutes",
                        FAILURE_WINDOW.as_secs() / 60
                    ),
                    retry_after: Some(wait.as_secs().max(1)),
                }));
            }
        }
        Ok(())
    }

    pub fn record_failure(&self, account: &str, address: Option<IpAddr>) {
        let now = Instant::now();
        let mut failures = self.failures.lock().unwrap_or_else(|p| p.into_inner());
        // Bound memory under a flood of distinct names: forget everything past this size.
        if failures.len() > 100_000 {
            failures.clear();
        }
        for (key, _) in Self::keys(account, address) {
            failures.entry(key).or_default().push_back(now);
        }
    }

    pub fn record_success(&self, account: &str) {
        let mut failures = self.failures.lock().unwrap_or_else(|p| p.into_inner());
        failures.remove(&format!("account:{account}"));
    }
}

/// Sessions already looked up, by token hash, so that a page view costs no session query.
/// Sessions never change once created; logout removes its entry, expiry is checked on use.
pub struct SessionCache {
    entries: BoundedCache<String, (Session, i64)>,
}

impl Default for SessionCache {
    fn default() -> Self {
        SessionCache {
            entries: BoundedCache::by_entries("sessions", Self::MAX_ENTRIES),
        }
    }
}

impl SessionCache {
    /// Entries kept at most.
    const MAX_ENTRIES: u64 = 100_000;

    fn get(&self, token_hash: &str, now_ms: i64) -> Option<Session> {
        let key = token_hash.to_owned();
        match self.entries.get(&key) {
            Some((session, expires)) if expires > now_ms => Some(session),
            Some(_) => {
                self.entries.remove(&key);
                None
            }
            None => None,
        }
    }

    fn insert(&self, token_hash: String, session: Session, expires_at_ms: i64) {
        self.entries.insert(token_hash, (session, expires_at_ms));
    }

    fn remove(&self, token_hash: &str) {
        self.entries.remove(&token_hash.to_owned());
    }

    fn clear(&self) {
        self.entries.clear();
    }

    /// Drops the sessions other server instances ended, until the hub's announcements stop.
    pub(super) async fn follow(&self, mut changes: tokio::sync::broadcast::Receiver<Change>) {
        use tokio::sync::broadcast::error::RecvError;
        loop {
            match changes.recv().await {
                Ok(Change::SessionEnded(hash)) => self.remove(&hash),
                // Missed announcements: any session may have ended.
                Ok(Change::Everything) | Err(RecvError::Lagged(_)) => self.clear(),
                Ok(_) => {}
                Err(RecvError::Closed) => return,
            }
        }
    }
}

/// Whether the client reached us over TLS, as a TLS-terminating proxy reports it.
fn over_tls(headers: &HeaderMap) -> bool {
    headers
        .get("x-forwarded-proto")
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.eq_ignore_ascii_case("https"))
}

fn set_cookie(headers: &HeaderMap, name: &str, value: &str, max_age: Duration) -> HeaderValue {
    let secure = if over_tls(headers) { "; Secure" } else { "" };
    let cookie = format!(
        "{name}={value}; Path=/; HttpOnly; SameSite=Strict; Max-Age={}{secure}",
        max_age.as_secs()
    );
    // Tokens are hex and names are constants: always a valid header value.
    HeaderValue::from_str(&cookie).unwrap_or_else(|_| HeaderValue::from_static(""))
}

/// The client's address, when the server was started with connection info: the connecting
/// address, or the one a trusted proxy forwarded ([`super::forwarded`]).
pub struct ClientAddress(pub Option<IpAddr>);

impl FromRequestParts<AppState> for ClientAddress {
    type Rejection = std::convert::Infallible;
    async fn from_request_parts(
        parts: &mut Parts,
        state: &AppState,
    ) -> Result<Self, Self::Rejection> {
        let peer = parts
            .extensions
            .get::<ConnectInfo<SocketAddr>>()
            .map(|c| c.0.ip());
        Ok(ClientAddress(super::forwarded::client_address(
            &state.trusted_proxies,
            peer,
            &parts.headers,
        )))
    }
}

/// A logged-in annotator. Without a valid session, pages redirect to the login form and
/// anything else is 401.
pub struct LoggedIn(pub Session);

impl FromRequestParts<AppState> for LoggedIn {
    type Rejection = Response;
    async fn from_request_parts(
        parts: &mut Parts,
        state: &AppState,
    ) -> Result<Self, Self::Rejection> {
        if let Some(AdminSession(session)) = parts.extensions.get::<AdminSession>() {
            return Ok(LoggedIn(session.clone()));
        }
        let now = now_ms();
        let session = match cookie(&parts.headers, SESSION_COOKIE) {
            None => None,
            Some(token) => {
                let hash = token_hash(&token);
                match state.sessions.get(&hash, now) {
                    Some(session) => Some(session),
                    None => {
                        let found = annotators::session(&state.hub, &hash)
                            .await
                            .map_err(|e| PageError::from(e).into_response())?;
                        if let Some((session, expires)) = &found {
                            state.sessions.insert(hash, session.clone(), *expires);
                        }
                        found.map(|(session, _)| session)
                    }
                }
            }
        };
        match session {
            Some(s) => Ok(LoggedIn(s)),
            None if parts.method == Method::GET && !wants_json(&parts.headers, &parts.uri) => {
                Err(Redirect::to("/login").into_response())
            }
            None => Err(ApiError::from(Refusal::NotLoggedIn).into_response()),
        }
    }
}

fn wants_json(headers: &HeaderMap, uri: &axum::http::Uri) -> bool {
    uri.path().ends_with("/answer")
        || headers
            .get(header::ACCEPT)
            .and_then(|v| v.to_str().ok())
            .is_some_and(|v| v.contains("application/json"))
}

/// An admin session; anyone else gets 403.
pub struct Admin(pub Session);

impl FromRequestParts<AppState> for Admin {
    type Rejection = Response;
    async fn from_request_parts(
        parts: &mut Parts,
        state: &AppState,
    ) -> Result<Self, Self::Rejection> {
        let LoggedIn(session) = LoggedIn::from_request_parts(parts, state).await?;
        if session.is_admin {
            Ok(Admin(session))
        } else {
            Err(PageError(AppError::from(Refusal::AdminOnly {
                annotator: session.name,
            }))
            .into_response())
        }
    }
}

/// The session [`admin_only`] let through, for the handler behind it.
#[derive(Clone)]
struct AdminSession(Session);

/// The gate in front of every admin page: refuses anyone but a logged-in admin (a redirect to
/// the login form, 401 or 403, as [`Admin`] does) before the handler runs, whatever the request
/// carries; lets admins through with their session.
pub(super) async fn admin_only(
    Admin(session): Admin,
    mut request: Request,
    next: axum::middleware::Next,
) -> Response {
    request.extensions_mut().insert(AdminSession(session));
    next.run(request).await
}

/// A state-changing request: a logged-in session whose CSRF token matched, and the body. Form
/// bodies carry the token in their `csrf` field, JSON bodies in the `X-CSRF-Token` header.
pub struct Protected<T> {
    pub session: Session,
    pub body: T,
}

fn csrf_rejected(json: bool) -> Response {
    let error = AppError::from(Refusal::StaleForm);
    if json {
        ApiError(error).into_response()
    } else {
        PageError(error).into_response()
    }
}

impl<T: DeserializeOwned + Send> FromRequest<AppState> for Protected<T> {
    type Rejection = Response;
    async fn from_request(request: Request, state: &AppState) -> Result<Self, Self::Rejection> {
        let (mut parts, body) = request.into_parts();
        let LoggedIn(session) = LoggedIn::from_request_parts(&mut parts, state).await?;
        let json = parts
            .headers
            .get(header::CONTENT_TYPE)
            .and_then(|v| v.to_str().ok())
            .is_some_and(|v| v.starts_with("application/json"));
        let header_token = parts
            .headers
            .get("x-csrf-token")
            .and_then(|v| v.to_str().ok())
            .map(str::to_owned);
        let bytes = Bytes::from_request(Request::from_parts(parts, body), state)
            .await
            .map_err(IntoResponse::into_response)?;
        let token_ok = |token: Option<&str>| {
            token.is_some_and(|t| constant_time_eq(t.as_bytes(), session.csrf_token.as_bytes()))
        };
        // The token is checked before the body is read, so a forged request learns nothing.
        let body = if json {
            if !token_ok(header_token.as_deref()) {
                return Err(csrf_rejected(true));
            }
            serde_json::from_slice::<T>(&bytes).map_err(|e| {
                ApiError(AppError::Invalid(format!("request body: {e}"))).into_response()
            })?
        } else {
            let fields: Vec<(String, String)> =
                serde_urlencoded::from_bytes(&bytes).unwrap_or_default();
            let field_token = fields
                .into_iter()
                .find(|(k, _)| k == "csrf")
                .map(|(_, v)| v)
                .or(header_token);
            if !token_ok(field_token.as_deref()) {
                return Err(csrf_rejected(false));
            }
            serde_urlencoded::from_bytes::<T>(&bytes)
                .map_err(|e| PageError(AppError::Invalid(format!("form: {e}"))).into_response())?
        };
        Ok(Protected { session, body })
    }
}

#[derive(Template)]
#[template(path = "login.html")]
struct LoginPage {
    tr: Tr,
    csrf: String,
    name: String,
    error: Option<String>,
}

/// A login-form page with a fresh double-submit token in a cookie and in the form.
fn login_form(
    tr: Tr,
    headers: &HeaderMap,
    status: axum::http::StatusCode,
    name: String,
    error: Option<String>,
) -> Result<Response, PageError> {
    let csrf = random_token();
    let page = LoginPage {
        tr,
        csrf: csrf.clone(),
        name,
        error,
    };
    let cookie = set_cookie(headers, LOGIN_CSRF_COOKIE, &csrf, Duration::from_secs(3600));
    Ok((
        status,
        [(header::SET_COOKIE, cookie)],
        Html(page.render_page()?),
    )
        .into_response())
}

async fn login_page(tr: Tr, headers: HeaderMap) -> Result<Response, PageError> {
    login_form(
        tr,
        &headers,
        axum::http::StatusCode::OK,
        String::new(),
        None,
    )
}

#[derive(Deserialize)]
struct LoginForm {
    #[serde(default)]
    csrf: String,
    #[serde(default)]
    name: String,
    #[serde(default)]
    password: String,
}

fn login_csrf_ok(headers: &HeaderMap, form_token: &str) -> bool {
    cookie(headers, LOGIN_CSRF_COOKIE)
        .is_some_and(|c| !c.is_empty() && constant_time_eq(c.as_bytes(), form_token.as_bytes()))
}

/// Starts a session for `annotator` and redirects to `to`.
async fn start_session(
    state: &AppState,
    headers: &HeaderMap,
    annotator: i64,
    to: &str,
) -> Result<Response, ApiError> {
    let token = annotators::start_session(&state.hub, annotator).await?;
    let cookie = set_cookie(headers, SESSION_COOKIE, &token, SESSION_LIFETIME);
    let mut cookies = vec![(header::SET_COOKIE, cookie)];
    // The annotator's saved language follows them to this browser.
    let saved = annotators::saved_locale(&state.hub, annotator).await?;
    if let Some(locale) = saved.as_deref().and_then(Locale::from_tag) {
        cookies.push((header::SET_COOKIE, locale_cookie(locale)));
    }
    Ok((AppendHeaders(cookies), Redirect::to(to)).into_response())
}

async fn login(
    State(state): State<AppState>,
    ClientAddress(address): ClientAddress,
    tr: Tr,
    headers: HeaderMap,
    axum::Form(form): axum::Form<LoginForm>,
) -> Result<Response, PageError> {
    use axum::http::StatusCode;
    if !login_csrf_ok(&headers, &form.csrf) {
        let error = tr.t("login-error-expired");
        return login_form(tr, &headers, StatusCode::FORBIDDEN, form.name, Some(error));
    }
    let name = form.name.trim().to_owned();
    if name.is_empty() || form.password.is_empty() {
        let error = tr.t("login-error-missing");
        return login_form(tr, &headers, StatusCode::BAD_REQUEST, name, Some(error));
    }
    if let Err(e) = state.logins.check(&name, address) {
        let (error, retry_after) = match &e {
            ApiError(AppError::LimitReached {
                retry_after: Some(seconds),
                ..
            }) => (
                tr.t_ns(
                    "login-error-limited",
                    "minutes",
                    seconds.div_ceil(60).max(1),
                    "detail",
                    e.to_string(),
                ),
                Some(*seconds),
            ),
            _ => (e.to_string(), None),
        };
        let mut page = login_form(tr, &headers, e.status(), name, Some(error))?;
        if let Some(seconds) = retry_after {
            page.headers_mut()
                .insert(header::RETRY_AFTER, HeaderValue::from(seconds));
        }
        return Ok(page);
    }
    let matched = annotators::check_password(&state.hub, &name, &form.password).await?;
    let Some(annotator) = matched else {
        state.logins.record_failure(&name, address);
        let error = tr.t("login-error-wrong");
        return login_form(tr, &headers, StatusCode::UNAUTHORIZED, name, Some(error));
    };
    state.logins.record_success(&name);
    Ok(start_session(&state, &headers, annotator, "/annotate").await?)
}

#[derive(Deserialize)]
struct EmptyForm {}

/// A single-use login link: starts a session and goes to the queue.
async fn follow_login_link(
    State(state): State<AppState>,
    headers: HeaderMap,
    Path(token): Path<String>,
) -> Result<Response, PageError> {
    let annotator = annotators::follow_login_link(&state.hub, &token).await?;
    Ok(start_session(&state, &headers, annotator, "/annotate").await?)
}

async fn logout(
    State(state): State<AppState>,
    headers: HeaderMap,
    _checked: Protected<EmptyForm>,
) -> Result<Response, PageError> {
    if let Some(token) = cookie(&headers, SESSION_COOKIE) {
        let hash = token_hash(&token);
        state.sessions.remove(&hash);
        annotators::end_session(&state.hub, &hash).await?;
    }
    let cookie = set_cookie(&headers, SESSION_COOKIE, "", Duration::ZERO);
    Ok(([(header::SET_COOKIE, cookie)], Redirect::to("/login")).into_response())
}

#[derive(Template)]
#[template(path = "invite.html")]
struct InvitePage {
    tr: Tr,
    csrf: String,
    name: String,
    token: String,
    min_chars: usize,
    error: Option<String>,
}

async fn invite_form(
    tr: Tr,
    state: &AppState,
    headers: &HeaderMap,
    token: String,
    status: axum::http::StatusCode,
    error: Option<String>,
) -> Result<Response, PageError> {
    let annotator = annotators::invited(&state.hub, &token).await?;
    let csrf = random_token();
    let page = InvitePage {
        tr,
        csrf: csrf.clone(),
        name: annotator.name,
        token,
        min_chars: MIN_PASSWORD_CHARS,
        error,
    };
    let cookie = set_cookie(headers, LOGIN_CSRF_COOKIE, &csrf, Duration::from_secs(3600));
    Ok((
        status,
        [(header::SET_COOKIE, cookie)],
        Html(page.render_page()?),
    )
        .into_response())
}

async fn invite_page(
    State(state): State<AppState>,
    tr: Tr,
    headers: HeaderMap,
    Path(token): Path<String>,
) -> Result<Response, PageError> {
    invite_form(
        tr,
        &state,
        &headers,
        token,
        axum::http::StatusCode::OK,
        None,
    )
    .await
}

#[derive(Deserialize)]
struct InviteForm {
    #[serde(default)]
    csrf: String,
    #[serde(default)]
    password: String,
    #[serde(default)]
    repeat: String,
}

async fn accept_invite(
    State(state): State<AppState>,
    tr: Tr,
    headers: HeaderMap,
    Path(token): Path<String>,
    axum::Form(form): axum::Form<InviteForm>,
) -> Result<Response, PageError> {
    use axum::http::StatusCode;
    if !login_csrf_ok(&headers, &form.csrf) {
        let message = tr.t("login-error-expired");
        return invite_form(
            tr,
            &state,
            &headers,
            token,
            StatusCode::FORBIDDEN,
            Some(message),
        )
        .await;
    }
    match annotators::accept_invite(&state.hub, &token, &form.password, &form.repeat).await {
        Ok(annotator) => Ok(start_session(&state, &headers, annotator, "/annotate").await?),
        // A password the rules refuse: the form again, saying why in the page's language.
        Err(AppError::Refused(
            refusal @ (Refusal::PasswordsDiffer | Refusal::PasswordTooShort { .. }),
        )) => {
            let message = tr.refusal(&refusal);
            invite_form(
                tr,
                &state,
                &headers,
                token,
                StatusCode::BAD_REQUEST,
                Some(message),
            )
            .await
        }
        Err(e) => Err(e.into()),
    }
}

/// Whether the reader is an admin: a logged-in admin (pages show them examples of hidden
/// datasets), or a client presenting an admin API token on a public route (the JSON twins of
/// those pages). Anything else, a bad token included, reads as anyone would.
pub(super) struct ReaderIsAdmin(pub(super) bool);

impl FromRequestParts<AppState> for ReaderIsAdmin {
    type Rejection = std::convert::Infallible;
    async fn from_request_parts(
        parts: &mut Parts,
        state: &AppState,
    ) -> Result<Self, Self::Rejection> {
        if let Ok(token) = super::auth::bearer_token(&parts.headers) {
            let admin = tokens::authorize(&state.hub, token, Scope::Admin).await;
            return Ok(ReaderIsAdmin(admin.is_ok()));
        }
        let has_cookie = parts.headers.contains_key(axum::http::header::COOKIE);
        if !has_cookie {
            return Ok(ReaderIsAdmin(false));
        }
        Ok(ReaderIsAdmin(
            LoggedIn::from_request_parts(parts, state)
                .await
                .is_ok_and(|LoggedIn(s)| s.is_admin),
        ))
    }
}
