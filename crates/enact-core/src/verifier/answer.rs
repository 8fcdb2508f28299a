//! Answers: the benchmark's item vocabulary (direction, step length, permutation) and the two
//! ways of reading a model's answer, ENACT's lenient `_parse_answer_string` and our strict one.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::verifier::pyint::PyInt;
use crate::verifier::pyjson::{PY_INT_MAX_STR_DIGITS, PyValue, small_labels};
use crate::verifier::unicode::{is_py_space, py_digit_value};

pub use crate::dataset::{Direction, StepLength};

/// ENACT quirk: the verifier ENACT runs for a record's `type` string is decided by substring,
/// `'inverse' in type.lower()`; everything else, including an empty type or one naming neither
/// direction, goes to the forward verifier.
pub fn enact_verifier_direction(task_type: &str) -> Direction {
    if task_type.to_lowercase().contains("inverse") {
        Direction::Inverse
    } else {
        Direction::Forward
    }
}

/// ENACT quirk: the report group of a `type` string checks `'forward'` first, then `'inverse'`;
/// a type naming neither (`None` here) is counted only in the overall group.
pub fn enact_report_group(task_type: &str) -> Option<Direction> {
    let lower = task_type.to_lowercase();
    if lower.contains("forward") {
        Some(Direction::Forward)
    } else if lower.contains("inverse") {
        Some(Direction::Inverse)
    } else {
        None
    }
}

/// An ordering of the labels 1..=n, each exactly once: a ground truth, or a strictly read answer.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(try_from = "Vec<u8>", into = "Vec<u8>")]
pub struct Permutation(Vec<u8>);

/// Why a label list is not a permutation of 1..=n.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PermutationError {
    #[error("empty list")]
    Empty,
    #[error("label {label} out of range 1..{max}")]
    OutOfRange { label: String, max: usize },
    #[error("label {label} repeated")]
    Repeated { label: u8 },
}

impl Permutation {
    /// Accepts `labels` if it holds each of 1..=labels.len() exactly once.
    pub fn new(labels: Vec<u8>) -> Result<Permutation, PermutationError> {
        if labels.is_empty() {
            return Err(PermutationError::Empty);
        }
        let max = labels.len();
        let mut seen = vec![false; max + 1];
        for &label in &labels {
            let index = usize::from(label);
            if index == 0 || index > max {
                return Err(PermutationError::OutOfRange {
                    label: label.to_string(),
                    max,
                });
            }
            if seen[index] {
                return Err(PermutationError::Repeated { label });
            }
            seen[index] = true;
        }
        Ok(Permutation(labels))
    }

    pub fn labels(&self) -> &[u8] {
        &self.0
    }

    pub fn len(&self) -> usize {
        self.0.len()
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// L = number of labels + 1, if that is a valid step length.
    pub fn step_length(&self) -> Option<StepLength> {
        StepLength::new(self.0.len() + 1)
    }
}

impl TryFrom<Vec<u8>> for Permutation {
    type Error = PermutationError;
    fn try_from(labels: Vec<u8>) -> Result<Self, Self::Error> {
        Permutation::new(labels)
    }
}

impl From<Permutation> for Vec<u8> {
    fn from(p: Permutation) -> Vec<u8> {
        p.0
    }
}

impl fmt::Display for Permutation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("[")?;
        for (i, label) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{label}")?;
        }
        f.write_str("]")
    }
}

/// An answer as ENACT's parser hands it to the verifier: any list, unvalidated. It can hold 0,
/// negative and huge integers, duplicates, and (from a raw JSON list) floats, strings, anything.
#[derive(Debug, Clone)]
pub struct ParsedAnswer {
    labels: Vec<PyValue>,
    /// The same labels as machine integers, when they all are small ints (the common case),
    /// so that verification need not touch Python values.
    small: Option<Vec<i64>>,
}

impl ParsedAnswer {
    pub fn new(labels: Vec<PyValue>) -> ParsedAnswer {
        let small = small_labels(&labels);
        ParsedAnswer { labels, small }
    }

    pub fn labels(&self) -> &[PyValue] {
        &self.labels
    }

    pub(crate) fn small_labels(&self) -> Option<&[i64]> {
        self.small.as_deref()
    }

    /// The list as ENACT writes it (`model_answer`).
    pub fn to_json(&self) -> String {
        PyValue::List(self.labels.clone()).to_json(false)
    }
}

impl From<&Permutation> for ParsedAnswer {
    fn from(p: &Permutation) -> ParsedAnswer {
        ParsedAnswer::new(
            p.labels()
                .iter()
                .map(|&l| PyValue::Int(PyInt::Small(i64::from(l))))
                .collect(),
        )
    }
}

/// ENACT's `_parse_answer_string(answer, gt_len)`, rule for rule. `None` is ENACT's parse
/// failure (the item is skipped as `failed_to_parse_answer`).
///
/// 1. A JSON list passes through untouched. 2. Anything falsy or not a string fails.
/// 3. The last `\[[\d\s,]+\]` match is read as a Python literal; a list longer than `gt_len`
///    keeps its last `gt_len` items, then it is re-based so its minimum is 1.
/// 4. Otherwise every run of digits in the whole string, unmodified.
pub fn parse_answer_enact(answer: &PyValue, gt_len: usize) -> Option<ParsedAnswer> {
    if let PyValue::List(items) = answer {
        return Some(ParsedAnswer::new(items.clone()));
    }
    let text = match answer {
        PyValue::Str(s) if !s.is_empty() => s.as_str(),
        _ => return None,
    };
    if let Some(inner) = last_enact_bracket_match(text)
        && let Some(mut labels) = enact_literal_int_list(inner)
    {
        if labels.len() > gt_len {
            labels.drain(..labels.len() - gt_len);
        }
        if let Some(rebased) = enact_rebase(labels) {
            return Some(ParsedAnswer::new(
                rebased.into_iter().map(PyValue::Int).collect(),
            ));
        }
    }
    enact_digit_fallback(text)
        .map(|labels| ParsedAnswer::new(labels.into_iter().map(PyValue::Int).collect()))
}

/// The inside of the last non-overlapping match of `\[[\d\s,]+\]` (Python 3.11 classes).
fn last_enact_bracket_match(text: &str) -> Option<&str> {
    let in_class = |c: char| c == ',' || is_py_space(c) || py_digit_value(c).is_some();
    let mut last = None;
    let mut rest_start = 0;
    while let Some(offset) = text[rest_start..].find('[') {
        let open = rest_start + offset;
        let inner_start = open + 1;
        let inner_len: usize = text[inner_start..]
            .chars()
            .take_while(|&c| in_class(c))
            .map(char::len_utf8)
            .sum();
        let close = inner_start + inner_len;
        if inner_len > 0 && text[close..].starts_with(']') {
            last = Some(&text[inner_start..close]);
            rest_start = close + 1;
        } else {
            rest_start = inner_start;
        }
    }
    last
}

/// ENACT quirk: `ast.literal_eval` on the bracket text. It only succeeds for a Python list
/// display of plain ASCII integer literals: separators `,` with optional trailing comma,
/// whitespace limited to what Python's tokenizer skips (space, tab, form feed, newlines), no
/// leading zeros (`007`; `000` is fine), no non-zero literal over 4300 digits. `[1,,2]`, `[,]`,
/// `[1 2]`, full-width digits and exotic spaces are syntax errors (→ `None`, then the fallback).
fn enact_literal_int_list(inner: &str) -> Option<Vec<PyInt>> {
    let mut labels = Vec::new();
    let mut expecting_value = true;
    let mut chars = inner.chars().peekable();
    while let Some(&c) = chars.peek() {
        match c {
            ' ' | '\t' | '\u{c}' | '\n' | '\r' => {
                chars.next();
            }
            ',' if !expecting_value => {
                expecting_value = true;
                chars.next();
            }
            '0'..='9' if expecting_value => {
                let mut digits = Vec::new();
                while let Some(&d) = chars.peek() {
                    match d.to_digit(10).filter(|_| d.is_ascii_digit()) {
                        Some(v) => {
                            digits.push(v as u8);
                            chars.next();
                        }
                        None => break,
                    }
                }
                let all_zero = digits.iter().all(|&d| d == 0);
                if digits.len() > 1 && digits[0] == 0 && !all_zero {
                    return None;
                }
                if !all_zero && digits.len() > PY_INT_MAX_STR_DIGITS {
                    return None;
                }
                labels.push(PyInt::from_decimal_digits(&digits));
                expecting_value = false;
            }
            _ => return None,
        }
    }
    // A trailing comma is allowed, a lone comma is not: `expecting_value` after the last value
    // only matters if there was no value at all (`[,]` failed above; `[ ]` gives []).
    Some(labels)
}

/// ENACT quirk: re-base a bracket-path list so that its minimum is 1 (`[0,1]` → `[1,2]`,
/// `[2,3]` → `[1,2]`). An empty list makes Python's `min()` raise → `None` (fallback).
fn enact_rebase(labels: Vec<PyInt>) -> Option<Vec<PyInt>> {
    let mut min = labels.iter().min()?.clone();
    let mut labels = labels;
    if min.is_zero() {
        labels = labels.iter().map(|x| x.add(&PyInt::ONE)).collect();
        min = PyInt::ONE;
    }
    if min > PyInt::ONE {
        let delta = min.sub(&PyInt::ONE);
        labels = labels.iter().map(|x| x.sub(&delta)).collect();
    }
    Some(labels)
}

/// ENACT quirk: the fallback `[int(x) for x in re.findall(r'\d+', s)]` over the whole string:
/// Unicode digits (`int('２')` is 2), no truncation, no re-basing. `None` when there is no digit,
/// or when a run is over Python's 4300-digit limit (`int()` raises, ENACT returns None).
fn enact_digit_fallback(text: &str) -> Option<Vec<PyInt>> {
    let mut labels = Vec::new();
    let mut run: Vec<u8> = Vec::new();
    let flush = |run: &mut Vec<u8>, labels: &mut Vec<PyInt>| -> bool {
        if run.is_empty() {
            return true;
        }
        if run.len() > PY_INT_MAX_STR_DIGITS {
            return false;
        }
        labels.push(PyInt::from_decimal_digits(run));
        run.clear();
        true
    };
    for c in text.chars() {
        match py_digit_value(c) {
            Some(v) => run.push(v),
            None => {
                if !flush(&mut run, &mut labels) {
                    return None;
                }
            }
        }
    }
    if !flush(&mut run, &mut labels) {
        return None;
    }
    (!labels.is_empty()).then_some(labels)
}

/// Why the strict reader refused an answer. The item then scores TA 0 / PA 0 with this reason.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, thiserror::Error)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum StrictParseFailure {
    #[error("no answer given")]
    Missing,
    #[error("answer is a {found}, expected a string or a list of integers")]
    NotText { found: &'static str },
    #[error("no list found")]
    NoList,
    #[error("label {item} is not an integer")]
    NotAnInteger { item: String },
    #[error("wrong length {found}, expected {expected}")]
    WrongLength { found: usize, expected: usize },
    #[error("label {label} out of range 1..{max}")]
    OutOfRange { label: String, max: usize },
    #[error("label {label} repeated")]
    Repeated { label: u8 },
}

/// Strict reading of an answer value for an item with `actions` (= L-1) labels: a string (see
/// [`parse_answer_text_strict`]) or a JSON list of integers, which must be a permutation of
/// 1..=actions.
pub fn parse_answer_strict(
    answer: Option<&PyValue>,
    actions: usize,
) -> Result<Permutation, StrictParseFailure> {
    match answer {
        None | Some(PyValue::None) => Err(StrictParseFailure::Missing),
        Some(PyValue::Str(text)) => parse_answer_text_strict(text, actions),
        Some(PyValue::List(items)) => {
            let mut labels = Vec::with_capacity(items.len());
            for item in items {
                match item {
                    PyValue::Int(i) => labels.push(i.clone()),
                    other => {
                        return Err(StrictParseFailure::NotAnInteger {
                            item: other.to_json(false),
                        });
                    }
                }
            }
            validate_strict(&labels, actions)
        }
        Some(other) => Err(StrictParseFailure::NotText {
            found: other.type_name(),
        }),
    }
}

/// Strict reading of an answer text. Prose around the list, code fences and `<think>…</think>`
/// blocks are tolerated (lists inside a think block are ignored; text before a closing
/// `</think>` without an opening tag is thinking too; an unclosed `<think>` hides the rest).
/// The last bracketed list of integers wins; an answer that is nothing but integers separated
/// by commas or whitespace is read as a list too. The list must hold exactly `actions` distinct
/// labels in 1..=actions.
pub fn parse_answer_text_strict(
    text: &str,
    actions: usize,
) -> Result<Permutation, StrictParseFailure> {
    let visible = strip_think_blocks(text);
    let labels = last_integer_list(&visible)
        .or_else(|| bare_integer_list(&visible))
        .ok_or(StrictParseFailure::NoList)?;
    validate_strict(&labels, actions)
}

fn validate_strict(labels: &[PyInt], actions: usize) -> Result<Permutation, StrictParseFailure> {
    if labels.len() != actions {
        return Err(StrictParseFailure::WrongLength {
            found: labels.len(),
            expected: actions,
        });
    }
    let mut small = Vec::with_capacity(labels.len());
    for label in labels {
        match label.to_i64() {
            Some(v) if v >= 1 && (v as u64) <= actions as u64 && v <= i64::from(u8::MAX) => {
                small.push(v as u8)
            }
            _ => {
                return Err(StrictParseFailure::OutOfRange {
                    label: label.to_string(),
                    max: actions,
                });
            }
        }
    }
    Permutation::new(small).map_err(|e| match e {
        PermutationError::Repeated { label } => StrictParseFailure::Repeated { label },
        PermutationError::OutOfRange { label, max } => {
            StrictParseFailure::OutOfRange { label, max }
        }
        PermutationError::Empty => StrictParseFailure::WrongLength {
            found: 0,
            expected: actions,
        },
    })
}

/// The text outside `<think>…</think>` blocks (tags matched case-insensitively).
fn strip_think_blocks(text: &str) -> String {
    // ASCII lowercasing keeps byte offsets, so positions found in `lower` index `text`.
    let lower = text.to_ascii_lowercase();
    let (open_tag, close_tag) = ("<think>", "</think>");
    let mut visible = String::new();
    let mut pos = 0;
    loop {
        let open = lower[pos..].find(open_tag).map(|i| pos + i);
        let close = lower[pos..].find(close_tag).map(|i| pos + i);
        match (open, close) {
            (_, Some(c)) if open.is_none_or(|o| c < o) => {
                // A closing tag without an opening one: everything so far was thinking.
                visible.clear();
                pos = c + close_tag.len();
            }
            (Some(o), _) => {
                visible.push_str(&text[pos..o]);
                match lower[o..].find(close_tag) {
                    Some(c) => pos = o + c + close_tag.len(),
                    None => return visible,
                }
            }
            _ => {
                visible.push_str(&text[pos..]);
                return visible;
            }
        }
    }
}

/// One integer token: optional sign, then decimal digits (any script).
fn integer_token(token: &str) -> Option<PyInt> {
    let (negative, digits) = match token.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, token.strip_prefix('+').unwrap_or(token)),
    };
    if digits.is_empty() {
        return None;
    }
    let values: Option<Vec<u8>> = digits.chars().map(py_digit_value).collect();
    let value = PyInt::from_decimal_digits(&values?);
    Some(if negative { value.negate() } else { value })
}

/// Labels of a comma-separated list body (`1, 2, 3` or `1, 2, 3,`); `None` if any item is not
/// an integer. An empty body is an empty list.
fn integer_items(body: &str) -> Option<Vec<PyInt>> {
    let trimmed = body.trim();
    if trimmed.is_empty() {
        return Some(Vec::new());
    }
    let trimmed = trimmed.strip_suffix(',').unwrap_or(trimmed);
    trimmed
        .split(',')
        .map(|item| integer_token(item.trim()))
        .collect()
}

/// The last `[...]` (without nested brackets) whose body is a list of integers.
fn last_integer_list(text: &str) -> Option<Vec<PyInt>> {
    let mut found = None;
    let mut pos = 0;
    while let Some(offset) = text[pos..].find('[') {
        let open = pos + offset;
        let body_start = open + 1;
        let Some(close_offset) = text[body_start..].find(']') else {
            break;
        };
        let close = body_start + close_offset;
        let body = &text[body_start..close];
        if let Some(nested) = body.rfind('[') {
            // Restart from the innermost opening bracket.
            pos = body_start + nested;
            continue;
        }
        if let Some(labels) = integer_items(body) {
            found = Some(labels);
        }
        pos = close + 1;
    }
    found
}

/// An answer that is only integers separated by commas/whitespace, possibly inside a code fence.
fn bare_integer_list(text: &str) -> Option<Vec<PyInt>> {
    let mut body = text.trim();
    if let Some(rest) = body.strip_prefix("```") {
        // Drop the fence and an optional language tag on its line.
        let rest = rest.trim_start_matches(|c: char| c.is_ascii_alphanumeric());
        body = rest.strip_suffix("```").unwrap_or(rest).trim();
    }
    if body.is_empty() {
        return None;
    }
    body.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|token| !token.is_empty())
        .map(integer_token)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::verifier::pyjson::parse_python_json;

    fn json(text: &str) -> PyValue {
        parse_python_json(text).expect("test JSON")
    }

    /// ENACT's parse of a string answer, written back as ENACT's JSON.
    fn enact(answer: &str, gt_len: usize) -> Option<String> {
        parse_answer_enact(&PyValue::Str(answer.to_owned()), gt_len).map(|a| a.to_json())
    }

    #[test]
    fn enact_dispatch_and_report_groups() {
        assert_eq!(
            enact_verifier_direction("INVERSE_World_Modeling_ordering_3_steps"),
            Direction::Inverse
        );
        assert_eq!(enact_verifier_direction(""), Direction::Forward);
        assert_eq!(
            enact_verifier_direction("ordering_4_steps"),
            Direction::Forward
        );
        assert_eq!(
            enact_report_group("forward_dynamics_ordering_4_steps"),
            Some(Direction::Forward)
        );
        assert_eq!(enact_report_group("ordering_4_steps"), None);
        // Dispatch looks for 'inverse' first, grouping for 'forward' first.
        assert_eq!(
            enact_verifier_direction("forward_inverse"),
            Direction::Inverse
        );
        assert_eq!(
            enact_report_group("forward_inverse"),
            Some(Direction::Forward)
        );
    }

    #[test]
    fn enact_prose_cases() {
        // Last list wins, even when an earlier one is the right answer.
        assert_eq!(
            enact("At first I thought [1, 2], but the answer is [2, 1].", 2).as_deref(),
            Some("[2, 1]")
        );
        assert_eq!(
            enact("The answer is [1, 2]. (Initially I considered [2, 1].)", 2).as_deref(),
            Some("[2, 1]")
        );
        // Shifted lists are re-based.
        assert_eq!(enact("Final answer: [3, 4]", 2).as_deref(), Some("[1, 2]"));
        assert_eq!(
            enact("Final answer: [5, 4, 3, 8, 6, 7]", 6).as_deref(),
            Some("[3, 2, 1, 6, 4, 5]")
        );
        assert_eq!(
            enact("```python\n[1, 2]\n```", 2).as_deref(),
            Some("[1, 2]")
        );
        // Longer lists keep their last n items (then re-base).
        assert_eq!(enact("So: [1, 1, 2]", 2).as_deref(), Some("[1, 2]"));
        assert_eq!(
            enact("So: [4, 5, 3, 1, 4, 2, 6]", 6).as_deref(),
            Some("[5, 3, 1, 4, 2, 6]")
        );
        assert_eq!(enact("[1, 2,]", 2).as_deref(), Some("[1, 2]"));
        assert_eq!(
            enact("[\n  1,\n  3,\n  2\n]", 3).as_deref(),
            Some("[1, 3, 2]")
        );
        // '[3,,2, 1]' is a SyntaxError: the fallback takes every digit of the whole text.
        assert_eq!(
            enact("I considered [2, 3, 1]. My answer: [3,,2, 1]", 3).as_deref(),
            Some("[2, 3, 1, 3, 2, 1]")
        );
        assert_eq!(
            enact("Next State 2 -> Next State 1 -> Next State 3", 3).as_deref(),
            Some("[2, 1, 3]")
        );
        // Full-width digits match \d but are a SyntaxError in Python source: fallback, int('２').
        assert_eq!(enact("答案：[２, ３, １]", 3).as_deref(), Some("[2, 3, 1]"));
        // '-' is not in the class: fallback over all digits, the sign is lost.
        assert_eq!(enact("[-1, 3, 1, 2]", 3).as_deref(), Some("[1, 3, 1, 2]"));
        assert_eq!(
            enact("Step 1 then step 2 ... the order is [2, 1, 3]", 3).as_deref(),
            Some("[2, 1, 3]")
        );
    }

    #[test]
    fn enact_out_of_range_and_zero_based_cases() {
        assert_eq!(
            enact("[1, 3, 4, 2, 8, 5]", 6).as_deref(),
            Some("[1, 3, 4, 2, 8, 5]")
        );
        assert_eq!(
            enact("[4, 6, 2, 3, 1, 0, 7]", 7).as_deref(),
            Some("[5, 7, 3, 4, 2, 1, 8]")
        );
        assert_eq!(
            enact("Order: 3 4 6 5 2 11", 6).as_deref(),
            Some("[3, 4, 6, 5, 2, 11]")
        );
        assert_eq!(
            enact("[2, 5, 3, 4, 1, 100000000000000000000]", 6).as_deref(),
            Some("[2, 5, 3, 4, 1, 100000000000000000000]")
        );
        // Zero-based via brackets is re-based; via the fallback it is not.
        assert_eq!(enact("[0, 2, 1]", 3).as_deref(), Some("[1, 3, 2]"));
        assert_eq!(enact("0 2 1", 3).as_deref(), Some("[0, 2, 1]"));
        // Huge minimum: re-based with big-integer arithmetic.
        assert_eq!(
            enact("[100000000000000000001, 100000000000000000000]", 2).as_deref(),
            Some("[2, 1]")
        );
    }

    #[test]
    fn enact_raw_lists_pass_through() {
        let parsed = |text: &str| parse_answer_enact(&json(text), 3).map(|a| a.to_json());
        assert_eq!(parsed("[0, 1, 2]").as_deref(), Some("[0, 1, 2]"));
        assert_eq!(
            parsed("[-1, 2, 3, 4, 5]").as_deref(),
            Some("[-1, 2, 3, 4, 5]")
        );
        assert_eq!(parsed("[1.0, 2.0]").as_deref(), Some("[1.0, 2.0]"));
        assert_eq!(parsed("[\"2\", \"1\"]").as_deref(), Some("[\"2\", \"1\"]"));
        assert_eq!(parsed("[]").as_deref(), Some("[]"));
    }

    #[test]
    fn enact_unparseable_cases() {
        for answer in [
            "",
            "[]",
            "[ ]",
            "[,]",
            "no numbers: [a, b]",
            "   \n ",
            "I cannot determine",
        ] {
            assert_eq!(enact(answer, 3), None, "{answer:?} is unparseable");
        }
        for value in ["null", "12", "{\"order\": [1, 2]}", "true", "1.5"] {
            assert!(
                parse_answer_enact(&json(value), 3).is_none(),
                "{value} is unparseable"
            );
        }
        // A digit run beyond Python's int() limit makes the fallback fail too.
        assert_eq!(enact(&format!("x {}", "7".repeat(4301)), 3), None);
    }

    #[test]
    fn enact_literal_edge_cases() {
        // '[007]' has leading zeros (SyntaxError), so the fallback reads 007 as 7.
        assert_eq!(enact("[007, 1]", 2).as_deref(), Some("[7, 1]"));
        assert_eq!(enact("[00, 1]", 2).as_deref(), Some("[1, 2]"));
        // The fallback keeps the numbers as written; a literal would be re-based to start at 1.
        assert_eq!(enact("[02, 03]", 2).as_deref(), Some("[2, 3]"));
        // A vertical tab matches \s but is not Python whitespace: SyntaxError, fallback.
        assert_eq!(enact("[3,\u{b}4]", 2).as_deref(), Some("[3, 4]"));
        assert_eq!(enact("[3,\u{c}4]", 2).as_deref(), Some("[1, 2]"));
        // `\[[\d\s,]+\]` needs something inside: the later "[]" is no match, so the literal
        // [0, 1] is read and re-based; the fallback would keep 0.
        assert_eq!(enact("[0, 1] []", 2).as_deref(), Some("[1, 2]"));
        // findall resumes after a failed '[': only '[2]' matches in '[1 [2]'.
        assert_eq!(enact("[1 [2]", 1).as_deref(), Some("[1]"));
        // Two values with no comma between are a SyntaxError too: the fallback keeps every
        // number as written, where a literal would be cut to the last three and re-based.
        assert_eq!(enact("[0 1 2 3]", 3).as_deref(), Some("[0, 1, 2, 3]"));
        // Python's 4,300-digit limit spares a literal of zeros (`ast.literal_eval` reads 5,000
        // of them as 0, re-based here) but not `int()`, which the fallback would need; and it
        // refuses a literal of 4,301 nines, whose fallback then fails too (Python 3.11).
        let zeros = format!("[{}, 1]", "0".repeat(5000));
        assert_eq!(enact(&zeros, 2).as_deref(), Some("[1, 2]"));
        let nines = format!("[1, {}]", "9".repeat(4301));
        assert_eq!(enact(&nines, 2), None);
    }

    #[test]
    fn a_bracket_without_its_closing_bracket_is_not_a_list_for_enact() {
        // `\[[\d\s,]+\]` needs its `]`: the unclosed "[1, 2 " is no match, the earlier list wins.
        assert_eq!(
            enact("Answer: [2, 1] ([1, 2 was my first guess)", 2).as_deref(),
            Some("[2, 1]")
        );
    }

    #[test]
    fn strict_accepts_wrapped_answers() {
        let ok = |text: &str| parse_answer_text_strict(text, 3).map(|p| p.to_string());
        assert_eq!(ok("[2, 1, 3]").as_deref(), Ok("[2, 1, 3]"));
        assert_eq!(
            ok("I think [1, 2, 3] but finally [3, 1, 2].").as_deref(),
            Ok("[3, 1, 2]")
        );
        assert_eq!(ok("```json\n[3, 2, 1]\n```").as_deref(), Ok("[3, 2, 1]"));
        assert_eq!(
            ok("<think>maybe [1, 1, 1]?</think>Answer: [2, 3, 1]").as_deref(),
            Ok("[2, 3, 1]")
        );
        assert_eq!(
            ok("reasoning [1,2,3] </think> [3, 2, 1]").as_deref(),
            Ok("[3, 2, 1]")
        );
        // What comes before a closed block is kept, what is inside it is not.
        assert_eq!(
            ok("Answer: [2, 3, 1] <think>or [1, 2, 3]?</think>").as_deref(),
            Ok("[2, 3, 1]")
        );
        assert_eq!(ok("[2, 3, 1,]").as_deref(), Ok("[2, 3, 1]"));
        assert_eq!(
            ok("Actions [Action 1] then: [2, 3, 1]").as_deref(),
            Ok("[2, 3, 1]")
        );
        assert_eq!(ok("2, 3, 1").as_deref(), Ok("[2, 3, 1]"));
        assert_eq!(ok("[２, ３, １]").as_deref(), Ok("[2, 3, 1]"));
        // An unclosed bracket before the list: the search restarts at the inner one.
        assert_eq!(ok("See [the list [2, 3, 1]").as_deref(), Ok("[2, 3, 1]"));
    }

    #[test]
    fn enact_fallback_reads_a_run_at_python_s_digit_limit_and_fails_one_over_it() {
        // Python's int() takes a string of exactly 4300 digits and raises on 4301.
        let run = |digits: usize| PyValue::Str(format!("order: {}", "7".repeat(digits)));
        let at_limit = parse_answer_enact(&run(PY_INT_MAX_STR_DIGITS), 3).expect("parsed");
        assert_eq!(at_limit.labels().len(), 1);
        assert!(parse_answer_enact(&run(PY_INT_MAX_STR_DIGITS + 1), 3).is_none());
    }

    #[test]
    fn enact_bracket_list_takes_a_literal_at_python_s_digit_limit_and_not_one_over_it() {
        // Inside the brackets too, int() takes exactly 4300 digits: the list is the answer.
        let text = |digits: usize| format!("[{}] then 5", "7".repeat(digits));
        // The one label, rebased as ENACT rebases a list.
        assert_eq!(
            enact(&text(PY_INT_MAX_STR_DIGITS), 3).as_deref(),
            Some("[1]")
        );
        // Over it, the digit fallback meets the same run, which int() refuses too.
        assert_eq!(enact(&text(PY_INT_MAX_STR_DIGITS + 1), 3), None);
    }

    #[test]
    fn enact_keeps_the_last_labels_of_a_list_longer_than_the_truth() {
        // parsed[-gt_len:]: five labels for three actions keep the last three.
        assert_eq!(enact("[4, 5, 1, 2, 3]", 3).as_deref(), Some("[1, 2, 3]"));
        assert_eq!(
            enact("[9, 8, 7, 6, 3, 1, 2]", 3).as_deref(),
            Some("[3, 1, 2]")
        );
    }

    #[test]
    fn strict_failure_reasons() {
        let fail = |text: &str, actions: usize| {
            parse_answer_text_strict(text, actions)
                .unwrap_err()
                .to_string()
        };
        assert_eq!(fail("[1, 2, 3]", 4), "wrong length 3, expected 4");
        assert_eq!(fail("[0, 1, 2, 3]", 4), "label 0 out of range 1..4");
        assert_eq!(fail("[1, 2, 2, 3]", 4), "label 2 repeated");
        assert_eq!(fail("I cannot tell", 4), "no list found");
        assert_eq!(
            fail("<think>[1, 2, 3, 4]</think> no idea", 4),
            "no list found"
        );
        assert_eq!(fail("<think>[1, 2, 3, 4] unclosed", 4), "no list found");
        // A closing tag without an opening one: the list before it was thinking.
        assert_eq!(
            fail("maybe [1, 2, 3, 4] </think> no idea", 4),
            "no list found"
        );
        // The same with a block after it: what precedes the stray tag is still thinking.
        assert_eq!(
            fail(
                "maybe [1, 2, 3, 4] </think> no idea <think>[4, 3, 2, 1]</think>",
                4
            ),
            "no list found"
        );
        assert_eq!(fail("[-1, 2, 3, 4]", 4), "label -1 out of range 1..4");
        assert_eq!(
            fail("[1, 2, 3, 100000000000000000000]", 4),
            "label 100000000000000000000 out of range 1..4"
        );
        assert_eq!(fail("[]", 2), "wrong length 0, expected 2");
        assert_eq!(fail("[1,,2]", 2), "no list found");
        let raw = |text: &str| parse_answer_strict(Some(&json(text)), 2).map_err(|e| e.to_string());
        assert_eq!(
            raw("[2, 1]").map(|p| p.to_string()),
            Ok("[2, 1]".to_owned())
        );
        assert_eq!(
            raw("[1.0, 2.0]"),
            Err("label 1.0 is not an integer".to_owned())
        );
        assert_eq!(
            raw("12"),
            Err("answer is a int, expected a string or a list of integers".to_owned())
        );
        assert_eq!(raw("null"), Err("no answer given".to_owned()));
        assert_eq!(
            parse_answer_strict(None, 2).unwrap_err(),
            StrictParseFailure::Missing
        );
    }

    #[test]
    fn strict_labels_past_255_are_out_of_range_not_wrapped_to_a_byte() {
        // 257 would wrap to the byte 1 and make [2, 1] a valid permutation.
        assert_eq!(
            parse_answer_text_strict("[2, 257]", 2),
            Err(StrictParseFailure::OutOfRange {
                label: "257".to_owned(),
                max: 2
            })
        );
    }

    #[test]
    fn permutation_validation() {
        let three = Permutation::new(vec![2, 3, 1]).unwrap();
        assert_eq!((three.len(), three.is_empty()), (3, false));
        assert_eq!(
            Permutation::new(vec![1, 1]).unwrap_err().to_string(),
            "label 1 repeated"
        );
        assert_eq!(
            Permutation::new(vec![0, 1]).unwrap_err().to_string(),
            "label 0 out of range 1..2"
        );
        assert_eq!(
            Permutation::new(vec![]).unwrap_err(),
            PermutationError::Empty
        );
        assert_eq!(
            Permutation::new(vec![2, 1]).unwrap().step_length(),
            StepLength::new(3)
        );
        let round_trip: Permutation = serde_json::from_str("[3, 1, 2]").expect("valid");
        assert_eq!(round_trip.labels(), &[3, 1, 2]);
        assert!(serde_json::from_str::<Permutation>("[3, 3, 2]").is_err());
    }
}
