//! Rows of the audit log.

use super::db::{Conn, Fields, WriteConn, on};

use enact_core::audit::{AuditEntry, AuditFilter, AuditRecord};

/// Writes one entry; call inside the transaction of the action it records.
pub async fn insert(conn: &mut WriteConn, record: &AuditRecord<'_>) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query(
            "INSERT INTO audit_log (actor_kind, actor, action, target, dataset, detail) \
         VALUES ($1, $2, $3, $4, $5, $6)",
        )
        .bind(record.actor.kind())
        .bind(record.actor.name())
        .bind(record.action.as_str())
        .bind(&record.target)
        .bind(record.dataset)
        .bind(&record.detail)
        .execute(&mut *c)
        .await?;
        Ok(())
    })
}

/// Entries matching `filter`, newest first, at most `filter.limit`.
pub async fn list(conn: &mut Conn, filter: &AuditFilter) -> Result<Vec<AuditEntry>, sqlx::Error> {
    on!(conn, |c| {
        let limit = i64::try_from(filter.limit).unwrap_or(i64::MAX);
        let rows = sqlx::query(
            "SELECT id, at, actor_kind, actor, action, target, dataset, detail FROM audit_log \
         WHERE ($1 IS NULL OR action = $1 OR action LIKE $1 || '.%') \
           AND ($2 IS NULL OR actor = $2) \
           AND ($3 IS NULL OR dataset = $3) \
           AND ($4 IS NULL OR at >= $4) \
           AND ($5 IS NULL OR id < $5) \
         ORDER BY id DESC LIMIT $6",
        )
        .bind(filter.action.as_deref())
        .bind(filter.actor.as_deref())
        .bind(filter.dataset.as_deref())
        .bind(filter.since.as_deref())
        .bind(filter.before_id)
        .bind(limit)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|row| {
                Ok(AuditEntry {
                    id: row.try_get("id")?,
                    at: row.try_get("at")?,
                    actor_kind: row.try_get("actor_kind")?,
                    actor: row.try_get("actor")?,
                    action: row.try_get("action")?,
                    target: row.try_get("target")?,
                    dataset: row.try_get("dataset")?,
                    detail: row.try_get("detail")?,
                })
            })
            .collect()
    })
}
