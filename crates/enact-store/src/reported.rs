//! Results a paper published, attached to a dataset: one row per model and source, its cells
//! stored as JSON and read back into [`ReportedModel`].

use std::collections::BTreeMap;

use super::db::{Conn, Fields, WriteConn, on};
use enact_core::paper::{Category, CellKey, ReportedModel};

/// A reported result as stored.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredReported {
    pub id: i64,
    pub reported: ReportedModel,
    /// The actor who entered it, as the audit log writes it.
    pub added_by: String,
    pub added_at: String,
}

/// Stores `reported` on the dataset; its id. A row with the same model and source must not be
/// there (the key `reported_results_model_source`).
pub async fn insert(
    conn: &mut WriteConn,
    dataset_id: i64,
    reported: &ReportedModel,
    added_by: &str,
) -> Result<i64, sqlx::Error> {
    let task = cells_text(&reported.task_accuracy)?;
    let pairwise = cells_text(&reported.pairwise_accuracy)?;
    on!(conn, |c| {
        sqlx::query_scalar(
            "INSERT INTO reported_results (dataset, model, source, category, family, size, \
             task_accuracy, pairwise_accuracy, added_by) \
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9) RETURNING id",
        )
        .bind(dataset_id)
        .bind(&reported.model)
        .bind(&reported.source)
        .bind(reported.category.as_str())
        .bind(&reported.family)
        .bind(&reported.size)
        .bind(&task)
        .bind(&pairwise)
        .bind(added_by)
        .fetch_one(&mut *c)
        .await
    })
}

/// Removes the dataset's row of `model` from `source`; whether there was one.
pub async fn delete_by_key(
    conn: &mut WriteConn,
    dataset_id: i64,
    model: &str,
    source: &str,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query(
            "DELETE FROM reported_results WHERE dataset = $1 AND model = $2 AND source = $3",
        )
        .bind(dataset_id)
        .bind(model)
        .bind(source)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() > 0)
    })
}

/// Removes the dataset's row `id`; whether there was one.
pub async fn delete(conn: &mut WriteConn, dataset_id: i64, id: i64) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query("DELETE FROM reported_results WHERE dataset = $1 AND id = $2")
            .bind(dataset_id)
            .bind(id)
            .execute(&mut *c)
            .await?;
        Ok(done.rows_affected() > 0)
    })
}

/// The dataset's reported results, in the order they were entered.
pub async fn of_dataset(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<StoredReported>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT id, model, source, category, family, size, task_accuracy, \
             pairwise_accuracy, added_by, created_at FROM reported_results \
             WHERE dataset = $1 ORDER BY id",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(read).collect()
    })
}

fn read<R: Fields>(r: &R) -> Result<StoredReported, sqlx::Error> {
    let category: String = r.try_get("category")?;
    Ok(StoredReported {
        id: r.try_get("id")?,
        reported: ReportedModel {
            model: r.try_get("model")?,
            category: Category::new(&category).map_err(|e| decode("category", e))?,
            family: r.try_get("family")?,
            size: r.try_get("size")?,
            source: r.try_get("source")?,
            task_accuracy: cells(&r.try_get::<String>("task_accuracy")?, "task_accuracy")?,
            pairwise_accuracy: cells(
                &r.try_get::<String>("pairwise_accuracy")?,
                "pairwise_accuracy",
            )?,
        },
        added_by: r.try_get("added_by")?,
        added_at: r.try_get("created_at")?,
    })
}

fn cells_text(cells: &BTreeMap<CellKey, f64>) -> Result<String, sqlx::Error> {
    serde_json::to_string(cells).map_err(|e| sqlx::Error::Encode(Box::new(e)))
}

fn cells(text: &str, column: &str) -> Result<BTreeMap<CellKey, f64>, sqlx::Error> {
    serde_json::from_str(text).map_err(|e| decode(column, e))
}

fn decode(column: &str, e: impl std::fmt::Display) -> sqlx::Error {
    sqlx::Error::ColumnDecode {
        index: column.to_owned(),
        source: e.to_string().into(),
    }
}
