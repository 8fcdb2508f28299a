//! Geometry of a study's heatmap, drawn like the paper's ablation figures: one panel per
//! family, one column per variant, forward and inverse rows; each cell coloured by the band of
//! Welch's two-tailed p (the same four bands as the agreement report's heatmap, and grey for
//! no test) with Δ and p printed in it. Pure; `templates/study/heatmap.svg` draws it.

use serde::Serialize;

use super::families;
use super::report::StudyReport;
use crate::core::agreement::report::heatmap::{
    HeatmapHeader, LegendEntry, significance, significance_legend,
};
use crate::core::dataset::Direction;

/// A generous advance of an 11 px sans-serif character, and of a 12 px bold one, so that
/// labels are never cut.
const CHAR_WIDTH: f64 = 7.0;
const BOLD_CHAR_WIDTH: f64 = 8.2;
const ROW_LABEL_WIDTH: f64 = 84.0;
const MIN_COLUMN_WIDTH: f64 = 88.0;
const CELL_HEIGHT: f64 = 46.0;
const PANEL_GAP: f64 = 18.0;
const TOP: f64 = 74.0;
const LEGEND_ENTRY_WIDTH: f64 = 112.0;
const MARGIN: f64 = 12.0;

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FigureCell {
    pub x: f64,
    pub y: f64,
    pub width: f64,
    pub fill: &'static str,
    pub text_fill: &'static str,
    /// `Δ=+0.12`, or `Δ n/a`.
    pub delta: String,
    /// `p=0.034`, `p<0.001` or `no test`.
    pub p: String,
    /// Hover text: the figures in full.
    pub title: String,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FigurePanel {
    pub title: String,
    /// Centre of the title.
    pub x: f64,
    /// Centres of the variant headings.
    pub columns: Vec<HeatmapHeader>,
    pub cells: Vec<FigureCell>,
}

/// The whole figure in SVG user units.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StudyFigure {
    pub width: f64,
    pub height: f64,
    pub title: String,
    pub cell_height: f64,
    /// Right edge of the row labels, and each row's (baseline y, label).
    pub label_right: f64,
    pub rows: Vec<(f64, String)>,
    pub panels: Vec<FigurePanel>,
    pub legend_y: f64,
    pub legend: Vec<LegendEntry>,
}

fn text_width(text: &str, char_width: f64) -> f64 {
    text.chars().count() as f64 * char_width + 14.0
}

/// `p=0.034`, `p<0.001`, or `no test`.
pub fn p_text(p: Option<f64>) -> String {
    match p {
        None => "no test".to_owned(),
        Some(p) if p < 0.001 => "p<0.001".to_owned(),
        Some(p) => format!("p={p:.3}"),
    }
}

impl StudyFigure {
    /// The figure of `report`'s direction cells (step-length cells are left to the tables).
    pub fn of_report(report: &StudyReport) -> StudyFigure {
        let title = format!(
            "{}: Δ mean pairwise accuracy, variant − baseline ({}), Welch two-tailed p",
            report.stamp.row, report.stamp.baseline.name
        );
        let specs: Vec<_> = report
            .variants
            .iter()
            .map(|v| super::VariantSpec {
                family: v.family.clone(),
                label: v.variant.clone(),
                dataset: v.dataset.clone(),
            })
            .collect();
        let mut x = ROW_LABEL_WIDTH;
        let mut panels = Vec::new();
        for (family, members) in families(&specs) {
            let mut widths: Vec<f64> = members
                .iter()
                .map(|v| text_width(&v.label, CHAR_WIDTH).max(MIN_COLUMN_WIDTH))
                .collect();
            let needed = text_width(family, BOLD_CHAR_WIDTH);
            let total: f64 = widths.iter().sum();
            if needed > total {
                let extra = (needed - total) / widths.len() as f64;
                widths.iter_mut().for_each(|w| *w += extra);
            }
            let panel_left = x;
            let mut columns = Vec::new();
            let mut cells = Vec::new();
            for (v, width) in members.iter().zip(&widths) {
                columns.push(HeatmapHeader {
                    x: x + width / 2.0,
                    label: v.label.clone(),
                });
                for (r, direction) in Direction::ALL.into_iter().enumerate() {
                    let y = TOP + r as f64 * CELL_HEIGHT;
                    let found = report.cells.iter().find(|c| {
                        c.family == v.family
                            && c.variant == v.label
                            && c.direction == direction
                            && c.step_length.is_none()
                    });
                    cells.push(figure_cell(found, x, y, *width, &v.label, direction));
                }
                x += width;
            }
            panels.push(FigurePanel {
                title: family.to_owned(),
                x: (panel_left + x) / 2.0,
                columns,
                cells,
            });
            x += PANEL_GAP;
        }
        let plot_right = x - PANEL_GAP;
        let legend_y = TOP + 2.0 * CELL_HEIGHT + 18.0;
        let legend: Vec<LegendEntry> = significance_legend()
            .into_iter()
            .enumerate()
            .map(|(i, (fill, label))| LegendEntry {
                x: ROW_LABEL_WIDTH + i as f64 * LEGEND_ENTRY_WIDTH,
                fill,
                label,
            })
            .collect();
        let legend_right = ROW_LABEL_WIDTH + legend.len() as f64 * LEGEND_ENTRY_WIDTH;
        let width = [
            plot_right,
            legend_right,
            MARGIN + text_width(&title, CHAR_WIDTH),
        ]
        .into_iter()
        .fold(0.0, f64::max)
            + MARGIN;
        StudyFigure {
            width,
            height: legend_y + 14.0 + MARGIN,
            title,
            cell_height: CELL_HEIGHT,
            label_right: ROW_LABEL_WIDTH - 8.0,
            rows: Direction::ALL
                .into_iter()
                .enumerate()
                .map(|(r, d)| {
                    let mut name = d.as_str().to_owned();
                    name[..1].make_ascii_uppercase();
                    (TOP + r as f64 * CELL_HEIGHT + CELL_HEIGHT / 2.0 + 4.0, name)
                })
                .collect(),
            panels,
            legend_y,
            legend,
        }
    }
}

fn figure_cell(
    cell: Option<&super::report::StudyCell>,
    x: f64,
    y: f64,
    width: f64,
    variant: &str,
    direction: Direction,
) -> FigureCell {
    let p = cell.and_then(|c| c.p);
    let (fill, text_fill) = significance(p);
    let delta = cell.and_then(|c| c.delta);
    let why = cell
        .and_then(|c| c.undefined.clone())
        .unwrap_or_else(|| "no test".to_owned());
    FigureCell {
        x,
        y,
        width,
        fill,
        text_fill,
        delta: delta.map_or_else(|| "Δ n/a".to_owned(), |d| format!("Δ={d:+.2}")),
        p: p_text(p),
        title: match (cell, p) {
            (Some(c), Some(p)) => format!(
                "{variant}, {direction}: Δ = {:+.4}, t = {:.3}, df = {:.1}, p = {p:.4}, \
                 n = {} baseline / {} variant",
                c.delta.unwrap_or_default(),
                c.t.unwrap_or_default(),
                c.df.unwrap_or_default(),
                c.n_baseline,
                c.n_variant
            ),
            _ => format!("{variant}, {direction}: {why}"),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::study::Alignment;
    use crate::core::study::report::{
        DatasetRef, STUDY_METRIC_VERSION, StudyCell, StudyStamp, VariantSummary,
    };
    use crate::core::study::stats::{paired_t_test, sign_test};

    fn report(variants: &[(&str, &str)]) -> StudyReport {
        let mut cells = Vec::new();
        for (family, variant) in variants {
            for (direction, p) in [
                (Direction::Forward, Some(0.0004)),
                (Direction::Inverse, None),
            ] {
                cells.push(StudyCell {
                    family: (*family).into(),
                    variant: (*variant).into(),
                    direction,
                    step_length: None,
                    delta: p.map(|_| -0.123),
                    t: p.map(|_| -4.0),
                    df: p.map(|_| 30.0),
                    p,
                    n_baseline: 20,
                    n_variant: 20,
                    mean_baseline: None,
                    mean_variant: None,
                    undefined: p
                        .is_none()
                        .then(|| "both samples have zero variance".into()),
                    paired_t: paired_t_test(&[]),
                    sign_test: sign_test(&[]),
                });
            }
        }
        StudyReport {
            stamp: StudyStamp {
                study: "s".into(),
                metric_version: STUDY_METRIC_VERSION.into(),
                hub: crate::core::version::THIS_BUILD,
                tests: String::new(),
                row: "model".into(),
                model: None,
                account: None,
                baseline: DatasetRef {
                    name: "base".into(),
                    hash: String::new(),
                },
                baseline_submission: None,
                variants: Vec::new(),
            },
            variants: variants
                .iter()
                .map(|(f, v)| VariantSummary {
                    family: (*f).into(),
                    variant: (*v).into(),
                    dataset: format!("d-{v}"),
                    alignment: Alignment::default(),
                    aligned: 20,
                    submission: None,
                    missing: None,
                })
                .collect(),
            cells,
            handedness: Vec::new(),
        }
    }

    #[test]
    fn panels_follow_families_and_fit_their_labels() {
        let figure = StudyFigure::of_report(&report(&[
            ("Camera FOV", "Aperture 30"),
            ("Image realism", "Ray tracing only (no denoiser)"),
            ("Camera FOV", "Fisheye"),
            ("Robot appearance with a long family name", "Skin"),
        ]));
        let titles: Vec<&str> = figure.panels.iter().map(|p| p.title.as_str()).collect();
        assert_eq!(
            titles,
            [
                "Camera FOV",
                "Image realism",
                "Robot appearance with a long family name"
            ]
        );
        assert_eq!(figure.panels[0].columns.len(), 2);
        for panel in &figure.panels {
            let left = panel.cells.iter().map(|c| c.x).fold(f64::MAX, f64::min);
            let right = panel
                .cells
                .iter()
                .map(|c| c.x + c.width)
                .fold(0.0, f64::max);
            assert!(right - left >= text_width(&panel.title, BOLD_CHAR_WIDTH) - 1e-9);
            for (column, cell) in panel.columns.iter().zip(panel.cells.iter().step_by(2)) {
                assert!(cell.width >= text_width(&column.label, CHAR_WIDTH));
            }
            assert!(right <= figure.width);
        }
        let cell = &figure.panels[0].cells[0];
        assert_eq!(
            (cell.delta.as_str(), cell.p.as_str()),
            ("Δ=-0.12", "p<0.001")
        );
        assert_eq!(cell.fill, significance(Some(0.0004)).0);
        let inverse = &figure.panels[0].cells[1];
        assert_eq!(inverse.p, "no test");
        assert!(inverse.title.contains("zero variance"));
    }
}
