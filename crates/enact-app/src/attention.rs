//! Attention checks: an admin marks items of a dataset as attention checks, each with an
//! instruction its question carries on the item page ("put the frames in reverse order",
//! "keep the given order": [`crate::core::attention`] says which answer each expects). They are
//! mixed into every annotator's queue like gold items ([`super::gold`]): one after every
//! `rate - 1` of the queue's ordinary items of the dataset. Their answers are judged against
//! the instruction, counted per annotator (passed, failed, pending) on the quality page and its
//! API, and never counted in the Human row or the agreement report.

use std::collections::HashSet;

use schemars::JsonSchema;
use serde::Serialize;

use super::refusal::Refusal;
use super::{AppError, Hub, audit, datasets};
use crate::Lane;
use crate::core::attention::{AttentionTally, Instruction, judge};
use crate::core::audit::{Actor, AuditAction};
use crate::core::gold::{self, GoldRate};
use crate::store;

/// One attention check as shown to admins.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, JsonSchema)]
pub struct AttentionCheck {
    pub item_id: String,
    pub instruction: Instruction,
}

/// A dataset's attention checks as shown to admins.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, JsonSchema)]
pub struct AttentionSet {
    pub dataset: String,
    /// One attention check in every `rate` queue items.
    pub rate: i64,
    pub set_by: String,
    pub set_at: String,
    pub checks: Vec<AttentionCheck>,
}

/// What setting or clearing attention checks did to the queues.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
pub struct AttentionQueues {
    /// Attention checks added to annotators' queues.
    pub added: u64,
    /// Unfinished attention checks (of an earlier set) taken out of queues.
    pub removed: u64,
}

/// Attention checks from a list file's text, one `ITEM_ID keep|reverse` per line
/// ([`crate::core::attention::parse_check_list`]); the refusal names the line.
pub fn parse_checks(text: &str) -> Result<Vec<(String, Instruction)>, String> {
    crate::core::attention::parse_check_list(text)
}

/// The dataset's attention checks, `None` when it has none.
pub async fn show(hub: &Hub, dataset: &str) -> Result<Option<AttentionSet>, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    let stored = store::attention::attention_set(&mut conn, dataset.id).await?;
    Ok(stored.map(|s| AttentionSet {
        dataset: dataset.name,
        rate: s.rate,
        set_by: s.set_by,
        set_at: s.created_at,
        checks: s
            .items
            .into_iter()
            .map(|(item_id, instruction)| AttentionCheck {
                item_id,
                instruction,
            })
            .collect(),
    }))
}

/// Makes `checks` (item id, instruction) the dataset's attention checks at `rate` (replacing
/// any earlier ones) and mixes them into every queue holding the dataset's items, in one
/// transaction with its audit entry. Refuses item ids not in the dataset (all named), gold
/// items, and a list naming every item.
pub async fn set(
    hub: &Hub,
    actor: &Actor,
    dataset: &str,
    checks: &[(String, Instruction)],
    rate: GoldRate,
) -> Result<(AttentionSet, AttentionQueues), AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    if checks.is_empty() {
        return Err(Refusal::EmptyList { field: "checks" }.into());
    }
    let mut seen = HashSet::new();
    if let Some((repeated, _)) = checks.iter().find(|(id, _)| !seen.insert(id.as_str())) {
        return Err(Refusal::ListedTwice {
            field: "checks",
            item: repeated.clone(),
        }
        .into());
    }
    let mut conn = hub.conn().await?;
    let ids: Vec<String> = checks.iter().map(|(id, _)| id.clone()).collect();
    let rows = super::items::listed(&mut conn, &dataset, &ids).await?;
    let all = store::annotations::dataset_items(&mut conn, dataset.id)
        .await?
        .len();
    if rows.len() >= all {
        return Err(Refusal::LeavesNoItems {
            field: "checks",
            dataset: dataset.name,
        }
        .into());
    }
    let gold: HashSet<i64> = store::gold::gold_item_rowids(&mut conn, dataset.id)
        .await?
        .into_iter()
        .collect();
    drop(conn);
    let golden: Vec<&str> = ids
        .iter()
        .zip(&rows)
        .filter(|(_, row)| gold.contains(row))
        .map(|(id, _)| id.as_str())
        .collect();
    if !golden.is_empty() {
        return Err(Refusal::GoldAndAttention {
            field: "checks",
            dataset: dataset.name,
            items: golden.join(", "),
        }
        .into());
    }
    let items: Vec<(i64, Instruction)> = rows
        .iter()
        .zip(checks)
        .map(|(row, (_, instruction))| (*row, *instruction))
        .collect();
    let mut tx = hub.write(Lane::Interactive).await?;
    let removed =
        store::attention::drop_unfinished_attention_assignments(&mut tx, dataset.id).await?;
    store::attention::replace(
        &mut tx,
        dataset.id,
        i64::from(rate.get()),
        &actor.to_string(),
        &items,
    )
    .await?;
    let added = mix_in(&mut tx, dataset.id, rate, None).await?;
    audit::record(
        &mut tx,
        actor,
        AuditAction::AttentionSet,
        format!("attention checks of {}", dataset.name),
        Some(&dataset.name),
        format!(
            "{} attention checks, one in every {} queue items; {added} added to queues, {} \
             unfinished taken out",
            items.len(),
            rate.get(),
            removed.len()
        ),
    )
    .await?;
    super::gold::announce(&mut tx, &removed).await?;
    tx.commit().await?;
    let shown = show(hub, &dataset.name)
        .await?
        .ok_or_else(|| AppError::internal("the attention checks just stored are not there"))?;
    Ok((
        shown,
        AttentionQueues {
            added,
            removed: removed.len() as u64,
        },
    ))
}

/// What clearing attention checks did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
pub struct AttentionCleared {
    /// False when the dataset had none (nothing changed, nothing audited).
    pub cleared: bool,
    /// Unfinished attention checks taken out of queues.
    pub removed: u64,
}

/// Removes the dataset's attention checks: unfinished ones leave the queues; answers given
/// stay (and, their items no longer checks, count in the Human row again).
pub async fn clear(hub: &Hub, actor: &Actor, dataset: &str) -> Result<AttentionCleared, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut tx = hub.write(Lane::Interactive).await?;
    let removed =
        store::attention::drop_unfinished_attention_assignments(&mut tx, dataset.id).await?;
    if !store::attention::clear(&mut tx, dataset.id).await? {
        tx.rollback().await?;
        return Ok(AttentionCleared {
            cleared: false,
            removed: 0,
        });
    }
    audit::record(
        &mut tx,
        actor,
        AuditAction::AttentionClear,
        format!("attention checks of {}", dataset.name),
        Some(&dataset.name),
        format!(
            "{} unfinished attention checks taken out of queues",
            removed.len()
        ),
    )
    .await?;
    super::gold::announce(&mut tx, &removed).await?;
    tx.commit().await?;
    Ok(AttentionCleared {
        cleared: true,
        removed: removed.len() as u64,
    })
}

/// Adds the dataset's attention checks to the queues of `annotators` (every annotator holding
/// an item of the dataset when `None`) until each has one per `rate - 1` ordinary items.
async fn mix_in(
    conn: &mut store::Tx,
    dataset_id: i64,
    rate: GoldRate,
    annotators: Option<&[i64]>,
) -> Result<u64, AppError> {
    let checks = store::attention::attention_item_rowids(conn, dataset_id).await?;
    if checks.is_empty() {
        return Ok(0);
    }
    let mut pairs = Vec::new();
    for standing in store::attention::attention_standings(conn, dataset_id).await? {
        if annotators.is_some_and(|only| !only.contains(&standing.annotator)) {
            continue;
        }
        let wanted = rate.wanted(standing.ordinary, checks.len());
        let need = wanted.saturating_sub(standing.held.len());
        let held: HashSet<i64> = standing.held.into_iter().collect();
        pairs.extend(
            gold::pick_for(&checks, standing.annotator, &held, need)
                .into_iter()
                .map(|item| (standing.annotator, item)),
        );
    }
    Ok(store::attention::assign_checks(conn, &pairs).await?)
}

/// After items of a dataset were assigned to `annotators`: their attention checks, at the
/// dataset's rate (nothing when it has none). Call inside the assigning transaction.
pub(super) async fn after_assignment(
    conn: &mut store::Tx,
    dataset_id: i64,
    annotators: &[i64],
) -> Result<u64, AppError> {
    let Some(stored) = store::attention::attention_set(conn, dataset_id).await? else {
        return Ok(0);
    };
    let rate = GoldRate::new(stored.rate).map_err(AppError::internal)?;
    mix_in(conn, dataset_id, rate, Some(annotators)).await
}

/// One annotator's attention checks on a dataset.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, JsonSchema)]
pub struct AnnotatorChecks {
    pub annotator: String,
    #[serde(flatten)]
    pub tally: AttentionTally,
}

/// Every annotator holding an attention check of the dataset, by name, with their checks
/// judged against the instructions.
pub(super) async fn tallies(
    conn: &mut store::Conn,
    dataset_id: i64,
) -> Result<Vec<AnnotatorChecks>, AppError> {
    let rows = store::attention::check_rows(conn, dataset_id).await?;
    let mut out: Vec<AnnotatorChecks> = Vec::new();
    for row in rows {
        if out.last().is_none_or(|a| a.annotator != row.annotator) {
            out.push(AnnotatorChecks {
                annotator: row.annotator.clone(),
                tally: AttentionTally::default(),
            });
        }
        if let Some(last) = out.last_mut() {
            last.tally.add(judge(
                row.instruction,
                row.step_length,
                row.finished,
                row.answer.as_deref(),
            ));
        }
    }
    Ok(out)
}

/// The instruction an item's question carries, when it is an attention check.
pub(super) async fn instruction_of(
    conn: &mut store::Conn,
    item: i64,
) -> Result<Option<Instruction>, AppError> {
    Ok(store::attention::instruction_of(conn, item).await?)
}
