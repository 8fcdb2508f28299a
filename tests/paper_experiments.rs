//! The paper's appendix experiments on generated data: key frames on contact changes
//! (`generate --key-frames contact`), the three action encodings of a baseline's items
//! (`--actions`) and perturbed deltas (`--perturb-deltas`). A synthetic replay is written here;
//! the ENACT fixture replays are used too when present.

use std::collections::BTreeSet;
use std::path::Path;

use enact_hub::core::dataset::{QaItem, parse_release_line};
use enact_hub::core::pipeline::actions::{
    ActionEncoding, ActionRewrite, DeltaPerturbation, rewrite_item,
};
use enact_hub::core::pipeline::variant::items_from;
use enact_hub::core::pipeline::{GenerateOptions, KeyFrameTrigger, SegmentationParams, generate};
use enact_hub::core::scene_graph::{
    FrameSelection, SceneGraph, SceneGraphTimeline, TransientFilter, contact_relations,
};
use enact_hub::core::semantics::from_scene_graphs;
use enact_hub::core::verifier::{ParsedAnswer, Permutation, verify};
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde_json::json;
use sha2::{Digest, Sha256};

#[path = "support/fixtures.rs"]
mod fixtures;

const TASK: &str = "stocking_the_kitchen_1";

fn node(name: &str, states: &[&str]) -> serde_json::Value {
    let category = name.rsplit_once('_').map_or(name, |(c, _)| c);
    json!({
        "name": name,
        "category": category,
        "states": states,
        "visibility": {"external_sensor1": [500, 0, 0, 9, 9, 512, 512]},
    })
}

fn edge(from: &str, to: &str, states: &[&str]) -> serde_json::Value {
    json!({"from": from, "to": to, "states": states})
}

/// The world at frame n: 40 steady states; the robot's left gripper touches the apple from 20
/// (contact only); the fridge opens with the apple inside it from 40; the right gripper touches
/// the fridge from 55 (contact only); the stove turns on under the pot from 70. A contact
/// change flips one of ~45 features (cosine ≈ 0.99, no key frame by state); a state change
/// flips three (cosine < 0.98).
fn world(n: u64) -> serde_json::Value {
    let mut nodes: Vec<serde_json::Value> = (0..40)
        .map(|k| node(&format!("shelf{k}_{k}"), &["Clean"]))
        .collect();
    nodes.push(node("robot_r1", &[]));
    nodes.push(node("apple_1", &[]));
    nodes.push(node("fridge_2", if n >= 40 { &["Open"] } else { &[] }));
    nodes.push(node("stove_3", if n >= 70 { &["ToggledOn"] } else { &[] }));
    nodes.push(node("pot_4", &[]));
    let mut edges = Vec::new();
    if n >= 20 {
        edges.push(edge("robot_r1", "apple_1", &["LeftContact"]));
    }
    if n >= 40 {
        edges.push(edge("apple_1", "fridge_2", &["Inside", "Touching"]));
    }
    if n >= 55 {
        edges.push(edge("robot_r1", "fridge_2", &["RightContact"]));
    }
    if n >= 70 {
        edges.push(edge("pot_4", "stove_3", &["OnTop", "Touching"]));
    }
    json!({"type": "full", "nodes": nodes, "edges": edges})
}

/// Writes the replay: 90 full records and a 512×512 image of every frame.
fn write_replay(replayed: &Path) {
    let dir = replayed.join(TASK);
    std::fs::create_dir_all(dir.join("external_sensor1")).unwrap();
    let mut doc = serde_json::Map::new();
    for n in 0..90u64 {
        doc.insert(n.to_string(), world(n));
    }
    std::fs::write(
        dir.join("scene_graph_0.json"),
        serde_json::to_vec(&doc).unwrap(),
    )
    .unwrap();
    let image = image::RgbImage::from_pixel(512, 512, image::Rgb([60, 110, 90]));
    for n in 0..90u64 {
        image
            .save(dir.join("external_sensor1").join(format!("{n:05}.png")))
            .unwrap();
    }
}

fn options(key_frames: KeyFrameTrigger) -> GenerateOptions {
    GenerateOptions {
        num_to_sample: 4,
        step_lengths: vec![3, 4],
        segmentation: SegmentationParams {
            skip_first_frames: 2,
            warmup_frames: 3,
            cosine_threshold: 0.98,
            min_gap: 10,
            stability_frames: 2,
            key_frames,
        },
        ..GenerateOptions::default()
    }
}

fn sha256_of(path: &Path) -> String {
    hex::encode(Sha256::digest(std::fs::read(path).unwrap()))
}

fn items_of(release: &Path) -> Vec<QaItem> {
    std::fs::read_to_string(release.join("QA/enact_ordering.jsonl"))
        .unwrap()
        .lines()
        .map(|l| parse_release_line(l).unwrap())
        .collect()
}

fn graph(timeline: &SceneGraphTimeline, frame: &str) -> SceneGraph {
    timeline.scene_graph(frame).unwrap().into_owned()
}

/// A baseline release from the synthetic replay, generated once per test.
struct Generated {
    _root: tempfile::TempDir,
    replayed: std::path::PathBuf,
    state: std::path::PathBuf,
    contact: std::path::PathBuf,
}

fn generated() -> Generated {
    let root = tempfile::tempdir().unwrap();
    let replayed = root.path().join("replayed_activities");
    write_replay(&replayed);
    let state = root.path().join("state");
    let contact = root.path().join("contact");
    generate(&replayed, &state, &options(KeyFrameTrigger::State), &|_| {}).unwrap();
    generate(
        &replayed,
        &contact,
        &options(KeyFrameTrigger::Contact),
        &|_| {},
    )
    .unwrap();
    Generated {
        replayed,
        state,
        contact,
        _root: root,
    }
}

fn key_frames(release: &Path) -> Vec<String> {
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(release.join("generation_summary.json")).unwrap())
            .unwrap();
    summary["tasks"][0]["key_frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap().to_owned())
        .collect()
}

#[test]
fn contact_key_frames_on_a_replay_with_contact_changes() {
    let g = generated();
    let state = key_frames(&g.state);
    let contact = key_frames(&g.contact);
    assert_eq!(state, ["4", "42", "72"]);
    assert_eq!(contact, ["4", "22", "42", "57", "72"]);
    // Each key frame only the contact run has is at a contact change from the key frame
    // before it.
    let timeline = SceneGraphTimeline::load(
        &g.replayed.join(TASK).join("scene_graph_0.json"),
        FrameSelection::All,
    )
    .unwrap();
    for (i, frame) in contact.iter().enumerate().skip(1) {
        if state.contains(frame) {
            continue;
        }
        let (before, now) = (graph(&timeline, &contact[i - 1]), graph(&timeline, frame));
        assert_ne!(
            contact_relations(&before),
            contact_relations(&now),
            "key frame {frame}"
        );
    }
    // The contact run says so in its summary; the state run's summary is ENACT's.
    use enact_hub::core::pipeline::release::release_vocabulary;
    use enact_hub::core::scene_graph::StateVocabulary;
    assert_eq!(release_vocabulary(&g.contact), StateVocabulary::WithContact);
    assert_eq!(release_vocabulary(&g.state), StateVocabulary::Enact);
    // The contact run's actions and signatures describe contact changes; the state run's never.
    let contact_items = items_of(&g.contact);
    assert!(contact_items.iter().any(|i| {
        i.actions
            .iter()
            .any(|a| a.contains("using the left gripper to touch"))
    }));
    assert!(
        items_of(&g.state)
            .iter()
            .all(|i| i.actions.iter().all(|a| !a.contains("gripper to touch")))
    );
    let refs: Vec<&QaItem> = contact_items.iter().collect();
    let tables = from_scene_graphs(&g.contact.join("replayed_activities"), &refs);
    let json = serde_json::to_string(
        &tables
            .iter()
            .map(|t| t.as_ref().unwrap())
            .collect::<Vec<_>>(),
    )
    .unwrap();
    assert!(json.contains("LeftContact"), "contact signatures");
    let state_items = items_of(&g.state);
    let refs: Vec<&QaItem> = state_items.iter().collect();
    let tables = from_scene_graphs(&g.state.join("replayed_activities"), &refs);
    let json = serde_json::to_string(
        &tables
            .iter()
            .map(|t| t.as_ref().unwrap())
            .collect::<Vec<_>>(),
    )
    .unwrap();
    assert!(
        !json.contains("Contact"),
        "no contact signature in a state run"
    );
    // The state run writes what `generate` wrote before contact key frames existed (hashes
    // taken with the previous build on this replay and these options).
    assert_eq!(
        sha256_of(&g.state.join("QA/enact_ordering.jsonl")),
        STATE_QA_SHA256
    );
    assert_eq!(
        sha256_of(&g.state.join("generation_summary.json")),
        STATE_SUMMARY_SHA256
    );
}

/// `QA/enact_ordering.jsonl` and `generation_summary.json` of the state run, as written by
/// `enact-hub generate` before this change.
const STATE_QA_SHA256: &str = "5f45fd511317ebc002a4df8fcc2e6a92c5232fff00a864c78a5945ee2ff29e25";
const STATE_SUMMARY_SHA256: &str =
    "95c63ce364d741404f4090d6bef8f9260987451b507daedfe569a5b78610e728";

/// The rewrite `generate --items-from baseline` makes (the vocabulary is the baseline run's).
fn rewrite(
    baseline: &Path,
    encoding: ActionEncoding,
    perturbation: Option<DeltaPerturbation>,
) -> ActionRewrite {
    ActionRewrite {
        encoding,
        perturbation,
        vocabulary: enact_hub::core::pipeline::release::release_vocabulary(baseline),
    }
}

/// Answers to judge on both sides: every order of the labels up to six steps; beyond, the
/// truth, each adjacent swap of it and 300 seeded random orders. The two sides' signature
/// tables are asserted equal first, so this checks the judging, not the tables: the whole
/// 10! orders of the fixtures' long items took 85 s of the test suite and proved no more.
fn answers_to_judge(truth: &[u8]) -> Vec<Vec<u8>> {
    fn every(prefix: &mut Vec<u8>, n: usize, out: &mut Vec<Vec<u8>>) {
        if prefix.len() == n {
            out.push(prefix.clone());
            return;
        }
        for l in 1..=n as u8 {
            if !prefix.contains(&l) {
                prefix.push(l);
                every(prefix, n, out);
                prefix.pop();
            }
        }
    }
    let n = truth.len();
    let mut out = Vec::new();
    if n <= 6 {
        every(&mut Vec::new(), n, &mut out);
        return out;
    }
    out.push(truth.to_vec());
    for i in 0..n - 1 {
        let mut swapped = truth.to_vec();
        swapped.swap(i, i + 1);
        out.push(swapped);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(n as u64);
    for _ in 0..300 {
        let mut order = truth.to_vec();
        order.shuffle(&mut rng);
        out.push(order);
    }
    out
}

/// Asserts that the variant keeps the baseline's items and that every answer to every item is
/// judged the same on both (the variant imported with the baseline's scene graphs).
fn judged_alike(baseline: &Path, variant: &Path) {
    let (base, var) = (items_of(baseline), items_of(variant));
    assert_eq!(base.len(), var.len());
    let graphs = baseline.join("replayed_activities");
    let base_refs: Vec<&QaItem> = base.iter().collect();
    let var_refs: Vec<&QaItem> = var.iter().collect();
    let base_tables = from_scene_graphs(&graphs, &base_refs);
    let var_tables = from_scene_graphs(&graphs, &var_refs);
    for (((b, v), bt), vt) in base.iter().zip(&var).zip(&base_tables).zip(&var_tables) {
        assert_eq!(
            (&b.id, &b.key_frame_ids, &b.gt_answer, &b.images),
            (&v.id, &v.key_frame_ids, &v.gt_answer, &v.images)
        );
        let (bt, vt) = (bt.as_ref().unwrap(), vt.as_ref().unwrap());
        assert_eq!(bt, vt, "{}: same signatures", b.id);
        let gt = Permutation::new(b.gt_answer.clone()).unwrap();
        for answer in answers_to_judge(&b.gt_answer) {
            let answer = ParsedAnswer::from(&Permutation::new(answer).unwrap());
            assert_eq!(
                verify(b.direction, &gt, &answer, Some(bt)).unwrap(),
                verify(v.direction, &gt, &answer, Some(vt)).unwrap(),
                "{}",
                b.id
            );
        }
    }
}

#[test]
fn the_three_encodings_of_one_item_are_judged_alike() {
    let g = generated();
    let root = tempfile::tempdir().unwrap();
    let mut texts = Vec::new();
    for encoding in ActionEncoding::ALL {
        let out = root.path().join(encoding.as_str());
        let done = items_from(
            &g.replayed,
            &g.contact,
            &out,
            &rewrite(&g.contact, encoding, None),
        )
        .unwrap();
        judged_alike(&g.contact, &out);
        if encoding == ActionEncoding::Natural {
            // Natural is the baseline's own text.
            assert_eq!(done.actions_rewritten, 0);
            assert_eq!(
                sha256_of(&out.join("QA/enact_ordering.jsonl")),
                sha256_of(&g.contact.join("QA/enact_ordering.jsonl"))
            );
        } else {
            assert!(done.actions_rewritten > 0);
        }
        texts.push(items_of(&out)[0].actions.clone());
    }
    // One item, three encodings: its first item is forward 4 → 22 → 42 (L = 3 comes first).
    let item = &items_of(&g.contact)[0];
    println!("{}: {:?}", item.id, texts);
    let [natural, symbolic, emoji] = [&texts[0], &texts[1], &texts[2]];
    assert_eq!(natural, &item.actions);
    for ((n, s), e) in natural.iter().zip(symbolic).zip(emoji) {
        let count = |text: &str, sep: &str| text.split(sep).count();
        // One predicate per sentence: as many parts in each encoding.
        assert_eq!(count(n, ". "), count(s, "; "), "{n} / {s}");
        assert_eq!(count(s, "; "), count(e, "; "), "{s} / {e}");
    }
    // Every part reads as the encoding's grammar; every transition of this replay changes a
    // contact relation, which the contact run's encodings write too.
    let predicate =
        regex::Regex::new(r"^(add|remove)\([A-Za-z]+, [a-z0-9_]+(, [a-z0-9_]+)?\)$").unwrap();
    for text in symbolic {
        for part in text.split("; ") {
            assert!(predicate.is_match(part), "{part:?} in {text:?}");
        }
        assert!(
            text.contains("Contact, robot_r1") || text.contains("(Touching, "),
            "{text}"
        );
    }
    for text in emoji {
        for part in text.split("; ") {
            assert!(part.starts_with('➕') || part.starts_with('➖'), "{part:?}");
        }
        assert!(
            text.contains('👈') || text.contains('👉') || text.contains('🤝'),
            "{text}"
        );
    }
}

#[test]
fn perturbed_deltas_follow_the_rule_and_the_seed() {
    let g = generated();
    let root = tempfile::tempdir().unwrap();
    let base_qa = sha256_of(&g.contact.join("QA/enact_ordering.jsonl"));
    let run = |name: &str, p: f64, seed: u64| {
        let out = root.path().join(name);
        let perturbation = Some(DeltaPerturbation::new(p, seed).unwrap());
        let done = items_from(
            &g.replayed,
            &g.contact,
            &out,
            &rewrite(&g.contact, ActionEncoding::Natural, perturbation),
        )
        .unwrap();
        (out, done)
    };
    // P = 0: the baseline, byte for byte.
    let (zero, done) = run("p0", 0.0, 1);
    assert_eq!(sha256_of(&zero.join("QA/enact_ordering.jsonl")), base_qa);
    assert_eq!((done.actions_rewritten, done.predicates_perturbed), (0, 0));
    // P > 0: the same seed twice gives the same file, ground truth untouched.
    let (a, done_a) = run("a", 0.5, 7);
    let (b, _) = run("b", 0.5, 7);
    assert_eq!(
        sha256_of(&a.join("QA/enact_ordering.jsonl")),
        sha256_of(&b.join("QA/enact_ordering.jsonl"))
    );
    assert!(done_a.predicates_perturbed > 0);
    judged_alike(&g.contact, &a);
    // Another seed changes other predicates.
    let (c, _) = run("c", 0.5, 8);
    assert_ne!(
        sha256_of(&a.join("QA/enact_ordering.jsonl")),
        sha256_of(&c.join("QA/enact_ordering.jsonl"))
    );
    // An action text changes exactly where the rule perturbed its transition.
    let timeline = SceneGraphTimeline::load(
        &g.contact
            .join("replayed_activities")
            .join(TASK)
            .join("scene_graph_0.json"),
        FrameSelection::All,
    )
    .unwrap();
    let rule = rewrite(
        &g.contact,
        ActionEncoding::Natural,
        Some(DeltaPerturbation::new(0.5, 7).unwrap()),
    );
    for (base, varied) in items_of(&g.contact).iter().zip(items_of(&a)) {
        let done = rewrite_item(base, &timeline, &rule).unwrap();
        let labels = enact_hub::core::pipeline::actions::transition_labels(base);
        for (transition, changes) in done.changes.iter().enumerate() {
            let slot = labels[transition] - 1;
            assert_eq!(
                changes.is_empty(),
                base.actions[slot] == varied.actions[slot],
                "{} transition {transition}",
                base.id
            );
        }
    }
}

#[test]
fn fixture_items_in_every_encoding_are_judged_as_enact_judges_them() {
    let Some(dir) = fixtures::parity_dir() else {
        return;
    };
    let root = tempfile::tempdir().unwrap();
    // The fixture release is a baseline whose scene graphs are the full replays.
    for encoding in [ActionEncoding::Symbolic, ActionEncoding::Emoji] {
        let out = root.path().join(encoding.as_str());
        let done = items_from(
            &dir.join("replayed_activities"),
            &dir,
            &out,
            &rewrite(&dir, encoding, None),
        )
        .unwrap();
        assert_eq!(done.items, 96);
        judged_alike(&dir, &out);
    }
}

#[test]
fn fixture_replays_get_more_key_frames_with_contact() {
    let Some(dir) = fixtures::parity_dir() else {
        return;
    };
    let replayed = dir.join("replayed_activities");
    for task in enact_hub::core::pipeline::task_names(&replayed).unwrap() {
        let path = replayed.join(&task).join("scene_graph_0.json");
        let filtered =
            SceneGraphTimeline::load_with(&path, FrameSelection::All, TransientFilter::Enact)
                .unwrap();
        let state =
            enact_hub::core::pipeline::segment_key_frames(&filtered, &Default::default()).unwrap();
        let params = SegmentationParams {
            key_frames: KeyFrameTrigger::Contact,
            ..Default::default()
        };
        let contact = enact_hub::core::pipeline::segment_key_frames(&filtered, &params).unwrap();
        let ours: BTreeSet<&String> = state.key_frames.iter().collect();
        let new = contact
            .key_frames
            .iter()
            .enumerate()
            .filter(|(_, f)| !ours.contains(f))
            .count();
        println!(
            "{task}: {} key frames by state, {} with contact ({new} not in the state run)",
            state.key_frames.len(),
            contact.key_frames.len()
        );
        assert!(contact.key_frames.len() > state.key_frames.len(), "{task}");
    }
}
