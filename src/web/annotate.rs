//! The annotator's side: the queue, the forward and inverse item pages (paper Figures 11 and
//! 12), autosaved drafts, submitting, skipping and flagging.
//!
//! Blind by construction: nothing here reads an item's ground truth or score, and an item not
//! assigned to the session's annotator is 403 on every route.

use std::sync::Arc;

use askama::Template;
use axum::Json;
use axum::Router;
use axum::extract::{Path, State};
use axum::response::{Html, IntoResponse, Redirect, Response};
use axum::routing::{get, post};
use serde::{Deserialize, Serialize};

use super::api::frame_url;
use super::error::PageError;
use super::session::{LoggedIn, Protected};
use super::{AppError, AppState};
use crate::core::annotation::Draft;
use crate::core::dataset::{Direction, StepLength};
use crate::store;
use crate::store::annotations::{Outcome, QueueStatus, Session, StoredDraft, Telemetry, now_ms};
use crate::store::items::StoredItem;

pub fn router() -> Router<AppState> {
    Router::new()
        .route("/annotate", get(queue_page))
        .route("/annotate/next", get(next_item))
        .route("/annotate/{dataset}/{item_id}", get(item_page))
        .route("/annotate/{dataset}/{item_id}/draft", post(save_draft))
        .route("/annotate/{dataset}/{item_id}/submit", post(submit))
        .route("/annotate/{dataset}/{item_id}/skip", post(skip))
        .route("/annotate/{dataset}/{item_id}/answer", get(own_answer))
}

fn item_href(dataset: &str, item_id: &str) -> String {
    format!("/annotate/{dataset}/{item_id}")
}

struct ProgressCell {
    done: usize,
    assigned: usize,
}

struct ProgressRow {
    direction: &'static str,
    cells: Vec<ProgressCell>,
}

struct QueueRow {
    href: String,
    dataset: String,
    item_id: String,
    direction: &'static str,
    step_length: u8,
    status: &'static str,
    done: bool,
}

#[derive(Template)]
#[template(path = "queue.html")]
struct QueuePage {
    name: String,
    is_admin: bool,
    csrf: String,
    step_lengths: Vec<u8>,
    progress: Vec<ProgressRow>,
    done: usize,
    total: usize,
    next: Option<String>,
    resume: bool,
    items: Vec<QueueRow>,
}

async fn queue_page(
    State(state): State<AppState>,
    LoggedIn(session): LoggedIn,
) -> Result<Html<String>, PageError> {
    let mut conn = state.pool.acquire().await?;
    let queue = store::annotations::queue(&mut conn, session.annotator).await?;
    let lengths: Vec<StepLength> = StepLength::all()
        .filter(|l| queue.iter().any(|e| e.step_length == *l))
        .collect();
    let progress = Direction::ALL
        .into_iter()
        .map(|d| ProgressRow {
            direction: d.as_str(),
            cells: lengths
                .iter()
                .map(|l| {
                    let of_kind = queue
                        .iter()
                        .filter(|e| e.direction == d && e.step_length == *l);
                    let (done, assigned) = of_kind.fold((0, 0), |(d, a), e| {
                        (d + usize::from(e.status.is_done()), a + 1)
                    });
                    ProgressCell { done, assigned }
                })
                .collect(),
        })
        .collect();
    let next = store::annotations::next_in_queue(&queue);
    let page = QueuePage {
        name: session.name,
        is_admin: session.is_admin,
        csrf: session.csrf_token,
        step_lengths: lengths.iter().map(|l| l.get()).collect(),
        progress,
        done: queue.iter().filter(|e| e.status.is_done()).count(),
        total: queue.len(),
        next: next.map(|e| item_href(&e.dataset, &e.item_id)),
        resume: next.is_some_and(|e| e.status == QueueStatus::Started),
        items: queue
            .iter()
            .map(|e| QueueRow {
                href: item_href(&e.dataset, &e.item_id),
                dataset: e.dataset.clone(),
                item_id: e.item_id.clone(),
                direction: e.direction.as_str(),
                step_length: e.step_length.get(),
                status: e.status.as_str(),
                done: e.status.is_done(),
            })
            .collect(),
    };
    Ok(Html(page.render()?))
}

async fn next_item(
    State(state): State<AppState>,
    LoggedIn(session): LoggedIn,
) -> Result<Redirect, PageError> {
    let mut conn = state.pool.acquire().await?;
    let queue = store::annotations::queue(&mut conn, session.annotator).await?;
    Ok(match store::annotations::next_in_queue(&queue) {
        Some(e) => Redirect::to(&item_href(&e.dataset, &e.item_id)),
        None => Redirect::to("/annotate"),
    })
}

/// An item assigned to the session's annotator, with the annotator's standing on it.
struct Assigned {
    item: Arc<StoredItem>,
    finished: bool,
    draft: Option<StoredDraft>,
}

impl Assigned {
    fn rowid(&self) -> i64 {
        self.item.rowid
    }
}

/// The item a URL names, from memory when it was read before (the item page is the hot path).
async fn cached_item(
    state: &AppState,
    dataset: &str,
    item_id: &str,
) -> Result<Arc<StoredItem>, AppError> {
    if let Some(found) = state.items.stored(dataset, item_id) {
        return Ok(found);
    }
    let conn = &mut *state.pool.acquire().await?;
    let stored = store::datasets::by_name(conn, dataset)
        .await?
        .ok_or_else(|| AppError::NotFound(format!("no dataset named '{dataset}'")))?;
    let item = store::items::get(conn, stored.id, item_id)
        .await?
        .ok_or_else(|| AppError::NotFound(format!("no item '{item_id}' in dataset '{dataset}'")))?;
    let found = Arc::new(item);
    state.items.insert_stored(dataset, item_id, found.clone());
    Ok(found)
}

/// Looks up an item assigned to the session's annotator: 404 for an unknown dataset or item,
/// 403 for an item that exists but is someone else's (or no one's).
/// Touches the store only for what is not already in memory.
async fn assigned(
    state: &AppState,
    session: &Session,
    dataset: &str,
    item_id: &str,
) -> Result<Assigned, AppError> {
    let item = cached_item(state, dataset, item_id).await?;
    let standing = match state.standings.get(session.annotator, item.rowid) {
        Some(known) => known,
        None => {
            let ticket = state.standings.ticket();
            let mut conn = state.pool.acquire().await?;
            let read =
                store::annotations::assignment_state(&mut conn, session.annotator, item.rowid)
                    .await?
                    .ok_or_else(|| {
                        AppError::Forbidden(format!(
                            "item '{item_id}' of dataset '{dataset}' is not assigned to you"
                        ))
                    })?;
            state
                .standings
                .remember(ticket, session.annotator, item.rowid, read.clone());
            read
        }
    };
    Ok(Assigned {
        item,
        finished: standing.finished,
        draft: standing.draft,
    })
}

/// A card of the library: an image or an action, with the label the item gives it.
struct Card {
    label: u8,
    name: String,
    src: Option<String>,
    text: Option<String>,
}

/// A state image shown for context (the current state, or a transition's ends).
struct Frame {
    name: String,
    src: String,
}

struct Transition {
    from: Frame,
    to: Frame,
}

#[derive(Template)]
#[template(path = "annotate_item.html")]
struct ItemPage {
    csrf: String,
    dataset: String,
    item_id: String,
    forward: bool,
    step_length: u8,
    slots: Vec<usize>,
    /// Forward: the pinned current state.
    current: Option<Frame>,
    /// Forward: the actions in order.
    actions: Vec<String>,
    /// Inverse: the ordered transitions, one slot each.
    transitions: Vec<Transition>,
    library: Vec<Card>,
    question: String,
    draft_json: String,
    finished: bool,
    base: String,
}

async fn item_page(
    State(state): State<AppState>,
    LoggedIn(session): LoggedIn,
    Path((dataset, item_id)): Path<(String, String)>,
) -> Result<Html<String>, PageError> {
    let found = assigned(&state, &session, &dataset, &item_id).await?;
    let item = &found.item;
    let finished = found.finished;
    let step_length = item.summary.step_length;
    let draft = match (finished, found.draft) {
        (true, _) => Draft::empty(step_length),
        (false, Some(stored)) => stored.draft,
        (false, None) => {
            let mut conn = state.pool.acquire().await?;
            let opened = store::annotations::open_draft(
                &mut conn,
                session.annotator,
                item.rowid,
                &Draft::empty(step_length),
                now_ms(),
            )
            .await?;
            state.standings.forget(session.annotator, item.rowid);
            opened.draft
        }
    };
    let frame = |position: usize| -> Option<Frame> {
        item.images.get(position).map(|img| Frame {
            name: img.label(),
            src: frame_url(&img.sha256),
        })
    };
    let forward = item.summary.direction == Direction::Forward;
    let library: Vec<Card> = if forward {
        item.images
            .iter()
            .skip(1)
            .map(|img| Card {
                label: u8::try_from(img.position).unwrap_or(u8::MAX),
                name: img.label(),
                src: Some(frame_url(&img.sha256)),
                text: None,
            })
            .collect()
    } else {
        item.actions
            .iter()
            .enumerate()
            .map(|(i, text)| Card {
                label: u8::try_from(i + 1).unwrap_or(u8::MAX),
                name: format!("Action {}", i + 1),
                src: None,
                text: Some(text.clone()),
            })
            .collect()
    };
    let transitions = if forward {
        Vec::new()
    } else {
        (0..step_length.actions())
            .filter_map(|i| {
                Some(Transition {
                    from: frame(i)?,
                    to: frame(i + 1)?,
                })
            })
            .collect()
    };
    let page = ItemPage {
        csrf: session.csrf_token,
        base: item_href(&dataset, &item_id),
        dataset,
        item_id: item.summary.item_id.clone(),
        forward,
        step_length: step_length.get(),
        slots: (1..=step_length.actions()).collect(),
        current: if forward { frame(0) } else { None },
        actions: if forward {
            item.actions.clone()
        } else {
            Vec::new()
        },
        transitions,
        library,
        question: item.question.clone(),
        draft_json: serde_json::to_string(&draft).map_err(|e| AppError::Internal(e.into()))?,
        finished,
    };
    Ok(Html(page.render()?))
}

/// Checks a draft against the item it is for; 409 once the item is finished.
async fn checked_draft(
    state: &AppState,
    session: &Session,
    dataset: &str,
    item_id: &str,
    draft: &Draft,
) -> Result<i64, AppError> {
    let found = assigned(state, session, dataset, item_id).await?;
    if found.finished {
        return Err(AppError::Conflict(format!(
            "item '{item_id}' is already finished; its answer can no longer change"
        )));
    }
    draft
        .check(found.item.summary.step_length)
        .map_err(|e| AppError::BadRequest(format!("draft of item '{item_id}': {e}")))?;
    Ok(found.rowid())
}

#[derive(Serialize)]
struct Saved {
    saved: bool,
}

async fn save_draft(
    State(state): State<AppState>,
    Path((dataset, item_id)): Path<(String, String)>,
    request: Protected<Draft>,
) -> Result<Json<Saved>, AppError> {
    let rowid = checked_draft(&state, &request.session, &dataset, &item_id, &request.body).await?;
    let mut conn = state.pool.acquire().await?;
    store::annotations::save_draft(
        &mut conn,
        request.session.annotator,
        rowid,
        &request.body,
        now_ms(),
    )
    .await?;
    state.standings.forget(request.session.annotator, rowid);
    Ok(Json(Saved { saved: true }))
}

#[derive(Serialize)]
struct Submitted {
    next: String,
}

async fn submit(
    State(state): State<AppState>,
    Path((dataset, item_id)): Path<(String, String)>,
    request: Protected<Draft>,
) -> Result<Json<Submitted>, AppError> {
    let session = &request.session;
    let draft = &request.body;
    let rowid = checked_draft(&state, session, &dataset, &item_id, draft).await?;
    let Some(answer) = draft.answer() else {
        let empty: Vec<String> = draft
            .slots
            .iter()
            .enumerate()
            .filter(|(_, s)| s.is_none())
            .map(|(i, _)| (i + 1).to_string())
            .collect();
        return Err(AppError::BadRequest(format!(
            "item '{item_id}': slots {} are empty; fill every slot before submitting",
            empty.join(", ")
        )));
    };
    let now = now_ms();
    let mut tx = state.pool.begin().await?;
    store::annotations::save_draft(&mut tx, session.annotator, rowid, draft, now).await?;
    let stored = store::annotations::draft(&mut tx, session.annotator, rowid)
        .await?
        .ok_or_else(|| AppError::Internal(anyhow::anyhow!("draft missing after save")))?;
    let finished = store::annotations::finish(
        &mut tx,
        session.annotator,
        rowid,
        &Outcome::Answered(answer),
        &Telemetry::of(&stored, now),
    )
    .await?;
    if !finished {
        return Err(AppError::Conflict(format!(
            "item '{item_id}' is already finished"
        )));
    }
    tx.commit().await?;
    state.standings.forget(session.annotator, rowid);
    Ok(Json(Submitted {
        next: "/annotate/next".to_owned(),
    }))
}

#[derive(Deserialize)]
struct SkipForm {
    #[serde(default)]
    reason: String,
    /// "skip" or "flag".
    #[serde(default)]
    action: String,
}

async fn skip(
    State(state): State<AppState>,
    Path((dataset, item_id)): Path<(String, String)>,
    request: Protected<SkipForm>,
) -> Result<Response, PageError> {
    let session = &request.session;
    let found = assigned(&state, session, &dataset, &item_id).await?;
    let (rowid, finished) = (found.rowid(), found.finished);
    if finished {
        return Err(AppError::Conflict(format!("item '{item_id}' is already finished")).into());
    }
    let reason = request.body.reason.trim().to_owned();
    if reason.is_empty() {
        return Err(AppError::BadRequest(format!(
            "to {} item '{item_id}', say why in the reason field",
            if request.body.action == "flag" {
                "flag"
            } else {
                "skip"
            }
        ))
        .into());
    }
    if reason.chars().count() > 2000 {
        return Err(AppError::BadRequest("the reason is over 2000 characters".to_owned()).into());
    }
    let outcome = match request.body.action.as_str() {
        "skip" => Outcome::Skipped(reason),
        "flag" => Outcome::Flagged(reason),
        other => {
            return Err(AppError::BadRequest(format!(
                "form field `action` is {other:?}; expected \"skip\" or \"flag\""
            ))
            .into());
        }
    };
    let now = now_ms();
    let mut tx = state.pool.begin().await?;
    let stored = store::annotations::draft(&mut tx, session.annotator, rowid).await?;
    let telemetry = stored.as_ref().map_or(
        Telemetry {
            time_on_item_ms: 0,
            time_to_first_placement_ms: None,
            placements: 0,
            swaps: 0,
            clears: 0,
            undos: 0,
        },
        |d| Telemetry::of(d, now),
    );
    store::annotations::finish(&mut tx, session.annotator, rowid, &outcome, &telemetry).await?;
    tx.commit().await?;
    state.standings.forget(session.annotator, rowid);
    Ok(Redirect::to("/annotate/next").into_response())
}

/// The annotator's own stored answer and telemetry: never a score or the ground truth.
#[derive(Serialize)]
struct OwnAnswer {
    dataset: String,
    item_id: String,
    outcome: String,
    answer: Option<Vec<u8>>,
    reason: String,
    time_on_item_ms: i64,
    time_to_first_placement_ms: Option<i64>,
    placements: u32,
    swaps: u32,
    clears: u32,
    undos: u32,
    finished_at: String,
}

async fn own_answer(
    State(state): State<AppState>,
    LoggedIn(session): LoggedIn,
    Path((dataset, item_id)): Path<(String, String)>,
) -> Result<Json<OwnAnswer>, AppError> {
    let found = assigned(&state, &session, &dataset, &item_id).await?;
    let mut conn = state.pool.acquire().await?;
    let a = store::annotations::annotation(&mut conn, session.annotator, found.rowid())
        .await?
        .ok_or_else(|| {
            AppError::NotFound(format!("item '{item_id}' has no answer from you yet"))
        })?;
    Ok(Json(OwnAnswer {
        dataset: a.dataset,
        item_id: a.item_id,
        outcome: a.outcome,
        answer: a.answer,
        reason: a.reason,
        time_on_item_ms: a.telemetry.time_on_item_ms,
        time_to_first_placement_ms: a.telemetry.time_to_first_placement_ms,
        placements: a.telemetry.placements,
        swaps: a.telemetry.swaps,
        clears: a.telemetry.clears,
        undos: a.telemetry.undos,
        finished_at: a.finished_at,
    }))
}
