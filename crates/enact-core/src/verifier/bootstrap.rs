//! Percentile bootstrap confidence intervals for a mean over items (pure, seeded).

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

/// The percentile bootstrap interval of the mean of `values`: `resamples` samples of the same
/// size drawn with replacement, and the (1-level)/2 and (1+level)/2 quantiles of their means
/// (linear interpolation between order statistics). `None` for no values or no resamples.
pub fn bootstrap_mean_ci(
    values: &[f64],
    resamples: usize,
    seed: u64,
    level: f64,
) -> Option<ConfidenceInterval> {
    if values.is_empty() || resamples == 0 {
        return None;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = values.len();
    let mut means: Vec<f64> = (0..resamples)
        .map(|_| {
            let mut sum = 0.0;
            for _ in 0..n {
                sum += values[rng.random_range(0..n)];
            }
            sum / n as f64
        })
        .collect();
    means.sort_by(f64::total_cmp);
    let alpha = (1.0 - level) / 2.0;
    Some(ConfidenceInterval {
        low: quantile(&means, alpha),
        high: quantile(&means, 1.0 - alpha),
    })
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
    fn quantile_interpolates_like_numpy() {
        let sorted = [0.0, 1.0, 2.0, 3.0];
        assert_eq!(quantile(&sorted, 0.5), 1.5);
        assert!((quantile(&sorted, 0.025) - 0.075).abs() < 1e-12);
        assert_eq!(quantile(&sorted, 1.0), 3.0);
    }
}
