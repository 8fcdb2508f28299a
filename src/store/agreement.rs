//! What agreement reports read and the protocol writes: a dataset's content hash, every
//! annotator's submitted answers with the kind of assignment behind them, completed primary
//! answers, and the protocol round with its cross-assignments.

use sqlx::{Row, SqliteConnection};

use crate::agreement_protocol::{AssignmentKind, PrimaryAnswer, ProtocolPlan};
use crate::agreement_report::{AnnotatorAnswer, dataset_content_hash};
use crate::annotation::HumanAnswer;
use crate::dataset::{Direction, StepLength};
use crate::verifier::Permutation;

fn corrupt(column: &str, detail: impl std::fmt::Display) -> sqlx::Error {
    sqlx::Error::ColumnDecode {
        index: column.to_owned(),
        source: detail.to_string().into(),
    }
}

fn kind_from_row(row: &sqlx::sqlite::SqliteRow) -> Result<(Direction, StepLength), sqlx::Error> {
    let direction: String = row.try_get("direction")?;
    let step_length: i64 = row.try_get("step_length")?;
    Ok((
        Direction::parse(&direction)
            .ok_or_else(|| corrupt("direction", format!("unknown direction {direction:?}")))?,
        usize::try_from(step_length)
            .ok()
            .and_then(StepLength::new)
            .ok_or_else(|| corrupt("step_length", format!("bad step length {step_length}")))?,
    ))
}

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
            let (direction, step_length) = kind_from_row(r)?;
            let permutation = |column: &str| -> Result<Permutation, sqlx::Error> {
                let text: String = r.try_get(column)?;
                serde_json::from_str(&text).map_err(|e| corrupt(column, e))
            };
            let signatures: Option<String> = r.try_get("signatures")?;
            let kind: String = r.try_get("kind")?;
            Ok(AnnotatorAnswer {
                annotator_id: r.try_get("annotator")?,
                annotator: r.try_get("name")?,
                item_id: r.try_get("item_id")?,
                kind: AssignmentKind::parse(&kind)
                    .ok_or_else(|| corrupt("kind", format!("unknown kind {kind:?}")))?,
                human: HumanAnswer {
                    direction,
                    step_length,
                    ground_truth: permutation("gt_answer")?,
                    answer: permutation("answer")?,
                    signatures: signatures
                        .map(|s| serde_json::from_str(&s).map_err(|e| corrupt("signatures", e)))
                        .transpose()?,
                },
            })
        })
        .collect()
}
