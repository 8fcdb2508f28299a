//! Model metadata and results a paper published, from the web: `PUT
//! /api/v1/datasets/{dataset}/models/{model}` (an admin, or the account that submitted the
//! model), and the reported results of a dataset (list for anyone, add and remove for admins).

use axum::extract::State;
use axum::http::StatusCode;
use schemars::JsonSchema;
use serde::Serialize;

use super::extract::{Json, Path};
use super::openapi::{ApiRoute, Verb};
use super::{AppError, AppState};
use crate::app::models::{self, MetadataEditor, ModelMetadata, ModelMetadataEntry};
use crate::app::reported::{self, ReportedModelSchema, ReportedResult};
use crate::app::tokens::Caller;
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
) -> Result<axum::Json<ReportedList>, AppError> {
    let reported = reported::list(&state.hub, &dataset).await?;
    Ok(axum::Json(ReportedList { dataset, reported }))
}

async fn add_reported_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    caller: Caller,
    Json(model): Json<ReportedModel>,
) -> Result<(StatusCode, axum::Json<ReportedResult>), AppError> {
    let stored = reported::add(&state.hub, &caller.actor(), &dataset, &model).await?;
    Ok((StatusCode::CREATED, axum::Json(stored)))
}

async fn remove_reported_api(
    State(state): State<AppState>,
    Path((dataset, id)): Path<(String, i64)>,
    caller: Caller,
) -> Result<StatusCode, AppError> {
    reported::remove(&state.hub, &caller.actor(), &dataset, id).await?;
    Ok(StatusCode::NO_CONTENT)
}

async fn set_metadata_api(
    State(state): State<AppState>,
    Path((dataset, model)): Path<(String, String)>,
    caller: Caller,
    Json(metadata): Json<ModelMetadata>,
) -> Result<axum::Json<ModelMetadataEntry>, AppError> {
    let editor = MetadataEditor {
        actor: caller.actor(),
        admin: caller.has(Scope::Admin),
    };
    Ok(axum::Json(
        models::set(&state.hub, &editor, &dataset, &model, &metadata).await?,
    ))
}
