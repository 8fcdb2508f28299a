//! Scoring a prediction file outside the leaderboard (`enact-hub score` and `errors`): the
//! items and signatures it is scored against, from a stored dataset or from a release folder
//! on disk, and the scoring itself under either policy.

use std::path::{Path, PathBuf};

use anyhow::Context;

use super::import::ReleaseLocation;
use super::{AppError, Hub, datasets};
use crate::core::dataset::{QaItem, parse_release_line};
use crate::core::scoring::ScoringItem;
use crate::core::scoring::{
    self, SceneGraphSignatures, ScoringTarget, SemanticCoverage, StoredSignatures,
};
use crate::core::semantics::{self, SignatureSource};
use crate::core::verifier::{
    EnactEvaluation, EnactSignatureSource, PerformanceReport, StrictItem, StrictScoring,
    enact_meta_performance_json, enact_model_name, python_text_lines, score_enact_predictions,
    score_strict_predictions,
};
use crate::store;

async fn scoring_items(hub: &Hub, dataset: &str) -> Result<Vec<ScoringItem>, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    Ok(store::items::scoring_items(&mut conn, dataset.id).await?)
}

/// Every item of a stored dataset with its ground truth and the signatures stored at import.
pub async fn stored_targets(hub: &Hub, dataset: &str) -> Result<Vec<ScoringTarget>, AppError> {
    let rows = scoring_items(hub, dataset).await?;
    // Parsing every item's signatures is heavy work for a full-size dataset.
    hub.heavy()
        .run(move || scoring::targets_from_stored(rows))
        .await?
        .map_err(AppError::internal)
}

/// The scene-graph signatures stored for a dataset's items, for the ENACT policy.
pub async fn stored_signatures(hub: &Hub, dataset: &str) -> Result<StoredSignatures, AppError> {
    let mut tables = Vec::new();
    for row in scoring_items(hub, dataset).await? {
        let Some((source, json)) = row.semantics else {
            continue;
        };
        if source != SignatureSource::SceneGraph.as_str() {
            continue;
        }
        let table = serde_json::from_str(&json).map_err(|e| {
            AppError::internal(format!(
                "item {}: stored signatures are unreadable: {e}",
                row.item_id
            ))
        })?;
        tables.push((row.task_name, row.key_frame_ids, table));
    }
    Ok(StoredSignatures::new(tables))
}

/// Reads a release's QA file (images are not needed to score) and computes each item's
/// signatures, from scene graphs when given. [`ScoreFileError::DatasetProblems`] names every
/// line that is not a valid item, with its file and line. Blocking: call from
/// `spawn_blocking`.
pub fn release_targets(
    data: &Path,
    scene_graphs: Option<&Path>,
) -> Result<Vec<ScoringTarget>, ScoreFileError> {
    let unscorable = |e: anyhow::Error| ScoreFileError::Unscorable(format!("{e:#}"));
    let location = ReleaseLocation::resolve(data).map_err(|e| unscorable(e.into()))?;
    let text = std::fs::read_to_string(&location.qa_file)
        .with_context(|| format!("cannot read {}", location.qa_file.display()))
        .map_err(unscorable)?;
    let file = location.qa_file.display().to_string();
    let mut items = Vec::new();
    let mut problems = Vec::new();
    for (index, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        match parse_release_line(line) {
            Ok(item) => items.push((index + 1, item)),
            Err(ps) => problems.extend(
                ps.iter()
                    .map(|p| format!("{file}: line {}: {p}", index + 1)),
            ),
        }
    }
    if !problems.is_empty() {
        return Err(ScoreFileError::DatasetProblems(problems));
    }
    let refs: Vec<&QaItem> = items.iter().map(|(_, i)| i).collect();
    let semantics = semantics::for_items(scene_graphs, &refs);
    let mut targets = Vec::with_capacity(items.len());
    for ((line, item), semantics) in items.iter().zip(semantics) {
        match semantics {
            Ok(s) => {
                targets.push(ScoringTarget::from_item(item, s).map_err(ScoreFileError::Unscorable)?)
            }
            Err(ps) => problems.extend(
                ps.iter()
                    .map(|p| format!("{file}: line {line} ({}): {p}", item.id)),
            ),
        }
    }
    if problems.is_empty() {
        Ok(targets)
    } else {
        Err(ScoreFileError::DatasetProblems(problems))
    }
}

/// What a prediction file is scored or analysed against.
pub enum Against<'a> {
    /// A dataset stored in the hub's database, with the signatures computed at its import.
    Stored { hub: &'a Hub, dataset: &'a str },
    /// An ENACT release folder (or its QA file) on disk; signatures are computed now, from
    /// the scene graphs of a `replayed_activities` folder when one is given.
    Release {
        data: PathBuf,
        scene_graphs: Option<PathBuf>,
    },
}

/// How a prediction file is read and scored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FilePolicy {
    /// ENACT's evaluator, quirks included: unparseable answers and duplicate ids are skipped.
    Enact,
    /// Every dataset item counts; a missing or unparseable answer scores TA 0 and PA 0.
    Strict,
}

/// A step of [`score_file`] that may take a while, for a caller that shows progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScoringStep {
    /// Reading a release folder (and its scene graphs, when `with_scene_graphs`).
    ReadingRelease { with_scene_graphs: bool },
    /// Loading the scene graphs a file's records name (the ENACT policy from a folder).
    LoadingSceneGraphs,
    /// Scoring (or analysing) the answers.
    Scoring,
    /// Done: nothing more will be reported.
    Finished,
}

/// A prediction file, scored.
pub enum ScoredFile {
    /// By ENACT's evaluator: what it skipped is listed and left out of every metric.
    Enact(EnactEvaluation),
    /// Under the strict policy, against every item of the dataset.
    Strict(StrictScoredFile),
}

/// A prediction file scored under the strict policy.
pub struct StrictScoredFile {
    pub model: String,
    pub targets: Vec<ScoringTarget>,
    pub scoring: StrictScoring,
    /// Where the items' signatures came from.
    pub semantic: SemanticCoverage,
}

impl ScoredFile {
    pub fn model(&self) -> &str {
        match self {
            ScoredFile::Enact(e) => &e.model_name,
            ScoredFile::Strict(s) => &s.model,
        }
    }

    pub fn report(&self) -> &PerformanceReport {
        match self {
            ScoredFile::Enact(e) => &e.report,
            ScoredFile::Strict(s) => &s.scoring.report,
        }
    }

    /// ENACT's two output files, as its evaluator writes them: the `meta_performance` JSON
    /// and the `detailed_eval` JSONL.
    pub fn enact_outputs(&self) -> (String, String) {
        match self {
            ScoredFile::Enact(e) => (e.meta_performance_json(), e.detailed_eval_jsonl()),
            ScoredFile::Strict(s) => (
                enact_meta_performance_json(&s.model, &s.scoring.report),
                scoring::strict_detailed_jsonl(&s.targets, &s.scoring),
            ),
        }
    }
}

/// Why a prediction file was not scored.
#[derive(Debug, thiserror::Error)]
pub enum ScoreFileError {
    /// The stored dataset could not be read (not found, or a failure of the database).
    #[error(transparent)]
    Refused(#[from] AppError),
    /// The ENACT policy reads signatures as ENACT's evaluator does, from scene graphs.
    #[error(
        "the enact policy scores as ENACT's evaluator does, which needs scene graphs: a \
         replayed_activities folder, or a stored dataset imported with them"
    )]
    NeedsSceneGraphs,
    /// The release's QA file has lines that are not valid items (each names file and line).
    #[error("the dataset has {} problems", .0.len())]
    DatasetProblems(Vec<String>),
    /// The prediction file has problems (each names its line); nothing was scored.
    #[error("{} problems in the prediction file", .0.len())]
    FileProblems(Vec<String>),
    /// The file or the scene graphs could not be read or scored at all.
    #[error("{0}")]
    Unscorable(String),
}

/// The model name a prediction file is reported under when none is given: from the file's
/// name, as ENACT's evaluator takes it.
pub fn model_name_of(file: &Path) -> String {
    enact_model_name(
        &file
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
    )
}

/// The items a prediction file is scored or analysed against, with the best signatures
/// available: those stored at import, or those computed now from a release folder.
pub async fn targets(
    against: &Against<'_>,
    progress: &(dyn Fn(ScoringStep) + Sync),
) -> Result<Vec<ScoringTarget>, ScoreFileError> {
    match against {
        Against::Stored { hub, dataset } => Ok(stored_targets(hub, dataset).await?),
        Against::Release { data, scene_graphs } => {
            progress(ScoringStep::ReadingRelease {
                with_scene_graphs: scene_graphs.is_some(),
            });
            let (data, scene_graphs) = (data.clone(), scene_graphs.clone());
            tokio::task::spawn_blocking(move || release_targets(&data, scene_graphs.as_deref()))
                .await
                .map_err(AppError::from)?
        }
    }
}

/// `enact-hub score`: a prediction file's `text` scored under `policy` against a dataset, as
/// ENACT's evaluator would (the `Enact` policy) or as the leaderboard does (`Strict`).
/// Nothing is stored. `progress` hears of each slow step.
pub async fn score_file(
    against: Against<'_>,
    policy: FilePolicy,
    text: String,
    model: String,
    progress: &(dyn Fn(ScoringStep) + Sync),
) -> Result<ScoredFile, ScoreFileError> {
    let scored = match policy {
        FilePolicy::Enact => score_enact(against, text, model, progress).await,
        FilePolicy::Strict => score_strict(against, text, model, progress).await,
    };
    progress(ScoringStep::Finished);
    scored
}

async fn score_enact(
    against: Against<'_>,
    text: String,
    model: String,
    progress: &(dyn Fn(ScoringStep) + Sync),
) -> Result<ScoredFile, ScoreFileError> {
    let source: Box<dyn EnactSignatureSource + Send> = match against {
        Against::Release {
            scene_graphs: Some(replayed),
            ..
        } => {
            progress(ScoringStep::LoadingSceneGraphs);
            let text = text.clone();
            let loaded = tokio::task::spawn_blocking(move || {
                SceneGraphSignatures::for_predictions(
                    &replayed,
                    python_text_lines(&text).map(|(_, l)| l),
                )
            })
            .await
            .map_err(AppError::from)?;
            Box::new(loaded.map_err(|e| ScoreFileError::Unscorable(e.to_string()))?)
        }
        Against::Stored { hub, dataset } => Box::new(stored_signatures(hub, dataset).await?),
        Against::Release {
            scene_graphs: None, ..
        } => return Err(ScoreFileError::NeedsSceneGraphs),
    };
    progress(ScoringStep::Scoring);
    let evaluation = tokio::task::spawn_blocking(move || {
        let lines: Vec<(usize, &str)> = python_text_lines(&text).collect();
        score_enact_predictions(lines, &model, source.as_ref())
    })
    .await
    .map_err(AppError::from)?;
    evaluation
        .map(ScoredFile::Enact)
        .map_err(|e| ScoreFileError::Unscorable(e.to_string()))
}

async fn score_strict(
    against: Against<'_>,
    text: String,
    model: String,
    progress: &(dyn Fn(ScoringStep) + Sync),
) -> Result<ScoredFile, ScoreFileError> {
    let targets = targets(&against, progress).await?;
    let semantic = SemanticCoverage::of(&targets);
    progress(ScoringStep::Scoring);
    let (targets, scoring) = tokio::task::spawn_blocking(move || {
        let items: Vec<StrictItem<'_>> = targets.iter().map(ScoringTarget::strict_item).collect();
        let scoring = score_strict_predictions(&items, python_text_lines(&text));
        drop(items);
        (targets, scoring)
    })
    .await
    .map_err(AppError::from)?;
    let scoring = scoring.map_err(|e| ScoreFileError::Unscorable(e.to_string()))?;
    if !scoring.problems.is_empty() {
        return Err(ScoreFileError::FileProblems(
            scoring.problems.iter().map(ToString::to_string).collect(),
        ));
    }
    Ok(ScoredFile::Strict(StrictScoredFile {
        model,
        targets,
        scoring,
        semantic,
    }))
}
