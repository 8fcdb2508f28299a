//! Key-frame images, stored once per distinct PNG content. A row's `png` holds the bytes, or
//! is empty when they are in an object store (`app::frames`).

use super::db::{Conn, Fields, WriteConn, on};

/// The id of the frame with this content hash, if stored.
pub async fn id_by_hash(conn: &mut Conn, sha256: &str) -> Result<Option<i64>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar("SELECT id FROM frames WHERE sha256 = $1")
            .bind(sha256)
            .fetch_optional(&mut *c)
            .await
    })
}

/// Stores a frame; `png` empty when its bytes were written to an object store.
pub async fn insert(
    conn: &mut WriteConn,
    sha256: &str,
    width: u32,
    height: u32,
    png: &[u8],
) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
            "INSERT INTO frames (sha256, width, height, png) VALUES ($1, $2, $3, $4) RETURNING id",
        )
        .bind(sha256)
        .bind(i64::from(width))
        .bind(i64::from(height))
        .bind(png)
        .fetch_one(&mut *c)
        .await
    })
}

/// A frame: `None` when no frame has this hash; `Some(None)` when its bytes are in an object
/// store (they are not read here); `Some(Some(png))` otherwise.
pub async fn png(conn: &mut Conn, sha256: &str) -> Result<Option<Option<Vec<u8>>>, sqlx::Error> {
    on!(conn, |c| {
        // length() of a blob does not read it, so a frame held elsewhere costs no blob read.
        sqlx::query_scalar(
            "SELECT CASE WHEN length(png) = 0 THEN NULL ELSE png END FROM frames WHERE sha256 = $1",
        )
        .bind(sha256)
        .fetch_optional(&mut *c)
        .await
    })
}

/// How many frames hold their bytes in the database, and how many elsewhere.
pub async fn count_by_place(conn: &mut Conn) -> Result<(u64, u64), sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(
            "SELECT \
             CAST(COALESCE(SUM(CASE WHEN length(png) > 0 THEN 1 ELSE 0 END), 0) AS BIGINT) AS here, \
             CAST(COALESCE(SUM(CASE WHEN length(png) = 0 THEN 1 ELSE 0 END), 0) AS BIGINT) \
             AS elsewhere FROM frames",
        )
        .fetch_one(&mut *c)
        .await?;
        let count = |column: &str| -> Result<u64, sqlx::Error> {
            let n: i64 = row.try_get(column)?;
            u64::try_from(n).map_err(|e| super::corrupt(column, e))
        };
        Ok((count("here")?, count("elsewhere")?))
    })
}

/// Up to `limit` frames whose bytes are in the database: `(sha256, png)`, by id.
pub async fn held_in_database(
    conn: &mut Conn,
    limit: usize,
) -> Result<Vec<(String, Vec<u8>)>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_as("SELECT sha256, png FROM frames WHERE length(png) > 0 ORDER BY id LIMIT $1")
            .bind(i64::try_from(limit).unwrap_or(i64::MAX))
            .fetch_all(&mut *c)
            .await
    })
}

/// Up to `limit` frames whose bytes are elsewhere, with ids above `after_id`: `(id, sha256)`,
/// by id.
pub async fn held_elsewhere(
    conn: &mut Conn,
    after_id: i64,
    limit: usize,
) -> Result<Vec<(i64, String)>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_as(
            "SELECT id, sha256 FROM frames WHERE length(png) = 0 AND id > $1 ORDER BY id LIMIT $2",
        )
        .bind(after_id)
        .bind(i64::try_from(limit).unwrap_or(i64::MAX))
        .fetch_all(&mut *c)
        .await
    })
}

/// Drops these frames' bytes from the database (they were written to an object store).
pub async fn drop_bytes(conn: &mut WriteConn, hashes: &[&str]) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        for sha256 in hashes {
            sqlx::query("UPDATE frames SET png = $1 WHERE sha256 = $2")
                .bind(&[] as &[u8])
                .bind(sha256)
                .execute(&mut *c)
                .await?;
        }
        Ok(())
    })
}

/// Puts a frame's bytes back into the database.
pub async fn restore_bytes(
    conn: &mut WriteConn,
    sha256: &str,
    png: &[u8],
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("UPDATE frames SET png = $1 WHERE sha256 = $2")
            .bind(png)
            .bind(sha256)
            .execute(&mut *c)
            .await?;
        Ok(())
    })
}
