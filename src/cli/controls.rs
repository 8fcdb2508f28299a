//! `enact-hub annotator pause|resume|handover`: stopping an annotator's queue for a while,
//! and handing their unfinished items to others ([`crate::app::controls`]).

use std::process::ExitCode;

use clap::Args;

use super::{DbArg, in_database, open, operator};
use crate::app;

#[derive(Args)]
pub(super) struct PauseArgs {
    /// The annotator's login name.
    name: String,
    #[command(flatten)]
    db: DbArg,
}

#[derive(Args)]
pub(super) struct HandoverArgs {
    /// The login name of the annotator whose unfinished items move.
    name: String,
    #[command(flatten)]
    db: DbArg,
    /// A recipient's login name (repeat, or separate with commas); without it, every other
    /// active annotator whose queue is not paused, admins aside.
    #[arg(long, value_name = "NAME", value_delimiter = ',')]
    to: Vec<String>,
    /// Print what moved as JSON instead of lines.
    #[arg(long)]
    json: bool,
}

pub(super) async fn pause(args: PauseArgs) -> anyhow::Result<ExitCode> {
    change(args, true).await
}

pub(super) async fn resume(args: PauseArgs) -> anyhow::Result<ExitCode> {
    change(args, false).await
}

async fn change(args: PauseArgs, pause: bool) -> anyhow::Result<ExitCode> {
    let hub = open(&args.db.db).await?;
    let actor = operator();
    let result = if pause {
        app::controls::pause(&hub, &actor, &args.name).await
    } else {
        app::controls::resume(&hub, &actor, &args.name).await
    };
    hub.close().await;
    let changed = in_database(result, &args.db.db)?;
    match (changed, pause) {
        (false, true) => println!("annotator '{}': queue paused already", args.name),
        (false, false) => println!("annotator '{}': queue was not paused", args.name),
        (true, true) => println!(
            "annotator '{}': queue paused (no item can be opened, saved, answered or skipped, \
             and no split assigns new items; `annotator resume` restores it)",
            args.name
        ),
        (true, false) => println!(
            "annotator '{}': queue resumed as it was, drafts included",
            args.name
        ),
    }
    Ok(ExitCode::SUCCESS)
}

pub(super) async fn handover(args: HandoverArgs) -> anyhow::Result<ExitCode> {
    let hub = open(&args.db.db).await?;
    let result = app::controls::handover(&hub, &operator(), &args.name, &args.to).await;
    hub.close().await;
    let done = in_database(result, &args.db.db)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&done)?);
        return Ok(ExitCode::SUCCESS);
    }
    let moved: usize = done.to.iter().map(|t| t.items.len()).sum();
    println!(
        "annotator '{}': {moved} unfinished items handed over, {} every recipient had stayed, \
         {} gold items and attention checks taken out, {} drafts removed",
        done.from,
        done.kept.len(),
        done.removed_checks,
        done.drafts_removed
    );
    for to in &done.to {
        println!("{}: {} items", to.annotator, to.items.len());
        for item in &to.items {
            println!("  {} {}", item.dataset, item.item_id);
        }
    }
    for item in &done.kept {
        println!("stayed: {} {}", item.dataset, item.item_id);
    }
    Ok(ExitCode::SUCCESS)
}
