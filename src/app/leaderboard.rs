//! A dataset's leaderboard: one row per published submission and, once annotators have
//! answered, the Human row, scored by the same verifier; best overall task accuracy first.

use super::{AppError, Hub, datasets};
use crate::core::annotation::human_entries;
use crate::core::leaderboard::{LeaderboardRow, RowIdentity, rank};
use crate::core::verifier::PerformanceReport;
use crate::store;
use crate::store::datasets::Dataset;
use crate::store::submissions::SubmissionRow;

/// A submission's leaderboard row.
pub fn submission_row(s: &SubmissionRow) -> LeaderboardRow {
    LeaderboardRow::from_scores(
        &RowIdentity {
            submission: s.id,
            model: &s.model,
            account: &s.account,
            baseline: s.baseline,
            submitted_at: &s.created_at,
        },
        &s.scores,
    )
}

/// Human performance on a dataset: every submitted answer scored as model answers are (the
/// item's stored signatures, exact match where there are none), by direction and step length.
/// `None` when nobody has answered an item yet. Skipped and flagged items are not answers; an
/// item answered by several annotators counts once per answer. Verification costs microseconds
/// per answer, so it runs inline.
pub async fn human_performance(
    hub: &Hub,
    dataset: &Dataset,
) -> Result<Option<PerformanceReport>, AppError> {
    let mut conn = hub.conn().await?;
    let answers = store::annotations::human_answers(&mut conn, dataset.id).await?;
    if answers.is_empty() {
        return Ok(None);
    }
    let entries = human_entries(&answers).map_err(|e| {
        AppError::internal(format!(
            "dataset '{}': stored annotations: {e}",
            dataset.name
        ))
    })?;
    Ok(Some(PerformanceReport::from_entries(&entries)))
}

/// The dataset's leaderboard rows, ranked.
pub async fn rows(hub: &Hub, dataset: &Dataset) -> Result<Vec<LeaderboardRow>, AppError> {
    let mut conn = hub.conn().await?;
    let submissions = store::submissions::published(&mut conn, dataset.id).await?;
    let items = store::datasets::counts(&mut conn, dataset.id).await?.total;
    drop(conn);
    let mut rows: Vec<LeaderboardRow> = submissions.iter().map(submission_row).collect();
    if let Some(report) = human_performance(hub, dataset).await? {
        rows.push(LeaderboardRow::human(
            &report,
            usize::try_from(items).unwrap_or(0),
        ));
    }
    rank(&mut rows);
    Ok(rows)
}

/// The leaderboard of the dataset named `name`.
pub async fn of(hub: &Hub, name: &str) -> Result<(Dataset, Vec<LeaderboardRow>), AppError> {
    let dataset = datasets::by_name(hub, name).await?;
    let rows = rows(hub, &dataset).await?;
    Ok((dataset, rows))
}
