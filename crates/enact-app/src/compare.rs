//! Two leaderboard rows of a dataset compared item by item (`core::paired`): the page
//! `/datasets/{d}/compare`, its API and `enact-hub compare`. A row is named by its model (the
//! board's row of that model: its latest published submission) or by a submission id.

use std::collections::HashMap;

use schemars::JsonSchema;
use serde::Serialize;

use crate::core::dataset::{AnswerVisibility, Direction, StepLength};
use crate::core::leaderboard::{RowSource, one_per_model};
use crate::core::paired::{PairedCell, PairedConfig, PairedItem, Side, compare};
use crate::store;
use crate::store::datasets::Dataset;
use crate::store::submissions::{StoredVerdict, SubmissionRow};

use super::refusal::Refusal;
use super::{AppError, Hub, datasets, leaderboard};

/// A compared row: the submission behind it.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ComparedRow {
    pub submission: i64,
    pub model: String,
    pub account: String,
    pub baseline: bool,
    /// The metric version its verdicts were computed with.
    pub metric_version: u32,
}

/// An item one row gets right and the other does not.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct DiscordantItem {
    pub item: String,
    pub direction: Direction,
    pub step_length: StepLength,
    pub activity: String,
}

/// Two rows compared on the items both were scored on.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct RowComparison {
    pub dataset: String,
    pub a: ComparedRow,
    pub b: ComparedRow,
    /// How the intervals were drawn: what was resampled (`activities` by default), how many
    /// times, the seed and the level.
    pub config: PairedConfig,
    /// Every paired item.
    pub overall: PairedCell,
    /// Per direction, then per direction and step length.
    pub cells: Vec<PairedCell>,
    /// Items of the dataset only one of the two has a verdict for (a row scored before a
    /// replacing import changed the items); they are left out of every figure.
    pub unpaired_items: usize,
    /// The two rows' figures come from different metric versions: a rescore of the older
    /// one makes them comparable.
    pub metric_versions_differ: bool,
    /// The items A gets right and B does not, and the other way round; `None` where per-item
    /// verdicts are not shown to this reader (a dataset whose answers are hidden, to anyone
    /// but an admin).
    pub a_only_items: Option<Vec<DiscordantItem>>,
    pub b_only_items: Option<Vec<DiscordantItem>>,
}

/// Compares rows `a` and `b` of the dataset named `dataset`. `admin`: the reader sees per-item
/// verdicts of a dataset whose answers are hidden.
pub async fn rows(
    hub: &Hub,
    dataset: &str,
    a: &str,
    b: &str,
    config: PairedConfig,
    admin: bool,
) -> Result<RowComparison, AppError> {
    let dataset = datasets::by_name(hub, dataset).await?;
    let shown =
        admin || datasets::answer_visibility(hub, &dataset).await? == AnswerVisibility::Public;
    let mut conn = hub.conn().await?;
    let published = store::submissions::published(&mut conn, dataset.id).await?;
    drop(conn);
    let board = one_per_model(&leaderboard::board(hub, &dataset.name).await?.rows);
    let row_a = resolve(&dataset, &published, &board, a, "a")?;
    let row_b = resolve(&dataset, &published, &board, b, "b")?;
    if row_a.id == row_b.id {
        return Err(AppError::Invalid(format!(
            "`a` and `b` are the same row (submission {}): compare two different rows",
            row_a.id
        )));
    }
    let mut conn = hub.conn().await?;
    let activities: HashMap<String, String> = store::items::activities(&mut conn, dataset.id)
        .await?
        .into_iter()
        .collect();
    let mut verdicts_a = store::submissions::verdicts(&mut conn, row_a.id).await?;
    let mut verdicts_b = store::submissions::verdicts(&mut conn, row_b.id).await?;
    drop(conn);
    // On a split dataset before its reveal, only the public part's items (as on the board).
    if let Some(shown) = super::challenge::items_shown(hub, &dataset, admin).await? {
        verdicts_a.retain(|v| shown.contains(&v.id));
        verdicts_b.retain(|v| shown.contains(&v.id));
    }
    let (ids, items, unpaired) = paired_items(&verdicts_a, &verdicts_b, &activities);
    if items.is_empty() {
        return Err(AppError::Invalid(format!(
            "submissions {} and {} of dataset '{}' have no item in common",
            row_a.id, row_b.id, dataset.name
        )));
    }
    let computed = hub.heavy().run(move || {
        let comparison = compare(&items, &config);
        (comparison, items)
    });
    let (comparison, items) = computed.await?;
    let comparison = comparison.ok_or_else(|| AppError::internal("no paired item"))?;
    let discordant = |a_right: bool| {
        items
            .iter()
            .zip(&ids)
            .filter(|(i, _)| i.a.task_correct == a_right && i.b.task_correct != a_right)
            .map(|(i, id)| DiscordantItem {
                item: id.clone(),
                direction: i.direction,
                step_length: i.step_length,
                activity: i.activity.clone(),
            })
            .collect::<Vec<_>>()
    };
    Ok(RowComparison {
        dataset: dataset.name.clone(),
        config: comparison.config,
        overall: comparison.overall,
        cells: comparison.cells,
        unpaired_items: unpaired,
        metric_versions_differ: row_a.metric_version != row_b.metric_version,
        a_only_items: shown.then(|| discordant(true)),
        b_only_items: shown.then(|| discordant(false)),
        a: compared(row_a),
        b: compared(row_b),
    })
}

fn compared(row: &SubmissionRow) -> ComparedRow {
    ComparedRow {
        submission: row.id,
        model: row.model.clone(),
        account: row.account.clone(),
        baseline: row.baseline,
        metric_version: row.metric_version,
    }
}

/// The published submission a row's name means: a submission id, or a model's board row.
fn resolve<'p>(
    dataset: &Dataset,
    published: &'p [SubmissionRow],
    board: &[crate::core::leaderboard::LeaderboardRow],
    name: &str,
    field: &str,
) -> Result<&'p SubmissionRow, AppError> {
    let name = name.trim();
    if name.is_empty() {
        return Err(AppError::Invalid(format!(
            "`{field}` is empty: give a model name or a submission id of dataset '{}'",
            dataset.name
        )));
    }
    if name == "Human" {
        return Err(AppError::Invalid(format!(
            "`{field}`: the Human row pools every annotator's answers, several per item, so it \
             cannot be paired item by item with a model; compare two model rows"
        )));
    }
    if let Ok(id) = name.parse::<i64>() {
        return published.iter().find(|s| s.id == id).ok_or_else(|| {
            AppError::from(Refusal::NoPublishedSubmission {
                field: field.to_owned(),
                dataset: dataset.name.clone(),
                submission: id.to_string(),
            })
        });
    }
    let rows: Vec<_> = board
        .iter()
        .filter(|r| r.source == RowSource::Submission && r.model == name)
        .collect();
    match rows.as_slice() {
        [row] => row
            .submission
            .and_then(|id| published.iter().find(|s| s.id == id))
            .ok_or_else(|| {
                AppError::internal(format!("board row of '{name}' without its submission"))
            }),
        [] => {
            let mut models: Vec<&str> = board
                .iter()
                .filter(|r| r.source == RowSource::Submission)
                .map(|r| r.model.as_str())
                .collect();
            models.sort_unstable();
            models.dedup();
            Err(Refusal::NoPublishedModel {
                field: field.to_owned(),
                dataset: dataset.name.clone(),
                model: name.to_owned(),
                models: models.join(", "),
            }
            .into())
        }
        several => Err(AppError::Invalid(format!(
            "`{field}`: model '{name}' has rows of {} accounts on dataset '{}' (submissions {}): \
             give a submission id",
            several.len(),
            dataset.name,
            several
                .iter()
                .filter_map(|r| r.submission.map(|id| id.to_string()))
                .collect::<Vec<_>>()
                .join(", ")
        ))),
    }
}

/// The items both submissions have a verdict for, in the dataset's order, with their ids; and
/// how many items only one of them has.
fn paired_items(
    a: &[StoredVerdict],
    b: &[StoredVerdict],
    activities: &HashMap<String, String>,
) -> (Vec<String>, Vec<PairedItem>, usize) {
    let side = |v: &StoredVerdict| Side {
        task_correct: v.task_accuracy,
        pairwise_accuracy: v.pairwise_accuracy,
    };
    let of_b: HashMap<&str, &StoredVerdict> = b.iter().map(|v| (v.id.as_str(), v)).collect();
    let mut ids = Vec::new();
    let mut items = Vec::new();
    for va in a {
        let Some(vb) = of_b.get(va.id.as_str()) else {
            continue;
        };
        ids.push(va.id.clone());
        items.push(PairedItem {
            direction: va.direction,
            step_length: va.step_length,
            activity: activities.get(&va.id).cloned().unwrap_or_default(),
            a: side(va),
            b: side(vb),
        });
    }
    let unpaired = a.len() + b.len() - 2 * items.len();
    (ids, items, unpaired)
}
