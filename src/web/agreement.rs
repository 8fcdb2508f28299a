//! The admins' agreement pages: the cross-annotation protocol action, and the dataset report
//! (page, JSON and the downloadable bundle).

use axum::Router;
use axum::extract::Path;
use axum::extract::State;
use axum::response::Html;
use axum::routing::post;
use serde::Deserialize;

use super::admin::{render_admin, require_admin};
use super::error::PageError;
use super::session::Protected;
use super::{AppError, AppState, dataset_or_404};
use crate::agreement_protocol::DEFAULT_ITEMS_PER_CELL;
use crate::store;
use crate::store::agreement::ProtocolRefusal;

pub fn router() -> Router<AppState> {
    Router::new().route(
        "/admin/datasets/{dataset}/agreement-protocol",
        post(run_protocol),
    )
}

/// The protocol form: k and an optional seed (a fresh random one, recorded, when empty).
#[derive(Deserialize)]
struct ProtocolForm {
    #[serde(default)]
    items_per_cell: String,
    #[serde(default)]
    seed: String,
}

fn parse_field<T: std::str::FromStr>(name: &str, text: &str, default: T) -> Result<T, AppError> {
    let text = text.trim();
    if text.is_empty() {
        return Ok(default);
    }
    text.parse().map_err(|_| {
        AppError::BadRequest(format!(
            "form field `{name}`: '{text}' is not a whole number ≥ 0"
        ))
    })
}

async fn run_protocol(
    State(state): State<AppState>,
    Path(name): Path<String>,
    request: Protected<ProtocolForm>,
) -> Result<Html<String>, PageError> {
    require_admin(&request.session)?;
    let dataset = dataset_or_404(&state.pool, &name).await?;
    let items_per_cell = parse_field(
        "items_per_cell",
        &request.body.items_per_cell,
        DEFAULT_ITEMS_PER_CELL,
    )?;
    let seed = parse_field("seed", &request.body.seed, rand::random::<u64>())?;
    let mut tx = state.pool.begin().await?;
    let run = store::agreement::run_protocol(
        &mut tx,
        dataset.id,
        items_per_cell,
        seed,
        Some(request.session.annotator),
    )
    .await?;
    let run = match run {
        Ok(run) => run,
        Err(refusal) => {
            tx.rollback().await?;
            let message = format!("dataset '{}': {refusal}", dataset.name);
            return Err(match refusal {
                ProtocolRefusal::AlreadyRan(_) => AppError::Conflict(message),
                ProtocolRefusal::Plan(_) => AppError::BadRequest(message),
            }
            .into());
        }
    };
    tx.commit().await?;
    let short = if run.plan.shortfalls.is_empty() {
        String::new()
    } else {
        format!(
            " {} annotator × direction × step length cells had fewer than {items_per_cell} \
             completed items and were taken whole.",
            run.plan.shortfalls.len()
        )
    };
    let notice = format!(
        "Agreement protocol on '{}': drew {} items (k = {items_per_cell}, seed = {seed}) from \
         the completed primary items of {} annotators and added {} assignments.{short}",
        dataset.name,
        run.plan.samples.len(),
        run.annotators.len(),
        run.assignments_added,
    );
    render_admin(&state, request.session, Some(notice), None).await
}
