//! Commands over a stored dataset's annotations: `agreement --db`, `agreement-protocol` and
//! `report`, printing JSON or writing the report bundle.

use std::path::Path;
use std::process::ExitCode;

use anyhow::Context;
use serde_json::json;

use super::{DEFAULT_DB, in_database, open};
use crate::app;
use crate::app::agreement::{AgreementOptions, ReportSettings};
use crate::core::agreement::report::{AgreementSection, REPORT_METRIC_VERSION};
use crate::core::agreement::{BootstrapConfig, MeasurementLevel, OrderingEncoding};

/// The JSON `agreement --db` prints for one agreement section.
pub fn agreement_json(
    dataset: &str,
    dataset_hash: &str,
    section: &AgreementSection,
) -> serde_json::Value {
    let alpha = &section.alpha;
    let ci = (alpha.replicates > 0).then(|| {
        json!({
            "low": alpha.ci_low,
            "high": alpha.ci_high,
            "confidence_level": alpha.confidence_level,
            "replicates": alpha.replicates,
            "undefined_replicates": alpha.undefined_replicates,
            "resampled": "items",
            "seed": alpha.seed,
            "rng": alpha.rng,
        })
    });
    json!({
        "dataset": dataset,
        "dataset_hash": dataset_hash,
        "metric_version": REPORT_METRIC_VERSION,
        "hub": crate::core::version::THIS_BUILD,
        "encoding": section.encoding,
        "level": section.level,
        "alpha": alpha.estimate.alpha,
        "reason": alpha.estimate.reason.as_ref().map(ToString::to_string),
        "ci": ci,
        "pairwise": section.pairwise,
        "mean_pairwise_alpha": section.mean_pairwise_alpha,
        "exact_agreement": section.exact_agreement,
        "annotators": section.annotators,
        "counts": {
            "annotators": section.annotators.len(),
            "items": section.items,
            "answers": section.answers,
            "units": alpha.estimate.units,
            "units_used": alpha.estimate.units_used,
            "pairable_values": alpha.estimate.pairable_values,
            "by_direction_and_step_length": section.counts,
        },
    })
}

/// `agreement --db PATH --dataset NAME`: alpha over the items two or more annotators answered.
pub async fn agreement(
    db: &Path,
    dataset: &str,
    options: AgreementOptions,
) -> anyhow::Result<ExitCode> {
    let hub = open(db).await?;
    let computed = app::agreement::agreement(&hub, dataset, options).await;
    hub.close().await;
    let (hash, section) = in_database(computed, db)?;
    println!(
        "{}",
        serde_json::to_string_pretty(&agreement_json(dataset, &hash, &section))?
    );
    Ok(ExitCode::SUCCESS)
}

#[derive(clap::Args)]
pub struct ProtocolArgs {
    /// SQLite database file, or a PostgreSQL URL
    /// (postgres://user:password@host/db; also ENACT_HUB_DATABASE_URL).
    #[arg(long, visible_alias = "database-url", env = "ENACT_HUB_DB", default_value = DEFAULT_DB)]
    db: std::path::PathBuf,
    /// The stored dataset.
    #[arg(long)]
    dataset: String,
    /// Items drawn per annotator, direction and step length (the paper: 5).
    #[arg(long, default_value_t = crate::core::agreement::protocol::DEFAULT_ITEMS_PER_CELL)]
    items_per_cell: usize,
    /// Seed of the draw, recorded with the round.
    #[arg(long, default_value_t = crate::core::agreement::protocol::DEFAULT_PROTOCOL_SEED)]
    seed: u64,
}

/// `agreement-protocol`: runs the protocol once and prints what it drew as JSON.
pub async fn agreement_protocol(args: &ProtocolArgs) -> anyhow::Result<ExitCode> {
    let hub = open(&args.db).await?;
    let run = app::agreement::run_protocol(
        &hub,
        &super::operator(),
        &args.dataset,
        args.items_per_cell,
        args.seed,
        None,
    )
    .await;
    hub.close().await;
    let run = in_database(run, &args.db)?;
    println!(
        "{}",
        serde_json::to_string_pretty(&json!({
            "dataset": args.dataset,
            "items_per_cell": run.plan.items_per_cell,
            "seed": run.plan.seed,
            "annotators": run.annotators,
            "samples": run.plan.samples,
            "assignments_added": run.assignments_added,
            "shortfalls": run.plan.shortfalls,
        }))?
    );
    Ok(ExitCode::SUCCESS)
}

#[derive(clap::Args)]
pub struct ReportArgs {
    /// SQLite database file, or a PostgreSQL URL
    /// (postgres://user:password@host/db; also ENACT_HUB_DATABASE_URL).
    #[arg(long, visible_alias = "database-url", env = "ENACT_HUB_DB", default_value = DEFAULT_DB)]
    db: std::path::PathBuf,
    /// The stored dataset.
    #[arg(long)]
    dataset: String,
    /// Folder to write the report files into (created if missing; files are overwritten).
    #[arg(long, value_name = "DIR")]
    out: std::path::PathBuf,
    /// How an ordering answer becomes reliability data: answer, position or rank.
    #[arg(long, default_value_t = crate::core::agreement::PAPER_COMPARABLE_ENCODING)]
    encoding: OrderingEncoding,
    /// Level of measurement (default: the encoding's).
    #[arg(long)]
    level: Option<MeasurementLevel>,
    /// Bootstrap resamples of the overlapping items.
    #[arg(long, default_value_t = crate::core::agreement::DEFAULT_REPLICATES)]
    bootstrap: usize,
    /// Seed of the bootstrap, recorded in every file.
    #[arg(long, default_value_t = crate::core::agreement::DEFAULT_BOOTSTRAP_SEED)]
    seed: u64,
    /// Coverage of the bootstrap interval.
    #[arg(long, default_value_t = crate::core::agreement::DEFAULT_CONFIDENCE_LEVEL)]
    confidence: f64,
    /// Two published submission ids to compare with each other (a − b).
    #[arg(long, num_args = 2, value_names = ["A", "B"])]
    compare: Option<Vec<i64>>,
}

/// `report`: builds the dataset's report and writes the bundle's files into `--out`.
pub async fn report(args: &ReportArgs) -> anyhow::Result<ExitCode> {
    let settings = ReportSettings {
        encoding: args.encoding,
        level: args.level,
        bootstrap: BootstrapConfig {
            replicates: args.bootstrap,
            confidence_level: args.confidence,
            seed: args.seed,
        },
        chosen_pair: args.compare.as_deref().and_then(|ids| match ids {
            [a, b] => Some((*a, *b)),
            _ => None,
        }),
    };
    let hub = open(&args.db).await?;
    let bundle = app::agreement::report_bundle(&hub, &args.dataset, &settings).await;
    hub.close().await;
    let (report, files) = in_database(bundle, &args.db)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    for file in &files {
        let path = args.out.join(&file.name);
        std::fs::write(&path, &file.bytes)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    match (&report.agreement, &report.agreement_unavailable) {
        (Some(a), _) => eprintln!(
            "alpha {} ({} encoding, {} items, {} annotators); exact agreement {}/{}",
            a.alpha
                .estimate
                .alpha
                .map_or_else(|| "undefined".to_owned(), |v| format!("{v:.4}")),
            a.encoding,
            a.items,
            a.annotators.len(),
            a.exact_agreement.agreeing_items,
            a.exact_agreement.compared_items
        ),
        (None, Some(why)) => eprintln!("no agreement figures: {why}"),
        (None, None) => {}
    }
    eprintln!(
        "wrote {} files to {} (dataset hash sha256:{})",
        files.len(),
        args.out.display(),
        report.stamp.dataset_hash
    );
    Ok(ExitCode::SUCCESS)
}
