//! `doctor`: a checkup of a hub's database for its operator.

use std::process::ExitCode;

use clap::Args;

use super::{DbArg, describe_db, is_missing_file, open, operator};
use crate::app::doctor::{self, Level, Options, STALE_IMPORT_HOURS};

#[derive(Args)]
pub(super) struct DoctorArgs {
    #[command(flatten)]
    db: DbArg,
    /// Discard unfinished imports untouched for 24 hours (audited, as `import --abandon`).
    #[arg(long)]
    remove_stale: bool,
    /// Also check every page of a SQLite database (`PRAGMA quick_check`; slow on a large one).
    #[arg(long)]
    integrity: bool,
    /// Fold SQLite's write-ahead log into the database and cut the log file back first.
    #[arg(long)]
    truncate_log: bool,
    /// Print the findings as JSON on stdout.
    #[arg(long)]
    json: bool,
}

/// Prints each finding; fails (exit 1) when any needs the operator's action.
pub(super) async fn doctor(args: DoctorArgs) -> anyhow::Result<ExitCode> {
    if is_missing_file(&args.db.db) {
        anyhow::bail!("{}: no such database", describe_db(&args.db.db));
    }
    let hub = open(&args.db.db).await?;
    let options = Options {
        remove_stale_imports: args.remove_stale,
        integrity: args.integrity,
        truncate_log: args.truncate_log,
    };
    let checkup = doctor::examine(&hub, &operator(), options).await;
    hub.close().await;
    let checkup = checkup?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&checkup)?);
    }
    for f in &checkup.findings {
        let mark = match f.level {
            Level::Ok => "ok",
            Level::Notice => "note",
            Level::Warning => "WARNING",
        };
        eprintln!("{mark:>7}  {}: {}", f.check, f.detail);
        if let Some(fix) = &f.fix {
            eprintln!("         fix: {fix}");
        }
    }
    let warnings = checkup
        .findings
        .iter()
        .filter(|f| f.level == Level::Warning)
        .count();
    eprintln!(
        "{}: {warnings} warnings (imports count as stale after {STALE_IMPORT_HOURS} hours)",
        describe_db(&args.db.db)
    );
    Ok(if checkup.worst() == Level::Warning {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}
