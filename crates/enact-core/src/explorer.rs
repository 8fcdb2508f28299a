//! The explorer: a dataset's items × its leaderboard rows as a grid of verdicts, filtered by
//! direction, step length, activity and pattern, sorted by difficulty or by one row, and
//! counted per filter. The grid is built once per board (one byte per cell, each item's tallies
//! computed then); every view is cut from it in memory, so a page of the full dataset costs a
//! pass over its items and one sort.
//!
//! The rules, in one place:
//! - A cell is a row's [`AnswerVerdict`] on an item. "Right" is task-correct: exact or
//!   accepted as equivalent. A model row's missing answer counts as wrong, as its task
//!   accuracy counts it.
//! - The Human column pools the answers the Human row counts ([`HumanTally`]): right when more
//!   than half of them are task-correct (exact when more than half are exact), wrong otherwise,
//!   missing when there is none. A missing Human cell is no verdict: it is neither right nor
//!   wrong, and an item's difficulty leaves it out.
//! - Difficulty is the share of an item's judged rows (every model row, and the Human column
//!   when it has a verdict) that are wrong.

use std::cmp::Ordering;
use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::Serialize;

use crate::bundle::{Stamp, csv_document, csv_field};
use crate::dataset::{Direction, StepLength};
use crate::submission::AnswerVerdict;

/// Items on a page unless the view asks for another number.
pub const DEFAULT_PER_PAGE: usize = 50;
/// The most items a page shows.
pub const MAX_PER_PAGE: usize = 500;

/// How the Human column's key reads in a view's text (`sort=wrong:human`).
pub const HUMAN_KEY: &str = "human";

/// An item of the grid, as the store has it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GridItem {
    pub id: String,
    pub direction: Direction,
    pub step_length: StepLength,
    /// ENACT's `task_name`.
    pub activity: String,
}

/// A model row of the grid: one leaderboard row, the submission behind it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, JsonSchema)]
pub struct GridRow {
    pub submission: i64,
    pub model: String,
    pub account: String,
    pub baseline: bool,
}

impl GridRow {
    /// How tables and files name the row: `model (#submission)`.
    pub fn label(&self) -> String {
        format!("{} (#{})", self.model, self.submission)
    }
}

/// The answers the Human row counts on one item.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, JsonSchema)]
pub struct HumanTally {
    pub answers: u32,
    /// Task-correct answers.
    pub right: u32,
    /// Answers in the true order.
    pub exact: u32,
}

impl HumanTally {
    pub fn add(&mut self, exact_match: bool, task_accuracy: bool) {
        self.answers += 1;
        self.right += u32::from(task_accuracy || exact_match);
        self.exact += u32::from(exact_match);
    }

    /// The column's verdict: the majority's. A tie is not a majority, so it is wrong.
    pub fn verdict(self) -> AnswerVerdict {
        if self.answers == 0 {
            AnswerVerdict::Missing
        } else if 2 * self.exact > self.answers {
            AnswerVerdict::Exact
        } else if 2 * self.right > self.answers {
            AnswerVerdict::Equivalent
        } else {
            AnswerVerdict::Wrong
        }
    }
}

/// Task-correct: exact or accepted as equivalent.
pub fn is_right(verdict: AnswerVerdict) -> bool {
    matches!(verdict, AnswerVerdict::Exact | AnswerVerdict::Equivalent)
}

/// A column of the grid: a model row (by its index) or the Human column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RowRef {
    Model(usize),
    Human,
}

/// Items picked by how the rows answered them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pattern {
    /// The Human column is right and no model row is.
    HumansRightModelsWrong,
    /// At least one model row is right and at least one is not.
    ModelsDisagree,
    /// At least one model row's answer could not be read.
    UnparseableByAny,
    /// This model row is right and no other model row is.
    OnlyRight(usize),
}

/// The order of the matching items. Ties keep the dataset's order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Sort {
    /// The largest share of judged rows wrong first; items without a judged row last.
    #[default]
    Difficulty,
    /// The row's wrong items first, then its right ones, then those it has no verdict on.
    WrongFirst(RowRef),
    /// The row's right items first, then its wrong ones, then those it has no verdict on.
    RightFirst(RowRef),
}

/// One view of the grid: the filters (each `None` for any) and the order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct View {
    pub direction: Option<Direction>,
    pub step_length: Option<StepLength>,
    /// An index into [`Grid::activities`].
    pub activity: Option<usize>,
    pub pattern: Option<Pattern>,
    pub sort: Sort,
}

/// A view as a query string spells it: each parameter's text, blank for the default.
#[derive(Debug, Clone, Copy, Default)]
pub struct ViewText<'a> {
    /// `forward` or `inverse`.
    pub direction: &'a str,
    /// 3 to 10.
    pub step_length: &'a str,
    /// An activity (`task_name`) of the dataset.
    pub activity: &'a str,
    /// `humans-right-models-wrong`, `models-disagree`, `unparseable` or `only:<submission>`.
    pub pattern: &'a str,
    /// `difficulty`, `wrong:<row>` or `right:<row>`, a row being a submission id or `human`.
    pub sort: &'a str,
}

/// What every view reads of an item, computed once when the grid is built.
#[derive(Debug, Clone, Copy)]
struct ItemTally {
    direction: Direction,
    step_length: StepLength,
    activity: usize,
    /// Model rows that are right.
    models_right: u32,
    /// The one model row that is right, when exactly one is.
    sole_right: Option<usize>,
    unparseable: bool,
    human: AnswerVerdict,
    /// Judged rows that are wrong, and judged rows.
    wrong: u32,
    judged: u32,
}

/// The grid: every item of a dataset × every model row, one verdict per cell, and the Human
/// column's tallies. Built by a [`GridBuilder`].
#[derive(Debug, Clone)]
pub struct Grid {
    ids: Vec<String>,
    /// Sorted; items refer to them by index.
    activities: Vec<String>,
    rows: Vec<GridRow>,
    /// Item-major: item `i`'s verdicts are `cells[i * rows.len()..][..rows.len()]`.
    cells: Vec<AnswerVerdict>,
    humans: Vec<HumanTally>,
    tallies: Vec<ItemTally>,
    /// The step lengths present, sorted.
    step_lengths: Vec<StepLength>,
}

/// Fills a grid: every cell starts missing.
#[derive(Debug, Clone)]
pub struct GridBuilder {
    items: Vec<GridItem>,
    rows: Vec<GridRow>,
    cells: Vec<AnswerVerdict>,
    humans: Vec<HumanTally>,
}

impl GridBuilder {
    /// `items` in the dataset's order; `rows` in the leaderboard's.
    pub fn new(items: Vec<GridItem>, rows: Vec<GridRow>) -> GridBuilder {
        GridBuilder {
            cells: vec![AnswerVerdict::Missing; items.len() * rows.len()],
            humans: vec![HumanTally::default(); items.len()],
            items,
            rows,
        }
    }

    /// Row `row`'s verdict on item `item` (indices into the lists given to [`Self::new`]).
    pub fn verdict(&mut self, item: usize, row: usize, verdict: AnswerVerdict) {
        let width = self.rows.len();
        if row < width
            && let Some(cell) = self.cells.get_mut(item * width + row)
        {
            *cell = verdict;
        }
    }

    /// One answer the Human row counts on item `item`.
    pub fn human_answer(&mut self, item: usize, exact_match: bool, task_accuracy: bool) {
        if let Some(tally) = self.humans.get_mut(item) {
            tally.add(exact_match, task_accuracy);
        }
    }

    pub fn finish(self) -> Grid {
        let width = self.rows.len();
        let mut activities: Vec<String> = self.items.iter().map(|i| i.activity.clone()).collect();
        activities.sort_unstable();
        activities.dedup();
        let mut step_lengths: Vec<StepLength> = self.items.iter().map(|i| i.step_length).collect();
        step_lengths.sort_unstable();
        step_lengths.dedup();
        let tallies = self
            .items
            .iter()
            .enumerate()
            .map(|(i, item)| {
                let verdicts = &self.cells[i * width..(i + 1) * width];
                let mut right = verdicts.iter().enumerate().filter(|(_, v)| is_right(**v));
                let first_right = right.next().map(|(r, _)| r);
                let models_right = u32::from(first_right.is_some()) + right.count() as u32;
                let human = self.humans[i].verdict();
                let human_judged = human != AnswerVerdict::Missing;
                ItemTally {
                    direction: item.direction,
                    step_length: item.step_length,
                    activity: activities.binary_search(&item.activity).unwrap_or_default(),
                    models_right,
                    sole_right: if models_right == 1 { first_right } else { None },
                    unparseable: verdicts.contains(&AnswerVerdict::Unparseable),
                    human,
                    wrong: width as u32 - models_right
                        + u32::from(human_judged && !is_right(human)),
                    judged: width as u32 + u32::from(human_judged),
                }
            })
            .collect();
        Grid {
            ids: self.items.into_iter().map(|i| i.id).collect(),
            activities,
            rows: self.rows,
            cells: self.cells,
            humans: self.humans,
            tallies,
            step_lengths,
        }
    }
}

/// How many items one value of a filter would show, the other filters kept.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, JsonSchema)]
pub struct FacetCount<T> {
    pub value: T,
    pub items: usize,
}

/// How many items each pattern would show, the other filters kept.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, JsonSchema)]
pub struct PatternCounts {
    /// Items the other filters match, whatever the pattern.
    pub any: usize,
    pub humans_right_models_wrong: usize,
    pub models_disagree: usize,
    pub unparseable: usize,
    /// Per model row, in the grid's order: the items only it gets right.
    pub only_right: Vec<FacetCount<i64>>,
}

/// The counts of a view.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, JsonSchema)]
pub struct Counts {
    /// Items in the dataset.
    pub items: usize,
    /// Items every filter matches.
    pub matching: usize,
    /// Per direction, step length, activity and pattern: the items that value would show with
    /// the other filters as they are.
    pub directions: Vec<FacetCount<Direction>>,
    pub step_lengths: Vec<FacetCount<StepLength>>,
    pub activities: Vec<FacetCount<String>>,
    pub patterns: PatternCounts,
    /// Per model row, in the grid's order, then the Human column: how many matching items it
    /// gets right.
    pub right: Vec<usize>,
}

/// A view's result: the matching items in the view's order, and its counts.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Exploration {
    /// Indices of items.
    pub order: Vec<usize>,
    pub counts: Counts,
}

impl Exploration {
    /// The items of page `page` (1-based) of `per_page` items.
    pub fn page(&self, page: usize, per_page: usize) -> &[usize] {
        let start = page.saturating_sub(1).saturating_mul(per_page);
        let start = start.min(self.order.len());
        let end = start.saturating_add(per_page).min(self.order.len());
        &self.order[start..end]
    }

    /// Pages of `per_page` items (at least one, empty when nothing matches).
    pub fn pages(&self, per_page: usize) -> usize {
        self.order.len().div_ceil(per_page.max(1)).max(1)
    }
}

/// What a CSV download is stamped with.
#[derive(Debug, Clone)]
pub struct ExplorerStamp {
    pub dataset: String,
    /// The view's query string.
    pub view: String,
    /// Each model row's label.
    pub rows: Vec<String>,
}

impl Stamp for ExplorerStamp {
    fn stamp_fields(&self) -> Vec<String> {
        let mut lines = vec![
            format!("dataset: {}", self.dataset),
            format!("view: {}", self.view),
        ];
        lines.extend(self.rows.iter().map(|r| format!("row: {r}")));
        lines.push(
            "human: the majority verdict of the answers the Human row counts \
             (right when more than half are task-correct)"
                .to_owned(),
        );
        lines
    }
}

/// The three classes a row's cell sorts by.
fn class(verdict: AnswerVerdict, row: RowRef, right_first: bool) -> u8 {
    let judged = row != RowRef::Human || verdict != AnswerVerdict::Missing;
    match (judged, is_right(verdict) == right_first) {
        (false, _) => 2,
        (true, true) => 0,
        (true, false) => 1,
    }
}

impl Grid {
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    pub fn rows(&self) -> &[GridRow] {
        &self.rows
    }

    /// The dataset's activities, sorted.
    pub fn activities(&self) -> &[String] {
        &self.activities
    }

    /// The step lengths the dataset has, sorted.
    pub fn step_lengths(&self) -> &[StepLength] {
        &self.step_lengths
    }

    pub fn id(&self, item: usize) -> &str {
        &self.ids[item]
    }

    pub fn direction(&self, item: usize) -> Direction {
        self.tallies[item].direction
    }

    pub fn step_length(&self, item: usize) -> StepLength {
        self.tallies[item].step_length
    }

    pub fn activity(&self, item: usize) -> &str {
        &self.activities[self.tallies[item].activity]
    }

    /// Each model row's verdict on `item`, in the rows' order.
    pub fn verdicts(&self, item: usize) -> &[AnswerVerdict] {
        let width = self.rows.len();
        &self.cells[item * width..(item + 1) * width]
    }

    pub fn human(&self, item: usize) -> HumanTally {
        self.humans[item]
    }

    /// The verdict in column `row` on `item`.
    pub fn cell(&self, item: usize, row: RowRef) -> AnswerVerdict {
        match row {
            RowRef::Model(r) => self.verdicts(item)[r],
            RowRef::Human => self.tallies[item].human,
        }
    }

    /// The share of the item's judged rows that are wrong; `None` with none judged.
    pub fn difficulty(&self, item: usize) -> Option<f64> {
        let t = &self.tallies[item];
        (t.judged > 0).then(|| f64::from(t.wrong) / f64::from(t.judged))
    }

    /// Wrong rows and judged rows on `item`.
    pub fn wrong_of_judged(&self, item: usize) -> (u32, u32) {
        let t = &self.tallies[item];
        (t.wrong, t.judged)
    }

    /// The column a view's text names: a model row's submission id, or `human`.
    pub fn row_by_key(&self, key: &str) -> Option<RowRef> {
        if key == HUMAN_KEY {
            return Some(RowRef::Human);
        }
        let id: i64 = key.parse().ok()?;
        self.rows
            .iter()
            .position(|r| r.submission == id)
            .map(RowRef::Model)
    }

    /// How a view's text names column `row`.
    pub fn row_key(&self, row: RowRef) -> String {
        match row {
            RowRef::Model(r) => self.rows[r].submission.to_string(),
            RowRef::Human => HUMAN_KEY.to_owned(),
        }
    }

    /// The text of a pattern, as [`Self::parse_view`] reads it.
    pub fn pattern_text(&self, pattern: Pattern) -> String {
        match pattern {
            Pattern::HumansRightModelsWrong => "humans-right-models-wrong".to_owned(),
            Pattern::ModelsDisagree => "models-disagree".to_owned(),
            Pattern::UnparseableByAny => "unparseable".to_owned(),
            Pattern::OnlyRight(r) => format!("only:{}", self.rows[r].submission),
        }
    }

    /// The text of an order, as [`Self::parse_view`] reads it.
    pub fn sort_text(&self, sort: Sort) -> String {
        match sort {
            Sort::Difficulty => "difficulty".to_owned(),
            Sort::WrongFirst(row) => format!("wrong:{}", self.row_key(row)),
            Sort::RightFirst(row) => format!("right:{}", self.row_key(row)),
        }
    }

    /// The view `text` spells; an error names the parameter and says what it may be.
    pub fn parse_view(&self, text: &ViewText<'_>) -> Result<View, String> {
        fn given(s: &str) -> Option<&str> {
            Some(s.trim()).filter(|s| !s.is_empty())
        }
        let direction =
            match given(text.direction) {
                None => None,
                Some(d) => Some(Direction::parse(&d.to_ascii_lowercase()).ok_or_else(|| {
                    format!("`direction` must be `forward` or `inverse`, not {d:?}")
                })?),
            };
        let step_length = match given(text.step_length) {
            None => None,
            Some(s) => Some(
                s.parse::<usize>()
                    .ok()
                    .and_then(StepLength::new)
                    .ok_or_else(|| {
                        format!("`step_length` must be a whole number from 3 to 10, not {s:?}")
                    })?,
            ),
        };
        let activity = match given(text.activity) {
            None => None,
            Some(a) => Some(
                self.activities
                    .binary_search_by(|x| x.as_str().cmp(a))
                    .map_err(|_| format!("`activity`: the dataset has no activity {a:?}"))?,
            ),
        };
        let model_row = |key: &str, what: &str| match self.row_by_key(key) {
            Some(RowRef::Model(r)) => Ok(r),
            _ => Err(format!(
                "`{what}`: {key:?} is not the submission id of a row of this leaderboard"
            )),
        };
        let pattern = match given(text.pattern) {
            None => None,
            Some("humans-right-models-wrong") => Some(Pattern::HumansRightModelsWrong),
            Some("models-disagree") => Some(Pattern::ModelsDisagree),
            Some("unparseable") => Some(Pattern::UnparseableByAny),
            Some(p) => match p.strip_prefix("only:") {
                Some(key) => Some(Pattern::OnlyRight(model_row(key.trim(), "pattern")?)),
                None => {
                    return Err(format!(
                        "`pattern` must be `humans-right-models-wrong`, `models-disagree`, \
                         `unparseable` or `only:<submission id>`, not {p:?}"
                    ));
                }
            },
        };
        let row = |key: &str| {
            self.row_by_key(key.trim()).ok_or_else(|| {
                format!(
                    "`sort`: {key:?} is neither `human` nor the submission id of a row of this \
                     leaderboard"
                )
            })
        };
        let sort = match given(text.sort) {
            None | Some("difficulty") => Sort::Difficulty,
            Some(s) => match (s.strip_prefix("wrong:"), s.strip_prefix("right:")) {
                (Some(key), _) => Sort::WrongFirst(row(key)?),
                (_, Some(key)) => Sort::RightFirst(row(key)?),
                _ => {
                    return Err(format!(
                        "`sort` must be `difficulty`, `wrong:<row>` or `right:<row>` (a row is \
                         a submission id or `human`), not {s:?}"
                    ));
                }
            },
        };
        Ok(View {
            direction,
            step_length,
            activity,
            pattern,
            sort,
        })
    }

    /// The view's query parameters, defaults left out, in a fixed order: the permalink's.
    pub fn view_query(&self, view: &View) -> Vec<(&'static str, String)> {
        let mut query = Vec::new();
        if let Some(d) = view.direction {
            query.push(("direction", d.as_str().to_owned()));
        }
        if let Some(l) = view.step_length {
            query.push(("step_length", l.to_string()));
        }
        if let Some(a) = view.activity {
            query.push(("activity", self.activities[a].clone()));
        }
        if let Some(p) = view.pattern {
            query.push(("pattern", self.pattern_text(p)));
        }
        if view.sort != Sort::Difficulty {
            query.push(("sort", self.sort_text(view.sort)));
        }
        query
    }

    fn matches(&self, t: &ItemTally, pattern: Pattern) -> bool {
        match pattern {
            Pattern::HumansRightModelsWrong => {
                is_right(t.human) && t.models_right == 0 && !self.rows.is_empty()
            }
            Pattern::ModelsDisagree => {
                t.models_right > 0 && (t.models_right as usize) < self.rows.len()
            }
            Pattern::UnparseableByAny => t.unparseable,
            Pattern::OnlyRight(r) => t.sole_right == Some(r),
        }
    }

    /// The items `view` shows, in its order, and its counts.
    pub fn explore(&self, view: &View) -> Exploration {
        let mut directions = [0usize; 2];
        let mut step_lengths: BTreeMap<StepLength, usize> =
            self.step_lengths.iter().map(|&l| (l, 0)).collect();
        let mut activities = vec![0usize; self.activities.len()];
        let mut patterns = PatternCounts {
            only_right: self
                .rows
                .iter()
                .map(|r| FacetCount {
                    value: r.submission,
                    items: 0,
                })
                .collect(),
            ..PatternCounts::default()
        };
        let mut order = Vec::new();
        for (i, t) in self.tallies.iter().enumerate() {
            let d = view.direction.is_none_or(|d| d == t.direction);
            let s = view.step_length.is_none_or(|l| l == t.step_length);
            let a = view.activity.is_none_or(|a| a == t.activity);
            let p = view.pattern.is_none_or(|p| self.matches(t, p));
            if s && a && p {
                directions[usize::from(t.direction == Direction::Inverse)] += 1;
            }
            if d && a && p {
                *step_lengths.entry(t.step_length).or_default() += 1;
            }
            if d && s && p {
                activities[t.activity] += 1;
            }
            if d && s && a {
                patterns.any += 1;
                let counted = [
                    (
                        Pattern::HumansRightModelsWrong,
                        &mut patterns.humans_right_models_wrong,
                    ),
                    (Pattern::ModelsDisagree, &mut patterns.models_disagree),
                    (Pattern::UnparseableByAny, &mut patterns.unparseable),
                ];
                for (pattern, count) in counted {
                    *count += usize::from(self.matches(t, pattern));
                }
                if let Some(r) = t.sole_right {
                    patterns.only_right[r].items += 1;
                }
                if p {
                    order.push(i);
                }
            }
        }
        let width = self.rows.len();
        let mut right = vec![0usize; width + 1];
        for &i in &order {
            for (r, v) in self.verdicts(i).iter().enumerate() {
                right[r] += usize::from(is_right(*v));
            }
            right[width] += usize::from(is_right(self.tallies[i].human));
        }
        self.sort(&mut order, view.sort);
        Exploration {
            counts: Counts {
                items: self.len(),
                matching: order.len(),
                directions: Direction::ALL
                    .into_iter()
                    .zip(directions)
                    .map(|(value, items)| FacetCount { value, items })
                    .collect(),
                step_lengths: step_lengths
                    .into_iter()
                    .map(|(value, items)| FacetCount { value, items })
                    .collect(),
                activities: self
                    .activities
                    .iter()
                    .zip(activities)
                    .map(|(value, items)| FacetCount {
                        value: value.clone(),
                        items,
                    })
                    .collect(),
                patterns,
                right,
            },
            order,
        }
    }

    fn sort(&self, order: &mut [usize], sort: Sort) {
        match sort {
            Sort::Difficulty => order.sort_by(|&a, &b| {
                let (a, b) = (&self.tallies[a], &self.tallies[b]);
                match (a.judged, b.judged) {
                    (0, 0) => Ordering::Equal,
                    (0, _) => Ordering::Greater,
                    (_, 0) => Ordering::Less,
                    // a / ja > b / jb first, compared without division.
                    _ => (u64::from(b.wrong) * u64::from(a.judged))
                        .cmp(&(u64::from(a.wrong) * u64::from(b.judged))),
                }
            }),
            Sort::WrongFirst(row) | Sort::RightFirst(row) => {
                let right_first = matches!(sort, Sort::RightFirst(_));
                order.sort_by_key(|&i| class(self.cell(i, row), row, right_first));
            }
        }
    }

    /// What a CSV download of this grid is stamped with.
    pub fn stamp(&self, dataset: &str, view: &View) -> ExplorerStamp {
        ExplorerStamp {
            dataset: dataset.to_owned(),
            view: self
                .view_query(view)
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect::<Vec<_>>()
                .join("&"),
            rows: self
                .rows
                .iter()
                .map(|r| {
                    format!(
                        "{} account {}{}",
                        r.label(),
                        r.account,
                        if r.baseline { " (baseline)" } else { "" }
                    )
                })
                .collect(),
        }
    }

    /// The items `order` names as CSV: one line per item, each row's verdict in a column of its
    /// own, then the Human column's verdict and tally.
    pub fn csv(&self, order: &[usize], stamp: &ExplorerStamp) -> String {
        let mut header: Vec<String> = [
            "item",
            "direction",
            "step_length",
            "activity",
            "rows_wrong",
            "rows_judged",
        ]
        .iter()
        .map(|h| (*h).to_owned())
        .collect();
        // Model names are anyone's text: quoted like every field.
        header.extend(self.rows.iter().map(|r| csv_field(&r.label())));
        header.extend(["human", "human_right", "human_answers"].map(str::to_owned));
        let header: Vec<&str> = header.iter().map(String::as_str).collect();
        let lines: Vec<Vec<String>> = order
            .iter()
            .map(|&i| {
                let (wrong, judged) = self.wrong_of_judged(i);
                let human = self.human(i);
                let mut line = vec![
                    self.id(i).to_owned(),
                    self.direction(i).as_str().to_owned(),
                    self.step_length(i).to_string(),
                    self.activity(i).to_owned(),
                    wrong.to_string(),
                    judged.to_string(),
                ];
                line.extend(self.verdicts(i).iter().map(|v| v.as_str().to_owned()));
                line.push(human.verdict().as_str().to_owned());
                line.push(human.right.to_string());
                line.push(human.answers.to_string());
                line
            })
            .collect();
        csv_document(stamp, &header, &lines)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use AnswerVerdict::{Equivalent as Q, Exact as E, Missing as M, Unparseable as U, Wrong as W};

    fn l(n: usize) -> StepLength {
        StepLength::new(n).expect("a step length")
    }

    fn row(submission: i64, model: &str) -> GridRow {
        GridRow {
            submission,
            model: model.to_owned(),
            account: "team".to_owned(),
            baseline: false,
        }
    }

    /// Eight items, three model rows (submissions 11, 12, 13) and the Human column:
    ///
    /// | item | kind  | activity | 11 | 12 | 13 | humans (right/exact of answers) |
    /// |------|-------|----------|----|----|----|---------------------------------|
    /// | i0   | F L=3 | cook     | E  | E  | E  | 1/1 of 1 → exact                |
    /// | i1   | F L=3 | cook     | W  | W  | W  | 2/2 of 3 → exact                |
    /// | i2   | I L=3 | wash     | E  | W  | U  | none → missing                  |
    /// | i3   | I L=4 | wash     | W  | Q  | W  | 1/0 of 2 → wrong (a tie)        |
    /// | i4   | F L=4 | cook     | W  | W  | M  | 2/0 of 3 → equivalent           |
    /// | i5   | I L=4 | cook     | U  | W  | W  | 0/0 of 1 → wrong                |
    /// | i6   | F L=5 | wash     | W  | E  | W  | none → missing                  |
    /// | i7   | I L=5 | wash     | Q  | W  | E  | 1/1 of 1 → exact                |
    fn grid() -> Grid {
        let kinds = [
            (Direction::Forward, 3, "cook"),
            (Direction::Forward, 3, "cook"),
            (Direction::Inverse, 3, "wash"),
            (Direction::Inverse, 4, "wash"),
            (Direction::Forward, 4, "cook"),
            (Direction::Inverse, 4, "cook"),
            (Direction::Forward, 5, "wash"),
            (Direction::Inverse, 5, "wash"),
        ];
        let items = kinds
            .iter()
            .enumerate()
            .map(|(i, (direction, n, activity))| GridItem {
                id: format!("i{i}"),
                direction: *direction,
                step_length: l(*n),
                activity: (*activity).to_owned(),
            })
            .collect();
        let mut b = GridBuilder::new(
            items,
            vec![row(11, "Alpha"), row(12, "Beta"), row(13, "Gamma")],
        );
        let cells = [
            [E, E, E],
            [W, W, W],
            [E, W, U],
            [W, Q, W],
            [W, W, M],
            [U, W, W],
            [W, E, W],
            [Q, W, E],
        ];
        for (i, line) in cells.iter().enumerate() {
            for (r, v) in line.iter().enumerate() {
                b.verdict(i, r, *v);
            }
        }
        // (item, exact, task-correct) per answer.
        for (item, exact, right) in [
            (0, true, true),
            (1, true, true),
            (1, true, true),
            (1, false, false),
            (3, false, true),
            (3, false, false),
            (4, false, true),
            (4, false, true),
            (4, false, false),
            (5, false, false),
            (7, true, true),
        ] {
            b.human_answer(item, exact, right);
        }
        b.finish()
    }

    fn ids(grid: &Grid, e: &Exploration) -> Vec<String> {
        e.order.iter().map(|&i| grid.id(i).to_owned()).collect()
    }

    fn shown(grid: &Grid, text: ViewText<'_>) -> Vec<String> {
        let view = grid.parse_view(&text).expect("a view");
        ids(grid, &grid.explore(&view))
    }

    fn set(grid: &Grid, text: ViewText<'_>) -> Vec<String> {
        let mut found = shown(grid, text);
        found.sort();
        found
    }

    #[test]
    fn the_human_column_is_the_majority_of_the_counted_answers() {
        let g = grid();
        let human: Vec<AnswerVerdict> = (0..g.len()).map(|i| g.cell(i, RowRef::Human)).collect();
        assert_eq!(human, [E, E, M, W, Q, W, M, E]);
        assert_eq!(
            g.human(1),
            HumanTally {
                answers: 3,
                right: 2,
                exact: 2
            }
        );
        assert_eq!(HumanTally::default().verdict(), M);
    }

    #[test]
    fn difficulty_is_the_share_of_judged_rows_wrong() {
        let g = grid();
        // Three model rows, plus the Human column where it has a verdict; a missing model
        // answer counts as wrong.
        assert_eq!(g.wrong_of_judged(0), (0, 4));
        assert_eq!(g.wrong_of_judged(1), (3, 4));
        assert_eq!(g.wrong_of_judged(2), (2, 3));
        assert_eq!(g.wrong_of_judged(4), (3, 4));
        assert_eq!(g.wrong_of_judged(5), (4, 4));
        assert_eq!(g.difficulty(5), Some(1.0));
        assert_eq!(g.difficulty(0), Some(0.0));
    }

    #[test]
    fn the_default_view_shows_every_item_hardest_first() {
        let g = grid();
        // 4/4; then 3/4 (i1, i3, i4 in the dataset's order); then 2/3 (i2, i6); 1/4; 0/4.
        assert_eq!(
            shown(&g, ViewText::default()),
            ["i5", "i1", "i3", "i4", "i2", "i6", "i7", "i0"]
        );
    }

    #[test]
    fn direction_step_length_and_activity_filter() {
        let g = grid();
        let forward = ViewText {
            direction: "forward",
            ..ViewText::default()
        };
        assert_eq!(set(&g, forward), ["i0", "i1", "i4", "i6"]);
        let inverse = ViewText {
            direction: "Inverse",
            ..ViewText::default()
        };
        assert_eq!(set(&g, inverse), ["i2", "i3", "i5", "i7"]);
        let l4 = ViewText {
            step_length: "4",
            ..ViewText::default()
        };
        assert_eq!(set(&g, l4), ["i3", "i4", "i5"]);
        let wash = ViewText {
            activity: "wash",
            ..ViewText::default()
        };
        assert_eq!(set(&g, wash), ["i2", "i3", "i6", "i7"]);
        let all_three = ViewText {
            direction: "inverse",
            step_length: "4",
            activity: "cook",
            ..ViewText::default()
        };
        assert_eq!(set(&g, all_three), ["i5"]);
    }

    #[test]
    fn humans_right_every_model_wrong() {
        let g = grid();
        let view = ViewText {
            pattern: "humans-right-models-wrong",
            ..ViewText::default()
        };
        // i1: humans exact, all wrong; i4: humans equivalent, a missing model answer is wrong.
        // Not i3 (a tie is wrong), i5 (humans wrong), i2 and i6 (no human answer).
        assert_eq!(set(&g, view), ["i1", "i4"]);
    }

    #[test]
    fn models_disagree() {
        let g = grid();
        let view = ViewText {
            pattern: "models-disagree",
            ..ViewText::default()
        };
        assert_eq!(set(&g, view), ["i2", "i3", "i6", "i7"]);
    }

    #[test]
    fn unparseable_by_any() {
        let g = grid();
        let view = ViewText {
            pattern: "unparseable",
            ..ViewText::default()
        };
        assert_eq!(set(&g, view), ["i2", "i5"]);
    }

    #[test]
    fn only_one_model_right() {
        let g = grid();
        let only = |key: &str| {
            let pattern = format!("only:{key}");
            set(
                &g,
                ViewText {
                    pattern: &pattern,
                    ..ViewText::default()
                },
            )
        };
        assert_eq!(only("11"), ["i2"]);
        assert_eq!(only("12"), ["i3", "i6"]);
        assert!(only("13").is_empty(), "i7: Alpha and Gamma both right");
    }

    #[test]
    fn a_pattern_combines_with_the_other_filters() {
        let g = grid();
        let view = ViewText {
            direction: "forward",
            pattern: "models-disagree",
            ..ViewText::default()
        };
        assert_eq!(set(&g, view), ["i6"]);
    }

    #[test]
    fn sorting_by_a_row_puts_its_wrong_or_right_items_first() {
        let g = grid();
        let by = |sort: &str| {
            shown(
                &g,
                ViewText {
                    sort,
                    ..ViewText::default()
                },
            )
        };
        // Beta (12) right on i0, i3, i6; ties keep the dataset's order.
        assert_eq!(
            by("wrong:12"),
            ["i1", "i2", "i4", "i5", "i7", "i0", "i3", "i6"]
        );
        assert_eq!(
            by("right:12"),
            ["i0", "i3", "i6", "i1", "i2", "i4", "i5", "i7"]
        );
        // Gamma's missing answer on i4 is wrong.
        assert_eq!(by("right:13")[..2], ["i0", "i7"]);
        // The Human column's items without a verdict come last either way.
        assert_eq!(
            by("wrong:human"),
            ["i3", "i5", "i0", "i1", "i4", "i7", "i2", "i6"]
        );
        assert_eq!(
            by("right:human"),
            ["i0", "i1", "i4", "i7", "i3", "i5", "i2", "i6"]
        );
        assert_eq!(by("difficulty"), by(""));
    }

    #[test]
    fn counts_per_filter_keep_the_other_filters() {
        let g = grid();
        let view = g
            .parse_view(&ViewText {
                direction: "forward",
                pattern: "models-disagree",
                ..ViewText::default()
            })
            .expect("view");
        let c = g.explore(&view).counts;
        assert_eq!((c.items, c.matching), (8, 1));
        // Directions with the pattern kept: forward i6; inverse i2, i3, i7.
        assert_eq!(
            c.directions,
            [
                FacetCount {
                    value: Direction::Forward,
                    items: 1
                },
                FacetCount {
                    value: Direction::Inverse,
                    items: 3
                }
            ]
        );
        // Step lengths, forward and disagreeing: only i6 (L=5); every length is listed.
        let lengths: Vec<(u8, usize)> = c
            .step_lengths
            .iter()
            .map(|f| (f.value.get(), f.items))
            .collect();
        assert_eq!(lengths, [(3, 0), (4, 0), (5, 1)]);
        let activities: Vec<(&str, usize)> = c
            .activities
            .iter()
            .map(|f| (f.value.as_str(), f.items))
            .collect();
        assert_eq!(activities, [("cook", 0), ("wash", 1)]);
        // Patterns, forward items (i0, i1, i4, i6) whatever the pattern.
        let p = &c.patterns;
        assert_eq!(p.any, 4);
        assert_eq!(
            (
                p.humans_right_models_wrong,
                p.models_disagree,
                p.unparseable
            ),
            (2, 1, 0)
        );
        let only: Vec<(i64, usize)> = p.only_right.iter().map(|f| (f.value, f.items)).collect();
        assert_eq!(only, [(11, 0), (12, 1), (13, 0)]);
        // Right answers among the matching items (i6): Beta only; no human verdict.
        assert_eq!(c.right, [0, 1, 0, 0]);
    }

    #[test]
    fn counts_without_filters_cover_the_dataset() {
        let g = grid();
        let c = g.explore(&View::default()).counts;
        assert_eq!(c.matching, 8);
        assert_eq!(c.patterns.any, 8);
        assert_eq!(
            (
                c.patterns.humans_right_models_wrong,
                c.patterns.models_disagree,
                c.patterns.unparseable
            ),
            (2, 4, 2)
        );
        assert_eq!(c.right, [3, 3, 2, 4]);
        assert_eq!(
            c.directions.iter().map(|f| f.items).sum::<usize>(),
            c.matching
        );
    }

    #[test]
    fn bad_view_texts_are_refused_with_the_parameter_named() {
        let g = grid();
        for (text, named) in [
            (
                ViewText {
                    direction: "sideways",
                    ..ViewText::default()
                },
                "`direction`",
            ),
            (
                ViewText {
                    step_length: "11",
                    ..ViewText::default()
                },
                "`step_length`",
            ),
            (
                ViewText {
                    activity: "juggle",
                    ..ViewText::default()
                },
                "`activity`",
            ),
            (
                ViewText {
                    pattern: "everyone",
                    ..ViewText::default()
                },
                "`pattern`",
            ),
            (
                ViewText {
                    pattern: "only:human",
                    ..ViewText::default()
                },
                "`pattern`",
            ),
            (
                ViewText {
                    pattern: "only:99",
                    ..ViewText::default()
                },
                "`pattern`",
            ),
            (
                ViewText {
                    sort: "wrong:99",
                    ..ViewText::default()
                },
                "`sort`",
            ),
            (
                ViewText {
                    sort: "alphabetical",
                    ..ViewText::default()
                },
                "`sort`",
            ),
        ] {
            let error = g.parse_view(&text).expect_err("refused");
            assert!(error.contains(named), "{error}");
        }
    }

    #[test]
    fn a_view_round_trips_through_its_permalink() {
        let g = grid();
        let text = ViewText {
            direction: "inverse",
            step_length: "4",
            activity: "wash",
            pattern: "only:12",
            sort: "right:human",
        };
        let view = g.parse_view(&text).expect("view");
        let query = g.view_query(&view);
        assert_eq!(
            query,
            [
                ("direction", "inverse".to_owned()),
                ("step_length", "4".to_owned()),
                ("activity", "wash".to_owned()),
                ("pattern", "only:12".to_owned()),
                ("sort", "right:human".to_owned()),
            ]
        );
        let find = |k: &str| {
            query
                .iter()
                .find(|(key, _)| *key == k)
                .map_or("", |(_, v)| v.as_str())
        };
        let again = g
            .parse_view(&ViewText {
                direction: find("direction"),
                step_length: find("step_length"),
                activity: find("activity"),
                pattern: find("pattern"),
                sort: find("sort"),
            })
            .expect("view");
        assert_eq!(again, view);
        assert!(g.view_query(&View::default()).is_empty());
    }

    #[test]
    fn pages_cut_the_order() {
        let g = grid();
        let e = g.explore(&View::default());
        assert_eq!(e.pages(3), 3);
        assert_eq!(e.page(1, 3).len(), 3);
        assert_eq!(e.page(3, 3), &e.order[6..]);
        assert!(e.page(4, 3).is_empty());
        let none = g.explore(&View {
            pattern: Some(Pattern::OnlyRight(2)),
            ..View::default()
        });
        assert_eq!((none.pages(50), none.page(1, 50).len()), (1, 0));
    }

    #[test]
    fn the_csv_has_a_line_per_item_and_a_column_per_row() {
        let g = grid();
        let view = g
            .parse_view(&ViewText {
                pattern: "unparseable",
                ..ViewText::default()
            })
            .expect("view");
        let e = g.explore(&view);
        let csv = g.csv(&e.order, &g.stamp("mini", &view));
        let lines: Vec<&str> = csv.lines().filter(|l| !l.starts_with('#')).collect();
        assert_eq!(
            lines,
            [
                "item,direction,step_length,activity,rows_wrong,rows_judged,Alpha (#11),\
                 Beta (#12),Gamma (#13),human,human_right,human_answers",
                "i5,inverse,4,cook,4,4,unparseable,wrong,wrong,wrong,0,1",
                "i2,inverse,3,wash,2,3,exact,wrong,unparseable,missing,0,0",
            ]
        );
        assert!(csv.starts_with("# dataset: mini\n# view: pattern=unparseable\n"));
    }

    #[test]
    fn a_model_name_in_the_csv_header_is_quoted() {
        let items = vec![GridItem {
            id: "x".to_owned(),
            direction: Direction::Forward,
            step_length: l(3),
            activity: "a".to_owned(),
        }];
        let g = GridBuilder::new(items, vec![row(1, "=cmd, \"x\"")]).finish();
        let e = g.explore(&View::default());
        let csv = g.csv(&e.order, &g.stamp("d", &View::default()));
        assert!(csv.contains(",\"'=cmd, \"\"x\"\" (#1)\","), "{csv}");
    }
}
