//! Annotator accounts: creating one with its single-use invite, setting a password through the
//! invite, logging in and out, and the sessions that prove a login.

use std::time::Duration;

use super::changes::Change;
use super::metrics::LoginFailure;
use super::refusal::Refusal;
use super::{AppError, Hub, audit};
use crate::Lane;
use crate::core::annotation::Session;
use crate::core::audit::{Actor, AuditAction};
use crate::core::credentials::{
    self, MIN_PASSWORD_CHARS, hash_password, random_token, token_hash, too_short_password,
    verify_password,
};
use crate::store;
use crate::store::annotations::Annotator;
use crate::store::db::UniqueKey;

/// How long a login lasts.
pub const SESSION_LIFETIME: Duration = Duration::from_secs(12 * 3600);

/// Milliseconds since the Unix epoch, the clock of sessions and drafts.
pub fn now_ms() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_millis()).unwrap_or(i64::MAX))
}

/// The invite link an annotator opens to set a password.
pub fn invite_url(base: &str, token: &str) -> String {
    format!("{}/invite/{token}", base.trim_end_matches('/'))
}

/// A new account and the secret of its single-use invite.
#[derive(Debug)]
pub struct Invited {
    pub name: String,
    pub is_admin: bool,
    pub invite_token: String,
}

/// Creates an annotator (an admin with `is_admin`) with a pending invite. The name follows
/// [`credentials::annotator_name`]; a name in use is a conflict.
pub async fn create(
    hub: &Hub,
    actor: &Actor,
    name: &str,
    is_admin: bool,
) -> Result<Invited, AppError> {
    let name = credentials::annotator_name(name).map_err(AppError::Invalid)?;
    let token = random_token();
    let mut tx = hub.write(Lane::Interactive).await?;
    match store::annotations::create_annotator(&mut tx, name, is_admin, &token_hash(&token)).await {
        Ok(_) => {}
        Err(e) if UniqueKey::ANNOTATOR_NAME.is_violated_by(&e) => {
            return Err(AppError::Conflict(format!(
                "an annotator named '{name}' already exists"
            )));
        }
        Err(e) => return Err(e.into()),
    }
    audit::record(
        &mut tx,
        actor,
        AuditAction::AnnotatorCreate,
        format!("annotator {name}"),
        None,
        if is_admin {
            "admin; invited"
        } else {
            "invited"
        },
    )
    .await?;
    tx.commit().await?;
    Ok(Invited {
        name: name.to_owned(),
        is_admin,
        invite_token: token,
    })
}

fn unknown_invite() -> AppError {
    Refusal::InviteLinkUsed.into()
}

/// The account an unused invite is for.
pub async fn invited(hub: &Hub, invite_token: &str) -> Result<Annotator, AppError> {
    let mut conn = hub.conn().await?;
    store::annotations::annotator_by_invite(&mut conn, &token_hash(invite_token))
        .await?
        .ok_or_else(unknown_invite)
}

/// Sets the password of the invite's account and uses the invite up; returns the annotator.
pub async fn accept_invite(
    hub: &Hub,
    invite_token: &str,
    password: &str,
    repeat: &str,
) -> Result<i64, AppError> {
    if password != repeat {
        return Err(Refusal::PasswordsDiffer.into());
    }
    if let Some(chars) = too_short_password(password) {
        return Err(Refusal::PasswordTooShort {
            chars: chars as u64,
            least: MIN_PASSWORD_CHARS as u64,
        }
        .into());
    }
    let password = password.to_owned();
    let hash = password_work(move || hash_password(&password))
        .await?
        .map_err(|e| AppError::internal(format!("argon2: {e}")))?;
    let invite = token_hash(invite_token);
    let mut tx = hub.write(Lane::Interactive).await?;
    let invited = store::annotations::annotator_by_invite(&mut tx, &invite)
        .await?
        .ok_or_else(unknown_invite)?;
    let id = store::annotations::accept_invite(&mut tx, &invite, &hash)
        .await?
        .ok_or_else(unknown_invite)?;
    audit::record(
        &mut tx,
        &Actor::Annotator(invited.name.clone()),
        AuditAction::AnnotatorActivate,
        format!("annotator {}", invited.name),
        None,
        "invite used, password set",
    )
    .await?;
    tx.commit().await?;
    Ok(id)
}

/// A new single-use login link secret for `annotator` (the path is `/login/link/{secret}`).
pub async fn login_link(hub: &Hub, annotator: i64) -> Result<String, AppError> {
    let token = random_token();
    let mut tx = hub.write(Lane::Interactive).await?;
    store::annotations::insert_login_link(&mut tx, &token_hash(&token), annotator).await?;
    tx.commit().await?;
    Ok(token)
}

/// Uses a login link up and returns its annotator; a link is good once.
pub async fn follow_login_link(hub: &Hub, token: &str) -> Result<i64, AppError> {
    let mut tx = hub.write(Lane::Interactive).await?;
    let annotator = store::annotations::take_login_link(&mut tx, &token_hash(token)).await?;
    tx.commit().await?;
    annotator.ok_or_else(|| AppError::from(Refusal::LoginLinkUsed))
}

/// The annotator whose password this is, if the name and password match.
///
/// An unknown name, or an account whose invite is still unused, is checked against
/// [`NO_ONES_HASH`], so that it costs the same password hash as a wrong password for a real
/// name: how long the answer takes does not tell which names exist.
pub async fn check_password(
    hub: &Hub,
    name: &str,
    password: &str,
) -> Result<Option<i64>, AppError> {
    let mut conn = hub.conn().await?;
    let stored = store::annotations::credentials(&mut conn, name).await?;
    drop(conn);
    let password = password.to_owned();
    let found = password_work(move || match stored {
        Some((id, hash)) => verify_password(&password, &hash).then_some(id),
        None => {
            // Never true: no one knows the random password behind it.
            let _ = verify_password(&password, &NO_ONES_HASH);
            None
        }
    })
    .await?;
    if found.is_none() {
        hub.metrics().login_failed(LoginFailure::Password);
    }
    Ok(found)
}

/// The hash of a random password no one knows, made once with the parameters of every stored
/// hash ([`hash_password`]): what [`check_password`] checks a password against when the name
/// has none. [`prepare_login`] makes it before the first login, so that login does not pay
/// for it.
static NO_ONES_HASH: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
    // Hashing 64 hex characters with a fresh 16-byte salt cannot fail: the salt encodes and
    // argon2's default parameters take any password length.
    hash_password(&random_token()).expect("argon2 hashes a random token with a fresh salt")
});

/// Makes the hash unknown names are checked against ([`NO_ONES_HASH`]), off the request
/// threads; the server calls it as it starts.
pub async fn prepare_login() -> Result<(), AppError> {
    password_work(|| {
        std::sync::LazyLock::force(&NO_ONES_HASH);
    })
    .await
}

/// Password hashes computed at once: one fewer than the cores (at least one). Each is tens of
/// milliseconds of CPU by design; a burst of logins (a class starting together) queues here
/// and leaves a core to the pages and answers of the annotators already working.
static PASSWORD_WORK: std::sync::LazyLock<tokio::sync::Semaphore> =
    std::sync::LazyLock::new(|| {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        tokio::sync::Semaphore::new(cores.saturating_sub(1).max(1))
    });

/// Runs a password hash or check off the request threads, in its turn ([`PASSWORD_WORK`]).
async fn password_work<T: Send + 'static>(
    work: impl FnOnce() -> T + Send + 'static,
) -> Result<T, AppError> {
    let _turn = PASSWORD_WORK.acquire().await.map_err(AppError::internal)?;
    Ok(tokio::task::spawn_blocking(work).await?)
}

/// Starts a session for `annotator`; returns its secret token (for the cookie).
pub async fn start_session(hub: &Hub, annotator: i64) -> Result<String, AppError> {
    let token = random_token();
    let mut tx = hub.write(Lane::Interactive).await?;
    store::annotations::create_session(
        &mut tx,
        &token_hash(&token),
        annotator,
        &random_token(),
        now_ms() + i64::try_from(SESSION_LIFETIME.as_millis()).unwrap_or(i64::MAX),
    )
    .await?;
    tx.commit().await?;
    Ok(token)
}

/// The unexpired session whose token hashes to `token_hash`, and when it expires.
pub async fn session(hub: &Hub, token_hash: &str) -> Result<Option<(Session, i64)>, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::annotations::session(&mut conn, token_hash, now_ms()).await?)
}

/// Ends the session whose token hashes to `token_hash` (and any expired ones).
pub async fn end_session(hub: &Hub, token_hash: &str) -> Result<(), AppError> {
    let mut tx = hub.write(Lane::Interactive).await?;
    store::annotations::delete_session(&mut tx, token_hash, now_ms()).await?;
    tx.announce(Change::SessionEnded(token_hash.to_owned()))
        .await?;
    tx.commit().await?;
    Ok(())
}

/// Saves `locale` (a tag the pages serve) as the preference of the annotator whose session
/// hashes to `token_hash`; nothing when the session is unknown or expired.
pub async fn save_locale(hub: &Hub, token_hash: &str, locale: &str) -> Result<(), AppError> {
    let mut tx = hub.write(Lane::Interactive).await?;
    store::annotations::set_locale_by_session(&mut tx, token_hash, locale, now_ms()).await?;
    tx.commit().await?;
    Ok(())
}

/// The locale `annotator` saved with the language switch, if any.
pub async fn saved_locale(hub: &Hub, annotator: i64) -> Result<Option<String>, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::annotations::locale(&mut conn, annotator).await?)
}

/// An annotator with their progress, as the admin page lists them.
pub struct AnnotatorProgress {
    pub annotator: Annotator,
    pub assigned: i64,
    pub finished: i64,
    pub answered: i64,
}

/// Every annotator, by name, with their progress.
pub async fn with_progress(hub: &Hub) -> Result<Vec<AnnotatorProgress>, AppError> {
    let mut conn = hub.conn().await?;
    let accounts = store::annotations::annotators(&mut conn).await?;
    let progress = store::annotations::progress_by_annotator(&mut conn).await?;
    Ok(accounts
        .into_iter()
        .map(|annotator| {
            let (assigned, finished, answered) = progress
                .iter()
                .find(|p| p.0 == annotator.id)
                .map_or((0, 0, 0), |p| (p.1, p.2, p.3));
            AnnotatorProgress {
                annotator,
                assigned,
                finished,
                answered,
            }
        })
        .collect())
}
