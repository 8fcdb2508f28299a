//! The leaderboard: rows in the paper's Table 1 layout (TA and PA overall, forward, inverse,
//! and per step length 3..10); one row per account and model, ranked with ties, sorted by any
//! column and paged; and the geometry of the accuracy-against-step-length chart (pure;
//! templates draw it).

use schemars::JsonSchema;
use serde::Serialize;

use crate::dataset::StepLength;
use crate::metric::MetricStamp;
use crate::submission::{Provenance, SubmissionScores};
use crate::verifier::{
    ConfidenceInterval, GroupPerformance, PerformanceReport, Resampling, StepPerformance,
};

/// Where a row comes from. Human performance rows (from annotations) will be a second kind:
/// they carry the same cells, so the table and chart draw them without change.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum RowSource {
    Submission,
    /// Annotators' submitted answers, scored by the same verifier as model submissions.
    Human,
}

/// How much the Human row rests on: answers, distinct items and distinct annotators.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, JsonSchema)]
pub struct HumanCoverage {
    pub answers: usize,
    pub items: usize,
    pub annotators: usize,
    /// The dataset's items the Human row can cover (its gold items aside).
    pub dataset_items: usize,
    /// Gold items, whose answers judge annotators and never count here.
    #[serde(default)]
    pub gold_items: usize,
    /// Annotators an admin excluded, whose answers do not count here.
    #[serde(default)]
    pub excluded_annotators: usize,
}

impl HumanCoverage {
    /// From `(annotator, item)` pairs of submitted answers.
    pub fn of_answers<A: Ord, I: Ord>(
        answers: impl IntoIterator<Item = (A, I)>,
        dataset_items: usize,
    ) -> HumanCoverage {
        let mut annotators = std::collections::BTreeSet::new();
        let mut items = std::collections::BTreeSet::new();
        let mut count = 0;
        for (a, i) in answers {
            annotators.insert(a);
            items.insert(i);
            count += 1;
        }
        HumanCoverage {
            answers: count,
            items: items.len(),
            annotators: annotators.len(),
            dataset_items,
            gold_items: 0,
            excluded_annotators: 0,
        }
    }

    /// The same coverage, saying what was left out: `gold_items` (not counted in
    /// `dataset_items` either) and `excluded_annotators`.
    pub fn leaving_out(self, gold_items: usize, excluded_annotators: usize) -> HumanCoverage {
        HumanCoverage {
            dataset_items: self.dataset_items.saturating_sub(gold_items),
            gold_items,
            excluded_annotators,
            ..self
        }
    }
}

/// Where a final row of a split dataset stands over each part, and how far it moved
/// (`crate::challenge::standings`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
pub struct Standing {
    /// Its rank among the final rows by overall task accuracy over the public part.
    pub public_rank: Option<usize>,
    /// Its rank among the same rows over the private part.
    pub private_rank: Option<usize>,
    /// `public_rank − private_rank`: places gained at the reveal (negative: lost).
    pub rank_change: Option<i64>,
}

/// A Human cell resting on fewer answers than this is marked, not shown as a bare figure.
pub const MIN_HUMAN_ANSWERS: usize = 5;

/// TA and PA as fractions in [0, 1]; `None` where the group had no item.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, JsonSchema)]
pub struct AccuracyCell {
    pub task_accuracy: Option<f64>,
    pub pairwise_accuracy: Option<f64>,
    pub count: usize,
}

#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct DirectionColumns {
    pub total: AccuracyCell,
    /// Step lengths 3..=10, in order.
    pub per_step: Vec<(u8, AccuracyCell)>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct Interval {
    pub low: f64,
    pub high: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct LeaderboardRow {
    /// The rank among ranked rows (submissions that are not baselines) by the board's sort;
    /// `None` for the Human row and baselines, which are shown for reference.
    pub rank: Option<usize>,
    /// Published submissions of this account and model (1 when every submission is shown).
    pub attempts: usize,
    /// Every submission of this account to the dataset, listed or not (hidden and withdrawn
    /// ones too): how many times it has been scored here. `None` for the Human row.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub account_submissions: Option<usize>,
    /// On a split dataset's final ranking (`crate::challenge`): the row's rank over the public
    /// part, over the private part, and the change.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub standing: Option<Standing>,
    pub source: RowSource,
    /// Where the row's answers came from: `run` (this hub asked the model) or `submitted`
    /// (uploaded); `None` for the Human row.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub provenance: Option<Provenance>,
    /// The model run a `run` row came from (its stamp: `GET /api/v1/runs/{run}/stamp`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub run: Option<i64>,
    /// The submission id.
    pub submission: Option<i64>,
    pub model: String,
    pub account: String,
    pub baseline: bool,
    pub submitted_at: String,
    pub overall: AccuracyCell,
    pub overall_task_accuracy_ci: Option<Interval>,
    pub overall_pairwise_accuracy_ci: Option<Interval>,
    /// What the intervals' bootstrap resampled (`activities` by default; `items` when asked
    /// for, or for scores stored before the hub clustered its intervals); `None` without
    /// intervals.
    pub interval_resampling: Option<Resampling>,
    /// The item bootstrap's `(task, pairwise)` intervals, swapped in when a reader asks for
    /// them.
    #[serde(skip)]
    #[schemars(skip)]
    pub item_intervals: Option<(Option<Interval>, Option<Interval>)>,
    pub forward: DirectionColumns,
    pub inverse: DirectionColumns,
    pub coverage: f64,
    pub parse_failure_rate: f64,
    /// The Human row's answers, items and annotators; `None` for submissions.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub human: Option<HumanCoverage>,
    /// The metric version the row's figures were computed with (the Human row: the oldest
    /// among its answers' verdicts), and whether that is older than the current one.
    #[serde(flatten)]
    pub metric: MetricStamp,
}

fn cell(group: Option<&StepPerformance>) -> AccuracyCell {
    group.map_or_else(AccuracyCell::default, |g| AccuracyCell {
        task_accuracy: Some(g.task_accuracy),
        pairwise_accuracy: g.pairwise_accuracy,
        count: g.count,
    })
}

fn columns(group: Option<&GroupPerformance>) -> DirectionColumns {
    DirectionColumns {
        total: cell(group.map(|g| &g.totals)),
        per_step: StepLength::all()
            .map(|l| {
                (
                    l.get(),
                    cell(group.and_then(|g| g.per_step.get(&l.states()))),
                )
            })
            .collect(),
    }
}

fn interval(v: Option<ConfidenceInterval>) -> Option<Interval> {
    v.map(|v| Interval {
        low: v.low,
        high: v.high,
    })
}

/// The identity of a submission row, as stored.
pub struct RowIdentity<'a> {
    pub submission: i64,
    pub model: &'a str,
    pub account: &'a str,
    pub baseline: bool,
    pub submitted_at: &'a str,
    /// The metric version its scores were computed with.
    pub metric_version: u32,
    pub provenance: Provenance,
    /// The model run that filed it, if any.
    pub run: Option<i64>,
}

impl LeaderboardRow {
    /// A row from a submission's scores.
    pub fn from_scores(who: &RowIdentity<'_>, scores: &SubmissionScores) -> LeaderboardRow {
        let report = &scores.report;
        LeaderboardRow {
            rank: None,
            attempts: 1,
            account_submissions: None,
            standing: None,
            source: RowSource::Submission,
            provenance: Some(who.provenance),
            run: who.run,
            submission: Some(who.submission),
            model: who.model.to_owned(),
            account: who.account.to_owned(),
            baseline: who.baseline,
            submitted_at: who.submitted_at.to_owned(),
            overall: cell(report.overall.as_ref().map(|g| &g.totals)),
            overall_task_accuracy_ci: interval(scores.confidence.task_accuracy),
            overall_pairwise_accuracy_ci: interval(scores.confidence.pairwise_accuracy),
            interval_resampling: (scores.confidence.task_accuracy.is_some()
                || scores.confidence.pairwise_accuracy.is_some())
            .then_some(scores.confidence.resampling),
            item_intervals: scores
                .confidence
                .by_items
                .map(|i| (interval(i.task_accuracy), interval(i.pairwise_accuracy))),
            forward: columns(report.forward_world_modeling.as_ref()),
            inverse: columns(report.inverse_world_modeling.as_ref()),
            coverage: scores.coverage.coverage,
            parse_failure_rate: scores.coverage.parse_failure_rate,
            human: None,
            metric: MetricStamp::of(who.metric_version),
        }
    }

    /// The Human row: `report` over the annotators' submitted answers, whose verdicts were
    /// computed with the metric version `metric` says. It is never ranked among models (it is a
    /// reference row, like baselines); `human` says what it rests on.
    pub fn human(
        report: &PerformanceReport,
        coverage: HumanCoverage,
        metric: MetricStamp,
    ) -> LeaderboardRow {
        let dataset_items = coverage.dataset_items;
        let overall = cell(report.overall.as_ref().map(|g| &g.totals));
        LeaderboardRow {
            rank: None,
            attempts: 1,
            account_submissions: None,
            standing: None,
            source: RowSource::Human,
            provenance: None,
            run: None,
            submission: None,
            model: "Human".to_owned(),
            account: "annotators".to_owned(),
            baseline: false,
            submitted_at: String::new(),
            coverage: if dataset_items == 0 {
                0.0
            } else {
                overall.count as f64 / dataset_items as f64
            },
            overall,
            overall_task_accuracy_ci: None,
            overall_pairwise_accuracy_ci: None,
            interval_resampling: None,
            item_intervals: None,
            forward: columns(report.forward_world_modeling.as_ref()),
            inverse: columns(report.inverse_world_modeling.as_ref()),
            parse_failure_rate: 0.0,
            human: Some(coverage),
            metric,
        }
    }
}

impl LeaderboardRow {
    /// The row with the item bootstrap's intervals, where it has them, when `resampling`
    /// asks for items.
    pub fn with_resampling(mut self, resampling: Resampling) -> Self {
        if resampling == Resampling::Items
            && let Some((task, pairwise)) = self.item_intervals
        {
            self.overall_task_accuracy_ci = task;
            self.overall_pairwise_accuracy_ci = pairwise;
            self.interval_resampling = Some(Resampling::Items);
        }
        self
    }

    /// Whether the row competes for a rank: a submission that is not a baseline.
    pub fn is_ranked(&self) -> bool {
        self.source == RowSource::Submission && !self.baseline
    }
}

/// A group of columns of the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColumnGroup {
    Overall,
    Forward,
    Inverse,
}

/// A column to sort and rank by: `overall_ta`, `overall_pa`, `forward_ta`, `inverse_pa`, or one
/// step length of a direction, `forward_ta_5`, `inverse_pa_10`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SortKey {
    pub group: ColumnGroup,
    /// A step length of the forward or inverse group.
    pub step: Option<StepLength>,
    /// Pairwise accuracy rather than task accuracy.
    pub pairwise: bool,
}

impl Default for SortKey {
    /// Overall task accuracy, the paper's headline figure.
    fn default() -> Self {
        SortKey {
            group: ColumnGroup::Overall,
            step: None,
            pairwise: false,
        }
    }
}

impl SortKey {
    /// Reads a column name; the message lists what is accepted.
    pub fn parse(text: &str) -> Result<SortKey, String> {
        let refuse = || {
            format!(
                "sort: {text:?} is not a column; use overall_ta, overall_pa, forward_ta, \
                 forward_pa, inverse_ta, inverse_pa, or forward_ta_L (…) with L from 3 to 10"
            )
        };
        let mut parts = text.trim().split('_');
        let group = match parts.next() {
            Some("overall") => ColumnGroup::Overall,
            Some("forward") => ColumnGroup::Forward,
            Some("inverse") => ColumnGroup::Inverse,
            _ => return Err(refuse()),
        };
        let pairwise = match parts.next() {
            Some("ta") => false,
            Some("pa") => true,
            _ => return Err(refuse()),
        };
        let step = match parts.next() {
            None => None,
            Some(_) if group == ColumnGroup::Overall => return Err(refuse()),
            Some(l) => Some(
                l.parse()
                    .ok()
                    .and_then(StepLength::new)
                    .ok_or_else(refuse)?,
            ),
        };
        if parts.next().is_some() {
            return Err(refuse());
        }
        Ok(SortKey {
            group,
            step,
            pairwise,
        })
    }

    /// The name [`SortKey::parse`] reads back.
    pub fn name(&self) -> String {
        let group = match self.group {
            ColumnGroup::Overall => "overall",
            ColumnGroup::Forward => "forward",
            ColumnGroup::Inverse => "inverse",
        };
        let metric = if self.pairwise { "pa" } else { "ta" };
        match self.step {
            None => format!("{group}_{metric}"),
            Some(l) => format!("{group}_{metric}_{l}"),
        }
    }

    /// The column as a person reads it: "overall TA", "forward PA at L=5".
    pub fn label(&self) -> String {
        let group = match self.group {
            ColumnGroup::Overall => "overall",
            ColumnGroup::Forward => "forward",
            ColumnGroup::Inverse => "inverse",
        };
        let metric = if self.pairwise { "PA" } else { "TA" };
        match self.step {
            None => format!("{group} {metric}"),
            Some(l) => format!("{group} {metric} at L={l}"),
        }
    }

    /// The row's value in this column, if the row has one.
    pub fn value(&self, row: &LeaderboardRow) -> Option<f64> {
        let columns = match self.group {
            ColumnGroup::Overall => None,
            ColumnGroup::Forward => Some(&row.forward),
            ColumnGroup::Inverse => Some(&row.inverse),
        };
        let cell = match (columns, self.step) {
            (None, _) => &row.overall,
            (Some(c), None) => &c.total,
            (Some(c), Some(l)) => &c.per_step.iter().find(|(step, _)| *step == l.get())?.1,
        };
        if self.pairwise {
            cell.pairwise_accuracy
        } else {
            cell.task_accuracy
        }
    }

    /// The value as the table shows it (a percentage to one decimal), so rows that look equal
    /// compare equal.
    fn shown(&self, row: &LeaderboardRow) -> Option<i64> {
        self.value(row).map(|v| (v * 1000.0).round() as i64)
    }
}

/// One row per account and model: the latest published submission of each (highest id), with
/// `attempts` counting them all. The latest is the entry because it is what the account last
/// chose to publish; an account that prefers an earlier run asks an admin to hide the later
/// ones, and every submission stays listed when asked for. The Human row passes through.
pub fn one_per_model(rows: &[LeaderboardRow]) -> Vec<LeaderboardRow> {
    let mut latest: std::collections::BTreeMap<(&str, &str), (usize, usize)> =
        std::collections::BTreeMap::new();
    let mut kept = Vec::new();
    for (i, row) in rows.iter().enumerate() {
        if row.source != RowSource::Submission {
            kept.push(i);
            continue;
        }
        let entry = latest
            .entry((row.account.as_str(), row.model.as_str()))
            .or_insert((i, 0));
        entry.1 += 1;
        if row.submission > rows[entry.0].submission {
            entry.0 = i;
        }
    }
    kept.extend(latest.values().map(|(i, _)| *i));
    kept.sort_unstable();
    kept.into_iter()
        .map(|i| {
            let mut row = rows[i].clone();
            if row.source == RowSource::Submission {
                row.attempts = latest[&(row.account.as_str(), row.model.as_str())].1;
            }
            row
        })
        .collect()
}

/// Sorts best first by `key` and ranks the ranked rows. Rows whose shown values are equal tie:
/// they share a rank, and the next distinct value takes the rank after all of them (1, 2, 2,
/// 4), as sports tables do; within a tie, the better overall task accuracy and then the earlier
/// submission come first. Rows without a value in the column go last, unranked.
pub fn rank_by(rows: &mut [LeaderboardRow], key: SortKey) {
    let overall = SortKey::default();
    rows.sort_by(|a, b| {
        let order = |r: &LeaderboardRow| (key.shown(r).is_some(), key.shown(r));
        order(b)
            .cmp(&order(a))
            .then_with(|| overall.shown(b).cmp(&overall.shown(a)))
            .then_with(|| a.submission.cmp(&b.submission))
    });
    let mut ranked = 0;
    let mut previous: Option<(Option<i64>, usize)> = None;
    for row in rows.iter_mut() {
        row.rank = None;
        if !row.is_ranked() {
            continue;
        }
        let shown = key.shown(row);
        ranked += 1;
        if shown.is_none() {
            continue;
        }
        let rank = match previous {
            Some((value, rank)) if value == shown => rank,
            _ => ranked,
        };
        row.rank = Some(rank);
        previous = Some((shown, rank));
    }
}

/// Best overall task accuracy first, with tie ranks (see [`rank_by`]).
pub fn rank(rows: &mut [LeaderboardRow]) {
    rank_by(rows, SortKey::default());
}

/// Which rows of a board to show.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BoardQuery {
    pub sort: SortKey,
    /// Every published submission rather than one row per account and model.
    pub every_submission: bool,
    /// What the rows' intervals resample: activities (the default) or items.
    pub intervals: Resampling,
    /// Only this model (exact name), and only this account.
    pub model: Option<String>,
    pub account: Option<String>,
    /// Only rows of this provenance (`reported` leaves no hub row: those rows are a paper's).
    pub provenance: Option<Provenance>,
    /// 1-based.
    pub page: usize,
    pub per_page: usize,
}

impl Default for BoardQuery {
    fn default() -> Self {
        BoardQuery {
            sort: SortKey::default(),
            every_submission: false,
            intervals: Resampling::Activities,
            model: None,
            account: None,
            provenance: None,
            page: 1,
            per_page: DEFAULT_PER_PAGE,
        }
    }
}

/// Rows a board page shows unless asked for another number.
pub const DEFAULT_PER_PAGE: usize = 50;

/// One page of a board.
#[derive(Debug, Clone, PartialEq)]
pub struct BoardPage {
    /// The page's ranked rows with the reference rows (Human, baselines), best first.
    pub rows: Vec<LeaderboardRow>,
    /// Ranked rows that match the filters, on every page together.
    pub matching: usize,
    pub pages: usize,
}

/// Every row `query` selects from a board's rows (each published submission once, and the
/// Human row), sorted and ranked; the Human row and baselines are always kept.
fn selected_rows(rows: &[LeaderboardRow], query: &BoardQuery) -> Vec<LeaderboardRow> {
    let mut rows = if query.every_submission {
        rows.to_vec()
    } else {
        one_per_model(rows)
    };
    let wanted = |r: &LeaderboardRow| {
        query.model.as_deref().is_none_or(|m| r.model == m)
            && query.account.as_deref().is_none_or(|a| r.account == a)
            && query.provenance.is_none_or(|p| r.provenance == Some(p))
    };
    rows.retain(|r| !r.is_ranked() || wanted(r));
    rank_by(&mut rows, query.sort);
    rows.into_iter()
        .map(|r| r.with_resampling(query.intervals))
        .collect()
}

/// The page `query` asks for. Ranks are over every matching row, not only the page's; the
/// Human row and baselines are shown on every page, in their place by the sort, and count
/// towards the page's `per_page` rows (one ranked row at least).
pub fn board_page(rows: &[LeaderboardRow], query: &BoardQuery) -> BoardPage {
    let rows = selected_rows(rows, query);
    let matching = rows.iter().filter(|r| r.is_ranked()).count();
    let references = rows.len() - matching;
    let per_page = query.per_page.saturating_sub(references).max(1);
    let first = (query.page.max(1) - 1).saturating_mul(per_page);
    let mut seen = 0;
    let rows = rows
        .into_iter()
        .filter(|r| {
            if !r.is_ranked() {
                return true;
            }
            seen += 1;
            (first + 1..=first + per_page).contains(&seen)
        })
        .collect();
    BoardPage {
        rows,
        matching,
        pages: matching.div_ceil(per_page).max(1),
    }
}

/// Lines the chart draws by default besides the Human row and baselines.
pub const CHART_TOP: usize = 10;

/// The rows the chart draws: the reference rows (Human, baselines) and either the submissions
/// the reader picked (by id) or the best [`CHART_TOP`] by the board's sort.
pub fn chart_rows(
    rows: &[LeaderboardRow],
    query: &BoardQuery,
    picked: Option<&[i64]>,
) -> Vec<LeaderboardRow> {
    let mut top = 0;
    selected_rows(rows, query)
        .into_iter()
        .filter(|r| {
            if !r.is_ranked() {
                return true;
            }
            match (picked, r.submission) {
                (Some(ids), Some(id)) => ids.contains(&id),
                (Some(_), None) => false,
                (None, _) => {
                    top += 1;
                    top <= CHART_TOP
                }
            }
        })
        .collect()
}

/// Plot geometry in SVG user units.
pub const CHART_PANEL_WIDTH: f64 = 420.0;
pub const CHART_PANEL_HEIGHT: f64 = 280.0;
const MARGIN_LEFT: f64 = 48.0;
const MARGIN_RIGHT: f64 = 12.0;
const MARGIN_TOP: f64 = 28.0;
const MARGIN_BOTTOM: f64 = 40.0;

/// Line colours, cycled (colour-blind-safe Okabe–Ito palette).
const PALETTE: [&str; 8] = [
    "#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00", "#56b4e9", "#000000", "#f0e442",
];

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChartTick {
    pub position: f64,
    pub label: String,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChartPoint {
    pub x: f64,
    pub y: f64,
    pub label: String,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChartSeries {
    pub model: String,
    pub colour: &'static str,
    /// SVG `points` of the polyline: consecutive step lengths with a value are joined.
    pub points: String,
    pub markers: Vec<ChartPoint>,
}

/// One panel (forward or inverse): TA against L, one line per model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChartPanel {
    pub title: &'static str,
    pub x_offset: f64,
    pub plot_left: f64,
    pub plot_right: f64,
    pub plot_top: f64,
    pub plot_bottom: f64,
    pub x_ticks: Vec<ChartTick>,
    pub y_ticks: Vec<ChartTick>,
    pub series: Vec<ChartSeries>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AccuracyChart {
    pub width: f64,
    pub height: f64,
    pub panels: Vec<ChartPanel>,
    /// (model, colour) in row order.
    pub legend: Vec<(String, &'static str)>,
}

impl AccuracyChart {
    /// Task accuracy (percent) against step length, forward and inverse panels side by side.
    pub fn task_accuracy_by_step_length(rows: &[LeaderboardRow]) -> AccuracyChart {
        let lengths: Vec<u8> = StepLength::all().map(StepLength::get).collect();
        let plot_left = MARGIN_LEFT;
        let plot_right = CHART_PANEL_WIDTH - MARGIN_RIGHT;
        let plot_top = MARGIN_TOP;
        let plot_bottom = CHART_PANEL_HEIGHT - MARGIN_BOTTOM;
        let span = (lengths.len().max(2) - 1) as f64;
        let x_of = |i: usize| plot_left + (plot_right - plot_left) * i as f64 / span;
        let y_of = |ta: f64| plot_bottom - (plot_bottom - plot_top) * ta.clamp(0.0, 1.0);
        let x_ticks: Vec<ChartTick> = lengths
            .iter()
            .enumerate()
            .map(|(i, l)| ChartTick {
                position: x_of(i),
                label: l.to_string(),
            })
            .collect();
        let y_ticks: Vec<ChartTick> = (0..=5)
            .map(|k| ChartTick {
                position: y_of(f64::from(k) / 5.0),
                label: (k * 20).to_string(),
            })
            .collect();
        let panel =
            |title: &'static str, index: usize, pick: fn(&LeaderboardRow) -> &DirectionColumns| {
                let series = rows
                    .iter()
                    .enumerate()
                    .map(|(r, row)| {
                        let markers: Vec<ChartPoint> = pick(row)
                            .per_step
                            .iter()
                            .enumerate()
                            .filter_map(|(i, (l, c))| {
                                c.task_accuracy.map(|ta| ChartPoint {
                                    x: round1(x_of(i)),
                                    y: round1(y_of(ta)),
                                    label: format!("{}: L={l}, TA {:.1}%", row.model, ta * 100.0),
                                })
                            })
                            .collect();
                        ChartSeries {
                            model: row.model.clone(),
                            colour: PALETTE[r % PALETTE.len()],
                            points: markers
                                .iter()
                                .map(|p| format!("{},{}", p.x, p.y))
                                .collect::<Vec<_>>()
                                .join(" "),
                            markers,
                        }
                    })
                    .collect();
                ChartPanel {
                    title,
                    x_offset: CHART_PANEL_WIDTH * index as f64,
                    plot_left,
                    plot_right,
                    plot_top,
                    plot_bottom,
                    x_ticks: x_ticks.clone(),
                    y_ticks: y_ticks.clone(),
                    series,
                }
            };
        AccuracyChart {
            width: CHART_PANEL_WIDTH * 2.0,
            height: CHART_PANEL_HEIGHT,
            panels: vec![
                panel("Forward world modeling", 0, |r| &r.forward),
                panel("Inverse world modeling", 1, |r| &r.inverse),
            ],
            legend: rows
                .iter()
                .enumerate()
                .map(|(r, row)| (row.model.clone(), PALETTE[r % PALETTE.len()]))
                .collect(),
        }
    }
}

fn round1(v: f64) -> f64 {
    (v * 10.0).round() / 10.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Scores as stored (JSON), read back into the typed value as the store does.
    fn scores(forward_l3: f64, overall: f64) -> SubmissionScores {
        let group = |count: usize, ta: f64, pa: f64| {
            serde_json::json!({"count": count, "task_accuracy": ta, "pairwise_accuracy": pa,
                "pairwise_count": count})
        };
        let mut forward = group(2, forward_l3, 0.5);
        forward["per_step"] = serde_json::json!({"3": group(2, forward_l3, 0.5)});
        let mut inverse = group(2, 0.0, 0.0);
        inverse["per_step"] = serde_json::json!({"4": group(2, 0.0, 0.0)});
        let mut all = group(4, overall, 0.5);
        all["per_step"] = serde_json::json!({});
        serde_json::from_value(serde_json::json!({
            "policy": "strict",
            "report": {
                "overall": all,
                "forward_world_modeling": forward,
                "inverse_world_modeling": inverse,
            },
            "coverage": {"dataset_items": 4, "answered": 4, "missing": 0, "unparseable": 1,
                "coverage": 1.0, "parse_failure_rate": 0.25, "exact_only": 0},
            "confidence": {"level": 0.95, "resamples": 1000, "seed": 0,
                "task_accuracy": {"low": 0.1, "high": 0.9}, "pairwise_accuracy": null}
        }))
        .expect("scores in the stored layout")
    }

    fn row(id: i64, forward_l3: f64, overall: f64) -> LeaderboardRow {
        LeaderboardRow::from_scores(
            &RowIdentity {
                submission: id,
                model: &format!("m{id}"),
                account: "team",
                baseline: false,
                submitted_at: "2026-01-01T00:00:00Z",
                metric_version: crate::metric::METRIC_VERSION,
                provenance: Provenance::Submitted,
                run: None,
            },
            &scores(forward_l3, overall),
        )
    }

    #[test]
    fn a_row_gives_the_item_bootstrap_s_intervals_when_asked() {
        let mut stored = scores(0.5, 0.25);
        stored.confidence.resampling = Resampling::Activities;
        stored.confidence.by_items = Some(crate::submission::ItemIntervals {
            task_accuracy: Some(ConfidenceInterval {
                low: 0.2,
                high: 0.3,
            }),
            pairwise_accuracy: None,
        });
        let who = RowIdentity {
            submission: 1,
            model: "m",
            account: "team",
            baseline: false,
            submitted_at: "2026-01-01T00:00:00Z",
            metric_version: crate::metric::METRIC_VERSION,
            provenance: Provenance::Submitted,
            run: None,
        };
        let r = LeaderboardRow::from_scores(&who, &stored);
        assert_eq!(r.interval_resampling, Some(Resampling::Activities));
        assert_eq!(r.overall_task_accuracy_ci.map(|i| i.low), Some(0.1));
        let items = r.with_resampling(Resampling::Items);
        assert_eq!(items.interval_resampling, Some(Resampling::Items));
        assert_eq!(items.overall_task_accuracy_ci.map(|i| i.low), Some(0.2));
    }

    #[test]
    fn rows_read_the_stored_scores() {
        let r = row(1, 0.5, 0.25);
        assert_eq!(r.overall.task_accuracy, Some(0.25));
        assert_eq!(
            r.forward.per_step[0],
            (
                3,
                AccuracyCell {
                    task_accuracy: Some(0.5),
                    pairwise_accuracy: Some(0.5),
                    count: 2
                }
            )
        );
        assert_eq!(r.forward.per_step[1].1.task_accuracy, None);
        assert_eq!(r.inverse.per_step[1].1.task_accuracy, Some(0.0));
        assert_eq!(
            r.overall_task_accuracy_ci,
            Some(Interval {
                low: 0.1,
                high: 0.9
            })
        );
        assert_eq!(r.overall_pairwise_accuracy_ci, None);
        // Stored before the hub clustered its intervals: they resampled items, and asking
        // for either keeps them, saying so.
        assert_eq!(r.interval_resampling, Some(Resampling::Items));
        assert_eq!(
            r.clone().with_resampling(Resampling::Activities),
            r.clone().with_resampling(Resampling::Items)
        );
        assert_eq!(r.parse_failure_rate, 0.25);
    }

    #[test]
    fn ranking_puts_the_best_overall_first() {
        let mut rows = vec![row(1, 0.0, 0.2), row(2, 0.0, 0.8), row(3, 0.0, 0.2)];
        rank(&mut rows);
        let ids: Vec<i64> = rows.iter().filter_map(|r| r.submission).collect();
        assert_eq!(ids, vec![2, 1, 3]);
    }

    #[test]
    fn chart_places_points_by_step_length_and_accuracy() {
        let chart =
            AccuracyChart::task_accuracy_by_step_length(&[row(1, 1.0, 0.5), row(2, 0.0, 0.5)]);
        assert_eq!(chart.panels.len(), 2);
        let forward = &chart.panels[0];
        assert_eq!(forward.x_ticks.len(), 8);
        assert_eq!(forward.x_ticks[0].label, "3");
        let first = &forward.series[0].markers[0];
        assert_eq!(first.x, forward.plot_left);
        assert_eq!(first.y, forward.plot_top);
        let second = &forward.series[1].markers[0];
        assert_eq!(second.y, forward.plot_bottom);
        assert_ne!(forward.series[0].colour, forward.series[1].colour);
        assert_eq!(chart.panels[1].series[0].markers.len(), 1);
        assert_eq!(chart.panels[1].x_offset, CHART_PANEL_WIDTH);
    }

    /// A submission row for `account`/`model` with overall TA `ta` (PA 0.5) and id `id`.
    fn entry(id: i64, account: &str, model: &str, ta: f64) -> LeaderboardRow {
        let mut r = row(id, ta, ta);
        r.account = account.to_owned();
        r.model = model.to_owned();
        r
    }

    fn ids(rows: &[LeaderboardRow]) -> Vec<Option<i64>> {
        rows.iter().map(|r| r.submission).collect()
    }

    fn ranks(rows: &[LeaderboardRow]) -> Vec<Option<usize>> {
        rows.iter().map(|r| r.rank).collect()
    }

    #[test]
    fn one_row_per_account_and_model_is_the_latest_with_its_attempts() {
        let rows = vec![
            entry(1, "a", "m", 0.9),
            entry(2, "a", "m", 0.1),
            entry(3, "b", "m", 0.5),
            entry(4, "a", "n", 0.2),
            entry(5, "a", "m", 0.3),
        ];
        let kept = one_per_model(&rows);
        assert_eq!(ids(&kept), vec![Some(3), Some(4), Some(5)]);
        let attempts: Vec<usize> = kept.iter().map(|r| r.attempts).collect();
        assert_eq!(attempts, vec![1, 1, 3]);
    }

    #[test]
    fn equal_shown_values_share_a_rank_and_the_next_skips() {
        let mut rows = vec![
            entry(1, "a", "m1", 0.4),
            entry(2, "b", "m2", 0.5004),
            entry(3, "c", "m3", 0.4996),
            entry(4, "d", "m4", 0.7),
        ];
        let mut baseline = entry(5, "e", "chance", 0.6);
        baseline.baseline = true;
        rows.push(baseline);
        rank(&mut rows);
        assert_eq!(
            ids(&rows),
            vec![Some(4), Some(5), Some(2), Some(3), Some(1)]
        );
        // 50.0 and 50.0 as shown: a tie; the baseline is placed but not ranked.
        assert_eq!(ranks(&rows), vec![Some(1), None, Some(2), Some(2), Some(4)]);
    }

    #[test]
    fn any_column_sorts_and_names_round_trip() {
        for name in [
            "overall_ta",
            "overall_pa",
            "forward_ta",
            "inverse_pa",
            "forward_ta_3",
            "inverse_pa_10",
        ] {
            assert_eq!(SortKey::parse(name).expect(name).name(), name);
        }
        for bad in [
            "",
            "overall",
            "overall_ta_3",
            "forward_xx",
            "forward_ta_11",
            "inverse_pa_4_1",
        ] {
            let e = SortKey::parse(bad).expect_err(bad);
            assert!(e.contains("sort:"), "{e}");
        }
        // Forward L=3 TA sorts the other way round from overall TA here.
        let mut rows = vec![row(1, 1.0, 0.2), row(2, 0.0, 0.9)];
        rank_by(&mut rows, SortKey::parse("forward_ta_3").expect("key"));
        assert_eq!(ids(&rows), vec![Some(1), Some(2)]);
        assert_eq!(ranks(&rows), vec![Some(1), Some(2)]);
        rank_by(&mut rows, SortKey::default());
        assert_eq!(ids(&rows), vec![Some(2), Some(1)]);
        // A column a row has no value in puts it last, unranked.
        let mut rows = vec![row(1, 1.0, 0.2), row(2, 0.0, 0.9)];
        rank_by(&mut rows, SortKey::parse("forward_ta_4").expect("key"));
        assert_eq!(ranks(&rows), vec![None, None]);
    }

    #[test]
    fn pages_rank_over_every_row_and_always_show_the_reference_rows() {
        let mut rows: Vec<LeaderboardRow> = (1..=5)
            .map(|i| entry(i, &format!("t{i}"), "m", f64::from(i as i32) / 10.0))
            .collect();
        let mut human = LeaderboardRow::human(
            &PerformanceReport::default(),
            HumanCoverage {
                dataset_items: 4,
                ..HumanCoverage::default()
            },
            MetricStamp::current(),
        );
        human.overall.task_accuracy = Some(0.35);
        rows.push(human);
        // Three rows a page: the Human row and two ranked ones.
        let query = BoardQuery {
            per_page: 3,
            page: 2,
            ..BoardQuery::default()
        };
        let page = board_page(&rows, &query);
        assert_eq!((page.matching, page.pages), (5, 3));
        // Ranks 3 and 4 (ids 3 and 2), with the Human row (35.0) in its place above them.
        assert_eq!(ids(&page.rows), vec![None, Some(3), Some(2)]);
        assert_eq!(ranks(&page.rows), vec![None, Some(3), Some(4)]);
        let only = BoardQuery {
            account: Some("t1".to_owned()),
            ..BoardQuery::default()
        };
        let page = board_page(&rows, &only);
        assert_eq!(ids(&page.rows), vec![None, Some(1)]);
        assert_eq!(page.matching, 1);
    }

    #[test]
    fn the_chart_draws_the_top_ten_or_the_picked_rows_and_the_reference_rows() {
        let rows: Vec<LeaderboardRow> = (1..=30)
            .map(|i| entry(i, &format!("t{i}"), "m", f64::from(i as i32) / 100.0))
            .collect();
        let query = BoardQuery::default();
        let drawn = chart_rows(&rows, &query, None);
        assert_eq!(drawn.len(), CHART_TOP);
        assert_eq!(drawn[0].submission, Some(30));
        let drawn = chart_rows(&rows, &query, Some(&[2, 5]));
        assert_eq!(ids(&drawn), vec![Some(5), Some(2)]);
    }
}
