//! Model metadata: what the hub's own leaderboard rows of a model on a dataset say about it
//! (its category, family, size and a link), set by an admin or by the account that submitted
//! the model, audited, and carried into the leaderboard's rows.
//!
//! Metadata is kept per dataset and model name, not globally: a submission, and so the account
//! that owns a model's rows, belongs to one dataset, and the same name on another dataset may
//! be another account's model.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::changes::Change;
use super::refusal::Refusal;
use super::{AppError, Hub, audit, datasets};
use crate::Lane;
use crate::core::audit::{Actor, AuditAction};
use crate::store;
use crate::store::model_metadata::StoredModelMetadata;

/// The categories a submitter may put its own model in; an admin may name any other.
pub const SUBMITTER_CATEGORIES: [&str; 2] = ["proprietary", "open-weight"];

/// The longest category, family or size accepted, in characters.
const MAX_FIELD: usize = 100;
/// The longest link accepted, in characters.
const MAX_LINK: usize = 2000;

/// A model's metadata as a client sends it and the leaderboard shows it; each field may be
/// absent.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ModelMetadata {
    /// `proprietary`, `open-weight`, or (set by an admin) any other name.
    #[serde(default)]
    #[schemars(
        length(max = 100),
        regex(pattern = r"^[^\u0000-\u001F\u007F-\u009F]*$")
    )]
    pub category: Option<String>,
    /// The model family ("Qwen2.5-VL", "GPT-4o").
    #[serde(default)]
    #[schemars(
        length(max = 100),
        regex(pattern = r"^[^\u0000-\u001F\u007F-\u009F]*$")
    )]
    pub family: Option<String>,
    /// The size as the model's authors give it ("7B", "72B").
    #[serde(default)]
    #[schemars(
        length(max = 100),
        regex(pattern = r"^[^\u0000-\u001F\u007F-\u009F]*$")
    )]
    pub size: Option<String>,
    /// An http or https URL about the model (blank: none).
    #[serde(default)]
    #[schemars(
        length(max = 2000),
        regex(
            pattern = r"^(https?://[A-Za-z0-9]([A-Za-z0-9.-]*[A-Za-z0-9])?(:[0-9]{1,4})?(/[!-~]*)?)?$"
        )
    )]
    pub link: Option<String>,
}

/// A model's metadata on a dataset as stored, with who set it last.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, schemars::JsonSchema)]
pub struct ModelMetadataEntry {
    pub dataset: String,
    pub model: String,
    #[serde(flatten)]
    pub metadata: ModelMetadata,
    pub updated_by: String,
    pub updated_at: String,
}

/// Who asks to change a model's metadata.
#[derive(Debug, Clone)]
pub struct MetadataEditor {
    pub actor: Actor,
    /// An admin (or the operator at the command line), who may edit any model's metadata and
    /// name any category; otherwise only the account that submitted the model may.
    pub admin: bool,
}

impl ModelMetadata {
    /// The metadata with blank fields as absent and surrounding spaces trimmed, or what is
    /// wrong with it, by field.
    fn checked(&self, admin: bool) -> Result<ModelMetadata, AppError> {
        let field = |name: &str, value: &Option<String>, max: usize| {
            let value = value
                .as_deref()
                .map(str::trim)
                .filter(|v| !v.is_empty())
                .map(str::to_owned);
            if let Some(v) = &value {
                if v.chars().count() > max {
                    return Err(AppError::Invalid(format!(
                        "`{name}`: longer than {max} characters"
                    )));
                }
                if v.chars().any(char::is_control) {
                    return Err(AppError::Invalid(format!(
                        "`{name}`: control characters are not allowed"
                    )));
                }
            }
            Ok(value)
        };
        let category = field("category", &self.category, MAX_FIELD)?;
        if let Some(c) = &category
            && !admin
            && !SUBMITTER_CATEGORIES.contains(&c.as_str())
        {
            return Err(AppError::Invalid(format!(
                "`category`: {c:?} is not one of {}; other categories are named by an admin",
                SUBMITTER_CATEGORIES.join(", ")
            )));
        }
        let link = field("link", &self.link, MAX_LINK)?;
        if let Some(l) = &link {
            let parsed = url::Url::parse(l)
                .map_err(|e| AppError::Invalid(format!("`link`: {l:?} is not a URL ({e})")))?;
            if !matches!(parsed.scheme(), "http" | "https") || parsed.host_str().is_none() {
                return Err(AppError::Invalid(format!(
                    "`link`: {l:?} is not an http or https URL"
                )));
            }
        }
        Ok(ModelMetadata {
            category,
            family: field("family", &self.family, MAX_FIELD)?,
            size: field("size", &self.size, MAX_FIELD)?,
            link,
        })
    }
}

fn entry(dataset: &str, stored: StoredModelMetadata) -> ModelMetadataEntry {
    ModelMetadataEntry {
        dataset: dataset.to_owned(),
        model: stored.model,
        metadata: ModelMetadata {
            category: stored.category,
            family: stored.family,
            size: stored.size,
            link: stored.link,
        },
        updated_by: stored.updated_by,
        updated_at: stored.updated_at,
    }
}

/// Sets `model`'s metadata on `dataset` (replacing what was there), audited and announced so
/// every server's leaderboard shows it. The model must have been submitted to the dataset; an
/// admin may set anyone's, an account only that of a model it submitted (403 otherwise), and
/// only the categories in [`SUBMITTER_CATEGORIES`].
pub async fn set(
    hub: &Hub,
    editor: &MetadataEditor,
    dataset: &str,
    model: &str,
    metadata: &ModelMetadata,
) -> Result<ModelMetadataEntry, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    let submitters = store::model_metadata::submitters(&mut conn, dataset.id, model).await?;
    drop(conn);
    if submitters.is_empty() {
        return Err(Refusal::NoModelSubmission {
            dataset: dataset.name,
            model: model.to_owned(),
        }
        .into());
    }
    let own = matches!(&editor.actor, Actor::Account(name) if submitters.contains(name));
    if !editor.admin && !own {
        return Err(Refusal::NotModelOwner {
            dataset: dataset.name,
            model: model.to_owned(),
        }
        .into());
    }
    let metadata = metadata.checked(editor.admin)?;
    let stored = StoredModelMetadata {
        model: model.to_owned(),
        category: metadata.category.clone(),
        family: metadata.family.clone(),
        size: metadata.size.clone(),
        link: metadata.link.clone(),
        updated_by: editor.actor.to_string(),
        updated_at: String::new(),
    };
    let mut tx = hub.write(Lane::Interactive).await?;
    store::model_metadata::put(&mut tx, dataset.id, &stored).await?;
    let shown = |v: &Option<String>| v.as_deref().unwrap_or("-").to_owned();
    audit::record(
        &mut tx,
        &editor.actor,
        AuditAction::ModelMetadata,
        format!("model {model}"),
        Some(&dataset.name),
        format!(
            "category {}, family {}, size {}, link {}",
            shown(&metadata.category),
            shown(&metadata.family),
            shown(&metadata.size),
            shown(&metadata.link)
        ),
    )
    .await?;
    tx.announce(Change::Boards).await?;
    tx.commit().await?;
    of_dataset(hub, &dataset.name)
        .await?
        .remove(model)
        .ok_or_else(|| AppError::internal("the metadata just stored is not there"))
}

/// Every model's metadata on the dataset, by model name.
pub async fn of_dataset(
    hub: &Hub,
    dataset: &str,
) -> Result<BTreeMap<String, ModelMetadataEntry>, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    let stored = store::model_metadata::of_dataset(&mut conn, dataset.id).await?;
    Ok(stored
        .into_iter()
        .map(|s| (s.model.clone(), entry(&dataset.name, s)))
        .collect())
}

/// The models submitted to the dataset (listed or not), by name: the models whose metadata
/// [`set`] takes.
pub async fn submitted(hub: &Hub, dataset: &str) -> Result<Vec<String>, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    Ok(store::model_metadata::submitted_models(&mut conn, dataset.id).await?)
}
