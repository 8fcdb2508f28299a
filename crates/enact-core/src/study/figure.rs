//! A study's heatmap, drawn like the paper's ablation figures: one panel per family, one
//! column per variant, forward and inverse rows; each cell coloured by the band of Welch's
//! two-tailed p with Δ and p printed in it ([`crate::heatmap`] lays it out).

use super::families;
use super::report::{StudyCell, StudyReport};
use crate::dataset::Direction;
use crate::heatmap::{CellFigures, ColumnFigures, Heatmap, HeatmapSizes, PanelFigures};

const SIZES: HeatmapSizes = HeatmapSizes {
    top: 74.0,
    cell_height: 46.0,
    min_label_width: 84.0,
    min_column_width: 88.0,
    panel_gap: 18.0,
};

/// `p=0.034`, `p<0.001`, or `no test`.
pub fn p_text(p: Option<f64>) -> String {
    match p {
        None => "no test".to_owned(),
        Some(p) if p < 0.001 => "p<0.001".to_owned(),
        Some(p) => format!("p={p:.3}"),
    }
}

/// The figure of `report`'s direction cells (step-length cells are left to the tables).
pub fn study_heatmap(report: &StudyReport) -> Heatmap {
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
    let panels = families(&specs)
        .into_iter()
        .map(|(family, members)| PanelFigures {
            title: family.to_owned(),
            columns: members
                .iter()
                .map(|v| ColumnFigures {
                    label: v.label.clone(),
                    cells: Direction::ALL
                        .into_iter()
                        .map(|direction| {
                            let found = report.cells.iter().find(|c| {
                                c.family == v.family
                                    && c.variant == v.label
                                    && c.direction == direction
                                    && c.step_length.is_none()
                            });
                            cell_figures(found, &v.label, direction)
                        })
                        .collect(),
                })
                .collect(),
        })
        .collect();
    let rows: Vec<String> = Direction::ALL
        .into_iter()
        .map(|d| {
            let mut name = d.as_str().to_owned();
            name[..1].make_ascii_uppercase();
            name
        })
        .collect();
    let heatmap = Heatmap::layout(
        format!(
            "{title}: one panel per family, one column per variant, forward and inverse rows; \
             colour shows the band of the p-value"
        ),
        Some(title),
        &rows,
        panels,
        SIZES,
        None,
    );
    Heatmap {
        class: "study-heatmap",
        ..heatmap
    }
}

fn cell_figures(cell: Option<&StudyCell>, variant: &str, direction: Direction) -> CellFigures {
    let p = cell.and_then(|c| c.p);
    let delta = cell.and_then(|c| c.delta);
    let why = cell
        .and_then(|c| c.undefined.clone())
        .unwrap_or_else(|| "no test".to_owned());
    CellFigures {
        p,
        lines: vec![
            delta.map_or_else(|| "Δ n/a".to_owned(), |d| format!("Δ={d:+.2}")),
            p_text(p),
        ],
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
    use crate::heatmap::{significance, text_width};
    use crate::study::Alignment;
    use crate::study::report::{
        DatasetRef, STUDY_METRIC_VERSION, StudyCell, StudyStamp, VariantSummary,
    };
    use crate::study::stats::{paired_t_test, sign_test};

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
                hub: crate::version::THIS_BUILD,
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
            table: crate::study::table::PaperTable {
                settings: Vec::new(),
            },
        }
    }

    #[test]
    fn panels_follow_families_and_fit_their_labels() {
        let figure = study_heatmap(&report(&[
            ("Camera FOV", "Aperture 30"),
            ("Image realism", "Ray tracing only (no denoiser)"),
            ("Camera FOV", "Fisheye"),
            ("Robot appearance with a long family name", "Skin"),
        ]));
        let titles: Vec<&str> = figure
            .panels
            .iter()
            .map(|p| p.title.label.as_str())
            .collect();
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
            assert!(right - left >= text_width(&panel.title.label, 8.2) - 1e-9);
            for (column, cell) in panel.columns.iter().zip(panel.cells.iter().step_by(2)) {
                assert!(cell.width >= text_width(&column.label, 7.0));
            }
            assert!(right <= figure.width);
        }
        let cell = &figure.panels[0].cells[0];
        assert_eq!(
            (cell.lines[0].text.as_str(), cell.lines[1].text.as_str()),
            ("Δ=-0.12", "p<0.001")
        );
        assert_eq!(cell.fill, significance(Some(0.0004)).0);
        let inverse = &figure.panels[0].cells[1];
        assert_eq!(inverse.lines[1].text, "no test");
        assert!(inverse.title.contains("zero variance"));
    }
}
