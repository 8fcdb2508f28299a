//! `enact-hub paper`: ENACT's result tables and files from a dataset's rows, beside the
//! results papers published (`enact-hub reported import`).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::{Args, ValueEnum};

use super::compare::ResampleArg;
use super::study::DbArg;
use super::{in_database, open};
use crate::app;
use crate::app::paper::PaperOptions;
use crate::core::paper::Metric;

/// Which table to write.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MetricArg {
    /// Task accuracy.
    Ta,
    /// Pairwise accuracy.
    Pa,
}

#[derive(Args)]
pub struct PaperArgs {
    #[command(flatten)]
    db: DbArg,
    /// The dataset.
    #[arg(long)]
    dataset: String,
    /// Write the folder here: each table as .tex (booktabs, the paper's layout), a standalone
    /// .tex that compiles, .csv, .md and .json; provenance.json; reproduction.json and .csv
    /// with --compare-reported.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// The rows, in this order, comma-separated (a main-text table like the paper's Table 1);
    /// every row when absent. A name takes every row of that model: a published one and the
    /// hub's own.
    #[arg(long, value_delimiter = ',', value_name = "MODEL,...")]
    models: Option<Vec<String>>,
    /// One table only; both when absent.
    #[arg(long, value_enum)]
    metric: Option<MetricArg>,
    /// Print the hub rows' 95 % bootstrap intervals under their values.
    #[arg(long)]
    intervals: bool,
    /// What the intervals' bootstrap resamples.
    #[arg(long, value_enum, default_value = "activities")]
    resample: ResampleArg,
    /// Compare each published model the hub also scored with the hub's figures, cell by cell,
    /// and say whether the published value lies in the hub's interval.
    #[arg(long)]
    compare_reported: bool,
}

pub async fn paper(args: PaperArgs) -> anyhow::Result<ExitCode> {
    let options = PaperOptions {
        models: args.models.clone(),
        metrics: match args.metric {
            None => Metric::ALL.to_vec(),
            Some(MetricArg::Ta) => vec![Metric::TaskAccuracy],
            Some(MetricArg::Pa) => vec![Metric::PairwiseAccuracy],
        },
        intervals: args.intervals,
        resampling: args.resample.into(),
    };
    let hub = open(&args.db.db).await?;
    let made = app::paper::paper(&hub, &args.dataset, &options).await;
    hub.close().await;
    let paper = in_database(made, &args.db.db)?;
    let files = in_database(paper.files(args.compare_reported), &args.db.db)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    for file in &files {
        let path = args.out.join(&file.name);
        std::fs::write(&path, &file.bytes)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    let rows = paper.tables.first().map_or(0, |t| t.table.rows.len());
    eprintln!(
        "wrote {} files to {} ({rows} rows per table)",
        files.len(),
        args.out.display()
    );
    if args.compare_reported {
        if paper.reproduction.is_empty() {
            eprintln!("no published model of this dataset was also scored on this hub");
        }
        for cell in &paper.reproduction {
            let interval = cell.interval.map_or_else(
                || "no interval".to_owned(),
                |(low, high)| format!("hub [{low:.2}, {high:.2}]"),
            );
            let inside = match cell.inside {
                Some(true) => "inside",
                Some(false) => "OUTSIDE",
                None => "-",
            };
            println!(
                "{} {} {}: reported {:.2}, hub {:.2} ({:+.2}), {interval}, {inside}",
                cell.model,
                cell.metric.as_str(),
                cell.cell,
                cell.reported,
                cell.hub,
                cell.difference
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}
