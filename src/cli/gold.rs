//! `enact-hub gold set|show|clear`: a dataset's gold items, mixed into every annotator's
//! queue ([`crate::app::gold`]).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Subcommand};

use super::{DbArg, in_database, is_missing_file, open, operator};
use crate::app;
use crate::core::gold::{GoldChoice, GoldRate};

#[derive(Subcommand)]
pub(super) enum GoldCommand {
    /// Choose a dataset's gold items (replacing any earlier choice) and mix them into every
    /// annotator's queue: one in every --rate items, unannounced. Their answers judge the
    /// annotator and never count in the Human row.
    Set(SetArgs),
    /// Print a dataset's gold set: how it was chosen, its rate and its items.
    Show(DatasetArgs),
    /// Remove a dataset's gold set; unfinished gold items leave the queues, answers stay.
    Clear(DatasetArgs),
}

#[derive(Args)]
pub(super) struct SetArgs {
    /// The dataset's name.
    dataset: String,
    #[command(flatten)]
    db: DbArg,
    /// This share of the dataset's items (0 < F < 1), drawn at random with --seed.
    #[arg(
        long,
        value_name = "F",
        conflicts_with = "items",
        required_unless_present = "items"
    )]
    share: Option<f64>,
    /// The seed of the --share draw (the same seed draws the same items).
    #[arg(long, value_name = "S", default_value_t = 0, requires = "share")]
    seed: u64,
    /// A file of item ids, one per line (blank lines and lines starting with # skipped).
    #[arg(long, value_name = "FILE")]
    items: Option<PathBuf>,
    /// One gold item in every N queue items (N - 1 ordinary items, then a gold one).
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

pub(super) async fn gold(command: GoldCommand) -> anyhow::Result<ExitCode> {
    match command {
        GoldCommand::Set(args) => set(args).await,
        GoldCommand::Show(args) => show(args).await,
        GoldCommand::Clear(args) => clear(args).await,
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
    let choice = match (args.share, &args.items) {
        (Some(share), _) => {
            GoldChoice::share(share, args.seed).map_err(|p| format!("--share: {p}"))
        }
        (None, Some(path)) => match std::fs::read_to_string(path) {
            Ok(text) => {
                GoldChoice::list(&text).map_err(|p| format!("--items {}: {p}", path.display()))
            }
            Err(e) => Err(format!("--items: cannot read {}: {e}", path.display())),
        },
        (None, None) => Err("give --share F or --items FILE".to_owned()),
    };
    let choice = match choice {
        Ok(choice) => choice,
        Err(problem) => {
            eprintln!("error: {problem}");
            return Ok(ExitCode::FAILURE);
        }
    };
    let hub = open(&args.db.db).await?;
    let result = app::gold::set(&hub, &operator(), &args.dataset, &choice, rate).await;
    hub.close().await;
    let (set, queues) = in_database(result, &args.db.db)?;
    println!(
        "dataset '{}': {} gold items, one in every {} queue items; {} added to annotators' \
         queues, {} unfinished ones of the earlier set taken out",
        set.dataset,
        set.items.len(),
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
    let result = app::gold::show(&hub, &args.dataset).await;
    hub.close().await;
    let Some(set) = in_database(result, &args.db.db)? else {
        println!("dataset '{}' has no gold set", args.dataset);
        return Ok(ExitCode::SUCCESS);
    };
    let how = match (set.share, set.seed) {
        (Some(share), Some(seed)) => format!("a share of {share} drawn with seed {seed}"),
        _ => "a list of items".to_owned(),
    };
    println!(
        "dataset '{}': {} gold items ({how}), one in every {} queue items; set by {} at {}",
        set.dataset,
        set.items.len(),
        set.rate,
        set.set_by,
        set.set_at
    );
    for item in &set.items {
        println!("{item}");
    }
    Ok(ExitCode::SUCCESS)
}

async fn clear(args: DatasetArgs) -> anyhow::Result<ExitCode> {
    let hub = open(&args.db.db).await?;
    let result = app::gold::clear(&hub, &operator(), &args.dataset).await;
    hub.close().await;
    let cleared = in_database(result, &args.db.db)?;
    if cleared.cleared {
        println!(
            "dataset '{}': gold set cleared; {} unfinished gold items taken out of queues",
            args.dataset, cleared.removed
        );
    } else {
        println!(
            "dataset '{}' had no gold set; nothing changed",
            args.dataset
        );
    }
    Ok(ExitCode::SUCCESS)
}
