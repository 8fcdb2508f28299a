//! `enact-hub study`: create, list, show and delete ablation studies, and write a study report.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::{Args, Subcommand};

use super::{DEFAULT_DB, in_database, open, operator};
use crate::app;
use crate::app::studies::{StudyRowChoice, StudyView};
use crate::core::study::VariantSpec;
use crate::core::study::figure::p_text;
use crate::core::study::report::StudyReport;

#[derive(Args)]
pub struct DbArg {
    /// SQLite database file, or a PostgreSQL URL
    /// (postgres://user:password@host/db; also ENACT_HUB_DATABASE_URL).
    #[arg(long, visible_alias = "database-url", env = "ENACT_HUB_DB", default_value = DEFAULT_DB)]
    pub(super) db: PathBuf,
}

#[derive(Subcommand)]
pub enum StudyCommand {
    /// Create a study: a baseline dataset and variants grouped in families.
    Create {
        #[command(flatten)]
        db: DbArg,
        /// Letters, digits, `.`, `_` and `-`.
        name: String,
        /// The baseline dataset.
        #[arg(long)]
        baseline: String,
        /// A variant as `FAMILY/LABEL=DATASET` ("Camera FOV/Aperture 30=enact-fov30");
        /// repeat for each. Families are drawn in the order of their first variant.
        #[arg(long = "variant", value_name = "FAMILY/LABEL=DATASET", required = true)]
        variants: Vec<String>,
    },
    /// List the studies.
    List {
        #[command(flatten)]
        db: DbArg,
        /// JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// One study with how each variant's items align with the baseline's.
    Show {
        #[command(flatten)]
        db: DbArg,
        name: String,
        #[arg(long)]
        json: bool,
    },
    /// Delete a study (its datasets and submissions stay).
    Delete {
        #[command(flatten)]
        db: DbArg,
        name: String,
    },
    /// The study report of a model (or of the Human row): Δ, Welch, paired t and sign tests
    /// per variant and direction, and the handedness panel.
    Report(ReportArgs),
}

#[derive(Args)]
pub struct ReportArgs {
    #[command(flatten)]
    db: DbArg,
    name: String,
    /// The model: its latest published submission on each dataset.
    #[arg(long, required_unless_present = "human", conflicts_with = "human")]
    model: Option<String>,
    /// The account, when several publish a model of that name.
    #[arg(long, requires = "model")]
    account: Option<String>,
    /// The annotators' answers instead of a model.
    #[arg(long)]
    human: bool,
    /// A cell per step length under each direction too.
    #[arg(long)]
    by_step_length: bool,
    /// Write the report's files (study.json, cells.csv, cells.tex, table.csv and table.tex in
    /// the paper's table layout, heatmap.svg, handedness.csv, handedness.svg) into this folder.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Print the report as JSON instead of a table.
    #[arg(long)]
    json: bool,
}

pub async fn study(command: StudyCommand) -> anyhow::Result<ExitCode> {
    match command {
        StudyCommand::Create {
            db,
            name,
            baseline,
            variants,
        } => {
            let specs = variants
                .iter()
                .map(|v| VariantSpec::parse(v))
                .collect::<Result<Vec<_>, _>>()
                .map_err(|e| anyhow::anyhow!("--variant {e}"))?;
            let hub = open(&db.db).await?;
            let created = app::studies::create(&hub, &operator(), &name, &baseline, &specs).await;
            hub.close().await;
            let view = in_database(created, &db.db)?;
            print!("{}", study_table(&view));
            Ok(ExitCode::SUCCESS)
        }
        StudyCommand::List { db, json } => {
            let hub = open(&db.db).await?;
            let listed = app::studies::list(&hub).await;
            hub.close().await;
            let views = in_database(listed, &db.db)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&views)?);
            } else if views.is_empty() {
                println!("no study in {}", db.db.display());
            } else {
                for v in &views {
                    println!(
                        "{}\tbaseline {}\t{} variants\tcreated {} by {}",
                        v.name,
                        v.baseline,
                        v.variants.len(),
                        v.created_at,
                        v.created_by
                    );
                }
            }
            Ok(ExitCode::SUCCESS)
        }
        StudyCommand::Show { db, name, json } => {
            let hub = open(&db.db).await?;
            let shown = app::studies::show(&hub, &name).await;
            hub.close().await;
            let view = in_database(shown, &db.db)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&view)?);
            } else {
                print!("{}", study_table(&view));
            }
            Ok(ExitCode::SUCCESS)
        }
        StudyCommand::Delete { db, name } => {
            let hub = open(&db.db).await?;
            let deleted = app::studies::delete(&hub, &operator(), &name).await;
            hub.close().await;
            in_database(deleted, &db.db)?;
            eprintln!("deleted study '{name}'; its datasets stay");
            Ok(ExitCode::SUCCESS)
        }
        StudyCommand::Report(args) => report(args).await,
    }
}

fn study_table(view: &StudyView) -> String {
    let mut out = format!(
        "study {}: baseline {}{}\n",
        view.name,
        view.baseline,
        view.baseline_items
            .map_or_else(String::new, |n| format!(" ({n} items)"))
    );
    for v in &view.variants {
        let alignment = v.alignment.as_ref().map_or_else(String::new, |a| {
            format!(
                ": {} aligned ({} by id, {} by task, type and key frames; {} baseline and {} \
                 variant items unaligned)",
                a.pairs.len(),
                a.by_id,
                a.by_key_frames,
                a.baseline_unaligned,
                a.variant_unaligned
            )
        });
        out.push_str(&format!(
            "  {}/{} = {}{alignment}\n",
            v.spec.family, v.spec.label, v.spec.dataset
        ));
        if let Some(a) = v.alignment.as_ref().filter(|a| a.verified_differently > 0) {
            out.push_str(&format!(
                "  warning: {} aligned items are judged by other rules than the baseline's \
                 (another ground truth or signature table); import the variant with the \
                 baseline's scene graphs\n",
                a.verified_differently
            ));
        }
    }
    out
}

fn report_table(report: &StudyReport) -> String {
    let mut out = format!(
        "{} against baseline {} (Δ = variant − baseline, mean pairwise accuracy)\n",
        report.stamp.row, report.stamp.baseline.name
    );
    out.push_str("family\tvariant\tdirection\tL\tΔ\tWelch p\tpaired t p\tsign p\tn\n");
    for c in &report.cells {
        out.push_str(&format!(
            "{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}/{}\n",
            c.family,
            c.variant,
            c.direction,
            c.step_length
                .map_or_else(|| "all".to_owned(), |l| l.to_string()),
            c.delta
                .map_or_else(|| "n/a".to_owned(), |d| format!("{d:+.4}")),
            c.p.map_or_else(
                || c.undefined.clone().unwrap_or_else(|| "no test".to_owned()),
                |p| p_text(Some(p))
            ),
            p_text(c.paired_t.p),
            p_text(Some(c.sign_test.p)),
            c.n_baseline,
            c.n_variant
        ));
    }
    for v in &report.variants {
        if let Some(why) = &v.missing {
            out.push_str(&format!("note: {}/{}: {why}\n", v.family, v.variant));
        }
    }
    out
}

async fn report(args: ReportArgs) -> anyhow::Result<ExitCode> {
    let choice = match (&args.model, args.human) {
        (Some(model), false) => StudyRowChoice::Model {
            model: model.clone(),
            account: args.account.clone(),
        },
        _ => StudyRowChoice::Human,
    };
    let hub = open(&args.db.db).await?;
    let made = app::studies::report(&hub, &args.name, &choice, args.by_step_length).await;
    hub.close().await;
    let report = in_database(made, &args.db.db)?;
    if let Some(out) = &args.out {
        let files = in_database(app::studies::files(&report), &args.db.db)?;
        std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
        for file in &files {
            let path = out.join(&file.name);
            std::fs::write(&path, &file.bytes)
                .with_context(|| format!("cannot write {}", path.display()))?;
        }
        eprintln!(
            "wrote {} files to {} (baseline sha256:{})",
            files.len(),
            out.display(),
            report.stamp.baseline.hash
        );
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else if args.out.is_none() {
        print!("{}", report_table(&report));
    }
    Ok(ExitCode::SUCCESS)
}
