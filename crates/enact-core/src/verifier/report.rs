//! Aggregation of verdicts into ENACT's performance report (overall / per direction / per step
//! length) and its `meta_performance` JSON file.

use schemars::JsonSchema;
use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::verifier::answer::Direction;
use crate::verifier::pyint::PyInt;
use crate::verifier::pyjson::PyValue;

/// One scored item as the report sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScoredEntry {
    /// The report group; `None` (a type naming neither direction) counts only in overall.
    pub group: Option<Direction>,
    /// L = number of labels in the ground truth + 1.
    pub states: usize,
    pub task_accuracy: bool,
    /// `None` when unavailable (exact-only scoring without scene graphs).
    pub pairwise_accuracy: Option<f64>,
}

/// Counts and means over one set of items.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct StepPerformance {
    pub count: usize,
    /// Fraction in [0, 1].
    pub task_accuracy: f64,
    /// Mean over the items that have a pairwise accuracy; `None` if none has.
    pub pairwise_accuracy: Option<f64>,
    /// Number of items the pairwise mean is over.
    pub pairwise_count: usize,
}

/// A report group: its totals plus a breakdown by step length L (ascending).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct GroupPerformance {
    #[serde(flatten)]
    pub totals: StepPerformance,
    pub per_step: BTreeMap<usize, StepPerformance>,
}

/// ENACT's `report_overall_score()`: groups with no items are absent.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PerformanceReport {
    pub overall: Option<GroupPerformance>,
    pub forward_world_modeling: Option<GroupPerformance>,
    pub inverse_world_modeling: Option<GroupPerformance>,
}

#[derive(Default)]
struct Bucket {
    count: usize,
    correct: usize,
    /// In item order: numpy's summation order depends on it.
    pairwise: Vec<f64>,
}

impl Bucket {
    fn push(&mut self, entry: &ScoredEntry) {
        self.count += 1;
        self.correct += usize::from(entry.task_accuracy);
        if let Some(value) = entry.pairwise_accuracy {
            self.pairwise.push(value);
        }
    }

    fn performance(&self) -> StepPerformance {
        StepPerformance {
            count: self.count,
            // Python: sum(bools) / len, a correctly rounded division as here.
            task_accuracy: self.correct as f64 / self.count as f64,
            pairwise_accuracy: (!self.pairwise.is_empty()).then(|| numpy_mean(&self.pairwise)),
            pairwise_count: self.pairwise.len(),
        }
    }
}

#[derive(Default)]
struct GroupBuckets {
    totals: Bucket,
    per_step: BTreeMap<usize, Bucket>,
}

impl GroupBuckets {
    fn push(&mut self, entry: &ScoredEntry) {
        self.totals.push(entry);
        self.per_step.entry(entry.states).or_default().push(entry);
    }

    fn performance(&self) -> Option<GroupPerformance> {
        (self.totals.count > 0).then(|| GroupPerformance {
            totals: self.totals.performance(),
            per_step: self
                .per_step
                .iter()
                .map(|(l, b)| (*l, b.performance()))
                .collect(),
        })
    }
}

impl PerformanceReport {
    /// Aggregates `entries` in the given order (the order fixes numpy's float summation).
    pub fn from_entries<'a>(
        entries: impl IntoIterator<Item = &'a ScoredEntry>,
    ) -> PerformanceReport {
        let (mut overall, mut forward, mut inverse) = (
            GroupBuckets::default(),
            GroupBuckets::default(),
            GroupBuckets::default(),
        );
        for entry in entries {
            overall.push(entry);
            match entry.group {
                Some(Direction::Forward) => forward.push(entry),
                Some(Direction::Inverse) => inverse.push(entry),
                None => {}
            }
        }
        PerformanceReport {
            overall: overall.performance(),
            forward_world_modeling: forward.performance(),
            inverse_world_modeling: inverse.performance(),
        }
    }

    /// ENACT's `overall_performance` object (key order and `"{L}_steps"` keys as ENACT has them).
    pub fn to_enact_value(&self) -> PyValue {
        let step = |p: &StepPerformance| {
            vec![
                (
                    "count".to_owned(),
                    PyValue::Int(PyInt::Small(p.count as i64)),
                ),
                ("task_accuracy".to_owned(), PyValue::Float(p.task_accuracy)),
                (
                    "pairwise_accuracy".to_owned(),
                    p.pairwise_accuracy.map_or(PyValue::None, PyValue::Float),
                ),
            ]
        };
        let group = |g: &GroupPerformance| {
            let mut entries = step(&g.totals);
            let per_step = g
                .per_step
                .iter()
                .map(|(l, p)| (format!("{l}_steps"), PyValue::Dict(step(p))))
                .collect();
            entries.push(("per_step".to_owned(), PyValue::Dict(per_step)));
            PyValue::Dict(entries)
        };
        let groups = [
            ("overall", &self.overall),
            ("forward_world_modeling", &self.forward_world_modeling),
            ("inverse_world_modeling", &self.inverse_world_modeling),
        ];
        PyValue::Dict(
            groups
                .into_iter()
                .filter_map(|(name, g)| g.as_ref().map(|g| (name.to_owned(), group(g))))
                .collect(),
        )
    }
}

/// The bytes of ENACT's `meta_performance/enact_ordering_{model}.json`
/// (`json.dump(..., indent=2)`, no trailing newline).
pub fn enact_meta_performance_json(model_name: &str, report: &PerformanceReport) -> String {
    PyValue::Dict(vec![
        ("model_name".to_owned(), PyValue::Str(model_name.to_owned())),
        ("overall_performance".to_owned(), report.to_enact_value()),
    ])
    .to_json_indented(2)
}

/// numpy's block size for unrolled pairwise summation (`PW_BLOCKSIZE`).
const NUMPY_PAIRWISE_BLOCK: usize = 128;
/// numpy's default ufunc buffer size: reductions are summed buffer by buffer.
const NUMPY_BUFFER_SIZE: usize = 8192;

/// ENACT quirk: `np.mean` of the pairwise accuracies, with numpy's pairwise summation (eight
/// accumulators below 128 items, halving above), so that the means come out to the same last bit.
pub fn numpy_mean(values: &[f64]) -> f64 {
    let mut total = 0.0;
    for chunk in values.chunks(NUMPY_BUFFER_SIZE) {
        total += numpy_pairwise_sum(chunk);
    }
    total / values.len() as f64
}

fn numpy_pairwise_sum(a: &[f64]) -> f64 {
    let n = a.len();
    if n < 8 {
        let mut sum = 0.0;
        for &x in a {
            sum += x;
        }
        sum
    } else if n <= NUMPY_PAIRWISE_BLOCK {
        let mut r = [a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]];
        let mut i = 8;
        while i < n - n % 8 {
            for (j, acc) in r.iter_mut().enumerate() {
                *acc += a[i + j];
            }
            i += 8;
        }
        let mut sum = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for &x in &a[i..] {
            sum += x;
        }
        sum
    } else {
        let mut half = n / 2;
        half -= half % 8;
        numpy_pairwise_sum(&a[..half]) + numpy_pairwise_sum(&a[half..])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(group: Option<Direction>, states: usize, ta: bool, pa: Option<f64>) -> ScoredEntry {
        ScoredEntry {
            group,
            states,
            task_accuracy: ta,
            pairwise_accuracy: pa,
        }
    }

    #[test]
    fn numpy_summation_order_is_reproduced() {
        // Twelve values (an ENACT per-step bucket) whose naive left-to-right mean differs from
        // numpy's in the last bit: numpy printed 0.30555555555555564.
        let third = 1.0 / 3.0;
        let values = [
            0.0,
            0.0,
            third,
            0.0,
            2.0 / 3.0,
            2.0 / 3.0,
            third,
            third,
            third,
            third,
            third,
            third,
        ];
        let naive: f64 = values.iter().sum::<f64>() / values.len() as f64;
        let mean = numpy_mean(&values);
        assert_eq!(mean, 0.30555555555555564);
        assert_ne!(naive, mean);
        assert_eq!(numpy_mean(&[1.0, 0.5]), 0.75);
        // Eight values already take numpy's eight accumulators, not the plain loop: 1e16 keeps
        // the ones its neighbours add in pairs (Python: ((r0+r1)+(r2+r3))+((r4+r5)+(r6+r7)) is
        // 1.0000000000000006e16 where the running sum stays 1e16).
        let eight = [1e16, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        assert_eq!(numpy_mean(&eight), 1.0000000000000006e16 / 8.0);
        // Long inputs split in halves rounded down to a multiple of eight.
        let long: Vec<f64> = (0..1000).map(|k| (k % 7) as f64 / 7.0).collect();
        assert!((numpy_mean(&long) - long.iter().sum::<f64>() / 1000.0).abs() < 1e-12);
    }

    #[test]
    fn numpy_splits_long_inputs_at_half_rounded_down_to_eight() {
        // 165 values: numpy splits 80 + 85 (82 rounded down); np.mean printed 0.3333333333333333,
        // a split at 84 would give 0.33333333333333337.
        let values: Vec<f64> = (0..165).map(|k| (k % 3) as f64 / 3.0).collect();
        assert_eq!(numpy_mean(&values), 0.3333333333333333);
        // 132 values: 64 + 68 (66 rounded down to eight). numpy 2.4.6's np.mean of this list
        // printed 2.5129870129870135; any other split point sums them to another last bit.
        let values: Vec<f64> = (0..132)
            .map(|i| ((i * 7919) % 13) as f64 / 7.0 + ((i * 104_729) % 11) as f64 / 3.0)
            .collect();
        assert_eq!(numpy_mean(&values), 2.5129870129870135);
    }

    #[test]
    fn groups_steps_and_neither_direction() {
        let entries = [
            entry(Some(Direction::Forward), 3, true, Some(1.0)),
            entry(Some(Direction::Forward), 4, false, Some(0.5)),
            entry(Some(Direction::Inverse), 3, false, Some(0.0)),
            entry(None, 10, true, Some(1.0)),
        ];
        let report = PerformanceReport::from_entries(&entries);
        let overall = report.overall.as_ref().expect("overall");
        assert_eq!(overall.totals.count, 4);
        assert_eq!(overall.totals.task_accuracy, 0.5);
        assert_eq!(overall.totals.pairwise_accuracy, Some(0.625));
        assert_eq!(
            overall.per_step.keys().copied().collect::<Vec<_>>(),
            vec![3, 4, 10]
        );
        let forward = report.forward_world_modeling.as_ref().expect("forward");
        assert_eq!(forward.totals.count, 2);
        assert_eq!(
            report
                .inverse_world_modeling
                .as_ref()
                .map(|g| g.totals.count),
            Some(1)
        );
        assert_eq!(
            PerformanceReport::from_entries(&[]),
            PerformanceReport::default()
        );
    }

    #[test]
    fn meta_json_has_enacts_layout() {
        let entries = [
            entry(Some(Direction::Inverse), 3, true, Some(1.0)),
            entry(Some(Direction::Inverse), 3, false, Some(0.0)),
        ];
        let json =
            enact_meta_performance_json("mymodel", &PerformanceReport::from_entries(&entries));
        let expected = r#"{
  "model_name": "mymodel",
  "overall_performance": {
    "overall": {
      "count": 2,
      "task_accuracy": 0.5,
      "pairwise_accuracy": 0.5,
      "per_step": {
        "3_steps": {
          "count": 2,
          "task_accuracy": 0.5,
          "pairwise_accuracy": 0.5
        }
      }
    },
    "inverse_world_modeling": {
      "count": 2,
      "task_accuracy": 0.5,
      "pairwise_accuracy": 0.5,
      "per_step": {
        "3_steps": {
          "count": 2,
          "task_accuracy": 0.5,
          "pairwise_accuracy": 0.5
        }
      }
    }
  }
}"#;
        assert_eq!(json, expected);
        assert_eq!(
            enact_meta_performance_json("none", &PerformanceReport::default()),
            "{\n  \"model_name\": \"none\",\n  \"overall_performance\": {}\n}"
        );
    }

    #[test]
    fn unavailable_pairwise_is_left_out_of_the_mean() {
        let entries = [
            entry(Some(Direction::Forward), 3, true, Some(1.0)),
            entry(Some(Direction::Forward), 3, false, None),
        ];
        let report = PerformanceReport::from_entries(&entries);
        let totals = &report.overall.as_ref().expect("overall").totals;
        assert_eq!(totals.task_accuracy, 0.5);
        assert_eq!(totals.pairwise_accuracy, Some(1.0));
        assert_eq!(totals.pairwise_count, 1);
    }
}
