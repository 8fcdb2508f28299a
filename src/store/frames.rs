//! Key-frame images, stored once per distinct PNG content. A row's `png` holds the bytes, or
//! is empty when they are in an object store (`app::frames`).

use sqlx::{Row, SqliteConnection};

/// The id of the frame with this content hash, if stored.
pub async fn id_by_hash(
    conn: &mut SqliteConnection,
    sha256: &str,
) -> Result<Option<i64>, sqlx::Error> {
    sqlx::query_scalar("SELECT id FROM frames WHERE sha256 = ?")
        .bind(sha256)
        .fetch_optional(conn)
        .await
}

/// Stores a frame; `png` empty when its bytes were written to an object store.
pub async fn insert(
    conn: &mut SqliteConnection,
    sha256: &str,
    width: u32,
    height: u32,
    png: &[u8],
) -> Result<i64, sqlx::Error> {
    sqlx::query_scalar(
        "INSERT INTO frames (sha256, width, height, png) VALUES (?, ?, ?, ?) RETURNING id",
    )
    .bind(sha256)
    .bind(width)
    .bind(height)
    .bind(png)
    .fetch_one(conn)
    .await
}

/// A frame: `None` when no frame has this hash; `Some(None)` when its bytes are in an object
/// store (they are not read here); `Some(Some(png))` otherwise.
pub async fn png(
    conn: &mut SqliteConnection,
    sha256: &str,
) -> Result<Option<Option<Vec<u8>>>, sqlx::Error> {
    // length() of a blob does not read it, so a frame held elsewhere costs no blob read.
    sqlx::query_scalar(
        "SELECT CASE WHEN length(png) = 0 THEN NULL ELSE png END FROM frames WHERE sha256 = ?",
    )
    .bind(sha256)
    .fetch_optional(conn)
    .await
}

/// How many frames hold their bytes in the database, and how many elsewhere.
pub async fn count_by_place(conn: &mut SqliteConnection) -> Result<(u64, u64), sqlx::Error> {
    let row = sqlx::query(
        "SELECT COALESCE(SUM(length(png) > 0), 0) AS here, COALESCE(SUM(length(png) = 0), 0) AS elsewhere \
         FROM frames",
    )
    .fetch_one(conn)
    .await?;
    let count = |column: &str| -> Result<u64, sqlx::Error> {
        let n: i64 = row.try_get(column)?;
        u64::try_from(n).map_err(|e| super::corrupt(column, e))
    };
    Ok((count("here")?, count("elsewhere")?))
}

/// Up to `limit` frames whose bytes are in the database: `(sha256, png)`, by id.
pub async fn held_in_database(
    conn: &mut SqliteConnection,
    limit: usize,
) -> Result<Vec<(String, Vec<u8>)>, sqlx::Error> {
    sqlx::query_as("SELECT sha256, png FROM frames WHERE length(png) > 0 ORDER BY id LIMIT ?")
        .bind(i64::try_from(limit).unwrap_or(i64::MAX))
        .fetch_all(conn)
        .await
}

/// Up to `limit` frames whose bytes are elsewhere, with ids above `after_id`: `(id, sha256)`,
/// by id.
pub async fn held_elsewhere(
    conn: &mut SqliteConnection,
    after_id: i64,
    limit: usize,
) -> Result<Vec<(i64, String)>, sqlx::Error> {
    sqlx::query_as(
        "SELECT id, sha256 FROM frames WHERE length(png) = 0 AND id > ? ORDER BY id LIMIT ?",
    )
    .bind(after_id)
    .bind(i64::try_from(limit).unwrap_or(i64::MAX))
    .fetch_all(conn)
    .await
}

/// Drops these frames' bytes from the database (they were written to an object store).
pub async fn drop_bytes(conn: &mut SqliteConnection, hashes: &[&str]) -> Result<(), sqlx::Error> {
    for sha256 in hashes {
        sqlx::query("UPDATE frames SET png = X'' WHERE sha256 = ?")
            .bind(sha256)
            .execute(&mut *conn)
            .await?;
    }
    Ok(())
}

/// Puts a frame's bytes back into the database.
pub async fn restore_bytes(
    conn: &mut SqliteConnection,
    sha256: &str,
    png: &[u8],
) -> Result<(), sqlx::Error> {
    sqlx::query("UPDATE frames SET png = ? WHERE sha256 = ?")
        .bind(png)
        .bind(sha256)
        .execute(conn)
        .await?;
    Ok(())
}
