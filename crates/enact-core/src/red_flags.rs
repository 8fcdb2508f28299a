//! Red flags an admin sees on a dataset: a leaderboard row that beats the humans on the items
//! the humans answered, a submission that answers a hidden dataset with its ground truth, and
//! items or frames the dataset shares with a public one. Pure: the hub reads the facts, this
//! decides what is a flag. A flag is a reason to look, not a verdict: a strong model may beat
//! a few annotators, and a dataset may share frames with a public one on purpose.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::explorer::{Grid, is_right};
use crate::leaderboard::MIN_HUMAN_ANSWERS;

/// The share of a hidden dataset's items answered exactly as the truth above which a
/// submission is flagged, unless the admin sets another.
pub const DEFAULT_TRUTH_SHARE: f64 = 0.9;

/// A row whose task accuracy on the items the humans answered is above theirs there.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct AboveHuman {
    pub submission: i64,
    pub model: String,
    pub account: String,
    /// The items the Human row has answers on (the comparison's items).
    pub items: usize,
    /// The row's task accuracy on those items (an unanswered item is wrong).
    pub task_accuracy: f64,
    /// The humans' on the same items: per item the share of its answers that are right,
    /// averaged over the items, so an item answered three times weighs as one.
    pub human_task_accuracy: f64,
    pub human_answers: u32,
}

/// Rows of `grid` above the Human column on the items it has answers on. None while the
/// humans rest on fewer than [`MIN_HUMAN_ANSWERS`] answers (the leaderboard marks such a
/// Human row too). Baselines are reference rows and never flagged.
pub fn above_human(grid: &Grid) -> Vec<AboveHuman> {
    let judged: Vec<usize> = (0..grid.len())
        .filter(|&i| grid.human(i).answers > 0)
        .collect();
    let human_answers: u32 = judged.iter().map(|&i| grid.human(i).answers).sum();
    if judged.is_empty() || (human_answers as usize) < MIN_HUMAN_ANSWERS {
        return Vec::new();
    }
    let items = judged.len() as f64;
    let human_task_accuracy = judged
        .iter()
        .map(|&i| {
            let tally = grid.human(i);
            f64::from(tally.right) / f64::from(tally.answers)
        })
        .sum::<f64>()
        / items;
    grid.rows()
        .iter()
        .enumerate()
        .filter(|(_, row)| !row.baseline)
        .filter_map(|(r, row)| {
            let right = judged
                .iter()
                .filter(|&&i| is_right(grid.verdicts(i)[r]))
                .count();
            let task_accuracy = right as f64 / items;
            (task_accuracy > human_task_accuracy).then(|| AboveHuman {
                submission: row.submission,
                model: row.model.clone(),
                account: row.account.clone(),
                items: judged.len(),
                task_accuracy,
                human_task_accuracy,
                human_answers,
            })
        })
        .collect()
}

/// How many of a dataset's items one submission answered exactly as the truth.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExactAnswers {
    pub submission: i64,
    pub model: String,
    pub account: String,
    /// Whether it is on the leaderboard (a hidden or withdrawn one is flagged as well: probing
    /// a hidden dataset need not be published).
    pub listed: bool,
    pub exact: usize,
}

/// A submission that gave the truth itself on more than the set share of a hidden dataset.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct TruthCopy {
    pub submission: i64,
    pub model: String,
    pub account: String,
    pub listed: bool,
    /// Items answered exactly as the ground truth, of the dataset's `items`.
    pub exact: usize,
    pub items: usize,
    pub share: f64,
}

/// Submissions answering more than `threshold` of the dataset's `items` exactly as the truth.
pub fn identical_to_truth(counts: &[ExactAnswers], items: usize, threshold: f64) -> Vec<TruthCopy> {
    if items == 0 {
        return Vec::new();
    }
    counts
        .iter()
        .filter_map(|c| {
            let share = c.exact as f64 / items as f64;
            (share > threshold).then(|| TruthCopy {
                submission: c.submission,
                model: c.model.clone(),
                account: c.account.clone(),
                listed: c.listed,
                exact: c.exact,
                items,
                share,
            })
        })
        .collect()
}

/// Items (by content hash) and frames (by the SHA-256 of their bytes) a dataset shares with
/// a dataset whose answers are public: its ground truth is out there.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct Leak {
    /// The public dataset.
    pub dataset: String,
    pub items: usize,
    pub frames: usize,
}

/// A threshold for [`identical_to_truth`] as typed (`0.9`), or what is wrong with it.
pub fn parse_share(text: &str) -> Result<f64, String> {
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|s| (0.0..1.0).contains(s))
        .ok_or_else(|| {
            format!("share must be a number from 0 up to (not including) 1, not {text:?}")
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::{Direction, StepLength};
    use crate::explorer::{GridBuilder, GridItem, GridRow};
    use crate::submission::AnswerVerdict::{Exact, Missing, Wrong};

    fn grid(verdicts: &[[crate::submission::AnswerVerdict; 3]], humans: &[(u32, u32)]) -> Grid {
        let items = (0..verdicts.len())
            .map(|i| GridItem {
                id: format!("item-{i}"),
                direction: Direction::Forward,
                step_length: StepLength::new(3).expect("3"),
                activity: "a".to_owned(),
            })
            .collect();
        let rows = ["strong", "weak", "chance"]
            .iter()
            .enumerate()
            .map(|(r, m)| GridRow {
                submission: r as i64 + 1,
                model: (*m).to_owned(),
                account: "lab".to_owned(),
                baseline: *m == "chance",
            })
            .collect();
        let mut b = GridBuilder::new(items, rows);
        for (i, row) in verdicts.iter().enumerate() {
            for (r, v) in row.iter().enumerate() {
                b.verdict(i, r, *v);
            }
        }
        for (i, (right, answers)) in humans.iter().enumerate() {
            for k in 0..*answers {
                b.human_answer(i, false, k < *right);
            }
        }
        b.finish()
    }

    #[test]
    fn a_row_above_the_humans_on_their_items_is_flagged_and_a_baseline_never() {
        // Humans: item 0 two of two right, item 1 none of two, item 2 one of two; item 3 has no
        // human answer and does not count. Item-weighted human TA = (1 + 0 + 0.5) / 3 = 0.5.
        let g = grid(
            &[
                [Exact, Wrong, Exact],
                [Exact, Wrong, Exact],
                [Wrong, Exact, Exact],
                [Wrong, Wrong, Wrong],
            ],
            &[(2, 2), (0, 2), (1, 2), (0, 0)],
        );
        let flags = above_human(&g);
        assert_eq!(flags.len(), 1, "{flags:?}");
        let f = &flags[0];
        assert_eq!(
            (f.model.as_str(), f.items, f.human_answers),
            ("strong", 3, 6)
        );
        assert!((f.task_accuracy - 2.0 / 3.0).abs() < 1e-12);
        assert!((f.human_task_accuracy - 0.5).abs() < 1e-12);
    }

    #[test]
    fn equal_to_the_humans_is_not_above_and_too_few_answers_flag_nothing() {
        let g = grid(
            &[[Exact, Missing, Exact], [Wrong, Missing, Exact]],
            &[(2, 3), (1, 3)],
        );
        // Humans: (2/3 + 1/3) / 2 = 0.5; strong: 1 of 2 = 0.5.
        assert!(above_human(&g).is_empty());
        let few = grid(&[[Exact, Exact, Exact]], &[(0, 4)]);
        assert!(
            above_human(&few).is_empty(),
            "4 answers are fewer than the minimum"
        );
    }

    #[test]
    fn the_truth_share_is_strictly_above_the_threshold() {
        let counts = [
            ExactAnswers {
                submission: 1,
                model: "copy".into(),
                account: "x".into(),
                listed: false,
                exact: 10,
            },
            ExactAnswers {
                submission: 2,
                model: "edge".into(),
                account: "y".into(),
                listed: true,
                exact: 9,
            },
        ];
        let flags = identical_to_truth(&counts, 10, 0.9);
        assert_eq!(flags.len(), 1);
        assert_eq!(flags[0].submission, 1);
        assert_eq!(flags[0].share, 1.0);
        assert!(!flags[0].listed);
        assert_eq!(identical_to_truth(&counts, 10, 0.85).len(), 2);
        assert!(identical_to_truth(&counts, 0, 0.5).is_empty());
    }

    #[test]
    fn a_share_is_read_or_refused_by_name() {
        assert_eq!(parse_share("0.75"), Ok(0.75));
        for bad in ["1", "-0.1", "x", "NaN"] {
            assert!(parse_share(bad).unwrap_err().contains("share"), "{bad}");
        }
    }
}
