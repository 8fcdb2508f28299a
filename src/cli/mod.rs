//! The `enact-hub` command line: argument parsing and the commands' terminal output.

use std::io::IsTerminal;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;
use clap::{Args, Parser, Subcommand};

use crate::app::cache::CacheLimits;
use crate::app::import::{
    ImportError, ImportOptions, ReleaseLocation, SkippedLine, import_release,
};
use crate::app::{self, AppError, Hub, Quotas};
use crate::core::audit::Actor;
use crate::core::credentials::Role;
use crate::core::scoring::{self, ScoringTarget, SemanticCoverage};
use crate::web::{Server, WebConfig, shutdown_signal};

/// Bytes in a mebibyte.
const MIB: u64 = 1024 * 1024;

mod audit;
mod frames;
mod simulate;
mod stored;
mod study;

#[derive(Parser)]
#[command(
    name = "enact-hub",
    version = crate::core::version::VERSION_LINE,
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
    /// The paper's error analysis of a prediction file: structural and semantic error classes,
    /// left/right hand precision, recall and mixing, and accepted-but-incomplete answers.
    Errors(ErrorsArgs),
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
    /// Write a consistent snapshot of the database (SQLite or PostgreSQL) into a SQLite file
    /// while the server runs.
    Backup(BackupArgs),
    /// Put a snapshot in place as the database (the server must be stopped), or copy it into
    /// an empty PostgreSQL database.
    Restore(RestoreArgs),
    /// The audit log: who issued and revoked tokens, submitted, changed visibility, imported,
    /// assigned, ran the protocol or finished annotations, and when.
    Audit(audit::AuditArgs),
    /// Ablation studies: a baseline dataset and variant datasets that ask its questions with
    /// other images; create, list, show, delete, and report a model's Δ and p per variant.
    #[command(subcommand)]
    Study(study::StudyCommand),
    /// Manage API tokens: create, list, revoke.
    #[command(subcommand)]
    Token(TokenCommand),
    /// Human annotator accounts.
    #[command(subcommand)]
    Annotator(AnnotatorCommand),
    /// Where frame images are kept: status, and moving them to or from object storage.
    #[command(subcommand)]
    Frames(frames::FramesCommand),
    /// Copy a whole database into a new, empty one on the other backend: a SQLite file into
    /// PostgreSQL (or back). Stop the servers first; the source's rows are left as they were.
    MigrateDb(MigrateDbArgs),
}

#[derive(Args)]
struct MigrateDbArgs {
    /// The database to copy: a SQLite file or a PostgreSQL URL.
    #[arg(long, value_name = "DB")]
    from: PathBuf,
    /// The database to copy into (created and migrated if it is a SQLite file; a PostgreSQL
    /// database must exist): it must hold nothing yet.
    #[arg(long, value_name = "DB")]
    to: PathBuf,
    /// Print the report as JSON on standard output.
    #[arg(long)]
    json: bool,
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
    /// A variant of this release: its items unchanged (ids, questions, answers, key frames),
    /// each image drawn from the replay's frame instead. No segmentation or sampling is done.
    #[arg(
        long,
        value_name = "BASELINE_DATA_DIR",
        conflicts_with_all = [
            "seed", "num_to_sample", "steps", "preset", "cosine_threshold", "min_gap",
            "stability_frames", "ordering_type_names",
        ]
    )]
    items_from: Option<PathBuf>,
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
        role: RoleArg,
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
enum RoleArg {
    Submitter,
    Admin,
}

impl From<RoleArg> for Role {
    fn from(role: RoleArg) -> Role {
        match role {
            RoleArg::Submitter => Role::Submitter,
            RoleArg::Admin => Role::Admin,
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum PolicyArg {
    /// ENACT's evaluator, quirks included: unparseable answers and duplicate ids are skipped.
    Enact,
    /// Every dataset item counts; a missing or unparseable answer scores TA 0 and PA 0.
    Strict,
}

/// The items a prediction file is read against: a stored dataset or a release folder.
#[derive(Args)]
struct AgainstArgs {
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
struct ScoreArgs {
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
struct ErrorsArgs {
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

#[derive(Args)]
struct BackupArgs {
    #[command(flatten)]
    db: DbArg,
    /// The snapshot file to write; it must not exist.
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
}

#[derive(Args)]
struct RestoreArgs {
    /// The snapshot to restore (written by `enact-hub backup`).
    #[arg(long, value_name = "FILE")]
    from: PathBuf,
    #[command(flatten)]
    db: DbArg,
    /// Move an existing database aside (to `{db}.before-restore`) instead of refusing.
    #[arg(long)]
    replace: bool,
}

#[derive(Args)]
struct DbArg {
    /// SQLite database file (created if missing), or a PostgreSQL URL
    /// (postgres://user:password@host/db; also ENACT_HUB_DATABASE_URL).
    #[arg(long, visible_alias = "database-url", env = "ENACT_HUB_DB", default_value = DEFAULT_DB)]
    db: PathBuf,
}

#[derive(Args)]
struct ServeArgs {
    /// SQLite database file (created if missing), or a PostgreSQL URL
    /// (postgres://user:password@host/db; also ENACT_HUB_DATABASE_URL). With --demo and no
    /// --db, a temporary SQLite database is used and removed at exit.
    #[arg(long, visible_alias = "database-url", env = "ENACT_HUB_DB")]
    db: Option<PathBuf>,
    /// Address to listen on.
    #[arg(long, env = "ENACT_HUB_ADDR", default_value = "127.0.0.1:8080")]
    addr: SocketAddr,
    #[command(flatten)]
    frames: frames::FramesArg,
    /// Answer requests for frames held in an object store that signs URLs (S3, GCS, Azure)
    /// with a redirect to a URL valid this many seconds, instead of the bytes.
    #[arg(long, value_name = "SECONDS")]
    frame_redirect: Option<u64>,
    /// Reverse proxies (addresses or networks, e.g. 10.0.0.0/8) whose X-Forwarded-For header
    /// names the client, for the login rate limit; repeat or separate with commas. Without
    /// one, every client behind a proxy counts as the proxy.
    #[arg(
        long = "trusted-proxy",
        env = "ENACT_HUB_TRUSTED_PROXIES",
        value_delimiter = ',',
        value_name = "ADDRESS[/BITS]"
    )]
    trusted_proxies: Vec<crate::web::forwarded::TrustedProxy>,
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
    #[arg(long, default_value_t = CacheLimits::default().frame_bytes / MIB)]
    frame_cache_mib: u64,
    /// Memory for caching items (their JSON and decoded form), in MiB.
    #[arg(long, default_value_t = CacheLimits::default().item_bytes / MIB)]
    item_cache_mib: u64,
    /// Annotators' item standings kept in memory, in entries.
    #[arg(long, default_value_t = CacheLimits::default().standing_entries)]
    standing_cache_entries: u64,
    /// Datasets whose scoring targets (every item's signatures) are kept in memory.
    #[arg(long, default_value_t = CacheLimits::default().target_datasets)]
    target_cache_datasets: u64,
    /// Datasets whose leaderboard is kept built in memory.
    #[arg(long, default_value_t = CacheLimits::default().board_datasets)]
    board_cache_datasets: u64,
    /// SQLite's page cache over all connections, in MiB.
    #[arg(long, default_value_t = CacheLimits::default().db_page_cache_bytes / MIB)]
    db_cache_mib: u64,
    /// Largest submission body accepted, in bytes.
    #[arg(long, default_value_t = WebConfig::default().submission_body_limit)]
    submission_body_limit: usize,
    /// Submissions a token may make per UTC day (rejected ones count too).
    #[arg(long, default_value_t = Quotas::default().daily)]
    daily_quota: i64,
    /// Submissions a token may make in total (rejected ones count too).
    #[arg(long, default_value_t = Quotas::default().total)]
    total_quota: i64,
}

#[derive(Args)]
struct ImportArgs {
    /// Release folder holding QA/enact_ordering.jsonl, or a path to a .jsonl file in its QA/ folder.
    data: PathBuf,
    #[command(flatten)]
    db: DbArg,
    #[command(flatten)]
    frames: frames::FramesArg,
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
    /// {task}/scene_graph_0.json for semantic scoring. Default: the release's own
    /// replayed_activities/ beside QA/, when there is one.
    #[arg(long, value_name = "REPLAYED_DIR")]
    scene_graphs: Option<PathBuf>,
    /// Do not read the release's replayed_activities/ even if it has one.
    #[arg(long, conflicts_with = "scene_graphs")]
    no_scene_graphs: bool,
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
/// Who runs a command, for the audit log: `$ENACT_HUB_OPERATOR`, else the login name.
pub(crate) fn operator() -> Actor {
    let name = ["ENACT_HUB_OPERATOR", "USER", "LOGNAME"]
        .iter()
        .filter_map(|var| std::env::var(var).ok())
        .find(|name| !name.trim().is_empty())
        .unwrap_or_else(|| "operator".to_owned());
    Actor::Operator(name.trim().to_owned())
}

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
            Command::Errors(args) => errors(args).await,
            Command::Agreement(args) => match (&args.db, &args.dataset) {
                (Some(db), Some(dataset)) => stored::agreement(db, dataset, args.stored()).await,
                _ => agreement(&args),
            },
            Command::AgreementProtocol(args) => stored::agreement_protocol(&args).await,
            Command::Report(args) => stored::report(&args).await,
            Command::Generate(args) => generate(args).await,
            Command::Simulate(args) => simulate::run(args),
            Command::Backup(args) => backup(args).await,
            Command::Restore(args) => restore(args).await,
            Command::Audit(args) => audit::audit(args).await,
            Command::Study(command) => study::study(command).await,
            Command::Token(command) => token(command).await,
            Command::Annotator(AnnotatorCommand::Create(args)) => create_annotator(args).await,
            Command::Frames(command) => frames::frames(command).await,
            Command::MigrateDb(args) => migrate_db(args).await,
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

/// The database file commands use when none is named.
pub(crate) const DEFAULT_DB: &str = "enact-hub.db";

/// The database a command names: `--db` (or `--database-url`), else `ENACT_HUB_DB`, else
/// `ENACT_HUB_DATABASE_URL`, else [`DEFAULT_DB`].
fn resolve(db: &Path) -> PathBuf {
    if db == Path::new(DEFAULT_DB)
        && std::env::var_os("ENACT_HUB_DB").is_none()
        && let Some(url) = std::env::var_os("ENACT_HUB_DATABASE_URL")
    {
        return PathBuf::from(url);
    }
    db.to_path_buf()
}

/// Whether `db` names a SQLite file that is not there (a command that only reads refuses it
/// rather than create an empty database).
fn is_missing_file(db: &Path) -> bool {
    let db = resolve(db);
    app::store_location(&db).is_file() && !db.exists()
}

/// The database for messages and logs (a URL's password hidden).
fn describe_db(db: &Path) -> String {
    app::describe_location(db)
}

/// Opens the database a command works on.
async fn open(db: &Path) -> anyhow::Result<Hub> {
    Hub::open(&resolve(db)).await
}

/// Prints a use case's refusal as the command's error and fails.
fn refused(e: AppError) -> anyhow::Result<ExitCode> {
    match e {
        AppError::Internal(e) => Err(e),
        other => {
            eprintln!("error: {other}");
            Ok(ExitCode::FAILURE)
        }
    }
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
        (None, false) => resolve(Path::new(DEFAULT_DB)),
    };
    let limits = CacheLimits {
        item_bytes: args.item_cache_mib * MIB,
        standing_entries: args.standing_cache_entries,
        target_datasets: args.target_cache_datasets,
        board_datasets: args.board_cache_datasets,
        frame_bytes: args.frame_cache_mib * MIB,
        db_page_cache_bytes: args.db_cache_mib * MIB,
    };
    let frame_store = args.frames.store()?;
    let hub = Hub::open_serving(&db, &limits)
        .await?
        .with_quotas(Quotas {
            daily: args.daily_quota,
            total: args.total_quota,
        })
        .with_frame_store(frame_store, args.frame_redirect.map(Duration::from_secs));
    if args.demo {
        app::demo::load(&hub).await?;
    }
    ensure_admin_token(&hub).await?;
    let config = WebConfig {
        body_limit: args.body_limit,
        request_timeout: Duration::from_secs(args.request_timeout),
        submission_body_limit: args.submission_body_limit,
        trusted_proxies: args.trusted_proxies.clone(),
    };
    let server = Server::bind(args.addr, hub.clone(), &config)
        .await
        .with_context(|| format!("cannot listen on {}", args.addr))?;
    let addr = server.local_addr()?;
    tracing::info!(
        %addr,
        db = %describe_db(&db),
        frames = hub.frame_store().describe(),
        "enact-hub is listening on http://{addr}/"
    );
    if args.demo {
        let link = app::demo::annotator_link(&hub)
            .await
            .map_err(anyhow::Error::from)?;
        eprintln!("enact-hub is serving the demo on http://{addr}/");
        eprintln!("annotate at once (a single-use login link for the demo admin):");
        println!("http://{addr}/login/link/{link}");
        if args.db.is_none() {
            eprintln!("(the demo database is temporary; give --db FILE to keep it)");
        }
    }
    server.run(shutdown_signal()).await?;
    hub.close().await;
    Ok(ExitCode::SUCCESS)
}

async fn migrate_db(args: MigrateDbArgs) -> anyhow::Result<ExitCode> {
    if is_missing_file(&args.from) {
        anyhow::bail!("{} does not exist: nothing to copy", args.from.display());
    }
    if resolve(&args.from) == resolve(&args.to) {
        anyhow::bail!("--from and --to name the same database");
    }
    let from = open(&args.from).await?;
    let to = open(&args.to).await?;
    let result = app::migrate_db::migrate_db(&from, &to, |table, rows| {
        eprintln!("{table}: {rows} rows");
    })
    .await;
    from.close().await;
    to.truncate_log().await;
    to.close().await;
    match result {
        Ok(report) => {
            if args.json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            }
            let rows: u64 = report.tables.iter().map(|(_, n)| n).sum();
            eprintln!(
                "copied {rows} rows of {} tables from {} to {} in {:.1} s",
                report.tables.len(),
                describe_db(&resolve(&args.from)),
                describe_db(&resolve(&args.to)),
                report.seconds
            );
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => refused(e),
    }
}

/// The admin token: ENACT_HUB_ADMIN_TOKEN if set (stored hashed on first sight), otherwise one
/// generated at the first start and printed once on standard output.
async fn ensure_admin_token(hub: &Hub) -> anyhow::Result<()> {
    let operator = std::env::var("ENACT_HUB_ADMIN_TOKEN")
        .ok()
        .filter(|t| !t.is_empty());
    match app::tokens::ensure_admin_token(hub, operator.as_deref()).await? {
        app::tokens::AdminToken::Present => {}
        app::tokens::AdminToken::StoredFromOperator(prefix) => {
            tracing::info!(%prefix, "admin token from ENACT_HUB_ADMIN_TOKEN stored");
        }
        app::tokens::AdminToken::Generated(token) => {
            eprintln!(
                "created the admin API token (shown only this once; set ENACT_HUB_ADMIN_TOKEN to \
                 choose your own):"
            );
            println!("{token}");
        }
    }
    Ok(())
}

fn print_snapshot(what: &str, s: &app::backup::Snapshot) {
    println!(
        "{what} {} ({} bytes: {} items, {} submissions, {} annotations; integrity ok)",
        s.path.display(),
        s.bytes,
        s.items,
        s.submissions,
        s.annotations
    );
}

async fn backup(args: BackupArgs) -> anyhow::Result<ExitCode> {
    if is_missing_file(&args.db.db) {
        anyhow::bail!(
            "{} does not exist: nothing to back up",
            args.db.db.display()
        );
    }
    let hub = open(&args.db.db).await?;
    let done = app::backup::backup(&hub, &operator(), &args.out).await;
    hub.close().await;
    match done {
        Ok(snapshot) => {
            print_snapshot("wrote", &snapshot);
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => refused(e),
    }
}

async fn restore(args: RestoreArgs) -> anyhow::Result<ExitCode> {
    let target = resolve(&args.db.db);
    match app::backup::restore(&args.from, &target, args.replace).await {
        Ok(snapshot) => {
            print_snapshot("restored", &snapshot);
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => refused(e),
    }
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
            let quotas = (daily_quota.map(i64::from), total_quota.map(i64::from));
            create_token(&db.db, &name, role.into(), quotas).await
        }
        TokenCommand::List { db } => list_tokens(&db.db).await,
        TokenCommand::Revoke { db, token } => revoke_token(&db.db, &token).await,
    }
}

/// `token create`: the secret alone on the last line.
async fn create_token(
    db: &Path,
    name: &str,
    role: Role,
    (daily_quota, total_quota): (Option<i64>, Option<i64>),
) -> anyhow::Result<ExitCode> {
    let hub = open(db).await?;
    let created = app::tokens::issue(&hub, &operator(), name, role, daily_quota, total_quota).await;
    hub.close().await;
    let created = match created {
        Ok(c) => c,
        Err(e) => return refused(e),
    };
    println!(
        "created token {} (prefix {}) for {} account '{}'; it is shown only once:",
        created.id, created.prefix, created.role, created.account
    );
    println!("{}", created.token);
    Ok(ExitCode::SUCCESS)
}

/// `token list`: one line per token, never a secret.
async fn list_tokens(db: &Path) -> anyhow::Result<ExitCode> {
    let hub = open(db).await?;
    let tokens = app::tokens::list(&hub).await;
    hub.close().await;
    println!(
        "{:>4}  {:<14} {:<20} {:<9} {:<20} {:<21} status",
        "id", "prefix", "account", "role", "quota (day/total)", "created"
    );
    for t in tokens? {
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
            t.id,
            t.prefix,
            t.account,
            t.role.as_str(),
            quota,
            t.created_at
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// `token revoke`: by id or prefix, effective at once.
async fn revoke_token(db: &Path, token: &str) -> anyhow::Result<ExitCode> {
    let hub = open(db).await?;
    let revoked = app::tokens::revoke(&hub, &operator(), token).await;
    hub.close().await;
    match revoked {
        Ok(()) => {
            println!("revoked token {token}");
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => refused(e),
    }
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
    let scene_graphs = match (&args.scene_graphs, args.no_scene_graphs) {
        (Some(dir), _) => Some(dir.clone()),
        (None, true) => None,
        // ENACT's download layout: QA/ beside replayed_activities/ (and segmented_activities/).
        (None, false) => ReleaseLocation::resolve(&args.data)
            .ok()
            .map(|location| location.root.join("replayed_activities"))
            .filter(|dir| dir.is_dir())
            .inspect(|dir| {
                eprintln!(
                    "scene graphs: {} (the release's own; --scene-graphs DIR overrides, \
                     --no-scene-graphs skips)",
                    dir.display()
                );
            }),
    };
    let hub = open(&args.db.db)
        .await?
        .with_frame_store(args.frames.store()?, None);
    let options = ImportOptions {
        dataset,
        skip_invalid: args.skip_invalid,
        replace: args.replace,
        progress: std::io::stderr().is_terminal(),
        scene_graphs,
    };
    let result = import_release(&hub, &operator(), &args.data, &options).await;
    if result.as_ref().is_ok_and(|r| r.new_frames > 0) {
        hub.truncate_log().await;
    }
    hub.close().await;
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
    targets_of(&args.against).await
}

/// The items a prediction file is scored or analysed against: a stored dataset, or a release
/// folder with its signatures computed now (from scene graphs when given).
async fn targets_of(
    against: &AgainstArgs,
) -> anyhow::Result<Result<Vec<ScoringTarget>, Vec<String>>> {
    if let (Some(db), Some(dataset)) = (&against.db, &against.dataset) {
        if against.scene_graphs.is_some() {
            anyhow::bail!(
                "--scene-graphs goes with --data; a stored dataset keeps the signatures computed \
                 at import (enact-hub import DATA_DIR --scene-graphs REPLAYED_DIR)"
            );
        }
        let hub = open(db).await?;
        let targets = app::scoring::stored_targets(&hub, dataset).await;
        hub.close().await;
        return Ok(Ok(in_database(targets, db)?));
    }
    let data = against
        .data
        .clone()
        .context("give --data DATA_DIR, or --db PATH --dataset NAME")?;
    let scene_graphs = against.scene_graphs.clone();
    let spinner = spinner(if scene_graphs.is_some() {
        "reading the release and its scene graphs"
    } else {
        "reading the release"
    });
    let targets = tokio::task::spawn_blocking(move || {
        app::scoring::release_targets(&data, scene_graphs.as_deref())
    })
    .await
    .context("reading the release failed")?;
    spinner.finish_and_clear();
    targets
}

/// A spinner on standard error for a step that may take a while (hidden when not a terminal).
fn spinner(message: &'static str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new_spinner().with_message(message);
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}

/// Prints an analysis as the table, or as JSON.
fn print_analysis(
    analysis: &crate::core::error_analysis::ErrorAnalysis,
    json: bool,
) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(analysis)?);
    } else {
        print!(
            "{}",
            crate::core::error_analysis::present::text_table(analysis)
        );
    }
    Ok(())
}

async fn errors(args: ErrorsArgs) -> anyhow::Result<ExitCode> {
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
    let targets = match targets_of(&args.against).await? {
        Ok(t) => t,
        Err(problems) => {
            for p in &problems {
                eprintln!("{p}");
            }
            eprintln!(
                "error: the dataset has {} problems; nothing was analysed",
                problems.len()
            );
            return Ok(ExitCode::FAILURE);
        }
    };
    let spinner = spinner("analysing answers");
    let analysis =
        tokio::task::spawn_blocking(move || app::error_analysis::analyse_file(&targets, &text))
            .await
            .context("the analysis failed")?
            .map_err(anyhow::Error::msg)?;
    spinner.finish_and_clear();
    let analysis = match analysis {
        Ok(a) => a,
        Err(problems) => {
            for p in &problems {
                eprintln!("{file}: {p}");
            }
            eprintln!(
                "error: {file}: {} problems; nothing was analysed",
                problems.len()
            );
            return Ok(ExitCode::FAILURE);
        }
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&analysis)?);
    } else {
        print!(
            "{}",
            crate::core::error_analysis::present::text_table(&analysis)
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// A use case's result on a database the user named: what was not found says where it looked.
fn in_database<T>(result: Result<T, AppError>, db: &Path) -> anyhow::Result<T> {
    result.map_err(|e| match e {
        AppError::Internal(e) => e,
        AppError::NotFound(what) => anyhow::anyhow!("{what} in {}", describe_db(db)),
        other => anyhow::anyhow!("{other}"),
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
        PolicyArg::Enact => score_enact(&args, &file, text, model).await,
        PolicyArg::Strict => score_strict(&args, &file, text, model).await,
    }
}

/// `score --policy enact`: ENACT's evaluator, quirks included, with its skipped lines listed.
async fn score_enact(
    args: &ScoreArgs,
    file: &str,
    text: String,
    model: String,
) -> anyhow::Result<ExitCode> {
    let source: Box<dyn crate::core::verifier::EnactSignatureSource + Send> = match (
        &args.against.scene_graphs,
        &args.against.db,
        &args.against.dataset,
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
        (None, Some(db), Some(dataset)) => {
            let hub = open(db).await?;
            let signatures = app::scoring::stored_signatures(&hub, dataset).await;
            hub.close().await;
            Box::new(in_database(signatures, db)?)
        }
        _ => anyhow::bail!(
            "the enact policy scores as ENACT's evaluator does, which needs scene \
                 graphs: give --scene-graphs REPLAYED_DIR, or a --db dataset imported with them"
        ),
    };
    let evaluation = tokio::task::spawn_blocking(move || {
        let lines: Vec<(usize, &str)> = crate::core::verifier::python_text_lines(&text).collect();
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

/// `score --policy strict`: every dataset item counts; problems refuse the whole file.
async fn score_strict(
    args: &ScoreArgs,
    file: &str,
    text: String,
    model: String,
) -> anyhow::Result<ExitCode> {
    let targets = match scoring_targets(args).await? {
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
        let meta = crate::core::verifier::enact_meta_performance_json(&model, &scoring.report);
        write_enact_outputs(
            out,
            &model,
            &meta,
            &scoring::strict_detailed_jsonl(&targets, &scoring),
        )?;
    }
    Ok(ExitCode::SUCCESS)
}

async fn create_annotator(args: CreateAnnotatorArgs) -> anyhow::Result<ExitCode> {
    let hub = open(&args.db.db).await?;
    let created = app::annotators::create(&hub, &operator(), &args.name, args.admin).await;
    hub.close().await;
    let invited = match created {
        Ok(invited) => invited,
        Err(AppError::BadRequest(problem)) => {
            eprintln!("error: --name: {problem}");
            return Ok(ExitCode::FAILURE);
        }
        Err(AppError::Conflict(problem)) => {
            eprintln!("error: {problem} in {}", args.db.db.display());
            return Ok(ExitCode::FAILURE);
        }
        Err(e) => return refused(e),
    };
    let role = if invited.is_admin {
        "admin"
    } else {
        "annotator"
    };
    println!(
        "created {role} '{}'; send them this single-use link to set a password:",
        invited.name
    );
    println!(
        "{}",
        app::annotators::invite_url(&args.base_url, &invited.invite_token)
    );
    Ok(ExitCode::SUCCESS)
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

/// `generate --items-from`: the baseline's items with the replay's images.
async fn generate_variant(args: &GenerateArgs, baseline: PathBuf) -> anyhow::Result<ExitCode> {
    let (replayed, out) = (args.replayed.clone(), args.out.clone());
    let baseline_graphs = baseline.join("replayed_activities");
    let started = std::time::Instant::now();
    let done = tokio::task::spawn_blocking(move || {
        crate::core::pipeline::variant::items_from(&replayed, &baseline, &out)
    })
    .await
    .context("generation task failed")??;
    eprintln!(
        "wrote {} items of {} tasks with {} images from {} into {} in {:.1} s",
        done.items,
        done.tasks,
        done.images,
        args.replayed.display(),
        args.out.display(),
        started.elapsed().as_secs_f64()
    );
    // The baseline's scene graphs, so that answers are judged as on the baseline and only the
    // images differ (a replay's own graphs record what its camera sees).
    eprintln!(
        "import it with: enact-hub import {} --dataset NAME --scene-graphs {}",
        args.out.display(),
        baseline_graphs.display()
    );
    Ok(ExitCode::SUCCESS)
}

async fn generate(args: GenerateArgs) -> anyhow::Result<ExitCode> {
    if let Some(baseline) = args.items_from.clone() {
        return generate_variant(&args, baseline).await;
    }
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
    // Import finds the release's own replayed_activities/ by itself.
    eprintln!("import it with: enact-hub import {}", args.out.display());
    Ok(ExitCode::SUCCESS)
}
