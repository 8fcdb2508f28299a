//! Reading items, from memory when they were read before (the item JSON and the
//! annotation item page are the hot paths).

use std::sync::Arc;

use super::refusal::Refusal;
use super::{AppError, Hub, datasets};
use crate::store;
pub use crate::store::items::{ItemFilter, ItemImage, ItemSummary, StoredItem};

/// One page of a dataset's items in import order, and how many items the filter matches.
pub async fn list(
    hub: &Hub,
    dataset: &str,
    filter: &ItemFilter,
    per_page: u32,
    offset: u32,
) -> Result<(Vec<ItemSummary>, i64), AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    Ok(store::items::list(&mut conn, dataset.id, filter, per_page, offset).await?)
}

fn no_item(dataset: &str, item: &str) -> AppError {
    Refusal::NoItem {
        dataset: dataset.to_owned(),
        item: item.to_owned(),
    }
    .into()
}

/// The item a URL names (ground truth included: callers choose what to show), or a 404 that
/// names the dataset or the item.
pub async fn get(hub: &Hub, dataset: &str, item_id: &str) -> Result<Arc<StoredItem>, AppError> {
    if let Some(found) = hub.items().stored(dataset, item_id) {
        return Ok(found);
    }
    // No stored id holds a NUL (PostgreSQL cannot even be asked about one).
    if item_id.contains('\0') {
        return Err(no_item(dataset, &item_id.escape_debug().to_string()));
    }
    let stored = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    let item = store::items::get(&mut conn, stored.id, item_id)
        .await?
        .ok_or_else(|| no_item(dataset, item_id))?;
    let found = Arc::new(item);
    hub.items().insert_stored(dataset, item_id, found.clone());
    Ok(found)
}

/// Store ids of the listed item ids of `dataset`, in the same order; every id not in the
/// dataset is named in one refusal.
pub(super) async fn listed(
    conn: &mut store::Conn,
    dataset: &store::datasets::Dataset,
    item_ids: &[String],
) -> Result<Vec<i64>, AppError> {
    let rows = store::annotations::item_rowids(conn, dataset.id, item_ids).await?;
    let missing: Vec<&str> = item_ids
        .iter()
        .zip(&rows)
        .filter(|(_, row)| row.is_none())
        .map(|(id, _)| id.as_str())
        .collect();
    if !missing.is_empty() {
        return Err(AppError::Invalid(format!(
            "items: not in dataset '{}': {}",
            dataset.name,
            missing.join(", ")
        )));
    }
    Ok(rows.into_iter().flatten().collect())
}
