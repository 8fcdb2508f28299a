//! Action sentences: rendering a diff as ENACT's natural language (`translate_diff` in the
//! `multi_*` modes the QA generator and evaluator use), and parsing such text back into
//! signatures (not in ENACT; needed to read the action lines of released QA items).

use std::collections::BTreeSet;

use rand::Rng;

use crate::scene_graph::diff::{ChangeOp, StateDiff};
use crate::scene_graph::names::NameError;
use crate::scene_graph::names::format_object_name;
use crate::scene_graph::signature::{
    ObjectTransition, STATE_PHRASES, StateArity, StateVocabulary, cooked_transition_signature,
    edge_signature, node_signature, object_transitions, transition_signature,
};

/// What ENACT writes for an empty diff (no final period, so it counts as zero sentences).
pub const NO_CHANGE_TEXT: &str = "No significant changes occurred";
/// What ENACT's QA generators write when a non-empty diff yields no sentence.
pub const NO_MEANINGFUL_CHANGE_TEXT: &str = "No meaningful change is observed.";

/// Sentence templates for a gained state; one is picked at random per sentence.
const ADD_VERBS: [&str; 4] = [
    "now becomes",
    "becomes",
    "changes to be",
    "transitions to be",
];
/// Sentence templates for a lost state.
const REMOVE_VERBS: [&str; 2] = ["is no longer", "stopped being"];
const TRANSITION_VERB: &str = "now becomes";
const MULTI_TRANSITION_VERB: &str = "now turn into";
const COOKED_SUFFIX: &str = " is now cooked";

fn verbs(op: ChangeOp) -> &'static [&'static str] {
    match op {
        ChangeOp::Add => &ADD_VERBS,
        ChangeOp::Remove => &REMOVE_VERBS,
    }
}

/// ENACT quirk: sentences are joined with Python's `str.capitalize`, which upper-cases the
/// first character and lower-cases all the others.
pub fn python_capitalize(s: &str) -> String {
    let mut chars = s.chars();
    match chars.next() {
        Some(first) => first
            .to_uppercase()
            .chain(chars.flat_map(char::to_lowercase))
            .collect(),
        None => String::new(),
    }
}

/// ENACT quirk: the sentence for a cooked system deletes every "cooked" from the formatted
/// name and keeps the spaces around it, e.g. "the  diced bacon is now cooked" (two spaces).
fn cooked_sentence(target: &str) -> String {
    format!("{}{COOKED_SUFFIX}", target.replace("cooked", ""))
}

fn transition_sentence(t: &ObjectTransition) -> String {
    match t {
        ObjectTransition::From { sources, target } => match sources.as_slice() {
            [one] => format!("{one} {TRANSITION_VERB} {target}"),
            [init @ .., last] => {
                format!(
                    "{}, and {last} {MULTI_TRANSITION_VERB} {target}",
                    init.join(", ")
                )
            }
            [] => String::new(),
        },
        ObjectTransition::Cooked { target } => cooked_sentence(target),
    }
}

/// The lower-case sentences of a diff in ENACT's order: gained node states, gained edge
/// states, lost node states, lost edge states, then object transitions. Each state sentence
/// picks its template with `rng`.
pub fn diff_sentences<R: Rng + ?Sized>(
    diff: &StateDiff,
    rng: &mut R,
) -> Result<Vec<String>, NameError> {
    sentences_with(diff, StateVocabulary::Enact, &mut |n| {
        rng.random_range(0..n)
    })
}

/// [`diff_sentences`] with the template index chosen by `pick(number_of_templates)`.
fn sentences_with(
    diff: &StateDiff,
    vocabulary: StateVocabulary,
    pick: &mut dyn FnMut(usize) -> usize,
) -> Result<Vec<String>, NameError> {
    let mut out = Vec::new();
    for op in ChangeOp::BOTH {
        let side = diff.side(op);
        let templates = verbs(op);
        for node in &side.nodes {
            let object = format_object_name(&node.name)?;
            for state in &node.states {
                if let Some(phrase) = vocabulary.phrase(state) {
                    let verb = templates[pick(templates.len())];
                    out.push(format!("{object} {verb} {phrase}"));
                }
            }
        }
        for edge in &side.edges {
            let from = format_object_name(&edge.from)?;
            let to = format_object_name(&edge.to)?;
            for state in &edge.states {
                if let Some(phrase) = vocabulary.phrase(state) {
                    let verb = templates[pick(templates.len())];
                    out.push(format!("{from} {verb} {phrase} {to}"));
                }
            }
        }
    }
    // ENACT collects these in a set, so identical transition sentences appear once.
    let transitions: BTreeSet<String> = object_transitions(diff)?
        .iter()
        .map(transition_sentence)
        .collect();
    out.extend(transitions);
    Ok(out)
}

/// ENACT's `translate_diff` text of a diff: [`NO_CHANGE_TEXT`] for an empty diff, `None` when
/// a non-empty diff has nothing describable, else the capitalised sentences joined by ". "
/// with a final ".".
pub fn render_diff<R: Rng + ?Sized>(
    diff: &StateDiff,
    rng: &mut R,
) -> Result<Option<String>, NameError> {
    render_with(diff, StateVocabulary::Enact, &mut |n| {
        rng.random_range(0..n)
    })
}

/// [`render_diff`] describing the states of `vocabulary`.
pub fn render_diff_in<R: Rng + ?Sized>(
    diff: &StateDiff,
    vocabulary: StateVocabulary,
    rng: &mut R,
) -> Result<Option<String>, NameError> {
    render_with(diff, vocabulary, &mut |n| rng.random_range(0..n))
}

/// [`render_diff`] with every sentence in its first template ("now becomes", "is no longer"):
/// one fixed rendering to show what the pipeline will write. The pipeline picks each verb at
/// random among four (gained) or two (lost) templates; the signatures do not depend on it.
pub fn render_diff_first_templates(diff: &StateDiff) -> Result<Option<String>, NameError> {
    render_with(diff, StateVocabulary::Enact, &mut |_| 0)
}

fn render_with(
    diff: &StateDiff,
    vocabulary: StateVocabulary,
    pick: &mut dyn FnMut(usize) -> usize,
) -> Result<Option<String>, NameError> {
    if diff.is_empty() {
        return Ok(Some(NO_CHANGE_TEXT.to_string()));
    }
    let sentences = sentences_with(diff, vocabulary, pick)?;
    if sentences.is_empty() {
        return Ok(None);
    }
    let joined: Vec<String> = sentences.iter().map(|s| python_capitalize(s)).collect();
    Ok(Some(format!("{}.", joined.join(". "))))
}

/// ENACT's sentence count for a diff, `text.count(".")` of [`render_diff`] (0 for an empty
/// diff or no text). The QA generator keeps transitions with 1 to 5. Templates contain no
/// period, so the count does not depend on the random choice.
pub fn sentence_count(diff: &StateDiff) -> Result<usize, NameError> {
    sentence_count_in(diff, StateVocabulary::Enact)
}

/// [`sentence_count`] describing the states of `vocabulary`.
pub fn sentence_count_in(
    diff: &StateDiff,
    vocabulary: StateVocabulary,
) -> Result<usize, NameError> {
    if diff.is_empty() {
        return Ok(NO_CHANGE_TEXT.matches('.').count());
    }
    // The periods of the rendered text, without rendering it: one after each sentence plus
    // any inside one (capitalising adds or removes none). KFTS asks this of every key-frame pair.
    let sentences = sentences_with(diff, vocabulary, &mut |_| 0)?;
    Ok(sentences.len()
        + sentences
            .iter()
            .map(|s| s.matches('.').count())
            .sum::<usize>())
}

/// Why an action text could not be read back into signatures.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SentenceParseError {
    #[error("empty action text")]
    Empty,
    #[error("sentence {index} ({sentence:?}) is not an ENACT state-change sentence")]
    Unrecognised { index: usize, sentence: String },
}

/// Undoes `capitalize` on our lower-case vocabulary: the first character back to lower case.
fn decapitalize(s: &str) -> String {
    let mut chars = s.chars();
    match chars.next() {
        Some(first) => first.to_lowercase().chain(chars).collect(),
        None => String::new(),
    }
}

/// Relation phrases, longest first, so that a phrase containing a shorter one ("on top of and
/// touching" contains "touching") is tried first.
fn relation_phrases() -> Vec<(&'static str, &'static str)> {
    let mut rel: Vec<(&str, &str)> = STATE_PHRASES
        .iter()
        .filter(|(_, _, arity)| *arity == StateArity::Binary)
        .map(|(state, phrase, _)| (*phrase, *state))
        .collect();
    rel.sort_by(|a, b| b.0.len().cmp(&a.0.len()).then(a.0.cmp(b.0)));
    rel
}

fn unary_state(phrase: &str) -> Option<&'static str> {
    STATE_PHRASES
        .iter()
        .find(|(_, p, arity)| *arity == StateArity::Unary && *p == phrase)
        .map(|(state, _, _)| *state)
}

/// The signature of the remainder after `{object} {verb} `, if it reads as a node state, an
/// edge state or (for "now becomes") an object transition.
fn read_rest(op: ChangeOp, verb: &str, object: &str, rest: &str) -> Option<String> {
    if let Some(state) = unary_state(rest) {
        return Some(node_signature(op, object, state));
    }
    for (phrase, state) in relation_phrases() {
        if let Some(target) = rest.strip_prefix(phrase).and_then(|r| r.strip_prefix(' '))
            && target.starts_with("the ")
        {
            return Some(edge_signature(op, object, target, state));
        }
    }
    if op == ChangeOp::Add && verb == TRANSITION_VERB && rest.starts_with("the ") {
        return Some(transition_signature(&[object], rest));
    }
    None
}

/// ENACT's cooked sentence removed "cooked" from the name; its signature removed "cooked ".
/// Where the removal left a doubled space (or a trailing one) we put the name back together.
fn cooked_target(written: &str) -> String {
    let mut name = written.replace("  ", " ");
    if name.ends_with(' ') {
        name.push_str("cooked");
    }
    name
}

/// Parses one lower-cased sentence (no final period).
fn parse_sentence(s: &str) -> Option<String> {
    if let Some(object) = s.strip_suffix(COOKED_SUFFIX)
        && object.starts_with("the ")
    {
        return Some(cooked_transition_signature(&cooked_target(object)));
    }
    if let Some((sources, target)) = s.split_once(&format!(" {MULTI_TRANSITION_VERB} "))
        && let Some((init, last)) = sources.rsplit_once(", and ")
    {
        let mut names: Vec<&str> = init.split(", ").collect();
        names.push(last);
        if target.starts_with("the ") && names.iter().all(|n| n.starts_with("the ")) {
            return Some(transition_signature(&names, target));
        }
    }
    // Try every place a verb occurs, leftmost first: object names can contain verb words
    // and relation phrases, the remainder decides.
    let mut candidates: Vec<(usize, ChangeOp, &str)> = Vec::new();
    for op in ChangeOp::BOTH {
        for verb in verbs(op) {
            let needle = format!(" {verb} ");
            candidates.extend(s.match_indices(&needle).map(|(i, _)| (i, op, *verb)));
        }
    }
    // At one position, "now becomes" must be tried before "becomes" (which starts later).
    candidates.sort_by_key(|(i, _, verb)| (*i, std::cmp::Reverse(verb.len())));
    for (i, op, verb) in candidates {
        let object = &s[..i];
        let rest = &s[i + verb.len() + 2..];
        if !object.starts_with("the ") {
            continue;
        }
        if let Some(sig) = read_rest(op, verb, object, rest) {
            return Some(sig);
        }
    }
    None
}

/// Reads an action text (1..5 ENACT sentences, "The x becomes open. The y ...") back into its
/// signature set. Both "no change" texts give the empty set.
pub fn parse_action(text: &str) -> Result<BTreeSet<String>, SentenceParseError> {
    let text = text.trim();
    if text.is_empty() {
        return Err(SentenceParseError::Empty);
    }
    let mut out = BTreeSet::new();
    if text == NO_CHANGE_TEXT || text == NO_MEANINGFUL_CHANGE_TEXT {
        return Ok(out);
    }
    let body = text.strip_suffix('.').unwrap_or(text);
    for (index, sentence) in body.split(". ").enumerate() {
        let unrecognised = || SentenceParseError::Unrecognised {
            index,
            sentence: sentence.to_string(),
        };
        // ENACT's object names never hold `_` (it splits names on it), and signatures use it
        // as their separator: a name with one would give a signature that reads two ways.
        if sentence.contains('_') {
            return Err(unrecognised());
        }
        let lowered = decapitalize(sentence);
        let sig = parse_sentence(&lowered).ok_or_else(unrecognised)?;
        out.insert(sig);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_graph::diff::DiffSide;
    use crate::scene_graph::diff::tests::{edge_change as edge, node_change as change};
    use crate::scene_graph::signature::diff_signatures;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn sample() -> StateDiff {
        StateDiff {
            add: DiffSide {
                nodes: vec![
                    change("oven_1", &["ToggledOn"], None),
                    change("half_mushroom_2", &[], Some(&["mushroom_1"])),
                    change("cooked__diced__bacon", &[], Some(&["diced__bacon"])),
                ],
                edges: vec![edge("robot_r1", "bok_choy_3", &["LeftGrasping"])],
            },
            remove: DiffSide {
                nodes: vec![
                    change("oven_1", &["Open"], None),
                    change("mushroom_1", &[], None),
                ],
                edges: vec![edge("apple_1", "plate_2", &["OnTop", "LeftContact"])],
            },
        }
    }

    #[test]
    fn capitalize_lowers_the_rest() {
        assert_eq!(python_capitalize("the robot r1 IS"), "The robot r1 is");
        assert_eq!(python_capitalize(""), "");
    }

    #[test]
    fn rendering_is_deterministic_under_a_seed_and_follows_enact_order() {
        let d = sample();
        let a = render_diff(&d, &mut ChaCha8Rng::seed_from_u64(7))
            .unwrap()
            .unwrap();
        let b = render_diff(&d, &mut ChaCha8Rng::seed_from_u64(7))
            .unwrap()
            .unwrap();
        assert_eq!(a, b);
        let sentences: Vec<&str> = a.strip_suffix('.').unwrap().split(". ").collect();
        assert_eq!(sentences.len(), 6);
        assert!(sentences[0].starts_with("The oven "));
        assert!(sentences[0].ends_with(" turned on"));
        assert!(sentences[1].starts_with("The robot r1 "));
        assert!(sentences[1].ends_with(" using the left gripper to grasp the bok choy"));
        assert!(sentences[2].starts_with("The oven ") && sentences[2].ends_with(" open"));
        assert!(sentences[3].ends_with(" on top of and touching the plate"));
        // Transition sentences, the cooked one with ENACT's double space.
        assert_eq!(sentences[4], "The  diced bacon is now cooked");
        assert_eq!(sentences[5], "The mushroom now becomes the half mushroom");
        assert_eq!(sentence_count(&d).unwrap(), 6);
    }

    #[test]
    fn every_template_is_used_and_parses_back() {
        let d = sample();
        let want = diff_signatures(&d).unwrap();
        let mut seen = BTreeSet::new();
        for seed in 0..64 {
            let text = render_diff(&d, &mut ChaCha8Rng::seed_from_u64(seed))
                .unwrap()
                .unwrap();
            for verb in ADD_VERBS.iter().chain(REMOVE_VERBS.iter()) {
                if text.contains(&format!(" {verb} ")) {
                    seen.insert(*verb);
                }
            }
            assert_eq!(parse_action(&text).unwrap(), want, "{text}");
        }
        assert_eq!(seen.len(), 6);
    }

    #[test]
    fn empty_and_silent_diffs() {
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        assert_eq!(
            render_diff(&StateDiff::default(), &mut rng)
                .unwrap()
                .as_deref(),
            Some(NO_CHANGE_TEXT)
        );
        assert_eq!(sentence_count(&StateDiff::default()).unwrap(), 0);
        let contact_only = StateDiff {
            add: DiffSide {
                nodes: vec![],
                edges: vec![edge("robot_r1", "pan_1", &["RightContact"])],
            },
            remove: DiffSide::default(),
        };
        assert_eq!(render_diff(&contact_only, &mut rng).unwrap(), None);
        assert_eq!(sentence_count(&contact_only).unwrap(), 0);
        assert!(parse_action(NO_CHANGE_TEXT).unwrap().is_empty());
        assert!(parse_action(NO_MEANINGFUL_CHANGE_TEXT).unwrap().is_empty());
    }

    #[test]
    fn several_parents_sentence() {
        let d = StateDiff {
            add: DiffSide {
                nodes: vec![change(
                    "diced__carrot",
                    &[],
                    Some(&["half_carrot_1", "carrot_9"]),
                )],
                edges: vec![],
            },
            remove: DiffSide {
                nodes: vec![
                    change("half_carrot_1", &[], None),
                    change("carrot_9", &[], None),
                ],
                edges: vec![],
            },
        };
        let text = render_diff(&d, &mut ChaCha8Rng::seed_from_u64(0))
            .unwrap()
            .unwrap();
        assert_eq!(
            text,
            "The carrot, and the half carrot now turn into the diced carrot."
        );
        assert_eq!(parse_action(&text).unwrap(), diff_signatures(&d).unwrap());
    }

    #[test]
    fn parser_handles_relation_words_inside_names() {
        // The object names contain "touching", "under", "inside" and even a verb.
        let d = StateDiff {
            add: DiffSide {
                nodes: vec![change("becomes_open_lid_1", &["Open"], None)],
                edges: vec![
                    edge("touching_pad_1", "under_shelf_2", &["OnTop"]),
                    edge("inside_box_3", "next_to_bin_4", &["Touching"]),
                ],
            },
            remove: DiffSide {
                nodes: vec![],
                edges: vec![edge("robot_r1", "on_top_rack_5", &["Under"])],
            },
        };
        let want = diff_signatures(&d).unwrap();
        for seed in 0..32 {
            let text = render_diff(&d, &mut ChaCha8Rng::seed_from_u64(seed))
                .unwrap()
                .unwrap();
            assert_eq!(parse_action(&text).unwrap(), want, "{text}");
        }
    }

    #[test]
    fn known_sentences_from_real_data() {
        let sigs = parse_action(
            "The robot r1 stopped being using the left gripper to grasp the bok choy.",
        )
        .unwrap();
        assert_eq!(
            sigs.into_iter().collect::<Vec<_>>(),
            ["edge_remove_the robot r1_the bok choy_LeftGrasping"]
        );
        let sigs =
            parse_action("The oven becomes turned on. The oven stopped being open.").unwrap();
        assert!(
            sigs.contains("node_add_the oven_ToggledOn")
                && sigs.contains("node_remove_the oven_Open")
        );
        let sigs =
            parse_action("The baking sheet now becomes covered by the grated cheese.").unwrap();
        assert!(sigs.contains("edge_add_the baking sheet_the grated cheese_Covered"));
        let sigs = parse_action("The mushroom now becomes the half mushroom.").unwrap();
        assert!(sigs.contains("node_transition_from_the mushroom_to_the half mushroom"));
    }

    #[test]
    fn unparseable_sentences_are_errors() {
        assert_eq!(parse_action("  "), Err(SentenceParseError::Empty));
        let err = parse_action("The oven becomes open. The cat sat on the mat.").unwrap_err();
        assert_eq!(
            err,
            SentenceParseError::Unrecognised {
                index: 1,
                sentence: "The cat sat on the mat".into()
            }
        );
        assert!(parse_action("The oven becomes purple.").is_err());
        assert!(parse_action("Oven becomes open.").is_err());
    }

    /// Found by `cargo fuzz run sentence`: a name holding `_` gave a signature that the error
    /// analysis could not split back into its fields.
    #[test]
    fn names_with_underscores_are_refused() {
        let err = parse_action(
            "The bowl becomes inside the node_transition_from_the apple_to_the basket.",
        )
        .unwrap_err();
        assert!(matches!(
            err,
            SentenceParseError::Unrecognised { index: 0, .. }
        ));
        assert!(parse_action("The oven_1 becomes open.").is_err());
    }
}
