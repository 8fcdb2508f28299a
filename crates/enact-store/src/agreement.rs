//! What agreement reports read and the protocol writes: a dataset's content hash, every
//! annotator's submitted answers with the kind of assignment behind them, completed primary
//! answers, and the protocol round with its cross-assignments.

use std::collections::HashSet;

use sqlx::QueryBuilder;

use super::db::{Conn, Fields, WriteConn, on};

use super::annotations::human_answer_from_row;
use super::kind_from_row;

use enact_core::agreement::protocol::{PrimaryAnswer, ProtocolPlan};
use enact_core::agreement::report::AnnotatorAnswer;

/// Every answered item of a dataset, per annotator, with the item's ground truth and
/// signatures and the kind of assignment it was answered under; by item, then annotator.
/// Answers on gold items and of annotators excluded from the dataset are left out.
pub async fn annotator_answers(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<AnnotatorAnswer>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT n.annotator, a.name, i.item_id, i.direction, i.step_length, i.gt_answer, \
         n.answer, s.signatures, coalesce(g.kind, 'primary') AS kind \
         FROM annotations n JOIN items i ON i.id = n.item \
         JOIN annotators a ON a.id = n.annotator \
         LEFT JOIN assignments g ON g.annotator = n.annotator AND g.item = n.item \
         LEFT JOIN item_signatures s ON s.item = i.id \
         WHERE i.dataset_id = $1 AND n.outcome = 'answered' \
         AND NOT EXISTS (SELECT 1 FROM gold_items gi WHERE gi.item = n.item) \
         AND NOT EXISTS (SELECT 1 FROM attention_items ti WHERE ti.item = n.item) \
         AND NOT EXISTS (SELECT 1 FROM annotator_exclusions x \
             WHERE x.dataset = i.dataset_id AND x.annotator = n.annotator) \
         ORDER BY i.item_id, n.annotator",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|r| {
                Ok(AnnotatorAnswer {
                    annotator_id: r.try_get("annotator")?,
                    annotator: r.try_get("name")?,
                    item_id: r.try_get("item_id")?,
                    kind: r.try_get("kind")?,
                    human: human_answer_from_row(r)?,
                })
            })
            .collect()
    })
}

/// Completed (answered) primary items of a dataset, gold items aside: what the protocol draws
/// from.
pub async fn primary_answers(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<PrimaryAnswer>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT n.item, n.annotator, i.direction, i.step_length FROM annotations n \
         JOIN items i ON i.id = n.item \
         LEFT JOIN assignments g ON g.annotator = n.annotator AND g.item = n.item \
         WHERE i.dataset_id = $1 AND n.outcome = 'answered' \
         AND coalesce(g.kind, 'primary') = 'primary' \
         AND NOT EXISTS (SELECT 1 FROM gold_items gi WHERE gi.item = n.item) \
         AND NOT EXISTS (SELECT 1 FROM attention_items ti WHERE ti.item = n.item) \
         ORDER BY n.item, n.annotator",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|r| {
                let (direction, step_length) = kind_from_row(r)?;
                Ok(PrimaryAnswer {
                    item: r.try_get("item")?,
                    annotator: r.try_get("annotator")?,
                    direction,
                    step_length,
                })
            })
            .collect()
    })
}

/// Annotators holding primary assignments in a dataset: the protocol's participants.
pub async fn primary_annotators(conn: &mut Conn, dataset_id: i64) -> Result<Vec<i64>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
            "SELECT DISTINCT g.annotator FROM assignments g JOIN items i ON i.id = g.item \
         WHERE i.dataset_id = $1 AND g.kind = 'primary' ORDER BY g.annotator",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await
    })
}

/// A dataset's protocol round as recorded.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct AgreementRound {
    pub items_per_cell: i64,
    pub seed: u64,
    /// Who ran it, when the account still exists.
    pub started_by: Option<String>,
    pub created_at: String,
    pub samples: i64,
    /// Agreement assignments made, and how many of them are answered.
    pub assignments: i64,
    pub answered: i64,
}

pub async fn round(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Option<AgreementRound>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(
            "SELECT r.items_per_cell, r.seed, a.name, r.created_at, \
         (SELECT count(*) FROM agreement_samples s WHERE s.dataset = r.dataset) AS samples, \
         (SELECT count(*) FROM assignments g JOIN items i ON i.id = g.item \
          WHERE i.dataset_id = r.dataset AND g.kind = 'agreement') AS assignments, \
         (SELECT count(*) FROM assignments g JOIN items i ON i.id = g.item \
          JOIN annotations n ON n.annotator = g.annotator AND n.item = g.item \
          WHERE i.dataset_id = r.dataset AND g.kind = 'agreement' \
          AND n.outcome = 'answered') AS answered \
         FROM agreement_rounds r LEFT JOIN annotators a ON a.id = r.started_by \
         WHERE r.dataset = $1",
        )
        .bind(dataset_id)
        .fetch_optional(&mut *c)
        .await?;
        row.map(|r| {
            Ok(AgreementRound {
                items_per_cell: r.try_get("items_per_cell")?,
                // Stored bit for bit in SQLite's signed integer.
                seed: r.try_get::<i64>("seed")? as u64,
                started_by: r.try_get("name")?,
                created_at: r.try_get("created_at")?,
                samples: r.try_get("samples")?,
                assignments: r.try_get("assignments")?,
                answered: r.try_get("answered")?,
            })
        })
        .transpose()
    })
}

/// Rows per multi-row INSERT: at most 4 bound values each, well under either database's limit.
const ROWS_PER_STATEMENT: usize = 1000;

/// Records a protocol round and its cross-assignments, appended to each annotator's queue
/// like any other assignment. Call inside a transaction. Returns the assignments added (a
/// pair already assigned, under either kind, is left as it was). A dataset that already has
/// a round refuses the insert with a violation of
/// [`UniqueKey::AGREEMENT_ROUND`](super::db::UniqueKey::AGREEMENT_ROUND); whether that may
/// happen is the caller's to decide.
pub async fn insert_round(
    conn: &mut WriteConn,
    dataset_id: i64,
    plan: &ProtocolPlan,
    started_by: Option<i64>,
) -> Result<u64, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query(
            "INSERT INTO agreement_rounds (dataset, items_per_cell, seed, started_by) \
         VALUES ($1, $2, $3, $4)",
        )
        .bind(dataset_id)
        .bind(i64::try_from(plan.items_per_cell).unwrap_or(i64::MAX))
        .bind(plan.seed as i64)
        .bind(started_by)
        .execute(&mut *c)
        .await?;
        for chunk in plan.samples.chunks(ROWS_PER_STATEMENT) {
            let mut builder = QueryBuilder::new(
                "INSERT INTO agreement_samples (dataset, item, source_annotator) ",
            );
            builder.push_values(chunk, |mut b, sample| {
                b.push_bind(dataset_id)
                    .push_bind(sample.item)
                    .push_bind(sample.source_annotator);
            });
            builder.build().execute(&mut *c).await?;
        }
        // Each annotator's new items go after the last of its queue, in the plan's order; an
        // item it already has is left where it is. Written a few statements per annotator,
        // not one per assignment: a round of 50 annotators is tens of thousands of rows, and
        // the whole round is one write transaction.
        let mut added = 0;
        for group in plan.assignments.chunk_by(|a, b| a.0 == b.0) {
            let annotator = group[0].0;
            let last: i64 = sqlx::query_scalar(
                "SELECT coalesce(max(position), 0) FROM assignments WHERE annotator = $1",
            )
            .bind(annotator)
            .fetch_one(&mut *c)
            .await?;
            let held: HashSet<i64> =
                sqlx::query_scalar("SELECT item FROM assignments WHERE annotator = $1")
                    .bind(annotator)
                    .fetch_all(&mut *c)
                    .await?
                    .into_iter()
                    .collect();
            let mut seen = HashSet::new();
            let new: Vec<(i64, i64)> = group
                .iter()
                .map(|&(_, item)| item)
                .filter(|item| !held.contains(item) && seen.insert(*item))
                .zip(last + 1..)
                .collect();
            for chunk in new.chunks(ROWS_PER_STATEMENT) {
                let mut builder =
                    QueryBuilder::new("INSERT INTO assignments (annotator, item, position, kind) ");
                builder.push_values(chunk, |mut b, &(item, position)| {
                    b.push_bind(annotator)
                        .push_bind(item)
                        .push_bind(position)
                        .push_bind("agreement");
                });
                builder.push(" ON CONFLICT (annotator, item) DO NOTHING");
                added += builder.build().execute(&mut *c).await?.rows_affected();
            }
        }
        Ok(added)
    })
}
