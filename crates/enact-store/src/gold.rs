//! Gold sets and the gold mix's assignments; annotators excluded from a dataset's Human row.

use super::db::{Conn, Fields, WriteConn, on};

/// A dataset's gold set as stored.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredGoldSet {
    pub rate: i64,
    /// `share` or `list`.
    pub chosen_by: String,
    pub share: Option<f64>,
    /// Stored bit for bit in SQLite's signed integer.
    pub seed: Option<u64>,
    pub set_by: String,
    pub created_at: String,
    /// Its items' ids, in id order.
    pub items: Vec<String>,
}

/// Replaces the dataset's gold set (its gold items go with it) by this one. Call inside a
/// transaction.
#[allow(clippy::too_many_arguments)]
pub async fn replace(
    conn: &mut WriteConn,
    dataset_id: i64,
    rate: i64,
    chosen_by: &str,
    share: Option<f64>,
    seed: Option<u64>,
    set_by: &str,
    items: &[i64],
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("DELETE FROM gold_sets WHERE dataset = $1")
            .bind(dataset_id)
            .execute(&mut *c)
            .await?;
        sqlx::query(
            "INSERT INTO gold_sets (dataset, rate, chosen_by, share, seed, set_by) \
             VALUES ($1, $2, $3, $4, $5, $6)",
        )
        .bind(dataset_id)
        .bind(rate)
        .bind(chosen_by)
        .bind(share)
        // Stored bit for bit in SQLite's signed integer.
        .bind(seed.map(|s| s as i64))
        .bind(set_by)
        .execute(&mut *c)
        .await?;
        for item in items {
            sqlx::query("INSERT INTO gold_items (item, dataset) VALUES ($1, $2)")
                .bind(item)
                .bind(dataset_id)
                .execute(&mut *c)
                .await?;
        }
        Ok(())
    })
}

/// Removes the dataset's gold set; whether there was one. Call inside a transaction.
pub async fn clear(conn: &mut WriteConn, dataset_id: i64) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query("DELETE FROM gold_sets WHERE dataset = $1")
            .bind(dataset_id)
            .execute(&mut *c)
            .await?;
        Ok(done.rows_affected() == 1)
    })
}

/// The dataset's gold set, if it has one.
pub async fn gold_set(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Option<StoredGoldSet>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(
            "SELECT rate, chosen_by, share, seed, set_by, created_at FROM gold_sets \
             WHERE dataset = $1",
        )
        .bind(dataset_id)
        .fetch_optional(&mut *c)
        .await?;
        let Some(row) = row else {
            return Ok(None);
        };
        let items: Vec<String> = sqlx::query_scalar(
            "SELECT i.item_id FROM gold_items g JOIN items i ON i.id = g.item \
             WHERE g.dataset = $1 ORDER BY i.id",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        Ok(Some(StoredGoldSet {
            rate: row.try_get("rate")?,
            chosen_by: row.try_get("chosen_by")?,
            share: row.try_get("share")?,
            seed: row.try_get::<Option<i64>>("seed")?.map(|s| s as u64),
            set_by: row.try_get("set_by")?,
            created_at: row.try_get("created_at")?,
            items,
        }))
    })
}

/// Store ids of the dataset's gold items, ascending.
pub async fn gold_item_rowids(conn: &mut Conn, dataset_id: i64) -> Result<Vec<i64>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar("SELECT item FROM gold_items WHERE dataset = $1 ORDER BY item")
            .bind(dataset_id)
            .fetch_all(&mut *c)
            .await
    })
}

/// How many of the dataset's items are gold.
pub async fn gold_count(conn: &mut Conn, dataset_id: i64) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar("SELECT count(*) FROM gold_items WHERE dataset = $1")
            .bind(dataset_id)
            .fetch_one(&mut *c)
            .await
    })
}

/// Takes out of the queues the unfinished assignments the gold mix made on the dataset's items
/// (with their drafts); finished ones stay with their answers. Returns the `(annotator, item)`
/// pairs that went.
pub async fn drop_unfinished_gold_assignments(
    conn: &mut WriteConn,
    dataset_id: i64,
) -> Result<Vec<(i64, i64)>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query(
            "DELETE FROM drafts WHERE EXISTS (SELECT 1 FROM assignments a \
             JOIN items i ON i.id = a.item \
             WHERE a.annotator = drafts.annotator AND a.item = drafts.item \
             AND a.gold = $2 AND i.dataset_id = $1)",
        )
        .bind(dataset_id)
        .bind(true)
        .execute(&mut *c)
        .await?;
        // Finished ones keep their assignment: the answer stays where it was given.
        let rows = sqlx::query(
            "DELETE FROM assignments WHERE gold = $2 \
             AND item IN (SELECT id FROM items WHERE dataset_id = $1) \
             AND NOT EXISTS (SELECT 1 FROM annotations n \
                 WHERE n.annotator = assignments.annotator AND n.item = assignments.item) \
             RETURNING annotator, item",
        )
        .bind(dataset_id)
        .bind(true)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|r| Ok((r.try_get("annotator")?, r.try_get("item")?)))
            .collect()
    })
}

/// One annotator's queue on a dataset, as the gold mix sees it.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct GoldStanding {
    pub annotator: i64,
    /// Assigned items of the dataset that are neither gold nor attention checks.
    pub ordinary: usize,
    /// Gold items already in the queue, however they got there.
    pub held: Vec<i64>,
}

/// Every annotator with an item of the dataset in their queue, with what the gold mix needs.
pub async fn gold_standings(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<GoldStanding>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT a.annotator, a.item, (g.item IS NOT NULL) AS is_gold, \
             (t.item IS NOT NULL) AS is_check FROM assignments a \
             JOIN items i ON i.id = a.item LEFT JOIN gold_items g ON g.item = a.item \
             LEFT JOIN attention_items t ON t.item = a.item \
             WHERE i.dataset_id = $1 ORDER BY a.annotator, a.item",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        let mut standings: Vec<GoldStanding> = Vec::new();
        for row in &rows {
            let annotator: i64 = row.try_get("annotator")?;
            if standings.last().is_none_or(|s| s.annotator != annotator) {
                standings.push(GoldStanding {
                    annotator,
                    ..GoldStanding::default()
                });
            }
            if let Some(standing) = standings.last_mut() {
                if row.try_get::<bool>("is_gold")? {
                    standing.held.push(row.try_get("item")?);
                } else if !row.try_get::<bool>("is_check")? {
                    // Attention checks are not the dataset's coverage either.
                    standing.ordinary += 1;
                }
            }
        }
        Ok(standings)
    })
}

/// Adds gold-mix assignments `(annotator, item)` at the end of each queue (the queue's order
/// is the mix's, computed when it is read); pairs already assigned stay as they are. Returns
/// how many were new. Call inside a transaction.
pub async fn assign_gold(conn: &mut WriteConn, pairs: &[(i64, i64)]) -> Result<u64, sqlx::Error> {
    on!(conn, |c| {
        let mut added = 0;
        for &(annotator, item) in pairs {
            let done = sqlx::query(
                "INSERT INTO assignments (annotator, item, position, gold) \
                 SELECT $1, $2, coalesce(max(position), 0) + 1, $3 FROM assignments \
                 WHERE annotator = $1 ON CONFLICT (annotator, item) DO NOTHING",
            )
            .bind(annotator)
            .bind(item)
            .bind(true)
            .execute(&mut *c)
            .await?;
            added += done.rows_affected();
        }
        Ok(added)
    })
}

/// Keeps an annotator's answers on a dataset out of its Human row and agreement report;
/// whether they were not excluded already. Call inside a transaction.
pub async fn exclude(
    conn: &mut WriteConn,
    dataset_id: i64,
    annotator: i64,
    excluded_by: &str,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query(
            "INSERT INTO annotator_exclusions (dataset, annotator, excluded_by) \
             VALUES ($1, $2, $3) ON CONFLICT (dataset, annotator) DO NOTHING",
        )
        .bind(dataset_id)
        .bind(annotator)
        .bind(excluded_by)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() == 1)
    })
}

/// Counts an excluded annotator's answers on a dataset again; whether they were excluded.
pub async fn include(
    conn: &mut WriteConn,
    dataset_id: i64,
    annotator: i64,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done =
            sqlx::query("DELETE FROM annotator_exclusions WHERE dataset = $1 AND annotator = $2")
                .bind(dataset_id)
                .bind(annotator)
                .execute(&mut *c)
                .await?;
        Ok(done.rows_affected() == 1)
    })
}

/// An annotator excluded from a dataset's Human row.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Exclusion {
    pub annotator: String,
    pub excluded_by: String,
    pub excluded_at: String,
}

/// The annotators excluded from a dataset's Human row, by name.
pub async fn exclusions(conn: &mut Conn, dataset_id: i64) -> Result<Vec<Exclusion>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT a.name, x.excluded_by, x.created_at FROM annotator_exclusions x \
             JOIN annotators a ON a.id = x.annotator WHERE x.dataset = $1 ORDER BY a.name",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|r| {
                Ok(Exclusion {
                    annotator: r.try_get("name")?,
                    excluded_by: r.try_get("excluded_by")?,
                    excluded_at: r.try_get("created_at")?,
                })
            })
            .collect()
    })
}
