//! Writing a stored dataset back out as an ENACT release (pure): the QA lines, with ground
//! truth only when the dataset's answers are public, and the tar entries of the archive.
//!
//! The archive holds `QA/enact_ordering.jsonl` first, then every image under the path its record
//! names, so that extracting it and running `enact-hub import DIR` reads the same items back.
//! Entries are produced one at a time so that a web handler can stream them.

use serde::Serialize;

/// Where the QA lines live inside a release.
pub const QA_FILE: &str = "QA/enact_ordering.jsonl";

/// The fields of one stored item that its release line needs.
#[derive(Debug, Clone)]
pub struct ReleaseItem {
    pub id: String,
    pub item_type: String,
    pub task_name: String,
    pub key_frame_ids: Vec<String>,
    pub images: Vec<String>,
    pub question: String,
    pub gt_answer: Vec<u8>,
}

/// One QA line, in ENACT's field order. Ground truth (`key_frame_ids`, which give the
/// chronological order of the frames, and `gt_answer`) is left out for hidden datasets.
#[derive(Serialize)]
struct ReleaseLine<'a> {
    id: &'a str,
    #[serde(rename = "type")]
    item_type: &'a str,
    task_name: &'a str,
    #[serde(skip_serializing_if = "Option::is_none")]
    key_frame_ids: Option<&'a [String]>,
    images: &'a [String],
    question: &'a str,
    /// ENACT's ordering items always carry an empty list here.
    options: [u8; 0],
    #[serde(skip_serializing_if = "Option::is_none")]
    gt_answer: Option<&'a [u8]>,
}

/// The QA line of `item`, without a trailing newline.
pub fn release_line(item: &ReleaseItem, with_truth: bool) -> String {
    let line = ReleaseLine {
        id: &item.id,
        item_type: &item.item_type,
        task_name: &item.task_name,
        key_frame_ids: with_truth.then_some(item.key_frame_ids.as_slice()),
        images: &item.images,
        question: &item.question,
        options: [],
        gt_answer: with_truth.then_some(item.gt_answer.as_slice()),
    };
    // Serialising strings and integer lists cannot fail.
    serde_json::to_string(&line).unwrap_or_default()
}

/// One line of ENACT's model-output JSONL (what `enact eval` reads): the item's QA fields,
/// ground truth included (the evaluator needs `key_frame_ids` and `gt_answer`), and `answer`,
/// the model's raw reply as a string, which ENACT's own answer parser reads.
#[derive(Serialize)]
struct ModelOutputLine<'a> {
    id: &'a str,
    #[serde(rename = "type")]
    item_type: &'a str,
    task_name: &'a str,
    key_frame_ids: &'a [String],
    images: &'a [String],
    question: &'a str,
    options: [u8; 0],
    gt_answer: &'a [u8],
    answer: &'a str,
}

/// The model-output line of `item` answered with `answer`, without a trailing newline.
pub fn model_output_line(item: &ReleaseItem, answer: &str) -> String {
    let line = ModelOutputLine {
        id: &item.id,
        item_type: &item.item_type,
        task_name: &item.task_name,
        key_frame_ids: &item.key_frame_ids,
        images: &item.images,
        question: &item.question,
        options: [],
        gt_answer: &item.gt_answer,
        answer,
    };
    // Serialising strings and integer lists cannot fail.
    serde_json::to_string(&line).unwrap_or_default()
}

/// A tar archive written entry by entry: each call returns the bytes to send next, so the
/// whole archive never sits in memory.
pub struct ArchiveWriter {
    builder: tar::Builder<Vec<u8>>,
}

impl Default for ArchiveWriter {
    fn default() -> Self {
        ArchiveWriter {
            builder: tar::Builder::new(Vec::new()),
        }
    }
}

impl ArchiveWriter {
    /// The bytes of one file entry at `path` (relative, `/`-separated).
    pub fn file(&mut self, path: &str, contents: &[u8]) -> std::io::Result<Vec<u8>> {
        let mut header = tar::Header::new_gnu();
        header.set_size(contents.len() as u64);
        header.set_mode(0o644);
        // A fixed time keeps the archive of unchanged items byte-identical.
        header.set_mtime(0);
        header.set_entry_type(tar::EntryType::Regular);
        // `append_data` refuses absolute paths and `..`, and writes long names as GNU entries.
        self.builder.append_data(&mut header, path, contents)?;
        Ok(std::mem::take(self.builder.get_mut()))
    }

    /// The end-of-archive marker.
    pub fn finish(mut self) -> std::io::Result<Vec<u8>> {
        self.builder.finish()?;
        self.builder.into_inner()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn item() -> ReleaseItem {
        ReleaseItem {
            id: "t_forward_world_modeling_ordering_3_steps_1".to_owned(),
            item_type: "forward_world_modeling_ordering_3_steps".to_owned(),
            task_name: "t".to_owned(),
            key_frame_ids: vec!["10".to_owned(), "20".to_owned(), "30".to_owned()],
            images: vec!["QA/images/a.png".to_owned(), "QA/images/b.png".to_owned()],
            question: "Q".to_owned(),
            gt_answer: vec![2, 1],
        }
    }

    #[test]
    fn public_lines_carry_ground_truth_and_hidden_ones_do_not() {
        let public: serde_json::Value =
            serde_json::from_str(&release_line(&item(), true)).expect("json");
        assert_eq!(public["gt_answer"], serde_json::json!([2, 1]));
        assert_eq!(public["key_frame_ids"][2], "30");
        assert_eq!(public["type"], "forward_world_modeling_ordering_3_steps");
        assert_eq!(public["options"], serde_json::json!([]));
        let hidden = release_line(&item(), false);
        assert!(!hidden.contains("gt_answer") && !hidden.contains("key_frame_ids"));
        assert!(hidden.contains("\"images\""));
    }

    #[test]
    fn a_model_output_line_has_what_enact_eval_requires_and_the_answer_as_a_string() {
        let line: serde_json::Value =
            serde_json::from_str(&model_output_line(&item(), "The order is [2, 1]."))
                .expect("json");
        for field in [
            "id",
            "task_name",
            "type",
            "key_frame_ids",
            "gt_answer",
            "answer",
        ] {
            assert!(line.get(field).is_some(), "{field} missing from {line}");
        }
        assert_eq!(line["answer"], "The order is [2, 1].");
        assert_eq!(line["gt_answer"], serde_json::json!([2, 1]));
        assert_eq!(line["key_frame_ids"][0], "10");
        assert_eq!(line["options"], serde_json::json!([]));
    }

    #[test]
    fn entries_read_back_as_a_tar_archive() {
        let mut writer = ArchiveWriter::default();
        let long = format!("QA/images/{}/x.png", "d".repeat(150));
        let mut bytes = writer.file(QA_FILE, b"line\n").expect("entry");
        bytes.extend(writer.file(&long, &[1, 2, 3]).expect("entry"));
        bytes.extend(writer.finish().expect("end"));
        let mut archive = tar::Archive::new(bytes.as_slice());
        let names: Vec<String> = archive
            .entries()
            .expect("entries")
            .map(|e| {
                let e = e.expect("entry");
                e.path().expect("path").to_string_lossy().into_owned()
            })
            .collect();
        assert_eq!(names, vec![QA_FILE.to_owned(), long]);
        assert!(writer_refuses("../escape.png"));
        assert!(writer_refuses("/etc/passwd"));
    }

    fn writer_refuses(path: &str) -> bool {
        ArchiveWriter::default().file(path, b"x").is_err()
    }
}
