//! Ablation studies as use cases: create one (an admin; audited), list, show with how the items
//! align, delete (audited), and the study report for a model or the Human row.
//!
//! Items are aligned whenever a study is shown or reported, so a study reads its datasets as
//! they are now; creating one refuses a variant none of whose items aligns.

use std::collections::HashMap;

use schemars::JsonSchema;
use serde::Serialize;

use super::refusal::Refusal;
use super::{AppError, Hub, agreement, audit, datasets, error_analysis};
use crate::Lane;
use crate::core::annotation::{human_entries, mean_by_item};
use crate::core::audit::{Actor, AuditAction};
use crate::core::bundle::BundleFile;
use crate::core::error_analysis::ErrorAnalysis;
use crate::core::metric::METRIC_VERSION;
use crate::core::study::export::study_files;
use crate::core::study::report::{
    DatasetRef, ItemScore, RowScores, StudyInputs, StudyReport, VariantInput, build_study_report,
};
use crate::core::study::{AlignKey, Alignment, VariantSpec, align, check_variants, study_name};
use crate::store;
use crate::store::datasets::Dataset;
use crate::store::db::UniqueKey;
use crate::store::studies::StudyRow;

/// A variant as shown: its spec and, when computed, how its items align with the baseline's.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct VariantView {
    #[serde(flatten)]
    pub spec: VariantSpec,
    /// Pairs of items (by id, or by task, type and key frames).
    pub aligned: Option<usize>,
    pub alignment: Option<Alignment>,
}

/// A study as shown.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct StudyView {
    pub name: String,
    pub baseline: String,
    pub baseline_items: Option<usize>,
    pub created_at: String,
    pub created_by: String,
    pub variants: Vec<VariantView>,
}

impl StudyView {
    fn of_row(row: &StudyRow) -> StudyView {
        StudyView {
            name: row.name.clone(),
            baseline: row.baseline.clone(),
            baseline_items: None,
            created_at: row.created_at.clone(),
            created_by: row.created_by.clone(),
            variants: row
                .variants
                .iter()
                .map(|(spec, _)| VariantView {
                    spec: spec.clone(),
                    aligned: None,
                    alignment: None,
                })
                .collect(),
        }
    }
}

/// Whose answers a report compares.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StudyRowChoice {
    /// The latest published submission of this model on each dataset; `account` picks among
    /// accounts that publish a model of the same name.
    Model {
        model: String,
        account: Option<String>,
    },
    /// The annotators' answers (each item's mean over its answers).
    Human,
}

async fn keys(hub: &Hub, dataset: i64) -> Result<Vec<AlignKey>, AppError> {
    let mut conn = hub.conn().await?;
    let items = store::items::scoring_items(&mut conn, dataset).await?;
    Ok(items.into_iter().map(AlignKey::of_stored).collect())
}

/// Each variant's alignment with the baseline, in the study's order.
async fn alignments(
    hub: &Hub,
    baseline: i64,
    variants: &[(VariantSpec, i64)],
) -> Result<(Vec<AlignKey>, Vec<(Vec<AlignKey>, Alignment)>), AppError> {
    let baseline_keys = keys(hub, baseline).await?;
    let mut out = Vec::with_capacity(variants.len());
    for (_, dataset) in variants {
        let variant_keys = keys(hub, *dataset).await?;
        let alignment = align(&baseline_keys, &variant_keys);
        out.push((variant_keys, alignment));
    }
    Ok((baseline_keys, out))
}

/// The dataset named `name`, or `missing` when there is none.
async fn dataset_named(hub: &Hub, name: &str, missing: Refusal) -> Result<Dataset, AppError> {
    match datasets::by_name(hub, name).await {
        Err(e) if e.is_not_found() => Err(AppError::Refused(missing)),
        other => other,
    }
}

/// Creates a study: checks the name and the variants, finds the datasets, and refuses a
/// variant with no item aligned with the baseline's. One transaction with its audit entry.
pub async fn create(
    hub: &Hub,
    actor: &Actor,
    name: &str,
    baseline: &str,
    variants: &[VariantSpec],
) -> Result<StudyView, AppError> {
    let name = study_name(name).map_err(AppError::Invalid)?;
    let baseline = baseline.trim();
    check_variants(baseline, variants).map_err(AppError::Invalid)?;
    let missing = Refusal::StudyBaselineMissing {
        dataset: baseline.to_owned(),
    };
    let base = dataset_named(hub, baseline, missing).await?;
    let mut resolved = Vec::with_capacity(variants.len());
    for spec in variants {
        let missing = Refusal::StudyVariantMissing {
            variant: format!("{}/{}", spec.family, spec.label),
            dataset: spec.dataset.clone(),
        };
        let dataset = dataset_named(hub, &spec.dataset, missing).await?;
        resolved.push((spec.clone(), dataset.id));
    }
    let (baseline_keys, aligned) = alignments(hub, base.id, &resolved).await?;
    for ((spec, _), (variant_keys, alignment)) in resolved.iter().zip(&aligned) {
        if alignment.aligned() == 0 {
            return Err(AppError::Refused(Refusal::StudyVariantUnaligned {
                variant: format!("{}/{}", spec.family, spec.label),
                dataset: spec.dataset.clone(),
                items: variant_keys.len() as u64,
                baseline: base.name.clone(),
                baseline_items: baseline_keys.len() as u64,
            }));
        }
    }
    let mut tx = hub.write(Lane::Interactive).await?;
    match store::studies::insert(&mut tx, name, base.id, actor.name(), &resolved).await {
        Ok(_) => {}
        Err(e) if UniqueKey::STUDY_NAME.is_violated_by(&e) => {
            return Err(AppError::Refused(Refusal::StudyExists {
                study: name.to_owned(),
            }));
        }
        Err(e) => return Err(e.into()),
    }
    let detail = resolved
        .iter()
        .zip(&aligned)
        .map(|((spec, _), (_, a))| {
            format!(
                "{}/{}={} ({} aligned)",
                spec.family,
                spec.label,
                spec.dataset,
                a.aligned()
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    audit::record(
        &mut tx,
        actor,
        AuditAction::StudyCreate,
        format!("study {name}"),
        Some(&base.name),
        format!("baseline {}; {detail}", base.name),
    )
    .await?;
    tx.commit().await?;
    tracing::info!(study = name, by = actor.name(), "study created");
    show(hub, name).await
}

async fn row_named(hub: &Hub, name: &str) -> Result<StudyRow, AppError> {
    let mut conn = hub.conn().await?;
    store::studies::by_name(&mut conn, name.trim())
        .await?
        .ok_or_else(|| {
            AppError::from(Refusal::NoStudy {
                study: name.trim().to_owned(),
            })
        })
}

/// Every study, by name (alignments are computed only for one study at a time: [`show`]).
pub async fn list(hub: &Hub) -> Result<Vec<StudyView>, AppError> {
    let mut conn = hub.conn().await?;
    let rows = store::studies::list(&mut conn).await?;
    Ok(rows.iter().map(StudyView::of_row).collect())
}

/// One study, without computing alignments (a report computes them itself).
pub async fn get(hub: &Hub, name: &str) -> Result<StudyView, AppError> {
    Ok(StudyView::of_row(&row_named(hub, name).await?))
}

/// One study with each variant's alignment.
pub async fn show(hub: &Hub, name: &str) -> Result<StudyView, AppError> {
    let row = row_named(hub, name).await?;
    let (baseline_keys, aligned) = alignments(hub, row.baseline_id, &row.variants).await?;
    let mut view = StudyView::of_row(&row);
    view.baseline_items = Some(baseline_keys.len());
    for (variant, (_, alignment)) in view.variants.iter_mut().zip(aligned) {
        variant.aligned = Some(alignment.aligned());
        variant.alignment = Some(alignment);
    }
    Ok(view)
}

/// Deletes a study (the datasets and submissions stay). Audited.
pub async fn delete(hub: &Hub, actor: &Actor, name: &str) -> Result<(), AppError> {
    let row = row_named(hub, name).await?;
    let mut tx = hub.write(Lane::Interactive).await?;
    if !store::studies::delete(&mut tx, &row.name).await? {
        return Err(Refusal::NoStudy { study: row.name }.into());
    }
    audit::record(
        &mut tx,
        actor,
        AuditAction::StudyDelete,
        format!("study {}", row.name),
        Some(&row.baseline),
        String::new(),
    )
    .await?;
    tx.commit().await?;
    Ok(())
}

/// The models with a published submission on a study's baseline, for pickers.
pub async fn models(hub: &Hub, name: &str) -> Result<Vec<String>, AppError> {
    let row = row_named(hub, name).await?;
    let mut conn = hub.conn().await?;
    let mut models: Vec<String> = store::submissions::published(&mut conn, row.baseline_id)
        .await?
        .into_iter()
        .map(|s| s.model)
        .collect();
    models.sort();
    models.dedup();
    Ok(models)
}

fn hands_of(analysis: &ErrorAnalysis) -> [crate::core::error_analysis::Handedness; 2] {
    [
        analysis.by_direction.forward.handedness.clone(),
        analysis.by_direction.inverse.handedness.clone(),
    ]
}

/// The chosen row's scores on `dataset`, or why it has none there.
async fn row_scores(
    hub: &Hub,
    dataset: &Dataset,
    choice: &StudyRowChoice,
) -> Result<Result<RowScores, String>, AppError> {
    match choice {
        StudyRowChoice::Human => {
            let mut conn = hub.conn().await?;
            let answers = store::annotations::human_answers(&mut conn, dataset.id).await?;
            drop(conn);
            if answers.is_empty() {
                return Ok(Err(format!(
                    "no annotator has answered an item of dataset '{}'",
                    dataset.name
                )));
            }
            let entries = human_entries(&answers).map_err(|e| {
                AppError::internal(format!(
                    "dataset '{}': stored annotations: {e}",
                    dataset.name
                ))
            })?;
            let task = mean_by_item(
                answers.iter().zip(
                    entries
                        .iter()
                        .map(|e| Some(if e.task_accuracy { 1.0 } else { 0.0 })),
                ),
            );
            let items = mean_by_item(
                answers
                    .iter()
                    .zip(entries.iter().map(|e| e.pairwise_accuracy)),
            )
            .into_iter()
            .map(|(id, (direction, step_length, value))| {
                let task_accuracy = task.get(&id).map(|(_, _, t)| *t);
                (
                    id,
                    ItemScore {
                        direction,
                        step_length,
                        task_accuracy,
                        pairwise_accuracy: Some(value),
                    },
                )
            })
            .collect();
            let hands = error_analysis::of_humans(hub, dataset)
                .await?
                .as_ref()
                .map(hands_of);
            Ok(Ok(RowScores {
                submission: None,
                items,
                hands,
                // Judged just now.
                metric_version: METRIC_VERSION,
            }))
        }
        StudyRowChoice::Model { model, account } => {
            let mut conn = hub.conn().await?;
            let published = store::submissions::published(&mut conn, dataset.id).await?;
            drop(conn);
            // Oldest first: the last of each account is its entry, as on the leaderboard.
            let mut latest: HashMap<&str, &store::submissions::SubmissionRow> = HashMap::new();
            for s in published.iter().filter(|s| &s.model == model) {
                if account.as_ref().is_none_or(|a| a == &s.account) {
                    latest.insert(&s.account, s);
                }
            }
            let who = account
                .as_ref()
                .map_or_else(String::new, |a| format!(" from account '{a}'"));
            let entry = match latest.len() {
                0 => {
                    return Ok(Err(format!(
                        "no published submission of model '{model}'{who} on dataset '{}'",
                        dataset.name
                    )));
                }
                1 => *latest.values().next().expect("one entry"),
                _ => {
                    let mut accounts: Vec<&str> = latest.keys().copied().collect();
                    accounts.sort_unstable();
                    return Err(AppError::Invalid(format!(
                        "model '{model}' is published on dataset '{}' by {} accounts ({}); \
                         choose one with `account`",
                        dataset.name,
                        accounts.len(),
                        accounts.join(", ")
                    )));
                }
            };
            let mut conn = hub.conn().await?;
            let verdicts = store::submissions::verdicts(&mut conn, entry.id).await?;
            drop(conn);
            let items = verdicts
                .into_iter()
                .map(|v| {
                    (
                        v.id,
                        ItemScore {
                            direction: v.direction,
                            step_length: v.step_length,
                            task_accuracy: Some(if v.task_accuracy { 1.0 } else { 0.0 }),
                            pairwise_accuracy: v.pairwise_accuracy,
                        },
                    )
                })
                .collect();
            let analysis = error_analysis::submission_analysis(hub, entry).await?;
            Ok(Ok(RowScores {
                submission: Some(entry.id),
                items,
                hands: Some(hands_of(&analysis)),
                metric_version: entry.metric_version,
            }))
        }
    }
}

/// The study report of `choice`: every variant against the baseline, per direction (and per
/// step length when `by_step_length`).
pub async fn report(
    hub: &Hub,
    name: &str,
    choice: &StudyRowChoice,
    by_step_length: bool,
) -> Result<StudyReport, AppError> {
    let row = row_named(hub, name).await?;
    let base = datasets::by_name(hub, &row.baseline).await?;
    let baseline_row = row_scores(hub, &base, choice).await?.map_err(|why| {
        AppError::NotFound(format!(
            "study '{}': {why}, its baseline; nothing to compare with",
            row.name
        ))
    })?;
    let (baseline_keys, aligned) = alignments(hub, row.baseline_id, &row.variants).await?;
    let mut variants = Vec::with_capacity(row.variants.len());
    for ((spec, _), (variant_keys, alignment)) in row.variants.iter().zip(aligned) {
        let dataset = datasets::by_name(hub, &spec.dataset).await?;
        let (dataset_hash, _) = agreement::dataset_hash(hub, &dataset).await?;
        let pairs = alignment
            .pairs
            .iter()
            .map(|&(b, v)| {
                (
                    baseline_keys[b].item_id.clone(),
                    variant_keys[v].item_id.clone(),
                )
            })
            .collect();
        variants.push(VariantInput {
            spec: spec.clone(),
            dataset_hash,
            alignment,
            pairs,
            row: row_scores(hub, &dataset, choice).await?,
        });
    }
    let (baseline_hash, _) = agreement::dataset_hash(hub, &base).await?;
    let (row_label, model, account) = match choice {
        StudyRowChoice::Human => ("Human".to_owned(), None, None),
        StudyRowChoice::Model { model, account } => (
            match account {
                Some(a) => format!("{model} ({a})"),
                None => model.clone(),
            },
            Some(model.clone()),
            account.clone(),
        ),
    };
    let inputs = StudyInputs {
        study: row.name.clone(),
        row_label,
        model,
        account,
        baseline: DatasetRef {
            name: base.name.clone(),
            hash: baseline_hash,
        },
        baseline_row,
        variants,
        by_step_length,
    };
    hub.heavy()
        .run(move || build_study_report(&inputs))
        .await?
        .map_err(|e| AppError::internal(format!("study '{}': {e}", row.name)))
}

/// The report's files (`core::study::export`).
pub fn files(report: &StudyReport) -> Result<Vec<BundleFile>, AppError> {
    study_files(report)
        .map_err(|e| AppError::internal(format!("study '{}': {e}", report.stamp.study)))
}
