//! Signed statements of scored submissions ([`crate::core::statement`] defines them): made and
//! stored in the transaction that stores or rescores a submission's scores, served newest
//! first, and checked against a hub's public keys (`enact-hub verify`).
//!
//! Submissions scored before statements existed get theirs when one is first asked for
//! ([`newest_or_make`]): made then from the stored scores and verdicts and kept, so the
//! statement says what is stored, signed at the time of the request (its `made_at`). A rescore
//! makes a new statement in the same transaction as the new scores.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Mutex;
use std::time::{SystemTime, UNIX_EPOCH};

use super::{AppError, Hub, signing};
use crate::Lane;
use crate::core::scoring::ScoringTarget;
use crate::core::statement::{
    DatasetDigest, DatasetFacts, Envelope, HubIdentity, PublishedKeys, STATEMENT_FORMAT,
    StatementPayload, SubmissionFacts, TrustedKey, VerdictFacts, VerdictLine, items_sha256,
    utc_timestamp, verdicts_sha256,
};
use crate::core::submission::ItemVerdict;
use crate::core::version::BUILD;
use crate::store;
use crate::store::submissions::SubmissionRow;

/// Each dataset's items digest at the content generation it was computed at: computing it
/// reads every item's content hash, so it is done once per change of the items.
#[derive(Debug, Default)]
pub struct ItemDigests {
    by_dataset: Mutex<HashMap<i64, (i64, DatasetDigest)>>,
}

impl crate::Kept for ItemDigests {
    fn make(_hub: &Hub) -> Self {
        ItemDigests::default()
    }
}

impl ItemDigests {
    fn get(&self, dataset: i64, generation: i64) -> Option<DatasetDigest> {
        let map = self.by_dataset.lock().unwrap_or_else(|p| p.into_inner());
        map.get(&dataset)
            .filter(|(g, _)| *g == generation)
            .map(|(_, d)| d.clone())
    }

    fn put(&self, dataset: i64, generation: i64, digest: DatasetDigest) {
        let mut map = self.by_dataset.lock().unwrap_or_else(|p| p.into_inner());
        map.insert(dataset, (generation, digest));
    }
}

/// The verdicts digest of a scoring just computed against `targets`.
pub fn scored_verdicts(targets: &[ScoringTarget], items: &[ItemVerdict]) -> VerdictFacts {
    verdicts_sha256(
        items
            .iter()
            .filter_map(|v| {
                let target = targets.get(v.target)?;
                Some(VerdictLine::of(&target.id, v))
            })
            .collect(),
    )
}

/// The verdicts digest of a submission's stored verdicts.
async fn stored_verdicts(
    conn: &mut store::Conn,
    submission: i64,
) -> Result<VerdictFacts, AppError> {
    let stored = store::submissions::verdicts(conn, submission).await?;
    Ok(verdicts_sha256(
        stored
            .iter()
            .map(|v| VerdictLine {
                item_id: &v.id,
                outcome: v.outcome,
                exact_match: v.exact_match,
                semantic_match: v.semantic_match,
                task_accuracy: v.task_accuracy,
                pairwise_accuracy: v.pairwise_accuracy,
            })
            .collect(),
    ))
}

/// The items digest of the dataset as `conn` sees it.
async fn dataset_digest(
    hub: &Hub,
    conn: &mut store::Conn,
    dataset: i64,
) -> Result<DatasetDigest, AppError> {
    let generation = store::content_generation(conn).await?;
    if let Some(digest) = hub.kept::<ItemDigests>().get(dataset, generation) {
        return Ok(digest);
    }
    let hashes = store::items::content_hashes(conn, dataset).await?;
    let digest = items_sha256(hashes.iter().map(|(id, hash)| (id.as_str(), hash.as_str())));
    hub.kept::<ItemDigests>()
        .put(dataset, generation, digest.clone());
    Ok(digest)
}

/// The statement's `provenance`: the row's, as the submission API reports it.
fn provenance(row: &SubmissionRow) -> String {
    row.provenance.as_str().to_owned()
}

/// The time now, as the store writes times.
fn now() -> String {
    utc_timestamp(
        SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_secs()),
    )
}

/// Makes, signs and stores the statement of submission `id` as `conn`'s transaction holds it
/// (its row and scores just written, `verdicts` the digest of its verdicts), inside that
/// transaction, so the scores and their statement commit together.
pub(crate) async fn record(
    hub: &Hub,
    conn: &mut store::Tx,
    id: i64,
    verdicts: VerdictFacts,
) -> Result<Envelope, AppError> {
    let row = store::submissions::by_id(conn, id)
        .await?
        .ok_or_else(|| AppError::internal(format!("submission {id} vanished")))?;
    let dataset = dataset_digest(hub, conn, row.dataset_id).await?;
    let key = signing::signing_key(hub, conn).await?;
    let payload = StatementPayload {
        statement: STATEMENT_FORMAT.to_owned(),
        hub: HubIdentity {
            name: "enact-hub".to_owned(),
            url: hub
                .kept::<signing::Signer>()
                .public_url()
                .map(str::to_owned),
            version: BUILD.to_owned(),
        },
        submission: SubmissionFacts {
            id: row.id,
            model: row.model.clone(),
            account: row.account.clone(),
            created_at: row.created_at.clone(),
            scored_by: row.scored_by.clone(),
        },
        dataset: DatasetFacts {
            name: row.dataset.clone(),
            items: dataset.items,
            items_sha256: dataset.sha256,
        },
        answers_sha256: row.body_sha256.clone(),
        verdicts,
        metric_version: row.metric_version,
        policy: row.policy,
        provenance: provenance(&row),
        scores: row.scores.clone(),
        made_at: now(),
    };
    let envelope = key.sign_statement(&payload);
    store::statements::insert_statement(
        conn,
        row.id,
        &key.keyid(),
        &envelope.to_json(),
        &payload.made_at,
    )
    .await?;
    Ok(envelope)
}

/// The newest statement of `row` (a submission its caller may read), made now from what is
/// stored when it has none (a submission scored before statements existed).
pub async fn newest_or_make(hub: &Hub, row: &SubmissionRow) -> Result<Envelope, AppError> {
    let mut conn = hub.conn().await?;
    let newest = store::statements::newest_statement(&mut conn, row.id).await?;
    drop(conn);
    if let Some(stored) = newest {
        return parse_stored(&stored.envelope, row.id);
    }
    let mut tx = hub.write(Lane::Interactive).await?;
    // Another request may have made it meanwhile.
    if let Some(stored) = store::statements::newest_statement(&mut tx, row.id).await? {
        tx.rollback().await?;
        return parse_stored(&stored.envelope, row.id);
    }
    let verdicts = stored_verdicts(&mut tx, row.id).await?;
    let envelope = record(hub, &mut tx, row.id, verdicts).await?;
    tx.commit().await?;
    tracing::info!(
        submission = row.id,
        "statement made for a submission scored before statements"
    );
    Ok(envelope)
}

fn parse_stored(text: &str, submission: i64) -> Result<Envelope, AppError> {
    Envelope::parse(text).map_err(|e| {
        AppError::internal(format!(
            "submission {submission}: stored statement unreadable: {e}"
        ))
    })
}

/// Where `enact-hub verify` takes the hub's public keys from.
#[derive(Debug, Clone)]
pub enum KeysFrom<'a> {
    /// A file in the `GET /api/v1/keys` format.
    File(&'a Path),
    /// The hub at this base URL (`GET {url}/api/v1/keys`).
    Hub(&'a str),
}

/// What a statement check found: the statement, the key that signed it, and whether the
/// answers file was compared.
#[derive(Debug, Clone)]
pub struct Checked {
    pub statement: StatementPayload,
    pub key: crate::core::statement::PublishedKey,
    /// The answers file that matched the statement's digest, when one was given.
    pub answers: Option<String>,
}

/// Why a check refused a statement: [`StatementError`](crate::core::statement::StatementError)
/// or a file or hub that could not be read, each with what was wrong.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct CheckRefused(pub String);

/// Checks the statement in the file `statement` against the hub's public keys, and with
/// `answers`, that the file's bytes are the answers the statement was made for. Offline but
/// for fetching the keys from a hub.
pub async fn check(
    statement: &Path,
    keys: KeysFrom<'_>,
    answers: Option<&Path>,
) -> Result<Checked, CheckRefused> {
    let refuse = |e: String| CheckRefused(e);
    let text = std::fs::read_to_string(statement)
        .map_err(|e| refuse(format!("cannot read {}: {e}", statement.display())))?;
    let envelope = Envelope::parse(&text).map_err(|e| refuse(e.to_string()))?;
    let keys = match keys {
        KeysFrom::File(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| refuse(format!("cannot read {}: {e}", path.display())))?;
            PublishedKeys::parse(&text).map_err(|e| refuse(format!("{}: {e}", path.display())))?
        }
        KeysFrom::Hub(url) => fetch_keys(url).await.map_err(refuse)?,
    };
    let verified =
        crate::core::statement::verify(&envelope, &keys).map_err(|e| refuse(e.to_string()))?;
    let payload = verified.statement().map_err(|e| refuse(e.to_string()))?;
    let answers = match answers {
        None => None,
        Some(path) => {
            let bytes = std::fs::read(path)
                .map_err(|e| refuse(format!("cannot read {}: {e}", path.display())))?;
            let name = path.display().to_string();
            payload
                .check_answers(&name, &bytes)
                .map_err(|e| refuse(e.to_string()))?;
            Some(name)
        }
    };
    Ok(Checked {
        statement: payload,
        key: verified.key,
        answers,
    })
}

/// The public keys the hub at `url` lists, checked.
async fn fetch_keys(url: &str) -> Result<Vec<TrustedKey>, String> {
    let base = url::Url::parse(url.trim()).map_err(|e| format!("--hub {url:?}: not a URL: {e}"))?;
    if !matches!(base.scheme(), "http" | "https") || base.host_str().is_none() {
        return Err(format!(
            "--hub {url:?}: must be an http:// or https:// URL with a host"
        ));
    }
    let endpoint = format!("{}/api/v1/keys", base.as_str().trim_end_matches('/'));
    let client = reqwest::Client::builder()
        .timeout(std::time::Duration::from_secs(30))
        .build()
        .map_err(|e| format!("cannot make an HTTP client: {e}"))?;
    let response = client
        .get(&endpoint)
        .send()
        .await
        .map_err(|e| format!("cannot fetch {endpoint}: {}", with_causes(&e)))?;
    let status = response.status();
    let text = response
        .text()
        .await
        .map_err(|e| format!("cannot read {endpoint}: {}", with_causes(&e)))?;
    if !status.is_success() {
        return Err(format!("{endpoint} answered {status}"));
    }
    PublishedKeys::parse(&text).map_err(|e| format!("{endpoint}: {e}"))
}

/// An error with its causes, on one line (a connection error says why it failed).
fn with_causes(e: &(dyn std::error::Error + 'static)) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(cause) = source {
        let cause_text = cause.to_string();
        if !text.contains(&cause_text) {
            text.push_str(": ");
            text.push_str(&cause_text);
        }
        source = cause.source();
    }
    text
}
