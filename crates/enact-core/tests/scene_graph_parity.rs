//! Parity of the scene-graph module with ENACT's own outputs (fixtures set A, "dev"):
//! transition and pair signature sets, the transient filter, and action sentences.
//! Skips (with a message) when the fixtures are not present.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

use enact_core::scene_graph::{
    FrameSelection, SceneGraph, SceneGraphTimeline, TransientFilter, View, diff_signatures,
    pair_signatures, parse_action, render_diff, transition_signatures, visible_diff,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde_json::Value;

#[path = "../../../tests/support/fixtures.rs"]
mod fixtures;

macro_rules! parity_or_skip {
    () => {
        match fixtures::parity_dir() {
            Some(dir) => dir,
            None => return,
        }
    };
}

fn read_jsonl(path: &Path) -> Vec<Value> {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn str_set(v: &Value) -> BTreeSet<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_string())
        .collect()
}

fn key_frames(dir: &Path) -> BTreeMap<String, Vec<String>> {
    let text = std::fs::read_to_string(dir.join("reference/key_frames.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// Each task's timeline, loaded with only its key frames selected.
fn key_frame_timelines(dir: &Path) -> HashMap<String, SceneGraphTimeline> {
    key_frames(dir)
        .into_iter()
        .map(|(task, frames)| {
            let path = dir
                .join("replayed_activities")
                .join(&task)
                .join("scene_graph_0.json");
            let selection = FrameSelection::Only(frames.into_iter().collect());
            (task, SceneGraphTimeline::load(&path, selection).unwrap())
        })
        .collect()
}

fn frame_ids(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_string())
        .collect()
}

#[test]
fn selection_loader_matches_full_loader() {
    let dir = parity_or_skip!();
    for (task, frames) in key_frames(&dir) {
        let path = dir
            .join("replayed_activities")
            .join(&task)
            .join("scene_graph_0.json");
        let all = SceneGraphTimeline::load(&path, FrameSelection::All).unwrap();
        let some = SceneGraphTimeline::load(
            &path,
            FrameSelection::Only(frames.iter().cloned().collect()),
        )
        .unwrap();
        for f in &frames {
            assert_eq!(
                *all.scene_graph(f).unwrap(),
                *some.scene_graph(f).unwrap(),
                "{task} {f}"
            );
        }
    }
}

#[test]
fn transition_signatures_match_enact() {
    let dir = parity_or_skip!();
    let timelines = key_frame_timelines(&dir);
    let items = read_jsonl(&dir.join("reference/transition_signatures.jsonl"));
    let (mut transitions, mut sets) = (0, 0);
    for item in &items {
        let task = item["task_name"].as_str().unwrap();
        let expected = item["transitions"].as_array().unwrap();
        let mut chain: Vec<String> = expected
            .iter()
            .map(|t| t["from_frame"].as_str().unwrap().to_string())
            .collect();
        chain.push(
            expected.last().unwrap()["to_frame"]
                .as_str()
                .unwrap()
                .to_string(),
        );
        let ours = transition_signatures(&timelines[task], &chain).unwrap();
        assert_eq!(ours.len(), expected.len(), "{}", item["id"]);
        for (i, (got, want)) in ours.iter().zip(expected).enumerate() {
            assert_eq!(
                got.visible,
                str_set(&want["visible"]),
                "{} transition {i} visible",
                item["id"]
            );
            assert_eq!(
                got.full,
                str_set(&want["full"]),
                "{} transition {i} full",
                item["id"]
            );
            transitions += 1;
            sets += 2;
        }
    }
    assert_eq!(items.len(), 96);
    eprintln!(
        "transition signatures: {} items, {transitions} transitions, {sets} sets equal",
        items.len()
    );
}

#[test]
fn pair_signatures_match_enact() {
    let dir = parity_or_skip!();
    let timelines = key_frame_timelines(&dir);
    let rows = read_jsonl(&dir.join("reference/pair_signatures.jsonl"));
    let (mut equal, mut errors) = (0, 0);
    for row in &rows {
        let task = row["task_name"].as_str().unwrap();
        let (from, to) = (
            row["from_frame"].as_str().unwrap(),
            row["to_frame"].as_str().unwrap(),
        );
        for (view, key) in [(View::Visible, "visible"), (View::Full, "full")] {
            let got = pair_signatures(&timelines[task], from, to, view);
            let enact_error = row
                .get("error")
                .and_then(|e| e.get(key))
                .filter(|e| !e.is_null());
            match (got, enact_error) {
                (Err(_), Some(_)) => errors += 1,
                (Ok(got), None) => {
                    assert_eq!(got, str_set(&row[key]), "{task} {from}->{to} {key}");
                    equal += 1;
                }
                (got, want) => {
                    panic!("{task} {from}->{to} {key}: ours {got:?}, ENACT error {want:?}")
                }
            }
        }
    }
    assert_eq!(rows.len(), 2688);
    eprintln!(
        "pair signatures: {} rows, {equal} sets equal, {errors} errors where ENACT raises too",
        rows.len()
    );
}

/// A graph as a multiset of order-free node and edge descriptions.
fn graph_bag(nodes: &[Value], edges: &[Value]) -> (Vec<String>, Vec<String>) {
    let sorted_states = |v: &Value| -> Vec<String> {
        let mut s: Vec<String> = v
            .get("states")
            .and_then(Value::as_array)
            .map(|a| a.iter().map(|x| x.as_str().unwrap().to_string()).collect())
            .unwrap_or_default();
        s.sort();
        s
    };
    let mut n: Vec<String> = nodes
        .iter()
        .map(|node| {
            let mut fields = canonical(node);
            if let Value::Object(map) = &mut fields {
                map.insert("states".into(), serde_json::json!(sorted_states(node)));
                if map.get("parent") == Some(&Value::Null) {
                    map.remove("parent");
                }
            }
            fields.to_string()
        })
        .collect();
    let mut e: Vec<String> = edges
        .iter()
        .map(|edge| {
            format!(
                "{}->{}:{:?}",
                edge["from"].as_str().unwrap(),
                edge["to"].as_str().unwrap(),
                sorted_states(edge)
            )
        })
        .collect();
    n.sort();
    e.sort();
    (n, e)
}

/// JSON with object keys sorted, so that key order does not matter.
fn canonical(v: &Value) -> Value {
    match v {
        Value::Object(map) => {
            let sorted: BTreeMap<&String, Value> =
                map.iter().map(|(k, v)| (k, canonical(v))).collect();
            Value::Object(sorted.into_iter().map(|(k, v)| (k.clone(), v)).collect())
        }
        Value::Array(a) => Value::Array(a.iter().map(canonical).collect()),
        other => other.clone(),
    }
}

fn our_bag(g: &SceneGraph) -> (Vec<String>, Vec<String>) {
    let v = serde_json::to_value(g).unwrap();
    graph_bag(
        v["nodes"].as_array().unwrap(),
        v["edges"].as_array().unwrap(),
    )
}

#[test]
fn transient_filter_unit_matches_enact() {
    let dir = parity_or_skip!();
    let unit = dir.join("reference/transient_filter_unit");
    let filtered = SceneGraphTimeline::load_with(
        &unit.join("scene_graph_0.json"),
        FrameSelection::All,
        TransientFilter::Enact,
    )
    .unwrap();
    // The same file read as a stream (as replays over 64 MB are).
    let streamed = SceneGraphTimeline::load_streamed(
        &unit.join("scene_graph_0.json"),
        &FrameSelection::All,
        TransientFilter::Enact,
    )
    .unwrap()
    .expect("frame ids in order");
    let rows = read_jsonl(&unit.join("filtered_graphs.jsonl"));
    for row in &rows {
        let frame = row["frame"].as_str().unwrap();
        let want = graph_bag(
            row["nodes"].as_array().unwrap(),
            row["edges"].as_array().unwrap(),
        );
        let got = our_bag(&filtered.scene_graph(frame).unwrap());
        assert_eq!(got, want, "frame {frame}");
        assert_eq!(
            our_bag(&streamed.scene_graph(frame).unwrap()),
            want,
            "streamed, frame {frame}"
        );
    }
    assert_eq!(rows.len(), 40);
    assert_eq!(filtered.frame_ids().count(), 40);
    eprintln!(
        "transient filter unit: {} frames equal as multisets",
        rows.len()
    );
}

/// The node fields other than name and states, in a fixed field order for comparison.
#[derive(serde::Serialize, serde::Deserialize)]
struct NodeFields {
    #[serde(default)]
    category: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    parent: Option<Vec<String>>,
    #[serde(default)]
    visibility: BTreeMap<String, Vec<serde_json::Number>>,
}

/// The feature strings of `transient_filter_changes.jsonl` (`nodefields` JSON in our
/// canonical form).
fn features(g: &SceneGraph) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for node in &g.nodes {
        let name = &node.name;
        out.insert(format!("node:{name}"));
        for s in &node.states {
            out.insert(format!("node:{name}:{s}"));
        }
        let fields = NodeFields {
            category: node.category.clone(),
            parent: node.parent.clone(),
            visibility: node.visibility.clone(),
        };
        out.insert(format!(
            "nodefields:{name}:{}",
            serde_json::to_string(&fields).unwrap()
        ));
    }
    for edge in &g.edges {
        out.insert(format!("edge:{}->{}", edge.from, edge.to));
        for s in &edge.states {
            out.insert(format!("edge:{}->{}:{s}", edge.from, edge.to));
        }
    }
    out
}

/// Cheap check that lets most frames skip the feature comparison: the same entries in the
/// same order with the same state sets (the filter rewrites state lists in sorted order).
fn same_up_to_state_order(a: &SceneGraph, b: &SceneGraph) -> bool {
    let same_states = |x: &[String], y: &[String]| {
        let (mut x, mut y) = (x.to_vec(), y.to_vec());
        x.sort();
        x.dedup();
        y.sort();
        y.dedup();
        x == y
    };
    a.nodes.len() == b.nodes.len()
        && a.edges.len() == b.edges.len()
        && a.nodes.iter().zip(&b.nodes).all(|(x, y)| {
            x.name == y.name
                && x.category == y.category
                && x.visibility == y.visibility
                && x.parent == y.parent
                && same_states(&x.states, &y.states)
        })
        && a.edges
            .iter()
            .zip(&b.edges)
            .all(|(x, y)| x.from == y.from && x.to == y.to && same_states(&x.states, &y.states))
}

fn canonical_feature(f: &str) -> String {
    match f.strip_prefix("nodefields:") {
        Some(rest) => {
            let brace = rest.find(":{").unwrap();
            let fields: NodeFields = serde_json::from_str(&rest[brace + 1..]).unwrap();
            format!(
                "nodefields:{}:{}",
                &rest[..brace],
                serde_json::to_string(&fields).unwrap()
            )
        }
        None => f.to_string(),
    }
}

#[test]
fn transient_filter_changes_match_enact() {
    let dir = parity_or_skip!();
    let mut want: BTreeMap<(String, String), (BTreeSet<String>, BTreeSet<String>)> =
        BTreeMap::new();
    for row in read_jsonl(&dir.join("reference/transient_filter_changes.jsonl")) {
        let set = |k: &str| -> BTreeSet<String> {
            str_set(&row[k])
                .iter()
                .map(|f| canonical_feature(f))
                .collect()
        };
        want.insert(
            (
                row["task_name"].as_str().unwrap().into(),
                row["frame"].as_str().unwrap().into(),
            ),
            (set("removed_by_filter"), set("added_by_filter")),
        );
    }
    let mut got = BTreeMap::new();
    for task in key_frames(&dir).keys() {
        let path = dir
            .join("replayed_activities")
            .join(task)
            .join("scene_graph_0.json");
        let raw = SceneGraphTimeline::load(&path, FrameSelection::All).unwrap();
        let filtered = raw.with_transients_filtered().unwrap();
        // Read as a stream through the filter, every frame is the same.
        let streamed =
            SceneGraphTimeline::load_streamed(&path, &FrameSelection::All, TransientFilter::Enact)
                .unwrap()
                .expect("frame ids in order");
        for frame in raw.frame_ids() {
            assert_eq!(
                *streamed.scene_graph(&frame).unwrap(),
                *filtered.scene_graph(&frame).unwrap(),
                "{task} frame {frame}"
            );
        }
        for frame in raw.frame_ids() {
            let (raw_graph, filtered_graph) = (
                raw.scene_graph(&frame).unwrap(),
                filtered.scene_graph(&frame).unwrap(),
            );
            if same_up_to_state_order(&raw_graph, &filtered_graph) {
                continue;
            }
            let before = features(&raw_graph);
            let after = features(&filtered_graph);
            let removed: BTreeSet<String> = before.difference(&after).cloned().collect();
            let added: BTreeSet<String> = after.difference(&before).cloned().collect();
            if !removed.is_empty() || !added.is_empty() {
                got.insert((task.clone(), frame), (removed, added));
            }
        }
    }
    assert_eq!(got, want);
    eprintln!(
        "transient filter changes: {} changed frames equal",
        want.len()
    );
}

#[test]
fn rendered_transitions_parse_back() {
    let dir = parity_or_skip!();
    let timelines = key_frame_timelines(&dir);
    let mut checked = 0;
    let mut rng = ChaCha8Rng::seed_from_u64(20251126);
    for item in read_jsonl(&dir.join("reference/transition_signatures.jsonl")) {
        let task = item["task_name"].as_str().unwrap();
        for t in item["transitions"].as_array().unwrap() {
            let (from, to) = (
                t["from_frame"].as_str().unwrap(),
                t["to_frame"].as_str().unwrap(),
            );
            for view in [View::Visible, View::Full] {
                let diff = visible_diff(&timelines[task], from, to, view).unwrap();
                let sigs = diff_signatures(&diff).unwrap();
                let text = render_diff(&diff, &mut rng).unwrap().unwrap_or_default();
                if text.is_empty() {
                    assert!(sigs.is_empty());
                    continue;
                }
                assert_eq!(
                    parse_action(&text).unwrap(),
                    sigs,
                    "{task} {from}->{to}: {text}"
                );
                checked += 1;
            }
        }
    }
    eprintln!("round trip: {checked} rendered diffs parsed back to their signatures");
}

/// The `[Action k] ...` lines of a question, by label.
fn action_lines(question: &str) -> BTreeMap<usize, String> {
    question
        .lines()
        .filter_map(|line| {
            let rest = line.strip_prefix("[Action ")?;
            let (label, text) = rest.split_once("] ")?;
            Some((label.parse().ok()?, text.to_string()))
        })
        .collect()
}

#[test]
fn qa_action_sentences_parse_to_visible_sets() {
    let dir = parity_or_skip!();
    let reference: HashMap<String, Vec<BTreeSet<String>>> =
        read_jsonl(&dir.join("reference/transition_signatures.jsonl"))
            .into_iter()
            .map(|item| {
                let sets = item["transitions"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|t| str_set(&t["visible"]))
                    .collect();
                (item["id"].as_str().unwrap().to_string(), sets)
            })
            .collect();
    let mut tally: BTreeMap<&str, (usize, usize)> = BTreeMap::new();
    let mut mismatches = Vec::new();
    for item in read_jsonl(&dir.join("QA/enact_ordering.jsonl")) {
        let id = item["id"].as_str().unwrap();
        let kind = if item["type"].as_str().unwrap().contains("inverse") {
            "inverse"
        } else {
            "forward"
        };
        let actions = action_lines(item["question"].as_str().unwrap());
        let gt: Vec<usize> = item["gt_answer"]
            .as_array()
            .unwrap()
            .iter()
            .map(|g| g.as_u64().unwrap() as usize)
            .collect();
        let visible = &reference[id];
        assert_eq!(actions.len(), visible.len(), "{id}");
        assert_eq!(frame_ids(&item["key_frame_ids"]).len(), visible.len() + 1);
        for (j, want) in visible.iter().enumerate() {
            // Inverse: transition j was caused by the action labelled gt[j]. Forward: the
            // actions are listed in chronological order.
            let label = if kind == "inverse" { gt[j] } else { j + 1 };
            let text = &actions[&label];
            let got = parse_action(text).unwrap_or_else(|e| panic!("{id}: {e}"));
            let entry = tally.entry(kind).or_default();
            entry.1 += 1;
            if &got == want {
                entry.0 += 1;
            } else {
                mismatches.push(format!(
                    "{id} transition {j}: {text:?}\n  parsed {got:?}\n  ENACT  {want:?}"
                ));
            }
        }
    }
    for (kind, (ok, total)) in &tally {
        eprintln!("{kind} action sentences: {ok}/{total} parse to ENACT's visible set");
    }
    for m in &mismatches {
        eprintln!("{m}");
    }
    assert!(
        mismatches.is_empty(),
        "{} action texts differ",
        mismatches.len()
    );
}
