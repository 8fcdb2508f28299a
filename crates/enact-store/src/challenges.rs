//! Split datasets (challenges): their settings, each item's part, what the final ranking reads
//! (verdicts, selections, submission counts), and the submissions selected for it.

use sqlx::QueryBuilder;

use super::corrupt;
use super::db::{Conn, Fields, WriteConn, on};
use enact_core::challenge::Part;
use enact_core::submission::VerdictOutcome;

/// A split dataset's challenge as stored.
#[derive(Debug, Clone, PartialEq)]
pub struct ChallengeRow {
    pub dataset: i64,
    /// Stored bit for bit in the databases' signed integer.
    pub seed: u64,
    pub public_share: f64,
    /// When the private part is revealed by itself (`2026-07-01T12:00:00Z`), if set.
    pub reveal_at: Option<String>,
    pub revealed_at: Option<String>,
    /// `deadline` or `hand`, once revealed.
    pub revealed_by: Option<String>,
    pub selection_limit: Option<i64>,
    pub split_by: String,
    pub created_at: String,
}

fn challenge_from_row(row: &impl Fields) -> Result<ChallengeRow, sqlx::Error> {
    Ok(ChallengeRow {
        dataset: row.try_get("dataset")?,
        seed: row.try_get::<i64>("seed")? as u64,
        public_share: row.try_get("public_share")?,
        reveal_at: row.try_get("reveal_at")?,
        revealed_at: row.try_get("revealed_at")?,
        revealed_by: row.try_get("revealed_by")?,
        selection_limit: row.try_get("selection_limit")?,
        split_by: row.try_get("split_by")?,
        created_at: row.try_get("created_at")?,
    })
}

/// The challenge of a dataset, if it was split.
pub async fn of_dataset(
    conn: &mut Conn,
    dataset: i64,
) -> Result<Option<ChallengeRow>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(
            "SELECT dataset, seed, public_share, reveal_at, revealed_at, revealed_by, \
             selection_limit, split_by, created_at FROM challenges WHERE dataset = $1",
        )
        .bind(dataset)
        .fetch_optional(&mut *c)
        .await?;
        row.as_ref().map(challenge_from_row).transpose()
    })
}

/// Rows per INSERT of parts: 3 bound values each, under SQLite's variable limit.
const PARTS_PER_STATEMENT: usize = 5000;

/// Stores a split: the challenge and each item's part (`items`: `items` row ids). Call inside
/// a transaction; a dataset split before refuses the insert (its primary key).
#[tracing::instrument(skip_all)]
pub async fn insert(
    conn: &mut WriteConn,
    dataset: i64,
    seed: u64,
    public_share: f64,
    split_by: &str,
    items: &[(i64, Part)],
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query(
            "INSERT INTO challenges (dataset, seed, public_share, split_by) \
             VALUES ($1, $2, $3, $4)",
        )
        .bind(dataset)
        .bind(seed as i64)
        .bind(public_share)
        .bind(split_by)
        .execute(&mut *c)
        .await?;
        for chunk in items.chunks(PARTS_PER_STATEMENT) {
            let mut builder =
                QueryBuilder::new("INSERT INTO challenge_items (item, dataset, part) ");
            builder.push_values(chunk, |mut b, (item, part)| {
                b.push_bind(*item)
                    .push_bind(dataset)
                    .push_bind(part.as_str());
            });
            builder.build().execute(&mut *c).await?;
        }
        Ok(())
    })
}

/// Sets the deadline (`None`: none). Returns whether the dataset has a challenge.
pub async fn set_reveal_at(
    conn: &mut WriteConn,
    dataset: i64,
    reveal_at: Option<&str>,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query("UPDATE challenges SET reveal_at = $2 WHERE dataset = $1")
            .bind(dataset)
            .bind(reveal_at)
            .execute(&mut *c)
            .await?;
        Ok(done.rows_affected() > 0)
    })
}

/// Sets the selection limit (`None`: no limit). Returns whether the dataset has a challenge.
pub async fn set_selection_limit(
    conn: &mut WriteConn,
    dataset: i64,
    limit: Option<i64>,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query("UPDATE challenges SET selection_limit = $2 WHERE dataset = $1")
            .bind(dataset)
            .bind(limit)
            .execute(&mut *c)
            .await?;
        Ok(done.rows_affected() > 0)
    })
}

/// Records the reveal at `now` (`2026-07-01T12:00:00Z`), `revealed_by` `hand`, unless it was
/// revealed before. Returns whether this call revealed it.
pub async fn reveal_by_hand(
    conn: &mut WriteConn,
    dataset: i64,
    now: &str,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query(
            "UPDATE challenges SET revealed_at = $2, revealed_by = 'hand' \
             WHERE dataset = $1 AND revealed_at IS NULL",
        )
        .bind(dataset)
        .bind(now)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() > 0)
    })
}

/// Records the reveal at `now`, `revealed_by` `deadline`, if the deadline is not after `now`
/// and it was not revealed before. Returns whether this call revealed it (once, whoever
/// reads first).
pub async fn reveal_at_deadline(
    conn: &mut WriteConn,
    dataset: i64,
    now: &str,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        // Both are `YYYY-MM-DDTHH:MM:SSZ`: their text order is their time order.
        let done = sqlx::query(
            "UPDATE challenges SET revealed_at = $2, revealed_by = 'deadline' \
             WHERE dataset = $1 AND revealed_at IS NULL AND reveal_at IS NOT NULL \
             AND reveal_at <= $2",
        )
        .bind(dataset)
        .bind(now)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() > 0)
    })
}

fn part_column(text: &str) -> Result<Part, sqlx::Error> {
    Part::parse(text).ok_or_else(|| corrupt("part", format!("unknown part {text:?}")))
}

/// Each assigned item's part: `(items row id, item id, part)`, by item id.
pub async fn parts(conn: &mut Conn, dataset: i64) -> Result<Vec<(i64, String, Part)>, sqlx::Error> {
    on!(conn, |c| {
        let rows: Vec<(i64, String, String)> = sqlx::query_as(
            "SELECT p.item, i.item_id, p.part FROM challenge_items p \
             JOIN items i ON i.id = p.item WHERE p.dataset = $1 ORDER BY i.item_id",
        )
        .bind(dataset)
        .fetch_all(&mut *c)
        .await?;
        rows.into_iter()
            .map(|(item, id, part)| Ok((item, id, part_column(&part)?)))
            .collect()
    })
}

/// One stored verdict of a listed submission, as a part's figures need it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ItemResult {
    pub submission: i64,
    /// The `items` row id.
    pub item: i64,
    pub outcome: VerdictOutcome,
    pub task_accuracy: bool,
    pub pairwise_accuracy: Option<f64>,
}

/// Every verdict of the dataset's published submissions, in one query (one snapshot), in no
/// particular order.
#[tracing::instrument(skip_all)]
pub async fn published_results(
    conn: &mut Conn,
    dataset: i64,
) -> Result<Vec<ItemResult>, sqlx::Error> {
    on!(conn, |c| {
        let rows: Vec<(i64, i64, VerdictOutcome, bool, Option<f64>)> = sqlx::query_as(
            "SELECT v.submission, v.item, v.outcome, v.task_accuracy, v.pairwise_accuracy \
             FROM submission_items v JOIN submissions s ON s.id = v.submission \
             WHERE s.dataset = $1 AND s.visibility = 'published'",
        )
        .bind(dataset)
        .fetch_all(&mut *c)
        .await?;
        Ok(rows
            .into_iter()
            .map(
                |(submission, item, outcome, task_accuracy, pairwise_accuracy)| ItemResult {
                    submission,
                    item,
                    outcome,
                    task_accuracy,
                    pairwise_accuracy,
                },
            )
            .collect())
    })
}

/// Each account's number of submissions to the dataset, listed or not: `(account id, count)`.
pub async fn submissions_per_account(
    conn: &mut Conn,
    dataset: i64,
) -> Result<Vec<(i64, i64)>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_as(
            "SELECT account, count(*) FROM submissions WHERE dataset = $1 GROUP BY account",
        )
        .bind(dataset)
        .fetch_all(&mut *c)
        .await
    })
}

/// The dataset's selections: `(submission, selection order)`, listed submissions or not,
/// in selection order.
pub async fn selections(conn: &mut Conn, dataset: i64) -> Result<Vec<(i64, i64)>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_as(
            "SELECT x.submission, x.id FROM challenge_selections x \
             JOIN submissions s ON s.id = x.submission WHERE s.dataset = $1 ORDER BY x.id",
        )
        .bind(dataset)
        .fetch_all(&mut *c)
        .await
    })
}

/// The published submissions an account selected on the dataset, in selection order.
pub async fn selected_by_account(
    conn: &mut Conn,
    dataset: i64,
    account: i64,
) -> Result<Vec<i64>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
            "SELECT x.submission FROM challenge_selections x \
             JOIN submissions s ON s.id = x.submission \
             WHERE s.dataset = $1 AND s.account = $2 AND s.visibility = 'published' \
             ORDER BY x.id",
        )
        .bind(dataset)
        .bind(account)
        .fetch_all(&mut *c)
        .await
    })
}

/// Selects a submission for the final ranking. Returns whether it was not selected before.
pub async fn select(conn: &mut WriteConn, submission: i64) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query(
            "INSERT INTO challenge_selections (submission) VALUES ($1) \
             ON CONFLICT (submission) DO NOTHING",
        )
        .bind(submission)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() > 0)
    })
}

/// Takes a submission out of the final ranking. Returns whether it was selected.
pub async fn unselect(conn: &mut WriteConn, submission: i64) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query("DELETE FROM challenge_selections WHERE submission = $1")
            .bind(submission)
            .execute(&mut *c)
            .await?;
        Ok(done.rows_affected() > 0)
    })
}
