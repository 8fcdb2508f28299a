//! Error analysis as a use case: of one submission (its owner or an admin), of the Human row,
//! of a prediction file against a dataset (the CLI), and of every published row of a dataset
//! side by side. `core::error_analysis` does the counting; this module finds the answers,
//! keeps a submission's result, and withholds examples where the truth is hidden.
//!
//! A submission's analysis is computed on first request and stored with it (its answers never
//! change); the Human row's is computed on each request from the current answers.

use std::collections::HashMap;

use super::refusal::Refusal;
use super::scoring::{self, ScoreFileError, ScoringStep};
use super::submissions::{self, DatasetTargets};
use super::tokens::Caller;
use super::{AppError, Hub, datasets, leaderboard};
use crate::Lane;
use crate::core::annotation::human_error_analysis;
use crate::core::dataset::AnswerVisibility;
use crate::core::error_analysis::{
    ANALYSIS_VERSION, AnsweredItem, ErrorAnalysis, Reading, analyse, analyse_strict,
};
use crate::core::leaderboard::RowSource;
use crate::core::scoring::ScoringTarget;
use crate::core::submission::VerdictOutcome;
use crate::core::verifier::{
    Permutation, StrictParseFailure, parse_answer_strict, parse_python_json, python_text_lines,
    score_strict_predictions,
};
use crate::store;
use crate::store::datasets::Dataset;
use crate::store::submissions::{StoredVerdict, SubmissionRow};

/// Why examples are left out of an analysis, for the reader.
pub fn examples_withheld(dataset: &str) -> String {
    format!(
        "examples are not shown: the answers of dataset '{dataset}' are hidden, so only \
         aggregate figures are"
    )
}

/// An analysis and what its reader may not see of it.
#[derive(Debug, Clone)]
pub struct Analysed {
    pub analysis: ErrorAnalysis,
    /// Set when examples were removed, saying why.
    pub withheld: Option<String>,
}

impl Analysed {
    fn shown(mut analysis: ErrorAnalysis, dataset: &str, examples: bool) -> Analysed {
        let withheld = (!examples).then(|| {
            analysis.examples.clear();
            examples_withheld(dataset)
        });
        Analysed { analysis, withheld }
    }
}

/// What the strict reader made of a stored answer: the stored permutation, or the raw answer
/// read again for why it was refused (a wrong length is told apart from other refusals).
fn stored_reading(
    verdict: &StoredVerdict,
    actions: usize,
) -> Result<(Option<Permutation>, Reading<'static>), String> {
    let corrupt = |what: &str, e: &dyn std::fmt::Display| {
        format!("item {}: stored {what} is unreadable: {e}", verdict.id)
    };
    match verdict.outcome {
        VerdictOutcome::Scored => {
            let text = verdict.permutation.as_deref().unwrap_or_default();
            let p: Permutation =
                serde_json::from_str(text).map_err(|e| corrupt("permutation", &e))?;
            Ok((Some(p), Reading::Missing))
        }
        VerdictOutcome::Missing => Ok((None, Reading::Missing)),
        VerdictOutcome::Unparseable => {
            let raw = verdict.raw_answer.as_deref().unwrap_or("null");
            let value = parse_python_json(raw).map_err(|e| corrupt("answer", &e))?;
            Ok(match parse_answer_strict(Some(&value), actions) {
                Err(StrictParseFailure::WrongLength { .. }) => (None, Reading::WrongLength),
                _ => (None, Reading::Unreadable),
            })
        }
    }
}

/// Analyses stored verdicts, in the dataset's order. Blocking.
fn analyse_verdicts(
    targets: &DatasetTargets,
    verdicts: &[StoredVerdict],
) -> Result<ErrorAnalysis, String> {
    let by_id: HashMap<&str, &StoredVerdict> =
        verdicts.iter().map(|v| (v.id.as_str(), v)).collect();
    let mut readings = Vec::with_capacity(targets.targets.len());
    for target in &targets.targets {
        let reading = match by_id.get(target.id.as_str()) {
            None => (None, Reading::Missing, false),
            Some(v) => {
                let (answer, reading) = stored_reading(v, target.ground_truth.len())?;
                (answer, reading, v.task_accuracy)
            }
        };
        readings.push(reading);
    }
    Ok(analyse(targets.targets.iter().zip(&readings).map(
        |(target, (answer, reading, task_accuracy))| AnsweredItem {
            item: target.strict_item(),
            reading: match answer {
                Some(answer) => Reading::Answer {
                    answer,
                    task_accuracy: *task_accuracy,
                },
                None => *reading,
            },
        },
    )))
}

/// A submission's analysis, from the stored result when it is of this version.
pub(crate) async fn submission_analysis(
    hub: &Hub,
    row: &SubmissionRow,
) -> Result<ErrorAnalysis, AppError> {
    let mut conn = hub.conn().await?;
    if let Some(json) = store::submissions::error_analysis(&mut conn, row.id).await?
        && let Ok(stored) = serde_json::from_str::<ErrorAnalysis>(&json)
        && stored.version == ANALYSIS_VERSION
    {
        return Ok(stored);
    }
    let verdicts = store::submissions::verdicts(&mut conn, row.id).await?;
    drop(conn);
    let targets = submissions::dataset_targets(hub, row.dataset_id).await?;
    let analysis = hub
        .heavy()
        .run(move || analyse_verdicts(&targets, &verdicts))
        .await?
        .map_err(|e| AppError::internal(format!("submission {}: {e}", row.id)))?;
    let json = serde_json::to_string(&analysis).map_err(AppError::internal)?;
    // Kept for the next reader; in the bulk lane, as it is work the request did not ask to store.
    let mut tx = hub.write(Lane::Bulk).await?;
    store::submissions::set_error_analysis(&mut tx, row.id, &json).await?;
    tx.commit().await?;
    Ok(analysis)
}

/// The analysis of a submission for its owner or an admin (others are told it does not
/// exist). Examples only when the dataset's answers are public.
pub async fn of_submission(
    hub: &Hub,
    caller: &Caller,
    id: &str,
) -> Result<(SubmissionRow, Analysed), AppError> {
    let row = submissions::readable(hub, caller, id).await?;
    let analysis = submission_analysis(hub, &row).await?;
    let mut conn = hub.conn().await?;
    let visibility = store::submissions::answer_visibility(&mut conn, row.dataset_id).await?;
    let shown = Analysed::shown(
        analysis,
        &row.dataset,
        visibility == AnswerVisibility::Public,
    );
    Ok((row, shown))
}

/// The analysis of every answer annotators gave on a dataset, `None` before the first one.
pub async fn of_humans(hub: &Hub, dataset: &Dataset) -> Result<Option<ErrorAnalysis>, AppError> {
    humans(hub, dataset, None).await
}

/// The analysis of one annotator's answers on the dataset named `dataset` (the command line;
/// pages show annotators pooled), `None` before their first answer.
pub async fn of_annotator(
    hub: &Hub,
    dataset: &str,
    annotator: &str,
) -> Result<Option<ErrorAnalysis>, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    let id = store::annotations::annotators(&mut conn)
        .await?
        .into_iter()
        .find(|a| a.name == annotator)
        .map(|a| a.id)
        .ok_or_else(|| {
            AppError::from(Refusal::NoAnnotator {
                annotator: annotator.to_owned(),
            })
        })?;
    drop(conn);
    humans(hub, &dataset, Some(id)).await
}

async fn humans(
    hub: &Hub,
    dataset: &Dataset,
    annotator: Option<i64>,
) -> Result<Option<ErrorAnalysis>, AppError> {
    let mut conn = hub.conn().await?;
    let answers = store::annotations::human_answers_of(&mut conn, dataset.id, annotator).await?;
    drop(conn);
    if answers.is_empty() {
        return Ok(None);
    }
    let name = dataset.name.clone();
    hub.heavy()
        .run(move || human_error_analysis(&answers))
        .await?
        .map(Some)
        .map_err(|e| AppError::internal(format!("dataset '{name}': stored annotations: {e}")))
}

/// One row of the comparison: a published submission or the Human row.
#[derive(Debug, Clone)]
pub struct ComparedRow {
    /// The submission id; `None` for the Human row.
    pub submission: Option<i64>,
    pub label: String,
    pub account: String,
    pub baseline: bool,
    pub analysis: Analysed,
}

/// The published rows of a dataset's leaderboard in board order (at most `limit` submissions,
/// or those in `picked`), then the Human row. `examples`: whether the reader may see examples
/// (an admin); public datasets show them to everyone.
pub async fn comparison(
    hub: &Hub,
    name: &str,
    limit: usize,
    picked: &[i64],
    admin: bool,
) -> Result<(Dataset, Vec<ComparedRow>), AppError> {
    let dataset = datasets::by_name(hub, name).await?;
    let examples =
        admin || datasets::answer_visibility(hub, &dataset).await? == AnswerVisibility::Public;
    let mut conn = hub.conn().await?;
    let published = store::submissions::published(&mut conn, dataset.id).await?;
    drop(conn);
    let board = leaderboard::rows(hub, &dataset).await?;
    let by_id: HashMap<i64, &SubmissionRow> = published.iter().map(|s| (s.id, s)).collect();
    let chosen = board
        .iter()
        .filter(|r| r.source != RowSource::Human)
        .filter_map(|r| r.submission)
        .filter(|id| picked.is_empty() || picked.contains(id))
        .take(if picked.is_empty() { limit } else { usize::MAX });
    let mut rows = Vec::new();
    for id in chosen {
        let Some(row) = by_id.get(&id) else { continue };
        let analysis = submission_analysis(hub, row).await?;
        rows.push(ComparedRow {
            submission: Some(id),
            label: row.model.clone(),
            account: row.account.clone(),
            baseline: row.baseline,
            analysis: Analysed::shown(analysis, &dataset.name, examples),
        });
    }
    if let Some(analysis) = of_humans(hub, &dataset).await? {
        rows.push(ComparedRow {
            submission: None,
            label: "Human".to_owned(),
            account: String::new(),
            baseline: false,
            analysis: Analysed::shown(analysis, &dataset.name, examples),
        });
    }
    Ok((dataset, rows))
}

/// A prediction file analysed against a stored dataset or a release folder, read as the
/// leaderboard reads submissions (`enact-hub errors`). `progress` hears of each slow step.
pub async fn of_file(
    against: scoring::Against<'_>,
    text: String,
    progress: &(dyn Fn(ScoringStep) + Sync),
) -> Result<ErrorAnalysis, ScoreFileError> {
    let targets = scoring::targets(&against, progress).await?;
    progress(ScoringStep::Scoring);
    let analysis = tokio::task::spawn_blocking(move || analyse_file(&targets, &text))
        .await
        .map_err(AppError::from)??;
    progress(ScoringStep::Finished);
    Ok(analysis)
}

/// A prediction file analysed against `targets` (strict reading, every item counts).
/// [`ScoreFileError::FileProblems`] when the file has problems, one message per problem.
/// Blocking.
pub fn analyse_file(
    targets: &[ScoringTarget],
    text: &str,
) -> Result<ErrorAnalysis, ScoreFileError> {
    let items: Vec<_> = targets.iter().map(ScoringTarget::strict_item).collect();
    let scoring = score_strict_predictions(&items, python_text_lines(text))
        .map_err(|e| ScoreFileError::Unscorable(e.to_string()))?;
    if !scoring.problems.is_empty() {
        return Err(ScoreFileError::FileProblems(
            scoring.problems.iter().map(|p| p.to_string()).collect(),
        ));
    }
    Ok(analyse_strict(&items, &scoring))
}
