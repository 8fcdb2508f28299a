//! Accounts and API tokens (hashed), and the submission attempts quotas count.

use super::db::{Conn, Dialect, Fields, WriteConn, on};
use schemars::JsonSchema;
use serde::Serialize;

use enact_core::credentials::{NewToken, Role, Scope, scopes_from_text, scopes_to_text};

/// A token as `token list` shows it: never its secret.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct TokenListing {
    pub id: i64,
    pub prefix: String,
    pub account: String,
    pub role: Role,
    pub scopes: String,
    pub daily_quota: Option<i64>,
    pub total_quota: Option<i64>,
    pub created_at: String,
    /// When the token last made a submission attempt (admin tokens: last submission).
    pub last_used_at: Option<String>,
    pub revoked_at: Option<String>,
}

/// The id and role of the account named `name`.
pub async fn account_by_name(
    conn: &mut Conn,
    name: &str,
) -> Result<Option<(i64, Role)>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_as("SELECT id, role FROM accounts WHERE name = $1")
            .bind(name)
            .fetch_optional(&mut *c)
            .await
    })
}

#[tracing::instrument(skip_all)]
pub async fn insert_account(
    conn: &mut WriteConn,
    name: &str,
    role: Role,
) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar("INSERT INTO accounts (name, role) VALUES ($1, $2) RETURNING id")
            .bind(name)
            .bind(role)
            .fetch_one(&mut *c)
            .await
    })
}

#[tracing::instrument(skip_all)]
pub async fn insert_token(
    conn: &mut WriteConn,
    account: i64,
    role: Role,
    token: &NewToken,
    daily_quota: Option<i64>,
    total_quota: Option<i64>,
) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
        "INSERT INTO api_tokens (account, prefix, token_hash, scopes, daily_quota, total_quota) \
         VALUES ($1, $2, $3, $4, $5, $6) RETURNING id",
    )
    .bind(account)
    .bind(&token.prefix)
    .bind(&token.hash)
    .bind(scopes_to_text(role.scopes()))
    .bind(daily_quota)
    .bind(total_quota)
    .fetch_one(&mut *c)
    .await
    })
}

/// A stored token with its account, as found by its public prefix.
#[derive(Debug, Clone)]
pub struct TokenRow {
    pub id: i64,
    pub account_id: i64,
    pub account_name: String,
    pub token_hash: String,
    pub scopes: Vec<Scope>,
    pub daily_quota: Option<i64>,
    pub total_quota: Option<i64>,
    pub revoked: bool,
}

pub async fn token_by_prefix(
    conn: &mut Conn,
    prefix: &str,
) -> Result<Option<TokenRow>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(
            "SELECT t.id, t.account, t.token_hash, t.scopes, t.daily_quota, t.total_quota, \
         t.revoked_at, a.name FROM api_tokens t JOIN accounts a ON a.id = t.account \
         WHERE t.prefix = $1",
        )
        .bind(prefix)
        .fetch_optional(&mut *c)
        .await?;
        row.map(|row| {
            let scopes: String = row.try_get("scopes")?;
            Ok(TokenRow {
                id: row.try_get("id")?,
                account_id: row.try_get("account")?,
                account_name: row.try_get("name")?,
                token_hash: row.try_get("token_hash")?,
                scopes: scopes_from_text(&scopes),
                daily_quota: row.try_get("daily_quota")?,
                total_quota: row.try_get("total_quota")?,
                revoked: row.try_get::<Option<String>>("revoked_at")?.is_some(),
            })
        })
        .transpose()
    })
}

pub async fn list_tokens(conn: &mut Conn) -> Result<Vec<TokenListing>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT t.id, t.prefix, a.name, a.role, t.scopes, t.daily_quota, t.total_quota, \
         t.created_at, t.revoked_at, \
         (SELECT max(c) FROM (SELECT created_at AS c FROM submission_attempts WHERE token = t.id \
          UNION ALL SELECT created_at FROM submissions WHERE token = t.id) AS uses) AS last_used_at \
         FROM api_tokens t JOIN accounts a ON a.id = t.account ORDER BY t.id",
        )
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|row| {
                Ok(TokenListing {
                    id: row.try_get("id")?,
                    prefix: row.try_get("prefix")?,
                    account: row.try_get("name")?,
                    role: row.try_get("role")?,
                    scopes: row.try_get("scopes")?,
                    daily_quota: row.try_get("daily_quota")?,
                    total_quota: row.try_get("total_quota")?,
                    created_at: row.try_get("created_at")?,
                    last_used_at: row.try_get("last_used_at")?,
                    revoked_at: row.try_get("revoked_at")?,
                })
            })
            .collect()
    })
}

/// Revokes the token with this id or prefix. Returns whether a live token was revoked.
#[tracing::instrument(skip_all)]
pub async fn revoke_token(conn: &mut WriteConn, which: &str) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let id: Option<i64> = which.parse().ok();
        let done = sqlx::query(&format!(
            "UPDATE api_tokens SET revoked_at = {} \
         WHERE (id = $1 OR prefix = $2) AND revoked_at IS NULL",
            c.utc_now()
        ))
        .bind(id)
        .bind(which)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() > 0)
    })
}

/// Whether any live admin token exists.
pub async fn has_admin_token(conn: &mut Conn) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let n: i64 = sqlx::query_scalar(
            "SELECT count(*) FROM api_tokens t JOIN accounts a ON a.id = t.account \
         WHERE a.role = 'admin' AND t.revoked_at IS NULL",
        )
        .fetch_one(&mut *c)
        .await?;
        Ok(n > 0)
    })
}

/// Whether a token with this hash is stored (revoked or not).
pub async fn token_hash_exists(conn: &mut Conn, hash: &str) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let n: i64 = sqlx::query_scalar("SELECT count(*) FROM api_tokens WHERE token_hash = $1")
            .bind(hash)
            .fetch_one(&mut *c)
            .await?;
        Ok(n > 0)
    })
}

/// A token's submission attempts so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AttemptsMade {
    /// Since midnight UTC.
    pub today: i64,
    pub total: i64,
}

/// How many attempts `token` has made, today and in all.
pub async fn attempts_made(conn: &mut Conn, token: i64) -> Result<AttemptsMade, sqlx::Error> {
    on!(conn, |c| {
        let today = c.utc_today();
        let (today, total): (i64, i64) = sqlx::query_as(&format!(
            "SELECT CAST(coalesce(sum(CASE WHEN created_at >= {today} THEN 1 ELSE 0 END), 0) \
             AS BIGINT), count(*) FROM submission_attempts WHERE token = $1"
        ))
        .bind(token)
        .fetch_one(&mut *c)
        .await?;
        Ok(AttemptsMade { today, total })
    })
}

/// Records one submission attempt by `token`; returns its id.
#[tracing::instrument(skip_all)]
pub async fn record_attempt(conn: &mut WriteConn, token: i64) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar("INSERT INTO submission_attempts (token) VALUES ($1) RETURNING id")
            .bind(token)
            .fetch_one(&mut *c)
            .await
    })
}

/// Forgets the attempt `id` (one the server could not take on).
pub async fn forget_attempt(conn: &mut WriteConn, id: i64) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("DELETE FROM submission_attempts WHERE id = $1")
            .bind(id)
            .execute(&mut *c)
            .await?;
        Ok(())
    })
}
