//! Writing a generated release in ENACT's layout: labelled item images, the JSONL, the
//! segmented and replayed scene graphs of each task, and `generation_summary.json`.

use std::collections::BTreeMap;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::Serialize;
use serde_json::{Map, Value};

use crate::pipeline::label::LabelFont;
use crate::pipeline::marked::MARKED_KEY_FRAMES_FILE;
use crate::pipeline::qa::GeneratedItem;
use crate::pipeline::{
    GenerationSummary, PipelineError, SegmentedTask, frame_image_path, scene_graph_path,
};
use crate::scene_graph::StateVocabulary;

/// What one task writes.
pub struct TaskRelease<'a> {
    /// The input `replayed_activities/` folder (source of the key-frame images).
    pub replayed_dir: &'a Path,
    pub segmented: &'a SegmentedTask,
    pub items: &'a [&'a GeneratedItem],
}

pub(crate) fn create_dir(dir: &Path) -> Result<(), PipelineError> {
    std::fs::create_dir_all(dir).map_err(|source| PipelineError::Write {
        path: dir.to_path_buf(),
        source,
    })
}

fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<(), PipelineError> {
    if let Some(dir) = path.parent() {
        create_dir(dir)?;
    }
    let write = |source| PipelineError::Write {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::create(path).map_err(write)?;
    let mut writer = BufWriter::new(file);
    serde_json::to_writer_pretty(&mut writer, value).map_err(|source| {
        PipelineError::Serialize {
            what: path.display().to_string(),
            source,
        }
    })?;
    writer.flush().map_err(write)
}

pub(crate) fn copy_file(from: &Path, to: &Path) -> Result<(), PipelineError> {
    std::fs::copy(from, to)
        .map(|_| ())
        .map_err(|source| PipelineError::Write {
            path: to.to_path_buf(),
            source,
        })
}

/// Whether two paths name the same existing folder.
pub(crate) fn same_dir(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// Draws `label` on the frame image `source` and saves it as `target` (PNG).
fn write_labelled(
    task: &str,
    frame: &str,
    source: &Path,
    label: &str,
    target: &Path,
    font: &LabelFont,
) -> Result<(), PipelineError> {
    let decoded = image::open(source).map_err(|e| PipelineError::Image {
        task: task.to_string(),
        frame: frame.to_string(),
        path: source.to_path_buf(),
        source: Box::new(e),
    })?;
    let mut rgb = decoded.to_rgb8();
    font.state_label(label, rgb.height()).apply(&mut rgb);
    rgb.save_with_format(target, image::ImageFormat::Png)
        .map_err(|e| match e {
            image::ImageError::IoError(source) => PipelineError::Write {
                path: target.to_path_buf(),
                source,
            },
            other => PipelineError::Write {
                path: target.to_path_buf(),
                source: std::io::Error::other(other),
            },
        })
}

/// Writes one task's files under `out`; returns the number of item images written.
pub(crate) fn write_release(
    out: &Path,
    release: &TaskRelease<'_>,
    font: &LabelFont,
) -> Result<usize, PipelineError> {
    let task = release.segmented.task_name.as_str();
    let segmentation = &release.segmented.segmentation;

    // segmented_activities/{task}/: ENACT's segmentation output plus the key-frame images.
    let segmented_dir = out.join("segmented_activities").join(task);
    write_json(
        &segmented_dir.join("segmented_scene_graph_0.json"),
        &segmentation.segmented_scene_graph(),
    )?;
    let mut image_dirs = vec![segmented_dir.join("external_sensor1")];

    // replayed_activities/{task}/: the raw key-frame graphs as full records, so signatures can
    // be computed from this release alone. Never over the input itself.
    let replayed_out = out.join("replayed_activities");
    if !same_dir(&replayed_out, release.replayed_dir) {
        let mut doc = Map::new();
        for frame in &segmentation.key_frames {
            let graph = release
                .segmented
                .key_frame_graphs
                .scene_graph(frame)
                .map_err(|source| PipelineError::SceneGraph {
                    task: task.to_string(),
                    source: Box::new(source),
                })?;
            doc.insert(
                frame.clone(),
                serde_json::json!({"nodes": graph.nodes, "edges": graph.edges, "type": "full"}),
            );
        }
        write_json(&scene_graph_path(&replayed_out, task), &Value::Object(doc))?;
        // Key frames a person marked travel with the release: the import reads the origin
        // and scene of a real-world dataset from them.
        let marked = release.replayed_dir.join(task).join(MARKED_KEY_FRAMES_FILE);
        if marked.is_file() {
            let to = replayed_out.join(task).join(MARKED_KEY_FRAMES_FILE);
            std::fs::copy(&marked, &to)
                .map_err(|source| PipelineError::Write { path: to, source })?;
        }
        image_dirs.push(replayed_out.join(task).join("external_sensor1"));
    }
    for dir in &image_dirs {
        create_dir(dir)?;
        for frame in &segmentation.key_frames {
            let source = frame_image_path(release.replayed_dir, task, frame);
            let name = source.file_name().map(PathBuf::from).unwrap_or_default();
            copy_file(&source, &dir.join(name))?;
        }
    }

    // QA/images/{type}/{task}/
    let mut targets = LabelledTargets::new();
    for item in release.items {
        for image in &item.labelled_images {
            targets
                .entry((task, image.frame.as_str(), image.label.clone()))
                .or_default()
                .push(out.join(&image.path));
        }
    }
    write_labelled_targets(release.replayed_dir, &targets, font)
}

/// Item images to write: (task, frame, label) -> the files that show that frame so labelled.
pub(crate) type LabelledTargets<'a> = BTreeMap<(&'a str, &'a str, String), Vec<PathBuf>>;

/// Draws each distinct labelled frame of `targets` once, from `replayed_dir`'s image of it,
/// and copies it to its other files; returns the number of files written.
pub(crate) fn write_labelled_targets(
    replayed_dir: &Path,
    targets: &LabelledTargets<'_>,
    font: &LabelFont,
) -> Result<usize, PipelineError> {
    let dirs: std::collections::BTreeSet<&Path> = targets
        .values()
        .flatten()
        .filter_map(|p| p.parent())
        .collect();
    for dir in dirs {
        create_dir(dir)?;
    }
    targets
        .par_iter()
        .try_for_each(|((task, frame, label), paths)| {
            let source = frame_image_path(replayed_dir, task, frame);
            let (first, rest) = paths.split_first().expect("every entry has a path");
            write_labelled(task, frame, &source, label, first, font)?;
            rest.iter().try_for_each(|p| copy_file(first, p))
        })?;
    Ok(targets.values().map(Vec::len).sum())
}

/// Writes `QA/enact_ordering.jsonl`, one item per line in the given order.
pub fn write_jsonl(out: &Path, items: &[&GeneratedItem]) -> Result<PathBuf, PipelineError> {
    let path = out.join("QA").join("enact_ordering.jsonl");
    if let Some(dir) = path.parent() {
        create_dir(dir)?;
    }
    let write = |source| PipelineError::Write {
        path: path.clone(),
        source,
    };
    let mut writer = BufWriter::new(std::fs::File::create(&path).map_err(write)?);
    for item in items {
        let mut serializer = serde_json::Serializer::with_formatter(&mut writer, PythonJson);
        item.serialize(&mut serializer)
            .map_err(|source| PipelineError::Serialize {
                what: format!("item {}", item.id),
                source,
            })?;
        writer.write_all(b"\n").map_err(write)?;
    }
    writer.flush().map_err(write)?;
    Ok(path)
}

/// ENACT quirk: ENACT writes its JSONL with Python's `json.dump`, whose separators are ", "
/// and ": "; the generated file has the same layout as a released one.
struct PythonJson;

impl serde_json::ser::Formatter for PythonJson {
    fn begin_array_value<W: ?Sized + Write>(
        &mut self,
        writer: &mut W,
        first: bool,
    ) -> std::io::Result<()> {
        if first {
            Ok(())
        } else {
            writer.write_all(b", ")
        }
    }

    fn begin_object_key<W: ?Sized + Write>(
        &mut self,
        writer: &mut W,
        first: bool,
    ) -> std::io::Result<()> {
        if first {
            Ok(())
        } else {
            writer.write_all(b", ")
        }
    }

    fn begin_object_value<W: ?Sized + Write>(&mut self, writer: &mut W) -> std::io::Result<()> {
        writer.write_all(b": ")
    }
}

/// The state vocabulary of the run that wrote a release: a contact run says so in its
/// `generation_summary.json`; anything else (ENACT's own releases have no summary) is ENACT's.
pub fn release_vocabulary(release: &Path) -> StateVocabulary {
    let summary = std::fs::read(release.join("generation_summary.json")).ok();
    let trigger = summary
        .and_then(|bytes| serde_json::from_slice::<serde_json::Value>(&bytes).ok())
        .and_then(|v| {
            v.pointer("/options/segmentation/key_frames")
                .and_then(|k| k.as_str().map(str::to_owned))
        });
    match trigger.as_deref() {
        Some("contact") => StateVocabulary::WithContact,
        _ => StateVocabulary::Enact,
    }
}

/// Writes `generation_summary.json`.
pub fn write_summary(out: &Path, summary: &GenerationSummary) -> Result<(), PipelineError> {
    write_json(&out.join("generation_summary.json"), summary)
}
