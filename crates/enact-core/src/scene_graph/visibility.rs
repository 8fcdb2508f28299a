//! Which changes a viewer can see: the visibility test on `external_sensor1`, the visible
//! ("partial") and full object sets, and the filter that drops changes of objects whose
//! category is ambiguous in view (ENACT's `get_visible_full_diff`).

use std::collections::{BTreeMap, BTreeSet, HashMap};

use crate::scene_graph::diff::{ChangeOp, DiffFault, DiffSide, GraphIndex, NodeChange, StateDiff};
use crate::scene_graph::record::{SceneGraph, SceneNode};

/// The camera ENACT evaluates with.
pub const EVALUATION_SENSORS: [&str; 1] = ["external_sensor1"];

/// ENACT quirk: an object counts as seen when its pixel share of the image is strictly above
/// this many percent (`OBJ_OBSERVABLE_PERCENT_THRESHOLD`). For 512x512 frames that is more
/// than 13.1 pixels: 13 is invisible, 14 visible.
pub const VISIBLE_PERCENT_THRESHOLD: f64 = 0.005;

/// Which object set a diff is restricted to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum View {
    /// ENACT's `partial_diff=True` (the "C" sets): objects seen in both frames, plus objects
    /// that appeared or disappeared and are seen in at least one frame.
    Visible,
    /// ENACT's `partial_diff=False` (the "F" sets): objects seen in either frame.
    Full,
}

/// Whether `node` is seen by any of `sensors` (ENACT's `is_object_visible` on a found node).
pub fn node_is_visible(node: &SceneNode, sensors: &[&str]) -> Result<bool, DiffFault> {
    for sensor in sensors {
        let Some(reading) = node.visibility.get(*sensor) else {
            continue;
        };
        if reading.is_empty() {
            continue;
        }
        let malformed = |problem: String| DiffFault::MalformedVisibility {
            object: node.name.clone(),
            sensor: sensor.to_string(),
            problem,
        };
        if reading.len() != 7 {
            return Err(malformed(format!(
                "expected 7 numbers [pixels, xmin, ymin, xmax, ymax, h, w], found {}",
                reading.len()
            )));
        }
        let value = |i: usize| {
            reading[i]
                .as_f64()
                .ok_or_else(|| malformed(format!("value {} is not a finite number", reading[i])))
        };
        let (pixels, height, width) = (value(0)?, value(5)?, value(6)?);
        let total = height * width;
        if total == 0.0 {
            return Err(malformed("image size is zero".to_string()));
        }
        if pixels / total * 100.0 > VISIBLE_PERCENT_THRESHOLD {
            return Ok(true);
        }
    }
    Ok(false)
}

/// The objects among `active` seen in a graph.
fn seen<'a>(
    active: &BTreeSet<&'a str>,
    graph: &GraphIndex<'_>,
    sensors: &[&str],
) -> Result<BTreeSet<&'a str>, DiffFault> {
    let mut out = BTreeSet::new();
    for &name in active {
        if let Some(node) = graph.first_node(name)
            && node_is_visible(node, sensors)?
        {
            out.insert(name);
        }
    }
    Ok(out)
}

/// ENACT quirk: formatted names drop instance ids ("the apple" for `apple_1` and `apple_2`),
/// so ENACT drops the changes of objects whose category occurs more than once (`System`
/// excepted) among the changed objects seen in *either* frame, whichever view is asked for.
/// Returns each such object's category and the ambiguous categories; an object seen without
/// a category is an error (ENACT's assertion).
fn ambiguous_categories<'a>(
    seen_either: &BTreeSet<&'a str>,
    from: &GraphIndex<'a>,
    to: &GraphIndex<'a>,
) -> Result<(HashMap<&'a str, &'a str>, BTreeSet<&'a str>), DiffFault> {
    let mut category: HashMap<&str, &str> = HashMap::with_capacity(seen_either.len());
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    for &name in seen_either {
        // Looked up in `from` first, as ENACT searches `from_graph['nodes'] + to_graph['nodes']`.
        let node = from.first_node(name).or_else(|| to.first_node(name));
        let cat =
            node.and_then(|n| n.category.as_deref())
                .ok_or_else(|| DiffFault::MissingCategory {
                    object: name.to_string(),
                })?;
        category.insert(name, cat);
        *counts.entry(cat).or_default() += 1;
    }
    let ambiguous = counts
        .into_iter()
        .filter(|&(cat, k)| k > 1 && cat != "System")
        .map(|(cat, _)| cat)
        .collect();
    Ok((category, ambiguous))
}

/// ENACT quirk: the exceptions to the ambiguity filter for node entries: a name containing
/// "half" that disappears (or loses states), or that appears (or gains states) while one of
/// its parents is in view. ENACT iterates the parent list in the second case, so a `half`
/// entry without one is a TypeError there, an error here.
fn keeps_ambiguous_node(
    node: &NodeChange,
    op: ChangeOp,
    visible: &BTreeSet<&str>,
) -> Result<bool, DiffFault> {
    if !node.name.contains("half") {
        return Ok(false);
    }
    if op == ChangeOp::Remove {
        return Ok(true);
    }
    let parent = node
        .parent
        .as_ref()
        .ok_or_else(|| DiffFault::HalfNodeWithoutParent {
            node: node.name.clone(),
        })?;
    Ok(parent.iter().any(|p| visible.contains(p.as_str())))
}

/// Restricts `full` (the state-centric diff from `from` to `to`) to what `view` shows, then
/// drops changes that formatted names cannot attribute (see [`ambiguous_categories`]).
/// Node entries need their object visible; edge entries need both ends visible.
pub fn restrict_to_view(
    from: &SceneGraph,
    to: &SceneGraph,
    full: &StateDiff,
    view: View,
    sensors: &[&str],
) -> Result<StateDiff, DiffFault> {
    restrict_to_view_indexed(
        &GraphIndex::new(from),
        &GraphIndex::new(to),
        full,
        view,
        sensors,
    )
}

/// [`restrict_to_view`] over graphs already indexed.
pub fn restrict_to_view_indexed(
    from: &GraphIndex<'_>,
    to: &GraphIndex<'_>,
    full: &StateDiff,
    view: View,
    sensors: &[&str],
) -> Result<StateDiff, DiffFault> {
    if full.is_empty() {
        return Ok(StateDiff::default());
    }
    let active = full.active_objects();
    let seen_from = seen(&active, from, sensors)?;
    let seen_to = seen(&active, to, sensors)?;
    let seen_either: BTreeSet<&str> = seen_from.union(&seen_to).copied().collect();
    let visible: BTreeSet<&str> = match view {
        View::Full => seen_either.clone(),
        View::Visible => {
            let mut both: BTreeSet<&str> = seen_from.intersection(&seen_to).copied().collect();
            // Whole objects appearing or disappearing count when seen in either frame.
            both.extend(
                full.created_or_deleted()
                    .into_iter()
                    .filter(|n| active.contains(n) && seen_either.contains(n)),
            );
            both
        }
    };
    let (category, ambiguous) = ambiguous_categories(&seen_either, from, to)?;
    let is_ambiguous = |name: &str| category.get(name).is_some_and(|c| ambiguous.contains(c));

    let mut out = StateDiff::default();
    for op in ChangeOp::BOTH {
        let side: &DiffSide = full.side(op);
        let kept: &mut DiffSide = match op {
            ChangeOp::Add => &mut out.add,
            ChangeOp::Remove => &mut out.remove,
        };
        for node in &side.nodes {
            if visible.contains(node.name.as_str())
                && (!is_ambiguous(&node.name) || keeps_ambiguous_node(node, op, &visible)?)
            {
                kept.nodes.push(node.clone());
            }
        }
        for edge in &side.edges {
            if visible.contains(edge.from.as_str())
                && visible.contains(edge.to.as_str())
                && !is_ambiguous(&edge.from)
                && !is_ambiguous(&edge.to)
            {
                kept.edges.push(edge.clone());
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_graph::diff::state_centric_diff;
    use crate::scene_graph::diff::tests::{edge, node, with_parent};

    fn seen_with(mut n: SceneNode, pixels: u64) -> SceneNode {
        n.visibility.insert(
            "external_sensor1".into(),
            vec![
                pixels.into(),
                0.into(),
                0.into(),
                5.into(),
                5.into(),
                512.into(),
                512.into(),
            ],
        );
        n
    }

    fn visible_diff(from: &SceneGraph, to: &SceneGraph, view: View) -> StateDiff {
        let full = state_centric_diff(from, to).unwrap();
        restrict_to_view(from, to, &full, view, &EVALUATION_SENSORS).unwrap()
    }

    #[test]
    fn threshold_is_between_13_and_14_pixels() {
        assert!(
            !node_is_visible(&seen_with(node("a", "x", &[]), 13), &EVALUATION_SENSORS).unwrap()
        );
        assert!(node_is_visible(&seen_with(node("a", "x", &[]), 14), &EVALUATION_SENSORS).unwrap());
        assert!(!node_is_visible(&node("a", "x", &[]), &EVALUATION_SENSORS).unwrap());
        let mut other = node("a", "x", &[]);
        other
            .visibility
            .insert("external_sensor2".into(), vec![100000.into(); 7]);
        assert!(!node_is_visible(&other, &EVALUATION_SENSORS).unwrap());
        let mut empty = node("a", "x", &[]);
        empty.visibility.insert("external_sensor1".into(), vec![]);
        assert!(!node_is_visible(&empty, &EVALUATION_SENSORS).unwrap());
        let mut short = node("a", "x", &[]);
        short
            .visibility
            .insert("external_sensor1".into(), vec![14.into(); 3]);
        assert!(matches!(
            node_is_visible(&short, &EVALUATION_SENSORS),
            Err(DiffFault::MalformedVisibility { .. })
        ));
    }

    #[test]
    fn visible_needs_both_frames_but_full_either() {
        // The fridge opens; it is in view only afterwards.
        let from = SceneGraph {
            nodes: vec![seen_with(node("fridge_1", "fridge", &[]), 13)],
            edges: vec![],
        };
        let to = SceneGraph {
            nodes: vec![seen_with(node("fridge_1", "fridge", &["Open"]), 14)],
            edges: vec![],
        };
        assert!(visible_diff(&from, &to, View::Visible).is_empty());
        assert_eq!(
            visible_diff(&from, &to, View::Full).add.nodes[0].states,
            ["Open"]
        );
    }

    #[test]
    fn whole_objects_count_when_seen_once() {
        let from = SceneGraph {
            nodes: vec![seen_with(node("apple_1", "apple", &[]), 500)],
            edges: vec![],
        };
        let to = SceneGraph {
            nodes: vec![seen_with(
                with_parent(node("half_apple_2", "half_apple", &[]), &["apple_1"]),
                500,
            )],
            edges: vec![],
        };
        let d = visible_diff(&from, &to, View::Visible);
        assert_eq!(d.add.nodes[0].name, "half_apple_2");
        assert_eq!(d.remove.nodes[0].name, "apple_1");
    }

    #[test]
    fn edges_need_both_ends_visible() {
        let robot = seen_with(node("robot_r1", "agent", &[]), 5000);
        let from = SceneGraph {
            nodes: vec![robot.clone(), node("cup_1", "cup", &[])],
            edges: vec![],
        };
        let to = SceneGraph {
            nodes: vec![robot, node("cup_1", "cup", &[])],
            edges: vec![edge("robot_r1", "cup_1", &["LeftGrasping"])],
        };
        assert!(visible_diff(&from, &to, View::Full).is_empty());
    }

    #[test]
    fn ambiguous_categories_are_dropped() {
        let from = SceneGraph {
            nodes: vec![
                seen_with(node("apple_1", "apple", &[]), 500),
                seen_with(node("apple_2", "apple", &[]), 500),
                seen_with(node("table_3", "table", &[]), 500),
                seen_with(node("dust", "System", &[]), 500),
                seen_with(node("water", "System", &[]), 500),
            ],
            edges: vec![edge("apple_1", "table_3", &["OnTop"])],
        };
        let mut to = from.clone();
        to.nodes[0].states = vec!["Cooked".into()];
        to.nodes[1].states = vec!["Cooked".into()];
        to.nodes[3].states = vec!["Frozen".into()];
        to.nodes[4].states = vec!["Frozen".into()];
        to.edges.clear();
        // Only the apples are ambiguous; the two Systems are exempt.
        let d = visible_diff(&from, &to, View::Full);
        let names: Vec<&str> = d.add.nodes.iter().map(|n| n.name.as_str()).collect();
        assert_eq!(names, ["dust", "water"]);
        assert!(d.remove.is_empty());
        // The count is over objects seen in either frame, also for the visible view: apple_2
        // is seen only in `to`, yet makes apple_1's change ambiguous.
        let mut from2 = from.clone();
        from2.nodes[1] = node("apple_2", "apple", &[]);
        let mut to2 = to.clone();
        to2.nodes[1] = seen_with(node("apple_2", "apple", &["Cooked"]), 500);
        let d = visible_diff(&from2, &to2, View::Visible);
        assert!(d.add.nodes.iter().all(|n| !n.name.starts_with("apple")));
    }

    #[test]
    fn half_objects_survive_the_ambiguity_filter() {
        let knife = seen_with(node("knife_9", "knife", &[]), 500);
        let from = SceneGraph {
            nodes: vec![knife.clone(), seen_with(node("apple_1", "apple", &[]), 500)],
            edges: vec![],
        };
        let half = |n: &str| seen_with(with_parent(node(n, "half_apple", &[]), &["apple_1"]), 500);
        let to = SceneGraph {
            nodes: vec![knife, half("half_apple_2"), half("half_apple_3")],
            edges: vec![],
        };
        let d = visible_diff(&from, &to, View::Full);
        assert_eq!(d.add.nodes.len(), 2);
        // Backwards: the halves disappear (kept), the apple appears.
        let d = visible_diff(&to, &from, View::Full);
        assert_eq!(d.remove.nodes.len(), 2);
        // A state change of an ambiguous half object without parent list: ENACT's TypeError.
        let mut cooked = to.clone();
        cooked.nodes[1].states = vec!["Cooked".into()];
        cooked.nodes[1].parent = None;
        cooked.nodes[2].states = vec!["Cooked".into()];
        let full = state_centric_diff(&to, &cooked).unwrap();
        assert!(matches!(
            restrict_to_view(&to, &cooked, &full, View::Full, &EVALUATION_SENSORS),
            Err(DiffFault::HalfNodeWithoutParent { .. })
        ));
    }

    #[test]
    fn missing_category_of_visible_object_is_an_error() {
        let mut a = seen_with(node("a_1", "x", &[]), 500);
        a.category = None;
        let from = SceneGraph {
            nodes: vec![a.clone()],
            edges: vec![],
        };
        let mut b = a.clone();
        b.states = vec!["Open".into()];
        let to = SceneGraph {
            nodes: vec![b],
            edges: vec![],
        };
        let full = state_centric_diff(&from, &to).unwrap();
        assert!(matches!(
            restrict_to_view(&from, &to, &full, View::Full, &EVALUATION_SENSORS),
            Err(DiffFault::MissingCategory { .. })
        ));
    }
}
