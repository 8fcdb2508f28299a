//! Curators' drafts of an episode's graphs: the editor's latest state, one row per curator.

use super::db::{Conn, WriteConn, on};

/// Writes `curator`'s draft of episode `episode_id` (the graphs file as JSON), replacing the
/// one before.
pub async fn save(
    conn: &mut WriteConn,
    episode_id: i64,
    curator: &str,
    graphs: &str,
    now_ms: i64,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query(
            "INSERT INTO episode_drafts (episode, curator, graphs, updated_at_ms) \
             VALUES ($1, $2, $3, $4) \
             ON CONFLICT (episode, curator) DO UPDATE SET graphs = excluded.graphs, \
             updated_at_ms = excluded.updated_at_ms",
        )
        .bind(episode_id)
        .bind(curator)
        .bind(graphs)
        .bind(now_ms)
        .execute(&mut *c)
        .await?;
        Ok(())
    })
}

/// `curator`'s draft of episode `episode_id`, as stored (JSON).
pub async fn get(
    conn: &mut Conn,
    episode_id: i64,
    curator: &str,
) -> Result<Option<String>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar("SELECT graphs FROM episode_drafts WHERE episode = $1 AND curator = $2")
            .bind(episode_id)
            .bind(curator)
            .fetch_optional(&mut *c)
            .await
    })
}

/// Removes `curator`'s draft of episode `episode_id`, if any.
pub async fn remove(
    conn: &mut WriteConn,
    episode_id: i64,
    curator: &str,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("DELETE FROM episode_drafts WHERE episode = $1 AND curator = $2")
            .bind(episode_id)
            .bind(curator)
            .execute(&mut *c)
            .await?;
        Ok(())
    })
}
