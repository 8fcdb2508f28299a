//! Submissions, their per-item verdicts, and the per-dataset answer visibility.

use sqlx::QueryBuilder;

use super::db::{Conn, Dialect, Fields, WriteConn, on};

use super::{corrupt, kind_from_row};
use enact_core::dataset::{AnswerVisibility, Direction, StepLength};
use enact_core::submission::{
    ItemVerdict, Provenance, SubmissionMetadata, SubmissionScores, SubmissionStatus,
    VerdictOutcome, Visibility,
};
use enact_core::verifier::{ScoringPolicy, StrictOutcome};

pub async fn answer_visibility(
    conn: &mut Conn,
    dataset: i64,
) -> Result<AnswerVisibility, sqlx::Error> {
    on!(conn, |c| {
        let answers: Option<AnswerVisibility> =
            sqlx::query_scalar("SELECT answers FROM dataset_settings WHERE dataset = $1")
                .bind(dataset)
                .fetch_optional(&mut *c)
                .await?;
        // A dataset without a setting keeps its answers hidden.
        Ok(answers.unwrap_or(AnswerVisibility::Hidden))
    })
}

pub async fn set_answer_visibility(
    conn: &mut WriteConn,
    dataset: i64,
    answers: AnswerVisibility,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query(
            "INSERT INTO dataset_settings (dataset, answers) VALUES ($1, $2) \
         ON CONFLICT (dataset) DO UPDATE SET answers = excluded.answers",
        )
        .bind(dataset)
        .bind(answers)
        .execute(&mut *c)
        .await?;
        Ok(())
    })
}

/// A stored submission.
#[derive(Debug, Clone)]
pub struct SubmissionRow {
    pub id: i64,
    pub dataset_id: i64,
    pub dataset: String,
    pub account_id: i64,
    pub account: String,
    pub model: String,
    pub description: String,
    pub url: String,
    pub prompt_version: String,
    pub notes: String,
    pub policy: ScoringPolicy,
    pub status: SubmissionStatus,
    pub visibility: Visibility,
    pub baseline: bool,
    pub scores: SubmissionScores,
    pub created_at: String,
    pub body_sha256: String,
    /// The metric version its scores, verdicts and kept error analysis were computed with.
    pub metric_version: u32,
    /// The build that computed its scores (empty: before builds were recorded).
    pub scored_by: String,
    /// Whether the hub asked the model itself (`Run`) or was handed the answers.
    pub provenance: Provenance,
    /// The model run that filed it (the row's link to the run's stamp).
    pub run: Option<i64>,
}

const SUBMISSION_COLUMNS: &str = "s.id, s.dataset, d.name AS dataset_name, s.account, \
    a.name AS account_name, s.model, s.description, s.url, s.prompt_version, s.notes, s.policy, \
    s.status, s.visibility, s.baseline, s.scores, s.created_at, s.body_sha256, \
    s.metric_version, s.scored_by, s.provenance, \
    (SELECT min(r.id) FROM model_runs r WHERE r.submission = s.id) AS run_id \
    FROM submissions s JOIN datasets d ON d.id = s.dataset JOIN accounts a ON a.id = s.account";

fn submission_from_row(row: &impl Fields) -> Result<SubmissionRow, sqlx::Error> {
    let id: i64 = row.try_get("id")?;
    let scores: String = row.try_get("scores")?;
    let scores = serde_json::from_str(&scores).map_err(|e| {
        corrupt(
            "scores",
            format!("submission {id}: stored scores unreadable: {e}"),
        )
    })?;
    Ok(SubmissionRow {
        id,
        dataset_id: row.try_get("dataset")?,
        dataset: row.try_get("dataset_name")?,
        account_id: row.try_get("account")?,
        account: row.try_get("account_name")?,
        model: row.try_get("model")?,
        description: row.try_get("description")?,
        url: row.try_get("url")?,
        prompt_version: row.try_get("prompt_version")?,
        notes: row.try_get("notes")?,
        policy: row.try_get("policy")?,
        status: row.try_get("status")?,
        visibility: row.try_get("visibility")?,
        baseline: row.try_get("baseline")?,
        scores,
        created_at: row.try_get("created_at")?,
        body_sha256: row.try_get("body_sha256")?,
        metric_version: version_column(row, "metric_version")?,
        scored_by: row.try_get("scored_by")?,
        provenance: row.try_get("provenance")?,
        run: row.try_get("run_id")?,
    })
}

/// A metric version column (a 64-bit integer in the store).
pub fn version_column(row: &impl Fields, column: &str) -> Result<u32, sqlx::Error> {
    let version: i64 = row.try_get(column)?;
    u32::try_from(version).map_err(|e| corrupt(column, e))
}

pub async fn by_id(conn: &mut Conn, id: i64) -> Result<Option<SubmissionRow>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(&format!("SELECT {SUBMISSION_COLUMNS} WHERE s.id = $1"))
            .bind(id)
            .fetch_optional(&mut *c)
            .await?;
        row.as_ref().map(submission_from_row).transpose()
    })
}

pub async fn by_idempotency_key(
    conn: &mut Conn,
    token: i64,
    key: &str,
) -> Result<Option<SubmissionRow>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(&format!(
            "SELECT {SUBMISSION_COLUMNS} WHERE s.token = $1 AND s.idempotency_key = $2"
        ))
        .bind(token)
        .bind(key)
        .fetch_optional(&mut *c)
        .await?;
        row.as_ref().map(submission_from_row).transpose()
    })
}

/// Published submissions of a dataset, oldest first.
pub async fn published(conn: &mut Conn, dataset: i64) -> Result<Vec<SubmissionRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "SELECT {SUBMISSION_COLUMNS} WHERE s.dataset = $1 AND s.visibility = 'published' \
         ORDER BY s.id"
        ))
        .bind(dataset)
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(submission_from_row).collect()
    })
}

/// Everything a new submission row needs.
pub struct NewSubmission<'a> {
    pub dataset: i64,
    pub account: i64,
    pub token: i64,
    pub idempotency_key: Option<&'a str>,
    pub body_sha256: &'a str,
    pub metadata: &'a SubmissionMetadata,
    pub scores: &'a SubmissionScores,
    /// The metric version `scores` were computed with.
    pub metric_version: u32,
    /// The build computing them.
    pub scored_by: &'a str,
    pub provenance: Provenance,
}

/// Inserts the submission; call inside the transaction that also stores its items. An
/// Idempotency-Key this token already used refuses the insert with a violation of
/// [`UniqueKey::SUBMISSION_IDEMPOTENCY_KEY`](super::db::UniqueKey::SUBMISSION_IDEMPOTENCY_KEY).
#[tracing::instrument(skip_all)]
pub async fn insert(conn: &mut WriteConn, new: &NewSubmission<'_>) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        let scores = serde_json::to_string(new.scores).map_err(|e| corrupt("scores", e))?;
        sqlx::query_scalar(
            "INSERT INTO submissions (dataset, account, token, idempotency_key, body_sha256, \
             model, description, url, prompt_version, notes, scores, metric_version, scored_by, \
             provenance) \
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14) RETURNING id",
        )
        .bind(new.dataset)
        .bind(new.account)
        .bind(new.token)
        .bind(new.idempotency_key)
        .bind(new.body_sha256)
        .bind(&new.metadata.model)
        .bind(&new.metadata.description)
        .bind(&new.metadata.url)
        .bind(&new.metadata.prompt_version)
        .bind(&new.metadata.notes)
        .bind(scores)
        .bind(i64::from(new.metric_version))
        .bind(new.scored_by)
        .bind(new.provenance)
        .fetch_one(&mut *c)
        .await
    })
}

/// Rows per INSERT: 11 bound values each, under SQLite's 32766-variable limit.
const ITEM_ROWS_PER_STATEMENT: usize = 2500;

/// Stores every item verdict; `item_rows[v.target]` is the `items` row id of verdict `v`.
#[tracing::instrument(skip_all)]
pub async fn insert_items(
    conn: &mut WriteConn,
    submission: i64,
    item_rows: &[i64],
    verdicts: &[ItemVerdict],
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        for chunk in verdicts.chunks(ITEM_ROWS_PER_STATEMENT) {
            let mut builder = QueryBuilder::new(
                "INSERT INTO submission_items (submission, item, line, raw_answer, permutation, \
             outcome, failure, exact_match, semantic_match, task_accuracy, pairwise_accuracy) ",
            );
            builder.push_values(chunk, |mut b, v| {
                let (permutation, failure, exact, semantic) = match &v.outcome {
                    StrictOutcome::Scored { answer, verdict } => (
                        serde_json::to_string(answer).ok(),
                        None,
                        verdict.exact_match,
                        verdict.semantic_match,
                    ),
                    StrictOutcome::Unparseable { reason } => {
                        (None, Some(reason.to_string()), false, false)
                    }
                    StrictOutcome::Missing => (None, None, false, false),
                };
                b.push_bind(submission)
                    .push_bind(item_rows.get(v.target).copied())
                    .push_bind(v.line.map(|l| l as i64))
                    .push_bind(v.raw_answer.clone())
                    .push_bind(permutation)
                    .push_bind(VerdictOutcome::of(&v.outcome))
                    .push_bind(failure)
                    .push_bind(exact)
                    .push_bind(semantic)
                    .push_bind(v.task_accuracy)
                    .push_bind(v.pairwise_accuracy);
            });
            builder.build().execute(&mut *c).await?;
        }
        Ok(())
    })
}

/// One stored verdict, with the item it is about.
#[derive(Debug, Clone)]
pub struct StoredVerdict {
    pub id: String,
    pub direction: Direction,
    pub step_length: StepLength,
    pub line: Option<i64>,
    pub raw_answer: Option<String>,
    pub permutation: Option<String>,
    pub outcome: VerdictOutcome,
    pub failure: Option<String>,
    pub exact_match: bool,
    pub semantic_match: bool,
    pub task_accuracy: bool,
    pub pairwise_accuracy: Option<f64>,
    pub gt_answer: String,
}

const VERDICT_COLUMNS: &str = "i.item_id, i.direction, i.step_length, i.gt_answer, v.line, \
    v.raw_answer, v.permutation, v.outcome, v.failure, v.exact_match, v.semantic_match, \
    v.task_accuracy, v.pairwise_accuracy";

fn verdict_from_row(row: &impl Fields) -> Result<StoredVerdict, sqlx::Error> {
    let (direction, step_length) = kind_from_row(row)?;
    Ok(StoredVerdict {
        id: row.try_get("item_id")?,
        direction,
        step_length,
        line: row.try_get("line")?,
        raw_answer: row.try_get("raw_answer")?,
        permutation: row.try_get("permutation")?,
        outcome: row.try_get("outcome")?,
        failure: row.try_get("failure")?,
        exact_match: row.try_get("exact_match")?,
        semantic_match: row.try_get("semantic_match")?,
        task_accuracy: row.try_get("task_accuracy")?,
        pairwise_accuracy: row.try_get("pairwise_accuracy")?,
        gt_answer: row.try_get("gt_answer")?,
    })
}

pub async fn verdicts(conn: &mut Conn, submission: i64) -> Result<Vec<StoredVerdict>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "SELECT {VERDICT_COLUMNS} FROM submission_items v JOIN items i ON i.id = v.item \
             WHERE v.submission = $1 ORDER BY i.id"
        ))
        .bind(submission)
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(verdict_from_row).collect()
    })
}

/// The verdicts every published submission of the item's dataset has for the item (row id
/// `item`), by submission id. Each is one lookup of the verdicts' key (submission, item).
pub async fn published_verdicts_of_item(
    conn: &mut Conn,
    item: i64,
) -> Result<Vec<(i64, StoredVerdict)>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "SELECT v.submission, {VERDICT_COLUMNS} FROM items i \
             JOIN submissions s ON s.dataset = i.dataset_id AND s.visibility = 'published' \
             JOIN submission_items v ON v.submission = s.id AND v.item = i.id \
             WHERE i.id = $1 ORDER BY s.id"
        ))
        .bind(item)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|row| Ok((row.try_get("submission")?, verdict_from_row(row)?)))
            .collect()
    })
}

/// What the explorer's grid keeps of one verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VerdictCell {
    pub submission: i64,
    /// The `items` row id.
    pub item: i64,
    pub outcome: VerdictOutcome,
    pub exact_match: bool,
    pub task_accuracy: bool,
}

/// Every verdict of these submissions, in one query (one snapshot), in no particular order.
/// A full-size grid is some 270,000 of them: read by position into tuples rather than by
/// column name, and not sorted.
#[tracing::instrument(skip_all)]
pub async fn verdict_cells(
    conn: &mut Conn,
    submissions: &[i64],
) -> Result<Vec<VerdictCell>, sqlx::Error> {
    on!(conn, |c| {
        let ids = serde_json::to_string(submissions).map_err(|e| corrupt("submission", e))?;
        let rows: Vec<(i64, i64, VerdictOutcome, bool, bool)> = sqlx::query_as(&format!(
            "SELECT v.submission, v.item, v.outcome, v.exact_match, v.task_accuracy \
             FROM submission_items v WHERE v.submission IN ({})",
            c.json_ids()
        ))
        .bind(ids)
        .fetch_all(&mut *c)
        .await?;
        Ok(rows
            .into_iter()
            .map(
                |(submission, item, outcome, exact_match, task_accuracy)| VerdictCell {
                    submission,
                    item,
                    outcome,
                    exact_match,
                    task_accuracy,
                },
            )
            .collect())
    })
}

/// Admin changes to a leaderboard row. Returns whether the submission exists.
#[tracing::instrument(skip_all)]
pub async fn update_listing(
    conn: &mut WriteConn,
    id: i64,
    baseline: Option<bool>,
    visibility: Option<Visibility>,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query(
            "UPDATE submissions SET baseline = coalesce($1, baseline), \
         visibility = coalesce($2, visibility) WHERE id = $3",
        )
        .bind(baseline)
        .bind(visibility)
        .bind(id)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() > 0)
    })
}

/// Whether `account` has ever submitted `model` to the dataset, listed or not.
pub async fn has_submitted(
    conn: &mut Conn,
    dataset: i64,
    account: &str,
    model: &str,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let found: Option<i64> = sqlx::query_scalar(
            "SELECT s.id FROM submissions s JOIN accounts a ON a.id = s.account \
         WHERE s.dataset = $1 AND a.name = $2 AND s.model = $3 LIMIT 1",
        )
        .bind(dataset)
        .bind(account)
        .bind(model)
        .fetch_optional(&mut *c)
        .await?;
        Ok(found.is_some())
    })
}

/// Counts used by tests and reports: submissions and verdict rows stored.
pub async fn counts(conn: &mut Conn) -> Result<(i64, i64), sqlx::Error> {
    on!(conn, |c| {
        let submissions: i64 = sqlx::query_scalar("SELECT count(*) FROM submissions")
            .fetch_one(&mut *c)
            .await?;
        let items: i64 = sqlx::query_scalar("SELECT count(*) FROM submission_items")
            .fetch_one(&mut *c)
            .await?;
        Ok((submissions, items))
    })
}

/// The stored error analysis of a submission (JSON), if one was computed.
pub async fn error_analysis(
    conn: &mut Conn,
    submission: i64,
) -> Result<Option<String>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar("SELECT error_analysis FROM submissions WHERE id = $1")
            .bind(submission)
            .fetch_optional(&mut *c)
            .await
            .map(Option::flatten)
    })
}

/// Keeps a submission's error analysis (JSON).
pub async fn set_error_analysis(
    conn: &mut WriteConn,
    submission: i64,
    json: &str,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("UPDATE submissions SET error_analysis = $1 WHERE id = $2")
            .bind(json)
            .bind(submission)
            .execute(&mut *c)
            .await
            .map(|_| ())
    })
}

/// Forgets the stored error analyses of a dataset's submissions (its items or signatures
/// changed); they are computed again on the next request.
pub async fn clear_error_analyses(conn: &mut WriteConn, dataset: i64) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("UPDATE submissions SET error_analysis = NULL WHERE dataset = $1")
            .bind(dataset)
            .execute(&mut *c)
            .await
            .map(|_| ())
    })
}

/// Ids of a dataset's submissions (listed or not) whose scores were computed with a metric
/// version below `version`, oldest first.
pub async fn below_version(
    conn: &mut Conn,
    dataset: i64,
    version: u32,
) -> Result<Vec<i64>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
            "SELECT id FROM submissions WHERE dataset = $1 AND metric_version < $2 ORDER BY id",
        )
        .bind(dataset)
        .bind(i64::from(version))
        .fetch_all(&mut *c)
        .await
    })
}

/// Replaces a submission's scores and every verdict row with ones computed under metric
/// `version`, and forgets its kept error analysis; only while the stored version is below
/// `version` (`Ok(false)` otherwise, and nothing is written). Call inside a transaction;
/// `item_rows[v.target]` is the `items` row id of verdict `v`.
#[tracing::instrument(skip_all)]
pub async fn replace_scores(
    conn: &mut WriteConn,
    submission: i64,
    scores: &SubmissionScores,
    version: u32,
    scored_by: &str,
    item_rows: &[i64],
    verdicts: &[ItemVerdict],
) -> Result<bool, sqlx::Error> {
    let json = serde_json::to_string(scores).map_err(|e| corrupt("scores", e))?;
    let updated = on!(conn, |c| {
        sqlx::query(
            "UPDATE submissions SET scores = $1, metric_version = $2, error_analysis = NULL, \
             scored_by = $4 WHERE id = $3 AND metric_version < $2",
        )
        .bind(json)
        .bind(i64::from(version))
        .bind(submission)
        .bind(scored_by)
        .execute(&mut *c)
        .await?
        .rows_affected()
    });
    if updated == 0 {
        return Ok(false);
    }
    on!(conn, |c| {
        sqlx::query("DELETE FROM submission_items WHERE submission = $1")
            .bind(submission)
            .execute(&mut *c)
            .await?;
    });
    insert_items(conn, submission, item_rows, verdicts).await?;
    Ok(true)
}

/// The stored scores of a submission as JSON text, exactly as kept.
pub async fn scores_json(conn: &mut Conn, submission: i64) -> Result<Option<String>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar("SELECT scores FROM submissions WHERE id = $1")
            .bind(submission)
            .fetch_optional(&mut *c)
            .await
    })
}
