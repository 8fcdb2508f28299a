//! `score` and `errors`: a prediction file scored or analysed against a stored dataset or a
//! release folder. The work is [`crate::app::scoring`]'s; this file parses and prints.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use clap::Args;

use super::{in_database, open, refusal_in, spinner};
use crate::app;
use crate::app::scoring::{Against, FilePolicy, ScoreFileError, ScoredFile, ScoringStep};
use crate::core::error_analysis::ErrorAnalysis;
use crate::core::error_analysis::present::text_table;
use crate::core::scoring::performance_table;

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum PolicyArg {
    /// ENACT's evaluator, quirks included: unparseable answers and duplicate ids are skipped.
    Enact,
    /// Every dataset item counts; a missing or unparseable answer scores TA 0 and PA 0.
    Strict,
}

/// The items a prediction file is read against: a stored dataset or a release folder.
#[derive(Args)]
pub(super) struct AgainstArgs {
    /// Use a dataset stored in this database (with --dataset).
    #[arg(long, requires = "dataset", conflicts_with = "data")]
    db: Option<PathBuf>,
    /// The stored dataset.
    #[arg(long, requires = "db")]
    dataset: Option<String>,
    /// Use an ENACT release folder (QA/enact_ordering.jsonl) instead of a database.
    #[arg(long, value_name = "DATA_DIR", required_unless_present = "db")]
    data: Option<PathBuf>,
    /// ENACT's replayed_activities folder, for semantic matching from scene graphs (forward
    /// items get signatures only from there).
    #[arg(long, value_name = "REPLAYED_DIR")]
    scene_graphs: Option<PathBuf>,
}

#[derive(Args)]
pub(super) struct ScoreArgs {
    /// The prediction file (JSONL).
    predictions: PathBuf,
    #[command(flatten)]
    against: AgainstArgs,
    /// Scoring policy.
    #[arg(long, value_enum, default_value = "strict")]
    policy: PolicyArg,
    /// Write ENACT's output files here: meta_performance/ and detailed_eval/.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Model name for the output files (default: from the file name, as ENACT does).
    #[arg(long)]
    model: Option<String>,
}

#[derive(Args)]
pub(super) struct ErrorsArgs {
    /// The prediction file (JSONL), read as the leaderboard reads submissions.
    #[arg(required_unless_present = "annotator")]
    predictions: Option<PathBuf>,
    #[command(flatten)]
    against: AgainstArgs,
    /// Analyse this annotator's answers on the --db dataset instead of a prediction file.
    #[arg(long, requires = "dataset", conflicts_with = "predictions")]
    annotator: Option<String>,
    /// Print one JSON object (the API's `/submissions/{id}/errors` shape) instead of a table.
    #[arg(long)]
    json: bool,
}

/// Writes `meta_performance/enact_ordering_{model}.json` and `detailed_eval/enact_ordering_{model}.jsonl`.
fn write_enact_outputs(out: &Path, scored: &ScoredFile) -> anyhow::Result<()> {
    let (meta, detailed) = scored.enact_outputs();
    for (folder, ext, content) in [
        ("meta_performance", "json", meta),
        ("detailed_eval", "jsonl", detailed),
    ] {
        let dir = out.join(folder);
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create {}", dir.display()))?;
        let path = dir.join(format!("enact_ordering_{}.{ext}", scored.model()));
        std::fs::write(&path, content)
            .with_context(|| format!("cannot write {}", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// Shows the slow steps of scoring as a spinner on standard error (hidden when not a terminal).
fn show_step(spinner: &indicatif::ProgressBar, step: ScoringStep) {
    let message = match step {
        ScoringStep::ReadingRelease {
            with_scene_graphs: true,
        } => "reading the release and its scene graphs",
        ScoringStep::ReadingRelease {
            with_scene_graphs: false,
        } => "reading the release",
        ScoringStep::LoadingSceneGraphs => "loading scene graphs",
        ScoringStep::Scoring => "scoring answers",
        ScoringStep::Finished => return spinner.finish_and_clear(),
    };
    spinner.set_message(message);
}

/// Runs `then` against the dataset `against` names: a stored one (opened and closed here), or
/// a release folder.
async fn with_against<T>(
    against: &AgainstArgs,
    then: impl AsyncFnOnce(Against<'_>) -> T,
) -> anyhow::Result<T> {
    if let (Some(db), Some(dataset)) = (&against.db, &against.dataset) {
        if against.scene_graphs.is_some() {
            anyhow::bail!(
                "--scene-graphs goes with --data; a stored dataset keeps the signatures computed \
                 at import (enact-hub import DATA_DIR --scene-graphs REPLAYED_DIR)"
            );
        }
        let hub = open(db).await?;
        let done = then(Against::Stored { hub: &hub, dataset }).await;
        hub.close().await;
        return Ok(done);
    }
    let data = against
        .data
        .clone()
        .context("give --data DATA_DIR, or --db PATH --dataset NAME")?;
    Ok(then(Against::Release {
        data,
        scene_graphs: against.scene_graphs.clone(),
    })
    .await)
}

/// Prints why a file was not scored or analysed (`what`: "scored", "analysed") and fails.
fn not_done(
    e: ScoreFileError,
    file: &str,
    against: &AgainstArgs,
    what: &str,
) -> anyhow::Result<ExitCode> {
    match e {
        ScoreFileError::Refused(e) => return Err(refusal_in(e, against.db.as_deref())),
        ScoreFileError::NeedsSceneGraphs => eprintln!(
            "error: the enact policy scores as ENACT's evaluator does, which needs scene \
             graphs: give --scene-graphs REPLAYED_DIR, or a --db dataset imported with them"
        ),
        ScoreFileError::DatasetProblems(problems) => {
            for p in &problems {
                eprintln!("{p}");
            }
            eprintln!(
                "error: the dataset has {} problems; nothing was {what}",
                problems.len()
            );
        }
        ScoreFileError::FileProblems(problems) => {
            for p in &problems {
                eprintln!("{file}: {p}");
            }
            eprintln!(
                "error: {file}: {} problems; nothing was {what}",
                problems.len()
            );
        }
        ScoreFileError::Unscorable(e) => eprintln!("error: {file}: {e}"),
    }
    Ok(ExitCode::FAILURE)
}

/// Prints an analysis as the table, or as JSON.
fn print_analysis(analysis: &ErrorAnalysis, json: bool) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(analysis)?);
    } else {
        print!("{}", text_table(analysis));
    }
    Ok(())
}

/// `errors`: the paper's error analysis of a prediction file, or of an annotator's answers.
pub(super) async fn errors(args: ErrorsArgs) -> anyhow::Result<ExitCode> {
    if let (Some(annotator), Some(db), Some(dataset)) =
        (&args.annotator, &args.against.db, &args.against.dataset)
    {
        let hub = open(db).await?;
        let analysis = app::error_analysis::of_annotator(&hub, dataset, annotator).await;
        hub.close().await;
        return match in_database(analysis, db)? {
            Some(analysis) => {
                print_analysis(&analysis, args.json)?;
                Ok(ExitCode::SUCCESS)
            }
            None => {
                eprintln!("error: {annotator} has not answered any item of '{dataset}' yet");
                Ok(ExitCode::FAILURE)
            }
        };
    }
    let predictions = args
        .predictions
        .clone()
        .context("give a prediction file, or --annotator NAME with --db and --dataset")?;
    let file = predictions.display().to_string();
    let text = std::fs::read_to_string(&predictions)
        .with_context(|| format!("cannot read {file} (it must be UTF-8 text)"))?;
    let spinner = spinner("analysing answers");
    let show = |step| show_step(&spinner, step);
    let analysis = with_against(&args.against, async |against| {
        app::error_analysis::of_file(against, text, &show).await
    })
    .await?;
    spinner.finish_and_clear();
    match analysis {
        Ok(analysis) => {
            print_analysis(&analysis, args.json)?;
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => not_done(e, &file, &args.against, "analysed"),
    }
}

/// `score`: a prediction file scored under `--policy`; the table on standard output, what was
/// skipped or missing on standard error, ENACT's output files with `--out`.
pub(super) async fn score(args: ScoreArgs) -> anyhow::Result<ExitCode> {
    let file = args.predictions.display().to_string();
    let bytes = std::fs::read(&args.predictions).with_context(|| format!("cannot read {file}"))?;
    let text = String::from_utf8(bytes).map_err(|e| {
        anyhow::anyhow!(
            "{file}: not UTF-8 text (byte {} is invalid)",
            e.utf8_error().valid_up_to()
        )
    })?;
    let model = args
        .model
        .clone()
        .unwrap_or_else(|| app::scoring::model_name_of(&args.predictions));
    let policy = match args.policy {
        PolicyArg::Enact => FilePolicy::Enact,
        PolicyArg::Strict => FilePolicy::Strict,
    };
    let spinner = spinner("scoring");
    let show = |step| show_step(&spinner, step);
    let scored = with_against(&args.against, async |against| {
        app::scoring::score_file(against, policy, text, model, &show).await
    })
    .await?;
    spinner.finish_and_clear();
    let scored = match scored {
        Ok(scored) => scored,
        Err(e) => return not_done(e, &file, &args.against, "scored"),
    };
    match &scored {
        ScoredFile::Enact(evaluation) => {
            if !evaluation.skipped.is_empty() {
                eprintln!(
                    "skipped {} lines (ENACT leaves them out of every metric):",
                    evaluation.skipped.len()
                );
                for s in &evaluation.skipped {
                    eprintln!("  {file}: line {}: {}", s.line, s.reason);
                }
            }
            print!("{}", performance_table(&evaluation.report));
            println!(
                "model {}: {} items evaluated, {} lines skipped (policy enact)",
                evaluation.model_name,
                evaluation.evaluated.len(),
                evaluation.skipped.len()
            );
        }
        ScoredFile::Strict(strict) => {
            let c = &strict.scoring.coverage;
            print!("{}", performance_table(&strict.scoring.report));
            println!(
                "model {}: {} of {} items answered (coverage {:.2}%), {} unparseable \
                 (parse-failure rate {:.2}%), {} missing (policy strict)",
                strict.model,
                c.answered,
                c.dataset_items,
                c.coverage * 100.0,
                c.unparseable,
                c.parse_failure_rate * 100.0,
                c.missing
            );
            println!("{}", strict.semantic.describe());
        }
    }
    if let Some(out) = &args.out {
        write_enact_outputs(out, &scored)?;
    }
    Ok(ExitCode::SUCCESS)
}
