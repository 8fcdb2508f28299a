//! Hidden test sets that resist overfitting: a dataset whose answers are hidden, split into a
//! public part (its figures shown while the challenge runs) and a private part (revealed at a
//! deadline an admin sets, or by hand); the submissions accounts select for the final
//! ranking; and what the leaderboard shows of it. The rules themselves are
//! [`crate::core::challenge`]'s.
//!
//! The board ([`super::leaderboard`]) asks [`on_board`] for its rows: every row carries its
//! account's number of submissions to the dataset, and a split dataset's rows are figured over
//! one part — the public part before the reveal, the private part after, where the rows are the
//! selected submissions ([`counted_submissions`]) with their rank change. The reveal at the
//! deadline needs no timer: the first board built or read after it records it (once, audited
//! as the server), and a board kept from before it is not served past it.

use std::collections::{BTreeMap, HashMap};

use rayon::prelude::*;
use schemars::JsonSchema;
use serde::Serialize;

use super::changes::Change;
use super::refusal::{Expected, Refusal};
use super::submissions::{self, SubmissionRow};
use super::tokens::Caller;
use super::{AppError, Hub, audit, datasets};
use crate::Lane;
use crate::core::audit::{Actor, AuditAction};
use crate::core::challenge::{
    Deadline, Entry, Part, PartVerdict, PublicShare, Stratum, StratumSplit, counted_submissions,
    draw_split, part_scores, split_counts, standings,
};
use crate::core::credentials::Scope;
use crate::core::dataset::AnswerVisibility;
use crate::core::leaderboard::LeaderboardRow;
use crate::core::submission::{SubmissionScores, VerdictOutcome, Visibility};
use crate::core::verifier::cluster_ids;
use crate::store;
use crate::store::challenges::{ChallengeRow, ItemResult};
use crate::store::datasets::Dataset;

/// The most submissions a selection limit may allow.
pub const MAX_SELECTION_LIMIT: i64 = 1000;

/// A split dataset's challenge, as its admins see it.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ChallengeView {
    pub dataset: String,
    /// The seed of the draw, and the share of each stratum drawn into the public part.
    pub seed: u64,
    pub public_share: f64,
    pub public_items: usize,
    pub private_items: usize,
    /// Items imported after the split: in neither part, so in no figure of the challenge.
    pub unassigned_items: usize,
    /// Public and private counts per direction and step length.
    pub strata: Vec<StratumSplit>,
    /// When the private part is revealed by itself (UTC), if set.
    pub reveal_at: Option<String>,
    /// When it was revealed; `None` while the challenge runs.
    pub revealed_at: Option<String>,
    /// `deadline` or `hand`, once revealed.
    pub revealed_by: Option<String>,
    /// How many submissions an account may select for the final ranking; `None`: no limit.
    pub selection_limit: Option<i64>,
    pub split_by: String,
    pub split_at: String,
    /// The public part's item ids, in id order (never shown to submitters).
    pub public_item_ids: Vec<String>,
}

/// What a split dataset's board says about its challenge, beside its rows.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct BoardChallenge {
    /// The part the rows' figures are over: `public` until the reveal, `private` after.
    pub part: Part,
    pub public_items: usize,
    pub private_items: usize,
    /// When the private part is revealed by itself (UTC), if set.
    pub reveal_at: Option<String>,
    /// When it was revealed; `None` while the challenge runs.
    pub revealed_at: Option<String>,
    /// How many submissions an account may select for the final ranking; `None`: no limit.
    pub selection_limit: Option<i64>,
}

/// A split dataset's board beyond its rows.
#[derive(Debug)]
pub struct ChallengeBoard {
    /// What the rows are (their part) and the challenge's dates.
    pub shown: BoardChallenge,
    /// The rows of the other part, ranked, with the Human row: before the reveal, the final
    /// ranking as a reveal now would make it (admins may preview it); after it, every
    /// published submission over the public part, as the board stood during the challenge.
    pub other: Vec<LeaderboardRow>,
    /// The deadline of a challenge not revealed yet: the board is stale from then on.
    due_at: Option<Deadline>,
}

impl ChallengeBoard {
    /// The rows over `part`, when `part` is the other one.
    pub fn rows_over(&self, part: Part) -> Option<&[LeaderboardRow]> {
        (part != self.shown.part).then_some(self.other.as_slice())
    }

    /// What the board says when it shows `part`'s rows.
    pub fn showing(&self, part: Part) -> BoardChallenge {
        BoardChallenge {
            part,
            ..self.shown.clone()
        }
    }
}

impl ChallengeBoard {
    /// Whether this board was built before its challenge's deadline, which has now passed: it
    /// must be built again (and the reveal recorded) rather than served.
    pub fn reveal_due(&self) -> bool {
        self.due_at.is_some_and(|d| d <= now())
    }
}

/// The current time, to the second.
fn now() -> Deadline {
    let seconds = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    Deadline::from_unix(i64::try_from(seconds).unwrap_or(i64::MAX))
}

fn not_split(dataset: &str) -> AppError {
    Refusal::ChallengeNotSplit {
        dataset: dataset.to_owned(),
    }
    .into()
}

fn revealed(dataset: &str, challenge: &ChallengeRow) -> Option<AppError> {
    let at = challenge.revealed_at.as_deref()?;
    Some(
        Refusal::ChallengeRevealed {
            dataset: dataset.to_owned(),
            at_deadline: challenge.revealed_by.as_deref() == Some("deadline"),
            at: at.to_owned(),
        }
        .into(),
    )
}

async fn challenge_of(hub: &Hub, dataset: &Dataset) -> Result<Option<ChallengeRow>, AppError> {
    let mut conn = hub.conn().await?;
    Ok(store::challenges::of_dataset(&mut conn, dataset.id).await?)
}

/// The challenge of the dataset named `name`, as its admins see it; 409 when it was not split.
pub async fn status(hub: &Hub, name: &str) -> Result<ChallengeView, AppError> {
    find(hub, name).await?.ok_or_else(|| not_split(name))
}

/// The challenge of the dataset named `name`, if it was split.
pub async fn find(hub: &Hub, name: &str) -> Result<Option<ChallengeView>, AppError> {
    let dataset = datasets::by_name(hub, name).await?;
    match challenge_of(hub, &dataset).await? {
        Some(challenge) => Ok(Some(view(hub, &dataset, &challenge).await?)),
        None => Ok(None),
    }
}

async fn view(
    hub: &Hub,
    dataset: &Dataset,
    challenge: &ChallengeRow,
) -> Result<ChallengeView, AppError> {
    let targets = submissions::dataset_targets(hub, dataset.id).await?;
    let mut conn = hub.conn().await?;
    let parts = store::challenges::parts(&mut conn, dataset.id).await?;
    drop(conn);
    let part_of: HashMap<i64, Part> = parts.iter().map(|(row, _, p)| (*row, *p)).collect();
    let (strata, kinds): (Vec<Stratum>, Vec<Part>) = targets
        .targets
        .iter()
        .zip(&targets.item_rows)
        .filter_map(|(t, row)| Some(((t.direction, t.step_length), *part_of.get(row)?)))
        .unzip();
    let public_items = kinds.iter().filter(|p| **p == Part::Public).count();
    Ok(ChallengeView {
        dataset: dataset.name.clone(),
        seed: challenge.seed,
        public_share: challenge.public_share,
        public_items,
        private_items: kinds.len() - public_items,
        unassigned_items: targets.targets.len() - kinds.len(),
        strata: split_counts(&strata, &kinds),
        reveal_at: challenge.reveal_at.clone(),
        revealed_at: challenge.revealed_at.clone(),
        revealed_by: challenge.revealed_by.clone(),
        selection_limit: challenge.selection_limit,
        split_by: challenge.split_by.clone(),
        split_at: challenge.created_at.clone(),
        public_item_ids: parts
            .into_iter()
            .filter(|(_, _, p)| *p == Part::Public)
            .map(|(_, id, _)| id)
            .collect(),
    })
}

/// Splits a hidden dataset into a public and a private part: `share` of each stratum
/// (direction × step length) drawn into the public part with `seed`
/// ([`crate::core::challenge::draw_split`], over the items in id order, so the same items,
/// share and seed give the same split on any hub). A dataset whose answers are public, or one
/// split before, is refused (a split is final). The split, its audit entry and the
/// announcement to other instances are one transaction.
pub async fn split(
    hub: &Hub,
    actor: &Actor,
    name: &str,
    share: f64,
    seed: u64,
) -> Result<ChallengeView, AppError> {
    let share = PublicShare::new(share).map_err(AppError::Invalid)?;
    let dataset = datasets::by_name(hub, name).await?;
    if datasets::answer_visibility(hub, &dataset).await? == AnswerVisibility::Public {
        return Err(Refusal::ChallengeAnswersPublic {
            dataset: name.to_owned(),
        }
        .into());
    }
    if let Some(existing) = challenge_of(hub, &dataset).await? {
        return Err(already_split(name, &existing));
    }
    let targets = submissions::dataset_targets(hub, dataset.id).await?;
    if targets.targets.len() < 2 {
        return Err(Refusal::ChallengeTooFewItems {
            dataset: name.to_owned(),
            items: targets.targets.len() as u64,
        }
        .into());
    }
    let mut order: Vec<usize> = (0..targets.targets.len()).collect();
    order.sort_by(|a, b| targets.targets[*a].id.cmp(&targets.targets[*b].id));
    let strata: Vec<Stratum> = order
        .iter()
        .map(|&i| (targets.targets[i].direction, targets.targets[i].step_length))
        .collect();
    let parts = draw_split(&strata, share, seed);
    let items: Vec<(i64, Part)> = order
        .iter()
        .zip(&parts)
        .map(|(&i, part)| (targets.item_rows[i], *part))
        .collect();
    let public = parts.iter().filter(|p| **p == Part::Public).count();

    let mut tx = hub.write(Lane::Interactive).await?;
    // Checked again in the write transaction: another admin may have split it meanwhile.
    if let Some(existing) = store::challenges::of_dataset(&mut tx, dataset.id).await? {
        return Err(already_split(name, &existing));
    }
    store::challenges::insert(
        &mut tx,
        dataset.id,
        seed,
        share.get(),
        &actor.to_string(),
        &items,
    )
    .await?;
    audit::record(
        &mut tx,
        actor,
        AuditAction::DatasetSplit,
        format!("dataset {name}"),
        Some(name),
        format!(
            "seed {seed}, public share {}: {public} public and {} private items",
            share.get(),
            parts.len() - public
        ),
    )
    .await?;
    tx.announce(Change::Boards).await?;
    tx.commit().await?;
    tracing::info!(dataset = %name, seed, public, "dataset split for a challenge");
    status(hub, name).await
}

fn already_split(name: &str, existing: &ChallengeRow) -> AppError {
    Refusal::ChallengeAlreadySplit {
        dataset: name.to_owned(),
        at: existing.created_at.clone(),
        by: existing.split_by.clone(),
        seed: existing.seed,
        public_share: existing.public_share.to_string(),
    }
    .into()
}

/// A change to a challenge's settings: each field left out stays as it is; `Some(None)`
/// clears it.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SettingsChange {
    /// RFC 3339 text; a deadline in the past reveals the private part at the next read.
    pub reveal_at: Option<Option<String>>,
    pub selection_limit: Option<Option<i64>>,
}

/// Sets a split dataset's deadline and selection limit, until its reveal (after which both
/// are fixed). An empty change changes nothing and records nothing.
pub async fn configure(
    hub: &Hub,
    actor: &Actor,
    name: &str,
    change: &SettingsChange,
) -> Result<ChallengeView, AppError> {
    let reveal_at = change
        .reveal_at
        .as_ref()
        .map(|d| {
            d.as_deref()
                .map(|text| {
                    Deadline::parse(text)
                        .map(Deadline::text)
                        .map_err(|e| AppError::Invalid(format!("reveal_at: {e}")))
                })
                .transpose()
        })
        .transpose()?;
    if let Some(Some(limit)) = change.selection_limit
        && !(1..=MAX_SELECTION_LIMIT).contains(&limit)
    {
        return Err(Refusal::bad_value(
            "selection_limit",
            limit.to_string(),
            Expected::WholeNumber {
                least: 1,
                most: MAX_SELECTION_LIMIT.unsigned_abs(),
            },
        )
        .into());
    }
    let dataset = datasets::by_name(hub, name).await?;
    let mut tx = hub.write(Lane::Interactive).await?;
    let challenge = store::challenges::of_dataset(&mut tx, dataset.id)
        .await?
        .ok_or_else(|| not_split(name))?;
    if let Some(refused) = revealed(name, &challenge) {
        return Err(refused);
    }
    let mut said = Vec::new();
    if let Some(reveal_at) = &reveal_at {
        store::challenges::set_reveal_at(&mut tx, dataset.id, reveal_at.as_deref()).await?;
        said.push(match reveal_at {
            Some(at) => format!("deadline {at}"),
            None => "no deadline".to_owned(),
        });
    }
    if let Some(limit) = change.selection_limit {
        store::challenges::set_selection_limit(&mut tx, dataset.id, limit).await?;
        said.push(match limit {
            Some(n) => format!("selection limit {n}"),
            None => "no selection limit".to_owned(),
        });
    }
    if said.is_empty() {
        tx.rollback().await?;
        return view(hub, &dataset, &challenge).await;
    }
    audit::record(
        &mut tx,
        actor,
        AuditAction::ChallengeSettings,
        format!("dataset {name}"),
        Some(name),
        said.join(", "),
    )
    .await?;
    tx.announce(Change::Boards).await?;
    tx.commit().await?;
    status(hub, name).await
}

/// Reveals a split dataset's private part now: the leaderboard's figures are over it from then
/// on, and the final ranking, its settings and the selections are fixed.
pub async fn reveal(hub: &Hub, actor: &Actor, name: &str) -> Result<ChallengeView, AppError> {
    let dataset = datasets::by_name(hub, name).await?;
    let mut tx = hub.write(Lane::Interactive).await?;
    let challenge = store::challenges::of_dataset(&mut tx, dataset.id)
        .await?
        .ok_or_else(|| not_split(name))?;
    if let Some(refused) = revealed(name, &challenge) {
        return Err(refused);
    }
    store::challenges::reveal_by_hand(&mut tx, dataset.id, &now().text()).await?;
    audit::record(
        &mut tx,
        actor,
        AuditAction::DatasetReveal,
        format!("dataset {name}"),
        Some(name),
        "private part revealed by hand",
    )
    .await?;
    tx.announce(Change::Boards).await?;
    tx.commit().await?;
    status(hub, name).await
}

/// Records the reveal of a challenge whose deadline has passed, once (whoever reads first;
/// audited as the server). Returns the challenge as it now stands.
async fn reveal_if_due(
    hub: &Hub,
    dataset: &Dataset,
    challenge: ChallengeRow,
) -> Result<ChallengeRow, AppError> {
    let due = challenge.revealed_at.is_none()
        && challenge
            .reveal_at
            .as_deref()
            .and_then(|at| Deadline::parse(at).ok())
            .is_some_and(|at| at <= now());
    if !due {
        return Ok(challenge);
    }
    let mut tx = hub.write(Lane::Interactive).await?;
    if store::challenges::reveal_at_deadline(&mut tx, dataset.id, &now().text()).await? {
        audit::record(
            &mut tx,
            &Actor::Server,
            AuditAction::DatasetReveal,
            format!("dataset {}", dataset.name),
            Some(&dataset.name),
            format!(
                "private part revealed at its deadline {}",
                challenge.reveal_at.as_deref().unwrap_or_default()
            ),
        )
        .await?;
        tx.announce(Change::Boards).await?;
        tx.commit().await?;
        tracing::info!(dataset = %dataset.name, "private part revealed at its deadline");
    } else {
        tx.rollback().await?;
    }
    let mut conn = hub.conn().await?;
    Ok(store::challenges::of_dataset(&mut conn, dataset.id)
        .await?
        .unwrap_or(challenge))
}

/// An account's selections on a split dataset.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct SelectionView {
    pub dataset: String,
    pub account: String,
    /// The account's published submissions it selected for the final ranking, in the order
    /// it selected them.
    pub selected: Vec<i64>,
    /// How many it may select; `None`: no limit.
    pub selection_limit: Option<i64>,
    /// The submissions that make its final rows now: those it selected (the last
    /// `selection_limit` of them), or its latest submission when it selected none.
    pub counted: Vec<i64>,
    /// When the private part was revealed; from then on the selections are fixed.
    pub revealed_at: Option<String>,
}

/// The caller's selections on the dataset named `name`.
pub async fn selection(hub: &Hub, caller: &Caller, name: &str) -> Result<SelectionView, AppError> {
    let dataset = datasets::by_name(hub, name).await?;
    let challenge = challenge_of(hub, &dataset)
        .await?
        .ok_or_else(|| not_split(name))?;
    selection_view(
        hub,
        &dataset,
        &challenge,
        caller.account_id,
        &caller.account_name,
    )
    .await
}

async fn selection_view(
    hub: &Hub,
    dataset: &Dataset,
    challenge: &ChallengeRow,
    account: i64,
    account_name: &str,
) -> Result<SelectionView, AppError> {
    let mut conn = hub.conn().await?;
    let selected = store::challenges::selected_by_account(&mut conn, dataset.id, account).await?;
    let published = store::submissions::published(&mut conn, dataset.id).await?;
    let selections = store::challenges::selections(&mut conn, dataset.id).await?;
    drop(conn);
    let mine: Vec<SubmissionRow> = published
        .into_iter()
        .filter(|s| s.account_id == account)
        .collect();
    Ok(SelectionView {
        dataset: dataset.name.clone(),
        account: account_name.to_owned(),
        selected,
        selection_limit: challenge.selection_limit,
        counted: counted(&mine, &selections, challenge.selection_limit)
            .into_iter()
            .collect(),
        revealed_at: challenge.revealed_at.clone(),
    })
}

/// The selection rule over published `submissions` with the dataset's `selections`.
fn counted(
    submissions: &[SubmissionRow],
    selections: &[(i64, i64)],
    limit: Option<i64>,
) -> std::collections::BTreeSet<i64> {
    let order: HashMap<i64, i64> = selections.iter().copied().collect();
    let entries: Vec<Entry> = submissions
        .iter()
        .map(|s| Entry {
            submission: s.id,
            account: s.account_id,
            selected: order.get(&s.id).copied(),
        })
        .collect();
    counted_submissions(&entries, limit.and_then(|n| usize::try_from(n).ok()))
}

/// Selects a submission for its dataset's final ranking (`selected`), or takes it out. Only
/// its account (or an admin) may; only a published submission of a split dataset can be
/// selected, only before the reveal, and no more than the selection limit per account.
/// Repeating either is harmless and records nothing.
pub async fn set_selected(
    hub: &Hub,
    caller: &Caller,
    id: &str,
    selected: bool,
) -> Result<SelectionView, AppError> {
    let row = submissions::readable(hub, caller, id).await?;
    let dataset = datasets::by_name(hub, &row.dataset).await?;
    let name = &dataset.name;
    if selected && row.visibility != Visibility::Published {
        return Err(Refusal::SelectionNotPublished {
            submission: row.id.to_string(),
            visibility: row.visibility.as_str().to_owned(),
        }
        .into());
    }
    let mut tx = hub.write(Lane::Interactive).await?;
    let challenge = store::challenges::of_dataset(&mut tx, dataset.id)
        .await?
        .ok_or_else(|| not_split(name))?;
    if let Some(refused) = revealed(name, &challenge) {
        return Err(refused);
    }
    let already =
        store::challenges::selected_by_account(&mut tx, dataset.id, row.account_id).await?;
    if selected
        && !already.contains(&row.id)
        && let Some(limit) = challenge.selection_limit
        && already.len() >= usize::try_from(limit).unwrap_or(usize::MAX)
    {
        let listed: Vec<String> = already.iter().map(i64::to_string).collect();
        return Err(Refusal::SelectionLimitReached {
            dataset: name.clone(),
            limit: u64::try_from(limit).unwrap_or(0),
            account: row.account.clone(),
            selected: listed.join(", "),
        }
        .into());
    }
    let changed = if selected {
        store::challenges::select(&mut tx, row.id).await?
    } else {
        store::challenges::unselect(&mut tx, row.id).await?
    };
    if changed {
        audit::record(
            &mut tx,
            &caller.actor(),
            AuditAction::SubmissionSelect,
            format!("submission {}", row.id),
            Some(name),
            if selected {
                "selected for the final ranking"
            } else {
                "taken out of the final ranking"
            },
        )
        .await?;
        tx.announce(Change::Boards).await?;
        tx.commit().await?;
    } else {
        tx.rollback().await?;
    }
    selection_view(hub, &dataset, &challenge, row.account_id, &row.account).await
}

/// The challenge of `dataset` while its private part is hidden from this reader: `None` for an
/// admin, an unsplit dataset, or once revealed (a reveal that is due is recorded here).
async fn hiding_private(
    hub: &Hub,
    dataset: &Dataset,
    admin: bool,
) -> Result<Option<ChallengeRow>, AppError> {
    if admin {
        return Ok(None);
    }
    let Some(challenge) = challenge_of(hub, dataset).await? else {
        return Ok(None);
    };
    let challenge = reveal_if_due(hub, dataset, challenge).await?;
    Ok(challenge.revealed_at.is_none().then_some(challenge))
}

/// Why `caller` may not read yet what carries `row`'s figures over the whole dataset (its
/// signed statement): the dataset is split for a challenge whose private part is not revealed,
/// and the whole dataset's figures beside the public part's give the private part's away.
/// `None` for an admin, an unsplit dataset, or after the reveal.
pub async fn whole_figures_withheld(
    hub: &Hub,
    caller: &Caller,
    row: &SubmissionRow,
) -> Result<Option<String>, AppError> {
    let dataset = datasets::by_name(hub, &row.dataset).await?;
    let Some(challenge) = hiding_private(hub, &dataset, caller.has(Scope::Admin)).await? else {
        return Ok(None);
    };
    let when = challenge
        .reveal_at
        .map(|at| format!(" (due at {at})"))
        .unwrap_or_default();
    Ok(Some(format!(
        "submission {}: dataset '{}' is split for a challenge whose private part is not \
         revealed yet{when}; a statement carries the whole dataset's scores, so it is given \
         after the reveal",
        row.id, row.dataset
    )))
}

/// The scores of a submission as `caller` may see them: on a split dataset before the
/// reveal, anyone but an admin sees them over the public part only (the whole dataset's
/// figures beside the public part's would give the private part's away).
pub async fn as_shown_to(
    hub: &Hub,
    caller: &Caller,
    mut row: SubmissionRow,
) -> Result<SubmissionRow, AppError> {
    let dataset = datasets::by_name(hub, &row.dataset).await?;
    if hiding_private(hub, &dataset, caller.has(Scope::Admin))
        .await?
        .is_none()
    {
        return Ok(row);
    }
    let figures = PartFigures::read(hub, &dataset).await?;
    let mut conn = hub.conn().await?;
    let verdicts = store::submissions::verdicts(&mut conn, row.id).await?;
    drop(conn);
    let by_id: HashMap<&str, usize> = figures
        .item_ids
        .iter()
        .enumerate()
        .map(|(i, id)| (id.as_str(), i))
        .collect();
    let results: HashMap<usize, ItemResult> = verdicts
        .iter()
        .filter_map(|v| {
            let target = *by_id.get(v.id.as_str())?;
            Some((
                target,
                ItemResult {
                    submission: row.id,
                    item: figures.item_rows[target],
                    outcome: v.outcome,
                    task_accuracy: v.task_accuracy,
                    pairwise_accuracy: v.pairwise_accuracy,
                },
            ))
        })
        .collect();
    // One submission's figures: a few milliseconds, so on this task rather than queued
    // behind the heavy pool.
    row.scores = figures.scores(&results, Part::Public);
    Ok(row)
}

/// The items a reader may see figures over on `dataset`: on a split dataset before the reveal,
/// anyone but an admin the public part's (by item id); `None` for every item.
pub async fn items_shown(
    hub: &Hub,
    dataset: &Dataset,
    admin: bool,
) -> Result<Option<std::collections::HashSet<String>>, AppError> {
    if hiding_private(hub, dataset, admin).await?.is_none() {
        return Ok(None);
    }
    let mut conn = hub.conn().await?;
    let parts = store::challenges::parts(&mut conn, dataset.id).await?;
    Ok(Some(
        parts
            .into_iter()
            .filter(|(_, _, part)| *part == Part::Public)
            .map(|(_, id, _)| id)
            .collect(),
    ))
}

/// What figuring a submission over a part needs: the dataset's items in scoring order with
/// their kind, activity and part.
struct PartFigures {
    item_ids: Vec<String>,
    item_rows: Vec<i64>,
    verdict_shape: Vec<PartVerdict>,
    parts: Vec<Option<Part>>,
}

impl PartFigures {
    async fn read(hub: &Hub, dataset: &Dataset) -> Result<PartFigures, AppError> {
        let targets = submissions::dataset_targets(hub, dataset.id).await?;
        let mut conn = hub.conn().await?;
        let parts = store::challenges::parts(&mut conn, dataset.id).await?;
        drop(conn);
        let part_of: HashMap<i64, Part> = parts.into_iter().map(|(row, _, p)| (row, p)).collect();
        let clusters = cluster_ids(targets.targets.iter().map(|t| t.task_name.as_str()));
        Ok(PartFigures {
            item_ids: targets.targets.iter().map(|t| t.id.clone()).collect(),
            item_rows: targets.item_rows.clone(),
            // Each item's verdict as a missing answer; the stored verdict fills it in.
            verdict_shape: targets
                .targets
                .iter()
                .zip(clusters)
                .map(|(t, cluster)| PartVerdict {
                    direction: t.direction,
                    step_length: t.step_length,
                    cluster,
                    outcome: VerdictOutcome::Missing,
                    task_accuracy: false,
                    pairwise_accuracy: Some(0.0),
                    exact_only: t.semantics.is_none(),
                })
                .collect(),
            parts: targets
                .item_rows
                .iter()
                .map(|row| part_of.get(row).copied())
                .collect(),
        })
    }

    /// A submission's scores over `part` from its verdicts by item position; an item it has
    /// no verdict for (imported after it was scored) counts as missing, as the strict policy
    /// counts it.
    fn scores(&self, results: &HashMap<usize, ItemResult>, part: Part) -> SubmissionScores {
        let verdicts: Vec<PartVerdict> = self
            .verdict_shape
            .iter()
            .enumerate()
            .filter(|(i, _)| self.parts[*i] == Some(part))
            .map(|(i, shape)| match results.get(&i) {
                Some(r) => PartVerdict {
                    outcome: r.outcome,
                    task_accuracy: r.task_accuracy,
                    pairwise_accuracy: r.pairwise_accuracy,
                    ..*shape
                },
                None => *shape,
            })
            .collect();
        part_scores(&verdicts)
    }

    fn count(&self, part: Part) -> usize {
        self.parts.iter().filter(|p| **p == Some(part)).count()
    }
}

/// The board's rows of `dataset`, for [`super::leaderboard`]: `rows` are the published
/// `submissions`' rows, in the same order. Each gets its account's number of submissions to
/// the dataset. On a split dataset (after recording a reveal whose deadline has passed) they
/// become the rows of the part shown: before the reveal every published submission over the
/// public part; after it the counted submissions over the private part, with their standing.
/// The other part's rows come back in the [`ChallengeBoard`], unranked and without the Human
/// row (the caller adds it to both). `row_of` is the board's own row of a submission (given
/// in, so that this module and the board's do not use each other).
pub(super) async fn on_board(
    hub: &Hub,
    dataset: &Dataset,
    submissions: &[SubmissionRow],
    rows: &mut Vec<LeaderboardRow>,
    row_of: fn(&SubmissionRow) -> LeaderboardRow,
) -> Result<Option<ChallengeBoard>, AppError> {
    let mut conn = hub.conn().await?;
    let tries: HashMap<i64, usize> =
        store::challenges::submissions_per_account(&mut conn, dataset.id)
            .await?
            .into_iter()
            .map(|(account, n)| (account, usize::try_from(n).unwrap_or(0)))
            .collect();
    let challenge = store::challenges::of_dataset(&mut conn, dataset.id).await?;
    drop(conn);
    for (row, s) in rows.iter_mut().zip(submissions) {
        row.account_submissions = tries.get(&s.account_id).copied();
    }
    let Some(challenge) = challenge else {
        return Ok(None);
    };
    let challenge = reveal_if_due(hub, dataset, challenge).await?;
    let figures = PartFigures::read(hub, dataset).await?;
    let mut conn = hub.conn().await?;
    let results = store::challenges::published_results(&mut conn, dataset.id).await?;
    let selections = store::challenges::selections(&mut conn, dataset.id).await?;
    drop(conn);
    let counted = counted(submissions, &selections, challenge.selection_limit);
    let submissions = submissions.to_vec();
    let (public, private) = hub
        .heavy()
        .run(move || {
            let position: HashMap<i64, usize> = figures
                .item_rows
                .iter()
                .enumerate()
                .map(|(i, row)| (*row, i))
                .collect();
            let mut by_submission: BTreeMap<i64, HashMap<usize, ItemResult>> = BTreeMap::new();
            for r in results {
                if let Some(&i) = position.get(&r.item) {
                    by_submission.entry(r.submission).or_default().insert(i, r);
                }
            }
            let none = HashMap::new();
            let rows_over = |part: Part, which: &(dyn Fn(&SubmissionRow) -> bool + Sync)| {
                submissions
                    .par_iter()
                    .filter(|s| which(s))
                    .map(|s| {
                        let results = by_submission.get(&s.id).unwrap_or(&none);
                        let mut row = row_of(&SubmissionRow {
                            scores: figures.scores(results, part),
                            ..s.clone()
                        });
                        row.account_submissions = tries.get(&s.account_id).copied();
                        row
                    })
                    .collect::<Vec<LeaderboardRow>>()
            };
            let public = rows_over(Part::Public, &|_| true);
            let mut private = rows_over(Part::Private, &|s| counted.contains(&s.id));
            let final_public: Vec<LeaderboardRow> = public
                .iter()
                .filter(|r| r.submission.is_some_and(|id| counted.contains(&id)))
                .cloned()
                .collect();
            let standing = standings(&final_public, &private);
            for row in &mut private {
                row.standing = row.submission.and_then(|id| standing.get(&id).copied());
            }
            let counts = (figures.count(Part::Public), figures.count(Part::Private));
            (public, (private, counts))
        })
        .await?;
    let (private, (public_items, private_items)) = private;
    let revealed = challenge.revealed_at.is_some();
    let (shown, other, part) = if revealed {
        (private, public, Part::Private)
    } else {
        (public, private, Part::Public)
    };
    *rows = shown;
    Ok(Some(ChallengeBoard {
        shown: BoardChallenge {
            part,
            public_items,
            private_items,
            reveal_at: challenge.reveal_at.clone(),
            revealed_at: challenge.revealed_at.clone(),
            selection_limit: challenge.selection_limit,
        },
        other,
        due_at: if revealed {
            None
        } else {
            challenge
                .reveal_at
                .as_deref()
                .and_then(|at| Deadline::parse(at).ok())
        },
    }))
}
