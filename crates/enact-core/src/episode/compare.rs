//! Two curators' graphs of one episode side by side: which components differ per key frame
//! and per transition, and how well they agree on the transitions (the part items are made
//! of).

use std::collections::{BTreeMap, BTreeSet};

use serde::Serialize;

use crate::agreement::alpha::{AlphaResult, AlphaUndefined, MeasurementLevel, krippendorff_alpha};
use crate::agreement::reliability::ReliabilityData;
use crate::episode::{EpisodeGraphs, KeyFrameGraph, describe};

/// How many components two sets share and how many only one side has.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct ComponentCounts {
    pub shared: usize,
    pub only_a: usize,
    pub only_b: usize,
}

impl ComponentCounts {
    fn add(&mut self, other: ComponentCounts) {
        self.shared += other.shared;
        self.only_a += other.only_a;
        self.only_b += other.only_b;
    }

    /// Components on one side only.
    pub fn differing(&self) -> usize {
        self.only_a + self.only_b
    }
}

/// The components of two sets: counts and the lists of those on one side only.
fn split(
    a: &BTreeSet<String>,
    b: &BTreeSet<String>,
) -> (ComponentCounts, Vec<String>, Vec<String>) {
    let only_a: Vec<String> = a.difference(b).cloned().collect();
    let only_b: Vec<String> = b.difference(a).cloned().collect();
    let counts = ComponentCounts {
        shared: a.intersection(b).count(),
        only_a: only_a.len(),
        only_b: only_b.len(),
    };
    (counts, only_a, only_b)
}

/// One key frame (matched by `frame`) as the two curators drew it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct KeyFrameDifference {
    pub frame: usize,
    /// Whether curator A (B) marked this frame as a key frame.
    pub in_a: bool,
    pub in_b: bool,
    /// Over the graph's components: `object NAME (CATEGORY)`, `NAME: STATE`,
    /// `FROM -> TO: STATE`, `visible NAME`. A key frame only one curator marked counts all its
    /// components on that side.
    pub components: ComponentCounts,
    pub only_a: Vec<String>,
    pub only_b: Vec<String>,
}

/// One transition (matched by its two frames) as the two curators described it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TransitionDifference {
    pub from_frame: usize,
    pub to_frame: usize,
    pub in_a: bool,
    pub in_b: bool,
    /// Over the transition's visible signature components (what items and the verifier use).
    pub components: ComponentCounts,
    pub only_a: Vec<String>,
    pub only_b: Vec<String>,
}

/// Where two curators' graphs of an episode differ.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    pub key_frames: Vec<KeyFrameDifference>,
    pub transitions: Vec<TransitionDifference>,
    /// Summed over the transitions both curators have.
    pub transition_components: ComponentCounts,
    /// Shared / (shared + only A + only B) over the transitions both curators have; `None`
    /// when they share no transition or those have no component.
    pub transition_agreement: Option<f64>,
    /// Krippendorff's alpha (nominal) with one unit per component of a transition both
    /// curators have, each curator's value 1 when their transition has it and 0 when not.
    /// Undefined (with the reason) when there is no such unit or every value is the same
    /// (then the two agree completely, see `transition_agreement`).
    pub transition_alpha: AlphaResult,
}

/// The components a key frame's graph is compared by.
fn key_frame_components(key_frame: &KeyFrameGraph) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for node in &key_frame.nodes {
        out.insert(format!("object {} ({})", node.name, node.category));
        for state in &node.states {
            out.insert(format!("{}: {state}", node.name));
        }
        if key_frame.is_visible(&node.name) {
            out.insert(format!("visible {}", node.name));
        }
    }
    for edge in &key_frame.edges {
        for state in &edge.states {
            out.insert(format!("{} -> {}: {state}", edge.from, edge.to));
        }
    }
    out
}

/// Compares curator A's graphs with curator B's.
pub fn compare(a: &EpisodeGraphs, b: &EpisodeGraphs) -> Comparison {
    let frames_of = |g: &EpisodeGraphs| -> BTreeMap<usize, BTreeSet<String>> {
        g.key_frames
            .iter()
            .map(|k| (k.frame, key_frame_components(k)))
            .collect()
    };
    let (frames_a, frames_b) = (frames_of(a), frames_of(b));
    let empty = BTreeSet::new();
    let all_frames: BTreeSet<usize> = frames_a.keys().chain(frames_b.keys()).copied().collect();
    let key_frames = all_frames
        .into_iter()
        .map(|frame| {
            let (ca, cb) = (frames_a.get(&frame), frames_b.get(&frame));
            let (components, only_a, only_b) = split(ca.unwrap_or(&empty), cb.unwrap_or(&empty));
            KeyFrameDifference {
                frame,
                in_a: ca.is_some(),
                in_b: cb.is_some(),
                components,
                only_a,
                only_b,
            }
        })
        .collect();

    let transitions_of = |g: &EpisodeGraphs| -> BTreeMap<(usize, usize), BTreeSet<String>> {
        describe(g)
            .into_iter()
            .map(|t| {
                (
                    (t.from_frame, t.to_frame),
                    t.visible_signatures.into_iter().collect(),
                )
            })
            .collect()
    };
    let (trans_a, trans_b) = (transitions_of(a), transitions_of(b));
    let all_pairs: BTreeSet<(usize, usize)> =
        trans_a.keys().chain(trans_b.keys()).copied().collect();
    let mut transitions = Vec::new();
    let mut shared_total = ComponentCounts::default();
    let (mut row_a, mut row_b) = (Vec::new(), Vec::new());
    for (from_frame, to_frame) in all_pairs {
        let (sa, sb) = (
            trans_a.get(&(from_frame, to_frame)),
            trans_b.get(&(from_frame, to_frame)),
        );
        let (components, only_a, only_b) = split(sa.unwrap_or(&empty), sb.unwrap_or(&empty));
        if let (Some(sa), Some(sb)) = (sa, sb) {
            shared_total.add(components);
            for component in sa.union(sb) {
                row_a.push(Some(if sa.contains(component) { 1.0 } else { 0.0 }));
                row_b.push(Some(if sb.contains(component) { 1.0 } else { 0.0 }));
            }
        }
        transitions.push(TransitionDifference {
            from_frame,
            to_frame,
            in_a: sa.is_some(),
            in_b: sb.is_some(),
            components,
            only_a,
            only_b,
        });
    }
    let union = shared_total.shared + shared_total.differing();
    let transition_agreement = (union > 0).then(|| shared_total.shared as f64 / union as f64);
    // Two rows of equal length with finite values: the table cannot be refused.
    let transition_alpha = match ReliabilityData::from_coder_rows(vec![row_a, row_b]) {
        Ok(data) => krippendorff_alpha(&data, MeasurementLevel::Nominal),
        Err(_) => no_units_alpha(),
    };
    Comparison {
        key_frames,
        transitions,
        transition_components: shared_total,
        transition_agreement,
        transition_alpha,
    }
}

/// Alpha over no unit: what a table that could not be built would give.
fn no_units_alpha() -> AlphaResult {
    AlphaResult {
        alpha: None,
        reason: Some(AlphaUndefined::NoPairableUnits),
        level: MeasurementLevel::Nominal,
        coders: 2,
        units: 0,
        units_used: 0,
        pairable_values: 0,
        distinct_values: 0,
        observed_disagreement: None,
        expected_disagreement: None,
    }
}
