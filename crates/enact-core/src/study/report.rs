//! A study report for one row (a model's published submission on each dataset, or the Human
//! row): for every variant and direction (and step length on request), Δ of mean pairwise
//! accuracy (variant − baseline) with the paper's two-tailed Welch test, and the paired t and
//! sign tests the alignment allows; and each dataset's left/right-hand figures (the paper's
//! panel C.2).

use std::collections::HashMap;

use schemars::JsonSchema;
use serde::Serialize;

use super::stats::{PairedT, SignTest, paired_t_test, sign_test};
pub use super::table::ItemScore;
use super::table::{PaperTable, SettingScores, paper_table};
use super::{Alignment, VariantSpec};
use crate::agreement::welch_t_test;
use crate::dataset::{Direction, StepLength};
use crate::error_analysis::Handedness;
use crate::metric::MetricStamp;
use crate::version::{HubBuild, THIS_BUILD};

/// Names what the numbers of a study report mean; bump it when a definition changes.
pub const STUDY_METRIC_VERSION: &str = "enact-hub-study-report/1";

/// The tests behind every cell, as the stamp states them.
pub const STUDY_TESTS: &str = "Welch two-tailed unpaired t-test (the paper's); Student paired \
    t-test and exact two-sided binomial sign test on per-item differences; no random draws";

/// A stored dataset as a report names it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, JsonSchema)]
pub struct DatasetRef {
    pub name: String,
    /// `dataset_content_hash` of its items.
    pub hash: String,
}

/// The compared row on one dataset.
#[derive(Debug, Clone, PartialEq)]
pub struct RowScores {
    /// The submission, or `None` for the Human row.
    pub submission: Option<i64>,
    /// By item id.
    pub items: HashMap<String, ItemScore>,
    /// Forward and inverse hand figures, when the error analysis could be made.
    pub hands: Option<[Handedness; 2]>,
    /// The metric version its scores were computed with.
    pub metric_version: u32,
}

/// One variant with what the report needs of it.
#[derive(Debug, Clone)]
pub struct VariantInput {
    pub spec: VariantSpec,
    pub dataset_hash: String,
    pub alignment: Alignment,
    /// (baseline item id, variant item id) for each aligned pair, in baseline order.
    pub pairs: Vec<(String, String)>,
    /// The row on this dataset, or why there is none.
    pub row: Result<RowScores, String>,
}

/// Everything a study report is built from.
#[derive(Debug, Clone)]
pub struct StudyInputs {
    pub study: String,
    /// The compared row: `model (account)` or `Human`.
    pub row_label: String,
    pub model: Option<String>,
    pub account: Option<String>,
    pub baseline: DatasetRef,
    pub baseline_row: RowScores,
    pub variants: Vec<VariantInput>,
    /// Add a cell per step length under each direction.
    pub by_step_length: bool,
}

/// A variant in the stamp.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct StampedVariant {
    pub family: String,
    pub variant: String,
    pub dataset: String,
    pub dataset_hash: String,
    pub submission: Option<i64>,
}

/// What every file of a study report carries.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct StudyStamp {
    pub study: String,
    pub metric_version: String,
    /// The enact-hub build that computed the report.
    pub hub: HubBuild,
    pub tests: String,
    pub row: String,
    pub model: Option<String>,
    pub account: Option<String>,
    pub baseline: DatasetRef,
    pub baseline_submission: Option<i64>,
    pub variants: Vec<StampedVariant>,
}

/// A variant as the report summarises it.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct VariantSummary {
    pub family: String,
    pub variant: String,
    pub dataset: String,
    pub alignment: Alignment,
    pub aligned: usize,
    pub submission: Option<i64>,
    /// Why the variant has no figures (no published submission of the row on it).
    pub missing: Option<String>,
}

/// One family × variant × direction (× step length) comparison.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct StudyCell {
    pub family: String,
    pub variant: String,
    pub direction: Direction,
    /// `None`: every step length of the direction.
    pub step_length: Option<u8>,
    /// Mean pairwise accuracy on the variant minus on the baseline, over the aligned items.
    pub delta: Option<f64>,
    /// Welch's t, its Welch–Satterthwaite df and two-tailed p (the paper's test).
    pub t: Option<f64>,
    pub df: Option<f64>,
    pub p: Option<f64>,
    pub n_baseline: usize,
    pub n_variant: usize,
    pub mean_baseline: Option<f64>,
    pub mean_variant: Option<f64>,
    /// Why Welch's test has no value, when it has none.
    pub undefined: Option<String>,
    /// Paired t-test on per-item differences (variant − baseline).
    pub paired_t: PairedT,
    pub sign_test: SignTest,
}

/// One dataset's left- and right-hand figures in one direction.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct HandednessRow {
    /// `Baseline` or the variant's label.
    pub label: String,
    /// `None` for the baseline.
    pub family: Option<String>,
    pub dataset: String,
    pub direction: Direction,
    pub hands: Handedness,
}

/// The report.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct StudyReport {
    pub stamp: StudyStamp,
    pub variants: Vec<VariantSummary>,
    /// Variants in the study's order; in each, forward then inverse, each direction's cell
    /// (`step_length: null`) before its step lengths.
    pub cells: Vec<StudyCell>,
    pub handedness: Vec<HandednessRow>,
    /// Task and pairwise accuracy per setting, direction and step length, in the layout of
    /// the paper's appendix tables.
    pub table: PaperTable,
}

/// Which items a cell covers.
#[derive(Debug, Clone, Copy)]
struct CellKey {
    direction: Direction,
    step_length: Option<StepLength>,
}

impl CellKey {
    fn covers(self, score: &ItemScore) -> bool {
        score.direction == self.direction && self.step_length.is_none_or(|l| l == score.step_length)
    }
}

/// Builds the report; an item score that is not a finite number is an error naming it.
pub fn build_study_report(inputs: &StudyInputs) -> Result<StudyReport, String> {
    let mut cells = Vec::new();
    let mut variants = Vec::new();
    let mut handedness = Vec::new();
    if let Some(hands) = &inputs.baseline_row.hands {
        push_hands(
            &mut handedness,
            "Baseline",
            None,
            &inputs.baseline.name,
            hands,
        );
    }
    for variant in &inputs.variants {
        let spec = &variant.spec;
        variants.push(VariantSummary {
            family: spec.family.clone(),
            variant: spec.label.clone(),
            dataset: spec.dataset.clone(),
            alignment: variant.alignment.clone(),
            aligned: variant.pairs.len(),
            submission: variant.row.as_ref().ok().and_then(|r| r.submission),
            missing: variant.row.as_ref().err().cloned(),
        });
        if let Ok(row) = &variant.row
            && let Some(hands) = &row.hands
        {
            push_hands(
                &mut handedness,
                &spec.label,
                Some(&spec.family),
                &spec.dataset,
                hands,
            );
        }
        for direction in Direction::ALL {
            let mut keys = vec![CellKey {
                direction,
                step_length: None,
            }];
            if inputs.by_step_length {
                keys.extend(
                    StepLength::all()
                        .filter(|&l| {
                            variant.pairs.iter().any(|(b, _)| {
                                inputs
                                    .baseline_row
                                    .items
                                    .get(b)
                                    .is_some_and(|s| s.direction == direction && s.step_length == l)
                            })
                        })
                        .map(|l| CellKey {
                            direction,
                            step_length: Some(l),
                        }),
                );
            }
            for key in keys {
                cells.push(cell(inputs, variant, key)?);
            }
        }
    }
    Ok(StudyReport {
        stamp: StudyStamp {
            study: inputs.study.clone(),
            metric_version: MetricStamp::oldest(
                std::iter::once(&inputs.baseline_row)
                    .chain(inputs.variants.iter().filter_map(|v| v.row.as_ref().ok()))
                    .map(|r| r.metric_version),
            )
            .with_report(STUDY_METRIC_VERSION),
            hub: THIS_BUILD,
            tests: STUDY_TESTS.to_owned(),
            row: inputs.row_label.clone(),
            model: inputs.model.clone(),
            account: inputs.account.clone(),
            baseline: inputs.baseline.clone(),
            baseline_submission: inputs.baseline_row.submission,
            variants: inputs
                .variants
                .iter()
                .map(|v| StampedVariant {
                    family: v.spec.family.clone(),
                    variant: v.spec.label.clone(),
                    dataset: v.spec.dataset.clone(),
                    dataset_hash: v.dataset_hash.clone(),
                    submission: v.row.as_ref().ok().and_then(|r| r.submission),
                })
                .collect(),
        },
        variants,
        cells,
        handedness,
        table: paper_table(&table_inputs(inputs)),
    })
}

/// Each dataset of the study as a setting of the paper's table: the baseline's scores, then
/// each variant's over its items aligned with the baseline's, under its family's name.
fn table_inputs(inputs: &StudyInputs) -> Vec<SettingScores<'_>> {
    let mut out = vec![SettingScores {
        setting: "Baseline".to_owned(),
        dataset: inputs.baseline.name.clone(),
        scores: inputs.baseline_row.items.values().collect(),
    }];
    let specs: Vec<VariantSpec> = inputs.variants.iter().map(|v| v.spec.clone()).collect();
    for (family, members) in super::families(&specs) {
        for spec in members {
            let Some(variant) = inputs.variants.iter().find(|v| v.spec == *spec) else {
                continue;
            };
            let Ok(row) = &variant.row else { continue };
            out.push(SettingScores {
                setting: family.to_owned(),
                dataset: spec.dataset.clone(),
                scores: variant
                    .pairs
                    .iter()
                    .filter_map(|(_, v)| row.items.get(v))
                    .collect(),
            });
        }
    }
    out
}

fn push_hands(
    rows: &mut Vec<HandednessRow>,
    label: &str,
    family: Option<&str>,
    dataset: &str,
    hands: &[Handedness; 2],
) {
    for (direction, hands) in Direction::ALL.into_iter().zip(hands) {
        rows.push(HandednessRow {
            label: label.to_owned(),
            family: family.map(str::to_owned),
            dataset: dataset.to_owned(),
            direction,
            hands: hands.clone(),
        });
    }
}

fn cell(inputs: &StudyInputs, variant: &VariantInput, key: CellKey) -> Result<StudyCell, String> {
    let empty = |undefined: String| StudyCell {
        family: variant.spec.family.clone(),
        variant: variant.spec.label.clone(),
        direction: key.direction,
        step_length: key.step_length.map(StepLength::get),
        delta: None,
        t: None,
        df: None,
        p: None,
        n_baseline: 0,
        n_variant: 0,
        mean_baseline: None,
        mean_variant: None,
        undefined: Some(undefined),
        paired_t: paired_t_test(&[]),
        sign_test: sign_test(&[]),
    };
    let row = match &variant.row {
        Ok(row) => row,
        Err(why) => return Ok(empty(why.clone())),
    };
    let (mut baseline, mut varied, mut differences) = (Vec::new(), Vec::new(), Vec::new());
    for (b_id, v_id) in &variant.pairs {
        let Some(b) = inputs.baseline_row.items.get(b_id) else {
            continue;
        };
        if !key.covers(b) {
            continue;
        }
        let b = b.pairwise_accuracy;
        let v = row.items.get(v_id).and_then(|s| s.pairwise_accuracy);
        baseline.extend(b);
        varied.extend(v);
        if let (Some(b), Some(v)) = (b, v) {
            differences.push(v - b);
        }
    }
    // Welch's `a` is the variant, so Δ = variant − baseline.
    let welch = welch_t_test(&varied, &baseline).map_err(|e| {
        format!(
            "variant {}/{}, {}: {e}",
            variant.spec.family, variant.spec.label, key.direction
        )
    })?;
    if baseline.is_empty() && varied.is_empty() {
        return Ok(empty(format!(
            "no aligned {} item{} has a pairwise accuracy",
            key.direction,
            key.step_length
                .map_or_else(String::new, |l| format!(" of length {l}"))
        )));
    }
    Ok(StudyCell {
        family: variant.spec.family.clone(),
        variant: variant.spec.label.clone(),
        direction: key.direction,
        step_length: key.step_length.map(StepLength::get),
        delta: welch.delta,
        t: welch.t,
        df: welch.df,
        p: welch.p,
        n_baseline: welch.n_b,
        n_variant: welch.n_a,
        mean_baseline: welch.mean_b,
        mean_variant: welch.mean_a,
        undefined: welch.reason.as_ref().map(ToString::to_string),
        paired_t: paired_t_test(&differences),
        sign_test: sign_test(&differences),
    })
}

/// Inputs for tests of this module and of `export`.
#[cfg(test)]
pub(crate) mod fixtures {
    use super::*;
    use crate::study::{AlignKey, align};

    pub fn l(n: usize) -> StepLength {
        StepLength::new(n).unwrap()
    }

    pub fn row(submission: i64, scores: &[(&str, Direction, usize, f64)]) -> RowScores {
        RowScores {
            submission: Some(submission),
            metric_version: crate::metric::METRIC_VERSION,
            items: scores
                .iter()
                .map(|(id, d, n, pa)| {
                    (
                        (*id).to_owned(),
                        ItemScore {
                            direction: *d,
                            step_length: l(*n),
                            task_accuracy: Some(if *pa == 1.0 { 1.0 } else { 0.0 }),
                            pairwise_accuracy: Some(*pa),
                        },
                    )
                })
                .collect(),
            hands: None,
        }
    }

    pub fn inputs(baseline: RowScores, variant: Result<RowScores, String>) -> StudyInputs {
        let keys: Vec<AlignKey> = baseline
            .items
            .keys()
            .map(|id| AlignKey {
                item_id: id.clone(),
                item_type: "t".into(),
                task_name: "task".into(),
                key_frame_ids: Vec::new(),
                verification: String::new(),
            })
            .collect();
        let alignment = align(&keys, &keys);
        let pairs = alignment
            .pairs
            .iter()
            .map(|&(b, v)| (keys[b].item_id.clone(), keys[v].item_id.clone()))
            .collect();
        StudyInputs {
            study: "s".into(),
            row_label: "m (team)".into(),
            model: Some("m".into()),
            account: Some("team".into()),
            baseline: DatasetRef {
                name: "base".into(),
                hash: "h0".into(),
            },
            baseline_row: baseline,
            variants: vec![VariantInput {
                spec: VariantSpec::new("Camera", "Fisheye", "fish").unwrap(),
                dataset_hash: "h1".into(),
                alignment,
                pairs,
                row: variant,
            }],
            by_step_length: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::fixtures::{inputs, row};
    use super::*;

    const F: Direction = Direction::Forward;
    const I: Direction = Direction::Inverse;

    #[test]
    fn the_same_answers_give_no_difference() {
        let scores = [
            ("a", F, 3, 1.0),
            ("b", F, 3, 0.5),
            ("c", F, 4, 0.0),
            ("d", I, 3, 1.0),
        ];
        let report = build_study_report(&inputs(row(1, &scores), Ok(row(2, &scores)))).unwrap();
        let forward = &report.cells[0];
        assert_eq!((forward.direction, forward.step_length), (F, None));
        assert_eq!(forward.delta, Some(0.0));
        assert_eq!(forward.p, Some(1.0));
        assert_eq!((forward.n_baseline, forward.n_variant), (3, 3));
        assert_eq!(forward.sign_test.p, 1.0);
        assert!(forward.paired_t.p.is_none(), "every difference is 0");
        // Forward 3 and 4, then inverse (one item: Welch needs two).
        let lengths: Vec<_> = report
            .cells
            .iter()
            .map(|c| (c.direction, c.step_length))
            .collect();
        assert_eq!(
            lengths,
            [
                (F, None),
                (F, Some(3)),
                (F, Some(4)),
                (I, None),
                (I, Some(3))
            ]
        );
        assert!(
            report.cells[3]
                .undefined
                .as_ref()
                .unwrap()
                .contains("at least 2")
        );
        assert_eq!(report.stamp.variants[0].submission, Some(2));
    }

    #[test]
    fn a_planted_drop_is_measured_on_the_aligned_items() {
        let baseline = row(
            1,
            &[
                ("a", F, 3, 1.0),
                ("b", F, 3, 0.8),
                ("c", F, 3, 0.6),
                ("d", F, 3, 0.9),
            ],
        );
        let variant = row(
            2,
            &[
                ("a", F, 3, 0.5),
                ("b", F, 3, 0.5),
                ("c", F, 3, 0.2),
                ("d", F, 3, 0.4),
            ],
        );
        let report = build_study_report(&inputs(baseline, Ok(variant))).unwrap();
        let c = &report.cells[0];
        // Differences −0.5, −0.3, −0.4, −0.5: Δ = −0.425 for both tests.
        assert!((c.delta.unwrap() + 0.425).abs() < 1e-12);
        assert!((c.paired_t.mean_difference.unwrap() + 0.425).abs() < 1e-12);
        assert_eq!((c.sign_test.negative, c.sign_test.positive), (4, 0));
        assert!((c.sign_test.p - 0.125).abs() < 1e-12);
        assert!(
            c.paired_t.p.unwrap() < c.p.unwrap(),
            "pairing removes item spread"
        );
    }

    #[test]
    fn a_variant_without_a_submission_says_so() {
        let report = build_study_report(&inputs(
            row(1, &[("a", F, 3, 1.0)]),
            Err("no published submission".into()),
        ))
        .unwrap();
        assert_eq!(
            report.variants[0].missing.as_deref(),
            Some("no published submission")
        );
        assert!(report.cells.iter().all(|c| c.delta.is_none()));
        assert_eq!(
            report.cells[0].undefined.as_deref(),
            Some("no published submission")
        );
    }
}
