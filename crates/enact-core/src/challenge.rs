//! Hidden test sets that resist overfitting (pure; `enact_hub::app::challenge` stores and
//! serves them): a hidden dataset split into a public part, whose figures are shown while a
//! challenge runs, and a private part, revealed at a deadline or by hand.
//!
//! - [`draw_split`]: the seeded stratified draw of items into the two parts.
//! - [`part_scores`]: a submission's figures over one part, from its stored per-item verdicts,
//!   aggregated as the verifier aggregates a whole submission.
//! - [`counted_submissions`]: the selection rule, which submissions make an account's final rows.
//! - [`standings`]: each final row's rank over the public part, over the private part, and the
//!   change between them.
//! - [`Deadline`]: a reveal deadline read from RFC 3339 text and written as the store writes
//!   every timestamp.

use std::collections::{BTreeMap, BTreeSet};

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::dataset::{Direction, StepLength};
pub use crate::leaderboard::Standing;
use crate::leaderboard::{LeaderboardRow, one_per_model, rank};
use crate::submission::{ConfidenceIntervals, SubmissionScores, VerdictOutcome};
use crate::verifier::{
    BOOTSTRAP_LEVEL, BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED, Coverage, PerformanceReport, Resampling,
    ScoredEntry, ScoringPolicy, leaderboard_ci,
};

/// The part of a split dataset an item belongs to.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Part {
    /// Scored on the leaderboard while the challenge runs.
    Public,
    /// Kept back until the reveal.
    Private,
}

impl Part {
    pub const ALL: [Part; 2] = [Part::Public, Part::Private];

    pub fn as_str(self) -> &'static str {
        match self {
            Part::Public => "public",
            Part::Private => "private",
        }
    }

    pub fn parse(text: &str) -> Option<Part> {
        Part::ALL.into_iter().find(|p| p.as_str() == text)
    }
}

/// The share of each stratum's items drawn into the public part: above 0 and below 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PublicShare(f64);

impl PublicShare {
    /// `share`, refused (naming the field) unless it is above 0 and below 1.
    pub fn new(share: f64) -> Result<PublicShare, String> {
        if share.is_finite() && share > 0.0 && share < 1.0 {
            Ok(PublicShare(share))
        } else {
            Err(format!(
                "share: the public part's share of the items must be above 0 and below 1, not \
                 {share}"
            ))
        }
    }

    pub fn get(self) -> f64 {
        self.0
    }

    /// How many of a stratum's `n` items go public: `round(share × n)` (halves away from zero),
    /// but at least one item in each part when the stratum has two or more.
    pub fn public_count(self, n: usize) -> usize {
        let drawn = (self.0 * n as f64).round() as usize;
        if n >= 2 {
            drawn.clamp(1, n - 1)
        } else {
            drawn.min(n)
        }
    }
}

/// A stratum of the draw: an item's direction and step length.
pub type Stratum = (Direction, StepLength);

/// Draws every item into the public or the private part, stratum by stratum, so that each
/// direction and step length is split in the same proportion. `items` are the items' strata
/// in a fixed order (the hub passes them by item id); the result is each item's part, in that
/// order.
///
/// The rule, to reproduce a split elsewhere: within a stratum the members are taken in the given
/// order and shuffled (rand 0.9's `SliceRandom::shuffle`) by ChaCha8 seeded with
/// sha256(`challenge-split\0` ‖ seed as 8 little-endian bytes ‖ direction ‖ `\0` ‖ L in decimal
/// ‖ `\0`); the first [`PublicShare::public_count`] of the shuffled members are public, the
/// rest private. The same items, share and seed always give the same split, and a stratum's
/// draw does not depend on the others.
pub fn draw_split(items: &[Stratum], share: PublicShare, seed: u64) -> Vec<Part> {
    let mut strata: BTreeMap<Stratum, Vec<usize>> = BTreeMap::new();
    for (index, stratum) in items.iter().enumerate() {
        strata.entry(*stratum).or_default().push(index);
    }
    let mut parts = vec![Part::Private; items.len()];
    for ((direction, length), mut members) in strata {
        members.shuffle(&mut stratum_rng(seed, direction, length));
        for &index in &members[..share.public_count(members.len())] {
            parts[index] = Part::Public;
        }
    }
    parts
}

fn stratum_rng(seed: u64, direction: Direction, length: StepLength) -> ChaCha8Rng {
    let mut hasher = Sha256::new();
    hasher.update(b"challenge-split\0");
    hasher.update(seed.to_le_bytes());
    hasher.update(direction.as_str().as_bytes());
    hasher.update([0u8]);
    hasher.update(length.get().to_string().as_bytes());
    hasher.update([0u8]);
    ChaCha8Rng::from_seed(hasher.finalize().into())
}

/// How a stratum was split.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, JsonSchema)]
pub struct StratumSplit {
    pub direction: Direction,
    pub step_length: u8,
    pub public: usize,
    pub private: usize,
}

/// The public and private counts of every stratum, in stratum order.
pub fn split_counts(items: &[Stratum], parts: &[Part]) -> Vec<StratumSplit> {
    let mut counts: BTreeMap<Stratum, (usize, usize)> = BTreeMap::new();
    for (stratum, part) in items.iter().zip(parts) {
        let count = counts.entry(*stratum).or_default();
        match part {
            Part::Public => count.0 += 1,
            Part::Private => count.1 += 1,
        }
    }
    counts
        .into_iter()
        .map(|((direction, length), (public, private))| StratumSplit {
            direction,
            step_length: length.get(),
            public,
            private,
        })
        .collect()
}

/// One item's stored verdict, as a part's figures need it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartVerdict {
    pub direction: Direction,
    pub step_length: StepLength,
    /// The item's activity as a number: its cluster in the intervals' bootstrap.
    pub cluster: u32,
    pub outcome: VerdictOutcome,
    pub task_accuracy: bool,
    /// As stored: 0 for a missing or unreadable answer, `None` only for an exact-only item
    /// whose answer is not exact.
    pub pairwise_accuracy: Option<f64>,
    /// The item has no scene graphs, so it was scored by exact match only.
    pub exact_only: bool,
}

/// A submission's scores over one part: `verdicts` are its verdicts on the part's items, in
/// dataset order (the order fixes the float sums, as at submission). The report is aggregated
/// exactly as a whole submission's ([`PerformanceReport::from_entries`]), so over every item it
/// equals the stored scores; coverage counts the part's items; the overall intervals resample
/// activities. The item bootstrap's intervals are left out (a board computes these for every
/// row and part at each build), so a reader asking for them gets the activities' and is told.
pub fn part_scores(verdicts: &[PartVerdict]) -> SubmissionScores {
    let entries: Vec<ScoredEntry> = verdicts
        .iter()
        .map(|v| ScoredEntry {
            group: Some(v.direction),
            states: v.step_length.states(),
            task_accuracy: v.task_accuracy,
            pairwise_accuracy: v.pairwise_accuracy,
        })
        .collect();
    let items = verdicts.len();
    let answered = verdicts
        .iter()
        .filter(|v| v.outcome != VerdictOutcome::Missing)
        .count();
    let unparseable = verdicts
        .iter()
        .filter(|v| v.outcome == VerdictOutcome::Unparseable)
        .count();
    let ratio = |a: usize, b: usize| if b == 0 { 0.0 } else { a as f64 / b as f64 };
    let ta: Vec<(u32, f64)> = verdicts
        .iter()
        .map(|v| (v.cluster, f64::from(u8::from(v.task_accuracy))))
        .collect();
    let pa: Vec<(u32, f64)> = verdicts
        .iter()
        .filter_map(|v| v.pairwise_accuracy.map(|p| (v.cluster, p)))
        .collect();
    SubmissionScores {
        policy: ScoringPolicy::Strict,
        report: PerformanceReport::from_entries(&entries),
        coverage: Coverage {
            dataset_items: items,
            answered,
            missing: items - answered,
            unparseable,
            coverage: ratio(answered, items),
            parse_failure_rate: ratio(unparseable, answered),
            exact_only: verdicts
                .iter()
                .filter(|v| v.exact_only && v.outcome == VerdictOutcome::Scored)
                .count(),
        },
        confidence: ConfidenceIntervals {
            level: BOOTSTRAP_LEVEL,
            resamples: BOOTSTRAP_RESAMPLES,
            seed: BOOTSTRAP_SEED,
            resampling: Resampling::Activities,
            task_accuracy: leaderboard_ci(&ta, Resampling::Activities),
            pairwise_accuracy: leaderboard_ci(&pa, Resampling::Activities),
            by_items: None,
        },
    }
}

/// A listed submission as the selection rule sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Entry {
    pub submission: i64,
    pub account: i64,
    /// When its account selected it for the final ranking, as an order (a later selection is
    /// larger); `None` when it is not selected.
    pub selected: Option<i64>,
}

/// The selection rule: the submissions that make each account's final rows. An account's final
/// rows are the submissions it selected; past `limit` (an admin lowered the limit after they
/// were chosen) the `limit` it selected last. An account that selected none is represented by
/// its latest submission (the highest id), so every account that took part has a final row.
pub fn counted_submissions(entries: &[Entry], limit: Option<usize>) -> BTreeSet<i64> {
    let mut by_account: BTreeMap<i64, Vec<&Entry>> = BTreeMap::new();
    for entry in entries {
        by_account.entry(entry.account).or_default().push(entry);
    }
    let mut counted = BTreeSet::new();
    for entries in by_account.values() {
        let mut selected: Vec<&&Entry> = entries.iter().filter(|e| e.selected.is_some()).collect();
        if selected.is_empty() {
            counted.extend(entries.iter().map(|e| e.submission).max());
            continue;
        }
        selected.sort_by_key(|e| std::cmp::Reverse((e.selected, e.submission)));
        counted.extend(
            selected
                .into_iter()
                .take(limit.unwrap_or(usize::MAX))
                .map(|e| e.submission),
        );
    }
    counted
}

/// The standing of every final row, by submission: `public` and `private` are the same final
/// rows with their figures over each part. Each is cut to one row per account and model and
/// ranked by overall task accuracy with ties, as the board's default view is; reference rows
/// (baselines, Human) have no rank and so no change.
pub fn standings(public: &[LeaderboardRow], private: &[LeaderboardRow]) -> BTreeMap<i64, Standing> {
    let ranks = |rows: &[LeaderboardRow]| -> BTreeMap<i64, Option<usize>> {
        let mut rows = one_per_model(rows);
        rank(&mut rows);
        rows.into_iter()
            .filter_map(|r| r.submission.map(|id| (id, r.rank)))
            .collect()
    };
    let public = ranks(public);
    let private = ranks(private);
    private
        .iter()
        .map(|(&id, &private_rank)| {
            let public_rank = public.get(&id).copied().flatten();
            let rank_change = match (public_rank, private_rank) {
                (Some(p), Some(q)) => Some(p as i64 - q as i64),
                _ => None,
            };
            (
                id,
                Standing {
                    public_rank,
                    private_rank,
                    rank_change,
                },
            )
        })
        .collect()
}

/// A moment in UTC to the second, such as a reveal deadline.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Deadline(i64);

impl Deadline {
    /// The moment `seconds` after 1970-01-01T00:00:00Z.
    pub fn from_unix(seconds: i64) -> Deadline {
        Deadline(seconds)
    }

    pub fn unix(self) -> i64 {
        self.0
    }

    /// Reads RFC 3339 (`2026-07-01T12:00:00Z`, `2026-07-01T14:00:00+02:00`, fractions of a
    /// second dropped), years 1970 to 9999; the message says what is wrong.
    pub fn parse(text: &str) -> Result<Deadline, String> {
        let refuse = |why: &str| {
            format!("{text:?} is not a UTC time of the form 2026-07-01T12:00:00Z (RFC 3339): {why}")
        };
        let t = text.trim().as_bytes();
        let digits = |range: std::ops::Range<usize>| -> Option<i64> {
            let part = t.get(range)?;
            part.iter()
                .all(u8::is_ascii_digit)
                .then(|| part.iter().fold(0, |n, d| n * 10 + i64::from(d - b'0')))
        };
        let (Some(year), Some(month), Some(day), Some(hour), Some(minute), Some(second)) = (
            digits(0..4),
            digits(5..7),
            digits(8..10),
            digits(11..13),
            digits(14..16),
            digits(17..19),
        ) else {
            return Err(refuse("the date or the time is incomplete"));
        };
        if t[4] != b'-' || t[7] != b'-' || !matches!(t[10], b'T' | b't' | b' ') {
            return Err(refuse("the date must be YYYY-MM-DD, followed by T"));
        }
        if t[13] != b':' || t[16] != b':' {
            return Err(refuse("the time must be HH:MM:SS"));
        }
        let mut rest = &t[19..];
        if let Some(fraction) = rest.strip_prefix(b".") {
            let kept = fraction.iter().take_while(|c| c.is_ascii_digit()).count();
            if kept == 0 {
                return Err(refuse("a fraction of a second needs digits"));
            }
            rest = &fraction[kept..];
        }
        let offset = match rest {
            b"Z" | b"z" => 0,
            [sign @ (b'+' | b'-'), h1, h2, b':', m1, m2]
                if [h1, h2, m1, m2].iter().all(|d| d.is_ascii_digit()) =>
            {
                let value = |a: &u8, b: &u8| i64::from(a - b'0') * 10 + i64::from(b - b'0');
                let (hours, minutes) = (value(h1, h2), value(m1, m2));
                if hours > 23 || minutes > 59 {
                    return Err(refuse("the offset is out of range"));
                }
                let seconds = hours * 3600 + minutes * 60;
                if *sign == b'+' { seconds } else { -seconds }
            }
            _ => return Err(refuse("it must end with Z or an offset such as +02:00")),
        };
        if !(1970..=9999).contains(&year) {
            return Err(refuse("the year must be from 1970 to 9999"));
        }
        if !(1..=12).contains(&month) || day < 1 || day > days_in_month(year, month) {
            return Err(refuse("there is no such day"));
        }
        if hour > 23 || minute > 59 || second > 60 {
            return Err(refuse("there is no such time of day"));
        }
        // A leap second is read as the second after it.
        let seconds =
            days_from_civil(year, month, day) * 86_400 + hour * 3600 + minute * 60 + second
                - offset;
        if !(0..=MAX_SECONDS).contains(&seconds) {
            return Err(refuse("the year must be from 1970 to 9999"));
        }
        Ok(Deadline(seconds))
    }

    /// As every timestamp column is written: `2026-07-01T12:00:00Z`.
    pub fn text(self) -> String {
        let days = self.0.div_euclid(86_400);
        let second_of_day = self.0.rem_euclid(86_400);
        let (year, month, day) = civil_from_days(days);
        format!(
            "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
            second_of_day / 3600,
            second_of_day / 60 % 60,
            second_of_day % 60
        )
    }
}

/// 9999-12-31T23:59:59Z.
const MAX_SECONDS: i64 = 253_402_300_799;

fn days_in_month(year: i64, month: i64) -> i64 {
    match month {
        2 if (year % 4 == 0 && year % 100 != 0) || year % 400 == 0 => 29,
        2 => 28,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    }
}

/// Days from 1970-01-01 to a date of the proleptic Gregorian calendar (H. Hinnant's
/// `days_from_civil`).
fn days_from_civil(year: i64, month: i64, day: i64) -> i64 {
    let y = if month <= 2 { year - 1 } else { year };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (month + 9) % 12;
    let doy = (153 * mp + 2) / 5 + day - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// The date `days` after 1970-01-01 (the inverse of [`days_from_civil`]).
fn civil_from_days(days: i64) -> (i64, i64, i64) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    (year, month, day)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leaderboard::RowIdentity;
    use crate::metric::METRIC_VERSION;
    use crate::scoring::ScoringTarget;
    use crate::submission::{Provenance, score_submission};
    use crate::verifier::{Permutation, cluster_ids};

    fn length(l: usize) -> StepLength {
        StepLength::new(l).expect("a step length")
    }

    fn share(s: f64) -> PublicShare {
        PublicShare::new(s).expect("a share")
    }

    #[test]
    fn a_share_is_above_0_and_below_1_and_rounds_per_stratum() {
        for bad in [0.0, 1.0, -0.5, 1.5, f64::NAN, f64::INFINITY] {
            let e = PublicShare::new(bad).expect_err("refused");
            assert!(e.starts_with("share:"), "{e}");
        }
        let half = share(0.5);
        // round(0.5 × n), halves away from zero, and one at least on each side from 2 items.
        let counts: Vec<usize> = (0..=6).map(|n| half.public_count(n)).collect();
        assert_eq!(counts, vec![0, 1, 1, 2, 2, 3, 3]);
        assert_eq!(share(0.01).public_count(10), 1);
        assert_eq!(share(0.99).public_count(10), 9);
        assert_eq!(share(0.3).public_count(1), 0);
        assert_eq!(share(0.7).public_count(1), 1);
    }

    #[test]
    fn the_draw_is_stratified_seeded_and_stable() {
        // Forward L=3: 10 items; inverse L=3: 4; forward L=5: 1; inverse L=4: 2.
        let mut items = Vec::new();
        items.extend(std::iter::repeat_n((Direction::Forward, length(3)), 10));
        items.extend(std::iter::repeat_n((Direction::Inverse, length(3)), 4));
        items.push((Direction::Forward, length(5)));
        items.extend(std::iter::repeat_n((Direction::Inverse, length(4)), 2));
        let parts = draw_split(&items, share(0.3), 7);
        assert_eq!(parts.len(), items.len());
        let counts = split_counts(&items, &parts);
        let shape: Vec<(Direction, u8, usize, usize)> = counts
            .iter()
            .map(|c| (c.direction, c.step_length, c.public, c.private))
            .collect();
        assert_eq!(
            shape,
            vec![
                (Direction::Forward, 3, 3, 7),
                (Direction::Forward, 5, 0, 1),
                (Direction::Inverse, 3, 1, 3),
                (Direction::Inverse, 4, 1, 1),
            ]
        );
        // The same seed, the same split; each stratum's draw is its own: adding items to
        // another stratum leaves this one's as it was.
        assert_eq!(draw_split(&items, share(0.3), 7), parts);
        let mut more = items.clone();
        more.extend(std::iter::repeat_n((Direction::Inverse, length(9)), 5));
        assert_eq!(&draw_split(&more, share(0.3), 7)[..items.len()], &parts[..]);
        // Another seed draws other items of the same counts.
        let other = draw_split(&items, share(0.3), 8);
        assert_ne!(other, parts);
        assert_eq!(split_counts(&items, &other), counts);
    }

    #[test]
    fn the_draw_is_the_documented_shuffle() {
        // The rule written out: ChaCha8 from sha256(tag, seed, direction, L), shuffle, take.
        let items = vec![(Direction::Inverse, length(6)); 5];
        let mut hasher = Sha256::new();
        hasher.update(b"challenge-split\0");
        hasher.update(42u64.to_le_bytes());
        hasher.update(b"inverse\x006\x00");
        let mut rng = ChaCha8Rng::from_seed(hasher.finalize().into());
        let mut order: Vec<usize> = (0..5).collect();
        order.shuffle(&mut rng);
        let mut expected = vec![Part::Private; 5];
        for &i in &order[..2] {
            expected[i] = Part::Public;
        }
        assert_eq!(draw_split(&items, share(0.4), 42), expected);
    }

    fn targets() -> Vec<ScoringTarget> {
        (0..6)
            .map(|i| {
                let (direction, l) = if i % 2 == 0 {
                    (Direction::Forward, 3)
                } else {
                    (Direction::Inverse, 4)
                };
                ScoringTarget {
                    id: format!("item{i}"),
                    item_type: format!("{}_world_modeling_{l}_steps", direction.as_str()),
                    task_name: format!("task{}", i / 3),
                    direction,
                    step_length: length(l),
                    ground_truth: Permutation::new((1..l as u8).rev().collect()).expect("perm"),
                    semantics: None,
                }
            })
            .collect()
    }

    /// Item 0 right, 1 wrong, 2 unreadable, 3 right, 4 missing, 5 right.
    const BODY: &str = "{\"id\":\"item0\",\"answer\":\"[2, 1]\"}\n\
                        {\"id\":\"item1\",\"answer\":[1,2,3]}\n\
                        {\"id\":\"item2\",\"answer\":\"no idea\"}\n\
                        {\"id\":\"item3\",\"answer\":[3,2,1]}\n\
                        {\"id\":\"item5\",\"answer\":\"[3, 2, 1]\"}\n";

    fn part_verdicts(targets: &[ScoringTarget], body: &str) -> Vec<PartVerdict> {
        let scored = score_submission(targets, body).expect("scored");
        let clusters = cluster_ids(targets.iter().map(|t| t.task_name.as_str()));
        scored
            .items
            .iter()
            .map(|v| {
                let t = &targets[v.target];
                PartVerdict {
                    direction: t.direction,
                    step_length: t.step_length,
                    cluster: clusters[v.target],
                    outcome: VerdictOutcome::of(&v.outcome),
                    task_accuracy: v.task_accuracy,
                    pairwise_accuracy: v.pairwise_accuracy,
                    exact_only: t.semantics.is_none(),
                }
            })
            .collect()
    }

    #[test]
    fn a_part_over_every_item_gives_the_submission_s_own_figures() {
        let targets = targets();
        let whole = score_submission(&targets, BODY).expect("scored").scores;
        let all = part_scores(&part_verdicts(&targets, BODY));
        assert_eq!(all.report, whole.report);
        assert_eq!(all.coverage, whole.coverage);
        assert_eq!(all.confidence.task_accuracy, whole.confidence.task_accuracy);
        assert_eq!(
            all.confidence.pairwise_accuracy,
            whole.confidence.pairwise_accuracy
        );
        assert_eq!(all.confidence.by_items, None);
    }

    #[test]
    fn a_part_s_figures_are_over_its_items_only() {
        let targets = targets();
        let verdicts = part_verdicts(&targets, BODY);
        // The part {1, 2, 3, 4}: forward items 2 (unreadable) and 4 (missing), inverse items 1
        // (wrong) and 3 (right).
        let part: Vec<PartVerdict> = verdicts[1..5].to_vec();
        let scores = part_scores(&part);
        let overall = scores.report.overall.as_ref().expect("overall");
        assert_eq!(overall.totals.count, 4);
        assert_eq!(overall.totals.task_accuracy, 0.25);
        let forward = scores.report.forward_world_modeling.expect("forward");
        assert_eq!(forward.totals.count, 2);
        assert_eq!(forward.totals.task_accuracy, 0.0);
        assert_eq!(forward.totals.pairwise_accuracy, Some(0.0));
        let inverse = scores.report.inverse_world_modeling.expect("inverse");
        assert_eq!(inverse.totals.task_accuracy, 0.5);
        assert_eq!(inverse.per_step[&4].count, 2);
        assert_eq!(scores.coverage.dataset_items, 4);
        assert_eq!(scores.coverage.answered, 3);
        assert_eq!(scores.coverage.missing, 1);
        assert_eq!(scores.coverage.unparseable, 1);
        assert_eq!(scores.coverage.coverage, 0.75);
        assert_eq!(scores.coverage.parse_failure_rate, 1.0 / 3.0);
        let ci = scores.confidence.task_accuracy.expect("an interval");
        assert!(ci.low <= 0.25 && 0.25 <= ci.high, "{ci:?}");
        // No item: no figures, no interval.
        let none = part_scores(&[]);
        assert_eq!(none.report, PerformanceReport::default());
        assert_eq!(none.coverage.coverage, 0.0);
        assert_eq!(none.confidence.task_accuracy, None);
    }

    fn entry(submission: i64, account: i64, selected: Option<i64>) -> Entry {
        Entry {
            submission,
            account,
            selected,
        }
    }

    #[test]
    fn an_account_s_selected_submissions_count_else_its_latest() {
        let entries = [
            // Account 1 selected 2 and then 1; 3 is its latest.
            entry(1, 1, Some(20)),
            entry(2, 1, Some(10)),
            entry(3, 1, None),
            // Account 2 selected nothing: its latest, 5, counts.
            entry(4, 2, None),
            entry(5, 2, None),
            // Account 3 selected its only one.
            entry(6, 3, Some(30)),
        ];
        let ids = |s: BTreeSet<i64>| s.into_iter().collect::<Vec<_>>();
        assert_eq!(ids(counted_submissions(&entries, None)), vec![1, 2, 5, 6]);
        assert_eq!(
            ids(counted_submissions(&entries, Some(2))),
            vec![1, 2, 5, 6]
        );
        // A limit lowered below what account 1 selected keeps what it selected last.
        assert_eq!(ids(counted_submissions(&entries, Some(1))), vec![1, 5, 6]);
        assert!(counted_submissions(&[], Some(1)).is_empty());
    }

    fn row(id: i64, account: &str, ta: f64) -> LeaderboardRow {
        let scores: SubmissionScores = serde_json::from_value(serde_json::json!({
            "policy": "strict",
            "report": {"overall": {"count": 10, "task_accuracy": ta, "pairwise_accuracy": ta,
                "pairwise_count": 10, "per_step": {}}},
            "coverage": {"dataset_items": 10, "answered": 10, "missing": 0, "unparseable": 0,
                "coverage": 1.0, "parse_failure_rate": 0.0, "exact_only": 0},
            "confidence": {"level": 0.95, "resamples": 1000, "seed": 0,
                "task_accuracy": null, "pairwise_accuracy": null}
        }))
        .expect("scores");
        LeaderboardRow::from_scores(
            &RowIdentity {
                submission: id,
                model: "m",
                account,
                baseline: false,
                submitted_at: "2026-01-01T00:00:00Z",
                metric_version: METRIC_VERSION,
                provenance: Provenance::Submitted,
                run: None,
            },
            &scores,
        )
    }

    #[test]
    fn standings_give_each_part_s_rank_and_the_change() {
        let public = [row(1, "a", 0.9), row(2, "b", 0.6), row(3, "c", 0.6)];
        let private = [row(1, "a", 0.2), row(2, "b", 0.7), row(3, "c", 0.5)];
        let s = standings(&public, &private);
        let standing = |public: usize, private: usize, change: i64| Standing {
            public_rank: Some(public),
            private_rank: Some(private),
            rank_change: Some(change),
        };
        // Public: a 1st, b and c tied 2nd. Private: b 1st, c 2nd, a 3rd.
        assert_eq!(
            s.into_iter().collect::<Vec<_>>(),
            vec![
                (1, standing(1, 3, -2)),
                (2, standing(2, 1, 1)),
                (3, standing(2, 2, 0)),
            ]
        );
        // A baseline is not ranked, so it has no change.
        let mut baseline = row(4, "d", 0.99);
        baseline.baseline = true;
        let s = standings(&[baseline.clone()], &[baseline]);
        assert_eq!(s[&4].rank_change, None);
    }

    #[test]
    fn deadlines_read_rfc_3339_and_write_the_store_s_format() {
        let d = Deadline::parse("2026-07-01T12:00:00Z").expect("a deadline");
        assert_eq!(d.text(), "2026-07-01T12:00:00Z");
        assert_eq!(d.unix(), 1_782_907_200);
        assert_eq!(
            Deadline::parse("2026-07-01T14:30:00.25+02:30").expect("offset"),
            d
        );
        assert_eq!(
            Deadline::parse("2026-06-30T23:00:00-13:00")
                .expect("a negative offset")
                .text(),
            "2026-07-01T12:00:00Z"
        );
        assert_eq!(Deadline::from_unix(0).text(), "1970-01-01T00:00:00Z");
        assert_eq!(
            Deadline::parse("2024-02-29T23:59:59Z")
                .expect("a leap day")
                .text(),
            "2024-02-29T23:59:59Z"
        );
        for bad in [
            "",
            "tomorrow",
            "2026-07-01",
            "2026-07-01T12:00:00",
            "2026-07-01T12:00Z",
            "2026-02-29T00:00:00Z",
            "2026-13-01T00:00:00Z",
            "2026-07-01T24:00:00Z",
            "1969-12-31T23:59:59Z",
            "2026-07-01T12:00:00+25:00",
            "2026-07-01T12:00:00.Z",
        ] {
            let e = Deadline::parse(bad).expect_err(bad);
            assert!(e.contains("RFC 3339"), "{bad}: {e}");
        }
        // Dates round-trip through the day count across centuries.
        for days in [-1, 0, 59, 365, 10_957, 2_932_896] {
            let (y, m, d) = civil_from_days(days);
            assert_eq!(days_from_civil(y, m, d), days);
        }
    }
}
