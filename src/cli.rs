//! The `enact-hub` command line: argument parsing and the commands' terminal output.

use std::io::IsTerminal;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;
use clap::{Args, Parser, Subcommand};
use sqlx::SqlitePool;

use crate::import::{ImportError, ImportOptions, ImportReport, SkippedLine, import_release};
use crate::scoring::{self, ScoringTarget, SemanticCoverage};
use crate::web::{AppState, Server, WebConfig, shutdown_signal};
use crate::{demo, store};

#[derive(Parser)]
#[command(
    name = "enact-hub",
    version,
    about = "Self-hosted evaluation service for the ENACT benchmark"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the web service.
    Serve(ServeArgs),
    /// Import an ENACT release (QA/enact_ordering.jsonl + images) into the database.
    Import(ImportArgs),
    /// Score a prediction file (ENACT model-output JSONL, or compact {"id", "answer"} lines).
    Score(ScoreArgs),
    /// Krippendorff's alpha of reliability data, with an optional bootstrap interval.
    Agreement(AgreementArgs),
    /// Human annotator accounts.
    #[command(subcommand)]
    Annotator(AnnotatorCommand),
}

#[derive(Subcommand)]
enum AnnotatorCommand {
    /// Create an annotator and print their single-use invite link (on the last line).
    Create(CreateAnnotatorArgs),
}

#[derive(Args)]
struct CreateAnnotatorArgs {
    #[command(flatten)]
    db: DbArg,
    /// Login name: letters, digits, '.', '_' and '-'.
    #[arg(long)]
    name: String,
    /// Give the account the admin pages (accounts, assignments, flags, human performance).
    #[arg(long)]
    admin: bool,
    /// Where annotators reach the service; the invite link starts with it.
    #[arg(long, env = "ENACT_HUB_URL", default_value = "http://127.0.0.1:8080")]
    base_url: String,
}

#[derive(Args)]
struct AgreementArgs {
    /// `{"data": [[...], ...]}`: one list per coder, numbers or null for a missing value.
    #[arg(long, value_name = "FILE.json")]
    input: PathBuf,
    /// Level of measurement: nominal, ordinal, interval or ratio.
    #[arg(long)]
    level: crate::agreement::MeasurementLevel,
    /// Number of bootstrap replicates (units resampled with replacement); 0 for none.
    #[arg(long, default_value_t = 0)]
    bootstrap: usize,
    /// Seed of the bootstrap, recorded in the output.
    #[arg(long, default_value_t = crate::agreement::DEFAULT_BOOTSTRAP_SEED)]
    seed: u64,
    /// Coverage of the bootstrap interval.
    #[arg(long, default_value_t = crate::agreement::DEFAULT_CONFIDENCE_LEVEL)]
    confidence: f64,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum PolicyArg {
    /// ENACT's evaluator, quirks included: unparseable answers and duplicate ids are skipped.
    Enact,
    /// Every dataset item counts; a missing or unparseable answer scores TA 0 and PA 0.
    Strict,
}

#[derive(Args)]
struct ScoreArgs {
    /// The prediction file (JSONL).
    predictions: PathBuf,
    /// Score against a dataset stored in this database (with --dataset).
    #[arg(long, requires = "dataset", conflicts_with = "data")]
    db: Option<PathBuf>,
    /// The stored dataset to score against.
    #[arg(long, requires = "db")]
    dataset: Option<String>,
    /// Score against an ENACT release folder (QA/enact_ordering.jsonl) instead of a database.
    #[arg(long, value_name = "DATA_DIR", required_unless_present = "db")]
    data: Option<PathBuf>,
    /// ENACT's replayed_activities folder, for semantic matching from scene graphs.
    #[arg(long, value_name = "REPLAYED_DIR")]
    scene_graphs: Option<PathBuf>,
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
struct DbArg {
    /// SQLite database file (created if missing).
    #[arg(long, env = "ENACT_HUB_DB", default_value = "enact-hub.db")]
    db: PathBuf,
}

#[derive(Args)]
struct ServeArgs {
    /// SQLite database file (created if missing). With --demo and no --db, a temporary
    /// database is used and removed at exit.
    #[arg(long, env = "ENACT_HUB_DB")]
    db: Option<PathBuf>,
    /// Address to listen on.
    #[arg(long, env = "ENACT_HUB_ADDR", default_value = "127.0.0.1:8080")]
    addr: SocketAddr,
    /// Generate the built-in demo dataset at start and serve it (as dataset "demo").
    #[arg(long)]
    demo: bool,
    /// Largest request body accepted, in bytes.
    #[arg(long, default_value_t = WebConfig::default().body_limit)]
    body_limit: usize,
    /// Seconds a request may take before it is answered with 408.
    #[arg(long, default_value_t = 30)]
    request_timeout: u64,
    /// Memory for caching frame images, in MiB.
    #[arg(long, default_value_t = 256)]
    frame_cache_mib: usize,
}

#[derive(Args)]
struct ImportArgs {
    /// Release folder holding QA/enact_ordering.jsonl, or a path to a .jsonl file in its QA/ folder.
    data: PathBuf,
    #[command(flatten)]
    db: DbArg,
    /// Dataset to import into (default: the release folder's name).
    #[arg(long)]
    dataset: Option<String>,
    /// Import the valid rows and report the invalid ones, instead of refusing the whole file.
    #[arg(long)]
    skip_invalid: bool,
    /// Overwrite stored items whose content differs from the file.
    #[arg(long)]
    replace: bool,
    /// ENACT's replayed_activities folder: compute transition signatures from
    /// {task}/scene_graph_0.json for semantic scoring.
    #[arg(long, value_name = "REPLAYED_DIR")]
    scene_graphs: Option<PathBuf>,
    /// Print the full report as JSON on standard output.
    #[arg(long)]
    json: bool,
}

fn init_tracing() {
    use tracing_subscriber::EnvFilter;
    let filter = EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| EnvFilter::new("info,sqlx=warn,tower_http=info"));
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr);
    // Structured JSON lines for log collectors; readable text otherwise.
    if std::env::var("ENACT_HUB_LOG_FORMAT").as_deref() == Ok("json") {
        builder.json().init();
    } else {
        builder.init();
    }
}

/// Entry point of the binary.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    init_tracing();
    let runtime = match tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
    {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("error: cannot start the async runtime: {e}");
            return ExitCode::FAILURE;
        }
    };
    let result = runtime.block_on(async {
        match cli.command {
            Command::Serve(args) => serve(args).await,
            Command::Import(args) => import(args).await,
            Command::Score(args) => score(args).await,
            Command::Agreement(args) => agreement(&args),
            Command::Annotator(AnnotatorCommand::Create(args)) => create_annotator(args).await,
        }
    });
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

async fn open_db(path: &Path) -> anyhow::Result<SqlitePool> {
    store::open(path)
        .await
        .with_context(|| format!("cannot open database {}", path.display()))
}

async fn serve(args: ServeArgs) -> anyhow::Result<ExitCode> {
    // Held until the server stops: dropping it removes the temporary demo database.
    let mut _temporary = None;
    let db = match (&args.db, args.demo) {
        (Some(db), _) => db.clone(),
        (None, true) => {
            let dir = tempfile::tempdir().context("cannot create a temporary directory")?;
            let db = dir.path().join("demo.db");
            _temporary = Some(dir);
            db
        }
        (None, false) => PathBuf::from("enact-hub.db"),
    };
    let pool = open_db(&db).await?;
    if args.demo {
        load_demo(&pool).await?;
    }
    let config = WebConfig {
        body_limit: args.body_limit,
        request_timeout: Duration::from_secs(args.request_timeout),
        frame_cache_bytes: args.frame_cache_mib * 1024 * 1024,
    };
    let server = Server::bind(args.addr, AppState::new(pool.clone(), &config), &config)
        .await
        .with_context(|| format!("cannot listen on {}", args.addr))?;
    let addr = server.local_addr()?;
    tracing::info!(%addr, db = %db.display(), "enact-hub is listening on http://{addr}/");
    server.run(shutdown_signal()).await?;
    pool.close().await;
    Ok(ExitCode::SUCCESS)
}

/// Writes the demo release to a temporary folder and imports it as dataset "demo".
pub async fn load_demo(pool: &SqlitePool) -> anyhow::Result<ImportReport> {
    let dir = tempfile::tempdir().context("cannot create a temporary directory")?;
    let out = dir.path().to_path_buf();
    tokio::task::spawn_blocking(move || demo::write_demo_release(&out, demo::DEFAULT_SEED))
        .await
        .context("demo generation task failed")?
        .context("cannot generate the demo dataset")?;
    let options = ImportOptions {
        dataset: "demo".to_owned(),
        skip_invalid: false,
        replace: true,
        progress: false,
        scene_graphs: None,
    };
    let report = import_release(pool, dir.path(), &options)
        .await
        .context("cannot import the demo dataset")?;
    tracing::info!("{}", report.summary_line());
    Ok(report)
}

/// The dataset name `import` uses when none is given: the release folder's name.
fn default_dataset_name(data: &Path) -> String {
    let folder = if data.is_file() {
        data.parent().and_then(Path::parent)
    } else {
        Some(data)
    };
    folder
        .and_then(|f| std::fs::canonicalize(f).ok())
        .and_then(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
        .filter(|n| !n.is_empty())
        .unwrap_or_else(|| "enact".to_owned())
}

/// One line per rejected row: the row's first problems, and how many more it has.
fn describe_line(line: &SkippedLine) -> String {
    const SHOWN: usize = 3;
    let mut s = format!("line {}", line.line);
    if let Some(id) = &line.item_id {
        s.push_str(&format!(" ({id})"));
    }
    s.push_str(": ");
    let shown: Vec<String> = line
        .problems
        .iter()
        .take(SHOWN)
        .map(ToString::to_string)
        .collect();
    s.push_str(&shown.join("; "));
    if line.problems.len() > SHOWN {
        s.push_str(&format!(
            " (+{} more problems)",
            line.problems.len() - SHOWN
        ));
    }
    s
}

async fn import(args: ImportArgs) -> anyhow::Result<ExitCode> {
    let dataset = args
        .dataset
        .clone()
        .unwrap_or_else(|| default_dataset_name(&args.data));
    let pool = open_db(&args.db.db).await?;
    let options = ImportOptions {
        dataset,
        skip_invalid: args.skip_invalid,
        replace: args.replace,
        progress: std::io::stderr().is_terminal(),
        scene_graphs: args.scene_graphs.clone(),
    };
    let result = import_release(&pool, &args.data, &options).await;
    pool.close().await;
    match result {
        Ok(report) => {
            if !report.skipped.is_empty() {
                eprintln!("skipped {} invalid rows:", report.skipped.len());
                for line in &report.skipped {
                    eprintln!("  {}", describe_line(line));
                }
            }
            if args.json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            }
            eprintln!("{}", report.summary_line());
            Ok(ExitCode::SUCCESS)
        }
        Err(ImportError::Invalid { file, rows, lines }) => {
            for line in &lines {
                eprintln!("{}", describe_line(line));
            }
            eprintln!(
                "error: {file}: {} invalid rows of {rows}; nothing was imported \
                 (fix them, or use --skip-invalid to import the {} valid rows)",
                lines.len(),
                rows - lines.len()
            );
            Ok(ExitCode::FAILURE)
        }
        Err(e) => {
            for detail in e.details() {
                eprintln!("{detail}");
            }
            eprintln!("error: {e}");
            Ok(ExitCode::FAILURE)
        }
    }
}

/// Writes `meta_performance/enact_ordering_{model}.json` and `detailed_eval/enact_ordering_{model}.jsonl`.
fn write_enact_outputs(out: &Path, model: &str, meta: &str, detailed: &str) -> anyhow::Result<()> {
    for (folder, ext, content) in [
        ("meta_performance", "json", meta),
        ("detailed_eval", "jsonl", detailed),
    ] {
        let dir = out.join(folder);
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create {}", dir.display()))?;
        let path = dir.join(format!("enact_ordering_{model}.{ext}"));
        std::fs::write(&path, content)
            .with_context(|| format!("cannot write {}", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// The dataset items a strict scoring runs over, with the best signatures available.
async fn scoring_targets(
    args: &ScoreArgs,
) -> anyhow::Result<Result<Vec<ScoringTarget>, Vec<String>>> {
    if let (Some(db), Some(dataset)) = (&args.db, &args.dataset) {
        if args.scene_graphs.is_some() {
            anyhow::bail!(
                "--scene-graphs goes with --data; a stored dataset keeps the signatures computed \
                 at import (enact-hub import DATA_DIR --scene-graphs REPLAYED_DIR)"
            );
        }
        let pool = open_db(db).await?;
        let mut conn = pool.acquire().await?;
        let stored = store::datasets::by_name(&mut conn, dataset)
            .await?
            .with_context(|| format!("no dataset named '{dataset}' in {}", db.display()))?;
        let rows = store::items::scoring_items(&mut conn, stored.id).await?;
        drop(conn);
        pool.close().await;
        let mut targets = Vec::with_capacity(rows.len());
        for row in rows {
            let semantics = match &row.semantics {
                None => None,
                Some((source, json)) => Some(crate::semantics::ItemSemantics {
                    source: crate::semantics::SignatureSource::parse(source).with_context(
                        || format!("item {}: unknown signature source {source:?}", row.item_id),
                    )?,
                    signatures: serde_json::from_str(json).with_context(|| {
                        format!("item {}: stored signatures are unreadable", row.item_id)
                    })?,
                }),
            };
            let item = crate::dataset::QaItem {
                id: row.item_id,
                item_type: row.item_type,
                direction: row.direction,
                step_length: row.step_length,
                task_name: row.task_name,
                key_frame_ids: row.key_frame_ids,
                images: Vec::new(),
                question: String::new(),
                actions: Vec::new(),
                gt_answer: row.gt_answer,
            };
            targets.push(ScoringTarget::from_item(&item, semantics).map_err(anyhow::Error::msg)?);
        }
        return Ok(Ok(targets));
    }
    let data = args
        .data
        .clone()
        .context("give --data DATA_DIR, or --db PATH --dataset NAME")?;
    let scene_graphs = args.scene_graphs.clone();
    tokio::task::spawn_blocking(move || read_release_targets(&data, scene_graphs.as_deref()))
        .await
        .context("reading the release failed")?
}

/// Reads a release's QA file (images are not needed to score) and computes signatures.
fn read_release_targets(
    data: &Path,
    scene_graphs: Option<&Path>,
) -> anyhow::Result<Result<Vec<ScoringTarget>, Vec<String>>> {
    let location = crate::import::ReleaseLocation::resolve(data)?;
    let text = std::fs::read_to_string(&location.qa_file)
        .with_context(|| format!("cannot read {}", location.qa_file.display()))?;
    let file = location.qa_file.display().to_string();
    let mut items = Vec::new();
    let mut problems = Vec::new();
    for (index, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        match crate::dataset::parse_release_line(line) {
            Ok(item) => items.push((index + 1, item)),
            Err(ps) => problems.extend(
                ps.iter()
                    .map(|p| format!("{file}: line {}: {p}", index + 1)),
            ),
        }
    }
    if !problems.is_empty() {
        return Ok(Err(problems));
    }
    let refs: Vec<&crate::dataset::QaItem> = items.iter().map(|(_, i)| i).collect();
    let semantics = crate::semantics::for_items(scene_graphs, &refs);
    let mut targets = Vec::with_capacity(items.len());
    for ((line, item), semantics) in items.iter().zip(semantics) {
        match semantics {
            Ok(s) => targets.push(ScoringTarget::from_item(item, s).map_err(anyhow::Error::msg)?),
            Err(ps) => problems.extend(
                ps.iter()
                    .map(|p| format!("{file}: line {line} ({}): {p}", item.id)),
            ),
        }
    }
    Ok(if problems.is_empty() {
        Ok(targets)
    } else {
        Err(problems)
    })
}

async fn score(args: ScoreArgs) -> anyhow::Result<ExitCode> {
    let file = args.predictions.display().to_string();
    let bytes = std::fs::read(&args.predictions).with_context(|| format!("cannot read {file}"))?;
    let text = String::from_utf8(bytes).map_err(|e| {
        anyhow::anyhow!(
            "{file}: not UTF-8 text (byte {} is invalid)",
            e.utf8_error().valid_up_to()
        )
    })?;
    let model = args.model.clone().unwrap_or_else(|| {
        crate::verifier::enact_model_name(
            &args
                .predictions
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
        )
    });

    match args.policy {
        PolicyArg::Enact => {
            let Some(replayed) = args.scene_graphs.clone() else {
                anyhow::bail!(
                    "the enact policy scores as ENACT's evaluator does, which reads scene graphs: \
                     give --scene-graphs REPLAYED_DIR"
                );
            };
            let evaluation = tokio::task::spawn_blocking(move || {
                let lines: Vec<(usize, &str)> = crate::verifier::python_text_lines(&text).collect();
                let source = scoring::SceneGraphSignatures::for_predictions(
                    &replayed,
                    lines.iter().map(|(_, l)| *l),
                )?;
                anyhow::Ok(crate::verifier::score_enact_predictions(
                    lines, &model, &source,
                ))
            })
            .await
            .context("scoring task failed")??;
            let evaluation = match evaluation {
                Ok(e) => e,
                Err(e) => {
                    eprintln!("error: {file}: {e}");
                    return Ok(ExitCode::FAILURE);
                }
            };
            if !evaluation.skipped.is_empty() {
                eprintln!(
                    "skipped {} lines (ENACT leaves them out of every metric):",
                    evaluation.skipped.len()
                );
                for s in &evaluation.skipped {
                    eprintln!("  {file}: line {}: {}", s.line, s.reason);
                }
            }
            print!("{}", scoring::performance_table(&evaluation.report));
            println!(
                "model {}: {} items evaluated, {} lines skipped (policy enact)",
                evaluation.model_name,
                evaluation.evaluated.len(),
                evaluation.skipped.len()
            );
            if let Some(out) = &args.out {
                write_enact_outputs(
                    out,
                    &evaluation.model_name,
                    &evaluation.meta_performance_json(),
                    &evaluation.detailed_eval_jsonl(),
                )?;
            }
            Ok(ExitCode::SUCCESS)
        }
        PolicyArg::Strict => {
            let targets = match scoring_targets(&args).await? {
                Ok(t) => t,
                Err(problems) => {
                    for p in &problems {
                        eprintln!("{p}");
                    }
                    eprintln!(
                        "error: the dataset has {} problems; nothing was scored",
                        problems.len()
                    );
                    return Ok(ExitCode::FAILURE);
                }
            };
            let semantic = SemanticCoverage::of(&targets);
            let scored = tokio::task::spawn_blocking(move || {
                let items: Vec<crate::verifier::StrictItem<'_>> =
                    targets.iter().map(ScoringTarget::strict_item).collect();
                let scoring = crate::verifier::score_strict_predictions(
                    &items,
                    crate::verifier::python_text_lines(&text),
                );
                (targets, scoring)
            })
            .await
            .context("scoring task failed")?;
            let (targets, scoring) = scored;
            let scoring = scoring?;
            if !scoring.problems.is_empty() {
                for p in &scoring.problems {
                    eprintln!("{file}: {p}");
                }
                eprintln!(
                    "error: {file}: {} problems; nothing was scored",
                    scoring.problems.len()
                );
                return Ok(ExitCode::FAILURE);
            }
            let c = &scoring.coverage;
            print!("{}", scoring::performance_table(&scoring.report));
            println!(
                "model {model}: {} of {} items answered (coverage {:.2}%), {} unparseable \
                 (parse-failure rate {:.2}%), {} missing (policy strict)",
                c.answered,
                c.dataset_items,
                c.coverage * 100.0,
                c.unparseable,
                c.parse_failure_rate * 100.0,
                c.missing
            );
            println!("{}", semantic.describe());
            if let Some(out) = &args.out {
                let meta = crate::verifier::enact_meta_performance_json(&model, &scoring.report);
                write_enact_outputs(
                    out,
                    &model,
                    &meta,
                    &scoring::strict_detailed_jsonl(&targets, &scoring),
                )?;
            }
            Ok(ExitCode::SUCCESS)
        }
    }
}

async fn create_annotator(args: CreateAnnotatorArgs) -> anyhow::Result<ExitCode> {
    if let Err(problem) = crate::web::check_annotator_name(&args.name) {
        eprintln!("error: --name: {problem}");
        return Ok(ExitCode::FAILURE);
    }
    let pool = open_db(&args.db.db).await?;
    let token = crate::annotation::new_token();
    let mut conn = pool.acquire().await?;
    let created = store::annotations::create_annotator(
        &mut conn,
        &args.name,
        args.admin,
        &crate::annotation::token_hash(&token),
    )
    .await?;
    drop(conn);
    pool.close().await;
    if created.is_none() {
        eprintln!(
            "error: an annotator named '{}' already exists in {}",
            args.name,
            args.db.db.display()
        );
        return Ok(ExitCode::FAILURE);
    }
    let role = if args.admin { "admin" } else { "annotator" };
    println!(
        "created {role} '{}'; send them this single-use link to set a password:",
        args.name
    );
    println!("{}", crate::web::invite_url(&args.base_url, &token));
    Ok(ExitCode::SUCCESS)
}

/// Prints alpha (null when undefined, with the reason) and, when asked, its bootstrap interval.
fn agreement(args: &AgreementArgs) -> anyhow::Result<ExitCode> {
    use crate::agreement::{BootstrapConfig, PreparedAlpha, UnitItems, read_reliability_json};
    let data = read_reliability_json(&args.input)?;
    let prepared =
        PreparedAlpha::with_items(&data, args.level, &UnitItems::one_per_unit(data.units()))?;
    let estimate = prepared.estimate();
    let mut out = serde_json::json!({
        "input": args.input.display().to_string(),
        "level": args.level.to_string(),
        "alpha": estimate.alpha,
        "reason": estimate.reason.as_ref().map(ToString::to_string),
        "coders": estimate.coders,
        "units": estimate.units,
        "units_used": estimate.units_used,
        "pairable_values": estimate.pairable_values,
    });
    if args.bootstrap > 0 {
        let config = BootstrapConfig {
            replicates: args.bootstrap,
            confidence_level: args.confidence,
            seed: args.seed,
        };
        let b = prepared.bootstrap(&config)?;
        out["bootstrap"] = serde_json::json!({
            "resampled": "units",
            "replicates": b.replicates,
            "undefined_replicates": b.undefined_replicates,
            "confidence_level": b.confidence_level,
            "ci_low": b.ci_low,
            "ci_high": b.ci_high,
            "seed": b.seed,
            "rng": b.rng,
        });
    }
    println!("{}", serde_json::to_string_pretty(&out)?);
    Ok(ExitCode::SUCCESS)
}
