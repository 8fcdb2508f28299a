//! The audit log: each audited use case writes its entry with [`record`] inside its own
//! transaction, so an action and its entry land together or not at all.

use super::{AppError, Hub};
use crate::core::audit::{Actor, AuditAction, AuditEntry, AuditFilter, AuditRecord};
use crate::store;

/// Writes the entry for `action` by `actor` on `target`.
pub async fn record(
    conn: &mut store::Tx,
    actor: &Actor,
    action: AuditAction,
    target: impl Into<String>,
    dataset: Option<&str>,
    detail: impl Into<String>,
) -> Result<(), AppError> {
    let record = AuditRecord {
        actor,
        action,
        target: target.into(),
        dataset,
        detail: detail.into(),
    };
    store::audit::insert(conn, &record).await?;
    Ok(())
}

/// Every entry that concerns `dataset`, newest first (for report bundles).
pub async fn of_dataset(hub: &Hub, dataset: &str) -> Result<Vec<AuditEntry>, AppError> {
    let filter = AuditFilter {
        dataset: Some(dataset.to_owned()),
        limit: usize::MAX,
        ..AuditFilter::default()
    };
    let mut conn = hub.conn().await?;
    Ok(store::audit::list(&mut conn, &filter).await?)
}

/// Entries matching `filter`, newest first; a filter value that cannot match is refused with
/// the field it is in.
pub async fn list(hub: &Hub, filter: AuditFilter) -> Result<Vec<AuditEntry>, AppError> {
    let filter = filter.checked().map_err(AppError::Invalid)?;
    let mut conn = hub.conn().await?;
    Ok(store::audit::list(&mut conn, &filter).await?)
}
