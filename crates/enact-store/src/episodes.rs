//! Rows of real-world episodes: the episode, its frames in order, and each curator's graphs
//! file (kept as the JSON text the use case validated).

use super::db::{Conn, Dialect, Fields, WriteConn, on};

/// A stored episode.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EpisodeRow {
    pub id: i64,
    pub name: String,
    pub scene: String,
    pub created_by: String,
    pub created_at: String,
    pub frame_count: i64,
    pub resolved_graphs: Option<String>,
    pub resolved_by: Option<String>,
}

/// One frame of an episode, with the hashes of its image and of its filmstrip copy.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EpisodeFrameRow {
    pub position: i64,
    pub file_name: String,
    pub sha256: String,
    pub width: i64,
    pub height: i64,
    pub thumbnail_sha256: String,
}

/// A curator's graphs file of an episode.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CuratorGraphsRow {
    pub curator: String,
    pub graphs: String,
    pub updated_at: String,
}

/// Writes an incomplete episode, its import's claim on the name until `alive_until_ms`. A name
/// in use refuses the insert with a violation of
/// [`UniqueKey::EPISODE_NAME`](super::db::UniqueKey::EPISODE_NAME).
pub async fn insert(
    conn: &mut WriteConn,
    name: &str,
    scene: &str,
    created_by: &str,
    alive_until_ms: i64,
) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
            "INSERT INTO episodes (name, scene, created_by, complete, import_alive_until_ms) \
             VALUES ($1, $2, $3, 0, $4) RETURNING id",
        )
        .bind(name)
        .bind(scene)
        .bind(created_by)
        .bind(alive_until_ms)
        .fetch_one(&mut *c)
        .await
    })
}

/// Extends the claim of an incomplete episode's import to `alive_until_ms`; false when the
/// episode is gone (another import took the name over) or complete.
pub async fn renew_claim(
    conn: &mut WriteConn,
    episode: i64,
    alive_until_ms: i64,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query(
            "UPDATE episodes SET import_alive_until_ms = $2 WHERE id = $1 AND complete = 0",
        )
        .bind(episode)
        .bind(alive_until_ms)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() == 1)
    })
}

/// Marks an episode whose frames are all written complete (pages, lists and exports show it)
/// and ends its import's claim; false when the episode is gone or complete already.
pub async fn mark_complete(conn: &mut WriteConn, episode: i64) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query(
            "UPDATE episodes SET complete = 1, import_alive_until_ms = NULL \
             WHERE id = $1 AND complete = 0",
        )
        .bind(episode)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() == 1)
    })
}

/// An incomplete episode: an import still writing it, or one that was killed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ImportClaim {
    pub episode: i64,
    pub created_by: String,
    pub created_at: String,
    /// Until when its import last said it was alive (none: left before imports said so).
    pub alive_until_ms: Option<i64>,
}

/// The incomplete episode named `name`, if any.
pub async fn incomplete(conn: &mut Conn, name: &str) -> Result<Option<ImportClaim>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(
            "SELECT id, created_by, created_at, import_alive_until_ms FROM episodes \
             WHERE name = $1 AND complete = 0",
        )
        .bind(name)
        .fetch_optional(&mut *c)
        .await?;
        row.map(|r| {
            Ok(ImportClaim {
                episode: r.try_get("id")?,
                created_by: r.try_get("created_by")?,
                created_at: r.try_get("created_at")?,
                alive_until_ms: r.try_get("import_alive_until_ms")?,
            })
        })
        .transpose()
    })
}

/// Deletes an incomplete episode with its frame list (not the frames themselves); a complete
/// one is left as it is.
pub async fn delete_incomplete(conn: &mut WriteConn, episode: i64) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("DELETE FROM episodes WHERE id = $1 AND complete = 0")
            .bind(episode)
            .execute(&mut *c)
            .await?;
        Ok(())
    })
}

/// Writes the frame at `position` of an episode (both frames already stored).
pub async fn insert_frame(
    conn: &mut WriteConn,
    episode: i64,
    position: i64,
    file_name: &str,
    frame: i64,
    thumbnail: i64,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query(
            "INSERT INTO episode_frames (episode, position, file_name, frame, thumbnail) \
             VALUES ($1, $2, $3, $4, $5)",
        )
        .bind(episode)
        .bind(position)
        .bind(file_name)
        .bind(frame)
        .bind(thumbnail)
        .execute(&mut *c)
        .await?;
        Ok(())
    })
}

const EPISODE_COLUMNS: &str = "e.id, e.name, e.scene, e.created_by, e.created_at, \
    e.resolved_graphs, e.resolved_by, \
    (SELECT COUNT(*) FROM episode_frames f WHERE f.episode = e.id) AS frame_count \
    FROM episodes e";

fn episode_row<R: Fields>(row: &R) -> Result<EpisodeRow, sqlx::Error> {
    Ok(EpisodeRow {
        id: row.try_get("id")?,
        name: row.try_get("name")?,
        scene: row.try_get("scene")?,
        created_by: row.try_get("created_by")?,
        created_at: row.try_get("created_at")?,
        frame_count: row.try_get("frame_count")?,
        resolved_graphs: row.try_get("resolved_graphs")?,
        resolved_by: row.try_get("resolved_by")?,
    })
}

/// Every complete episode, by name.
pub async fn list(conn: &mut Conn) -> Result<Vec<EpisodeRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "SELECT {EPISODE_COLUMNS} WHERE e.complete = 1 ORDER BY e.name"
        ))
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(episode_row).collect()
    })
}

/// The complete episode named `name`.
pub async fn by_name(conn: &mut Conn, name: &str) -> Result<Option<EpisodeRow>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(&format!(
            "SELECT {EPISODE_COLUMNS} WHERE e.name = $1 AND e.complete = 1"
        ))
        .bind(name)
        .fetch_optional(&mut *c)
        .await?;
        row.as_ref().map(episode_row).transpose()
    })
}

/// An episode's frames in order.
pub async fn frames(conn: &mut Conn, episode: i64) -> Result<Vec<EpisodeFrameRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT f.position, f.file_name, i.sha256, i.width, i.height, \
             t.sha256 AS thumbnail_sha256 FROM episode_frames f \
             JOIN frames i ON i.id = f.frame JOIN frames t ON t.id = f.thumbnail \
             WHERE f.episode = $1 ORDER BY f.position",
        )
        .bind(episode)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|row| {
                Ok(EpisodeFrameRow {
                    position: row.try_get("position")?,
                    file_name: row.try_get("file_name")?,
                    sha256: row.try_get("sha256")?,
                    width: row.try_get("width")?,
                    height: row.try_get("height")?,
                    thumbnail_sha256: row.try_get("thumbnail_sha256")?,
                })
            })
            .collect()
    })
}

/// Every curator's graphs of an episode, by curator.
pub async fn graphs(conn: &mut Conn, episode: i64) -> Result<Vec<CuratorGraphsRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT curator, graphs, updated_at FROM episode_graphs WHERE episode = $1 \
             ORDER BY curator",
        )
        .bind(episode)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|row| {
                Ok(CuratorGraphsRow {
                    curator: row.try_get("curator")?,
                    graphs: row.try_get("graphs")?,
                    updated_at: row.try_get("updated_at")?,
                })
            })
            .collect()
    })
}

/// Stores (or replaces) a curator's graphs of an episode.
pub async fn set_graphs(
    conn: &mut WriteConn,
    episode: i64,
    curator: &str,
    graphs: &str,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query(&format!(
            "INSERT INTO episode_graphs (episode, curator, graphs) VALUES ($1, $2, $3) \
             ON CONFLICT (episode, curator) \
             DO UPDATE SET graphs = excluded.graphs, updated_at = {}",
            c.utc_now()
        ))
        .bind(episode)
        .bind(curator)
        .bind(graphs)
        .execute(&mut *c)
        .await?;
        Ok(())
    })
}

/// Sets the graphs an episode exports and who chose them.
pub async fn set_resolved(
    conn: &mut WriteConn,
    episode: i64,
    graphs: &str,
    resolved_by: &str,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("UPDATE episodes SET resolved_graphs = $1, resolved_by = $2 WHERE id = $3")
            .bind(graphs)
            .bind(resolved_by)
            .bind(episode)
            .execute(&mut *c)
            .await?;
        Ok(())
    })
}
