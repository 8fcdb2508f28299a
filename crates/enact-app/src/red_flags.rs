//! A dataset's red flags for its admins (`core::red_flags` decides; this reads the facts): rows
//! above the Human row on the humans' items, submissions answering a hidden dataset with its
//! ground truth, and items or frames shared with public datasets. An import reports its
//! shared items and frames as it finishes ([`leak_at_import`]).

use schemars::JsonSchema;
use serde::Serialize;

use super::{AppError, Hub, audit, datasets, explore, leaderboard};
use crate::Lane;
use crate::core::audit::{Actor, AuditAction};
use crate::core::dataset::AnswerVisibility;
use crate::core::red_flags::{self, AboveHuman, Leak, TruthCopy};
use crate::store;

/// What an admin is shown about a dataset.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct RedFlags {
    pub dataset: String,
    pub answers: AnswerVisibility,
    /// Leaderboard rows whose task accuracy on the items with human answers is above the
    /// humans' there.
    pub above_human: Vec<AboveHuman>,
    /// Submissions (listed or not) answering more than `truth_share` of the items exactly as
    /// the ground truth; only looked for while the dataset's answers are hidden.
    pub identical_to_truth: Vec<TruthCopy>,
    pub truth_share: f64,
    /// Public datasets holding some of this dataset's items or frames; only looked for while
    /// its answers are hidden.
    pub leaks: Vec<Leak>,
}

impl RedFlags {
    pub fn count(&self) -> usize {
        self.above_human.len() + self.identical_to_truth.len() + self.leaks.len()
    }
}

/// The red flags of dataset `name`, with submissions flagged above `truth_share` exact answers.
pub async fn of(hub: &Hub, name: &str, truth_share: f64) -> Result<RedFlags, AppError> {
    let board = leaderboard::board(hub, name).await?;
    let dataset = &board.dataset;
    let answers = datasets::answer_visibility(hub, dataset).await?;
    let grid = explore::grid(hub, &board).await?;
    let above_human = red_flags::above_human(&grid);
    let (identical_to_truth, leaks) = if answers == AnswerVisibility::Hidden {
        let mut conn = hub.conn().await?;
        let counts = store::red_flags::exact_answers(&mut conn, dataset.id).await?;
        let leaks = store::red_flags::leaks(&mut conn, dataset.id).await?;
        (
            red_flags::identical_to_truth(&counts, grid.len(), truth_share),
            leaks,
        )
    } else {
        (Vec::new(), Vec::new())
    };
    Ok(RedFlags {
        dataset: dataset.name.clone(),
        answers,
        above_human,
        identical_to_truth,
        truth_share,
        leaks,
    })
}

/// After an import into `name`: the public datasets sharing its items or frames, audited
/// (`dataset.leak`) when there are any and its answers are hidden (a new dataset's are). A
/// dataset whose answers are public leaks nothing by sharing.
pub async fn leak_at_import(hub: &Hub, actor: &Actor, name: &str) -> Result<Vec<Leak>, AppError> {
    let dataset = datasets::by_name(hub, name).await?;
    if datasets::answer_visibility(hub, &dataset).await? == AnswerVisibility::Public {
        return Ok(Vec::new());
    }
    let mut conn = hub.conn().await?;
    let leaks = store::red_flags::leaks(&mut conn, dataset.id).await?;
    drop(conn);
    if !leaks.is_empty() {
        let detail = leaks
            .iter()
            .map(|l| {
                format!(
                    "{} items and {} frames also in public dataset '{}'",
                    l.items, l.frames, l.dataset
                )
            })
            .collect::<Vec<_>>()
            .join("; ");
        let mut tx = hub.write(Lane::Interactive).await?;
        audit::record(
            &mut tx,
            actor,
            AuditAction::DatasetLeak,
            format!("dataset {name}"),
            Some(name),
            detail,
        )
        .await?;
        tx.commit().await?;
    }
    Ok(leaks)
}
