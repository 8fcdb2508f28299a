//! `enact-hub compare A B`: two leaderboard rows of a stored dataset compared item by item,
//! with McNemar's exact test and a paired bootstrap of the difference (`app::compare`).

use std::fmt::Write as _;
use std::process::ExitCode;

use clap::{Args, ValueEnum};

use super::study::DbArg;
use super::{in_database, open};
use crate::app;
use crate::app::compare::{DiscordantItem, RowComparison};
use crate::core::paired::{PairedCell, PairedConfig, Resampling};
use crate::core::verifier::{BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED};

/// What the bootstrap resamples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ResampleArg {
    /// Whole activities (ENACT's task_name) with their items: items of one activity are not
    /// independent.
    Activities,
    /// Items one by one.
    Items,
}

impl From<ResampleArg> for Resampling {
    fn from(arg: ResampleArg) -> Resampling {
        match arg {
            ResampleArg::Activities => Resampling::Activities,
            ResampleArg::Items => Resampling::Items,
        }
    }
}

#[derive(Args)]
pub struct CompareArgs {
    /// Row A: a model name (its leaderboard row: the latest published submission of that
    /// model) or a submission id.
    a: String,
    /// Row B, named the same way.
    b: String,
    #[command(flatten)]
    db: DbArg,
    /// The dataset.
    #[arg(long)]
    dataset: String,
    /// What the bootstrap resamples.
    #[arg(long, value_enum, default_value = "activities")]
    resample: ResampleArg,
    /// Bootstrap resamples.
    #[arg(long, default_value_t = BOOTSTRAP_RESAMPLES as u32, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    resamples: u32,
    /// The bootstrap's seed (the leaderboard's by default, so figures repeat).
    #[arg(long, default_value_t = BOOTSTRAP_SEED)]
    seed: u64,
    /// Print the comparison as JSON (what `GET /api/v1/datasets/{d}/compare` returns).
    #[arg(long)]
    json: bool,
}

pub async fn compare(args: CompareArgs) -> anyhow::Result<ExitCode> {
    let config = PairedConfig {
        resampling: args.resample.into(),
        resamples: args.resamples as usize,
        seed: args.seed,
        ..PairedConfig::default()
    };
    let hub = open(&args.db.db).await?;
    let made = app::compare::rows(&hub, &args.dataset, &args.a, &args.b, config, true).await;
    hub.close().await;
    let comparison = in_database(made, &args.db.db)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&comparison)?);
    } else {
        print!("{}", text(&comparison));
    }
    Ok(ExitCode::SUCCESS)
}

fn percent(value: f64) -> String {
    format!("{:.2}", 100.0 * value)
}

fn cell_name(cell: &PairedCell) -> String {
    match (cell.direction, cell.step_length) {
        (None, _) => "overall".to_owned(),
        (Some(d), None) => d.as_str().to_owned(),
        (Some(d), Some(l)) => format!("{d} L={}", l.get()),
    }
}

/// The comparison as a table for a terminal.
pub fn text(c: &RowComparison) -> String {
    let mut out = String::new();
    let row = |r: &app::compare::ComparedRow| {
        format!(
            "{} (submission {}, account {})",
            r.model, r.submission, r.account
        )
    };
    let _ = writeln!(out, "dataset '{}'", c.dataset);
    let _ = writeln!(out, "A: {}", row(&c.a));
    let _ = writeln!(out, "B: {}", row(&c.b));
    let _ = writeln!(
        out,
        "differences A − B in points, with {:.0} % paired bootstrap intervals ({} resamples of {}, seed {}); McNemar's exact test on task success",
        100.0 * c.config.level,
        c.config.resamples,
        c.config.resampling.as_str(),
        c.config.seed
    );
    if c.metric_versions_differ {
        let _ = writeln!(
            out,
            "warning: the rows were scored under different metric versions ({} and {}); \
             `enact-hub rescore` makes them comparable",
            c.a.metric_version, c.b.metric_version
        );
    }
    if c.unpaired_items > 0 {
        let _ = writeln!(
            out,
            "note: {} items have a verdict in only one of the rows and are left out",
            c.unpaired_items
        );
    }
    let _ = writeln!(
        out,
        "\n{:<12} {:>5} {:>7} {:>7} {:>24} {:>7} {:>7} {:>9} {:>7} {:>7} {:>24}",
        "cell",
        "n",
        "TA A",
        "TA B",
        "TA A−B [interval]",
        "A only",
        "B only",
        "McNemar p",
        "PA A",
        "PA B",
        "PA A−B [interval]"
    );
    for cell in std::iter::once(&c.overall).chain(&c.cells) {
        let pa = |v: Option<f64>| v.map_or_else(|| "–".to_owned(), percent);
        let pd = cell
            .pairwise_difference
            .map_or_else(|| "–".to_owned(), |d| difference(d.estimate, d.low, d.high));
        let _ = writeln!(
            out,
            "{:<12} {:>5} {:>7} {:>7} {:>24} {:>7} {:>7} {:>9.4} {:>7} {:>7} {:>24}",
            cell_name(cell),
            cell.n,
            percent(cell.a_task_accuracy),
            percent(cell.b_task_accuracy),
            difference(
                cell.difference.estimate,
                cell.difference.low,
                cell.difference.high
            ),
            cell.a_only,
            cell.b_only,
            cell.mcnemar_p,
            pa(cell.a_pairwise_accuracy),
            pa(cell.b_pairwise_accuracy),
            pd
        );
    }
    let list = |out: &mut String, title: &str, items: &Option<Vec<DiscordantItem>>| {
        if let Some(items) = items {
            let _ = writeln!(out, "\n{title} ({}):", items.len());
            for i in items {
                let _ = writeln!(
                    out,
                    "  {}  {} L={}  {}",
                    i.item,
                    i.direction,
                    i.step_length.get(),
                    i.activity
                );
            }
        }
    };
    list(&mut out, "A right, B wrong", &c.a_only_items);
    list(&mut out, "B right, A wrong", &c.b_only_items);
    out
}

fn difference(estimate: f64, low: f64, high: f64) -> String {
    format!(
        "{:+.2} [{:+.2}, {:+.2}]",
        100.0 * estimate,
        100.0 * low,
        100.0 * high
    )
}
