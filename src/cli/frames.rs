//! `--frames`, and `enact-hub frames`: where frame bytes are kept, and moving them.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

use super::{DEFAULT_DB, is_missing_file, open, refused};
use crate::app::frames::{self, FrameStore};

/// Where frame bytes are kept, for commands that write or read them.
#[derive(Args, Clone)]
pub struct FramesArg {
    /// Where frame images are stored: `database` (in the SQLite file), or an object store:
    /// s3://bucket/prefix, gs://bucket/prefix, az://container/prefix, file:///dir.
    /// Credentials, region and endpoint come from the cloud's usual environment variables
    /// (AWS_ACCESS_KEY_ID, AWS_ENDPOINT, ...). Frames already stored stay where they are until
    /// `enact-hub frames migrate` moves them.
    #[arg(long = "frames", env = "ENACT_HUB_FRAMES", default_value = frames::DATABASE, value_name = "URL")]
    pub url: String,
}

impl FramesArg {
    pub fn store(&self) -> anyhow::Result<FrameStore> {
        FrameStore::parse(&self.url).map_err(|e| anyhow::anyhow!("{e}"))
    }
}

#[derive(Subcommand)]
pub enum FramesCommand {
    /// How many frames hold their bytes in the database and how many in object storage.
    Status(StatusArgs),
    /// Move every frame's bytes to another place: out of the database into an object store,
    /// between object stores, or back into the database. Resumable: run it again after an
    /// interruption and it carries on.
    Migrate(MigrateArgs),
}

#[derive(Args)]
pub struct StatusArgs {
    /// SQLite database file, or a PostgreSQL URL
    /// (postgres://user:password@host/db; also ENACT_HUB_DATABASE_URL).
    #[arg(long, visible_alias = "database-url", env = "ENACT_HUB_DB", default_value = DEFAULT_DB)]
    db: PathBuf,
}

#[derive(Args)]
pub struct MigrateArgs {
    /// SQLite database file, or a PostgreSQL URL
    /// (postgres://user:password@host/db; also ENACT_HUB_DATABASE_URL).
    #[arg(long, visible_alias = "database-url", env = "ENACT_HUB_DB", default_value = DEFAULT_DB)]
    db: PathBuf,
    /// Where the bytes go: an object store URL, or `database`.
    #[arg(long, value_name = "URL")]
    to: String,
    /// Where the frames not held in the database are now (needed to move them back into the
    /// database or to another object store).
    #[arg(long, value_name = "URL")]
    from: Option<String>,
    /// Print the report as JSON on standard output.
    #[arg(long)]
    json: bool,
}

pub async fn frames(command: FramesCommand) -> anyhow::Result<ExitCode> {
    match command {
        FramesCommand::Status(args) => status(args).await,
        FramesCommand::Migrate(args) => migrate(args).await,
    }
}

async fn status(args: StatusArgs) -> anyhow::Result<ExitCode> {
    if is_missing_file(&args.db) {
        anyhow::bail!("{} does not exist", args.db.display());
    }
    let hub = open(&args.db).await?;
    let counts = frames::count_by_place(&hub).await;
    hub.close().await;
    match counts {
        Ok((here, elsewhere)) => {
            println!("{here} frames in the database, {elsewhere} in object storage");
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => refused(e),
    }
}

async fn migrate(args: MigrateArgs) -> anyhow::Result<ExitCode> {
    if is_missing_file(&args.db) {
        anyhow::bail!("{} does not exist", args.db.display());
    }
    let to = match FrameStore::parse(&args.to) {
        Ok(to) => to,
        Err(e) => return refused(e),
    };
    let from = match args.from.as_deref().map(FrameStore::parse).transpose() {
        Ok(from) => from.unwrap_or_default(),
        Err(e) => return refused(e),
    };
    let hub = open(&args.db).await?;
    let bar = if std::io::stderr().is_terminal() {
        let bar = ProgressBar::new(0);
        bar.set_style(
            ProgressStyle::with_template("{bar:40} {pos}/{len} frames ({eta} left)")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        Some(bar)
    } else {
        None
    };
    let result = frames::migrate(&hub, &from, &to, |done, total| {
        if let Some(bar) = &bar {
            bar.set_length(total);
            bar.set_position(done);
        }
    })
    .await;
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    // Dropped bytes free pages inside the file; emptying the log keeps it from holding them.
    hub.truncate_log().await;
    hub.close().await;
    match result {
        Ok(report) => {
            if args.json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            }
            eprintln!(
                "moved {} frames ({:.1} MB) to {} in {:.1} s{}",
                report.moved,
                report.bytes as f64 / 1e6,
                to.describe(),
                report.seconds,
                if report.already_there > 0 {
                    format!("; {} were there already", report.already_there)
                } else {
                    String::new()
                }
            );
            if to.objects().is_some() && report.moved > 0 {
                eprintln!(
                    "start servers and imports with --frames {} (or ENACT_HUB_FRAMES); the \
                     database file keeps its size until it is vacuumed",
                    to.describe()
                );
            }
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => refused(e),
    }
}
