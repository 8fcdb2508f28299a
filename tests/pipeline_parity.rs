//! Parity of the data pipeline with ENACT's own output on the fixture replays (set A):
//! key frames, segmentation traces, the KFTS graph and path counts, and generated items.

use std::collections::{BTreeMap, HashSet};
use std::path::Path;

use enact_hub::core::pipeline::{
    GenerateOptions, PathTable, TransitionGraph, generate, segment_task,
};
use enact_hub::core::scene_graph::{FrameSelection, SceneGraphTimeline, transition_signatures};
use serde_json::Value;

#[path = "support/fixtures.rs"]
mod fixtures;

fn read_json(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

fn strings(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_string())
        .collect()
}

#[test]
fn segmentation_and_kfts_match_enact() {
    let Some(dir) = fixtures::parity_dir() else {
        return;
    };
    let replayed = dir.join("replayed_activities");
    let key_frames = read_json(&dir.join("reference/key_frames.json"));
    let traces = read_json(&dir.join("reference/segmentation_trace.json"));
    let counts = read_json(&dir.join("reference/path_counts.json"));
    let tasks = key_frames.as_object().unwrap();
    assert_eq!(tasks.len(), 3);
    for (task, expected) in tasks {
        let segmented = segment_task(&replayed, task, &Default::default()).unwrap();
        let s = &segmented.segmentation;
        let trace = &traces[task];
        assert_eq!(
            s.num_frames as u64,
            trace["num_frames"].as_u64().unwrap(),
            "{task}"
        );
        assert_eq!(
            s.first_considered_frame,
            trace["first_considered_frame"].as_str().unwrap()
        );
        assert_eq!(
            s.key_frames[0],
            trace["initial_key_frame"].as_str().unwrap()
        );
        for (ours, theirs) in s
            .consecutive_cosines
            .iter()
            .zip(trace["consecutive_key_frame_cosine"].as_array().unwrap())
        {
            assert_eq!(
                ours.from_frame,
                theirs["from_frame"].as_str().unwrap(),
                "{task}"
            );
            assert_eq!(
                ours.to_frame,
                theirs["to_frame"].as_str().unwrap(),
                "{task}"
            );
            assert_eq!(
                ours.cosine,
                theirs["cosine"].as_f64().unwrap(),
                "{task} {}",
                ours.to_frame
            );
        }
        assert_eq!(s.key_frames, strings(expected), "{task}: key frames");
        println!("{task}: {} key frames match", s.key_frames.len());

        // KFTS graph over the key frames, on the raw graphs.
        let graph = TransitionGraph::build(&segmented.key_frame_graphs, &s.key_frames).unwrap();
        let reference = &counts[task];
        let mut ours: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for (i, frame) in graph.frames().iter().enumerate() {
            ours.insert(
                frame.clone(),
                graph
                    .successors(i)
                    .iter()
                    .map(|&j| graph.frames()[j as usize].clone())
                    .collect(),
            );
        }
        let theirs: BTreeMap<String, Vec<String>> = reference["valid_transitions"]
            .as_object()
            .unwrap()
            .iter()
            .map(|(k, v)| (k.clone(), strings(v)))
            .collect();
        assert_eq!(ours, theirs, "{task}: valid transitions");
        assert_eq!(
            graph.edge_count() as u64,
            reference["num_valid_transitions"].as_u64().unwrap()
        );
        for length in 3..=10 {
            let table = PathTable::count(&graph, length).unwrap();
            let key = length.to_string();
            assert_eq!(
                table.total(),
                reference["total_paths"][&key].as_u64().unwrap() as u128,
                "{task} L={length}"
            );
            let ending: Vec<u128> = reference["paths_ending_at"][&key]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_u64().unwrap() as u128)
                .collect();
            assert_eq!(
                table.paths_ending_at(),
                ending.as_slice(),
                "{task} L={length}"
            );
        }
        println!(
            "{task}: {} valid transitions and totals for L=3..10 match",
            graph.edge_count()
        );
    }
}

#[test]
fn generated_release_is_valid_and_keeps_signatures() {
    let Some(dir) = fixtures::parity_dir() else {
        return;
    };
    let replayed = dir.join("replayed_activities");
    let counts = read_json(&dir.join("reference/path_counts.json"));
    let out = tempfile::tempdir().unwrap();
    let options = GenerateOptions {
        num_to_sample: 2,
        ..GenerateOptions::default()
    };
    let started = std::time::Instant::now();
    let summary = generate(&replayed, out.path(), &options, &|_| {}).unwrap();
    println!(
        "generated {} items, {} images in {:?}",
        summary.items,
        summary.images,
        started.elapsed()
    );
    // As ENACT with --num-to-sample 2: 48 forward + 48 inverse items.
    assert_eq!((summary.forward_items, summary.inverse_items), (48, 48));

    let jsonl = std::fs::read_to_string(out.path().join("QA/enact_ordering.jsonl")).unwrap();
    let mut per_bucket: BTreeMap<(String, usize, String), usize> = BTreeMap::new();
    let mut originals: BTreeMap<String, SceneGraphTimeline> = BTreeMap::new();
    let mut written: BTreeMap<String, SceneGraphTimeline> = BTreeMap::new();
    let mut ids = HashSet::new();
    let mut lines = 0;
    for line in jsonl.lines() {
        lines += 1;
        let item = enact_hub::core::dataset::parse_release_line(line).unwrap();
        assert!(ids.insert(item.id.clone()), "duplicate id {}", item.id);
        let l = item.step_length.states();
        *per_bucket
            .entry((
                item.task_name.clone(),
                l,
                item.direction.as_str().to_string(),
            ))
            .or_default() += 1;
        for image in &item.images {
            let (w, h) = image::image_dimensions(out.path().join(image)).unwrap();
            assert_eq!((w, h), (512, 512), "{image}");
        }
        // The key frames form a path of ENACT's valid-transition graph.
        let successors = &counts[&item.task_name]["valid_transitions"];
        for pair in item.key_frame_ids.windows(2) {
            assert!(
                strings(&successors[&pair[0]]).contains(&pair[1]),
                "{}",
                item.id
            );
        }
        let original = originals.entry(item.task_name.clone()).or_insert_with(|| {
            SceneGraphTimeline::load(
                &replayed.join(&item.task_name).join("scene_graph_0.json"),
                FrameSelection::All,
            )
            .unwrap()
        });
        let ours = transition_signatures(original, &item.key_frame_ids).unwrap();
        let copy = written.entry(item.task_name.clone()).or_insert_with(|| {
            SceneGraphTimeline::load(
                &out.path()
                    .join("replayed_activities")
                    .join(&item.task_name)
                    .join("scene_graph_0.json"),
                FrameSelection::All,
            )
            .unwrap()
        });
        assert_eq!(
            transition_signatures(copy, &item.key_frame_ids).unwrap(),
            ours,
            "{}",
            item.id
        );
        // Every action line has 1 to 5 sentences.
        for action in &item.actions {
            assert!(
                (1..=5).contains(&action.matches('.').count()),
                "{}: {action}",
                item.id
            );
        }
        // ... and reads back as its transition's visible signature set C_i.
        for (j, sets) in ours.iter().enumerate() {
            let label = match item.direction {
                enact_hub::core::dataset::Direction::Forward => j,
                enact_hub::core::dataset::Direction::Inverse => usize::from(item.gt_answer[j]) - 1,
            };
            let read_back =
                enact_hub::core::scene_graph::parse_action(&item.actions[label]).unwrap();
            assert_eq!(read_back, sets.visible, "{} transition {j}", item.id);
        }
    }
    assert_eq!(lines, summary.items);
    for (task, reference) in counts.as_object().unwrap() {
        for l in 3..=10 {
            let total = reference["total_paths"][&l.to_string()].as_u64().unwrap() as usize;
            for direction in ["forward", "inverse"] {
                let cap = if direction == "inverse" {
                    25
                } else {
                    usize::MAX
                };
                let expected = options.num_to_sample.min(total).min(cap);
                let got = per_bucket
                    .get(&(task.clone(), l, direction.to_string()))
                    .copied()
                    .unwrap_or(0);
                assert_eq!(got, expected, "{task} L={l} {direction}");
            }
        }
        let segmented = out
            .path()
            .join("segmented_activities")
            .join(task)
            .join("segmented_scene_graph_0.json");
        let written = read_json(&segmented);
        let keys: Vec<String> = written.as_object().unwrap().keys().cloned().collect();
        assert_eq!(
            keys,
            strings(&read_json(&dir.join("reference/key_frames.json"))[task])
        );
        // ENACT's own file, compared as sets (its list order comes from Python set iteration).
        let theirs = read_json(
            &dir.join("segmented_activities")
                .join(task)
                .join("segmented_scene_graph_0.json"),
        );
        assert_eq!(
            canonical_records(&written),
            canonical_records(&theirs),
            "{task}"
        );
    }
    let summary_json = read_json(&out.path().join("generation_summary.json"));
    assert_eq!(summary_json["tasks"].as_array().unwrap().len(), 3);
}

/// A segmented scene graph with every list of records (and every `states` list) sorted.
fn canonical_records(doc: &Value) -> BTreeMap<String, BTreeMap<String, Vec<String>>> {
    fn entries(list: &Value) -> Vec<String> {
        let mut out: Vec<String> = list
            .as_array()
            .map(|a| a.as_slice())
            .unwrap_or_default()
            .iter()
            .map(|entry| {
                let mut entry = entry.as_object().unwrap().clone();
                if let Some(Value::Array(states)) = entry.get_mut("states") {
                    states.sort_by_key(|s| s.to_string());
                }
                entry.sort_keys();
                serde_json::to_string(&entry).unwrap()
            })
            .collect();
        out.sort();
        out
    }
    doc.as_object()
        .unwrap()
        .iter()
        .map(|(frame, record)| {
            let mut lists = BTreeMap::new();
            lists.insert("type".to_string(), vec![record["type"].to_string()]);
            for side in ["", "add", "remove", "update"] {
                let holder = if side.is_empty() {
                    record
                } else {
                    &record[side]
                };
                for kind in ["nodes", "edges"] {
                    if !holder[kind].is_null() {
                        lists.insert(format!("{side}/{kind}"), entries(&holder[kind]));
                    }
                }
            }
            (frame.clone(), lists)
        })
        .collect()
}
