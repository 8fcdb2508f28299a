//! Geometry of the comparison heatmap, after the paper's ablation figures: one row per
//! comparison, one column per direction × step length, each cell coloured by the significance
//! of Welch's test (darker red: smaller p) with Δ printed in it. Pure; the template draws it.

use serde::Serialize;

use crate::core::agreement::report::Comparison;
use crate::core::dataset::{Direction, StepLength};

/// The narrowest label column; it widens to fit the longest row label.
const LABEL_WIDTH: f64 = 230.0;
/// A generous average advance of an 11 px sans-serif character, so labels are never cut.
const CHAR_WIDTH: f64 = 7.0;
const CELL_WIDTH: f64 = 50.0;
const CELL_HEIGHT: f64 = 28.0;
const TOP: f64 = 52.0;
const LEGEND_HEIGHT: f64 = 44.0;
const RIGHT: f64 = 12.0;

/// Significance classes: (p below, fill, text colour, legend label), most significant first.
const CLASSES: [(f64, &str, &str, &str); 3] = [
    (0.001, "#99000d", "#ffffff", "p < 0.001"),
    (0.01, "#cb181d", "#ffffff", "p < 0.01"),
    (0.05, "#fb6a4a", "#000000", "p < 0.05"),
];
const NOT_SIGNIFICANT: (&str, &str, &str) = ("#fee5d9", "#000000", "p ≥ 0.05");
const UNDEFINED: (&str, &str, &str) = ("#d9d9d9", "#404040", "no test");

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeatmapCell {
    pub x: f64,
    pub y: f64,
    pub fill: &'static str,
    pub text_fill: &'static str,
    /// Δ with two decimals and its sign, or "n/a".
    pub text: String,
    /// Hover text: Δ, p, items.
    pub title: String,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeatmapRow {
    pub label: String,
    /// Baseline of the row label.
    pub label_y: f64,
    pub cells: Vec<HeatmapCell>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeatmapHeader {
    pub x: f64,
    pub label: String,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LegendEntry {
    pub x: f64,
    pub fill: &'static str,
    pub label: &'static str,
}

/// The whole figure in SVG user units.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Heatmap {
    pub width: f64,
    pub height: f64,
    pub cell_width: f64,
    pub cell_height: f64,
    pub label_right: f64,
    /// Centres of the direction headings.
    pub groups: Vec<HeatmapHeader>,
    /// Centres of the step-length headings.
    pub columns: Vec<HeatmapHeader>,
    pub rows: Vec<HeatmapRow>,
    pub legend_y: f64,
    pub legend: Vec<LegendEntry>,
}

/// Fill and text colour of a cell with two-tailed p-value `p` (`None`: no test), in the four
/// bands of the paper's ablation figures plus one for no test.
pub fn significance(p: Option<f64>) -> (&'static str, &'static str) {
    let Some(p) = p else {
        return (UNDEFINED.0, UNDEFINED.1);
    };
    CLASSES.iter().find(|(below, ..)| p < *below).map_or(
        (NOT_SIGNIFICANT.0, NOT_SIGNIFICANT.1),
        |(_, fill, text, _)| (*fill, *text),
    )
}

/// The legend of [`significance`]: (fill, label), most significant first.
pub fn significance_legend() -> Vec<(&'static str, &'static str)> {
    CLASSES
        .iter()
        .map(|(_, fill, _, label)| (*fill, *label))
        .chain([
            (NOT_SIGNIFICANT.0, NOT_SIGNIFICANT.2),
            (UNDEFINED.0, UNDEFINED.2),
        ])
        .collect()
}

impl Heatmap {
    /// Rows are `comparisons` in order, labelled "a − b".
    pub fn of_comparisons(comparisons: &[Comparison]) -> Heatmap {
        let columns_per_group = StepLength::all().count();
        let labels: Vec<String> = comparisons
            .iter()
            .map(|c| format!("{} − {}", c.a.label, c.b.label))
            .collect();
        let label_width = labels
            .iter()
            .map(|l| l.chars().count() as f64 * CHAR_WIDTH + 16.0)
            .fold(LABEL_WIDTH, f64::max);
        let x_of = |column: usize| label_width + column as f64 * CELL_WIDTH;
        let rows: Vec<HeatmapRow> = comparisons
            .iter()
            .enumerate()
            .map(|(r, comparison)| {
                let y = TOP + r as f64 * CELL_HEIGHT;
                HeatmapRow {
                    label: labels[r].clone(),
                    label_y: y + CELL_HEIGHT / 2.0 + 4.0,
                    cells: comparison
                        .cells
                        .iter()
                        .enumerate()
                        .map(|(c, cell)| {
                            let welch = &cell.welch;
                            let (fill, text_fill) = significance(welch.p);
                            let delta = welch.delta.map(|d| format!("{d:+.2}"));
                            let p = welch.p.map_or_else(
                                || {
                                    welch
                                        .reason
                                        .as_ref()
                                        .map_or_else(|| "no test".to_owned(), ToString::to_string)
                                },
                                |p| format!("p = {p:.4}"),
                            );
                            HeatmapCell {
                                x: x_of(c),
                                y,
                                fill,
                                text_fill,
                                text: delta.clone().unwrap_or_else(|| "n/a".to_owned()),
                                title: format!(
                                    "{} L={}: Δ = {}, {p}, {} items",
                                    cell.direction,
                                    cell.step_length,
                                    delta.unwrap_or_else(|| "n/a".to_owned()),
                                    welch.n_a
                                ),
                            }
                        })
                        .collect(),
                }
            })
            .collect();
        let groups = Direction::ALL
            .iter()
            .enumerate()
            .map(|(g, direction)| HeatmapHeader {
                x: x_of(g * columns_per_group) + CELL_WIDTH * columns_per_group as f64 / 2.0,
                label: format!("{} world modeling", capitalised(direction.as_str())),
            })
            .collect();
        let columns = Direction::ALL
            .iter()
            .flat_map(|_| StepLength::all())
            .enumerate()
            .map(|(c, length)| HeatmapHeader {
                x: x_of(c) + CELL_WIDTH / 2.0,
                label: format!("L={length}"),
            })
            .collect();
        let legend_y = TOP + rows.len() as f64 * CELL_HEIGHT + 16.0;
        let legend = significance_legend()
            .into_iter()
            .enumerate()
            .map(|(i, (fill, label))| LegendEntry {
                x: label_width + i as f64 * 110.0,
                fill,
                label,
            })
            .collect();
        Heatmap {
            width: label_width + 2.0 * columns_per_group as f64 * CELL_WIDTH + RIGHT,
            height: legend_y + LEGEND_HEIGHT,
            cell_width: CELL_WIDTH,
            cell_height: CELL_HEIGHT,
            label_right: label_width - 8.0,
            groups,
            columns,
            rows,
            legend_y,
            legend,
        }
    }
}

fn capitalised(word: &str) -> String {
    let mut chars = word.chars();
    chars.next().map_or_else(String::new, |first| {
        first.to_uppercase().collect::<String>() + chars.as_str()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::agreement::report::{CellComparison, ComparisonSide};
    use crate::core::agreement::welch_t_test;

    fn side(label: &str) -> ComparisonSide {
        ComparisonSide {
            label: label.to_owned(),
            submission: None,
        }
    }

    #[test]
    fn cells_are_coloured_by_significance_and_print_delta() {
        let strong =
            welch_t_test(&[0.9, 1.0, 0.95, 0.92, 0.97], &[0.1, 0.2, 0.15, 0.12, 0.18]).unwrap();
        let weak = welch_t_test(&[0.5, 0.6, 0.4], &[0.55, 0.45, 0.5]).unwrap();
        let none = welch_t_test(&[], &[]).unwrap();
        let mut cells = Vec::new();
        for direction in Direction::ALL {
            for step_length in StepLength::all() {
                let welch = match (direction, step_length.get()) {
                    (Direction::Forward, 3) => strong.clone(),
                    (Direction::Forward, 4) => weak.clone(),
                    _ => none.clone(),
                };
                cells.push(CellComparison {
                    direction,
                    step_length,
                    welch,
                });
            }
        }
        let comparison = Comparison {
            a: side("model"),
            b: side("Human"),
            items: 8,
            overall: strong.clone(),
            cells,
        };
        let map = Heatmap::of_comparisons(&[comparison]);
        assert_eq!(map.rows.len(), 1);
        assert_eq!(map.rows[0].label, "model − Human");
        let row = &map.rows[0].cells;
        assert_eq!(row.len(), 16);
        assert!(strong.p.unwrap() < 0.001);
        assert_eq!(row[0].fill, "#99000d");
        assert_eq!(row[0].text, "+0.80");
        assert_eq!(row[1].fill, NOT_SIGNIFICANT.0);
        assert_eq!(row[1].text, "+0.00");
        assert_eq!(row[2].fill, UNDEFINED.0);
        assert_eq!(row[2].text, "n/a");
        assert!(row[8].x > row[7].x, "inverse columns follow forward ones");
        assert_eq!(map.columns.len(), 16);
        assert_eq!(map.columns[8].label, "L=3");
        assert_eq!(map.groups[1].label, "Inverse world modeling");
        assert_eq!(map.legend.len(), 5);
        assert!(map.height > map.legend_y);
        assert_eq!(
            map.label_right,
            LABEL_WIDTH - 8.0,
            "short labels keep the narrowest column"
        );

        // A long label widens the label column instead of running off the left edge.
        let mut long = Heatmap::of_comparisons(&[]);
        assert!(long.rows.is_empty());
        let name = "a-very-long-model-name-with-a-version-2025-11-26-instruct (#12345)";
        let comparison = Comparison {
            a: side(name),
            b: side("Human"),
            items: 8,
            overall: none.clone(),
            cells: Vec::new(),
        };
        long = Heatmap::of_comparisons(&[comparison]);
        let label = &long.rows[0].label;
        assert!(long.label_right >= label.chars().count() as f64 * CHAR_WIDTH);
        assert!(long.width > map.width);
    }
}
