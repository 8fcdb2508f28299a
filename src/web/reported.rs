//! Model metadata and results a paper published, from the web: `PUT
//! /api/v1/datasets/{dataset}/models/{model}` (an admin, or the account that submitted the
//! model), and the reported results of a dataset (list for anyone, add and remove for admins).

use axum::extract::State;

use super::extract::{Json, Path};
use super::openapi::{ApiRoute, Verb};
use super::{AppError, AppState};
use crate::app::models::{self, MetadataEditor, ModelMetadata, ModelMetadataEntry};
use crate::app::tokens::Caller;
use crate::core::credentials::Scope;

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
    ]
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
