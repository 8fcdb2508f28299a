//! Per-item signature tables: the visible (C) and full (F) signature sets of an item's key-frame
//! pairs, interned to bitsets so that the verifier's subset tests are a few word operations.
//!
//! The scene-graph code computes signature sets; this module only stores what it is given. An
//! [`ItemSignatures`] is built once per item (from its key frames) and can be stored with serde.

use std::collections::{BTreeMap, BTreeSet, HashMap};

use serde::{Deserialize, Serialize};

pub use crate::scene_graph::View;

/// Which ordered key-frame pairs have a visible set.
///
/// The verifier needs visible sets only along the ground-truth chain, which is the chronological
/// one whenever the ground truth has the right length; full sets are needed for every ordered
/// pair, since a forward prediction can chain frames in any order (backwards, or a frame with
/// itself after a repeated label).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VisibleCoverage {
    /// Only the transitions (i, i+1).
    Chronological,
    /// Every ordered pair, for ENACT records whose ground truth is longer than L-1.
    AllPairs,
}

/// Index of an interned signature set inside one [`ItemSignatures`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct SetId(u32);

/// What a pair lookup found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PairLookup {
    Set(SetId),
    /// ENACT raised computing this pair (or a frame is unknown).
    Raised,
    /// The table was built without this pair.
    NotCovered,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
enum Entry {
    Set(u32),
    Raised { raised: u32 },
}

/// The signature sets of one item's key frames `kf[0..L]`, interned.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "ItemSignaturesRepr", into = "ItemSignaturesRepr")]
pub struct ItemSignatures {
    key_frame_ids: Vec<String>,
    /// Distinct signature strings, sorted; bit `k` of a set stands for `signatures[k]`.
    signatures: Vec<String>,
    /// u64 words per set.
    words: usize,
    /// Distinct sets, `words` words each.
    bits: Vec<u64>,
    visible_coverage: VisibleCoverage,
    /// The visible cells, then the full cells, packed as [`Cell`]s in one allocation (one cache
    /// line or two per item). Visible, chronological: cell `i` is pair (i, i+1); visible, all
    /// pairs: cell `i * L + j` is pair (i, j). Full: cell `visible_cells + i * L + j`, the
    /// diagonal included.
    cells: Vec<u32>,
    visible_cells: usize,
    /// ENACT's exception messages for pairs that raised.
    errors: Vec<String>,
}

/// A packed table cell: a set id, or (top bit set) the index of an error message.
struct Cell;

impl Cell {
    const RAISED: u32 = 1 << 31;

    fn pack(entry: Entry) -> u32 {
        match entry {
            Entry::Set(id) => id,
            Entry::Raised { raised } => raised | Cell::RAISED,
        }
    }

    fn unpack(cell: u32) -> Entry {
        if cell & Cell::RAISED == 0 {
            Entry::Set(cell)
        } else {
            Entry::Raised {
                raised: cell & !Cell::RAISED,
            }
        }
    }
}

/// Why a stored [`ItemSignatures`] was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("invalid item signatures: {0}")]
pub struct ItemSignaturesError(String);

impl ItemSignatures {
    /// Builds the table for key frames `key_frame_ids` by asking `signature_set(from, to, view)`
    /// for every pair the verifier may need: full sets of every ordered pair (the diagonal too:
    /// ENACT diffs a frame with itself after a repeated label, which is empty for a known frame),
    /// visible sets of the pairs `coverage` names. An `Err` records that ENACT raised (or that a
    /// frame is unknown); its text is kept for display only.
    pub fn build<F>(
        key_frame_ids: &[String],
        coverage: VisibleCoverage,
        mut signature_set: F,
    ) -> ItemSignatures
    where
        F: FnMut(&str, &str, View) -> Result<BTreeSet<String>, String>,
    {
        let n = key_frame_ids.len();
        let visible_pairs: Vec<(usize, usize)> = match coverage {
            VisibleCoverage::Chronological => (1..n).map(|j| (j - 1, j)).collect(),
            VisibleCoverage::AllPairs => all_pairs(n),
        };
        let full_pairs = all_pairs(n);
        let mut raw_visible = Vec::with_capacity(visible_pairs.len());
        for &(i, j) in &visible_pairs {
            raw_visible.push(signature_set(
                &key_frame_ids[i],
                &key_frame_ids[j],
                View::Visible,
            ));
        }
        let mut raw_full = Vec::with_capacity(full_pairs.len());
        for &(i, j) in &full_pairs {
            raw_full.push(signature_set(
                &key_frame_ids[i],
                &key_frame_ids[j],
                View::Full,
            ));
        }
        let mut interner = Interner::default();
        for set in raw_visible.iter().chain(&raw_full).flatten() {
            interner.note(set);
        }
        let mut builder = TableBuilder::new(interner.finish());
        let cells = raw_visible
            .iter()
            .chain(&raw_full)
            .map(|r| Cell::pack(builder.entry(r)))
            .collect();
        ItemSignatures {
            key_frame_ids: key_frame_ids.to_vec(),
            signatures: builder.signatures,
            words: builder.words,
            bits: builder.bits,
            visible_coverage: coverage,
            cells,
            visible_cells: raw_visible.len(),
            errors: builder.errors,
        }
    }

    /// A table for an item with no key frames (used where ENACT fails before any lookup).
    pub fn empty() -> ItemSignatures {
        ItemSignatures::build(&[], VisibleCoverage::Chronological, |_, _, _| {
            Ok(BTreeSet::new())
        })
    }

    pub fn key_frame_ids(&self) -> &[String] {
        &self.key_frame_ids
    }

    pub fn key_frame_count(&self) -> usize {
        self.key_frame_ids.len()
    }

    pub fn visible_coverage(&self) -> VisibleCoverage {
        self.visible_coverage
    }

    /// The stored set of pair (from, to) as sorted strings, `Err(message)` if ENACT raised, or
    /// `None` if the table does not cover the pair.
    pub fn signature_set(
        &self,
        view: View,
        from: usize,
        to: usize,
    ) -> Option<Result<Vec<&str>, &str>> {
        match self.lookup(view, from, to) {
            PairLookup::NotCovered => None,
            PairLookup::Raised => {
                let entry = self.entry(view, from, to)?;
                match entry {
                    Entry::Raised { raised } => Some(Err(self.errors[raised as usize].as_str())),
                    Entry::Set(_) => None,
                }
            }
            PairLookup::Set(id) => {
                let words =
                    &self.bits[id.0 as usize * self.words..(id.0 as usize + 1) * self.words];
                let members = self
                    .signatures
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| words[k / 64] >> (k % 64) & 1 == 1)
                    .map(|(_, s)| s.as_str())
                    .collect();
                Some(Ok(members))
            }
        }
    }

    fn entry(&self, view: View, from: usize, to: usize) -> Option<Entry> {
        let n = self.key_frame_ids.len();
        if from >= n || to >= n {
            return None;
        }
        let cell = match (view, self.visible_coverage) {
            (View::Full, _) => self.visible_cells + from * n + to,
            (View::Visible, VisibleCoverage::AllPairs) => from * n + to,
            (View::Visible, VisibleCoverage::Chronological) if to == from + 1 => from,
            (View::Visible, VisibleCoverage::Chronological) => return None,
        };
        self.cells.get(cell).map(|&c| Cell::unpack(c))
    }

    pub(crate) fn lookup(&self, view: View, from: usize, to: usize) -> PairLookup {
        match self.entry(view, from, to) {
            None => PairLookup::NotCovered,
            Some(Entry::Set(id)) => PairLookup::Set(SetId(id)),
            Some(Entry::Raised { .. }) => PairLookup::Raised,
        }
    }

    /// `a ⊆ b`.
    pub(crate) fn is_subset(&self, a: SetId, b: SetId) -> bool {
        if a == b {
            return true;
        }
        let (a, b) = (a.0 as usize * self.words, b.0 as usize * self.words);
        (0..self.words).all(|w| self.bits[a + w] & !self.bits[b + w] == 0)
    }
}

fn all_pairs(n: usize) -> Vec<(usize, usize)> {
    (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).collect()
}

#[derive(Default)]
struct Interner {
    seen: BTreeSet<String>,
}

impl Interner {
    fn note(&mut self, set: &BTreeSet<String>) {
        for signature in set {
            if !self.seen.contains(signature) {
                self.seen.insert(signature.clone());
            }
        }
    }

    fn finish(self) -> Vec<String> {
        self.seen.into_iter().collect()
    }
}

/// Turns signature sets into deduplicated bitsets.
struct TableBuilder {
    index: BTreeMap<String, usize>,
    signatures: Vec<String>,
    words: usize,
    bits: Vec<u64>,
    distinct: HashMap<Vec<u64>, u32>,
    errors: Vec<String>,
}

impl TableBuilder {
    fn new(signatures: Vec<String>) -> TableBuilder {
        let index = signatures
            .iter()
            .enumerate()
            .map(|(k, s)| (s.clone(), k))
            .collect();
        let words = signatures.len().div_ceil(64).max(1);
        TableBuilder {
            index,
            signatures,
            words,
            bits: Vec::new(),
            distinct: HashMap::new(),
            errors: Vec::new(),
        }
    }

    fn intern_bits(&mut self, set: Vec<u64>) -> u32 {
        if let Some(&id) = self.distinct.get(&set) {
            return id;
        }
        let id = (self.bits.len() / self.words) as u32;
        self.bits.extend_from_slice(&set);
        self.distinct.insert(set, id);
        id
    }

    fn entry(&mut self, raw: &Result<BTreeSet<String>, String>) -> Entry {
        match raw {
            Ok(set) => {
                let mut words = vec![0u64; self.words];
                for signature in set {
                    if let Some(&k) = self.index.get(signature) {
                        words[k / 64] |= 1 << (k % 64);
                    }
                }
                Entry::Set(self.intern_bits(words))
            }
            Err(message) => {
                let raised = match self.errors.iter().position(|e| e == message) {
                    Some(i) => i as u32,
                    None => {
                        self.errors.push(message.clone());
                        (self.errors.len() - 1) as u32
                    }
                };
                Entry::Raised { raised }
            }
        }
    }
}

/// Storage form: sets as lists of signature indexes, which is compact for the small sets ENACT
/// produces; bitsets are rebuilt (and everything checked) on load.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct ItemSignaturesRepr {
    key_frame_ids: Vec<String>,
    signatures: Vec<String>,
    sets: Vec<Vec<u32>>,
    visible_coverage: VisibleCoverage,
    visible: Vec<Entry>,
    full: Vec<Entry>,
    errors: Vec<String>,
}

impl From<ItemSignatures> for ItemSignaturesRepr {
    fn from(table: ItemSignatures) -> Self {
        let set_count = table.bits.len() / table.words;
        let sets = (0..set_count)
            .map(|s| {
                let words = &table.bits[s * table.words..(s + 1) * table.words];
                (0..table.signatures.len() as u32)
                    .filter(|&k| words[k as usize / 64] >> (k % 64) & 1 == 1)
                    .collect()
            })
            .collect();
        let mut entries = table.cells.iter().map(|&c| Cell::unpack(c));
        let visible = entries.by_ref().take(table.visible_cells).collect();
        let full = entries.collect();
        ItemSignaturesRepr {
            key_frame_ids: table.key_frame_ids,
            signatures: table.signatures,
            sets,
            visible_coverage: table.visible_coverage,
            visible,
            full,
            errors: table.errors,
        }
    }
}

impl TryFrom<ItemSignaturesRepr> for ItemSignatures {
    type Error = ItemSignaturesError;

    fn try_from(repr: ItemSignaturesRepr) -> Result<Self, Self::Error> {
        let fail = |message: String| Err(ItemSignaturesError(message));
        if !repr.signatures.windows(2).all(|w| w[0] < w[1]) {
            return fail("signatures are not sorted and distinct".to_owned());
        }
        let n = repr.key_frame_ids.len();
        let expected_visible = match repr.visible_coverage {
            VisibleCoverage::Chronological => n.saturating_sub(1),
            VisibleCoverage::AllPairs => n * n,
        };
        if repr.visible.len() != expected_visible {
            return fail(format!(
                "{} visible entries for {n} key frames, expected {expected_visible}",
                repr.visible.len()
            ));
        }
        if repr.full.len() != n * n {
            return fail(format!(
                "{} full entries for {n} key frames, expected {}",
                repr.full.len(),
                n * n
            ));
        }
        let words = repr.signatures.len().div_ceil(64).max(1);
        let mut bits = vec![0u64; repr.sets.len() * words];
        for (s, members) in repr.sets.iter().enumerate() {
            for &k in members {
                if k as usize >= repr.signatures.len() {
                    return fail(format!(
                        "set {s} names signature {k}, only {} exist",
                        repr.signatures.len()
                    ));
                }
                bits[s * words + k as usize / 64] |= 1 << (k % 64);
            }
        }
        for entry in repr.visible.iter().chain(&repr.full) {
            match *entry {
                Entry::Set(s) if s as usize >= repr.sets.len() => {
                    return fail(format!(
                        "entry names set {s}, only {} exist",
                        repr.sets.len()
                    ));
                }
                Entry::Raised { raised } if raised as usize >= repr.errors.len() => {
                    return fail(format!(
                        "entry names error {raised}, only {} exist",
                        repr.errors.len()
                    ));
                }
                _ => {}
            }
        }
        if repr.sets.len() >= Cell::RAISED as usize || repr.errors.len() >= Cell::RAISED as usize {
            return fail("too many sets or errors".to_owned());
        }
        Ok(ItemSignatures {
            key_frame_ids: repr.key_frame_ids,
            signatures: repr.signatures,
            words,
            bits,
            visible_coverage: repr.visible_coverage,
            visible_cells: repr.visible.len(),
            cells: repr
                .visible
                .into_iter()
                .chain(repr.full)
                .map(Cell::pack)
                .collect(),
            errors: repr.errors,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(ids: &[&str]) -> Vec<String> {
        ids.iter().map(|s| s.to_string()).collect()
    }

    fn set(items: &[&str]) -> BTreeSet<String> {
        items.iter().map(|s| s.to_string()).collect()
    }

    /// A tiny world: frame b adds "open", c adds "grasp"; going back from c to a raises.
    fn toy(from: &str, to: &str, view: View) -> Result<BTreeSet<String>, String> {
        match (from, to, view) {
            (f, t, _) if f == t => Ok(set(&[])),
            ("a", "b", View::Visible) => Ok(set(&["open"])),
            ("a", "b", View::Full) => Ok(set(&["open", "light"])),
            ("b", "c", _) => Ok(set(&["grasp"])),
            ("c", "a", _) => Err("AssertionError: no parent".to_owned()),
            _ => Ok(set(&["other"])),
        }
    }

    #[test]
    fn lookups_and_subsets() {
        let table = ItemSignatures::build(
            &frames(&["a", "b", "c"]),
            VisibleCoverage::Chronological,
            toy,
        );
        let id = |view, i, j| match table.lookup(view, i, j) {
            PairLookup::Set(id) => id,
            other => panic!("({i},{j}) {other:?}"),
        };
        assert!(table.is_subset(id(View::Visible, 0, 1), id(View::Full, 0, 1)));
        assert!(!table.is_subset(id(View::Full, 0, 1), id(View::Visible, 0, 1)));
        assert!(table.is_subset(id(View::Full, 1, 1), id(View::Visible, 1, 2)));
        assert_eq!(table.lookup(View::Full, 2, 0), PairLookup::Raised);
        assert_eq!(table.lookup(View::Visible, 0, 2), PairLookup::NotCovered);
        assert_eq!(
            table.signature_set(View::Full, 0, 1),
            Some(Ok(vec!["light", "open"]))
        );
        assert_eq!(
            table.signature_set(View::Full, 2, 0),
            Some(Err("AssertionError: no parent"))
        );
        let all = ItemSignatures::build(&frames(&["a", "b", "c"]), VisibleCoverage::AllPairs, toy);
        assert_eq!(all.lookup(View::Visible, 2, 0), PairLookup::Raised);
        assert!(matches!(
            all.lookup(View::Visible, 0, 2),
            PairLookup::Set(_)
        ));
    }

    #[test]
    fn each_pair_that_raised_keeps_its_own_message() {
        let table = ItemSignatures::build(
            &frames(&["a", "b"]),
            VisibleCoverage::AllPairs,
            |f, t, _| match (f, t) {
                ("a", "b") => Err("KeyError: 'b'".to_owned()),
                ("b", "a") => Err("AssertionError: no parent".to_owned()),
                _ => Ok(BTreeSet::new()),
            },
        );
        for view in [View::Visible, View::Full] {
            assert_eq!(table.signature_set(view, 0, 1), Some(Err("KeyError: 'b'")));
            assert_eq!(
                table.signature_set(view, 1, 0),
                Some(Err("AssertionError: no parent"))
            );
        }
        // A message raised again is kept once.
        assert_eq!(table.errors.len(), 2);
    }

    #[test]
    fn wide_sets_use_several_words() {
        let many: BTreeSet<String> = (0..150).map(|k| format!("sig{k:03}")).collect();
        let some: BTreeSet<String> = many.iter().step_by(7).cloned().collect();
        // The first visible pair's set is empty, so that the sets compared below are not the
        // table's first: a subset test must find each set at its own id times the words.
        let table = ItemSignatures::build(
            &frames(&["x", "y", "z"]),
            VisibleCoverage::Chronological,
            |f, t, view| {
                Ok(match (f == t || (f, t) == ("x", "y"), view) {
                    (true, _) => BTreeSet::new(),
                    // A set only in the last word: no other set holds sig141.
                    (false, View::Full) if (f, t) == ("x", "z") => {
                        BTreeSet::from(["sig141".to_owned()])
                    }
                    (false, View::Visible) => some.clone(),
                    (false, View::Full) => many.clone(),
                })
            },
        );
        let (PairLookup::Set(last_word), PairLookup::Set(visible)) = (
            table.lookup(View::Full, 0, 2),
            table.lookup(View::Visible, 1, 2),
        ) else {
            panic!("sets expected");
        };
        // Its one member is in the third word: in the full set, not in the visible one.
        assert!(!table.is_subset(last_word, visible));
        let PairLookup::Set(full) = table.lookup(View::Full, 1, 2) else {
            panic!("a set expected");
        };
        assert!(table.is_subset(last_word, full));
        let (PairLookup::Set(v), PairLookup::Set(full)) = (
            table.lookup(View::Visible, 1, 2),
            table.lookup(View::Full, 1, 2),
        ) else {
            panic!("sets expected");
        };
        assert!(table.is_subset(v, full));
        assert!(!table.is_subset(full, v));
        assert_eq!(
            table
                .signature_set(View::Visible, 1, 2)
                .and_then(Result::ok)
                .map(|s| s.len()),
            Some(some.len())
        );
    }

    #[test]
    fn serde_round_trip_and_validation() {
        let table = ItemSignatures::build(
            &frames(&["a", "b", "c"]),
            VisibleCoverage::Chronological,
            toy,
        );
        let text = serde_json::to_string(&table).expect("serialise");
        let back: ItemSignatures = serde_json::from_str(&text).expect("deserialise");
        assert_eq!(back, table);
        let mut value: serde_json::Value = serde_json::from_str(&text).expect("json");
        value["full"] = serde_json::json!([0]);
        assert!(serde_json::from_value::<ItemSignatures>(value).is_err());
        // The signature list must be sorted and hold each once: a repeat is refused first.
        let mut repeated: serde_json::Value = serde_json::from_str(&text).expect("json");
        let first = repeated["signatures"][0].clone();
        repeated["signatures"]
            .as_array_mut()
            .expect("a list")
            .insert(0, first);
        let refused = serde_json::from_value::<ItemSignatures>(repeated).expect_err("a repeat");
        assert!(
            refused.to_string().contains("not sorted and distinct"),
            "{refused}"
        );
    }

    /// A frame index past the key frames is no pair of the table, whichever end it is.
    #[test]
    fn pairs_past_the_key_frames_are_not_covered() {
        for coverage in [VisibleCoverage::Chronological, VisibleCoverage::AllPairs] {
            let table = ItemSignatures::build(&frames(&["a", "b", "c"]), coverage, toy);
            for (from, to) in [(0, 3), (3, 0), (2, 3), (3, 3)] {
                for view in [View::Visible, View::Full] {
                    assert_eq!(
                        table.signature_set(view, from, to),
                        None,
                        "{from} {to} {view:?}"
                    );
                    assert_eq!(table.lookup(view, from, to), PairLookup::NotCovered);
                }
            }
        }
    }

    /// Tables of more than 64 signatures take several words a set, and survive being stored,
    /// with visible sets of the chronological pairs or of every pair.
    #[test]
    fn a_table_of_many_signatures_survives_a_round_trip() {
        let ids = frames(&["a", "b", "c"]);
        for coverage in [VisibleCoverage::Chronological, VisibleCoverage::AllPairs] {
            let table = ItemSignatures::build(&ids, coverage, |from, to, _| {
                // Pair (a, c) changes 70 things, the others a few of them.
                let count = match (from, to) {
                    ("a", "c") => 70,
                    (f, t) if f == t => 0,
                    _ => 3,
                };
                Ok((0..count).map(|k| format!("sig{k:02}_{from}")).collect())
            });
            let stored = serde_json::to_string(&table).expect("serialise");
            let back: ItemSignatures = serde_json::from_str(&stored).expect("read back");
            assert_eq!(back, table);
            let wide = back
                .signature_set(View::Full, 0, 2)
                .expect("covered")
                .expect("a set");
            assert_eq!(wide.len(), 70);
            assert_eq!(wide[69], "sig69_a");
        }
    }

    #[test]
    fn a_stored_table_naming_what_it_lacks_is_refused() {
        let refused = |json: &str| {
            serde_json::from_str::<ItemSignatures>(json)
                .expect_err("refused")
                .to_string()
        };
        let table = |visible: &str, full: &str, errors: &str| {
            format!(
                r#"{{"key_frame_ids": ["a", "b"], "signatures": ["s"], "sets": [[0]],
                   "visible_coverage": "chronological", "visible": {visible},
                   "full": {full}, "errors": {errors}}}"#
            )
        };
        assert!(
            serde_json::from_str::<ItemSignatures>(&table("[0]", "[0, 0, 0, 0]", "[]")).is_ok()
        );
        assert!(
            refused(&table("[0]", r#"[0, 0, 0, {"raised": 0}]"#, "[]"))
                .contains("entry names error 0, only 0 exist")
        );
        assert!(
            refused(&table("[1]", "[0, 0, 0, 0]", "[]"))
                .contains("entry names set 1, only 1 exist")
        );
        assert!(
            refused(&table("[0, 0]", "[0, 0, 0, 0]", "[]"))
                .contains("2 visible entries for 2 key frames")
        );
        assert!(
            refused(&table("[0]", "[0, 0, 0]", "[]")).contains("3 full entries for 2 key frames")
        );
    }
}
