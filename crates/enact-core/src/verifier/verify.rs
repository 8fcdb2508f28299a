//! Per-item scoring: ENACT's `verify_forward` / `verify_inverse`, Python semantics included.
//!
//! ENACT wraps part of each verifier in `try/except`. An exception inside it is swallowed
//! (semantic match false, pairwise accuracy the int 0); an exception outside it skips the item
//! as `evaluation_error`. Which operations sit where decides the score of odd answers, so this
//! module replays the same operations in the same regions: Python list indexing (0 is the
//! current state, negative indexes wrap), `x - 1` on labels of any type, `0 <= x < n` filters.

use std::borrow::Cow;
use std::cmp::Ordering;

use serde::{Deserialize, Serialize};

use crate::dataset::Direction;
use crate::verifier::answer::{ParsedAnswer, Permutation};
use crate::verifier::pyint::PyInt;
use crate::verifier::pyjson::{Number, PyValue, small_labels};
use crate::verifier::signatures::{ItemSignatures, PairLookup, SetId, View};

/// ENACT's pairwise accuracy, keeping the Python type it has in ENACT's output.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "value", rename_all = "snake_case")]
pub enum PairwiseAccuracy {
    /// The int `1` ENACT sets whenever task accuracy is true.
    IntOne,
    /// The int `0` ENACT leaves when its try block raised.
    IntZero,
    /// A computed ratio (`0.0` included).
    Float(f64),
    /// Exact-only scoring without scene graphs, answer not exact: no partial credit is known.
    Unavailable,
}

impl PairwiseAccuracy {
    pub fn value(self) -> Option<f64> {
        match self {
            PairwiseAccuracy::IntOne => Some(1.0),
            PairwiseAccuracy::IntZero => Some(0.0),
            PairwiseAccuracy::Float(v) => Some(v),
            PairwiseAccuracy::Unavailable => None,
        }
    }

    /// The value as ENACT's JSON writes it (`1`, `0`, `0.5`); `null` when unavailable.
    pub fn to_py_value(self) -> PyValue {
        match self {
            PairwiseAccuracy::IntOne => PyValue::Int(PyInt::ONE),
            PairwiseAccuracy::IntZero => PyValue::Int(PyInt::ZERO),
            PairwiseAccuracy::Float(v) => PyValue::Float(v),
            PairwiseAccuracy::Unavailable => PyValue::None,
        }
    }
}

/// The score of one answer.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Verdict {
    pub exact_match: bool,
    pub semantic_match: bool,
    /// exact OR semantic.
    pub task_accuracy: bool,
    pub pairwise_accuracy: PairwiseAccuracy,
    /// False when the item has no scene graphs: only exact match was checked.
    pub semantic_available: bool,
}

/// Why an item could not be scored.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum VerifyError {
    /// A Python exception ENACT raises outside its try block: the item is skipped as
    /// `evaluation_error: {message}` and excluded from all metrics.
    #[error("evaluation_error: {message}")]
    Evaluation { message: String },
    /// The signature table lacks a pair the verifier needs (built with too little coverage).
    #[error("the signature table has no {view:?} set for key frames ({from}, {to})")]
    SignaturesNotCovered { view: View, from: usize, to: usize },
    /// The signature table was built for a different number of key frames.
    #[error("the signature table covers {table} key frames, the item has {item}")]
    FrameCountMismatch { table: usize, item: usize },
}

fn evaluation_error(message: impl Into<String>) -> VerifyError {
    VerifyError::Evaluation {
        message: message.into(),
    }
}

/// How a record's `key_frame_ids` behaves under the Python operations ENACT applies to it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeyFrameShape {
    /// A list (or a string, indexed by character) of this length.
    Sequence(usize),
    /// A dict of this length: `kf[0]` raises `KeyError(0)`.
    Mapping(usize),
    /// A number or bool: `len()` raises; the Python type name.
    Unsized(&'static str),
}

impl KeyFrameShape {
    /// The shape of a JSON `key_frame_ids` value and, for sequences, the frame ids ENACT looks up
    /// (`str(x)` of each element, or each character of a string).
    pub fn of(value: &PyValue) -> (KeyFrameShape, Vec<String>) {
        match value {
            PyValue::List(items) => (
                KeyFrameShape::Sequence(items.len()),
                items.iter().map(PyValue::py_str).collect(),
            ),
            PyValue::Str(s) => {
                let frames: Vec<String> = s.chars().map(String::from).collect();
                (KeyFrameShape::Sequence(frames.len()), frames)
            }
            PyValue::Dict(entries) => (KeyFrameShape::Mapping(entries.len()), Vec::new()),
            other => (KeyFrameShape::Unsized(other.type_name()), Vec::new()),
        }
    }
}

/// A ground-truth value as ENACT iterates it: its items (a list's elements, a string's
/// characters, a dict's keys), whether it is a list (only a list can equal the answer), and its
/// items as small integers when they all are.
#[derive(Debug, Clone)]
pub struct GroundTruthView<'a> {
    items: Cow<'a, [PyValue]>,
    is_list: bool,
    small: Option<Vec<i64>>,
}

impl<'a> GroundTruthView<'a> {
    /// `Err` carries Python's `len()` TypeError message for values without a length.
    pub fn of(value: &'a PyValue) -> Result<GroundTruthView<'a>, String> {
        let items: Cow<'a, [PyValue]> = match value {
            PyValue::List(items) => Cow::Borrowed(items.as_slice()),
            PyValue::Str(s) => Cow::Owned(s.chars().map(|c| PyValue::Str(c.to_string())).collect()),
            PyValue::Dict(entries) => Cow::Owned(
                entries
                    .iter()
                    .map(|(k, _)| PyValue::Str(k.clone()))
                    .collect(),
            ),
            other => {
                return Err(format!(
                    "object of type '{}' has no len()",
                    other.type_name()
                ));
            }
        };
        let is_list = matches!(value, PyValue::List(_));
        let small = if is_list { small_labels(&items) } else { None };
        Ok(GroundTruthView {
            items,
            is_list,
            small,
        })
    }

    /// Python `len(gt)`.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
}

/// Scores `answer` for a dataset item whose ground truth is a valid permutation, exactly as
/// ENACT would. `signatures` are the item's tables (its key frames must number
/// `ground_truth.len() + 1`); without them only exact match is checked
/// (`semantic_available: false`).
pub fn verify(
    direction: Direction,
    ground_truth: &Permutation,
    answer: &ParsedAnswer,
    signatures: Option<&ItemSignatures>,
) -> Result<Verdict, VerifyError> {
    let shape = KeyFrameShape::Sequence(ground_truth.len() + 1);
    check_frame_count(shape, signatures)?;
    if let Some(pred) = answer.small_labels() {
        let mut gt = ShortList::new();
        for &label in ground_truth.labels() {
            gt.push(i64::from(label));
        }
        return run(direction, shape, &gt, true, pred, signatures);
    }
    let gt: Vec<PyValue> = ground_truth
        .labels()
        .iter()
        .map(|&l| PyValue::Int(PyInt::Small(i64::from(l))))
        .collect();
    run(direction, shape, &gt, true, answer.labels(), signatures)
}

/// Scores one ENACT record with its own (possibly malformed) ground truth and key frames.
/// `signatures: None` means exact match only.
pub fn verify_enact_record(
    direction: Direction,
    key_frames: KeyFrameShape,
    ground_truth: &GroundTruthView<'_>,
    answer: &ParsedAnswer,
    signatures: Option<&ItemSignatures>,
) -> Result<Verdict, VerifyError> {
    check_frame_count(key_frames, signatures)?;
    if let (Some(gt), Some(pred)) = (&ground_truth.small, answer.small_labels()) {
        return run(
            direction,
            key_frames,
            gt,
            ground_truth.is_list,
            pred,
            signatures,
        );
    }
    run(
        direction,
        key_frames,
        &ground_truth.items,
        ground_truth.is_list,
        answer.labels(),
        signatures,
    )
}

fn check_frame_count(
    key_frames: KeyFrameShape,
    signatures: Option<&ItemSignatures>,
) -> Result<(), VerifyError> {
    match (key_frames, signatures) {
        (KeyFrameShape::Sequence(n), Some(table)) if table.key_frame_count() != n => {
            Err(VerifyError::FrameCountMismatch {
                table: table.key_frame_count(),
                item: n,
            })
        }
        _ => Ok(()),
    }
}

fn run<L: Label>(
    direction: Direction,
    key_frames: KeyFrameShape,
    gt: &[L],
    gt_is_list: bool,
    pred: &[L],
    signatures: Option<&ItemSignatures>,
) -> Result<Verdict, VerifyError> {
    match direction {
        Direction::Forward => verify_forward(key_frames, gt, gt_is_list, pred, signatures),
        Direction::Inverse => verify_inverse(key_frames, gt, pred, signatures),
    }
}

/// The Python operations ENACT applies to a label. Implemented for Python values and, as a
/// fast path with identical results, for machine integers.
trait Label: Sized {
    /// `seq[label]` on a list of length `len` (negative indexes wrap); `Err` is Python's message.
    fn index(&self, len: usize, assignment: bool) -> Result<usize, String>;
    /// `label - 1`; `Err` is Python's TypeError message.
    fn minus_one(&self) -> Result<Self, String>;
    /// `0 <= label < len`.
    fn in_range(&self, len: usize) -> bool;
    /// `==`.
    fn equals(&self, other: &Self) -> bool;
}

fn index_message(assignment: bool) -> String {
    if assignment {
        "list assignment index out of range".to_owned()
    } else {
        "list index out of range".to_owned()
    }
}

impl Label for i64 {
    fn index(&self, len: usize, assignment: bool) -> Result<usize, String> {
        let len_i = len as i64;
        let i = if *self < 0 { *self + len_i } else { *self };
        if (0..len_i).contains(&i) {
            Ok(i as usize)
        } else {
            Err(index_message(assignment))
        }
    }

    fn minus_one(&self) -> Result<Self, String> {
        Ok(*self - 1)
    }

    fn in_range(&self, len: usize) -> bool {
        *self >= 0 && *self < len as i64
    }

    fn equals(&self, other: &Self) -> bool {
        self == other
    }
}

impl Label for PyValue {
    fn index(&self, len: usize, assignment: bool) -> Result<usize, String> {
        let Some(value) = self.as_int() else {
            return Err(format!(
                "list indices must be integers or slices, not {}",
                self.type_name()
            ));
        };
        match value.to_i64() {
            Some(i) => i.index(len, assignment),
            None => Err("cannot fit 'int' into an index-sized integer".to_owned()),
        }
    }

    fn minus_one(&self) -> Result<Self, String> {
        match self {
            PyValue::Int(_) | PyValue::Bool(_) => Ok(PyValue::Int(
                self.as_int().unwrap_or(PyInt::ZERO).sub(&PyInt::ONE),
            )),
            PyValue::Float(f) => Ok(PyValue::Float(f - 1.0)),
            other => Err(format!(
                "unsupported operand type(s) for -: '{}' and 'int'",
                other.type_name()
            )),
        }
    }

    fn in_range(&self, len: usize) -> bool {
        let Some(number) = Number::of(self) else {
            return false;
        };
        let zero = Number::Int(PyInt::ZERO);
        let limit = Number::Int(PyInt::Small(len as i64));
        matches!(number.cmp(&zero), Some(Ordering::Greater | Ordering::Equal))
            && number.cmp(&limit) == Some(Ordering::Less)
    }

    fn equals(&self, other: &Self) -> bool {
        self.py_eq(other)
    }
}

fn labels_equal<L: Label>(a: &[L], b: &[L]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.equals(y))
}

/// How a computation inside ENACT's try block ended badly.
enum TryFailure {
    /// A Python exception, swallowed by ENACT.
    Raised,
    /// Our table lacks a pair: not ENACT behaviour, reported to the caller.
    NotCovered(View, usize, usize),
}

impl TryFailure {
    fn into_verify_error(self) -> Option<VerifyError> {
        match self {
            TryFailure::Raised => None,
            TryFailure::NotCovered(view, from, to) => {
                Some(VerifyError::SignaturesNotCovered { view, from, to })
            }
        }
    }
}

/// The signature sets along a chain of key-frame positions.
fn chain_sets(
    table: &ItemSignatures,
    chain: &[usize],
    view: View,
) -> Result<ShortList<SetId>, TryFailure> {
    let mut sets = ShortList::new();
    for pair in chain.windows(2) {
        match table.lookup(view, pair[0], pair[1]) {
            PairLookup::Set(id) => sets.push(id),
            PairLookup::Raised => return Err(TryFailure::Raised),
            PairLookup::NotCovered => return Err(TryFailure::NotCovered(view, pair[0], pair[1])),
        }
    }
    Ok(sets)
}

/// Room for the lists of one item without a heap allocation (answers have at most nine
/// labels, items at most ten key frames); longer lists, from odd answers, spill to the heap.
const SHORT_LIST: usize = 16;

/// A short list of `Copy` values kept on the stack while it fits.
#[derive(Debug, Clone)]
enum ShortList<T: Copy + Default> {
    Inline { items: [T; SHORT_LIST], len: usize },
    Heap(Vec<T>),
}

impl<T: Copy + Default> ShortList<T> {
    fn new() -> Self {
        ShortList::Inline {
            items: [T::default(); SHORT_LIST],
            len: 0,
        }
    }

    fn filled(len: usize, value: T) -> Self {
        if len <= SHORT_LIST {
            let mut items = [T::default(); SHORT_LIST];
            items[..len].fill(value);
            ShortList::Inline { items, len }
        } else {
            ShortList::Heap(vec![value; len])
        }
    }

    fn push(&mut self, value: T) {
        match self {
            ShortList::Inline { items, len } if *len < SHORT_LIST => {
                items[*len] = value;
                *len += 1;
            }
            ShortList::Inline { items, len } => {
                let mut spilled = items[..*len].to_vec();
                spilled.push(value);
                *self = ShortList::Heap(spilled);
            }
            ShortList::Heap(items) => items.push(value),
        }
    }
}

impl<T: Copy + Default> std::ops::Deref for ShortList<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        match self {
            ShortList::Inline { items, len } => &items[..*len],
            ShortList::Heap(items) => items,
        }
    }
}

impl<T: Copy + Default> std::ops::DerefMut for ShortList<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        match self {
            ShortList::Inline { items, len } => &mut items[..*len],
            ShortList::Heap(items) => items,
        }
    }
}

/// ENACT quirk: the length-mismatch alignment. An LCS-style monotone matching of the ground
/// truth sets `c` against the predicted sets `p`, normalised by the LONGER length. A pair
/// matches if `c ⊆ p`, or (inverse only, when `full` is given) if `p ⊆ full`.
fn align(table: &ItemSignatures, c: &[SetId], p: &[SetId], full: Option<&[SetId]>) -> f64 {
    if c.is_empty() || p.is_empty() {
        return 0.0;
    }
    let (m, n) = (c.len(), p.len());
    let full = full.filter(|f| !f.is_empty());
    let mut dp = vec![0u32; (m + 1) * (n + 1)];
    let at = |i: usize, j: usize| i * (n + 1) + j;
    for i in 1..=m {
        for j in 1..=n {
            let mut best = dp[at(i - 1, j)].max(dp[at(i, j - 1)]);
            let matched = table.is_subset(c[i - 1], p[j - 1])
                || full.is_some_and(|f| table.is_subset(p[j - 1], f[i - 1]));
            if matched {
                best = best.max(dp[at(i - 1, j - 1)] + 1);
            }
            dp[at(i, j)] = best;
        }
    }
    f64::from(dp[at(m, n)]) / m.max(n) as f64
}

/// Exact-only scoring (no scene graphs): an exact answer still earns ENACT's int 1, any other
/// answer has no known partial credit.
fn exact_only(exact_match: bool) -> Verdict {
    Verdict {
        exact_match,
        semantic_match: false,
        task_accuracy: exact_match,
        pairwise_accuracy: if exact_match {
            PairwiseAccuracy::IntOne
        } else {
            PairwiseAccuracy::Unavailable
        },
        semantic_available: false,
    }
}

/// ENACT quirk: task accuracy is exact OR semantic match, and whenever it holds the pairwise
/// accuracy is overwritten with the int 1, whatever partial credit was computed.
fn finish(exact_match: bool, semantic_match: bool, pairwise: PairwiseAccuracy) -> Verdict {
    let task_accuracy = exact_match || semantic_match;
    Verdict {
        exact_match,
        semantic_match,
        task_accuracy,
        pairwise_accuracy: if task_accuracy {
            PairwiseAccuracy::IntOne
        } else {
            pairwise
        },
        semantic_available: true,
    }
}

fn ratio(hits: usize, total: usize) -> PairwiseAccuracy {
    if total > 0 {
        PairwiseAccuracy::Float(hits as f64 / total as f64)
    } else {
        PairwiseAccuracy::IntZero
    }
}

fn verify_forward<L: Label>(
    key_frames: KeyFrameShape,
    gt: &[L],
    gt_is_list: bool,
    pred: &[L],
    signatures: Option<&ItemSignatures>,
) -> Result<Verdict, VerifyError> {
    // Rebuild the shuffled image order S from the ground truth (outside the try block).
    let n = match key_frames {
        KeyFrameShape::Sequence(n) => n,
        KeyFrameShape::Mapping(_) => return Err(evaluation_error("0")),
        KeyFrameShape::Unsized(name) => {
            return Err(evaluation_error(format!(
                "object of type '{name}' has no len()"
            )));
        }
    };
    if n == 0 {
        return Err(evaluation_error("list index out of range"));
    }
    let mut slots: ShortList<Option<usize>> = ShortList::filled(n, None);
    slots[0] = Some(0);
    for (i, label) in gt.iter().enumerate() {
        if i + 1 < n {
            let slot = label.index(n, true).map_err(evaluation_error)?;
            slots[slot] = Some(i + 1);
        }
    }
    let mut shuffled: ShortList<usize> = ShortList::new();
    for (i, slot) in slots.iter().enumerate() {
        match slot {
            Some(position) => shuffled.push(*position),
            None => {
                return Err(evaluation_error(format!(
                    "Actual shuffled sequence is not fully reconstructed. Missing frame at index {i}"
                )));
            }
        }
    }

    let exact_match = gt_is_list && labels_equal(gt, pred);
    let equal_length = gt.len() == pred.len();
    let Some(table) = signatures else {
        return Ok(exact_only(exact_match));
    };

    // Inside ENACT's try: chains [kf0] + [S[x] for x in labels], C along the ground truth
    // (visible), P along the prediction (full).
    let chains = || -> Result<(ShortList<SetId>, ShortList<SetId>), TryFailure> {
        let chain = |labels: &[L]| -> Result<ShortList<usize>, TryFailure> {
            let mut positions = ShortList::new();
            positions.push(shuffled[0]);
            for label in labels {
                let slot = label.index(n, false).map_err(|_| TryFailure::Raised)?;
                positions.push(shuffled[slot]);
            }
            Ok(positions)
        };
        let correct = chain(gt)?;
        let predicted = chain(pred)?;
        Ok((
            chain_sets(table, &correct, View::Visible)?,
            chain_sets(table, &predicted, View::Full)?,
        ))
    };

    let mut semantic_match = false;
    let mut pairwise = PairwiseAccuracy::IntZero;
    match chains() {
        Ok((c, p)) if equal_length => {
            let hits = c
                .iter()
                .zip(p.iter())
                .filter(|(c, p)| table.is_subset(**c, **p))
                .count();
            semantic_match = hits == c.len();
            pairwise = ratio(hits, gt.len());
        }
        Ok((c, p)) => pairwise = PairwiseAccuracy::Float(align(table, &c, &p, None)),
        Err(failure) => {
            if let Some(error) = failure.into_verify_error() {
                return Err(error);
            }
        }
    }
    Ok(finish(exact_match, semantic_match, pairwise))
}

/// What ENACT's inverse try block computes: C and F of the chronological transitions, and the
/// transition whose action each surviving predicted label names.
struct InverseChoice {
    visible: ShortList<SetId>,
    full: ShortList<SetId>,
    chosen: ShortList<usize>,
}

fn verify_inverse<L: Label>(
    key_frames: KeyFrameShape,
    gt: &[L],
    pred: &[L],
    signatures: Option<&ItemSignatures>,
) -> Result<Verdict, VerifyError> {
    // Outside the try block: 0-based labels (a string label raises here).
    let g0: Vec<L> = gt
        .iter()
        .map(L::minus_one)
        .collect::<Result<_, _>>()
        .map_err(evaluation_error)?;
    let p0: Vec<L> = pred
        .iter()
        .map(L::minus_one)
        .collect::<Result<_, _>>()
        .map_err(evaluation_error)?;
    let exact_match = labels_equal(&g0, &p0);
    let equal_length = g0.len() == p0.len();
    let Some(table) = signatures else {
        return Ok(exact_only(exact_match));
    };

    // Inside the try: C and F of the chronological transitions, the actions' visible sets A in
    // label order (out-of-range labels dropped, list compacted), and the prediction's choice.
    let choose = || -> Result<InverseChoice, TryFailure> {
        let (visible, full) = match key_frames {
            KeyFrameShape::Sequence(n) => {
                let mut chain = ShortList::new();
                for position in 0..n {
                    chain.push(position);
                }
                (
                    chain_sets(table, &chain, View::Visible)?,
                    chain_sets(table, &chain, View::Full)?,
                )
            }
            KeyFrameShape::Mapping(len) if len <= 1 => (ShortList::new(), ShortList::new()),
            KeyFrameShape::Mapping(_) | KeyFrameShape::Unsized(_) => {
                return Err(TryFailure::Raised);
            }
        };
        let m = visible.len();
        let mut by_label: ShortList<Option<usize>> = ShortList::filled(m, None);
        for (i, label) in g0.iter().enumerate() {
            if label.in_range(m) {
                if i >= m {
                    return Err(TryFailure::Raised);
                }
                let slot = label.index(m, true).map_err(|_| TryFailure::Raised)?;
                by_label[slot] = Some(i);
            }
        }
        let mut actions: ShortList<usize> = ShortList::new();
        for action in by_label.iter().flatten() {
            actions.push(*action);
        }
        let k = actions.len();
        let mut chosen: ShortList<Option<usize>> = ShortList::filled(k, None);
        for (i, label) in p0.iter().enumerate() {
            if label.in_range(k) {
                let slot = label.index(k, false).map_err(|_| TryFailure::Raised)?;
                if i >= k {
                    return Err(TryFailure::Raised);
                }
                chosen[i] = Some(actions[slot]);
            }
        }
        let mut surviving = ShortList::new();
        for transition in chosen.iter().flatten() {
            surviving.push(*transition);
        }
        Ok(InverseChoice {
            visible,
            full,
            chosen: surviving,
        })
    };

    let mut semantic_match = false;
    let mut pairwise = PairwiseAccuracy::IntZero;
    match choose() {
        Ok(InverseChoice {
            visible,
            full,
            chosen,
        }) => {
            let mut input: ShortList<SetId> = ShortList::new();
            for &transition in chosen.iter() {
                input.push(visible[transition]);
            }
            if equal_length {
                let hits = input
                    .iter()
                    .zip(full.iter())
                    .filter(|(i, f)| table.is_subset(**i, **f))
                    .count();
                semantic_match = visible.len() == input.len() && hits == input.len();
                pairwise = ratio(hits, g0.len());
            } else {
                pairwise = PairwiseAccuracy::Float(align(table, &visible, &input, Some(&full)));
            }
        }
        Err(failure) => {
            if let Some(error) = failure.into_verify_error() {
                return Err(error);
            }
        }
    }
    Ok(finish(exact_match, semantic_match, pairwise))
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;
    use crate::verifier::pyjson::parse_python_json;
    use crate::verifier::signatures::VisibleCoverage;

    fn set(items: &[&str]) -> BTreeSet<String> {
        items.iter().map(|s| s.to_string()).collect()
    }

    /// Four key frames a, b, c, d. Transitions: a→b opens the fridge, b→c grasps the milk,
    /// c→d places the milk inside. The full sets add an unseen light switch on a→b. Any other
    /// pair only shows an unrelated change, except that d→a raises (ENACT's parent assertion).
    fn world(from: &str, to: &str, view: View) -> Result<BTreeSet<String>, String> {
        let visible = match (from, to) {
            (f, t) if f == t => set(&[]),
            ("a", "b") => set(&["open"]),
            ("b", "c") => set(&["grasp"]),
            ("c", "d") => set(&["inside"]),
            ("d", "a") => return Err("AssertionError".to_owned()),
            _ => set(&["far"]),
        };
        Ok(match (from, to, view) {
            ("a", "b", View::Full) => set(&["open", "light"]),
            _ => visible,
        })
    }

    fn table(frames: &[&str]) -> ItemSignatures {
        let frames: Vec<String> = frames.iter().map(|s| s.to_string()).collect();
        ItemSignatures::build(&frames, VisibleCoverage::Chronological, world)
    }

    fn answer(text: &str) -> ParsedAnswer {
        match parse_python_json(text).expect("test JSON") {
            PyValue::List(items) => ParsedAnswer::new(items),
            other => panic!("not a list: {other:?}"),
        }
    }

    fn perm(labels: &[u8]) -> Permutation {
        Permutation::new(labels.to_vec()).expect("test permutation")
    }

    fn score(direction: Direction, gt: &[u8], pred: &str) -> Verdict {
        verify(
            direction,
            &perm(gt),
            &answer(pred),
            Some(&table(&["a", "b", "c", "d"])),
        )
        .expect("scored")
    }

    #[test]
    fn machine_integer_path_agrees_with_python_values() {
        // Random small-integer labels (out of range, negative, repeated, wrong length) through
        // both implementations of the label operations.
        let frames: Vec<String> = ["a", "b", "c", "d", "e", "f"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut next = move |bound: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state % bound
        };
        for case in 0..4000 {
            let n = 1 + next(5) as usize;
            let t = ItemSignatures::build(&frames[..n], VisibleCoverage::AllPairs, world);
            let (gt_len, pred_len) = (next(7) as usize, next(7) as usize);
            let gt: Vec<i64> = (0..gt_len).map(|_| next(13) as i64 - 5).collect();
            let pred: Vec<i64> = (0..pred_len).map(|_| next(13) as i64 - 5).collect();
            let as_values = |v: &[i64]| -> Vec<PyValue> {
                v.iter().map(|&x| PyValue::Int(PyInt::Small(x))).collect()
            };
            for direction in [Direction::Forward, Direction::Inverse] {
                let shape = KeyFrameShape::Sequence(n);
                let fast = run(direction, shape, &gt, true, &pred, Some(&t));
                let slow = run(
                    direction,
                    shape,
                    &as_values(&gt),
                    true,
                    &as_values(&pred),
                    Some(&t),
                );
                assert_eq!(
                    fast, slow,
                    "case {case}: {direction} gt {gt:?} pred {pred:?} n {n}"
                );
            }
        }
    }

    #[test]
    fn labels_near_the_ends_of_i64_take_the_python_value_path() {
        // Small labels run on machine integers; near i64's ends `label - 1` and the index
        // arithmetic would overflow there, so such labels take the Python-value path.
        assert!(answer("[2, 3, 1]").small_labels().is_some());
        // Zero and negative labels are small too (both paths give the same; this one is fast).
        assert_eq!(answer("[0, -1, 2]").small_labels(), Some(&[0, -1, 2][..]));
        for extreme in [i64::MIN, i64::MIN / 2, i64::MAX / 2, i64::MAX] {
            let text = format!("[2, 3, {extreme}]");
            assert!(answer(&text).small_labels().is_none(), "{text}");
            // A label no frame has: neither exact nor semantic, and no overflow on the way.
            for direction in [Direction::Forward, Direction::Inverse] {
                let v = score(direction, &[2, 3, 1], &text);
                assert!(!v.exact_match && !v.semantic_match, "{direction} {text}");
            }
        }
    }

    #[test]
    fn a_record_whose_truth_outruns_its_key_frames_needs_a_pair_a_chronological_table_lacks() {
        // ENACT fills the shuffled order from the first len(key_frame_ids) - 1 labels only, but
        // chains every label: [2, 3, 1, 2] over four key frames walks 0, 1, 2, 3 and back to 1.
        // ENACT computes that visible change from the scene graphs; a table of chronological
        // visible pairs does not hold it, and the item is refused rather than scored as if
        // ENACT had raised.
        let truth = parse_python_json("[2, 3, 1, 2]").expect("test JSON");
        let view = GroundTruthView::of(&truth).expect("sized");
        let verdict = verify_enact_record(
            Direction::Forward,
            KeyFrameShape::Sequence(4),
            &view,
            &answer("[2, 3, 1]"),
            Some(&table(&["a", "b", "c", "d"])),
        );
        assert_eq!(
            verdict,
            Err(VerifyError::SignaturesNotCovered {
                view: View::Visible,
                from: 3,
                to: 1
            })
        );
    }

    #[test]
    fn forward_exact_answer_short_circuits_to_int_one() {
        let v = score(Direction::Forward, &[2, 3, 1], "[2, 3, 1]");
        assert!(v.exact_match && v.semantic_match && v.task_accuracy);
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::IntOne);
        // [1.0] == [1] in Python: exact, though the float indexes make semantic false.
        let v = score(Direction::Forward, &[2, 3, 1], "[2.0, 3.0, 1.0]");
        assert!(v.exact_match && !v.semantic_match);
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::IntOne);
    }

    #[test]
    fn forward_swap_breaks_two_transitions() {
        // gt [2,3,1]: S = [a, d, b, c]. Predicting [3,2,1] chains a→c→b→d.
        let v = score(Direction::Forward, &[2, 3, 1], "[3, 2, 1]");
        assert!(!v.task_accuracy && !v.semantic_match);
        // C: open, grasp, inside. P: a→c, c→b, b→d all {far}.
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::Float(0.0));
        // A duplicated label chains a frame with itself: the empty set holds no C.
        let v = score(Direction::Forward, &[2, 3, 1], "[2, 2, 1]");
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::Float(1.0 / 3.0));
    }

    #[test]
    fn forward_python_indexing() {
        // 0 selects the current state: a→a→c→d, only c→d holds its C.
        let v = score(Direction::Forward, &[2, 3, 1], "[0, 3, 1]");
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::Float(1.0 / 3.0));
        // -1 wraps to S[3] = c: a→b→c→c.
        let v = score(Direction::Forward, &[2, 3, 1], "[2, 3, -1]");
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::Float(2.0 / 3.0));
        // Out of range, huge and string labels raise inside the try: PA is the int 0.
        for pred in [
            "[2, 3, 9]",
            "[2, 3, 100000000000000000000]",
            "[\"2\", \"3\", \"1\"]",
        ] {
            let v = score(Direction::Forward, &[2, 3, 1], pred);
            assert!(!v.semantic_match, "{pred}");
            assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::IntZero, "{pred}");
        }
        // A backward pair that raises (d→a) also gives the int 0 for the whole item.
        let v = score(Direction::Forward, &[2, 3, 1], "[1, 3, 2]");
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::Float(0.0));
        let v = verify(
            Direction::Forward,
            &perm(&[1, 2, 3]),
            &answer("[3, 0, 1]"),
            Some(&table(&["a", "b", "c", "d"])),
        )
        .expect("scored");
        assert_eq!(
            v.pairwise_accuracy,
            PairwiseAccuracy::IntZero,
            "chain a→d→a raises"
        );
    }

    #[test]
    fn forward_length_mismatch_uses_the_alignment() {
        // C = [open, grasp, inside]; prediction [2, 3] chains a→b→c: two sets match in order.
        let v = score(Direction::Forward, &[2, 3, 1], "[2, 3]");
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::Float(2.0 / 3.0));
        // Longer: normalised by the longer length (4).
        let v = score(Direction::Forward, &[2, 3, 1], "[2, 3, 1, 1]");
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::Float(3.0 / 4.0));
        // Twenty labels: the chain spills from the stack to the heap.
        let long = format!("[2, 3, 1{}]", ", 1".repeat(17));
        let v = score(Direction::Forward, &[2, 3, 1], &long);
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::Float(3.0 / 20.0));
        let v = score(Direction::Forward, &[2, 3, 1], "[]");
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::Float(0.0));
        let v = score(Direction::Forward, &[2, 3, 1], "[2, 3, 7, 1]");
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::IntZero);
    }

    #[test]
    fn inverse_rules() {
        let v = score(Direction::Inverse, &[1, 2, 3], "[1, 2, 3]");
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::IntOne);
        // gt [3,1,2]: action 3 caused a→b (open), 1 caused b→c (grasp), 2 caused c→d (inside).
        // Predict [3, 2, 1]: open ⊆ F0 yes; inside ⊆ F1 no; grasp ⊆ F2 no.
        let v = score(Direction::Inverse, &[3, 1, 2], "[3, 2, 1]");
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::Float(1.0 / 3.0));
        // Out-of-range labels are dropped and the list compacts: [0, 3, 1] → [open, grasp],
        // which moves grasp into position 1, where it matches.
        let v = score(Direction::Inverse, &[3, 1, 2], "[0, 3, 1]");
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::Float(2.0 / 3.0));
        assert!(!v.semantic_match);
        // String labels raise outside the try: the item is an evaluation error.
        let err = verify(
            Direction::Inverse,
            &perm(&[1, 2]),
            &answer("[\"1\", \"2\"]"),
            None,
        )
        .unwrap_err();
        assert_eq!(
            err.to_string(),
            "evaluation_error: unsupported operand type(s) for -: 'str' and 'int'"
        );
        // Floats: exact via Python equality, semantic raises on the float index.
        let v = score(Direction::Inverse, &[3, 1, 2], "[3.0, 1.0, 2.0]");
        assert!(v.exact_match && !v.semantic_match);
    }

    #[test]
    fn inverse_alignment_uses_the_or_rule() {
        // Shorter prediction [3, 1] (open, grasp) against C [open, grasp, inside].
        let v = score(Direction::Inverse, &[3, 1, 2], "[3, 1]");
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::Float(2.0 / 3.0));
        // A prediction whose set is a subset of F but not a superset of C still aligns:
        // build a world where action "light" ⊆ F0 but ⊉ C0.
        let frames: Vec<String> = ["a", "b", "c"].iter().map(|s| s.to_string()).collect();
        let t = ItemSignatures::build(&frames, VisibleCoverage::Chronological, |f, to, view| {
            Ok(match (f, to, view) {
                ("a", "b", View::Visible) => set(&["x", "y"]),
                ("a", "b", View::Full) => set(&["x", "y", "z"]),
                ("b", "c", View::Visible) => set(&["y"]),
                ("b", "c", View::Full) => set(&["y"]),
                _ => set(&[]),
            })
        });
        // gt [1,2]: A = [{x,y}, {y}]. Prediction [2]: I = [{y}]; {x,y} ⊄ {y} but {y} ⊆ F0.
        let v =
            verify(Direction::Inverse, &perm(&[1, 2]), &answer("[2]"), Some(&t)).expect("scored");
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::Float(1.0 / 2.0));
        // Same prediction at equal length: [2, 2] → I = [{y}, {y}], {y} ⊆ F0 and {y} ⊆ F1:
        // semantically correct although a label is repeated.
        let v = verify(
            Direction::Inverse,
            &perm(&[1, 2]),
            &answer("[2, 2]"),
            Some(&t),
        )
        .expect("scored");
        assert!(v.semantic_match && !v.exact_match);
    }

    #[test]
    fn verdicts_serialise_with_the_int_float_distinction() {
        let v = score(Direction::Forward, &[2, 3, 1], "[2, 3]");
        let json = serde_json::to_string(&v).expect("serialise");
        assert!(
            json.contains(r#""pairwise_accuracy":{"kind":"float","value":0.6666666666666666}"#),
            "{json}"
        );
        let back: Verdict = serde_json::from_str(&json).expect("deserialise");
        assert_eq!(back, v);
        let one = serde_json::to_string(&PairwiseAccuracy::IntOne).expect("serialise");
        assert_eq!(one, r#"{"kind":"int_one"}"#);
    }

    #[test]
    fn exact_only_without_scene_graphs() {
        let v =
            verify(Direction::Forward, &perm(&[2, 1]), &answer("[2, 1]"), None).expect("scored");
        assert!(v.task_accuracy && !v.semantic_available);
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::IntOne);
        let v =
            verify(Direction::Inverse, &perm(&[2, 1]), &answer("[1, 2]"), None).expect("scored");
        assert!(!v.task_accuracy && !v.semantic_available);
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::Unavailable);
    }

    #[test]
    fn a_table_of_other_key_frames_than_the_item_is_refused() {
        // Four key frames in the table, three images in the item (two actions).
        let wrong = table(&["a", "b", "c", "d"]);
        assert_eq!(
            verify(
                Direction::Forward,
                &perm(&[1, 2]),
                &answer("[1, 2]"),
                Some(&wrong)
            ),
            Err(VerifyError::FrameCountMismatch { table: 4, item: 3 })
        );
        let right = table(&["a", "b", "c"]);
        assert!(
            verify(
                Direction::Forward,
                &perm(&[1, 2]),
                &answer("[1, 2]"),
                Some(&right)
            )
            .is_ok()
        );
    }

    #[test]
    fn items_longer_than_the_inline_list_are_verified_on_the_heap() {
        // 18 key frames: more than SHORT_LIST slots for the shuffled order.
        let labels: Vec<u8> = (1..=17).rev().collect();
        let text = format!("{labels:?}");
        let v = verify(Direction::Forward, &perm(&labels), &answer(&text), None).expect("scored");
        assert!(v.exact_match && v.task_accuracy);
    }

    #[test]
    fn a_bool_label_is_the_int_python_takes_it_for() {
        // bool is an int subclass: ["a", "b", "c"][True] is "b", True - 1 is 0. A label that
        // is neither (a float, a string) is Python's TypeError.
        let yes = PyValue::Bool(true);
        assert_eq!(yes.index(3, false), Ok(1));
        assert_eq!(PyValue::Bool(false).index(3, true), Ok(0));
        assert!(
            yes.minus_one()
                .expect("an int")
                .py_eq(&PyValue::Int(PyInt::ZERO))
        );
        assert!(
            matches!(yes.minus_one(), Ok(PyValue::Int(_))),
            "True - 1 is an int"
        );
        assert_eq!(
            PyValue::Float(1.0).index(3, false),
            Err("list indices must be integers or slices, not float".to_owned())
        );
    }

    #[test]
    fn malformed_ground_truths_raise_like_python() {
        let record = |gt: &str, kf: &str, pred: &str, direction| {
            let gt_value = parse_python_json(gt).expect("json");
            let kf_value = parse_python_json(kf).expect("json");
            let gt_view = GroundTruthView::of(&gt_value).expect("sized");
            let (shape, frames) = KeyFrameShape::of(&kf_value);
            let t = ItemSignatures::build(&frames, VisibleCoverage::AllPairs, world);
            verify_enact_record(direction, shape, &gt_view, &answer(pred), Some(&t))
                .map_err(|e| e.to_string())
        };
        let err = |r: Result<Verdict, String>| r.expect_err("should raise");
        assert_eq!(
            err(record(
                "[1, 1, 1]",
                "[\"a\", \"b\", \"c\", \"d\"]",
                "[1, 2]",
                Direction::Forward
            )),
            "evaluation_error: Actual shuffled sequence is not fully reconstructed. Missing frame at index 2"
        );
        assert_eq!(
            err(record(
                "[2, 3, 6]",
                "[\"a\", \"b\", \"c\", \"d\"]",
                "[1]",
                Direction::Forward
            )),
            "evaluation_error: list assignment index out of range"
        );
        assert_eq!(
            err(record(
                "[\"1\"]",
                "[\"a\", \"b\"]",
                "[1]",
                Direction::Forward
            )),
            "evaluation_error: list indices must be integers or slices, not str"
        );
        assert_eq!(
            err(record("[1]", "{\"a\": 1}", "[1]", Direction::Forward)),
            "evaluation_error: 0"
        );
        assert_eq!(
            err(record("[1]", "5", "[1]", Direction::Forward)),
            "evaluation_error: object of type 'int' has no len()"
        );
        // Inverse with a repeated gt label: the compacted action list is one short, the
        // prediction's last position raises inside the try → PA int 0.
        let v = record(
            "[1, 1]",
            "[\"a\", \"b\", \"c\"]",
            "[2, 1]",
            Direction::Inverse,
        )
        .expect("scored");
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::IntZero);
        // The same with an inverse dict of key frames: swallowed too.
        let v = record(
            "[1, 2]",
            "{\"a\": 1, \"b\": 2}",
            "[1, 2]",
            Direction::Inverse,
        )
        .expect("scored");
        assert!(v.exact_match && !v.semantic_match);
        // A dict of one key frame has no transition to index, so nothing raises: zero
        // transitions all match, and a wrong answer is a semantic match (int 1).
        let v = record("[1]", "{\"a\": 1}", "[2]", Direction::Inverse).expect("scored");
        assert!(!v.exact_match && v.semantic_match && v.task_accuracy);
        assert_eq!(v.pairwise_accuracy, PairwiseAccuracy::IntOne);
        // A ground truth longer than L-1 chains past the chronological path (visible a→b→c→b).
        let v = record(
            "[1, 2, 1]",
            "[\"a\", \"b\", \"c\"]",
            "[1, 2, 1]",
            Direction::Forward,
        )
        .expect("scored");
        assert!(v.exact_match && v.semantic_match);
    }
}
