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

use crate::bundle::{Stamp, csv_document, tex_escape, tex_stamp};
use crate::dataset::{Direction, StepLength};

/// One item's score for the compared row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ItemScore {
    pub direction: Direction,
    pub step_length: StepLength,
    /// 1 or 0 for a model's answer, the mean over its answers for the Human row.
    pub task_accuracy: Option<f64>,
    /// `None` where the verifier gives no pairwise accuracy.
    pub pairwise_accuracy: Option<f64>,
}

/// One dataset's scores under the setting (table row group) it belongs to.
#[derive(Debug, Clone)]
pub struct SettingScores<'a> {
    /// `Baseline`, or a family's name: datasets with the same one are averaged.
    pub setting: String,
    pub dataset: String,
    pub scores: Vec<&'a ItemScore>,
}

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

/// The table of the datasets' scores, settings in the order of their first dataset; step
/// lengths that any dataset has items of, both directions.
pub fn paper_table(per_dataset: &[SettingScores<'_>]) -> PaperTable {
    let lengths: Vec<StepLength> = StepLength::all()
        .filter(|l| {
            per_dataset
                .iter()
                .any(|d| d.scores.iter().any(|s| s.step_length == *l))
        })
        .collect();
    let mut settings: Vec<TableSetting> = Vec::new();
    for d in per_dataset {
        match settings.iter_mut().find(|s| s.setting == d.setting) {
            Some(s) => s.datasets.push(d.dataset.clone()),
            None => settings.push(TableSetting {
                setting: d.setting.clone(),
                datasets: vec![d.dataset.clone()],
                cells: Vec::new(),
            }),
        }
    }
    for setting in &mut settings {
        let members: Vec<&Vec<&ItemScore>> = per_dataset
            .iter()
            .filter(|d| d.setting == setting.setting)
            .map(|d| &d.scores)
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

    struct NoStamp;

    impl Stamp for NoStamp {
        fn stamp_fields(&self) -> Vec<String> {
            vec!["test".to_owned()]
        }
    }

    fn score(direction: Direction, l: usize, pa: f64) -> ItemScore {
        ItemScore {
            direction,
            step_length: StepLength::new(l).unwrap(),
            task_accuracy: Some(if pa == 1.0 { 1.0 } else { 0.0 }),
            pairwise_accuracy: Some(pa),
        }
    }

    #[test]
    fn a_family_of_seeds_gives_mean_and_sd_per_cell() {
        let base = [score(F, 3, 1.0), score(F, 3, 0.5), score(I, 4, 0.0)];
        let seeds: Vec<[ItemScore; 2]> = [0.5, 0.0, 1.0]
            .iter()
            .map(|&pa| [score(F, 3, pa), score(F, 3, pa)])
            .collect();
        let mut datasets = vec![SettingScores {
            setting: "Baseline".to_owned(),
            dataset: "base".to_owned(),
            scores: base.iter().collect(),
        }];
        for (k, scores) in seeds.iter().enumerate() {
            datasets.push(SettingScores {
                setting: "Perturbed".to_owned(),
                dataset: format!("seed-{k}"),
                scores: scores.iter().collect(),
            });
        }
        let table = paper_table(&datasets);
        assert_eq!(table.settings.len(), 2);
        assert_eq!(table.settings[0].setting, "Baseline");
        let family = &table.settings[1];
        assert_eq!(family.datasets, ["seed-0", "seed-1", "seed-2"]);
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
        let f3 = table.settings[0]
            .cells
            .iter()
            .find(|c| c.direction == F && c.step_length == 3)
            .unwrap();
        assert_eq!(f3.task_accuracy.unwrap().mean, 0.5);
        let csv = table_csv(&NoStamp, &table);
        assert!(csv.contains("setting,metric,forward_3,forward_4,inverse_3,inverse_4"));
        assert!(
            csv.contains("Perturbed,Pairwise Accuracy,50.00 ± 50.00,,,\n"),
            "{csv}"
        );
        assert!(
            csv.contains("Baseline,Task Accuracy,50.00,,,0.00\n"),
            "{csv}"
        );
        let tex = table_tex(&NoStamp, &table);
        assert!(tex.contains("$50.00 \\pm 50.00$"));
        assert!(tex.contains("\\textit{\\footnotesize Baseline}"));
    }
}
