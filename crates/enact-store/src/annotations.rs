//! Annotators, their sessions, assignments, drafts and finished annotations; and the human
//! performance report built from the answers.

use super::db::{Conn, Fields, WriteConn, on};

use super::{corrupt, kind_from_row};

use enact_core::annotation::{
    AssignmentState, CountedAnswer, CountedVerdict, Draft, HumanAnswer, HumanVerdict, Outcome,
    OutcomeKind, Session, SplitItem, StoredDraft, Telemetry,
};
use enact_core::dataset::{Direction, StepLength};
use enact_core::quality::FinishedItem;
use enact_core::verifier::Permutation;

#[derive(Debug, Clone)]
pub struct Annotator {
    pub id: i64,
    pub name: String,
    pub is_admin: bool,
    /// False until the invite has been used to set a password.
    pub active: bool,
    pub created_at: String,
}

fn annotator_from_row(row: &impl Fields) -> Result<Annotator, sqlx::Error> {
    Ok(Annotator {
        id: row.try_get("id")?,
        name: row.try_get("name")?,
        is_admin: row.try_get("is_admin")?,
        active: row.try_get::<Option<String>>("password_hash")?.is_some(),
        created_at: row.try_get("created_at")?,
    })
}

const ANNOTATOR_COLUMNS: &str = "id, name, is_admin, password_hash, created_at";

/// Creates an annotator with a pending invite (`invite_hash` = sha256 of the invite token).
/// A name in use refuses the insert with a violation of
/// [`UniqueKey::ANNOTATOR_NAME`](super::db::UniqueKey::ANNOTATOR_NAME).
pub async fn create_annotator(
    conn: &mut WriteConn,
    name: &str,
    is_admin: bool,
    invite_hash: &str,
) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
            "INSERT INTO annotators (name, is_admin, invite_hash) VALUES ($1, $2, $3) RETURNING id",
        )
        .bind(name)
        .bind(is_admin)
        .bind(invite_hash)
        .fetch_one(&mut *c)
        .await
    })
}

/// Replaces an annotator's invite (the old link stops working).
pub async fn renew_invite(
    conn: &mut WriteConn,
    annotator: i64,
    invite_hash: &str,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query("UPDATE annotators SET invite_hash = $1 WHERE id = $2")
            .bind(invite_hash)
            .bind(annotator)
            .execute(&mut *c)
            .await?;
        Ok(done.rows_affected() == 1)
    })
}

pub async fn annotators(conn: &mut Conn) -> Result<Vec<Annotator>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "SELECT {ANNOTATOR_COLUMNS} FROM annotators ORDER BY name"
        ))
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(annotator_from_row).collect()
    })
}

pub async fn annotator_by_invite(
    conn: &mut Conn,
    invite_hash: &str,
) -> Result<Option<Annotator>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(&format!(
            "SELECT {ANNOTATOR_COLUMNS} FROM annotators WHERE invite_hash = $1"
        ))
        .bind(invite_hash)
        .fetch_optional(&mut *c)
        .await?;
        row.as_ref().map(annotator_from_row).transpose()
    })
}

/// Sets the password and consumes the invite, if the invite is still valid.
pub async fn accept_invite(
    conn: &mut WriteConn,
    invite_hash: &str,
    password_hash: &str,
) -> Result<Option<i64>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
            "UPDATE annotators SET password_hash = $1, invite_hash = NULL WHERE invite_hash = $2 \
         RETURNING id",
        )
        .bind(password_hash)
        .bind(invite_hash)
        .fetch_optional(&mut *c)
        .await
    })
}

/// `(annotator, password hash)` of an account that has set its password.
pub async fn credentials(
    conn: &mut Conn,
    name: &str,
) -> Result<Option<(i64, String)>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(
        "SELECT id, password_hash FROM annotators WHERE name = $1 AND password_hash IS NOT NULL",
    )
    .bind(name)
    .fetch_optional(&mut *c)
    .await?;
        row.map(|r| Ok((r.try_get("id")?, r.try_get("password_hash")?)))
            .transpose()
    })
}

pub async fn create_session(
    conn: &mut WriteConn,
    token_hash: &str,
    annotator: i64,
    csrf_token: &str,
    expires_at_ms: i64,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query(
        "INSERT INTO sessions (token_hash, annotator, csrf_token, expires_at_ms) VALUES ($1, $2, $3, $4)",
    )
    .bind(token_hash)
    .bind(annotator)
    .bind(csrf_token)
    .bind(expires_at_ms)
    .execute(&mut *c)
    .await?;
        Ok(())
    })
}

/// The unexpired session with this token hash, and when it expires.
pub async fn session(
    conn: &mut Conn,
    token_hash: &str,
    now_ms: i64,
) -> Result<Option<(Session, i64)>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(
            "SELECT s.annotator, s.csrf_token, s.expires_at_ms, a.name, a.is_admin FROM sessions s \
         JOIN annotators a ON a.id = s.annotator WHERE s.token_hash = $1 AND s.expires_at_ms > $2",
        )
        .bind(token_hash)
        .bind(now_ms)
        .fetch_optional(&mut *c)
        .await?;
        row.map(|r| {
            Ok((
                Session {
                    annotator: r.try_get("annotator")?,
                    name: r.try_get("name")?,
                    is_admin: r.try_get("is_admin")?,
                    csrf_token: r.try_get("csrf_token")?,
                },
                r.try_get("expires_at_ms")?,
            ))
        })
        .transpose()
    })
}

/// Ends a session, and any expired ones while at it.
pub async fn delete_session(
    conn: &mut WriteConn,
    token_hash: &str,
    now_ms: i64,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("DELETE FROM sessions WHERE token_hash = $1 OR expires_at_ms <= $2")
            .bind(token_hash)
            .bind(now_ms)
            .execute(&mut *c)
            .await?;
        Ok(())
    })
}

/// Saves the locale of the annotator whose unexpired session hashes to `token_hash`; false
/// when there is no such session.
pub async fn set_locale_by_session(
    conn: &mut WriteConn,
    token_hash: &str,
    locale: &str,
    now_ms: i64,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query(
            "UPDATE annotators SET locale = $1 WHERE id = \
             (SELECT annotator FROM sessions WHERE token_hash = $2 AND expires_at_ms > $3)",
        )
        .bind(locale)
        .bind(token_hash)
        .bind(now_ms)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() > 0)
    })
}

/// The locale an annotator saved, if any.
pub async fn locale(conn: &mut Conn, annotator: i64) -> Result<Option<String>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query("SELECT locale FROM annotators WHERE id = $1")
            .bind(annotator)
            .fetch_optional(&mut *c)
            .await?;
        Ok(row
            .map(|r| r.try_get::<Option<String>>("locale"))
            .transpose()?
            .flatten())
    })
}

/// Every item of a dataset with its kind, in id order.
pub async fn dataset_items(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<SplitItem>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
        "SELECT i.id, i.direction, i.step_length FROM items i WHERE i.dataset_id = $1 ORDER BY i.id",
    )
    .bind(dataset_id)
    .fetch_all(&mut *c)
    .await?;
        rows.iter().map(split_item_from_row).collect()
    })
}

fn split_item_from_row(r: &impl Fields) -> Result<SplitItem, sqlx::Error> {
    let (direction, step_length) = kind_from_row(r)?;
    Ok(SplitItem {
        item: r.try_get("id")?,
        direction,
        step_length,
    })
}

/// Store ids and kinds of a dataset's items that no annotator has yet and that are not gold
/// (the gold mix hands those out), in import order.
pub async fn unassigned_items(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<SplitItem>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT i.id, i.direction, i.step_length FROM items i WHERE i.dataset_id = $1 \
         AND NOT EXISTS (SELECT 1 FROM assignments a WHERE a.item = i.id) \
         AND NOT EXISTS (SELECT 1 FROM gold_items g WHERE g.item = i.id) \
         AND NOT EXISTS (SELECT 1 FROM attention_items t WHERE t.item = i.id) ORDER BY i.id",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(split_item_from_row).collect()
    })
}

/// Store ids of the given item ids of a dataset, in the same order; `None` for an id not in
/// the dataset.
pub async fn item_rowids(
    conn: &mut Conn,
    dataset_id: i64,
    item_ids: &[String],
) -> Result<Vec<Option<i64>>, sqlx::Error> {
    on!(conn, |c| {
        let mut found = Vec::with_capacity(item_ids.len());
        for id in item_ids {
            found.push(
                sqlx::query_scalar("SELECT id FROM items WHERE dataset_id = $1 AND item_id = $2")
                    .bind(dataset_id)
                    .bind(id)
                    .fetch_optional(&mut *c)
                    .await?,
            );
        }
        Ok(found)
    })
}

/// Appends `(annotator, item)` pairs to the annotators' queues; pairs already assigned are
/// left as they are. Returns how many were new. Call inside a transaction.
pub async fn assign(conn: &mut WriteConn, pairs: &[(i64, i64)]) -> Result<u64, sqlx::Error> {
    on!(conn, |c| {
        let mut added = 0;
        for &(annotator, item) in pairs {
            let done = sqlx::query(
                "INSERT INTO assignments (annotator, item, position) \
             SELECT $1, $2, coalesce(max(position), 0) + 1 FROM assignments WHERE annotator = $1 \
             ON CONFLICT (annotator, item) DO NOTHING",
            )
            .bind(annotator)
            .bind(item)
            .execute(&mut *c)
            .await?;
            added += done.rows_affected();
        }
        Ok(added)
    })
}

/// One assigned item of an annotator's queue: how it was finished, if it was, and whether a
/// draft of it exists.
#[derive(Debug, Clone)]
pub struct QueuedItem {
    pub dataset: String,
    pub item_id: String,
    pub direction: Direction,
    pub step_length: StepLength,
    pub finished: Option<OutcomeKind>,
    pub started: bool,
    /// The gold set's rate when the gold mix put this gold item in the queue.
    pub gold_rate: Option<i64>,
    /// The attention checks' rate when their mix put this check in the queue.
    pub attention_rate: Option<i64>,
}

/// An annotator's assigned items in queue order.
pub async fn queue(conn: &mut Conn, annotator: i64) -> Result<Vec<QueuedItem>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT d.name AS dataset, i.item_id, i.direction, i.step_length, n.outcome, \
         (dr.item IS NOT NULL) AS started, \
         CASE WHEN a.gold = $2 THEN gs.rate END AS gold_rate, \
         CASE WHEN a.attention = $2 THEN ts.rate END AS attention_rate \
         FROM assignments a JOIN items i ON i.id = a.item JOIN datasets d ON d.id = i.dataset_id \
         LEFT JOIN annotations n ON n.annotator = a.annotator AND n.item = a.item \
         LEFT JOIN drafts dr ON dr.annotator = a.annotator AND dr.item = a.item \
         LEFT JOIN gold_items gi ON gi.item = a.item \
         LEFT JOIN gold_sets gs ON gs.dataset = gi.dataset \
         LEFT JOIN attention_items ti ON ti.item = a.item \
         LEFT JOIN attention_sets ts ON ts.dataset = ti.dataset \
         WHERE a.annotator = $1 ORDER BY a.position",
        )
        .bind(annotator)
        .bind(true)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|r| {
                let (direction, step_length) = kind_from_row(r)?;
                Ok(QueuedItem {
                    dataset: r.try_get("dataset")?,
                    item_id: r.try_get("item_id")?,
                    direction,
                    step_length,
                    finished: r.try_get("outcome")?,
                    started: r.try_get("started")?,
                    gold_rate: r.try_get("gold_rate")?,
                    attention_rate: r.try_get("attention_rate")?,
                })
            })
            .collect()
    })
}

/// The annotator's standing on `item` in one query (the item page's hot path), or `None` when
/// the item is not assigned to them.
pub async fn assignment_state(
    conn: &mut Conn,
    annotator: i64,
    item: i64,
) -> Result<Option<AssignmentState>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(
            "SELECT (n.item IS NOT NULL) AS finished, d.state, d.started_at_ms, \
         d.first_placement_at_ms FROM assignments a \
         LEFT JOIN annotations n ON n.annotator = a.annotator AND n.item = a.item \
         LEFT JOIN drafts d ON d.annotator = a.annotator AND d.item = a.item \
         WHERE a.annotator = $1 AND a.item = $2",
        )
        .bind(annotator)
        .bind(item)
        .fetch_optional(&mut *c)
        .await?;
        row.map(|r| {
            let has_draft = r.try_get::<Option<String>>("state")?.is_some();
            Ok(AssignmentState {
                finished: r.try_get("finished")?,
                draft: if has_draft {
                    Some(stored_draft(&r)?)
                } else {
                    None
                },
            })
        })
        .transpose()
    })
}

/// Creates an empty draft of an item (which starts the item's clock) unless the item is
/// finished or already has a draft: the check and the write are one statement, so a draft
/// can never outlive the answer that finished its item. Returns whether it was created.
pub async fn create_draft(
    conn: &mut WriteConn,
    annotator: i64,
    item: i64,
    empty: &Draft,
    now_ms: i64,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let json = serde_json::to_string(empty).map_err(|e| corrupt("state", e))?;
        let done = sqlx::query(
            "INSERT INTO drafts (annotator, item, slots, state, started_at_ms, updated_at_ms) \
         SELECT $1, $2, '[]', $3, $4, $4 WHERE NOT EXISTS \
         (SELECT 1 FROM annotations WHERE annotator = $1 AND item = $2) \
         ON CONFLICT (annotator, item) DO NOTHING",
        )
        .bind(annotator)
        .bind(item)
        .bind(json)
        .bind(now_ms)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() > 0)
    })
}

pub async fn draft(
    conn: &mut Conn,
    annotator: i64,
    item: i64,
) -> Result<Option<StoredDraft>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(
            "SELECT state, started_at_ms, first_placement_at_ms FROM drafts \
         WHERE annotator = $1 AND item = $2",
        )
        .bind(annotator)
        .bind(item)
        .fetch_optional(&mut *c)
        .await?;
        row.as_ref().map(stored_draft).transpose()
    })
}

/// Reads a draft from a row holding `state`, `started_at_ms` and `first_placement_at_ms`.
fn stored_draft(r: &impl Fields) -> Result<StoredDraft, sqlx::Error> {
    let state: String = r.try_get("state")?;
    Ok(StoredDraft {
        draft: serde_json::from_str(&state).map_err(|e| corrupt("state", e))?,
        started_at_ms: r.try_get("started_at_ms")?,
        first_placement_at_ms: r.try_get("first_placement_at_ms")?,
    })
}

/// Saves a draft; the first save with a card placed records the time of the first placement.
/// `Ok(false)` when the item is finished: the check and the write are one statement, so a
/// draft can never outlive the answer that finished its item.
pub async fn save_draft(
    conn: &mut WriteConn,
    annotator: i64,
    item: i64,
    draft: &Draft,
    now_ms: i64,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let state = serde_json::to_string(draft).map_err(|e| corrupt("state", e))?;
        let slots = serde_json::to_string(&draft.slots).map_err(|e| corrupt("slots", e))?;
        let done = sqlx::query(
        "INSERT INTO drafts (annotator, item, slots, state, started_at_ms, first_placement_at_ms, \
         updated_at_ms) SELECT $1, $2, $3, $4, $5, CASE WHEN $6 THEN $5 END, $5 \
         WHERE NOT EXISTS (SELECT 1 FROM annotations WHERE annotator = $1 AND item = $2) \
         ON CONFLICT (annotator, item) DO UPDATE SET slots = excluded.slots, \
         state = excluded.state, updated_at_ms = excluded.updated_at_ms, \
         first_placement_at_ms = coalesce(drafts.first_placement_at_ms, \
             excluded.first_placement_at_ms)",
    )
    .bind(annotator)
    .bind(item)
    .bind(slots)
    .bind(state)
    .bind(now_ms)
    .bind(draft.has_placement())
    .execute(&mut *c)
    .await?;
        Ok(done.rows_affected() > 0)
    })
}

/// Records a finished item and drops its draft. `Ok(false)` if it was already finished.
pub async fn finish(
    conn: &mut WriteConn,
    annotator: i64,
    item: i64,
    outcome: &Outcome,
    telemetry: &Telemetry,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let (answer, reason) = match outcome {
            Outcome::Answered(p) => (
                Some(serde_json::to_string(p).map_err(|e| corrupt("answer", e))?),
                "",
            ),
            Outcome::Skipped(r) | Outcome::Flagged(r) => (None, r.as_str()),
        };
        let done = sqlx::query(
        "INSERT INTO annotations (annotator, item, outcome, answer, reason, time_on_item_ms, \
         time_to_first_placement_ms, placements, swaps, clears, undos) \
         VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11) ON CONFLICT (annotator, item) DO NOTHING",
    )
    .bind(annotator)
    .bind(item)
    .bind(outcome.kind())
    .bind(answer)
    .bind(reason)
    .bind(telemetry.time_on_item_ms)
    .bind(telemetry.time_to_first_placement_ms)
    .bind(i64::from(telemetry.placements))
    .bind(i64::from(telemetry.swaps))
    .bind(i64::from(telemetry.clears))
    .bind(i64::from(telemetry.undos))
    .execute(&mut *c)
    .await?;
        sqlx::query("DELETE FROM drafts WHERE annotator = $1 AND item = $2")
            .bind(annotator)
            .bind(item)
            .execute(&mut *c)
            .await?;
        Ok(done.rows_affected() == 1)
    })
}

/// One finished item as stored (for the annotator's own view and for admins).
#[derive(Debug, Clone)]
pub struct StoredAnnotation {
    pub annotator: String,
    pub dataset: String,
    pub item_id: String,
    pub outcome: OutcomeKind,
    pub answer: Option<Vec<u8>>,
    pub reason: String,
    pub telemetry: Telemetry,
    pub finished_at: String,
}

const ANNOTATION_SELECT: &str = "SELECT a.name AS annotator, d.name AS dataset, i.item_id, \
     n.outcome, n.answer, n.reason, n.time_on_item_ms, n.time_to_first_placement_ms, \
     n.placements, n.swaps, n.clears, n.undos, n.finished_at FROM annotations n \
     JOIN annotators a ON a.id = n.annotator JOIN items i ON i.id = n.item \
     JOIN datasets d ON d.id = i.dataset_id";

/// A counter column (stored as a 64-bit integer) as the `u32` telemetry keeps.
fn count_column(r: &impl Fields, column: &str) -> Result<u32, sqlx::Error> {
    let n: i64 = r.try_get(column)?;
    u32::try_from(n).map_err(|e| corrupt(column, e))
}

fn annotation_from_row(r: &impl Fields) -> Result<StoredAnnotation, sqlx::Error> {
    let answer: Option<String> = r.try_get("answer")?;
    Ok(StoredAnnotation {
        annotator: r.try_get("annotator")?,
        dataset: r.try_get("dataset")?,
        item_id: r.try_get("item_id")?,
        outcome: r.try_get("outcome")?,
        answer: answer
            .map(|a| serde_json::from_str(&a).map_err(|e| corrupt("answer", e)))
            .transpose()?,
        reason: r.try_get("reason")?,
        telemetry: Telemetry {
            time_on_item_ms: r.try_get("time_on_item_ms")?,
            time_to_first_placement_ms: r.try_get("time_to_first_placement_ms")?,
            placements: count_column(r, "placements")?,
            swaps: count_column(r, "swaps")?,
            clears: count_column(r, "clears")?,
            undos: count_column(r, "undos")?,
        },
        finished_at: r.try_get("finished_at")?,
    })
}

/// An annotator's own finished item.
pub async fn annotation(
    conn: &mut Conn,
    annotator: i64,
    item: i64,
) -> Result<Option<StoredAnnotation>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(&format!(
            "{ANNOTATION_SELECT} WHERE n.annotator = $1 AND n.item = $2"
        ))
        .bind(annotator)
        .bind(item)
        .fetch_optional(&mut *c)
        .await?;
        row.as_ref().map(annotation_from_row).transpose()
    })
}

/// Skipped and flagged items with their reasons, newest first.
pub async fn flags(conn: &mut Conn) -> Result<Vec<StoredAnnotation>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "{ANNOTATION_SELECT} WHERE n.outcome IN ('skipped', 'flagged') \
         ORDER BY n.finished_at DESC, i.item_id"
        ))
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(annotation_from_row).collect()
    })
}

/// Answered items of a dataset with what scoring needs, in the order they were finished, as
/// the Human row counts them (see [`human_answers_of`]).
pub async fn human_answers(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<HumanAnswer>, sqlx::Error> {
    on!(conn, |c| {
        human_answers_of(&mut *c, dataset_id, None).await
    })
}

/// The submitted answers on a dataset as the Human row counts them (none on gold items, none
/// of excluded annotators), or of one annotator when `annotator` names one (gold items still
/// left out).
pub async fn human_answers_of(
    conn: &mut Conn,
    dataset_id: i64,
    annotator: Option<i64>,
) -> Result<Vec<HumanAnswer>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT i.item_id, i.direction, i.step_length, i.gt_answer, n.answer, s.signatures \
         FROM annotations n JOIN items i ON i.id = n.item \
         LEFT JOIN item_signatures s ON s.item = i.id \
         WHERE i.dataset_id = $1 AND n.outcome = 'answered' \
         AND ($2 IS NULL OR n.annotator = $3) \
         AND NOT EXISTS (SELECT 1 FROM gold_items g WHERE g.item = n.item) \
         AND NOT EXISTS (SELECT 1 FROM attention_items t WHERE t.item = n.item) \
         AND ($4 IS NOT NULL OR NOT EXISTS (SELECT 1 FROM annotator_exclusions x \
             WHERE x.dataset = i.dataset_id AND x.annotator = n.annotator)) \
         ORDER BY n.finished_at, i.id, n.annotator",
        )
        .bind(dataset_id)
        .bind(annotator)
        .bind(annotator)
        .bind(annotator)
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(human_answer_from_row).collect()
    })
}

/// A human answer from a row holding the item's `direction`, `step_length`, `gt_answer` and
/// `signatures`, and the annotation's `answer`.
pub fn human_answer_from_row(r: &impl Fields) -> Result<HumanAnswer, sqlx::Error> {
    let (direction, step_length) = kind_from_row(r)?;
    let permutation = |column: &str| -> Result<Permutation, sqlx::Error> {
        let text: String = r.try_get(column)?;
        serde_json::from_str(&text).map_err(|e| corrupt(column, e))
    };
    let signatures: Option<String> = r.try_get("signatures")?;
    Ok(HumanAnswer {
        item_id: r.try_get("item_id")?,
        direction,
        step_length,
        ground_truth: permutation("gt_answer")?,
        answer: permutation("answer")?,
        signatures: signatures
            .map(|s| serde_json::from_str(&s).map_err(|e| corrupt("signatures", e)))
            .transpose()?,
    })
}

/// Per annotator: assigned, finished and answered items.
pub async fn progress_by_annotator(
    conn: &mut Conn,
) -> Result<Vec<(i64, i64, i64, i64)>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT a.annotator, count(*) AS assigned, count(n.item) AS finished, \
         CAST(sum(CASE WHEN n.outcome = 'answered' THEN 1 ELSE 0 END) AS BIGINT) AS answered FROM assignments a \
         LEFT JOIN annotations n ON n.annotator = a.annotator AND n.item = a.item \
         GROUP BY a.annotator",
        )
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|r| {
                Ok((
                    r.try_get("annotator")?,
                    r.try_get("assigned")?,
                    r.try_get("finished")?,
                    r.try_get::<Option<i64>>("answered")?.unwrap_or(0),
                ))
            })
            .collect()
    })
}

/// Stores a single-use login link for `annotator`.
pub async fn insert_login_link(
    conn: &mut WriteConn,
    hash: &str,
    annotator: i64,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("INSERT INTO login_links (hash, annotator) VALUES ($1, $2)")
            .bind(hash)
            .bind(annotator)
            .execute(&mut *c)
            .await
            .map(|_| ())
    })
}

/// Uses a login link up: the annotator it was for, if it existed.
pub async fn take_login_link(conn: &mut WriteConn, hash: &str) -> Result<Option<i64>, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar("DELETE FROM login_links WHERE hash = $1 RETURNING annotator")
            .bind(hash)
            .fetch_optional(&mut *c)
            .await
    })
}

/// Every submitted answer on a dataset as the Human row counts it (none on a gold item, none
/// of an annotator excluded from the dataset), in one query (one
/// snapshot: the figures and the coverage drawn from them agree), in the order answers were
/// finished. An answer with a stored verdict comes with it and its metric version; one without
/// comes with what judging it needs (its item's ground truth and signatures, read only then).
pub async fn counted_answers(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<CountedAnswer>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT n.annotator, n.item, i.item_id, i.direction, i.step_length, \
             n.exact_match, n.semantic_match, n.task_accuracy, n.pairwise_accuracy, \
             n.metric_version, \
             CASE WHEN n.metric_version IS NULL THEN i.gt_answer END AS gt_answer, \
             CASE WHEN n.metric_version IS NULL THEN n.answer END AS answer, \
             CASE WHEN n.metric_version IS NULL THEN s.signatures END AS signatures \
             FROM annotations n JOIN items i ON i.id = n.item \
             LEFT JOIN item_signatures s ON s.item = i.id \
             WHERE i.dataset_id = $1 AND n.outcome = 'answered' \
             AND NOT EXISTS (SELECT 1 FROM gold_items g WHERE g.item = n.item) \
         AND NOT EXISTS (SELECT 1 FROM attention_items t WHERE t.item = n.item) \
             AND NOT EXISTS (SELECT 1 FROM annotator_exclusions x \
                 WHERE x.dataset = i.dataset_id AND x.annotator = n.annotator) \
             ORDER BY n.finished_at, i.id, n.annotator",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(counted_answer_from_row).collect()
    })
}

fn counted_answer_from_row(r: &impl Fields) -> Result<CountedAnswer, sqlx::Error> {
    let (direction, step_length) = kind_from_row(r)?;
    let verdict = match stored_verdict(r)? {
        Some((verdict, metric_version)) => CountedVerdict::Stored {
            verdict,
            metric_version,
        },
        None => CountedVerdict::Unscored(Box::new(human_answer_from_row(r)?)),
    };
    Ok(CountedAnswer {
        annotator: r.try_get("annotator")?,
        item: r.try_get("item")?,
        direction,
        step_length,
        verdict,
    })
}

/// A submitted answer with the row ids of its annotator and item.
#[derive(Debug, Clone)]
pub struct KeyedAnswer {
    pub annotator: i64,
    pub item: i64,
    pub answer: HumanAnswer,
    /// The verdict stored with it, if any (of whichever metric version).
    pub verdict: Option<HumanVerdict>,
}

const KEYED_ANSWER_SELECT: &str = "SELECT n.annotator, n.item, i.item_id, i.direction, \
     i.step_length, i.gt_answer, n.answer, s.signatures, n.exact_match, n.semantic_match, \
     n.task_accuracy, n.pairwise_accuracy, n.metric_version \
     FROM annotations n JOIN items i ON i.id = n.item \
     LEFT JOIN item_signatures s ON s.item = i.id";

fn keyed_answer_from_row(r: &impl Fields) -> Result<KeyedAnswer, sqlx::Error> {
    Ok(KeyedAnswer {
        annotator: r.try_get("annotator")?,
        item: r.try_get("item")?,
        answer: human_answer_from_row(r)?,
        verdict: stored_verdict(r)?.map(|(verdict, _)| verdict),
    })
}

/// The verdict columns of an annotation row and its metric version, when one is stored.
fn stored_verdict(r: &impl Fields) -> Result<Option<(HumanVerdict, u32)>, sqlx::Error> {
    let Some(version) = r.try_get::<Option<i64>>("metric_version")? else {
        return Ok(None);
    };
    let verdict = HumanVerdict {
        exact_match: r.try_get("exact_match")?,
        semantic_match: r.try_get("semantic_match")?,
        task_accuracy: r.try_get("task_accuracy")?,
        pairwise_accuracy: r.try_get("pairwise_accuracy")?,
    };
    let version = u32::try_from(version).map_err(|e| corrupt("metric_version", e))?;
    Ok(Some((verdict, version)))
}

/// A submitted answer on one item, with who gave it and whether the Human row counts it.
#[derive(Debug, Clone)]
pub struct ItemAnswer {
    pub annotator_name: String,
    pub answer: KeyedAnswer,
    /// The annotator's answers on this dataset are left out of the Human row.
    pub excluded: bool,
    pub finished_at: String,
}

/// Every submitted answer on the item (row id `item`), in the order they were finished.
pub async fn answers_on_item(conn: &mut Conn, item: i64) -> Result<Vec<ItemAnswer>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT n.annotator, n.item, i.item_id, i.direction, i.step_length, i.gt_answer, \
             n.answer, s.signatures, n.exact_match, n.semantic_match, n.task_accuracy, \
             n.pairwise_accuracy, n.metric_version, n.finished_at, a.name AS annotator_name \
             FROM annotations n JOIN items i ON i.id = n.item \
             JOIN annotators a ON a.id = n.annotator \
             LEFT JOIN item_signatures s ON s.item = i.id \
             WHERE n.item = $1 AND n.outcome = 'answered' ORDER BY n.finished_at, n.annotator",
        )
        .bind(item)
        .fetch_all(&mut *c)
        .await?;
        let excluded: Vec<i64> = sqlx::query_scalar(
            "SELECT x.annotator FROM annotator_exclusions x JOIN items i ON i.dataset_id = x.dataset \
             WHERE i.id = $1",
        )
        .bind(item)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|r| {
                let answer = keyed_answer_from_row(r)?;
                Ok(ItemAnswer {
                    annotator_name: r.try_get("annotator_name")?,
                    excluded: excluded.contains(&answer.annotator),
                    finished_at: r.try_get("finished_at")?,
                    answer,
                })
            })
            .collect()
    })
}

/// The annotator's submitted answer on `item`, with what judging it needs.
pub async fn answer_to_judge(
    conn: &mut Conn,
    annotator: i64,
    item: i64,
) -> Result<Option<KeyedAnswer>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(&format!(
            "{KEYED_ANSWER_SELECT} WHERE n.annotator = $1 AND n.item = $2 \
             AND n.outcome = 'answered'"
        ))
        .bind(annotator)
        .bind(item)
        .fetch_optional(&mut *c)
        .await?;
        row.as_ref().map(keyed_answer_from_row).transpose()
    })
}

/// Up to `limit` submitted answers on a dataset whose verdict is missing or was computed with
/// a metric version below `version`, after `(item, annotator)` in that order (a cursor, so
/// answers that cannot be judged are passed over, not read again).
pub async fn answers_below_version(
    conn: &mut Conn,
    dataset_id: i64,
    version: u32,
    after: (i64, i64),
    limit: i64,
) -> Result<Vec<KeyedAnswer>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "{KEYED_ANSWER_SELECT} WHERE i.dataset_id = $1 AND n.outcome = 'answered' \
             AND (n.metric_version IS NULL OR n.metric_version < $2) \
             AND (n.item > $3 OR (n.item = $3 AND n.annotator > $4)) \
             ORDER BY n.item, n.annotator LIMIT $5"
        ))
        .bind(dataset_id)
        .bind(i64::from(version))
        .bind(after.0)
        .bind(after.1)
        .bind(limit)
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(keyed_answer_from_row).collect()
    })
}

/// Stores the verdict of a submitted answer, computed with metric `version`. Returns whether
/// the answer exists.
pub async fn set_verdict(
    conn: &mut WriteConn,
    annotator: i64,
    item: i64,
    verdict: &HumanVerdict,
    version: u32,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query(
            "UPDATE annotations SET exact_match = $1, semantic_match = $2, task_accuracy = $3, \
             pairwise_accuracy = $4, metric_version = $5 \
             WHERE annotator = $6 AND item = $7 AND outcome = 'answered'",
        )
        .bind(verdict.exact_match)
        .bind(verdict.semantic_match)
        .bind(verdict.task_accuracy)
        .bind(verdict.pairwise_accuracy)
        .bind(i64::from(version))
        .bind(annotator)
        .bind(item)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() == 1)
    })
}

/// Forgets the stored verdicts of every answer on a dataset (its items' signatures changed):
/// they read as never computed until judged again.
pub async fn forget_verdicts(conn: &mut WriteConn, dataset_id: i64) -> Result<u64, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query(
            "UPDATE annotations SET exact_match = NULL, semantic_match = NULL, \
             task_accuracy = NULL, pairwise_accuracy = NULL, metric_version = NULL \
             WHERE outcome = 'answered' \
             AND item IN (SELECT id FROM items WHERE dataset_id = $1)",
        )
        .bind(dataset_id)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected())
    })
}

/// How many submitted answers on a dataset have no verdict or one computed with a metric
/// version below `version`.
pub async fn count_below_version(
    conn: &mut Conn,
    dataset_id: i64,
    version: u32,
) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        sqlx::query_scalar(
            "SELECT count(*) FROM annotations n JOIN items i ON i.id = n.item \
             WHERE i.dataset_id = $1 AND n.outcome = 'answered' \
             AND (n.metric_version IS NULL OR n.metric_version < $2)",
        )
        .bind(dataset_id)
        .bind(i64::from(version))
        .fetch_one(&mut *c)
        .await
    })
}

/// One finished item of a dataset as the quality figures read it, with its annotator.
#[derive(Debug, Clone)]
pub struct QualityRow {
    pub annotator: i64,
    pub name: String,
    pub finished: FinishedItem,
}

/// Every finished item of a dataset (answered, skipped or flagged), gold or not, by annotator
/// name then item.
pub async fn quality_rows(
    conn: &mut Conn,
    dataset_id: i64,
) -> Result<Vec<QualityRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT n.annotator, a.name, n.item, (g.item IS NOT NULL) AS gold, n.outcome, \
             n.answer, n.time_on_item_ms, i.item_id, i.direction, i.step_length, i.gt_answer, \
             s.signatures, n.exact_match, n.semantic_match, n.task_accuracy, \
             n.pairwise_accuracy, n.metric_version \
             FROM annotations n JOIN annotators a ON a.id = n.annotator \
             JOIN items i ON i.id = n.item \
             LEFT JOIN item_signatures s ON s.item = i.id \
             LEFT JOIN gold_items g ON g.item = n.item \
             WHERE i.dataset_id = $1 \
             AND NOT EXISTS (SELECT 1 FROM attention_items t WHERE t.item = n.item) \
             ORDER BY a.name, n.item",
        )
        .bind(dataset_id)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|r| {
                let outcome: OutcomeKind = r.try_get("outcome")?;
                let answered = outcome == OutcomeKind::Answered;
                Ok(QualityRow {
                    annotator: r.try_get("annotator")?,
                    name: r.try_get("name")?,
                    finished: FinishedItem {
                        item: r.try_get("item")?,
                        gold: r.try_get("gold")?,
                        outcome,
                        answer: if answered {
                            Some(human_answer_from_row(r)?)
                        } else {
                            None
                        },
                        verdict: stored_verdict(r)?.map(|(verdict, _)| verdict),
                        time_on_item_ms: r.try_get("time_on_item_ms")?,
                    },
                })
            })
            .collect()
    })
}
