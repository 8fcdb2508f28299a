//! `enact-hub dataset`: operations on stored datasets (a stratified subset as a dataset of its
//! own).

use std::process::ExitCode;

use clap::Subcommand;

use super::{DbArg, in_database, open, operator};
use crate::app;
use crate::app::datasets::{SubsetReport, SubsetRule};
use crate::core::study::subset::{Allocation, StratumField};

#[derive(Subcommand)]
pub enum DatasetCommand {
    /// Store a stratified subset of a dataset as a dataset of its own, keeping the source's
    /// items (ids, questions, answers, images, signatures), so a study pairs it with the source.
    Subset {
        /// The source dataset.
        source: String,
        #[command(flatten)]
        db: DbArg,
        /// The new dataset's name (letters, digits, `.`, `_` and `-`).
        #[arg(long)]
        into: String,
        /// How many items the subset holds.
        #[arg(long)]
        size: usize,
        /// The fields the strata are made of, comma-separated: direction, step_length, task.
        #[arg(long, default_value = "direction,step_length")]
        stratify: String,
        /// `proportional` (each stratum in proportion to its items) or `equal` (the same number
        /// per stratum, as the paper's 2,304 = 16 × 144).
        #[arg(long, default_value = "proportional")]
        allocation: String,
        /// Seed of the draw in each stratum.
        #[arg(long, default_value_t = 42)]
        seed: u64,
        /// Print what was stored as JSON.
        #[arg(long)]
        json: bool,
    },
}

pub async fn dataset(command: DatasetCommand) -> anyhow::Result<ExitCode> {
    match command {
        DatasetCommand::Subset {
            source,
            db,
            into,
            size,
            stratify,
            allocation,
            seed,
            json,
        } => {
            let rule = SubsetRule {
                fields: StratumField::parse_list(&stratify)
                    .map_err(|e| anyhow::anyhow!("--stratify: {e}"))?,
                size,
                allocation: Allocation::parse(&allocation).ok_or_else(|| {
                    anyhow::anyhow!(
                        "--allocation: unknown allocation {allocation:?} (use proportional or \
                         equal)"
                    )
                })?,
                seed,
            };
            let hub = open(&db.db).await?;
            let stored = app::datasets::subset(&hub, &operator(), &source, &into, &rule).await;
            hub.close().await;
            let report = in_database(stored, &db.db)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{}", strata_table(&report));
            }
            Ok(ExitCode::SUCCESS)
        }
    }
}

fn strata_table(report: &SubsetReport) -> String {
    let mut out = format!(
        "stored dataset {} with {} items of {} (seed {})\n",
        report.dataset, report.items, report.source, report.seed
    );
    let header: Vec<&str> = report.fields.iter().map(|f| f.as_str()).collect();
    out.push_str(&format!("{}\tavailable\tchosen\n", header.join("\t")));
    for stratum in &report.strata {
        out.push_str(&format!(
            "{}\t{}\t{}\n",
            stratum.stratum.join("\t"),
            stratum.available,
            stratum.chosen
        ));
    }
    out
}
