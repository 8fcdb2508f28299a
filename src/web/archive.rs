//! A dataset as one downloadable ENACT release archive (tar), streamed entry by entry.
//!
//! Ground truth (`gt_answer`, `key_frame_ids`) is written only for datasets whose answers are
//! public; see [`crate::core::release`] for the layout.

use std::collections::HashSet;

use axum::body::{Body, Bytes};
use axum::extract::{Path, State};
use axum::http::{HeaderValue, header};
use axum::response::{IntoResponse, Response};
use sqlx::SqlitePool;
use tokio::sync::mpsc;

use super::openapi::{ApiRoute, Verb};
use super::{AppError, AppState, dataset_or_404};
use crate::core::release::{ArchiveWriter, QA_FILE, release_line};
use crate::store;
use crate::store::submissions::AnswerVisibility;

/// Items whose frames are read from the database at a time.
const ITEMS_PER_BATCH: usize = 16;

pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Get,
            "/datasets/{dataset}/archive",
            download,
            "The dataset as an ENACT release archive",
        )
        .describe(
            "A tar archive, streamed: `QA/enact_ordering.jsonl` then every image under the path \
             its record names. For a dataset whose answers are public, extracting it and running \
             `enact-hub import DIR` reads back the same items. For a hidden dataset `gt_answer` \
             and `key_frame_ids` are left out of every line (the importer then refuses it). The \
             `X-Enact-Ground-Truth` header says `included` or `omitted`.",
        )
        .responds(200, Some("application/x-tar"), "The archive.")
        .errors(&[404]),
    ]
}

/// A name safe inside a quoted `Content-Disposition` filename.
fn archive_file_name(dataset: &str) -> String {
    let stem: String = dataset
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("{stem}.tar")
}

async fn download(
    State(state): State<AppState>,
    Path(name): Path<String>,
) -> Result<Response, AppError> {
    let dataset = dataset_or_404(&state.pool, &name).await?;
    let mut conn = state.pool.acquire().await?;
    let with_truth = store::submissions::answer_visibility(&mut conn, dataset.id).await?
        == AnswerVisibility::Public;
    let items = store::items::release_items(&mut conn, dataset.id).await?;
    drop(conn);

    // The QA file goes first and its size is in its header, so it is built whole; it is small
    // beside the frames (about 27 MB for a full release), which are streamed.
    let mut qa = String::new();
    for (_, item) in &items {
        qa.push_str(&release_line(item, with_truth));
        qa.push('\n');
    }
    let mut writer = ArchiveWriter::default();
    let head = writer
        .file(QA_FILE, qa.as_bytes())
        .map_err(|e| AppError::Internal(e.into()))?;
    let rows: Vec<i64> = items.iter().map(|(row, _)| *row).collect();
    drop(items);

    let (tx, rx) = mpsc::channel(4);
    tokio::spawn(stream_frames(
        state.pool.clone(),
        dataset.name.clone(),
        rows,
        writer,
        head,
        tx,
    ));
    let disposition = format!(
        "attachment; filename=\"{}\"",
        archive_file_name(&dataset.name)
    );
    let mut response =
        Body::from_stream(tokio_stream::wrappers::ReceiverStream::new(rx)).into_response();
    let headers = response.headers_mut();
    headers.insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/x-tar"),
    );
    if let Ok(v) = HeaderValue::from_str(&disposition) {
        headers.insert(header::CONTENT_DISPOSITION, v);
    }
    headers.insert(
        "x-enact-ground-truth",
        HeaderValue::from_static(if with_truth { "included" } else { "omitted" }),
    );
    Ok(response)
}

type Chunk = Result<Bytes, std::io::Error>;

/// Sends the archive's remaining entries. A failure ends the body with an error, so the client
/// sees a broken transfer rather than a short archive that looks complete.
async fn stream_frames(
    pool: SqlitePool,
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
        let images = match pool.acquire().await {
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
        for (path, png) in images {
            // Two records naming one file hold the same bytes (the importer read one file).
            if !written.insert(path.clone()) {
                continue;
            }
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
