//! Human annotation, the parts without HTTP or SQL: credentials, the balanced split of a dataset
//! over annotators, the draft an annotator is working on, and the scoring of submitted answers
//! into the same report models get.

use std::collections::BTreeMap;

use argon2::Argon2;
use argon2::password_hash::{PasswordHash, PasswordHasher, PasswordVerifier, SaltString};
use rand::RngCore;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::core::dataset::{Direction, StepLength};
use crate::core::verifier::{ItemSignatures, ParsedAnswer, Permutation, ScoredEntry, verify};

/// Shortest password accepted when an invite is used.
pub const MIN_PASSWORD_CHARS: usize = 10;

/// A fresh random token (256 bits, hex): session cookies, invite links, CSRF tokens.
pub fn new_token() -> String {
    let mut bytes = [0u8; 32];
    rand::rng().fill_bytes(&mut bytes);
    hex::encode(bytes)
}

/// What the store keeps of a token: its sha256, so a leaked database opens no session.
pub fn token_hash(token: &str) -> String {
    hex::encode(Sha256::digest(token.as_bytes()))
}

/// Constant-time comparison of two tokens, so timing does not reveal a CSRF token prefix.
pub fn tokens_equal(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// argon2id with the crate's default cost. Slow on purpose: call it from `spawn_blocking`.
pub fn hash_password(password: &str) -> Result<String, argon2::password_hash::Error> {
    let mut salt = [0u8; 16];
    rand::rng().fill_bytes(&mut salt);
    let salt = SaltString::encode_b64(&salt)?;
    Ok(Argon2::default()
        .hash_password(password.as_bytes(), &salt)?
        .to_string())
}

/// Whether `password` matches a stored PHC string. Slow on purpose: call it from `spawn_blocking`.
pub fn verify_password(password: &str, stored: &str) -> bool {
    PasswordHash::new(stored).is_ok_and(|hash| {
        Argon2::default()
            .verify_password(password.as_bytes(), &hash)
            .is_ok()
    })
}

/// Why a new password is refused.
pub fn password_problem(password: &str) -> Option<String> {
    let chars = password.chars().count();
    (chars < MIN_PASSWORD_CHARS)
        .then(|| format!("the password has {chars} characters; use at least {MIN_PASSWORD_CHARS}"))
}

/// An item to deal out: its store id and its kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SplitItem {
    pub item: i64,
    pub direction: Direction,
    pub step_length: StepLength,
}

/// Deals `items` over `annotators` disjointly so that every annotator gets the same number of
/// items of each direction × step length, ±1, and the same total, ±1. Items keep their order
/// within a kind; returns `(annotator, item)` pairs.
pub fn balanced_split(items: &[SplitItem], annotators: &[i64]) -> Vec<(i64, i64)> {
    if annotators.is_empty() {
        return Vec::new();
    }
    let mut by_kind: BTreeMap<(Direction, StepLength), Vec<i64>> = BTreeMap::new();
    for it in items {
        by_kind
            .entry((it.direction, it.step_length))
            .or_default()
            .push(it.item);
    }
    // One running counter across kinds: each kind's remainder goes to the annotators who got
    // the fewest so far, which keeps the totals balanced too.
    let mut next = 0usize;
    let mut out = Vec::with_capacity(items.len());
    for kind_items in by_kind.values() {
        for &item in kind_items {
            out.push((annotators[next % annotators.len()], item));
            next += 1;
        }
    }
    out
}

/// Interaction counts the item page reports with each change.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct InteractionCounts {
    pub placements: u32,
    pub swaps: u32,
    pub clears: u32,
    pub undos: u32,
}

/// The half-placed answer of an item: one slot per transition, each a label or empty.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Draft {
    pub slots: Vec<Option<u8>>,
    pub counts: InteractionCounts,
    /// Earlier slot states, oldest first, so undo survives a reload.
    #[serde(default)]
    pub history: Vec<Vec<Option<u8>>>,
}

/// Undo steps kept per item.
pub const MAX_HISTORY: usize = 200;

impl Draft {
    pub fn empty(step_length: StepLength) -> Draft {
        Draft {
            slots: vec![None; step_length.actions()],
            counts: InteractionCounts::default(),
            history: Vec::new(),
        }
    }

    /// Checks a draft sent by the page against the item: L-1 slots, labels in 1..L-1, none twice.
    pub fn check(&self, step_length: StepLength) -> Result<(), String> {
        let n = step_length.actions();
        check_slots("slots", &self.slots, n)?;
        if self.history.len() > MAX_HISTORY {
            return Err(format!(
                "history: {} entries; at most {MAX_HISTORY}",
                self.history.len()
            ));
        }
        for (i, h) in self.history.iter().enumerate() {
            check_slots(&format!("history[{i}]"), h, n)?;
        }
        Ok(())
    }

    pub fn has_placement(&self) -> bool {
        self.slots.iter().any(Option::is_some)
    }

    /// The answer, when every slot is filled.
    pub fn answer(&self) -> Option<Permutation> {
        let labels: Option<Vec<u8>> = self.slots.iter().copied().collect();
        labels.and_then(|l| Permutation::new(l).ok())
    }
}

fn check_slots(field: &str, slots: &[Option<u8>], n: usize) -> Result<(), String> {
    if slots.len() != n {
        return Err(format!(
            "{field}: {} slots given, this item has {n}",
            slots.len()
        ));
    }
    let mut seen = vec![false; n + 1];
    for (i, label) in slots.iter().enumerate() {
        let Some(label) = label else { continue };
        let index = usize::from(*label);
        if index == 0 || index > n {
            return Err(format!("{field}[{i}]: label {label} is not in 1..{n}"));
        }
        if seen[index] {
            return Err(format!("{field}[{i}]: label {label} is placed twice"));
        }
        seen[index] = true;
    }
    Ok(())
}

/// One submitted human answer with what scoring needs of its item.
#[derive(Debug, Clone)]
pub struct HumanAnswer {
    pub direction: Direction,
    pub step_length: StepLength,
    pub ground_truth: Permutation,
    pub answer: Permutation,
    pub signatures: Option<ItemSignatures>,
}

/// Scores human answers with the verifier models are scored with. Every answer is one entry (an
/// item answered by two people counts twice); an answer the verifier cannot judge is an error
/// naming its position.
pub fn human_entries(answers: &[HumanAnswer]) -> Result<Vec<ScoredEntry>, String> {
    answers
        .iter()
        .enumerate()
        .map(|(i, a)| {
            let verdict = verify(
                a.direction,
                &a.ground_truth,
                &ParsedAnswer::from(&a.answer),
                a.signatures.as_ref(),
            )
            .map_err(|e| format!("answer {i}: {e}"))?;
            Ok(ScoredEntry {
                group: Some(a.direction),
                states: a.step_length.states(),
                task_accuracy: verdict.task_accuracy,
                pairwise_accuracy: verdict.pairwise_accuracy.value(),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l(n: usize) -> StepLength {
        StepLength::new(n).expect("valid L")
    }

    #[test]
    fn split_is_disjoint_and_balanced_per_kind() {
        let mut items = Vec::new();
        let mut id = 0;
        for (direction, n, count) in [
            (Direction::Forward, 3, 5),
            (Direction::Inverse, 3, 4),
            (Direction::Forward, 10, 3),
        ] {
            for _ in 0..count {
                id += 1;
                items.push(SplitItem {
                    item: id,
                    direction,
                    step_length: l(n),
                });
            }
        }
        let pairs = balanced_split(&items, &[100, 200]);
        assert_eq!(pairs.len(), items.len());
        let mut seen: Vec<i64> = pairs.iter().map(|p| p.1).collect();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), items.len(), "an item was dealt twice");
        let kind = |item: i64| {
            let it = items.iter().find(|i| i.item == item).expect("item");
            (it.direction, it.step_length)
        };
        for k in [
            (Direction::Forward, l(3)),
            (Direction::Inverse, l(3)),
            (Direction::Forward, l(10)),
        ] {
            let per: Vec<usize> = [100, 200]
                .iter()
                .map(|a| {
                    pairs
                        .iter()
                        .filter(|(who, item)| who == a && kind(*item) == k)
                        .count()
                })
                .collect();
            assert!(per[0].abs_diff(per[1]) <= 1, "{k:?}: {per:?}");
        }
        let totals: Vec<usize> = [100, 200]
            .iter()
            .map(|a| pairs.iter().filter(|(who, _)| who == a).count())
            .collect();
        assert_eq!(totals, vec![6, 6]);
        assert!(balanced_split(&items, &[]).is_empty());
    }

    #[test]
    fn drafts_are_checked_against_the_item() {
        let mut d = Draft::empty(l(4));
        assert_eq!(d.check(l(4)), Ok(()));
        assert!(d.answer().is_none());
        d.slots = vec![Some(2), None, Some(2)];
        assert_eq!(
            d.check(l(4)).expect_err("repeat"),
            "slots[2]: label 2 is placed twice"
        );
        d.slots = vec![Some(4), None, None];
        assert_eq!(
            d.check(l(4)).expect_err("range"),
            "slots[0]: label 4 is not in 1..3"
        );
        d.slots = vec![None, None];
        assert_eq!(
            d.check(l(4)).expect_err("length"),
            "slots: 2 slots given, this item has 3"
        );
        d.slots = vec![Some(3), Some(1), Some(2)];
        assert_eq!(d.answer().expect("full").labels(), &[3, 1, 2]);
    }

    #[test]
    fn passwords_and_tokens() {
        let hash = hash_password("correct horse").expect("hash");
        assert!(verify_password("correct horse", &hash));
        assert!(!verify_password("wrong horse", &hash));
        assert!(!verify_password("correct horse", "not a phc string"));
        assert!(password_problem("short").is_some());
        assert!(password_problem("long enough!").is_none());
        let (a, b) = (new_token(), new_token());
        assert_eq!(a.len(), 64);
        assert_ne!(a, b);
        assert!(tokens_equal(&a, &a.clone()));
        assert!(!tokens_equal(&a, &b));
        assert_ne!(token_hash(&a), a);
    }

    #[test]
    fn human_answers_are_scored_like_model_answers() {
        let gt = Permutation::new(vec![2, 1]).expect("gt");
        let answers = [
            HumanAnswer {
                direction: Direction::Forward,
                step_length: l(3),
                ground_truth: gt.clone(),
                answer: gt.clone(),
                signatures: None,
            },
            HumanAnswer {
                direction: Direction::Inverse,
                step_length: l(3),
                ground_truth: gt.clone(),
                answer: Permutation::new(vec![1, 2]).expect("answer"),
                signatures: None,
            },
        ];
        let entries = human_entries(&answers).expect("scored");
        assert!(entries[0].task_accuracy);
        assert_eq!(entries[0].pairwise_accuracy, Some(1.0));
        assert!(!entries[1].task_accuracy);
        let report = crate::core::verifier::PerformanceReport::from_entries(&entries);
        assert_eq!(report.overall.expect("overall").totals.task_accuracy, 0.5);
    }
}
