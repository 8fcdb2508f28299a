//! Error analysis on ENACT's parity fixtures: the per-step sets it compares are exactly the
//! `correct_signatures` / `input_signatures` ENACT's own evaluator writes with
//! `--analyze-wrong-cases`, computed here from the scene graphs by the project's code, and the
//! component identities hold on every prediction file.

use std::collections::{BTreeSet, HashMap};
use std::fs;

use enact_core::dataset::{QaItem, parse_release_line};
use enact_core::error_analysis::{ErrorFigures, StructuralClass, analyse_strict, answer_steps};
use enact_core::scoring::ScoringTarget;
use enact_core::semantics;
use enact_core::verifier::{Permutation, python_text_lines, score_strict_predictions};
use serde_json::Value;

#[path = "../../../tests/support/fixtures.rs"]
mod fixtures;

fn targets(dir: &std::path::Path) -> Vec<ScoringTarget> {
    let text = fs::read_to_string(dir.join("QA/enact_ordering.jsonl")).unwrap();
    let items: Vec<QaItem> = text
        .lines()
        .map(|l| parse_release_line(l).unwrap())
        .collect();
    let refs: Vec<&QaItem> = items.iter().collect();
    semantics::for_items(Some(&dir.join("replayed_activities")), &refs)
        .into_iter()
        .zip(&items)
        .map(|(s, item)| ScoringTarget::from_item(item, s.unwrap()).unwrap())
        .collect()
}

fn as_set(v: &Value) -> BTreeSet<String> {
    v.as_array()
        .map(|a| a.iter().map(|s| s.as_str().unwrap().to_owned()).collect())
        .unwrap_or_default()
}

#[test]
fn step_sets_are_the_ones_enact_writes() {
    let Some(dir) = fixtures::parity_dir() else {
        return;
    };
    let targets = targets(&dir);
    let by_id: HashMap<&str, &ScoringTarget> = targets.iter().map(|t| (t.id.as_str(), t)).collect();
    let mut compared_steps = 0;
    let mut compared_forward_off_chain = 0;
    for entry in fs::read_dir(dir.join("reference/eval_analyze/signatures")).unwrap() {
        let path = entry.unwrap().path();
        for line in fs::read_to_string(&path).unwrap().lines() {
            let record: Value = serde_json::from_str(line).unwrap();
            let Some(target) = by_id.get(record["id"].as_str().unwrap_or_default()) else {
                continue;
            };
            // Only records that carry the dataset's own truth, answered by a permutation of
            // the right length (what the analysis takes in).
            let gt: Option<Vec<u8>> = serde_json::from_value(record["gt_answer"].clone()).ok();
            let frames: Option<Vec<String>> =
                serde_json::from_value(record["key_frame_ids"].clone()).ok();
            if gt.as_deref() != Some(target.ground_truth.labels())
                || frames.as_ref().map(Vec::len) != Some(target.ground_truth.len() + 1)
                || record["equal_length"] != Value::Bool(true)
            {
                continue;
            }
            let Some(answer) = serde_json::from_value::<Vec<u8>>(record["parsed_answer"].clone())
                .ok()
                .and_then(|labels| Permutation::new(labels).ok())
                .filter(|p| p.len() == target.ground_truth.len())
            else {
                continue;
            };
            let table = &target.semantics.as_ref().expect("scene graphs").signatures;
            let steps = answer_steps(target.direction, &target.ground_truth, &answer, table)
                .unwrap_or_else(|e| panic!("{}: {} {:?}: {e}", path.display(), target.id, answer));
            let correct = record["correct_signatures"].as_array().unwrap();
            let input = record["input_signatures"].as_array().unwrap();
            assert_eq!(steps.len(), correct.len(), "{}", target.id);
            for (k, step) in steps.iter().enumerate() {
                let ours = |cs: &[enact_core::error_analysis::Component]| {
                    cs.iter().map(|c| c.to_string()).collect::<BTreeSet<_>>()
                };
                assert_eq!(
                    ours(&step.truth),
                    as_set(&correct[k]),
                    "{} step {k} truth",
                    target.id
                );
                assert_eq!(
                    ours(&step.predicted),
                    as_set(&input[k]),
                    "{} {}: step {k} predicted ({answer:?})",
                    path.display(),
                    target.id
                );
                compared_steps += 1;
            }
            if target.direction == enact_core::verifier::Direction::Forward
                && answer.labels() != target.ground_truth.labels()
            {
                compared_forward_off_chain += 1;
            }
        }
    }
    // The fixtures hold hundreds of such records; make sure they were not all skipped.
    assert!(
        compared_steps > 1000,
        "only {compared_steps} steps compared"
    );
    assert!(
        compared_forward_off_chain > 50,
        "{compared_forward_off_chain}"
    );
}

fn check_identities(name: &str, f: &ErrorFigures) {
    let count = |c| f.structural_count(c);
    let paired = count(StructuralClass::PolarityInversion)
        + count(StructuralClass::PredicateSubstitution)
        + count(StructuralClass::EntitySubstitution);
    assert_eq!(
        f.components.matched + paired + count(StructuralClass::Omission),
        f.components.truth,
        "{name}: truth components"
    );
    assert_eq!(
        f.components.matched + paired + count(StructuralClass::Hallucination),
        f.components.predicted,
        "{name}: predicted components"
    );
    assert_eq!(
        f.errors,
        StructuralClass::ALL
            .iter()
            .map(|&c| count(c))
            .sum::<usize>()
    );
}

#[test]
fn identities_hold_on_every_prediction_file() {
    let Some(dir) = fixtures::parity_dir() else {
        return;
    };
    let targets = targets(&dir);
    let items: Vec<_> = targets.iter().map(ScoringTarget::strict_item).collect();
    let mut files = 0;
    for entry in fs::read_dir(dir.join("predictions")).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if !name.starts_with("enact_ordering_") {
            continue;
        }
        let text = fs::read_to_string(&path).unwrap();
        let scoring = score_strict_predictions(&items, python_text_lines(&text)).unwrap();
        let analysis = analyse_strict(&items, &scoring);
        check_identities(&name, &analysis.overall);
        let forward = &analysis.by_direction.forward;
        let inverse = &analysis.by_direction.inverse;
        check_identities(&name, forward);
        check_identities(&name, inverse);
        assert_eq!(
            forward.analysed_answers + inverse.analysed_answers,
            analysis.overall.analysed_answers
        );
        let o = &analysis.overall;
        assert_eq!(
            o.analysed_answers
                + o.excluded_unequal_length
                + o.excluded_unreadable
                + o.excluded_missing
                + o.excluded_without_signatures,
            targets.len(),
            "{name}: every dataset item is analysed or excluded once"
        );
        if name == "enact_ordering_perfect.jsonl" {
            assert_eq!(o.analysed_answers, 96);
            assert_eq!(o.errors, 0);
            assert_eq!(o.accepted_incomplete.accepted_answers, 96);
            assert_eq!(o.accepted_incomplete.incomplete_answers, 0);
        }
        if name == "enact_ordering_random.jsonl" {
            assert!(o.errors > 100, "random answers make errors: {}", o.errors);
        }
        files += 1;
    }
    assert!(files >= 10, "{files} prediction files");
}
