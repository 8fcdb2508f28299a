//! Gold items without I/O: choosing a dataset's gold set (a seeded share or a list of ids),
//! how many gold items each annotator's queue gets and which, and where in the queue they
//! stand (one in every `rate` items, unannounced).
//!
//! A gold item is an ordinary item of the dataset whose answers are kept for judging the
//! annotator who gave them: the verifier judges them as it judges every answer, and they count
//! for the annotator's quality, never in the Human row or the agreement report.

use std::collections::{HashMap, HashSet};

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

/// One gold item in every `rate` queue items: `rate - 1` ordinary items, then a gold one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GoldRate(u32);

impl GoldRate {
    /// The slowest rate accepted: one gold item in every 1000.
    pub const MAX: u32 = 1000;

    /// A rate from 2 (every other item gold) to [`GoldRate::MAX`].
    pub fn new(rate: i64) -> Result<GoldRate, String> {
        match u32::try_from(rate) {
            Ok(r) if (2..=Self::MAX).contains(&r) => Ok(GoldRate(r)),
            _ => Err(format!(
                "rate {rate}: give N from 2 to {} for one gold item in every N queue items",
                Self::MAX
            )),
        }
    }

    pub fn get(self) -> u32 {
        self.0
    }

    /// Ordinary items between two gold ones.
    fn ordinary_per_gold(self) -> usize {
        self.0 as usize - 1
    }

    /// How many gold items a queue holding `ordinary` items of the dataset should have: one
    /// after every `rate - 1` of them, and never more than the `available` gold items.
    pub fn wanted(self, ordinary: usize, available: usize) -> usize {
        (ordinary / self.ordinary_per_gold()).min(available)
    }
}

/// How a gold set was chosen.
#[derive(Debug, Clone, PartialEq)]
pub enum GoldChoice {
    /// This share of the dataset's items, drawn with this seed.
    Share { share: f64, seed: u64 },
    /// The item ids an admin listed.
    List(Vec<String>),
}

impl GoldChoice {
    /// A share strictly between 0 and 1 (all items gold would leave nothing for the Human row).
    pub fn share(share: f64, seed: u64) -> Result<GoldChoice, String> {
        if share.is_finite() && share > 0.0 && share < 1.0 {
            Ok(GoldChoice::Share { share, seed })
        } else {
            Err(format!(
                "share {share}: give a fraction above 0 and below 1 (0.1 for a tenth of the items)"
            ))
        }
    }

    /// The items a list file names ([`parse_item_list`]).
    pub fn list(text: &str) -> Result<GoldChoice, String> {
        parse_item_list(text).map(GoldChoice::List)
    }

    /// The stored name of the way items were chosen.
    pub fn kind(&self) -> &'static str {
        match self {
            GoldChoice::Share { .. } => "share",
            GoldChoice::List(_) => "list",
        }
    }
}

/// A seeded `share` of `items` (store ids, in any order): `round(share × n)` of them, at least
/// one, drawn uniformly by a seeded shuffle, returned in ascending id order. The same items
/// and seed always give the same set.
pub fn draw_share(items: &[i64], share: f64, seed: u64) -> Vec<i64> {
    if items.is_empty() {
        return Vec::new();
    }
    let mut pool = items.to_vec();
    pool.sort_unstable();
    pool.dedup();
    // A share below 1 never takes every item, so the Human row keeps something to rest on.
    let wanted = ((share * pool.len() as f64).round() as usize).clamp(1, pool.len().max(2) - 1);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    pool.shuffle(&mut rng);
    pool.truncate(wanted);
    pool.sort_unstable();
    pool
}

/// Item ids from a list file: one per line; blank lines and lines starting with `#` are
/// skipped. Refuses a repeated id, naming both lines, and an empty list.
pub fn parse_item_list(text: &str) -> Result<Vec<String>, String> {
    let mut seen: HashMap<&str, usize> = HashMap::new();
    let mut ids = Vec::new();
    for (index, line) in text.lines().enumerate() {
        let id = line.trim();
        if id.is_empty() || id.starts_with('#') {
            continue;
        }
        if let Some(first) = seen.insert(id, index + 1) {
            return Err(format!(
                "line {}: item '{id}' is listed already on line {first}",
                index + 1
            ));
        }
        ids.push(id.to_owned());
    }
    if ids.is_empty() {
        return Err("the item list names no item (one item id per line)".to_owned());
    }
    Ok(ids)
}

/// The gold items to add to one annotator's queue: `need` of `gold` (the dataset's gold
/// items, ascending) not already in it (`held`), taken in turn from a starting point that
/// depends on the annotator, so different annotators start on different gold items.
pub fn pick_for(gold: &[i64], annotator: i64, held: &HashSet<i64>, need: usize) -> Vec<i64> {
    if gold.is_empty() || need == 0 {
        return Vec::new();
    }
    let start = usize::try_from(annotator.rem_euclid(gold.len() as i64)).unwrap_or(0);
    gold.iter()
        .cycle()
        .skip(start)
        .take(gold.len())
        .filter(|item| !held.contains(item))
        .take(need)
        .copied()
        .collect()
}

/// One queue entry as stored, before the gold mix orders it.
#[derive(Debug, Clone)]
pub struct QueuedEntry<T> {
    pub entry: T,
    /// The dataset the item is in.
    pub dataset: String,
    /// The gold set's rate when the gold mix put this item here; `None` for every other item.
    pub gold_rate: Option<GoldRate>,
    /// The attention checks' rate when their mix put this item here
    /// ([`crate::attention`]); `None` for every other item.
    pub attention_rate: Option<GoldRate>,
}

/// The queue in the order the annotator works it: every other item in its stored order, and
/// after every `rate - 1` items of a dataset with gold, that dataset's next gold item (any
/// left over go last); attention checks stand the same way at their own rate, after the gold
/// item of the same place. Mixed items are never marked: the entries come out as they went in.
pub fn mix<T>(queue: Vec<QueuedEntry<T>>) -> Vec<T> {
    // By (dataset, is an attention check): the rate and the items waiting for their place.
    type Waiting<T> = (GoldRate, std::collections::VecDeque<T>);
    let mut mixed_in: HashMap<(String, bool), Waiting<T>> = HashMap::new();
    let mut order: Vec<(String, bool)> = Vec::new();
    let mut ordinary = Vec::new();
    for queued in queue {
        let (rate, attention) = match (queued.gold_rate, queued.attention_rate) {
            (Some(rate), _) => (rate, false),
            (None, Some(rate)) => (rate, true),
            (None, None) => {
                ordinary.push((queued.dataset, queued.entry));
                continue;
            }
        };
        let key = (queued.dataset, attention);
        if !mixed_in.contains_key(&key) {
            order.push(key.clone());
        }
        mixed_in
            .entry(key)
            .or_insert_with(|| (rate, std::collections::VecDeque::new()))
            .1
            .push_back(queued.entry);
    }
    let mut mixed =
        Vec::with_capacity(ordinary.len() + mixed_in.values().map(|g| g.1.len()).sum::<usize>());
    let mut counts: HashMap<String, usize> = HashMap::new();
    for (dataset, entry) in ordinary {
        mixed.push(entry);
        let count = counts.entry(dataset.clone()).or_default();
        *count += 1;
        let count = *count;
        for attention in [false, true] {
            if let Some((rate, waiting)) = mixed_in.get_mut(&(dataset.clone(), attention))
                && count.is_multiple_of(rate.ordinary_per_gold())
                && let Some(next) = waiting.pop_front()
            {
                mixed.push(next);
            }
        }
    }
    for key in order {
        if let Some((_, waiting)) = mixed_in.remove(&key) {
            mixed.extend(waiting);
        }
    }
    mixed
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rate(n: i64) -> GoldRate {
        GoldRate::new(n).unwrap()
    }

    #[test]
    fn rates_below_two_or_above_the_maximum_are_refused() {
        assert!(GoldRate::new(1).unwrap_err().contains("rate 1"));
        assert!(GoldRate::new(0).is_err());
        assert!(GoldRate::new(-5).is_err());
        assert!(GoldRate::new(1001).is_err());
        assert_eq!(rate(5).get(), 5);
    }

    #[test]
    fn a_queue_gets_one_gold_item_per_rate_minus_one_ordinary_items() {
        assert_eq!(rate(5).wanted(20, 100), 5);
        assert_eq!(rate(5).wanted(19, 100), 4);
        assert_eq!(rate(5).wanted(3, 100), 0);
        assert_eq!(rate(2).wanted(7, 100), 7);
        // Never more than there are gold items.
        assert_eq!(rate(5).wanted(20, 3), 3);
    }

    #[test]
    fn shares_outside_zero_to_one_are_refused() {
        assert!(GoldChoice::share(0.0, 1).is_err());
        assert!(GoldChoice::share(1.0, 1).is_err());
        assert!(GoldChoice::share(f64::NAN, 1).is_err());
        assert!(GoldChoice::share(0.2, 1).is_ok());
    }

    #[test]
    fn a_drawn_share_is_seeded_sized_and_never_the_whole_dataset() {
        let items: Vec<i64> = (1..=50).collect();
        let a = draw_share(&items, 0.2, 7);
        assert_eq!(a.len(), 10);
        assert_eq!(a, draw_share(&items, 0.2, 7));
        assert_ne!(a, draw_share(&items, 0.2, 8));
        assert!(a.windows(2).all(|w| w[0] < w[1]));
        assert!(a.iter().all(|i| items.contains(i)));
        // At least one, and at most all but one.
        assert_eq!(draw_share(&items, 0.001, 1).len(), 1);
        assert_eq!(draw_share(&items, 0.999, 1).len(), 49);
        assert!(draw_share(&[], 0.5, 1).is_empty());
    }

    #[test]
    fn item_lists_skip_blanks_and_comments_and_name_repeats() {
        assert_eq!(
            parse_item_list("# gold\na\n\n  b  \n").unwrap(),
            vec!["a".to_owned(), "b".to_owned()]
        );
        assert_eq!(
            parse_item_list("a\nb\na\n").unwrap_err(),
            "line 3: item 'a' is listed already on line 1"
        );
        assert!(parse_item_list("# nothing\n\n").is_err());
    }

    #[test]
    fn each_annotator_gets_gold_items_it_does_not_hold_from_its_own_start() {
        let gold = [10, 20, 30, 40];
        assert_eq!(pick_for(&gold, 1, &HashSet::new(), 2), vec![20, 30]);
        assert_eq!(pick_for(&gold, 4, &HashSet::new(), 2), vec![10, 20]);
        let held: HashSet<i64> = [20].into();
        assert_eq!(pick_for(&gold, 1, &held, 2), vec![30, 40]);
        assert_eq!(pick_for(&gold, 1, &held, 9), vec![30, 40, 10]);
        assert!(pick_for(&[], 1, &held, 2).is_empty());
    }

    fn queued(name: &str, dataset: &str, gold: Option<i64>) -> QueuedEntry<String> {
        QueuedEntry {
            entry: name.to_owned(),
            dataset: dataset.to_owned(),
            gold_rate: gold.map(rate),
            attention_rate: None,
        }
    }

    #[test]
    fn attention_checks_stand_at_their_own_rate_beside_gold_items() {
        let check = |name: &str, r: i64| QueuedEntry {
            entry: name.to_owned(),
            dataset: "d".to_owned(),
            gold_rate: None,
            attention_rate: Some(rate(r)),
        };
        let queue = vec![
            check("t1", 2),
            queued("a", "d", None),
            queued("g1", "d", Some(2)),
            queued("b", "d", None),
            check("t2", 2),
            check("t3", 2),
        ];
        assert_eq!(mix(queue), ["a", "g1", "t1", "b", "t2", "t3"]);
    }

    #[test]
    fn gold_items_stand_after_every_rate_minus_one_items_of_their_dataset() {
        let queue = vec![
            queued("g1", "d", Some(3)),
            queued("a", "d", None),
            queued("x", "other", None),
            queued("b", "d", None),
            queued("c", "d", None),
            queued("g2", "d", Some(3)),
            queued("g3", "d", Some(3)),
            queued("d", "d", None),
        ];
        assert_eq!(mix(queue), ["a", "x", "b", "g1", "c", "d", "g2", "g3"]);
    }

    #[test]
    fn a_queue_without_gold_keeps_its_order() {
        let queue = vec![queued("a", "d", None), queued("b", "e", None)];
        assert_eq!(mix(queue), ["a", "b"]);
    }
}
