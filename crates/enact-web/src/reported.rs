//! Model metadata and results a paper published, from the web: `PUT
//! /api/v1/datasets/{dataset}/models/{model}` (an admin, or the account that submitted the
//! model), and the reported results of a dataset (list for anyone, add and remove for admins);
//! and the admin page of both, `/admin/datasets/{dataset}/reported` (list, import the ENACT
//! paper's results or a pasted table, remove a row, set a submitted model's metadata).

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{Html, IntoResponse, Response};
use axum::routing::{get, post};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::auth::TokenCaller;
use super::error::{ApiError, PageError, RenderPage};
use super::extract::{Json, Path};
use super::openapi::{ApiRoute, Verb};
use super::session::{Admin, Protected};
use super::{AppError, AppState};
use crate::app::models::{self, MetadataEditor, ModelMetadata, ModelMetadataEntry};
use crate::app::refusal::{Expected, Refusal};
use crate::app::reported::{self, ReportedModelSchema, ReportedResult};
use crate::core::annotation::Session;
use crate::core::credentials::Scope;
use crate::core::paper::ReportedModel;

pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Put,
            "/datasets/{dataset}/models/{model}",
            set_metadata_api,
            "Set a model's metadata on a dataset",
        )
        .describe(
            "Replaces the category, family, size and link of the hub's own rows of `model` on \
             the dataset (absent or blank fields are cleared); the leaderboard's rows carry \
             them in `metadata`. An admin may set any model's; an account only that of a model \
             it submitted to the dataset (403 otherwise), and only the categories \
             `proprietary` and `open-weight`. The link must be an http or https URL. Audited \
             (`model.metadata`).",
        )
        .bearer(Scope::Submit)
        .body_json::<ModelMetadata>(
            "Any of `category`, `family`, `size`, `link`.",
            "{\"category\": \"open-weight\", \"family\": \"Qwen2.5-VL\", \"size\": \"7B\", \
             \"link\": \"https://huggingface.co/Qwen/Qwen2.5-VL-7B-Instruct\"}",
        )
        .responds_json::<ModelMetadataEntry>(200, "The metadata as stored.")
        .errors(&[400, 401, 403, 404, 415, 422]),
        ApiRoute::new(
            Verb::Get,
            "/datasets/{dataset}/reported",
            list_reported_api,
            "Results papers published for a dataset",
        )
        .describe(
            "Every reported result attached to the dataset (a paper's numbers entered as data,              e.g. the ENACT paper's by `enact-hub reported import --paper`): model, category,              family, size, source, and task and pairwise accuracy in percent by cell              (`forward_3` .. `inverse_10`). The leaderboard shows them with `reported=1`.",
        )
        .responds_json::<ReportedList>(200, "The reported results, in the order entered.")
        .errors(&[404]),
        ApiRoute::new(
            Verb::Post,
            "/datasets/{dataset}/reported",
            add_reported_api,
            "Add a reported result",
        )
        .describe(
            "Attaches one paper's result for one model to the dataset. Values are percentages              (0 to 100); at least one cell is given. A second row of the same model and source              is refused (409). Audited (`reported.add`); every server's leaderboard shows it.",
        )
        .bearer(Scope::Admin)
        .body_json::<ReportedModelSchema>(
            "The model, its category, source, optional family and size, and its cells.",
            "{\"model\": \"GPT-5\", \"category\": \"proprietary\", \"source\": \
             \"ENACT paper, Table 1\", \"task_accuracy\": {\"forward_3\": 80.59}, \
             \"pairwise_accuracy\": {\"forward_3\": 84.62}}",
        )
        .responds_json::<ReportedResult>(201, "The reported result as stored, with its id.")
        .errors(&[400, 401, 403, 404, 409, 415, 422]),
        ApiRoute::new(
            Verb::Delete,
            "/datasets/{dataset}/reported/{reported_id}",
            remove_reported_api,
            "Remove a reported result",
        )
        .describe("Removes the dataset's reported result `reported_id` (its `id` in the list). Audited \
             (`reported.remove`).")
        .bearer(Scope::Admin)
        .responds(204, None, "Removed.")
        .errors(&[400, 401, 403, 404]),
    ]
}

#[derive(Serialize, JsonSchema)]
struct ReportedList {
    dataset: String,
    reported: Vec<ReportedResult>,
}

async fn list_reported_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
) -> Result<axum::Json<ReportedList>, ApiError> {
    let reported = reported::list(&state.hub, &dataset).await?;
    Ok(axum::Json(ReportedList { dataset, reported }))
}

async fn add_reported_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    TokenCaller(caller): TokenCaller,
    Json(model): Json<ReportedModel>,
) -> Result<(StatusCode, axum::Json<ReportedResult>), ApiError> {
    let stored = reported::add(&state.hub, &caller.actor(), &dataset, &model).await?;
    Ok((StatusCode::CREATED, axum::Json(stored)))
}

async fn remove_reported_api(
    State(state): State<AppState>,
    Path((dataset, id)): Path<(String, i64)>,
    TokenCaller(caller): TokenCaller,
) -> Result<StatusCode, ApiError> {
    reported::remove(&state.hub, &caller.actor(), &dataset, id).await?;
    Ok(StatusCode::NO_CONTENT)
}

async fn set_metadata_api(
    State(state): State<AppState>,
    Path((dataset, model)): Path<(String, String)>,
    TokenCaller(caller): TokenCaller,
    Json(body): Json<serde_json::Map<String, serde_json::Value>>,
) -> Result<axum::Json<ModelMetadataEntry>, ApiError> {
    // Taken as an object first: serde would read a struct from an array of its fields.
    let metadata: ModelMetadata =
        serde_json::from_value(serde_json::Value::Object(body)).map_err(|e| {
            AppError::Rejected {
                message: format!("the JSON body does not fit this route: {e}"),
                problems: Vec::new(),
            }
        })?;
    let editor = MetadataEditor {
        actor: caller.actor(),
        admin: caller.has(Scope::Admin),
    };
    Ok(axum::Json(
        models::set(&state.hub, &editor, &dataset, &model, &metadata).await?,
    ))
}

/// The admin's page (mounted behind the admin gate, [`super::admin_pages`]).
pub fn admin_router() -> Router<AppState> {
    Router::new()
        .route("/admin/datasets/{dataset}/reported", get(admin_page))
        .route(
            "/admin/datasets/{dataset}/reported/paper",
            post(admin_import_paper),
        )
        .route(
            "/admin/datasets/{dataset}/reported/tables",
            post(admin_import_tables),
        )
        .route(
            "/admin/datasets/{dataset}/reported/remove",
            post(admin_remove),
        )
        .route("/admin/datasets/{dataset}/models", post(admin_set_metadata))
}

/// A reported row as the admin page lists it; absent fields as a dash.
struct ReportedLine {
    id: i64,
    model: String,
    category: String,
    family: String,
    size: String,
    source: String,
    added_by: String,
    added_at: String,
}

/// A submitted model and its metadata as the admin page lists it.
struct ModelLine {
    model: String,
    category: String,
    family: String,
    size: String,
    link: Option<String>,
    /// Who set it and when, when anyone has.
    updated: Option<String>,
}

#[derive(Template)]
#[template(path = "admin_reported.html")]
struct AdminReportedPage {
    name: String,
    csrf: String,
    dataset: String,
    reported: Vec<ReportedLine>,
    models: Vec<ModelLine>,
    /// What the last action did, shown on top.
    notice: Option<String>,
    /// Why the last action was refused (nothing of it stored), shown on top.
    error: Option<String>,
    /// The table last pasted, kept in its field when it was refused.
    pasted: String,
}

/// What an admin form asked for and how it went, for [`render_admin`].
enum Outcome {
    Shown,
    Done(String),
    /// Refused for a reason the admin can act on (400); the pasted text is kept.
    Refused(String, String),
}

fn dash(value: Option<&str>) -> String {
    value.unwrap_or("–").to_owned()
}

async fn render_admin(
    state: &AppState,
    session: Session,
    dataset: &str,
    outcome: Outcome,
) -> Result<Response, PageError> {
    let reported = reported::list(&state.hub, dataset).await?;
    let mut metadata = models::of_dataset(&state.hub, dataset).await?;
    let models = models::submitted(&state.hub, dataset)
        .await?
        .into_iter()
        .map(|model| match metadata.remove(&model) {
            Some(entry) => ModelLine {
                model,
                category: dash(entry.metadata.category.as_deref()),
                family: dash(entry.metadata.family.as_deref()),
                size: dash(entry.metadata.size.as_deref()),
                link: entry.metadata.link,
                updated: Some(format!("{} by {}", entry.updated_at, entry.updated_by)),
            },
            None => ModelLine {
                model,
                category: dash(None),
                family: dash(None),
                size: dash(None),
                link: None,
                updated: None,
            },
        })
        .collect();
    let (status, notice, error, pasted) = match outcome {
        Outcome::Shown => (StatusCode::OK, None, None, String::new()),
        Outcome::Done(notice) => (StatusCode::OK, Some(notice), None, String::new()),
        Outcome::Refused(error, pasted) => (StatusCode::BAD_REQUEST, None, Some(error), pasted),
    };
    let page = AdminReportedPage {
        name: session.name,
        csrf: session.csrf_token,
        dataset: dataset.to_owned(),
        reported: reported
            .into_iter()
            .map(|r| ReportedLine {
                id: r.id,
                model: r.reported.model,
                category: r.reported.category.as_str().to_owned(),
                family: dash(r.reported.family.as_deref()),
                size: dash(r.reported.size.as_deref()),
                source: r.reported.source,
                added_by: r.added_by,
                added_at: r.added_at,
            })
            .collect(),
        models,
        notice,
        error,
        pasted,
    };
    Ok((status, Html(page.render_page()?)).into_response())
}

/// The page after a use case ran: its notice, or the refusal of a mistake the admin can fix in
/// the form (a table or field that does not read) shown above the forms, the pasted table kept;
/// anything else (an unknown dataset, model or row) is an error page.
async fn after<T>(
    state: &AppState,
    session: Session,
    dataset: &str,
    result: Result<T, AppError>,
    notice: impl FnOnce(T) -> String,
    pasted: String,
) -> Result<Response, PageError> {
    let outcome = match result {
        Ok(done) => Outcome::Done(notice(done)),
        Err(AppError::Invalid(m)) => Outcome::Refused(m, pasted),
        Err(e) => return Err(e.into()),
    };
    render_admin(state, session, dataset, outcome).await
}

async fn admin_page(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    Admin(session): Admin,
) -> Result<Response, PageError> {
    render_admin(&state, session, &dataset, Outcome::Shown).await
}

fn imported(done: reported::ReportedImport) -> String {
    format!(
        "Stored {} reported rows on '{}' ({} replacing rows of the same model and source).",
        done.stored, done.dataset, done.replaced
    )
}

#[derive(Deserialize)]
struct EmptyForm {}

async fn admin_import_paper(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    request: Protected<EmptyForm>,
) -> Result<Response, PageError> {
    let actor = request.session.actor();
    let result = reported::import_paper(&state.hub, &actor, &dataset).await;
    after(
        &state,
        request.session,
        &dataset,
        result,
        imported,
        String::new(),
    )
    .await
}

#[derive(Deserialize)]
struct TablesForm {
    /// One table in the JSON shape `paper` writes.
    #[serde(default)]
    table: String,
}

/// The name a pasted table goes by in refusals and in the audit entry.
const PASTED: &str = "pasted.json";

async fn admin_import_tables(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    request: Protected<TablesForm>,
) -> Result<Response, PageError> {
    let actor = request.session.actor();
    let table = request.body.table;
    let files = [(PASTED.to_owned(), table.clone())];
    let result = reported::import_tables(&state.hub, &actor, &dataset, &files).await;
    after(&state, request.session, &dataset, result, imported, table).await
}

#[derive(Deserialize)]
struct RemoveForm {
    #[serde(default)]
    id: String,
}

async fn admin_remove(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    request: Protected<RemoveForm>,
) -> Result<Response, PageError> {
    let id: i64 = request
        .body
        .id
        .trim()
        .parse()
        .map_err(|_| Refusal::bad_value("id", request.body.id.trim(), Expected::ReportedId))?;
    let actor = request.session.actor();
    let result = reported::remove(&state.hub, &actor, &dataset, id).await;
    after(
        &state,
        request.session,
        &dataset,
        result,
        |()| format!("Removed reported result {id}."),
        String::new(),
    )
    .await
}

#[derive(Deserialize)]
struct MetadataForm {
    #[serde(default)]
    model: String,
    #[serde(default)]
    category: String,
    #[serde(default)]
    family: String,
    #[serde(default)]
    size: String,
    #[serde(default)]
    link: String,
}

async fn admin_set_metadata(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    request: Protected<MetadataForm>,
) -> Result<Response, PageError> {
    let form = request.body;
    // Blank fields are cleared, as the API's absent ones are.
    let metadata = ModelMetadata {
        category: Some(form.category),
        family: Some(form.family),
        size: Some(form.size),
        link: Some(form.link),
    };
    let editor = MetadataEditor {
        actor: request.session.actor(),
        admin: true,
    };
    let result = models::set(&state.hub, &editor, &dataset, &form.model, &metadata).await;
    after(
        &state,
        request.session,
        &dataset,
        result,
        |entry| format!("Set the metadata of model '{}'.", entry.model),
        String::new(),
    )
    .await
}
