//! Signed statements: every scored submission's DSSE envelope, verified with the key the hub
//! publishes (in Rust, and with `enact-hub verify`), refused after any changed byte or with
//! other answers; key rotation keeping old statements verifiable; a rescore's new statement;
//! statements made on first request for submissions scored before them; the secret kept out
//! of backups.

use std::time::Duration;

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;
use enact_hub::app::{Hub, rescore};
use enact_hub::core::audit::Actor;
use enact_hub::core::credentials::Role;
use enact_hub::core::dataset::AnswerVisibility;
use enact_hub::core::metric::METRIC_VERSION;
use enact_hub::core::statement::{
    Envelope, PAYLOAD_TYPE, PublishedKeys, StatementError, StatementPayload, verify,
};
use reqwest::Method;
use serde_json::{Value, json};
use sha2::{Digest, Sha256};

use crate::helpers::*;
use crate::runs::{answer_text, run_fixture, scripts};
use crate::server_runs::{keyed, run_to_submission};
use crate::standin::{StandIn, StandInConfig, Step};

/// A server with dataset "mini", a submitter's token and an admin's.
struct Hubs {
    server: TestServer,
    records: Vec<Value>,
    submitter: String,
    admin: String,
}

async fn hub_with_tokens() -> Hubs {
    let (server, records) = spawn_app_with_release().await;
    let (_, submitter) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    Hubs {
        server,
        records,
        submitter,
        admin,
    }
}

impl Hubs {
    /// Submits `body` as model `model`; the submission's id.
    async fn submit(&self, model: &str, body: &str) -> i64 {
        let reply = submit_to(
            &self.server,
            "mini",
            &format!("model={model}"),
            &self.submitter,
            body.to_owned(),
        )
        .await;
        assert_eq!(reply.status, 201, "{}", reply.text);
        reply.id()
    }

    /// The statement of submission `id` as its text.
    async fn statement_text(&self, id: i64) -> String {
        self.server
            .call(Method::GET, &format!("/api/v1/submissions/{id}/statement"))
            .bearer(&self.submitter)
            .expect(200)
            .await
            .text
    }

    async fn statement(&self, id: i64) -> Envelope {
        Envelope::parse(&self.statement_text(id).await).expect("an envelope")
    }

    /// `GET /api/v1/keys`, as text.
    async fn keys_text(&self) -> String {
        self.server
            .call(Method::GET, "/api/v1/keys")
            .expect(200)
            .await
            .text
    }
}

/// The statement's payload, once its signature verifies against the hub's published keys.
fn verified(envelope: &Envelope, keys_text: &str) -> (StatementPayload, String) {
    let keys = PublishedKeys::parse(keys_text).expect("the keys list");
    let verified = verify(envelope, &keys).expect("the statement verifies");
    (
        verified.statement().expect("a statement payload"),
        verified.key.keyid,
    )
}

fn sha256_hex(bytes: &[u8]) -> String {
    hex::encode(Sha256::digest(bytes))
}

/// The verdicts digest as a third party computes it from the per-item verdicts the submission
/// API lists (README "How to check a result").
fn verdicts_digest_of(items: &[Value]) -> String {
    let mut lines: Vec<String> = items
        .iter()
        .map(|v| {
            let flag = |name: &str| if v[name] == true { "1" } else { "0" };
            let pairwise = match v["pairwise_accuracy"].as_f64() {
                Some(p) => hex::encode(p.to_be_bytes()),
                None => "-".to_owned(),
            };
            format!(
                "{}\t{}\t{}\t{}\t{}\t{pairwise}\n",
                v["id"].as_str().expect("item id"),
                v["outcome"].as_str().expect("outcome"),
                flag("exact_match"),
                flag("semantic_match"),
                flag("task_accuracy"),
            )
        })
        .collect();
    lines.sort_by(|a, b| {
        let id = |l: &str| l.split('\t').next().unwrap_or_default().to_owned();
        id(a).as_bytes().cmp(id(b).as_bytes())
    });
    sha256_hex(lines.concat().as_bytes())
}

/// The items digest of dataset `name` from its stored content hashes.
async fn items_digest_of(server: &TestServer, name: &str) -> String {
    let mut rows: Vec<(String, String)> = db!(
        server.pool,
        fetch_all,
        sqlx::query_as(
            "SELECT i.item_id, i.content_hash FROM items i JOIN datasets d ON d.id = i.dataset_id \
             WHERE d.name = $1"
        )
        .bind(name)
    )
    .expect("content hashes");
    rows.sort_by(|a, b| a.0.as_bytes().cmp(b.0.as_bytes()));
    let text: String = rows.iter().map(|(id, h)| format!("{id}\t{h}\n")).collect();
    sha256_hex(text.as_bytes())
}

async fn statements_of(server: &TestServer, id: i64) -> i64 {
    count(
        &server.pool,
        &format!("SELECT count(*) FROM submission_statements WHERE submission = {id}"),
    )
    .await
}

/// `enact-hub verify` with `args`: its exit code, standard output and standard error. Run off
/// the test's runtime, which serves the hub `--hub` fetches keys from meanwhile.
async fn verify_cli(args: &[&std::ffi::OsStr]) -> (Option<i32>, String, String) {
    let mut command = enact_hub();
    command.arg("verify").args(args);
    let out = tokio::task::spawn_blocking(move || command.output())
        .await
        .expect("the command's thread")
        .expect("run enact-hub verify");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// An `enact-hub` command beside the running server: its output.
async fn command_output(mut command: std::process::Command) -> std::process::Output {
    tokio::task::spawn_blocking(move || command.output())
        .await
        .expect("the command's thread")
        .expect("run enact-hub")
}

#[tokio::test]
async fn a_scored_submission_s_statement_verifies_with_the_published_key_and_says_what_was_scored()
{
    let hubs = hub_with_tokens().await;
    set_mini_answers(&hubs.server.pool, AnswerVisibility::Public).await;
    let body = answers(&hubs.records, &[1]);
    let id = hubs.submit("m", &body).await;
    // Stored with the submission, in its transaction.
    assert_eq!(statements_of(&hubs.server, id).await, 1);

    let text = hubs.statement_text(id).await;
    let raw: Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(raw["payloadType"], PAYLOAD_TYPE);
    assert_eq!(raw["signatures"].as_array().map(Vec::len), Some(1));
    let envelope = Envelope::parse(&text).expect("an envelope");
    let keys_text = hubs.keys_text().await;
    let keys: Value = serde_json::from_str(&keys_text).expect("JSON");
    let listed = keys["keys"].as_array().expect("keys");
    assert_eq!(listed.len(), 1, "{keys}");
    assert_eq!(listed[0]["algorithm"], "ed25519");
    assert_eq!(
        STANDARD
            .decode(listed[0]["public_key"].as_str().expect("public key"))
            .expect("base64")
            .len(),
        32
    );
    assert!(listed[0].get("retired_at").is_none(), "{keys}");
    let (statement, keyid) = verified(&envelope, &keys_text);
    assert_eq!(keyid, listed[0]["keyid"]);

    // What it says is what the hub stored and reports.
    let shown = hubs
        .server
        .call(Method::GET, &format!("/api/v1/submissions/{id}"))
        .bearer(&hubs.submitter)
        .expect(200)
        .await
        .json();
    assert_eq!(statement.submission.id, id);
    assert_eq!(statement.submission.model, "m");
    assert_eq!(statement.submission.account, "team");
    assert_eq!(statement.submission.created_at, shown["created_at"]);
    assert_eq!(statement.submission.scored_by, shown["scored_by"]);
    assert_eq!(statement.dataset.name, "mini");
    assert_eq!(statement.dataset.items, hubs.records.len());
    assert_eq!(
        statement.dataset.items_sha256,
        items_digest_of(&hubs.server, "mini").await
    );
    assert_eq!(statement.answers_sha256, sha256_hex(body.as_bytes()));
    let items = shown["items"].as_array().expect("per-item verdicts");
    assert_eq!(statement.verdicts.count, items.len());
    assert_eq!(statement.verdicts.sha256, verdicts_digest_of(items));
    assert_eq!(statement.metric_version, METRIC_VERSION);
    assert_eq!(json!(statement.policy), shown["policy"]);
    assert_eq!(statement.provenance, "submitted");
    assert_eq!(json!(statement.scores), shown["scores"]);
    assert!(statement.hub.version.starts_with(env!("CARGO_PKG_VERSION")));
    assert!(statement.made_at.ends_with('Z'), "{}", statement.made_at);

    // Read as the submission is: not without a token, not by another account, by an admin.
    hubs.server
        .call(Method::GET, &format!("/api/v1/submissions/{id}/statement"))
        .expect(401)
        .await;
    let (_, other) = api_token(&hubs.server.pool, "other", Role::Submitter, None, None).await;
    let refused = hubs
        .server
        .call(Method::GET, &format!("/api/v1/submissions/{id}/statement"))
        .bearer(&other)
        .expect(404)
        .await;
    assert!(refused.error().contains(&format!("no submission {id}")));
    hubs.server
        .call(Method::GET, &format!("/api/v1/submissions/{id}/statement"))
        .bearer(&hubs.admin)
        .expect(200)
        .await;
    hubs.server
        .call(Method::GET, "/api/v1/submissions/nope/statement")
        .bearer(&hubs.submitter)
        .expect(404)
        .await;
    hubs.server.stop().await;
}

#[tokio::test]
async fn changing_any_byte_of_the_payload_or_the_signature_fails() {
    let hubs = hub_with_tokens().await;
    let id = hubs.submit("m", &answers(&hubs.records, &[])).await;
    let envelope = hubs.statement(id).await;
    let keys = PublishedKeys::parse(&hubs.keys_text().await).expect("keys");
    verify(&envelope, &keys).expect("verifies as served");

    let payload = STANDARD.decode(&envelope.payload).expect("base64");
    for i in 0..payload.len() {
        let mut changed = payload.clone();
        changed[i] = changed[i].wrapping_add(1);
        let tampered = Envelope {
            payload: STANDARD.encode(&changed),
            ..envelope.clone()
        };
        assert!(
            matches!(
                verify(&tampered, &keys),
                Err(StatementError::BadSignature { .. })
            ),
            "payload byte {i} changed and it still verifies"
        );
    }
    let sig = STANDARD
        .decode(&envelope.signatures[0].sig)
        .expect("base64");
    for i in 0..sig.len() {
        let mut changed = sig.clone();
        changed[i] = changed[i].wrapping_add(1);
        let mut tampered = envelope.clone();
        tampered.signatures[0].sig = STANDARD.encode(&changed);
        assert!(
            verify(&tampered, &keys).is_err(),
            "signature byte {i} changed and it still verifies"
        );
    }

    // And the command line says so, in one line, with exit code 1.
    let dir = tempfile::tempdir().expect("tempdir");
    let keys_file = dir.path().join("keys.json");
    std::fs::write(&keys_file, hubs.keys_text().await).expect("write keys");
    let good = dir.path().join("statement.json");
    std::fs::write(&good, envelope.to_json()).expect("write");
    let (code, stdout, stderr) =
        verify_cli(&[good.as_os_str(), "--keys".as_ref(), keys_file.as_os_str()]).await;
    assert_eq!(code, Some(0), "{stdout}{stderr}");
    assert!(stdout.starts_with("verified: "), "{stdout}");
    let mut changed = payload.clone();
    let last = changed.len() - 2;
    changed[last] = changed[last].wrapping_add(1);
    let bad = dir.path().join("changed.json");
    let tampered = Envelope {
        payload: STANDARD.encode(&changed),
        ..envelope.clone()
    };
    std::fs::write(&bad, tampered.to_json()).expect("write");
    let (code, stdout, stderr) =
        verify_cli(&[bad.as_os_str(), "--keys".as_ref(), keys_file.as_os_str()]).await;
    assert_eq!(code, Some(1), "{stdout}{stderr}");
    assert!(stdout.is_empty(), "{stdout}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("error: bad signature: "), "{stderr}");

    // A malformed envelope names the field; a key the list lacks is named too.
    let malformed = dir.path().join("malformed.json");
    let mut value: Value = serde_json::from_str(&envelope.to_json()).expect("JSON");
    value.as_object_mut().expect("object").remove("payload");
    std::fs::write(&malformed, value.to_string()).expect("write");
    let (code, _, stderr) = verify_cli(&[
        malformed.as_os_str(),
        "--keys".as_ref(),
        keys_file.as_os_str(),
    ])
    .await;
    assert_eq!(code, Some(1));
    assert_eq!(
        stderr.trim(),
        "error: malformed envelope: `payload` is missing"
    );
    let stranger = enact_hub::core::statement::StatementKey::from_secret(&[7; 32]);
    let other_keys = dir.path().join("other-keys.json");
    std::fs::write(
        &other_keys,
        serde_json::to_string(&PublishedKeys {
            keys: vec![stranger.published("2026-01-01T00:00:00Z", None)],
        })
        .expect("json"),
    )
    .expect("write");
    let (code, _, stderr) =
        verify_cli(&[good.as_os_str(), "--keys".as_ref(), other_keys.as_os_str()]).await;
    assert_eq!(code, Some(1));
    assert!(
        stderr.starts_with(&format!(
            "error: unknown key id {}",
            envelope.signatures[0].keyid
        )),
        "{stderr}"
    );
    hubs.server.stop().await;
}

#[tokio::test]
async fn verify_with_answers_refuses_a_different_file_and_fetches_keys_from_the_hub() {
    let hubs = hub_with_tokens().await;
    let body = answers(&hubs.records, &[0, 2]);
    let id = hubs.submit("m", &body).await;
    let dir = tempfile::tempdir().expect("tempdir");
    let statement = dir.path().join("statement.json");
    std::fs::write(&statement, hubs.statement_text(id).await).expect("write");
    let same = dir.path().join("answers.jsonl");
    std::fs::write(&same, &body).expect("write");
    let other = dir.path().join("other.jsonl");
    std::fs::write(&other, answers(&hubs.records, &[0])).expect("write");
    let hub_url = hubs.server.url("");

    let (code, stdout, stderr) = verify_cli(&[
        statement.as_os_str(),
        "--hub".as_ref(),
        hub_url.as_ref(),
        "--answers".as_ref(),
        same.as_os_str(),
    ])
    .await;
    assert_eq!(code, Some(0), "{stdout}{stderr}");
    assert!(stdout.contains("dataset:    mini"), "{stdout}");
    assert!(
        stdout.contains(&format!("submission: {id}, model \"m\"")),
        "{stdout}"
    );
    assert!(
        stdout.contains(&format!("the same as {}", same.display())),
        "{stdout}"
    );
    assert!(stdout.contains("task accuracy"), "{stdout}");

    let (code, stdout, stderr) = verify_cli(&[
        statement.as_os_str(),
        "--hub".as_ref(),
        hub_url.as_ref(),
        "--answers".as_ref(),
        other.as_os_str(),
    ])
    .await;
    assert_eq!(code, Some(1), "{stdout}{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with(&format!(
            "error: answers differ: {} has SHA-256 {}, the statement names {}",
            other.display(),
            sha256_hex(&std::fs::read(&other).expect("read")),
            sha256_hex(body.as_bytes())
        )),
        "{stderr}"
    );
    hubs.server.stop().await;
}

#[tokio::test]
async fn after_a_rotation_old_statements_still_verify_and_new_ones_use_the_new_key() {
    let hubs = hub_with_tokens().await;
    let first = hubs.submit("before", &answers(&hubs.records, &[])).await;
    let old = hubs.statement(first).await;
    let old_key = old.signatures[0].keyid.clone();

    // A submitter may not rotate; an admin may.
    hubs.server
        .call(Method::POST, "/api/v1/admin/keys/rotate")
        .bearer(&hubs.submitter)
        .expect(403)
        .await;
    let rotated = hubs
        .server
        .call(Method::POST, "/api/v1/admin/keys/rotate")
        .bearer(&hubs.admin)
        .expect(200)
        .await
        .json();
    let new_key = rotated["key"]["keyid"].as_str().expect("keyid").to_owned();
    assert_ne!(new_key, old_key);
    assert_eq!(rotated["retired"], json!([old_key]));

    let second = hubs.submit("after", &answers(&hubs.records, &[1])).await;
    let new = hubs.statement(second).await;
    assert_eq!(new.signatures[0].keyid, new_key);
    let keys_text = hubs.keys_text().await;
    let keys: Value = serde_json::from_str(&keys_text).expect("JSON");
    let listed: Vec<(&str, bool)> = keys["keys"]
        .as_array()
        .expect("keys")
        .iter()
        .map(|k| {
            (
                k["keyid"].as_str().expect("keyid"),
                k.get("retired_at").is_some(),
            )
        })
        .collect();
    assert_eq!(
        listed,
        [(old_key.as_str(), true), (new_key.as_str(), false)]
    );
    let (statement, signer) = verified(&old, &keys_text);
    assert_eq!((statement.submission.id, signer), (first, old_key.clone()));
    let (statement, signer) = verified(&new, &keys_text);
    assert_eq!((statement.submission.id, signer), (second, new_key.clone()));
    // The served old statement is still the one signed with the old key.
    assert_eq!(hubs.statement(first).await, old);
    assert_eq!(
        count(
            &hubs.server.pool,
            "SELECT count(*) FROM audit_log WHERE action = 'key.rotate' AND actor = 'root'"
        )
        .await,
        1
    );

    if on_sqlite() {
        // From the command line beside the running server: the server reads the key file
        // again before its next statement.
        let mut rotate = enact_hub();
        rotate
            .args(["keys", "rotate", "--db"])
            .arg(hubs.server.db_path());
        let out = command_output(rotate).await;
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let third_key = String::from_utf8_lossy(&out.stdout).trim().to_owned();
        assert!(third_key != new_key && third_key.len() == 16, "{third_key}");
        let third = hubs.submit("later", &answers(&hubs.records, &[2])).await;
        let newest = hubs.statement(third).await;
        assert_eq!(newest.signatures[0].keyid, third_key);
        let keys_text = hubs.keys_text().await;
        verified(&old, &keys_text);
        verified(&new, &keys_text);
        verified(&newest, &keys_text);
        let mut list = enact_hub();
        list.args(["keys", "list", "--db"])
            .arg(hubs.server.db_path());
        let out = command_output(list).await;
        assert!(out.status.success());
        let listed: Value = serde_json::from_slice(&out.stdout).expect("the keys as JSON");
        assert_eq!(listed["keys"].as_array().map(Vec::len), Some(3), "{listed}");
    }
    hubs.server.stop().await;
}

#[tokio::test]
async fn a_rescore_makes_a_new_statement_and_old_submissions_get_one_when_first_asked() {
    let hubs = hub_with_tokens().await;
    let id = hubs.submit("m", &answers(&hubs.records, &[1])).await;
    let at_submission = hubs.statement(id).await;
    let keys_text = hubs.keys_text().await;
    let (before, _) = verified(&at_submission, &keys_text);

    // A rescore (of results an older metric version computed) signs what it wrote.
    db!(
        hubs.server.pool,
        execute,
        sqlx::query("UPDATE submissions SET metric_version = 1 WHERE id = $1").bind(id)
    )
    .expect("age the submission");
    // Statements name the second they were made: let the rescore's be a later one.
    tokio::time::sleep(Duration::from_millis(1100)).await;
    let summary = rescore::rescore(
        &Hub::from(hubs.server.pool.clone()),
        &Actor::Operator("tester".to_owned()),
        Some("mini"),
        &|_| {},
    )
    .await
    .expect("rescored");
    assert_eq!(summary.submissions, 1);
    assert_eq!(statements_of(&hubs.server, id).await, 2);
    let after_rescore = hubs.statement(id).await;
    assert_ne!(
        after_rescore, at_submission,
        "the newest statement is served"
    );
    // On PostgreSQL without a key file, the rescoring process signed with a key of its own.
    let keys_text = hubs.keys_text().await;
    verified(&at_submission, &keys_text);
    let (after, _) = verified(&after_rescore, &keys_text);
    assert!(after.made_at > before.made_at);
    assert_eq!(after.verdicts, before.verdicts);
    assert_eq!(after.scores, before.scores);

    // A submission stored before statements existed gets one when it is first asked for,
    // from its stored verdicts: the same digests as when it was scored.
    db!(
        hubs.server.pool,
        execute,
        sqlx::query("DELETE FROM submission_statements WHERE submission = $1").bind(id)
    )
    .expect("forget the statements");
    let made_late = hubs.statement(id).await;
    assert_eq!(statements_of(&hubs.server, id).await, 1);
    let (late, _) = verified(&made_late, &keys_text);
    assert_eq!(late.verdicts, before.verdicts);
    assert_eq!(late.dataset, before.dataset);
    assert_eq!(late.answers_sha256, before.answers_sha256);
    // Asked again, the same statement is served, not a new one made.
    assert_eq!(hubs.statement(id).await, made_late);
    assert_eq!(statements_of(&hubs.server, id).await, 1);
    hubs.server.stop().await;
}

#[tokio::test]
async fn the_secret_key_lives_beside_the_database_and_no_backup_holds_it() {
    if !on_sqlite() {
        // PostgreSQL keeps no file beside it: a server without --signing-key signs with a key of
        // its own process (covered by the other tests).
        return;
    }
    let hubs = hub_with_tokens().await;
    let id = hubs.submit("m", &answers(&hubs.records, &[])).await;
    let key_file =
        std::path::PathBuf::from(format!("{}.signing-key", hubs.server.db_path().display()));
    let text = std::fs::read_to_string(&key_file).expect("the key file beside the database");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(&key_file)
            .expect("meta")
            .permissions()
            .mode();
        assert_eq!(mode & 0o777, 0o600, "only its owner may read it");
    }
    let secret_line = text
        .lines()
        .find(|l| !l.starts_with('#') && !l.is_empty())
        .expect("a key line");
    let secret = STANDARD.decode(secret_line).expect("base64");
    let key = enact_hub::core::statement::StatementKey::from_secret(
        &secret.as_slice().try_into().expect("32 bytes"),
    );
    assert_eq!(
        hubs.statement(id).await.signatures[0].keyid,
        key.keyid(),
        "statements are signed with the file's key"
    );

    let dir = tempfile::tempdir().expect("tempdir");
    let snapshot = dir.path().join("snap.db");
    let mut backup = enact_hub();
    backup
        .args(["backup", "--db"])
        .arg(hubs.server.db_path())
        .arg("--out")
        .arg(&snapshot);
    let out = command_output(backup).await;
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&snapshot).expect("the snapshot");
    let holds = |needle: &[u8]| bytes.windows(needle.len()).any(|w| w == needle);
    assert!(!holds(&secret), "the backup holds the raw secret");
    assert!(
        !holds(secret_line.as_bytes()),
        "the backup holds the secret's base64"
    );
    assert!(
        holds(STANDARD.encode(key.public_key()).as_bytes()),
        "the backup lists the public key"
    );
    assert!(
        std::fs::read_dir(dir.path()).expect("dir").all(|e| !e
            .expect("entry")
            .file_name()
            .to_string_lossy()
            .contains("signing-key")),
        "no key file beside the snapshot"
    );
    hubs.server.stop().await;
}

#[tokio::test]
async fn a_model_run_s_statement_says_run() {
    let (dir, pool, records) = run_fixture(1).await;
    let root = dir.path().join("release");
    let standin = StandIn::start(StandInConfig {
        scripts: scripts(&root, &records, |_, r| {
            vec![Step::Answer(answer_text(r, true))]
        }),
        ..StandInConfig::default()
    })
    .await;
    let hub = keyed(Hub::from(pool.clone()));
    let server = serve_hub(hub.clone(), pool.clone(), dir, &Default::default()).await;
    let (_, admin) = api_token(&pool, "root", Role::Admin, None, None).await;
    let (_, submission) = run_to_submission(&server, &hub, &admin, &standin, "signed").await;
    let text = server
        .call(
            Method::GET,
            &format!("/api/v1/submissions/{submission}/statement"),
        )
        .bearer(&admin)
        .expect(200)
        .await
        .text;
    let keys = server
        .call(Method::GET, "/api/v1/keys")
        .expect(200)
        .await
        .text;
    let (statement, _) = verified(&Envelope::parse(&text).expect("an envelope"), &keys);
    assert_eq!(statement.provenance, "run");
    assert_eq!(statement.submission.model, "Stand-in");
    let body_sha256: String = db!(
        pool,
        fetch_one,
        sqlx::query_scalar("SELECT body_sha256 FROM submissions WHERE id = $1").bind(submission)
    )
    .expect("the submission's digest");
    assert_eq!(statement.answers_sha256, body_sha256);
    server.stop().await;
}
