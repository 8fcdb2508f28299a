//! The language switch on every page: `POST /locale` remembers the choice in a cookie and, for
//! a signed-in annotator, as their saved preference.

use axum::Router;
use axum::extract::State;
use axum::http::{HeaderMap, header};
use axum::response::{IntoResponse, Redirect, Response};
use axum::routing::post;
use serde::Deserialize;

use super::AppState;
use super::cookies::cookie;
use super::error::PageError;
use super::i18n::{Locale, locale_cookie};
use super::session::SESSION_COOKIE;
use crate::app::annotators;
use crate::app::refusal::{Expected, Refusal};
use crate::core::credentials::token_hash;

pub fn router() -> Router<AppState> {
    Router::new().route("/locale", post(switch))
}

#[derive(Deserialize)]
struct SwitchForm {
    #[serde(default)]
    locale: String,
    /// The page to go back to: a path on this site.
    #[serde(default)]
    back: String,
}

/// The switch: remembers the locale in a cookie and, for a signed-in annotator, as their
/// preference; then back to the page it was used on.
///
/// No CSRF token: the session cookie is `SameSite=Strict`, so a request from another site
/// never carries it and can at most set this browser's language cookie, which changes nothing
/// stored.
async fn switch(
    State(state): State<AppState>,
    headers: HeaderMap,
    axum::Form(form): axum::Form<SwitchForm>,
) -> Result<Response, PageError> {
    let Some(locale) = Locale::from_tag(&form.locale) else {
        let known: Vec<&'static str> = Locale::ALL.iter().map(|l| l.tag()).collect();
        return Err(Refusal::bad_value("locale", form.locale, Expected::OneOf(known)).into());
    };
    if let Some(token) = cookie(&headers, SESSION_COOKIE) {
        annotators::save_locale(&state.hub, &token_hash(&token), locale.tag()).await?;
    }
    // Only a path on this site, never `//host` or a scheme: no open redirect.
    let back = if form.back.starts_with('/') && !form.back.starts_with("//") {
        form.back.as_str()
    } else {
        "/"
    };
    Ok((
        [(header::SET_COOKIE, locale_cookie(locale))],
        Redirect::to(back),
    )
        .into_response())
}
