//! Key-frame images, stored once per distinct PNG content.

use sqlx::SqliteConnection;

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

/// The PNG bytes of a frame.
pub async fn png(
    conn: &mut SqliteConnection,
    sha256: &str,
) -> Result<Option<Vec<u8>>, sqlx::Error> {
    sqlx::query_scalar("SELECT png FROM frames WHERE sha256 = ?")
        .bind(sha256)
        .fetch_optional(conn)
        .await
}
