//! Annotator controls: pausing and resuming an annotator's queue, and handing their unfinished
//! items to other annotators.
//!
//! A pause is read from the store by every use case it stops ([`refuse_if_paused`]: opening,
//! saving a draft, answering, skipping or flagging an item), inside the write's own
//! transaction where there is one, so a pause made by another process (the command line beside
//! a server, another instance) holds from its commit on with nothing cached to clear. Nothing
//! else changes: drafts, assignments and answers stay, and resuming restores the queue as it
//! was. A balanced split leaves paused annotators out.
//!
//! A handover takes every item of the annotator's queue without a finished answer (their
//! drafts of them go too) and deals the items of the datasets' coverage over the recipients
//! with [`handover_split`]: kind by kind, to whoever got the fewest so far, never to someone
//! who holds the item already (an item every recipient holds stays where it was). Items the
//! gold or attention mix put there judge that annotator only, so they leave the queue without
//! being handed on; the recipients get their own from the mixes. Finished answers stay with
//! the annotator who gave them.

use std::collections::{BTreeMap, HashMap};

use schemars::JsonSchema;
use serde::Serialize;

use super::changes::Change;
use super::refusal::Refusal;
use super::{AppError, Hub, audit};
use crate::Lane;
use crate::core::annotation::{Session, handover_split};
use crate::core::audit::{Actor, AuditAction};
use crate::store;
use crate::store::annotations::Annotator;
use crate::store::controls::Pause;

/// A paused queue as admins and the annotator see it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, JsonSchema)]
pub struct PauseView {
    pub annotator: String,
    pub paused_by: String,
    pub paused_at: String,
}

impl From<Pause> for PauseView {
    fn from(p: Pause) -> PauseView {
        PauseView {
            annotator: p.name,
            paused_by: p.paused_by,
            paused_at: p.paused_at,
        }
    }
}

async fn annotator_named(hub: &Hub, name: &str) -> Result<Annotator, AppError> {
    let mut conn = hub.conn().await?;
    store::annotations::annotators(&mut conn)
        .await?
        .into_iter()
        .find(|a| a.name == name)
        .ok_or_else(|| {
            AppError::from(Refusal::NoAnnotator {
                annotator: name.to_owned(),
            })
        })
}

/// Pauses `annotator`'s queue, audited: they keep reading it but cannot open, save, answer or
/// skip an item until [`resume`], and no balanced split gives them items. Returns whether it
/// changed anything (false when already paused: nothing is audited then).
pub async fn pause(hub: &Hub, actor: &Actor, annotator: &str) -> Result<bool, AppError> {
    change_pause(hub, actor, annotator, true).await
}

/// Resumes a paused queue as it was (drafts kept), audited. Returns whether it changed
/// anything (false when it was not paused).
pub async fn resume(hub: &Hub, actor: &Actor, annotator: &str) -> Result<bool, AppError> {
    change_pause(hub, actor, annotator, false).await
}

async fn change_pause(
    hub: &Hub,
    actor: &Actor,
    annotator: &str,
    pause: bool,
) -> Result<bool, AppError> {
    let account = annotator_named(hub, annotator).await?;
    let mut tx = hub.write(Lane::Interactive).await?;
    let changed = if pause {
        store::controls::pause(&mut tx, account.id, &actor.to_string()).await?
    } else {
        store::controls::resume(&mut tx, account.id).await?
    };
    if !changed {
        tx.rollback().await?;
        return Ok(false);
    }
    let (action, detail) = if pause {
        (
            AuditAction::AnnotatorPause,
            "queue paused: no item can be opened, saved, answered or skipped, and no split \
             assigns new items; drafts kept",
        )
    } else {
        (AuditAction::AnnotatorResume, "queue resumed as it was")
    };
    audit::record(
        &mut tx,
        actor,
        action,
        format!("annotator {annotator}"),
        None,
        detail,
    )
    .await?;
    tx.commit().await?;
    Ok(true)
}

/// The annotator's pause, if their queue is paused.
pub async fn paused(hub: &Hub, annotator: i64) -> Result<Option<PauseView>, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::controls::pause_of(&mut conn, annotator)
        .await?
        .map(PauseView::from))
}

/// Every paused queue, by annotator name.
pub async fn pauses(hub: &Hub) -> Result<Vec<PauseView>, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::controls::pauses(&mut conn)
        .await?
        .into_iter()
        .map(PauseView::from)
        .collect())
}

/// The refusal of any work on a paused queue.
fn paused_refusal(pause: &Pause) -> AppError {
    Refusal::QueuePaused {
        since: pause.paused_at.clone(),
    }
    .into()
}

/// 409 when the session's annotator's queue is paused. Call inside the write's transaction
/// when there is one, so the check and the write see the same pause.
pub(super) async fn refuse_if_paused(
    conn: &mut store::Conn,
    session: &Session,
) -> Result<(), AppError> {
    match store::controls::pause_of(conn, session.annotator).await? {
        Some(pause) => Err(paused_refusal(&pause)),
        None => Ok(()),
    }
}

/// The ids among `annotators` whose queue is paused.
pub(super) async fn paused_among(
    conn: &mut store::Conn,
    annotators: &[i64],
) -> Result<Vec<i64>, AppError> {
    let paused = store::controls::pauses(conn).await?;
    Ok(annotators
        .iter()
        .copied()
        .filter(|a| paused.iter().any(|p| p.annotator == *a))
        .collect())
}

/// One item handed over.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, JsonSchema)]
pub struct HandedItem {
    pub dataset: String,
    pub item_id: String,
}

/// What one recipient got.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, JsonSchema)]
pub struct HandedTo {
    pub annotator: String,
    pub items: Vec<HandedItem>,
}

/// What a handover did.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, JsonSchema)]
pub struct Handover {
    /// The annotator whose unfinished items moved.
    pub from: String,
    /// Each recipient (in the order chosen) with the items they got.
    pub to: Vec<HandedTo>,
    /// Unfinished items every recipient held already: they stay in `from`'s queue.
    pub kept: Vec<HandedItem>,
    /// Unfinished gold items and attention checks taken out of `from`'s queue (not handed on:
    /// they judge the annotator they were mixed in for).
    pub removed_checks: u64,
    /// Drafts of moved items removed.
    pub drafts_removed: u64,
    /// Gold items and attention checks mixed into the recipients' queues for what they got.
    pub mixed_in: u64,
}

/// Hands `from`'s unfinished items to `to` (every other active annotator, admins aside, whose
/// queue is running, when empty) with a balanced split, in one transaction with its audit
/// entry; see the module's documentation for what moves and what stays.
pub async fn handover(
    hub: &Hub,
    actor: &Actor,
    from: &str,
    to: &[String],
) -> Result<Handover, AppError> {
    let mut conn = hub.conn().await?;
    let accounts = store::annotations::annotators(&mut conn).await?;
    let paused = store::controls::pauses(&mut conn).await?;
    drop(conn);
    let by_name = |name: &str| accounts.iter().find(|a| a.name == name);
    let giver = by_name(from).ok_or_else(|| {
        AppError::from(Refusal::NoAnnotator {
            annotator: from.to_owned(),
        })
    })?;
    let is_paused = |id: i64| paused.iter().any(|p| p.annotator == id);
    let recipients: Vec<&Annotator> = if to.is_empty() {
        accounts
            .iter()
            .filter(|a| a.id != giver.id && a.active && !a.is_admin && !is_paused(a.id))
            .collect()
    } else {
        let mut chosen: Vec<&Annotator> = Vec::new();
        for name in to {
            let account = by_name(name.trim()).ok_or_else(|| Refusal::NoAnnotator {
                annotator: name.trim().to_owned(),
            })?;
            if account.id == giver.id {
                return Err(Refusal::HandoverToSelf {
                    annotator: from.to_owned(),
                }
                .into());
            }
            if is_paused(account.id) {
                return Err(Refusal::RecipientPaused {
                    annotator: account.name.clone(),
                }
                .into());
            }
            if !chosen.iter().any(|c| c.id == account.id) {
                chosen.push(account);
            }
        }
        chosen
    };
    if recipients.is_empty() {
        return Err(Refusal::NoRecipient {
            annotator: from.to_owned(),
        }
        .into());
    }
    let recipient_ids: Vec<i64> = recipients.iter().map(|a| a.id).collect();

    let mut tx = hub.write(Lane::Interactive).await?;
    let unfinished = store::controls::unfinished(&mut tx, giver.id).await?;
    let held = store::controls::held_items(&mut tx, &recipient_ids).await?;
    let (coverage, checks): (Vec<_>, Vec<_>) = unfinished.iter().partition(|u| !u.mixed);
    let splits: Vec<_> = coverage.iter().map(|u| u.split).collect();
    let (pairs, left) = handover_split(&splits, &recipient_ids, &held);
    let moving: Vec<i64> = pairs
        .iter()
        .map(|p| p.1)
        .chain(checks.iter().map(|u| u.split.item))
        .collect();
    let taken = store::controls::take_unfinished(&mut tx, giver.id, &moving).await?;
    let (taken, drafts_removed) = (taken.items, taken.drafts);
    // Only what left the queue in this transaction moves (all of it: the write lock is ours).
    let pairs: Vec<(i64, i64)> = pairs
        .into_iter()
        .filter(|(_, item)| taken.contains(item))
        .collect();
    store::annotations::assign(&mut tx, &pairs).await?;
    let mut datasets: BTreeMap<i64, &str> = BTreeMap::new();
    for u in &coverage {
        if pairs.iter().any(|p| p.1 == u.split.item) {
            datasets.insert(u.dataset_id, &u.dataset);
        }
    }
    let mut mixed_in = 0;
    for &dataset_id in datasets.keys() {
        mixed_in += super::gold::after_assignment(&mut tx, dataset_id, &recipient_ids).await?;
        mixed_in += super::attention::after_assignment(&mut tx, dataset_id, &recipient_ids).await?;
    }
    let info: HashMap<i64, &store::controls::Unfinished> =
        unfinished.iter().map(|u| (u.split.item, u)).collect();
    let handed = |item: &i64| HandedItem {
        dataset: info[item].dataset.clone(),
        item_id: info[item].item_id.clone(),
    };
    let to: Vec<HandedTo> = recipients
        .iter()
        .map(|r| HandedTo {
            annotator: r.name.clone(),
            items: pairs
                .iter()
                .filter(|p| p.0 == r.id)
                .map(|p| handed(&p.1))
                .collect(),
        })
        .collect();
    let removed_checks = checks
        .iter()
        .filter(|u| taken.contains(&u.split.item))
        .count() as u64;
    let detail = format!(
        "{} unfinished items handed over ({}); {} every recipient held stayed; {} gold items \
         and attention checks taken out; {drafts_removed} drafts removed",
        pairs.len(),
        to.iter()
            .map(|t| format!("{} to {}", t.items.len(), t.annotator))
            .collect::<Vec<_>>()
            .join(", "),
        left.len(),
        removed_checks,
    );
    audit::record(
        &mut tx,
        actor,
        AuditAction::AnnotatorHandover,
        format!("annotator {from}"),
        match datasets.values().next() {
            Some(name) if datasets.len() == 1 => Some(*name),
            _ => None,
        },
        detail,
    )
    .await?;
    for &item in &taken {
        tx.announce(Change::Standing {
            annotator: giver.id,
            item,
        })
        .await?;
    }
    tx.commit().await?;
    Ok(Handover {
        from: from.to_owned(),
        to,
        kept: left.iter().map(handed).collect(),
        removed_checks,
        drafts_removed,
        mixed_in,
    })
}
