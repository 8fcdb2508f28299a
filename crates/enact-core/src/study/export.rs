//! A study report's files: `study.json` (the whole report), `cells.csv`, `cells.tex` (a
//! booktabs table), `handedness.csv`, `heatmap.svg` (the paper's figure) and `handedness.svg`
//! (its panel C.2), each stamped with the study, the compared row, every dataset's content
//! hash and submission, the metric version and the tests.

use askama::Template;

use super::figure::study_heatmap;
use super::report::{StudyReport, StudyStamp};
use super::table::{table_csv, table_tex};
use crate::bundle::{BundleFile, Stamp, csv_document, fixed, stamp_text, tex_escape, tex_stamp};
use crate::dataset::Direction;
use crate::error_analysis::HandFigures;
use crate::error_analysis::chart::{BarChart, ChartNames, hand_chart_of};

impl Stamp for StudyStamp {
    fn stamp_fields(&self) -> Vec<String> {
        let submission = |s: Option<i64>| s.map_or_else(|| "none".to_owned(), |id| id.to_string());
        let mut lines = vec![
            format!("study: {}", self.study),
            format!("row: {}", self.row),
            format!("metric_version: {}", self.metric_version),
            format!(
                "hub: enact-hub {} (commit {})",
                self.hub.version, self.hub.commit
            ),
            format!("tests: {}", self.tests),
            format!(
                "baseline: {} sha256:{} submission {}",
                self.baseline.name,
                self.baseline.hash,
                submission(self.baseline_submission)
            ),
        ];
        for v in &self.variants {
            lines.push(format!(
                "variant: {}/{} = {} sha256:{} submission {}",
                v.family,
                v.variant,
                v.dataset,
                v.dataset_hash,
                submission(v.submission)
            ));
        }
        lines
    }
}

/// One direction's hand chart.
pub struct HandPanel {
    pub title: String,
    pub top: f64,
    pub chart: BarChart,
}

#[derive(Template)]
#[template(path = "study/handedness.svg")]
struct HandednessSvg<'a> {
    width: f64,
    height: f64,
    panels: &'a [HandPanel],
    legend: Vec<(f64, String, &'static str)>,
    stamp: String,
}

/// The heatmap as a standalone SVG.
pub fn heatmap_svg(report: &StudyReport) -> Result<String, askama::Error> {
    study_heatmap(report).svg(&stamp_text(&report.stamp))
}

/// Panel C.2: per direction, left and right precision, recall and mixing (± SE) of the
/// baseline and each variant. `None` when no dataset has an error analysis.
pub fn handedness_svg(report: &StudyReport) -> Result<Option<String>, askama::Error> {
    if report.handedness.is_empty() {
        return Ok(None);
    }
    let mut panels = Vec::new();
    let mut top = 0.0;
    let mut width: f64 = 0.0;
    let mut labels = Vec::new();
    for direction in Direction::ALL {
        let rows: Vec<(&str, &crate::error_analysis::Handedness)> = report
            .handedness
            .iter()
            .filter(|r| r.direction == direction)
            .map(|r| (r.label.as_str(), &r.hands))
            .collect();
        // The exported figure is the paper's, in English.
        let chart = hand_chart_of(&rows, &ChartNames::english());
        labels = chart.legend.clone();
        width = width.max(chart.width);
        let height = chart.height;
        panels.push(HandPanel {
            title: format!("{direction} world modeling: left and right hand (± SE)"),
            top: top + 24.0,
            chart,
        });
        top += 24.0 + height + 12.0;
    }
    let legend: Vec<(f64, String, &'static str)> = labels
        .into_iter()
        .enumerate()
        .map(|(i, (label, colour))| (top + 18.0 * i as f64, label, colour))
        .collect();
    let height = top + 18.0 * legend.len() as f64 + 8.0;
    HandednessSvg {
        width,
        height,
        panels: &panels,
        legend,
        stamp: stamp_text(&report.stamp),
    }
    .render()
    .map(Some)
}

const CELL_HEADER: [&str; 20] = [
    "family",
    "variant",
    "direction",
    "step_length",
    "delta",
    "t",
    "df",
    "p",
    "n_baseline",
    "n_variant",
    "mean_baseline",
    "mean_variant",
    "undefined",
    "paired_n",
    "paired_mean_difference",
    "paired_t",
    "paired_p",
    "sign_positive",
    "sign_negative",
    "sign_p",
];

fn cell_rows(report: &StudyReport) -> Vec<Vec<String>> {
    report
        .cells
        .iter()
        .map(|c| {
            vec![
                c.family.clone(),
                c.variant.clone(),
                c.direction.to_string(),
                c.step_length.map_or_else(String::new, |l| l.to_string()),
                fixed(c.delta, 4),
                fixed(c.t, 4),
                fixed(c.df, 2),
                c.p.map_or_else(String::new, |p| format!("{p:.4e}")),
                c.n_baseline.to_string(),
                c.n_variant.to_string(),
                fixed(c.mean_baseline, 4),
                fixed(c.mean_variant, 4),
                c.undefined.clone().unwrap_or_default(),
                c.paired_t.n.to_string(),
                fixed(c.paired_t.mean_difference, 4),
                fixed(c.paired_t.t, 4),
                c.paired_t
                    .p
                    .map_or_else(String::new, |p| format!("{p:.4e}")),
                c.sign_test.positive.to_string(),
                c.sign_test.negative.to_string(),
                format!("{:.4e}", c.sign_test.p),
            ]
        })
        .collect()
}

fn hand_fields(h: &HandFigures) -> Vec<String> {
    vec![
        fixed(h.precision, 4),
        fixed(h.precision_se, 4),
        fixed(h.recall, 4),
        fixed(h.recall_se, 4),
        fixed(h.mixing, 4),
        fixed(h.mixing_se, 4),
    ]
}

const HANDEDNESS_HEADER: [&str; 16] = [
    "row",
    "family",
    "dataset",
    "direction",
    "left_precision",
    "left_precision_se",
    "left_recall",
    "left_recall_se",
    "left_mixing",
    "left_mixing_se",
    "right_precision",
    "right_precision_se",
    "right_recall",
    "right_recall_se",
    "right_mixing",
    "right_mixing_se",
];

fn handedness_csv(report: &StudyReport) -> String {
    let rows: Vec<Vec<String>> = report
        .handedness
        .iter()
        .map(|r| {
            let mut row = vec![
                r.label.clone(),
                r.family.clone().unwrap_or_default(),
                r.dataset.clone(),
                r.direction.to_string(),
            ];
            row.extend(hand_fields(&r.hands.left));
            row.extend(hand_fields(&r.hands.right));
            row
        })
        .collect();
    csv_document(&report.stamp, &HANDEDNESS_HEADER, &rows)
}

/// The cells as one CSV document (stamp lines first, as `# ` comments).
pub fn cells_csv(report: &StudyReport) -> String {
    csv_document(&report.stamp, &CELL_HEADER, &cell_rows(report))
}

/// The cells as a booktabs table: Δ, Welch's p and the paired p-values.
pub fn cells_tex(report: &StudyReport) -> String {
    let mut out = tex_stamp(&report.stamp);
    out.push_str(
        "\\begin{table}[t]\n\\centering\n\\small\n\\begin{tabular}{llllrrrrrr}\n\\toprule\n\
         Family & Variant & Direction & $L$ & $\\Delta$ & $t$ & df & $p$ (Welch) & \
         $p$ (paired $t$) & $p$ (sign) \\\\\n\\midrule\n",
    );
    let p = |p: Option<f64>| p.map_or_else(|| "--".to_owned(), |p| format!("{p:.3e}"));
    for c in &report.cells {
        out.push_str(&format!(
            "{} & {} & {} & {} & {} & {} & {} & {} & {} & {} \\\\\n",
            tex_escape(&c.family),
            tex_escape(&c.variant),
            c.direction,
            c.step_length
                .map_or_else(|| "all".to_owned(), |l| l.to_string()),
            c.delta
                .map_or_else(|| "--".to_owned(), |d| format!("{d:+.3}")),
            c.t.map_or_else(|| "--".to_owned(), |t| format!("{t:.2}")),
            c.df.map_or_else(|| "--".to_owned(), |df| format!("{df:.1}")),
            p(c.p),
            p(c.paired_t.p),
            p(Some(c.sign_test.p)),
        ));
    }
    out.push_str(&format!(
        "\\bottomrule\n\\end{{tabular}}\n\\caption{{{}: change in pairwise accuracy against \
         the baseline ({}); two-tailed Welch test as in the paper, with the paired $t$ and \
         sign tests on per-item differences.}}\n\\label{{tab:enact_hub_study_{}}}\n\
         \\end{{table}}\n",
        tex_escape(&report.stamp.row),
        tex_escape(&report.stamp.baseline.name),
        report
            .stamp
            .study
            .chars()
            .filter(char::is_ascii_alphanumeric)
            .collect::<String>()
    ));
    out
}

/// Every file of the report.
pub fn study_files(report: &StudyReport) -> Result<Vec<BundleFile>, String> {
    let json = serde_json::to_string_pretty(report).map_err(|e| e.to_string())?;
    let mut files = vec![
        BundleFile {
            name: "study.json".into(),
            bytes: json.into_bytes(),
        },
        BundleFile {
            name: "cells.csv".into(),
            bytes: cells_csv(report).into_bytes(),
        },
        BundleFile {
            name: "cells.tex".into(),
            bytes: cells_tex(report).into_bytes(),
        },
        BundleFile {
            name: "table.csv".into(),
            bytes: table_csv(&report.stamp, &report.table).into_bytes(),
        },
        BundleFile {
            name: "table.tex".into(),
            bytes: table_tex(&report.stamp, &report.table).into_bytes(),
        },
        BundleFile {
            name: "heatmap.svg".into(),
            bytes: heatmap_svg(report).map_err(|e| e.to_string())?.into_bytes(),
        },
    ];
    if !report.handedness.is_empty() {
        files.push(BundleFile {
            name: "handedness.csv".into(),
            bytes: handedness_csv(report).into_bytes(),
        });
    }
    if let Some(svg) = handedness_svg(report).map_err(|e| e.to_string())? {
        files.push(BundleFile {
            name: "handedness.svg".into(),
            bytes: svg.into_bytes(),
        });
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use crate::dataset::Direction;
    use crate::study::report::fixtures::{inputs, row};
    use crate::study::report::{STUDY_METRIC_VERSION, build_study_report};

    const F: Direction = Direction::Forward;
    const I: Direction = Direction::Inverse;

    #[test]
    fn every_file_is_stamped_with_the_datasets() {
        let baseline = row(1, &[("a", F, 3, 1.0), ("b", F, 3, 0.5), ("c", I, 4, 0.0)]);
        let variant = row(2, &[("a", F, 3, 0.5), ("b", F, 3, 0.5), ("c", I, 4, 1.0)]);
        let mut with_hands = inputs(baseline, Ok(variant));
        let hands = crate::error_analysis::analyse([]).overall.handedness;
        with_hands.baseline_row.hands = Some([hands.clone(), hands]);
        let report = build_study_report(&with_hands).unwrap();
        let files = super::study_files(&report).unwrap();
        let names: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "study.json",
                "cells.csv",
                "cells.tex",
                "table.csv",
                "table.tex",
                "heatmap.svg",
                "handedness.csv",
                "handedness.svg"
            ]
        );
        for file in &files {
            let text = String::from_utf8(file.bytes.clone()).unwrap();
            for needle in ["h0", "h1", STUDY_METRIC_VERSION, "m (team)"] {
                assert!(text.contains(needle), "{} lacks {needle}", file.name);
            }
        }
        let csv = String::from_utf8(files[1].bytes.clone()).unwrap();
        assert!(csv.contains("\nCamera,Fisheye,forward,,-0.2500,"), "{csv}");
        let tex = String::from_utf8(files[2].bytes.clone()).unwrap();
        assert!(
            tex.contains("Camera & Fisheye & forward & all & -0.250 &"),
            "{tex}"
        );
    }
}
