//! Attention checks without I/O: an item whose question carries an instruction that makes its
//! answer follow from what the annotator is shown, not from the scene, so that an annotator who
//! reads the page gets it right and one who clicks through does not.
//!
//! The item page lists the cards to place (the candidate images of a forward item, the
//! candidate actions of an inverse one) in label order: card 1, card 2, … card L−1. The
//! instruction says how to fill the L−1 slots from that list:
//! - [`Instruction::Keep`]: "keep the given order": card k in slot k, so the expected answer is
//!   `[1, 2, …, L−1]`;
//! - [`Instruction::Reverse`]: "put the frames (actions) in reverse order": the last listed card
//!   in slot 1, so the expected answer is `[L−1, …, 2, 1]`.
//!
//! An answer equal to the expected one passes; any other answer fails, and so does a skip or a
//! flag (the instruction can always be followed); an unfinished check is pending. Attention
//! checks are mixed into the queues as gold items are ([`crate::gold::mix`]) and, like gold
//! answers, never count in the Human row or the agreement report.

use std::collections::HashMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::annotation::OutcomeKind;
use crate::dataset::StepLength;

/// What an attention check's question tells the annotator to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Instruction {
    /// Keep the given order: card k in slot k.
    Keep,
    /// Put the cards in reverse order: the last listed card in slot 1.
    Reverse,
}

impl Instruction {
    pub const ALL: [Instruction; 2] = [Instruction::Keep, Instruction::Reverse];

    /// The stored name (`attention_items.instruction`).
    pub fn as_str(self) -> &'static str {
        match self {
            Instruction::Keep => "keep",
            Instruction::Reverse => "reverse",
        }
    }

    pub fn parse(text: &str) -> Result<Instruction, String> {
        Instruction::ALL
            .into_iter()
            .find(|i| i.as_str() == text)
            .ok_or_else(|| {
                format!("instruction {text:?}: give \"keep\" (the given order) or \"reverse\"")
            })
    }

    /// The answer that follows the instruction on an item of `step_length`: labels in slot
    /// order.
    pub fn expected(self, step_length: StepLength) -> Vec<u8> {
        let n = u8::try_from(step_length.actions()).unwrap_or(u8::MAX);
        match self {
            Instruction::Keep => (1..=n).collect(),
            Instruction::Reverse => (1..=n).rev().collect(),
        }
    }
}

/// Where one attention check of one annotator stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CheckResult {
    Passed,
    Failed,
    Pending,
}

/// Judges an attention check: `finished` is how the annotator finished it (`None`: not yet),
/// `answer` their labels in slot order when they answered.
pub fn judge(
    instruction: Instruction,
    step_length: StepLength,
    finished: Option<OutcomeKind>,
    answer: Option<&[u8]>,
) -> CheckResult {
    match (finished, answer) {
        (None, _) => CheckResult::Pending,
        (Some(OutcomeKind::Answered), Some(given))
            if given == instruction.expected(step_length).as_slice() =>
        {
            CheckResult::Passed
        }
        // Another answer, a skip or a flag: the instruction could have been followed.
        (Some(_), _) => CheckResult::Failed,
    }
}

/// One annotator's attention checks on a dataset, counted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, JsonSchema)]
pub struct AttentionTally {
    pub passed: u64,
    pub failed: u64,
    /// In the queue, not finished yet.
    pub pending: u64,
}

impl AttentionTally {
    pub fn add(&mut self, result: CheckResult) {
        match result {
            CheckResult::Passed => self.passed += 1,
            CheckResult::Failed => self.failed += 1,
            CheckResult::Pending => self.pending += 1,
        }
    }
}

/// Attention checks from a list file: one `ITEM_ID INSTRUCTION` per line (`keep` or
/// `reverse`); blank lines and lines starting with `#` are skipped. Refuses an unknown
/// instruction and a repeated id, naming the line, and an empty list.
pub fn parse_check_list(text: &str) -> Result<Vec<(String, Instruction)>, String> {
    let mut seen: HashMap<&str, usize> = HashMap::new();
    let mut checks = Vec::new();
    for (index, line) in text.lines().enumerate() {
        let line_no = index + 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut words = line.split_whitespace();
        let (Some(id), Some(instruction), None) = (words.next(), words.next(), words.next()) else {
            return Err(format!(
                "line {line_no}: expected an item id and an instruction (keep or reverse), \
                 e.g. \"kitchen_0001 reverse\""
            ));
        };
        let instruction =
            Instruction::parse(instruction).map_err(|e| format!("line {line_no}: {e}"))?;
        if let Some(first) = seen.insert(id, line_no) {
            return Err(format!(
                "line {line_no}: item '{id}' is listed already on line {first}"
            ));
        }
        checks.push((id.to_owned(), instruction));
    }
    if checks.is_empty() {
        return Err(
            "the list names no attention check (one `ITEM_ID keep|reverse` per line)".to_owned(),
        );
    }
    Ok(checks)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l(n: usize) -> StepLength {
        StepLength::new(n).unwrap()
    }

    #[test]
    fn the_expected_answer_follows_the_instruction_and_the_listed_cards() {
        assert_eq!(Instruction::Keep.expected(l(4)), vec![1, 2, 3]);
        assert_eq!(Instruction::Reverse.expected(l(4)), vec![3, 2, 1]);
        assert_eq!(Instruction::Reverse.expected(l(3)), vec![2, 1]);
    }

    #[test]
    fn answers_pass_or_fail_and_unfinished_checks_are_pending() {
        let answered = Some(OutcomeKind::Answered);
        assert_eq!(
            judge(Instruction::Reverse, l(4), answered, Some(&[3, 2, 1])),
            CheckResult::Passed
        );
        assert_eq!(
            judge(Instruction::Reverse, l(4), answered, Some(&[1, 2, 3])),
            CheckResult::Failed
        );
        assert_eq!(
            judge(Instruction::Keep, l(4), Some(OutcomeKind::Skipped), None),
            CheckResult::Failed
        );
        assert_eq!(
            judge(Instruction::Keep, l(4), None, None),
            CheckResult::Pending
        );
    }

    #[test]
    fn check_lists_name_the_line_of_each_problem() {
        assert_eq!(
            parse_check_list("# checks\na reverse\n\n b keep \n").unwrap(),
            vec![
                ("a".to_owned(), Instruction::Reverse),
                ("b".to_owned(), Instruction::Keep)
            ]
        );
        assert!(
            parse_check_list("a sideways")
                .unwrap_err()
                .starts_with("line 1:")
        );
        assert!(parse_check_list("a").unwrap_err().starts_with("line 1:"));
        assert_eq!(
            parse_check_list("a keep\na reverse").unwrap_err(),
            "line 2: item 'a' is listed already on line 1"
        );
        assert!(parse_check_list("\n# none\n").is_err());
    }
}
