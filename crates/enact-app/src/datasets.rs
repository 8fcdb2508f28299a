//! Reading datasets: by name, their overview and counts, whether their answers are public,
//! and the whole dataset as a streamed ENACT release archive; and storing a stratified subset
//! of one as a dataset of its own.

use std::collections::HashSet;

use bytes::Bytes;
use tokio::sync::mpsc;

use super::refusal::Refusal;
use super::{AppError, Hub, audit};
use crate::Lane;
use crate::core::audit::{Actor, AuditAction};
use crate::core::dataset::AnswerVisibility;
use crate::core::release::{ArchiveWriter, QA_FILE, release_line};
use crate::core::study::subset::{
    Allocation, StratumCount, StratumField, SubsetCandidate, stratified_subset,
};
use crate::store;
pub use crate::store::datasets::{Dataset, DatasetOverview, ItemCounts};

/// Items whose frames are read from the database at a time while an archive streams.
const ITEMS_PER_BATCH: usize = 16;

/// The dataset named `name`, or a 404 that names it.
pub async fn by_name(hub: &Hub, name: &str) -> Result<Dataset, AppError> {
    let mut conn = hub.conn().await?;
    store::datasets::by_name(&mut conn, name)
        .await?
        .ok_or_else(|| no_dataset(name))
}

fn no_dataset(name: &str) -> AppError {
    Refusal::NoDataset {
        dataset: name.to_owned(),
    }
    .into()
}

/// Every dataset with its item counts.
pub async fn overview(hub: &Hub) -> Result<Vec<DatasetOverview>, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::datasets::overview(&mut conn).await?)
}

/// One dataset with its item counts.
pub async fn overview_of(hub: &Hub, name: &str) -> Result<DatasetOverview, AppError> {
    overview(hub)
        .await?
        .into_iter()
        .find(|o| o.dataset.name == name)
        .ok_or_else(|| no_dataset(name))
}

/// The tasks a dataset's items come from, for filters.
pub async fn task_names(hub: &Hub, dataset: &Dataset) -> Result<Vec<String>, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::items::task_names(&mut conn, dataset.id).await?)
}

pub async fn answer_visibility(hub: &Hub, dataset: &Dataset) -> Result<AnswerVisibility, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::submissions::answer_visibility(&mut conn, dataset.id).await?)
}

/// Makes a dataset's ground truth and per-item verdicts public, or hides them again.
pub async fn set_answer_visibility(
    hub: &Hub,
    actor: &Actor,
    name: &str,
    answers: AnswerVisibility,
) -> Result<Dataset, AppError> {
    let dataset = by_name(hub, name).await?;
    let mut tx = hub.write(Lane::Interactive).await?;
    store::submissions::set_answer_visibility(&mut tx, dataset.id, answers).await?;
    audit::record(
        &mut tx,
        actor,
        AuditAction::DatasetAnswerVisibility,
        format!("dataset {}", dataset.name),
        Some(&dataset.name),
        format!("answers {}", answers.as_str()),
    )
    .await?;
    tx.commit().await?;
    Ok(dataset)
}

/// A release archive on its way out: whether it holds ground truth, and its bytes in order.
pub struct ReleaseArchive {
    pub dataset: Dataset,
    pub with_truth: bool,
    /// The tar stream. A failure ends it with an error, so a reader sees a broken transfer
    /// rather than a short archive that looks complete.
    pub chunks: mpsc::Receiver<Result<Bytes, std::io::Error>>,
}

/// The dataset in ENACT's release layout, as a tar stream: ground truth only when its answers
/// are public. The QA file is built whole (it is small beside the frames); frames stream.
pub async fn release_archive(hub: &Hub, name: &str) -> Result<ReleaseArchive, AppError> {
    let dataset = by_name(hub, name).await?;
    let mut conn = hub.conn().await?;
    let with_truth = store::submissions::answer_visibility(&mut conn, dataset.id).await?
        == AnswerVisibility::Public;
    let items = store::items::release_items(&mut conn, dataset.id).await?;
    drop(conn);
    let mut qa = String::new();
    for (_, item) in &items {
        qa.push_str(&release_line(item, with_truth));
        qa.push('\n');
    }
    let mut writer = ArchiveWriter::default();
    let head = writer.file(QA_FILE, qa.as_bytes())?;
    let rows: Vec<i64> = items.iter().map(|(row, _)| *row).collect();
    drop(items);
    let (tx, rx) = mpsc::channel(4);
    tokio::spawn(stream_frames(
        hub.clone(),
        dataset.name.clone(),
        rows,
        writer,
        head,
        tx,
    ));
    Ok(ReleaseArchive {
        dataset,
        with_truth,
        chunks: rx,
    })
}

type Chunk = Result<Bytes, std::io::Error>;

/// Sends the archive's remaining entries.
async fn stream_frames(
    hub: Hub,
    dataset: String,
    rows: Vec<i64>,
    mut writer: ArchiveWriter,
    head: Vec<u8>,
    tx: mpsc::Sender<Chunk>,
) {
    if tx.send(Ok(Bytes::from(head))).await.is_err() {
        return;
    }
    let mut written: HashSet<String> = HashSet::new();
    for batch in rows.chunks(ITEMS_PER_BATCH) {
        let images = match hub.pool().acquire().await {
            Ok(mut conn) => store::items::release_images(&mut conn, batch).await,
            Err(e) => Err(e),
        };
        let images = match images {
            Ok(images) => images,
            Err(e) => {
                tracing::error!(error = %e, dataset, "archive: reading frames failed");
                let _ = tx.send(Err(std::io::Error::other(e))).await;
                return;
            }
        };
        for (path, sha256, png) in images {
            // Two records naming one file hold the same bytes (the importer read one file).
            if !written.insert(path.clone()) {
                continue;
            }
            let png = match png {
                Some(png) => Bytes::from(png),
                None => match super::frames::object_bytes(&hub, &sha256).await {
                    Ok(png) => png,
                    Err(e) => {
                        tracing::error!(error = %e, dataset, path, "archive: reading frame failed");
                        let _ = tx.send(Err(std::io::Error::other(e.to_string()))).await;
                        return;
                    }
                },
            };
            let chunk = writer.file(&path, &png);
            let failed = chunk.is_err();
            if let Err(e) = &chunk {
                tracing::error!(error = %e, dataset, path, "archive: cannot write entry");
            }
            if tx.send(chunk.map(Bytes::from)).await.is_err() || failed {
                return;
            }
        }
    }
    let _ = tx.send(writer.finish().map(Bytes::from)).await;
}

/// What [`subset`] stored.
#[derive(Debug, Clone, serde::Serialize, schemars::JsonSchema)]
pub struct SubsetReport {
    pub source: String,
    pub dataset: String,
    pub items: usize,
    pub fields: Vec<StratumField>,
    pub allocation: Allocation,
    pub seed: u64,
    /// Per stratum: the source's items and the chosen.
    pub strata: Vec<StratumCount>,
}

/// What a subset is drawn by: the stratum fields, the size, the allocation and the seed.
#[derive(Debug, Clone)]
pub struct SubsetRule {
    pub fields: Vec<StratumField>,
    pub size: usize,
    pub allocation: Allocation,
    pub seed: u64,
}

/// Stores a stratified subset of dataset `source` as the new dataset `into` (see
/// [`crate::core::study::subset`]): the chosen items copied as they are (ids, questions,
/// answers, images and signature tables), so a study pairs them with the source's. Refuses a
/// name in use and a rule the source cannot satisfy before writing; one transaction holds the
/// dataset, its items and the audit entry.
pub async fn subset(
    hub: &Hub,
    actor: &Actor,
    source: &str,
    into: &str,
    rule: &SubsetRule,
) -> Result<SubsetReport, AppError> {
    let into =
        crate::core::credentials::plain_name(into, "dataset", 64).map_err(AppError::Invalid)?;
    if rule.fields.is_empty() {
        return Err(Refusal::EmptyList { field: "fields" }.into());
    }
    let from = by_name(hub, source).await?;
    let mut conn = hub.conn().await?;
    let items = store::items::scoring_items(&mut conn, from.id).await?;
    drop(conn);
    let candidates: Vec<SubsetCandidate<'_>> = items
        .iter()
        .map(|i| SubsetCandidate {
            direction: i.direction,
            step_length: i.step_length,
            task_name: &i.task_name,
        })
        .collect();
    let drawn = stratified_subset(
        &candidates,
        &rule.fields,
        rule.size,
        rule.allocation,
        rule.seed,
    )
    .map_err(|e| AppError::Invalid(format!("dataset '{}': {e}", from.name)))?;
    let rows: Vec<i64> = drawn.chosen.iter().map(|&i| items[i].row_id).collect();
    let fields: Vec<&str> = rule.fields.iter().map(|f| f.as_str()).collect();
    let fields = fields.join(",");
    let description = format!(
        "subset of {}: {} items stratified by {fields}, seed {}",
        from.name, rule.size, rule.seed
    );
    let mut tx = hub.write(Lane::Interactive).await?;
    if store::datasets::by_name(&mut tx, into).await?.is_some() {
        return Err(Refusal::DatasetExists {
            dataset: into.to_owned(),
        }
        .into());
    }
    store::datasets::insert_copy(&mut tx, &from, into, &description, &rows).await?;
    store::bump_content_generation(&mut tx).await?;
    audit::record(
        &mut tx,
        actor,
        AuditAction::DatasetSubset,
        format!("dataset {into}"),
        Some(into),
        description,
    )
    .await?;
    tx.commit().await?;
    tracing::info!(source = %from.name, dataset = into, items = rows.len(), "subset stored");
    Ok(SubsetReport {
        source: from.name,
        dataset: into.to_owned(),
        items: rows.len(),
        fields: rule.fields.clone(),
        allocation: rule.allocation,
        seed: rule.seed,
        strata: drawn.strata,
    })
}
