//! The checks a graphs file must pass before it is stored: every problem names the key frame
//! (its index and frame), the field (`nodes[2].states[0]`, `edges[1].to`) and what is wrong.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;

use serde::Serialize;

use crate::episode::{EpisodeGraphs, FrameSize, KeyFrameGraph};
use crate::pipeline::kfts::SENTENCES_PER_ACTION;
use crate::scene_graph::signature::{STATE_PHRASES, StateArity};
use crate::scene_graph::visibility::EVALUATION_SENSORS;
use crate::scene_graph::{
    View, format_object_name, restrict_to_view, sentence_count, state_centric_diff,
};

/// One thing wrong with a graphs file.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct GraphProblem {
    /// The key frame's index in `key_frames`; `None` for the file as a whole.
    pub key_frame: Option<usize>,
    /// That key frame's `frame`.
    pub frame: Option<usize>,
    /// The field at fault inside the key frame (`nodes[2].states[0]`), or `transition` for
    /// the change from the previous key frame.
    pub field: String,
    pub message: String,
}

impl fmt::Display for GraphProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.key_frame, self.frame) {
            (Some(index), Some(frame)) => write!(f, "key frame {index} (frame {frame})")?,
            (Some(index), None) => write!(f, "key frame {index}")?,
            _ => f.write_str("graphs")?,
        }
        if !self.field.is_empty() {
            write!(f, ", {}", self.field)?;
        }
        write!(f, ": {}", self.message)
    }
}

/// How a state may be used: the states ENACT's sentences describe, with their arity.
fn arity(state: &str) -> Option<StateArity> {
    STATE_PHRASES
        .iter()
        .find(|(name, _, _)| *name == state)
        .map(|(_, _, arity)| *arity)
}

/// The known states of one arity, for the message that refuses an unknown one.
fn known_states(wanted: StateArity) -> String {
    STATE_PHRASES
        .iter()
        .filter(|(_, _, a)| *a == wanted)
        .map(|(name, _, _)| *name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// ENACT's gripper relations have the robot as their subject ("the robot r1 is using the
/// left gripper to grasp the cup").
fn is_gripper_state(state: &str) -> bool {
    matches!(state, "LeftGrasping" | "RightGrasping" | "Grasping")
}

/// An agent's name starts with one of the words ENACT keeps agent ids after (`robot_r1`).
fn is_agent(name: &str) -> bool {
    let first = name.split('_').next().unwrap_or_default();
    ["robot", "agent", "player"].contains(&first)
}

/// Every problem of `graphs` for an episode of `frame_count` frames; `Ok` when there is none.
/// Transitions are checked only between key frames that are themselves valid, so one mistake
/// is reported once.
pub fn validate(graphs: &EpisodeGraphs, frame_count: usize) -> Result<(), Vec<GraphProblem>> {
    let mut problems = Vec::new();
    let mut valid = Vec::with_capacity(graphs.key_frames.len());
    let mut previous_frame: Option<usize> = None;
    for (index, key_frame) in graphs.key_frames.iter().enumerate() {
        let before = problems.len();
        let mut problem = |field: String, message: String| {
            problems.push(GraphProblem {
                key_frame: Some(index),
                frame: Some(key_frame.frame),
                field,
                message,
            })
        };
        if key_frame.frame >= frame_count {
            problem(
                "frame".into(),
                format!(
                    "frame {} is outside the episode, whose {frame_count} frames are 0..{}",
                    key_frame.frame,
                    frame_count.saturating_sub(1)
                ),
            );
        }
        if let Some(previous) = previous_frame
            && key_frame.frame <= previous
        {
            problem(
                "frame".into(),
                format!(
                    "key frames must be in increasing frame order, and this one does not come \
                     after the previous key frame's frame {previous}"
                ),
            );
        }
        previous_frame = Some(key_frame.frame);
        check_graph(key_frame, &mut problem);
        valid.push(problems.len() == before);
    }
    for index in 1..graphs.key_frames.len() {
        if valid[index - 1] && valid[index] {
            check_transition(graphs, index, &mut problems);
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems)
    }
}

/// The checks of one key frame's own graph.
fn check_graph(key_frame: &KeyFrameGraph, problem: &mut dyn FnMut(String, String)) {
    let mut names: BTreeMap<&str, usize> = BTreeMap::new();
    let mut formatted: BTreeMap<String, usize> = BTreeMap::new();
    for (i, node) in key_frame.nodes.iter().enumerate() {
        let field = format!("nodes[{i}]");
        if node.name.trim().is_empty() {
            problem(format!("{field}.name"), "an object needs a name".into());
        } else if let Some(first) = names.insert(&node.name, i) {
            names.insert(&node.name, first);
            problem(
                format!("{field}.name"),
                format!("{:?} is already the name of nodes[{first}]", node.name),
            );
        } else {
            match format_object_name(&node.name) {
                Err(e) => problem(format!("{field}.name"), e.to_string()),
                Ok(name) => {
                    if let Some(&first) = formatted.get(&name) {
                        problem(
                            format!("{field}.name"),
                            format!(
                                "ENACT's sentences call both this and nodes[{first}] {name:?}, so \
                                 nobody could tell their changes apart: give one a distinct name"
                            ),
                        );
                    } else {
                        formatted.insert(name, i);
                    }
                }
            }
        }
        if node.category.trim().is_empty() {
            problem(
                format!("{field}.category"),
                "an object needs a category (ENACT refuses a visible object without one)".into(),
            );
        }
        let mut seen = BTreeSet::new();
        for (k, state) in node.states.iter().enumerate() {
            let field = format!("{field}.states[{k}]");
            match arity(state) {
                None => problem(
                    field,
                    format!(
                        "unknown predicate {state:?}: an object's state is one of {}",
                        known_states(StateArity::Unary)
                    ),
                ),
                Some(StateArity::Binary) => problem(
                    field,
                    format!("{state} relates two objects: put it on an edge, not on a node"),
                ),
                Some(StateArity::Unary) if !seen.insert(state) => {
                    problem(field, format!("{state} is listed twice"))
                }
                Some(StateArity::Unary) => {}
            }
        }
        if let Some(parent) = &node.parent {
            for (k, p) in parent.iter().enumerate() {
                if p.trim().is_empty() {
                    problem(
                        format!("{field}.parent[{k}]"),
                        "a parent needs a name".into(),
                    );
                }
            }
        }
    }
    let mut pairs: BTreeMap<(&str, &str), usize> = BTreeMap::new();
    for (i, edge) in key_frame.edges.iter().enumerate() {
        let field = format!("edges[{i}]");
        for (end, name) in [("from", &edge.from), ("to", &edge.to)] {
            if !names.contains_key(name.as_str()) {
                problem(
                    format!("{field}.{end}"),
                    format!("{name:?} is not an object of this key frame"),
                );
            }
        }
        if edge.from == edge.to {
            problem(
                format!("{field}.to"),
                format!(
                    "an edge relates two objects, but both ends are {:?}",
                    edge.to
                ),
            );
        }
        if let Some(first) = pairs.insert((&edge.from, &edge.to), i) {
            pairs.insert((&edge.from, &edge.to), first);
            problem(
                field.clone(),
                format!(
                    "edges[{first}] already relates {:?} to {:?}: list every state of the pair \
                     in one edge",
                    edge.from, edge.to
                ),
            );
        }
        if edge.states.is_empty() {
            problem(
                format!("{field}.states"),
                "an edge needs at least one state".into(),
            );
        }
        let mut seen = BTreeSet::new();
        for (k, state) in edge.states.iter().enumerate() {
            let field = format!("{field}.states[{k}]");
            match arity(state) {
                None => problem(
                    field,
                    format!(
                        "unknown predicate {state:?}: a relation is one of {}",
                        known_states(StateArity::Binary)
                    ),
                ),
                Some(StateArity::Unary) => problem(
                    field,
                    format!("{state} is a state of one object: put it on a node, not on an edge"),
                ),
                Some(StateArity::Binary) if !seen.insert(state) => {
                    problem(field, format!("{state} is listed twice"))
                }
                Some(StateArity::Binary) if is_gripper_state(state) && !is_agent(&edge.from) => {
                    problem(
                        field,
                        format!(
                            "{state} has the robot as its subject: the edge must go from the \
                             robot (a name starting with robot_, agent_ or player_, like \
                             robot_r1), not from {:?}",
                            edge.from
                        ),
                    )
                }
                Some(StateArity::Binary) => {}
            }
        }
    }
    if let Some(visible) = &key_frame.visible {
        let mut seen = BTreeSet::new();
        for (k, name) in visible.iter().enumerate() {
            if !names.contains_key(name.as_str()) {
                problem(
                    format!("visible[{k}]"),
                    format!("{name:?} is not an object of this key frame"),
                );
            } else if !seen.insert(name) {
                problem(format!("visible[{k}]"), format!("{name:?} is listed twice"));
            }
        }
    }
}

/// The checks of the change from key frame `index - 1` to `index`: ENACT must be able to ask
/// about it, i.e. KFTS must accept it as a transition.
fn check_transition(graphs: &EpisodeGraphs, index: usize, problems: &mut Vec<GraphProblem>) {
    let (prev, next) = (&graphs.key_frames[index - 1], &graphs.key_frames[index]);
    let mut problem = |message: String| {
        problems.push(GraphProblem {
            key_frame: Some(index),
            frame: Some(next.frame),
            field: "transition".into(),
            message: format!(
                "from key frame {} (frame {}): {message}",
                index - 1,
                prev.frame
            ),
        })
    };
    let (a, b) = (
        prev.scene_graph(FrameSize::NOMINAL),
        next.scene_graph(FrameSize::NOMINAL),
    );
    let full = match state_centric_diff(&a, &b) {
        Ok(full) => full,
        Err(fault) => return problem(fault.to_string()),
    };
    if full.is_empty() {
        return problem(
            "nothing changed: ENACT cannot ask about a step with no change; edit the graph or \
             drop the key frame"
                .into(),
        );
    }
    let visible = match restrict_to_view(&a, &b, &full, View::Visible, &EVALUATION_SENSORS) {
        Ok(visible) => visible,
        Err(fault) => return problem(fault.to_string()),
    };
    if visible.is_empty() || !visible.has_meaningful_change() {
        return problem(
            "no change the camera sees in both key frames: ENACT only asks about visible \
             changes; mark the changed objects visible"
                .into(),
        );
    }
    match sentence_count(&visible) {
        Err(e) => problem(e.to_string()),
        Ok(n) if !SENTENCES_PER_ACTION.contains(&n) => problem(format!(
            "the change takes {n} sentences, but ENACT only asks about steps of {} to {}: \
             mark a key frame in between",
            SENTENCES_PER_ACTION.start(),
            SENTENCES_PER_ACTION.end()
        )),
        Ok(_) => {}
    }
}
