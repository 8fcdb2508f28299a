//! The `enact-hub` command line: argument parsing and the commands' terminal output.

use std::io::IsTerminal;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;
use clap::{Args, Parser, Subcommand};
use sqlx::SqlitePool;

use crate::app::import::{ImportError, ImportOptions, ImportReport, SkippedLine, import_release};
use crate::core::credentials::{NewToken, Role};
use crate::core::demo;
use crate::core::scoring::{self, ScoringTarget, SemanticCoverage};
use crate::store;
use crate::web::{AppState, Server, WebConfig, shutdown_signal};

mod simulate;
mod stored;

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
    /// The paper's cross-annotation protocol on a stored dataset: draw k completed primary items
    /// per annotator × direction × step length and assign each to the other annotators.
    AgreementProtocol(stored::ProtocolArgs),
    /// Write a stored dataset's agreement report (JSON, CSV, Markdown, LaTeX, SVG) to a folder.
    Report(stored::ReportArgs),
    /// Run ENACT's data pipeline on BEHAVIOR-format replays: key-frame segmentation, then
    /// forward and inverse QA items in the ENACT release layout.
    Generate(GenerateArgs),
    /// Simulate household activities in the built-in synthetic world and write them as
    /// BEHAVIOR-format replays that `generate` reads.
    Simulate(simulate::SimulateArgs),
    /// Manage API tokens: create, list, revoke.
    #[command(subcommand)]
    Token(TokenCommand),
    /// Human annotator accounts.
    #[command(subcommand)]
    Annotator(AnnotatorCommand),
}

#[derive(Args)]
struct GenerateArgs {
    /// Folder of replays: {task}/scene_graph_0.json and {task}/external_sensor1/{frame:05d}.png.
    replayed: PathBuf,
    /// Where to write the release (QA/, segmented_activities/, replayed_activities/,
    /// generation_summary.json).
    #[arg(long, value_name = "DATA_DIR")]
    out: PathBuf,
    /// Seed of path sampling, shuffles and sentence templates.
    #[arg(long, default_value_t = 42)]
    seed: u64,
    /// Paths sampled per task, step length and direction.
    #[arg(long, default_value_t = 5)]
    num_to_sample: usize,
    /// Step lengths, as a range `3..10` or a list `3,5,7`.
    #[arg(long, default_value = "3..10")]
    steps: String,
    /// Segmentation constants: `enact-code` (ENACT's code: cosine 0.98, stability 10) or
    /// `paper` (the paper's text: cosine 0.97, stability 40).
    #[arg(long, default_value = "enact-code")]
    preset: String,
    /// Override the preset's cosine-similarity threshold.
    #[arg(long)]
    cosine_threshold: Option<f64>,
    /// Override the preset's minimum gap in frames between key frames.
    #[arg(long)]
    min_gap: Option<u64>,
    /// Override the preset's stability interval in frames.
    #[arg(long)]
    stability_frames: Option<u64>,
    /// Write type names as the released dataset does (`*_world_modeling_ordering_{L}_steps`)
    /// instead of ENACT's code (`*_world_modeling_{L}_steps`).
    #[arg(long)]
    ordering_type_names: bool,
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

#[derive(Subcommand)]
enum TokenCommand {
    /// Create an account's token (the account is created if missing). The token is printed
    /// once, alone on the last line of standard output.
    Create {
        #[command(flatten)]
        db: DbArg,
        /// submitter: submit and read own results; admin: everything.
        #[arg(long, value_enum, default_value = "submitter")]
        role: Role,
        /// The account's name (a person or team).
        #[arg(long)]
        name: String,
        /// Submissions per UTC day (default: the server's --daily-quota).
        #[arg(long)]
        daily_quota: Option<u32>,
        /// Submissions in total (default: the server's --total-quota).
        #[arg(long)]
        total_quota: Option<u32>,
    },
    /// List tokens (never their secrets).
    List {
        #[command(flatten)]
        db: DbArg,
    },
    /// Revoke a token by id or prefix; it stops working at once.
    Revoke {
        #[command(flatten)]
        db: DbArg,
        /// The token's id or prefix, as `token list` shows them.
        token: String,
    },
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
    /// Largest submission body accepted, in bytes.
    #[arg(long, default_value_t = WebConfig::default().submission_body_limit)]
    submission_body_limit: usize,
    /// Submissions a token may make per UTC day (rejected ones count too).
    #[arg(long, default_value_t = WebConfig::default().daily_quota)]
    daily_quota: i64,
    /// Submissions a token may make in total (rejected ones count too).
    #[arg(long, default_value_t = WebConfig::default().total_quota)]
    total_quota: i64,
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
            Command::Agreement(args) => match (&args.db, &args.dataset) {
                (Some(db), Some(dataset)) => stored::agreement(db, dataset, &args.stored()).await,
                _ => agreement(&args),
            },
            Command::AgreementProtocol(args) => stored::agreement_protocol(&args).await,
            Command::Report(args) => stored::report(&args).await,
            Command::Generate(args) => generate(args).await,
            Command::Simulate(args) => simulate::run(args),
            Command::Token(command) => token(command).await,
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
    ensure_admin_token(&pool).await?;
    let config = WebConfig {
        body_limit: args.body_limit,
        request_timeout: Duration::from_secs(args.request_timeout),
        frame_cache_bytes: args.frame_cache_mib * 1024 * 1024,
        submission_body_limit: args.submission_body_limit,
        daily_quota: args.daily_quota,
        total_quota: args.total_quota,
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

/// The admin token: ENACT_HUB_ADMIN_TOKEN if set (stored hashed on first sight), otherwise one
/// generated at the first start and printed once on standard output.
async fn ensure_admin_token(pool: &SqlitePool) -> anyhow::Result<()> {
    let mut tx = pool.begin().await?;
    let from_env = std::env::var("ENACT_HUB_ADMIN_TOKEN")
        .ok()
        .filter(|t| !t.is_empty());
    let token = match from_env {
        Some(text) => {
            let token = NewToken::from_operator(&text)
                .map_err(|e| anyhow::anyhow!("ENACT_HUB_ADMIN_TOKEN: {e}"))?;
            if store::accounts::token_hash_exists(&mut tx, &token.hash).await? {
                return Ok(());
            }
            Some((token, false))
        }
        None if store::accounts::has_admin_token(&mut tx).await? => None,
        None => Some((NewToken::generate(), true)),
    };
    let Some((token, generated)) = token else {
        return Ok(());
    };
    let account = store::accounts::ensure_account(&mut tx, "admin", Role::Admin)
        .await?
        .map_err(anyhow::Error::msg)?;
    store::accounts::insert_token(&mut tx, account, Role::Admin, &token, None, None).await?;
    tx.commit().await?;
    if generated {
        eprintln!(
            "created the admin API token (shown only this once; set ENACT_HUB_ADMIN_TOKEN to \
             choose your own):"
        );
        println!("{}", token.token);
    } else {
        tracing::info!(prefix = %token.prefix, "admin token from ENACT_HUB_ADMIN_TOKEN stored");
    }
    Ok(())
}

async fn token(command: TokenCommand) -> anyhow::Result<ExitCode> {
    match command {
        TokenCommand::Create {
            db,
            role,
            name,
            daily_quota,
            total_quota,
        } => {
            let name = name.trim();
            anyhow::ensure!(
                !name.is_empty() && name.chars().count() <= 100,
                "--name must be 1 to 100 characters"
            );
            let pool = open_db(&db.db).await?;
            let token = NewToken::generate();
            let mut tx = pool.begin().await?;
            let account = match store::accounts::ensure_account(&mut tx, name, role).await? {
                Ok(id) => id,
                Err(message) => {
                    eprintln!("error: {message}");
                    return Ok(ExitCode::FAILURE);
                }
            };
            let id = store::accounts::insert_token(
                &mut tx,
                account,
                role,
                &token,
                daily_quota.map(i64::from),
                total_quota.map(i64::from),
            )
            .await?;
            tx.commit().await?;
            pool.close().await;
            println!(
                "created token {id} (prefix {}) for {} account '{name}'; it is shown only once:",
                token.prefix,
                role.as_str()
            );
            println!("{}", token.token);
            Ok(ExitCode::SUCCESS)
        }
        TokenCommand::List { db } => {
            let pool = open_db(&db.db).await?;
            let mut conn = pool.acquire().await?;
            let tokens = store::accounts::list_tokens(&mut conn).await?;
            drop(conn);
            pool.close().await;
            println!(
                "{:>4}  {:<14} {:<20} {:<9} {:<20} {:<21} status",
                "id", "prefix", "account", "role", "quota (day/total)", "created"
            );
            for t in tokens {
                let quota = format!(
                    "{}/{}",
                    t.daily_quota
                        .map_or("default".to_owned(), |q| q.to_string()),
                    t.total_quota
                        .map_or("default".to_owned(), |q| q.to_string())
                );
                let status = t
                    .revoked_at
                    .map_or_else(|| "live".to_owned(), |at| format!("revoked {at}"));
                println!(
                    "{:>4}  {:<14} {:<20} {:<9} {:<20} {:<21} {status}",
                    t.id, t.prefix, t.account, t.role, quota, t.created_at
                );
            }
            Ok(ExitCode::SUCCESS)
        }
        TokenCommand::Revoke { db, token } => {
            let pool = open_db(&db.db).await?;
            let mut conn = pool.acquire().await?;
            let revoked = store::accounts::revoke_token(&mut conn, &token).await?;
            drop(conn);
            pool.close().await;
            if revoked {
                println!("revoked token {token}");
                Ok(ExitCode::SUCCESS)
            } else {
                eprintln!("error: no live token with id or prefix {token:?}");
                Ok(ExitCode::FAILURE)
            }
        }
    }
}

/// Writes the demo release to a temporary folder and imports it as dataset "demo".
pub async fn load_demo(pool: &SqlitePool) -> anyhow::Result<ImportReport> {
    let dir = tempfile::tempdir().context("cannot create a temporary directory")?;
    let out = dir.path().to_path_buf();
    let written =
        tokio::task::spawn_blocking(move || demo::write_demo_release(&out, demo::DEFAULT_SEED))
            .await
            .context("demo generation task failed")?
            .context("cannot generate the demo dataset")?;
    let options = ImportOptions {
        dataset: "demo".to_owned(),
        skip_invalid: false,
        replace: true,
        progress: false,
        scene_graphs: Some(written.replayed_dir),
    };
    let report = import_release(pool, dir.path(), &options)
        .await
        .context("cannot import the demo dataset")?;
    tracing::info!("{}", report.summary_line());
    submit_chance_baseline(pool, &options.dataset)
        .await
        .context("cannot add the demo's chance baseline")?;
    Ok(report)
}

/// The account the demo's baseline row is filed under.
const DEMO_ACCOUNT: &str = "enact-hub demo";

/// Puts the chance baseline on the demo leaderboard (once per database), scored and stored as
/// any submission is, under an account whose only token is revoked at once: nobody can submit
/// as it.
async fn submit_chance_baseline(pool: &SqlitePool, dataset_name: &str) -> anyhow::Result<()> {
    use crate::store::submissions::{NewSubmission, SubmissionMetadata};
    use sha2::Digest;

    let mut tx = pool.begin().await?;
    let dataset = store::datasets::by_name(&mut tx, dataset_name)
        .await?
        .with_context(|| format!("no dataset named '{dataset_name}'"))?;
    // Once per database, even if an admin has since hidden or withdrawn the row.
    let already = store::submissions::has_submitted(
        &mut tx,
        dataset.id,
        DEMO_ACCOUNT,
        demo::CHANCE_BASELINE_MODEL,
    )
    .await?;
    if already {
        return Ok(());
    }
    let rows = store::items::scoring_items(&mut tx, dataset.id).await?;
    let body = demo::chance_baseline(
        rows.iter().map(|r| (r.item_id.as_str(), r.gt_answer.len())),
        demo::DEFAULT_SEED,
    );
    let item_rows: Vec<i64> = rows.iter().map(|r| r.row_id).collect();
    let targets = scoring::targets_from_stored(rows).map_err(anyhow::Error::msg)?;
    let scored = crate::core::submission::score_submission(&targets, &body)
        .map_err(|e| anyhow::anyhow!("the baseline does not score: {e}"))?;
    let account = store::accounts::ensure_account(&mut tx, DEMO_ACCOUNT, Role::Submitter)
        .await?
        .map_err(anyhow::Error::msg)?;
    let token = NewToken::generate();
    let token_id =
        store::accounts::insert_token(&mut tx, account, Role::Submitter, &token, None, None)
            .await?;
    store::accounts::revoke_token(&mut tx, &token_id.to_string()).await?;
    let metadata = SubmissionMetadata {
        model: demo::CHANCE_BASELINE_MODEL.to_owned(),
        description: "Every item answered with a uniformly random ordering (seeded); what \
                      chance earns at each step length."
            .to_owned(),
        ..SubmissionMetadata::default()
    };
    let body_sha256 = hex::encode(sha2::Sha256::digest(body.as_bytes()));
    let scores_json = serde_json::to_string(&scored.scores)?;
    let id = store::submissions::insert(
        &mut tx,
        &NewSubmission {
            dataset: dataset.id,
            account,
            token: token_id,
            idempotency_key: None,
            body_sha256: &body_sha256,
            metadata: &metadata,
            scores_json: &scores_json,
        },
    )
    .await?
    .context("the baseline's submission row was not written")?;
    store::submissions::insert_items(&mut tx, id, &item_rows, &scored.items).await?;
    store::submissions::update_listing(&mut tx, id, Some(true), None).await?;
    tx.commit().await?;
    Ok(())
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
        let rows = stored_scoring_items(db, dataset).await?;
        let targets = scoring::targets_from_stored(rows).map_err(anyhow::Error::msg)?;
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
    let location = crate::app::import::ReleaseLocation::resolve(data)?;
    let text = std::fs::read_to_string(&location.qa_file)
        .with_context(|| format!("cannot read {}", location.qa_file.display()))?;
    let file = location.qa_file.display().to_string();
    let mut items = Vec::new();
    let mut problems = Vec::new();
    for (index, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        match crate::core::dataset::parse_release_line(line) {
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
    let refs: Vec<&crate::core::dataset::QaItem> = items.iter().map(|(_, i)| i).collect();
    let semantics = crate::core::semantics::for_items(scene_graphs, &refs);
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
        crate::core::verifier::enact_model_name(
            &args
                .predictions
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
        )
    });

    match args.policy {
        PolicyArg::Enact => {
            let source: Box<dyn crate::core::verifier::EnactSignatureSource + Send> = match (
                &args.scene_graphs,
                &args.db,
                &args.dataset,
            ) {
                (Some(replayed), _, _) => {
                    let replayed = replayed.clone();
                    let text = text.clone();
                    Box::new(
                        tokio::task::spawn_blocking(move || {
                            scoring::SceneGraphSignatures::for_predictions(
                                &replayed,
                                crate::core::verifier::python_text_lines(&text).map(|(_, l)| l),
                            )
                        })
                        .await
                        .context("loading scene graphs failed")??,
                    )
                }
                (None, Some(db), Some(dataset)) => Box::new(stored_signatures(db, dataset).await?),
                _ => anyhow::bail!(
                    "the enact policy scores as ENACT's evaluator does, which needs scene \
                         graphs: give --scene-graphs REPLAYED_DIR, or a --db dataset imported with them"
                ),
            };
            let evaluation = tokio::task::spawn_blocking(move || {
                let lines: Vec<(usize, &str)> =
                    crate::core::verifier::python_text_lines(&text).collect();
                crate::core::verifier::score_enact_predictions(lines, &model, source.as_ref())
            })
            .await
            .context("scoring task failed")?;
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
                let items: Vec<crate::core::verifier::StrictItem<'_>> =
                    targets.iter().map(ScoringTarget::strict_item).collect();
                let scoring = crate::core::verifier::score_strict_predictions(
                    &items,
                    crate::core::verifier::python_text_lines(&text),
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
                let meta =
                    crate::core::verifier::enact_meta_performance_json(&model, &scoring.report);
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
    let token = crate::core::annotation::new_token();
    let mut conn = pool.acquire().await?;
    let created = store::annotations::create_annotator(
        &mut conn,
        &args.name,
        args.admin,
        &crate::core::annotation::token_hash(&token),
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

impl AgreementArgs {
    fn stored(&self) -> stored::AgreementOptions {
        stored::AgreementOptions {
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
fn agreement(args: &AgreementArgs) -> anyhow::Result<ExitCode> {
    use crate::core::agreement::{
        BootstrapConfig, PreparedAlpha, UnitItems, read_reliability_json,
    };
    let (Some(input), Some(level)) = (&args.input, args.level) else {
        anyhow::bail!("--input and --level are both needed without --db");
    };
    let data = read_reliability_json(input)?;
    let prepared = PreparedAlpha::with_items(&data, level, &UnitItems::one_per_unit(data.units()))?;
    let estimate = prepared.estimate();
    let mut out = serde_json::json!({
        "input": input.display().to_string(),
        "level": level.to_string(),
        "alpha": estimate.alpha,
        "reason": estimate.reason.as_ref().map(ToString::to_string),
        "coders": estimate.coders,
        "units": estimate.units,
        "units_used": estimate.units_used,
        "pairable_values": estimate.pairable_values,
    });
    let replicates = args.bootstrap.unwrap_or(0);
    if replicates > 0 {
        let config = BootstrapConfig {
            replicates,
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

/// The scene-graph signatures stored for a dataset's items, for the enact policy.
async fn stored_signatures(db: &Path, dataset: &str) -> anyhow::Result<scoring::StoredSignatures> {
    let rows = stored_scoring_items(db, dataset).await?;
    let mut tables = Vec::new();
    for row in rows {
        let Some((source, json)) = row.semantics else {
            continue;
        };
        if source != crate::core::semantics::SignatureSource::SceneGraph.as_str() {
            continue;
        }
        let table = serde_json::from_str(&json)
            .with_context(|| format!("item {}: stored signatures are unreadable", row.item_id))?;
        tables.push((row.task_name, row.key_frame_ids, table));
    }
    Ok(scoring::StoredSignatures::new(tables))
}

/// `3..10`, `3..=10` or `3,5,7` into step lengths, each checked to lie in 3..10.
fn parse_steps(text: &str) -> anyhow::Result<Vec<usize>> {
    let number = |s: &str| -> anyhow::Result<usize> {
        let n: usize = s
            .trim()
            .parse()
            .with_context(|| format!("--steps: {s:?} is not a whole number"))?;
        anyhow::ensure!(
            (3..=10).contains(&n),
            "--steps: step length {n} is outside 3..10"
        );
        Ok(n)
    };
    let steps: Vec<usize> = match text.split_once("..") {
        Some((a, b)) => {
            let (a, b) = (number(a)?, number(b.trim_start_matches('='))?);
            anyhow::ensure!(a <= b, "--steps: empty range {text:?}");
            (a..=b).collect()
        }
        None => text.split(',').map(number).collect::<anyhow::Result<_>>()?,
    };
    Ok(steps)
}

async fn generate(args: GenerateArgs) -> anyhow::Result<ExitCode> {
    use crate::core::pipeline::{
        GenerateOptions, GenerateProgress, SegmentationParams, TypeNaming,
    };
    let mut segmentation = SegmentationParams::preset(&args.preset).with_context(|| {
        format!(
            "--preset: unknown preset {:?} (use enact-code or paper)",
            args.preset
        )
    })?;
    if let Some(v) = args.cosine_threshold {
        segmentation.cosine_threshold = v;
    }
    if let Some(v) = args.min_gap {
        segmentation.min_gap = v;
    }
    if let Some(v) = args.stability_frames {
        segmentation.stability_frames = v;
    }
    let options = GenerateOptions {
        seed: args.seed,
        num_to_sample: args.num_to_sample,
        step_lengths: parse_steps(&args.steps)?,
        segmentation,
        type_naming: if args.ordering_type_names {
            TypeNaming::Ordering
        } else {
            TypeNaming::Code
        },
    };
    let bar = if std::io::stderr().is_terminal() {
        indicatif::ProgressBar::new(0)
    } else {
        indicatif::ProgressBar::hidden()
    };
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{msg:>24} [{bar:40}] {pos}/{len} tasks")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    let (replayed, out) = (args.replayed.clone(), args.out.clone());
    let started = std::time::Instant::now();
    let summary = tokio::task::spawn_blocking(move || {
        crate::core::pipeline::generate(&replayed, &out, &options, &|event| match event {
            GenerateProgress::Started { tasks } => bar.set_length(tasks as u64 * 3),
            GenerateProgress::Segmented { task, .. }
            | GenerateProgress::TransitionsBuilt { task, .. }
            | GenerateProgress::ImagesWritten { task, .. } => {
                bar.set_message(task);
                bar.inc(1);
            }
            GenerateProgress::Finished { .. } => bar.finish_and_clear(),
        })
    })
    .await
    .context("generation task failed")??;
    eprintln!(
        "generated {} items ({} forward, {} inverse) and {} images from {} tasks into {} in {:.1} s",
        summary.items,
        summary.forward_items,
        summary.inverse_items,
        summary.images,
        summary.tasks.len(),
        args.out.display(),
        started.elapsed().as_secs_f64()
    );
    eprintln!(
        "import it with: enact-hub import {} --scene-graphs {}",
        args.out.display(),
        args.out.join("replayed_activities").display()
    );
    Ok(ExitCode::SUCCESS)
}

/// Every item of a stored dataset with what scoring needs (ground truth, signatures).
async fn stored_scoring_items(
    db: &Path,
    dataset: &str,
) -> anyhow::Result<Vec<store::items::ScoringItem>> {
    let pool = open_db(db).await?;
    let mut conn = pool.acquire().await?;
    let stored = store::datasets::by_name(&mut conn, dataset)
        .await?
        .with_context(|| format!("no dataset named '{dataset}' in {}", db.display()))?;
    let rows = store::items::scoring_items(&mut conn, stored.id).await?;
    drop(conn);
    pool.close().await;
    Ok(rows)
}
