//! The admin page for the audit log: newest entries first, filtered by action, actor,
//! dataset and time, a hundred at a time.

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::response::Html;
use axum::routing::get;
use serde::Deserialize;

use super::AppState;
use super::error::{PageError, RenderPage};
use super::extract::Query;
use super::session::Admin;
use crate::app::audit;
use crate::core::audit::{AuditAction, AuditEntry, AuditFilter};

/// Entries on one page.
const PAGE: usize = 100;

pub fn router() -> Router<AppState> {
    Router::new().route("/admin/audit", get(audit_page))
}

/// The filter form's fields; empty means "any".
#[derive(Debug, Default, Deserialize)]
struct AuditQuery {
    #[serde(default)]
    action: String,
    #[serde(default)]
    actor: String,
    #[serde(default)]
    dataset: String,
    #[serde(default)]
    since: String,
    /// Entries older than this id: the next page.
    before: Option<i64>,
}

impl AuditQuery {
    fn filter(&self) -> AuditFilter {
        let given = |text: &str| Some(text.trim().to_owned()).filter(|t| !t.is_empty());
        AuditFilter {
            action: given(&self.action),
            actor: given(&self.actor),
            dataset: given(&self.dataset),
            since: given(&self.since),
            before_id: self.before,
            limit: PAGE,
        }
    }

    /// The query string of the page after the one ending at entry `last`.
    fn older(&self, last: i64) -> String {
        serde_urlencoded::to_string([
            ("action", self.action.trim()),
            ("actor", self.actor.trim()),
            ("dataset", self.dataset.trim()),
            ("since", self.since.trim()),
            ("before", &last.to_string()),
        ])
        .unwrap_or_default()
    }
}

#[derive(Template)]
#[template(path = "admin_audit.html")]
struct AuditPage {
    name: String,
    csrf: String,
    actions: Vec<&'static str>,
    query: AuditQuery,
    entries: Vec<AuditEntry>,
    /// Link to older entries when this page is full.
    older: Option<String>,
}

async fn audit_page(
    State(state): State<AppState>,
    Admin(session): Admin,
    Query(query): Query<AuditQuery>,
) -> Result<Html<String>, PageError> {
    let entries = audit::list(&state.hub, query.filter()).await?;
    let older = (entries.len() == PAGE)
        .then(|| entries.last().map(|e| query.older(e.id)))
        .flatten();
    let page = AuditPage {
        name: session.name,
        csrf: session.csrf_token,
        actions: AuditAction::ALL.iter().map(|a| a.as_str()).collect(),
        query,
        entries,
        older,
    };
    Ok(Html(page.render_page()?))
}
