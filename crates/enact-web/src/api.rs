//! The JSON read API under `/api/v1`. Ground truth never appears in these responses.

use serde_json::json;
use std::collections::BTreeMap;

use axum::body::{Body, Bytes};
use axum::extract::State;
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::error::ApiError;
use super::extract::{Json, Path, Query, whole_number_between};
use super::openapi::{ApiRoute, Verb};
use super::session::ReaderIsAdmin;
use super::{AppError, AppState};
use crate::app::datasets::{self, DatasetOverview};
use crate::app::frames;
use crate::app::item_answers::{self, ItemAnswers};
use crate::app::items::{self, ItemFilter, ItemSummary, StoredItem};
use crate::app::refusal::Expected;
use crate::app::refusal::Refusal;
use crate::core::dataset::{Direction, StepLength};

/// The read API's routes (see [`super::openapi`]).
pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(Verb::Get, "/datasets", list_datasets, "List datasets")
            .describe("Every dataset with its item counts by direction and step length.")
            .responds_json::<DatasetList>(200, "Every dataset."),
        ApiRoute::new(Verb::Get, "/datasets/{dataset}", get_dataset, "One dataset")
            .describe("A dataset's item counts by direction and step length, and its items URL.")
            .responds_json::<DatasetView>(200, "The dataset.")
            .errors(&[404]),
        ApiRoute::new(
            Verb::Get,
            "/datasets/{dataset}/items",
            list_items,
            "List items",
        )
        .describe(
            "A dataset's items in import order, filtered and paged; `next` is the URL of \
                 the following page, or null on the last. Never includes ground truth.",
        )
        .query_with(
            "direction",
            false,
            // Empty values mean "any", as the dataset page's filter form sends them.
            json!({"enum": ["", "forward", "inverse"]}),
            "`forward` or `inverse`.",
        )
        .query_with(
            "step_length",
            false,
            json!({"anyOf": [{"type": "integer", "minimum": 3, "maximum": 10}, {"const": ""}]}),
            "L, the number of images: 3 to 10.",
        )
        .query("task", false, "An ENACT task name.")
        .query_with(
            "page",
            false,
            json!({"anyOf": [{"type": "integer", "minimum": 1, "maximum": 1_000_000}, {"const": ""}]}),
            "1-based page number (default 1).",
        )
        .query_with(
            "per_page",
            false,
            json!({"anyOf": [{"type": "integer", "minimum": 1, "maximum": MAX_PER_PAGE}, {"const": ""}]}),
            "Items per page, 1 to 500 (default 50).",
        )
        .responds_json::<ItemList>(200, "A page of items.")
        .errors(&[400, 404]),
        ApiRoute::new(
            Verb::Get,
            "/datasets/{dataset}/items/{item_id}",
            get_item,
            "One item",
        )
        .describe(
            "An item as a model sees it: question, action texts, and its images' labels \
                 and URLs in order. Never includes ground truth or key frame ids.",
        )
        .responds_json::<ItemView>(200, "The item.")
        .errors(&[404]),
        ApiRoute::new(
            Verb::Get,
            "/datasets/{dataset}/items/{item_id}/answers",
            get_item_answers,
            "Every answer to an item",
        )
        .describe(
            "The item's true order; every leaderboard row's answer (each account's latest \
             published submission of a model) with the order read from it, `task_correct`, \
             `pairwise_accuracy`, the `verdict` (`exact`, `equivalent`: another order the \
             verifier accepts, `wrong`, `unparseable`, `missing`) and, for a wrong answer on an \
             item with state changes, `why`: each step judged, with the changes the answer \
             implies that the true step lacks and those it misses (ENACT's sentences), and the \
             pairs of labels out of order; then every annotator's answer, pseudonymous. Only \
             for a dataset whose answers are public (404 otherwise, as for its ground truth), \
             unless the caller sends an admin token (`Authorization: Bearer`): then hidden \
             datasets too, with annotators' names, exclusions and the gold flag.",
        )
        .responds_json::<ItemAnswers>(200, "The item's answers.")
        .errors(&[404, 503]),
        ApiRoute::new(Verb::Get, "/frames/{sha256}", get_frame, "A frame")
            .describe(
                "A key frame as PNG, with a strong ETag and `Cache-Control: immutable`; \
                 `If-None-Match` with the ETag answers 304.",
            )
            .header(
                "If-None-Match",
                json!({"type": "string"}),
                "The ETag of a copy the client holds.",
            )
            .responds(200, Some("image/png"), "The PNG bytes.")
            .responds(304, None, "The client's copy is current.")
            .errors(&[404]),
    ]
}

pub fn frame_url(sha256: &str) -> String {
    format!("/api/v1/frames/{sha256}")
}

#[derive(Serialize, JsonSchema)]
struct DatasetView {
    name: String,
    created_at: String,
    /// `simulation`, or `real` for items made from a recorded real-world episode.
    origin: String,
    /// The scene(s) a real-world dataset was recorded in; empty otherwise.
    scene: String,
    items: i64,
    forward: i64,
    inverse: i64,
    tasks: i64,
    /// `direction -> step length -> count`.
    by_step_length: BTreeMap<Direction, BTreeMap<StepLength, i64>>,
    items_url: String,
}

impl From<DatasetOverview> for DatasetView {
    fn from(o: DatasetOverview) -> Self {
        DatasetView {
            items_url: format!("/api/v1/datasets/{}/items", o.dataset.name),
            name: o.dataset.name,
            created_at: o.dataset.created_at,
            origin: o.dataset.origin,
            scene: o.dataset.scene,
            items: o.items.total,
            forward: o.items.forward,
            inverse: o.items.inverse,
            tasks: o.tasks,
            by_step_length: o.items.by_kind,
        }
    }
}

#[derive(Serialize, JsonSchema)]
struct DatasetList {
    datasets: Vec<DatasetView>,
}

async fn list_datasets(State(state): State<AppState>) -> Result<Json<DatasetList>, ApiError> {
    let all = datasets::overview(&state.hub).await?;
    Ok(Json(DatasetList {
        datasets: all.into_iter().map(DatasetView::from).collect(),
    }))
}

async fn get_dataset(
    State(state): State<AppState>,
    Path(name): Path<String>,
) -> Result<Json<DatasetView>, ApiError> {
    Ok(Json(datasets::overview_of(&state.hub, &name).await?.into()))
}

/// Query parameters of item lists, as typed by people: parsed by hand for clear messages.
#[derive(Debug, Default, Deserialize)]
pub struct ItemQuery {
    pub direction: Option<String>,
    pub step_length: Option<String>,
    pub task: Option<String>,
    pub page: Option<String>,
    pub per_page: Option<String>,
}

pub const DEFAULT_PER_PAGE: u32 = 50;
pub const MAX_PER_PAGE: u32 = 500;

/// A validated item-list query.
pub struct ItemSelection {
    pub filter: ItemFilter,
    pub page: u32,
    pub per_page: u32,
}

impl ItemSelection {
    /// Rows to skip before this page.
    pub fn offset(&self) -> u32 {
        (self.page - 1).saturating_mul(self.per_page)
    }

    /// The query string that selects `page` with the same filters.
    pub fn query_string(&self, page: u32) -> String {
        let mut q = format!("page={page}&per_page={}", self.per_page);
        if let Some(d) = self.filter.direction {
            q.push_str(&format!("&direction={d}"));
        }
        if let Some(l) = self.filter.step_length {
            q.push_str(&format!("&step_length={l}"));
        }
        if let Some(t) = &self.filter.task {
            q.push_str(&format!("&task={t}"));
        }
        q
    }

    /// The page of items this selection names, and how many items match in all.
    pub async fn fetch(
        &self,
        state: &AppState,
        dataset: &str,
    ) -> Result<(Vec<ItemSummary>, i64), ApiError> {
        items::list(
            &state.hub,
            dataset,
            &self.filter,
            self.per_page,
            self.offset(),
        )
        .await
        .map_err(ApiError)
    }
}

impl ItemQuery {
    pub fn selection(&self) -> Result<ItemSelection, AppError> {
        let blank = |v: &Option<String>| {
            v.as_deref()
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(str::to_owned)
        };
        let direction = match blank(&self.direction) {
            None => None,
            Some(d) => Some(Direction::parse(&d.to_ascii_lowercase()).ok_or_else(|| {
                Refusal::bad_value(
                    "direction",
                    d.as_str(),
                    Expected::OneOf(vec!["forward", "inverse"]),
                )
            })?),
        };
        let step_length = match blank(&self.step_length) {
            None => None,
            Some(s) => Some(
                s.parse::<usize>()
                    .ok()
                    .and_then(StepLength::new)
                    .ok_or_else(|| {
                        Refusal::bad_value(
                            "step_length",
                            s.as_str(),
                            Expected::WholeNumber { least: 3, most: 10 },
                        )
                    })?,
            ),
        };
        let number = |name: &str, v: &Option<String>, default: u32, max: u32| match blank(v) {
            None => Ok(default),
            Some(s) => whole_number_between(name, &s, 1, max.into()).map(|n| n as u32),
        };
        Ok(ItemSelection {
            filter: ItemFilter {
                direction,
                step_length,
                task: blank(&self.task),
            },
            page: number("page", &self.page, 1, 1_000_000)?,
            per_page: number("per_page", &self.per_page, DEFAULT_PER_PAGE, MAX_PER_PAGE)?,
        })
    }
}

#[derive(Serialize, JsonSchema)]
struct ItemListEntry {
    id: String,
    #[serde(rename = "type")]
    item_type: String,
    direction: Direction,
    step_length: StepLength,
    task_name: String,
    url: String,
}

#[derive(Serialize, JsonSchema)]
struct ItemList {
    dataset: String,
    total: i64,
    page: u32,
    per_page: u32,
    items: Vec<ItemListEntry>,
    /// URL of the next page, if there is one.
    next: Option<String>,
}

async fn list_items(
    State(state): State<AppState>,
    Path(name): Path<String>,
    Query(query): Query<ItemQuery>,
) -> Result<Json<ItemList>, ApiError> {
    let selection = query.selection()?;
    let (items, total) = selection.fetch(&state, &name).await?;
    let shown = i64::from(selection.offset()) + items.len() as i64;
    let next = (shown < total).then(|| {
        format!(
            "/api/v1/datasets/{name}/items?{}",
            selection.query_string(selection.page + 1)
        )
    });
    Ok(Json(ItemList {
        items: items
            .into_iter()
            .map(|i| ItemListEntry {
                url: format!("/api/v1/datasets/{name}/items/{}", i.item_id),
                id: i.item_id,
                item_type: i.item_type,
                direction: i.direction,
                step_length: i.step_length,
                task_name: i.task_name,
            })
            .collect(),
        dataset: name,
        total,
        page: selection.page,
        per_page: selection.per_page,
        next,
    }))
}

#[derive(Serialize, JsonSchema)]
struct ActionView {
    label: usize,
    text: String,
}

#[derive(Serialize, JsonSchema)]
struct ImageView {
    position: usize,
    label: String,
    url: String,
}

/// What a model or a person is shown of an item: never its ground truth.
#[derive(Serialize, JsonSchema)]
struct ItemView {
    id: String,
    dataset: String,
    #[serde(rename = "type")]
    item_type: String,
    direction: Direction,
    step_length: StepLength,
    task_name: String,
    question: String,
    actions: Vec<ActionView>,
    images: Vec<ImageView>,
}

impl ItemView {
    fn new(dataset: String, item: &StoredItem) -> Self {
        ItemView {
            id: item.summary.item_id.clone(),
            dataset,
            item_type: item.summary.item_type.clone(),
            direction: item.summary.direction,
            step_length: item.summary.step_length,
            task_name: item.summary.task_name.clone(),
            question: item.question.clone(),
            actions: item
                .actions
                .iter()
                .enumerate()
                .map(|(i, text)| ActionView {
                    label: i + 1,
                    text: text.clone(),
                })
                .collect(),
            images: item
                .images
                .iter()
                .map(|img| ImageView {
                    position: img.position,
                    label: img.label(),
                    url: frame_url(&img.sha256),
                })
                .collect(),
        }
    }
}

async fn get_item_answers(
    State(state): State<AppState>,
    ReaderIsAdmin(admin): ReaderIsAdmin,
    Path((name, item_id)): Path<(String, String)>,
) -> Result<axum::Json<ItemAnswers>, ApiError> {
    Ok(axum::Json(
        item_answers::of(&state.hub, &name, &item_id, admin).await?,
    ))
}

async fn get_item(
    State(state): State<AppState>,
    Path((name, item_id)): Path<(String, String)>,
) -> Result<Response, ApiError> {
    let cache = state.hub.items();
    let json = match cache.json(&name, &item_id) {
        Some(json) => json,
        None => {
            let item = items::get(&state.hub, &name, &item_id).await?;
            let json = Bytes::from(serde_json::to_vec(&ItemView::new(name.to_string(), &item))?);
            cache.insert_json(&name, &item_id, json.clone());
            json
        }
    };
    Ok((
        [(
            header::CONTENT_TYPE,
            HeaderValue::from_static("application/json"),
        )],
        json,
    )
        .into_response())
}

fn is_sha256_hex(s: &str) -> bool {
    s.len() == 64
        && s.bytes()
            .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
}

/// True when an `If-None-Match` header names this entity tag (or is `*`).
pub(super) fn matches_etag(headers: &HeaderMap, etag: &str) -> bool {
    headers
        .get_all(header::IF_NONE_MATCH)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(','))
        .map(str::trim)
        .any(|tag| tag == "*" || tag == etag || tag.strip_prefix("W/") == Some(etag))
}

/// A frame as PNG. Frames are addressed by content hash, so the response never changes:
/// a strong ETag and `immutable` let clients skip the request entirely.
async fn get_frame(
    State(state): State<AppState>,
    Path(sha256): Path<String>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    let not_found = || {
        AppError::from(Refusal::NoFrame {
            frame: sha256.clone(),
        })
    };
    if !is_sha256_hex(&sha256) {
        return Err(ApiError(not_found()));
    }
    let etag = format!("\"{sha256}\"");
    // The hash is the content: a client that has it needs nothing read.
    if matches_etag(&headers, &etag) {
        return Ok(frame_response(
            StatusCode::NOT_MODIFIED.into_response(),
            &etag,
        ));
    }
    let png = match frames::png_or_redirect(&state.hub, &sha256, state.hub.frame_redirect()).await?
    {
        frames::FrameBytes::Png(png) => png,
        frames::FrameBytes::Redirect(url) => {
            // The presigned URL expires: the redirect is cached for less than its life.
            let mut r = StatusCode::TEMPORARY_REDIRECT.into_response();
            let h = r.headers_mut();
            if let Ok(v) = HeaderValue::from_str(url.as_str()) {
                h.insert(header::LOCATION, v);
            }
            let max_age = state.hub.frame_redirect().unwrap_or_default().as_secs() / 2;
            if let Ok(v) = HeaderValue::from_str(&format!("private, max-age={max_age}")) {
                h.insert(header::CACHE_CONTROL, v);
            }
            return Ok(r);
        }
    };
    let mut r = Response::new(Body::from(png));
    r.headers_mut()
        .insert(header::CONTENT_TYPE, HeaderValue::from_static("image/png"));
    Ok(frame_response(r, &etag))
}

/// A frame's headers: a strong ETag (its hash) and caching for a year, never revalidated.
fn frame_response(mut response: Response, etag: &str) -> Response {
    let h = response.headers_mut();
    if let Ok(v) = HeaderValue::from_str(etag) {
        h.insert(header::ETAG, v);
    }
    h.insert(
        header::CACHE_CONTROL,
        HeaderValue::from_static("public, max-age=31536000, immutable"),
    );
    response
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn etag_matching_follows_if_none_match_rules() {
        let mut h = HeaderMap::new();
        h.insert(
            header::IF_NONE_MATCH,
            HeaderValue::from_static("\"a\", \"b\""),
        );
        assert!(matches_etag(&h, "\"b\""));
        assert!(!matches_etag(&h, "\"c\""));
        h.insert(header::IF_NONE_MATCH, HeaderValue::from_static("W/\"c\""));
        assert!(matches_etag(&h, "\"c\""));
        h.insert(header::IF_NONE_MATCH, HeaderValue::from_static("*"));
        assert!(matches_etag(&h, "\"z\""));
    }

    #[test]
    fn item_query_rejects_bad_values_with_their_name() {
        let field_of = |q: ItemQuery| match q.selection() {
            Err(AppError::Refused(Refusal::BadValue { field, .. })) => field,
            other => panic!("expected a bad value, got {:?}", other.err()),
        };
        let q = ItemQuery {
            direction: Some("sideways".into()),
            ..ItemQuery::default()
        };
        assert_eq!(field_of(q), "direction");
        let q = ItemQuery {
            step_length: Some("11".into()),
            ..ItemQuery::default()
        };
        assert_eq!(field_of(q), "step_length");
        let q = ItemQuery {
            per_page: Some("0".into()),
            ..ItemQuery::default()
        };
        assert_eq!(field_of(q), "per_page");
    }
}
