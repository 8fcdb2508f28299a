//! Why one answer is wrong, in the verifier's own terms: for each step of the answer, whether
//! the verifier accepts it, the state changes the answer implies there that the true step does
//! not have, and those of the true step it misses, in ENACT's sentences ("The fridge is no
//! longer open."). The item page shows it beside every wrong answer.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::classify::compare_step;
use super::component::Component;
use super::steps::{StepsUnavailable, answer_steps};
use crate::verifier::{Direction, ItemSignatures, Permutation};

/// One step of an answer, judged.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct StepWhy {
    /// 1-based: the first transition after the current state is step 1.
    pub step: usize,
    /// The label the answer put at this step.
    pub label: u8,
    /// Whether the verifier accepts the step (it counts toward pairwise accuracy).
    pub accepted: bool,
    /// Changes the answer implies at this step that the true step does not have.
    pub implied: Vec<String>,
    /// Changes of the true step that the answer's step does not have.
    pub missed: Vec<String>,
}

/// An answer's steps, judged, with how many the verifier rejects, and the pairs of labels it
/// puts in the opposite order to the truth's.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct AnswerWhy {
    pub steps: Vec<StepWhy>,
    pub rejected_steps: usize,
    /// `[x, y]`: the truth has label `x` before `y`, the answer after it.
    pub pairs_out_of_order: Vec<[u8; 2]>,
}

/// The pairs of labels `answer` orders against `truth` (both permutations of the same labels),
/// each as the truth orders it, in the truth's order.
pub fn pairs_out_of_order(truth: &Permutation, answer: &Permutation) -> Vec<[u8; 2]> {
    let mut place = vec![0usize; answer.len() + 1];
    for (i, &label) in answer.labels().iter().enumerate() {
        if let Some(p) = place.get_mut(usize::from(label)) {
            *p = i;
        }
    }
    let labels = truth.labels();
    let mut pairs = Vec::new();
    for (i, &x) in labels.iter().enumerate() {
        for &y in &labels[i + 1..] {
            let at = |label: u8| place.get(usize::from(label)).copied().unwrap_or(0);
            if at(x) > at(y) {
                pairs.push([x, y]);
            }
        }
    }
    pairs
}

fn sentences(components: &[Component]) -> Vec<String> {
    components.iter().map(Component::sentence).collect()
}

/// Why `answer` (a permutation of the item's labels, of the truth's length) is judged as it is.
pub fn why(
    direction: Direction,
    truth: &Permutation,
    answer: &Permutation,
    table: &ItemSignatures,
) -> Result<AnswerWhy, StepsUnavailable> {
    let steps: Vec<StepWhy> = answer_steps(direction, truth, answer, table)?
        .into_iter()
        .zip(answer.labels())
        .enumerate()
        .map(|(k, (sets, &label))| {
            let compared = compare_step(&sets.truth, &sets.predicted);
            StepWhy {
                step: k + 1,
                label,
                accepted: sets.accepted,
                implied: sentences(&compared.hallucinated),
                missed: sentences(&compared.missing),
            }
        })
        .collect();
    Ok(AnswerWhy {
        rejected_steps: steps.iter().filter(|s| !s.accepted).count(),
        steps,
        pairs_out_of_order: pairs_out_of_order(truth, answer),
    })
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;
    use crate::verifier::VisibleCoverage;

    const BURNER_ON: &str = "node_add_the burner_ToggledOn";
    const GRASP: &str = "edge_add_the robot r1_the apple_RightGrasping";
    const RELEASE: &str = "edge_remove_the robot r1_the apple_RightGrasping";
    const BURNER_OFF: &str = "node_remove_the burner_ToggledOn";

    /// Key frames k0, k1, k2: the burner goes on, then the robot grasps the apple.
    fn table() -> ItemSignatures {
        let ids: Vec<String> = ["k0", "k1", "k2"].map(str::to_owned).to_vec();
        ItemSignatures::build(&ids, VisibleCoverage::AllPairs, |from, to, _| {
            let set: &[&str] = match (from, to) {
                ("k0", "k1") => &[BURNER_ON],
                ("k1", "k2") => &[GRASP],
                ("k0", "k2") => &[BURNER_ON, GRASP],
                ("k1", "k0") => &[BURNER_OFF],
                ("k2", "k1") => &[RELEASE],
                ("k2", "k0") => &[BURNER_OFF, RELEASE],
                _ => &[],
            };
            Ok(set.iter().map(|s| (*s).to_owned()).collect::<BTreeSet<_>>())
        })
    }

    fn sentence(signature: &str) -> String {
        Component::parse(signature).expect("signature").sentence()
    }

    #[test]
    fn a_swapped_forward_answer_says_which_changes_it_implies_and_misses() {
        let truth = Permutation::new(vec![1, 2]).expect("truth");
        let swapped = Permutation::new(vec![2, 1]).expect("answer");
        let w = why(Direction::Forward, &truth, &swapped, &table()).expect("steps");
        // Step 1 jumps to k2: it holds the burner's change (accepted) and also the grasp.
        assert!(w.steps[0].accepted);
        assert_eq!(w.steps[0].implied, [sentence(GRASP)]);
        assert!(w.steps[0].missed.is_empty());
        // Step 2 goes back from k2 to k1: the apple is released, not grasped.
        assert!(!w.steps[1].accepted);
        assert_eq!((w.steps[1].step, w.steps[1].label), (2, 1));
        assert_eq!(w.steps[1].implied, [sentence(RELEASE)]);
        assert_eq!(w.steps[1].missed, [sentence(GRASP)]);
        assert_eq!(w.rejected_steps, 1);
        assert_eq!(w.pairs_out_of_order, [[1, 2]]);

        let exact = why(Direction::Forward, &truth, &truth, &table()).expect("steps");
        assert_eq!(exact.rejected_steps, 0);
        assert!(exact.pairs_out_of_order.is_empty());
        assert!(
            exact
                .steps
                .iter()
                .all(|s| s.implied.is_empty() && s.missed.is_empty())
        );
    }

    #[test]
    fn a_swapped_inverse_answer_names_the_actions_changes() {
        let truth = Permutation::new(vec![1, 2]).expect("truth");
        let swapped = Permutation::new(vec![2, 1]).expect("answer");
        let w = why(Direction::Inverse, &truth, &swapped, &table()).expect("steps");
        // Step 1 is said to be action 2, which grasps the apple; the burner went on.
        assert!(!w.steps[0].accepted);
        assert_eq!(w.steps[0].implied, [sentence(GRASP)]);
        assert_eq!(w.steps[0].missed, [sentence(BURNER_ON)]);
        assert_eq!(w.rejected_steps, 2);
        // The true order: each action's change lies within its own step's full change.
        let exact = why(Direction::Inverse, &truth, &truth, &table()).expect("steps");
        assert_eq!(exact.rejected_steps, 0);
        assert!(exact.steps.iter().all(|s| s.accepted));
        let short = Permutation::new(vec![1]).expect("answer");
        assert!(why(Direction::Inverse, &truth, &short, &table()).is_err());
    }

    #[test]
    fn pairs_out_of_order_are_named_as_the_truth_orders_them() {
        let p = |labels: &[u8]| Permutation::new(labels.to_vec()).expect("permutation");
        assert_eq!(
            pairs_out_of_order(&p(&[3, 1, 2]), &p(&[3, 1, 2])),
            Vec::<[u8; 2]>::new()
        );
        // By hand: the truth orders 3 < 1 < 2; the answer 2, 3, 1 puts 2 before both.
        assert_eq!(
            pairs_out_of_order(&p(&[3, 1, 2]), &p(&[2, 3, 1])),
            [[3, 2], [1, 2]]
        );
        let reversed = pairs_out_of_order(&p(&[1, 2, 3, 4]), &p(&[4, 3, 2, 1]));
        assert_eq!(reversed.len(), 6, "every pair of four");
    }
}
