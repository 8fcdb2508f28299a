//! One item, every answer: the truth, each leaderboard row's answer (the board's rows: each
//! account's latest published submission of a model) with its verdict and, for a wrong one,
//! why in the verifier's terms; then every annotator's answer. The item page and
//! `GET /api/v1/datasets/{d}/items/{id}/answers` show it; a dataset whose answers are hidden
//! shows it to admins only.

use schemars::JsonSchema;
use serde::Serialize;

use crate::core::annotation::human_verdict;
use crate::core::dataset::{AnswerVisibility, Direction, StepLength};
use crate::core::error_analysis::why::{AnswerWhy, why};
use crate::core::leaderboard::{RowSource, one_per_model};
use crate::core::submission::{AnswerVerdict, VerdictOutcome};
use crate::core::verifier::{ItemSignatures, Permutation};
use crate::store;

use super::refusal::Refusal;
use super::{AppError, Hub, datasets, items, leaderboard};

/// The item the answers are about.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct AnsweredItem {
    pub id: String,
    pub direction: Direction,
    pub step_length: StepLength,
    /// ENACT's `task_name`.
    pub activity: String,
}

/// A leaderboard row's answer.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ModelAnswer {
    pub model: String,
    pub account: String,
    pub submission: i64,
    pub baseline: bool,
    /// The `answer` value as submitted (JSON text); `None` when the item was not answered.
    pub answer: Option<String>,
    /// The order read from it, when it could be read.
    pub parsed: Option<Vec<u8>>,
    pub task_correct: bool,
    pub pairwise_accuracy: Option<f64>,
    pub verdict: AnswerVerdict,
    /// Why the answer could not be read.
    pub failure: Option<String>,
    /// For a wrong answer of the right length on an item with state changes: each step
    /// judged, in ENACT's sentences.
    pub why: Option<AnswerWhy>,
}

/// An annotator's answer.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct HumanAnswerView {
    /// The annotator's name for admins; for others "annotator 1", "annotator 2", … in the
    /// order the answers were given.
    pub annotator: String,
    pub answer: Vec<u8>,
    pub task_correct: bool,
    pub pairwise_accuracy: Option<f64>,
    pub verdict: AnswerVerdict,
    pub why: Option<AnswerWhy>,
    /// The annotator is excluded from the Human row on this dataset (shown to admins only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub excluded: Option<bool>,
    pub finished_at: String,
}

/// Every answer to one item.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ItemAnswers {
    pub dataset: String,
    pub item: AnsweredItem,
    /// The true order.
    pub truth: Vec<u8>,
    pub models: Vec<ModelAnswer>,
    pub humans: Vec<HumanAnswerView>,
    /// Whether the item is a gold item (admins only: annotators must not learn which are).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gold: Option<bool>,
}

/// Why `answer` is judged as it is, for a wrong one that can be explained.
fn explained(
    verdict: AnswerVerdict,
    direction: Direction,
    truth: &Permutation,
    answer: Option<&Permutation>,
    table: Option<&ItemSignatures>,
) -> Option<AnswerWhy> {
    if verdict != AnswerVerdict::Wrong {
        return None;
    }
    why(direction, truth, answer?, table?).ok()
}

/// Every answer to item `item_id` of dataset `dataset`. `admin`: the reader is an admin (names,
/// exclusions, gold, and hidden datasets).
pub async fn of(
    hub: &Hub,
    dataset: &str,
    item_id: &str,
    admin: bool,
) -> Result<ItemAnswers, AppError> {
    let stored = datasets::by_name(hub, dataset).await?;
    if !admin && datasets::answer_visibility(hub, &stored).await? != AnswerVisibility::Public {
        return Err(Refusal::AnswersHidden {
            dataset: stored.name,
        }
        .into());
    }
    let item = items::get(hub, &stored.name, item_id).await?;
    let truth = Permutation::new(item.gt_answer.clone())
        .map_err(|e| AppError::internal(format!("item {item_id}: stored gt_answer: {e}")))?;
    // The cached board: an item page must not rebuild the Human row.
    let board = one_per_model(&leaderboard::board(hub, &stored.name).await?.rows);
    let mut conn = hub.conn().await?;
    let table: Option<ItemSignatures> =
        match store::items::semantics_json(&mut conn, stored.id, item_id).await? {
            Some((_, json)) => Some(serde_json::from_str(&json).map_err(|e| {
                AppError::internal(format!("item {item_id}: stored signatures: {e}"))
            })?),
            None => None,
        };
    let verdicts = store::submissions::published_verdicts_of_item(&mut conn, item.rowid).await?;
    let human = store::annotations::answers_on_item(&mut conn, item.rowid).await?;
    let gold = if admin {
        Some(
            store::gold::gold_item_rowids(&mut conn, stored.id)
                .await?
                .contains(&item.rowid),
        )
    } else {
        None
    };
    drop(conn);
    let direction = item.summary.direction;

    let mut models = Vec::new();
    for row in board.iter().filter(|r| r.source == RowSource::Submission) {
        let Some((_, v)) = verdicts.iter().find(|(s, _)| Some(*s) == row.submission) else {
            continue;
        };
        let parsed: Option<Vec<u8>> = v
            .permutation
            .as_deref()
            .and_then(|p| serde_json::from_str(p).ok());
        let verdict = AnswerVerdict::of(v.outcome, v.exact_match, v.task_accuracy);
        let answer = parsed.clone().and_then(|p| Permutation::new(p).ok());
        models.push(ModelAnswer {
            model: row.model.clone(),
            account: row.account.clone(),
            submission: row.submission.unwrap_or_default(),
            baseline: row.baseline,
            answer: v.raw_answer.clone(),
            parsed,
            task_correct: v.task_accuracy,
            pairwise_accuracy: v.pairwise_accuracy,
            verdict,
            failure: v.failure.clone(),
            why: explained(verdict, direction, &truth, answer.as_ref(), table.as_ref()),
        });
    }

    let mut humans = Vec::new();
    for (n, a) in human.iter().enumerate() {
        // Answers finished before verdicts were stored are judged here.
        let judged = match a.answer.verdict {
            Some(v) => v,
            None => human_verdict(&a.answer.answer)
                .map_err(|e| AppError::internal(format!("item {item_id}: a stored answer: {e}")))?,
        };
        let verdict = AnswerVerdict::of(
            VerdictOutcome::Scored,
            judged.exact_match,
            judged.task_accuracy,
        );
        humans.push(HumanAnswerView {
            annotator: if admin {
                a.annotator_name.clone()
            } else {
                format!("annotator {}", n + 1)
            },
            answer: a.answer.answer.answer.labels().to_vec(),
            task_correct: judged.task_accuracy,
            pairwise_accuracy: judged.pairwise_accuracy,
            verdict,
            why: explained(
                verdict,
                direction,
                &truth,
                Some(&a.answer.answer.answer),
                table.as_ref(),
            ),
            excluded: admin.then_some(a.excluded),
            finished_at: a.finished_at.clone(),
        });
    }
    Ok(ItemAnswers {
        dataset: stored.name.clone(),
        item: AnsweredItem {
            id: item.summary.item_id.clone(),
            direction,
            step_length: item.summary.step_length,
            activity: item.summary.task_name.clone(),
        },
        truth: item.gt_answer.clone(),
        models,
        humans,
        gold,
    })
}
