//! Attention checks' rows: a dataset's attention set and items, and the attention mix's
//! assignments (mirroring [`super::gold`]).

use super::db::{Conn, Fields, WriteConn, on};
use super::gold::GoldStanding;
use super::{corrupt, kind_from_row};
use enact_core::annotation::OutcomeKind;
use enact_core::attention::Instruction;
use enact_core::dataset::StepLength;

/// A dataset's attention checks as stored.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredAttentionSet {
    pub rate: i64,
    pub set_by: String,
    pub created_at: String,
    /// Its items' ids with their instructions, in id order.
    pub items: Vec<(String, Instruction)>,
}

fn instruction(r: &impl Fields) -> Result<Instruction, sqlx::Error> {
    let text: String = r.try_get("instruction")?;
    Instruction::parse(&text).map_err(|e| corrupt("instruction", e))
}

/// Replaces the dataset's attention set (its items go with it) by this one: `(item row id,
/// instruction)` pairs. Call inside a transaction.
pub async fn replace(
    conn: &mut WriteConn,
    dataset_id: i64,
    rate: i64,
    set_by: &str,
    items: &[(i64, Instruction)],
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("DELETE FROM attention_sets WHERE dataset = $1")
            .bind(dataset_id)
            .execute(&mut *c)
            .await?;
        sqlx::query("INSERT INTO attention_sets (dataset, rate, set_by) VALUES ($1, $2, $3)")
            .bind(dataset_id)
            .bind(rate)
            .bind(set_by)
            .execute(&mut *c)
            .await?;
        for (item, instruction) in items {
            sqlx::query(
                "INSERT INTO attention_items (item, dataset, instruction) VALUES ($1, $2, $3)",
            )
            .bind(item)
            .bind(dataset_id)
            .bind(instruction.as_str())
            .execute(&mut *c)
            .await?;
        }
        Ok(())
    })
}

/// Removes the dataset's attention set; whether there was one. Call inside a transaction.
pub async fn clear(conn: &mut WriteConn, dataset_id: i64) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query("DELETE FROM attention_sets WHERE dataset = $1")
            .bind(dataset_id)
            .execute(&mut *c)
            .await?;
        Ok(done.rows_affected() == 1)
    })
}

/// The dataset's attention set, if it has one.
pub async fn attention_set(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Option<StoredAttentionSet>, sqlx::Error> {
    on!(conn, |c| {
        let row =
            sqlx::query("SELECT rate, set_by, created_at FROM attention_sets WHERE dataset = $1")
                .bind(dataset_id)
                .fetch_optional(&mut *c)
                .await?;
        let Some(row) = row else {
            return Ok(None);
        };
        let rows = sqlx::query(
            "SELECT i.item_id, t.instruction FROM attention_items t JOIN items i ON i.id = t.item \
             WHERE t.dataset = $1 ORDER BY i.id",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        let items = rows
            .iter()
            .map(|r| Ok((r.try_get("item_id")?, instruction(r)?)))
            .collect::<Result<Vec<_>, sqlx::Error>>()?;
        Ok(Some(StoredAttentionSet {
            rate: row.try_get("rate")?,
            set_by: row.try_get("set_by")?,
            created_at: row.try_get("created_at")?,
            items,
        }))
    })
}

/// Store ids of the dataset's attention-check items, ascending.
pub async fn attention_item_rowids(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<i64>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar("SELECT item FROM attention_items WHERE dataset = $1 ORDER BY item")
            .bind(dataset_id)
            .fetch_all(&mut *c)
            .await
    })
}

/// How many of the dataset's items are attention checks.
pub async fn attention_count(conn: &mut Conn, dataset_id: i64) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar("SELECT count(*) FROM attention_items WHERE dataset = $1")
            .bind(dataset_id)
            .fetch_one(&mut *c)
            .await
    })
}

/// The instruction an item's question carries, when it is an attention check.
pub async fn instruction_of(
    conn: &mut Conn,
    item: i64,
) -> Result<Option<Instruction>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query("SELECT instruction FROM attention_items WHERE item = $1")
            .bind(item)
            .fetch_optional(&mut *c)
            .await?;
        row.as_ref().map(instruction).transpose()
    })
}

/// Takes out of the queues the unfinished assignments the attention mix made on the dataset's
/// items (with their drafts); finished ones stay with their answers. Returns the
/// `(annotator, item)` pairs that went.
pub async fn drop_unfinished_attention_assignments(
    conn: &mut WriteConn,
    dataset_id: i64,
) -> Result<Vec<(i64, i64)>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query(
            "DELETE FROM drafts WHERE EXISTS (SELECT 1 FROM assignments a \
             JOIN items i ON i.id = a.item \
             WHERE a.annotator = drafts.annotator AND a.item = drafts.item \
             AND a.attention = $2 AND i.dataset_id = $1)",
        )
        .bind(dataset_id)
        .bind(true)
        .execute(&mut *c)
        .await?;
        let rows = sqlx::query(
            "DELETE FROM assignments WHERE attention = $2 \
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

/// Every annotator with an item of the dataset in their queue, with what the attention mix
/// needs: `ordinary` counts the items that are neither gold nor attention checks, `held` the
/// attention checks already there.
pub async fn attention_standings(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<GoldStanding>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT a.annotator, a.item, (t.item IS NOT NULL) AS is_check, \
             (g.item IS NOT NULL) AS is_gold FROM assignments a \
             JOIN items i ON i.id = a.item LEFT JOIN attention_items t ON t.item = a.item \
             LEFT JOIN gold_items g ON g.item = a.item \
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
                if row.try_get::<bool>("is_check")? {
                    standing.held.push(row.try_get("item")?);
                } else if !row.try_get::<bool>("is_gold")? {
                    standing.ordinary += 1;
                }
            }
        }
        Ok(standings)
    })
}

/// Adds attention-mix assignments `(annotator, item)` at the end of each queue; pairs already
/// assigned stay as they are. Returns how many were new. Call inside a transaction.
pub async fn assign_checks(conn: &mut WriteConn, pairs: &[(i64, i64)]) -> Result<u64, sqlx::Error> {
    on!(conn, |c| {
        let mut added = 0;
        for &(annotator, item) in pairs {
            let done = sqlx::query(
                "INSERT INTO assignments (annotator, item, position, attention) \
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

/// One attention check in one annotator's queue, with how it was finished.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CheckRow {
    pub annotator: String,
    pub instruction: Instruction,
    pub step_length: StepLength,
    pub finished: Option<OutcomeKind>,
    /// The labels in slot order, when answered.
    pub answer: Option<Vec<u8>>,
}

/// Every attention check of the dataset in anyone's queue, by annotator name.
pub async fn check_rows(conn: &mut Conn, dataset_id: i64) -> Result<Vec<CheckRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT an.name, t.instruction, i.direction, i.step_length, n.outcome, n.answer \
             FROM assignments a JOIN attention_items t ON t.item = a.item \
             JOIN items i ON i.id = a.item JOIN annotators an ON an.id = a.annotator \
             LEFT JOIN annotations n ON n.annotator = a.annotator AND n.item = a.item \
             WHERE t.dataset = $1 ORDER BY an.name, a.item",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|r| {
                let (_, step_length) = kind_from_row(r)?;
                let answer: Option<String> = r.try_get("answer")?;
                Ok(CheckRow {
                    annotator: r.try_get("name")?,
                    instruction: instruction(r)?,
                    step_length,
                    finished: r.try_get("outcome")?,
                    answer: answer
                        .map(|a| serde_json::from_str(&a).map_err(|e| corrupt("answer", e)))
                        .transpose()?,
                })
            })
            .collect()
    })
}
