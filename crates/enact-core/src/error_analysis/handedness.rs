//! Left- and right-hand use (the paper's "Dataset-Level Detection of Left–Right Hand
//! Confusion"): per hand, precision (matched over predicted), recall (matched over true) and
//! the mixing rate (true components of this hand attributed to the other one, over true
//! components of this hand).
//!
//! Mixing is decided per step, on the set-level differences: when the missing components hold
//! this hand and the hallucinated ones hold the other hand but not this one, every missing
//! component of this hand counts as mixed.
//!
//! Standard errors are binomial, `sqrt(p (1 − p) / n)` over the ratio's denominator; a ratio
//! with a zero denominator is `null`.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::classify::StepComparison;
use super::component::Hand;

/// Counts for one hand.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct HandTally {
    pub truth: usize,
    pub predicted: usize,
    pub matched: usize,
    pub mixed: usize,
}

impl HandTally {
    /// Adds one step's counts for `hand`.
    pub fn add(&mut self, hand: Hand, step: &StepComparison) {
        let of =
            |cs: &[super::Component], h: Hand| cs.iter().filter(|c| c.hand() == Some(h)).count();
        let matched = of(&step.matched, hand);
        let missing = of(&step.missing, hand);
        let hallucinated = of(&step.hallucinated, hand);
        self.matched += matched;
        self.truth += matched + missing;
        self.predicted += matched + hallucinated;
        if missing > 0 && hallucinated == 0 && of(&step.hallucinated, hand.other()) > 0 {
            self.mixed += missing;
        }
    }

    pub fn figures(&self) -> HandFigures {
        let (precision, precision_se) = proportion(self.matched, self.predicted);
        let (recall, recall_se) = proportion(self.matched, self.truth);
        let (mixing, mixing_se) = proportion(self.mixed, self.truth);
        HandFigures {
            truth: self.truth,
            predicted: self.predicted,
            matched: self.matched,
            mixed: self.mixed,
            precision,
            precision_se,
            recall,
            recall_se,
            mixing,
            mixing_se,
        }
    }
}

fn proportion(part: usize, whole: usize) -> (Option<f64>, Option<f64>) {
    if whole == 0 {
        return (None, None);
    }
    let p = part as f64 / whole as f64;
    (Some(p), Some((p * (1.0 - p) / whole as f64).sqrt()))
}

/// One hand's figures.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct HandFigures {
    pub truth: usize,
    pub predicted: usize,
    pub matched: usize,
    pub mixed: usize,
    pub precision: Option<f64>,
    pub precision_se: Option<f64>,
    pub recall: Option<f64>,
    pub recall_se: Option<f64>,
    pub mixing: Option<f64>,
    pub mixing_se: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error_analysis::{Component, compare_step};

    fn step(truth: &[&str], predicted: &[&str]) -> StepComparison {
        let p = |v: &[&str]| {
            v.iter()
                .map(|s| Component::parse(s).unwrap())
                .collect::<Vec<_>>()
        };
        compare_step(&p(truth), &p(predicted))
    }

    const LEFT_A: &str = "edge_add_the robot r1_the a_LeftGrasping";
    const RIGHT_A: &str = "edge_add_the robot r1_the a_RightGrasping";
    const LEFT_B: &str = "edge_remove_the robot r1_the b_LeftGrasping";
    const RIGHT_B: &str = "edge_remove_the robot r1_the b_RightGrasping";

    fn tallies(steps: &[StepComparison]) -> (HandTally, HandTally) {
        let (mut left, mut right) = (HandTally::default(), HandTally::default());
        for s in steps {
            left.add(Hand::Left, s);
            right.add(Hand::Right, s);
        }
        (left, right)
    }

    #[test]
    fn left_mixed_into_right() {
        let (left, right) = tallies(&[step(&[LEFT_A, LEFT_B], &[RIGHT_A])]);
        assert_eq!(
            left,
            HandTally {
                truth: 2,
                predicted: 0,
                matched: 0,
                mixed: 2
            }
        );
        assert_eq!(
            right,
            HandTally {
                truth: 0,
                predicted: 1,
                matched: 0,
                mixed: 0
            }
        );
        let f = left.figures();
        assert_eq!(f.mixing, Some(1.0));
        assert_eq!(f.mixing_se, Some(0.0));
        assert_eq!(f.precision, None);
    }

    #[test]
    fn right_mixed_into_left() {
        let (left, right) = tallies(&[step(&[RIGHT_B], &[LEFT_B]), step(&[RIGHT_A], &[RIGHT_A])]);
        assert_eq!(
            right,
            HandTally {
                truth: 2,
                predicted: 1,
                matched: 1,
                mixed: 1
            }
        );
        assert_eq!(left.mixed, 0);
        let f = right.figures();
        assert_eq!(
            (f.precision, f.recall, f.mixing),
            (Some(1.0), Some(0.5), Some(0.5))
        );
        assert!((f.mixing_se.unwrap() - (0.25f64 / 2.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn no_mixing_when_the_same_hand_is_also_hallucinated() {
        // The paper's algorithm skips the step when the hallucinated side holds the same hand.
        let (left, _) = tallies(&[step(&[LEFT_A], &[RIGHT_A, LEFT_B])]);
        assert_eq!(left.mixed, 0);
        assert_eq!(left.truth, 1);
        assert_eq!(left.predicted, 1);
    }

    #[test]
    fn no_mixing_without_the_other_hand() {
        let (left, _) = tallies(&[step(&[LEFT_A], &["edge_add_the a_the b_Inside"])]);
        assert_eq!(left.mixed, 0);
    }
}
