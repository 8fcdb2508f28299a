//! The built-in demo: the synthetic world's release written to a temporary folder, imported
//! as dataset "demo" with scene-graph semantics, and two reference rows on its leaderboard: a
//! chance baseline and a one-rule heuristic, whose replies are text as a model's are.

use anyhow::Context;

use super::import::{BATCH_LINES, ImportOptions, ImportReport, import_release};
use super::{AppError, Hub, annotators, datasets, submissions};
use crate::Lane;
use crate::core::annotation::balanced_sample;
use crate::core::audit::Actor;
use crate::core::credentials::{random_token, token_hash};
use crate::core::dataset::parse_release_line;
use crate::core::demo;
use crate::core::submission::SubmissionMetadata;
use crate::store;

/// The dataset the demo is imported as.
pub const DEMO_DATASET: &str = "demo";

/// The demo's admin annotator, whose queue holds a sample of the demo.
pub const DEMO_ANNOTATOR: &str = "demo-admin";

/// Demo items of each direction × step length in the demo admin's queue.
const SAMPLE_PER_KIND: usize = 2;

/// The account the demo's baseline row is filed under.
pub const DEMO_ACCOUNT: &str = "enact-hub demo";

/// Generates the demo release and imports it as dataset "demo" (replacing an older demo), then
/// files the chance baseline once per database.
pub async fn load(hub: &Hub) -> anyhow::Result<ImportReport> {
    let dir = tempfile::tempdir().context("cannot create a temporary directory")?;
    let out = dir.path().to_path_buf();
    let written = hub
        .heavy()
        .run_waiting(move || demo::write_demo_release(&out, demo::DEFAULT_SEED))
        .await
        .context("cannot generate the demo dataset")?;
    let heuristic = heuristic_replies(&written.jsonl_path)?;
    let options = ImportOptions {
        dataset: DEMO_DATASET.to_owned(),
        skip_invalid: false,
        replace: true,
        progress: None,
        scene_graphs: Some(written.replayed_dir),
        batch_lines: BATCH_LINES,
        stop: None,
    };
    let report = import_release(hub, &Actor::Server, dir.path(), &options)
        .await
        .context("cannot import the demo dataset")?;
    tracing::info!("{}", report.summary_line());
    file_reference_row(
        hub,
        demo::CHANCE_BASELINE_MODEL,
        "Every item answered with a uniformly random ordering (seeded); what chance earns at \
         each step length.",
        |dataset| {
            demo::chance_baseline(
                dataset
                    .targets
                    .iter()
                    .map(|t| (t.id.as_str(), t.ground_truth.len())),
                demo::DEFAULT_SEED,
            )
        },
    )
    .await?;
    file_reference_row(
        hub,
        demo::GRASP_HEURISTIC_MODEL,
        "Not a model: one rule over ENACT's sentences. Inverse items: each object grasped \
         before it is released, otherwise the order listed; forward items (images it cannot \
         see): the order listed.",
        |_| heuristic,
    )
    .await?;
    Ok(report)
}

/// Files `model`'s answers (made from the dataset's scoring targets by `body`) on the demo's
/// leaderboard as a reference row, once per database.
async fn file_reference_row(
    hub: &Hub,
    model: &str,
    description: &str,
    body: impl FnOnce(&submissions::DatasetTargets) -> String,
) -> anyhow::Result<()> {
    let metadata = SubmissionMetadata {
        model: model.to_owned(),
        description: description.to_owned(),
        ..SubmissionMetadata::default()
    };
    submissions::file_baseline(
        hub,
        &Actor::Server,
        DEMO_DATASET,
        DEMO_ACCOUNT,
        metadata,
        body,
    )
    .await
    .with_context(|| format!("cannot add the demo's row '{model}'"))?;
    Ok(())
}

/// The heuristic's replies to every item of the demo release at `jsonl`.
fn heuristic_replies(jsonl: &std::path::Path) -> anyhow::Result<String> {
    let text = std::fs::read_to_string(jsonl)
        .with_context(|| format!("cannot read {}", jsonl.display()))?;
    let items = text
        .lines()
        .enumerate()
        .filter(|(_, line)| !line.trim().is_empty())
        .map(|(n, line)| {
            parse_release_line(line).map_err(|problems| {
                anyhow::anyhow!("{} line {}: {problems:?}", jsonl.display(), n + 1)
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    Ok(demo::grasp_heuristic(items.iter().map(|i| {
        (
            i.id.as_str(),
            i.direction,
            i.question.as_str(),
            i.gt_answer.len(),
        )
    })))
}

/// A single-use login link secret for the demo admin (created on first use, with a balanced
/// sample of the demo in their queue: both directions, every step length), so a newcomer
/// annotates with one click. Their answers make the Human row.
pub async fn annotator_link(hub: &Hub) -> Result<String, AppError> {
    let dataset = datasets::by_name(hub, DEMO_DATASET).await?;
    let mut tx = hub.write(Lane::Interactive).await?;
    let existing = store::annotations::annotators(&mut tx)
        .await?
        .into_iter()
        .find(|a| a.name == DEMO_ANNOTATOR)
        .map(|a| a.id);
    let annotator = match existing {
        Some(id) => id,
        None => {
            // An invite nobody holds: the account is reached through login links only.
            let hash = token_hash(&random_token());
            store::annotations::create_annotator(&mut tx, DEMO_ANNOTATOR, true, &hash).await?
        }
    };
    let items = store::annotations::dataset_items(&mut tx, dataset.id).await?;
    let sample = balanced_sample(&items, SAMPLE_PER_KIND);
    let pairs: Vec<(i64, i64)> = sample.iter().map(|&item| (annotator, item)).collect();
    store::annotations::assign(&mut tx, &pairs).await?;
    tx.commit().await?;
    annotators::login_link(hub, annotator).await
}
