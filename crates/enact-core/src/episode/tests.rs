use serde_json::json;

use super::*;

/// A kitchen episode of four key frames: the fridge opens, the robot grasps the apple, the
/// apple goes on the table and the robot lets go, the stove turns on.
pub(crate) fn kitchen() -> EpisodeGraphs {
    serde_json::from_value(json!({"key_frames": [
        {"frame": 0, "nodes": [
            {"name": "robot_r1", "category": "agent", "states": []},
            {"name": "fridge_1", "category": "fridge", "states": []},
            {"name": "apple_2", "category": "apple", "states": []},
            {"name": "table_3", "category": "table", "states": []},
            {"name": "stove_4", "category": "stove", "states": []}],
         "edges": [{"from": "apple_2", "to": "fridge_1", "states": ["Inside"]}]},
        {"frame": 3, "nodes": [
            {"name": "robot_r1", "category": "agent", "states": []},
            {"name": "fridge_1", "category": "fridge", "states": ["Open"]},
            {"name": "apple_2", "category": "apple", "states": []},
            {"name": "table_3", "category": "table", "states": []},
            {"name": "stove_4", "category": "stove", "states": []}],
         "edges": [{"from": "apple_2", "to": "fridge_1", "states": ["Inside"]}]},
        {"frame": 6, "nodes": [
            {"name": "robot_r1", "category": "agent", "states": []},
            {"name": "fridge_1", "category": "fridge", "states": ["Open"]},
            {"name": "apple_2", "category": "apple", "states": []},
            {"name": "table_3", "category": "table", "states": []},
            {"name": "stove_4", "category": "stove", "states": []}],
         "edges": [{"from": "robot_r1", "to": "apple_2", "states": ["LeftGrasping"]}]},
        {"frame": 9, "nodes": [
            {"name": "robot_r1", "category": "agent", "states": []},
            {"name": "fridge_1", "category": "fridge", "states": ["Open"]},
            {"name": "apple_2", "category": "apple", "states": []},
            {"name": "table_3", "category": "table", "states": []},
            {"name": "stove_4", "category": "stove", "states": ["ToggledOn"]}],
         "edges": [{"from": "apple_2", "to": "table_3", "states": ["OnTop"]}]}
    ]}))
    .unwrap()
}

fn problems(graphs: &EpisodeGraphs, frames: usize) -> Vec<String> {
    validate(graphs, frames)
        .err()
        .unwrap_or_default()
        .iter()
        .map(ToString::to_string)
        .collect()
}

#[test]
fn the_graphs_file_reads_and_writes_in_the_issue_shape() {
    let graphs = kitchen();
    assert_eq!(graphs.key_frames.len(), 4);
    assert_eq!(graphs.key_frames[0].visible, None);
    let written = serde_json::to_value(&graphs).unwrap();
    assert!(written["key_frames"][0].get("visible").is_none());
    assert_eq!(
        written["key_frames"][1]["nodes"][1]["states"],
        json!(["Open"])
    );
    let back: EpisodeGraphs = serde_json::from_value(written).unwrap();
    assert_eq!(back, graphs);
    // A misspelt field is refused rather than ignored.
    let err = serde_json::from_value::<EpisodeGraphs>(json!({"key_frames": [
        {"frame": 0, "nodes": [{"name": "a_1", "category": "a", "sates": []}], "edges": []}
    ]}))
    .unwrap_err();
    assert!(err.to_string().contains("sates"), "{err}");
}

#[test]
fn a_valid_episode_passes() {
    assert_eq!(validate(&kitchen(), 12), Ok(()));
}

#[test]
fn every_problem_names_the_key_frame_and_the_field() {
    let mut graphs = kitchen();
    graphs.key_frames[1].nodes[1].states = vec!["Opn".into()];
    graphs.key_frames[2].nodes[2].states = vec!["Inside".into()];
    graphs.key_frames[2].edges[0].to = "pear_9".into();
    graphs.key_frames[3].nodes.push(EpisodeNode {
        name: "table_3".into(),
        category: "table".into(),
        states: vec![],
        parent: None,
    });
    graphs.key_frames[3].edges.push(SceneEdge {
        from: "apple_2".into(),
        to: "stove_4".into(),
        states: vec!["Open".into()],
    });
    assert_eq!(
        problems(&graphs, 12),
        [
            "key frame 1 (frame 3), nodes[1].states[0]: unknown predicate \"Opn\": an object's \
             state is one of Burnt, Cooked, Folded, Unfolded, Frozen, HeatSourceOrSink, Heated, \
             OnFire, InFOVofRobot, Open, ToggledOn",
            "key frame 2 (frame 6), nodes[2].states[0]: Inside relates two objects: put it on \
             an edge, not on a node",
            "key frame 2 (frame 6), edges[0].to: \"pear_9\" is not an object of this key frame",
            "key frame 3 (frame 9), nodes[5].name: \"table_3\" is already the name of nodes[3]",
            "key frame 3 (frame 9), edges[1].states[0]: Open is a state of one object: put it \
             on a node, not on an edge",
        ]
    );
}

#[test]
fn frames_must_increase_and_lie_inside_the_episode() {
    let mut graphs = kitchen();
    graphs.key_frames[2].frame = 3;
    graphs.key_frames[3].frame = 12;
    let found = problems(&graphs, 12);
    assert_eq!(found.len(), 2, "{found:?}");
    assert!(found[0].starts_with("key frame 2 (frame 3), frame: key frames must be in increasing"));
    assert!(found[1].starts_with(
        "key frame 3 (frame 12), frame: frame 12 is outside the episode, whose 12 frames are 0..11"
    ));
}

#[test]
fn names_enact_cannot_use_are_refused() {
    let mut graphs = kitchen();
    graphs.key_frames[0].nodes.push(EpisodeNode {
        name: "_1".into(),
        category: "x".into(),
        states: vec![],
        parent: None,
    });
    graphs.key_frames[0].nodes.push(EpisodeNode {
        name: "apple_7".into(),
        category: "apple".into(),
        states: vec![],
        parent: None,
    });
    graphs.key_frames[0].nodes[1].category = " ".into();
    let found = problems(&graphs, 12);
    assert_eq!(found.len(), 3, "{found:?}");
    assert!(found[0].starts_with("key frame 0 (frame 0), nodes[1].category: an object needs"));
    assert!(found[1].starts_with("key frame 0 (frame 0), nodes[5].name: object name \"_1\""));
    assert!(found[2].starts_with(
        "key frame 0 (frame 0), nodes[6].name: ENACT's sentences call both this and nodes[2] \
         \"the apple\""
    ));
}

#[test]
fn grasping_goes_from_the_robot() {
    let mut graphs = kitchen();
    graphs.key_frames[2].edges[0] = SceneEdge {
        from: "apple_2".into(),
        to: "robot_r1".into(),
        states: vec!["LeftGrasping".into()],
    };
    let found = problems(&graphs, 12);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].starts_with(
        "key frame 2 (frame 6), edges[0].states[0]: LeftGrasping has the robot as its subject"
    ));
}

#[test]
fn a_step_without_a_visible_change_is_flagged() {
    let mut graphs = kitchen();
    graphs.key_frames[1].nodes[1].states.clear();
    let found = problems(&graphs, 12);
    assert_eq!(
        found,
        [
            "key frame 1 (frame 3), transition: from key frame 0 (frame 0): nothing changed: ENACT \
          cannot ask about a step with no change; edit the graph or drop the key frame"
        ]
    );
    // The fridge opens out of sight: a change, but none the items could be made of.
    let mut graphs = kitchen();
    graphs.key_frames[1].visible = Some(vec!["robot_r1".into(), "apple_2".into()]);
    let found = problems(&graphs, 12);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].contains("transition: from key frame 0 (frame 0): no change the camera sees"));
    // Unknown names in the visible list are named.
    graphs.key_frames[1].visible = Some(vec!["ghost_1".into()]);
    assert!(problems(&graphs, 12)[0].starts_with(
        "key frame 1 (frame 3), visible[0]: \"ghost_1\" is not an object of this key frame"
    ));
}

#[test]
fn describe_shows_the_sentences_and_signatures_enact_will_use() {
    let views = describe(&kitchen());
    assert_eq!(views.len(), 3);
    assert_eq!((views[0].from_frame, views[0].to_frame), (0, 3));
    assert_eq!(
        views[0].action.as_deref(),
        Some("The fridge now becomes open.")
    );
    assert_eq!(views[0].visible_signatures, ["node_add_the fridge_Open"]);
    assert_eq!(
        views[1].action.as_deref(),
        Some(
            "The robot r1 now becomes using the left gripper to grasp the apple. The apple is \
             no longer inside the fridge."
        )
    );
    assert_eq!(
        views[2].visible_signatures,
        [
            "edge_add_the apple_the table_OnTop",
            "edge_remove_the robot r1_the apple_LeftGrasping",
            "node_add_the stove_ToggledOn",
        ]
    );
    assert!(views.iter().all(|v| v.error.is_none()));
    // An object out of sight: in the full view only.
    let mut graphs = kitchen();
    graphs.key_frames[3].visible = Some(
        ["robot_r1", "fridge_1", "apple_2", "table_3"]
            .map(String::from)
            .to_vec(),
    );
    let last = &describe(&graphs)[2];
    assert!(
        !last
            .visible_signatures
            .contains(&"node_add_the stove_ToggledOn".to_string())
    );
    assert!(
        last.full_signatures
            .contains(&"node_add_the stove_ToggledOn".to_string())
    );
    // A name ENACT cannot format is reported on the transition, not panicked on.
    let mut graphs = kitchen();
    graphs.key_frames[1].nodes[1].name = "_1".into();
    graphs.key_frames[1].nodes[1].category = "thing".into();
    graphs.key_frames[1].edges[0].to = "_1".into();
    assert!(describe(&graphs)[0].error.is_some());
}

#[test]
fn the_scene_graph_round_trips_with_visibility() {
    let mut graphs = kitchen();
    graphs.key_frames[2].visible = Some(vec!["robot_r1".into(), "apple_2".into()]);
    for key_frame in &graphs.key_frames {
        let graph = key_frame.scene_graph(FrameSize {
            width: 640,
            height: 480,
        });
        assert_eq!(
            &KeyFrameGraph::from_scene_graph(key_frame.frame, &graph),
            key_frame
        );
    }
    let graph = graphs.key_frames[2].scene_graph(FrameSize::NOMINAL);
    assert_eq!(graph.nodes[1].visibility, Default::default());
    assert_eq!(
        serde_json::to_value(&graph.nodes[0].visibility).unwrap(),
        json!({"external_sensor1": [262144, 0, 0, 511, 511, 512, 512]})
    );
}

#[test]
fn two_curators_with_planted_differences() {
    let a = kitchen();
    let mut b = kitchen();
    // B drew the stove as already on at frame 6 (two key frames differ by one component
    // each, transitions 3->6 and 6->9 each change by one component) ...
    b.key_frames[2].nodes[4].states.push("ToggledOn".into());
    // ... and used the right gripper (key frame 6 differs by one more component on each
    // side; transitions 3->6 and 6->9 each differ by one signature on each side).
    b.key_frames[2].edges[0].states = vec!["RightGrasping".into()];
    let c = compare(&a, &b);
    let counts: Vec<(usize, usize, usize)> = c
        .key_frames
        .iter()
        .map(|k| {
            (
                k.components.shared,
                k.components.only_a,
                k.components.only_b,
            )
        })
        .collect();
    // Key frame components: 5 objects + 5 visible + states + edge states.
    assert_eq!(counts, [(11, 0, 0), (12, 0, 0), (11, 1, 2), (13, 0, 0)]);
    assert_eq!(
        c.key_frames[2].only_a,
        ["robot_r1 -> apple_2: LeftGrasping"]
    );
    assert_eq!(
        c.key_frames[2].only_b,
        ["robot_r1 -> apple_2: RightGrasping", "stove_4: ToggledOn"]
    );
    let counts: Vec<(usize, usize, usize)> = c
        .transitions
        .iter()
        .map(|t| {
            (
                t.components.shared,
                t.components.only_a,
                t.components.only_b,
            )
        })
        .collect();
    // 0->3: the fridge opens (same). 3->6: A {grasp L, apple leaves fridge}, B {grasp R,
    // apple leaves fridge, stove on}. 6->9: A {on table, release L, stove on}, B {on table,
    // release R}.
    assert_eq!(counts, [(1, 0, 0), (1, 1, 2), (1, 2, 1)]);
    assert_eq!(c.transition_components.shared, 3);
    assert_eq!(c.transition_components.differing(), 6);
    assert_eq!(c.transition_agreement, Some(3.0 / 9.0));
    // Nine units, three agreeing (1, 1), six split (1, 0): D_o = 12/18, and the 18 values hold
    // 12 ones and 6 zeros, so D_e = 2·12·6/(18·17) and alpha = 1 − D_o/D_e = −0.4167.
    let alpha = c.transition_alpha.alpha.unwrap();
    assert!(
        (alpha - (1.0 - (12.0 / 18.0) / (144.0 / 306.0))).abs() < 1e-12,
        "{alpha}"
    );

    // Identical graphs agree completely; alpha has no variation to work with.
    let same = compare(&a, &a);
    assert_eq!(same.transition_agreement, Some(1.0));
    assert!(same.transition_alpha.alpha.is_none());
    assert!(
        same.key_frames
            .iter()
            .all(|k| k.components.differing() == 0)
    );

    // A key frame only one curator marked: all its components on that side, and its
    // transitions are matched with nothing.
    let mut fewer = kitchen();
    fewer.key_frames.remove(1);
    let c = compare(&a, &fewer);
    assert_eq!((c.key_frames[1].in_a, c.key_frames[1].in_b), (true, false));
    assert_eq!(
        c.key_frames[1].components,
        ComponentCounts {
            shared: 0,
            only_a: 12,
            only_b: 0
        }
    );
    let pairs: Vec<(usize, usize, bool, bool)> = c
        .transitions
        .iter()
        .map(|t| (t.from_frame, t.to_frame, t.in_a, t.in_b))
        .collect();
    assert_eq!(
        pairs,
        [
            (0, 3, true, false),
            (0, 6, false, true),
            (3, 6, true, false),
            (6, 9, true, true)
        ]
    );
}

mod round_trip {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::super::*;
    use crate::pipeline::marked::MARKED_KEY_FRAMES_FILE;
    use crate::pipeline::{SegmentationParams, segment_task};
    use crate::scene_graph::{View, pair_signatures};

    const CATEGORIES: [&str; 6] = ["fridge", "apple", "table", "stove", "cabinet", "bowl"];
    const UNARY: [&str; 4] = ["Open", "ToggledOn", "Cooked", "Folded"];
    const BINARY: [&str; 4] = ["OnTop", "Inside", "NextTo", "Under"];
    const GRIPPERS: [&str; 2] = ["LeftGrasping", "RightGrasping"];

    /// Adds `state` to the list if absent, removes it if present.
    fn toggle(states: &mut Vec<String>, state: &str) {
        match states.iter().position(|s| s == state) {
            Some(i) => {
                states.remove(i);
            }
            None => states.push(state.to_string()),
        }
    }

    fn toggle_edge(key_frame: &mut KeyFrameGraph, from: &str, to: &str, state: &str) {
        match key_frame
            .edges
            .iter()
            .position(|e| e.from == from && e.to == to)
        {
            Some(i) => {
                toggle(&mut key_frame.edges[i].states, state);
                if key_frame.edges[i].states.is_empty() {
                    key_frame.edges.remove(i);
                }
            }
            None => key_frame.edges.push(SceneEdge {
                from: from.into(),
                to: to.into(),
                states: vec![state.into()],
            }),
        }
    }

    /// One random edit of a key frame: a unary state, a relation or a grasp toggled.
    fn edit(rng: &mut ChaCha8Rng, key_frame: &mut KeyFrameGraph) {
        let objects = key_frame.nodes.len() - 1; // node 0 is the robot
        let pick = |rng: &mut ChaCha8Rng| 1 + rng.random_range(0..objects);
        match rng.random_range(0..3) {
            0 => {
                let i = pick(rng);
                toggle(
                    &mut key_frame.nodes[i].states,
                    UNARY[rng.random_range(0..UNARY.len())],
                );
            }
            1 => {
                let (a, b) = (pick(rng), pick(rng));
                if a != b {
                    let (from, to) = (
                        key_frame.nodes[a].name.clone(),
                        key_frame.nodes[b].name.clone(),
                    );
                    toggle_edge(
                        key_frame,
                        &from,
                        &to,
                        BINARY[rng.random_range(0..BINARY.len())],
                    );
                }
            }
            _ => {
                let to = key_frame.nodes[pick(rng)].name.clone();
                toggle_edge(key_frame, "robot_r1", &to, GRIPPERS[rng.random_range(0..2)]);
            }
        }
    }

    /// Random valid graphs: 3 to 6 objects, 4 to 8 key frames, each later one the one before
    /// with one to three edits; sometimes an object out of sight.
    fn random_graphs(rng: &mut ChaCha8Rng) -> (EpisodeGraphs, usize) {
        loop {
            let objects = rng.random_range(3..=CATEGORIES.len());
            let mut first = KeyFrameGraph {
                frame: rng.random_range(0..3),
                nodes: vec![EpisodeNode {
                    name: "robot_r1".into(),
                    category: "agent".into(),
                    states: vec![],
                    parent: None,
                }],
                edges: vec![],
                visible: None,
            };
            for (i, category) in CATEGORIES.iter().take(objects).enumerate() {
                first.nodes.push(EpisodeNode {
                    name: format!("{category}_{}", i + 1),
                    category: (*category).into(),
                    states: vec![],
                    parent: None,
                });
            }
            let mut key_frames = vec![first];
            for _ in 1..rng.random_range(4..=8) {
                let mut next = key_frames[key_frames.len() - 1].clone();
                next.frame += rng.random_range(1..5);
                for _ in 0..rng.random_range(1..=3) {
                    edit(rng, &mut next);
                }
                // Out of sight: an object no edge touches, now and then.
                next.visible = None;
                if rng.random_bool(0.3) {
                    let hidden = &next.nodes[next.nodes.len() - 1].name;
                    if !next
                        .edges
                        .iter()
                        .any(|e| &e.from == hidden || &e.to == hidden)
                    {
                        next.visible = Some(
                            next.nodes
                                .iter()
                                .filter(|n| &n.name != hidden)
                                .map(|n| n.name.clone())
                                .collect(),
                        );
                    }
                }
                key_frames.push(next);
            }
            let frame_count = key_frames[key_frames.len() - 1].frame + 1 + rng.random_range(0..3);
            let graphs = EpisodeGraphs { key_frames };
            if validate(&graphs, frame_count).is_ok() {
                return (graphs, frame_count);
            }
        }
    }

    /// The export read back by the hub's segmentation and scene-graph reader gives the same key
    /// frames, graphs and transitions, over many random episodes.
    #[test]
    fn exports_read_back_as_the_same_key_frames_and_transitions() {
        let mut rng = ChaCha8Rng::seed_from_u64(28);
        let dir = tempfile::tempdir().unwrap();
        for case in 0..150 {
            let (graphs, _) = random_graphs(&mut rng);
            let task = format!("episode_{case}");
            let export = export_task(&task, "kitchen", &graphs, |_| FrameSize::NOMINAL);
            let task_dir = dir.path().join(&task);
            std::fs::create_dir_all(task_dir.join("external_sensor1")).unwrap();
            std::fs::write(
                task_dir.join("scene_graph_0.json"),
                serde_json::to_vec(&export.scene_graph).unwrap(),
            )
            .unwrap();
            std::fs::write(
                task_dir.join(MARKED_KEY_FRAMES_FILE),
                serde_json::to_vec(&export.marked).unwrap(),
            )
            .unwrap();
            for k in &graphs.key_frames {
                std::fs::write(
                    task_dir.join(format!("external_sensor1/{:05}.png", k.frame)),
                    b"png",
                )
                .unwrap();
            }
            let segmented = segment_task(dir.path(), &task, &SegmentationParams::default())
                .unwrap_or_else(|e| panic!("case {case}: {e}"));
            let frames: Vec<String> = graphs
                .key_frames
                .iter()
                .map(|k| k.frame.to_string())
                .collect();
            assert_eq!(segmented.segmentation.key_frames, frames, "case {case}");
            let timeline = &segmented.key_frame_graphs;
            for k in &graphs.key_frames {
                let graph = timeline.scene_graph(&k.frame.to_string()).unwrap();
                assert_eq!(
                    &KeyFrameGraph::from_scene_graph(k.frame, &graph),
                    k,
                    "case {case}"
                );
            }
            for t in describe(&graphs) {
                let (from, to) = (t.from_frame.to_string(), t.to_frame.to_string());
                let visible: Vec<String> = pair_signatures(timeline, &from, &to, View::Visible)
                    .unwrap()
                    .into_iter()
                    .collect();
                let full: Vec<String> = pair_signatures(timeline, &from, &to, View::Full)
                    .unwrap()
                    .into_iter()
                    .collect();
                assert_eq!(visible, t.visible_signatures, "case {case}: {from} -> {to}");
                assert_eq!(full, t.full_signatures, "case {case}: {from} -> {to}");
                assert!(
                    !visible.is_empty(),
                    "case {case}: a valid transition shows a change"
                );
            }
        }
    }
}
