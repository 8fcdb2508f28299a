//! Action text: turns a [`StateDiff`] into the 1–5 sentence descriptions ENACT puts in its
//! prompts, using ENACT's sentence templates and predicate phrases.

use rand::Rng;
use rand::seq::IndexedRandom;

use crate::demo::diff::{EdgeState, NodeState, StateDiff};

/// Phrasings of a gained unary state; `{}` order: object, state phrase.
const NODE_GAINED: [&str; 4] = [
    "now becomes",
    "becomes",
    "changes to be",
    "transitions to be",
];
/// Phrasings of a lost unary state or relation.
const LOST: [&str; 2] = ["is no longer", "stopped being"];

fn node_phrase(state: NodeState) -> &'static str {
    match state {
        NodeState::Cooked => "cooked",
        NodeState::Open => "open",
        NodeState::ToggledOn => "turned on",
    }
}

fn edge_phrase(state: EdgeState) -> &'static str {
    match state {
        EdgeState::Inside => "inside",
        EdgeState::OnTop => "on top of and touching",
        EdgeState::LeftGrasping => "using the left gripper to grasp",
        EdgeState::RightGrasping => "using the right gripper to grasp",
    }
}

/// ENACT quirk: sentences go through Python's `str.capitalize`, which upper-cases the first
/// character and lower-cases all the others (so "The robot R1" could never appear).
fn python_capitalize(sentence: &str) -> String {
    let mut chars = sentence.chars();
    match chars.next() {
        Some(first) => first
            .to_uppercase()
            .chain(chars.flat_map(char::to_lowercase))
            .collect(),
        None => String::new(),
    }
}

/// The lower-case sentences for a diff in ENACT's order: added node states, added relations,
/// lost node states, lost relations, then objects that turned into other objects.
pub(crate) fn sentences<R: Rng + ?Sized>(diff: &StateDiff, rng: &mut R) -> Vec<String> {
    let mut out = Vec::new();
    for (side, verbs) in [(&diff.add, &NODE_GAINED[..]), (&diff.remove, &LOST[..])] {
        for node in &side.nodes {
            for state in &node.states {
                let verb = verbs.choose(rng).copied().unwrap_or(verbs[0]);
                out.push(format!(
                    "{} {verb} {}",
                    node.thing.phrase(),
                    node_phrase(*state)
                ));
            }
        }
        for edge in &side.edges {
            for state in &edge.states {
                let verb = verbs.choose(rng).copied().unwrap_or(verbs[0]);
                out.push(format!(
                    "{} {verb} {} {}",
                    edge.from.phrase(),
                    edge_phrase(*state),
                    edge.to.phrase()
                ));
            }
        }
    }
    for transition in diff.transitions() {
        out.push(format!(
            "{} now becomes {}",
            transition.from.phrase(),
            transition.to.phrase()
        ));
    }
    out
}

/// The action text for a diff ("The fridge becomes open. The robot r1 ..."), or `None` when
/// nothing describable changed.
pub(crate) fn action_text<R: Rng + ?Sized>(diff: &StateDiff, rng: &mut R) -> Option<String> {
    let sentences = sentences(diff, rng);
    if sentences.is_empty() {
        return None;
    }
    let capitalised: Vec<String> = sentences.iter().map(|s| python_capitalize(s)).collect();
    Some(capitalised.join(". ") + ".")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::diff::SceneGraph;
    use crate::demo::world::{Gripper, Step, Thing, activities};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn capitalize_lowers_everything_after_the_first_character() {
        assert_eq!(
            python_capitalize("the robot R1 holds"),
            "The robot r1 holds"
        );
        assert_eq!(python_capitalize(""), "");
    }

    #[test]
    fn grasping_the_apple_reads_like_enact() {
        let slicing = &activities()[1];
        let states = slicing.states().unwrap();
        assert_eq!(slicing.steps[0], Step::Grasp(Gripper::Left, Thing::Apple));
        let diff = StateDiff::between(&SceneGraph::of(&states[0]), &SceneGraph::of(&states[1]));
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let text = action_text(&diff, &mut rng).unwrap();
        let (first, second) = text.split_once(". ").unwrap();
        let grasp_forms: Vec<String> = NODE_GAINED
            .iter()
            .map(|v| format!("The robot r1 {v} using the left gripper to grasp the apple"))
            .collect();
        assert!(grasp_forms.contains(&first.to_string()), "{text}");
        let release_forms: Vec<String> = LOST
            .iter()
            .map(|v| format!("The apple {v} on top of and touching the countertop."))
            .collect();
        assert!(release_forms.contains(&second.to_string()), "{text}");
    }

    #[test]
    fn slicing_says_the_apple_becomes_the_half_apple() {
        let slicing = &activities()[1];
        let states = slicing.states().unwrap();
        let at = slicing
            .steps
            .iter()
            .position(|s| *s == Step::SliceApple)
            .unwrap();
        let diff = StateDiff::between(
            &SceneGraph::of(&states[at]),
            &SceneGraph::of(&states[at + 1]),
        );
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let text = action_text(&diff, &mut rng).unwrap();
        assert!(
            text.ends_with(". The apple now becomes the half apple."),
            "{text}"
        );
        assert!(
            text.contains("on top of and touching the chopping board"),
            "{text}"
        );
        assert_eq!(diff.sentence_count(), 2);
    }

    #[test]
    fn every_sentence_count_matches_the_text() {
        for activity in activities() {
            let states = activity.states().unwrap();
            let mut rng = ChaCha8Rng::seed_from_u64(9);
            for i in 0..states.len() {
                for j in i + 1..states.len() {
                    let diff = StateDiff::between(
                        &SceneGraph::of(&states[i]),
                        &SceneGraph::of(&states[j]),
                    );
                    let n = sentences(&diff, &mut rng).len();
                    assert_eq!(n, diff.sentence_count(), "{} {i}->{j}", activity.name);
                }
            }
        }
    }

    #[test]
    fn an_empty_diff_has_no_action_text() {
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        assert_eq!(action_text(&StateDiff::default(), &mut rng), None);
    }
}
