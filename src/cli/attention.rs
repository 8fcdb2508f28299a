//! `enact-hub attention set|show|clear`: a dataset's attention checks, mixed into every
//! annotator's queue like gold items ([`crate::app::attention`]).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Subcommand};

use super::{DbArg, in_database, is_missing_file, open, operator};
use crate::app;
use crate::core::gold::GoldRate;

#[derive(Subcommand)]
pub(super) enum AttentionCommand {
    /// Choose a dataset's attention checks (replacing any earlier ones) and mix them into
    /// every annotator's queue: one in every --rate items. Each check's question carries its
    /// instruction (keep: the cards in the order listed; reverse: in reverse order); answers
    /// are judged against it and never count in the Human row.
    Set(SetArgs),
    /// Print a dataset's attention checks: their rate, items and instructions.
    Show(DatasetArgs),
    /// Remove a dataset's attention checks; unfinished ones leave the queues, answers stay.
    Clear(DatasetArgs),
}

#[derive(Args)]
pub(super) struct SetArgs {
    /// The dataset's name.
    dataset: String,
    #[command(flatten)]
    db: DbArg,
    /// A file of checks, one `ITEM_ID keep|reverse` per line (blank lines and lines starting
    /// with # skipped).
    #[arg(long, value_name = "FILE")]
    checks: PathBuf,
    /// One attention check in every N queue items.
    #[arg(long, value_name = "N")]
    rate: i64,
}

#[derive(Args)]
pub(super) struct DatasetArgs {
    /// The dataset's name.
    dataset: String,
    #[command(flatten)]
    db: DbArg,
}

pub(super) async fn attention(command: AttentionCommand) -> anyhow::Result<ExitCode> {
    match command {
        AttentionCommand::Set(args) => set(args).await,
        AttentionCommand::Show(args) => show(args).await,
        AttentionCommand::Clear(args) => clear(args).await,
    }
}

async fn set(args: SetArgs) -> anyhow::Result<ExitCode> {
    let rate = match GoldRate::new(args.rate) {
        Ok(rate) => rate,
        Err(problem) => {
            eprintln!("error: --rate: {problem}");
            return Ok(ExitCode::FAILURE);
        }
    };
    let checks = match std::fs::read_to_string(&args.checks) {
        Ok(text) => app::attention::parse_checks(&text)
            .map_err(|p| format!("--checks {}: {p}", args.checks.display())),
        Err(e) => Err(format!(
            "--checks: cannot read {}: {e}",
            args.checks.display()
        )),
    };
    let checks = match checks {
        Ok(checks) => checks,
        Err(problem) => {
            eprintln!("error: {problem}");
            return Ok(ExitCode::FAILURE);
        }
    };
    let hub = open(&args.db.db).await?;
    let result = app::attention::set(&hub, &operator(), &args.dataset, &checks, rate).await;
    hub.close().await;
    let (set, queues) = in_database(result, &args.db.db)?;
    println!(
        "dataset '{}': {} attention checks, one in every {} queue items; {} added to \
         annotators' queues, {} unfinished ones of the earlier set taken out",
        set.dataset,
        set.checks.len(),
        set.rate,
        queues.added,
        queues.removed
    );
    Ok(ExitCode::SUCCESS)
}

async fn show(args: DatasetArgs) -> anyhow::Result<ExitCode> {
    if is_missing_file(&args.db.db) {
        eprintln!("error: no database at {}", args.db.db.display());
        return Ok(ExitCode::FAILURE);
    }
    let hub = open(&args.db.db).await?;
    let result = app::attention::show(&hub, &args.dataset).await;
    hub.close().await;
    let Some(set) = in_database(result, &args.db.db)? else {
        println!("dataset '{}' has no attention checks", args.dataset);
        return Ok(ExitCode::SUCCESS);
    };
    println!(
        "dataset '{}': {} attention checks, one in every {} queue items; set by {} at {}",
        set.dataset,
        set.checks.len(),
        set.rate,
        set.set_by,
        set.set_at
    );
    for check in &set.checks {
        println!("{} {}", check.item_id, check.instruction.as_str());
    }
    Ok(ExitCode::SUCCESS)
}

async fn clear(args: DatasetArgs) -> anyhow::Result<ExitCode> {
    let hub = open(&args.db.db).await?;
    let result = app::attention::clear(&hub, &operator(), &args.dataset).await;
    hub.close().await;
    let cleared = in_database(result, &args.db.db)?;
    if cleared.cleared {
        println!(
            "dataset '{}': attention checks cleared; {} unfinished ones taken out of queues",
            args.dataset, cleared.removed
        );
    } else {
        println!(
            "dataset '{}' had no attention checks; nothing changed",
            args.dataset
        );
    }
    Ok(ExitCode::SUCCESS)
}
