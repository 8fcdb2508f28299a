//! Percentile bootstrap confidence intervals for a mean over items (pure, seeded).
//!
//! ENACT's items come from a few dozen activities (its `task_name`); items of one activity
//! share scenes and fail together, so resampling items one by one, as if each were
//! independent, understates the uncertainty. The hub's intervals therefore resample whole
//! activities with their items by default ([`Resampling::Activities`], a cluster bootstrap);
//! the item bootstrap stays as an option.

use std::collections::BTreeMap;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Resamples the leaderboard uses.
pub const BOOTSTRAP_RESAMPLES: usize = 1000;
/// Seed the leaderboard uses, so an interval is the same every time it is computed.
/// ("ENACT" in ASCII.)
pub const BOOTSTRAP_SEED: u64 = 0x0045_4e41_4354;
/// Two-sided confidence level.
pub const BOOTSTRAP_LEVEL: f64 = 0.95;

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ConfidenceInterval {
    pub low: f64,
    pub high: f64,
}

/// What the bootstrap resamples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema, Hash)]
#[serde(rename_all = "lowercase")]
pub enum Resampling {
    /// Whole activities with all their items (the default): items of one activity are not
    /// independent.
    #[default]
    Activities,
    /// Items one by one, as if every item were independent of every other.
    Items,
}

impl Resampling {
    pub const ALL: [Resampling; 2] = [Resampling::Activities, Resampling::Items];

    pub fn as_str(self) -> &'static str {
        match self {
            Resampling::Activities => "activities",
            Resampling::Items => "items",
        }
    }

    pub fn parse(text: &str) -> Option<Resampling> {
        Resampling::ALL.into_iter().find(|r| r.as_str() == text)
    }

    /// What intervals stored before the hub clustered them resampled.
    pub fn before_clustering() -> Resampling {
        Resampling::Items
    }
}

/// The sorted means of `resamples` bootstrap samples of `values` (`(cluster, value)` pairs).
/// [`Resampling::Items`] draws as many values as there are, with replacement (the same draws
/// as the hub's item bootstrap made before it clustered intervals, for the same seed); [`Resampling::Activities`] draws as many
/// clusters as there are, with replacement, and takes the mean over all their values (a
/// cluster of many items weighs more than one of few).
pub(crate) fn resampled_means(
    values: &[(u32, f64)],
    resampling: Resampling,
    resamples: usize,
    seed: u64,
) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut means: Vec<f64> = match resampling {
        Resampling::Items => {
            let n = values.len();
            (0..resamples)
                .map(|_| {
                    let mut sum = 0.0;
                    for _ in 0..n {
                        sum += values[rng.random_range(0..n)].1;
                    }
                    sum / n as f64
                })
                .collect()
        }
        Resampling::Activities => {
            let mut totals: BTreeMap<u32, (f64, usize)> = BTreeMap::new();
            for &(cluster, value) in values {
                let t = totals.entry(cluster).or_default();
                t.0 += value;
                t.1 += 1;
            }
            let totals: Vec<(f64, usize)> = totals.into_values().collect();
            let k = totals.len();
            (0..resamples)
                .map(|_| {
                    let (mut sum, mut count) = (0.0, 0usize);
                    for _ in 0..k {
                        let (s, c) = totals[rng.random_range(0..k)];
                        sum += s;
                        count += c;
                    }
                    sum / count as f64
                })
                .collect()
        }
    };
    means.sort_by(f64::total_cmp);
    means
}

/// The two-sided percentile interval at `level` of sorted, non-empty `sorted`.
pub(crate) fn percentile_interval(sorted: &[f64], level: f64) -> ConfidenceInterval {
    let tail = (1.0 - level) / 2.0;
    ConfidenceInterval {
        low: quantile(sorted, tail),
        high: quantile(sorted, 1.0 - tail),
    }
}

/// The percentile bootstrap interval of the mean of `values` (`(cluster, value)` pairs: the
/// cluster is the item's activity), resampling what `resampling` says. `None` for no values
/// or no resamples.
pub fn clustered_mean_ci(
    values: &[(u32, f64)],
    resampling: Resampling,
    resamples: usize,
    seed: u64,
    level: f64,
) -> Option<ConfidenceInterval> {
    if values.is_empty() || resamples == 0 {
        return None;
    }
    let means = resampled_means(values, resampling, resamples, seed);
    Some(percentile_interval(&means, level))
}

/// [`clustered_mean_ci`] with the leaderboard's resamples, seed and level.
pub fn leaderboard_ci(values: &[(u32, f64)], resampling: Resampling) -> Option<ConfidenceInterval> {
    clustered_mean_ci(
        values,
        resampling,
        BOOTSTRAP_RESAMPLES,
        BOOTSTRAP_SEED,
        BOOTSTRAP_LEVEL,
    )
}

/// Each of `names` as a small number, the same for equal names: the clusters of
/// [`clustered_mean_ci`].
pub fn cluster_ids<'a>(names: impl IntoIterator<Item = &'a str>) -> Vec<u32> {
    let mut ids: std::collections::HashMap<&'a str, u32> = std::collections::HashMap::new();
    names
        .into_iter()
        .map(|name| {
            let next = ids.len() as u32;
            *ids.entry(name).or_insert(next)
        })
        .collect()
}

/// The percentile bootstrap interval of the mean of `values`: `resamples` samples of the same
/// size drawn with replacement, and the (1-level)/2 and (1+level)/2 quantiles of their means
/// (linear interpolation between order statistics). `None` for no values or no resamples.
pub fn bootstrap_mean_ci(
    values: &[f64],
    resamples: usize,
    seed: u64,
    level: f64,
) -> Option<ConfidenceInterval> {
    let unclustered: Vec<(u32, f64)> = values.iter().map(|v| (0, *v)).collect();
    clustered_mean_ci(&unclustered, Resampling::Items, resamples, seed, level)
}

/// Quantile `q` of sorted, non-empty `sorted` (numpy's default "linear" method).
pub(crate) fn quantile(sorted: &[f64], q: f64) -> f64 {
    let position = q.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let below = position.floor() as usize;
    let above = position.ceil() as usize;
    let fraction = position - below as f64;
    sorted[below] + (sorted[above] - sorted[below]) * fraction
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interval_brackets_the_mean_and_is_reproducible() {
        let values: Vec<f64> = (0..200).map(|i| f64::from(u8::from(i % 3 == 0))).collect();
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        let ci = bootstrap_mean_ci(&values, 1000, 7, 0.95).expect("values");
        assert!(ci.low < mean && mean < ci.high, "{ci:?} around {mean}");
        // Standard error of a proportion p=1/3 over 200 items is 0.033: the 95% interval is
        // about ±0.065 wide.
        assert!(ci.high - ci.low > 0.08 && ci.high - ci.low < 0.18, "{ci:?}");
        assert_eq!(bootstrap_mean_ci(&values, 1000, 7, 0.95), Some(ci));
        assert_ne!(bootstrap_mean_ci(&values, 1000, 8, 0.95), Some(ci));
    }

    #[test]
    fn constant_values_give_a_point_and_no_values_give_nothing() {
        let ci = bootstrap_mean_ci(&[1.0; 10], 100, 1, 0.95).expect("values");
        assert_eq!((ci.low, ci.high), (1.0, 1.0));
        assert_eq!(bootstrap_mean_ci(&[], 100, 1, 0.95), None);
    }

    #[test]
    fn a_cluster_resample_takes_the_mean_over_every_item_of_the_drawn_activities() {
        // By hand: activity 0 has one item worth 1, activity 1 three worth 0. A resample
        // draws two activities: {0,0} with probability 1/4 (mean 2/2 = 1), {0,1} 1/2 (mean
        // 1/4, not the mean of the activities' means, 1/2) and {1,1} 1/4 (mean 0).
        let values = [(0, 1.0), (1, 0.0), (1, 0.0), (1, 0.0)];
        let means = resampled_means(&values, Resampling::Activities, 20_000, 3);
        let share = |m: f64| {
            means.iter().filter(|x| (**x - m).abs() < 1e-12).count() as f64 / means.len() as f64
        };
        assert!((share(1.0) - 0.25).abs() < 0.015, "{}", share(1.0));
        assert!((share(0.25) - 0.5).abs() < 0.015, "{}", share(0.25));
        assert!((share(0.0) - 0.25).abs() < 0.015, "{}", share(0.0));
        assert_eq!(share(1.0) + share(0.25) + share(0.0), 1.0);
        // The 2.5 % and 97.5 % quantiles fall in the outer masses.
        let ci = clustered_mean_ci(&values, Resampling::Activities, 20_000, 3, 0.95).expect("ci");
        assert_eq!((ci.low, ci.high), (0.0, 1.0));
        // Resampling items draws four items: the mean is k/4 with k ~ Binomial(4, 1/4), so
        // P(0) = 81/256 and the 2.5 % quantile is 0; P(k ≥ 3) = 13/256 > 2.5 %, so the
        // 97.5 % quantile is 3/4.
        let ci = clustered_mean_ci(&values, Resampling::Items, 20_000, 3, 0.95).expect("ci");
        assert_eq!((ci.low, ci.high), (0.0, 0.75));
    }

    /// The item bootstrap as the hub computed it before it clustered intervals.
    fn item_bootstrap_before_clustering(values: &[f64], resamples: usize, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let n = values.len();
        let mut means: Vec<f64> = (0..resamples)
            .map(|_| (0..n).map(|_| values[rng.random_range(0..n)]).sum::<f64>() / n as f64)
            .collect();
        means.sort_by(f64::total_cmp);
        means
    }

    #[test]
    fn resampling_items_draws_as_the_plain_item_bootstrap_does() {
        let plain: Vec<f64> = (0..50).map(|i| f64::from(u8::from(i % 4 == 0))).collect();
        let before = item_bootstrap_before_clustering(&plain, 500, 9);
        assert_eq!(
            bootstrap_mean_ci(&plain, 500, 9, 0.95),
            Some(percentile_interval(&before, 0.95))
        );
        let clustered: Vec<(u32, f64)> = plain
            .iter()
            .enumerate()
            .map(|(i, v)| ((i % 7) as u32, *v))
            .collect();
        assert_eq!(
            clustered_mean_ci(&clustered, Resampling::Items, 500, 9, 0.95),
            bootstrap_mean_ci(&plain, 500, 9, 0.95)
        );
        assert_ne!(
            clustered_mean_ci(&clustered, Resampling::Activities, 500, 9, 0.95),
            bootstrap_mean_ci(&plain, 500, 9, 0.95)
        );
        assert_eq!(
            clustered_mean_ci(&[], Resampling::Activities, 500, 9, 0.95),
            None
        );
        assert_eq!(cluster_ids(["b", "a", "b", "c"]), vec![0, 1, 0, 2]);
    }

    #[test]
    fn with_correlated_activities_the_clustered_interval_covers_the_true_rate_and_the_item_one_does_not()
     {
        // Seeded simulation: 24 activities of 12 items each. Each activity has its own success
        // rate (0.5 ± 0.35, uniform), shared by its items; an item succeeds with its
        // activity's rate. The true task accuracy is 0.5. The clustered interval should cover
        // it about 95 % of the time; the item interval treats 288 correlated items as
        // independent and is too narrow.
        let mut rng = ChaCha8Rng::seed_from_u64(38);
        let trials = 200;
        let (mut clustered, mut itemwise) = (0, 0);
        for trial in 0..trials {
            let mut values = Vec::new();
            for activity in 0..24u32 {
                let rate = 0.15 + 0.7 * rng.random::<f64>();
                for _ in 0..12 {
                    values.push((activity, f64::from(u8::from(rng.random::<f64>() < rate))));
                }
            }
            let covers = |resampling| {
                let ci = clustered_mean_ci(&values, resampling, 400, trial, 0.95).expect("ci");
                usize::from(ci.low <= 0.5 && 0.5 <= ci.high)
            };
            clustered += covers(Resampling::Activities);
            itemwise += covers(Resampling::Items);
        }
        let rate = |covered: usize| covered as f64 / trials as f64;
        // A percentile bootstrap over 24 clusters covers a little under its level.
        assert!(
            (0.88..=0.99).contains(&rate(clustered)),
            "clustered coverage {}",
            rate(clustered)
        );
        assert!(
            rate(itemwise) < rate(clustered) - 0.1,
            "item coverage {} against clustered {}",
            rate(itemwise),
            rate(clustered)
        );
    }

    #[test]
    fn quantile_interpolates_like_numpy() {
        let sorted = [0.0, 1.0, 2.0, 3.0];
        assert_eq!(quantile(&sorted, 0.5), 1.5);
        assert!((quantile(&sorted, 0.025) - 0.075).abs() < 1e-12);
        assert_eq!(quantile(&sorted, 1.0), 3.0);
    }
}
