//! Datasets and their item counts.

use std::collections::BTreeMap;

use super::db::{Conn, Fields, WriteConn, on};
use serde::Serialize;

use enact_core::dataset::{Direction, StepLength};

#[derive(Debug, Clone, Serialize)]
pub struct Dataset {
    pub id: i64,
    pub name: String,
    pub created_at: String,
    pub source: String,
    /// `simulation`, or `real` for items made from an exported real-world episode.
    pub origin: String,
    /// The scene(s) a real-world dataset was recorded in; empty otherwise.
    pub scene: String,
}

/// Item counts of one dataset by direction and step length.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ItemCounts {
    pub total: i64,
    pub forward: i64,
    pub inverse: i64,
    /// `[direction][step length] -> count`; absent cells are 0.
    pub by_kind: BTreeMap<Direction, BTreeMap<StepLength, i64>>,
}

impl ItemCounts {
    pub fn get(&self, direction: Direction, step_length: StepLength) -> i64 {
        self.by_kind
            .get(&direction)
            .and_then(|m| m.get(&step_length))
            .copied()
            .unwrap_or(0)
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct DatasetOverview {
    #[serde(flatten)]
    pub dataset: Dataset,
    pub items: ItemCounts,
    pub tasks: i64,
}

/// Leaves out the hidden rows staged imports write under and the retired rows of replaced
/// datasets (see `store::staged`).
const PUBLISHED: &str = "NOT EXISTS (SELECT 1 FROM staged_imports s WHERE s.staging = datasets.id) \
     AND NOT EXISTS (SELECT 1 FROM retired_datasets r WHERE r.dataset = datasets.id)";

fn dataset_from_row(row: &impl Fields) -> Result<Dataset, sqlx::Error> {
    Ok(Dataset {
        id: row.try_get("id")?,
        name: row.try_get("name")?,
        created_at: row.try_get("created_at")?,
        source: row.try_get("source")?,
        origin: row.try_get("origin")?,
        scene: row.try_get("scene")?,
    })
}

pub async fn by_name(conn: &mut Conn, name: &str) -> Result<Option<Dataset>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(&format!(
            "SELECT id, name, created_at, source, origin, scene FROM datasets WHERE name = $1 AND {PUBLISHED}"
        ))
        .bind(name)
        .fetch_optional(&mut *c)
        .await?;
        row.as_ref().map(dataset_from_row).transpose()
    })
}

/// Every dataset with its item counts, by name.
pub async fn overview(conn: &mut Conn) -> Result<Vec<DatasetOverview>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "SELECT id, name, created_at, source, origin, scene FROM datasets WHERE {PUBLISHED} ORDER BY name"
        ))
        .fetch_all(&mut *c)
        .await?;
        let mut out = Vec::with_capacity(rows.len());
        for row in &rows {
            let dataset = dataset_from_row(row)?;
            let items = counts(&mut *c, dataset.id).await?;
            let tasks: i64 = sqlx::query_scalar(
                "SELECT count(DISTINCT task_name) FROM items WHERE dataset_id = $1",
            )
            .bind(dataset.id)
            .fetch_one(&mut *c)
            .await?;
            out.push(DatasetOverview {
                dataset,
                items,
                tasks,
            });
        }
        Ok(out)
    })
}

pub async fn counts(conn: &mut Conn, dataset_id: i64) -> Result<ItemCounts, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT direction, step_length, count(*) AS n FROM items WHERE dataset_id = $1 \
         GROUP BY direction, step_length",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        let mut counts = ItemCounts::default();
        for row in rows {
            let direction: String = row.try_get("direction")?;
            let step_length: i64 = row.try_get("step_length")?;
            let n: i64 = row.try_get("n")?;
            let (Some(direction), Some(step_length)) = (
                Direction::parse(&direction),
                usize::try_from(step_length).ok().and_then(StepLength::new),
            ) else {
                // The CHECK constraints make this unreachable for rows written by this program.
                continue;
            };
            counts.total += n;
            match direction {
                Direction::Forward => counts.forward += n,
                Direction::Inverse => counts.inverse += n,
            }
            counts
                .by_kind
                .entry(direction)
                .or_default()
                .insert(step_length, n);
        }
        Ok(counts)
    })
}

/// Records where a dataset's items come from (`simulation` or `real`) and the scene.
pub async fn set_origin(
    conn: &mut WriteConn,
    dataset: &str,
    origin: &str,
    scene: &str,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("UPDATE datasets SET origin = $1, scene = $2 WHERE name = $3")
            .bind(origin)
            .bind(scene)
            .bind(dataset)
            .execute(&mut *c)
            .await?;
        Ok(())
    })
}

/// Creates dataset `name` holding copies of the items `item_rows` (row ids in `items`, all of
/// dataset `source`) with their images and signature tables, in the order given; its origin and
/// scene are the source's. Returns the new dataset's id.
pub async fn insert_copy(
    conn: &mut WriteConn,
    source: &Dataset,
    name: &str,
    description: &str,
    item_rows: &[i64],
) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        let dataset: i64 = sqlx::query_scalar(
            "INSERT INTO datasets (name, source, origin, scene) VALUES ($1, $2, $3, $4) \
             RETURNING id",
        )
        .bind(name)
        .bind(description)
        .bind(&source.origin)
        .bind(&source.scene)
        .fetch_one(&mut *c)
        .await?;
        for &row in item_rows {
            let copy: i64 = sqlx::query_scalar(
                "INSERT INTO items (dataset_id, item_id, item_type, direction, step_length, \
                 task_name, key_frame_ids, question, actions, gt_answer, content_hash, \
                 source_line) \
                 SELECT $1, item_id, item_type, direction, step_length, task_name, \
                 key_frame_ids, question, actions, gt_answer, content_hash, source_line \
                 FROM items WHERE id = $2 AND dataset_id = $3 RETURNING id",
            )
            .bind(dataset)
            .bind(row)
            .bind(source.id)
            .fetch_one(&mut *c)
            .await?;
            sqlx::query(
                "INSERT INTO item_images (item, position, path, frame) \
                 SELECT $1, position, path, frame FROM item_images WHERE item = $2",
            )
            .bind(copy)
            .bind(row)
            .execute(&mut *c)
            .await?;
            sqlx::query(
                "INSERT INTO item_signatures (item, source, signatures) \
                 SELECT $1, source, signatures FROM item_signatures WHERE item = $2",
            )
            .bind(copy)
            .bind(row)
            .execute(&mut *c)
            .await?;
        }
        Ok(dataset)
    })
}
