//! Signed statements at the command line: `keys list` and `keys rotate` (the hub's signing
//! keys), and `verify` (a statement checked offline against a hub's public keys).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Subcommand};

use super::{
    DbArg, describe_db, in_database, is_missing_file, open, open_signing, operator, resolve,
};
use crate::app::{signing, statements};

#[derive(Subcommand)]
pub(super) enum KeysCommand {
    /// Every public key statements were signed with, as `GET /api/v1/keys` lists them (JSON):
    /// save it as the KEYS.json `enact-hub verify --keys` reads.
    List(ListArgs),
    /// Make a new signing key (in the key file), list its public key and retire the others:
    /// new statements use it, old ones keep verifying. Running servers switch to it before
    /// their next statement.
    Rotate(RotateArgs),
}

#[derive(Args)]
pub(super) struct ListArgs {
    #[command(flatten)]
    db: DbArg,
}

#[derive(Args)]
pub(super) struct RotateArgs {
    #[command(flatten)]
    db: DbArg,
    /// The key file to write the new secret to: the one the servers sign with (also
    /// ENACT_HUB_SIGNING_KEY). A SQLite database's default is `<db>.signing-key` beside it.
    #[arg(long, value_name = "FILE")]
    signing_key: Option<PathBuf>,
}

#[derive(Args)]
#[command(group(clap::ArgGroup::new("public_keys").required(true).args(["keys", "hub"])))]
pub(super) struct VerifyArgs {
    /// The statement: the DSSE envelope `GET /api/v1/submissions/{id}/statement` serves.
    #[arg(value_name = "STATEMENT.json")]
    statement: PathBuf,
    /// The hub's public keys, in the `GET /api/v1/keys` format (checked offline).
    #[arg(long, value_name = "KEYS.json")]
    keys: Option<PathBuf>,
    /// Fetch the public keys from the hub at this URL (`GET URL/api/v1/keys`) instead.
    #[arg(long, value_name = "URL")]
    hub: Option<String>,
    /// Also check that this file's bytes are the answers the statement was made for (their
    /// SHA-256).
    #[arg(long, value_name = "FILE")]
    answers: Option<PathBuf>,
}

pub(super) async fn keys(command: KeysCommand) -> anyhow::Result<ExitCode> {
    match command {
        KeysCommand::List(args) => {
            if is_missing_file(&args.db.db) {
                anyhow::bail!("{} does not exist", args.db.db.display());
            }
            let hub = open(&args.db.db).await?;
            let keys = signing::public_keys(&hub).await;
            hub.close().await;
            let keys = in_database(keys, &args.db.db)?;
            println!("{}", serde_json::to_string_pretty(&keys)?);
            if keys.keys.is_empty() {
                eprintln!(
                    "no key yet in {}: one is made at a server's first start or first statement",
                    describe_db(&resolve(&args.db.db))
                );
            }
            Ok(ExitCode::SUCCESS)
        }
        KeysCommand::Rotate(args) => {
            let hub = open_signing(&args.db.db, args.signing_key).await?;
            let rotated = signing::rotate_key_file(&hub, &operator()).await;
            hub.close().await;
            let rotated = in_database(rotated, &args.db.db)?;
            println!("{}", rotated.key.keyid);
            eprintln!(
                "new signing key {} in {}; retired: {}",
                rotated.key.keyid,
                rotated.source.describe(),
                if rotated.retired.is_empty() {
                    "none".to_owned()
                } else {
                    rotated.retired.join(", ")
                }
            );
            Ok(ExitCode::SUCCESS)
        }
    }
}

pub(super) async fn verify(args: VerifyArgs) -> anyhow::Result<ExitCode> {
    let keys = match (&args.keys, &args.hub) {
        (Some(path), _) => statements::KeysFrom::File(path),
        (None, Some(url)) => statements::KeysFrom::Hub(url),
        // clap requires one of them.
        (None, None) => anyhow::bail!("give --keys KEYS.json or --hub URL"),
    };
    let checked = match statements::check(&args.statement, keys, args.answers.as_deref()).await {
        Ok(checked) => checked,
        Err(refused) => {
            eprintln!("error: {refused}");
            return Ok(ExitCode::FAILURE);
        }
    };
    let s = &checked.statement;
    let key = &checked.key;
    println!(
        "verified: {} is signed by key {} ({}, listed {}{})",
        args.statement.display(),
        key.keyid,
        key.algorithm,
        key.created_at,
        key.retired_at
            .as_deref()
            .map(|t| format!(", retired {t}"))
            .unwrap_or_default()
    );
    println!(
        "hub:        {} {}{}",
        s.hub.name,
        s.hub.version,
        s.hub
            .url
            .as_deref()
            .map(|u| format!(" at {u}"))
            .unwrap_or_default()
    );
    println!(
        "submission: {}, model {:?} by {:?}, {} on {}",
        s.submission.id,
        s.submission.model,
        s.submission.account,
        s.provenance,
        s.submission.created_at
    );
    println!(
        "dataset:    {}, {} items, items SHA-256 {}",
        s.dataset.name, s.dataset.items, s.dataset.items_sha256
    );
    match &checked.answers {
        Some(file) => println!(
            "answers:    SHA-256 {}, the same as {file}",
            s.answers_sha256
        ),
        None => println!(
            "answers:    SHA-256 {} (not compared: give --answers FILE)",
            s.answers_sha256
        ),
    }
    println!(
        "verdicts:   {}, SHA-256 {}",
        s.verdicts.count, s.verdicts.sha256
    );
    println!(
        "scores:     {} (metric version {}, policy {}, scored by {})",
        s.scores_summary(),
        s.metric_version,
        s.policy.as_str(),
        if s.submission.scored_by.is_empty() {
            "an unrecorded build"
        } else {
            &s.submission.scored_by
        }
    );
    println!("made at:    {}", s.made_at);
    Ok(ExitCode::SUCCESS)
}
