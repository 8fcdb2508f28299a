//! Human annotation: assigning items to annotators, each annotator's queue, opening an item,
//! saving drafts, and finishing an item with an answer, a skip or a flag.
//!
//! Blind by construction: nothing here hands an annotator an item's ground truth or score, and
//! an item not assigned to the annotator is 403 on every use case.

use std::collections::HashMap;
use std::sync::Arc;

use super::annotators::now_ms;
use super::changes::Change;
use super::refusal::{Expected, Refusal, SkipAction};
use super::{AppError, Hub, audit, datasets, items};
use crate::Lane;
use crate::core::annotation::{
    AssignmentState, Draft, Outcome, QueueEntry, QueueStatus, Session, Telemetry, balanced_split,
    next_in_queue,
};
use crate::core::attention::Instruction;
use crate::core::audit::{Actor, AuditAction};
use crate::core::gold::{self, GoldRate, QueuedEntry};
use crate::store;
use crate::store::annotations::StoredAnnotation;
use crate::store::items::StoredItem;

/// How items go to annotators.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Assignment {
    /// A balanced split of the dataset's unassigned items over these annotators.
    Split(Vec<i64>),
    /// These item ids to one annotator.
    List {
        annotator: i64,
        item_ids: Vec<String>,
    },
}

/// What an assignment did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Assigned {
    /// Pairs asked for.
    pub requested: u64,
    /// Pairs new to the queues (the others were assigned already and left as they were).
    pub added: u64,
    /// Annotators chosen for a split whose queue is paused: left out of it.
    pub paused: Vec<String>,
}

/// Appends items of `dataset` to annotators' queues. A balanced split leaves out annotators
/// whose queue is paused ([`super::controls`]); a split over paused annotators only is refused.
pub async fn assign(
    hub: &Hub,
    actor: &Actor,
    dataset: &str,
    how: &Assignment,
) -> Result<Assigned, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    let names: HashMap<i64, String> = store::annotations::annotators(&mut conn)
        .await?
        .into_iter()
        .map(|a| (a.id, a.name))
        .collect();
    let chosen: &[i64] = match how {
        Assignment::Split(annotators) => annotators,
        Assignment::List { annotator, .. } => std::slice::from_ref(annotator),
    };
    if let Some(unknown) = chosen.iter().find(|a| !names.contains_key(a)) {
        return Err(AppError::Invalid(format!(
            "annotator: no annotator has id {unknown}"
        )));
    }
    let mut paused = Vec::new();
    let pairs = match how {
        Assignment::Split(annotators) => {
            if annotators.is_empty() {
                return Err(Refusal::EmptyList { field: "annotator" }.into());
            }
            paused = super::controls::paused_among(&mut conn, annotators).await?;
            let running: Vec<i64> = annotators
                .iter()
                .copied()
                .filter(|a| !paused.contains(a))
                .collect();
            if running.is_empty() {
                return Err(Refusal::AllChosenPaused.into());
            }
            let items = store::annotations::unassigned_items(&mut conn, dataset.id).await?;
            balanced_split(&items, &running)
        }
        Assignment::List {
            annotator,
            item_ids,
        } => {
            if item_ids.is_empty() {
                return Err(Refusal::EmptyList { field: "items" }.into());
            }
            items::listed(&mut conn, &dataset, item_ids)
                .await?
                .into_iter()
                .map(|r| (*annotator, r))
                .collect()
        }
    };
    drop(conn);
    let mut tx = hub.write(Lane::Interactive).await?;
    let added = store::annotations::assign(&mut tx, &pairs).await?;
    // More ordinary items may call for more gold items and attention checks.
    let gold = super::gold::after_assignment(&mut tx, dataset.id, chosen).await?
        + super::attention::after_assignment(&mut tx, dataset.id, chosen).await?;
    let named: Vec<&str> = chosen.iter().map(|a| names[a].as_str()).collect();
    let how = match how {
        Assignment::Split(_) => "balanced split of the unassigned items",
        Assignment::List { .. } => "listed items",
    };
    audit::record(
        &mut tx,
        actor,
        AuditAction::AssignmentChange,
        format!("annotators {}", named.join(", ")),
        Some(&dataset.name),
        format!(
            "{how}: {} asked, {added} new to the queues{}{}",
            pairs.len(),
            if gold > 0 {
                format!(", and {gold} gold items and attention checks mixed in")
            } else {
                String::new()
            },
            if paused.is_empty() {
                String::new()
            } else {
                let names: Vec<&str> = paused.iter().map(|a| names[a].as_str()).collect();
                format!("; paused, left out: {}", names.join(", "))
            }
        ),
    )
    .await?;
    tx.commit().await?;
    Ok(Assigned {
        requested: pairs.len() as u64,
        added,
        paused: paused.iter().map(|a| names[a].clone()).collect(),
    })
}

/// An annotator's assigned items in queue order, with where each stands: the gold mix's order
/// ([`gold::mix`]), in which nothing tells a gold item from another.
pub async fn queue(hub: &Hub, annotator: i64) -> Result<Vec<QueueEntry>, AppError> {
    let mut conn = hub.conn().await?;
    let rows = store::annotations::queue(&mut conn, annotator).await?;
    let queued = rows
        .into_iter()
        .map(|r| {
            let rate = |stored: Option<i64>| {
                stored
                    .map(GoldRate::new)
                    .transpose()
                    .map_err(AppError::internal)
            };
            Ok(QueuedEntry {
                dataset: r.dataset.clone(),
                gold_rate: rate(r.gold_rate)?,
                attention_rate: rate(r.attention_rate)?,
                entry: QueueEntry {
                    dataset: r.dataset,
                    item_id: r.item_id,
                    direction: r.direction,
                    step_length: r.step_length,
                    status: QueueStatus::of(r.finished, r.started),
                },
            })
        })
        .collect::<Result<Vec<_>, AppError>>()?;
    Ok(gold::mix(queued))
}

/// The item an annotator should work on next: one already started, else the first to do.
pub async fn next(hub: &Hub, annotator: i64) -> Result<Option<QueueEntry>, AppError> {
    Ok(next_in_queue(&queue(hub, annotator).await?).cloned())
}

/// An item assigned to the session's annotator, with the annotator's standing on it.
pub struct AssignedItem {
    pub item: Arc<StoredItem>,
    pub finished: bool,
    /// The draft, when one exists (always after [`open`] on an unfinished item).
    pub draft: Option<Draft>,
    /// The instruction its question carries when the item is an attention check.
    pub attention: Option<Instruction>,
}

/// Looks up an item assigned to the session's annotator: 404 for an unknown dataset or item,
/// 403 for an item that exists but is someone else's (or no one's). Touches the store only
/// for what is not already in memory.
async fn assigned(
    hub: &Hub,
    session: &Session,
    dataset: &str,
    item_id: &str,
) -> Result<(Arc<StoredItem>, AssignmentState), AppError> {
    let item = super::items::get(hub, dataset, item_id).await?;
    let standings = hub.kept::<super::standings::StandingCache>();
    if let Some(known) = standings.get(session.annotator, item.rowid) {
        return Ok((item, known));
    }
    let ticket = standings.ticket();
    let mut conn = hub.conn().await?;
    let read = store::annotations::assignment_state(&mut conn, session.annotator, item.rowid)
        .await?
        .ok_or_else(|| {
            AppError::from(Refusal::NotAssigned {
                dataset: dataset.to_owned(),
                item: item_id.to_owned(),
            })
        })?;
    standings.remember(ticket, session.annotator, item.rowid, read.clone());
    Ok((item, read))
}

/// The announcement that `session`'s standing on `item` changed.
fn standing_changed(session: &Session, item: &StoredItem) -> Change {
    Change::Standing {
        annotator: session.annotator,
        item: item.rowid,
    }
}

/// Opens an assigned item: its first opening creates an empty draft, which starts the item's
/// clock. 409 while the annotator's queue is paused.
pub async fn open(
    hub: &Hub,
    session: &Session,
    dataset: &str,
    item_id: &str,
) -> Result<AssignedItem, AppError> {
    let (item, standing) = assigned(hub, session, dataset, item_id).await?;
    let mut conn = hub.conn().await?;
    super::controls::refuse_if_paused(&mut conn, session).await?;
    let attention = super::attention::instruction_of(&mut conn, item.rowid).await?;
    drop(conn);
    let draft = match (standing.finished, standing.draft) {
        (true, _) => None,
        (false, Some(stored)) => Some(stored.draft),
        (false, None) => {
            // Ordered with a finish made on another instance, as `save_draft` is.
            let mut tx = hub.write(Lane::Interactive).await?;
            // A draft made meanwhile (another tab, another instance) is the one to open.
            let opened =
                match store::annotations::draft(&mut tx, session.annotator, item.rowid).await? {
                    Some(found) => Some(found.draft),
                    None => {
                        let empty = Draft::empty(item.summary.step_length);
                        let created = store::annotations::create_draft(
                            &mut tx,
                            session.annotator,
                            item.rowid,
                            &empty,
                            now_ms(),
                        )
                        .await?;
                        // Not created: finished meanwhile (the standing read was older than the
                        // answer), which leaves no draft.
                        created.then_some(empty)
                    }
                };
            tx.announce(standing_changed(session, &item)).await?;
            tx.commit().await?;
            opened
        }
    };
    Ok(AssignedItem {
        item,
        finished: draft.is_none(),
        draft,
        attention,
    })
}

/// Checks a draft against the item it is for; 409 once the item is finished.
async fn unfinished(
    hub: &Hub,
    session: &Session,
    dataset: &str,
    item_id: &str,
) -> Result<Arc<StoredItem>, AppError> {
    let (item, standing) = assigned(hub, session, dataset, item_id).await?;
    if standing.finished {
        return Err(finished_already(item_id));
    }
    Ok(item)
}

fn finished_already(item_id: &str) -> AppError {
    Refusal::ItemFinished {
        item: item_id.to_owned(),
    }
    .into()
}

fn checked(item: &StoredItem, draft: &Draft) -> Result<(), AppError> {
    draft.check(item.summary.step_length).map_err(|problem| {
        Refusal::DraftInvalid {
            item: item.summary.item_id.clone(),
            problem,
        }
        .into()
    })
}

/// Saves the annotator's draft of an unfinished item.
pub async fn save_draft(
    hub: &Hub,
    session: &Session,
    dataset: &str,
    item_id: &str,
    draft: &Draft,
) -> Result<(), AppError> {
    let item = unfinished(hub, session, dataset, item_id).await?;
    checked(&item, draft)?;
    // A write transaction, so a save is ordered with a finish of the same item made on another
    // instance: it lands before the finish (which drops it) or sees the answer and is refused.
    let mut tx = hub.write(Lane::Interactive).await?;
    super::controls::refuse_if_paused(&mut tx, session).await?;
    let saved =
        store::annotations::save_draft(&mut tx, session.annotator, item.rowid, draft, now_ms())
            .await?;
    tx.announce(standing_changed(session, &item)).await?;
    tx.commit().await?;
    if !saved {
        return Err(finished_already(item_id));
    }
    Ok(())
}

/// Finishes an item with the draft's answer (every slot filled) and its telemetry.
pub async fn answer(
    hub: &Hub,
    session: &Session,
    dataset: &str,
    item_id: &str,
    draft: &Draft,
) -> Result<(), AppError> {
    let item = unfinished(hub, session, dataset, item_id).await?;
    checked(&item, draft)?;
    let Some(answer) = draft.answer() else {
        let empty: Vec<usize> = draft
            .slots
            .iter()
            .enumerate()
            .filter(|(_, s)| s.is_none())
            .map(|(i, _)| i + 1)
            .collect();
        return Err(Refusal::SlotsEmpty {
            item: item_id.to_owned(),
            slots: empty,
        }
        .into());
    };
    finish(
        hub,
        session,
        dataset,
        &item,
        Some(draft),
        Outcome::Answered(answer),
    )
    .await?;
    hub.metrics().annotator_answered();
    Ok(())
}

/// Records a finished item with its telemetry and drops its draft, in one transaction; `save`
/// is written first, so the telemetry counts its last moves. 409 if it was finished meanwhile.
async fn finish(
    hub: &Hub,
    session: &Session,
    dataset: &str,
    item: &StoredItem,
    save: Option<&Draft>,
    outcome: Outcome,
) -> Result<(), AppError> {
    let answered = matches!(outcome, Outcome::Answered(_));
    let now = now_ms();
    let mut tx = hub.write(Lane::Interactive).await?;
    super::controls::refuse_if_paused(&mut tx, session).await?;
    if let Some(draft) = save
        && !store::annotations::save_draft(&mut tx, session.annotator, item.rowid, draft, now)
            .await?
    {
        return Err(finished_already(&item.summary.item_id));
    }
    let stored = store::annotations::draft(&mut tx, session.annotator, item.rowid).await?;
    let telemetry = stored
        .as_ref()
        .map_or_else(Telemetry::none, |d| Telemetry::of(d, now));
    let finished =
        store::annotations::finish(&mut tx, session.annotator, item.rowid, &outcome, &telemetry)
            .await?;
    if !finished {
        return Err(finished_already(&item.summary.item_id));
    }
    if answered {
        // Judged once, here, like a submission's lines: the Human row reads the verdict.
        super::rescore::judge_answer(&mut tx, session.annotator, item.rowid).await?;
    }
    let (action, detail) = match &outcome {
        Outcome::Answered(answer) => (
            AuditAction::AnnotationAnswer,
            format!("{:?}", answer.labels()),
        ),
        Outcome::Skipped(reason) => (AuditAction::AnnotationSkip, format!("skipped: {reason}")),
        Outcome::Flagged(reason) => (AuditAction::AnnotationSkip, format!("flagged: {reason}")),
    };
    audit::record(
        &mut tx,
        &session.actor(),
        action,
        format!("item {}", item.summary.item_id),
        Some(dataset),
        detail,
    )
    .await?;
    tx.announce(standing_changed(session, item)).await?;
    if answered {
        tx.announce(Change::Boards).await?;
    }
    tx.commit().await?;
    Ok(())
}

/// The longest reason a skip or flag may give, in characters.
const MAX_REASON_CHARS: usize = 2000;

/// Finishes an item without an answer: `action` is "skip" or "flag", with a reason.
pub async fn skip(
    hub: &Hub,
    session: &Session,
    dataset: &str,
    item_id: &str,
    action: &str,
    reason: &str,
) -> Result<(), AppError> {
    let item = unfinished(hub, session, dataset, item_id).await?;
    let action = match action {
        "skip" => SkipAction::Skip,
        "flag" => SkipAction::Flag,
        other => {
            let actions = Expected::OneOf(vec!["skip", "flag"]);
            return Err(Refusal::bad_value("action", other, actions).into());
        }
    };
    let reason = reason.trim().to_owned();
    if reason.is_empty() {
        return Err(Refusal::ReasonMissing {
            item: item_id.to_owned(),
            action,
        }
        .into());
    }
    if reason.chars().count() > MAX_REASON_CHARS {
        return Err(Refusal::ReasonTooLong {
            limit: MAX_REASON_CHARS as u64,
        }
        .into());
    }
    let outcome = match action {
        SkipAction::Skip => Outcome::Skipped(reason),
        SkipAction::Flag => Outcome::Flagged(reason),
    };
    finish(hub, session, dataset, &item, None, outcome).await
}

/// The annotator's own finished item: their answer and telemetry, never a score.
pub async fn own_answer(
    hub: &Hub,
    session: &Session,
    dataset: &str,
    item_id: &str,
) -> Result<StoredAnnotation, AppError> {
    let (item, _) = assigned(hub, session, dataset, item_id).await?;
    let mut conn = hub.conn().await?;
    store::annotations::annotation(&mut conn, session.annotator, item.rowid)
        .await?
        .ok_or_else(|| {
            AppError::from(Refusal::NoAnswerYet {
                item: item_id.to_owned(),
            })
        })
}

/// Skipped and flagged items with their reasons, newest first.
pub async fn flags(hub: &Hub) -> Result<Vec<StoredAnnotation>, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::annotations::flags(&mut conn).await?)
}
