//! Gold items: an admin marks a share (or a list) of a dataset's items as gold, and every
//! annotator's queue gets one of them after every `rate - 1` of its ordinary items of that
//! dataset, unannounced (the queue's order is the mix's: [`crate::core::gold::mix`]). A gold
//! answer is judged by the verifier when it is finished, like every answer, and counts for the
//! annotator's quality, never in the Human row or the agreement report.
//!
//! Also here: excluding an annotator's answers from a dataset's Human row and agreement
//! report, and counting them again.

use std::collections::HashSet;

use serde::Serialize;

use super::changes::Change;
use super::refusal::Refusal;
use super::{AppError, Hub, audit, datasets};
use crate::core::audit::{Actor, AuditAction};
use crate::core::gold::{self, GoldChoice, GoldRate};
use crate::store;
use crate::store::gold::Exclusion;
use crate::{Lane, Write};

/// A dataset's gold set as shown to admins.
#[derive(Debug, Clone, PartialEq, Serialize, schemars::JsonSchema)]
pub struct GoldSet {
    pub dataset: String,
    /// One gold item in every `rate` queue items.
    pub rate: i64,
    /// `share` (a seeded random share of the items) or `list` (ids an admin gave).
    pub chosen_by: String,
    pub share: Option<f64>,
    pub seed: Option<u64>,
    pub set_by: String,
    pub set_at: String,
    /// The gold items' ids.
    pub items: Vec<String>,
}

/// What setting or clearing a gold set did to the queues.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, schemars::JsonSchema)]
pub struct GoldQueues {
    /// Gold items added to annotators' queues.
    pub added: u64,
    /// Unfinished gold items taken out of queues (of an earlier gold set).
    pub removed: u64,
}

/// The dataset's gold set, `None` when it has none.
pub async fn show(hub: &Hub, dataset: &str) -> Result<Option<GoldSet>, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    let stored = store::gold::gold_set(&mut conn, dataset.id).await?;
    Ok(stored.map(|s| GoldSet {
        dataset: dataset.name,
        rate: s.rate,
        chosen_by: s.chosen_by,
        share: s.share,
        seed: s.seed,
        set_by: s.set_by,
        set_at: s.created_at,
        items: s.items,
    }))
}

/// Makes `choice` the dataset's gold set at `rate` (replacing any earlier one), and mixes it
/// into every queue holding the dataset's items, in one transaction with its audit entry.
/// Refuses item ids not in the dataset (all of them named) and a choice that would make every
/// item gold.
pub async fn set(
    hub: &Hub,
    actor: &Actor,
    dataset: &str,
    choice: &GoldChoice,
    rate: GoldRate,
) -> Result<(GoldSet, GoldQueues), AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    let all: Vec<i64> = store::annotations::dataset_items(&mut conn, dataset.id)
        .await?
        .into_iter()
        .map(|i| i.item)
        .collect();
    if all.len() < 2 {
        return Err(Refusal::TooFewForGold {
            dataset: dataset.name.clone(),
            items: all.len() as u64,
        }
        .into());
    }
    // An item is a gold item or an attention check, never both.
    let checks: HashSet<i64> = store::attention::attention_item_rowids(&mut conn, dataset.id)
        .await?
        .into_iter()
        .collect();
    let items = match choice {
        GoldChoice::Share { share, seed } => {
            let pool: Vec<i64> = all
                .iter()
                .copied()
                .filter(|i| !checks.contains(i))
                .collect();
            gold::draw_share(&pool, *share, *seed)
        }
        GoldChoice::List(ids) => {
            let mut rows = super::items::listed(&mut conn, &dataset, ids).await?;
            if let Some(check) = ids
                .iter()
                .zip(&rows)
                .find(|(_, row)| checks.contains(row))
                .map(|(id, _)| id)
            {
                return Err(Refusal::GoldAndAttention {
                    field: "items",
                    dataset: dataset.name.clone(),
                    items: check.clone(),
                }
                .into());
            }
            rows.sort_unstable();
            rows.dedup();
            if rows.len() >= all.len() {
                return Err(Refusal::LeavesNoItems {
                    field: "items",
                    dataset: dataset.name.clone(),
                }
                .into());
            }
            rows
        }
    };
    drop(conn);
    let (share, seed) = match choice {
        GoldChoice::Share { share, seed } => (Some(*share), Some(*seed)),
        GoldChoice::List(_) => (None, None),
    };
    let mut tx = hub.write(Lane::Interactive).await?;
    let removed = store::gold::drop_unfinished_gold_assignments(&mut tx, dataset.id).await?;
    store::gold::replace(
        &mut tx,
        dataset.id,
        i64::from(rate.get()),
        choice.kind(),
        share,
        seed,
        &actor.to_string(),
        &items,
    )
    .await?;
    let added = mix_in(&mut tx, dataset.id, rate, None).await?;
    let how = match choice {
        GoldChoice::Share { share, seed } => format!("a share of {share} drawn with seed {seed}"),
        GoldChoice::List(_) => "listed items".to_owned(),
    };
    audit::record(
        &mut tx,
        actor,
        AuditAction::GoldSet,
        format!("gold set of {}", dataset.name),
        Some(&dataset.name),
        format!(
            "{} gold items ({how}), one in every {} queue items; {added} added to queues, {} \
             unfinished taken out",
            items.len(),
            rate.get(),
            removed.len()
        ),
    )
    .await?;
    announce(&mut tx, &removed).await?;
    tx.commit().await?;
    let shown = show(hub, &dataset.name)
        .await?
        .ok_or_else(|| AppError::internal("the gold set just stored is not there"))?;
    Ok((
        shown,
        GoldQueues {
            added,
            removed: removed.len() as u64,
        },
    ))
}

/// What clearing a gold set did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, schemars::JsonSchema)]
pub struct GoldCleared {
    /// False when the dataset had no gold set (nothing changed, nothing audited).
    pub cleared: bool,
    /// Unfinished gold items taken out of queues.
    pub removed: u64,
}

/// Removes the dataset's gold set: its unfinished gold items leave the queues; answers given
/// stay, and (their items no longer gold) count in the Human row again. A dataset without a
/// gold set is left as it is.
pub async fn clear(hub: &Hub, actor: &Actor, dataset: &str) -> Result<GoldCleared, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut tx = hub.write(Lane::Interactive).await?;
    let removed = store::gold::drop_unfinished_gold_assignments(&mut tx, dataset.id).await?;
    if !store::gold::clear(&mut tx, dataset.id).await? {
        // Without a gold set no assignment is the gold mix's to remove.
        tx.rollback().await?;
        return Ok(GoldCleared {
            cleared: false,
            removed: 0,
        });
    }
    audit::record(
        &mut tx,
        actor,
        AuditAction::GoldClear,
        format!("gold set of {}", dataset.name),
        Some(&dataset.name),
        format!(
            "{} unfinished gold items taken out of queues",
            removed.len()
        ),
    )
    .await?;
    announce(&mut tx, &removed).await?;
    tx.commit().await?;
    Ok(GoldCleared {
        cleared: true,
        removed: removed.len() as u64,
    })
}

/// Announces that the Human row and these standings changed (gold items or attention checks
/// taken out of queues).
pub(super) async fn announce(tx: &mut Write, removed: &[(i64, i64)]) -> Result<(), AppError> {
    for &(annotator, item) in removed {
        tx.announce(Change::Standing { annotator, item }).await?;
    }
    tx.announce(Change::Boards).await
}

/// Adds the dataset's gold items to the queues of `annotators` (every annotator holding an
/// item of the dataset when `None`) until each has one per `rate - 1` ordinary items. Returns
/// how many were added. Call inside the transaction that changed the queues or the gold set.
async fn mix_in(
    conn: &mut store::Tx,
    dataset_id: i64,
    rate: GoldRate,
    annotators: Option<&[i64]>,
) -> Result<u64, AppError> {
    let gold_items = store::gold::gold_item_rowids(conn, dataset_id).await?;
    if gold_items.is_empty() {
        return Ok(0);
    }
    let mut pairs = Vec::new();
    for standing in store::gold::gold_standings(conn, dataset_id).await? {
        if annotators.is_some_and(|only| !only.contains(&standing.annotator)) {
            continue;
        }
        let wanted = rate.wanted(standing.ordinary, gold_items.len());
        let need = wanted.saturating_sub(standing.held.len());
        let held: HashSet<i64> = standing.held.into_iter().collect();
        pairs.extend(
            gold::pick_for(&gold_items, standing.annotator, &held, need)
                .into_iter()
                .map(|item| (standing.annotator, item)),
        );
    }
    Ok(store::gold::assign_gold(conn, &pairs).await?)
}

/// After items of a dataset were assigned to `annotators`: their gold items, at the dataset's
/// rate (nothing when it has no gold set). Call inside the assigning transaction.
pub(super) async fn after_assignment(
    conn: &mut store::Tx,
    dataset_id: i64,
    annotators: &[i64],
) -> Result<u64, AppError> {
    let Some(stored) = store::gold::gold_set(conn, dataset_id).await? else {
        return Ok(0);
    };
    let rate = GoldRate::new(stored.rate).map_err(AppError::internal)?;
    mix_in(conn, dataset_id, rate, Some(annotators)).await
}

/// Keeps `annotator`'s answers on `dataset` out of its Human row and agreement report (they
/// stay stored; [`include`] counts them again), audited. Returns whether it changed anything
/// (false when already excluded: nothing is audited then).
pub async fn exclude(
    hub: &Hub,
    actor: &Actor,
    dataset: &str,
    annotator: &str,
) -> Result<bool, AppError> {
    change_exclusion(hub, actor, dataset, annotator, true).await
}

/// Counts an excluded annotator's answers on `dataset` again, audited. Returns whether it
/// changed anything (false when the annotator was not excluded).
pub async fn include(
    hub: &Hub,
    actor: &Actor,
    dataset: &str,
    annotator: &str,
) -> Result<bool, AppError> {
    change_exclusion(hub, actor, dataset, annotator, false).await
}

async fn change_exclusion(
    hub: &Hub,
    actor: &Actor,
    dataset: &str,
    annotator: &str,
    exclude: bool,
) -> Result<bool, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    let account = store::annotations::annotators(&mut conn)
        .await?
        .into_iter()
        .find(|a| a.name == annotator)
        .ok_or_else(|| {
            AppError::from(Refusal::NoAnnotator {
                annotator: annotator.to_owned(),
            })
        })?;
    drop(conn);
    let mut tx = hub.write(Lane::Interactive).await?;
    let changed = if exclude {
        store::gold::exclude(&mut tx, dataset.id, account.id, &actor.to_string()).await?
    } else {
        store::gold::include(&mut tx, dataset.id, account.id).await?
    };
    if !changed {
        tx.rollback().await?;
        return Ok(false);
    }
    let (action, detail) = if exclude {
        (
            AuditAction::AnnotatorExclude,
            "answers left out of the Human row and the agreement report",
        )
    } else {
        (
            AuditAction::AnnotatorInclude,
            "answers counted in the Human row and the agreement report again",
        )
    };
    audit::record(
        &mut tx,
        actor,
        action,
        format!("annotator {annotator}"),
        Some(&dataset.name),
        detail,
    )
    .await?;
    tx.announce(Change::Boards).await?;
    tx.commit().await?;
    Ok(true)
}

/// The annotators excluded from a dataset's Human row, by name.
pub async fn exclusions(hub: &Hub, dataset: &str) -> Result<Vec<Exclusion>, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    Ok(store::gold::exclusions(&mut conn, dataset.id).await?)
}
