//! The annotator's side: the queue, the forward and inverse item pages (paper Figures 11 and
//! 12), autosaved drafts, submitting, skipping and flagging.
//!
//! Blind by construction: nothing here reads an item's ground truth or score, and an item not
//! assigned to the session's annotator is 403 on every route.

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::response::{Html, IntoResponse, Redirect, Response};
use axum::routing::{get, post};
use serde::{Deserialize, Serialize};

use super::AppState;
use super::api::frame_url;
use super::error::{ApiError, PageError, RenderPage};
use super::extract::{Json, Path};
use super::i18n::{Tr, msg};
use super::session::{LoggedIn, Protected};
use crate::app::annotation::{self, AssignedItem};
use crate::app::controls;
use crate::app::items::StoredItem;
use crate::core::annotation::{Draft, QueueStatus, next_in_queue};
use crate::core::attention::Instruction;
use crate::core::dataset::{Direction, StepLength};

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

/// The message key naming a direction.
pub(super) fn direction_key(direction: Direction) -> &'static str {
    match direction {
        Direction::Forward => msg("direction-forward"),
        Direction::Inverse => msg("direction-inverse"),
    }
}

/// The message key naming where an item of the queue stands.
fn status_key(status: QueueStatus) -> &'static str {
    match status {
        QueueStatus::Todo => msg("status-todo"),
        QueueStatus::Started => msg("status-started"),
        QueueStatus::Answered => msg("status-answered"),
        QueueStatus::Skipped => msg("status-skipped"),
        QueueStatus::Flagged => msg("status-flagged"),
    }
}

/// The message key of an attention check's instruction on an item of `direction`: the cards
/// it names are the page's (candidate images forward, candidate actions inverse).
fn attention_key(instruction: Instruction, direction: Direction) -> &'static str {
    match (instruction, direction) {
        (Instruction::Keep, Direction::Forward) => msg("annotate-attention-keep-forward"),
        (Instruction::Reverse, Direction::Forward) => msg("annotate-attention-reverse-forward"),
        (Instruction::Keep, Direction::Inverse) => msg("annotate-attention-keep-inverse"),
        (Instruction::Reverse, Direction::Inverse) => msg("annotate-attention-reverse-inverse"),
    }
}

fn item_href(dataset: &str, item_id: &str) -> String {
    format!("/annotate/{dataset}/{item_id}")
}

struct ProgressCell {
    done: usize,
    assigned: usize,
}

struct ProgressRow {
    direction: String,
    cells: Vec<ProgressCell>,
}

struct QueueRow {
    href: String,
    dataset: String,
    item_id: String,
    direction: String,
    step_length: u8,
    status: String,
    done: bool,
}

#[derive(Template)]
#[template(path = "queue.html")]
struct QueuePage {
    tr: Tr,
    name: String,
    is_admin: bool,
    csrf: String,
    step_lengths: Vec<u8>,
    progress: Vec<ProgressRow>,
    done: usize,
    total: usize,
    next: Option<String>,
    resume: bool,
    /// An admin paused the queue: the page says so and offers no item to open.
    paused: bool,
    items: Vec<QueueRow>,
}

async fn queue_page(
    State(state): State<AppState>,
    LoggedIn(session): LoggedIn,
    tr: Tr,
) -> Result<Html<String>, PageError> {
    let queue = annotation::queue(&state.hub, session.annotator).await?;
    let paused = controls::paused(&state.hub, session.annotator)
        .await?
        .is_some();
    let lengths: Vec<StepLength> = StepLength::all()
        .filter(|l| queue.iter().any(|e| e.step_length == *l))
        .collect();
    let progress = Direction::ALL
        .into_iter()
        .map(|d| ProgressRow {
            direction: tr.t(direction_key(d)),
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
    let next = next_in_queue(&queue).filter(|_| !paused);
    let page = QueuePage {
        tr: tr.clone(),
        name: session.name,
        is_admin: session.is_admin,
        csrf: session.csrf_token,
        step_lengths: lengths.iter().map(|l| l.get()).collect(),
        progress,
        done: queue.iter().filter(|e| e.status.is_done()).count(),
        total: queue.len(),
        next: next.map(|e| item_href(&e.dataset, &e.item_id)),
        resume: next.is_some_and(|e| e.status == QueueStatus::Started),
        paused,
        items: queue
            .iter()
            .map(|e| QueueRow {
                href: item_href(&e.dataset, &e.item_id),
                dataset: e.dataset.clone(),
                item_id: e.item_id.clone(),
                direction: tr.t(direction_key(e.direction)),
                step_length: e.step_length.get(),
                status: tr.t(status_key(e.status)),
                done: e.status.is_done(),
            })
            .collect(),
    };
    Ok(Html(page.render_page()?))
}

async fn next_item(
    State(state): State<AppState>,
    LoggedIn(session): LoggedIn,
) -> Result<Redirect, PageError> {
    // A paused queue has no next item: its page says why.
    if controls::paused(&state.hub, session.annotator)
        .await?
        .is_some()
    {
        return Ok(Redirect::to("/annotate"));
    }
    Ok(
        match annotation::next(&state.hub, session.annotator).await? {
            Some(e) => Redirect::to(&item_href(&e.dataset, &e.item_id)),
            None => Redirect::to("/annotate"),
        },
    )
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
    tr: Tr,
    csrf: String,
    dataset: String,
    item_id: String,
    forward: bool,
    step_length: u8,
    /// Forward: the pinned current state.
    current: Option<Frame>,
    /// Forward: each slot with the action that leads to it, in order.
    steps: Vec<(usize, String)>,
    /// Thumbnails shrink from 140 to 110 px for long items (L ≥ 7), so L = 10 fits.
    long: bool,
    /// Inverse: the ordered transitions, one slot each.
    transitions: Vec<Transition>,
    library: Vec<Card>,
    question: String,
    /// An attention check's instruction, in the annotator's language.
    attention: Option<String>,
    draft_json: String,
    finished: bool,
    base: String,
}

async fn item_page(
    State(state): State<AppState>,
    LoggedIn(session): LoggedIn,
    Path((dataset, item_id)): Path<(String, String)>,
    tr: Tr,
) -> Result<Html<String>, PageError> {
    let opened = annotation::open(&state.hub, &session, &dataset, &item_id).await?;
    let page = ItemPage::new(tr, &opened, session.csrf_token, dataset)?;
    Ok(Html(page.render_page()?))
}

/// A state image of `item` by position.
fn frame(item: &StoredItem, position: usize) -> Option<Frame> {
    item.images.get(position).map(|img| Frame {
        name: img.label(),
        src: frame_url(&img.sha256),
    })
}

/// The cards to order: the future images (forward) or the action texts (inverse).
fn library(item: &StoredItem) -> Vec<Card> {
    if item.summary.direction == Direction::Forward {
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
    }
}

impl ItemPage {
    fn new(
        tr: Tr,
        opened: &AssignedItem,
        csrf: String,
        dataset: String,
    ) -> Result<ItemPage, ApiError> {
        let item = &opened.item;
        let step_length = item.summary.step_length;
        let forward = item.summary.direction == Direction::Forward;
        let draft = match &opened.draft {
            Some(draft) => serde_json::to_string(draft)?,
            None => serde_json::to_string(&Draft::empty(step_length))?,
        };
        let transitions = if forward {
            Vec::new()
        } else {
            (0..step_length.actions())
                .filter_map(|i| {
                    Some(Transition {
                        from: frame(item, i)?,
                        to: frame(item, i + 1)?,
                    })
                })
                .collect()
        };
        let attention = opened
            .attention
            .map(|i| tr.t(attention_key(i, item.summary.direction)));
        Ok(ItemPage {
            tr,
            csrf,
            base: item_href(&dataset, &item.summary.item_id),
            dataset,
            item_id: item.summary.item_id.clone(),
            forward,
            step_length: step_length.get(),
            current: if forward { frame(item, 0) } else { None },
            steps: if forward {
                item.actions
                    .iter()
                    .enumerate()
                    .map(|(i, a)| (i + 1, a.clone()))
                    .collect()
            } else {
                Vec::new()
            },
            long: step_length.get() >= 7,
            transitions,
            library: library(item),
            question: item.question.clone(),
            attention,
            draft_json: draft,
            finished: opened.finished,
        })
    }
}

#[derive(Serialize)]
struct Saved {
    saved: bool,
}

async fn save_draft(
    State(state): State<AppState>,
    Path((dataset, item_id)): Path<(String, String)>,
    request: Protected<Draft>,
) -> Result<Json<Saved>, ApiError> {
    annotation::save_draft(
        &state.hub,
        &request.session,
        &dataset,
        &item_id,
        &request.body,
    )
    .await?;
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
) -> Result<Json<Submitted>, ApiError> {
    annotation::answer(
        &state.hub,
        &request.session,
        &dataset,
        &item_id,
        &request.body,
    )
    .await?;
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
    let form = &request.body;
    annotation::skip(
        &state.hub,
        &request.session,
        &dataset,
        &item_id,
        &form.action,
        &form.reason,
    )
    .await?;
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
) -> Result<Json<OwnAnswer>, ApiError> {
    let a = annotation::own_answer(&state.hub, &session, &dataset, &item_id).await?;
    Ok(Json(OwnAnswer {
        dataset: a.dataset,
        item_id: a.item_id,
        outcome: a.outcome.as_str().to_owned(),
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
