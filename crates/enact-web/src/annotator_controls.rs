//! Annotator controls from the web: pausing and resuming a queue, handing an annotator's
//! unfinished items to others, and a dataset's attention checks; the admin API
//! (`/api/v1/admin/annotators/{annotator}/pause|handover`,
//! `/api/v1/admin/datasets/{dataset}/attention`) and the forms of the admin quality page
//! (`/admin/quality`, rendered by [`super::quality`]).

use axum::Router;
use axum::extract::State;
use axum::response::Html;
use axum::routing::post;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::auth::TokenCaller;
use super::error::{ApiError, PageError};
use super::extract::{Json, Path, required_whole_number};
use super::openapi::{ApiRoute, Verb};
use super::quality::{PageQuery, render};
use super::session::Protected;
use super::{AppError, AppState};
use crate::app::attention::{AttentionCleared, AttentionQueues, AttentionSet};
use crate::app::controls::Handover;
use crate::app::refusal::{Expected, Refusal};
use crate::app::{attention, controls};
use crate::core::attention::{Instruction, parse_check_list};
use crate::core::credentials::Scope;
use crate::core::gold::GoldRate;

pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Put,
            "/admin/annotators/{annotator}/pause",
            pause_api,
            "Pause an annotator's queue",
        )
        .describe(
            "While paused, the annotator's queue page says so and opening, saving, answering \
             or skipping an item is refused (409); no balanced split assigns them items. \
             Drafts, assignments and answers stay. DELETE on the same path resumes. Audited \
             (`annotator.pause`) when it changes anything (`changed`).",
        )
        .bearer(Scope::Admin)
        .responds_json::<PauseChanged>(200, "The queue is paused.")
        .errors(&[401, 403, 404]),
        ApiRoute::new(
            Verb::Delete,
            "/admin/annotators/{annotator}/pause",
            resume_api,
            "Resume an annotator's queue",
        )
        .describe(
            "The queue is as it was before the pause, drafts included. Audited \
             (`annotator.resume`) when it changes anything (`changed`: false when it was not \
             paused).",
        )
        .bearer(Scope::Admin)
        .responds_json::<PauseChanged>(200, "The queue runs.")
        .errors(&[401, 403, 404]),
        ApiRoute::new(
            Verb::Post,
            "/admin/annotators/{annotator}/handover",
            handover_api,
            "Hand an annotator's unfinished items to others",
        )
        .describe(
            "Every item assigned to the annotator without a finished answer leaves their queue \
             (with their draft of it) and is split evenly over `to` (all other active \
             annotators, admins aside, whose queue is not paused, when `to` is empty or \
             absent), kind by kind, never to someone who has the item already: an item every \
             recipient has stays. Gold items and attention checks mixed into the annotator's \
             queue are taken out, not handed on. Finished answers stay with the annotator. \
             Audited (`annotator.handover`).",
        )
        .bearer(Scope::Admin)
        .body_json::<HandoverRequest>(
            "The recipients' names (optional).",
            "{\"to\": [\"bob\", \"carol\"]}",
        )
        .responds_json::<Handover>(200, "What moved where.")
        .errors(&[400, 401, 403, 404, 409, 415, 422]),
        ApiRoute::new(
            Verb::Get,
            "/admin/datasets/{dataset}/attention",
            attention_api,
            "A dataset's attention checks",
        )
        .describe(
            "The attention-check items with their instructions and the rate they are mixed \
             in at; `attention` is null when the dataset has none.",
        )
        .bearer(Scope::Admin)
        .responds_json::<AttentionOfDataset>(200, "The attention checks, or null.")
        .errors(&[401, 403, 404]),
        ApiRoute::new(
            Verb::Put,
            "/admin/datasets/{dataset}/attention",
            set_attention_api,
            "Choose a dataset's attention checks",
        )
        .describe(
            "Replaces the dataset's attention checks with `checks` and mixes them into every \
             annotator's queue like gold items: one in every `rate` items. Each check's \
             question carries its instruction: `keep` (put the listed cards in the slots in \
             the order listed, so the expected answer is 1, 2, …, L−1) or `reverse` (in \
             reverse order: L−1, …, 1). Answers are judged against the instruction, counted \
             per annotator on the quality report, and never count in the Human row or the \
             agreement report. Gold items cannot be checks. Audited (`attention.set`).",
        )
        .bearer(Scope::Admin)
        .body_json::<AttentionRequest>(
            "`rate` and the `checks`.",
            "{\"rate\": 10, \"checks\": [{\"item_id\": \"cook_bacon_1700000000000042_forward_world_modeling_ordering_3_steps_1acd8e69\", \"instruction\": \"reverse\"}]}",
        )
        .responds_json::<AttentionChanged>(
            200,
            "The attention checks as stored, and what changed in queues.",
        )
        .errors(&[400, 401, 403, 404, 415, 422]),
        ApiRoute::new(
            Verb::Delete,
            "/admin/datasets/{dataset}/attention",
            clear_attention_api,
            "Remove a dataset's attention checks",
        )
        .describe(
            "Unfinished attention checks leave the queues; answers given stay. Audited \
             (`attention.clear`). A dataset without attention checks is left as it is \
             (`cleared` false).",
        )
        .bearer(Scope::Admin)
        .responds_json::<AttentionCleared>(200, "Whether there were checks, and what left queues.")
        .errors(&[401, 403, 404]),
    ]
}

/// The quality page's forms (behind the admin pages' gate, `web::admin_pages`).
pub fn router() -> Router<AppState> {
    Router::new()
        .route("/admin/quality/pause", post(pause_page))
        .route("/admin/quality/handover", post(handover_page))
        .route("/admin/quality/attention", post(set_attention_page))
        .route("/admin/quality/attention/clear", post(clear_attention_page))
}

#[derive(Serialize, JsonSchema)]
struct PauseChanged {
    annotator: String,
    paused: bool,
    /// False when it was so already.
    changed: bool,
}

async fn pause_api(
    State(state): State<AppState>,
    Path(annotator): Path<String>,
    TokenCaller(caller): TokenCaller,
) -> Result<axum::Json<PauseChanged>, ApiError> {
    let changed = controls::pause(&state.hub, &caller.actor(), &annotator).await?;
    Ok(axum::Json(PauseChanged {
        annotator,
        paused: true,
        changed,
    }))
}

async fn resume_api(
    State(state): State<AppState>,
    Path(annotator): Path<String>,
    TokenCaller(caller): TokenCaller,
) -> Result<axum::Json<PauseChanged>, ApiError> {
    let changed = controls::resume(&state.hub, &caller.actor(), &annotator).await?;
    Ok(axum::Json(PauseChanged {
        annotator,
        paused: false,
        changed,
    }))
}

/// Who gets the items; everyone eligible when empty.
#[derive(Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct HandoverRequest {
    /// Annotators' login names, each once.
    #[serde(default)]
    #[schemars(extend("uniqueItems" = true))]
    to: Vec<String>,
}

async fn handover_api(
    State(state): State<AppState>,
    Path(annotator): Path<String>,
    TokenCaller(caller): TokenCaller,
    Json(request): Json<HandoverRequest>,
) -> Result<axum::Json<Handover>, ApiError> {
    Ok(axum::Json(
        controls::handover(&state.hub, &caller.actor(), &annotator, &request.to).await?,
    ))
}

/// A dataset's attention checks, if it has some.
#[derive(Serialize, JsonSchema)]
struct AttentionOfDataset {
    dataset: String,
    attention: Option<AttentionSet>,
}

async fn attention_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
) -> Result<axum::Json<AttentionOfDataset>, ApiError> {
    let attention = attention::show(&state.hub, &dataset).await?;
    Ok(axum::Json(AttentionOfDataset { dataset, attention }))
}

/// One attention check to set.
#[derive(Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct CheckRequest {
    /// An item id of the dataset.
    #[schemars(regex(pattern = r"^\S+$"))]
    item_id: String,
    instruction: Instruction,
}

/// Attention checks to choose: `rate` and the `checks`.
#[derive(Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct AttentionRequest {
    /// One attention check in every `rate` queue items (2 to 1000).
    #[serde(deserialize_with = "required_whole_number")]
    #[schemars(with = "i64", range(min = 2, max = GoldRate::MAX))]
    rate: i64,
    /// Each item once.
    #[schemars(length(min = 1))]
    checks: Vec<CheckRequest>,
}

#[derive(Serialize, JsonSchema)]
struct AttentionChanged {
    attention: AttentionSet,
    queues: AttentionQueues,
}

async fn set_attention_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    TokenCaller(caller): TokenCaller,
    Json(request): Json<AttentionRequest>,
) -> Result<axum::Json<AttentionChanged>, ApiError> {
    let rate = GoldRate::new(request.rate)
        .map_err(|_| super::quality::rate_refused(&request.rate.to_string()))?;
    let checks: Vec<(String, Instruction)> = request
        .checks
        .into_iter()
        .map(|c| (c.item_id, c.instruction))
        .collect();
    let (attention, queues) =
        attention::set(&state.hub, &caller.actor(), &dataset, &checks, rate).await?;
    Ok(axum::Json(AttentionChanged { attention, queues }))
}

async fn clear_attention_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    TokenCaller(caller): TokenCaller,
) -> Result<axum::Json<AttentionCleared>, ApiError> {
    Ok(axum::Json(
        attention::clear(&state.hub, &caller.actor(), &dataset).await?,
    ))
}

fn back_to(dataset: String) -> PageQuery {
    PageQuery::of(dataset)
}

/// Pause or resume: `action` is `pause` or `resume`; `dataset` is the page's.
#[derive(Deserialize)]
struct PauseForm {
    #[serde(default)]
    dataset: String,
    annotator: String,
    action: String,
}

async fn pause_page(
    State(state): State<AppState>,
    request: Protected<PauseForm>,
) -> Result<Html<String>, PageError> {
    let form = request.body;
    let actor = request.session.actor();
    let notice = match form.action.as_str() {
        "pause" => {
            if controls::pause(&state.hub, &actor, &form.annotator).await? {
                format!("The queue of '{}' is paused.", form.annotator)
            } else {
                format!("The queue of '{}' was paused already.", form.annotator)
            }
        }
        "resume" => {
            if controls::resume(&state.hub, &actor, &form.annotator).await? {
                format!("The queue of '{}' runs again.", form.annotator)
            } else {
                format!("The queue of '{}' was not paused.", form.annotator)
            }
        }
        other => {
            return Err(Refusal::bad_value(
                "action",
                other,
                Expected::OneOf(vec!["pause", "resume"]),
            )
            .into());
        }
    };
    render(&state, request.session, back_to(form.dataset), Some(notice)).await
}

/// A handover: `to` is names separated by commas or spaces, empty for everyone eligible.
#[derive(Deserialize)]
struct HandoverForm {
    #[serde(default)]
    dataset: String,
    annotator: String,
    #[serde(default)]
    to: String,
}

async fn handover_page(
    State(state): State<AppState>,
    request: Protected<HandoverForm>,
) -> Result<Html<String>, PageError> {
    let form = request.body;
    let to: Vec<String> = form
        .to
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|s| !s.is_empty())
        .map(str::to_owned)
        .collect();
    let done =
        controls::handover(&state.hub, &request.session.actor(), &form.annotator, &to).await?;
    let moved: Vec<String> = done
        .to
        .iter()
        .map(|t| format!("{} to {}", t.items.len(), t.annotator))
        .collect();
    let notice = format!(
        "Unfinished items of '{}' handed over: {}; {} stayed (every recipient had them); {} \
         gold items and attention checks taken out; {} drafts removed.",
        done.from,
        moved.join(", "),
        done.kept.len(),
        done.removed_checks,
        done.drafts_removed
    );
    render(&state, request.session, back_to(form.dataset), Some(notice)).await
}

/// The attention form: `rate` and `checks` (one `ITEM_ID keep|reverse` per line).
#[derive(Deserialize)]
struct AttentionForm {
    dataset: String,
    #[serde(default)]
    rate: String,
    #[serde(default)]
    checks: String,
}

async fn set_attention_page(
    State(state): State<AppState>,
    request: Protected<AttentionForm>,
) -> Result<Html<String>, PageError> {
    let form = request.body;
    let rate = form
        .rate
        .trim()
        .parse::<i64>()
        .ok()
        .and_then(|r| GoldRate::new(r).ok())
        .ok_or_else(|| super::quality::rate_refused(form.rate.trim()))?;
    let checks =
        parse_check_list(&form.checks).map_err(|e| AppError::Invalid(format!("checks: {e}")))?;
    let (set, queues) = attention::set(
        &state.hub,
        &request.session.actor(),
        &form.dataset,
        &checks,
        rate,
    )
    .await?;
    let notice = format!(
        "Attention checks of '{}': {} items, one in every {} queue items; {} added to queues, \
         {} unfinished ones of the earlier set taken out.",
        set.dataset,
        set.checks.len(),
        set.rate,
        queues.added,
        queues.removed
    );
    render(&state, request.session, back_to(form.dataset), Some(notice)).await
}

#[derive(Deserialize)]
struct DatasetForm {
    dataset: String,
}

async fn clear_attention_page(
    State(state): State<AppState>,
    request: Protected<DatasetForm>,
) -> Result<Html<String>, PageError> {
    let dataset = request.body.dataset;
    let cleared = attention::clear(&state.hub, &request.session.actor(), &dataset).await?;
    let notice = if cleared.cleared {
        format!(
            "Attention checks of '{dataset}' cleared; {} unfinished ones taken out of queues.",
            cleared.removed
        )
    } else {
        format!("Dataset '{dataset}' had no attention checks.")
    };
    render(&state, request.session, back_to(dataset), Some(notice)).await
}
