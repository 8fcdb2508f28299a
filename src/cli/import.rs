//! `import`: an ENACT release into the database, with a progress bar on a terminal.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;

use super::{DbArg, frames, open, operator};
use crate::app::import::{
    BATCH_LINES, ImportError, ImportObserver, ImportOptions, ImportProgress, ReleaseLocation,
    SkippedLine, abandon, default_dataset_name, import_release, stale,
};

#[derive(Args)]
pub(super) struct ImportArgs {
    /// Release folder holding QA/enact_ordering.jsonl, or a path to a .jsonl file in its QA/ folder.
    #[arg(required_unless_present_any = ["abandon", "stale"])]
    data: Option<PathBuf>,
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
    /// Lines validated and written per batch; each batch is one short transaction of its own.
    #[arg(long, default_value_t = BATCH_LINES as u32, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    batch_lines: u32,
    /// Discard the unfinished (killed) import into DATASET instead of importing; the dataset
    /// itself is untouched.
    #[arg(long, value_name = "DATASET", conflicts_with_all = ["data", "stale"])]
    abandon: Option<String>,
    /// List unfinished imports no batch was written to for a day; with --remove, discard them.
    #[arg(long, conflicts_with = "data")]
    stale: bool,
    /// With --stale: discard the listed imports.
    #[arg(long, requires = "stale")]
    remove: bool,
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

/// How long an unfinished import waits untouched before `--stale` lists it.
const STALE_HOURS: u32 = 24;

/// `import --abandon DATASET` and `import --stale [--remove]`.
async fn unfinished(args: &ImportArgs) -> anyhow::Result<ExitCode> {
    let hub = open(&args.db.db).await?;
    let result = unfinished_on(&hub, args).await;
    hub.close().await;
    result
}

async fn unfinished_on(hub: &crate::app::Hub, args: &ImportArgs) -> anyhow::Result<ExitCode> {
    if let Some(dataset) = &args.abandon {
        return match abandon(hub, &operator(), dataset).await? {
            Some(s) => {
                eprintln!(
                    "abandoned the unfinished import into dataset '{}' ({} records written, \
                     started {}, last batch {}); the dataset is unchanged",
                    s.dataset, s.rows_done, s.started_at, s.updated_at
                );
                Ok(ExitCode::SUCCESS)
            }
            None => {
                eprintln!("error: no unfinished import into dataset '{dataset}'");
                Ok(ExitCode::FAILURE)
            }
        };
    }
    let found = stale(hub, STALE_HOURS).await?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&found)?);
    }
    for s in &found {
        eprintln!(
            "dataset '{}': {} records written, started {}, last batch {}",
            s.dataset, s.rows_done, s.started_at, s.updated_at
        );
        if args.remove {
            abandon(hub, &operator(), &s.dataset).await?;
            eprintln!("  removed");
        }
    }
    eprintln!(
        "{} unfinished imports untouched for {STALE_HOURS} hours{}",
        found.len(),
        if args.remove || found.is_empty() {
            ""
        } else {
            " (--remove discards them; running the same import again resumes one)"
        }
    );
    Ok(ExitCode::SUCCESS)
}

pub(super) async fn import(args: ImportArgs) -> anyhow::Result<ExitCode> {
    let Some(data) = args.data.clone() else {
        return unfinished(&args).await;
    };
    let dataset = args
        .dataset
        .clone()
        .unwrap_or_else(|| default_dataset_name(&data));
    let scene_graphs = match (&args.scene_graphs, args.no_scene_graphs) {
        (Some(dir), _) => Some(dir.clone()),
        (None, true) => None,
        // ENACT's download layout: QA/ beside replayed_activities/ (and segmented_activities/).
        (None, false) => ReleaseLocation::resolve(&data)
            .ok()
            .and_then(|location| location.own_scene_graphs())
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
        progress: std::io::stderr().is_terminal().then(progress_bar),
        scene_graphs,
        batch_lines: args.batch_lines as usize,
        stop: None,
    };
    let result = import_release(&hub, &operator(), &data, &options).await;
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
        // The hub's own sentence names the import form's checkbox; here the flag.
        Err(
            ref e @ ImportError::Conflict {
                ref file,
                ref dataset,
                ref conflicts,
            },
        ) => {
            for detail in e.details() {
                eprintln!("{detail}");
            }
            eprintln!(
                "error: {file}: {} items already exist in dataset '{dataset}' with different \
                 content; nothing was imported (use --replace to overwrite them)",
                conflicts.len()
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

/// A bar over the QA file's bytes; its message counts items and image bytes.
fn progress_bar() -> ImportObserver {
    let bar = indicatif::ProgressBar::new(0);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{msg:>32} [{bar:40}] {bytes}/{total_bytes} of QA file ({bytes_per_sec}, eta {eta})",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    ImportObserver(std::sync::Arc::new(move |p: &ImportProgress| {
        if p.finished {
            bar.finish_and_clear();
            return;
        }
        bar.set_length(p.qa_bytes);
        bar.set_position(p.qa_bytes_read);
        bar.set_message(format!(
            "{} items, {} MB of images",
            p.rows,
            p.image_bytes / 1_000_000
        ));
    }))
}
