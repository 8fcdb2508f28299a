//! The leaderboard: one row per published submission in the paper's Table 1 layout (TA and PA
//! overall, forward, inverse, and per step length 3..10), and the geometry of the
//! accuracy-against-step-length chart (pure; templates draw it).

use serde::Serialize;

use crate::core::dataset::StepLength;
use crate::core::submission::SubmissionScores;
use crate::core::verifier::{
    ConfidenceInterval, GroupPerformance, PerformanceReport, StepPerformance,
};

/// Where a row comes from. Human performance rows (from annotations) will be a second kind:
/// they carry the same cells, so the table and chart draw them without change.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RowSource {
    Submission,
    /// Annotators' submitted answers, scored by the same verifier as model submissions.
    Human,
}

/// TA and PA as fractions in [0, 1]; `None` where the group had no item.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct AccuracyCell {
    pub task_accuracy: Option<f64>,
    pub pairwise_accuracy: Option<f64>,
    pub count: usize,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DirectionColumns {
    pub total: AccuracyCell,
    /// Step lengths 3..=10, in order.
    pub per_step: Vec<(u8, AccuracyCell)>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Interval {
    pub low: f64,
    pub high: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LeaderboardRow {
    pub source: RowSource,
    /// The submission id.
    pub submission: Option<i64>,
    pub model: String,
    pub account: String,
    pub baseline: bool,
    pub submitted_at: String,
    pub overall: AccuracyCell,
    pub overall_task_accuracy_ci: Option<Interval>,
    pub overall_pairwise_accuracy_ci: Option<Interval>,
    pub forward: DirectionColumns,
    pub inverse: DirectionColumns,
    pub coverage: f64,
    pub parse_failure_rate: f64,
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
}

impl LeaderboardRow {
    /// A row from a submission's scores.
    pub fn from_scores(who: &RowIdentity<'_>, scores: &SubmissionScores) -> LeaderboardRow {
        let report = &scores.report;
        LeaderboardRow {
            source: RowSource::Submission,
            submission: Some(who.submission),
            model: who.model.to_owned(),
            account: who.account.to_owned(),
            baseline: who.baseline,
            submitted_at: who.submitted_at.to_owned(),
            overall: cell(report.overall.as_ref().map(|g| &g.totals)),
            overall_task_accuracy_ci: interval(scores.confidence.task_accuracy),
            overall_pairwise_accuracy_ci: interval(scores.confidence.pairwise_accuracy),
            forward: columns(report.forward_world_modeling.as_ref()),
            inverse: columns(report.inverse_world_modeling.as_ref()),
            coverage: scores.coverage.coverage,
            parse_failure_rate: scores.coverage.parse_failure_rate,
        }
    }

    /// The Human row: `report` over the annotators' submitted answers; `dataset_items` gives
    /// its coverage.
    pub fn human(report: &PerformanceReport, dataset_items: usize) -> LeaderboardRow {
        let overall = cell(report.overall.as_ref().map(|g| &g.totals));
        LeaderboardRow {
            source: RowSource::Human,
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
            forward: columns(report.forward_world_modeling.as_ref()),
            inverse: columns(report.inverse_world_modeling.as_ref()),
            parse_failure_rate: 0.0,
        }
    }
}

/// Best overall task accuracy first; ties by earlier submission.
pub fn rank(rows: &mut [LeaderboardRow]) {
    rows.sort_by(|a, b| {
        let ta = |r: &LeaderboardRow| r.overall.task_accuracy.unwrap_or(-1.0);
        ta(b)
            .total_cmp(&ta(a))
            .then_with(|| a.submission.cmp(&b.submission))
    });
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
            },
            &scores(forward_l3, overall),
        )
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
}
