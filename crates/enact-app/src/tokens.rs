//! API tokens and the accounts behind them: issuing, listing and revoking tokens, the admin
//! token a server starts with, and who a presented token stands for.

use schemars::JsonSchema;
use serde::Serialize;

use super::audit;
use super::metrics::LoginFailure;
use super::refusal::{Expected, Refusal};
use super::{AppError, Hub};
use crate::Lane;
use crate::core::audit::{Actor, AuditAction};
pub use crate::core::credentials::Caller;
use crate::core::credentials::{self, NewToken, Role, Scope};
use crate::store;
pub use crate::store::accounts::TokenListing;

/// The caller `presented` stands for, if it may do what needs `scope`: refused as
/// unauthorized when the token is unknown or revoked, as forbidden when it lacks the scope.
/// The web checks every route's scope here, once, before the route's handler runs.
pub async fn authorize(hub: &Hub, presented: &str, scope: Scope) -> Result<Caller, AppError> {
    let caller = authenticate(hub, presented).await.inspect_err(|e| {
        if matches!(e, AppError::Refused(Refusal::TokenUnknown)) {
            hub.metrics().login_failed(LoginFailure::Token);
        }
    })?;
    if !caller.has(scope) {
        return Err(Refusal::ScopeMissing {
            scope: scope.as_str(),
        }
        .into());
    }
    Ok(caller)
}

/// The live (unrevoked) token `presented` stands for; 401 otherwise.
async fn authenticate(hub: &Hub, presented: &str) -> Result<Caller, AppError> {
    let refused = || AppError::from(Refusal::TokenUnknown);
    let mut conn = hub.conn().await?;
    let row = store::accounts::token_by_prefix(&mut conn, &credentials::lookup_prefix(presented))
        .await?
        .ok_or_else(refused)?;
    if row.revoked || !credentials::token_matches(presented, &row.token_hash) {
        return Err(refused());
    }
    Ok(Caller {
        token_id: row.id,
        account_id: row.account_id,
        account_name: row.account_name,
        scopes: row.scopes,
        daily_quota: row.daily_quota,
        total_quota: row.total_quota,
    })
}

/// A token just created: its secret is in this value only.
#[derive(Debug, Serialize, JsonSchema)]
pub struct CreatedToken {
    pub id: i64,
    pub prefix: String,
    pub account: String,
    pub role: Role,
    /// The secret, shown this once.
    pub token: String,
}

/// The account named `name` with `role`, created if missing, inside `tx`. An existing account
/// keeps its role: asking for another is a conflict.
pub(super) async fn ensure_account(
    conn: &mut store::Tx,
    name: &str,
    role: Role,
) -> Result<i64, AppError> {
    match store::accounts::account_by_name(&mut *conn, name).await? {
        Some((id, stored)) if stored == role => Ok(id),
        Some((_, stored)) => Err(AppError::Conflict(format!(
            "account '{name}' exists with role {}, not {}",
            stored.as_str(),
            role.as_str()
        ))),
        None => Ok(store::accounts::insert_account(conn, name, role).await?),
    }
}

/// Creates a token for the account `name` (created with `role` if new). Quotas left out are
/// the server's.
pub async fn issue(
    hub: &Hub,
    actor: &Actor,
    name: &str,
    role: Role,
    daily_quota: Option<i64>,
    total_quota: Option<i64>,
) -> Result<CreatedToken, AppError> {
    let name = credentials::account_name(name).map_err(AppError::Invalid)?;
    for (field, quota) in [("daily_quota", daily_quota), ("total_quota", total_quota)] {
        if let Some(q) = quota.filter(|q| *q < 0) {
            let whole = Expected::WholeNumberFrom { least: 0 };
            return Err(Refusal::bad_value(field, q.to_string(), whole).into());
        }
    }
    let token = NewToken::generate();
    let mut tx = hub.write(Lane::Interactive).await?;
    let account = ensure_account(&mut tx, name, role).await?;
    let id =
        store::accounts::insert_token(&mut tx, account, role, &token, daily_quota, total_quota)
            .await?;
    let quotas = |q: Option<i64>| q.map_or_else(|| "server's".to_owned(), |q| q.to_string());
    audit::record(
        &mut tx,
        actor,
        AuditAction::TokenIssue,
        format!("token {}", token.prefix),
        None,
        format!(
            "account {name} ({}); daily quota {}, total quota {}",
            role.as_str(),
            quotas(daily_quota),
            quotas(total_quota)
        ),
    )
    .await?;
    tx.commit().await?;
    Ok(CreatedToken {
        id,
        prefix: token.prefix.clone(),
        account: name.to_owned(),
        role,
        token: token.token,
    })
}

/// Every token with its account, quotas and use; never a secret.
pub async fn list(hub: &Hub) -> Result<Vec<TokenListing>, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::accounts::list_tokens(&mut conn).await?)
}

/// Revokes the live token with this id or prefix; it stops working at once.
pub async fn revoke(hub: &Hub, actor: &Actor, which: &str) -> Result<(), AppError> {
    let mut tx = hub.write(Lane::Interactive).await?;
    if store::accounts::revoke_token(&mut tx, which).await? {
        audit::record(
            &mut tx,
            actor,
            AuditAction::TokenRevoke,
            format!("token {which}"),
            None,
            "",
        )
        .await?;
        tx.commit().await?;
        Ok(())
    } else {
        Err(Refusal::NoToken {
            token: which.to_owned(),
        }
        .into())
    }
}

/// What [`ensure_admin_token`] did.
#[derive(Debug)]
pub enum AdminToken {
    /// A live admin token exists, or the operator's token is stored already.
    Present,
    /// The operator's token (ENACT_HUB_ADMIN_TOKEN) was stored; its prefix.
    StoredFromOperator(String),
    /// A new token was generated: show its secret once.
    Generated(String),
}

/// Makes sure an admin can reach the API: the operator's chosen token when given (stored
/// hashed on first sight), otherwise a generated one when no live admin token exists.
pub async fn ensure_admin_token(hub: &Hub, operator: Option<&str>) -> Result<AdminToken, AppError> {
    let mut tx = hub.write(Lane::Interactive).await?;
    let (token, generated) = match operator {
        Some(text) => {
            let token = NewToken::from_operator(text)
                .map_err(|e| AppError::Invalid(format!("ENACT_HUB_ADMIN_TOKEN: {e}")))?;
            if store::accounts::token_hash_exists(&mut tx, &token.hash).await? {
                return Ok(AdminToken::Present);
            }
            (token, false)
        }
        None if store::accounts::has_admin_token(&mut tx).await? => {
            return Ok(AdminToken::Present);
        }
        None => (NewToken::generate(), true),
    };
    let account = ensure_account(&mut tx, "admin", Role::Admin).await?;
    store::accounts::insert_token(&mut tx, account, Role::Admin, &token, None, None).await?;
    audit::record(
        &mut tx,
        &Actor::Server,
        AuditAction::TokenIssue,
        format!("token {}", token.prefix),
        None,
        if generated {
            "account admin (admin); generated at start: no live admin token"
        } else {
            "account admin (admin); from ENACT_HUB_ADMIN_TOKEN"
        },
    )
    .await?;
    tx.commit().await?;
    Ok(if generated {
        AdminToken::Generated(token.token)
    } else {
        AdminToken::StoredFromOperator(token.prefix)
    })
}
