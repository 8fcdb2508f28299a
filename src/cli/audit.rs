//! `enact-hub audit`: the audit log, filtered, as a table or JSON.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;

use super::{DEFAULT_DB, in_database, is_missing_file, open};
use crate::app;
use crate::core::audit::{AuditEntry, AuditFilter};

#[derive(Args)]
pub struct AuditArgs {
    /// SQLite database file, or a PostgreSQL URL
    /// (postgres://user:password@host/db; also ENACT_HUB_DATABASE_URL).
    #[arg(long, visible_alias = "database-url", env = "ENACT_HUB_DB", default_value = DEFAULT_DB)]
    db: PathBuf,
    /// Only this action (`token.issue`), or every action of a noun (`token`).
    #[arg(long)]
    action: Option<String>,
    /// Only entries by this account, annotator or operator name.
    #[arg(long)]
    actor: Option<String>,
    /// Only entries about this dataset.
    #[arg(long)]
    dataset: Option<String>,
    /// Only entries at or after this UTC date or time (2026-11-25 or 2026-11-25T10:00:00Z).
    #[arg(long)]
    since: Option<String>,
    /// At most this many entries, newest first.
    #[arg(long, default_value_t = 100)]
    limit: usize,
    /// One JSON array instead of a table.
    #[arg(long)]
    json: bool,
}

pub async fn audit(args: AuditArgs) -> anyhow::Result<ExitCode> {
    if is_missing_file(&args.db) {
        anyhow::bail!("{} does not exist: no audit log to read", args.db.display());
    }
    let hub = open(&args.db).await?;
    let filter = AuditFilter {
        action: args.action,
        actor: args.actor,
        dataset: args.dataset,
        since: args.since,
        before_id: None,
        limit: args.limit,
    };
    let entries = app::audit::list(&hub, filter).await;
    hub.close().await;
    let entries = in_database(entries, &args.db)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&entries)?);
    } else {
        print!("{}", table(&entries));
    }
    Ok(ExitCode::SUCCESS)
}

/// Entries as aligned columns; the detail, last, is not padded.
fn table(entries: &[AuditEntry]) -> String {
    if entries.is_empty() {
        return "no audit entries match\n".to_owned();
    }
    let rows: Vec<[String; 6]> = entries
        .iter()
        .map(|e| {
            [
                e.at.clone(),
                format!("{} {}", e.actor_kind, e.actor),
                e.action.clone(),
                e.target.clone(),
                e.dataset.clone().unwrap_or_else(|| "-".to_owned()),
                e.detail.clone(),
            ]
        })
        .collect();
    let header = ["at", "actor", "action", "target", "dataset", "detail"];
    let widths: Vec<usize> = (0..5)
        .map(|c| {
            rows.iter()
                .map(|r| r[c].chars().count())
                .chain([header[c].len()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let line = |cells: [&str; 6]| {
        let mut out = String::new();
        for (c, cell) in cells.iter().enumerate().take(5) {
            out.push_str(&format!("{cell:<width$}  ", width = widths[c]));
        }
        out.push_str(cells[5]);
        out.trim_end().to_owned() + "\n"
    };
    let mut out = line(header);
    for r in &rows {
        out.push_str(&line([&r[0], &r[1], &r[2], &r[3], &r[4], &r[5]]));
    }
    out
}
