//! Reported results: what a paper published for a dataset's task (a model's task and pairwise
//! accuracy by direction and step length, its category, family, size and source), entered as
//! data. The ENACT paper's own results ship with the hub ([`import_paper`]); any other paper's
//! numbers come from JSON tables in the shape `paper` writes ([`import_tables`]); an admin adds
//! or removes single rows. Every write is audited and announced, so every server's leaderboard
//! shows the change; the leaderboard shows them as their own kind of row, never ranked.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::Serialize;

use super::changes::Change;
use super::refusal::Refusal;
use super::{AppError, Hub, audit, datasets};
use crate::Lane;
use crate::core::audit::{Actor, AuditAction};
use crate::core::paper::{self, Category, CellKey, Metric, PaperError, PaperTable, ReportedModel};
use crate::store;
use crate::store::db::UniqueKey;
use crate::store::reported::StoredReported;

/// The longest model name, source, category, family or size accepted, in characters.
const MAX_TEXT: usize = 300;

/// A reported result on a dataset as the API shows it; values in percent as printed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportedResult {
    /// Its id on this hub (what `DELETE /api/v1/datasets/{dataset}/reported/{reported_id}`
    /// takes).
    pub id: i64,
    pub dataset: String,
    #[serde(flatten)]
    pub reported: ReportedModel,
    /// Who entered it, as the audit log writes it.
    pub added_by: String,
    pub added_at: String,
}

// Documented field by field: schemars marks every field of a flattened `with` type required,
// where the JSON leaves out absent family, size and cells.
impl JsonSchema for ReportedResult {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "ReportedResult".into()
    }

    fn json_schema(generator: &mut schemars::SchemaGenerator) -> schemars::Schema {
        ReportedResultSchema::json_schema(generator)
    }
}

/// The shape of [`ReportedResult`] in JSON.
#[derive(JsonSchema)]
#[allow(dead_code)]
struct ReportedResultSchema {
    /// Its id on this hub (what `DELETE /api/v1/datasets/{dataset}/reported/{reported_id}`
    /// takes).
    id: i64,
    dataset: String,
    model: String,
    /// `proprietary`, `open-weight`, `human`, or any other name.
    category: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    family: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    size: Option<String>,
    /// Where the numbers were published: paper and table label, or a URL.
    source: String,
    /// Task accuracy in percent by cell (none: `{}`).
    task_accuracy: CellsSchema,
    /// Pairwise accuracy in percent, by the same cells.
    pairwise_accuracy: CellsSchema,
    /// Who entered it, as the audit log writes it.
    added_by: String,
    added_at: String,
}

/// The shape of [`ReportedModel`] in JSON, for the API's documentation (the core type has no
/// JSON Schema: its cell keys are parsed from text, `forward_3` .. `inverse_10`). Unknown fields
/// are refused, as the core type's reading refuses them.
#[derive(JsonSchema)]
#[schemars(deny_unknown_fields)]
// At least one cell, in either metric (checked again when stored).
#[schemars(extend("anyOf" = [
    {"required": ["task_accuracy"], "properties": {"task_accuracy": {"minProperties": 1}}},
    {"required": ["pairwise_accuracy"], "properties": {"pairwise_accuracy": {"minProperties": 1}}}
]))]
#[allow(dead_code)]
pub struct ReportedModelSchema {
    #[schemars(
        length(min = 1, max = 300),
        regex(
            pattern = r"^[^\u0000-\u001F\u007F-\u009F]*[^\s\u0000-\u001F\u007F-\u009F][^\u0000-\u001F\u007F-\u009F]*$"
        )
    )]
    pub model: String,
    /// `proprietary`, `open-weight`, `human`, or any other name.
    #[schemars(
        length(min = 1, max = 300),
        regex(
            pattern = r"^[^\u0000-\u001F\u007F-\u009F]*[^\s\u0000-\u001F\u007F-\u009F][^\u0000-\u001F\u007F-\u009F]*$"
        )
    )]
    pub category: String,
    #[serde(default)]
    #[schemars(
        length(min = 1, max = 300),
        regex(
            pattern = r"^[^\u0000-\u001F\u007F-\u009F]*[^\s\u0000-\u001F\u007F-\u009F][^\u0000-\u001F\u007F-\u009F]*$"
        )
    )]
    pub family: Option<String>,
    #[serde(default)]
    #[schemars(
        length(min = 1, max = 300),
        regex(
            pattern = r"^[^\u0000-\u001F\u007F-\u009F]*[^\s\u0000-\u001F\u007F-\u009F][^\u0000-\u001F\u007F-\u009F]*$"
        )
    )]
    pub size: Option<String>,
    /// Where the numbers were published: paper and table label, or a URL.
    #[schemars(
        length(min = 1, max = 300),
        regex(
            pattern = r"^[^\u0000-\u001F\u007F-\u009F]*[^\s\u0000-\u001F\u007F-\u009F][^\u0000-\u001F\u007F-\u009F]*$"
        )
    )]
    pub source: String,
    /// Task accuracy in percent by cell.
    #[serde(default)]
    pub task_accuracy: CellsSchema,
    /// Pairwise accuracy in percent, by the same cells.
    #[serde(default)]
    pub pairwise_accuracy: CellsSchema,
}

/// For the schemas only: a cell is optional in both directions (a reply leaves out cells
/// without a value), which schemars reads from these serde attributes.
#[allow(dead_code)]
fn absent(_: &f64) -> bool {
    false
}

/// The cells of a reported result in JSON, for the API's documentation: the paper's 16 columns,
/// each optional, in percent.
#[derive(Default, JsonSchema)]
#[schemars(deny_unknown_fields)]
#[allow(dead_code)]
pub struct CellsSchema {
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub forward_3: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub forward_4: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub forward_5: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub forward_6: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub forward_7: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub forward_8: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub forward_9: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub forward_10: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub inverse_3: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub inverse_4: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub inverse_5: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub inverse_6: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub inverse_7: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub inverse_8: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub inverse_9: f64,
    #[serde(default, skip_serializing_if = "absent")]
    #[schemars(range(min = 0, max = 100))]
    pub inverse_10: f64,
}

fn shown(dataset: &str, stored: StoredReported) -> ReportedResult {
    ReportedResult {
        id: stored.id,
        dataset: dataset.to_owned(),
        reported: stored.reported,
        added_by: stored.added_by,
        added_at: stored.added_at,
    }
}

/// What an import did.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, JsonSchema)]
pub struct ReportedImport {
    pub dataset: String,
    /// Rows stored.
    pub stored: usize,
    /// Of them, rows that replaced one of the same model and source.
    pub replaced: usize,
}

/// The dataset's reported results, in the order they were entered. What the leaderboard and
/// the paper's tables show beside the hub's own rows.
pub async fn list(hub: &Hub, dataset: &str) -> Result<Vec<ReportedResult>, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    let stored = store::reported::of_dataset(&mut conn, dataset.id).await?;
    Ok(stored
        .into_iter()
        .map(|s| shown(&dataset.name, s))
        .collect())
}

/// Attaches the ENACT paper's published results (every model of its appendix tables and the
/// Human row) to the dataset, replacing rows of the same model and source; see [`import`].
pub async fn import_paper(
    hub: &Hub,
    actor: &Actor,
    dataset: &str,
) -> Result<ReportedImport, AppError> {
    import(
        hub,
        actor,
        dataset,
        paper::enact_paper_results(),
        "the ENACT paper",
    )
    .await
}

/// Reads tables of another paper's numbers (`(file name, text)`, each in the JSON shape
/// `paper` writes, one metric per table) and merges them by model: the task- and
/// pairwise-accuracy tables of a model become one reported result. Refuses the whole input,
/// naming the file, row and field, when a table does not read, a model is in two tables of the
/// same metric, or its category, source, family or size differ between tables.
pub fn merge_tables(files: &[(String, String)]) -> Result<Vec<ReportedModel>, AppError> {
    let mut merged: Vec<ReportedModel> = Vec::new();
    // Where each model's entry came from, per metric: (file, row).
    let mut seen: BTreeMap<(String, Metric), (String, usize)> = BTreeMap::new();
    for (file, text) in files {
        let table = PaperTable::from_json(text).map_err(|e| match e {
            PaperError::Table(m) => AppError::Invalid(format!("{file}: {m}")),
            row @ PaperError::Row { .. } => AppError::Invalid(format!("{file}: {row}")),
        })?;
        for (i, row) in table.rows.into_iter().enumerate() {
            let at = format!("{file}: row {} ({})", i + 1, row.model);
            if let Some((first, first_row)) =
                seen.insert((row.model.clone(), table.metric), (file.clone(), i + 1))
            {
                return Err(AppError::Invalid(format!(
                    "{at}: model: also in row {first_row} of {first}, a {} table too",
                    table.metric.as_str()
                )));
            }
            let values: BTreeMap<CellKey, f64> = row
                .cells
                .iter()
                .filter_map(|(key, cell)| cell.value.map(|v| (*key, v)))
                .collect();
            let entry = match merged.iter_mut().find(|m| m.model == row.model) {
                Some(entry) => {
                    let differs = |field: &str, ours: &str, theirs: &str| {
                        AppError::Invalid(format!(
                            "{at}: {field}: {theirs:?} differs from {ours:?} given for this \
                             model in another table"
                        ))
                    };
                    if entry.category != row.category {
                        return Err(differs(
                            "category",
                            entry.category.as_str(),
                            row.category.as_str(),
                        ));
                    }
                    if entry.source != row.source {
                        return Err(differs("source", &entry.source, &row.source));
                    }
                    for (field, ours, theirs) in [
                        ("family", &mut entry.family, row.family),
                        ("size", &mut entry.size, row.size),
                    ] {
                        match (ours.as_deref(), theirs) {
                            (Some(a), Some(b)) if a != b => return Err(differs(field, a, &b)),
                            (None, Some(b)) => *ours = Some(b),
                            _ => {}
                        }
                    }
                    entry
                }
                None => {
                    merged.push(ReportedModel {
                        model: row.model,
                        category: row.category,
                        family: row.family,
                        size: row.size,
                        source: row.source,
                        task_accuracy: BTreeMap::new(),
                        pairwise_accuracy: BTreeMap::new(),
                    });
                    merged
                        .last_mut()
                        .ok_or_else(|| AppError::internal("just pushed"))?
                }
            };
            match table.metric {
                Metric::TaskAccuracy => entry.task_accuracy = values,
                Metric::PairwiseAccuracy => entry.pairwise_accuracy = values,
            }
        }
    }
    if merged.is_empty() {
        return Err(AppError::Invalid(
            "the tables hold no rows; nothing to import".to_owned(),
        ));
    }
    Ok(merged)
}

/// Imports other papers' tables (see [`merge_tables`]) into the dataset; see [`import`].
pub async fn import_tables(
    hub: &Hub,
    actor: &Actor,
    dataset: &str,
    files: &[(String, String)],
) -> Result<ReportedImport, AppError> {
    let models = merge_tables(files)?;
    let names: Vec<&str> = files.iter().map(|(name, _)| name.as_str()).collect();
    import(hub, actor, dataset, models, &names.join(", ")).await
}

/// Stores `models` on the dataset in one transaction with one audit entry and the leaderboard's
/// change announcement: all of them or none. A row of the same model and source is replaced.
async fn import(
    hub: &Hub,
    actor: &Actor,
    dataset: &str,
    models: Vec<ReportedModel>,
    from: &str,
) -> Result<ReportedImport, AppError> {
    for (i, model) in models.iter().enumerate() {
        check(model).map_err(|m| {
            AppError::Invalid(format!("{from}: row {} ({}): {m}", i + 1, model.model))
        })?;
    }
    let dataset = datasets::by_name(hub, dataset).await?;
    let added_by = actor.to_string();
    let mut tx = hub.write(Lane::Interactive).await?;
    let mut replaced = 0;
    for model in &models {
        if store::reported::delete_by_key(&mut tx, dataset.id, &model.model, &model.source).await? {
            replaced += 1;
        }
        store::reported::insert(&mut tx, dataset.id, model, &added_by).await?;
    }
    audit::record(
        &mut tx,
        actor,
        AuditAction::ReportedAdd,
        format!("reported results from {from}"),
        Some(&dataset.name),
        format!(
            "{} reported rows ({replaced} replacing rows of the same model and source)",
            models.len()
        ),
    )
    .await?;
    tx.announce(Change::Boards).await?;
    tx.commit().await?;
    Ok(ReportedImport {
        dataset: dataset.name,
        stored: models.len(),
        replaced,
    })
}

/// Adds one reported result to the dataset, audited and announced. Refuses (409) a second row
/// of the same model and source.
pub async fn add(
    hub: &Hub,
    actor: &Actor,
    dataset: &str,
    reported: &ReportedModel,
) -> Result<ReportedResult, AppError> {
    check(reported).map_err(AppError::Invalid)?;
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut tx = hub.write(Lane::Interactive).await?;
    let id = match store::reported::insert(&mut tx, dataset.id, reported, &actor.to_string()).await
    {
        Ok(id) => id,
        Err(e) if UniqueKey::REPORTED_MODEL_SOURCE.is_violated_by(&e) => {
            return Err(AppError::Conflict(format!(
                "dataset '{}' already has a reported row of model '{}' from '{}'",
                dataset.name, reported.model, reported.source
            )));
        }
        Err(e) => return Err(e.into()),
    };
    audit::record(
        &mut tx,
        actor,
        AuditAction::ReportedAdd,
        format!("reported result {id} ({})", reported.model),
        Some(&dataset.name),
        format!("from {}", reported.source),
    )
    .await?;
    tx.announce(Change::Boards).await?;
    tx.commit().await?;
    list(hub, &dataset.name)
        .await?
        .into_iter()
        .find(|r| r.id == id)
        .ok_or_else(|| AppError::internal("the reported result just stored is not there"))
}

/// Removes the dataset's reported result `id`, audited and announced; 404 when it has none.
pub async fn remove(hub: &Hub, actor: &Actor, dataset: &str, id: i64) -> Result<(), AppError> {
    let rows = list(hub, dataset).await?;
    let Some(row) = rows.into_iter().find(|r| r.id == id) else {
        return Err(Refusal::NoReported {
            dataset: dataset.to_owned(),
            reported: id.to_string(),
        }
        .into());
    };
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut tx = hub.write(Lane::Interactive).await?;
    if !store::reported::delete(&mut tx, dataset.id, id).await? {
        tx.rollback().await?;
        return Err(Refusal::NoReported {
            dataset: dataset.name.clone(),
            reported: id.to_string(),
        }
        .into());
    }
    audit::record(
        &mut tx,
        actor,
        AuditAction::ReportedRemove,
        format!("reported result {id} ({})", row.reported.model),
        Some(&dataset.name),
        format!("from {}", row.reported.source),
    )
    .await?;
    tx.announce(Change::Boards).await?;
    tx.commit().await?;
    Ok(())
}

/// What is wrong with a reported result, by field: blank or overlong text, values that are not
/// percentages.
fn check(reported: &ReportedModel) -> Result<(), String> {
    let text = |field: &str, value: &str| {
        if value.trim().is_empty() {
            Err(format!("{field}: must not be blank"))
        } else if value.chars().count() > MAX_TEXT {
            Err(format!("{field}: longer than {MAX_TEXT} characters"))
        } else if value.chars().any(char::is_control) {
            Err(format!("{field}: control characters are not allowed"))
        } else {
            Ok(())
        }
    };
    text("model", &reported.model)?;
    text("source", &reported.source)?;
    if let Category::Named(name) = &reported.category {
        text("category", name)?;
    }
    for (field, value) in [("family", &reported.family), ("size", &reported.size)] {
        if let Some(v) = value {
            text(field, v)?;
        }
    }
    for metric in Metric::ALL {
        for (key, value) in reported.values(metric) {
            if !(0.0..=100.0).contains(value) {
                return Err(format!(
                    "{}.{key}: {value} is not a percentage (0..100)",
                    metric.as_str()
                ));
            }
        }
    }
    if reported.task_accuracy.is_empty() && reported.pairwise_accuracy.is_empty() {
        return Err("task_accuracy, pairwise_accuracy: no values".to_owned());
    }
    Ok(())
}
