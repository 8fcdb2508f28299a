//! The `enact-hub` command line: argument parsing and the commands' terminal output, one
//! file per command family. Each command parses its arguments, calls use cases in
//! [`crate::app`] and prints; the work itself is never done here (`tests/layers.rs` checks).
//! What several commands share lives in this file: which database a command names, who the
//! operator is, and how a use case's refusal is printed.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};

use crate::app::{self, AppError, Hub};
use crate::core::audit::Actor;

/// Bytes in a mebibyte.
const MIB: u64 = 1024 * 1024;

mod accounts;
mod agreement;
mod attention;
mod audit;
mod compare;
mod controls;
mod database;
mod dataset;
mod doctor;
mod episode;
mod frames;
mod generate;
mod gold;
mod import;
mod paper;
mod quality;
mod reported;
mod rescore;
mod run;
mod scoring;
mod serve;
mod simulate;
mod statements;
mod stored;
mod study;

#[derive(Parser)]
#[command(
    name = "enact-hub",
    version = crate::app::version::version_line(),
    about = "Self-hosted evaluation service for the ENACT benchmark"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the web service.
    Serve(serve::ServeArgs),
    /// Import an ENACT release (QA/enact_ordering.jsonl + images) into the database.
    Import(import::ImportArgs),
    /// Score a prediction file (ENACT model-output JSONL, or compact {"id", "answer"} lines).
    Score(scoring::ScoreArgs),
    /// The paper's error analysis of a prediction file: structural and semantic error classes,
    /// left/right hand precision, recall and mixing, and accepted-but-incomplete answers.
    Errors(scoring::ErrorsArgs),
    /// Krippendorff's alpha of reliability data, with an optional bootstrap interval.
    Agreement(agreement::AgreementArgs),
    /// The paper's cross-annotation protocol on a stored dataset: draw k completed primary items
    /// per annotator × direction × step length and assign each to the other annotators.
    AgreementProtocol(stored::ProtocolArgs),
    /// Write a stored dataset's agreement report (JSON, CSV, Markdown, LaTeX, SVG) to a folder.
    Report(stored::ReportArgs),
    /// Run ENACT's data pipeline on BEHAVIOR-format replays: key-frame segmentation, then
    /// forward and inverse QA items in the ENACT release layout.
    Generate(generate::GenerateArgs),
    /// Simulate household activities in the built-in synthetic world and write them as
    /// BEHAVIOR-format replays that `generate` reads.
    Simulate(simulate::SimulateArgs),
    /// Write a consistent snapshot of the database (SQLite or PostgreSQL) into a SQLite file
    /// while the server runs.
    Backup(database::BackupArgs),
    /// Put a snapshot in place as the database (the server must be stopped), or copy it into
    /// an empty PostgreSQL database.
    Restore(database::RestoreArgs),
    /// The audit log: who issued and revoked tokens, submitted, changed visibility, imported,
    /// assigned, ran the protocol or finished annotations, and when.
    Audit(audit::AuditArgs),
    /// Stored datasets: a stratified subset of one as a dataset of its own.
    #[command(subcommand)]
    Dataset(dataset::DatasetCommand),
    /// Ablation studies: a baseline dataset and variant datasets that ask its questions with
    /// other images; create, list, show, delete, and report a model's Δ and p per variant.
    #[command(subcommand)]
    Study(study::StudyCommand),
    /// ENACT's result tables from a dataset's rows beside the results papers published, marked
    /// as the paper marks them, with where each cell came from (.tex, .csv, .md, .json).
    Paper(paper::PaperArgs),
    /// Two leaderboard rows of a dataset compared item by item: each side's task and pairwise
    /// accuracy per direction and step length, the difference with a paired bootstrap interval
    /// (resampling activities), McNemar's exact test, and the items only one gets right.
    Compare(compare::CompareArgs),
    /// Ask an OpenAI-compatible model every item of a dataset (resumable: each reply is kept
    /// as it arrives) and submit its answers.
    Run(Box<run::RunArgs>),
    /// Manage API tokens: create, list, revoke.
    #[command(subcommand)]
    Token(accounts::TokenCommand),
    /// Human annotator accounts.
    #[command(subcommand)]
    Annotator(accounts::AnnotatorCommand),
    /// Where frame images are kept: status, and moving them to or from object storage.
    #[command(subcommand)]
    Frames(frames::FramesCommand),
    /// Copy a whole database into a new, empty one on the other backend: a SQLite file into
    /// PostgreSQL (or back). Stop the servers first; the source's rows are left as they were.
    MigrateDb(database::MigrateDbArgs),
    /// Compute stored submissions' scores and human answers' verdicts again under the current
    /// metric version (those already current are skipped, so a stopped run resumes).
    Rescore(rescore::RescoreArgs),
    /// Gold items: a share (or a list) of a dataset's items with a known answer, mixed into
    /// every annotator's queue to check their work.
    #[command(subcommand)]
    Gold(gold::GoldCommand),
    /// Attention checks: items whose question tells the annotator how to order the cards,
    /// mixed into every annotator's queue to check that they read it.
    #[command(subcommand)]
    Attention(attention::AttentionCommand),
    /// Results papers published (the ENACT paper's own, or another paper's tables), attached
    /// to a dataset and shown on its leaderboard as reported rows, never ranked.
    #[command(subcommand)]
    Reported(reported::ReportedCommand),
    /// A checkup of the database for its operator: schema against this build, unfinished and
    /// stale imports, stuck or failed jobs, the write-ahead log's size, optionally integrity.
    /// Exits 1 when something needs action.
    Doctor(doctor::DoctorArgs),
    /// Real-world episodes: import recorded frames, set each curator's key frames and scene
    /// graphs, compare two curators, choose the graphs to export, export for `generate`.
    #[command(subcommand)]
    Episode(episode::EpisodeCommand),
    /// The keys the hub signs each scored submission's statement with: list the public keys,
    /// or rotate to a new key (old statements keep verifying).
    #[command(subcommand)]
    Keys(statements::KeysCommand),
    /// Check a submission's signed statement offline: its signature against the hub's public
    /// keys and, with --answers, that a file is the answers it was made for. Exits 1 with the
    /// reason when it does not hold.
    Verify(statements::VerifyArgs),
}

#[derive(Args)]
pub(crate) struct DbArg {
    /// SQLite database file (created if missing), or a PostgreSQL URL
    /// (postgres://user:password@host/db; also ENACT_HUB_DATABASE_URL).
    #[arg(long, visible_alias = "database-url", env = "ENACT_HUB_DB", default_value = DEFAULT_DB)]
    db: PathBuf,
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

/// Who runs a command, for the audit log: `$ENACT_HUB_OPERATOR`, else the login name.
pub(crate) fn operator() -> Actor {
    let name = ["ENACT_HUB_OPERATOR", "USER", "LOGNAME"]
        .iter()
        .filter_map(|var| std::env::var(var).ok())
        .find(|name| !name.trim().is_empty())
        .unwrap_or_else(|| "operator".to_owned());
    Actor::Operator(name.trim().to_owned())
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
            Command::Serve(args) => serve::serve(args).await,
            Command::Import(args) => import::import(args).await,
            Command::Score(args) => scoring::score(args).await,
            Command::Errors(args) => scoring::errors(args).await,
            Command::Agreement(args) => agreement::agreement(args).await,
            Command::AgreementProtocol(args) => stored::agreement_protocol(&args).await,
            Command::Report(args) => stored::report(&args).await,
            Command::Generate(args) => generate::generate(args).await,
            Command::Simulate(args) => simulate::run(args),
            Command::Backup(args) => database::backup(args).await,
            Command::Restore(args) => database::restore(args).await,
            Command::Audit(args) => audit::audit(args).await,
            Command::Dataset(command) => dataset::dataset(command).await,
            Command::Study(command) => study::study(command).await,
            Command::Paper(args) => paper::paper(args).await,
            Command::Compare(args) => compare::compare(args).await,
            Command::Run(args) => run::run(*args).await,
            Command::Token(command) => accounts::token(command).await,
            Command::Annotator(command) => accounts::annotator(command).await,
            Command::Frames(command) => frames::frames(command).await,
            Command::MigrateDb(args) => database::migrate_db(args).await,
            Command::Rescore(args) => rescore::rescore(args).await,
            Command::Gold(command) => gold::gold(command).await,
            Command::Attention(command) => attention::attention(command).await,
            Command::Reported(command) => reported::reported(command).await,
            Command::Doctor(args) => doctor::doctor(args).await,
            Command::Episode(command) => episode::episode(command).await,
            Command::Keys(command) => statements::keys(command).await,
            Command::Verify(args) => statements::verify(args).await,
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
    open_signing(db, None).await
}

/// Opens the database; statements it makes are signed with the key in `key_file`, else the
/// file `ENACT_HUB_SIGNING_KEY` names, else the one beside a SQLite database, and name the hub
/// by `ENACT_HUB_PUBLIC_URL` (the variables `serve` also reads).
async fn open_signing(db: &Path, key_file: Option<PathBuf>) -> anyhow::Result<Hub> {
    let from_env = |name: &str| std::env::var(name).ok().filter(|v| !v.trim().is_empty());
    let key_file = key_file.or_else(|| from_env("ENACT_HUB_SIGNING_KEY").map(PathBuf::from));
    let hub = Hub::open(&resolve(db)).await?;
    Ok(app::signing::with_signing(
        hub,
        key_file,
        from_env("ENACT_HUB_PUBLIC_URL"),
    ))
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

/// A spinner on standard error for a step that may take a while (hidden when not a terminal).
fn spinner(message: &'static str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new_spinner().with_message(message);
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}

/// A use case's result on a database the user named: what was not found says where it looked.
fn in_database<T>(result: Result<T, AppError>, db: &Path) -> anyhow::Result<T> {
    result.map_err(|e| refusal_in(e, Some(db)))
}

/// A use case's refusal as the command's error; what was not found says in which database.
fn refusal_in(e: AppError, db: Option<&Path>) -> anyhow::Error {
    match (e, db) {
        (AppError::Internal(e), _) => e,
        (e, Some(db)) if e.is_not_found() => anyhow::anyhow!("{e} in {}", describe_db(db)),
        (other, _) => anyhow::anyhow!("{other}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_command_line_definition_is_consistent() {
        // clap's own checks: no clashing flags, every `requires`/`conflicts_with` names an
        // argument that exists, defaults parse.
        <Cli as clap::CommandFactory>::command().debug_assert();
    }

    #[test]
    fn a_use_case_refusal_names_the_database_it_looked_in() {
        let e = refusal_in(
            AppError::NotFound("dataset 'x' does not exist".into()),
            Some(Path::new("hub.db")),
        );
        assert_eq!(e.to_string(), "dataset 'x' does not exist in hub.db");
        let e = refusal_in(AppError::NotFound("no such thing".into()), None);
        assert_eq!(e.to_string(), "no such thing");
        // A typed reason is found missing in the same way.
        let e = refusal_in(
            crate::app::refusal::Refusal::NoStudy {
                study: "camera".into(),
            }
            .into(),
            Some(Path::new("hub.db")),
        );
        assert_eq!(e.to_string(), "no study named 'camera' in hub.db");
    }
}
