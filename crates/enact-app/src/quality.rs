//! Per-annotator quality on a dataset: everything each annotator finished, gold items
//! included, turned into the figures of [`crate::core::quality`] for the admin page, the API
//! and the command line; and each annotator's attention checks ([`super::attention`]),
//! counted apart (their answers are no answers to the scene, so they stay out of the figures).

use schemars::JsonSchema;
use serde::Serialize;

use super::attention::AnnotatorChecks;
use super::{AppError, Hub, datasets};
use crate::core::quality::{self, AnnotatorQuality, AnnotatorWork};
use crate::store;
use crate::store::gold::Exclusion;

/// The quality figures of every annotator who finished an item of a dataset (or is excluded
/// from it), by name.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct QualityReport {
    pub dataset: String,
    /// The bar of each annotator's `fast_share`, in seconds.
    pub fast_seconds: f64,
    /// The dataset's gold items (0 without a gold set).
    pub gold_items: i64,
    pub annotators: Vec<AnnotatorQuality>,
    /// Who is excluded from the Human row and the agreement report, by whom and when.
    pub exclusions: Vec<ExclusionView>,
    /// The dataset's attention checks (0 without any).
    pub attention_checks: i64,
    /// Every annotator with an attention check of the dataset in their queue, by name: how
    /// many they passed, failed (another answer, a skip or a flag) and have still to do.
    pub attention: Vec<AnnotatorChecks>,
}

/// An annotator excluded from a dataset's Human row.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ExclusionView {
    pub annotator: String,
    pub excluded_by: String,
    pub excluded_at: String,
}

impl From<Exclusion> for ExclusionView {
    fn from(e: Exclusion) -> ExclusionView {
        ExclusionView {
            annotator: e.annotator,
            excluded_by: e.excluded_by,
            excluded_at: e.excluded_at,
        }
    }
}

/// Checks the fast-answer bar an admin chose.
pub fn fast_seconds(value: Option<f64>) -> Result<f64, AppError> {
    match value {
        None => Ok(quality::DEFAULT_FAST_SECONDS),
        Some(s) if s.is_finite() && s > 0.0 && s <= 3600.0 => Ok(s),
        Some(s) => Err(AppError::Invalid(format!(
            "fast_seconds {s}: give a number of seconds above 0 and at most 3600"
        ))),
    }
}

/// Every annotator's figures on `dataset`; items answered in under `fast_seconds` count as
/// fast. Answers without a stored verdict are judged here, as the Human row judges them.
pub async fn report(
    hub: &Hub,
    dataset: &str,
    fast_seconds: f64,
) -> Result<QualityReport, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    let rows = store::annotations::quality_rows(&mut conn, dataset.id).await?;
    let exclusions = store::gold::exclusions(&mut conn, dataset.id).await?;
    let gold_items = store::gold::gold_count(&mut conn, dataset.id).await?;
    let attention_checks = store::attention::attention_count(&mut conn, dataset.id).await?;
    let attention = super::attention::tallies(&mut conn, dataset.id).await?;
    drop(conn);
    let mut work: Vec<AnnotatorWork> = Vec::new();
    for row in rows {
        if work.last().is_none_or(|w| w.name != row.name) {
            work.push(AnnotatorWork {
                name: row.name.clone(),
                excluded: exclusions.iter().any(|e| e.annotator == row.name),
                items: Vec::new(),
            });
        }
        if let Some(annotator) = work.last_mut() {
            annotator.items.push(row.finished);
        }
    }
    for e in &exclusions {
        if !work.iter().any(|w| w.name == e.annotator) {
            work.push(AnnotatorWork {
                name: e.annotator.clone(),
                excluded: true,
                items: Vec::new(),
            });
        }
    }
    work.sort_by(|a, b| a.name.cmp(&b.name));
    // Judging answers without a stored verdict and the pairwise alphas are CPU work.
    let annotators = hub
        .heavy()
        .run(move || quality::annotator_quality(&work, fast_seconds))
        .await?
        .map_err(|e| {
            AppError::internal(format!(
                "dataset '{}': stored annotations: {e}",
                dataset.name
            ))
        })?;
    Ok(QualityReport {
        dataset: dataset.name,
        fast_seconds,
        gold_items,
        annotators,
        exclusions: exclusions.into_iter().map(ExclusionView::from).collect(),
        attention_checks,
        attention,
    })
}
