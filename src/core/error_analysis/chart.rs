//! Geometry of the error-analysis charts (the markup is in templates): a 100 % stacked bar per
//! row for the structural classes, and grouped bars (one per row) for semantic categories and
//! for hand precision, recall and mixing with standard-error whiskers.

use super::{ErrorFigures, Hand, HandFigures, Handedness, SemanticCategory, StructuralClass};

/// Series colours, chosen to stay apart for colour-blind readers (Okabe–Ito).
pub const PALETTE: [&str; 8] = [
    "#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#F0E442", "#000000",
];

const LABEL_WIDTH: f64 = 190.0;
const PLOT_WIDTH: f64 = 520.0;
const BAR_HEIGHT: f64 = 22.0;

/// One drawn rectangle with its tooltip.
#[derive(Debug, Clone, PartialEq)]
pub struct Bar {
    pub x: f64,
    pub y: f64,
    pub width: f64,
    pub height: f64,
    pub colour: &'static str,
    pub title: String,
    /// Standard-error whisker: from x1 to x2 at the bar's middle height (grouped charts).
    pub whisker: Option<(f64, f64)>,
}

/// A labelled line of bars.
#[derive(Debug, Clone, PartialEq)]
pub struct ChartRow {
    pub label: String,
    pub y: f64,
    pub bars: Vec<Bar>,
}

/// A horizontal bar chart.
#[derive(Debug, Clone, PartialEq)]
pub struct BarChart {
    pub width: f64,
    pub height: f64,
    pub plot_left: f64,
    pub plot_width: f64,
    pub rows: Vec<ChartRow>,
    /// Gridlines: (x, label).
    pub ticks: Vec<(f64, String)>,
    pub legend: Vec<(String, &'static str)>,
}

fn ticks() -> Vec<(f64, String)> {
    (0..=4)
        .map(|k| {
            (
                LABEL_WIDTH + PLOT_WIDTH * k as f64 / 4.0,
                format!("{}%", k * 25),
            )
        })
        .collect()
}

/// Each row's errors split by structural class, as shares of that row's errors.
pub fn structural_chart(rows: &[(&str, &ErrorFigures)]) -> BarChart {
    let mut chart_rows = Vec::new();
    for (i, (label, figures)) in rows.iter().enumerate() {
        let y = 10.0 + i as f64 * (BAR_HEIGHT + 10.0);
        let mut x = LABEL_WIDTH;
        let mut bars = Vec::new();
        for (k, class) in StructuralClass::ALL.iter().enumerate() {
            let n = figures.structural.get(*class);
            if figures.errors == 0 || n == 0 {
                continue;
            }
            let share = n as f64 / figures.errors as f64;
            let width = PLOT_WIDTH * share;
            bars.push(Bar {
                x,
                y,
                width,
                height: BAR_HEIGHT,
                colour: PALETTE[k],
                title: format!("{label}: {} {n} ({:.1}%)", class.label(), share * 100.0),
                whisker: None,
            });
            x += width;
        }
        chart_rows.push(ChartRow {
            label: (*label).to_owned(),
            y,
            bars,
        });
    }
    BarChart {
        width: LABEL_WIDTH + PLOT_WIDTH + 20.0,
        height: 30.0 + rows.len() as f64 * (BAR_HEIGHT + 10.0),
        plot_left: LABEL_WIDTH,
        plot_width: PLOT_WIDTH,
        rows: chart_rows,
        ticks: ticks(),
        legend: StructuralClass::ALL
            .iter()
            .enumerate()
            .map(|(k, c)| (c.label().to_owned(), PALETTE[k]))
            .collect(),
    }
}

/// Groups of bars, one bar per series; values are fractions 0..=1 with optional SE.
fn grouped(
    groups: &[String],
    series: &[&str],
    value: impl Fn(usize, usize) -> (Option<f64>, Option<f64>, String),
) -> BarChart {
    let bar = 12.0;
    let group_height = series.len().max(1) as f64 * (bar + 2.0) + 12.0;
    let mut rows = Vec::new();
    for (g, group) in groups.iter().enumerate() {
        let top = 10.0 + g as f64 * group_height;
        let mut bars = Vec::new();
        for s in 0..series.len() {
            let (v, se, title) = value(g, s);
            let Some(v) = v else { continue };
            let y = top + s as f64 * (bar + 2.0);
            let width = PLOT_WIDTH * v.clamp(0.0, 1.0);
            bars.push(Bar {
                x: LABEL_WIDTH,
                y,
                width,
                height: bar,
                colour: PALETTE[s % PALETTE.len()],
                title,
                whisker: se.map(|se| {
                    (
                        LABEL_WIDTH + PLOT_WIDTH * (v - se).clamp(0.0, 1.0),
                        LABEL_WIDTH + PLOT_WIDTH * (v + se).clamp(0.0, 1.0),
                    )
                }),
            });
        }
        rows.push(ChartRow {
            label: group.clone(),
            y: top,
            bars,
        });
    }
    BarChart {
        width: LABEL_WIDTH + PLOT_WIDTH + 20.0,
        height: 30.0 + groups.len() as f64 * group_height,
        plot_left: LABEL_WIDTH,
        plot_width: PLOT_WIDTH,
        rows,
        ticks: ticks(),
        legend: series
            .iter()
            .enumerate()
            .map(|(s, l)| ((*l).to_owned(), PALETTE[s % PALETTE.len()]))
            .collect(),
    }
}

/// Per semantic category, each row's share of its errors in that category.
pub fn semantic_chart(rows: &[(&str, &ErrorFigures)]) -> BarChart {
    let groups: Vec<String> = SemanticCategory::ALL
        .iter()
        .map(|c| c.label().to_owned())
        .collect();
    let series: Vec<&str> = rows.iter().map(|(l, _)| *l).collect();
    grouped(&groups, &series, |g, s| {
        let (label, f) = rows[s];
        let n = f.semantic.get(SemanticCategory::ALL[g]).total;
        let share = (f.errors > 0).then(|| n as f64 / f.errors as f64);
        let title = format!(
            "{label}: {} {n} of {} errors ({:.1}%)",
            SemanticCategory::ALL[g].label(),
            f.errors,
            share.unwrap_or(0.0) * 100.0
        );
        (share, None, title)
    })
}

/// Per hand and measure, each row's value with its standard error.
pub fn hand_chart(rows: &[(&str, &ErrorFigures)]) -> BarChart {
    let hands: Vec<(&str, &Handedness)> = rows.iter().map(|(l, f)| (*l, &f.handedness)).collect();
    hand_chart_of(&hands)
}

/// [`hand_chart`] of hand figures alone.
pub fn hand_chart_of(rows: &[(&str, &Handedness)]) -> BarChart {
    type Pick = fn(&HandFigures) -> (Option<f64>, Option<f64>);
    let measures: [(&str, Pick); 3] = [
        ("precision", |h| (h.precision, h.precision_se)),
        ("recall", |h| (h.recall, h.recall_se)),
        ("mixing", |h| (h.mixing, h.mixing_se)),
    ];
    let mut groups = Vec::new();
    let mut picks = Vec::new();
    for hand in Hand::BOTH {
        for (name, pick) in measures {
            groups.push(format!("{} hand {name}", hand.as_str()));
            picks.push((hand, pick));
        }
    }
    let series: Vec<&str> = rows.iter().map(|(l, _)| *l).collect();
    grouped(&groups, &series, |g, s| {
        let (label, f) = rows[s];
        let (hand, pick) = picks[g];
        let figures = match hand {
            Hand::Left => &f.left,
            Hand::Right => &f.right,
        };
        let (v, se) = pick(figures);
        let title = match (v, se) {
            (Some(v), Some(se)) => format!("{label}: {} {v:.3} ± {se:.3}", groups[g]),
            _ => format!("{label}: {} not defined", groups[g]),
        };
        (v, se, title)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::error_analysis::analyse;

    #[test]
    fn empty_rows_draw_no_bars_and_fit_the_box() {
        let a = analyse([]);
        for chart in [
            structural_chart(&[("m", &a.overall)]),
            semantic_chart(&[("m", &a.overall)]),
            hand_chart(&[("m", &a.overall)]),
        ] {
            assert!(chart.rows.iter().all(|r| r.bars.is_empty()));
            assert!(chart.rows.iter().all(|r| r.y < chart.height));
        }
    }
}
