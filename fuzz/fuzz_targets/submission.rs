//! The submission reader and scorer: a body (JSONL or a JSON array) against two small items,
//! one per direction. A body is either refused with problems that name a line, or scored with
//! one verdict per item.
#![no_main]

use std::sync::OnceLock;

use enact_hub::core::dataset::parse_release_line;
use enact_hub::core::scoring::ScoringTarget;
use enact_hub::core::semantics::{ItemSemantics, SignatureSource, from_action_text};
use enact_hub::core::submission::{SubmissionError, score_submission};
use libfuzzer_sys::fuzz_target;
use serde_json::json;

fn release_line(id: &str, kind: &str, question: &str, gt: &[u8]) -> String {
    json!({
        "id": id,
        "type": format!("{kind}_world_modeling_ordering_3_steps"),
        "task_name": "fuzz_task_1",
        "key_frame_ids": ["10", "20", "30"],
        "images": ["a.png", "b.png", "c.png"],
        "question": question,
        "options": [],
        "gt_answer": gt,
    })
    .to_string()
}

fn targets() -> &'static [ScoringTarget] {
    static TARGETS: OnceLock<Vec<ScoringTarget>> = OnceLock::new();
    TARGETS.get_or_init(|| {
        let inverse = release_line(
            "inv",
            "inverse",
            "## Shuffled Actions\n\
             [Action 1] The apple becomes on top of the table.\n\
             [Action 2] The robot r1 is using the left gripper to grasp the apple.\n",
            &[2, 1],
        );
        let forward = release_line(
            "fwd",
            "forward",
            "## Actions\n\
             [Action 1] The robot r1 is using the left gripper to grasp the apple.\n\
             [Action 2] The apple becomes on top of the table.\n",
            &[1, 2],
        );
        [inverse, forward]
            .iter()
            .map(|line| {
                let item = parse_release_line(line).expect("the fuzz items are well formed");
                let semantics = from_action_text(&item).map(|signatures| ItemSemantics {
                    source: SignatureSource::ActionText,
                    signatures,
                });
                ScoringTarget::from_item(&item, semantics).expect("a scoring target")
            })
            .collect()
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(body) = std::str::from_utf8(data) else {
        return;
    };
    let targets = targets();
    match score_submission(targets, body) {
        Ok(scored) => assert_eq!(scored.items.len(), targets.len(), "one verdict per item"),
        Err(SubmissionError::Rejected(problems)) => {
            assert!(!problems.is_empty(), "a refusal says why");
            for problem in &problems {
                assert!(problem.line >= 1, "problems name a line: {problem:?}");
            }
        }
        Err(SubmissionError::Dataset(e)) => panic!("the fuzz items are scorable: {e}"),
    }
});
