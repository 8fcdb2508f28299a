//! `enact-hub annotator quality|exclude|include`: each annotator's figures on a dataset, and
//! keeping an annotator's answers out of its Human row ([`crate::app::quality`],
//! [`crate::app::gold`]).

use std::process::ExitCode;

use clap::Args;

use super::{DbArg, in_database, is_missing_file, open, operator};
use crate::app;
use crate::core::quality::AnnotatorQuality;

#[derive(Args)]
pub(super) struct QualityArgs {
    #[command(flatten)]
    db: DbArg,
    /// The dataset's name.
    #[arg(long)]
    dataset: String,
    /// Items answered in under this many seconds count as fast.
    #[arg(long, value_name = "SECONDS")]
    fast_seconds: Option<f64>,
    /// Print the figures as JSON (`{"annotators": [...]}`) instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
pub(super) struct ExclusionArgs {
    /// The annotator's login name.
    name: String,
    #[command(flatten)]
    db: DbArg,
    /// The dataset's name.
    #[arg(long)]
    dataset: String,
}

pub(super) async fn quality(args: QualityArgs) -> anyhow::Result<ExitCode> {
    if is_missing_file(&args.db.db) {
        eprintln!("error: no database at {}", args.db.db.display());
        return Ok(ExitCode::FAILURE);
    }
    let fast = match app::quality::fast_seconds(args.fast_seconds) {
        Ok(fast) => fast,
        Err(e) => {
            eprintln!("error: --fast-seconds: {e}");
            return Ok(ExitCode::FAILURE);
        }
    };
    let hub = open(&args.db.db).await?;
    let result = app::quality::report(&hub, &args.dataset, fast).await;
    hub.close().await;
    let report = in_database(result, &args.db.db)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(ExitCode::SUCCESS);
    }
    println!(
        "dataset '{}': {} gold items; fast means under {} s",
        report.dataset, report.gold_items, report.fast_seconds
    );
    println!(
        "{:<20} {:>5} {:>5} {:>13} {:>13} {:>6} {:>6} {:>7} {:>7} {:>6} {:>5} {:>5}",
        "annotator",
        "done",
        "gold",
        "gold TA",
        "gold PA",
        "alpha",
        "exact",
        "med s",
        "p10 s",
        "fast",
        "skip",
        "flag"
    );
    for a in &report.annotators {
        println!("{}", table_row(a));
    }
    for c in &report.attention {
        println!(
            "attention checks of {}: {} passed, {} failed, {} pending",
            c.annotator, c.tally.passed, c.tally.failed, c.tally.pending
        );
    }
    for e in &report.exclusions {
        println!(
            "excluded: {} (by {} at {})",
            e.annotator, e.excluded_by, e.excluded_at
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn percent(value: Option<f64>) -> String {
    value.map_or_else(|| "–".to_owned(), |v| format!("{:.0}%", v * 100.0))
}

fn number(value: Option<f64>) -> String {
    value.map_or_else(|| "–".to_owned(), |v| format!("{v:.2}"))
}

fn with_interval(value: Option<f64>, interval: Option<crate::core::quality::Interval>) -> String {
    match (value, interval) {
        (Some(v), Some(i)) => format!(
            "{:.0}% [{:.0}-{:.0}]",
            v * 100.0,
            i.low * 100.0,
            i.high * 100.0
        ),
        _ => "–".to_owned(),
    }
}

fn table_row(a: &AnnotatorQuality) -> String {
    let name = if a.excluded {
        format!("{} (excl.)", a.name)
    } else {
        a.name.clone()
    };
    format!(
        "{:<20} {:>5} {:>5} {:>13} {:>13} {:>6} {:>6} {:>7} {:>7} {:>6} {:>5} {:>5}",
        name,
        a.items_done,
        a.gold_answered,
        with_interval(a.gold_task_accuracy, a.gold_task_accuracy_interval),
        with_interval(a.gold_pairwise_accuracy, a.gold_pairwise_accuracy_interval),
        number(a.pairwise_alpha),
        percent(a.exact_agreement),
        number(a.median_seconds),
        number(a.lower_decile_seconds),
        percent(a.fast_share),
        percent(a.skip_rate),
        percent(a.flag_rate),
    )
}

pub(super) async fn exclude(args: ExclusionArgs) -> anyhow::Result<ExitCode> {
    change(args, true).await
}

pub(super) async fn include(args: ExclusionArgs) -> anyhow::Result<ExitCode> {
    change(args, false).await
}

async fn change(args: ExclusionArgs, exclude: bool) -> anyhow::Result<ExitCode> {
    let hub = open(&args.db.db).await?;
    let actor = operator();
    let result = if exclude {
        app::gold::exclude(&hub, &actor, &args.dataset, &args.name).await
    } else {
        app::gold::include(&hub, &actor, &args.dataset, &args.name).await
    };
    hub.close().await;
    if !in_database(result, &args.db.db)? {
        println!(
            "annotator '{}' is {} on dataset '{}' already; nothing changed",
            args.name,
            if exclude { "excluded" } else { "included" },
            args.dataset
        );
    } else if exclude {
        println!(
            "annotator '{}': answers on dataset '{}' left out of the Human row and the \
             agreement report (kept; `annotator include` counts them again)",
            args.name, args.dataset
        );
    } else {
        println!(
            "annotator '{}': answers on dataset '{}' counted in the Human row and the \
             agreement report again",
            args.name, args.dataset
        );
    }
    Ok(ExitCode::SUCCESS)
}
