//! A run's per-item responses as people read them: a page of rows for the run's page, and
//! every answer as ENACT's model-output JSONL (what `enact eval` reads), streamed a page of
//! items at a time. Admins see every run's; anyone sees those of a run whose dataset has
//! public answers (the file holds ground truth, and the raw replies give answers away).

use bytes::Bytes;
use tokio::sync::mpsc;

use super::RunRow;
use crate::core::dataset::AnswerVisibility;
use crate::core::release::model_output_line;
use crate::refusal::Refusal;
use crate::store;
use crate::store::datasets::Dataset;
use crate::store::runs::RunItemRow;
use crate::{AppError, Hub};

/// Who is reading a run's responses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Audience {
    /// An admin: every run.
    Admin,
    /// Anyone: only runs of datasets whose answers are public.
    Public,
}

/// Rows shown on one page of a run's responses.
pub const RESPONSES_PER_PAGE: i64 = 50;

/// Items read from the database per chunk of the JSONL download.
const OUTPUT_CHUNK: i64 = 500;

/// One page of a run's per-item responses.
#[derive(Debug, Clone)]
pub struct ResponsePage {
    pub run: RunRow,
    pub rows: Vec<RunItemRow>,
    /// 1-based; `pages` is at least 1.
    pub page: i64,
    pub pages: i64,
    /// Items with a row (answered or failed).
    pub total: i64,
}

/// Run `id` if `audience` may read its responses; a hidden one is not found for the public.
pub async fn visible_run(hub: &Hub, id: i64, audience: Audience) -> Result<RunRow, AppError> {
    let mut conn = hub.conn().await?;
    let run = store::runs::by_id(&mut conn, id).await?;
    let run = match (run, audience) {
        (Some(run), Audience::Admin) => Some(run),
        (Some(run), Audience::Public) => {
            let answers = store::submissions::answer_visibility(&mut conn, run.dataset_id).await?;
            (answers == AnswerVisibility::Public).then_some(run)
        }
        (None, _) => None,
    };
    run.ok_or_else(|| match audience {
        Audience::Admin => Refusal::NoRun {
            run: id.to_string(),
        }
        .into(),
        Audience::Public => AppError::NotFound(format!(
            "no model run {id} with public responses (a run's responses are public only \
             when its dataset's answers are)"
        )),
    })
}

/// A run's stamp as a leaderboard reader sees it: what the hub asked, how, and which
/// submission the replies became.
#[derive(Debug, Clone)]
pub struct StampedRun {
    pub run: RunRow,
    pub submission: i64,
    /// The stamp's JSON as stored when the run submitted.
    pub stamp: serde_json::Value,
}

/// Run `id`'s stamp, for an admin always, for anyone else once the run's submission is on
/// its leaderboard (a stamp names the endpoint's host, model, parameters and prompt, never an
/// answer, so a hidden dataset's runs show theirs too). A run that has not submitted has none.
pub async fn stamp(hub: &Hub, id: i64, audience: Audience) -> Result<StampedRun, AppError> {
    let missing = || {
        AppError::NotFound(format!(
            "no model run {id} with a submission on a leaderboard"
        ))
    };
    let mut conn = hub.conn().await?;
    let run = store::runs::by_id(&mut conn, id)
        .await?
        .ok_or_else(missing)?;
    let (Some(submission), Some(stamp)) = (run.submission, run.stamp.as_deref()) else {
        return Err(missing());
    };
    if audience == Audience::Public {
        let listed = store::submissions::by_id(&mut conn, submission)
            .await?
            .is_some_and(|s| s.visibility == crate::core::submission::Visibility::Published);
        if !listed {
            return Err(missing());
        }
    }
    let stamp = serde_json::from_str(stamp)
        .map_err(|e| AppError::internal(format!("model run {id}: stored stamp unreadable: {e}")))?;
    Ok(StampedRun {
        run,
        submission,
        stamp,
    })
}

/// The runs of `dataset` anyone may read the responses of: all of them when its answers are
/// public, none otherwise. Newest first.
pub async fn public_runs(hub: &Hub, dataset: &Dataset) -> Result<Vec<RunRow>, AppError> {
    let mut conn = hub.conn().await?;
    if store::submissions::answer_visibility(&mut conn, dataset.id).await?
        != AnswerVisibility::Public
    {
        return Ok(Vec::new());
    }
    Ok(store::runs::of_dataset(&mut conn, dataset.id).await?)
}

/// Page `page` (1-based) of run `id`'s responses, in dataset order.
pub async fn response_page(
    hub: &Hub,
    id: i64,
    audience: Audience,
    page: i64,
) -> Result<ResponsePage, AppError> {
    if page < 1 {
        return Err(AppError::Invalid(format!(
            "page must be 1 or more, not {page}"
        )));
    }
    let run = visible_run(hub, id, audience).await?;
    let mut conn = hub.conn().await?;
    let total = store::runs::count_items(&mut conn, run.id).await?;
    let pages = (total + RESPONSES_PER_PAGE - 1).max(RESPONSES_PER_PAGE) / RESPONSES_PER_PAGE;
    if page > pages {
        return Err(AppError::NotFound(format!(
            "run {id} has {pages} page(s) of responses, not {page}"
        )));
    }
    let offset = (page - 1).saturating_mul(RESPONSES_PER_PAGE);
    let rows = store::runs::item_page(&mut conn, run.id, offset, RESPONSES_PER_PAGE).await?;
    Ok(ResponsePage {
        run,
        rows,
        page,
        pages,
        total,
    })
}

/// A run's answers on their way out as model-output JSONL.
pub struct RunOutput {
    pub run: RunRow,
    /// The lines, a chunk of items at a time. A failure ends the stream with an error, so a
    /// reader sees a broken transfer rather than a short file that looks complete.
    pub chunks: mpsc::Receiver<Result<Bytes, std::io::Error>>,
}

/// Every answered item of run `id` as one line of ENACT's model-output JSONL, in dataset
/// order. Failed items are left out: they have no answer (ENACT would skip an empty one
/// anyway), and the hub's own scoring counts them as unanswered.
pub async fn output(hub: &Hub, id: i64, audience: Audience) -> Result<RunOutput, AppError> {
    let run = visible_run(hub, id, audience).await?;
    let (send, chunks) = mpsc::channel(2);
    let (hub, run_id) = (hub.clone(), run.id);
    tokio::spawn(async move {
        let mut after = 0;
        loop {
            let page = async {
                let mut conn = hub.conn().await?;
                Ok::<_, AppError>(
                    store::runs::answered_page(&mut conn, run_id, after, OUTPUT_CHUNK).await?,
                )
            }
            .await;
            let page = match page {
                Ok(page) => page,
                Err(e) => {
                    tracing::warn!(run = run_id, error = %e, "reading a run's answers failed");
                    let _ = send.send(Err(std::io::Error::other(e.to_string()))).await;
                    return;
                }
            };
            let Some((last, _, _)) = page.last() else {
                return;
            };
            after = *last;
            let mut chunk = String::new();
            for (_, item, answer) in &page {
                chunk.push_str(&model_output_line(item, answer));
                chunk.push('\n');
            }
            // The reader went away: nothing more to write.
            if send.send(Ok(Bytes::from(chunk))).await.is_err() {
                return;
            }
        }
    });
    Ok(RunOutput { run, chunks })
}
