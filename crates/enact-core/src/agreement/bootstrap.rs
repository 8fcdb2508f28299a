//! Percentile bootstrap confidence intervals for alpha that resample whole items, so every unit
//! of an item (all positions of one ordering, say) is drawn together.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::agreement::alpha::{AlphaResult, ItemOutOfRange, MeasurementLevel, PreparedAlpha};
use crate::agreement::reliability::{ReliabilityData, UnitItems, UnitItemsError};

pub const DEFAULT_REPLICATES: usize = 1000;
pub const DEFAULT_CONFIDENCE_LEVEL: f64 = 0.95;
pub const DEFAULT_BOOTSTRAP_SEED: u64 = 0;

/// How replicate `b` draws its items. Each replicate has its own ChaCha stream, so the result
/// depends on the seed only, never on how rayon splits the work across threads.
pub const BOOTSTRAP_RNG: &str = "rand_chacha::ChaCha8Rng::seed_from_u64(seed) with set_stream(replicate index); \
     items drawn with Rng::random_range(0..items)";

/// How many replicates to draw, the interval's coverage and the RNG seed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BootstrapConfig {
    pub replicates: usize,
    /// Coverage of the percentile interval, strictly between 0 and 1.
    pub confidence_level: f64,
    pub seed: u64,
}

impl Default for BootstrapConfig {
    fn default() -> Self {
        Self {
            replicates: DEFAULT_REPLICATES,
            confidence_level: DEFAULT_CONFIDENCE_LEVEL,
            seed: DEFAULT_BOOTSTRAP_SEED,
        }
    }
}

/// Why a bootstrap could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BootstrapError {
    #[error("the bootstrap needs at least one replicate")]
    NoReplicates,
    #[error("confidence level {level} is not strictly between 0 and 1")]
    ConfidenceLevel { level: f64 },
    #[error("replicate {replicate}: {source}")]
    ItemOutOfRange {
        replicate: usize,
        #[source]
        source: ItemOutOfRange,
    },
    #[error(transparent)]
    UnitItems(#[from] UnitItemsError),
}

/// Alpha with its percentile bootstrap interval.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BootstrapAlpha {
    /// Alpha on the data as given.
    pub estimate: AlphaResult,
    /// Number of items resampled (each replicate draws this many, with replacement).
    pub items: usize,
    pub replicates: usize,
    /// Replicates whose alpha was undefined; they are left out of the interval.
    pub undefined_replicates: usize,
    pub confidence_level: f64,
    /// `None` when no replicate was defined.
    pub ci_low: Option<f64>,
    pub ci_high: Option<f64>,
    pub replicate_mean: Option<f64>,
    /// Sample standard deviation (n − 1) of the defined replicates: the bootstrap standard error.
    pub replicate_sd: Option<f64>,
    /// `None` when the replicates were given explicitly.
    pub seed: Option<u64>,
    pub rng: Option<String>,
    /// Each replicate's alpha, in replicate order; left out of serialized output for size.
    #[serde(skip)]
    pub replicate_alphas: Vec<Option<f64>>,
}

/// Alpha of `data` with a percentile bootstrap over the items of `items`.
pub fn bootstrap_alpha(
    data: &ReliabilityData,
    level: MeasurementLevel,
    items: &UnitItems,
    config: &BootstrapConfig,
) -> Result<BootstrapAlpha, BootstrapError> {
    PreparedAlpha::with_items(data, level, items)?.bootstrap(config)
}

impl PreparedAlpha {
    /// Draws `config.replicates` resamples of the items with replacement, each the size of the
    /// item set, and returns the percentile interval of their alphas.
    pub fn bootstrap(&self, config: &BootstrapConfig) -> Result<BootstrapAlpha, BootstrapError> {
        check_config(config.replicates, config.confidence_level)?;
        let items = self.items();
        let item_patterns = self.item_patterns();
        let alphas: Vec<Option<f64>> = (0..config.replicates)
            .into_par_iter()
            .map_init(
                || (self.new_tally(), vec![0u32; self.patterns()]),
                |(tally, draws), replicate| {
                    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
                    rng.set_stream(replicate as u64);
                    draws.fill(0);
                    for _ in 0..items {
                        draws[item_patterns[rng.random_range(0..items)] as usize] += 1;
                    }
                    self.tally_pattern_draws(tally, draws);
                    self.tally_alpha(tally).ok()
                },
            )
            .collect();
        Ok(self.summarize(
            alphas,
            config.confidence_level,
            Some(config.seed),
            Some(BOOTSTRAP_RNG.to_owned()),
        ))
    }

    /// The same summary over replicates given as lists of item indices (repeats allowed), for
    /// checking against another implementation's draws without sharing its RNG.
    pub fn bootstrap_replicates(
        &self,
        replicates: &[Vec<usize>],
        confidence_level: f64,
    ) -> Result<BootstrapAlpha, BootstrapError> {
        check_config(replicates.len(), confidence_level)?;
        let items = self.items();
        for (replicate, draw) in replicates.iter().enumerate() {
            if let Some((position, &item)) =
                draw.iter().enumerate().find(|&(_, &item)| item >= items)
            {
                return Err(BootstrapError::ItemOutOfRange {
                    replicate,
                    source: ItemOutOfRange {
                        position,
                        item,
                        items,
                    },
                });
            }
        }
        let alphas: Vec<Option<f64>> = replicates
            .par_iter()
            .map_init(
                || (self.new_tally(), vec![0u32; self.patterns()]),
                |(tally, draws), draw| {
                    draws.fill(0);
                    for &item in draw {
                        draws[self.item_patterns()[item] as usize] += 1;
                    }
                    self.tally_pattern_draws(tally, draws);
                    self.tally_alpha(tally).ok()
                },
            )
            .collect();
        Ok(self.summarize(alphas, confidence_level, None, None))
    }

    fn summarize(
        &self,
        replicate_alphas: Vec<Option<f64>>,
        confidence_level: f64,
        seed: Option<u64>,
        rng: Option<String>,
    ) -> BootstrapAlpha {
        let mut defined: Vec<f64> = replicate_alphas.iter().flatten().copied().collect();
        defined.sort_by(f64::total_cmp);
        let tail = (1.0 - confidence_level) / 2.0;
        let (replicate_mean, replicate_sd) = mean_and_sd(&defined);
        BootstrapAlpha {
            estimate: self.estimate(),
            items: self.items(),
            replicates: replicate_alphas.len(),
            undefined_replicates: replicate_alphas.len() - defined.len(),
            confidence_level,
            ci_low: percentile(&defined, tail),
            ci_high: percentile(&defined, 1.0 - tail),
            replicate_mean,
            replicate_sd,
            seed,
            rng,
            replicate_alphas,
        }
    }
}

fn check_config(replicates: usize, confidence_level: f64) -> Result<(), BootstrapError> {
    if replicates == 0 {
        return Err(BootstrapError::NoReplicates);
    }
    if !(confidence_level > 0.0 && confidence_level < 1.0) {
        return Err(BootstrapError::ConfidenceLevel {
            level: confidence_level,
        });
    }
    Ok(())
}

/// The `fraction` quantile of ascending `sorted` values with linear interpolation between order
/// statistics (Hyndman–Fan type 7, numpy's default), or `None` for no values.
pub fn percentile(sorted: &[f64], fraction: f64) -> Option<f64> {
    let last = sorted.len().checked_sub(1)?;
    let position = fraction.clamp(0.0, 1.0) * last as f64;
    let below = position.floor() as usize;
    let above = (below + 1).min(last);
    let weight = position - below as f64;
    Some(sorted[below] + weight * (sorted[above] - sorted[below]))
}

fn mean_and_sd(values: &[f64]) -> (Option<f64>, Option<f64>) {
    if values.is_empty() {
        return (None, None);
    }
    let count = values.len() as f64;
    let mean = values.iter().sum::<f64>() / count;
    let sd = (values.len() >= 2).then(|| {
        let squares: f64 = values
            .iter()
            .map(|value| (value - mean) * (value - mean))
            .sum();
        (squares / (count - 1.0)).sqrt()
    });
    (Some(mean), sd)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::agreement::alpha::{AlphaUndefined, krippendorff_alpha};

    /// A 2 × 6 data set whose alpha is clearly positive but not perfect.
    fn small_data() -> ReliabilityData {
        let first = [1.0, 2.0, 3.0, 4.0, 2.0, 1.0];
        let second = [1.0, 2.0, 3.0, 3.0, 2.0, 2.0];
        ReliabilityData::from_coder_rows(vec![
            first.iter().copied().map(Some).collect(),
            second.iter().copied().map(Some).collect(),
        ])
        .unwrap()
    }

    #[test]
    fn replicate_mean_and_sample_standard_deviation() {
        assert_eq!(mean_and_sd(&[]), (None, None));
        assert_eq!(mean_and_sd(&[0.25]), (Some(0.25), None));
        let (mean, sd) = mean_and_sd(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(mean, Some(2.5));
        // Σ(x − 2.5)² = 5 over n − 1 = 3.
        assert!((sd.expect("two or more values") - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
        // Squared deviations, not Σx² − n·mean²: far from zero the mean's rounding would swamp
        // a spread of one (Python: statistics.stdev([1e9, 1e9 + 1, 1e9 + 1]) = 0.5773…).
        let (_, sd) = mean_and_sd(&[1e9, 1e9 + 1.0, 1e9 + 1.0]);
        assert!((sd.expect("three values") - (1.0f64 / 3.0).sqrt()).abs() < 1e-6);
    }

    #[test]
    fn percentile_interpolates_like_numpy() {
        let sorted = [1.0, 2.0, 4.0, 8.0];
        assert_eq!(percentile(&sorted, 0.0), Some(1.0));
        assert_eq!(percentile(&sorted, 1.0), Some(8.0));
        // position 0.5 · 3 = 1.5 → halfway between 2 and 4.
        assert_eq!(percentile(&sorted, 0.5), Some(3.0));
        // position 0.025 · 3 = 0.075 → 1 + 0.075 · 1.
        assert!((percentile(&sorted, 0.025).unwrap() - 1.075).abs() < 1e-15);
        assert_eq!(percentile(&[5.0], 0.3), Some(5.0));
        assert_eq!(percentile(&[], 0.5), None);
    }

    #[test]
    fn same_seed_same_interval_other_seed_differs() {
        let prepared = PreparedAlpha::new(&small_data(), MeasurementLevel::Ordinal);
        let config = BootstrapConfig {
            replicates: 300,
            ..BootstrapConfig::default()
        };
        let first = prepared.bootstrap(&config).unwrap();
        let again = prepared.bootstrap(&config).unwrap();
        assert_eq!(first, again);
        assert_eq!(first.replicates, 300);
        assert_eq!(first.seed, Some(0));
        assert_eq!(
            first.replicates,
            first.undefined_replicates + first.replicate_alphas.iter().flatten().count()
        );
        let other = prepared
            .bootstrap(&BootstrapConfig { seed: 7, ..config })
            .unwrap();
        assert_ne!(first.replicate_alphas, other.replicate_alphas);
    }

    #[test]
    fn result_does_not_depend_on_thread_count() {
        let prepared = PreparedAlpha::new(&small_data(), MeasurementLevel::Interval);
        let config = BootstrapConfig {
            replicates: 200,
            ..BootstrapConfig::default()
        };
        let single = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| prepared.bootstrap(&config).unwrap());
        let several = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap()
            .install(|| prepared.bootstrap(&config).unwrap());
        assert_eq!(single, several);
    }

    #[test]
    fn undefined_replicates_are_counted_and_left_out() {
        // Unit 0 varies, units 1 and 2 agree on 5: any draw without unit 0 has no variation.
        let data = ReliabilityData::from_coder_rows(vec![
            vec![Some(1.0), Some(5.0), Some(5.0)],
            vec![Some(2.0), Some(5.0), Some(5.0)],
        ])
        .unwrap();
        let prepared = PreparedAlpha::new(&data, MeasurementLevel::Nominal);
        let replicates = vec![vec![1, 2, 2], vec![0, 1, 2], vec![0, 0, 1]];
        let summary = prepared.bootstrap_replicates(&replicates, 0.9).unwrap();
        assert_eq!(summary.undefined_replicates, 1);
        assert_eq!(summary.replicate_alphas[0], None);
        assert_eq!(
            summary.replicate_alphas[1],
            krippendorff_alpha(&data, MeasurementLevel::Nominal).alpha
        );
        assert!(summary.ci_low.is_some());
        let random = prepared
            .bootstrap(&BootstrapConfig {
                replicates: 500,
                ..BootstrapConfig::default()
            })
            .unwrap();
        // P(unit 0 never drawn) = (2/3)³ ≈ 0.30.
        assert!(random.undefined_replicates > 100 && random.undefined_replicates < 200);
    }

    #[test]
    fn all_undefined_leaves_no_interval() {
        let data = ReliabilityData::from_coder_rows(vec![vec![Some(3.0); 4]; 2]).unwrap();
        let summary = PreparedAlpha::new(&data, MeasurementLevel::Ordinal)
            .bootstrap(&BootstrapConfig {
                replicates: 20,
                ..BootstrapConfig::default()
            })
            .unwrap();
        assert_eq!(
            summary.estimate.reason,
            Some(AlphaUndefined::NoVariation { value: 3.0 })
        );
        assert_eq!(summary.undefined_replicates, 20);
        assert_eq!((summary.ci_low, summary.ci_high), (None, None));
    }

    #[test]
    fn items_are_resampled_as_wholes() {
        // Item 0 owns units 0 and 1, item 1 owns unit 2. A replicate of item 1 twice must equal
        // alpha on unit 2 duplicated, which has no variation.
        let data = ReliabilityData::from_coder_rows(vec![
            vec![Some(1.0), Some(2.0), Some(3.0)],
            vec![Some(1.0), Some(1.0), Some(3.0)],
        ])
        .unwrap();
        let items = UnitItems::new(vec![0, 0, 1], 2).unwrap();
        let prepared = PreparedAlpha::with_items(&data, MeasurementLevel::Nominal, &items).unwrap();
        let summary = prepared
            .bootstrap_replicates(&[vec![1, 1], vec![0, 0]], 0.95)
            .unwrap();
        assert_eq!(summary.replicate_alphas[0], None);
        let doubled = ReliabilityData::from_coder_rows(vec![
            vec![Some(1.0), Some(2.0), Some(1.0), Some(2.0)],
            vec![Some(1.0), Some(1.0), Some(1.0), Some(1.0)],
        ])
        .unwrap();
        let expected = krippendorff_alpha(&doubled, MeasurementLevel::Nominal)
            .alpha
            .unwrap();
        assert!((summary.replicate_alphas[1].unwrap() - expected).abs() < 1e-15);
        let random = bootstrap_alpha(
            &data,
            MeasurementLevel::Nominal,
            &items,
            &BootstrapConfig {
                replicates: 50,
                ..BootstrapConfig::default()
            },
        )
        .unwrap();
        assert_eq!(random.items, 2);
    }

    #[test]
    fn replicates_agree_with_direct_resamples_when_items_share_patterns() {
        // Units 0, 2 and 4 are identical, as are 1 and 5, so several items share a pattern.
        let data = ReliabilityData::from_coder_rows(vec![
            vec![
                Some(1.0),
                Some(2.0),
                Some(1.0),
                Some(3.0),
                Some(1.0),
                Some(2.0),
            ],
            vec![
                Some(1.0),
                Some(3.0),
                Some(1.0),
                Some(3.0),
                Some(1.0),
                Some(3.0),
            ],
            vec![Some(2.0), None, Some(2.0), Some(1.0), Some(2.0), None],
        ])
        .unwrap();
        for level in MeasurementLevel::ALL {
            let prepared = PreparedAlpha::new(&data, level);
            let draws = vec![
                vec![0, 0, 1, 3, 5, 5],
                vec![2, 4, 3, 3, 1, 0],
                vec![5, 1, 1, 0],
            ];
            let summary = prepared.bootstrap_replicates(&draws, 0.95).unwrap();
            for (draw, alpha) in draws.iter().zip(&summary.replicate_alphas) {
                let direct = prepared.alpha_for_items(draw).unwrap().alpha.unwrap();
                assert!((alpha.unwrap() - direct).abs() < 1e-14, "{level} {draw:?}");
            }
        }
    }

    #[test]
    fn keyed_units_group_into_items() {
        // Units addressed as (item id, position); the bootstrap must resample the two items.
        let entries = vec![
            (0, ("q1", 1), Some(1.0)),
            (1, ("q1", 1), Some(1.0)),
            (0, ("q1", 2), Some(2.0)),
            (1, ("q1", 2), Some(3.0)),
            (0, ("q2", 1), Some(3.0)),
            (1, ("q2", 1), Some(3.0)),
        ];
        let keyed = ReliabilityData::from_keyed_values(
            2,
            entries.into_iter().map(|(coder, (item, position), value)| {
                (coder, format!("{item}#{position}"), value)
            }),
        )
        .unwrap();
        let (items, item_ids) = UnitItems::group_units(&keyed.unit_keys, |key| {
            key.split('#').next().map(str::to_owned)
        });
        assert_eq!(item_ids, vec![Some("q1".to_owned()), Some("q2".to_owned())]);
        let summary = bootstrap_alpha(
            &keyed.data,
            MeasurementLevel::Ordinal,
            &items,
            &BootstrapConfig {
                replicates: 64,
                ..BootstrapConfig::default()
            },
        )
        .unwrap();
        assert_eq!(summary.items, 2);
        assert_eq!(summary.estimate.units, 3);
        let mismatch = bootstrap_alpha(
            &keyed.data,
            MeasurementLevel::Ordinal,
            &UnitItems::one_per_unit(2),
            &BootstrapConfig::default(),
        );
        assert!(matches!(mismatch, Err(BootstrapError::UnitItems(_))));
    }

    #[test]
    fn bad_configurations_are_refused() {
        let prepared = PreparedAlpha::new(&small_data(), MeasurementLevel::Ordinal);
        let zero = BootstrapConfig {
            replicates: 0,
            ..BootstrapConfig::default()
        };
        assert_eq!(prepared.bootstrap(&zero), Err(BootstrapError::NoReplicates));
        // A level is strictly between 0 and 1: neither end is an interval.
        for level in [0.0, 1.0] {
            let config = BootstrapConfig {
                confidence_level: level,
                ..BootstrapConfig::default()
            };
            assert!(
                matches!(
                    prepared.bootstrap(&config),
                    Err(BootstrapError::ConfidenceLevel { .. })
                ),
                "{level}"
            );
        }
        let err = prepared
            .bootstrap_replicates(&[vec![0, 1], vec![0, 6]], 0.95)
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "replicate 1: entry 1 names item 6, but the data has 6 items"
        );
    }

    #[test]
    fn interval_brackets_the_estimate_and_is_serialized_without_replicates() {
        let summary = PreparedAlpha::new(&small_data(), MeasurementLevel::Ordinal)
            .bootstrap(&BootstrapConfig::default())
            .unwrap();
        let (low, high) = (summary.ci_low.unwrap(), summary.ci_high.unwrap());
        assert!(low <= summary.estimate.alpha.unwrap() && summary.estimate.alpha.unwrap() <= high);
        let json = serde_json::to_value(&summary).unwrap();
        assert!(json.get("replicate_alphas").is_none());
        assert_eq!(json["seed"], 0);
        assert_eq!(json["replicates"], 1000);
    }
}
