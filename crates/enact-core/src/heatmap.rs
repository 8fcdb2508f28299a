//! The significance heatmap both reports draw, after the paper's ablation figures: labelled
//! rows of cells under column headings grouped in panels, each cell coloured by the band of
//! Welch's two-tailed p (darker red: smaller p; grey: no test) with its figures printed in it,
//! and a legend of the bands. The agreement report lays out one row per comparison and a
//! panel per direction; a study one panel per variant family and a row per direction. Pure
//! geometry; `templates/heatmap.svg` draws it.

use askama::Template;
use serde::Serialize;

/// A generous average advance of an 11 px sans-serif character, and of a 12 px bold one, so
/// that labels are never cut.
const CHAR_WIDTH: f64 = 7.0;
const BOLD_CHAR_WIDTH: f64 = 8.2;
/// Baseline-to-baseline distance of the lines printed in a cell.
const LINE_HEIGHT: f64 = 16.0;
const LEGEND_GAP: f64 = 18.0;
const LEGEND_ENTRY_WIDTH: f64 = 112.0;
const MARGIN: f64 = 12.0;

/// Significance classes: (p below, fill, text colour, legend label), most significant first.
const CLASSES: [(f64, &str, &str, &str); 3] = [
    (0.001, "#99000d", "#ffffff", "p < 0.001"),
    (0.01, "#cb181d", "#ffffff", "p < 0.01"),
    (0.05, "#fb6a4a", "#000000", "p < 0.05"),
];
const NOT_SIGNIFICANT: (&str, &str, &str) = ("#fee5d9", "#000000", "p ≥ 0.05");
const UNDEFINED: (&str, &str, &str) = ("#d9d9d9", "#404040", "no test");

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

/// What one cell shows.
#[derive(Debug, Clone, PartialEq)]
pub struct CellFigures {
    /// Welch's two-tailed p, which colours the cell (`None`: no test).
    pub p: Option<f64>,
    /// Printed in the cell, one under the other, the first in bold (Δ first).
    pub lines: Vec<String>,
    /// Hover text: the figures in full.
    pub title: String,
}

/// One column: its heading and a cell per row.
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnFigures {
    pub label: String,
    pub cells: Vec<CellFigures>,
}

/// A panel: a heading over its columns.
#[derive(Debug, Clone, PartialEq)]
pub struct PanelFigures {
    pub title: String,
    pub columns: Vec<ColumnFigures>,
}

/// The sizes that differ between the two figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeatmapSizes {
    /// Top of the first row, below the headings (and the title, if any).
    pub top: f64,
    pub cell_height: f64,
    /// The narrowest row-label column and column; both widen to fit their labels.
    pub min_label_width: f64,
    pub min_column_width: f64,
    pub panel_gap: f64,
}

/// A line of text in a cell, as drawn: its baseline below the cell's top.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CellLine {
    pub dy: f64,
    pub text: String,
    pub bold: bool,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeatmapCell {
    pub x: f64,
    pub y: f64,
    pub width: f64,
    pub fill: &'static str,
    pub text_fill: &'static str,
    pub lines: Vec<CellLine>,
    pub title: String,
}

/// A heading centred at `x`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeatmapHeader {
    pub x: f64,
    pub label: String,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeatmapPanel {
    /// The panel's heading, centred over its columns.
    pub title: HeatmapHeader,
    pub columns: Vec<HeatmapHeader>,
    pub cells: Vec<HeatmapCell>,
}

/// A row label's baseline and text.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RowLabel {
    pub y: f64,
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
    /// The SVG's class, for the page's styles and tests.
    pub class: &'static str,
    /// What the figure shows, for screen readers.
    pub description: String,
    pub title: Option<String>,
    pub width: f64,
    pub height: f64,
    pub cell_height: f64,
    /// Baselines of the panel headings and the column headings.
    pub panel_title_y: f64,
    pub column_label_y: f64,
    /// Right edge of the row labels.
    pub label_right: f64,
    pub rows: Vec<RowLabel>,
    pub panels: Vec<HeatmapPanel>,
    pub legend_y: f64,
    pub legend: Vec<LegendEntry>,
    /// What the printed numbers are, right-aligned beside the legend.
    pub note: Option<String>,
}

/// Width of `text` as a label, with a little room either side.
pub fn text_width(text: &str, char_width: f64) -> f64 {
    text.chars().count() as f64 * char_width + 14.0
}

impl Heatmap {
    /// Lays out `panels` of columns beside a column of `rows` labels; every column has a cell
    /// per row. A column is as wide as its heading needs (at least the minimum), and a
    /// panel's columns share out whatever more its heading needs.
    pub fn layout(
        description: String,
        title: Option<String>,
        rows: &[String],
        panels: Vec<PanelFigures>,
        sizes: HeatmapSizes,
        note: Option<String>,
    ) -> Heatmap {
        let label_width = rows
            .iter()
            .map(|l| text_width(l, CHAR_WIDTH) + 2.0)
            .fold(sizes.min_label_width, f64::max);
        let mut x = label_width;
        let mut laid_out = Vec::new();
        for panel in panels {
            let mut widths: Vec<f64> = panel
                .columns
                .iter()
                .map(|c| text_width(&c.label, CHAR_WIDTH).max(sizes.min_column_width))
                .collect();
            let needed = text_width(&panel.title, BOLD_CHAR_WIDTH);
            let total: f64 = widths.iter().sum();
            if needed > total && !widths.is_empty() {
                let extra = (needed - total) / widths.len() as f64;
                widths.iter_mut().for_each(|w| *w += extra);
            }
            let left = x;
            let mut columns = Vec::new();
            let mut cells = Vec::new();
            for (column, width) in panel.columns.into_iter().zip(widths) {
                columns.push(HeatmapHeader {
                    x: x + width / 2.0,
                    label: column.label,
                });
                for (r, cell) in column.cells.into_iter().enumerate() {
                    cells.push(laid_out_cell(cell, x, r, width, &sizes));
                }
                x += width;
            }
            laid_out.push(HeatmapPanel {
                title: HeatmapHeader {
                    x: (left + x) / 2.0,
                    label: panel.title,
                },
                columns,
                cells,
            });
            x += sizes.panel_gap;
        }
        let plot_right = if laid_out.is_empty() {
            x
        } else {
            x - sizes.panel_gap
        };
        let legend_y = sizes.top + rows.len() as f64 * sizes.cell_height + LEGEND_GAP;
        let legend: Vec<LegendEntry> = significance_legend()
            .into_iter()
            .enumerate()
            .map(|(i, (fill, label))| LegendEntry {
                x: label_width + i as f64 * LEGEND_ENTRY_WIDTH,
                fill,
                label,
            })
            .collect();
        let legend_right = label_width + legend.len() as f64 * LEGEND_ENTRY_WIDTH;
        let title_right = title
            .as_deref()
            .map_or(0.0, |t| MARGIN + text_width(t, BOLD_CHAR_WIDTH));
        let width = [plot_right, legend_right, title_right]
            .into_iter()
            .fold(0.0, f64::max)
            + MARGIN;
        Heatmap {
            class: "heatmap",
            description,
            title,
            width,
            height: legend_y + 14.0 + MARGIN,
            cell_height: sizes.cell_height,
            panel_title_y: sizes.top - 30.0,
            column_label_y: sizes.top - 8.0,
            label_right: label_width - 8.0,
            rows: rows
                .iter()
                .enumerate()
                .map(|(r, label)| RowLabel {
                    y: sizes.top + r as f64 * sizes.cell_height + sizes.cell_height / 2.0 + 4.0,
                    label: label.clone(),
                })
                .collect(),
            panels: laid_out,
            legend_y,
            legend,
            note,
        }
    }
}

#[derive(Template)]
#[template(path = "heatmap.svg")]
struct HeatmapSvg<'a> {
    heatmap: &'a Heatmap,
    stamp: &'a str,
}

impl Heatmap {
    /// The figure as a standalone SVG file, `stamp` in its `<metadata>`.
    pub fn svg(&self, stamp: &str) -> Result<String, askama::Error> {
        HeatmapSvg {
            heatmap: self,
            stamp,
        }
        .render()
    }
}

/// A cell of row `r` at `x`: coloured by its p, its lines centred one under the other.
fn laid_out_cell(
    cell: CellFigures,
    x: f64,
    r: usize,
    width: f64,
    sizes: &HeatmapSizes,
) -> HeatmapCell {
    let (fill, text_fill) = significance(cell.p);
    let first = sizes.cell_height / 2.0 + 4.0 - (cell.lines.len().max(1) - 1) as f64 * 8.0;
    HeatmapCell {
        x,
        y: sizes.top + r as f64 * sizes.cell_height,
        width,
        fill,
        text_fill,
        lines: cell
            .lines
            .into_iter()
            .enumerate()
            .map(|(i, text)| CellLine {
                dy: first + i as f64 * LINE_HEIGHT,
                text,
                bold: i == 0,
            })
            .collect(),
        title: cell.title,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SIZES: HeatmapSizes = HeatmapSizes {
        top: 74.0,
        cell_height: 46.0,
        min_label_width: 84.0,
        min_column_width: 50.0,
        panel_gap: 18.0,
    };

    fn cell(p: Option<f64>, lines: &[&str]) -> CellFigures {
        CellFigures {
            p,
            lines: lines.iter().map(|l| (*l).to_owned()).collect(),
            title: String::new(),
        }
    }

    fn column(label: &str, cells: Vec<CellFigures>) -> ColumnFigures {
        ColumnFigures {
            label: label.to_owned(),
            cells,
        }
    }

    #[test]
    fn bands_follow_the_paper() {
        assert_eq!(significance(Some(0.0004)).0, "#99000d");
        assert_eq!(significance(Some(0.005)).0, "#cb181d");
        assert_eq!(significance(Some(0.03)).0, "#fb6a4a");
        assert_eq!(significance(Some(0.05)).0, NOT_SIGNIFICANT.0);
        assert_eq!(significance(None).0, UNDEFINED.0);
        assert_eq!(significance_legend().len(), 5);
    }

    #[test]
    fn cells_sit_in_rows_and_columns_and_labels_fit() {
        let rows = ["Forward".to_owned(), "Inverse".to_owned()];
        let map = Heatmap::layout(
            "test".into(),
            Some("A title".into()),
            &rows,
            vec![
                PanelFigures {
                    title: "A family with a rather long heading".into(),
                    columns: vec![column(
                        "v",
                        vec![cell(Some(0.0001), &["Δ=+0.50", "p<0.001"]), cell(None, &[])],
                    )],
                },
                PanelFigures {
                    title: "B".into(),
                    columns: vec![
                        column("a variant with a long name", vec![cell(None, &["n/a"]); 2]),
                        column("w", vec![cell(Some(0.5), &["+0.01"]); 2]),
                    ],
                },
            ],
            SIZES,
            Some("Δ = variant − baseline".into()),
        );
        assert_eq!(map.rows.len(), 2);
        assert_eq!(map.rows[1].y, 74.0 + 46.0 + 23.0 + 4.0);
        let [first, second] = &map.panels[..] else {
            panic!("two panels: {:?}", map.panels)
        };
        // A lone column widens to its panel's heading; long column labels widen their column.
        let heading = text_width(&first.title.label, BOLD_CHAR_WIDTH);
        assert!((first.cells[0].width - heading).abs() < 1e-9);
        assert!(second.cells[0].width >= text_width("a variant with a long name", CHAR_WIDTH));
        assert_eq!(second.cells[2].width, SIZES.min_column_width);
        // Panels are apart by the gap; the second row lies under the first.
        assert_eq!(
            second.cells[0].x,
            first.cells[0].x + heading + SIZES.panel_gap
        );
        assert_eq!(first.cells[1].x, first.cells[0].x);
        assert_eq!(first.cells[1].y, first.cells[0].y + SIZES.cell_height);
        // Colours by p; two lines centred with the first in bold, one line in the middle.
        assert_eq!(first.cells[0].fill, "#99000d");
        let dys: Vec<(f64, bool)> = first.cells[0]
            .lines
            .iter()
            .map(|l| (l.dy, l.bold))
            .collect();
        assert_eq!(dys, [(19.0, true), (35.0, false)]);
        assert_eq!(second.cells[0].lines[0].dy, 27.0);
        let right = second.cells[3].x + second.cells[3].width;
        assert!(map.width >= right + MARGIN);
        assert!(map.height > map.legend_y);
        assert_eq!(map.legend.len(), 5);
        assert_eq!(map.label_right, SIZES.min_label_width - 8.0);

        // A long row label widens the label column instead of running off the left edge.
        let long = ["a-very-long-model-name-with-a-version-2025-11-26-instruct − Human".to_owned()];
        let wide = Heatmap::layout(String::new(), None, &long, Vec::new(), SIZES, None);
        assert!(wide.label_right >= long[0].chars().count() as f64 * CHAR_WIDTH);
        assert!(wide.width > wide.label_right);
    }
}
