//! Krippendorff's alpha in the coincidence-matrix form (nominal, ordinal, interval and ratio
//! levels), the per-item tallies the bootstrap reuses, and pairwise alphas between coders.
//!
//! The data is reduced once, unit by unit, to per-item tallies: how many pairable values of each
//! distinct value the item holds, and its off-diagonal coincidences. Alpha for any multiset of
//! items is then a weighted sum of those tallies followed by O(V) work (O(V²) for ratio), so a
//! bootstrap replicate never revisits coders or units. Items with identical tallies share one
//! row, which with few distinct values makes a replicate little more than counting draws.

use std::collections::HashMap;
use std::collections::hash_map::DefaultHasher;
use std::fmt;
use std::hash::{Hash, Hasher};
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::agreement::reliability::{ReliabilityData, UnitItems, UnitItemsError};

/// The level of measurement, which fixes the difference function δ².
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MeasurementLevel {
    /// δ² = 1 for any two different values.
    Nominal,
    /// δ² from the ranks of the values and the marginal frequencies of the pairable values.
    Ordinal,
    /// δ² = (c − k)².
    Interval,
    /// δ² = ((c − k) / (c + k))², with 0 when both are 0; values must not be negative.
    Ratio,
}

impl MeasurementLevel {
    pub const ALL: [MeasurementLevel; 4] = [
        MeasurementLevel::Nominal,
        MeasurementLevel::Ordinal,
        MeasurementLevel::Interval,
        MeasurementLevel::Ratio,
    ];

    pub fn name(self) -> &'static str {
        match self {
            MeasurementLevel::Nominal => "nominal",
            MeasurementLevel::Ordinal => "ordinal",
            MeasurementLevel::Interval => "interval",
            MeasurementLevel::Ratio => "ratio",
        }
    }
}

impl fmt::Display for MeasurementLevel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A level name that is not one of nominal, ordinal, interval, ratio.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown level of measurement {0:?}: expected nominal, ordinal, interval or ratio")]
pub struct UnknownMeasurementLevel(pub String);

impl FromStr for MeasurementLevel {
    type Err = UnknownMeasurementLevel;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        MeasurementLevel::ALL
            .into_iter()
            .find(|level| level.name() == text)
            .ok_or_else(|| UnknownMeasurementLevel(text.to_owned()))
    }
}

/// Why alpha has no value. Alpha is 0/0 in these cases; reporting 0, 1 or NaN instead would
/// each be wrong in a different way, so the caller gets the reason.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, thiserror::Error)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum AlphaUndefined {
    #[error("no unit has values from two or more coders, so there is nothing to pair")]
    NoPairableUnits,
    #[error("every pairable value is {value}, so expected disagreement is zero and alpha is 0/0")]
    NoVariation { value: f64 },
    #[error(
        "coder {coder}, unit {unit}: value {value} is negative, which a ratio scale does not allow"
    )]
    NegativeRatioValue {
        coder: usize,
        unit: usize,
        value: f64,
    },
}

/// Alpha for one data set, with the counts it rests on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AlphaResult {
    /// `None` exactly when `reason` is set.
    pub alpha: Option<f64>,
    pub reason: Option<AlphaUndefined>,
    pub level: MeasurementLevel,
    pub coders: usize,
    /// Units in the data (for a resample: units drawn, counting repeats).
    pub units: usize,
    /// Units with two or more values, the only ones alpha uses.
    pub units_used: usize,
    /// n, the number of values in the units used.
    pub pairable_values: usize,
    /// Distinct values among the pairable values.
    pub distinct_values: usize,
    /// D_o = Σ o_ck δ²_ck / n.
    pub observed_disagreement: Option<f64>,
    /// D_e = Σ n_c n_k δ²_ck / (n (n − 1)).
    pub expected_disagreement: Option<f64>,
}

/// Krippendorff's alpha of `data` at `level`.
pub fn krippendorff_alpha(data: &ReliabilityData, level: MeasurementLevel) -> AlphaResult {
    PreparedAlpha::new(data, level).estimate()
}

/// Alpha between one pair of coders, over the units both of them coded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PairwiseAlpha {
    pub coder_a: usize,
    pub coder_b: usize,
    /// `result.units_used` is the number of units both coders coded.
    pub result: AlphaResult,
}

/// Alpha for every pair of coders `a < b`, in lexicographic order.
pub fn pairwise_alphas(data: &ReliabilityData, level: MeasurementLevel) -> Vec<PairwiseAlpha> {
    let coders = data.coders();
    let mut pairs = Vec::with_capacity(coders * coders.saturating_sub(1) / 2);
    for coder_a in 0..coders {
        for coder_b in coder_a + 1..coders {
            // With two coders a unit is pairable only when both coded it, which is exactly the
            // restriction to shared units.
            let result = krippendorff_alpha(&data.select_coders(&[coder_a, coder_b]), level);
            pairs.push(PairwiseAlpha {
                coder_a,
                coder_b,
                result,
            });
        }
    }
    pairs
}

/// The mean of the defined pairwise alphas, or `None` when none is defined.
pub fn mean_pairwise_alpha(pairs: &[PairwiseAlpha]) -> Option<f64> {
    let defined: Vec<f64> = pairs.iter().filter_map(|pair| pair.result.alpha).collect();
    if defined.is_empty() {
        None
    } else {
        Some(defined.iter().sum::<f64>() / defined.len() as f64)
    }
}

/// An item index outside the prepared data.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("entry {position} names item {item}, but the data has {items} items")]
pub struct ItemOutOfRange {
    pub position: usize,
    pub item: usize,
    pub items: usize,
}

/// Sparse rows of (tally slot, weight) plus the fixed-δ² observed disagreement, one row per
/// distinct item contribution ("pattern"), stored back to back.
#[derive(Debug, Clone)]
struct PatternRows {
    offsets: Vec<usize>,
    slots: Vec<u32>,
    weights: Vec<f64>,
    observed: Vec<f64>,
}

impl PatternRows {
    fn len(&self) -> usize {
        self.observed.len()
    }
}

/// Data reduced to per-item tallies, ready for alpha over the whole set or over any resample
/// of its items.
#[derive(Debug, Clone)]
pub struct PreparedAlpha {
    level: MeasurementLevel,
    coders: usize,
    units: usize,
    /// Distinct pairable values, ascending.
    values: Vec<f64>,
    /// Value-index pairs (c < k) that coincide within some unit; ordinal level only.
    pairs: Vec<(u32, u32)>,
    /// What one item adds to a tally. Over the tally slots: slot c < V holds how many pairable
    /// values equal to `values[c]` the item has; at the ordinal level, slot V + p holds o_ck
    /// for `pairs[p]` summed over the item's units. `observed` holds, for the other levels,
    /// Σ_{c≠k} o_ck δ²_ck over the item's units (the ordinal δ² depends on the marginals of the
    /// whole (re)sample, so there it is computed later from the pair slots and this stays 0).
    /// Items that contribute identically share a pattern: with few distinct values most items
    /// do, and a bootstrap replicate then only counts draws per pattern.
    patterns: PatternRows,
    item_pattern: Vec<u32>,
    item_units: Vec<u32>,
    item_units_used: Vec<u32>,
    /// A fault of the data as a whole that makes every alpha over it undefined.
    data_fault: Option<AlphaUndefined>,
}

/// Running sums for one (re)sample: the tally slots (value counts, then ordinal pair weights)
/// and the observed disagreement of the fixed-δ² levels.
#[derive(Debug, Clone)]
pub(crate) struct Tally {
    slots: Vec<f64>,
    observed: f64,
}

impl Tally {
    pub(crate) fn clear(&mut self) {
        self.slots.fill(0.0);
        self.observed = 0.0;
    }
}

impl PreparedAlpha {
    /// Prepares `data` with every unit its own item.
    pub fn new(data: &ReliabilityData, level: MeasurementLevel) -> Self {
        Self::build(data, level, &UnitItems::one_per_unit(data.units()))
    }

    /// Prepares `data` with units grouped into the items the bootstrap will resample.
    pub fn with_items(
        data: &ReliabilityData,
        level: MeasurementLevel,
        items: &UnitItems,
    ) -> Result<Self, UnitItemsError> {
        if items.units() != data.units() {
            return Err(UnitItemsError::UnitCountMismatch {
                assigned: items.units(),
                units: data.units(),
            });
        }
        Ok(Self::build(data, level, items))
    }

    pub fn level(&self) -> MeasurementLevel {
        self.level
    }

    pub fn items(&self) -> usize {
        self.item_units.len()
    }

    fn build(data: &ReliabilityData, level: MeasurementLevel, items: &UnitItems) -> Self {
        let coders = data.coders();
        let data_fault = if level == MeasurementLevel::Ratio {
            first_negative_value(data)
        } else {
            None
        };

        let mut values: Vec<f64> = (0..data.units())
            .map(|unit| data.unit_values(unit))
            .filter(|row| row.iter().flatten().count() >= 2)
            .flat_map(|row| row.iter().flatten().copied())
            .collect();
        values.sort_unstable_by(f64::total_cmp);
        values.dedup();

        // Units in item order (a counting sort), so each item's tallies are built in one go.
        let item_count = items.items();
        let mut item_offsets = vec![0usize; item_count + 1];
        for &item in items.item_of_unit() {
            item_offsets[item + 1] += 1;
        }
        for item in 0..item_count {
            item_offsets[item + 1] += item_offsets[item];
        }
        let mut next_slot = item_offsets.clone();
        let mut units_by_item = vec![0usize; data.units()];
        for (unit, &item) in items.item_of_unit().iter().enumerate() {
            units_by_item[next_slot[item]] = unit;
            next_slot[item] += 1;
        }

        let fixed_metric = FixedMetric::of(level);
        // Rows of (value index, count) and of (pair key, o_ck) per item; pair keys become slot
        // numbers once every pair occurring anywhere is known.
        let mut value_rows: Vec<(u32, f64)> = Vec::new();
        let mut value_offsets = vec![0usize];
        let mut pair_rows: Vec<(u64, f64)> = Vec::new();
        let mut pair_offsets = vec![0usize];
        let mut item_observed = Vec::with_capacity(item_count);
        let mut item_units = Vec::with_capacity(item_count);
        let mut item_units_used = Vec::with_capacity(item_count);

        let mut unit_indices: Vec<u32> = Vec::with_capacity(coders);
        let mut unit_counts: Vec<(u32, f64)> = Vec::with_capacity(coders);
        let mut scratch_values: Vec<(u32, f64)> = Vec::new();
        let mut scratch_pairs: Vec<(u64, f64)> = Vec::new();
        for item in 0..item_count {
            let item_unit_list = &units_by_item[item_offsets[item]..item_offsets[item + 1]];
            scratch_values.clear();
            scratch_pairs.clear();
            let mut observed = 0.0;
            let mut used = 0u32;
            for &unit in item_unit_list {
                unit_indices.clear();
                unit_indices.extend(data.unit_values(unit).iter().flatten().map(|value| {
                    // Every value of a unit with two or more values is in `values`.
                    values.partition_point(|probe| probe.total_cmp(value).is_lt()) as u32
                }));
                let present = unit_indices.len();
                if present < 2 {
                    continue;
                }
                used += 1;
                unit_indices.sort_unstable();
                unit_counts.clear();
                for &index in &unit_indices {
                    match unit_counts.last_mut() {
                        Some((last, count)) if *last == index => *count += 1.0,
                        _ => unit_counts.push((index, 1.0)),
                    }
                }
                scratch_values.extend_from_slice(&unit_counts);
                // o_ck gains n_uc · n_uk / (m_u − 1) from this unit; the diagonal never matters
                // because δ²_cc = 0.
                let pair_scale = 1.0 / (present - 1) as f64;
                let mut unit_observed = 0.0;
                for (a, &(c, count_c)) in unit_counts.iter().enumerate() {
                    for &(k, count_k) in &unit_counts[a + 1..] {
                        let product = count_c * count_k;
                        match fixed_metric {
                            Some(metric) => {
                                unit_observed +=
                                    product * metric.delta(values[c as usize], values[k as usize]);
                            }
                            None => scratch_pairs.push((pair_key(c, k), product * pair_scale)),
                        }
                    }
                }
                // Both orders (c, k) and (k, c) count, hence the 2.
                observed += 2.0 * unit_observed * pair_scale;
            }
            merge_sorted_into(&mut scratch_values, &mut value_rows);
            value_offsets.push(value_rows.len());
            merge_sorted_into(&mut scratch_pairs, &mut pair_rows);
            pair_offsets.push(pair_rows.len());
            item_observed.push(observed);
            item_units.push(item_unit_list.len() as u32);
            item_units_used.push(used);
        }

        let mut pair_keys: Vec<u64> = pair_rows.iter().map(|&(key, _)| key).collect();
        pair_keys.sort_unstable();
        pair_keys.dedup();
        let pair_slot_base = values.len();
        let mut patterns = PatternRows {
            offsets: vec![0],
            slots: Vec::new(),
            weights: Vec::new(),
            observed: Vec::new(),
        };
        // Fingerprint → patterns with that fingerprint; candidates are compared in full.
        let mut patterns_by_fingerprint: HashMap<u64, Vec<u32>> = HashMap::new();
        let mut item_pattern = Vec::with_capacity(item_count);
        let mut row_slots: Vec<u32> = Vec::new();
        let mut row_weights: Vec<f64> = Vec::new();
        for item in 0..item_count {
            row_slots.clear();
            row_weights.clear();
            for &(value, count) in &value_rows[value_offsets[item]..value_offsets[item + 1]] {
                row_slots.push(value);
                row_weights.push(count);
            }
            for &(key, weight) in &pair_rows[pair_offsets[item]..pair_offsets[item + 1]] {
                let pair = pair_keys.partition_point(|&probe| probe < key);
                row_slots.push((pair_slot_base + pair) as u32);
                row_weights.push(weight);
            }
            let observed = item_observed[item];
            let mut hasher = DefaultHasher::new();
            row_slots.hash(&mut hasher);
            for weight in row_weights.iter().chain([&observed]) {
                weight.to_bits().hash(&mut hasher);
            }
            let candidates = patterns_by_fingerprint.entry(hasher.finish()).or_default();
            // Bitwise identity: items share a pattern only if they add exactly the same sums.
            let same_as = |pattern: u32| {
                let pattern = pattern as usize;
                let range = patterns.offsets[pattern]..patterns.offsets[pattern + 1];
                patterns.slots[range.clone()] == row_slots[..]
                    && patterns.weights[range]
                        .iter()
                        .zip(&row_weights)
                        .all(|(a, b)| a.to_bits() == b.to_bits())
                    && patterns.observed[pattern].to_bits() == observed.to_bits()
            };
            let pattern = match candidates.iter().copied().find(|&pattern| same_as(pattern)) {
                Some(pattern) => pattern,
                None => {
                    let pattern = patterns.len() as u32;
                    patterns.slots.extend_from_slice(&row_slots);
                    patterns.weights.extend_from_slice(&row_weights);
                    patterns.offsets.push(patterns.slots.len());
                    patterns.observed.push(observed);
                    candidates.push(pattern);
                    pattern
                }
            };
            item_pattern.push(pattern);
        }
        let pairs = pair_keys
            .iter()
            .map(|&key| ((key >> 32) as u32, key as u32))
            .collect();

        Self {
            level,
            coders,
            units: data.units(),
            values,
            pairs,
            patterns,
            item_pattern,
            item_units,
            item_units_used,
            data_fault,
        }
    }

    /// Alpha over all the data.
    pub fn estimate(&self) -> AlphaResult {
        let mut tally = self.new_tally();
        for item in 0..self.items() {
            self.add_item(&mut tally, item);
        }
        let units_used = self.item_units_used.iter().map(|&used| used as usize).sum();
        self.result(&tally, self.units, units_used)
    }

    /// Alpha over the multiset of items `items` (repeats count as often as they appear), as one
    /// bootstrap replicate would compute it.
    pub fn alpha_for_items(&self, items: &[usize]) -> Result<AlphaResult, ItemOutOfRange> {
        let mut tally = self.new_tally();
        let (mut units, mut units_used) = (0, 0);
        for (position, &item) in items.iter().enumerate() {
            if item >= self.items() {
                return Err(ItemOutOfRange {
                    position,
                    item,
                    items: self.items(),
                });
            }
            self.add_item(&mut tally, item);
            units += self.item_units[item] as usize;
            units_used += self.item_units_used[item] as usize;
        }
        Ok(self.result(&tally, units, units_used))
    }

    pub(crate) fn new_tally(&self) -> Tally {
        Tally {
            slots: vec![0.0; self.values.len() + self.pairs.len()],
            observed: 0.0,
        }
    }

    /// Adds one copy of `item` to `tally`.
    fn add_item(&self, tally: &mut Tally, item: usize) {
        self.add_pattern(tally, self.item_pattern[item] as usize, 1.0);
    }

    fn add_pattern(&self, tally: &mut Tally, pattern: usize, times: f64) {
        let rows = &self.patterns;
        let range = rows.offsets[pattern]..rows.offsets[pattern + 1];
        for (&slot, &weight) in rows.slots[range.clone()].iter().zip(&rows.weights[range]) {
            tally.slots[slot as usize] += times * weight;
        }
        tally.observed += times * rows.observed[pattern];
    }

    /// Number of distinct item patterns; a replicate's draws are counted per pattern.
    pub(crate) fn patterns(&self) -> usize {
        self.patterns.len()
    }

    /// The pattern of each item, for counting a replicate's draws.
    pub(crate) fn item_patterns(&self) -> &[u32] {
        &self.item_pattern
    }

    /// Resets `tally` and fills it from how often each pattern was drawn.
    pub(crate) fn tally_pattern_draws(&self, tally: &mut Tally, draws: &[u32]) {
        tally.clear();
        for (pattern, &times) in draws.iter().enumerate() {
            if times > 0 {
                self.add_pattern(tally, pattern, f64::from(times));
            }
        }
    }

    /// Alpha from a finished tally, or why it is undefined.
    pub(crate) fn tally_alpha(&self, tally: &Tally) -> Result<f64, AlphaUndefined> {
        self.disagreements(tally).map(|sums| sums.alpha())
    }

    fn result(&self, tally: &Tally, units: usize, units_used: usize) -> AlphaResult {
        let sums = self.disagreements(tally);
        let counts = &tally.slots[..self.values.len()];
        let n: f64 = counts.iter().sum();
        let (alpha, reason, observed, expected) = match sums {
            Ok(sums) => (
                Some(sums.alpha()),
                None,
                Some(sums.observed / sums.n),
                Some(sums.expected / (sums.n * (sums.n - 1.0))),
            ),
            Err(reason) => (None, Some(reason), None, None),
        };
        AlphaResult {
            alpha,
            reason,
            level: self.level,
            coders: self.coders,
            units,
            units_used,
            pairable_values: n as usize,
            distinct_values: counts.iter().filter(|&&count| count > 0.0).count(),
            observed_disagreement: observed,
            expected_disagreement: expected,
        }
    }

    fn disagreements(&self, tally: &Tally) -> Result<DisagreementSums, AlphaUndefined> {
        if let Some(fault) = &self.data_fault {
            return Err(fault.clone());
        }
        let (counts, pair_weights) = tally.slots.split_at(self.values.len());
        let mut present = counts
            .iter()
            .enumerate()
            .filter(|&(_, &count)| count > 0.0)
            .map(|(index, _)| index);
        let Some(first) = present.next() else {
            return Err(AlphaUndefined::NoPairableUnits);
        };
        if present.next().is_none() {
            return Err(AlphaUndefined::NoVariation {
                value: self.values[first],
            });
        }
        let n: f64 = counts.iter().sum();

        let (observed, expected) = match self.level {
            MeasurementLevel::Nominal => {
                let squares: f64 = counts.iter().map(|count| count * count).sum();
                (tally.observed, n * n - squares)
            }
            MeasurementLevel::Interval => {
                let mean = counts
                    .iter()
                    .zip(&self.values)
                    .map(|(count, value)| count * value)
                    .sum::<f64>()
                    / n;
                // Σ_ck n_c n_k (c − k)² = 2n Σ_c n_c (c − mean)², which avoids the V² loop and
                // the cancellation of the raw-moment form.
                let spread: f64 = counts
                    .iter()
                    .zip(&self.values)
                    .map(|(count, value)| count * (value - mean) * (value - mean))
                    .sum();
                (tally.observed, 2.0 * n * spread)
            }
            MeasurementLevel::Ordinal => {
                // With s_c = (values ranked below c) + n_c / 2, the ordinal δ²_ck equals
                // (s_k − s_c)²: the interval metric on mid-ranks. The mid-ranks of all n values
                // average exactly n / 2, and with integer counts every term stays exact.
                let mut mid_ranks = Vec::with_capacity(counts.len());
                let mut below = 0.0;
                for &count in counts {
                    mid_ranks.push(below + count / 2.0);
                    below += count;
                }
                let half = n / 2.0;
                let spread: f64 = counts
                    .iter()
                    .zip(&mid_ranks)
                    .map(|(count, rank)| count * (rank - half) * (rank - half))
                    .sum();
                let observed: f64 = self
                    .pairs
                    .iter()
                    .zip(pair_weights)
                    .filter(|&(_, &weight)| weight > 0.0)
                    .map(|(&(c, k), weight)| {
                        let gap = mid_ranks[k as usize] - mid_ranks[c as usize];
                        weight * gap * gap
                    })
                    .sum();
                (2.0 * observed, 2.0 * n * spread)
            }
            MeasurementLevel::Ratio => {
                let present: Vec<(f64, f64)> = counts
                    .iter()
                    .zip(&self.values)
                    .filter(|&(&count, _)| count > 0.0)
                    .map(|(&count, &value)| (count, value))
                    .collect();
                let mut expected = 0.0;
                for (a, &(count_c, c)) in present.iter().enumerate() {
                    for &(count_k, k) in &present[a + 1..] {
                        expected += count_c * count_k * FixedMetric::Ratio.delta(c, k);
                    }
                }
                (tally.observed, 2.0 * expected)
            }
        };
        Ok(DisagreementSums {
            n,
            observed,
            expected,
        })
    }
}

/// Σ o_ck δ²_ck and Σ n_c n_k δ²_ck over all ordered (c, k), with n.
struct DisagreementSums {
    n: f64,
    observed: f64,
    expected: f64,
}

impl DisagreementSums {
    fn alpha(&self) -> f64 {
        1.0 - (self.n - 1.0) * self.observed / self.expected
    }
}

/// The levels whose δ² depends only on the two values compared; the ordinal δ² also depends
/// on the marginals of whatever (re)sample it is computed for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum FixedMetric {
    Nominal,
    Interval,
    Ratio,
}

impl FixedMetric {
    fn of(level: MeasurementLevel) -> Option<Self> {
        match level {
            MeasurementLevel::Nominal => Some(FixedMetric::Nominal),
            MeasurementLevel::Interval => Some(FixedMetric::Interval),
            MeasurementLevel::Ratio => Some(FixedMetric::Ratio),
            MeasurementLevel::Ordinal => None,
        }
    }

    fn delta(self, c: f64, k: f64) -> f64 {
        match self {
            FixedMetric::Nominal => {
                if c == k {
                    0.0
                } else {
                    1.0
                }
            }
            FixedMetric::Interval => (c - k) * (c - k),
            FixedMetric::Ratio => {
                let sum = c + k;
                if sum == 0.0 {
                    // Both values are 0 (negative values are refused): no difference.
                    0.0
                } else {
                    let ratio = (c - k) / sum;
                    ratio * ratio
                }
            }
        }
    }
}

fn pair_key(c: u32, k: u32) -> u64 {
    (u64::from(c) << 32) | u64::from(k)
}

/// Sorts `scratch` by key, sums entries with equal keys and appends the result to `out`.
fn merge_sorted_into<K: Ord + Copy>(scratch: &mut [(K, f64)], out: &mut Vec<(K, f64)>) {
    scratch.sort_unstable_by_key(|&(key, _)| key);
    let start = out.len();
    for &(key, weight) in scratch.iter() {
        let row_has_entries = out.len() > start;
        match out.last_mut() {
            Some((last, total)) if row_has_entries && *last == key => *total += weight,
            _ => out.push((key, weight)),
        }
    }
}

fn first_negative_value(data: &ReliabilityData) -> Option<AlphaUndefined> {
    (0..data.units()).find_map(|unit| {
        data.unit_values(unit)
            .iter()
            .enumerate()
            .find_map(|(coder, value)| match *value {
                Some(value) if value < 0.0 => {
                    Some(AlphaUndefined::NegativeRatioValue { coder, unit, value })
                }
                _ => None,
            })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A level prints as the name it is parsed from (the agreement export's header names it).
    #[test]
    fn a_level_prints_as_its_name_and_parses_back() {
        for level in MeasurementLevel::ALL {
            assert_eq!(level.to_string(), level.name());
            assert_eq!(level.to_string().parse::<MeasurementLevel>(), Ok(level));
        }
        assert_eq!(MeasurementLevel::Ordinal.to_string(), "ordinal");
    }

    fn rows(rows: &[&[Option<f64>]]) -> ReliabilityData {
        ReliabilityData::from_coder_rows(rows.iter().map(|row| row.to_vec()).collect()).unwrap()
    }

    fn parse_row(text: &str) -> Vec<Option<f64>> {
        text.split_whitespace()
            .map(|cell| {
                if cell == "." {
                    None
                } else {
                    Some(cell.parse().unwrap())
                }
            })
            .collect()
    }

    /// Krippendorff (2011) reliability data with four observers and twelve units.
    fn canonical() -> ReliabilityData {
        ReliabilityData::from_coder_rows(vec![
            parse_row("1 2 3 3 2 1 4 1 2 . . ."),
            parse_row("1 2 3 3 2 2 4 1 2 5 . 3"),
            parse_row(". 3 3 3 2 3 4 2 2 5 1 ."),
            parse_row("1 2 3 3 2 4 4 1 2 5 1 ."),
        ])
        .unwrap()
    }

    fn close(actual: Option<f64>, expected: f64) {
        let actual = actual.expect("alpha should be defined");
        assert!(
            (actual - expected).abs() < 1e-12,
            "alpha {actual} differs from {expected}"
        );
    }

    #[test]
    fn canonical_example_at_all_levels() {
        let data = canonical();
        close(
            krippendorff_alpha(&data, MeasurementLevel::Nominal).alpha,
            113.0 / 152.0,
        );
        close(
            krippendorff_alpha(&data, MeasurementLevel::Ordinal).alpha,
            108577.0 / 133160.0,
        );
        close(
            krippendorff_alpha(&data, MeasurementLevel::Interval).alpha,
            951.0 / 1120.0,
        );
        close(
            krippendorff_alpha(&data, MeasurementLevel::Ratio).alpha,
            18222619.0 / 22852465.0,
        );
    }

    #[test]
    fn a_subset_of_items_counts_only_the_values_it_holds() {
        // Unit 0 holds 1 and 2, unit 1 holds 3 twice; each unit is an item.
        let data = rows(&[&[Some(1.0), Some(3.0)], &[Some(2.0), Some(3.0)]]);
        let prepared = PreparedAlpha::new(&data, MeasurementLevel::Nominal);
        let whole = prepared.estimate();
        assert_eq!((whole.pairable_values, whole.distinct_values), (4, 3));
        let first = prepared.alpha_for_items(&[0]).unwrap();
        assert_eq!((first.pairable_values, first.distinct_values), (2, 2));
        let second_twice = prepared.alpha_for_items(&[1, 1]).unwrap();
        assert_eq!(
            (second_twice.pairable_values, second_twice.distinct_values),
            (4, 1)
        );
    }

    #[test]
    fn canonical_example_counts_and_disagreements() {
        let result = krippendorff_alpha(&canonical(), MeasurementLevel::Nominal);
        // Unit 12 has a single value and is dropped.
        assert_eq!(result.units, 12);
        assert_eq!(result.units_used, 11);
        assert_eq!(result.pairable_values, 40);
        assert_eq!(result.distinct_values, 5);
        close(result.observed_disagreement, 1.0 / 5.0);
        close(result.expected_disagreement, 152.0 / 195.0);
        let ordinal = krippendorff_alpha(&canonical(), MeasurementLevel::Ordinal);
        close(ordinal.observed_disagreement, 1891.0 / 40.0);
        close(ordinal.expected_disagreement, 3329.0 / 13.0);
    }

    #[test]
    fn two_coder_nominal_matches_small_sample_formula() {
        // A binary, two-coder case worked by hand: n = 8, n_0 = 5, n_1 = 3, o_01 = 1 (one
        // disagreeing unit), so alpha = 1 − 7 · 1 / (5 · 3) = 8/15.
        let data = rows(&[
            &[Some(0.0), Some(0.0), Some(1.0), Some(0.0)],
            &[Some(0.0), Some(1.0), Some(1.0), Some(0.0)],
        ]);
        close(
            krippendorff_alpha(&data, MeasurementLevel::Nominal).alpha,
            8.0 / 15.0,
        );
    }

    #[test]
    fn swapped_pair_is_negative() {
        let data = rows(&[&[Some(1.0), Some(2.0)], &[Some(2.0), Some(1.0)]]);
        close(
            krippendorff_alpha(&data, MeasurementLevel::Nominal).alpha,
            -0.5,
        );
    }

    #[test]
    fn missing_values_are_not_a_category() {
        let data = rows(&[
            &[Some(1.0), Some(1.0), Some(2.0)],
            &[Some(1.0), Some(1.0), None],
            &[None, Some(1.0), Some(2.0)],
        ]);
        close(
            krippendorff_alpha(&data, MeasurementLevel::Nominal).alpha,
            1.0,
        );
    }

    #[test]
    fn single_disagreement_gives_zero() {
        let mut data = vec![vec![Some(1.0); 5]; 5];
        data[4][4] = Some(2.0);
        let data = ReliabilityData::from_coder_rows(data).unwrap();
        close(
            krippendorff_alpha(&data, MeasurementLevel::Nominal).alpha,
            0.0,
        );
    }

    #[test]
    fn no_pairable_units_is_undefined() {
        let data = rows(&[&[Some(1.0), None, Some(3.0)], &[None, Some(2.0), None]]);
        let result = krippendorff_alpha(&data, MeasurementLevel::Nominal);
        assert_eq!(result.alpha, None);
        assert_eq!(result.reason, Some(AlphaUndefined::NoPairableUnits));
        assert_eq!(result.units_used, 0);
        let single_coder = rows(&[&[Some(1.0), Some(2.0)]]);
        assert_eq!(
            krippendorff_alpha(&single_coder, MeasurementLevel::Interval).reason,
            Some(AlphaUndefined::NoPairableUnits)
        );
    }

    #[test]
    fn no_variation_is_undefined_at_every_level() {
        // The 1 sits in a unit with a single value, so the pairable data never varies.
        let data = rows(&[
            &[Some(2.0), Some(2.0), Some(1.0)],
            &[Some(2.0), Some(2.0), None],
        ]);
        for level in MeasurementLevel::ALL {
            let result = krippendorff_alpha(&data, level);
            assert_eq!(result.alpha, None, "{level}");
            assert_eq!(
                result.reason,
                Some(AlphaUndefined::NoVariation { value: 2.0 })
            );
            assert!(result.observed_disagreement.is_none());
        }
    }

    #[test]
    fn ratio_treats_two_zeros_as_no_difference() {
        // Units (0,0), (0,1), (1,1), (2,2): n = 8 with counts 0:3, 1:3, 2:2.
        // δ²(0,1) = 1, δ²(0,2) = 1, δ²(1,2) = 1/9.
        // Σ o δ² = 2 · 1 = 2; Σ n n δ² = 2 (3·3·1 + 3·2·1 + 3·2·1/9) = 94/3.
        // alpha = 1 − 7 · 2 / (94/3) = 1 − 42/94 = 26/47.
        let data = rows(&[
            &[Some(0.0), Some(0.0), Some(1.0), Some(2.0)],
            &[Some(0.0), Some(1.0), Some(1.0), Some(2.0)],
        ]);
        close(
            krippendorff_alpha(&data, MeasurementLevel::Ratio).alpha,
            26.0 / 47.0,
        );
    }

    #[test]
    fn ratio_refuses_negative_values() {
        let data = rows(&[&[Some(1.0), Some(2.0)], &[Some(1.0), Some(-2.0)]]);
        let result = krippendorff_alpha(&data, MeasurementLevel::Ratio);
        assert_eq!(
            result.reason,
            Some(AlphaUndefined::NegativeRatioValue {
                coder: 1,
                unit: 1,
                value: -2.0
            })
        );
        assert!(
            krippendorff_alpha(&data, MeasurementLevel::Interval)
                .alpha
                .is_some()
        );
    }

    #[test]
    fn ordinal_ignores_monotone_relabelling_but_interval_does_not() {
        let base = rows(&[
            &[Some(1.0), Some(2.0), Some(3.0), Some(3.0), Some(1.0)],
            &[Some(1.0), Some(3.0), Some(3.0), Some(2.0), Some(2.0)],
        ]);
        let stretched = rows(&[
            &[Some(1.0), Some(5.0), Some(40.0), Some(40.0), Some(1.0)],
            &[Some(1.0), Some(40.0), Some(40.0), Some(5.0), Some(5.0)],
        ]);
        let ordinal_base = krippendorff_alpha(&base, MeasurementLevel::Ordinal)
            .alpha
            .unwrap();
        close(
            krippendorff_alpha(&stretched, MeasurementLevel::Ordinal).alpha,
            ordinal_base,
        );
        let interval_base = krippendorff_alpha(&base, MeasurementLevel::Interval)
            .alpha
            .unwrap();
        let interval_stretched = krippendorff_alpha(&stretched, MeasurementLevel::Interval)
            .alpha
            .unwrap();
        assert!((interval_base - interval_stretched).abs() > 1e-3);
    }

    #[test]
    fn interval_alpha_is_the_same_for_values_far_from_zero() {
        // δ² = (c − k)² does not see where the values sit, and the expected disagreement,
        // summed around the mean, keeps them: the raw moments (Σ n_c c² − n·mean²) of values
        // near 10⁹ would cancel away every digit of the spread.
        let near: [&[f64]; 2] = [&[1.0, 2.0, 3.0, 3.0, 1.0], &[1.0, 3.0, 3.0, 2.0, 2.0]];
        let shifted = |by: f64| -> Vec<Vec<Option<f64>>> {
            near.iter()
                .map(|row| row.iter().map(|v| Some(v + by)).collect())
                .collect()
        };
        let alpha = |data: Vec<Vec<Option<f64>>>| {
            let data = ReliabilityData::from_coder_rows(data).unwrap();
            krippendorff_alpha(&data, MeasurementLevel::Interval).alpha
        };
        let at_zero = alpha(shifted(0.0)).unwrap();
        close(alpha(shifted(1e9)), at_zero);
    }

    #[test]
    fn ordinal_two_coder_case_by_hand() {
        // Units (1,1), (1,2), (2,3), (3,3): counts 1:3, 2:2, 3:3, n = 8.
        // Mid-ranks: s1 = 1.5, s2 = 4, s3 = 6.5; δ²(1,2) = 6.25, δ²(2,3) = 6.25, δ²(1,3) = 25.
        // Σ o δ² = 2 (6.25 + 6.25) = 25.
        // Σ n n δ² = 2 (3·2·6.25 + 2·3·6.25 + 3·3·25) = 600. alpha = 1 − 7 · 25 / 600 = 17/24.
        let data = rows(&[
            &[Some(1.0), Some(1.0), Some(2.0), Some(3.0)],
            &[Some(1.0), Some(2.0), Some(3.0), Some(3.0)],
        ]);
        close(
            krippendorff_alpha(&data, MeasurementLevel::Ordinal).alpha,
            17.0 / 24.0,
        );
    }

    #[test]
    fn pairwise_uses_only_shared_units() {
        let data = rows(&[
            &[Some(1.0), Some(2.0), Some(1.0), None],
            &[Some(1.0), Some(2.0), Some(2.0), Some(2.0)],
            &[Some(1.0), Some(2.0), None, Some(1.0)],
        ]);
        let pairs = pairwise_alphas(&data, MeasurementLevel::Nominal);
        assert_eq!(pairs.len(), 3);
        assert_eq!((pairs[0].coder_a, pairs[0].coder_b), (0, 1));
        assert_eq!(pairs[0].result.units_used, 3);
        assert_eq!(pairs[1].result.units_used, 2);
        close(pairs[1].result.alpha, 1.0);
        let direct = krippendorff_alpha(&data.select_coders(&[1, 2]), MeasurementLevel::Nominal);
        assert_eq!(pairs[2].result, direct);
        let mean = mean_pairwise_alpha(&pairs).unwrap();
        let by_hand = pairs
            .iter()
            .map(|pair| pair.result.alpha.unwrap())
            .sum::<f64>()
            / 3.0;
        assert!((mean - by_hand).abs() < 1e-15);
    }

    #[test]
    fn resampling_items_matches_alpha_on_the_resampled_table() {
        let data = canonical();
        let prepared = PreparedAlpha::new(&data, MeasurementLevel::Ordinal);
        let draw = [10, 7, 6, 3, 3, 0, 0, 0, 2, 9, 7, 10];
        let resampled_rows: Vec<Vec<Option<f64>>> = data
            .coder_rows()
            .into_iter()
            .map(|row| draw.iter().map(|&unit| row[unit]).collect())
            .collect();
        let direct = krippendorff_alpha(
            &ReliabilityData::from_coder_rows(resampled_rows).unwrap(),
            MeasurementLevel::Ordinal,
        );
        let via_items = prepared.alpha_for_items(&draw).unwrap();
        close(via_items.alpha, direct.alpha.unwrap());
        assert_eq!(via_items.units, 12);
        assert_eq!(via_items.units_used, direct.units_used);
        assert_eq!(
            prepared.alpha_for_items(&[12]).unwrap_err(),
            ItemOutOfRange {
                position: 0,
                item: 12,
                items: 12
            }
        );
    }

    #[test]
    fn grouped_items_give_the_same_point_estimate() {
        let data = canonical();
        let items = UnitItems::new(vec![0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5], 6).unwrap();
        for level in MeasurementLevel::ALL {
            let grouped = PreparedAlpha::with_items(&data, level, &items)
                .unwrap()
                .estimate();
            let plain = krippendorff_alpha(&data, level);
            close(grouped.alpha, plain.alpha.unwrap());
        }
        let wrong = UnitItems::one_per_unit(3);
        assert!(PreparedAlpha::with_items(&data, MeasurementLevel::Nominal, &wrong).is_err());
    }

    #[test]
    fn levels_parse_and_print() {
        for level in MeasurementLevel::ALL {
            assert_eq!(level.name().parse::<MeasurementLevel>().unwrap(), level);
        }
        assert!("cardinal".parse::<MeasurementLevel>().is_err());
        assert_eq!(
            serde_json::to_string(&MeasurementLevel::Ordinal).unwrap(),
            "\"ordinal\""
        );
        let result = krippendorff_alpha(
            &rows(&[&[Some(2.0)], &[Some(2.0)]]),
            MeasurementLevel::Nominal,
        );
        let json = serde_json::to_value(&result).unwrap();
        assert_eq!(json["alpha"], serde_json::Value::Null);
        assert_eq!(json["reason"]["kind"], "no_variation");
    }
}
