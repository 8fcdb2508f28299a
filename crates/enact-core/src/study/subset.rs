//! Stratified subsets of a dataset (`enact-hub dataset subset`): the paper's appendix tables use
//! "a 2,304-QA subset of ENACT". A subset keeps the source's items as they are, so it is a
//! variant in the studies' sense and its comparisons with the full set are paired.
//!
//! The rule: items are grouped into strata by the chosen fields (direction, step length, task);
//! each stratum gets its share of the size ([`Allocation`]), and its items are drawn uniformly
//! without replacement by ChaCha8 seeded with sha256(seed, stratum). The chosen items keep the
//! source's order.

use std::collections::BTreeMap;

use rand::SeedableRng;
use rand::seq::index::sample;
use rand_chacha::ChaCha8Rng;
use schemars::JsonSchema;
use serde::Serialize;
use sha2::{Digest, Sha256};

use crate::dataset::{Direction, StepLength};

/// A field items are stratified by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum StratumField {
    Direction,
    StepLength,
    Task,
}

impl StratumField {
    const ALL: [StratumField; 3] = [
        StratumField::Direction,
        StratumField::StepLength,
        StratumField::Task,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            StratumField::Direction => "direction",
            StratumField::StepLength => "step_length",
            StratumField::Task => "task",
        }
    }

    /// `direction`, `step_length` or `task`.
    pub fn parse(name: &str) -> Option<StratumField> {
        Self::ALL.into_iter().find(|f| f.as_str() == name.trim())
    }

    /// A comma-separated list (`direction,step_length`), each field once.
    pub fn parse_list(text: &str) -> Result<Vec<StratumField>, String> {
        let mut fields = Vec::new();
        for part in text.split(',') {
            let field = StratumField::parse(part).ok_or_else(|| {
                format!(
                    "unknown stratum field {:?} (use direction, step_length or task)",
                    part.trim()
                )
            })?;
            if fields.contains(&field) {
                return Err(format!("stratum field {:?} is given twice", part.trim()));
            }
            fields.push(field);
        }
        Ok(fields)
    }
}

/// How the size is shared among the strata.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Allocation {
    /// In proportion to each stratum's items; the seats left by rounding down go to the
    /// largest remainders (ties to the first stratum in order).
    #[default]
    Proportional,
    /// The same number per stratum (the paper's 2,304 = 16 × 144); the size must divide
    /// evenly and every stratum must have its share.
    Equal,
}

impl Allocation {
    pub fn parse(name: &str) -> Option<Allocation> {
        match name {
            "proportional" => Some(Allocation::Proportional),
            "equal" => Some(Allocation::Equal),
            _ => None,
        }
    }
}

/// What the rule reads of an item.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SubsetCandidate<'a> {
    pub direction: Direction,
    pub step_length: StepLength,
    pub task_name: &'a str,
}

/// One stratum: its values (in the order of the fields), the source's items in it, the chosen.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, JsonSchema)]
pub struct StratumCount {
    pub stratum: Vec<String>,
    pub available: usize,
    pub chosen: usize,
}

/// A subset: indices into the candidates, in source order, and the strata's counts.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Subset {
    pub chosen: Vec<usize>,
    pub strata: Vec<StratumCount>,
}

fn stratum_of(fields: &[StratumField], item: &SubsetCandidate<'_>) -> Vec<String> {
    fields
        .iter()
        .map(|f| match f {
            StratumField::Direction => item.direction.as_str().to_owned(),
            StratumField::StepLength => item.step_length.get().to_string(),
            StratumField::Task => item.task_name.to_owned(),
        })
        .collect()
}

/// Draws a stratified subset of `size` items; refuses (saying which stratum) what the rule
/// cannot give.
pub fn stratified_subset(
    candidates: &[SubsetCandidate<'_>],
    fields: &[StratumField],
    size: usize,
    allocation: Allocation,
    seed: u64,
) -> Result<Subset, String> {
    if size == 0 {
        return Err("a subset needs a size of at least 1".to_owned());
    }
    if size > candidates.len() {
        return Err(format!(
            "a subset of {size} items from {} items: the size is larger than the source",
            candidates.len()
        ));
    }
    // Strata sorted by their values (step lengths as numbers).
    let mut strata: BTreeMap<Vec<(u8, String)>, Vec<usize>> = BTreeMap::new();
    for (index, item) in candidates.iter().enumerate() {
        let key = stratum_of(fields, item)
            .into_iter()
            .zip(fields)
            .map(|(value, field)| match field {
                StratumField::StepLength => (item.step_length.get(), value),
                _ => (0, value),
            })
            .collect();
        strata.entry(key).or_default().push(index);
    }
    let sizes: Vec<usize> = strata.values().map(Vec::len).collect();
    let names: Vec<Vec<String>> = strata
        .keys()
        .map(|k| k.iter().map(|(_, v)| v.clone()).collect())
        .collect();
    let shares = match allocation {
        Allocation::Proportional => proportional(&sizes, size),
        Allocation::Equal => {
            let n = sizes.len();
            if !size.is_multiple_of(n) {
                return Err(format!(
                    "{size} items cannot be shared equally among {n} strata"
                ));
            }
            let share = size / n;
            if let Some(i) = sizes.iter().position(|&s| s < share) {
                return Err(format!(
                    "stratum {} has {} items, fewer than its equal share of {share}",
                    names[i].join(" "),
                    sizes[i]
                ));
            }
            vec![share; n]
        }
    };
    let mut chosen = Vec::with_capacity(size);
    let mut counts = Vec::with_capacity(sizes.len());
    for ((members, share), name) in strata.values().zip(&shares).zip(names) {
        let mut hasher = Sha256::new();
        hasher.update(b"stratified-subset\0");
        hasher.update(seed.to_le_bytes());
        for value in &name {
            hasher.update(value.as_bytes());
            hasher.update([0u8]);
        }
        let mut rng = ChaCha8Rng::from_seed(hasher.finalize().into());
        chosen.extend(
            sample(&mut rng, members.len(), *share)
                .into_iter()
                .map(|i| members[i]),
        );
        counts.push(StratumCount {
            stratum: name,
            available: members.len(),
            chosen: *share,
        });
    }
    chosen.sort_unstable();
    Ok(Subset {
        chosen,
        strata: counts,
    })
}

/// Largest-remainder shares of `size` in proportion to `sizes` (which sum to at least `size`).
fn proportional(sizes: &[usize], size: usize) -> Vec<usize> {
    let total: usize = sizes.iter().sum();
    let mut shares: Vec<usize> = sizes.iter().map(|&s| s * size / total).collect();
    let mut order: Vec<usize> = (0..sizes.len()).collect();
    // Remainder of s·size/total, compared exactly as s·size mod total.
    order.sort_by_key(|&i| (std::cmp::Reverse(sizes[i] * size % total), i));
    let mut left = size - shares.iter().sum::<usize>();
    for i in order {
        if left == 0 {
            break;
        }
        if shares[i] < sizes[i] {
            shares[i] += 1;
            left -= 1;
        }
    }
    shares
}

#[cfg(test)]
mod tests {
    use super::*;

    fn candidates(per_cell: &[(Direction, usize, usize)]) -> Vec<SubsetCandidate<'static>> {
        let mut out = Vec::new();
        for &(direction, l, n) in per_cell {
            for k in 0..n {
                out.push(SubsetCandidate {
                    direction,
                    step_length: StepLength::new(l).unwrap(),
                    task_name: if k % 2 == 0 { "a" } else { "b" },
                });
            }
        }
        out
    }

    const F: Direction = Direction::Forward;
    const I: Direction = Direction::Inverse;

    #[test]
    fn strata_counts_follow_the_allocation() {
        let items = candidates(&[(F, 3, 50), (F, 10, 30), (I, 3, 20)]);
        let fields = StratumField::parse_list("direction,step_length").unwrap();
        let s = stratified_subset(&items, &fields, 10, Allocation::Proportional, 1).unwrap();
        let counts: Vec<(Vec<String>, usize, usize)> = s
            .strata
            .iter()
            .map(|c| (c.stratum.clone(), c.available, c.chosen))
            .collect();
        // 50:30:20 of 10 is 5:3:2; L = 3 sorts before L = 10.
        assert_eq!(
            counts,
            [
                (vec!["forward".to_owned(), "3".to_owned()], 50, 5),
                (vec!["forward".to_owned(), "10".to_owned()], 30, 3),
                (vec!["inverse".to_owned(), "3".to_owned()], 20, 2),
            ]
        );
        assert_eq!(s.chosen.len(), 10);
        assert!(s.chosen.windows(2).all(|w| w[0] < w[1]), "source order");
        // Each chosen item is in its stratum's range of the source.
        assert_eq!(s.chosen.iter().filter(|&&i| i < 50).count(), 5);
        assert_eq!(
            s.chosen.iter().filter(|&&i| (50..80).contains(&i)).count(),
            3
        );
        // Deterministic by seed; another seed draws other items, same counts.
        let again = stratified_subset(&items, &fields, 10, Allocation::Proportional, 1).unwrap();
        assert_eq!(again, s);
        let other = stratified_subset(&items, &fields, 10, Allocation::Proportional, 2).unwrap();
        assert_ne!(other.chosen, s.chosen);
        assert_eq!(other.strata, s.strata);
    }

    #[test]
    fn largest_remainders_fill_the_rounding() {
        // 3 strata of 1/3 each: 10 = 3 + 3 + 3 + 1 to the first.
        assert_eq!(proportional(&[7, 7, 7], 10), [4, 3, 3]);
        assert_eq!(proportional(&[1, 99], 3), [0, 3]);
        assert_eq!(proportional(&[5, 5], 10), [5, 5]);
    }

    #[test]
    fn equal_allocation_and_its_refusals() {
        let items = candidates(&[(F, 3, 10), (F, 4, 6), (I, 3, 9), (I, 4, 8)]);
        let fields = StratumField::parse_list("direction, step_length").unwrap();
        let s = stratified_subset(&items, &fields, 24, Allocation::Equal, 5).unwrap();
        assert!(s.strata.iter().all(|c| c.chosen == 6));
        let err = stratified_subset(&items, &fields, 28, Allocation::Equal, 5).unwrap_err();
        assert_eq!(
            err,
            "stratum forward 4 has 6 items, fewer than its equal share of 7"
        );
        assert!(
            stratified_subset(&items, &fields, 10, Allocation::Equal, 5)
                .unwrap_err()
                .contains("equally among 4 strata")
        );
        assert!(
            stratified_subset(&items, &fields, 34, Allocation::Proportional, 5)
                .unwrap_err()
                .contains("larger than the source")
        );
        assert!(
            StratumField::parse_list("direction,colour")
                .unwrap_err()
                .contains("colour")
        );
        assert!(
            StratumField::parse_list("task,task")
                .unwrap_err()
                .contains("twice")
        );
    }
}
