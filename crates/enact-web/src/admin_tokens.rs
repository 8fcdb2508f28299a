//! The admin page for API tokens: list accounts' tokens, issue one (its secret shown once, on
//! the result page only), revoke one with immediate effect. Same session and CSRF rules as
//! `/admin`.

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::http::header;
use axum::response::{Html, IntoResponse, Response};
use axum::routing::{get, post};
use serde::Deserialize;

use super::AppState;
use super::error::{ApiError, PageError, RenderPage};
use super::session::{Admin, Protected};
use super::submissions::parse_role;
use crate::app::refusal::{Expected, Refusal};
use crate::app::tokens::{self, CreatedToken, TokenListing};
use crate::core::annotation::Session;
use crate::core::credentials::Role;

pub fn router() -> Router<AppState> {
    Router::new()
        .route("/admin/tokens", get(tokens_page).post(create))
        .route("/admin/tokens/revoke", post(revoke))
}

#[derive(Template)]
#[template(path = "admin_tokens.html")]
struct TokensPage {
    name: String,
    csrf: String,
    tokens: Vec<TokenListing>,
    notice: Option<String>,
    /// A token just created: the only time its secret is shown.
    created: Option<CreatedToken>,
}

async fn render(
    state: &AppState,
    session: Session,
    notice: Option<String>,
    created: Option<CreatedToken>,
) -> Result<Response, PageError> {
    let tokens = tokens::list(&state.hub).await?;
    let page = TokensPage {
        name: session.name,
        csrf: session.csrf_token,
        tokens,
        notice,
        created,
    };
    // The page may carry a secret: keep it out of every cache, the browser's included.
    Ok((
        [(header::CACHE_CONTROL, "no-store")],
        Html(page.render_page()?),
    )
        .into_response())
}

async fn tokens_page(
    State(state): State<AppState>,
    Admin(session): Admin,
) -> Result<Response, PageError> {
    render(&state, session, None, None).await
}

#[derive(Deserialize)]
struct NewTokenForm {
    #[serde(default)]
    name: String,
    #[serde(default)]
    role: String,
    /// Empty means the server's default.
    #[serde(default)]
    daily_quota: String,
    #[serde(default)]
    total_quota: String,
}

fn optional_quota(field: &str, text: &str) -> Result<Option<i64>, ApiError> {
    let text = text.trim();
    if text.is_empty() {
        return Ok(None);
    }
    // A negative number is the use case's to refuse (`tokens::create`), as for the API.
    text.parse::<i64>()
        .map(Some)
        .map_err(|_| Refusal::bad_value(field, text, Expected::WholeNumberFrom { least: 0 }))
        .map_err(ApiError::from)
}

async fn create(
    State(state): State<AppState>,
    request: Protected<NewTokenForm>,
) -> Result<Response, PageError> {
    let form = request.body;
    let role = if form.role.trim().is_empty() {
        Role::Submitter
    } else {
        parse_role(form.role.trim())?
    };
    let daily = optional_quota("daily quota", &form.daily_quota)?;
    let total = optional_quota("total quota", &form.total_quota)?;
    let created = tokens::issue(
        &state.hub,
        &request.session.actor(),
        &form.name,
        role,
        daily,
        total,
    )
    .await?;
    tracing::info!(
        token = created.id,
        account = %created.account,
        by = %request.session.name,
        "API token created on the admin page"
    );
    let notice = format!(
        "Created token {} (prefix {}) for {} account '{}'.",
        created.id, created.prefix, created.role, created.account
    );
    render(&state, request.session, Some(notice), Some(created)).await
}

#[derive(Deserialize)]
struct RevokeForm {
    #[serde(default)]
    token: String,
}

async fn revoke(
    State(state): State<AppState>,
    request: Protected<RevokeForm>,
) -> Result<Response, PageError> {
    let which = request.body.token.trim().to_owned();
    tokens::revoke(&state.hub, &request.session.actor(), &which).await?;
    tracing::info!(token = %which, by = %request.session.name, "API token revoked on the admin page");
    render(
        &state,
        request.session,
        Some(format!(
            "Revoked token {which}; requests with it are refused from now on."
        )),
        None,
    )
    .await
}
