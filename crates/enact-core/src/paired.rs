//! Two leaderboard rows compared on the items both were scored on: each side's Task and
//! Pairwise Accuracy per direction and step length, the difference with a paired bootstrap
//! interval, and McNemar's exact test on task success.
//!
//! The two rows answered the same items, so the honest question is paired: on how many items
//! does one succeed where the other fails? Two leaderboard intervals that overlap say nothing
//! about that. The bootstrap resamples items *together* (both sides' results of an item stay
//! paired) and, by default, resamples whole activities (ENACT's `task_name`) with their items:
//! items of one activity share scenes and fail together, so resampling items one by one
//! understates the uncertainty.
//!
//! Pure and synchronous: the hub reads both rows' stored verdicts and calls [`compare`].

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::dataset::{Direction, StepLength};
pub use crate::verifier::bootstrap::Resampling;
use crate::verifier::bootstrap::{cluster_ids, percentile_interval, resampled_means};
use crate::verifier::{BOOTSTRAP_LEVEL, BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED};

/// What one side made of one item: task success, and its pairwise accuracy (`None` where the
/// verifier gives none, as for a wrong answer to an exact-only item).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Side {
    pub task_correct: bool,
    pub pairwise_accuracy: Option<f64>,
}

/// One item both rows were scored on.
#[derive(Debug, Clone, PartialEq)]
pub struct PairedItem {
    pub direction: Direction,
    pub step_length: StepLength,
    /// The activity (ENACT's `task_name`): the bootstrap's cluster.
    pub activity: String,
    pub a: Side,
    pub b: Side,
}

/// How a comparison's intervals are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PairedConfig {
    pub resampling: Resampling,
    pub resamples: usize,
    pub seed: u64,
    /// Two-sided confidence level.
    pub level: f64,
}

impl Default for PairedConfig {
    /// The leaderboard's resamples, seed and level, resampling activities.
    fn default() -> Self {
        PairedConfig {
            resampling: Resampling::Activities,
            resamples: BOOTSTRAP_RESAMPLES,
            seed: BOOTSTRAP_SEED,
            level: BOOTSTRAP_LEVEL,
        }
    }
}

/// A difference `a − b` with its bootstrap interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Difference {
    pub estimate: f64,
    pub low: f64,
    pub high: f64,
}

/// The comparison over one group of items (a direction and step length, a direction, or all).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PairedCell {
    /// `None` for every direction.
    pub direction: Option<Direction>,
    /// `None` for every step length.
    pub step_length: Option<StepLength>,
    /// Items in the group.
    pub n: usize,
    /// Activities the group's items come from (the clusters resampled).
    pub activities: usize,
    pub a_task_accuracy: f64,
    pub b_task_accuracy: f64,
    /// Mean over the items where that side has a pairwise accuracy; `None` if it has none.
    pub a_pairwise_accuracy: Option<f64>,
    pub b_pairwise_accuracy: Option<f64>,
    /// Items A gets right and B does not.
    pub a_only: usize,
    /// Items B gets right and A does not.
    pub b_only: usize,
    pub both: usize,
    pub neither: usize,
    /// McNemar's exact (binomial) two-sided p-value on the discordant items.
    pub mcnemar_p: f64,
    /// Task accuracy of A minus B.
    pub difference: Difference,
    /// Pairwise accuracy of A minus B over the items where both have one; `None` if none.
    pub pairwise_difference: Option<Difference>,
}

/// Two rows compared: every item, then per direction, then per direction and step length.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PairedComparison {
    pub config: PairedConfig,
    pub overall: PairedCell,
    /// Per direction (`step_length: None`) and per direction and step length, in that order
    /// within each direction; groups without items are left out.
    pub cells: Vec<PairedCell>,
}

/// Compares the two sides of `items`. `None` when there is no item.
pub fn compare(items: &[PairedItem], config: &PairedConfig) -> Option<PairedComparison> {
    let cluster_of = cluster_ids(items.iter().map(|i| i.activity.as_str()));
    let group = |keep: &dyn Fn(&PairedItem) -> bool, salt: u64| {
        let chosen: Vec<usize> = (0..items.len()).filter(|&i| keep(&items[i])).collect();
        cell(items, &cluster_of, &chosen, config, salt)
    };
    let overall = group(&|_| true, 0)?;
    let mut cells = Vec::new();
    for (d, direction) in Direction::ALL.into_iter().enumerate() {
        let salt = 1 + d as u64 * 16;
        let Some(mut total) = group(&|i| i.direction == direction, salt) else {
            continue;
        };
        total.direction = Some(direction);
        cells.push(total);
        for step_length in StepLength::all() {
            let salt = salt + u64::from(step_length.get());
            let keep = |i: &PairedItem| i.direction == direction && i.step_length == step_length;
            if let Some(mut c) = group(&keep, salt) {
                c.direction = Some(direction);
                c.step_length = Some(step_length);
                cells.push(c);
            }
        }
    }
    Some(PairedComparison {
        config: *config,
        overall,
        cells,
    })
}

/// The cell of the items at `chosen` (indices into `items`); its bootstrap seeded from the
/// configured seed and `salt`, so each cell's interval is the same every time.
fn cell(
    items: &[PairedItem],
    cluster_of: &[u32],
    chosen: &[usize],
    config: &PairedConfig,
    salt: u64,
) -> Option<PairedCell> {
    if chosen.is_empty() {
        return None;
    }
    let n = chosen.len();
    let (mut a_only, mut b_only, mut both, mut neither) = (0, 0, 0, 0);
    for &i in chosen {
        match (items[i].a.task_correct, items[i].b.task_correct) {
            (true, false) => a_only += 1,
            (false, true) => b_only += 1,
            (true, true) => both += 1,
            (false, false) => neither += 1,
        }
    }
    let mean = |values: &mut dyn Iterator<Item = f64>| {
        let (sum, count) = values.fold((0.0, 0usize), |(s, c), v| (s + v, c + 1));
        (count > 0).then(|| sum / count as f64)
    };
    let pa_a = mean(&mut chosen.iter().filter_map(|&i| items[i].a.pairwise_accuracy));
    let pa_b = mean(&mut chosen.iter().filter_map(|&i| items[i].b.pairwise_accuracy));

    let task: Vec<(u32, f64)> = chosen
        .iter()
        .map(|&i| {
            let d = f64::from(u8::from(items[i].a.task_correct))
                - f64::from(u8::from(items[i].b.task_correct));
            (cluster_of[i], d)
        })
        .collect();
    let pairwise: Vec<(u32, f64)> = chosen
        .iter()
        .filter_map(
            |&i| match (items[i].a.pairwise_accuracy, items[i].b.pairwise_accuracy) {
                (Some(a), Some(b)) => Some((cluster_of[i], a - b)),
                _ => None,
            },
        )
        .collect();
    let seed = config.seed ^ salt.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    let mut activities: Vec<u32> = task.iter().map(|(c, _)| *c).collect();
    activities.sort_unstable();
    activities.dedup();
    Some(PairedCell {
        direction: None,
        step_length: None,
        n,
        activities: activities.len(),
        a_task_accuracy: (a_only + both) as f64 / n as f64,
        b_task_accuracy: (b_only + both) as f64 / n as f64,
        a_pairwise_accuracy: pa_a,
        b_pairwise_accuracy: pa_b,
        a_only,
        b_only,
        both,
        neither,
        mcnemar_p: mcnemar_exact(a_only, b_only),
        difference: paired_difference(&task, config, seed)?,
        pairwise_difference: paired_difference(&pairwise, config, seed ^ 1),
    })
}

/// The mean of the per-item differences `(cluster, difference)` with its percentile bootstrap
/// interval, resampling what `config` says. `None` for no item.
pub fn paired_difference(
    differences: &[(u32, f64)],
    config: &PairedConfig,
    seed: u64,
) -> Option<Difference> {
    if differences.is_empty() {
        return None;
    }
    let estimate = differences.iter().map(|(_, d)| d).sum::<f64>() / differences.len() as f64;
    if config.resamples == 0 {
        return Some(Difference {
            estimate,
            low: estimate,
            high: estimate,
        });
    }
    let means = resampled_means(differences, config.resampling, config.resamples, seed);
    let interval = percentile_interval(&means, config.level);
    Some(Difference {
        estimate,
        low: interval.low,
        high: interval.high,
    })
}

/// McNemar's exact test: the two-sided binomial p-value of `a_only` successes in
/// `a_only + b_only` discordant items at probability one half (twice the smaller tail, at most
/// 1). With no discordant item there is no evidence either way: 1.
pub fn mcnemar_exact(a_only: usize, b_only: usize) -> f64 {
    let n = a_only + b_only;
    if n == 0 {
        return 1.0;
    }
    let k = a_only.min(b_only);
    if n <= 1000 {
        // Binomial coefficients and 0.5^n as plain floats: exact for small counts.
        let (mut choose, mut tail) = (1.0f64, 1.0f64);
        for i in 1..=k {
            choose = choose * (n - i + 1) as f64 / i as f64;
            tail += choose;
        }
        return (2.0 * tail * 0.5f64.powi(n as i32)).min(1.0);
    }
    // ln C(n, i) built up term by term; the tail summed in log space, since 0.5^n underflows
    // for a full split's thousands of discordant items.
    let ln_half_n = n as f64 * 0.5f64.ln();
    let mut ln_choose = 0.0;
    let mut terms = Vec::with_capacity(k + 1);
    for i in 0..=k {
        if i > 0 {
            ln_choose += ((n - i + 1) as f64).ln() - (i as f64).ln();
        }
        terms.push(ln_choose + ln_half_n);
    }
    let top = terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let ln_tail = top + terms.iter().map(|t| (t - top).exp()).sum::<f64>().ln();
    (2.0 * ln_tail.exp()).min(1.0)
}

#[cfg(test)]
mod tests;
