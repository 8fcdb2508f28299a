//! Laws Krippendorff's alpha obeys, checked on random reliability data: it agrees with a
//! direct computation from the definition (coincidences, then D_o and D_e), it never exceeds
//! 1, it does not depend on the order of coders or units, and each level's difference function
//! is blind to exactly the transformations it should be (relabelling for nominal, monotone
//! maps for ordinal, affine maps for interval, scaling for ratio). Bootstrap intervals are
//! reproducible from their seed and ordered.

use std::collections::BTreeMap;

use enact_core::agreement::{
    BootstrapConfig, MeasurementLevel, PreparedAlpha, ReliabilityData, UnitItems, bootstrap_alpha,
    krippendorff_alpha, pairwise_alphas,
};
use proptest::prelude::*;

/// Coders × units, values 1..=5 with about one cell in four missing.
fn coder_rows() -> impl Strategy<Value = Vec<Vec<Option<f64>>>> {
    (2usize..=5, 1usize..=12).prop_flat_map(|(coders, units)| {
        proptest::collection::vec(
            proptest::collection::vec(
                prop_oneof![1 => Just(None), 3 => (1u8..=5).prop_map(|v| Some(f64::from(v)))],
                units,
            ),
            coders,
        )
    })
}

fn data(rows: &[Vec<Option<f64>>]) -> ReliabilityData {
    ReliabilityData::from_coder_rows(rows.to_vec()).expect("rectangular rows")
}

/// Alpha straight from its definition, written apart from the crate's implementation:
/// `None` when it is undefined (fewer than two pairable values, or no expected disagreement).
fn alpha_by_definition(rows: &[Vec<Option<f64>>], level: MeasurementLevel) -> Option<f64> {
    let units = rows[0].len();
    // o[c][k]: the coincidences of values c and k (as keys, exact floats compared by bits).
    let mut o: BTreeMap<(u64, u64), f64> = BTreeMap::new();
    let mut values: Vec<f64> = Vec::new();
    for u in 0..units {
        let in_unit: Vec<f64> = rows.iter().filter_map(|row| row[u]).collect();
        let m = in_unit.len();
        if m < 2 {
            continue;
        }
        for (i, &c) in in_unit.iter().enumerate() {
            for (j, &k) in in_unit.iter().enumerate() {
                if i != j {
                    *o.entry((c.to_bits(), k.to_bits())).or_default() += 1.0 / (m - 1) as f64;
                }
            }
            values.push(c);
        }
    }
    let mut n_c: BTreeMap<u64, f64> = BTreeMap::new();
    for (&(c, _), &count) in &o {
        *n_c.entry(c).or_default() += count;
    }
    let n: f64 = n_c.values().sum();
    if n < 2.0 {
        return None;
    }
    let mut sorted: Vec<f64> = n_c.keys().map(|&bits| f64::from_bits(bits)).collect();
    sorted.sort_by(f64::total_cmp);
    let frequency = |v: f64| n_c[&v.to_bits()];
    let delta2 = |c: f64, k: f64| -> f64 {
        match level {
            MeasurementLevel::Nominal => f64::from(u8::from(c != k)),
            MeasurementLevel::Interval => (c - k).powi(2),
            MeasurementLevel::Ratio => {
                if c + k == 0.0 {
                    0.0
                } else {
                    ((c - k) / (c + k)).powi(2)
                }
            }
            MeasurementLevel::Ordinal => {
                let (low, high) = if c <= k { (c, k) } else { (k, c) };
                let between: f64 = sorted
                    .iter()
                    .filter(|&&g| g >= low && g <= high)
                    .map(|&g| frequency(g))
                    .sum();
                (between - (frequency(c) + frequency(k)) / 2.0).powi(2)
            }
        }
    };
    let observed: f64 = o
        .iter()
        .map(|(&(c, k), &count)| count * delta2(f64::from_bits(c), f64::from_bits(k)))
        .sum::<f64>()
        / n;
    let mut expected = 0.0;
    for &c in &sorted {
        for &k in &sorted {
            expected += frequency(c) * frequency(k) * delta2(c, k);
        }
    }
    expected /= n * (n - 1.0);
    (expected > 0.0).then(|| 1.0 - observed / expected)
}

fn close(a: Option<f64>, b: Option<f64>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs())),
        (None, None) => true,
        _ => false,
    }
}

/// The same data with every value passed through `map`.
fn mapped(rows: &[Vec<Option<f64>>], map: impl Fn(f64) -> f64) -> Vec<Vec<Option<f64>>> {
    rows.iter()
        .map(|row| row.iter().map(|v| v.map(&map)).collect())
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn alpha_is_what_its_definition_gives_at_every_level(rows in coder_rows()) {
        for level in MeasurementLevel::ALL {
            let ours = krippendorff_alpha(&data(&rows), level);
            let defined = alpha_by_definition(&rows, level);
            prop_assert!(close(ours.alpha, defined), "{level:?}: {:?} against {defined:?}", ours.alpha);
            prop_assert_eq!(ours.alpha.is_none(), ours.reason.is_some());
            let pairable: usize = (0..rows[0].len())
                .map(|u| rows.iter().filter(|row| row[u].is_some()).count())
                .filter(|&m| m >= 2)
                .sum();
            prop_assert_eq!(ours.pairable_values, pairable);
            prop_assert_eq!(ours.coders, rows.len());
            prop_assert_eq!(ours.units, rows[0].len());
        }
    }

    #[test]
    fn alpha_never_exceeds_one_and_is_one_exactly_without_observed_disagreement(
        rows in coder_rows()
    ) {
        for level in MeasurementLevel::ALL {
            let result = krippendorff_alpha(&data(&rows), level);
            if let (Some(alpha), Some(observed), Some(expected)) = (
                result.alpha,
                result.observed_disagreement,
                result.expected_disagreement,
            ) {
                prop_assert!(alpha <= 1.0 + 1e-12, "{level:?}: {alpha}");
                prop_assert!(observed >= 0.0 && expected > 0.0);
                prop_assert!((alpha - (1.0 - observed / expected)).abs() < 1e-12);
                prop_assert_eq!(observed == 0.0, (alpha - 1.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn the_order_of_coders_and_of_units_changes_nothing(
        rows in coder_rows(),
        coder_seed in any::<u64>(),
        unit_seed in any::<u64>(),
    ) {
        let mut shuffled = rows.clone();
        shuffle(&mut shuffled, coder_seed);
        let units = rows[0].len();
        let mut order: Vec<usize> = (0..units).collect();
        shuffle(&mut order, unit_seed);
        let shuffled: Vec<Vec<Option<f64>>> = shuffled
            .iter()
            .map(|row| order.iter().map(|&u| row[u]).collect())
            .collect();
        for level in MeasurementLevel::ALL {
            let before = krippendorff_alpha(&data(&rows), level);
            let after = krippendorff_alpha(&data(&shuffled), level);
            prop_assert!(close(before.alpha, after.alpha), "{level:?}");
            prop_assert_eq!(before.pairable_values, after.pairable_values);
            prop_assert_eq!(before.units_used, after.units_used);
            prop_assert_eq!(before.distinct_values, after.distinct_values);
        }
    }

    #[test]
    fn each_level_ignores_what_its_difference_function_ignores(rows in coder_rows()) {
        let alpha = |rows: &[Vec<Option<f64>>], level| krippendorff_alpha(&data(rows), level).alpha;
        // Nominal: any relabelling that keeps values apart.
        let relabelled = mapped(&rows, |v| [0.0, 40.0, -3.0, 7.5, 2.0, 11.0][v as usize]);
        prop_assert!(close(alpha(&rows, MeasurementLevel::Nominal), alpha(&relabelled, MeasurementLevel::Nominal)));
        // Ordinal: any increasing map.
        let monotone = mapped(&rows, |v| v.powi(3) + 100.0);
        prop_assert!(close(alpha(&rows, MeasurementLevel::Ordinal), alpha(&monotone, MeasurementLevel::Ordinal)));
        // Interval: any affine map, decreasing ones too.
        let affine = mapped(&rows, |v| -2.5 * v + 9.0);
        prop_assert!(close(alpha(&rows, MeasurementLevel::Interval), alpha(&affine, MeasurementLevel::Interval)));
        // Ratio: scaling.
        let scaled = mapped(&rows, |v| 3.0 * v);
        prop_assert!(close(alpha(&rows, MeasurementLevel::Ratio), alpha(&scaled, MeasurementLevel::Ratio)));
    }

    #[test]
    fn two_coders_pairwise_alpha_is_their_alpha(rows in coder_rows()) {
        let two = &rows[..2];
        for level in MeasurementLevel::ALL {
            let pairs = pairwise_alphas(&data(two), level);
            prop_assert_eq!(pairs.len(), 1);
            prop_assert_eq!((pairs[0].coder_a, pairs[0].coder_b), (0, 1));
            prop_assert!(close(pairs[0].result.alpha, krippendorff_alpha(&data(two), level).alpha));
        }
        let all = pairwise_alphas(&data(&rows), MeasurementLevel::Nominal);
        prop_assert_eq!(all.len(), rows.len() * (rows.len() - 1) / 2);
    }

    #[test]
    fn a_resample_of_items_is_alpha_over_the_units_repeated_as_drawn(
        rows in coder_rows(),
        draws in proptest::collection::vec(any::<usize>(), 1..=16),
    ) {
        let units = rows[0].len();
        let draws: Vec<usize> = draws.into_iter().map(|d| d % units).collect();
        let repeated: Vec<Vec<Option<f64>>> = rows
            .iter()
            .map(|row| draws.iter().map(|&u| row[u]).collect())
            .collect();
        for level in MeasurementLevel::ALL {
            let prepared = PreparedAlpha::new(&data(&rows), level);
            let resample = prepared.alpha_for_items(&draws).expect("items in range");
            prop_assert!(close(resample.alpha, alpha_by_definition(&repeated, level)), "{level:?}");
            prop_assert_eq!(resample.units, draws.len());
        }
        let prepared = PreparedAlpha::new(&data(&rows), MeasurementLevel::Nominal);
        prop_assert!(prepared.alpha_for_items(&[units]).is_err());
    }

    #[test]
    fn a_bootstrap_is_reproducible_from_its_seed_and_its_interval_is_ordered(
        rows in coder_rows(),
        seed in any::<u64>(),
    ) {
        let data = data(&rows);
        let items = UnitItems::one_per_unit(data.units());
        let config = BootstrapConfig { replicates: 200, confidence_level: 0.9, seed };
        let first = bootstrap_alpha(&data, MeasurementLevel::Interval, &items, &config)
            .expect("a valid configuration");
        let again = bootstrap_alpha(&data, MeasurementLevel::Interval, &items, &config)
            .expect("a valid configuration");
        prop_assert_eq!(&first, &again);
        prop_assert_eq!(first.replicates, 200);
        prop_assert!(close(first.estimate.alpha, krippendorff_alpha(&data, MeasurementLevel::Interval).alpha));
        if let (Some(low), Some(high)) = (first.ci_low, first.ci_high) {
            prop_assert!(low <= high);
            prop_assert!(high <= 1.0 + 1e-12);
            let mean = first.replicate_mean.expect("a mean where an interval is");
            prop_assert!(mean <= 1.0 + 1e-12);
        }
        prop_assert_eq!(first.ci_low.is_some(), first.undefined_replicates < 200);
    }
}

/// Fisher–Yates driven by a splitmix64 stream of `seed`.
fn shuffle<T>(items: &mut [T], seed: u64) {
    let mut state = seed;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    for i in (1..items.len()).rev() {
        let j = (next() % (i as u64 + 1)) as usize;
        items.swap(i, j);
    }
}
