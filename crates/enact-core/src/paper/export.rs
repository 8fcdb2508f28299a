//! The folder `enact-hub paper` writes (and the page downloads as a tar): every table in each
//! format, where every cell came from, and the reproduction check when asked for.

use serde::Serialize;

use super::Metric;
use super::error_figure::{AnalysedRow, ErrorChart};
use super::figure::{FigureError, StepChart};
use super::heatmap_png::heatmap_png;
use super::hub::{AssembledTable, CellProvenance, ReproducedCell};
use super::write::{to_csv, to_json, to_markdown, to_tex};
use crate::bundle::{BundleFile, csv_field};
use crate::study::export::heatmap_svg;
use crate::study::figure::study_heatmap;
use crate::study::report::StudyReport;

/// What the folder is made from.
#[derive(Debug, Clone)]
pub struct PaperBundle<'a> {
    pub dataset: &'a str,
    /// The hub build that assembled it.
    pub hub_version: &'a str,
    pub tables: &'a [AssembledTable],
    /// The published models the hub also scored, cell by cell; `None` when not asked for.
    pub reproduction: Option<&'a [ReproducedCell]>,
    /// The error analyses of the chosen hub rows (submissions and the Human row), in table
    /// order; the error-analysis figure is left out when there are none.
    pub error_analyses: &'a [AnalysedRow],
    /// The studies whose baseline is the dataset, each reported for one row.
    pub studies: &'a [StudyFigure],
}

/// A study of the dataset and its report for the row its heat map shows.
#[derive(Debug, Clone)]
pub struct StudyFigure {
    /// The study's name (plain: letters, digits, `.`, `_` and `-`, so safe in a file name).
    pub study: String,
    pub report: StudyReport,
}

/// The file names of a study's heat map, SVG and PNG.
pub fn study_heatmap_names(study: &str) -> [String; 2] {
    [
        format!("study-{study}-heatmap.svg"),
        format!("study-{study}-heatmap.png"),
    ]
}

#[derive(Serialize)]
struct Provenance<'a> {
    dataset: &'a str,
    hub_version: &'a str,
    cells: Vec<&'a CellProvenance>,
}

#[derive(Serialize)]
struct Reproduction<'a> {
    dataset: &'a str,
    hub_version: &'a str,
    cells: &'a [ReproducedCell],
}

/// Why the folder could not be written (a defect, not the data's fault).
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("JSON: {0}")]
    Json(#[from] serde_json::Error),
    #[error("figure: {0}")]
    Svg(#[from] askama::Error),
    #[error("figure: {0}")]
    Png(#[from] FigureError),
}

/// File names per table: tex, standalone tex, csv, md, json, and the figure as svg and png.
fn names(metric: Metric) -> [&'static str; 7] {
    match metric {
        Metric::TaskAccuracy => [
            "task_accuracy.tex",
            "task_accuracy_standalone.tex",
            "task_accuracy.csv",
            "task_accuracy.md",
            "task_accuracy.json",
            "task_accuracy_by_step_length.svg",
            "task_accuracy_by_step_length.png",
        ],
        Metric::PairwiseAccuracy => [
            "pairwise_accuracy.tex",
            "pairwise_accuracy_standalone.tex",
            "pairwise_accuracy.csv",
            "pairwise_accuracy.md",
            "pairwise_accuracy.json",
            "pairwise_accuracy_by_step_length.svg",
            "pairwise_accuracy_by_step_length.png",
        ],
    }
}

/// The figure of a table: accuracy by step length per direction.
pub fn figure(table: &super::PaperTable) -> StepChart {
    StepChart::accuracy_by_step_length(table)
}

/// What a figure's `<metadata>` says it was made from.
pub fn figure_stamp(dataset: &str, hub_version: &str) -> String {
    format!("dataset: {dataset}; enact-hub {hub_version}")
}

fn interval_text(interval: Option<(f64, f64)>) -> [String; 2] {
    interval.map_or_else(Default::default, |(low, high)| {
        [format!("{low:.2}"), format!("{high:.2}")]
    })
}

/// The reproduction check as CSV: one line per cell.
pub fn reproduction_csv(cells: &[ReproducedCell]) -> String {
    let mut out = String::from(
        "model,metric,cell,reported,hub,difference,hub_low,hub_high,inside,submission,source\n",
    );
    for c in cells {
        let [low, high] = interval_text(c.interval);
        let fields = [
            csv_field(&c.model),
            c.metric.as_str().to_owned(),
            c.cell.to_string(),
            format!("{:.2}", c.reported),
            format!("{:.2}", c.hub),
            format!("{:.2}", c.difference),
            low,
            high,
            c.inside.map_or_else(String::new, |i| i.to_string()),
            c.submission.map_or_else(String::new, |s| s.to_string()),
            csv_field(&c.source),
        ];
        out.push_str(&fields.join(","));
        out.push('\n');
    }
    out
}

/// Every file of the folder, in a fixed order: each table's files, the error-analysis figure,
/// the studies' heat maps, provenance and the reproduction check.
pub fn files(bundle: &PaperBundle<'_>) -> Result<Vec<BundleFile>, ExportError> {
    let mut files = Vec::new();
    let stamp = figure_stamp(bundle.dataset, bundle.hub_version);
    for assembled in bundle.tables {
        let table = &assembled.table;
        let [tex, standalone, csv, md, json, svg, png] = names(table.metric);
        files.push(BundleFile {
            name: tex.into(),
            bytes: to_tex(table, false).into_bytes(),
        });
        files.push(BundleFile {
            name: standalone.into(),
            bytes: to_tex(table, true).into_bytes(),
        });
        files.push(BundleFile {
            name: csv.into(),
            bytes: to_csv(table).into_bytes(),
        });
        files.push(BundleFile {
            name: md.into(),
            bytes: to_markdown(table).into_bytes(),
        });
        files.push(BundleFile {
            name: json.into(),
            bytes: to_json(table).into_bytes(),
        });
        let chart = figure(table);
        files.push(BundleFile {
            name: svg.into(),
            bytes: chart.svg(&stamp)?.into_bytes(),
        });
        files.push(BundleFile {
            name: png.into(),
            bytes: chart.png()?,
        });
    }
    if !bundle.error_analyses.is_empty() {
        let chart = ErrorChart::of(bundle.error_analyses);
        files.push(BundleFile {
            name: "error_analysis.svg".into(),
            bytes: chart.svg(&stamp)?.into_bytes(),
        });
        files.push(BundleFile {
            name: "error_analysis.png".into(),
            bytes: chart.png()?,
        });
    }
    for figure in bundle.studies {
        let [svg, png] = study_heatmap_names(&figure.study);
        files.push(BundleFile {
            name: svg,
            bytes: heatmap_svg(&figure.report)?.into_bytes(),
        });
        files.push(BundleFile {
            name: png,
            bytes: heatmap_png(&study_heatmap(&figure.report))?,
        });
    }
    let provenance = Provenance {
        dataset: bundle.dataset,
        hub_version: bundle.hub_version,
        cells: bundle
            .tables
            .iter()
            .flat_map(|t| t.provenance.iter())
            .collect(),
    };
    files.push(BundleFile {
        name: "provenance.json".into(),
        bytes: serde_json::to_vec_pretty(&provenance)?,
    });
    if let Some(cells) = bundle.reproduction {
        let reproduction = Reproduction {
            dataset: bundle.dataset,
            hub_version: bundle.hub_version,
            cells,
        };
        files.push(BundleFile {
            name: "reproduction.json".into(),
            bytes: serde_json::to_vec_pretty(&reproduction)?,
        });
        files.push(BundleFile {
            name: "reproduction.csv".into(),
            bytes: reproduction_csv(cells).into_bytes(),
        });
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;
    use crate::dataset::{Direction, StepLength};
    use crate::paper::heatmap_png::tests::camera_study;
    use crate::paper::hub::{HUB_CATEGORY, HubRow, Origin, assemble, reproduction};
    use crate::paper::{Category, CellKey, PaperTable, ReportedModel};
    use crate::verifier::Resampling;

    fn f3() -> CellKey {
        CellKey {
            direction: Direction::Forward,
            step_length: StepLength::new(3).unwrap(),
        }
    }

    #[test]
    fn the_folder_holds_each_table_in_every_format_and_where_each_cell_came_from() {
        let published = ReportedModel {
            model: "GPT-5".to_owned(),
            category: Category::Proprietary,
            family: None,
            size: None,
            source: "ENACT paper, tab:app_task_acc".to_owned(),
            task_accuracy: BTreeMap::from([(f3(), 84.62)]),
            pairwise_accuracy: BTreeMap::from([(f3(), 90.0)]),
        };
        let mut ours = HubRow {
            model: "GPT-5".to_owned(),
            category: Category::Named(HUB_CATEGORY.to_owned()),
            family: None,
            size: None,
            origin: Origin::Submission {
                submission: 12,
                provenance: crate::submission::Provenance::Submitted,
                account: "lab".to_owned(),
                metric_version: 3,
                hub_version: "0.1.0+abc".to_owned(),
            },
            task_accuracy: BTreeMap::from([(f3(), 80.0)]),
            pairwise_accuracy: BTreeMap::from([(f3(), 88.5)]),
            intervals: BTreeMap::new(),
            interval_resampling: Some(Resampling::Activities),
        };
        ours.intervals
            .insert((Metric::TaskAccuracy, f3()), (70.0, 86.0));
        let reported = [published];
        let own = [ours];
        let tables: Vec<AssembledTable> = Metric::ALL
            .iter()
            .map(|m| assemble(*m, &reported, &own, None, false).unwrap())
            .collect();
        let cells = reproduction(&reported, &own);
        let bundle = PaperBundle {
            dataset: "enact",
            hub_version: "0.1.0+abc",
            tables: &tables,
            reproduction: Some(&cells),
            error_analyses: &[AnalysedRow {
                model: "GPT-5".to_owned(),
                analysis: crate::error_analysis::analyse(std::iter::empty()),
            }],
            studies: &[StudyFigure {
                study: "camera".to_owned(),
                report: camera_study(),
            }],
        };
        let files = files(&bundle).unwrap();
        let names: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "task_accuracy.tex",
                "task_accuracy_standalone.tex",
                "task_accuracy.csv",
                "task_accuracy.md",
                "task_accuracy.json",
                "task_accuracy_by_step_length.svg",
                "task_accuracy_by_step_length.png",
                "pairwise_accuracy.tex",
                "pairwise_accuracy_standalone.tex",
                "pairwise_accuracy.csv",
                "pairwise_accuracy.md",
                "pairwise_accuracy.json",
                "pairwise_accuracy_by_step_length.svg",
                "pairwise_accuracy_by_step_length.png",
                "error_analysis.svg",
                "error_analysis.png",
                "study-camera-heatmap.svg",
                "study-camera-heatmap.png",
                "provenance.json",
                "reproduction.json",
                "reproduction.csv",
            ]
        );
        let text = |name: &str| {
            String::from_utf8(files.iter().find(|f| f.name == name).unwrap().bytes.clone()).unwrap()
        };
        // The JSON table reads back as the table it was written from.
        let back = PaperTable::from_json(&text("task_accuracy.json")).unwrap();
        let svg = text("task_accuracy_by_step_length.svg");
        assert!(
            svg.starts_with("<svg") && svg.contains("dataset: enact"),
            "{svg}"
        );
        let png = &files
            .iter()
            .find(|f| f.name == "task_accuracy_by_step_length.png")
            .unwrap()
            .bytes;
        assert!(png.starts_with(b"\x89PNG"));
        assert_eq!(back, tables[0].table);
        let heatmap = text("study-camera-heatmap.svg");
        assert!(
            heatmap.contains("study-heatmap") && heatmap.contains("Fisheye"),
            "{heatmap}"
        );
        let provenance: serde_json::Value = serde_json::from_str(&text("provenance.json")).unwrap();
        let cells = provenance["cells"].as_array().unwrap();
        assert_eq!(cells.len(), 4);
        assert!(cells.iter().any(|c| c["table"] == "task_accuracy"
            && c["value"] == 80.0
            && c["from"]["kind"] == "submission"
            && c["from"]["submission"] == 12));
        assert!(cells.iter().any(|c| c["from"]["kind"] == "reported"
            && c["from"]["source"] == "ENACT paper, tab:app_task_acc"));
        assert_eq!(
            text("reproduction.csv"),
            "model,metric,cell,reported,hub,difference,hub_low,hub_high,inside,submission,source\n\
             GPT-5,task_accuracy,forward_3,84.62,80.00,-4.62,70.00,86.00,true,12,\
             \"ENACT paper, tab:app_task_acc\"\n\
             GPT-5,pairwise_accuracy,forward_3,90.00,88.50,-1.50,,,,12,\
             \"ENACT paper, tab:app_task_acc\"\n"
        );
    }
}
