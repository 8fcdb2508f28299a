//! A dataset as one downloadable ENACT release archive (tar), streamed entry by entry.
//!
//! Ground truth (`gt_answer`, `key_frame_ids`) is written only for datasets whose answers are
//! public; see [`crate::core::release`] for the layout.

use axum::body::Body;
use axum::extract::State;
use axum::http::{HeaderValue, header};
use axum::response::{IntoResponse, Response};

use super::error::ApiError;
use super::extract::Path;
use super::openapi::{ApiRoute, Verb};
use super::{AppError, AppState};
use crate::app::datasets;

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
    format!("{}.tar", super::file_name_safe(dataset))
}

/// A report's files as one tar download: `{folder}/…` inside, `{folder}.tar` as its name
/// (`folder` already safe in a quoted header).
pub(super) fn bundle_download(
    folder: &str,
    files: &[crate::core::bundle::BundleFile],
) -> Result<Response, ApiError> {
    let archive = crate::core::bundle::tar_archive(folder, files).map_err(AppError::from)?;
    let disposition = HeaderValue::from_str(&format!("attachment; filename=\"{folder}.tar\""))
        .map_err(anyhow::Error::from)?;
    Ok((
        [
            (
                header::CONTENT_TYPE,
                HeaderValue::from_static("application/x-tar"),
            ),
            (header::CONTENT_DISPOSITION, disposition),
        ],
        archive,
    )
        .into_response())
}

/// A tar stream as a download named `file_name` (already safe in a quoted header).
pub(super) fn tar_download(
    chunks: tokio::sync::mpsc::Receiver<Result<bytes::Bytes, std::io::Error>>,
    file_name: &str,
) -> Response {
    let mut response =
        Body::from_stream(tokio_stream::wrappers::ReceiverStream::new(chunks)).into_response();
    let headers = response.headers_mut();
    headers.insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/x-tar"),
    );
    if let Ok(v) = HeaderValue::from_str(&format!("attachment; filename=\"{file_name}\"")) {
        headers.insert(header::CONTENT_DISPOSITION, v);
    }
    response
}

async fn download(
    State(state): State<AppState>,
    Path(name): Path<String>,
) -> Result<Response, ApiError> {
    let archive = datasets::release_archive(&state.hub, &name).await?;
    let mut response = tar_download(archive.chunks, &archive_file_name(&archive.dataset.name));
    let headers = response.headers_mut();
    headers.insert(
        "x-enact-ground-truth",
        HeaderValue::from_static(if archive.with_truth {
            "included"
        } else {
            "omitted"
        }),
    );
    Ok(response)
}
