//! `agreement`: Krippendorff's alpha of a reliability-data file, or of a stored dataset's
//! annotations (the stored form is in [`super::stored`]).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;

use super::stored;
use crate::app;
use crate::core::agreement::BootstrapConfig;

#[derive(Args)]
pub(super) struct AgreementArgs {
    /// `{"data": [[...], ...]}`: one list per coder, numbers or null for a missing value.
    #[arg(
        long,
        value_name = "FILE.json",
        required_unless_present = "db",
        conflicts_with = "db"
    )]
    input: Option<PathBuf>,
    /// Agreement on a stored dataset's submitted annotations instead of a file (with --dataset).
    #[arg(long, requires = "dataset")]
    db: Option<PathBuf>,
    /// The stored dataset whose annotations to use.
    #[arg(long, requires = "db")]
    dataset: Option<String>,
    /// With --db: how an ordering answer becomes reliability data: answer (whole permutation,
    /// nominal; comparable with the paper), position or rank (ordinal).
    #[arg(long, requires = "db", default_value_t = crate::core::agreement::PAPER_COMPARABLE_ENCODING)]
    encoding: crate::core::agreement::OrderingEncoding,
    /// Level of measurement: nominal, ordinal, interval or ratio. Required with --input; with
    /// --db it defaults to the encoding's level.
    #[arg(long, required_unless_present = "db")]
    level: Option<crate::core::agreement::MeasurementLevel>,
    /// Number of bootstrap replicates (units resampled with replacement, or items with --db);
    /// 0 for none. Default: 0 with --input, 1000 with --db.
    #[arg(long)]
    bootstrap: Option<usize>,
    /// Seed of the bootstrap, recorded in the output.
    #[arg(long, default_value_t = crate::core::agreement::DEFAULT_BOOTSTRAP_SEED)]
    seed: u64,
    /// Coverage of the bootstrap interval.
    #[arg(long, default_value_t = crate::core::agreement::DEFAULT_CONFIDENCE_LEVEL)]
    confidence: f64,
}

/// `agreement`: of a stored dataset with `--db`, else of the `--input` file.
pub(super) async fn agreement(args: AgreementArgs) -> anyhow::Result<ExitCode> {
    match (&args.db, &args.dataset) {
        (Some(db), Some(dataset)) => stored::agreement(db, dataset, args.stored()).await,
        _ => of_file(&args),
    }
}

impl AgreementArgs {
    fn stored(&self) -> app::agreement::AgreementOptions {
        app::agreement::AgreementOptions {
            encoding: self.encoding,
            level: self.level,
            bootstrap: crate::core::agreement::BootstrapConfig {
                replicates: self
                    .bootstrap
                    .unwrap_or(crate::core::agreement::DEFAULT_REPLICATES),
                confidence_level: self.confidence,
                seed: self.seed,
            },
        }
    }
}

/// Prints alpha (null when undefined, with the reason) and, when asked, its bootstrap interval.
fn of_file(args: &AgreementArgs) -> anyhow::Result<ExitCode> {
    let (Some(input), Some(level)) = (&args.input, args.level) else {
        anyhow::bail!("--input and --level are both needed without --db");
    };
    let bootstrap = BootstrapConfig {
        replicates: args.bootstrap.unwrap_or(0),
        confidence_level: args.confidence,
        seed: args.seed,
    };
    match app::agreement::of_file(input, level, Some(&bootstrap)) {
        Ok(agreement) => {
            println!("{}", serde_json::to_string_pretty(&agreement)?);
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => super::refused(e),
    }
}
