//! Leaderboard submissions: submitting (quota, idempotency, scoring and storing, all or
//! nothing), reading one back with what its reader may see, and the admin's listing controls.

use std::future::Future;
use std::sync::Arc;

use sha2::{Digest, Sha256};

use super::cache::{BoundedCache, CacheLimits};
use super::changes::Change;
use super::refusal::{Expected, Refusal};
use super::tokens::Caller;
use super::{AppError, Hub, audit, datasets, statements};
use crate::Lane;
use crate::core::audit::{Actor, AuditAction};
use crate::core::credentials::{NewToken, Role, Scope};
use crate::core::dataset::AnswerVisibility;
use crate::core::metric::METRIC_VERSION;
use crate::core::scoring::{self, ScoringTarget};
use crate::core::submission::{
    Provenance, ScoredSubmission, SubmissionError, SubmissionMetadata, Visibility, score_submission,
};
use crate::core::version::BUILD;
use crate::store;
use crate::store::accounts::AttemptsMade;
use crate::store::datasets::Dataset;
use crate::store::db::UniqueKey;
use crate::store::submissions::NewSubmission;
pub use crate::store::submissions::{StoredVerdict, SubmissionRow};

/// A dataset's scoring targets and their `items` row ids, in dataset order.
pub struct DatasetTargets {
    pub targets: Vec<ScoringTarget>,
    pub item_rows: Vec<i64>,
}

/// Scoring targets per dataset, kept until the stored items change: deserialising the
/// signature tables of a full dataset costs more than scoring a submission against them.
pub struct TargetCache {
    /// By (dataset id, content generation): a newer generation is a new key, and the old
    /// entry ages out.
    entries: BoundedCache<(i64, i64), Arc<DatasetTargets>>,
}

impl Default for TargetCache {
    fn default() -> Self {
        TargetCache::new(CacheLimits::default().target_datasets)
    }
}

impl crate::Kept for TargetCache {
    fn make(hub: &Hub) -> Self {
        TargetCache::new(hub.cache_limits().target_datasets)
    }

    // Keyed by the content generation: a change to stored items is a new key.

    fn stats(&self) -> Vec<super::cache::CacheStats> {
        vec![TargetCache::stats(self)]
    }
}

impl TargetCache {
    /// At most `datasets` datasets' targets.
    pub fn new(datasets: u64) -> TargetCache {
        TargetCache {
            entries: BoundedCache::by_entries("scoring_targets", datasets),
        }
    }

    fn get(&self, dataset: i64, generation: i64) -> Option<Arc<DatasetTargets>> {
        self.entries.get(&(dataset, generation))
    }

    fn put(&self, dataset: i64, generation: i64, targets: Arc<DatasetTargets>) {
        self.entries.insert((dataset, generation), targets);
    }

    pub fn stats(&self) -> super::cache::CacheStats {
        self.entries.stats()
    }
}

/// What every submission to `dataset` is scored against.
pub async fn dataset_targets(hub: &Hub, dataset: i64) -> Result<Arc<DatasetTargets>, AppError> {
    let mut conn = hub.conn().await?;
    let generation = store::content_generation(&mut conn).await?;
    if let Some(t) = hub.kept::<TargetCache>().get(dataset, generation) {
        return Ok(t);
    }
    let rows = store::items::scoring_items(&mut conn, dataset).await?;
    drop(conn);
    let targets = hub
        .heavy()
        .run(move || {
            let item_rows = rows.iter().map(|r| r.row_id).collect();
            scoring::targets_from_stored(rows).map(|targets| DatasetTargets { targets, item_rows })
        })
        .await?
        .map_err(AppError::internal)?;
    let targets = Arc::new(targets);
    hub.kept::<TargetCache>()
        .put(dataset, generation, targets.clone());
    Ok(targets)
}

/// Times a submission is scored while imports keep changing its dataset under it before it is
/// refused as unavailable (to be sent again).
const SCORING_ATTEMPTS: usize = 3;

/// Submission attempts a token may make, unless the token sets its own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Quotas {
    /// Per UTC day.
    pub daily: i64,
    /// In total.
    pub total: i64,
}

impl Default for Quotas {
    fn default() -> Self {
        Quotas {
            daily: 20,
            total: 1000,
        }
    }
}

/// The server's quotas (`serve --daily-quota`, `--total-quota`), set before serving.
impl crate::Kept for Quotas {
    fn make(_hub: &Hub) -> Self {
        Quotas::default()
    }
}

/// Seconds until the next UTC midnight, when daily quotas reset.
fn seconds_until_utc_midnight() -> u64 {
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    86_400 - now % 86_400
}

/// How a submission request ended.
#[derive(Debug)]
pub enum Submitted {
    /// Scored and stored.
    Created(SubmissionRow),
    /// A repeat of an earlier request with the same idempotency key and body.
    Repeated(SubmissionRow),
}

/// The outcome of asking for one more submission attempt.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum AttemptQuota {
    Granted,
    DailyExhausted {
        limit: i64,
    },
    /// `used` attempts were made against a total of `limit`; waiting will not help.
    TotalExhausted {
        used: i64,
        limit: i64,
    },
}

/// Whether one more attempt fits under `daily` and `total`, given those already `made`. The
/// total is named first when both are used up: it is the one waiting cannot fix.
fn attempt_quota(made: AttemptsMade, daily: i64, total: i64) -> AttemptQuota {
    if made.total >= total {
        AttemptQuota::TotalExhausted {
            used: made.total,
            limit: total,
        }
    } else if made.today >= daily {
        AttemptQuota::DailyExhausted { limit: daily }
    } else {
        AttemptQuota::Granted
    }
}

/// Takes one attempt from the caller's quotas, refused ones counted too; admins are exempt.
/// Counts one attempt against the caller's quotas; returns its id (none for an admin, whose
/// attempts are not counted).
async fn take_attempt(hub: &Hub, caller: &Caller) -> Result<Option<i64>, AppError> {
    if caller.has(Scope::Admin) {
        return Ok(None);
    }
    let quotas = *hub.kept::<Quotas>();
    let daily = caller.daily_quota.unwrap_or(quotas.daily);
    let total = caller.total_quota.unwrap_or(quotas.total);
    // In a write transaction, serialised with every other on either database: the count and
    // the insert hold across every server instance, so two requests cannot both take the
    // last attempt.
    let mut tx = hub.write(Lane::Interactive).await?;
    let made = store::accounts::attempts_made(&mut tx, caller.token_id).await?;
    let quota = attempt_quota(made, daily, total);
    let attempt = if quota == AttemptQuota::Granted {
        Some(store::accounts::record_attempt(&mut tx, caller.token_id).await?)
    } else {
        None
    };
    tx.commit().await?;
    match quota {
        AttemptQuota::Granted => Ok(attempt),
        AttemptQuota::DailyExhausted { limit } => Err(Refusal::DailyQuotaUsed {
            limit: count(limit),
            retry_after: seconds_until_utc_midnight(),
        }
        .into()),
        // No Retry-After: the total never refills, so waiting would not help.
        AttemptQuota::TotalExhausted { used, limit } => Err(Refusal::TotalQuotaUsed {
            used: count(used),
            limit: count(limit),
        }
        .into()),
    }
}

/// A count of submissions as a refusal names it (never negative).
fn count(n: i64) -> u64 {
    n.max(0).unsigned_abs()
}

fn body_sha256(body: &[u8]) -> String {
    hex::encode(Sha256::digest(body))
}

/// Scores `body` against every item of the dataset (on the heavy-work pool): 422 with every
/// problem when the body is refused, 503 when the pool is full.
async fn score_body(
    hub: &Hub,
    targets: Arc<DatasetTargets>,
    dataset_name: &str,
    body: Arc<Vec<u8>>,
) -> Result<ScoredSubmission, AppError> {
    let dataset_name = dataset_name.to_owned();
    hub.heavy()
        .run(move || {
            let text = std::str::from_utf8(&body).map_err(|e| {
                let line = body[..e.valid_up_to()]
                    .iter()
                    .filter(|b| **b == b'\n')
                    .count()
                    + 1;
                AppError::Rejected {
                    message: format!(
                        "line {line}: the body is not UTF-8 text (byte {} is invalid)",
                        e.valid_up_to()
                    ),
                    problems: Vec::new(),
                }
            })?;
            match score_submission(&targets.targets, text) {
                Ok(scored) => Ok(scored),
                Err(SubmissionError::Rejected(problems)) => {
                    let first: Vec<String> =
                        problems.iter().take(5).map(|p| p.message.clone()).collect();
                    Err(AppError::Rejected {
                        message: format!(
                            "{} problems; nothing was stored: {}{}",
                            problems.len(),
                            first.join("; "),
                            if problems.len() > 5 { "; …" } else { "" }
                        ),
                        problems,
                    })
                }
                Err(SubmissionError::Dataset(e)) => Err(AppError::internal(format!(
                    "dataset {dataset_name} cannot be scored: {e}"
                ))),
            }
        })
        .await?
}

async fn by_id(hub: &Hub, id: i64) -> Result<Option<SubmissionRow>, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::submissions::by_id(&mut conn, id).await?)
}

/// Submits a model's answers to `dataset`: counts the attempt against the caller's quotas
/// (given back when the server was too busy to take it on or a twin request stored it), reads
/// the body (only then, so an attempt over quota never uploads), scores it against every item
/// and stores the submission with every verdict in one transaction. The caller's `submit`
/// scope was checked before the request reached this (the web's route table).
///
/// With an `idempotency_key` already used by this token, the first submission is returned
/// when the body is the same, and 409 when it differs.
pub async fn submit<B>(
    hub: &Hub,
    caller: &Caller,
    dataset_name: &str,
    metadata: SubmissionMetadata,
    provenance: Provenance,
    idempotency_key: Option<&str>,
    body: B,
) -> Result<Submitted, AppError>
where
    B: Future<Output = Result<Vec<u8>, AppError>>,
{
    let dataset = datasets::by_name(hub, dataset_name).await?;
    let metadata = metadata.checked().map_err(AppError::Invalid)?;
    if let Some(key) = idempotency_key {
        let mut conn = hub.conn().await?;
        let existing =
            store::submissions::by_idempotency_key(&mut conn, caller.token_id, key).await?;
        drop(conn);
        if let Some(existing) = existing {
            let body = body.await?;
            return repeat_of(existing, &body);
        }
    }
    let attempt = take_attempt(hub, caller).await?;
    let arrived = Arrived {
        metadata,
        provenance,
        idempotency_key,
    };
    let stored = match body.await {
        Ok(body) => store_submission(hub, caller, &dataset, arrived, body).await,
        Err(e) => Err(e),
    };
    // The server was too busy to take it on (a full scoring queue, a write lock held too
    // long), or a twin request with the same key stored it first: neither is the caller's
    // attempt to pay for (a repeat sent after the first one ended costs none).
    if let (Err(AppError::Unavailable(_)) | Ok(Submitted::Repeated(_)), Some(attempt)) =
        (&stored, attempt)
    {
        give_back_attempt(hub, attempt).await;
    }
    stored
}

/// Forgets an attempt the server refused for being busy; a failure is logged, not answered
/// (the caller is already being told to retry).
async fn give_back_attempt(hub: &Hub, attempt: i64) {
    let given_back = async {
        let mut tx = hub.write(Lane::Interactive).await?;
        store::accounts::forget_attempt(&mut tx, attempt).await?;
        tx.commit().await?;
        Ok::<(), AppError>(())
    };
    if let Err(e) = given_back.await {
        tracing::warn!(attempt, error = %e, "a refused submission still counts against its quota");
    }
}

/// What a submission came with besides its body ([`submit`]).
struct Arrived<'a> {
    metadata: SubmissionMetadata,
    provenance: Provenance,
    idempotency_key: Option<&'a str>,
}

/// Scores and stores a submission whose attempt is counted ([`submit`]).
async fn store_submission(
    hub: &Hub,
    caller: &Caller,
    dataset: &Dataset,
    arrived: Arrived<'_>,
    body: Vec<u8>,
) -> Result<Submitted, AppError> {
    let Arrived {
        metadata,
        provenance,
        idempotency_key,
    } = arrived;
    let body = Arc::new(body);
    let sha256 = body_sha256(&body);
    let mut attempt = 1;
    let (dataset, mut tx, targets, scored, verdicts) = loop {
        let generation = {
            let mut conn = hub.conn().await?;
            store::content_generation(&mut conn).await?
        };
        // Looked up again after the generation: the body may have taken seconds to arrive,
        // and a replacing import may have given the dataset another row meanwhile.
        let dataset = datasets::by_name(hub, &dataset.name).await?;
        let targets = dataset_targets(hub, dataset.id).await?;
        let scored = score_body(hub, targets.clone(), &dataset.name, body.clone()).await?;
        let verdicts = statements::scored_verdicts(&targets.targets, &scored.items);
        let mut tx = hub.write(Lane::Bulk).await?;
        if store::content_generation(&mut tx).await? == generation {
            break (dataset, tx, targets, scored, verdicts);
        }
        // An import changed the items while the body was scored (or a replacing import's
        // cut-over gave the dataset another row): scored again against what it left, under
        // the dataset's row as it is now.
        tx.rollback().await?;
        if attempt == SCORING_ATTEMPTS {
            return Err(AppError::Unavailable(format!(
                "dataset {} changed {attempt} times while the submission was scored; send it again",
                dataset.name
            )));
        }
        attempt += 1;
    };
    let dataset = &dataset;
    let new = NewSubmission {
        dataset: dataset.id,
        account: caller.account_id,
        token: caller.token_id,
        idempotency_key,
        body_sha256: &sha256,
        metadata: &metadata,
        scores: &scored.scores,
        metric_version: METRIC_VERSION,
        scored_by: BUILD,
        provenance,
    };
    let id = match store::submissions::insert(&mut tx, &new).await {
        Ok(id) => id,
        // A twin request with the same key committed first (both passed the lookup above
        // before either stored anything): answered as a repeat of it. The failed statement
        // ends a PostgreSQL transaction, so the twin is read after rolling back.
        Err(e) if UniqueKey::SUBMISSION_IDEMPOTENCY_KEY.is_violated_by(&e) => {
            tx.rollback().await?;
            let mut conn = hub.conn().await?;
            let existing = store::submissions::by_idempotency_key(
                &mut conn,
                caller.token_id,
                idempotency_key.unwrap_or_default(),
            )
            .await?
            .ok_or_else(|| AppError::internal("an idempotent twin submission vanished"))?;
            return repeat_of_digest(existing, &sha256);
        }
        Err(e) => return Err(e.into()),
    };
    store::submissions::insert_items(&mut tx, id, &targets.item_rows, &scored.items).await?;
    statements::record(hub, &mut tx, id, verdicts).await?;
    audit::record(
        &mut tx,
        &caller.actor(),
        AuditAction::SubmissionCreate,
        format!("submission {id}"),
        Some(&dataset.name),
        format!("model {}", metadata.model),
    )
    .await?;
    tx.announce(Change::Boards).await?;
    tx.commit().await?;
    hub.metrics().submission_scored();
    tracing::info!(
        submission = id,
        dataset = %dataset.name,
        account = %caller.account_name,
        model = %metadata.model,
        "submission scored"
    );
    let row = by_id(hub, id)
        .await?
        .ok_or_else(|| AppError::internal(format!("submission {id} vanished")))?;
    Ok(Submitted::Created(row))
}

fn repeat_of(existing: SubmissionRow, body: &[u8]) -> Result<Submitted, AppError> {
    repeat_of_digest(existing, &body_sha256(body))
}

/// The earlier submission under the same Idempotency-Key, when the body (by its SHA-256) is
/// the same; 409 when it differs.
fn repeat_of_digest(existing: SubmissionRow, sha256: &str) -> Result<Submitted, AppError> {
    if sha256 != existing.body_sha256 {
        return Err(Refusal::IdempotencyKeyReused {
            submission: existing.id.to_string(),
        }
        .into());
    }
    Ok(Submitted::Repeated(existing))
}

/// A submission as its reader may see it: per-item verdicts only for its owner or an admin,
/// and only when the dataset's answers are public; otherwise why they are withheld.
pub struct SubmissionDetail {
    pub row: SubmissionRow,
    pub verdicts: Result<Vec<StoredVerdict>, String>,
}

/// Reads a submission. Another account's submission is answered like a missing one, so ids
/// reveal nothing.
pub async fn read(hub: &Hub, caller: &Caller, id: &str) -> Result<SubmissionDetail, AppError> {
    let row = readable(hub, caller, id).await?;
    let numeric = row.id;
    let mut conn = hub.conn().await?;
    let visibility = store::submissions::answer_visibility(&mut conn, row.dataset_id).await?;
    let verdicts = if visibility == AnswerVisibility::Public {
        Ok(store::submissions::verdicts(&mut conn, numeric).await?)
    } else {
        Err(format!(
            "per-item verdicts are not shown: the answers of dataset '{}' are {}",
            row.dataset,
            visibility.as_str()
        ))
    };
    Ok(SubmissionDetail { row, verdicts })
}

/// A submission its caller may read: their own, or any when the caller is an admin. Another
/// account's submission is answered like a missing one. (The `read_own` scope is the route's
/// to check, before this is called.)
pub async fn readable(hub: &Hub, caller: &Caller, id: &str) -> Result<SubmissionRow, AppError> {
    let not_found = || {
        AppError::from(Refusal::NoSubmission {
            submission: id.to_owned(),
        })
    };
    let numeric: i64 = id.parse().map_err(|_| not_found())?;
    let admin = caller.has(Scope::Admin);
    by_id(hub, numeric)
        .await?
        .filter(|r| r.account_id == caller.account_id || admin)
        .ok_or_else(not_found)
}

/// An admin's change to a leaderboard row: mark a baseline, or hide, publish or withdraw it.
pub async fn update_listing(
    hub: &Hub,
    actor: &Actor,
    id: &str,
    baseline: Option<bool>,
    visibility: Option<&str>,
) -> Result<SubmissionRow, AppError> {
    let not_found = || {
        AppError::from(Refusal::NoSubmission {
            submission: id.to_owned(),
        })
    };
    let numeric: i64 = id.parse().map_err(|_| not_found())?;
    let visibility = visibility
        .map(|v| {
            Visibility::parse(v).ok_or_else(|| {
                let visibilities = Expected::OneOf(vec!["published", "hidden", "withdrawn"]);
                Refusal::bad_value("visibility", v, visibilities)
            })
        })
        .transpose()?;
    let mut tx = hub.write(Lane::Interactive).await?;
    if !store::submissions::update_listing(&mut tx, numeric, baseline, visibility).await? {
        return Err(not_found());
    }
    let row = store::submissions::by_id(&mut tx, numeric)
        .await?
        .ok_or_else(not_found)?;
    let mut changes = Vec::new();
    if let Some(baseline) = baseline {
        changes.push(format!("baseline {baseline}"));
    }
    if let Some(visibility) = visibility {
        changes.push(format!("visibility {}", visibility.as_str()));
    }
    audit::record(
        &mut tx,
        actor,
        AuditAction::SubmissionListing,
        format!("submission {numeric}"),
        Some(&row.dataset),
        changes.join(", "),
    )
    .await?;
    tx.announce(Change::Boards).await?;
    tx.commit().await?;
    Ok(row)
}

/// Files a baseline on a dataset's leaderboard (once per account and model, even if an admin
/// has since hidden or withdrawn it), scored and stored as any submission is. Its account's
/// only token is revoked at once, so nobody can submit as it. Returns whether it was added.
pub async fn file_baseline(
    hub: &Hub,
    actor: &Actor,
    dataset_name: &str,
    account_name: &str,
    metadata: SubmissionMetadata,
    answer_body: impl FnOnce(&DatasetTargets) -> String,
) -> Result<bool, AppError> {
    // The generation first: a replacing import that gives the dataset another row after it
    // is caught below, before anything is stored under the old one.
    let generation = {
        let mut conn = hub.conn().await?;
        store::content_generation(&mut conn).await?
    };
    let dataset = datasets::by_name(hub, dataset_name).await?;
    let mut conn = hub.conn().await?;
    let already =
        store::submissions::has_submitted(&mut conn, dataset.id, account_name, &metadata.model)
            .await?;
    drop(conn);
    if already {
        return Ok(false);
    }
    let targets = dataset_targets(hub, dataset.id).await?;
    let body = answer_body(&targets);
    let sha256 = body_sha256(body.as_bytes());
    let scored = score_body(
        hub,
        targets.clone(),
        &dataset.name,
        Arc::new(body.into_bytes()),
    )
    .await?;
    let verdicts = statements::scored_verdicts(&targets.targets, &scored.items);
    let mut tx = hub.write(Lane::Bulk).await?;
    if store::content_generation(&mut tx).await? != generation {
        tx.rollback().await?;
        return Err(AppError::Unavailable(format!(
            "dataset {} changed while the baseline was scored; file it again",
            dataset.name
        )));
    }
    let account = super::tokens::ensure_account(&mut tx, account_name, Role::Submitter).await?;
    let token = NewToken::generate();
    let token_id =
        store::accounts::insert_token(&mut tx, account, Role::Submitter, &token, None, None)
            .await?;
    store::accounts::revoke_token(&mut tx, &token_id.to_string()).await?;
    let new = NewSubmission {
        dataset: dataset.id,
        account,
        token: token_id,
        idempotency_key: None,
        body_sha256: &sha256,
        metadata: &metadata,
        scores: &scored.scores,
        metric_version: METRIC_VERSION,
        scored_by: BUILD,
        // The hub computed a baseline's answers itself, but asked no model: not a run.
        provenance: Provenance::Submitted,
    };
    let id = store::submissions::insert(&mut tx, &new).await?;
    store::submissions::insert_items(&mut tx, id, &targets.item_rows, &scored.items).await?;
    store::submissions::update_listing(&mut tx, id, Some(true), None).await?;
    statements::record(hub, &mut tx, id, verdicts).await?;
    audit::record(
        &mut tx,
        actor,
        AuditAction::BaselineFile,
        format!("submission {id}"),
        Some(&dataset.name),
        format!("account {account_name}, model {}", metadata.model),
    )
    .await?;
    tx.announce(Change::Boards).await?;
    tx.commit().await?;
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn made(today: i64, total: i64) -> AttemptsMade {
        AttemptsMade { today, total }
    }

    #[test]
    fn an_attempt_is_granted_while_both_quotas_have_room() {
        assert_eq!(attempt_quota(made(0, 0), 1, 1), AttemptQuota::Granted);
        assert_eq!(attempt_quota(made(4, 9), 5, 10), AttemptQuota::Granted);
    }

    #[test]
    fn the_daily_quota_runs_out_on_its_own() {
        assert_eq!(
            attempt_quota(made(5, 7), 5, 10),
            AttemptQuota::DailyExhausted { limit: 5 }
        );
    }

    #[test]
    fn the_total_quota_is_named_when_both_are_used_up() {
        assert_eq!(
            attempt_quota(made(5, 10), 5, 10),
            AttemptQuota::TotalExhausted {
                used: 10,
                limit: 10
            }
        );
        // A total lowered below what was already used still reports what was used.
        assert_eq!(
            attempt_quota(made(0, 12), 5, 10),
            AttemptQuota::TotalExhausted {
                used: 12,
                limit: 10
            }
        );
    }
}
