//! `enact-hub reported import|list|add|remove`: results papers published, attached to a
//! dataset and shown on its leaderboard as reported rows ([`crate::app::reported`]).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Subcommand};

use super::{DbArg, in_database, is_missing_file, open, operator};
use crate::app;
use crate::core::paper::ReportedModel;

#[derive(Subcommand)]
pub(super) enum ReportedCommand {
    /// Attach a paper's results to a dataset: the ENACT paper's own (--paper), or other
    /// papers' tables in the JSON shape `paper` writes (one metric per file; a model's task-
    /// and pairwise-accuracy tables are merged). All rows or none are stored; a row of the
    /// same model and source is replaced.
    Import(ImportArgs),
    /// Print a dataset's reported results.
    List(DatasetArgs),
    /// Add one reported result from a JSON file: {"model", "category", "source", "family",
    /// "size", "task_accuracy": {"forward_3": 80.59, …}, "pairwise_accuracy": {…}}.
    Add(AddArgs),
    /// Remove a dataset's reported result by its id (as `list` prints it).
    Remove(RemoveArgs),
}

#[derive(Args)]
pub(super) struct ImportArgs {
    /// JSON tables of another paper's numbers.
    #[arg(
        value_name = "FILE.json",
        required_unless_present = "paper",
        conflicts_with = "paper"
    )]
    files: Vec<PathBuf>,
    /// The ENACT paper's published results (its appendix tables' 30 models and the Human row).
    #[arg(long)]
    paper: bool,
    /// The dataset's name.
    #[arg(long, value_name = "D")]
    dataset: String,
    #[command(flatten)]
    db: DbArg,
}

#[derive(Args)]
pub(super) struct DatasetArgs {
    /// The dataset's name.
    #[arg(long, value_name = "D")]
    dataset: String,
    #[command(flatten)]
    db: DbArg,
}

#[derive(Args)]
pub(super) struct AddArgs {
    /// The reported result, as JSON.
    #[arg(value_name = "FILE.json")]
    file: PathBuf,
    /// The dataset's name.
    #[arg(long, value_name = "D")]
    dataset: String,
    #[command(flatten)]
    db: DbArg,
}

#[derive(Args)]
pub(super) struct RemoveArgs {
    /// The reported result's id.
    id: i64,
    /// The dataset's name.
    #[arg(long, value_name = "D")]
    dataset: String,
    #[command(flatten)]
    db: DbArg,
}

pub(super) async fn reported(command: ReportedCommand) -> anyhow::Result<ExitCode> {
    match command {
        ReportedCommand::Import(args) => import(args).await,
        ReportedCommand::List(args) => list(args).await,
        ReportedCommand::Add(args) => add(args).await,
        ReportedCommand::Remove(args) => remove(args).await,
    }
}

async fn import(args: ImportArgs) -> anyhow::Result<ExitCode> {
    let mut files = Vec::new();
    for path in &args.files {
        match std::fs::read_to_string(path) {
            Ok(text) => files.push((path.display().to_string(), text)),
            Err(e) => {
                eprintln!("error: cannot read {}: {e}", path.display());
                return Ok(ExitCode::FAILURE);
            }
        }
    }
    let hub = open(&args.db.db).await?;
    let result = if args.paper {
        app::reported::import_paper(&hub, &operator(), &args.dataset).await
    } else {
        app::reported::import_tables(&hub, &operator(), &args.dataset, &files).await
    };
    hub.close().await;
    let done = in_database(result, &args.db.db)?;
    println!(
        "dataset '{}': {} reported rows stored ({} replacing rows of the same model and source)",
        done.dataset, done.stored, done.replaced
    );
    Ok(ExitCode::SUCCESS)
}

async fn list(args: DatasetArgs) -> anyhow::Result<ExitCode> {
    if is_missing_file(&args.db.db) {
        eprintln!("error: no database at {}", args.db.db.display());
        return Ok(ExitCode::FAILURE);
    }
    let hub = open(&args.db.db).await?;
    let result = app::reported::list(&hub, &args.dataset).await;
    hub.close().await;
    let rows = in_database(result, &args.db.db)?;
    if rows.is_empty() {
        println!("dataset '{}' has no reported results", args.dataset);
    }
    for row in rows {
        let m = &row.reported;
        println!(
            "{}\t{}\t{}\t{}\t{} TA and {} PA cells\t{}",
            row.id,
            m.model,
            m.category,
            [m.family.as_deref(), m.size.as_deref()]
                .into_iter()
                .flatten()
                .collect::<Vec<_>>()
                .join(" "),
            m.task_accuracy.len(),
            m.pairwise_accuracy.len(),
            m.source
        );
    }
    Ok(ExitCode::SUCCESS)
}

async fn add(args: AddArgs) -> anyhow::Result<ExitCode> {
    let parsed = std::fs::read_to_string(&args.file)
        .map_err(|e| format!("cannot read {}: {e}", args.file.display()))
        .and_then(|text| {
            serde_json::from_str::<ReportedModel>(&text)
                .map_err(|e| format!("{}: {e}", args.file.display()))
        });
    let model = match parsed {
        Ok(model) => model,
        Err(problem) => {
            eprintln!("error: {problem}");
            return Ok(ExitCode::FAILURE);
        }
    };
    let hub = open(&args.db.db).await?;
    let result = app::reported::add(&hub, &operator(), &args.dataset, &model).await;
    hub.close().await;
    let row = in_database(result, &args.db.db)?;
    println!(
        "dataset '{}': reported result {} ({}, from {}) added",
        row.dataset, row.id, row.reported.model, row.reported.source
    );
    Ok(ExitCode::SUCCESS)
}

async fn remove(args: RemoveArgs) -> anyhow::Result<ExitCode> {
    let hub = open(&args.db.db).await?;
    let result = app::reported::remove(&hub, &operator(), &args.dataset, args.id).await;
    hub.close().await;
    in_database(result, &args.db.db)?;
    println!(
        "dataset '{}': reported result {} removed",
        args.dataset, args.id
    );
    Ok(ExitCode::SUCCESS)
}
