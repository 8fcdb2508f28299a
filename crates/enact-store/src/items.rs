//! Items of a dataset: listing with filters, one item with its images, and import writes.

use std::collections::HashMap;

use super::db::{Conn, Dialect, Fields, WriteConn, on};

use super::{corrupt, kind_from_row};

use enact_core::dataset::{Direction, QaItem, StepLength};
use enact_core::scoring::ScoringItem;
use enact_core::semantics::SignatureSource;

/// What a list of items shows of each one.
#[derive(Debug, Clone)]
pub struct ItemSummary {
    pub item_id: String,
    pub item_type: String,
    pub direction: Direction,
    pub step_length: StepLength,
    pub task_name: String,
}

#[derive(Debug, Clone)]
pub struct ItemImage {
    /// Index in the record's `images` list (0 = current state).
    pub position: usize,
    pub path: String,
    pub sha256: String,
}

impl ItemImage {
    pub fn label(&self) -> String {
        QaItem::image_label(self.position)
    }
}

/// One stored item, ground truth included: web handlers choose what to show of it.
#[derive(Debug, Clone)]
pub struct StoredItem {
    /// The row id in `items`.
    pub rowid: i64,
    pub summary: ItemSummary,
    pub key_frame_ids: Vec<String>,
    pub question: String,
    pub actions: Vec<String>,
    pub images: Vec<ItemImage>,
    pub gt_answer: Vec<u8>,
}

#[derive(Debug, Clone, Default)]
pub struct ItemFilter {
    pub direction: Option<Direction>,
    pub step_length: Option<StepLength>,
    pub task: Option<String>,
}

fn summary_from_row(row: &impl Fields) -> Result<ItemSummary, sqlx::Error> {
    let (direction, step_length) = kind_from_row(row)?;
    Ok(ItemSummary {
        item_id: row.try_get("item_id")?,
        item_type: row.try_get("item_type")?,
        direction,
        step_length,
        task_name: row.try_get("task_name")?,
    })
}

pub(super) fn json_column<T: serde::de::DeserializeOwned>(
    row: &impl Fields,
    column: &str,
) -> Result<T, sqlx::Error> {
    let text: String = row.try_get(column)?;
    serde_json::from_str(&text).map_err(|e| corrupt(column, e))
}

const FILTER: &str = "dataset_id = $1 AND ($2 IS NULL OR direction = $2) \
                      AND ($3 IS NULL OR step_length = $3) AND ($4 IS NULL OR task_name = $4)";

/// One page of a dataset's items in import order, and the number of items the filter matches.
pub async fn list(
    conn: &mut Conn,
    dataset_id: i64,
    filter: &ItemFilter,
    limit: u32,
    offset: u32,
) -> Result<(Vec<ItemSummary>, i64), sqlx::Error> {
    on!(conn, |c| {
        let direction = filter.direction.map(Direction::as_str);
        let step_length = filter.step_length.map(StepLength::get);
        let total: i64 = sqlx::query_scalar(&format!("SELECT count(*) FROM items WHERE {FILTER}"))
            .bind(dataset_id)
            .bind(direction)
            .bind(step_length.map(i64::from))
            .bind(filter.task.as_deref())
            .fetch_one(&mut *c)
            .await?;
        let rows = sqlx::query(&format!(
            "SELECT item_id, item_type, direction, step_length, task_name FROM items \
         WHERE {FILTER} ORDER BY id LIMIT $5 OFFSET $6"
        ))
        .bind(dataset_id)
        .bind(direction)
        .bind(step_length.map(i64::from))
        .bind(filter.task.as_deref())
        .bind(i64::from(limit))
        .bind(i64::from(offset))
        .fetch_all(&mut *c)
        .await?;
        let items = rows
            .iter()
            .map(summary_from_row)
            .collect::<Result<Vec<_>, _>>()?;
        Ok((items, total))
    })
}

/// Every item's activity (`task_name`), by item id.
pub async fn activities(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<(String, String)>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query("SELECT item_id, task_name FROM items WHERE dataset_id = $1")
            .bind(dataset_id)
            .fetch_all(&mut *c)
            .await?;
        rows.iter()
            .map(|row| Ok((row.try_get("item_id")?, row.try_get("task_name")?)))
            .collect()
    })
}

/// Every item of a dataset with its row id, in import order (the explorer's grid).
pub async fn summaries(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<(i64, ItemSummary)>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT id, item_id, item_type, direction, step_length, task_name FROM items \
             WHERE dataset_id = $1 ORDER BY id",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|row| Ok((row.try_get("id")?, summary_from_row(row)?)))
            .collect()
    })
}

/// The distinct task names of a dataset, sorted.
pub async fn task_names(conn: &mut Conn, dataset_id: i64) -> Result<Vec<String>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
            "SELECT DISTINCT task_name FROM items WHERE dataset_id = $1 ORDER BY task_name",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await
    })
}

pub async fn get(
    conn: &mut Conn,
    dataset_id: i64,
    item_id: &str,
) -> Result<Option<StoredItem>, sqlx::Error> {
    on!(conn, |c| {
        let Some(row) = sqlx::query(
            "SELECT id, item_id, item_type, direction, step_length, task_name, key_frame_ids, \
         question, actions, gt_answer FROM items WHERE dataset_id = $1 AND item_id = $2",
        )
        .bind(dataset_id)
        .bind(item_id)
        .fetch_optional(&mut *c)
        .await?
        else {
            return Ok(None);
        };
        let rowid: i64 = row.try_get("id")?;
        let images = sqlx::query(
            "SELECT ii.position, ii.path, f.sha256 FROM item_images ii \
         JOIN frames f ON f.id = ii.frame WHERE ii.item = $1 ORDER BY ii.position",
        )
        .bind(rowid)
        .fetch_all(&mut *c)
        .await?
        .iter()
        .map(|r| {
            let position: i64 = r.try_get("position")?;
            Ok(ItemImage {
                position: usize::try_from(position).map_err(|e| corrupt("position", e))?,
                path: r.try_get("path")?,
                sha256: r.try_get("sha256")?,
            })
        })
        .collect::<Result<Vec<_>, sqlx::Error>>()?;
        Ok(Some(StoredItem {
            rowid,
            summary: summary_from_row(&row)?,
            key_frame_ids: json_column(&row, "key_frame_ids")?,
            question: row.try_get("question")?,
            actions: json_column(&row, "actions")?,
            images,
            gt_answer: json_column(&row, "gt_answer")?,
        }))
    })
}

/// `item_id -> content_hash` for every item of a dataset.
pub async fn content_hashes(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<HashMap<String, String>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query("SELECT item_id, content_hash FROM items WHERE dataset_id = $1")
            .bind(dataset_id)
            .fetch_all(&mut *c)
            .await?;
        rows.iter()
            .map(|r| Ok((r.try_get("item_id")?, r.try_get("content_hash")?)))
            .collect()
    })
}

/// Writes one item and links its images; `frame_ids[i]` is the stored frame of `item.images[i]`.
pub async fn insert(
    conn: &mut WriteConn,
    dataset_id: i64,
    item: &QaItem,
    content_hash: &str,
    source_line: usize,
    frame_ids: &[i64],
) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        let rowid: i64 = sqlx::query_scalar(
            "INSERT INTO items (dataset_id, item_id, item_type, direction, step_length, task_name, \
         key_frame_ids, question, actions, gt_answer, content_hash, source_line) \
         VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12) RETURNING id",
        )
        .bind(dataset_id)
        .bind(&item.id)
        .bind(&item.item_type)
        .bind(item.direction.as_str())
        .bind(i64::from(item.step_length.get()))
        .bind(&item.task_name)
        .bind(json_list(&item.key_frame_ids))
        .bind(&item.question)
        .bind(json_list(&item.actions))
        .bind(json_list(&item.gt_answer))
        .bind(content_hash)
        .bind(i64::try_from(source_line).unwrap_or(i64::MAX))
        .fetch_one(&mut *c)
        .await?;
        for (position, (path, frame)) in item.images.iter().zip(frame_ids).enumerate() {
            sqlx::query(
                "INSERT INTO item_images (item, position, path, frame) VALUES ($1, $2, $3, $4)",
            )
            .bind(rowid)
            .bind(position as i64)
            .bind(path)
            .bind(frame)
            .execute(&mut *c)
            .await?;
        }
        Ok(rowid)
    })
}

/// Lists of strings or small integers always serialise; the fallback is never taken.
fn json_list<T: serde::Serialize>(list: &[T]) -> String {
    serde_json::to_string(list).unwrap_or_else(|_| "[]".to_owned())
}

/// The stored signature source and table (JSON) of an item, if any.
pub async fn semantics_json(
    conn: &mut Conn,
    dataset_id: i64,
    item_id: &str,
) -> Result<Option<(SignatureSource, String)>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(
            "SELECT s.source, s.signatures FROM item_signatures s JOIN items i ON i.id = s.item \
         WHERE i.dataset_id = $1 AND i.item_id = $2",
        )
        .bind(dataset_id)
        .bind(item_id)
        .fetch_optional(&mut *c)
        .await?;
        row.map(|r| Ok((r.try_get("source")?, r.try_get("signatures")?)))
            .transpose()
    })
}

/// Stores (or replaces) an item's signature table.
pub async fn set_semantics(
    conn: &mut WriteConn,
    dataset_id: i64,
    item_id: &str,
    source: SignatureSource,
    signatures_json: &str,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query(
        "INSERT INTO item_signatures (item, source, signatures) \
         SELECT id, $1, $2 FROM items WHERE dataset_id = $3 AND item_id = $4 \
         ON CONFLICT (item) DO UPDATE SET source = excluded.source, signatures = excluded.signatures",
    )
    .bind(source)
    .bind(signatures_json)
    .bind(dataset_id)
    .bind(item_id)
    .execute(&mut *c)
    .await?;
        Ok(())
    })
}

/// Everything scoring needs of every item of a dataset, in import order.
pub async fn scoring_items(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<ScoringItem>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
        "SELECT i.id AS row_id, i.item_id, i.item_type, i.direction, i.step_length, i.task_name, \
         i.key_frame_ids, i.gt_answer, s.source, s.signatures \
         FROM items i LEFT JOIN item_signatures s ON s.item = i.id \
         WHERE i.dataset_id = $1 ORDER BY i.id",
    )
    .bind(dataset_id)
    .fetch_all(&mut *c)
    .await?;
        rows.iter()
            .map(|row| {
                let summary = summary_from_row(row)?;
                let source: Option<String> = row.try_get("source")?;
                let signatures: Option<String> = row.try_get("signatures")?;
                Ok(ScoringItem {
                    row_id: row.try_get("row_id")?,
                    item_id: summary.item_id,
                    item_type: summary.item_type,
                    direction: summary.direction,
                    step_length: summary.step_length,
                    task_name: summary.task_name,
                    key_frame_ids: json_column(row, "key_frame_ids")?,
                    gt_answer: json_column(row, "gt_answer")?,
                    semantics: source.zip(signatures),
                })
            })
            .collect()
    })
}

/// Every item of a dataset as its release line needs it, in file order, each with its row id
/// in `items`. Ground truth included: the caller decides whether to write it.
pub async fn release_items(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<(i64, enact_core::release::ReleaseItem)>, sqlx::Error> {
    on!(conn, |c| {
        let mut paths: HashMap<i64, Vec<String>> = HashMap::new();
        let image_rows = sqlx::query(
            "SELECT ii.item, ii.path FROM item_images ii JOIN items i ON i.id = ii.item \
         WHERE i.dataset_id = $1 ORDER BY ii.item, ii.position",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        for row in &image_rows {
            paths
                .entry(row.try_get("item")?)
                .or_default()
                .push(row.try_get("path")?);
        }
        let rows = sqlx::query(
            "SELECT id, item_id, item_type, task_name, key_frame_ids, question, gt_answer \
         FROM items WHERE dataset_id = $1 ORDER BY source_line, id",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|row| {
                let row_id: i64 = row.try_get("id")?;
                Ok((
                    row_id,
                    enact_core::release::ReleaseItem {
                        id: row.try_get("item_id")?,
                        item_type: row.try_get("item_type")?,
                        task_name: row.try_get("task_name")?,
                        key_frame_ids: json_column(row, "key_frame_ids")?,
                        images: paths.remove(&row_id).unwrap_or_default(),
                        question: row.try_get("question")?,
                        gt_answer: json_column(row, "gt_answer")?,
                    },
                ))
            })
            .collect()
    })
}

/// The image files of the items with these row ids: `(path, sha256, PNG bytes)`, item by item
/// in row-id order, each item's images in position order. The bytes are `None` for a frame
/// held in an object store.
pub async fn release_images(
    conn: &mut Conn,
    item_rows: &[i64],
) -> Result<Vec<(String, String, Option<Vec<u8>>)>, sqlx::Error> {
    on!(conn, |c| {
        let ids = serde_json::to_string(item_rows).map_err(|e| corrupt("item", e))?;
        sqlx::query_as(&format!(
            "SELECT ii.path, f.sha256, CASE WHEN length(f.png) = 0 THEN NULL ELSE f.png END \
         FROM item_images ii JOIN frames f ON f.id = ii.frame \
         WHERE ii.item IN ({}) ORDER BY ii.item, ii.position",
            c.json_ids()
        ))
        .bind(ids)
        .fetch_all(&mut *c)
        .await
    })
}
