//! ENACT release records: the QA line format, its validation, and the item model built from it.
//!
//! Pure and synchronous: the importer feeds it lines and reports what comes back; nothing here
//! touches files or the database.

use schemars::JsonSchema;
use std::fmt;

use serde::{Deserialize, Serialize};
use serde_json::Value;

/// Which way an item asks the model to reason.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// Current image + actions in order; order the shuffled future images.
    Forward,
    /// Images in order; order the shuffled action descriptions.
    Inverse,
}

impl Direction {
    pub const ALL: [Direction; 2] = [Direction::Forward, Direction::Inverse];

    pub fn as_str(self) -> &'static str {
        match self {
            Direction::Forward => "forward",
            Direction::Inverse => "inverse",
        }
    }

    pub fn parse(s: &str) -> Option<Direction> {
        match s {
            "forward" => Some(Direction::Forward),
            "inverse" => Some(Direction::Inverse),
            _ => None,
        }
    }
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Number of states in an item, the current one included (ENACT's L, 3..=10).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, JsonSchema,
)]
#[serde(try_from = "u8", into = "u8")]
pub struct StepLength(u8);

impl StepLength {
    pub const MIN: u8 = 3;
    pub const MAX: u8 = 10;

    pub fn new(states: usize) -> Option<StepLength> {
        u8::try_from(states)
            .ok()
            .filter(|l| (Self::MIN..=Self::MAX).contains(l))
            .map(StepLength)
    }

    pub fn all() -> impl Iterator<Item = StepLength> {
        (Self::MIN..=Self::MAX).map(StepLength)
    }

    /// L: the number of images.
    pub fn states(self) -> usize {
        usize::from(self.0)
    }

    /// L - 1: the number of actions, and the length of an answer.
    pub fn actions(self) -> usize {
        usize::from(self.0) - 1
    }

    pub fn get(self) -> u8 {
        self.0
    }
}

impl TryFrom<u8> for StepLength {
    type Error = String;
    fn try_from(v: u8) -> Result<Self, Self::Error> {
        StepLength::new(usize::from(v)).ok_or_else(|| format!("step length {v} is outside 3..10"))
    }
}

impl From<StepLength> for u8 {
    fn from(l: StepLength) -> u8 {
        l.0
    }
}

impl fmt::Display for StepLength {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// One validated QA item of an ENACT release file.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct QaItem {
    pub id: String,
    /// The `type` string exactly as the file has it (three naming variants exist).
    pub item_type: String,
    pub direction: Direction,
    pub step_length: StepLength,
    pub task_name: String,
    /// Chronological key frame ids (decimal strings), L of them.
    pub key_frame_ids: Vec<String>,
    /// Image paths relative to the release root: `[cur_state, next_state_1, ..]`.
    pub images: Vec<String>,
    pub question: String,
    /// The `[Action k]` texts in the order the question shows them.
    pub actions: Vec<String>,
    /// ENACT's ground truth: a permutation of 1..L-1.
    pub gt_answer: Vec<u8>,
}

impl QaItem {
    /// The label drawn on (and shown beside) image `position` of the item.
    pub fn image_label(position: usize) -> String {
        if position == 0 {
            "Current State".to_owned()
        } else {
            format!("Next State {position}")
        }
    }
}

/// A problem with one field of one line.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FieldProblem {
    pub field: String,
    pub message: String,
}

impl FieldProblem {
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        FieldProblem {
            field: field.into(),
            message: message.into(),
        }
    }
}

impl fmt::Display for FieldProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.field.is_empty() {
            f.write_str(&self.message)
        } else {
            write!(f, "`{}`: {}", self.field, self.message)
        }
    }
}

/// Reads the direction and step length from an ENACT `type` string.
///
/// Accepts every naming the ENACT code and data use: `{dir}_world_modeling_ordering_{L}_steps`
/// (release), `{dir}_world_modeling_{L}_steps` (public code) and `{dir}_dynamics_ordering_{L}_steps`
/// (README examples), in any letter case.
pub fn parse_item_type(item_type: &str) -> Result<(Direction, usize), String> {
    let lower = item_type.to_ascii_lowercase();
    let (direction, rest) = if let Some(rest) = lower.strip_prefix("forward_") {
        (Direction::Forward, rest)
    } else if let Some(rest) = lower.strip_prefix("inverse_") {
        (Direction::Inverse, rest)
    } else {
        return Err(format!(
            "unknown type {item_type:?}: expected forward_… or inverse_…"
        ));
    };
    let middle = [
        "world_modeling_ordering_",
        "world_modeling_",
        "dynamics_ordering_",
    ]
    .into_iter()
    .find_map(|prefix| rest.strip_prefix(prefix));
    let steps = middle
        .and_then(|m| m.strip_suffix("_steps"))
        .and_then(|n| n.parse::<usize>().ok());
    match steps {
        Some(l) => Ok((direction, l)),
        None => Err(format!(
            "unknown type {item_type:?}: expected {d}_world_modeling_ordering_{{L}}_steps, \
             {d}_world_modeling_{{L}}_steps or {d}_dynamics_ordering_{{L}}_steps",
            d = direction
        )),
    }
}

/// The `[Action k] text` lines of a question, in the order shown.
///
/// Returns the texts and the labels `k` as written, so the caller can check they run 1..L-1.
pub fn action_lines(question: &str) -> Vec<(u32, String)> {
    question
        .lines()
        .filter_map(|line| {
            let rest = line.trim_start().strip_prefix("[Action ")?;
            let (number, text) = rest.split_once(']')?;
            let label = number.trim().parse::<u32>().ok()?;
            Some((label, text.trim().to_owned()))
        })
        .collect()
}

/// Parses and validates one line of `enact_ordering.jsonl`.
///
/// Every problem found is returned, not only the first, so one pass over a file tells the user
/// everything that needs fixing. Image files are not looked at here (see the importer).
pub fn parse_release_line(line: &str) -> Result<QaItem, Vec<FieldProblem>> {
    let value: Value = match serde_json::from_str(line) {
        Ok(v) => v,
        Err(e) => {
            return Err(vec![FieldProblem::new("", format!("invalid JSON: {e}"))]);
        }
    };
    let Some(object) = value.as_object() else {
        return Err(vec![FieldProblem::new(
            "",
            "expected a JSON object for the record",
        )]);
    };

    let mut problems = Vec::new();
    let mut string_field = |name: &str| -> Option<String> {
        match object.get(name) {
            None => {
                problems.push(FieldProblem::new(name, "missing"));
                None
            }
            Some(Value::String(s)) if s.trim().is_empty() => {
                problems.push(FieldProblem::new(name, "is empty"));
                None
            }
            Some(Value::String(s)) => Some(s.clone()),
            Some(other) => {
                problems.push(FieldProblem::new(
                    name,
                    format!("expected a string, found {}", json_kind(other)),
                ));
                None
            }
        }
    };
    let id = string_field("id");
    let item_type = string_field("type");
    let task_name = string_field("task_name");
    let question = string_field("question");

    let key_frame_ids = string_list(object.get("key_frame_ids"), "key_frame_ids", &mut problems);
    let images = string_list(object.get("images"), "images", &mut problems);
    let gt_answer = label_list(object.get("gt_answer"), &mut problems);

    let mut direction_and_length = None;
    if let Some(t) = &item_type {
        match parse_item_type(t) {
            Ok((direction, l)) => match StepLength::new(l) {
                Some(step_length) => direction_and_length = Some((direction, step_length)),
                None => problems.push(FieldProblem::new(
                    "type",
                    format!("step length {l} is outside 3..10"),
                )),
            },
            Err(message) => problems.push(FieldProblem::new("type", message)),
        }
    }

    if let Some(kf) = &key_frame_ids {
        for (i, frame) in kf.iter().enumerate() {
            if frame.parse::<u64>().is_err() {
                problems.push(FieldProblem::new(
                    format!("key_frame_ids[{i}]"),
                    format!("{frame:?} is not a decimal frame id"),
                ));
            }
        }
    }

    let mut actions = Vec::new();
    if let (Some((_, step_length)), Some(q)) = (direction_and_length, &question) {
        let l = step_length.states();
        if let Some(kf) = &key_frame_ids
            && kf.len() != l
        {
            problems.push(FieldProblem::new(
                "key_frame_ids",
                format!("has {} frame ids, the type says L = {l}", kf.len()),
            ));
        }
        if let Some(imgs) = &images
            && imgs.len() != l
        {
            problems.push(FieldProblem::new(
                "images",
                format!("has {} images, the type says L = {l}", imgs.len()),
            ));
        }
        if let Some(gt) = &gt_answer {
            check_permutation(gt, step_length.actions(), &mut problems);
        }
        let lines = action_lines(q);
        let expected: Vec<u32> = (1..=step_length.actions() as u32).collect();
        let found: Vec<u32> = lines.iter().map(|(k, _)| *k).collect();
        if found != expected {
            problems.push(FieldProblem::new(
                "question",
                format!(
                    "expected {} lines [Action 1]..[Action {}], found {} ({})",
                    step_length.actions(),
                    step_length.actions(),
                    lines.len(),
                    if found.is_empty() {
                        "none".to_owned()
                    } else {
                        found
                            .iter()
                            .map(|k| format!("[Action {k}]"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    }
                ),
            ));
        } else if let Some((k, _)) = lines.iter().find(|(_, text)| text.is_empty()) {
            problems.push(FieldProblem::new(
                "question",
                format!("[Action {k}] has no text"),
            ));
        }
        actions = lines.into_iter().map(|(_, text)| text).collect();
    }

    if !problems.is_empty() {
        return Err(problems);
    }
    // Every Option below is Some when no problem was recorded.
    match (
        id,
        item_type,
        direction_and_length,
        task_name,
        key_frame_ids,
        images,
        question,
        gt_answer,
    ) {
        (
            Some(id),
            Some(item_type),
            Some((direction, step_length)),
            Some(task_name),
            Some(key_frame_ids),
            Some(images),
            Some(question),
            Some(gt_answer),
        ) => Ok(QaItem {
            id,
            item_type,
            direction,
            step_length,
            task_name,
            key_frame_ids,
            images,
            question,
            actions,
            gt_answer,
        }),
        _ => Err(vec![FieldProblem::new("", "incomplete record")]),
    }
}

fn json_kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "an object",
    }
}

fn string_list(
    value: Option<&Value>,
    name: &str,
    problems: &mut Vec<FieldProblem>,
) -> Option<Vec<String>> {
    let Some(value) = value else {
        problems.push(FieldProblem::new(name, "missing"));
        return None;
    };
    let Some(list) = value.as_array() else {
        problems.push(FieldProblem::new(
            name,
            format!("expected a list of strings, found {}", json_kind(value)),
        ));
        return None;
    };
    if list.is_empty() {
        problems.push(FieldProblem::new(name, "is empty"));
        return None;
    }
    let mut out = Vec::with_capacity(list.len());
    let mut ok = true;
    for (i, v) in list.iter().enumerate() {
        match v.as_str() {
            Some(s) if !s.is_empty() => out.push(s.to_owned()),
            _ => {
                ok = false;
                problems.push(FieldProblem::new(
                    format!("{name}[{i}]"),
                    format!("expected a non-empty string, found {}", json_kind(v)),
                ));
            }
        }
    }
    ok.then_some(out)
}

fn label_list(value: Option<&Value>, problems: &mut Vec<FieldProblem>) -> Option<Vec<u8>> {
    let Some(value) = value else {
        problems.push(FieldProblem::new("gt_answer", "missing"));
        return None;
    };
    let Some(list) = value.as_array() else {
        problems.push(FieldProblem::new(
            "gt_answer",
            format!("expected a list of integers, found {}", json_kind(value)),
        ));
        return None;
    };
    let mut out = Vec::with_capacity(list.len());
    for (i, v) in list.iter().enumerate() {
        match v.as_u64().and_then(|n| u8::try_from(n).ok()) {
            Some(n) => out.push(n),
            None => {
                problems.push(FieldProblem::new(
                    format!("gt_answer[{i}]"),
                    format!("expected a label 1..9, found {v}"),
                ));
                return None;
            }
        }
    }
    Some(out)
}

fn check_permutation(gt: &[u8], actions: usize, problems: &mut Vec<FieldProblem>) {
    let mut seen = vec![false; actions + 1];
    let mut ok = gt.len() == actions;
    for &label in gt {
        let l = usize::from(label);
        if l == 0 || l > actions || seen[l] {
            ok = false;
        } else {
            seen[l] = true;
        }
    }
    if !ok {
        problems.push(FieldProblem::new(
            "gt_answer",
            format!("{gt:?} is not a permutation of 1..{actions}"),
        ));
    }
}

/// Whether a dataset's ground truth and per-item correctness may be shown to submitters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum AnswerVisibility {
    Public,
    Hidden,
}

impl AnswerVisibility {
    pub fn as_str(self) -> &'static str {
        match self {
            AnswerVisibility::Public => "public",
            AnswerVisibility::Hidden => "hidden",
        }
    }

    pub fn parse(text: &str) -> Option<AnswerVisibility> {
        match text {
            "public" => Some(AnswerVisibility::Public),
            "hidden" => Some(AnswerVisibility::Hidden),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(l: usize, direction: &str) -> serde_json::Map<String, Value> {
        let mut question = String::from("Intro\n\n## Actions in Order\n");
        for k in 1..l {
            question.push_str(&format!("[Action {k}] The apple becomes cooked.\n"));
        }
        question.push_str("\nNow please provide your answer in the requested format.\n");
        let kf: Vec<String> = (0..l).map(|i| (100 * (i + 1)).to_string()).collect();
        let images: Vec<String> = (0..l).map(|i| format!("QA/images/x/{i}.png")).collect();
        let gt: Vec<usize> = (1..l).rev().collect();
        serde_json::json!({
            "id": "t_1_x",
            "type": format!("{direction}_world_modeling_ordering_{l}_steps"),
            "task_name": "task_1",
            "key_frame_ids": kf,
            "images": images,
            "question": question,
            "options": [],
            "gt_answer": gt,
        })
        .as_object()
        .cloned()
        .expect("object literal")
    }

    fn line(map: &serde_json::Map<String, Value>) -> String {
        serde_json::to_string(map).expect("serialisable")
    }

    fn problems(map: &serde_json::Map<String, Value>) -> Vec<String> {
        parse_release_line(&line(map))
            .expect_err("record should be invalid")
            .into_iter()
            .map(|p| p.to_string())
            .collect()
    }

    #[test]
    fn valid_record_parses_with_actions_in_order() {
        let item = parse_release_line(&line(&record(4, "inverse"))).expect("valid");
        assert_eq!(item.direction, Direction::Inverse);
        assert_eq!(item.step_length.states(), 4);
        assert_eq!(item.actions.len(), 3);
        assert_eq!(item.gt_answer, vec![3, 2, 1]);
    }

    #[test]
    fn every_type_variant_is_accepted() {
        for t in [
            "forward_world_modeling_ordering_3_steps",
            "forward_world_modeling_3_steps",
            "forward_dynamics_ordering_3_steps",
            "INVERSE_world_modeling_3_steps",
        ] {
            let (_, l) = parse_item_type(t).expect(t);
            assert_eq!(l, 3);
        }
        assert!(parse_item_type("sideways_world_modeling_3_steps").is_err());
        assert!(parse_item_type("forward_world_modeling_x_steps").is_err());
    }

    #[test]
    fn bad_json_is_reported() {
        let p = parse_release_line("{not json").expect_err("invalid");
        assert!(p[0].message.starts_with("invalid JSON"), "{p:?}");
    }

    #[test]
    fn missing_fields_are_each_named() {
        let mut r = record(3, "forward");
        r.remove("task_name");
        r.remove("gt_answer");
        let p = problems(&r);
        assert!(p.contains(&"`task_name`: missing".to_owned()), "{p:?}");
        assert!(p.contains(&"`gt_answer`: missing".to_owned()), "{p:?}");
    }

    #[test]
    fn step_length_outside_range_is_rejected() {
        let mut r = record(3, "forward");
        r.insert(
            "type".into(),
            "forward_world_modeling_ordering_11_steps".into(),
        );
        let p = problems(&r);
        assert!(p.iter().any(|m| m.contains("outside 3..10")), "{p:?}");
    }

    #[test]
    fn non_permutation_ground_truth_is_rejected() {
        let mut r = record(4, "forward");
        r.insert("gt_answer".into(), serde_json::json!([1, 1, 2]));
        let p = problems(&r);
        assert!(
            p.iter().any(|m| m.contains("not a permutation of 1..3")),
            "{p:?}"
        );
        r.insert("gt_answer".into(), serde_json::json!([1, 2]));
        assert!(problems(&r).iter().any(|m| m.contains("not a permutation")));
    }

    #[test]
    fn image_count_must_equal_step_length() {
        let mut r = record(4, "forward");
        r.insert("images".into(), serde_json::json!(["a.png", "b.png"]));
        let p = problems(&r);
        assert!(
            p.iter()
                .any(|m| m.contains("has 2 images, the type says L = 4")),
            "{p:?}"
        );
    }

    #[test]
    fn question_needs_one_line_per_action() {
        let mut r = record(4, "forward");
        r.insert(
            "question".into(),
            "## Actions in Order\n[Action 1] a.\n[Action 2] b.\n".into(),
        );
        let p = problems(&r);
        assert!(p.iter().any(|m| m.contains("expected 3 lines")), "{p:?}");
    }

    #[test]
    fn labels_follow_enact_naming() {
        assert_eq!(QaItem::image_label(0), "Current State");
        assert_eq!(QaItem::image_label(3), "Next State 3");
    }
}
