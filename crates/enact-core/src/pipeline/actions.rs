//! Action texts other than ENACT's sentences, for the paper's appendix experiments on a
//! baseline's own items: the same transitions written as symbolic predicates or emoji
//! (table `tab:app_action_repr`), and transitions whose predicates were perturbed at random
//! (table `tab:predicate_noise`). Item ids, frames and ground truth never change, so a variant
//! imported with the baseline's scene graphs is judged by the baseline's signatures.
//!
//! - [`ActionEncoding`]: natural (ENACT's sentences), symbolic (`add(Inside, apple_1, fridge_1)`,
//!   one predicate per change) and emoji ([`PREDICATE_EMOJI`], [`OBJECT_EMOJI`], text where a
//!   word has no emoji).
//! - [`perturb_delta`]: the documented perturbation rule ([`DeltaPerturbation`]).
//! - [`rewrite_item`]: one item's new action texts, in the question's `[Action k]` lines.

use rand::Rng;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sha2::{Digest, Sha256};

use crate::dataset::{Direction, QaItem};
use crate::scene_graph::diff::{ChangeOp, StateDiff};
use crate::scene_graph::names::{NameError, format_object_name};
use crate::scene_graph::sentence::NO_MEANINGFUL_CHANGE_TEXT;
use crate::scene_graph::signature::{
    ObjectTransition, STATE_PHRASES, StateArity, object_transitions,
};
use crate::scene_graph::{
    DiffError, SceneGraphTimeline, StateVocabulary, View, render_diff_in, visible_diff,
};

/// How an action is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ActionEncoding {
    /// ENACT's sentences ("The apple becomes inside the fridge.").
    #[default]
    Natural,
    /// One predicate per change: `add(Inside, apple_1, fridge_1); remove(Open, fridge_1)`.
    Symbolic,
    /// Emoji per operation, predicate and object word: `➕📥(🍎, fridge); ➖📂(fridge)`.
    Emoji,
}

impl ActionEncoding {
    pub const ALL: [ActionEncoding; 3] = [
        ActionEncoding::Natural,
        ActionEncoding::Symbolic,
        ActionEncoding::Emoji,
    ];

    /// `natural`, `symbolic` or `emoji`.
    pub fn parse(name: &str) -> Option<ActionEncoding> {
        Self::ALL.into_iter().find(|e| e.as_str() == name)
    }

    pub fn as_str(self) -> &'static str {
        match self {
            ActionEncoding::Natural => "natural",
            ActionEncoding::Symbolic => "symbolic",
            ActionEncoding::Emoji => "emoji",
        }
    }
}

/// The emoji of each predicate ENACT describes, and of the robot's contact states. Every state
/// of [`STATE_PHRASES`] has one (a test checks the two lists agree), and no two share one.
pub const PREDICATE_EMOJI: [(&str, &str); 28] = [
    ("Burnt", "🟫"),
    ("Cooked", "🍳"),
    ("Folded", "📁"),
    ("Unfolded", "📄"),
    ("Frozen", "🧊"),
    ("HeatSourceOrSink", "🌡️"),
    ("Heated", "♨️"),
    ("OnFire", "🔥"),
    ("InFOVofRobot", "👁️"),
    ("Open", "📂"),
    ("ToggledOn", "🔛"),
    ("AttachedTo", "📎"),
    ("Contains", "🫙"),
    ("Covered", "⛱️"),
    ("Draped", "🧣"),
    ("Filled", "🥛"),
    ("Inside", "📥"),
    ("NextTo", "↔️"),
    ("OnTop", "🔝"),
    ("Overlaid", "🩹"),
    ("Saturated", "💧"),
    ("Touching", "🤝"),
    ("Under", "⬇️"),
    ("Grasping", "✊"),
    ("LeftGrasping", "🤛"),
    ("RightGrasping", "🤜"),
    ("LeftContact", "👈"),
    ("RightContact", "👉"),
];

/// The emoji of an object word (a word of its formatted name: "the half apple" → "half 🍎").
/// A word without one is written as text, so every object stays nameable.
pub const OBJECT_EMOJI: [(&str, &str); 40] = [
    ("robot", "🤖"),
    ("apple", "🍎"),
    ("banana", "🍌"),
    ("bacon", "🥓"),
    ("bread", "🍞"),
    ("carrot", "🥕"),
    ("tomato", "🍅"),
    ("potato", "🥔"),
    ("onion", "🧅"),
    ("garlic", "🧄"),
    ("pepper", "🫑"),
    ("lemon", "🍋"),
    ("orange", "🍊"),
    ("mushroom", "🍄"),
    ("cucumber", "🥒"),
    ("broccoli", "🥦"),
    ("egg", "🥚"),
    ("cheese", "🧀"),
    ("butter", "🧈"),
    ("cookie", "🍪"),
    ("milk", "🥛"),
    ("water", "💧"),
    ("knife", "🔪"),
    ("plate", "🍽️"),
    ("bowl", "🥣"),
    ("cup", "☕"),
    ("mug", "☕"),
    ("bottle", "🍾"),
    ("box", "📦"),
    ("book", "📖"),
    ("door", "🚪"),
    ("sink", "🚰"),
    ("chair", "🪑"),
    ("bed", "🛏️"),
    ("lamp", "💡"),
    ("basket", "🧺"),
    ("towel", "🧻"),
    ("shirt", "👕"),
    ("broom", "🧹"),
    ("sponge", "🧽"),
];

const EMOJI_ADD: &str = "➕";
const EMOJI_REMOVE: &str = "➖";
const EMOJI_TRANSITION: &str = "🔄";
/// What a symbolic or emoji action says when nothing it could describe is left.
const SYMBOLIC_NOTHING: &str = "none()";
const EMOJI_NOTHING: &str = "∅";

fn predicate_emoji(state: &str) -> Option<&'static str> {
    PREDICATE_EMOJI
        .iter()
        .find(|(name, _)| *name == state)
        .map(|(_, emoji)| *emoji)
}

/// A formatted object name with each word that has an emoji replaced by it ("the" dropped).
fn emoji_object(name: &str) -> Result<String, NameError> {
    let formatted = format_object_name(name)?;
    Ok(emoji_words(&formatted))
}

fn emoji_words(formatted: &str) -> String {
    formatted
        .strip_prefix("the ")
        .unwrap_or(formatted)
        .split(' ')
        .filter(|w| !w.is_empty())
        .map(|w| {
            OBJECT_EMOJI
                .iter()
                .find(|(word, _)| *word == w)
                .map_or(w, |(_, emoji)| *emoji)
        })
        .collect::<Vec<_>>()
        .join(" ")
}

fn bare(formatted: &str) -> &str {
    formatted.strip_prefix("the ").unwrap_or(formatted)
}

/// An object transition as a predicate: `transition(apple -> half apple)`, or
/// `transition(diced bacon -> cooked)` for a cooked system.
fn symbolic_transition(t: &ObjectTransition) -> String {
    match t {
        ObjectTransition::From { sources, target } => {
            let sources: Vec<&str> = sources.iter().map(|s| bare(s)).collect();
            format!("transition({} -> {})", sources.join(", "), bare(target))
        }
        ObjectTransition::Cooked { target } => {
            format!(
                "transition({} -> cooked)",
                bare(&target.replace("cooked ", ""))
            )
        }
    }
}

fn emoji_transition(t: &ObjectTransition) -> String {
    match t {
        ObjectTransition::From { sources, target } => {
            let sources: Vec<String> = sources.iter().map(|s| emoji_words(s)).collect();
            format!(
                "{EMOJI_TRANSITION}({} → {})",
                sources.join(", "),
                emoji_words(target)
            )
        }
        ObjectTransition::Cooked { target } => format!(
            "{EMOJI_TRANSITION}({} → {})",
            emoji_words(&target.replace("cooked ", "")),
            predicate_emoji("Cooked").unwrap_or("cooked")
        ),
    }
}

/// A diff in a non-natural encoding: every state change `vocabulary` describes, in ENACT's
/// sentence order (gained node states, gained edge states, lost node states, lost edge
/// states), then the object transitions. The same changes as the signatures, one for one.
fn encode_predicates(
    diff: &StateDiff,
    encoding: ActionEncoding,
    vocabulary: StateVocabulary,
) -> Result<String, NameError> {
    let mut parts = Vec::new();
    for slot in slots(diff, vocabulary) {
        let side = diff.side(slot.op);
        let (state, subject, object) = if slot.edge {
            let e = &side.edges[slot.entry];
            (&e.states[slot.state], &e.from, Some(&e.to))
        } else {
            let n = &side.nodes[slot.entry];
            (&n.states[slot.state], &n.name, None)
        };
        parts.push(match encoding {
            ActionEncoding::Emoji => {
                let mut names = vec![emoji_object(subject)?];
                if let Some(object) = object {
                    names.push(emoji_object(object)?);
                }
                format!(
                    "{}{}({})",
                    op_emoji(slot.op),
                    predicate_emoji(state).unwrap_or(state),
                    names.join(", ")
                )
            }
            _ => match object {
                Some(object) => format!("{}({state}, {subject}, {object})", slot.op.as_str()),
                None => format!("{}({state}, {subject})", slot.op.as_str()),
            },
        });
    }
    for t in object_transitions(diff)? {
        parts.push(match encoding {
            ActionEncoding::Emoji => emoji_transition(&t),
            _ => symbolic_transition(&t),
        });
    }
    Ok(match (parts.is_empty(), encoding) {
        (true, ActionEncoding::Emoji) => EMOJI_NOTHING.to_owned(),
        (true, _) => SYMBOLIC_NOTHING.to_owned(),
        (false, _) => parts.join("; "),
    })
}

fn op_emoji(op: ChangeOp) -> &'static str {
    match op {
        ChangeOp::Add => EMOJI_ADD,
        ChangeOp::Remove => EMOJI_REMOVE,
    }
}

/// The action text of a diff in `encoding`; natural text picks its templates with `rng`, as
/// the generator does.
pub fn encode_action<R: Rng + ?Sized>(
    diff: &StateDiff,
    encoding: ActionEncoding,
    vocabulary: StateVocabulary,
    rng: &mut R,
) -> Result<String, NameError> {
    match encoding {
        ActionEncoding::Natural => Ok(render_diff_in(diff, vocabulary, rng)?
            .unwrap_or_else(|| NO_MEANINGFUL_CHANGE_TEXT.to_owned())),
        _ => encode_predicates(diff, encoding, vocabulary),
    }
}

/// The perturbation of `generate --perturb-deltas P --seed S`.
///
/// The rule: the predicates of a transition are the state changes of its visible delta that the
/// run describes (each gained or lost node state, each gained or lost edge state); object
/// transitions are not predicates and stay. Each predicate, in the delta's order, is perturbed
/// with probability `probability`; a perturbed predicate is dropped or swapped with equal
/// probability, and a swap replaces its state by another state of the same arity from ENACT's
/// table (a node state for a node, a relation for an edge), drawn uniformly among those the
/// entry does not hold. A transition left with nothing to say has its last dropped predicate
/// swapped instead. Draws come from ChaCha8 seeded by sha256(seed, task, from frame, to frame),
/// so a transition is perturbed alike in every item that holds it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DeltaPerturbation {
    pub probability: f64,
    pub seed: u64,
}

impl DeltaPerturbation {
    /// Checks that the probability lies in [0, 1].
    pub fn new(probability: f64, seed: u64) -> Result<DeltaPerturbation, String> {
        if !(0.0..=1.0).contains(&probability) {
            return Err(format!(
                "the perturbation probability {probability} is not between 0 and 1"
            ));
        }
        Ok(DeltaPerturbation { probability, seed })
    }

    /// The random stream of one transition.
    pub fn rng(&self, task: &str, from: &str, to: &str) -> ChaCha8Rng {
        let mut hasher = Sha256::new();
        hasher.update(b"perturb-deltas\0");
        hasher.update(self.seed.to_le_bytes());
        for part in [task, from, to] {
            hasher.update(part.as_bytes());
            hasher.update([0u8]);
        }
        ChaCha8Rng::from_seed(hasher.finalize().into())
    }
}

/// What the perturbation did to one predicate.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PredicateChange {
    Dropped { state: String },
    Swapped { state: String, replacement: String },
}

/// Where a predicate sits in a diff: side, node or edge entry, entry index, state index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Slot {
    op: ChangeOp,
    edge: bool,
    entry: usize,
    state: usize,
}

fn slots(diff: &StateDiff, vocabulary: StateVocabulary) -> Vec<Slot> {
    let mut out = Vec::new();
    for op in ChangeOp::BOTH {
        let side = diff.side(op);
        for (entry, node) in side.nodes.iter().enumerate() {
            for (state, s) in node.states.iter().enumerate() {
                if vocabulary.phrase(s).is_some() {
                    out.push(Slot {
                        op,
                        edge: false,
                        entry,
                        state,
                    });
                }
            }
        }
        for (entry, edge) in side.edges.iter().enumerate() {
            for (state, s) in edge.states.iter().enumerate() {
                if vocabulary.phrase(s).is_some() {
                    out.push(Slot {
                        op,
                        edge: true,
                        entry,
                        state,
                    });
                }
            }
        }
    }
    out
}

fn slot_states_mut(diff: &mut StateDiff, slot: Slot) -> &mut Vec<String> {
    let side = match slot.op {
        ChangeOp::Add => &mut diff.add,
        ChangeOp::Remove => &mut diff.remove,
    };
    if slot.edge {
        &mut side.edges[slot.entry].states
    } else {
        &mut side.nodes[slot.entry].states
    }
}

fn slot_states(diff: &StateDiff, slot: Slot) -> &[String] {
    let side = diff.side(slot.op);
    if slot.edge {
        &side.edges[slot.entry].states
    } else {
        &side.nodes[slot.entry].states
    }
}

/// A state of the slot's arity that its entry does not hold, drawn uniformly.
fn wrong_state<R: Rng + ?Sized>(held: &[String], edge: bool, rng: &mut R) -> Option<String> {
    let arity = if edge {
        StateArity::Binary
    } else {
        StateArity::Unary
    };
    let choices: Vec<&str> = STATE_PHRASES
        .iter()
        .filter(|(state, _, a)| *a == arity && !held.iter().any(|h| h == state))
        .map(|(state, _, _)| *state)
        .collect();
    (!choices.is_empty()).then(|| choices[rng.random_range(0..choices.len())].to_owned())
}

/// Perturbs a transition's delta by the rule of [`DeltaPerturbation`]; returns the perturbed
/// delta and what changed (nothing at probability 0).
pub fn perturb_delta<R: Rng + ?Sized>(
    diff: &StateDiff,
    probability: f64,
    vocabulary: StateVocabulary,
    rng: &mut R,
) -> Result<(StateDiff, Vec<PredicateChange>), NameError> {
    let slots = slots(diff, vocabulary);
    // Per slot: None (kept), Some(None) (dropped), Some(Some(state)) (swapped).
    let mut decisions: Vec<Option<Option<String>>> = Vec::with_capacity(slots.len());
    for &slot in &slots {
        if !rng.random_bool(probability) {
            decisions.push(None);
        } else if rng.random_bool(0.5) {
            decisions.push(Some(None));
        } else {
            decisions.push(Some(wrong_state(slot_states(diff, slot), slot.edge, rng)));
        }
    }
    let kept = decisions
        .iter()
        .filter(|d| !matches!(d, Some(None)))
        .count();
    if kept == 0
        && object_transitions(diff)?.is_empty()
        && let Some(last) = decisions.iter().rposition(|d| matches!(d, Some(None)))
    {
        decisions[last] = Some(wrong_state(
            slot_states(diff, slots[last]),
            slots[last].edge,
            rng,
        ));
    }

    let mut out = diff.clone();
    let mut changes = Vec::new();
    // Swaps first (indices stay valid), then drops from the back.
    for (slot, decision) in slots.iter().zip(&decisions) {
        if let Some(Some(replacement)) = decision {
            let states = slot_states_mut(&mut out, *slot);
            changes.push(PredicateChange::Swapped {
                state: std::mem::replace(&mut states[slot.state], replacement.clone()),
                replacement: replacement.clone(),
            });
        }
    }
    for (slot, decision) in slots.iter().zip(&decisions).rev() {
        if let Some(None) = decision {
            changes.push(PredicateChange::Dropped {
                state: slot_states_mut(&mut out, *slot).remove(slot.state),
            });
        }
    }
    // An entry whose states were all dropped goes: left empty, it would read as a whole object
    // appearing or disappearing. Whole objects (empty from the start) stay.
    for op in ChangeOp::BOTH {
        let original = diff.side(op);
        let side = match op {
            ChangeOp::Add => &mut out.add,
            ChangeOp::Remove => &mut out.remove,
        };
        let mut index = 0;
        side.nodes.retain(|n| {
            let keep = !n.states.is_empty() || original.nodes[index].states.is_empty();
            index += 1;
            keep
        });
        let mut index = 0;
        side.edges.retain(|e| {
            let keep = !e.states.is_empty() || original.edges[index].states.is_empty();
            index += 1;
            keep
        });
    }
    Ok((out, changes))
}

/// How a variant's actions are rewritten.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct ActionRewrite {
    pub encoding: ActionEncoding,
    pub perturbation: Option<DeltaPerturbation>,
    /// The baseline run's vocabulary (contact runs describe contact changes).
    pub vocabulary: StateVocabulary,
}

impl ActionRewrite {
    /// Whether the rewrite leaves every baseline text as it is.
    pub fn is_identity(&self) -> bool {
        self.encoding == ActionEncoding::Natural
            && self.perturbation.is_none_or(|p| p.probability == 0.0)
    }
}

/// What rewriting one item did.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct RewrittenItem {
    /// The new question, or `None` when every action text stays the baseline's.
    pub question: Option<String>,
    /// The new texts in the question's label order.
    pub actions: Vec<String>,
    /// Per chronological transition, what the perturbation changed.
    pub changes: Vec<Vec<PredicateChange>>,
}

/// Why an item could not be rewritten.
#[derive(Debug, thiserror::Error)]
pub enum RewriteError {
    #[error(transparent)]
    Diff(#[from] DiffError),
    #[error("frames {from} -> {to}: {source}")]
    Name {
        from: String,
        to: String,
        #[source]
        source: NameError,
    },
    #[error("the ground truth names no action for transition {transition}")]
    GroundTruth { transition: usize },
}

/// The question label of each chronological transition: forward items list the actions in
/// time order; an inverse item's transition `i` was caused by action `gt_answer[i]`.
pub fn transition_labels(item: &QaItem) -> Vec<usize> {
    match item.direction {
        Direction::Forward => (1..=item.key_frame_ids.len().saturating_sub(1)).collect(),
        Direction::Inverse => item.gt_answer.iter().map(|&l| usize::from(l)).collect(),
    }
}

/// One item's action texts rewritten from the task's key-frame graphs. A natural text whose
/// transition was not perturbed stays the baseline's, byte for byte.
pub fn rewrite_item(
    item: &QaItem,
    timeline: &SceneGraphTimeline,
    rewrite: &ActionRewrite,
) -> Result<RewrittenItem, RewriteError> {
    let mut actions = item.actions.clone();
    let mut changes = Vec::new();
    let labels = transition_labels(item);
    for (i, pair) in item.key_frame_ids.windows(2).enumerate() {
        let (from, to) = (pair[0].as_str(), pair[1].as_str());
        let name_error = |source| RewriteError::Name {
            from: from.to_owned(),
            to: to.to_owned(),
            source,
        };
        let slot = labels
            .get(i)
            .and_then(|l| l.checked_sub(1))
            .filter(|&s| s < actions.len())
            .ok_or(RewriteError::GroundTruth { transition: i + 1 })?;
        let diff = visible_diff(timeline, from, to, View::Visible)?;
        let (perturbed, changed, mut rng) = match &rewrite.perturbation {
            Some(p) => {
                let mut rng = p.rng(&item.task_name, from, to);
                let (perturbed, changed) =
                    perturb_delta(&diff, p.probability, rewrite.vocabulary, &mut rng)
                        .map_err(name_error)?;
                (perturbed, changed, rng)
            }
            // Never drawn from: without a perturbation no natural text is rendered anew.
            None => (diff, Vec::new(), ChaCha8Rng::seed_from_u64(0)),
        };
        if rewrite.encoding != ActionEncoding::Natural || !changed.is_empty() {
            actions[slot] =
                encode_action(&perturbed, rewrite.encoding, rewrite.vocabulary, &mut rng)
                    .map_err(name_error)?;
        }
        changes.push(changed);
    }
    let question =
        (actions != item.actions).then(|| replace_action_lines(&item.question, &actions));
    Ok(RewrittenItem {
        question,
        actions,
        changes,
    })
}

/// The question with each `[Action k] text` line's text replaced by `actions[k - 1]`; every
/// other byte stays.
pub fn replace_action_lines(question: &str, actions: &[String]) -> String {
    question
        .split('\n')
        .map(|line| {
            let indent = line.len() - line.trim_start().len();
            let rest = &line[indent..];
            let label = rest
                .strip_prefix("[Action ")
                .and_then(|r| r.split_once(']'))
                .and_then(|(n, _)| n.trim().parse::<usize>().ok());
            match label
                .and_then(|k| k.checked_sub(1))
                .and_then(|k| actions.get(k))
            {
                Some(text) => {
                    let head = &rest[..rest.find(']').map_or(0, |i| i + 1)];
                    format!("{}{head} {text}", &line[..indent])
                }
                None => line.to_owned(),
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_graph::diff::DiffSide;
    use crate::scene_graph::diff::tests::{edge_change, node_change};
    use crate::scene_graph::signature::diff_signatures;

    /// The fridge opens, the apple goes into it, the robot lets go of it, the mushroom is halved.
    fn delta() -> StateDiff {
        StateDiff {
            add: DiffSide {
                nodes: vec![
                    node_change("fridge_1", &["Open"], None),
                    node_change("half_mushroom_2", &[], Some(&["mushroom_1"])),
                ],
                edges: vec![edge_change("apple_3", "fridge_1", &["Inside"])],
            },
            remove: DiffSide {
                nodes: vec![node_change("mushroom_1", &[], None)],
                edges: vec![edge_change(
                    "robot_r1",
                    "apple_3",
                    &["LeftGrasping", "LeftContact"],
                )],
            },
        }
    }

    #[test]
    fn one_delta_in_the_three_encodings() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let enact = StateVocabulary::Enact;
        let natural = encode_action(&delta(), ActionEncoding::Natural, enact, &mut rng).unwrap();
        assert!(natural.starts_with("The fridge "), "{natural}");
        assert!(natural.contains(" open. The apple "), "{natural}");
        assert!(natural.ends_with("The mushroom now becomes the half mushroom."));
        let symbolic = encode_action(&delta(), ActionEncoding::Symbolic, enact, &mut rng).unwrap();
        assert_eq!(
            symbolic,
            "add(Open, fridge_1); add(Inside, apple_3, fridge_1); \
             remove(LeftGrasping, robot_r1, apple_3); transition(mushroom -> half mushroom)"
        );
        let emoji = encode_action(&delta(), ActionEncoding::Emoji, enact, &mut rng).unwrap();
        assert_eq!(
            emoji,
            "➕📂(fridge); ➕📥(🍎, fridge); ➖🤛(🤖 r1, 🍎); 🔄(🍄 → half 🍄)"
        );
        // The contact vocabulary writes the gripper's contact too, in every encoding.
        let contact = StateVocabulary::WithContact;
        let symbolic =
            encode_action(&delta(), ActionEncoding::Symbolic, contact, &mut rng).unwrap();
        assert!(symbolic.contains("remove(LeftContact, robot_r1, apple_3)"));
        let natural = encode_action(&delta(), ActionEncoding::Natural, contact, &mut rng).unwrap();
        assert!(natural.contains("using the left gripper to touch the apple"));
        // One predicate per signature: the symbolic action has as many parts as signatures.
        let signatures = diff_signatures(&delta()).unwrap();
        let symbolic = encode_action(&delta(), ActionEncoding::Symbolic, enact, &mut rng).unwrap();
        assert_eq!(symbolic.split("; ").count(), signatures.len());
    }

    #[test]
    fn every_predicate_has_its_own_emoji() {
        let mut states: Vec<&str> = STATE_PHRASES.iter().map(|(s, _, _)| *s).collect();
        states.extend(crate::scene_graph::contact::CONTACT_PHRASES.map(|(s, _)| s));
        let mapped: Vec<&str> = PREDICATE_EMOJI.iter().map(|(s, _)| *s).collect();
        assert_eq!(mapped, states);
        let distinct: std::collections::BTreeSet<&str> =
            PREDICATE_EMOJI.iter().map(|(_, e)| *e).collect();
        assert_eq!(distinct.len(), PREDICATE_EMOJI.len());
        assert!(!distinct.contains(EMOJI_ADD) && !distinct.contains(EMOJI_TRANSITION));
        // A word without an emoji stays text.
        assert_eq!(emoji_words("the top cabinet"), "top cabinet");
    }

    #[test]
    fn no_perturbation_at_probability_zero() {
        let p = DeltaPerturbation::new(0.0, 7).unwrap();
        let mut rng = p.rng("task", "10", "20");
        let (perturbed, changes) =
            perturb_delta(&delta(), 0.0, StateVocabulary::Enact, &mut rng).unwrap();
        assert_eq!(perturbed, delta());
        assert!(changes.is_empty());
        assert!(DeltaPerturbation::new(1.5, 7).is_err());
        assert!(DeltaPerturbation::new(f64::NAN, 7).is_err());
    }

    #[test]
    fn perturbation_follows_the_rule_and_the_seed() {
        let enact = StateVocabulary::Enact;
        let run = |seed: u64, probability: f64| {
            let p = DeltaPerturbation::new(probability, seed).unwrap();
            perturb_delta(&delta(), probability, enact, &mut p.rng("t", "1", "2")).unwrap()
        };
        // At 1 every predicate (Open, Inside, LeftGrasping; not LeftContact, not the
        // transition) is dropped or swapped.
        let mut kinds = std::collections::BTreeSet::new();
        for seed in 0..40 {
            let (perturbed, changes) = run(seed, 1.0);
            assert_eq!(changes.len(), 3, "seed {seed}");
            for change in &changes {
                match change {
                    PredicateChange::Dropped { state } => {
                        kinds.insert("dropped");
                        assert!(["Open", "Inside", "LeftGrasping"].contains(&state.as_str()));
                    }
                    PredicateChange::Swapped { state, replacement } => {
                        kinds.insert("swapped");
                        assert_ne!(state, replacement);
                        let arity = |s: &str| {
                            STATE_PHRASES
                                .iter()
                                .find(|(n, _, _)| *n == s)
                                .map(|(_, _, a)| *a)
                        };
                        assert_eq!(arity(state), arity(replacement), "same arity");
                    }
                }
            }
            // The object transition and the undescribed contact state stay.
            assert!(
                perturbed
                    .add
                    .nodes
                    .iter()
                    .any(|n| n.name == "half_mushroom_2")
            );
            assert!(
                perturbed
                    .remove
                    .edges
                    .iter()
                    .all(|e| e.states.contains(&"LeftContact".to_owned()))
            );
            // No entry is left empty (it would read as a whole object).
            assert!(
                perturbed
                    .add
                    .nodes
                    .iter()
                    .all(|n| !n.states.is_empty() || n.name == "half_mushroom_2")
            );
            // The same seed gives the same perturbation.
            assert_eq!(run(seed, 1.0), (perturbed, changes));
        }
        assert_eq!(kinds.len(), 2, "both kinds occur over 40 seeds");
        // Another seed, another draw (for some seed pair among these).
        assert!((1..10).any(|s| run(s, 0.5) != run(0, 0.5)));
    }

    #[test]
    fn a_transition_never_ends_up_saying_nothing() {
        let only_open = StateDiff {
            add: DiffSide {
                nodes: vec![node_change("fridge_1", &["Open"], None)],
                edges: vec![],
            },
            remove: DiffSide::default(),
        };
        for seed in 0..30 {
            let p = DeltaPerturbation::new(1.0, seed).unwrap();
            let (perturbed, changes) = perturb_delta(
                &only_open,
                1.0,
                StateVocabulary::Enact,
                &mut p.rng("t", "1", "2"),
            )
            .unwrap();
            assert!(matches!(
                changes.as_slice(),
                [PredicateChange::Swapped { .. }]
            ));
            assert_eq!(perturbed.add.nodes.len(), 1);
        }
    }

    #[test]
    fn action_lines_are_replaced_in_place() {
        let question = "Intro\n## Actions\n[Action 1] A.\n  [Action 2] B.\nEnd [Action 9]";
        let out = replace_action_lines(question, &["x".to_owned(), "y".to_owned()]);
        assert_eq!(
            out,
            "Intro\n## Actions\n[Action 1] x\n  [Action 2] y\nEnd [Action 9]"
        );
    }
}
