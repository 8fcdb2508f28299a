//! Rows of model runs and of the items they asked.

use std::collections::HashMap;

use super::corrupt;
use super::db::{Conn, Dialect, Fields, WriteConn, on};
use super::items::json_column;

use enact_core::model_run::{ItemOutcome, RunFailure};
use enact_core::release::ReleaseItem;

use enact_core::credentials::{Caller, scopes_from_text};

/// A stored model run.
#[derive(Debug, Clone)]
pub struct RunRow {
    pub id: i64,
    pub name: String,
    pub dataset_id: i64,
    pub dataset: String,
    pub endpoint: String,
    pub model: String,
    /// JSON of the generation parameters.
    pub params: String,
    pub prompt_version: String,
    pub prompt_hash: String,
    pub token: i64,
    pub submission: Option<i64>,
    /// JSON, once submitted.
    pub stamp: Option<String>,
    pub created_by: String,
    pub created_at: String,
    /// The job the run was last started on the server with; `None` for a CLI-only run.
    pub job: Option<i64>,
}

const RUN_COLUMNS: &str = "r.id, r.name, r.dataset, d.name AS dataset_name, r.endpoint, r.model, \
    r.params, r.prompt_version, r.prompt_hash, r.token, r.submission, r.stamp, r.created_by, \
    r.created_at, r.job FROM model_runs r JOIN datasets d ON d.id = r.dataset";

fn run_from_row(row: &impl Fields) -> Result<RunRow, sqlx::Error> {
    Ok(RunRow {
        id: row.try_get("id")?,
        name: row.try_get("name")?,
        dataset_id: row.try_get("dataset")?,
        dataset: row.try_get("dataset_name")?,
        endpoint: row.try_get("endpoint")?,
        model: row.try_get("model")?,
        params: row.try_get("params")?,
        prompt_version: row.try_get("prompt_version")?,
        prompt_hash: row.try_get("prompt_hash")?,
        token: row.try_get("token")?,
        submission: row.try_get("submission")?,
        stamp: row.try_get("stamp")?,
        created_by: row.try_get("created_by")?,
        created_at: row.try_get("created_at")?,
        job: row.try_get("job")?,
    })
}

/// A run to store.
pub struct NewRun<'a> {
    pub name: &'a str,
    pub dataset: i64,
    pub endpoint: &'a str,
    pub model: &'a str,
    pub params: &'a str,
    pub prompt_version: &'a str,
    pub prompt_hash: &'a str,
    pub token: i64,
    pub created_by: &'a str,
}

/// Writes a run; `None` when its name is taken.
pub async fn insert(conn: &mut WriteConn, new: &NewRun<'_>) -> Result<Option<i64>, sqlx::Error> {
    on!(conn, |c| {
        let inserted = sqlx::query_scalar(
            "INSERT INTO model_runs (name, dataset, endpoint, model, params, prompt_version, \
             prompt_hash, token, created_by) VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9) \
             RETURNING id",
        )
        .bind(new.name)
        .bind(new.dataset)
        .bind(new.endpoint)
        .bind(new.model)
        .bind(new.params)
        .bind(new.prompt_version)
        .bind(new.prompt_hash)
        .bind(new.token)
        .bind(new.created_by)
        .fetch_one(&mut *c)
        .await;
        match inserted {
            Ok(id) => Ok(Some(id)),
            Err(sqlx::Error::Database(e)) if e.is_unique_violation() => Ok(None),
            Err(e) => Err(e),
        }
    })
}

pub async fn by_name(conn: &mut Conn, name: &str) -> Result<Option<RunRow>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(&format!("SELECT {RUN_COLUMNS} WHERE r.name = $1"))
            .bind(name)
            .fetch_optional(&mut *c)
            .await?;
        row.as_ref().map(run_from_row).transpose()
    })
}

pub async fn by_id(conn: &mut Conn, id: i64) -> Result<Option<RunRow>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(&format!("SELECT {RUN_COLUMNS} WHERE r.id = $1"))
            .bind(id)
            .fetch_optional(&mut *c)
            .await?;
        row.as_ref().map(run_from_row).transpose()
    })
}

/// The run whose answers went into `submission`.
pub async fn by_submission(
    conn: &mut Conn,
    submission: i64,
) -> Result<Option<RunRow>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(&format!("SELECT {RUN_COLUMNS} WHERE r.submission = $1"))
            .bind(submission)
            .fetch_optional(&mut *c)
            .await?;
        row.as_ref().map(run_from_row).transpose()
    })
}

/// Every run, newest first.
pub async fn list(conn: &mut Conn) -> Result<Vec<RunRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!("SELECT {RUN_COLUMNS} ORDER BY r.id DESC"))
            .fetch_all(&mut *c)
            .await?;
        rows.iter().map(run_from_row).collect()
    })
}

/// The runs of one dataset, newest first.
pub async fn of_dataset(conn: &mut Conn, dataset: i64) -> Result<Vec<RunRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "SELECT {RUN_COLUMNS} WHERE r.dataset = $1 ORDER BY r.id DESC"
        ))
        .bind(dataset)
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(run_from_row).collect()
    })
}

/// An item's outcome as its row's `state` and `failure` columns hold it.
fn outcome_columns(outcome: ItemOutcome) -> (&'static str, Option<String>) {
    match outcome {
        ItemOutcome::Answered => ("answered", None),
        ItemOutcome::Failed(failure) => ("failed", Some(failure.code())),
    }
}

/// The outcome a row's `state` and `failure` columns hold. A failed row without a kind was
/// written by a hub older than the column (an instance not yet upgraded beside this one).
fn outcome_of(state: &str, failure: Option<&str>) -> Result<ItemOutcome, sqlx::Error> {
    match (state, failure) {
        ("answered", _) => Ok(ItemOutcome::Answered),
        ("failed", None) => Ok(ItemOutcome::Failed(RunFailure::Unrecorded)),
        ("failed", Some(code)) => RunFailure::from_code(code)
            .map(ItemOutcome::Failed)
            .ok_or_else(|| {
                corrupt(
                    "failure",
                    format!("model_run_items.failure is {code:?}, not a failure's code"),
                )
            }),
        (other, _) => Err(corrupt(
            "state",
            format!("model_run_items.state is {other:?}, not answered or failed"),
        )),
    }
}

/// An item of the run's dataset in import order, with the state of its row when it has one.
#[derive(Debug, Clone)]
pub struct RunItemState {
    pub item_row: i64,
    pub item_id: String,
    /// `None` when never finished.
    pub state: Option<ItemOutcome>,
}

/// The first `limit` items of the run's dataset (all when `None`), in import order.
pub async fn item_states(
    conn: &mut Conn,
    run: i64,
    dataset: i64,
    limit: Option<i64>,
) -> Result<Vec<RunItemState>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT i.id, i.item_id, r.state, r.failure FROM items i \
             LEFT JOIN model_run_items r ON r.run = $1 AND r.item = i.id \
             WHERE i.dataset_id = $2 ORDER BY i.id LIMIT $3",
        )
        .bind(run)
        .bind(dataset)
        .bind(limit.unwrap_or(i64::MAX))
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|row| {
                let state: Option<String> = row.try_get("state")?;
                let failure: Option<String> = row.try_get("failure")?;
                Ok(RunItemState {
                    item_row: row.try_get("id")?,
                    item_id: row.try_get("item_id")?,
                    state: state
                        .as_deref()
                        .map(|state| outcome_of(state, failure.as_deref()))
                        .transpose()?,
                })
            })
            .collect()
    })
}

/// What a finished item's row holds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunItemRow {
    pub item_id: String,
    pub outcome: ItemOutcome,
    pub response: Option<String>,
    pub finish_reason: Option<String>,
    pub prompt_tokens: i64,
    pub completion_tokens: i64,
    pub latency_ms: i64,
    pub attempts: i64,
    pub error: Option<String>,
    pub done_at: String,
}

/// Writes (or, for a failed item asked again, replaces) an item's row.
pub async fn record_item(
    conn: &mut WriteConn,
    run: i64,
    item_row: i64,
    row: &RunItemRow,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        let query = format!(
            "INSERT INTO model_run_items (run, item, state, failure, response, finish_reason, \
             prompt_tokens, completion_tokens, latency_ms, attempts, error) \
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11) \
             ON CONFLICT (run, item) DO UPDATE SET state = excluded.state, \
             failure = excluded.failure, \
             response = excluded.response, finish_reason = excluded.finish_reason, \
             prompt_tokens = model_run_items.prompt_tokens + excluded.prompt_tokens, \
             completion_tokens = model_run_items.completion_tokens + excluded.completion_tokens, \
             latency_ms = excluded.latency_ms, \
             attempts = model_run_items.attempts + excluded.attempts, \
             error = excluded.error, done_at = {}",
            c.utc_now()
        );
        let (state, failure) = outcome_columns(row.outcome);
        sqlx::query(&query)
            .bind(run)
            .bind(item_row)
            .bind(state)
            .bind(failure)
            .bind(&row.response)
            .bind(&row.finish_reason)
            .bind(row.prompt_tokens)
            .bind(row.completion_tokens)
            .bind(row.latency_ms)
            .bind(row.attempts)
            .bind(&row.error)
            .execute(&mut *c)
            .await?;
        Ok(())
    })
}

/// Every finished item of a run, in import order.
pub async fn items(conn: &mut Conn, run: i64) -> Result<Vec<RunItemRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT i.item_id, r.state, r.failure, r.response, r.finish_reason, r.prompt_tokens, \
             r.completion_tokens, r.latency_ms, r.attempts, r.error, r.done_at \
             FROM model_run_items r JOIN items i ON i.id = r.item WHERE r.run = $1 ORDER BY i.id",
        )
        .bind(run)
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(item_from_row).collect()
    })
}

fn item_from_row(row: &impl Fields) -> Result<RunItemRow, sqlx::Error> {
    let state: String = row.try_get("state")?;
    let failure: Option<String> = row.try_get("failure")?;
    Ok(RunItemRow {
        item_id: row.try_get("item_id")?,
        outcome: outcome_of(&state, failure.as_deref())?,
        response: row.try_get("response")?,
        finish_reason: row.try_get("finish_reason")?,
        prompt_tokens: row.try_get("prompt_tokens")?,
        completion_tokens: row.try_get("completion_tokens")?,
        latency_ms: row.try_get("latency_ms")?,
        attempts: row.try_get("attempts")?,
        error: row.try_get("error")?,
        done_at: row.try_get("done_at")?,
    })
}

/// How many items of a run have a row (answered or failed).
pub async fn count_items(conn: &mut Conn, run: i64) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar("SELECT COUNT(*) FROM model_run_items WHERE run = $1")
            .bind(run)
            .fetch_one(&mut *c)
            .await
    })
}

/// One page of a run's finished items, in import order.
pub async fn item_page(
    conn: &mut Conn,
    run: i64,
    offset: i64,
    limit: i64,
) -> Result<Vec<RunItemRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT i.item_id, r.state, r.failure, r.response, r.finish_reason, r.prompt_tokens, \
             r.completion_tokens, r.latency_ms, r.attempts, r.error, r.done_at \
             FROM model_run_items r JOIN items i ON i.id = r.item WHERE r.run = $1 \
             ORDER BY i.id LIMIT $2 OFFSET $3",
        )
        .bind(run)
        .bind(limit)
        .bind(offset)
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(item_from_row).collect()
    })
}

/// Up to `limit` answered items of a run after item row `after`, in import order: each
/// item's row id, its release fields (ground truth included) and the model's raw answer.
pub async fn answered_page(
    conn: &mut Conn,
    run: i64,
    after: i64,
    limit: i64,
) -> Result<Vec<(i64, ReleaseItem, String)>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT i.id, i.item_id, i.item_type, i.task_name, i.key_frame_ids, i.question, \
             i.gt_answer, r.response FROM model_run_items r JOIN items i ON i.id = r.item \
             WHERE r.run = $1 AND r.state = 'answered' AND r.response IS NOT NULL AND i.id > $2 \
             ORDER BY i.id LIMIT $3",
        )
        .bind(run)
        .bind(after)
        .bind(limit)
        .fetch_all(&mut *c)
        .await?;
        let ids: Vec<i64> = rows
            .iter()
            .map(|row| row.try_get("id"))
            .collect::<Result<_, _>>()?;
        let mut paths: HashMap<i64, Vec<String>> = HashMap::new();
        if !ids.is_empty() {
            let ids = serde_json::to_string(&ids).map_err(|e| corrupt("item", e))?;
            let image_rows = sqlx::query(&format!(
                "SELECT item, path FROM item_images WHERE item IN ({}) ORDER BY item, position",
                c.json_ids()
            ))
            .bind(ids)
            .fetch_all(&mut *c)
            .await?;
            for row in &image_rows {
                paths
                    .entry(row.try_get("item")?)
                    .or_default()
                    .push(row.try_get("path")?);
            }
        }
        rows.iter()
            .map(|row| {
                let id: i64 = row.try_get("id")?;
                let item = ReleaseItem {
                    id: row.try_get("item_id")?,
                    item_type: row.try_get("item_type")?,
                    task_name: row.try_get("task_name")?,
                    key_frame_ids: json_column(row, "key_frame_ids")?,
                    images: paths.remove(&id).unwrap_or_default(),
                    question: row.try_get("question")?,
                    gt_answer: json_column(row, "gt_answer")?,
                };
                Ok((id, item, row.try_get("response")?))
            })
            .collect()
    })
}

/// Links a run to the job it was just started on the server with.
pub async fn set_job(conn: &mut WriteConn, run: i64, job: i64) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("UPDATE model_runs SET job = $1 WHERE id = $2")
            .bind(job)
            .bind(run)
            .execute(&mut *c)
            .await?;
        Ok(())
    })
}

/// Links a run to the submission its answers went into, with the stamp it was made with.
pub async fn set_submission(
    conn: &mut WriteConn,
    run: i64,
    submission: i64,
    stamp: &str,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("UPDATE model_runs SET submission = $1, stamp = $2 WHERE id = $3")
            .bind(submission)
            .bind(stamp)
            .bind(run)
            .execute(&mut *c)
            .await?;
        Ok(())
    })
}

/// The token with id `token`, with its account, revoked or not.
pub async fn token_caller(conn: &mut Conn, token: i64) -> Result<Option<Caller>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(
            "SELECT t.id, t.account, a.name, t.scopes, t.daily_quota, t.total_quota \
             FROM api_tokens t JOIN accounts a ON a.id = t.account WHERE t.id = $1",
        )
        .bind(token)
        .fetch_optional(&mut *c)
        .await?;
        row.map(|row| {
            let scopes: String = row.try_get("scopes")?;
            Ok(Caller {
                token_id: row.try_get("id")?,
                account_id: row.try_get("account")?,
                account_name: row.try_get("name")?,
                scopes: scopes_from_text(&scopes),
                daily_quota: row.try_get("daily_quota")?,
                total_quota: row.try_get("total_quota")?,
            })
        })
        .transpose()
    })
}

/// The oldest token of the account `account` (revoked or not).
pub async fn first_token_of(conn: &mut Conn, account: i64) -> Result<Option<i64>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar("SELECT id FROM api_tokens WHERE account = $1 ORDER BY id LIMIT 1")
            .bind(account)
            .fetch_optional(&mut *c)
            .await
    })
}
