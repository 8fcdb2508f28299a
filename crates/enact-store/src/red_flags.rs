//! The facts behind a dataset's red flags (`core::red_flags`): how many items each submission
//! answered exactly as the truth, and what the dataset shares with public datasets.

use super::db::{Conn, Fields, on};
use enact_core::red_flags::{ExactAnswers, Leak};

/// Every submission to `dataset` (listed or not) with its count of exactly right answers (of
/// the dataset's items: not verdicts a replacing import left to be swept).
pub async fn exact_answers(
    conn: &mut Conn,
    dataset: i64,
) -> Result<Vec<ExactAnswers>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT s.id, s.model, a.name AS account, s.visibility, \
             (SELECT coalesce(sum(CASE WHEN v.exact_match THEN 1 ELSE 0 END), 0) \
              FROM submission_items v JOIN items i ON i.id = v.item AND i.dataset_id = s.dataset \
              WHERE v.submission = s.id) AS exact \
             FROM submissions s JOIN accounts a ON a.id = s.account \
             WHERE s.dataset = $1 ORDER BY s.id",
        )
        .bind(dataset)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|row| {
                let visibility: String = row.try_get("visibility")?;
                let exact: i64 = row.try_get("exact")?;
                Ok(ExactAnswers {
                    submission: row.try_get("id")?,
                    model: row.try_get("model")?,
                    account: row.try_get("account")?,
                    listed: visibility == "published",
                    exact: usize::try_from(exact).unwrap_or(0),
                })
            })
            .collect()
    })
}

/// Per dataset whose answers are public (not `dataset`, not an import's hidden staging row):
/// how many of `dataset`'s items have the same content, and how many of its frames that
/// dataset's items show. Only datasets sharing something are listed, by name.
pub async fn leaks(conn: &mut Conn, dataset: i64) -> Result<Vec<Leak>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT o.name, \
             (SELECT count(*) FROM items i WHERE i.dataset_id = $1 AND EXISTS \
                (SELECT 1 FROM items j WHERE j.dataset_id = o.id AND j.content_hash = i.content_hash)) \
                AS items, \
             (SELECT count(DISTINCT ii.frame) FROM items i JOIN item_images ii ON ii.item = i.id \
              WHERE i.dataset_id = $1 AND EXISTS \
                (SELECT 1 FROM item_images jj JOIN items j ON j.id = jj.item \
                 WHERE jj.frame = ii.frame AND j.dataset_id = o.id)) AS frames \
             FROM datasets o JOIN dataset_settings s ON s.dataset = o.id \
             WHERE o.id <> $1 AND s.answers = 'public' \
               AND o.id NOT IN (SELECT staging FROM staged_imports) \
               AND o.id NOT IN (SELECT dataset FROM retired_datasets) \
             ORDER BY o.name",
        )
        .bind(dataset)
        .fetch_all(&mut *c)
        .await?;
        let mut leaks = Vec::new();
        for row in &rows {
            let items: i64 = row.try_get("items")?;
            let frames: i64 = row.try_get("frames")?;
            if items > 0 || frames > 0 {
                leaks.push(Leak {
                    dataset: row.try_get("name")?,
                    items: usize::try_from(items).unwrap_or(0),
                    frames: usize::try_from(frames).unwrap_or(0),
                });
            }
        }
        Ok(leaks)
    })
}
