//! The answer readers: a model's reply as text (strict), as a Python/JSON value (strict and
//! ENACT's own rules), then the verifier on whatever ENACT's reading gives.
//!
//! The first byte picks the item's number of actions (1..=9); the rest is the reply.
#![no_main]

use enact_hub::core::dataset::Direction;
use enact_hub::core::verifier::answer::{
    Permutation, parse_answer_enact, parse_answer_strict, parse_answer_text_strict,
};
use enact_hub::core::verifier::{parse_python_json, verify};
use libfuzzer_sys::fuzz_target;

fn check_permutation(answer: &Permutation, actions: usize) {
    let mut labels = answer.labels().to_vec();
    labels.sort_unstable();
    let expected: Vec<u8> = (1..=actions as u8).collect();
    assert_eq!(
        labels, expected,
        "a strict reading must be a permutation of 1..={actions}"
    );
}

fuzz_target!(|data: &[u8]| {
    let Some((&first, rest)) = data.split_first() else {
        return;
    };
    let actions = usize::from(first % 9) + 1;
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    if let Ok(answer) = parse_answer_text_strict(text, actions) {
        check_permutation(&answer, actions);
    }
    let Ok(value) = parse_python_json(text) else {
        return;
    };
    if let Ok(answer) = parse_answer_strict(Some(&value), actions) {
        check_permutation(&answer, actions);
    }
    // ENACT's reading may hold anything (huge ints, strings, floats); the verifier must answer
    // every one of them without panicking.
    if let Some(parsed) = parse_answer_enact(&value, actions) {
        let truth = Permutation::new((1..=actions as u8).rev().collect()).unwrap();
        for direction in [Direction::Forward, Direction::Inverse] {
            let _ = verify(direction, &truth, &parsed, None);
        }
    }
});
