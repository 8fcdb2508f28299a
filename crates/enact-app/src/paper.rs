//! The paper regenerated from this hub's data: ENACT's result tables (task and pairwise accuracy
//! by direction and step length) with the hub's own rows beside the results papers published,
//! marked as the paper marks them, where every cell came from, and the reproduction check of a
//! published model the hub also scored. The tables and files are `core::paper`'s; this module
//! gathers the rows.

use std::collections::HashMap;

use crate::core::bundle::BundleFile;
use crate::core::leaderboard::{LeaderboardRow, RowSource, one_per_model};
use crate::core::paper::error_figure::AnalysedRow;
use crate::core::paper::export::{PaperBundle, StudyFigure, files as bundle_files};
use crate::core::paper::hub::{
    AssembledTable, HubRow, ItemResult, Origin, ReproducedCell, RowMetadata, assemble, reproduction,
};
use crate::core::paper::{Category, CellKey, Metric, ReportedModel};
use crate::core::verifier::{Resampling, cluster_ids};
use crate::core::version::BUILD;
use crate::store;

use super::studies::{self, StudyRowChoice};
use super::{AppError, Hub, error_analysis, leaderboard, models, reported};

/// What to put in the tables.
#[derive(Debug, Clone)]
pub struct PaperOptions {
    /// The rows, in this order (a main-text table like the paper's Table 1); every row when
    /// `None`.
    pub models: Option<Vec<String>>,
    /// The tables to make.
    pub metrics: Vec<Metric>,
    /// Print the hub rows' bootstrap intervals under their values.
    pub intervals: bool,
    /// What the intervals' bootstrap resamples: activities (the default) or items.
    pub resampling: Resampling,
}

impl Default for PaperOptions {
    fn default() -> Self {
        PaperOptions {
            models: None,
            metrics: Metric::ALL.to_vec(),
            intervals: false,
            resampling: Resampling::Activities,
        }
    }
}

/// A dataset's paper tables.
#[derive(Debug, Clone)]
pub struct Paper {
    pub dataset: String,
    pub tables: Vec<AssembledTable>,
    /// Every published model the hub also scored, cell by cell, with the hub's interval.
    pub reproduction: Vec<ReproducedCell>,
    /// The error analyses of the chosen hub rows (published rows have no per-item answers to
    /// analyse); empty when the tables have no hub row.
    pub error_analyses: Vec<AnalysedRow>,
    /// The studies whose baseline is this dataset, each reported for the Human row when it is
    /// chosen and has answers, else for the first chosen submission the study can report;
    /// a study no chosen row can report is left out.
    pub studies: Vec<StudyFigure>,
}

impl Paper {
    /// The folder's files; the reproduction check among them when `with_reproduction`.
    pub fn files(&self, with_reproduction: bool) -> Result<Vec<BundleFile>, AppError> {
        bundle_files(&PaperBundle {
            dataset: &self.dataset,
            hub_version: BUILD,
            tables: &self.tables,
            reproduction: with_reproduction.then_some(self.reproduction.as_slice()),
            error_analyses: &self.error_analyses,
            studies: &self.studies,
        })
        .map_err(|e| AppError::internal(format!("paper of '{}': {e}", self.dataset)))
    }
}

/// The metadata an admin or the submitter gave a model, as the paper's rows take it. A
/// category the core does not take (none should be stored) leaves the hub's own.
fn row_metadata(entry: Option<&models::ModelMetadataEntry>) -> RowMetadata {
    let Some(entry) = entry else {
        return RowMetadata::default();
    };
    RowMetadata {
        category: entry
            .metadata
            .category
            .as_deref()
            .and_then(|c| Category::new(c).ok()),
        family: entry.metadata.family.clone(),
        size: entry.metadata.size.clone(),
    }
}

/// The per-item results of a submission, by column: what its intervals are drawn from.
async fn column_results(
    hub: &Hub,
    submission: i64,
    activities: &HashMap<String, u32>,
) -> Result<Vec<ItemResult>, AppError> {
    let mut conn = hub.conn().await?;
    let verdicts = store::submissions::verdicts(&mut conn, submission).await?;
    Ok(verdicts
        .into_iter()
        .map(|v| ItemResult {
            column: CellKey {
                direction: v.direction,
                step_length: v.step_length,
            },
            // Every verdict is of an item of the dataset; a missing one is its own cluster.
            activity: activities.get(&v.id).copied().unwrap_or(u32::MAX),
            task_correct: v.task_accuracy,
            pairwise_accuracy: v.pairwise_accuracy,
        })
        .collect())
}

/// Each item's activity (ENACT's `task_name`) as a bootstrap cluster number, by item id.
async fn activity_clusters(
    hub: &Hub,
    dataset: &store::datasets::Dataset,
) -> Result<HashMap<String, u32>, AppError> {
    let mut conn = hub.conn().await?;
    let items = store::items::activities(&mut conn, dataset.id).await?;
    let clusters = cluster_ids(items.iter().map(|(_, activity)| activity.as_str()));
    Ok(items
        .into_iter()
        .zip(clusters)
        .map(|((id, _), cluster)| (id, cluster))
        .collect())
}

/// The hub rows the tables show: every one without `models`, else those named, in the order
/// named; the Human row last, as the tables print it.
fn chosen_rows<'a>(own: &'a [HubRow], models: Option<&[String]>) -> Vec<&'a HubRow> {
    let position = |row: &HubRow| match models {
        None => Some(0),
        Some(names) => names.iter().position(|n| *n == row.model),
    };
    let mut chosen: Vec<(bool, usize, &HubRow)> = own
        .iter()
        .filter_map(|row| position(row).map(|p| (row.category == Category::Human, p, row)))
        .collect();
    chosen.sort_by_key(|(human, p, _)| (*human, *p));
    chosen.into_iter().map(|(_, _, row)| row).collect()
}

/// The error analyses of the `chosen` hub rows, in their order. A submission's is its stored
/// analysis (computed on first request); the Human row's is of the current answers.
async fn analysed_rows(
    hub: &Hub,
    dataset: &store::datasets::Dataset,
    chosen: &[&HubRow],
) -> Result<Vec<AnalysedRow>, AppError> {
    let mut rows = Vec::with_capacity(chosen.len());
    for row in chosen {
        let analysis = match &row.origin {
            Origin::Submission { submission, .. } => {
                let mut conn = hub.conn().await?;
                let stored = store::submissions::by_id(&mut conn, *submission).await?;
                drop(conn);
                match stored {
                    Some(stored) => Some(error_analysis::submission_analysis(hub, &stored).await?),
                    None => None,
                }
            }
            Origin::Annotations { .. } => error_analysis::of_humans(hub, dataset).await?,
            Origin::Reported { .. } => None,
        };
        if let Some(analysis) = analysis {
            rows.push(AnalysedRow {
                model: row.model.clone(),
                analysis,
            });
        }
    }
    Ok(rows)
}

/// The heat map of every study whose baseline is `dataset`, for the Human row when it is among
/// the `chosen` rows and the study can report it, else for the first chosen submission's model
/// (of its account) the study can report. A study none of them can be reported for is left
/// out.
async fn study_figures(
    hub: &Hub,
    dataset: &str,
    chosen: &[&HubRow],
) -> Result<Vec<StudyFigure>, AppError> {
    let choices: Vec<StudyRowChoice> = chosen
        .iter()
        .filter(|row| matches!(row.origin, Origin::Annotations { .. }))
        .map(|_| StudyRowChoice::Human)
        .chain(chosen.iter().filter_map(|row| match &row.origin {
            Origin::Submission { account, .. } => Some(StudyRowChoice::Model {
                model: row.model.clone(),
                account: Some(account.clone()),
            }),
            _ => None,
        }))
        .collect();
    let mut figures = Vec::new();
    for study in studies::list(hub).await? {
        if study.baseline != dataset {
            continue;
        }
        for choice in &choices {
            match studies::report(hub, &study.name, choice, false).await {
                Ok(report) => {
                    figures.push(StudyFigure {
                        study: study.name.clone(),
                        report,
                    });
                    break;
                }
                // This row has no answers the study can compare: try the next.
                Err(e) if e.is_not_found() || matches!(e, AppError::Invalid(_)) => {}
                Err(e) => return Err(e),
            }
        }
    }
    Ok(figures)
}

/// The tables of the dataset named `dataset`: its published results (`reported`), every
/// model's latest published submission (the leaderboard's rows, one per account and model;
/// baselines, which the leaderboard shows for reference, are left out) and its Human row, each
/// hub row in the category its metadata names or the hub's own. Intervals are computed for
/// the rows that print them and for every model a paper also published (the reproduction
/// check says whether the published value lies inside).
pub async fn paper(hub: &Hub, dataset: &str, options: &PaperOptions) -> Result<Paper, AppError> {
    let (dataset, rows) = leaderboard::of(hub, dataset).await?;
    let metadata = models::of_dataset(hub, &dataset.name).await?;
    let published: Vec<ReportedModel> = reported::list(hub, &dataset.name)
        .await?
        .into_iter()
        .map(|r| r.reported)
        .collect();
    let rows: Vec<LeaderboardRow> = one_per_model(&rows)
        .into_iter()
        .filter(|r| r.source == RowSource::Human || !r.baseline)
        .collect();
    let mut own = Vec::with_capacity(rows.len());
    // The bootstrap's clusters, read when some row's intervals are computed.
    let activities = if options.intervals || !published.is_empty() {
        activity_clusters(hub, &dataset).await?
    } else {
        HashMap::new()
    };
    for row in &rows {
        let hub_row = HubRow::of_leaderboard(row, row_metadata(metadata.get(&row.model)), BUILD);
        let reproduced = published
            .iter()
            .any(|p| p.model.eq_ignore_ascii_case(&hub_row.model));
        let hub_row = match row.submission {
            Some(submission)
                if row.source == RowSource::Submission && (options.intervals || reproduced) =>
            {
                hub_row.with_intervals(
                    &column_results(hub, submission, &activities).await?,
                    options.resampling,
                )
            }
            _ => hub_row,
        };
        own.push(hub_row);
    }
    let tables = options
        .metrics
        .iter()
        .map(|metric| {
            assemble(
                *metric,
                &published,
                &own,
                options.models.as_deref(),
                options.intervals,
            )
            .map_err(|e| AppError::Invalid(format!("models: {e}")))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let chosen = chosen_rows(&own, options.models.as_deref());
    let error_analyses = analysed_rows(hub, &dataset, &chosen).await?;
    let studies = study_figures(hub, &dataset.name, &chosen).await?;
    Ok(Paper {
        error_analyses,
        studies,
        reproduction: reproduction(&published, &own),
        dataset: dataset.name,
        tables,
    })
}
