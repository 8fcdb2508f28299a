//! Scoring a prediction file outside the leaderboard (`enact-hub score`): the items and
//! signatures it is scored against, from a stored dataset or from a release folder on disk.

use std::path::Path;

use anyhow::Context;

use super::import::ReleaseLocation;
use super::{AppError, Hub, datasets};
use crate::core::dataset::{QaItem, parse_release_line};
use crate::core::scoring::ScoringItem;
use crate::core::scoring::{self, ScoringTarget, StoredSignatures};
use crate::core::semantics::{self, SignatureSource};
use crate::store;

async fn scoring_items(hub: &Hub, dataset: &str) -> Result<Vec<ScoringItem>, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    Ok(store::items::scoring_items(&mut conn, dataset.id).await?)
}

/// Every item of a stored dataset with its ground truth and the signatures stored at import.
pub async fn stored_targets(hub: &Hub, dataset: &str) -> Result<Vec<ScoringTarget>, AppError> {
    let rows = scoring_items(hub, dataset).await?;
    scoring::targets_from_stored(rows).map_err(AppError::internal)
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
/// signatures, from scene graphs when given. `Ok(Err(problems))` names every line that is
/// not a valid item, with its file and line. Blocking: call from `spawn_blocking`.
pub fn release_targets(
    data: &Path,
    scene_graphs: Option<&Path>,
) -> anyhow::Result<Result<Vec<ScoringTarget>, Vec<String>>> {
    let location = ReleaseLocation::resolve(data)?;
    let text = std::fs::read_to_string(&location.qa_file)
        .with_context(|| format!("cannot read {}", location.qa_file.display()))?;
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
        return Ok(Err(problems));
    }
    let refs: Vec<&QaItem> = items.iter().map(|(_, i)| i).collect();
    let semantics = semantics::for_items(scene_graphs, &refs);
    let mut targets = Vec::with_capacity(items.len());
    for ((line, item), semantics) in items.iter().zip(semantics) {
        match semantics {
            Ok(s) => targets.push(ScoringTarget::from_item(item, s).map_err(anyhow::Error::msg)?),
            Err(ps) => problems.extend(
                ps.iter()
                    .map(|p| format!("{file}: line {line} ({}): {p}", item.id)),
            ),
        }
    }
    Ok(if problems.is_empty() {
        Ok(targets)
    } else {
        Err(problems)
    })
}
