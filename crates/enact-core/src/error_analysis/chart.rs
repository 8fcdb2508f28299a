//! Geometry of the error-analysis charts (the markup is in templates): a 100 % stacked bar per
//! row for the structural classes, and grouped bars (one per row) for semantic categories and
//! for hand precision, recall and mixing with standard-error whiskers.

use super::{ErrorFigures, Hand, HandFigures, Handedness, SemanticCategory, StructuralClass};

/// Series colours, chosen to stay apart for colour-blind readers (Okabe–Ito).
pub const PALETTE: [&str; 8] = [
    "#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#F0E442", "#000000",
];

const PLOT_WIDTH: f64 = 520.0;
const BAR_HEIGHT: f64 = 22.0;
/// Row labels are drawn at 12 px, one line every [`LINE_HEIGHT`] px.
const LINE_HEIGHT: f64 = 14.0;
/// A label longer than this wraps at its spaces; the label column is as wide as the widest
/// line (a word longer than this gets a line of its own, and the column grows to hold it).
const LABEL_WRAP: f64 = 300.0;
/// Between a label's end and the plot.
const LABEL_GAP: f64 = 8.0;
/// The narrowest label column, so that short labels leave the charts aligned with each other.
const MIN_LABEL_COLUMN: f64 = 90.0;

/// The names a chart shows, in the reader's language: the structural classes and semantic
/// categories in their `ALL` order, and the six hand measures (left then right; precision,
/// recall, mixing). [`ChartNames::english`] is the taxonomy's own English names.
#[derive(Debug, Clone, PartialEq)]
pub struct ChartNames {
    pub structural: Vec<String>,
    pub semantic: Vec<String>,
    pub hands: Vec<String>,
}

impl ChartNames {
    pub fn english() -> ChartNames {
        let mut hands = Vec::new();
        for hand in Hand::BOTH {
            for measure in ["precision", "recall", "mixing"] {
                hands.push(format!("{} hand {measure}", hand.as_str()));
            }
        }
        ChartNames {
            structural: StructuralClass::ALL
                .iter()
                .map(|c| c.label().to_owned())
                .collect(),
            semantic: SemanticCategory::ALL
                .iter()
                .map(|c| c.label().to_owned())
                .collect(),
            hands,
        }
    }

    fn name(names: &[String], i: usize) -> &str {
        names.get(i).map_or("", String::as_str)
    }
}

/// The width a 12 px system sans-serif gives `text`, estimated from its characters'
/// classes and rounded up (an SVG cannot wrap or measure text, and a cut label is worse than a
/// little room to spare): wide CJK and full-width forms, capitals and wide letters, narrow
/// letters and punctuation, and the rest.
pub fn label_width(text: &str) -> f64 {
    text.chars()
        .map(|c| match c {
            '\u{1100}'..='\u{115F}'
            | '\u{2E80}'..='\u{A4CF}'
            | '\u{AC00}'..='\u{D7A3}'
            | '\u{F900}'..='\u{FAFF}'
            | '\u{FE30}'..='\u{FE4F}'
            | '\u{FF00}'..='\u{FF60}'
            | '\u{FFE0}'..='\u{FFE6}' => 12.0,
            'M' | 'W' | 'm' | 'w' | '@' | '%' => 10.5,
            'i' | 'j' | 'l' | 'I' | '.' | ',' | ':' | ';' | '\'' | '|' | '!' => 3.5,
            'A'..='Z' | '#' | '&' => 8.5,
            ' ' | '(' | ')' | '[' | ']' | 'f' | 't' | 'r' | '-' | '/' => 4.5,
            _ => 7.0,
        })
        .sum::<f64>()
        // Fonts differ from system to system: a tenth to spare.
        * 1.1
}

/// `label` in lines of at most [`LABEL_WRAP`] px, broken at spaces.
fn wrap_label(label: &str) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in label.split_whitespace() {
        match lines.last_mut() {
            Some(line)
                if label_width(line) + label_width(" ") + label_width(word) <= LABEL_WRAP =>
            {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_owned()),
        }
    }
    if lines.is_empty() {
        lines.push(String::new());
    }
    lines
}

/// Where the plot starts: after the widest line of `labels`.
fn label_column(labels: &[Vec<String>]) -> f64 {
    let widest = labels
        .iter()
        .flatten()
        .map(|l| label_width(l))
        .fold(0.0, f64::max);
    (widest + LABEL_GAP + 4.0).max(MIN_LABEL_COLUMN).ceil()
}

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
    /// The label wrapped to fit the label column: drawn one under the other from `y`.
    pub lines: Vec<String>,
    pub y: f64,
    pub bars: Vec<Bar>,
}

impl ChartRow {
    /// Each line of the label with its baseline.
    pub fn label_lines(&self) -> Vec<(f64, &str)> {
        self.lines
            .iter()
            .enumerate()
            .map(|(i, l)| (self.y + 12.0 + i as f64 * LINE_HEIGHT, l.as_str()))
            .collect()
    }
}

/// The height a row needs: its bars' or its label's, whichever is taller.
fn row_height(bars: f64, lines: usize) -> f64 {
    bars.max(lines as f64 * LINE_HEIGHT)
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

fn ticks(plot_left: f64) -> Vec<(f64, String)> {
    (0..=4)
        .map(|k| {
            (
                plot_left + PLOT_WIDTH * k as f64 / 4.0,
                format!("{}%", k * 25),
            )
        })
        .collect()
}

/// Each row's errors split by structural class, as shares of that row's errors.
pub fn structural_chart(rows: &[(&str, &ErrorFigures)], names: &ChartNames) -> BarChart {
    let lines: Vec<Vec<String>> = rows.iter().map(|(l, _)| wrap_label(l)).collect();
    let plot_left = label_column(&lines);
    let mut chart_rows = Vec::new();
    let mut y = 10.0;
    for ((label, figures), lines) in rows.iter().zip(lines) {
        let mut x = plot_left;
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
                title: format!(
                    "{label}: {} {n} ({:.1}%)",
                    ChartNames::name(&names.structural, k),
                    share * 100.0
                ),
                whisker: None,
            });
            x += width;
        }
        let height = row_height(BAR_HEIGHT, lines.len());
        chart_rows.push(ChartRow {
            label: (*label).to_owned(),
            lines,
            y,
            bars,
        });
        y += height + 10.0;
    }
    BarChart {
        width: plot_left + PLOT_WIDTH + 20.0,
        height: y + 20.0,
        plot_left,
        plot_width: PLOT_WIDTH,
        rows: chart_rows,
        ticks: ticks(plot_left),
        legend: (0..StructuralClass::ALL.len())
            .map(|k| {
                (
                    ChartNames::name(&names.structural, k).to_owned(),
                    PALETTE[k],
                )
            })
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
    let bars_height = series.len().max(1) as f64 * (bar + 2.0);
    let lines: Vec<Vec<String>> = groups.iter().map(|g| wrap_label(g)).collect();
    let plot_left = label_column(&lines);
    let mut rows = Vec::new();
    let mut top = 10.0;
    for (g, (group, lines)) in groups.iter().zip(lines).enumerate() {
        let mut bars = Vec::new();
        for s in 0..series.len() {
            let (v, se, title) = value(g, s);
            let Some(v) = v else { continue };
            let y = top + s as f64 * (bar + 2.0);
            let width = PLOT_WIDTH * v.clamp(0.0, 1.0);
            bars.push(Bar {
                x: plot_left,
                y,
                width,
                height: bar,
                colour: PALETTE[s % PALETTE.len()],
                title,
                whisker: se.map(|se| {
                    (
                        plot_left + PLOT_WIDTH * (v - se).clamp(0.0, 1.0),
                        plot_left + PLOT_WIDTH * (v + se).clamp(0.0, 1.0),
                    )
                }),
            });
        }
        let height = row_height(bars_height, lines.len());
        rows.push(ChartRow {
            label: group.clone(),
            lines,
            y: top,
            bars,
        });
        top += height + 12.0;
    }
    BarChart {
        width: plot_left + PLOT_WIDTH + 20.0,
        height: top + 20.0,
        plot_left,
        plot_width: PLOT_WIDTH,
        rows,
        ticks: ticks(plot_left),
        legend: series
            .iter()
            .enumerate()
            .map(|(s, l)| ((*l).to_owned(), PALETTE[s % PALETTE.len()]))
            .collect(),
    }
}

/// Per semantic category, each row's share of its errors in that category.
pub fn semantic_chart(rows: &[(&str, &ErrorFigures)], names: &ChartNames) -> BarChart {
    let groups: Vec<String> = (0..SemanticCategory::ALL.len())
        .map(|g| ChartNames::name(&names.semantic, g).to_owned())
        .collect();
    let series: Vec<&str> = rows.iter().map(|(l, _)| *l).collect();
    grouped(&groups, &series, |g, s| {
        let (label, f) = rows[s];
        let n = f.semantic.get(SemanticCategory::ALL[g]).total;
        let share = (f.errors > 0).then(|| n as f64 / f.errors as f64);
        // Figures only, no words: the tooltip reads the same in every language.
        let title = format!(
            "{label}: {} {n}/{} ({:.1}%)",
            groups[g],
            f.errors,
            share.unwrap_or(0.0) * 100.0
        );
        (share, None, title)
    })
}

/// Per hand and measure, each row's value with its standard error.
pub fn hand_chart(rows: &[(&str, &ErrorFigures)], names: &ChartNames) -> BarChart {
    let hands: Vec<(&str, &Handedness)> = rows.iter().map(|(l, f)| (*l, &f.handedness)).collect();
    hand_chart_of(&hands, names)
}

/// [`hand_chart`] of hand figures alone.
pub fn hand_chart_of(rows: &[(&str, &Handedness)], names: &ChartNames) -> BarChart {
    type Pick = fn(&HandFigures) -> (Option<f64>, Option<f64>);
    let measures: [Pick; 3] = [
        |h| (h.precision, h.precision_se),
        |h| (h.recall, h.recall_se),
        |h| (h.mixing, h.mixing_se),
    ];
    let mut groups = Vec::new();
    let mut picks = Vec::new();
    for hand in Hand::BOTH {
        for pick in measures {
            groups.push(ChartNames::name(&names.hands, groups.len()).to_owned());
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
            // A dash for "not defined", as the tables write it, in any language.
            _ => format!("{label}: {} –", groups[g]),
        };
        (v, se, title)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error_analysis::analyse;

    #[test]
    fn empty_rows_draw_no_bars_and_fit_the_box() {
        let a = analyse([]);
        let names = ChartNames::english();
        for chart in [
            structural_chart(&[("m", &a.overall)], &names),
            semantic_chart(&[("m", &a.overall)], &names),
            hand_chart(&[("m", &a.overall)], &names),
        ] {
            assert!(chart.rows.iter().all(|r| r.bars.is_empty()));
            assert!(chart.rows.iter().all(|r| r.y < chart.height));
        }
    }

    /// The demo's chance row was cut at a fixed 190 px label column: the column now holds the
    /// widest label, and a label too long for one line wraps and makes its row taller.
    #[test]
    fn the_label_column_holds_its_longest_label() {
        let a = analyse([]);
        let names = ChartNames::english();
        let chance = "chance (uniformly random order) (#1)";
        let chart = structural_chart(&[("m", &a.overall), (chance, &a.overall)], &names);
        assert_eq!(chart.rows[1].lines, vec![chance.to_owned()]);
        assert!(
            chart.plot_left >= label_width(chance) + LABEL_GAP,
            "{chart:?}"
        );
        assert_eq!(chart.ticks[0].0, chart.plot_left);
        assert_eq!(chart.width, chart.plot_left + PLOT_WIDTH + 20.0);

        let long = "a model whose name goes on and on well past what one line of the column holds";
        let chart = structural_chart(&[(long, &a.overall), ("m", &a.overall)], &names);
        let lines = &chart.rows[0].lines;
        assert!(lines.len() >= 2, "{lines:?}");
        assert_eq!(lines.join(" "), long);
        assert!(lines.iter().all(|l| label_width(l) <= LABEL_WRAP));
        // The second row starts below the first one's last line.
        let last = chart.rows[0].label_lines().last().expect("a line").0;
        assert!(chart.rows[1].y + 12.0 > last, "{chart:?}");
        assert!(chart.rows[1].y + BAR_HEIGHT < chart.height);

        // Chinese characters are counted full width.
        assert!(label_width("结构性错误") >= 60.0);
    }

    /// A row is as tall as its bars or as its label's lines, whichever is taller: a label of
    /// three lines needs three lines' height, not one more line's.
    #[test]
    fn a_row_is_as_tall_as_its_bars_or_its_label_lines() {
        assert_eq!(row_height(BAR_HEIGHT, 1), BAR_HEIGHT);
        assert_eq!(row_height(BAR_HEIGHT, 3), 3.0 * LINE_HEIGHT);
        assert_eq!(row_height(60.0, 2), 60.0);
    }

    /// Figures with four errors: three omissions (two of them spatial) and one hallucination,
    /// and a left hand whose precision is 0.8 ± 0.1.
    fn figures() -> ErrorFigures {
        let mut f = analyse([]).overall;
        f.errors = 4;
        f.structural.omission = 3;
        f.structural.hallucination = 1;
        f.semantic.spatial_relations.total = 2;
        f.semantic.agent_interaction.total = 1;
        f.handedness.left.precision = Some(0.8);
        f.handedness.left.precision_se = Some(0.1);
        f.handedness.right.recall = Some(0.95);
        f.handedness.right.recall_se = Some(0.2);
        f
    }

    /// No two rows overlap, each row as tall as its bars or its label, and the box holds them.
    fn assert_rows_stacked(chart: &BarChart, bars_height: f64, gap: f64) {
        for pair in chart.rows.windows(2) {
            let height = bars_height.max(pair[0].lines.len() as f64 * LINE_HEIGHT);
            assert_eq!(pair[1].y, pair[0].y + height + gap, "{chart:?}");
        }
        let last = chart.rows.last().expect("a row");
        let height = bars_height.max(last.lines.len() as f64 * LINE_HEIGHT);
        assert_eq!(chart.height, last.y + height + gap + 20.0);
        assert_eq!(chart.rows[0].y, 10.0);
        // The box is the plot and a 20 px margin, wider than anything drawn: a full bar and a
        // whisker at 100 % included.
        assert_eq!(chart.width, chart.plot_left + chart.plot_width + 20.0);
        assert!(
            chart.width > chart.plot_left + chart.plot_width,
            "{chart:?}"
        );
        for bar in chart.rows.iter().flat_map(|r| &r.bars) {
            let right = bar.whisker.map_or(bar.x + bar.width, |(_, high)| high);
            assert!(
                right < chart.width,
                "{bar:?} leaves the box of {}",
                chart.width
            );
        }
    }

    #[test]
    fn a_structural_row_is_one_bar_split_by_class_shares() {
        let f = figures();
        let empty = analyse([]).overall;
        let names = ChartNames::english();
        let chart = structural_chart(&[("model", &f), ("none", &empty)], &names);
        let bars = &chart.rows[0].bars;
        assert_eq!(bars.len(), 2, "{bars:?}");
        let (omission, hallucination) = (&bars[0], &bars[1]);
        assert_eq!(omission.x, chart.plot_left);
        assert_eq!(omission.width, PLOT_WIDTH * 0.75);
        assert_eq!(hallucination.x, chart.plot_left + PLOT_WIDTH * 0.75);
        assert_eq!(hallucination.width, PLOT_WIDTH * 0.25);
        assert_eq!(omission.colour, PALETTE[3]);
        assert_eq!(hallucination.colour, PALETTE[4]);
        assert_eq!(omission.title, "model: Omission 3 (75.0%)");
        assert_eq!(hallucination.title, "model: Hallucination 1 (25.0%)");
        assert!(
            bars.iter()
                .all(|b| b.y == chart.rows[0].y && b.height == BAR_HEIGHT)
        );
        assert!(chart.rows[1].bars.is_empty());
        assert_rows_stacked(&chart, BAR_HEIGHT, 10.0);
        assert_eq!(
            chart
                .legend
                .iter()
                .map(|(name, _)| name.as_str())
                .collect::<Vec<_>>(),
            [
                "Polarity inversion",
                "Predicate substitution",
                "Entity substitution",
                "Omission",
                "Hallucination"
            ]
        );
        assert_eq!(
            chart.ticks,
            (0..=4)
                .map(|k| (
                    chart.plot_left + 130.0 * f64::from(k),
                    format!("{}%", 25 * k)
                ))
                .collect::<Vec<_>>()
        );
    }

    #[test]
    fn grouped_bars_are_one_per_row_under_each_group_with_whiskers() {
        let f = figures();
        let other = analyse([]).overall;
        let names = ChartNames::english();
        let semantic = semantic_chart(&[("a", &f), ("b", &other)], &names);
        assert_eq!(semantic.rows.len(), SemanticCategory::ALL.len());
        let spatial = &semantic.rows[0];
        assert_eq!(spatial.bars.len(), 1, "b has no errors: no share, no bar");
        assert_eq!(spatial.bars[0].width, PLOT_WIDTH * 0.5);
        assert_eq!(spatial.bars[0].x, semantic.plot_left);
        assert_eq!(spatial.bars[0].y, spatial.y);
        assert_eq!(spatial.bars[0].title, "a: Spatial relations 2/4 (50.0%)");
        let agent = &semantic.rows[3];
        assert_eq!(agent.bars[0].width, PLOT_WIDTH * 0.25);
        // Two series: each group is two bars of 12 px with 2 px between, then 12 px.
        assert_rows_stacked(&semantic, 2.0 * 14.0, 12.0);
        assert_eq!(
            semantic.legend,
            vec![("a".to_owned(), PALETTE[0]), ("b".to_owned(), PALETTE[1])]
        );

        let hands = hand_chart(&[("b", &other), ("a", &f)], &names);
        assert_eq!(hands.rows.len(), 6);
        let precision = &hands.rows[0];
        assert_eq!(precision.label, "left hand precision");
        let bar = &precision.bars[0];
        // The second series, one bar down.
        assert_eq!(bar.y, precision.y + 14.0);
        assert_eq!(bar.colour, PALETTE[1]);
        assert!((bar.width - PLOT_WIDTH * 0.8).abs() < 1e-9);
        let (low, high) = bar.whisker.expect("a whisker");
        assert!((low - (hands.plot_left + PLOT_WIDTH * 0.7)).abs() < 1e-9);
        assert!((high - (hands.plot_left + PLOT_WIDTH * 0.9)).abs() < 1e-9);
        assert_eq!(bar.title, "a: left hand precision 0.800 ± 0.100");
        // A whisker past 100 % stops at the plot's edge.
        let recall = &hands.rows[4].bars[0];
        assert_eq!(
            recall.whisker.map(|w| w.1),
            Some(hands.plot_left + PLOT_WIDTH)
        );
        assert_rows_stacked(&hands, 2.0 * 14.0, 12.0);
    }

    #[test]
    fn label_widths_follow_character_classes_and_the_column_its_widest_line() {
        for (text, width) in [
            ("W", 10.5),
            ("i", 3.5),
            ("A", 8.5),
            ("f", 4.5),
            ("a", 7.0),
            ("结", 12.0),
            ("Wi", 14.0),
        ] {
            assert!((label_width(text) - width * 1.1).abs() < 1e-9, "{text}");
        }
        assert_eq!(label_column(&[vec!["ab".to_owned()]]), MIN_LABEL_COLUMN);
        let wide = "W".repeat(20);
        assert_eq!(
            label_column(&[vec!["a".to_owned()], vec![wide.clone()]]),
            (label_width(&wide) + LABEL_GAP + 4.0).ceil()
        );
        let row = ChartRow {
            label: "x y".to_owned(),
            lines: vec!["x".to_owned(), "y".to_owned()],
            y: 30.0,
            bars: Vec::new(),
        };
        assert_eq!(row.label_lines(), vec![(42.0, "x"), (56.0, "y")]);
        assert_eq!(wrap_label(""), vec![String::new()]);
    }
}
