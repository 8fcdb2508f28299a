//! The verifier against an executable reading of ENACT's rules (ENACT's `verify_forward`,
//! `verify_inverse` and the length-mismatch alignment), written here apart from the crate's
//! implementation, on random items: random signature tables, ground truths and answers of
//! every length around the truth's. Also the laws a leaderboard relies on: the truth is always
//! an exact match with full credit, an inverse order that only swaps actions with the same
//! signatures is accepted, and permutations survive a round trip through their labels.

use std::collections::{BTreeSet, HashMap};

use enact_core::verifier::pyint::PyInt;
use enact_core::verifier::{
    Direction, ItemSignatures, ParsedAnswer, Permutation, PyValue, View, VisibleCoverage, verify,
};
use proptest::prelude::*;

/// A random item: its ground truth (a permutation of 1..=n, n in 3..=10) and the visible and
/// full signature sets of its key frames 0..=n, drawn from a small vocabulary so that subsets
/// happen often.
#[derive(Debug, Clone)]
struct Item {
    truth: Vec<u8>,
    /// `visible[i]`: the transition (i, i + 1).
    visible: Vec<BTreeSet<String>>,
    /// `full[i][j]`: the pair (i, j), the diagonal included.
    full: Vec<Vec<BTreeSet<String>>>,
}

fn signature_set() -> impl Strategy<Value = BTreeSet<String>> {
    proptest::collection::btree_set(
        prop_oneof![
            Just("open(door)"),
            Just("on(cup,table)"),
            Just("in(apple,bowl)")
        ]
        .prop_map(str::to_owned),
        0..=2,
    )
}

fn item() -> impl Strategy<Value = Item> {
    (3usize..=10).prop_flat_map(|n| {
        (
            Just((1..=n as u8).collect::<Vec<u8>>()).prop_shuffle(),
            proptest::collection::vec(signature_set(), n),
            proptest::collection::vec(proptest::collection::vec(signature_set(), n + 1), n + 1),
        )
            .prop_map(|(truth, visible, full)| Item {
                truth,
                visible,
                full,
            })
    })
}

/// An item and an answer for it: a permutation, the truth with a few labels changed, or a
/// list one shorter or longer, with labels from 0 to n + 1 (out of range included).
fn item_and_answer() -> impl Strategy<Value = (Item, Vec<i64>)> {
    item().prop_flat_map(|item| {
        let n = item.truth.len();
        let truth: Vec<i64> = item.truth.iter().map(|&l| i64::from(l)).collect();
        let shuffled = Just(truth.clone()).prop_shuffle().boxed();
        let edited = proptest::collection::vec((0..n, 0..=n as i64 + 1), 1..=2)
            .prop_map(move |edits| {
                let mut answer = truth.clone();
                for (at, label) in edits {
                    answer[at] = label;
                }
                answer
            })
            .boxed();
        let other_length = proptest::collection::vec(0..=n as i64 + 1, 0..=n + 1)
            .prop_filter("a length other than n", move |a| a.len() != n)
            .boxed();
        let answer = prop_oneof![shuffled, edited, other_length];
        (Just(item), answer)
    })
}

fn frame_ids(n: usize) -> Vec<String> {
    (0..=n).map(|i| format!("kf{i}")).collect()
}

fn table(item: &Item) -> ItemSignatures {
    let ids = frame_ids(item.truth.len());
    let index: HashMap<String, usize> = ids.iter().cloned().zip(0..).collect();
    ItemSignatures::build(&ids, VisibleCoverage::Chronological, |from, to, view| {
        let (i, j) = (index[from], index[to]);
        Ok(match view {
            View::Visible => {
                assert_eq!(
                    j,
                    i + 1,
                    "the verifier asked for a visible set off the chain"
                );
                item.visible[i].clone()
            }
            View::Full => item.full[i][j].clone(),
        })
    })
}

/// What ENACT's verifier gives, when it raises nothing: (exact, semantic, task accuracy,
/// pairwise accuracy).
type Expected = (bool, bool, bool, f64);

/// ENACT's `align(C, P, full)`: the longest monotone matching, over the longer length.
fn align(
    c: &[&BTreeSet<String>],
    p: &[&BTreeSet<String>],
    full: Option<&[&BTreeSet<String>]>,
) -> f64 {
    if c.is_empty() || p.is_empty() {
        return 0.0;
    }
    let (m, n) = (c.len(), p.len());
    let mut dp = vec![vec![0usize; n + 1]; m + 1];
    for i in 1..=m {
        for j in 1..=n {
            dp[i][j] = dp[i - 1][j].max(dp[i][j - 1]);
            let matched = c[i - 1].is_subset(p[j - 1])
                || full.is_some_and(|f| !f.is_empty() && p[j - 1].is_subset(f[i - 1]));
            if matched {
                dp[i][j] = dp[i][j].max(dp[i - 1][j - 1] + 1);
            }
        }
    }
    dp[m][n] as f64 / m.max(n) as f64
}

/// ENACT's forward rule, for answers whose labels are all in 0..=n (none raises).
fn forward_by_rule(item: &Item, answer: &[i64]) -> Expected {
    let n = item.truth.len();
    let truth: Vec<i64> = item.truth.iter().map(|&l| i64::from(l)).collect();
    // The shuffled frames: slot `g` of the truth's i-th label holds key frame i + 1.
    let mut slot = vec![0usize; n + 1];
    for (i, &g) in item.truth.iter().enumerate() {
        slot[usize::from(g)] = i + 1;
    }
    let c: Vec<&BTreeSet<String>> = item.visible.iter().collect();
    let mut chain = vec![0usize];
    chain.extend(answer.iter().map(|&p| slot[p as usize]));
    let p: Vec<&BTreeSet<String>> = chain.windows(2).map(|w| &item.full[w[0]][w[1]]).collect();
    let exact = truth == answer;
    let (semantic, pairwise) = if answer.len() == n {
        let held = c.iter().zip(&p).filter(|(c, p)| c.is_subset(p)).count();
        (held == n, held as f64 / n as f64)
    } else {
        (false, align(&c, &p, None))
    };
    let task = exact || semantic;
    (exact, semantic, task, if task { 1.0 } else { pairwise })
}

/// ENACT's inverse rule. The chosen actions are a list as long as the truth, filled at the
/// answer's positions; labels outside 1..=n leave their slot empty and empty slots are dropped.
/// A label in range at a position past the end raises (IndexError): no semantic match, no
/// partial credit.
fn inverse_by_rule(item: &Item, answer: &[i64]) -> Expected {
    let n = item.truth.len();
    let truth: Vec<i64> = item.truth.iter().map(|&l| i64::from(l)).collect();
    let exact = truth == answer;
    let c: Vec<&BTreeSet<String>> = item.visible.iter().collect();
    let f: Vec<&BTreeSet<String>> = (0..n).map(|i| &item.full[i][i + 1]).collect();
    // The visible change of the action labelled g: the transition the truth puts it at.
    let mut action = vec![c[0]; n];
    for (i, &g) in item.truth.iter().enumerate() {
        action[usize::from(g) - 1] = c[i];
    }
    let mut slots: Vec<Option<&BTreeSet<String>>> = vec![None; n];
    for (i, &p) in answer.iter().enumerate() {
        if (1..=n as i64).contains(&p) {
            if i >= n {
                return (exact, false, exact, if exact { 1.0 } else { 0.0 });
            }
            slots[i] = Some(action[p as usize - 1]);
        }
    }
    let chosen: Vec<&BTreeSet<String>> = slots.into_iter().flatten().collect();
    let (semantic, pairwise) = if answer.len() == n {
        let held = chosen
            .iter()
            .zip(&f)
            .filter(|(i, f)| i.is_subset(f))
            .count();
        (chosen.len() == n && held == n, held as f64 / n as f64)
    } else {
        (false, align(&c, &chosen, Some(&f)))
    };
    let task = exact || semantic;
    (exact, semantic, task, if task { 1.0 } else { pairwise })
}

fn parsed(answer: &[i64]) -> ParsedAnswer {
    ParsedAnswer::new(
        answer
            .iter()
            .map(|&l| PyValue::Int(PyInt::Small(l)))
            .collect(),
    )
}

fn verdict(direction: Direction, item: &Item, answer: &[i64]) -> Expected {
    let truth = Permutation::new(item.truth.clone()).expect("a permutation");
    let verdict = verify(direction, &truth, &parsed(answer), Some(&table(item)))
        .expect("every label is one ENACT can index");
    assert!(verdict.semantic_available);
    assert_eq!(
        verdict.task_accuracy,
        verdict.exact_match || verdict.semantic_match
    );
    (
        verdict.exact_match,
        verdict.semantic_match,
        verdict.task_accuracy,
        verdict
            .pairwise_accuracy
            .value()
            .expect("a pairwise accuracy"),
    )
}

fn same(ours: Expected, rule: Expected) -> bool {
    ours.0 == rule.0 && ours.1 == rule.1 && ours.2 == rule.2 && (ours.3 - rule.3).abs() < 1e-12
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn forward_verdicts_follow_enacts_rule((item, answer) in item_and_answer()) {
        let n = item.truth.len() as i64;
        // Labels past n make ENACT raise inside its try block; they are the parity tests' job.
        let answer: Vec<i64> = answer.into_iter().map(|l| l.min(n)).collect();
        let ours = verdict(Direction::Forward, &item, &answer);
        let rule = forward_by_rule(&item, &answer);
        prop_assert!(same(ours, rule), "answer {answer:?}: ours {ours:?}, ENACT's rule {rule:?}");
    }

    #[test]
    fn inverse_verdicts_follow_enacts_rule((item, answer) in item_and_answer()) {
        let ours = verdict(Direction::Inverse, &item, &answer);
        let rule = inverse_by_rule(&item, &answer);
        prop_assert!(same(ours, rule), "answer {answer:?}: ours {ours:?}, ENACT's rule {rule:?}");
    }

    #[test]
    fn the_truth_is_an_exact_match_with_full_credit(item in item()) {
        let truth: Vec<i64> = item.truth.iter().map(|&l| i64::from(l)).collect();
        for direction in [Direction::Forward, Direction::Inverse] {
            prop_assert_eq!(verdict(direction, &item, &truth), (true, truth_is_semantic(&item), true, 1.0));
        }
    }

    #[test]
    fn swapping_two_actions_with_the_same_signatures_is_still_right(
        mut item in item(),
        a in 0usize..10,
        b in 0usize..10,
    ) {
        let n = item.truth.len();
        let (a, b) = (a % n, b % n);
        prop_assume!(a != b);
        // Transitions a and b change the same things, and each transition's full set holds
        // what is visible of it.
        item.visible[b] = item.visible[a].clone();
        for i in 0..n {
            let visible = item.visible[i].clone();
            item.full[i][i + 1].extend(visible);
        }
        let mut answer: Vec<i64> = item.truth.iter().map(|&l| i64::from(l)).collect();
        answer.swap(a, b);
        let (exact, semantic, task, pairwise) = verdict(Direction::Inverse, &item, &answer);
        prop_assert!(!exact && semantic && task);
        prop_assert_eq!(pairwise, 1.0);
    }

    #[test]
    fn a_permutation_is_rebuilt_from_its_labels_and_nothing_else_is_one(
        labels in (1usize..=10).prop_flat_map(|n| Just((1..=n as u8).collect::<Vec<u8>>()).prop_shuffle()),
        at in 0usize..10,
        other in 0u8..=11,
    ) {
        let permutation = Permutation::new(labels.clone()).expect("a permutation");
        prop_assert_eq!(permutation.labels(), &labels[..]);
        prop_assert_eq!(permutation.len(), labels.len());
        let json = serde_json::to_string(&permutation).expect("serialise");
        let back: Permutation = serde_json::from_str(&json).expect("read back");
        prop_assert_eq!(back.labels(), &labels[..]);
        // Changing one label to another value breaks it: a repeat, a 0, or past the end.
        let at = at % labels.len();
        prop_assume!(other != labels[at]);
        let mut broken = labels.clone();
        broken[at] = other;
        prop_assert!(Permutation::new(broken).is_err());
    }
}

/// Integers around and far past the machine range, the way ENACT's answers can hold them.
fn python_int() -> impl Strategy<Value = i128> {
    prop_oneof![
        any::<i64>().prop_map(i128::from),
        (i128::from(i64::MAX) - 3)..(i128::from(i64::MAX) + 3),
        (i128::from(i64::MIN) - 3)..(i128::from(i64::MIN) + 3),
        -(1i128 << 100)..(1i128 << 100),
        // Limb boundaries (10⁹ per limb).
        (0u32..76).prop_map(|k| 10i128.pow(k / 2) - i128::from(k % 2)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn python_ints_read_print_add_subtract_and_compare_as_i128_does(
        a in python_int(),
        b in python_int(),
    ) {
        let int = |v: i128| PyInt::parse_ascii(&v.to_string()).expect("an integer");
        let (x, y) = (int(a), int(b));
        prop_assert_eq!(x.to_string(), a.to_string());
        prop_assert_eq!(x.to_i64(), i64::try_from(a).ok());
        prop_assert_eq!(x.add(&y).to_string(), (a + b).to_string());
        prop_assert_eq!(x.sub(&y).to_string(), (a - b).to_string());
        prop_assert_eq!(x.negate().to_string(), (-a).to_string());
        prop_assert_eq!(x.cmp(&y), a.cmp(&b));
        prop_assert_eq!(x.is_zero(), a == 0);
        prop_assert_eq!(x.is_negative(), a < 0);
        // Exactly representable floats compare exactly.
        if b.unsigned_abs() < 1 << 52 {
            prop_assert_eq!(x.cmp_f64(b as f64), Some(a.cmp(&b)));
            prop_assert_eq!(x.cmp_f64(b as f64 + 0.5), Some(if a <= b { std::cmp::Ordering::Less } else { std::cmp::Ordering::Greater }));
        }
    }
}

/// Whether the truth is also a semantic match, in either direction: every transition's visible
/// change is within its full change.
fn truth_is_semantic(item: &Item) -> bool {
    let n = item.truth.len();
    (0..n).all(|i| item.visible[i].is_subset(&item.full[i][i + 1]))
}
