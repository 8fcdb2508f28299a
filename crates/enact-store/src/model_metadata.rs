//! What the hub's own leaderboard rows say about a model on a dataset: its category, family,
//! size and link.

use super::db::{Conn, Fields, WriteConn, on};

/// A model's metadata on a dataset as stored; every field but the model may be empty.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct StoredModelMetadata {
    pub model: String,
    pub category: Option<String>,
    pub family: Option<String>,
    pub size: Option<String>,
    pub link: Option<String>,
    pub updated_by: String,
    pub updated_at: String,
}

/// Writes the model's metadata on the dataset (replacing what was there).
pub async fn put(
    conn: &mut WriteConn,
    dataset_id: i64,
    metadata: &StoredModelMetadata,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("DELETE FROM model_metadata WHERE dataset = $1 AND model = $2")
            .bind(dataset_id)
            .bind(&metadata.model)
            .execute(&mut *c)
            .await?;
        sqlx::query(
            "INSERT INTO model_metadata (dataset, model, category, family, size, link, \
             updated_by) VALUES ($1, $2, $3, $4, $5, $6, $7)",
        )
        .bind(dataset_id)
        .bind(&metadata.model)
        .bind(&metadata.category)
        .bind(&metadata.family)
        .bind(&metadata.size)
        .bind(&metadata.link)
        .bind(&metadata.updated_by)
        .execute(&mut *c)
        .await?;
        Ok(())
    })
}

/// Every model's metadata on the dataset, by model name.
pub async fn of_dataset(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<StoredModelMetadata>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT model, category, family, size, link, updated_by, updated_at \
             FROM model_metadata WHERE dataset = $1 ORDER BY model",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(read).collect()
    })
}

fn read<R: Fields>(r: &R) -> Result<StoredModelMetadata, sqlx::Error> {
    Ok(StoredModelMetadata {
        model: r.try_get("model")?,
        category: r.try_get("category")?,
        family: r.try_get("family")?,
        size: r.try_get("size")?,
        link: r.try_get("link")?,
        updated_by: r.try_get("updated_by")?,
        updated_at: r.try_get("updated_at")?,
    })
}

/// The accounts that submitted `model` to the dataset (listed or not), by name.
pub async fn submitters(
    conn: &mut Conn,
    dataset_id: i64,
    model: &str,
) -> Result<Vec<String>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
            "SELECT DISTINCT a.name FROM submissions s JOIN accounts a ON a.id = s.account \
             WHERE s.dataset = $1 AND s.model = $2 ORDER BY a.name",
        )
        .bind(dataset_id)
        .bind(model)
        .fetch_all(&mut *c)
        .await
    })
}

/// The models submitted to the dataset (listed or not, by any account), by name.
pub async fn submitted_models(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<String>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
            "SELECT DISTINCT model FROM submissions WHERE dataset = $1 ORDER BY model",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await
    })
}
