//! What agreement reports read and the protocol writes: a dataset's content hash, every
//! annotator's submitted answers with the kind of assignment behind them, completed primary
//! answers, and the protocol round with its cross-assignments.

use sqlx::{Row, SqliteConnection};

use super::annotations::human_answer_from_row;
use super::{corrupt, kind_from_row};

use crate::core::agreement::protocol::{
    AssignmentKind, PrimaryAnswer, ProtocolError, ProtocolPlan, plan_cross_assignments,
};
use crate::core::agreement::report::{AnnotatorAnswer, dataset_content_hash};
use crate::core::dataset::{Direction, StepLength};

/// [`dataset_content_hash`] of a stored dataset, from its items' ids and content hashes.
pub async fn dataset_hash(
    conn: &mut SqliteConnection,
    dataset_id: i64,
) -> Result<(String, usize), sqlx::Error> {
    let rows: Vec<(String, String)> =
        sqlx::query_as("SELECT item_id, content_hash FROM items WHERE dataset_id = ?")
            .bind(dataset_id)
            .fetch_all(conn)
            .await?;
    let hash = dataset_content_hash(rows.iter().map(|(id, hash)| (id.as_str(), hash.as_str())));
    Ok((hash, rows.len()))
}

/// Every answered item of a dataset, per annotator, with the item's ground truth and
/// signatures and the kind of assignment it was answered under; by item, then annotator.
pub async fn annotator_answers(
    conn: &mut SqliteConnection,
    dataset_id: i64,
) -> Result<Vec<AnnotatorAnswer>, sqlx::Error> {
    let rows = sqlx::query(
        "SELECT n.annotator, a.name, i.item_id, i.direction, i.step_length, i.gt_answer, \
         n.answer, s.signatures, coalesce(g.kind, 'primary') AS kind \
         FROM annotations n JOIN items i ON i.id = n.item \
         JOIN annotators a ON a.id = n.annotator \
         LEFT JOIN assignments g ON g.annotator = n.annotator AND g.item = n.item \
         LEFT JOIN item_signatures s ON s.item = i.id \
         WHERE i.dataset_id = ? AND n.outcome = 'answered' \
         ORDER BY i.item_id, n.annotator",
    )
    .bind(dataset_id)
    .fetch_all(conn)
    .await?;
    rows.iter()
        .map(|r| {
            let kind: String = r.try_get("kind")?;
            Ok(AnnotatorAnswer {
                annotator_id: r.try_get("annotator")?,
                annotator: r.try_get("name")?,
                item_id: r.try_get("item_id")?,
                kind: AssignmentKind::parse(&kind)
                    .ok_or_else(|| corrupt("kind", format!("unknown kind {kind:?}")))?,
                human: human_answer_from_row(r)?,
            })
        })
        .collect()
}

/// Completed (answered) primary items of a dataset: what the protocol draws from.
pub async fn primary_answers(
    conn: &mut SqliteConnection,
    dataset_id: i64,
) -> Result<Vec<PrimaryAnswer>, sqlx::Error> {
    let rows = sqlx::query(
        "SELECT n.item, n.annotator, i.direction, i.step_length FROM annotations n \
         JOIN items i ON i.id = n.item \
         LEFT JOIN assignments g ON g.annotator = n.annotator AND g.item = n.item \
         WHERE i.dataset_id = ? AND n.outcome = 'answered' \
         AND coalesce(g.kind, 'primary') = 'primary' ORDER BY n.item, n.annotator",
    )
    .bind(dataset_id)
    .fetch_all(conn)
    .await?;
    rows.iter()
        .map(|r| {
            let (direction, step_length) = kind_from_row(r)?;
            Ok(PrimaryAnswer {
                item: r.try_get("item")?,
                annotator: r.try_get("annotator")?,
                direction,
                step_length,
            })
        })
        .collect()
}

/// Annotators holding primary assignments in a dataset: the protocol's participants.
pub async fn primary_annotators(
    conn: &mut SqliteConnection,
    dataset_id: i64,
) -> Result<Vec<i64>, sqlx::Error> {
    sqlx::query_scalar(
        "SELECT DISTINCT g.annotator FROM assignments g JOIN items i ON i.id = g.item \
         WHERE i.dataset_id = ? AND g.kind = 'primary' ORDER BY g.annotator",
    )
    .bind(dataset_id)
    .fetch_all(conn)
    .await
}

/// A dataset's protocol round as recorded.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct AgreementRound {
    pub items_per_cell: i64,
    pub seed: u64,
    /// Who ran it, when the account still exists.
    pub started_by: Option<String>,
    pub created_at: String,
    pub samples: i64,
    /// Agreement assignments made, and how many of them are answered.
    pub assignments: i64,
    pub answered: i64,
}

pub async fn round(
    conn: &mut SqliteConnection,
    dataset_id: i64,
) -> Result<Option<AgreementRound>, sqlx::Error> {
    let row = sqlx::query(
        "SELECT r.items_per_cell, r.seed, a.name, r.created_at, \
         (SELECT count(*) FROM agreement_samples s WHERE s.dataset = r.dataset) AS samples, \
         (SELECT count(*) FROM assignments g JOIN items i ON i.id = g.item \
          WHERE i.dataset_id = r.dataset AND g.kind = 'agreement') AS assignments, \
         (SELECT count(*) FROM assignments g JOIN items i ON i.id = g.item \
          JOIN annotations n ON n.annotator = g.annotator AND n.item = g.item \
          WHERE i.dataset_id = r.dataset AND g.kind = 'agreement' \
          AND n.outcome = 'answered') AS answered \
         FROM agreement_rounds r LEFT JOIN annotators a ON a.id = r.started_by \
         WHERE r.dataset = ?",
    )
    .bind(dataset_id)
    .fetch_optional(conn)
    .await?;
    row.map(|r| {
        Ok(AgreementRound {
            items_per_cell: r.try_get("items_per_cell")?,
            // Stored bit for bit in SQLite's signed integer.
            seed: r.try_get::<i64, _>("seed")? as u64,
            started_by: r.try_get("name")?,
            created_at: r.try_get("created_at")?,
            samples: r.try_get("samples")?,
            assignments: r.try_get("assignments")?,
            answered: r.try_get("answered")?,
        })
    })
    .transpose()
}

/// Records a protocol round and its cross-assignments, appended to each annotator's queue
/// like any other assignment. Call inside a transaction. `Ok(Err(round))` when the dataset
/// already has a round: nothing is written then. Otherwise returns the assignments added (a
/// pair already assigned, under either kind, is left as it was).
pub async fn record_round(
    conn: &mut SqliteConnection,
    dataset_id: i64,
    plan: &ProtocolPlan,
    started_by: Option<i64>,
) -> Result<Result<u64, AgreementRound>, sqlx::Error> {
    if let Some(existing) = round(&mut *conn, dataset_id).await? {
        return Ok(Err(existing));
    }
    let inserted = sqlx::query(
        "INSERT INTO agreement_rounds (dataset, items_per_cell, seed, started_by) \
         VALUES (?, ?, ?, ?)",
    )
    .bind(dataset_id)
    .bind(i64::try_from(plan.items_per_cell).unwrap_or(i64::MAX))
    .bind(plan.seed as i64)
    .bind(started_by)
    .execute(&mut *conn)
    .await;
    match inserted {
        Ok(_) => {}
        // A concurrent run got there first.
        Err(sqlx::Error::Database(e)) if e.is_unique_violation() => {
            if let Some(existing) = round(&mut *conn, dataset_id).await? {
                return Ok(Err(existing));
            }
            return Err(sqlx::Error::Database(e));
        }
        Err(e) => return Err(e),
    }
    for sample in &plan.samples {
        sqlx::query(
            "INSERT INTO agreement_samples (dataset, item, source_annotator) VALUES (?, ?, ?)",
        )
        .bind(dataset_id)
        .bind(sample.item)
        .bind(sample.source_annotator)
        .execute(&mut *conn)
        .await?;
    }
    let mut added = 0;
    for &(annotator, item) in &plan.assignments {
        let done = sqlx::query(
            "INSERT INTO assignments (annotator, item, position, kind) \
             SELECT ?1, ?2, coalesce(max(position), 0) + 1, 'agreement' FROM assignments \
             WHERE annotator = ?1 ON CONFLICT (annotator, item) DO NOTHING",
        )
        .bind(annotator)
        .bind(item)
        .execute(&mut *conn)
        .await?;
        added += done.rows_affected();
    }
    Ok(Ok(added))
}

/// Why the protocol did not run on a dataset.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProtocolRefusal {
    #[error(
        "the agreement protocol already ran on this dataset on {} (k = {}, seed = {}, {} items \
         drawn); it runs once per dataset so that the recorded sample stays the one used",
        .0.created_at, .0.items_per_cell, .0.seed, .0.samples
    )]
    AlreadyRan(AgreementRound),
    #[error(transparent)]
    Plan(#[from] ProtocolError),
}

/// What a protocol run did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProtocolRun {
    pub plan: ProtocolPlan,
    pub annotators: Vec<i64>,
    pub assignments_added: u64,
}

/// Plans the protocol on the dataset's completed primary answers and records it. Call inside a
/// transaction, and commit only on `Ok(Ok(_))`.
pub async fn run_protocol(
    conn: &mut SqliteConnection,
    dataset_id: i64,
    items_per_cell: usize,
    seed: u64,
    started_by: Option<i64>,
) -> Result<Result<ProtocolRun, ProtocolRefusal>, sqlx::Error> {
    if let Some(existing) = round(&mut *conn, dataset_id).await? {
        return Ok(Err(ProtocolRefusal::AlreadyRan(existing)));
    }
    let answers = primary_answers(&mut *conn, dataset_id).await?;
    let annotators = primary_annotators(&mut *conn, dataset_id).await?;
    let plan = match plan_cross_assignments(&answers, &annotators, items_per_cell, seed) {
        Ok(plan) => plan,
        Err(e) => return Ok(Err(e.into())),
    };
    Ok(
        match record_round(conn, dataset_id, &plan, started_by).await? {
            Ok(added) => Ok(ProtocolRun {
                plan,
                annotators,
                assignments_added: added,
            }),
            Err(existing) => Err(ProtocolRefusal::AlreadyRan(existing)),
        },
    )
}

/// How a report is computed: the admin's or the command line's choices.
#[derive(Debug, Clone, Copy)]
pub struct ReportSettings {
    pub encoding: crate::core::agreement::OrderingEncoding,
    pub level: Option<crate::core::agreement::MeasurementLevel>,
    pub bootstrap: crate::core::agreement::BootstrapConfig,
    pub chosen_pair: Option<(i64, i64)>,
}

/// Everything [`crate::core::agreement::report::build_report`] needs about a stored dataset.
pub async fn report_inputs(
    conn: &mut SqliteConnection,
    dataset: &crate::store::datasets::Dataset,
    settings: &ReportSettings,
) -> Result<crate::core::agreement::report::ReportInputs, sqlx::Error> {
    use crate::core::agreement::report::{ItemScore, ProtocolStamp, ReportInputs, SubmissionInput};
    use crate::core::leaderboard::{LeaderboardRow, RowIdentity};
    let (dataset_hash, dataset_items) = dataset_hash(&mut *conn, dataset.id).await?;
    let answers = annotator_answers(&mut *conn, dataset.id).await?;
    let mut submissions = Vec::new();
    for s in crate::store::submissions::published(&mut *conn, dataset.id).await? {
        let scores: serde_json::Value = serde_json::from_str(&s.scores)
            .map_err(|e| corrupt("scores", format!("submission {}: {e}", s.id)))?;
        let row = LeaderboardRow::from_scores(
            &RowIdentity {
                submission: s.id,
                model: &s.model,
                account: &s.account,
                baseline: s.baseline,
                submitted_at: &s.created_at,
            },
            &scores,
        );
        let mut item_scores = Vec::new();
        for v in crate::store::submissions::verdicts(&mut *conn, s.id).await? {
            let (Some(direction), Some(step_length)) = (
                Direction::parse(&v.direction),
                usize::try_from(v.step_length)
                    .ok()
                    .and_then(StepLength::new),
            ) else {
                return Err(corrupt("items", format!("item {}: bad kind", v.id)));
            };
            item_scores.push(ItemScore {
                item_id: v.id,
                direction,
                step_length,
                pairwise_accuracy: v.pairwise_accuracy,
            });
        }
        submissions.push(SubmissionInput { row, item_scores });
    }
    let protocol = round(&mut *conn, dataset.id).await?.map(|r| ProtocolStamp {
        items_per_cell: r.items_per_cell,
        seed: r.seed,
    });
    Ok(ReportInputs {
        dataset: dataset.name.clone(),
        dataset_hash,
        dataset_items,
        answers,
        submissions,
        chosen_pair: settings.chosen_pair,
        encoding: settings.encoding,
        level: settings.level,
        bootstrap: settings.bootstrap,
        protocol,
    })
}
