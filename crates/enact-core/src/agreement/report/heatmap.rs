//! The agreement report's heatmap, after the paper's ablation figures: one row per
//! comparison, one column per step length in a panel per direction, each cell coloured by the
//! significance of Welch's test with Δ printed in it ([`crate::heatmap`] lays it out).

use crate::agreement::report::Comparison;
use crate::dataset::{Direction, StepLength};
use crate::heatmap::{CellFigures, ColumnFigures, Heatmap, HeatmapSizes, PanelFigures};

const SIZES: HeatmapSizes = HeatmapSizes {
    top: 52.0,
    cell_height: 28.0,
    min_label_width: 230.0,
    min_column_width: 50.0,
    panel_gap: 0.0,
};

/// Rows are `comparisons` in order, labelled "a − b".
pub fn comparison_heatmap(comparisons: &[Comparison]) -> Heatmap {
    let rows: Vec<String> = comparisons
        .iter()
        .map(|c| format!("{} − {}", c.a.label, c.b.label))
        .collect();
    let panels = Direction::ALL
        .iter()
        .map(|&direction| PanelFigures {
            title: format!("{} world modeling", capitalised(direction.as_str())),
            columns: StepLength::all()
                .map(|length| ColumnFigures {
                    label: format!("L={length}"),
                    cells: comparisons
                        .iter()
                        .map(|comparison| {
                            let cell = comparison
                                .cells
                                .iter()
                                .find(|c| c.direction == direction && c.step_length == length);
                            cell_figures(cell, direction, length)
                        })
                        .collect(),
                })
                .collect(),
        })
        .collect();
    Heatmap::layout(
        "Welch comparisons of per-item pairwise accuracy: one row per comparison, one column \
         per direction and step length; colour shows significance, the number is the \
         difference in means"
            .to_owned(),
        None,
        &rows,
        panels,
        SIZES,
        Some("Δ = mean PA (a − b)".to_owned()),
    )
}

fn cell_figures(
    cell: Option<&super::CellComparison>,
    direction: Direction,
    length: StepLength,
) -> CellFigures {
    let welch = cell.map(|c| &c.welch);
    let delta = welch
        .and_then(|w| w.delta)
        .map_or_else(|| "n/a".to_owned(), |d| format!("{d:+.2}"));
    let p = welch.and_then(|w| w.p).map_or_else(
        || {
            welch
                .and_then(|w| w.reason.as_ref())
                .map_or_else(|| "no test".to_owned(), ToString::to_string)
        },
        |p| format!("p = {p:.4}"),
    );
    CellFigures {
        p: welch.and_then(|w| w.p),
        title: format!(
            "{direction} L={length}: Δ = {delta}, {p}, {} items",
            welch.map_or(0, |w| w.n_a)
        ),
        lines: vec![delta],
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
    use crate::agreement::report::{CellComparison, ComparisonSide};
    use crate::agreement::welch_t_test;

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
        let map = comparison_heatmap(&[comparison]);
        assert_eq!(map.rows.len(), 1);
        assert_eq!(map.rows[0].label, "model − Human");
        let row: Vec<_> = map.panels.iter().flat_map(|p| &p.cells).collect();
        assert_eq!(row.len(), 16);
        assert!(strong.p.unwrap() < 0.001);
        let text = |c: &crate::heatmap::HeatmapCell| c.lines[0].text.clone();
        assert_eq!(row[0].fill, "#99000d");
        assert_eq!(text(row[0]), "+0.80");
        assert_eq!(row[1].fill, "#fee5d9");
        assert_eq!(text(row[1]), "+0.00");
        assert_eq!(row[2].fill, "#d9d9d9");
        assert_eq!(text(row[2]), "n/a");
        assert!(row[8].x > row[7].x, "inverse columns follow forward ones");
        let columns: Vec<&str> = map
            .panels
            .iter()
            .flat_map(|p| p.columns.iter().map(|c| c.label.as_str()))
            .collect();
        assert_eq!(columns.len(), 16);
        assert_eq!(columns[8], "L=3");
        assert_eq!(map.panels[1].title.label, "Inverse world modeling");
        assert_eq!(map.legend.len(), 5);

        // A comparison without cells gets "no test" in every one.
        let comparison = Comparison {
            a: side("a"),
            b: side("Human"),
            items: 0,
            overall: none.clone(),
            cells: Vec::new(),
        };
        let empty = comparison_heatmap(&[comparison]);
        assert!(
            empty
                .panels
                .iter()
                .flat_map(|p| &p.cells)
                .all(|c| c.fill == "#d9d9d9" && c.lines[0].text == "n/a")
        );
    }
}
