//! ENACT's data pipeline in Rust: key-frame segmentation of replayed tasks ([`segment`]), the
//! KFTS transition DAG with exact path counts and uniform path sampling ([`kfts`]), forward and
//! inverse ordering items ([`qa`]), and [`generate`], which runs all of it over a
//! `replayed_activities/` folder and writes an ENACT-layout release ([`release`]);
//! [`variant`] re-renders a baseline release's items from another replay of the same tasks,
//! optionally with [`actions`] in another encoding or from perturbed deltas.
//!
//! Randomness is seeded ChaCha8, so a run is reproducible; it does not reproduce ENACT's
//! Python `random` stream (which is not reproducible across Python hash seeds anyway).

pub mod actions;
pub mod kfts;
pub(crate) mod label;
pub mod marked;
pub(crate) mod prompt;
pub mod qa;
pub mod release;
pub mod segment;
pub mod variant;

use std::path::{Path, PathBuf};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;
use sha2::{Digest, Sha256};

use crate::dataset::Direction;
use crate::scene_graph::timeline::STREAM_THRESHOLD_BYTES;
use crate::scene_graph::{
    FrameRecord, FrameSelection, SceneGraphTimeline, TimelineError, TransientFilter,
};

pub use kfts::{KftsError, PathTable, SampledPaths, TransitionGraph, sample_paths};
use marked::{MARKED_KEY_FRAMES_FILE, MarkedKeyFrames, marked_segmentation};
pub use qa::{GeneratedItem, TypeNaming};
pub use release::TaskRelease;
use release::write_release;
pub use segment::{
    KeyFrameTrigger, Segmentation, SegmentationError, SegmentationParams, segment_key_frames,
};

/// What [`generate`] does.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GenerateOptions {
    /// Seeds path sampling, action templates and shuffles.
    pub seed: u64,
    /// Paths sampled per (task, L, direction); ENACT's CLI default is 5.
    pub num_to_sample: usize,
    /// Step lengths L to generate, each in 3..=10.
    pub step_lengths: Vec<usize>,
    pub segmentation: SegmentationParams,
    pub type_naming: TypeNaming,
}

impl Default for GenerateOptions {
    fn default() -> Self {
        GenerateOptions {
            seed: 42,
            num_to_sample: 5,
            step_lengths: (3..=10).collect(),
            segmentation: SegmentationParams::default(),
            type_naming: TypeNaming::default(),
        }
    }
}

/// Reported by [`generate`] as each task advances (tasks run in parallel, so events of
/// different tasks interleave).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum GenerateProgress {
    Started {
        tasks: usize,
    },
    Segmented {
        task: String,
        key_frames: usize,
    },
    TransitionsBuilt {
        task: String,
        valid_transitions: usize,
    },
    ImagesWritten {
        task: String,
        images: usize,
    },
    Finished {
        items: usize,
    },
}

/// Per step length of one task: how many valid paths exist and how many items were made.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct StepSummary {
    pub step_length: usize,
    /// All valid paths of this length (the DP total).
    pub valid_paths: u128,
    pub forward_items: usize,
    pub inverse_items: usize,
}

/// What was generated for one task.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TaskSummary {
    pub task_name: String,
    pub num_frames: usize,
    pub key_frames: Vec<String>,
    pub valid_transitions: usize,
    pub steps: Vec<StepSummary>,
}

/// `generation_summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GenerationSummary {
    pub options: GenerateOptions,
    pub tasks: Vec<TaskSummary>,
    pub items: usize,
    pub forward_items: usize,
    pub inverse_items: usize,
    pub images: usize,
    /// `QA/enact_ordering.jsonl` under the output folder.
    #[serde(skip)]
    pub jsonl_path: PathBuf,
}

/// Why generation stopped. Every variant names the file (and frame) at fault.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    #[error("invalid options: {0}")]
    Options(String),
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{dir} holds no task folder")]
    NoTasks { dir: PathBuf },
    #[error("task {task}: scene graph {path} is missing")]
    MissingSceneGraph { task: String, path: PathBuf },
    #[error("task {task}: {path}: {message}")]
    MarkedKeyFrames {
        task: String,
        path: PathBuf,
        message: String,
    },
    #[error("task {task}: {source}")]
    SceneGraph {
        task: String,
        #[source]
        source: Box<TimelineError>,
    },
    #[error("task {task}: {source}")]
    Segmentation {
        task: String,
        #[source]
        source: Box<SegmentationError>,
    },
    #[error("task {task}: key frame {frame} has no image {path}")]
    MissingKeyFrameImage {
        task: String,
        frame: String,
        path: PathBuf,
    },
    #[error("task {task}: key frame {frame}: cannot decode {path}: {source}")]
    Image {
        task: String,
        frame: String,
        path: PathBuf,
        #[source]
        source: Box<image::ImageError>,
    },
    #[error("task {task}: {source}")]
    Kfts {
        task: String,
        #[source]
        source: Box<KftsError>,
    },
    #[error("cannot serialise {what}: {source}")]
    Serialize {
        what: String,
        #[source]
        source: serde_json::Error,
    },
    #[error("{path}, line {line}: {message}")]
    Baseline {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error(
        "task {task} of the baseline is not in {dir}: a variant must replay the same tasks \
         (same activity and seed)"
    )]
    TaskNotInVariant { task: String, dir: PathBuf },
    #[error("the bundled label font is unreadable: {0}")]
    Font(#[from] ab_glyph::InvalidFont),
}

/// The scene graph of a task inside `replayed_activities/`.
pub fn scene_graph_path(replayed_dir: &Path, task: &str) -> PathBuf {
    replayed_dir.join(task).join("scene_graph_0.json")
}

/// The image of a frame inside `replayed_activities/` (ENACT's frame extraction numbers
/// files with five digits).
pub fn frame_image_path(replayed_dir: &Path, task: &str, frame: &str) -> PathBuf {
    let number = frame
        .parse::<u64>()
        .map_or_else(|_| frame.to_string(), |n| format!("{n:05}"));
    replayed_dir
        .join(task)
        .join("external_sensor1")
        .join(format!("{number}.png"))
}

/// The task folders of `replayed_dir`, sorted by name (ENACT's order).
pub fn task_names(replayed_dir: &Path) -> Result<Vec<String>, PipelineError> {
    let read = |source| PipelineError::Read {
        path: replayed_dir.to_path_buf(),
        source,
    };
    let mut tasks = Vec::new();
    for entry in std::fs::read_dir(replayed_dir).map_err(read)? {
        let entry = entry.map_err(read)?;
        if entry.file_type().map_err(read)?.is_dir() {
            tasks.push(entry.file_name().to_string_lossy().into_owned());
        }
    }
    tasks.sort();
    if tasks.is_empty() {
        return Err(PipelineError::NoTasks {
            dir: replayed_dir.to_path_buf(),
        });
    }
    Ok(tasks)
}

/// One task after segmentation: its key frames and their raw graphs.
pub struct SegmentedTask {
    pub task_name: String,
    pub segmentation: Segmentation,
    /// The raw (unfiltered) graphs of the key frames, as full records: what QA generation and
    /// the evaluator diff.
    pub key_frame_graphs: SceneGraphTimeline,
}

/// Loads one task's scene graph and finds its key frames (on transient-filtered graphs).
pub fn segment_task(
    replayed_dir: &Path,
    task: &str,
    params: &SegmentationParams,
) -> Result<SegmentedTask, PipelineError> {
    let path = scene_graph_path(replayed_dir, task);
    if !path.is_file() {
        return Err(PipelineError::MissingSceneGraph {
            task: task.to_string(),
            path,
        });
    }
    let graph_error = |source| PipelineError::SceneGraph {
        task: task.to_string(),
        source: Box::new(source),
    };
    let segment = |filtered: &SceneGraphTimeline| {
        segment_key_frames(filtered, params).map_err(|source| PipelineError::Segmentation {
            task: task.to_string(),
            source: Box::new(source),
        })
    };
    let marked_path = replayed_dir.join(task).join(MARKED_KEY_FRAMES_FILE);
    let large = std::fs::metadata(&path).is_ok_and(|m| m.len() > STREAM_THRESHOLD_BYTES);
    let (segmentation, raw) = if marked_path.is_file() {
        // Key frames a person marked (an exported episode): taken as they are, never scanned,
        // so no similarity or stability filter drops one.
        marked_task(task, &path, &marked_path)?
    } else if large {
        // Read as a stream twice: through the filter for segmentation, then only the records
        // the key frames are rebuilt from. Neither pass holds the file or every frame.
        let filtered =
            SceneGraphTimeline::load_with(&path, FrameSelection::All, TransientFilter::Enact)
                .map_err(graph_error)?;
        let segmentation = segment(&filtered)?;
        drop(filtered);
        let key_frames = segmentation.key_frames.iter().cloned().collect();
        let raw = SceneGraphTimeline::load(&path, FrameSelection::Only(key_frames))
            .map_err(graph_error)?;
        (segmentation, raw)
    } else {
        // Small enough to read once and keep whole.
        let raw = SceneGraphTimeline::load(&path, FrameSelection::All).map_err(graph_error)?;
        let filtered = raw.with_transients_filtered().map_err(graph_error)?;
        (segment(&filtered)?, raw)
    };
    let mut records = Vec::with_capacity(segmentation.key_frames.len());
    for frame in &segmentation.key_frames {
        let graph = raw.scene_graph(frame).map_err(graph_error)?.into_owned();
        let number = frame.parse::<u64>().unwrap_or_default();
        records.push((number, FrameRecord::Full(graph)));
    }
    for frame in &segmentation.key_frames {
        let image = frame_image_path(replayed_dir, task, frame);
        if !image.is_file() {
            return Err(PipelineError::MissingKeyFrameImage {
                task: task.to_string(),
                frame: frame.clone(),
                path: image,
            });
        }
    }
    Ok(SegmentedTask {
        task_name: task.to_string(),
        segmentation,
        key_frame_graphs: SceneGraphTimeline::from_records(path, records),
    })
}

/// The segmentation of a task whose key frames are listed in its marker file.
fn marked_task(
    task: &str,
    path: &Path,
    marked_path: &Path,
) -> Result<(Segmentation, SceneGraphTimeline), PipelineError> {
    let marked_error = |message: String| PipelineError::MarkedKeyFrames {
        task: task.to_string(),
        path: marked_path.to_path_buf(),
        message,
    };
    let text = std::fs::read(marked_path).map_err(|source| PipelineError::Read {
        path: marked_path.to_path_buf(),
        source,
    })?;
    let marked: MarkedKeyFrames =
        serde_json::from_slice(&text).map_err(|e| marked_error(e.to_string()))?;
    let raw = SceneGraphTimeline::load(path, FrameSelection::All).map_err(|source| {
        PipelineError::SceneGraph {
            task: task.to_string(),
            source: Box::new(source),
        }
    })?;
    let numbers: Vec<u64> = marked
        .key_frames
        .iter()
        .map(|f| {
            f.parse::<u64>()
                .map_err(|_| marked_error(format!("key frame {f:?} is not a frame number")))
        })
        .collect::<Result<_, _>>()?;
    if numbers.windows(2).any(|w| w[0] >= w[1]) {
        return Err(marked_error(
            "key frames are not in increasing order".into(),
        ));
    }
    let mut graphs = Vec::with_capacity(marked.key_frames.len());
    for frame in &marked.key_frames {
        let graph = raw.scene_graph(frame).map_err(|e| {
            marked_error(format!("key frame {frame} has no scene graph record: {e}"))
        })?;
        graphs.push((frame.clone(), graph.into_owned()));
    }
    let segmentation = marked_segmentation(&graphs, raw.frame_ids().count());
    Ok((segmentation, raw))
}

/// ENACT quirk: ENACT re-seeds its RNG with the same constant before each generator runs on a
/// task, so the forward and the inverse items of one (task, L) come from the same paths. We
/// keep that (one stream per task and L, shared by both directions) but derive it from the
/// user's seed, which ENACT ignores.
pub fn task_rng(seed: u64, task: &str, step_length: usize) -> ChaCha8Rng {
    let mut hasher = Sha256::new();
    hasher.update(seed.to_le_bytes());
    hasher.update(task.as_bytes());
    hasher.update([0u8]);
    hasher.update((step_length as u64).to_le_bytes());
    ChaCha8Rng::from_seed(hasher.finalize().into())
}

/// The items of one task for one L and direction, from its transition graph.
pub fn task_items(
    task: &SegmentedTask,
    graph: &TransitionGraph,
    table: &PathTable,
    direction: Direction,
    options: &GenerateOptions,
) -> Result<Vec<GeneratedItem>, KftsError> {
    let length = table.length();
    let mut rng = task_rng(options.seed, &task.task_name, length);
    let paths = sample_paths(graph, table, options.num_to_sample, &mut rng);
    let qa_type = qa::qa_type(direction, length, options.type_naming);
    let mut items = Vec::with_capacity(paths.len());
    for indices in paths.iter() {
        let path: Vec<String> = indices
            .iter()
            .map(|&i| graph.frames()[i as usize].clone())
            .collect();
        let actions = qa::action_texts_in(
            &task.key_frame_graphs,
            &path,
            options.segmentation.key_frames.vocabulary(),
            &mut rng,
        )?;
        items.push(match direction {
            Direction::Forward => {
                qa::forward_item(&task.task_name, &qa_type, &path, &actions, &mut rng)
            }
            Direction::Inverse => {
                qa::inverse_item(&task.task_name, &qa_type, &path, &actions, &mut rng)
            }
        });
    }
    if direction == Direction::Inverse {
        qa::cap_inverse_items(&mut items, &mut rng);
    }
    Ok(items)
}

/// Everything one task contributes: summary, items per (L, direction), release files.
struct TaskOutcome {
    summary: TaskSummary,
    /// Indexed like `options.step_lengths`: (forward items, inverse items).
    items: Vec<(Vec<GeneratedItem>, Vec<GeneratedItem>)>,
    images: usize,
}

fn check_options(options: &GenerateOptions) -> Result<(), PipelineError> {
    if options.step_lengths.is_empty() {
        return Err(PipelineError::Options("no step length given".into()));
    }
    if let Some(l) = options.step_lengths.iter().find(|l| !(3..=10).contains(*l)) {
        return Err(PipelineError::Options(format!(
            "step length {l} is outside 3..=10"
        )));
    }
    let p = &options.segmentation;
    if !(p.cosine_threshold.is_finite()) {
        return Err(PipelineError::Options(
            "the cosine threshold must be a finite number".into(),
        ));
    }
    if p.warmup_frames == 0 {
        return Err(PipelineError::Options(
            "warmup frames must be at least 1 (the first key frame is the last warm-up frame)"
                .into(),
        ));
    }
    Ok(())
}

fn run_task(
    replayed_dir: &Path,
    out: &Path,
    task: &str,
    options: &GenerateOptions,
    font: &crate::pipeline::label::LabelFont,
    progress: &(dyn Fn(GenerateProgress) + Sync),
) -> Result<TaskOutcome, PipelineError> {
    let segmented = segment_task(replayed_dir, task, &options.segmentation)?;
    progress(GenerateProgress::Segmented {
        task: task.to_string(),
        key_frames: segmented.segmentation.key_frames.len(),
    });
    let kfts_error = |source| PipelineError::Kfts {
        task: task.to_string(),
        source: Box::new(source),
    };
    let graph = TransitionGraph::build_in(
        &segmented.key_frame_graphs,
        &segmented.segmentation.key_frames,
        options.segmentation.key_frames.vocabulary(),
    )
    .map_err(kfts_error)?;
    progress(GenerateProgress::TransitionsBuilt {
        task: task.to_string(),
        valid_transitions: graph.edge_count(),
    });
    let mut steps = Vec::new();
    let mut items = Vec::new();
    for &length in &options.step_lengths {
        let table = PathTable::count(&graph, length).map_err(kfts_error)?;
        // ENACT makes no item for a task with fewer key frames than L (the count is 0 then).
        let forward = task_items(&segmented, &graph, &table, Direction::Forward, options)
            .map_err(kfts_error)?;
        let inverse = task_items(&segmented, &graph, &table, Direction::Inverse, options)
            .map_err(kfts_error)?;
        steps.push(StepSummary {
            step_length: length,
            valid_paths: table.total(),
            forward_items: forward.len(),
            inverse_items: inverse.len(),
        });
        items.push((forward, inverse));
    }
    let all: Vec<&GeneratedItem> = items.iter().flat_map(|(f, i)| f.iter().chain(i)).collect();
    let task_release = TaskRelease {
        replayed_dir,
        segmented: &segmented,
        items: &all,
    };
    let images = write_release(out, &task_release, font)?;
    progress(GenerateProgress::ImagesWritten {
        task: task.to_string(),
        images,
    });
    Ok(TaskOutcome {
        summary: TaskSummary {
            task_name: task.to_string(),
            num_frames: segmented.segmentation.num_frames,
            key_frames: segmented.segmentation.key_frames.clone(),
            valid_transitions: graph.edge_count(),
            steps,
        },
        items,
        images,
    })
}

/// Runs the pipeline over every task folder of `replayed_dir` (each with `scene_graph_0.json`
/// and `external_sensor1/{frame:05}.png` for at least the key frames) and writes under `out`:
/// `QA/enact_ordering.jsonl` (ordered by L, then forward before inverse, then task, as ENACT
/// does), `QA/images/{type}/{task}/...`, `segmented_activities/{task}/...`,
/// `replayed_activities/{task}/scene_graph_0.json` with the key frames as full records (unless
/// `out/replayed_activities` is `replayed_dir` itself), and `generation_summary.json`.
/// Tasks run in parallel (rayon); the output does not depend on the thread count.
pub fn generate(
    replayed_dir: &Path,
    out: &Path,
    options: &GenerateOptions,
    progress: &(dyn Fn(GenerateProgress) + Sync),
) -> Result<GenerationSummary, PipelineError> {
    check_options(options)?;
    let tasks = task_names(replayed_dir)?;
    progress(GenerateProgress::Started { tasks: tasks.len() });
    let font = crate::pipeline::label::LabelFont::load()?;
    let outcomes: Vec<TaskOutcome> = tasks
        .par_iter()
        .map(|task| run_task(replayed_dir, out, task, options, &font, progress))
        .collect::<Result<_, _>>()?;

    let mut ordered: Vec<&GeneratedItem> = Vec::new();
    for step in 0..options.step_lengths.len() {
        for outcome in &outcomes {
            ordered.extend(&outcome.items[step].0);
        }
        for outcome in &outcomes {
            ordered.extend(&outcome.items[step].1);
        }
    }
    let jsonl_path = release::write_jsonl(out, &ordered)?;
    let items = ordered.len();
    let forward_items = outcomes
        .iter()
        .flat_map(|o| &o.items)
        .map(|(f, _)| f.len())
        .sum();
    let inverse_items = outcomes
        .iter()
        .flat_map(|o| &o.items)
        .map(|(_, i)| i.len())
        .sum();
    let summary = GenerationSummary {
        options: options.clone(),
        images: outcomes.iter().map(|o| o.images).sum(),
        tasks: outcomes.into_iter().map(|o| o.summary).collect(),
        items,
        forward_items,
        inverse_items,
        jsonl_path,
    };
    release::write_summary(out, &summary)?;
    progress(GenerateProgress::Finished {
        items: summary.items,
    });
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_graph::{SceneEdge, SceneGraph, SceneNode};

    fn seen(name: &str, states: &[&str]) -> SceneNode {
        let mut visibility = std::collections::BTreeMap::new();
        visibility.insert(
            "external_sensor1".to_string(),
            [500u64, 0, 0, 9, 9, 512, 512]
                .iter()
                .map(|&v| v.into())
                .collect(),
        );
        SceneNode {
            name: name.into(),
            // Distinct categories: same-category objects would make names ambiguous.
            category: name.rsplit_once('_').map(|(c, _)| c.to_string()),
            states: states.iter().map(|s| s.to_string()).collect(),
            visibility,
            parent: None,
        }
    }

    /// The world at frame n: the fridge opens at 20, the apple goes on the table at 40, the
    /// stove turns on at 60 (visible changes the generator can narrate).
    fn world(n: u64) -> SceneGraph {
        let mut fridge = seen("fridge_1", &[]);
        if n >= 20 {
            fridge.states.push("Open".into());
        }
        let mut stove = seen("stove_3", &[]);
        if n >= 60 {
            stove.states.push("ToggledOn".into());
        }
        let mut edges = vec![];
        if n >= 40 {
            edges.push(SceneEdge {
                from: "apple_2".into(),
                to: "table_4".into(),
                states: vec!["OnTop".into()],
            });
        }
        SceneGraph {
            nodes: vec![
                seen("robot_r1", &[]),
                fridge,
                seen("apple_2", &["Cold"]),
                stove,
                seen("table_4", &[]),
            ],
            edges,
        }
    }

    fn small_options() -> GenerateOptions {
        GenerateOptions {
            num_to_sample: 3,
            step_lengths: vec![3, 4],
            segmentation: SegmentationParams {
                skip_first_frames: 2,
                warmup_frames: 3,
                cosine_threshold: 0.98,
                min_gap: 10,
                stability_frames: 2,
                key_frames: KeyFrameTrigger::State,
            },
            ..GenerateOptions::default()
        }
    }

    /// Writes a replay of 90 full-record frames plus 512×512 images of every frame.
    fn write_replay(root: &Path, task: &str) {
        let dir = root.join(task);
        std::fs::create_dir_all(dir.join("external_sensor1")).unwrap();
        let mut doc = serde_json::Map::new();
        for n in 0..90u64 {
            let g = world(n);
            doc.insert(
                n.to_string(),
                serde_json::json!({"nodes": g.nodes, "edges": g.edges, "type": "full"}),
            );
        }
        std::fs::write(
            dir.join("scene_graph_0.json"),
            serde_json::to_vec(&doc).unwrap(),
        )
        .unwrap();
        let img = image::RgbImage::from_pixel(512, 512, image::Rgb([40, 90, 140]));
        for n in 0..90u64 {
            img.save(dir.join("external_sensor1").join(format!("{n:05}.png")))
                .unwrap();
        }
    }

    #[test]
    fn generates_a_small_release() {
        let root = tempfile::tempdir().unwrap();
        let replayed = root.path().join("replayed_activities");
        write_replay(&replayed, "toy_task_1");
        let out = root.path().join("data");
        let events = std::sync::Mutex::new(Vec::new());
        let summary = generate(&replayed, &out, &small_options(), &|e| {
            events.lock().unwrap().push(e)
        })
        .unwrap();
        let task = &summary.tasks[0];
        // Key frames: 4, then 22 (candidate 20 + 2), 42, 62.
        assert_eq!(task.key_frames, vec!["4", "22", "42", "62"]);
        // Every forward pair has 1..=3 sentences, so the DAG is complete: C(4,3), C(4,4).
        assert_eq!(task.valid_transitions, 6);
        assert_eq!(task.steps[0].valid_paths, 4);
        assert_eq!(task.steps[1].valid_paths, 1);
        assert_eq!(
            (task.steps[0].forward_items, task.steps[0].inverse_items),
            (3, 3)
        );
        assert_eq!(
            (task.steps[1].forward_items, task.steps[1].inverse_items),
            (1, 1)
        );
        assert_eq!(summary.items, 8);
        let jsonl = std::fs::read_to_string(&summary.jsonl_path).unwrap();
        let kinds: Vec<String> = jsonl
            .lines()
            .map(|l| crate::dataset::parse_release_line(l).unwrap().item_type)
            .collect();
        // Ordered by L, then forward before inverse.
        assert_eq!(kinds[0], "forward_world_modeling_3_steps");
        assert_eq!(kinds[3], "inverse_world_modeling_3_steps");
        assert_eq!(kinds[7], "inverse_world_modeling_4_steps");
        for line in jsonl.lines() {
            let item = crate::dataset::parse_release_line(line).unwrap();
            for image in &item.images {
                assert!(out.join(image).is_file(), "{image}");
            }
        }
        assert!(
            out.join("segmented_activities/toy_task_1/segmented_scene_graph_0.json")
                .is_file()
        );
        assert!(
            out.join("segmented_activities/toy_task_1/external_sensor1/00042.png")
                .is_file()
        );
        let copy = SceneGraphTimeline::load(
            &out.join("replayed_activities/toy_task_1/scene_graph_0.json"),
            crate::scene_graph::FrameSelection::All,
        )
        .unwrap();
        assert_eq!(copy.frame_ids().count(), 4);
        assert!(out.join("generation_summary.json").is_file());
        let events = events.into_inner().unwrap();
        assert_eq!(
            events.first(),
            Some(&GenerateProgress::Started { tasks: 1 })
        );
        assert_eq!(
            events.last(),
            Some(&GenerateProgress::Finished { items: 8 })
        );

        // Same seed, same release; another seed may differ but stays valid.
        let again = root.path().join("again");
        generate(&replayed, &again, &small_options(), &|_| {}).unwrap();
        assert_eq!(
            std::fs::read(&summary.jsonl_path).unwrap(),
            std::fs::read(again.join("QA/enact_ordering.jsonl")).unwrap()
        );
    }

    #[test]
    fn output_over_the_input_keeps_the_input_scene_graph() {
        let root = tempfile::tempdir().unwrap();
        let replayed = root.path().join("replayed_activities");
        write_replay(&replayed, "toy_task_1");
        let before = std::fs::read(replayed.join("toy_task_1/scene_graph_0.json")).unwrap();
        generate(&replayed, root.path(), &small_options(), &|_| {}).unwrap();
        let after = std::fs::read(replayed.join("toy_task_1/scene_graph_0.json")).unwrap();
        assert_eq!(before, after);
    }

    #[test]
    fn malformed_replays_name_file_and_frame() {
        let root = tempfile::tempdir().unwrap();
        let replayed = root.path().join("replayed_activities");
        let out = root.path().join("out");
        let run = || generate(&replayed, &out, &small_options(), &|_| {}).unwrap_err();

        std::fs::create_dir_all(&replayed).unwrap();
        assert!(matches!(run(), PipelineError::NoTasks { .. }));

        std::fs::create_dir_all(replayed.join("toy_task_1")).unwrap();
        let err = run();
        assert!(
            matches!(err, PipelineError::MissingSceneGraph { .. }),
            "{err}"
        );
        assert!(err.to_string().contains("toy_task_1/scene_graph_0.json"));

        write_replay(&replayed, "toy_task_1");
        let sg = replayed.join("toy_task_1/scene_graph_0.json");
        let text = std::fs::read_to_string(&sg).unwrap();
        std::fs::write(&sg, text.replacen("\"nodes\":[", "\"nodes\":[[", 1)).unwrap();
        let err = run();
        assert!(matches!(err, PipelineError::SceneGraph { .. }), "{err}");
        assert!(err.to_string().contains("in frame 0"), "{err}");

        write_replay(&replayed, "toy_task_1");
        std::fs::remove_file(replayed.join("toy_task_1/external_sensor1/00042.png")).unwrap();
        let err = run();
        match &err {
            PipelineError::MissingKeyFrameImage { frame, path, .. } => {
                assert_eq!(frame, "42");
                assert!(path.ends_with("external_sensor1/00042.png"));
            }
            other => panic!("unexpected {other}"),
        }

        write_replay(&replayed, "toy_task_1");
        std::fs::write(
            replayed.join("toy_task_1/external_sensor1/00042.png"),
            b"no png",
        )
        .unwrap();
        let err = run();
        assert!(
            matches!(err, PipelineError::Image { ref frame, .. } if frame == "42"),
            "{err}"
        );

        let short = GenerateOptions {
            segmentation: SegmentationParams {
                skip_first_frames: 45,
                ..SegmentationParams::enact_code()
            },
            ..small_options()
        };
        write_replay(&replayed, "toy_task_1");
        let err = generate(&replayed, &out, &short, &|_| {}).unwrap_err();
        assert!(err.to_string().contains("90 frames"), "{err}");

        let bad = GenerateOptions {
            step_lengths: vec![2],
            ..small_options()
        };
        assert!(matches!(
            generate(&replayed, &out, &bad, &|_| {}),
            Err(PipelineError::Options(_))
        ));
    }

    #[test]
    fn presets() {
        assert_eq!(
            SegmentationParams::default(),
            SegmentationParams::enact_code()
        );
        let paper = SegmentationParams::preset("paper").unwrap();
        assert_eq!((paper.cosine_threshold, paper.stability_frames), (0.97, 40));
        assert_eq!(paper.min_gap, 200);
        assert!(SegmentationParams::preset("other").is_none());
    }
}
