//! Signed statements: the hub's public signing keys and the envelopes signed with them. The
//! secret keys are never stored here (`app::signing` keeps them in a key file).

use std::path::PathBuf;

use super::db::{Conn, Dialect, Fields, Pool, WriteConn, on};

/// One public key the hub signed (or signs) with.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct KeyRow {
    pub keyid: String,
    pub algorithm: String,
    /// Base64 of the 32 raw public-key bytes.
    pub public_key: String,
    pub created_at: String,
    pub retired_at: Option<String>,
}

const KEY_COLUMNS: &str = "keyid, algorithm, public_key, created_at, retired_at";

fn key_from_row(row: &impl Fields) -> Result<KeyRow, sqlx::Error> {
    Ok(KeyRow {
        keyid: row.try_get("keyid")?,
        algorithm: row.try_get("algorithm")?,
        public_key: row.try_get("public_key")?,
        created_at: row.try_get("created_at")?,
        retired_at: row.try_get("retired_at")?,
    })
}

/// Every key, in the order they were listed (oldest first).
pub async fn keys(conn: &mut Conn) -> Result<Vec<KeyRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "SELECT {KEY_COLUMNS} FROM signing_keys ORDER BY id"
        ))
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(key_from_row).collect()
    })
}

/// The key `keyid`, if listed.
pub async fn key(conn: &mut Conn, keyid: &str) -> Result<Option<KeyRow>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(&format!(
            "SELECT {KEY_COLUMNS} FROM signing_keys WHERE keyid = $1"
        ))
        .bind(keyid)
        .fetch_optional(&mut *c)
        .await?;
        row.as_ref().map(key_from_row).transpose()
    })
}

/// Lists a public key (created now); `false` when it was listed already.
#[tracing::instrument(skip_all)]
pub async fn insert_key(
    conn: &mut WriteConn,
    keyid: &str,
    algorithm: &str,
    public_key: &str,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query(&format!(
            "INSERT INTO signing_keys (keyid, algorithm, public_key, created_at) \
             VALUES ($1, $2, $3, {}) ON CONFLICT (keyid) DO NOTHING",
            c.utc_now()
        ))
        .bind(keyid)
        .bind(algorithm)
        .bind(public_key)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() > 0)
    })
}

/// Retires every listed key but `keyid` (now); returns the ids retired.
#[tracing::instrument(skip_all)]
pub async fn retire_all_but(conn: &mut WriteConn, keyid: &str) -> Result<Vec<String>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(&format!(
            "UPDATE signing_keys SET retired_at = {} \
             WHERE keyid <> $1 AND retired_at IS NULL RETURNING keyid",
            c.utc_now()
        ))
        .bind(keyid)
        .fetch_all(&mut *c)
        .await
    })
}

/// A stored statement.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StatementRow {
    pub id: i64,
    pub submission: i64,
    pub keyid: String,
    /// The DSSE envelope, JSON text.
    pub envelope: String,
    pub made_at: String,
}

/// Stores a statement about `submission`.
#[tracing::instrument(skip_all)]
pub async fn insert_statement(
    conn: &mut WriteConn,
    submission: i64,
    keyid: &str,
    envelope: &str,
    made_at: &str,
) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
            "INSERT INTO submission_statements (submission, keyid, envelope, made_at) \
             VALUES ($1, $2, $3, $4) RETURNING id",
        )
        .bind(submission)
        .bind(keyid)
        .bind(envelope)
        .bind(made_at)
        .fetch_one(&mut *c)
        .await
    })
}

/// The newest statement about `submission`, if one was made.
pub async fn newest_statement(
    conn: &mut Conn,
    submission: i64,
) -> Result<Option<StatementRow>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(
            "SELECT id, submission, keyid, envelope, made_at FROM submission_statements \
             WHERE submission = $1 ORDER BY id DESC LIMIT 1",
        )
        .bind(submission)
        .fetch_optional(&mut *c)
        .await?;
        row.as_ref()
            .map(|r| {
                Ok(StatementRow {
                    id: r.try_get("id")?,
                    submission: r.try_get("submission")?,
                    keyid: r.try_get("keyid")?,
                    envelope: r.try_get("envelope")?,
                    made_at: r.try_get("made_at")?,
                })
            })
            .transpose()
    })
}

/// The file a SQLite pool's database lives in (none for PostgreSQL or an in-memory database).
pub fn database_file(pool: &Pool) -> Option<PathBuf> {
    match pool {
        Pool::Pg(_) => None,
        Pool::Sqlite(p) => {
            let options = p.connect_options();
            let file = options.get_filename();
            let text = file.to_string_lossy();
            if text.is_empty() || text == ":memory:" || text.starts_with("file:") {
                None
            } else {
                Some(file.to_path_buf())
            }
        }
    }
}
