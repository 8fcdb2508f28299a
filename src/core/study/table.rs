//! A study in the layout of the paper's appendix tables (`tab:app_action_repr`,
//! `tab:predicate_noise`): a row per setting, task and pairwise accuracy per direction and step
//! length. The baseline is the first setting; each family is one more. A family of one variant
//! shows its means; a family of several (the seeds of a perturbation) shows the mean ± sample
//! standard deviation of its variants' means, as `tab:predicate_noise` does over three seeds.
//!
//! A variant's means are over its items aligned with the baseline's, so a baseline that is a
//! subset of the variants' items (`dataset subset`) gives each setting the subset's questions.

use schemars::JsonSchema;
use serde::Serialize;

use super::families;
use super::report::{ItemScore, StudyInputs};
use crate::core::bundle::{Stamp, csv_document, tex_escape, tex_stamp};
use crate::core::dataset::{Direction, StepLength};

/// A value over a setting's datasets: the mean, and the sample standard deviation when the
/// setting has several.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct MeanSd {
    pub mean: f64,
    pub sd: Option<f64>,
}

impl MeanSd {
    /// The mean and sample standard deviation of `values` (`None` when empty).
    pub fn of(values: &[f64]) -> Option<MeanSd> {
        let n = values.len();
        if n == 0 {
            return None;
        }
        let mean = values.iter().sum::<f64>() / n as f64;
        let sd = (n > 1).then(|| {
            (values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1) as f64).sqrt()
        });
        Some(MeanSd { mean, sd })
    }

    /// As a percentage with two decimals, `68.51 ± 1.44` when there is a deviation.
    pub fn percent(&self) -> String {
        match self.sd {
            Some(sd) => format!("{:.2} ± {:.2}", 100.0 * self.mean, 100.0 * sd),
            None => format!("{:.2}", 100.0 * self.mean),
        }
    }
}

/// One setting's figures for one direction and step length.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct TableCell {
    pub direction: Direction,
    pub step_length: u8,
    /// Items scored, per dataset of the setting.
    pub items: Vec<usize>,
    pub task_accuracy: Option<MeanSd>,
    pub pairwise_accuracy: Option<MeanSd>,
}

/// One row group of the table: the baseline or a family.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct TableSetting {
    /// `Baseline`, or the family's name.
    pub setting: String,
    /// The datasets averaged over.
    pub datasets: Vec<String>,
    pub cells: Vec<TableCell>,
}

/// The table.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct PaperTable {
    pub settings: Vec<TableSetting>,
}

/// One dataset's mean TA and PA in one direction and step length, over `scores`.
fn means<'a>(
    scores: impl Iterator<Item = &'a ItemScore>,
    direction: Direction,
    step_length: StepLength,
) -> (usize, Option<f64>, Option<f64>) {
    let (mut n, mut ta, mut pa, mut n_ta, mut n_pa) = (0, 0.0, 0.0, 0usize, 0usize);
    for s in scores.filter(|s| s.direction == direction && s.step_length == step_length) {
        n += 1;
        if let Some(t) = s.task_accuracy {
            ta += t;
            n_ta += 1;
        }
        if let Some(p) = s.pairwise_accuracy {
            pa += p;
            n_pa += 1;
        }
    }
    let mean = |sum: f64, k: usize| (k > 0).then(|| sum / k as f64);
    (n, mean(ta, n_ta), mean(pa, n_pa))
}

/// The table of a study's inputs: step lengths that any setting has items of, both directions.
pub fn paper_table(inputs: &StudyInputs) -> PaperTable {
    // Each dataset's scores, over the items aligned with the baseline for a variant.
    let baseline: Vec<&ItemScore> = inputs.baseline_row.items.values().collect();
    let mut per_dataset: Vec<(String, String, Vec<&ItemScore>)> = vec![(
        "Baseline".to_owned(),
        inputs.baseline.name.clone(),
        baseline,
    )];
    let specs: Vec<_> = inputs.variants.iter().map(|v| v.spec.clone()).collect();
    for (family, members) in families(&specs) {
        for spec in members {
            let Some(variant) = inputs.variants.iter().find(|v| v.spec == *spec) else {
                continue;
            };
            let Ok(row) = &variant.row else { continue };
            let scores = variant
                .pairs
                .iter()
                .filter_map(|(_, v)| row.items.get(v))
                .collect();
            per_dataset.push((family.to_owned(), spec.dataset.clone(), scores));
        }
    }
    let lengths: Vec<StepLength> = StepLength::all()
        .filter(|l| {
            per_dataset
                .iter()
                .any(|(_, _, s)| s.iter().any(|s| s.step_length == *l))
        })
        .collect();
    let mut settings: Vec<TableSetting> = Vec::new();
    for (setting, dataset, _) in &per_dataset {
        match settings.iter_mut().find(|s| &s.setting == setting) {
            Some(s) => s.datasets.push(dataset.clone()),
            None => settings.push(TableSetting {
                setting: setting.clone(),
                datasets: vec![dataset.clone()],
                cells: Vec::new(),
            }),
        }
    }
    for setting in &mut settings {
        let members: Vec<&Vec<&ItemScore>> = per_dataset
            .iter()
            .filter(|(s, _, _)| *s == setting.setting)
            .map(|(_, _, scores)| scores)
            .collect();
        for direction in Direction::ALL {
            for &l in &lengths {
                let figures: Vec<(usize, Option<f64>, Option<f64>)> = members
                    .iter()
                    .map(|scores| means(scores.iter().copied(), direction, l))
                    .collect();
                let ta: Vec<f64> = figures.iter().filter_map(|f| f.1).collect();
                let pa: Vec<f64> = figures.iter().filter_map(|f| f.2).collect();
                setting.cells.push(TableCell {
                    direction,
                    step_length: l.get(),
                    items: figures.iter().map(|f| f.0).collect(),
                    task_accuracy: MeanSd::of(&ta),
                    pairwise_accuracy: MeanSd::of(&pa),
                });
            }
        }
    }
    PaperTable { settings }
}

const METRICS: [&str; 2] = ["Task Accuracy", "Pairwise Accuracy"];

/// A cell's figure for metric 0 (task) or 1 (pairwise), if it has one.
fn metric_text(cell: Option<&TableCell>, metric: usize) -> Option<String> {
    let cell = cell?;
    let value = if metric == 0 {
        cell.task_accuracy
    } else {
        cell.pairwise_accuracy
    };
    value.map(|v| v.percent())
}

fn lengths_of(table: &PaperTable) -> Vec<u8> {
    let mut lengths: Vec<u8> = table
        .settings
        .iter()
        .flat_map(|s| s.cells.iter().map(|c| c.step_length))
        .collect();
    lengths.sort_unstable();
    lengths.dedup();
    lengths
}

fn cells_in_order<'a>(setting: &'a TableSetting, lengths: &[u8]) -> Vec<Option<&'a TableCell>> {
    Direction::ALL
        .into_iter()
        .flat_map(|d| {
            lengths.iter().map(move |&l| {
                setting
                    .cells
                    .iter()
                    .find(|c| c.direction == d && c.step_length == l)
            })
        })
        .collect()
}

/// The table as CSV: `setting, metric`, then a column per direction and step length
/// (percentages; `mean ± sd` for a family of several datasets; empty where nothing is scored).
pub fn table_csv(stamp: &impl Stamp, table: &PaperTable) -> String {
    let lengths = lengths_of(table);
    let mut header = vec!["setting".to_owned(), "metric".to_owned()];
    for d in Direction::ALL {
        header.extend(lengths.iter().map(|l| format!("{d}_{l}")));
    }
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    let mut rows = Vec::new();
    for setting in &table.settings {
        for (m, metric) in METRICS.iter().enumerate() {
            let mut row = vec![setting.setting.clone(), (*metric).to_owned()];
            row.extend(
                cells_in_order(setting, &lengths)
                    .into_iter()
                    .map(|c| metric_text(c, m).unwrap_or_default()),
            );
            rows.push(row);
        }
    }
    csv_document(stamp, &header, &rows)
}

/// The table as LaTeX in the paper's layout: a block per setting with its Task and Pairwise
/// Accuracy rows, columns Forward 3..10 then Inverse 3..10.
pub fn table_tex(stamp: &impl Stamp, table: &PaperTable) -> String {
    let lengths = lengths_of(table);
    let n = lengths.len();
    let mut out = tex_stamp(stamp);
    out.push_str(&format!(
        "\\begin{{table*}}[!htbp]\n\\centering\n\\small\n\\begin{{tabular}}{{l{}}}\n\\toprule\n",
        "c".repeat(2 * n)
    ));
    out.push_str(&format!(
        "\\textbf{{Metric}} & \\multicolumn{{{n}}}{{c}}{{\\textbf{{Forward}}}} & \
         \\multicolumn{{{n}}}{{c}}{{\\textbf{{Inverse}}}} \\\\\n"
    ));
    let numbers: Vec<String> = lengths.iter().map(|l| format!("\\bf {l}")).collect();
    out.push_str(&format!(
        " & {} & {} \\\\\n",
        numbers.join(" & "),
        numbers.join(" & ")
    ));
    for setting in &table.settings {
        out.push_str(&format!(
            "\\midrule\n\\multicolumn{{{}}}{{l}}{{\\textit{{\\footnotesize {}}}}}\\\\\n",
            2 * n + 1,
            tex_escape(&setting.setting)
        ));
        for (m, metric) in METRICS.iter().enumerate() {
            let cells: Vec<String> = cells_in_order(setting, &lengths)
                .into_iter()
                .map(|c| {
                    let text = metric_text(c, m).unwrap_or_else(|| "--".to_owned());
                    if text.contains('±') {
                        format!("${}$", text.replace('±', "\\pm"))
                    } else {
                        text
                    }
                })
                .collect();
            out.push_str(&format!("{metric} & {} \\\\\n", cells.join(" & ")));
        }
    }
    out.push_str("\\bottomrule\n\\end{tabular}\n\\end{table*}\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::study::VariantSpec;
    use crate::core::study::report::fixtures::{inputs, row};

    const F: Direction = Direction::Forward;
    const I: Direction = Direction::Inverse;

    #[test]
    fn mean_and_sample_sd() {
        let v = MeanSd::of(&[0.6, 0.7, 0.8]).unwrap();
        assert!((v.mean - 0.7).abs() < 1e-12);
        assert!((v.sd.unwrap() - 0.1).abs() < 1e-12);
        assert_eq!(v.percent(), "70.00 ± 10.00");
        assert_eq!(MeanSd::of(&[0.5]).unwrap().percent(), "50.00");
        assert_eq!(MeanSd::of(&[]), None);
    }

    #[test]
    fn a_family_of_seeds_gives_mean_and_sd_per_cell() {
        let base = row(1, &[("a", F, 3, 1.0), ("b", F, 3, 0.5), ("c", I, 4, 0.0)]);
        let mut study = inputs(base, Ok(row(2, &[("a", F, 3, 0.5), ("b", F, 3, 0.5)])));
        // Two more seeds of the same family.
        let first = study.variants[0].clone();
        for (k, pa) in [(3, 0.0), (4, 1.0)] {
            let mut v = first.clone();
            v.spec = VariantSpec::new("Camera", &format!("seed {k}"), &format!("d{k}")).unwrap();
            v.row = Ok(row(k, &[("a", F, 3, pa), ("b", F, 3, pa)]));
            study.variants.push(v);
        }
        let table = paper_table(&study);
        assert_eq!(table.settings.len(), 2);
        assert_eq!(table.settings[0].setting, "Baseline");
        let family = &table.settings[1];
        assert_eq!(family.datasets, ["fish", "d3", "d4"]);
        // Forward L = 3: the seeds' means are 0.5, 0.0, 1.0.
        let cell = family
            .cells
            .iter()
            .find(|c| c.direction == F && c.step_length == 3)
            .unwrap();
        let pa = cell.pairwise_accuracy.unwrap();
        assert!((pa.mean - 0.5).abs() < 1e-12);
        assert!((pa.sd.unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(cell.items, [2, 2, 2]);
        // Task accuracy is 1 exactly where pairwise accuracy is (the fixture's rule).
        let base = &table.settings[0].cells;
        let f3 = base
            .iter()
            .find(|c| c.direction == F && c.step_length == 3)
            .unwrap();
        assert_eq!(f3.task_accuracy.unwrap().mean, 0.5);
        let stamp = crate::core::study::report::build_study_report(&study)
            .unwrap()
            .stamp;
        let csv = table_csv(&stamp, &table);
        assert!(csv.contains("setting,metric,forward_3,forward_4,inverse_3,inverse_4"));
        assert!(csv.contains("Camera,Pairwise Accuracy,50.00 ± 50.00,,,\n"));
        let tex = table_tex(&stamp, &table);
        assert!(tex.contains("$50.00 \\pm 50.00$"));
        assert!(tex.contains("\\textit{\\footnotesize Baseline}"));
    }
}
