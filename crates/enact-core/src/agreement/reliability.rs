//! Reliability data: the coders × units table of values that agreement is computed from, and
//! the grouping of units into items that the bootstrap resamples.

use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::fmt::Display;
use std::hash::Hash;

use serde::Serialize;

/// Values assigned by `coders` coders to `units` units; a cell is `None` where a coder gave no
/// value. Every present value is finite.
#[derive(Debug, Clone, PartialEq)]
pub struct ReliabilityData {
    coders: usize,
    units: usize,
    /// Unit-major (`cells[unit * coders + coder]`) because alpha walks the data unit by unit.
    cells: Vec<Option<f64>>,
}

/// Why a table of values could not be turned into [`ReliabilityData`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReliabilityDataError {
    #[error("reliability data needs at least one coder")]
    NoCoders,
    #[error(
        "coder {coder} has {found} values but coder 0 has {expected}; \
         every coder needs one entry (a value or a missing mark) per unit"
    )]
    UnequalLength {
        coder: usize,
        found: usize,
        expected: usize,
    },
    #[error("coder {coder}, unit {unit}: {value} is not a finite number")]
    NonFiniteValue {
        coder: usize,
        unit: String,
        value: f64,
    },
    #[error("coder {coder}, unit {unit}: coder index out of range, the data has {coders} coders")]
    CoderOutOfRange {
        coder: usize,
        unit: String,
        coders: usize,
    },
    #[error("coder {coder}, unit {unit}: a second value for the same unit")]
    DuplicateValue { coder: usize, unit: String },
}

/// Reliability data whose units were given by key; `unit_keys[u]` is the key of unit `u`.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyedReliability<K> {
    pub data: ReliabilityData,
    pub unit_keys: Vec<K>,
}

impl ReliabilityData {
    /// Builds the table from one row per coder, each with one entry per unit.
    pub fn from_coder_rows(rows: Vec<Vec<Option<f64>>>) -> Result<Self, ReliabilityDataError> {
        let coders = rows.len();
        let Some(first) = rows.first() else {
            return Err(ReliabilityDataError::NoCoders);
        };
        let units = first.len();
        let mut cells = vec![None; units * coders];
        for (coder, row) in rows.iter().enumerate() {
            if row.len() != units {
                return Err(ReliabilityDataError::UnequalLength {
                    coder,
                    found: row.len(),
                    expected: units,
                });
            }
            for (unit, value) in row.iter().enumerate() {
                if let Some(value) = *value {
                    cells[unit * coders + coder] = Some(finite(value, coder, || unit.to_string())?);
                }
            }
        }
        Ok(Self {
            coders,
            units,
            cells,
        })
    }

    /// Builds the table from `(coder, unit key, value)` entries, for data that is naturally
    /// addressed by id (an item id, or an item id and a position within it). Units are numbered
    /// in the order their key first appears; a coder with no entry for a unit is missing there,
    /// and so is an entry whose value is `None`.
    pub fn from_keyed_values<K, I>(
        coders: usize,
        entries: I,
    ) -> Result<KeyedReliability<K>, ReliabilityDataError>
    where
        K: Clone + Eq + Hash + Display,
        I: IntoIterator<Item = (usize, K, Option<f64>)>,
    {
        if coders == 0 {
            return Err(ReliabilityDataError::NoCoders);
        }
        let mut unit_of_key: HashMap<K, usize> = HashMap::new();
        let mut unit_keys: Vec<K> = Vec::new();
        let mut cells: Vec<Option<f64>> = Vec::new();
        // Tracks which (unit, coder) cells were given, so a repeated `None` is caught too.
        let mut given: Vec<bool> = Vec::new();
        for (coder, key, value) in entries {
            if coder >= coders {
                return Err(ReliabilityDataError::CoderOutOfRange {
                    coder,
                    unit: key.to_string(),
                    coders,
                });
            }
            let unit = match unit_of_key.entry(key.clone()) {
                Entry::Occupied(slot) => *slot.get(),
                Entry::Vacant(slot) => {
                    let unit = unit_keys.len();
                    slot.insert(unit);
                    unit_keys.push(key.clone());
                    cells.resize(cells.len() + coders, None);
                    given.resize(given.len() + coders, false);
                    unit
                }
            };
            let cell = unit * coders + coder;
            if given[cell] {
                return Err(ReliabilityDataError::DuplicateValue {
                    coder,
                    unit: key.to_string(),
                });
            }
            given[cell] = true;
            if let Some(value) = value {
                cells[cell] = Some(finite(value, coder, || key.to_string())?);
            }
        }
        Ok(KeyedReliability {
            data: Self {
                coders,
                units: unit_keys.len(),
                cells,
            },
            unit_keys,
        })
    }

    /// Builds the table from unit-major cells that the caller has already checked to be finite.
    pub(crate) fn from_checked_unit_major(
        coders: usize,
        units: usize,
        cells: Vec<Option<f64>>,
    ) -> Self {
        debug_assert_eq!(cells.len(), coders * units);
        debug_assert!(cells.iter().flatten().all(|value| value.is_finite()));
        Self {
            coders,
            units,
            cells,
        }
    }

    pub fn coders(&self) -> usize {
        self.coders
    }

    pub fn units(&self) -> usize {
        self.units
    }

    /// The value `coder` gave to `unit`, or `None` when missing or out of range.
    pub fn value(&self, coder: usize, unit: usize) -> Option<f64> {
        if coder >= self.coders || unit >= self.units {
            return None;
        }
        self.cells[unit * self.coders + coder]
    }

    /// Every coder's entry for `unit`, in coder order (empty when `unit` is out of range).
    pub fn unit_values(&self, unit: usize) -> &[Option<f64>] {
        if unit >= self.units {
            return &[];
        }
        &self.cells[unit * self.coders..(unit + 1) * self.coders]
    }

    /// One row per coder, the shape [`ReliabilityData::from_coder_rows`] takes.
    pub fn coder_rows(&self) -> Vec<Vec<Option<f64>>> {
        (0..self.coders)
            .map(|coder| {
                (0..self.units)
                    .map(|unit| self.value(coder, unit))
                    .collect()
            })
            .collect()
    }

    /// The same units seen only through the listed coders (in the order listed); indices out
    /// of range are skipped.
    pub fn select_coders(&self, coders: &[usize]) -> Self {
        let kept: Vec<usize> = coders
            .iter()
            .copied()
            .filter(|&coder| coder < self.coders)
            .collect();
        let mut cells = Vec::with_capacity(kept.len() * self.units);
        for unit in 0..self.units {
            let row = self.unit_values(unit);
            cells.extend(kept.iter().map(|&coder| row[coder]));
        }
        Self {
            coders: kept.len(),
            units: self.units,
            cells,
        }
    }
}

fn finite(
    value: f64,
    coder: usize,
    unit: impl FnOnce() -> String,
) -> Result<f64, ReliabilityDataError> {
    if value.is_finite() {
        // Adding +0.0 folds -0.0 into 0.0, so the two never count as different values.
        Ok(value + 0.0)
    } else {
        Err(ReliabilityDataError::NonFiniteValue {
            coder,
            unit: unit(),
            value,
        })
    }
}

/// Which item each unit belongs to. The bootstrap resamples items, so all units of an item
/// (for instance every position of one ordering) are drawn together.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct UnitItems {
    item_of_unit: Vec<usize>,
    items: usize,
}

/// Why a unit-to-item assignment was rejected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum UnitItemsError {
    #[error("unit {unit} is assigned to item {item}, but there are only {items} items")]
    ItemOutOfRange {
        unit: usize,
        item: usize,
        items: usize,
    },
    #[error("the item assignment covers {assigned} units but the reliability data has {units}")]
    UnitCountMismatch { assigned: usize, units: usize },
}

impl UnitItems {
    /// Every unit is its own item: the plain unit bootstrap.
    pub fn one_per_unit(units: usize) -> Self {
        Self {
            item_of_unit: (0..units).collect(),
            items: units,
        }
    }

    /// `item_of_unit[u]` is the item of unit `u`. Items that own no unit are allowed: they are
    /// still drawn by the bootstrap and contribute nothing, just as an unanswered item would.
    pub fn new(item_of_unit: Vec<usize>, items: usize) -> Result<Self, UnitItemsError> {
        if let Some((unit, &item)) = item_of_unit
            .iter()
            .enumerate()
            .find(|&(_, &item)| item >= items)
        {
            return Err(UnitItemsError::ItemOutOfRange { unit, item, items });
        }
        Ok(Self {
            item_of_unit,
            items,
        })
    }

    /// Groups keyed units by the item `item_of` names; items are numbered in order of first
    /// appearance and returned alongside.
    pub fn group_units<K, T>(unit_keys: &[K], item_of: impl Fn(&K) -> T) -> (Self, Vec<T>)
    where
        T: Clone + Eq + Hash,
    {
        let mut index_of: HashMap<T, usize> = HashMap::new();
        let mut item_keys: Vec<T> = Vec::new();
        let item_of_unit = unit_keys
            .iter()
            .map(|key| {
                let item = item_of(key);
                *index_of.entry(item.clone()).or_insert_with(|| {
                    item_keys.push(item);
                    item_keys.len() - 1
                })
            })
            .collect();
        let items = item_keys.len();
        (
            Self {
                item_of_unit,
                items,
            },
            item_keys,
        )
    }

    pub fn items(&self) -> usize {
        self.items
    }

    pub fn units(&self) -> usize {
        self.item_of_unit.len()
    }

    pub fn item_of_unit(&self) -> &[usize] {
        &self.item_of_unit
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_stored_and_read_back() {
        let data = ReliabilityData::from_coder_rows(vec![
            vec![Some(1.0), None],
            vec![Some(2.0), Some(3.0)],
        ])
        .unwrap();
        assert_eq!((data.coders(), data.units()), (2, 2));
        assert_eq!(data.value(0, 1), None);
        assert_eq!(data.value(1, 1), Some(3.0));
        // Out of range on either side: nothing, not another cell.
        assert_eq!(data.value(0, 2), None);
        assert_eq!(data.value(2, 1), None);
        assert_eq!(data.unit_values(0), &[Some(1.0), Some(2.0)]);
        assert_eq!(
            data.coder_rows(),
            vec![vec![Some(1.0), None], vec![Some(2.0), Some(3.0)]]
        );
    }

    #[test]
    fn unequal_rows_name_the_coder() {
        let err = ReliabilityData::from_coder_rows(vec![vec![Some(1.0); 3], vec![Some(1.0); 2]])
            .unwrap_err();
        assert_eq!(
            err,
            ReliabilityDataError::UnequalLength {
                coder: 1,
                found: 2,
                expected: 3
            }
        );
        assert!(err.to_string().contains("coder 1 has 2 values"));
    }

    #[test]
    fn non_finite_values_name_coder_and_unit() {
        let err = ReliabilityData::from_coder_rows(vec![
            vec![Some(1.0), Some(2.0)],
            vec![Some(1.0), Some(f64::NAN)],
        ])
        .unwrap_err();
        assert!(matches!(
            err,
            ReliabilityDataError::NonFiniteValue { coder: 1, ref unit, .. } if unit == "1"
        ));
        assert_eq!(
            ReliabilityData::from_coder_rows(vec![]).unwrap_err(),
            ReliabilityDataError::NoCoders
        );
    }

    #[test]
    fn negative_zero_is_zero() {
        let data = ReliabilityData::from_coder_rows(vec![vec![Some(-0.0)]]).unwrap();
        assert!(data.value(0, 0).unwrap().is_sign_positive());
    }

    #[test]
    fn keyed_values_number_units_by_first_appearance() {
        let keyed = ReliabilityData::from_keyed_values(
            2,
            vec![
                (0, "item-b", Some(1.0)),
                (1, "item-a", Some(2.0)),
                (1, "item-b", None),
                (0, "item-a", Some(3.0)),
            ],
        )
        .unwrap();
        assert_eq!(keyed.unit_keys, vec!["item-b", "item-a"]);
        assert_eq!(
            keyed.data.coder_rows(),
            vec![vec![Some(1.0), Some(3.0)], vec![None, Some(2.0)]]
        );
    }

    #[test]
    fn keyed_values_reject_duplicates_and_bad_coders() {
        let duplicate =
            ReliabilityData::from_keyed_values(2, vec![(0, "x", None), (0, "x", Some(1.0))])
                .unwrap_err();
        assert_eq!(
            duplicate,
            ReliabilityDataError::DuplicateValue {
                coder: 0,
                unit: "x".into()
            }
        );
        let out_of_range =
            ReliabilityData::from_keyed_values(2, vec![(2, "x", Some(1.0))]).unwrap_err();
        assert!(out_of_range.to_string().contains("coder 2, unit x"));
    }

    #[test]
    fn select_coders_keeps_units() {
        let data = ReliabilityData::from_coder_rows(vec![
            vec![Some(1.0), Some(2.0)],
            vec![Some(3.0), None],
            vec![Some(5.0), Some(6.0)],
        ])
        .unwrap();
        let pair = data.select_coders(&[2, 0]);
        assert_eq!(
            pair.coder_rows(),
            vec![vec![Some(5.0), Some(6.0)], vec![Some(1.0), Some(2.0)]]
        );
        // An index one past the last coder is out of range too, and skipped.
        let kept = data.select_coders(&[1, 3, 4]);
        assert_eq!(kept.coder_rows(), vec![vec![Some(3.0), None]]);
    }

    #[test]
    fn unit_items_validate_and_group() {
        assert_eq!(
            UnitItems::new(vec![0, 2], 2).unwrap_err(),
            UnitItemsError::ItemOutOfRange {
                unit: 1,
                item: 2,
                items: 2
            }
        );
        let keys = [("q1", 1), ("q1", 2), ("q2", 1), ("q1", 3)];
        let (items, names) = UnitItems::group_units(&keys, |key| key.0);
        assert_eq!(items.item_of_unit(), &[0, 0, 1, 0]);
        assert_eq!(names, vec!["q1", "q2"]);
        assert_eq!(UnitItems::one_per_unit(3).items(), 3);
    }
}
