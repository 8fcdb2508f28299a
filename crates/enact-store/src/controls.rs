//! Annotator controls' rows: paused queues, and the unfinished assignments a handover moves.

use std::collections::{HashMap, HashSet};

use super::db::{Conn, Fields, WriteConn, on};
use super::kind_from_row;
use enact_core::annotation::SplitItem;

/// A paused queue: who paused it and when.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pause {
    pub annotator: i64,
    pub name: String,
    pub paused_by: String,
    pub paused_at: String,
}

fn pause_from_row(r: &impl Fields) -> Result<Pause, sqlx::Error> {
    Ok(Pause {
        annotator: r.try_get("annotator")?,
        name: r.try_get("name")?,
        paused_by: r.try_get("paused_by")?,
        paused_at: r.try_get("created_at")?,
    })
}

/// Pauses an annotator's queue; whether it was running. Call inside a transaction.
pub async fn pause(
    conn: &mut WriteConn,
    annotator: i64,
    paused_by: &str,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query(
            "INSERT INTO annotator_pauses (annotator, paused_by) VALUES ($1, $2) \
             ON CONFLICT (annotator) DO NOTHING",
        )
        .bind(annotator)
        .bind(paused_by)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() == 1)
    })
}

/// Resumes an annotator's queue; whether it was paused. Call inside a transaction.
pub async fn resume(conn: &mut WriteConn, annotator: i64) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query("DELETE FROM annotator_pauses WHERE annotator = $1")
            .bind(annotator)
            .execute(&mut *c)
            .await?;
        Ok(done.rows_affected() == 1)
    })
}

/// The annotator's pause, if their queue is paused.
pub async fn pause_of(conn: &mut Conn, annotator: i64) -> Result<Option<Pause>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(
            "SELECT p.annotator, a.name, p.paused_by, p.created_at FROM annotator_pauses p \
             JOIN annotators a ON a.id = p.annotator WHERE p.annotator = $1",
        )
        .bind(annotator)
        .fetch_optional(&mut *c)
        .await?;
        row.as_ref().map(pause_from_row).transpose()
    })
}

/// Every paused queue, by annotator name.
pub async fn pauses(conn: &mut Conn) -> Result<Vec<Pause>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT p.annotator, a.name, p.paused_by, p.created_at FROM annotator_pauses p \
             JOIN annotators a ON a.id = p.annotator ORDER BY a.name",
        )
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(pause_from_row).collect()
    })
}

/// One unfinished assignment of an annotator.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unfinished {
    pub dataset_id: i64,
    pub dataset: String,
    pub item_id: String,
    pub split: SplitItem,
    /// Put there by the gold or the attention mix (the annotator's own checks, not the
    /// dataset's coverage).
    pub mixed: bool,
}

/// The annotator's assigned items without a finished answer, skip or flag, in queue order.
pub async fn unfinished(conn: &mut Conn, annotator: i64) -> Result<Vec<Unfinished>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT i.id, i.dataset_id, d.name AS dataset, i.item_id, i.direction, \
             i.step_length, (a.gold = $2 OR a.attention = $2) AS mixed FROM assignments a \
             JOIN items i ON i.id = a.item JOIN datasets d ON d.id = i.dataset_id \
             WHERE a.annotator = $1 \
             AND NOT EXISTS (SELECT 1 FROM annotations n \
                 WHERE n.annotator = a.annotator AND n.item = a.item) \
             ORDER BY a.position",
        )
        .bind(annotator)
        .bind(true)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|r| {
                let (direction, step_length) = kind_from_row(r)?;
                Ok(Unfinished {
                    dataset_id: r.try_get("dataset_id")?,
                    dataset: r.try_get("dataset")?,
                    item_id: r.try_get("item_id")?,
                    split: SplitItem {
                        item: r.try_get("id")?,
                        direction,
                        step_length,
                    },
                    mixed: r.try_get("mixed")?,
                })
            })
            .collect()
    })
}

/// The items in each of `annotators`' queues.
pub async fn held_items(
    conn: &mut Conn,
    annotators: &[i64],
) -> Result<HashMap<i64, HashSet<i64>>, sqlx::Error> {
    on!(conn, |c| {
        let mut held = HashMap::new();
        for &annotator in annotators {
            let items: Vec<i64> =
                sqlx::query_scalar("SELECT item FROM assignments WHERE annotator = $1")
                    .bind(annotator)
                    .fetch_all(&mut *c)
                    .await?;
            held.insert(annotator, items.into_iter().collect());
        }
        Ok(held)
    })
}

/// What [`take_unfinished`] took out of a queue.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Taken {
    pub items: Vec<i64>,
    /// Drafts removed with them.
    pub drafts: u64,
}

/// Takes `items` out of the annotator's queue with their drafts, unless finished meanwhile
/// (an answer stays with its assignment). Call inside a transaction.
pub async fn take_unfinished(
    conn: &mut WriteConn,
    annotator: i64,
    items: &[i64],
) -> Result<Taken, sqlx::Error> {
    on!(conn, |c| {
        let mut taken = Taken::default();
        for &item in items {
            let done = sqlx::query(
                "DELETE FROM assignments WHERE annotator = $1 AND item = $2 \
                 AND NOT EXISTS (SELECT 1 FROM annotations n \
                     WHERE n.annotator = $1 AND n.item = $2)",
            )
            .bind(annotator)
            .bind(item)
            .execute(&mut *c)
            .await?;
            if done.rows_affected() == 1 {
                let drafts = sqlx::query("DELETE FROM drafts WHERE annotator = $1 AND item = $2")
                    .bind(annotator)
                    .bind(item)
                    .execute(&mut *c)
                    .await?;
                taken.drafts += drafts.rows_affected();
                taken.items.push(item);
            }
        }
        Ok(taken)
    })
}
