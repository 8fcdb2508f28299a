//! Signed statements: what the hub computed for a submission, in a form anyone can check
//! offline with the hub's public key.
//!
//! A statement is a DSSE envelope (the in-toto / Sigstore envelope,
//! <https://github.com/secure-systems-lab/dsse/blob/master/protocol.md>):
//!
//! ```json
//! {"payloadType": "application/vnd.enact-hub.statement+json",
//!  "payload": "<base64 of the statement's JSON>",
//!  "signatures": [{"keyid": "<16 hex digits>", "sig": "<base64 of 64 bytes>"}]}
//! ```
//!
//! The signature is Ed25519 over DSSE's pre-authentication encoding of the payload ([`pae`]):
//! `"DSSEv1" SP LEN(type) SP type SP LEN(body) SP body`, each length the ASCII decimal count of
//! bytes. A key's id ([`keyid_of`]) is the first 16 hex digits of the SHA-256 of its 32 raw
//! public-key bytes. Base64 is the standard alphabet with padding (RFC 4648 §4), written and
//! read only that way, so one envelope's bytes have one spelling.
//!
//! The payload ([`StatementPayload`], compact JSON) names the hub, the submission, the dataset
//! and three digests, each defined here so that a third party can compute it again:
//!
//! - `answers_sha256` ([`answers_sha256`]): SHA-256 of the answers exactly as uploaded (the
//!   request body's bytes; for a model run, the answers file it submitted).
//! - `dataset.items_sha256` ([`items_sha256`]): the dataset fingerprint the agreement reports
//!   also carry: SHA-256 over one line `item_id TAB content_hash LF` per item, sorted by item id
//!   (bytewise), where an item's `content_hash` is the SHA-256 of its canonical JSON as the
//!   import stored it (id, type, task name, key frame ids, image paths, frame SHA-256s,
//!   question, ground truth).
//! - `verdicts.sha256` ([`verdicts_sha256`]): SHA-256 over one line per item verdict, sorted by
//!   item id (bytewise): `item_id TAB outcome TAB exact TAB semantic TAB task TAB pairwise LF`,
//!   where `outcome` is `scored`, `unparseable` or `missing`, the three flags are `1` or `0`
//!   (exact match, semantic match, task accuracy), and `pairwise` is `-` when the item has no
//!   pairwise accuracy, else the 16 lowercase hex digits of the value's IEEE 754 binary64 bits,
//!   big-endian (Python: `struct.pack(">d", x).hex()`), so no decimal formatting is involved.
//!   These are the fields `GET /api/v1/submissions/{id}` lists per item when a dataset's
//!   answers are public.
//!
//! Nothing here reads a file, a clock or a random source: the hub makes keys from 32 random
//! bytes and passes the time in.

use std::fmt;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;
use ed25519_dalek::{Signature, Signer as _, SigningKey, Verifier as _, VerifyingKey};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use sha2::{Digest, Sha256};

use crate::agreement::report::dataset_content_hash;
use crate::submission::{ItemVerdict, SubmissionScores, VerdictOutcome};
use crate::verifier::{ScoringPolicy, StrictOutcome};

/// The DSSE payload type of every statement this hub makes.
pub const PAYLOAD_TYPE: &str = "application/vnd.enact-hub.statement+json";

/// The payload's format, its `statement` field: bump it when a field's meaning changes.
pub const STATEMENT_FORMAT: &str = "enact-hub.statement/1";

/// The only signature algorithm, as the keys list names it.
pub const ALGORITHM: &str = "ed25519";

/// Bytes in a raw Ed25519 secret key (its seed) and in a raw public key.
pub const KEY_BYTES: usize = 32;

/// Why a statement, a keys list or an answers file was refused: each names what was wrong and
/// where.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum StatementError {
    /// The envelope is not what DSSE says it is; the message names the field.
    #[error("malformed envelope: {0}")]
    MalformedEnvelope(String),
    /// The keys list is not the `/api/v1/keys` format; the message names the field.
    #[error("malformed keys list: {0}")]
    MalformedKeys(String),
    /// No signature is by a key in the list.
    #[error("unknown key id {keyid}: the keys given list {known}")]
    UnknownKey { keyid: String, known: String },
    /// A signature by a listed key does not verify: the payload or the signature changed.
    #[error(
        "bad signature: signatures[{index}] by key {keyid} does not verify over the payload \
         (the payload or the signature was changed, or it was signed by another key)"
    )]
    BadSignature { index: usize, keyid: String },
    /// The signature verifies but the payload is not a statement this build reads.
    #[error("malformed payload: {0}")]
    MalformedPayload(String),
    /// The answers file is not the one the statement was made for.
    #[error("answers differ: {file} has SHA-256 {actual}, the statement names {expected}")]
    AnswersDiffer {
        file: String,
        actual: String,
        expected: String,
    },
}

/// DSSE's pre-authentication encoding of `body` as `payload_type`: what is signed.
pub fn pae(payload_type: &str, body: &[u8]) -> Vec<u8> {
    let head = format!(
        "DSSEv1 {} {} {} ",
        payload_type.len(),
        payload_type,
        body.len()
    );
    let mut out = Vec::with_capacity(head.len() + body.len());
    out.extend_from_slice(head.as_bytes());
    out.extend_from_slice(body);
    out
}

/// A key's id: the first 16 hex digits of the SHA-256 of its 32 raw public-key bytes.
pub fn keyid_of(public_key: &[u8; KEY_BYTES]) -> String {
    let mut id = hex::encode(Sha256::digest(public_key));
    id.truncate(16);
    id
}

/// A DSSE envelope.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct Envelope {
    /// `application/vnd.enact-hub.statement+json`.
    #[serde(rename = "payloadType")]
    pub payload_type: String,
    /// The statement's JSON, base64 (standard alphabet, padded).
    pub payload: String,
    /// One signature per key that signed; the hub signs with one.
    pub signatures: Vec<EnvelopeSignature>,
}

/// One signature of an envelope.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct EnvelopeSignature {
    /// The signing key's id, as `GET /api/v1/keys` lists it.
    pub keyid: String,
    /// The Ed25519 signature over the pre-authentication encoding, base64 of its 64 bytes.
    pub sig: String,
}

/// A string field of a JSON object, or why not, naming it by `path`.
fn string_field(
    object: &serde_json::Map<String, Value>,
    path: &str,
    name: &str,
) -> Result<String, String> {
    match object.get(name) {
        None => Err(format!("`{path}{name}` is missing")),
        Some(Value::String(s)) => Ok(s.clone()),
        Some(other) => Err(format!(
            "`{path}{name}` must be a string, not {}",
            json_kind(other)
        )),
    }
}

fn json_kind(value: &Value) -> &'static str {
    match value {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

/// Base64 (standard alphabet, padded) of `bytes`.
fn base64(bytes: &[u8]) -> String {
    STANDARD.encode(bytes)
}

/// The bytes of a base64 field, or why not, naming the field.
fn unbase64(text: &str, field: &str) -> Result<Vec<u8>, String> {
    STANDARD
        .decode(text)
        .map_err(|e| format!("`{field}` is not base64 (standard alphabet, padded): {e}"))
}

impl Envelope {
    /// Reads an envelope from JSON text; a refusal names the field that is wrong.
    pub fn parse(text: &str) -> Result<Envelope, StatementError> {
        let bad = StatementError::MalformedEnvelope;
        let value: Value = serde_json::from_str(text).map_err(|e| bad(format!("not JSON: {e}")))?;
        let Value::Object(object) = value else {
            return Err(bad(format!(
                "the envelope must be a JSON object, not {}",
                json_kind(&value)
            )));
        };
        let payload_type = string_field(&object, "", "payloadType").map_err(bad)?;
        let payload = string_field(&object, "", "payload").map_err(bad)?;
        let signatures = match object.get("signatures") {
            None => return Err(bad("`signatures` is missing".to_owned())),
            Some(Value::Array(list)) if list.is_empty() => {
                return Err(bad("`signatures` is empty".to_owned()));
            }
            Some(Value::Array(list)) => list,
            Some(other) => {
                return Err(bad(format!(
                    "`signatures` must be an array, not {}",
                    json_kind(other)
                )));
            }
        };
        let signatures = signatures
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let path = format!("signatures[{i}].");
                let Value::Object(s) = s else {
                    return Err(format!(
                        "`signatures[{i}]` must be an object, not {}",
                        json_kind(s)
                    ));
                };
                Ok(EnvelopeSignature {
                    keyid: string_field(s, &path, "keyid")?,
                    sig: string_field(s, &path, "sig")?,
                })
            })
            .collect::<Result<Vec<_>, String>>()
            .map_err(bad)?;
        Ok(Envelope {
            payload_type,
            payload,
            signatures,
        })
    }

    /// The envelope as JSON text (what the hub stores and serves).
    pub fn to_json(&self) -> String {
        // A struct of strings always serialises.
        serde_json::to_string(self).unwrap_or_default()
    }
}

/// The hub's signing key: an Ed25519 secret key. Its `Debug` never shows the secret.
pub struct StatementKey {
    signing: SigningKey,
}

impl fmt::Debug for StatementKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("StatementKey")
            .field("keyid", &self.keyid())
            .finish_non_exhaustive()
    }
}

impl StatementKey {
    /// The key whose raw secret (Ed25519 seed) is `secret`.
    pub fn from_secret(secret: &[u8; KEY_BYTES]) -> StatementKey {
        StatementKey {
            signing: SigningKey::from_bytes(secret),
        }
    }

    /// The raw secret, to be written to the key file.
    pub fn secret(&self) -> [u8; KEY_BYTES] {
        self.signing.to_bytes()
    }

    /// The raw public key.
    pub fn public_key(&self) -> [u8; KEY_BYTES] {
        self.signing.verifying_key().to_bytes()
    }

    /// The key's id ([`keyid_of`]).
    pub fn keyid(&self) -> String {
        keyid_of(&self.public_key())
    }

    /// The key as `GET /api/v1/keys` lists it.
    pub fn published(&self, created_at: &str, retired_at: Option<&str>) -> PublishedKey {
        PublishedKey {
            keyid: self.keyid(),
            algorithm: ALGORITHM.to_owned(),
            public_key: base64(&self.public_key()),
            created_at: created_at.to_owned(),
            retired_at: retired_at.map(str::to_owned),
        }
    }

    /// `body` as `payload_type` in an envelope signed with this key.
    pub fn sign_envelope(&self, payload_type: &str, body: &[u8]) -> Envelope {
        let signature = self.signing.sign(&pae(payload_type, body));
        Envelope {
            payload_type: payload_type.to_owned(),
            payload: base64(body),
            signatures: vec![EnvelopeSignature {
                keyid: self.keyid(),
                sig: base64(&signature.to_bytes()),
            }],
        }
    }

    /// `statement` signed with this key.
    pub fn sign_statement(&self, statement: &StatementPayload) -> Envelope {
        self.sign_envelope(PAYLOAD_TYPE, &statement.to_bytes())
    }
}

/// The public keys a hub lists (`GET /api/v1/keys`): every key it ever signed with.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct PublishedKeys {
    pub keys: Vec<PublishedKey>,
}

/// One public key of the hub.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct PublishedKey {
    /// The first 16 hex digits of the SHA-256 of the raw public key.
    pub keyid: String,
    /// `ed25519`.
    pub algorithm: String,
    /// Base64 of the 32 raw public-key bytes.
    pub public_key: String,
    /// When the hub started signing with it (UTC, ISO 8601).
    pub created_at: String,
    /// When it was rotated away (it signs no new statement since, and still verifies the old).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub retired_at: Option<String>,
}

/// A listed key, checked and ready to verify with.
#[derive(Debug, Clone)]
pub struct TrustedKey {
    pub listed: PublishedKey,
    key: VerifyingKey,
}

impl PublishedKeys {
    /// Reads a keys list in the `/api/v1/keys` format and checks every key: its algorithm, its
    /// 32 bytes, and that its `keyid` is its own. A refusal names the field.
    pub fn parse(text: &str) -> Result<Vec<TrustedKey>, StatementError> {
        let bad = StatementError::MalformedKeys;
        let value: Value = serde_json::from_str(text).map_err(|e| bad(format!("not JSON: {e}")))?;
        let keys = match &value {
            Value::Object(o) => match o.get("keys") {
                Some(Value::Array(keys)) => keys,
                Some(other) => {
                    return Err(bad(format!(
                        "`keys` must be an array, not {}",
                        json_kind(other)
                    )));
                }
                None => return Err(bad("`keys` is missing".to_owned())),
            },
            other => {
                return Err(bad(format!(
                    "the keys list must be a JSON object, not {}",
                    json_kind(other)
                )));
            }
        };
        keys.iter()
            .enumerate()
            .map(|(i, k)| {
                let path = format!("keys[{i}].");
                let Value::Object(k) = k else {
                    return Err(bad(format!(
                        "`keys[{i}]` must be an object, not {}",
                        json_kind(k)
                    )));
                };
                let retired_at = match k.get("retired_at") {
                    None | Some(Value::Null) => None,
                    Some(_) => Some(string_field(k, &path, "retired_at").map_err(bad)?),
                };
                let listed = PublishedKey {
                    keyid: string_field(k, &path, "keyid").map_err(bad)?,
                    algorithm: string_field(k, &path, "algorithm").map_err(bad)?,
                    public_key: string_field(k, &path, "public_key").map_err(bad)?,
                    created_at: string_field(k, &path, "created_at").unwrap_or_default(),
                    retired_at,
                };
                TrustedKey::of(listed, &format!("keys[{i}]"))
            })
            .collect()
    }
}

impl TrustedKey {
    /// `listed`, checked (`at` names it in a refusal).
    pub fn of(listed: PublishedKey, at: &str) -> Result<TrustedKey, StatementError> {
        let bad = StatementError::MalformedKeys;
        if listed.algorithm != ALGORITHM {
            return Err(bad(format!(
                "`{at}.algorithm` is {:?}; only {ALGORITHM:?} is known",
                listed.algorithm
            )));
        }
        let bytes = unbase64(&listed.public_key, &format!("{at}.public_key")).map_err(bad)?;
        let raw: [u8; KEY_BYTES] = bytes.as_slice().try_into().map_err(|_| {
            bad(format!(
                "`{at}.public_key` holds {} bytes; an Ed25519 public key is {KEY_BYTES}",
                bytes.len()
            ))
        })?;
        let key = VerifyingKey::from_bytes(&raw)
            .map_err(|_| bad(format!("`{at}.public_key` is not an Ed25519 public key")))?;
        let own = keyid_of(&raw);
        if listed.keyid != own {
            return Err(bad(format!(
                "`{at}.keyid` is {:?} but its public key's id is {own:?}",
                listed.keyid
            )));
        }
        Ok(TrustedKey { listed, key })
    }
}

/// What a verified envelope holds: the key that signed it and the payload's bytes.
#[derive(Debug, Clone)]
pub struct Verified {
    pub key: PublishedKey,
    pub payload_type: String,
    pub payload: Vec<u8>,
}

/// Checks `envelope`'s signatures against `keys`: it verifies when a signature by a listed key
/// verifies over the pre-authentication encoding of its payload. A signature by a listed key
/// that does not verify refuses the envelope (a changed payload or signature), whatever the
/// others say; no signature by a listed key is an unknown key.
pub fn verify(envelope: &Envelope, keys: &[TrustedKey]) -> Result<Verified, StatementError> {
    let bad = StatementError::MalformedEnvelope;
    let payload = unbase64(&envelope.payload, "payload").map_err(bad)?;
    if envelope.signatures.is_empty() {
        return Err(bad("`signatures` is empty".to_owned()));
    }
    let signed = pae(&envelope.payload_type, &payload);
    let mut good = None;
    for (i, s) in envelope.signatures.iter().enumerate() {
        let Some(key) = keys.iter().find(|k| k.listed.keyid == s.keyid) else {
            continue;
        };
        let field = format!("signatures[{i}].sig");
        let bytes = unbase64(&s.sig, &field).map_err(bad)?;
        let raw: [u8; 64] = bytes.as_slice().try_into().map_err(|_| {
            bad(format!(
                "`{field}` holds {} bytes; an Ed25519 signature is 64",
                bytes.len()
            ))
        })?;
        let signature = Signature::from_bytes(&raw);
        if key.key.verify(&signed, &signature).is_err() {
            return Err(StatementError::BadSignature {
                index: i,
                keyid: s.keyid.clone(),
            });
        }
        good.get_or_insert_with(|| key.listed.clone());
    }
    match good {
        Some(key) => Ok(Verified {
            key,
            payload_type: envelope.payload_type.clone(),
            payload,
        }),
        None => Err(StatementError::UnknownKey {
            keyid: envelope
                .signatures
                .iter()
                .map(|s| s.keyid.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            known: if keys.is_empty() {
                "no key".to_owned()
            } else {
                keys.iter()
                    .map(|k| k.listed.keyid.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            },
        }),
    }
}

impl Verified {
    /// The payload as a statement of this build's format.
    pub fn statement(&self) -> Result<StatementPayload, StatementError> {
        if self.payload_type != PAYLOAD_TYPE {
            return Err(StatementError::MalformedPayload(format!(
                "`payloadType` is {:?}, not {PAYLOAD_TYPE:?}: not an enact-hub statement",
                self.payload_type
            )));
        }
        StatementPayload::from_bytes(&self.payload)
    }
}

/// The hub that made a statement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HubIdentity {
    /// `enact-hub`.
    pub name: String,
    /// The hub's public URL as its operator set it (`serve --public-url`), if they did.
    pub url: Option<String>,
    /// The build that made the statement (`version+commit`).
    pub version: String,
}

/// The submission a statement is about.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SubmissionFacts {
    pub id: i64,
    pub model: String,
    pub account: String,
    /// When it was submitted (UTC, ISO 8601).
    pub created_at: String,
    /// The build that computed its scores (empty for scores from before builds were kept).
    pub scored_by: String,
}

/// The dataset a submission was scored on.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct DatasetFacts {
    pub name: String,
    /// How many items `items_sha256` is over.
    pub items: usize,
    /// [`items_sha256`].
    pub items_sha256: String,
}

/// The per-item verdicts of a submission.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct VerdictFacts {
    /// How many verdicts `sha256` is over.
    pub count: usize,
    /// [`verdicts_sha256`].
    pub sha256: String,
}

/// What a statement says (its payload, as compact JSON).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StatementPayload {
    /// [`STATEMENT_FORMAT`].
    pub statement: String,
    pub hub: HubIdentity,
    pub submission: SubmissionFacts,
    pub dataset: DatasetFacts,
    /// [`answers_sha256`].
    pub answers_sha256: String,
    pub verdicts: VerdictFacts,
    /// The metric version the scores and verdicts were computed with.
    pub metric_version: u32,
    pub policy: ScoringPolicy,
    /// `run` (the hub asked the model itself) or `submitted` (answers uploaded).
    pub provenance: String,
    /// The scores, as `GET /api/v1/submissions/{id}` reports them (its `scores`).
    pub scores: SubmissionScores,
    /// When the statement was made (UTC, ISO 8601).
    pub made_at: String,
}

impl StatementPayload {
    /// The payload's bytes: compact JSON, fields in declaration order.
    pub fn to_bytes(&self) -> Vec<u8> {
        // Strings, numbers and the scores (which the API serialises the same way) always
        // serialise.
        serde_json::to_vec(self).unwrap_or_default()
    }

    /// Reads a payload; a refusal names the field.
    pub fn from_bytes(bytes: &[u8]) -> Result<StatementPayload, StatementError> {
        let bad = StatementError::MalformedPayload;
        let value: Value =
            serde_json::from_slice(bytes).map_err(|e| bad(format!("not JSON: {e}")))?;
        match value.get("statement") {
            Some(Value::String(format)) if format == STATEMENT_FORMAT => {}
            Some(Value::String(format)) => {
                return Err(bad(format!(
                    "`statement` is {format:?}; this build reads {STATEMENT_FORMAT:?}"
                )));
            }
            _ => return Err(bad("`statement` is missing or not a string".to_owned())),
        }
        serde_json::from_value(value).map_err(|e| bad(e.to_string()))
    }

    /// One line about the scores: overall task and pairwise accuracy.
    pub fn scores_summary(&self) -> String {
        match &self.scores.report.overall {
            None => "no item scored".to_owned(),
            Some(overall) => {
                let totals = &overall.totals;
                let pairwise = totals
                    .pairwise_accuracy
                    .map_or("n/a".to_owned(), |p| format!("{:.1}%", p * 100.0));
                format!(
                    "task accuracy {:.1}%, pairwise accuracy {pairwise} over {} items",
                    totals.task_accuracy * 100.0,
                    totals.count
                )
            }
        }
    }

    /// Whether `answers` are the bytes the statement was made for.
    pub fn check_answers(&self, file: &str, answers: &[u8]) -> Result<(), StatementError> {
        let actual = answers_sha256(answers);
        if actual == self.answers_sha256 {
            Ok(())
        } else {
            Err(StatementError::AnswersDiffer {
                file: file.to_owned(),
                actual,
                expected: self.answers_sha256.clone(),
            })
        }
    }
}

/// SHA-256 (lowercase hex) of the answers exactly as uploaded.
pub fn answers_sha256(body: &[u8]) -> String {
    hex::encode(Sha256::digest(body))
}

/// A dataset's items digest (see the module's documentation) over `(item_id, content_hash)`
/// pairs in any order.
pub fn items_sha256<'a>(items: impl IntoIterator<Item = (&'a str, &'a str)>) -> DatasetDigest {
    let items: Vec<(&str, &str)> = items.into_iter().collect();
    DatasetDigest {
        items: items.len(),
        sha256: dataset_content_hash(items),
    }
}

/// [`items_sha256`] of a dataset's items.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DatasetDigest {
    pub items: usize,
    pub sha256: String,
}

/// One item's verdict as the verdicts digest reads it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerdictLine<'a> {
    pub item_id: &'a str,
    pub outcome: VerdictOutcome,
    pub exact_match: bool,
    pub semantic_match: bool,
    pub task_accuracy: bool,
    pub pairwise_accuracy: Option<f64>,
}

impl<'a> VerdictLine<'a> {
    /// A verdict just computed, about item `item_id`, with the flags the store keeps for it
    /// (an answer that was not scored matches nothing).
    pub fn of(item_id: &'a str, verdict: &ItemVerdict) -> VerdictLine<'a> {
        let (exact_match, semantic_match) = match &verdict.outcome {
            StrictOutcome::Scored { verdict, .. } => (verdict.exact_match, verdict.semantic_match),
            StrictOutcome::Unparseable { .. } | StrictOutcome::Missing => (false, false),
        };
        VerdictLine {
            item_id,
            outcome: VerdictOutcome::of(&verdict.outcome),
            exact_match,
            semantic_match,
            task_accuracy: verdict.task_accuracy,
            pairwise_accuracy: verdict.pairwise_accuracy,
        }
    }

    fn write(&self, out: &mut Vec<u8>) {
        let flag = |b: bool| if b { "1" } else { "0" };
        let pairwise = self
            .pairwise_accuracy
            .map_or("-".to_owned(), |p| format!("{:016x}", p.to_bits()));
        out.extend_from_slice(self.item_id.as_bytes());
        for field in [
            self.outcome.as_str(),
            flag(self.exact_match),
            flag(self.semantic_match),
            flag(self.task_accuracy),
            &pairwise,
        ] {
            out.push(b'\t');
            out.extend_from_slice(field.as_bytes());
        }
        out.push(b'\n');
    }
}

/// The verdicts digest (see the module's documentation) over `lines` in any order.
pub fn verdicts_sha256(mut lines: Vec<VerdictLine<'_>>) -> VerdictFacts {
    lines.sort_by(|a, b| a.item_id.as_bytes().cmp(b.item_id.as_bytes()));
    let mut hasher = Sha256::new();
    let mut line = Vec::new();
    for verdict in &lines {
        line.clear();
        verdict.write(&mut line);
        hasher.update(&line);
    }
    VerdictFacts {
        count: lines.len(),
        sha256: hex::encode(hasher.finalize()),
    }
}

/// `unix_seconds` as the store writes times: `2026-11-25T10:00:00Z` (UTC).
pub fn utc_timestamp(unix_seconds: u64) -> String {
    let days = unix_seconds / 86_400;
    let rest = unix_seconds % 86_400;
    let (year, month, day) = civil_from_days(days);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rest / 3600,
        rest % 3600 / 60,
        rest % 60
    )
}

/// The proleptic Gregorian date `days` after 1970-01-01 (Howard Hinnant's algorithm).
fn civil_from_days(days: u64) -> (u64, u64, u64) {
    let z = days + 719_468;
    let era = z / 146_097;
    let doe = z % 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + u64::from(month <= 2);
    (year, month, day)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::submission::ConfidenceIntervals;
    use crate::verifier::{Coverage, PerformanceReport, Resampling};

    fn key(seed: u8) -> StatementKey {
        StatementKey::from_secret(&[seed; KEY_BYTES])
    }

    fn trusted(key: &StatementKey) -> TrustedKey {
        TrustedKey::of(key.published("2026-01-01T00:00:00Z", None), "keys[0]")
            .expect("a key's own listing is valid")
    }

    fn statement() -> StatementPayload {
        StatementPayload {
            statement: STATEMENT_FORMAT.to_owned(),
            hub: HubIdentity {
                name: "enact-hub".to_owned(),
                url: Some("https://hub.example".to_owned()),
                version: "0.1.0+abcdef123456".to_owned(),
            },
            submission: SubmissionFacts {
                id: 7,
                model: "m".to_owned(),
                account: "team".to_owned(),
                created_at: "2026-01-01T00:00:00Z".to_owned(),
                scored_by: "0.1.0+abcdef123456".to_owned(),
            },
            dataset: DatasetFacts {
                name: "mini".to_owned(),
                items: 2,
                items_sha256: "ab".repeat(32),
            },
            answers_sha256: answers_sha256(b"answers"),
            verdicts: VerdictFacts {
                count: 2,
                sha256: "cd".repeat(32),
            },
            metric_version: 3,
            policy: ScoringPolicy::Strict,
            provenance: "submitted".to_owned(),
            scores: SubmissionScores {
                policy: ScoringPolicy::Strict,
                report: PerformanceReport::default(),
                coverage: Coverage {
                    dataset_items: 2,
                    answered: 2,
                    missing: 0,
                    unparseable: 0,
                    coverage: 1.0,
                    parse_failure_rate: 0.0,
                    exact_only: 0,
                },
                confidence: ConfidenceIntervals {
                    level: 0.95,
                    resamples: 1000,
                    seed: 1,
                    resampling: Resampling::Activities,
                    task_accuracy: None,
                    pairwise_accuracy: None,
                    by_items: None,
                },
            },
            made_at: "2026-01-02T03:04:05Z".to_owned(),
        }
    }

    #[test]
    fn pae_matches_the_dsse_specification_example() {
        // protocol.md: PAE("http://example.com/HelloWorld", "hello world"); the type is 29
        // bytes ("http://" 7 + "example.com" 11 + "/HelloWorld" 11), the body 11.
        assert_eq!(
            pae("http://example.com/HelloWorld", b"hello world"),
            b"DSSEv1 29 http://example.com/HelloWorld 11 hello world".to_vec()
        );
        assert_eq!(pae("", b""), b"DSSEv1 0  0 ".to_vec());
        // Lengths count bytes, not characters.
        assert_eq!(pae("é", b"\xff"), b"DSSEv1 2 \xc3\xa9 1 \xff".to_vec());
    }

    #[test]
    fn ed25519_matches_rfc_8032_test_1() {
        let secret: [u8; 32] =
            hex::decode("9d61b19deffd5a60ba844af492ec2cc44449c5697b326919703bac031cae7f60")
                .expect("hex")
                .try_into()
                .expect("32 bytes");
        let key = StatementKey::from_secret(&secret);
        assert_eq!(
            hex::encode(key.public_key()),
            "d75a980182b10ab7d54bfed3c964073a0ee172f3daa62325af021a68f707511a"
        );
        assert_eq!(
            hex::encode(key.signing.sign(b"").to_bytes()),
            "e5564300c360ac729086e2cc806e828a84877f1eb8e5d974d873e065224901555fb8821590a33bacc61e39701cf9b46bd25bf5f0595bbe24655141438e7a100b"
        );
        assert_eq!(
            key.keyid(),
            hex::encode(Sha256::digest(key.public_key()))[..16]
        );
    }

    #[test]
    fn a_signed_statement_verifies_and_reads_back() {
        let key = key(1);
        let envelope = key.sign_statement(&statement());
        let parsed = Envelope::parse(&envelope.to_json()).expect("its own JSON parses");
        assert_eq!(parsed, envelope);
        let verified = verify(&parsed, &[trusted(&key)]).expect("verifies");
        assert_eq!(verified.key.keyid, key.keyid());
        assert_eq!(verified.statement().expect("a statement"), statement());
    }

    #[test]
    fn changing_any_byte_of_the_payload_or_the_signature_fails() {
        let key = key(2);
        let envelope = key.sign_statement(&statement());
        let keys = [trusted(&key)];
        let payload = STANDARD.decode(&envelope.payload).expect("base64");
        for i in 0..payload.len() {
            let mut changed = payload.clone();
            changed[i] ^= 0x01;
            let tampered = Envelope {
                payload: base64(&changed),
                ..envelope.clone()
            };
            assert!(
                matches!(
                    verify(&tampered, &keys),
                    Err(StatementError::BadSignature { .. })
                ),
                "payload byte {i}"
            );
        }
        let sig = STANDARD
            .decode(&envelope.signatures[0].sig)
            .expect("base64");
        for i in 0..sig.len() {
            let mut changed = sig.clone();
            changed[i] ^= 0x80;
            let mut tampered = envelope.clone();
            tampered.signatures[0].sig = base64(&changed);
            assert!(
                matches!(
                    verify(&tampered, &keys),
                    Err(StatementError::BadSignature { .. })
                ),
                "signature byte {i}"
            );
        }
        // The type is signed too.
        let retyped = Envelope {
            payload_type: "application/json".to_owned(),
            ..envelope
        };
        assert!(verify(&retyped, &keys).is_err());
    }

    #[test]
    fn another_key_is_an_unknown_key_and_a_listed_impostor_a_bad_signature() {
        let (signer, other) = (key(3), key(4));
        let envelope = signer.sign_statement(&statement());
        let e = verify(&envelope, &[trusted(&other)]).expect_err("unknown");
        assert!(e.to_string().starts_with("unknown key id "), "{e}");
        assert!(e.to_string().contains(&other.keyid()), "{e}");
        let mut impostor = envelope.clone();
        impostor.signatures[0].keyid = other.keyid();
        assert!(matches!(
            verify(&impostor, &[trusted(&other)]),
            Err(StatementError::BadSignature { .. })
        ));
    }

    #[test]
    fn a_malformed_envelope_names_the_field() {
        let cases = [
            ("[]", "must be a JSON object"),
            (
                "{\"payload\": \"\", \"signatures\": []}",
                "`payloadType` is missing",
            ),
            (
                "{\"payloadType\": 1, \"payload\": \"\", \"signatures\": []}",
                "`payloadType` must be a string",
            ),
            (
                "{\"payloadType\": \"t\", \"payload\": \"\", \"signatures\": []}",
                "`signatures` is empty",
            ),
            (
                "{\"payloadType\": \"t\", \"payload\": \"\", \"signatures\": [{\"keyid\": \"k\"}]}",
                "`signatures[0].sig` is missing",
            ),
        ];
        for (text, expected) in cases {
            let e = Envelope::parse(text).expect_err(text);
            assert!(e.to_string().contains(expected), "{text}: {e}");
            assert!(e.to_string().starts_with("malformed envelope: "), "{e}");
        }
        let key = key(5);
        let mut envelope = key.sign_statement(&statement());
        envelope.payload.insert(3, '*');
        let e = verify(&envelope, &[trusted(&key)]).expect_err("not base64");
        assert!(e.to_string().contains("`payload` is not base64"), "{e}");
    }

    #[test]
    fn a_keys_list_is_checked_key_by_key() {
        let key = key(6);
        let good = serde_json::to_string(&PublishedKeys {
            keys: vec![key.published("2026-01-01T00:00:00Z", Some("2026-02-01T00:00:00Z"))],
        })
        .expect("json");
        let parsed = PublishedKeys::parse(&good).expect("valid");
        assert_eq!(
            parsed[0].listed.retired_at.as_deref(),
            Some("2026-02-01T00:00:00Z")
        );
        let wrong_id = good.replace(&key.keyid(), "0000000000000000");
        let e = PublishedKeys::parse(&wrong_id).expect_err("not its id");
        assert!(e.to_string().contains("`keys[0].keyid`"), "{e}");
        let e = PublishedKeys::parse("{\"keys\": [{\"keyid\": \"x\"}]}").expect_err("no key");
        assert!(
            e.to_string().contains("`keys[0].algorithm` is missing"),
            "{e}"
        );
        let e = PublishedKeys::parse("{}").expect_err("no keys");
        assert!(e.to_string().contains("`keys` is missing"), "{e}");
    }

    #[test]
    fn answers_are_checked_by_their_bytes() {
        let s = statement();
        assert!(s.check_answers("a.jsonl", b"answers").is_ok());
        let e = s
            .check_answers("b.jsonl", b"answers\n")
            .expect_err("differs");
        assert!(
            e.to_string()
                .starts_with("answers differ: b.jsonl has SHA-256 "),
            "{e}"
        );
    }

    #[test]
    fn the_verdicts_digest_is_the_documented_lines_in_item_order() {
        let line = |item_id, outcome, t, pa| VerdictLine {
            item_id,
            outcome,
            exact_match: t,
            semantic_match: t,
            task_accuracy: t,
            pairwise_accuracy: pa,
        };
        let facts = verdicts_sha256(vec![
            line("b", VerdictOutcome::Missing, false, None),
            line("a", VerdictOutcome::Scored, true, Some(1.0)),
        ]);
        let expected = "a\tscored\t1\t1\t1\t3ff0000000000000\nb\tmissing\t0\t0\t0\t-\n";
        assert_eq!(facts.count, 2);
        assert_eq!(facts.sha256, hex::encode(Sha256::digest(expected)));
    }

    #[test]
    fn the_items_digest_is_the_agreement_reports_fingerprint() {
        let digest = items_sha256([("b", "2"), ("a", "1")]);
        assert_eq!(digest.items, 2);
        assert_eq!(digest.sha256, hex::encode(Sha256::digest("a\t1\nb\t2\n")));
    }

    #[test]
    fn timestamps_are_utc_iso_8601() {
        assert_eq!(utc_timestamp(0), "1970-01-01T00:00:00Z");
        assert_eq!(utc_timestamp(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(utc_timestamp(1_798_761_599), "2026-12-31T23:59:59Z");
    }
}
