//! A dataset's red flags for admins: `GET /api/v1/admin/datasets/{dataset}/flags` and the
//! page `/admin/datasets/{dataset}/flags`.

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::response::Html;
use axum::routing::get;
use serde::Deserialize;
use serde_json::json;

use super::error::{ApiError, PageError, RenderPage};
use super::extract::{Path, Query};
use super::openapi::{ApiRoute, Verb};
use super::session::Admin;
use super::{AppError, AppState};
use crate::app::red_flags::{self, RedFlags};
use crate::core::credentials::Scope;
use crate::core::red_flags::{DEFAULT_TRUTH_SHARE, parse_share};

pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Get,
            "/admin/datasets/{dataset}/flags",
            flags_api,
            "A dataset's red flags",
        )
        .describe(
            "What an admin should look at before trusting the dataset's rows: \
             `above_human`, leaderboard rows whose task accuracy on the items the humans \
             answered is above the humans' on the same items (per item the share of its \
             answers that are right, averaged; none while the humans have fewer than 5 \
             answers); and, while the dataset's answers are hidden, `identical_to_truth`, \
             submissions (listed or not) answering more than `share` of its items exactly as \
             the ground truth, and `leaks`, datasets with public answers holding some of its \
             items (by content hash) or frames (by the SHA-256 of their bytes). An import \
             reports its leaks as it finishes and audits them (`dataset.leak`).",
        )
        .bearer(Scope::Admin)
        .query_with(
            "share",
            false,
            json!({"anyOf": [
                {"type": "number", "minimum": 0, "exclusiveMaximum": 1},
                {"const": ""}
            ]}),
            "The share of exact answers above which a submission is flagged (default 0.9).",
        )
        .responds_json::<RedFlags>(200, "The flags; empty lists when nothing is flagged.")
        .errors(&[400, 401, 403, 404, 503]),
    ]
}

pub fn admin_router() -> Router<AppState> {
    Router::new().route("/admin/datasets/{dataset}/flags", get(flags_page))
}

#[derive(Debug, Default, Deserialize)]
struct FlagsQuery {
    share: Option<String>,
}

impl FlagsQuery {
    fn share(&self) -> Result<f64, ApiError> {
        match self.share.as_deref().map(str::trim) {
            None | Some("") => Ok(DEFAULT_TRUTH_SHARE),
            Some(text) => parse_share(text)
                .map_err(AppError::Invalid)
                .map_err(ApiError),
        }
    }
}

async fn flags_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    Query(query): Query<FlagsQuery>,
) -> Result<axum::Json<RedFlags>, ApiError> {
    let share = query.share()?;
    Ok(axum::Json(
        red_flags::of(&state.hub, &dataset, share).await?,
    ))
}

#[derive(Template)]
#[template(path = "admin_red_flags.html")]
struct FlagsPage {
    name: String,
    csrf: String,
    flags: RedFlags,
    /// The threshold as a percentage, for the page's text and form.
    share_percent: String,
}

impl FlagsPage {
    fn percent(fraction: &f64) -> String {
        format!("{:.1} %", fraction * 100.0)
    }
}

async fn flags_page(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    Query(query): Query<FlagsQuery>,
    Admin(session): Admin,
) -> Result<Html<String>, PageError> {
    let share = query.share()?;
    let flags = red_flags::of(&state.hub, &dataset, share).await?;
    let page = FlagsPage {
        name: session.name,
        csrf: session.csrf_token,
        share_percent: FlagsPage::percent(&share),
        flags,
    };
    Ok(Html(page.render_page()?))
}
