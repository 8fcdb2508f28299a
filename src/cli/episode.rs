//! `enact-hub episode import|list|graphs|resolve|compare|export`: real-world episodes, their
//! curators' key frames and scene graphs, and the export `generate` makes items from
//! ([`crate::app::episodes`]).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Subcommand};

use super::{DbArg, in_database, is_missing_file, open, operator};
use crate::app::episodes::Resolution;
use crate::app::refusal::Refusal;
use crate::app::{self, AppError};
use crate::core::episode::EpisodeGraphs;

#[derive(Subcommand)]
pub(super) enum EpisodeCommand {
    /// Import a folder of PNG or JPEG frames (ordered by file name, naturally) as an episode.
    Import(ImportArgs),
    /// List the episodes: frames, curators, whether the exported graphs are chosen.
    List(ListArgs),
    /// Write a curator's key frames and scene graphs to a file (--get) or replace them from
    /// one (--set); a graph with a problem is refused with its key frame and field named.
    Graphs(GraphsArgs),
    /// Choose the graphs an episode exports: one curator's, or a merged graphs file.
    Resolve(ResolveArgs),
    /// Where two curators' graphs differ, per key frame and transition, with their agreement.
    Compare(CompareArgs),
    /// Write the episode in ENACT's replay layout; `generate OUT/replayed_activities` then
    /// makes items keeping every key frame the curator marked.
    Export(ExportArgs),
}

#[derive(Args)]
pub(super) struct ImportArgs {
    /// The folder of frames.
    dir: PathBuf,
    #[command(flatten)]
    db: DbArg,
    /// The episode's name (letters, digits, '_' and '-'; it names the exported task).
    #[arg(long)]
    name: String,
    /// The scene it was recorded in ("kitchen").
    #[arg(long, default_value = "")]
    scene: String,
}

#[derive(Args)]
pub(super) struct ListArgs {
    #[command(flatten)]
    db: DbArg,
}

#[derive(Args)]
pub(super) struct GraphsArgs {
    /// The episode's name.
    name: String,
    #[command(flatten)]
    db: DbArg,
    /// Replace the curator's graphs with this graphs file.
    #[arg(
        long,
        value_name = "FILE",
        conflicts_with = "get",
        required_unless_present = "get"
    )]
    set: Option<PathBuf>,
    /// Write the curator's graphs to this file.
    #[arg(long, value_name = "FILE")]
    get: Option<PathBuf>,
    /// Whose graphs (default: the operator, $ENACT_HUB_OPERATOR or the login name).
    #[arg(long)]
    curator: Option<String>,
}

#[derive(Args)]
pub(super) struct ResolveArgs {
    /// The episode's name.
    name: String,
    #[command(flatten)]
    db: DbArg,
    /// Export this curator's graphs as they are.
    #[arg(long, conflicts_with = "set", required_unless_present = "set")]
    curator: Option<String>,
    /// Export this graphs file (a merge of the curators').
    #[arg(long, value_name = "FILE")]
    set: Option<PathBuf>,
}

#[derive(Args)]
pub(super) struct CompareArgs {
    /// The episode's name.
    name: String,
    #[command(flatten)]
    db: DbArg,
    /// The two curators, as A,B.
    #[arg(long, value_name = "A,B")]
    curators: String,
    /// Print the comparison as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
pub(super) struct ExportArgs {
    /// The episode's name.
    name: String,
    #[command(flatten)]
    db: DbArg,
    /// The folder to write (created if missing).
    #[arg(long)]
    out: PathBuf,
}

pub(super) async fn episode(command: EpisodeCommand) -> anyhow::Result<ExitCode> {
    match command {
        EpisodeCommand::Import(args) => import(args).await,
        EpisodeCommand::List(args) => list(args).await,
        EpisodeCommand::Graphs(args) => graphs(args).await,
        EpisodeCommand::Resolve(args) => resolve(args).await,
        EpisodeCommand::Compare(args) => compare(args).await,
        EpisodeCommand::Export(args) => export(args).await,
    }
}

/// Reads a graphs file, naming the file, line and column of a mistake.
fn read_graphs(path: &Path) -> Result<EpisodeGraphs, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

fn missing_db(db: &Path) -> Option<ExitCode> {
    is_missing_file(db).then(|| {
        eprintln!("error: no database at {}", db.display());
        ExitCode::FAILURE
    })
}

async fn import(args: ImportArgs) -> anyhow::Result<ExitCode> {
    let hub = open(&args.db.db).await?;
    let result = app::episodes::import(&hub, &operator(), &args.dir, &args.name, &args.scene).await;
    hub.close().await;
    let episode = in_database(result, &args.db.db)?;
    println!(
        "episode '{}': {} frames imported{}",
        episode.name,
        episode.frame_count,
        if episode.scene.is_empty() {
            String::new()
        } else {
            format!(" (scene {})", episode.scene)
        }
    );
    Ok(ExitCode::SUCCESS)
}

async fn list(args: ListArgs) -> anyhow::Result<ExitCode> {
    if let Some(code) = missing_db(&args.db.db) {
        return Ok(code);
    }
    let hub = open(&args.db.db).await?;
    let result = app::episodes::list(&hub).await;
    hub.close().await;
    let episodes = in_database(result, &args.db.db)?;
    if episodes.is_empty() {
        println!("no episode");
    }
    for e in episodes {
        println!(
            "{}\t{} frames\tscene {}\tcurators: {}\texport: {}",
            e.name,
            e.frame_count,
            if e.scene.is_empty() { "-" } else { &e.scene },
            if e.curators.is_empty() {
                "-".to_string()
            } else {
                e.curators.join(", ")
            },
            match &e.resolved_by {
                Some(by) => format!("resolved by {by}"),
                None => "not resolved".to_string(),
            }
        );
    }
    Ok(ExitCode::SUCCESS)
}

async fn graphs(args: GraphsArgs) -> anyhow::Result<ExitCode> {
    if let Some(code) = missing_db(&args.db.db) {
        return Ok(code);
    }
    let actor = operator();
    let curator = args
        .curator
        .clone()
        .unwrap_or_else(|| actor.name().to_owned());
    if let Some(path) = &args.set {
        let graphs = match read_graphs(path) {
            Ok(graphs) => graphs,
            Err(problem) => {
                eprintln!("error: {problem}");
                return Ok(ExitCode::FAILURE);
            }
        };
        let hub = open(&args.db.db).await?;
        let result = app::episodes::set_graphs(&hub, &actor, &args.name, &curator, &graphs).await;
        hub.close().await;
        in_database(result, &args.db.db)?;
        println!(
            "episode '{}': graphs of curator {curator} set ({} key frames)",
            args.name,
            graphs.key_frames.len()
        );
        return Ok(ExitCode::SUCCESS);
    }
    let Some(path) = &args.get else {
        eprintln!("error: give --set FILE or --get FILE");
        return Ok(ExitCode::FAILURE);
    };
    let hub = open(&args.db.db).await?;
    let result = app::episodes::graphs(&hub, &args.name, &curator).await;
    hub.close().await;
    let Some(graphs) = in_database(result, &args.db.db)? else {
        eprintln!(
            "error: curator {curator} has no graphs of episode '{}'",
            args.name
        );
        return Ok(ExitCode::FAILURE);
    };
    std::fs::write(path, serde_json::to_vec_pretty(&graphs)?)
        .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
    println!(
        "episode '{}': graphs of curator {curator} written to {}",
        args.name,
        path.display()
    );
    Ok(ExitCode::SUCCESS)
}

async fn resolve(args: ResolveArgs) -> anyhow::Result<ExitCode> {
    if let Some(code) = missing_db(&args.db.db) {
        return Ok(code);
    }
    let resolution = match (&args.curator, &args.set) {
        (Some(curator), _) => Resolution::Curator(curator.clone()),
        (None, Some(path)) => match read_graphs(path) {
            Ok(graphs) => Resolution::Graphs(graphs),
            Err(problem) => {
                eprintln!("error: {problem}");
                return Ok(ExitCode::FAILURE);
            }
        },
        (None, None) => {
            eprintln!("error: give --curator NAME or --set FILE");
            return Ok(ExitCode::FAILURE);
        }
    };
    let hub = open(&args.db.db).await?;
    let result = app::episodes::resolve(&hub, &operator(), &args.name, resolution).await;
    hub.close().await;
    in_database(result, &args.db.db)?;
    println!("episode '{}': the graphs to export are chosen", args.name);
    Ok(ExitCode::SUCCESS)
}

async fn compare(args: CompareArgs) -> anyhow::Result<ExitCode> {
    if let Some(code) = missing_db(&args.db.db) {
        return Ok(code);
    }
    let Some((a, b)) = args
        .curators
        .split_once(',')
        .map(|(a, b)| (a.trim(), b.trim()))
        .filter(|(a, b)| !a.is_empty() && !b.is_empty() && !b.contains(','))
    else {
        eprintln!(
            "error: --curators: expected two names as A,B, got {:?}",
            args.curators
        );
        return Ok(ExitCode::FAILURE);
    };
    let hub = open(&args.db.db).await?;
    let result = app::episodes::compare(&hub, &args.name, a, b).await;
    hub.close().await;
    let comparison = in_database(result, &args.db.db)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&comparison)?);
        return Ok(ExitCode::SUCCESS);
    }
    let side = |in_a: bool, in_b: bool| match (in_a, in_b) {
        (true, true) => "both",
        (true, false) => "A only",
        _ => "B only",
    };
    println!("key frames (A = {a}, B = {b}): frame, marked by, shared, A only, B only");
    for k in &comparison.key_frames {
        println!(
            "  {}\t{}\t{}\t{}\t{}",
            k.frame,
            side(k.in_a, k.in_b),
            k.components.shared,
            k.components.only_a,
            k.components.only_b
        );
        for c in &k.only_a {
            println!("      A only: {c}");
        }
        for c in &k.only_b {
            println!("      B only: {c}");
        }
    }
    println!("transitions: frames, described by, shared, A only, B only");
    for t in &comparison.transitions {
        println!(
            "  {} -> {}\t{}\t{}\t{}\t{}",
            t.from_frame,
            t.to_frame,
            side(t.in_a, t.in_b),
            t.components.shared,
            t.components.only_a,
            t.components.only_b
        );
    }
    match comparison.transition_agreement {
        Some(rate) => println!(
            "agreement on transition components: {:.3} ({} shared of {})",
            rate,
            comparison.transition_components.shared,
            comparison.transition_components.shared + comparison.transition_components.differing()
        ),
        None => println!("agreement on transition components: none shared to compare"),
    }
    match (
        comparison.transition_alpha.alpha,
        &comparison.transition_alpha.reason,
    ) {
        (Some(alpha), _) => println!("Krippendorff's alpha (nominal): {alpha:.3}"),
        (None, Some(reason)) => println!("Krippendorff's alpha: undefined: {reason}"),
        (None, None) => println!("Krippendorff's alpha: undefined"),
    }
    Ok(ExitCode::SUCCESS)
}

async fn export(args: ExportArgs) -> anyhow::Result<ExitCode> {
    if let Some(code) = missing_db(&args.db.db) {
        return Ok(code);
    }
    let hub = open(&args.db.db).await?;
    let result = app::episodes::export(&hub, &args.name, &args.out).await;
    hub.close().await;
    // What to run next, in this command line's own words.
    let hint = match &result {
        Err(AppError::Refused(Refusal::EpisodeNotResolved { .. })) => Some(format!(
            "choose with: enact-hub episode resolve {} --curator NAME (or --set FILE)",
            args.name
        )),
        Err(AppError::Refused(Refusal::EpisodeHasNoGraphs { .. })) => Some(format!(
            "set them with: enact-hub episode graphs {} --set FILE",
            args.name
        )),
        _ => None,
    };
    let report = match in_database(result, &args.db.db) {
        Ok(report) => report,
        Err(e) => match hint {
            Some(hint) => return Err(anyhow::anyhow!("{e}\n{hint}")),
            None => return Err(e),
        },
    };
    println!(
        "episode '{}': {} frames and {} key frames ({}) written; make items with: enact-hub \
         generate {} --out DIR",
        args.name,
        report.frames,
        report.key_frames.len(),
        report.key_frames.join(", "),
        report.replayed_dir.display()
    );
    Ok(ExitCode::SUCCESS)
}
