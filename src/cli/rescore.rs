//! `enact-hub rescore`: stored submissions and human answers computed again under the current
//! metric version, in the foreground with a progress bar.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use super::{DEFAULT_DB, in_database, is_missing_file, open, operator};
use crate::app::rescore::{self, RescoreProgress};

#[derive(Args)]
pub struct RescoreArgs {
    /// SQLite database file, or a PostgreSQL URL
    /// (postgres://user:password@host/db; also ENACT_HUB_DATABASE_URL).
    #[arg(long, visible_alias = "database-url", env = "ENACT_HUB_DB", default_value = DEFAULT_DB)]
    db: PathBuf,
    /// Only this dataset (default: every dataset).
    #[arg(long)]
    dataset: Option<String>,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

pub async fn rescore(args: RescoreArgs) -> anyhow::Result<ExitCode> {
    if is_missing_file(&args.db) {
        anyhow::bail!("{} does not exist: nothing to rescore", args.db.display());
    }
    let hub = open(&args.db).await?;
    let bar = std::io::stderr().is_terminal().then(|| {
        let bar = ProgressBar::new(0);
        bar.set_style(
            ProgressStyle::with_template("{msg} {bar:40} {pos}/{len} ({eta} left)")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar
    });
    let show = |p: RescoreProgress| {
        if let Some(bar) = &bar {
            bar.set_message(format!("{}: {}", p.dataset, p.stage.as_str()));
            bar.set_length(p.total as u64);
            bar.set_position(p.done as u64);
        }
    };
    let result = rescore::rescore(&hub, &operator(), args.dataset.as_deref(), &show).await;
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    hub.close().await;
    let summary = in_database(result, &args.db)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        println!(
            "rescored to metric version {}: {} submissions ({} scored differently), {} human \
             answers ({} judged differently), over {} datasets",
            summary.metric_version,
            summary.submissions,
            summary.submissions_changed,
            summary.human_answers,
            summary.human_answers_changed,
            summary.datasets
        );
    }
    for failure in &summary.failures {
        eprintln!("not rescored: {failure}");
    }
    Ok(if summary.failures.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
