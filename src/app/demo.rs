//! The built-in demo: the synthetic world's release written to a temporary folder, imported
//! as dataset "demo" with scene-graph semantics, and a chance baseline on its leaderboard.

use anyhow::Context;

use super::import::{ImportOptions, ImportReport, import_release};
use super::{Hub, submissions};
use crate::core::demo;
use crate::core::submission::SubmissionMetadata;

/// The dataset the demo is imported as.
pub const DEMO_DATASET: &str = "demo";

/// The account the demo's baseline row is filed under.
pub const DEMO_ACCOUNT: &str = "enact-hub demo";

/// Generates the demo release and imports it as dataset "demo" (replacing an older demo), then
/// files the chance baseline once per database.
pub async fn load(hub: &Hub) -> anyhow::Result<ImportReport> {
    let dir = tempfile::tempdir().context("cannot create a temporary directory")?;
    let out = dir.path().to_path_buf();
    let written =
        tokio::task::spawn_blocking(move || demo::write_demo_release(&out, demo::DEFAULT_SEED))
            .await
            .context("demo generation task failed")?
            .context("cannot generate the demo dataset")?;
    let options = ImportOptions {
        dataset: DEMO_DATASET.to_owned(),
        skip_invalid: false,
        replace: true,
        progress: false,
        scene_graphs: Some(written.replayed_dir),
    };
    let report = import_release(hub, dir.path(), &options)
        .await
        .context("cannot import the demo dataset")?;
    tracing::info!("{}", report.summary_line());
    let metadata = SubmissionMetadata {
        model: demo::CHANCE_BASELINE_MODEL.to_owned(),
        description: "Every item answered with a uniformly random ordering (seeded); what \
                      chance earns at each step length."
            .to_owned(),
        ..SubmissionMetadata::default()
    };
    submissions::file_baseline(hub, DEMO_DATASET, DEMO_ACCOUNT, metadata, |dataset| {
        demo::chance_baseline(
            dataset
                .targets
                .iter()
                .map(|t| (t.id.as_str(), t.ground_truth.len())),
            demo::DEFAULT_SEED,
        )
    })
    .await
    .context("cannot add the demo's chance baseline")?;
    Ok(report)
}
