//! The explorer: a dataset's items × its leaderboard rows (the board's rows, one per account
//! and model, and the Human column) as a grid of verdicts, filtered, sorted and counted by
//! `core::explorer`. The page `/datasets/{d}/explore`, its JSON and its CSV read it.
//!
//! The grid is built once per board and kept with it ([`leaderboard::Board::explorer`]): what
//! changes the board (a submission, a listing, an annotator's answer, an exclusion, an import)
//! drops both, and the next reader builds them again. A view is then a pass over the grid's
//! items in memory. A dataset whose answers are hidden shows it to admins only.

use std::collections::BTreeMap;
use std::sync::Arc;

use schemars::JsonSchema;
use serde::Serialize;

use crate::core::annotation::{CountedVerdict, human_verdict};
use crate::core::dataset::{AnswerVisibility, Direction, StepLength};
use crate::core::explorer::{
    Counts, Exploration, Grid, GridBuilder, GridItem, GridRow, HumanTally, View, ViewText,
};
use crate::core::leaderboard::{RowSource, one_per_model};
use crate::core::submission::AnswerVerdict;
use crate::store;

use super::leaderboard::Board;
use super::refusal::Refusal;
use super::{AppError, Hub, datasets, leaderboard};

/// One view of a dataset's grid, ready to be cut into pages.
#[derive(Debug, Clone)]
pub struct Explored {
    pub dataset: String,
    pub grid: Arc<Grid>,
    pub view: View,
    pub exploration: Exploration,
}

/// The Human column's cell: its verdict and the answers it rests on.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct HumanCell {
    pub verdict: AnswerVerdict,
    #[serde(flatten)]
    pub tally: HumanTally,
}

/// One item of a page.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ExploredItem {
    pub id: String,
    pub direction: Direction,
    pub step_length: StepLength,
    /// ENACT's `task_name`.
    pub activity: String,
    /// The share of the judged rows (every model row, and the Human column when it has a
    /// verdict) that are wrong; `null` when no row is judged.
    pub difficulty: Option<f64>,
    pub rows_wrong: u32,
    pub rows_judged: u32,
    /// Each model row's verdict, in the order of `rows`.
    pub verdicts: Vec<AnswerVerdict>,
    pub human: HumanCell,
}

/// A page of the explorer, as the API serves it.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ExplorerPage {
    pub dataset: String,
    /// The view's query parameters, defaults left out (its permalink's, with `page`).
    pub view: BTreeMap<String, String>,
    /// The model rows, in the leaderboard's order; the Human column follows them.
    pub rows: Vec<GridRow>,
    pub counts: Counts,
    pub page: usize,
    pub per_page: usize,
    pub pages: usize,
    pub items: Vec<ExploredItem>,
}

impl Explored {
    /// Item `i` of the grid as a page shows it.
    pub fn item(&self, i: usize) -> ExploredItem {
        let g = &self.grid;
        let (rows_wrong, rows_judged) = g.wrong_of_judged(i);
        let tally = g.human(i);
        ExploredItem {
            id: g.id(i).to_owned(),
            direction: g.direction(i),
            step_length: g.step_length(i),
            activity: g.activity(i).to_owned(),
            difficulty: g.difficulty(i),
            rows_wrong,
            rows_judged,
            verdicts: g.verdicts(i).to_vec(),
            human: HumanCell {
                verdict: tally.verdict(),
                tally,
            },
        }
    }

    /// Page `page` (1-based) of `per_page` items.
    pub fn page(&self, page: usize, per_page: usize) -> ExplorerPage {
        ExplorerPage {
            dataset: self.dataset.clone(),
            view: self
                .grid
                .view_query(&self.view)
                .into_iter()
                .map(|(k, v)| (k.to_owned(), v))
                .collect(),
            rows: self.grid.rows().to_vec(),
            counts: self.exploration.counts.clone(),
            page,
            per_page,
            pages: self.exploration.pages(per_page),
            items: self
                .exploration
                .page(page, per_page)
                .iter()
                .map(|&i| self.item(i))
                .collect(),
        }
    }

    /// Every matching item as CSV, in the view's order, stamped with the dataset, the view and
    /// the rows.
    pub fn csv(&self) -> String {
        let stamp = self.grid.stamp(&self.dataset, &self.view);
        self.grid.csv(&self.exploration.order, &stamp)
    }
}

/// The view `text` of the explorer of dataset `dataset`. `admin`: the reader is an admin (who
/// also sees datasets whose answers are hidden).
pub async fn view(
    hub: &Hub,
    dataset: &str,
    text: &ViewText<'_>,
    admin: bool,
) -> Result<Explored, AppError> {
    let board = leaderboard::board(hub, dataset).await?;
    if !admin && datasets::answer_visibility(hub, &board.dataset).await? != AnswerVisibility::Public
    {
        return Err(Refusal::AnswersHidden {
            dataset: board.dataset.name.clone(),
        }
        .into());
    }
    let grid = grid(hub, &board).await?;
    let view = grid.parse_view(text).map_err(AppError::Invalid)?;
    let exploration = grid.explore(&view);
    Ok(Explored {
        dataset: board.dataset.name.clone(),
        grid,
        view,
        exploration,
    })
}

/// The board's grid, built by its first reader and kept with the board.
pub async fn grid(hub: &Hub, board: &Board) -> Result<Arc<Grid>, AppError> {
    Ok(board
        .explorer
        .get_or_try_init(|| build(hub, board))
        .await?
        .clone())
}

/// Reads the board's verdicts and the answers its Human row counts, and builds the grid.
async fn build(hub: &Hub, board: &Board) -> Result<Arc<Grid>, AppError> {
    let rows: Vec<GridRow> = one_per_model(&board.rows)
        .into_iter()
        .filter(|r| r.source == RowSource::Submission)
        .filter_map(|r| {
            Some(GridRow {
                submission: r.submission?,
                model: r.model,
                account: r.account,
                baseline: r.baseline,
            })
        })
        .collect();
    let submissions: Vec<i64> = rows.iter().map(|r| r.submission).collect();
    let mut conn = hub.conn().await?;
    let items = store::items::summaries(&mut conn, board.dataset.id).await?;
    let cells = store::submissions::verdict_cells(&mut conn, &submissions).await?;
    let answers = store::annotations::counted_answers(&mut conn, board.dataset.id).await?;
    drop(conn);
    let name = board.dataset.name.clone();
    let built = hub.heavy().run(move || {
        let index: rustc_hash::FxHashMap<i64, usize> = items
            .iter()
            .enumerate()
            .map(|(i, (rowid, _))| (*rowid, i))
            .collect();
        let column: rustc_hash::FxHashMap<i64, usize> = submissions
            .iter()
            .enumerate()
            .map(|(r, id)| (*id, r))
            .collect();
        let mut grid = GridBuilder::new(
            items
                .into_iter()
                .map(|(_, s)| GridItem {
                    id: s.item_id,
                    direction: s.direction,
                    step_length: s.step_length,
                    activity: s.task_name,
                })
                .collect(),
            rows,
        );
        // Verdicts of items a replacing import removed name no item here: left out.
        for cell in &cells {
            if let (Some(&item), Some(&row)) = (index.get(&cell.item), column.get(&cell.submission))
            {
                grid.verdict(
                    item,
                    row,
                    AnswerVerdict::of(cell.outcome, cell.exact_match, cell.task_accuracy),
                );
            }
        }
        for answer in &answers {
            let Some(&item) = index.get(&answer.item) else {
                continue;
            };
            // Answers finished before verdicts were stored are judged here, as the Human row
            // judges them.
            let verdict = match &answer.verdict {
                CountedVerdict::Stored { verdict, .. } => *verdict,
                CountedVerdict::Unscored(a) => human_verdict(a).map_err(|e| {
                    AppError::internal(format!(
                        "dataset '{name}': a stored answer on item {}: {e}",
                        a.item_id
                    ))
                })?,
            };
            grid.human_answer(item, verdict.exact_match, verdict.task_accuracy);
        }
        Ok::<_, AppError>(Arc::new(grid.finish()))
    });
    built.await?
}
