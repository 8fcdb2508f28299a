//! Whole-database commands: `backup`, `restore` and `migrate-db`.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;

use super::{DbArg, describe_db, is_missing_file, open, operator, refused, resolve};
use crate::app;

#[derive(Args)]
pub(super) struct MigrateDbArgs {
    /// The database to copy: a SQLite file or a PostgreSQL URL.
    #[arg(long, value_name = "DB")]
    from: PathBuf,
    /// The database to copy into (created and migrated if it is a SQLite file; a PostgreSQL
    /// database must exist): it must hold nothing yet.
    #[arg(long, value_name = "DB")]
    to: PathBuf,
    /// Print the report as JSON on standard output.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
pub(super) struct BackupArgs {
    #[command(flatten)]
    db: DbArg,
    /// The snapshot file to write; it must not exist.
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
}

#[derive(Args)]
pub(super) struct RestoreArgs {
    /// The snapshot to restore (written by `enact-hub backup`).
    #[arg(long, value_name = "FILE")]
    from: PathBuf,
    #[command(flatten)]
    db: DbArg,
    /// Move an existing database aside (to `{db}.before-restore`) instead of refusing.
    #[arg(long)]
    replace: bool,
}

pub(super) async fn migrate_db(args: MigrateDbArgs) -> anyhow::Result<ExitCode> {
    if is_missing_file(&args.from) {
        anyhow::bail!("{} does not exist: nothing to copy", args.from.display());
    }
    if resolve(&args.from) == resolve(&args.to) {
        anyhow::bail!("--from and --to name the same database");
    }
    let from = open(&args.from).await?;
    let to = open(&args.to).await?;
    let result = app::migrate_db::migrate_db(&from, &to, |table, rows| {
        eprintln!("{table}: {rows} rows");
    })
    .await;
    from.close().await;
    to.truncate_log().await;
    to.close().await;
    match result {
        Ok(report) => {
            if args.json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            }
            let rows: u64 = report.tables.iter().map(|(_, n)| n).sum();
            eprintln!(
                "copied {rows} rows of {} tables from {} to {} in {:.1} s",
                report.tables.len(),
                describe_db(&resolve(&args.from)),
                describe_db(&resolve(&args.to)),
                report.seconds
            );
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => refused(e),
    }
}

fn print_snapshot(what: &str, s: &app::backup::Snapshot) {
    println!(
        "{what} {} ({} bytes: {} items, {} submissions, {} annotations; integrity ok)",
        s.path.display(),
        s.bytes,
        s.items,
        s.submissions,
        s.annotations
    );
}

pub(super) async fn backup(args: BackupArgs) -> anyhow::Result<ExitCode> {
    if is_missing_file(&args.db.db) {
        anyhow::bail!(
            "{} does not exist: nothing to back up",
            args.db.db.display()
        );
    }
    let hub = open(&args.db.db).await?;
    let done = app::backup::backup(&hub, &operator(), &args.out).await;
    hub.close().await;
    match done {
        Ok(snapshot) => {
            print_snapshot("wrote", &snapshot);
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => refused(e),
    }
}

pub(super) async fn restore(args: RestoreArgs) -> anyhow::Result<ExitCode> {
    let target = resolve(&args.db.db);
    match app::backup::restore(&args.from, &target, args.replace).await {
        Ok(snapshot) => {
            print_snapshot("restored", &snapshot);
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => refused(e),
    }
}
