//! Importing an ENACT release (`QA/enact_ordering.jsonl` + images) into the store.
//!
//! Three phases, a batch of lines at a time, so memory holds one batch whatever the release's
//! size:
//! 1. read and validate the lines and every image they name (CPU work, on rayon threads);
//! 2. decide per item: new, unchanged, or changed (an error unless `replace`);
//! 3. write the batch's new and changed items in one short transaction of its own, reading
//!    only the frames not stored yet, under the hidden staging row of a staged import
//!    (`store::staged`) that no reader sees, with how far the import got.
//!
//! When every line is written and checked, one short transaction makes the staged items the
//! dataset's (the cut-over): readers see the old dataset or the new one, never part, and a
//! running server's writers wait for one batch at most, never for the whole import. A killed
//! import resumes after its last committed batch when run again with the same file and
//! options; `abandon` discards it.
//!
//! Kept across batches: each id's first line (duplicates) and each distinct frame's hash (the
//! report's count), a few dozen bytes per item.

use std::collections::{HashMap, HashSet};
use std::fmt;
use std::io::{BufRead, BufReader};
use std::path::{Component, Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::frames::{self, FrameStore};
use super::heavy::HeavyPool;
use crate::Lane;
use crate::core::audit::{Actor, AuditAction, AuditRecord};
use crate::core::credentials::random_token;
use crate::core::dataset::{FieldProblem, QaItem, parse_release_line};
use crate::core::semantics::{self, ItemSemantics, SignatureSource};
use crate::store;

/// Where a release lives: the QA file and the folder its image paths are relative to.
#[derive(Debug, Clone)]
pub struct ReleaseLocation {
    pub qa_file: PathBuf,
    pub root: PathBuf,
}

impl ReleaseLocation {
    /// Accepts a release directory (holding `QA/enact_ordering.jsonl`) or a path to a `.jsonl`
    /// file inside its `QA/` folder; image paths are relative to the parent of `QA/`.
    /// The release's own scene graphs, in ENACT's download layout (`QA/` beside
    /// `replayed_activities/`), when it has them.
    pub fn own_scene_graphs(&self) -> Option<PathBuf> {
        Some(self.root.join("replayed_activities")).filter(|dir| dir.is_dir())
    }

    pub fn resolve(path: &Path) -> Result<ReleaseLocation, ImportError> {
        if path.is_dir() {
            let qa_file = path.join("QA").join("enact_ordering.jsonl");
            if !qa_file.is_file() {
                return Err(ImportError::Location(format!(
                    "{} has no QA/enact_ordering.jsonl (give the release folder, or a .jsonl file)",
                    path.display()
                )));
            }
            return Ok(ReleaseLocation {
                qa_file,
                root: path.to_path_buf(),
            });
        }
        if path.is_file() {
            let root = path
                .parent()
                .and_then(Path::parent)
                .map(Path::to_path_buf)
                .unwrap_or_else(|| PathBuf::from("."));
            let root = if root.as_os_str().is_empty() {
                PathBuf::from(".")
            } else {
                root
            };
            return Ok(ReleaseLocation {
                qa_file: path.to_path_buf(),
                root,
            });
        }
        Err(ImportError::Location(format!(
            "{} does not exist",
            path.display()
        )))
    }
}

/// The dataset name an import takes when none is given: the release folder's name (`data` is
/// the folder or its `QA/*.jsonl` file), else `enact`.
pub fn default_dataset_name(data: &Path) -> String {
    let folder = if data.is_file() {
        data.parent().and_then(Path::parent)
    } else {
        Some(data)
    };
    folder
        .and_then(|f| std::fs::canonicalize(f).ok())
        .and_then(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
        .filter(|n| !n.is_empty())
        .unwrap_or_else(|| "enact".to_owned())
}

#[derive(Debug, Clone)]
pub struct ImportOptions {
    pub dataset: String,
    /// Import the valid rows and report the others, instead of refusing the whole file.
    pub skip_invalid: bool,
    /// Overwrite stored items whose content differs from the file.
    pub replace: bool,
    /// Told after each batch how far the import has got (the command line draws a bar).
    pub progress: Option<ImportObserver>,
    /// ENACT's `replayed_activities` folder: compute each item's transition signatures from
    /// `{task}/scene_graph_0.json`. Without it, inverse items get signatures parsed from their
    /// action text where possible (see `semantics`).
    pub scene_graphs: Option<PathBuf>,
    /// Lines validated and written per batch at most, each batch its own transaction
    /// ([`BATCH_LINES`] unless a caller tunes it); fewer while batches hold the write lock
    /// longer than 100 ms.
    pub batch_lines: usize,
    /// Asked between batches whether to stop: the import then ends with
    /// [`ImportError::Stopped`], its committed batches kept for a later run to resume.
    pub stop: Option<ImportStop>,
}

/// Whether an import should stop at its next batch (a paused or cancelled import job, or a
/// server shutting down).
#[derive(Clone)]
pub struct ImportStop(pub std::sync::Arc<dyn Fn() -> bool + Send + Sync>);

impl fmt::Debug for ImportStop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("ImportStop")
    }
}

/// How far an import has got: told after each batch and once at the end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImportProgress {
    /// Bytes of the QA file read so far, of `qa_bytes`.
    pub qa_bytes_read: u64,
    pub qa_bytes: u64,
    /// Lines read so far.
    pub rows: usize,
    /// Bytes of the images the lines read so far name.
    pub image_bytes: u64,
    /// Every line is read (the import may still be refused).
    pub finished: bool,
}

/// Who hears of an import's [`ImportProgress`].
#[derive(Clone)]
pub struct ImportObserver(pub std::sync::Arc<dyn Fn(&ImportProgress) + Send + Sync>);

impl fmt::Debug for ImportObserver {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("ImportObserver")
    }
}

impl ImportObserver {
    fn tell(observer: Option<&ImportObserver>, progress: ImportProgress) {
        if let Some(observer) = observer {
            (observer.0)(&progress);
        }
    }
}

/// A problem with one line of the QA file.
#[derive(Debug, Clone, Serialize)]
pub struct LineProblem {
    pub line: usize,
    pub item_id: Option<String>,
    #[serde(flatten)]
    pub problem: FieldProblem,
}

impl fmt::Display for LineProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}", self.line)?;
        if let Some(id) = &self.item_id {
            write!(f, " ({id})")?;
        }
        write!(f, ": {}", self.problem)
    }
}

/// A line left out by `--skip-invalid`, with every reason.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SkippedLine {
    pub line: usize,
    pub item_id: Option<String>,
    pub problems: Vec<FieldProblem>,
}

#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct ImportReport {
    pub dataset: String,
    pub qa_file: String,
    /// Records read (blank lines are not records).
    pub rows: usize,
    pub new_items: usize,
    pub replaced_items: usize,
    pub unchanged_items: usize,
    pub skipped: Vec<SkippedLine>,
    /// Distinct frames the imported items use.
    pub frames: usize,
    pub new_frames: usize,
    pub reused_frames: usize,
    /// Valid items of the file by where their transition signatures come from.
    pub scene_graph_items: usize,
    pub action_text_items: usize,
    pub exact_only_items: usize,
    /// Unchanged items whose stored signatures were added or refreshed.
    pub signatures_updated: usize,
    /// Items this run wrote (new and replaced ones; a resumed run leaves out those that
    /// earlier runs' committed batches wrote).
    pub items_written: usize,
    /// Records an earlier, interrupted run of the same import had committed, which this run
    /// resumed after.
    pub resumed_rows: usize,
    /// An unfinished import of the dataset from another file or with other options was
    /// discarded first.
    pub discarded_staged: bool,
    /// The longest any of the import's write transactions (a batch, or the cut-over) held the
    /// database's write lock, and the cut-over's, in milliseconds: how long a running server's
    /// writers may have waited for it.
    pub longest_transaction_ms: f64,
    pub cut_over_ms: f64,
    /// Verdicts of replaced items deleted after the cut-over (a submission per transaction);
    /// replaced items deleted after a cut-over that retired the dataset's old row (a few
    /// hundred per transaction); the longest of those transactions in milliseconds.
    pub swept_verdicts: u64,
    pub retired_items: u64,
    pub longest_sweep_ms: f64,
    pub seconds: f64,
    /// Public datasets holding some of the imported dataset's items or frames (its ground
    /// truth is out there); reported while its answers are hidden, as a new dataset's are.
    pub leaks: Vec<crate::core::red_flags::Leak>,
}

impl ImportReport {
    pub fn changed_anything(&self) -> bool {
        self.new_items + self.replaced_items + self.signatures_updated > 0
    }

    /// The one-line summary printed at the end of an import.
    pub fn summary_line(&self) -> String {
        let mut s = if self.new_items + self.replaced_items > 0 {
            format!(
                "imported {} items into dataset '{}' ({} new, {} replaced, {} unchanged)",
                self.new_items + self.replaced_items,
                self.dataset,
                self.new_items,
                self.replaced_items,
                self.unchanged_items
            )
        } else if self.signatures_updated > 0 {
            format!(
                "dataset '{}' already holds all {} valid items of the file; signatures added to {}",
                self.dataset, self.unchanged_items, self.signatures_updated
            )
        } else {
            format!(
                "nothing changed: dataset '{}' already holds all {} valid items of the file",
                self.dataset, self.unchanged_items
            )
        };
        s.push_str(&format!(
            "; semantic scoring: {} from scene graphs, {} from action text, {} exact-only",
            self.scene_graph_items, self.action_text_items, self.exact_only_items
        ));
        s.push_str(&format!(
            "; frames: {} ({} new, {} reused)",
            self.frames, self.new_frames, self.reused_frames
        ));
        if !self.skipped.is_empty() {
            s.push_str(&format!("; {} invalid rows skipped", self.skipped.len()));
        }
        if self.resumed_rows > 0 {
            s.push_str(&format!(
                "; resumed after {} records an interrupted run had written ({} items written now)",
                self.resumed_rows, self.items_written
            ));
        }
        if self.discarded_staged {
            s.push_str(
                "; an unfinished import from another file or with other options was discarded",
            );
        }
        if self.swept_verdicts > 0 {
            s.push_str(&format!(
                "; {} stored verdicts of replaced items deleted after the cut-over",
                self.swept_verdicts
            ));
        }
        if self.retired_items > 0 {
            s.push_str(&format!(
                "; {} replaced items deleted after the cut-over",
                self.retired_items
            ));
        }
        for leak in &self.leaks {
            s.push_str(&format!(
                "; warning: {} items and {} frames are also in public dataset '{}', so their \
                 answers are public",
                leak.items, leak.frames, leak.dataset
            ));
        }
        s.push_str(&format!("; {:.2} s", self.seconds));
        s
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error("{0}")]
    Location(String),
    #[error("cannot read {path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{file}: {} invalid rows of {rows}; nothing was imported (skip invalid rows to import the valid ones)", lines.len())]
    Invalid {
        file: String,
        rows: usize,
        /// Every problem, grouped by line.
        lines: Vec<SkippedLine>,
    },
    #[error("{file}: {} items already exist in dataset '{dataset}' with different content; nothing was imported (replace changed items to overwrite them)", conflicts.len())]
    Conflict {
        file: String,
        dataset: String,
        conflicts: Vec<LineProblem>,
    },
    #[error("image {path} changed on disk during the import; nothing was imported")]
    ImageChanged { path: String },
    #[error("cannot serialise the signatures of item {item_id}: {message}")]
    Signatures { item_id: String, message: String },
    #[error("database error: {0}")]
    Database(#[from] sqlx::Error),
    /// Writing frames to the object store failed; nothing was imported.
    #[error("{0}; nothing was imported")]
    FrameStorage(String),
    /// The unfinished import of the dataset cannot go on.
    #[error("the unfinished import of dataset '{dataset}': {message}")]
    Staged { dataset: String, message: String },
    #[error(
        "the import into dataset '{dataset}' stopped after {lines} lines; run it again to resume"
    )]
    Stopped { dataset: String, lines: i64 },
    #[error(
        "another run of the import into dataset '{dataset}' took it over (or it was abandoned); this one stopped, nothing of it is visible"
    )]
    TakenOver { dataset: String },
}

impl ImportError {
    /// Every individual problem, one per line of output.
    pub fn details(&self) -> Vec<String> {
        match self {
            ImportError::Invalid { lines, .. } => lines
                .iter()
                .flat_map(|l| {
                    l.problems.iter().map(|p| {
                        LineProblem {
                            line: l.line,
                            item_id: l.item_id.clone(),
                            problem: p.clone(),
                        }
                        .to_string()
                    })
                })
                .collect(),
            ImportError::Conflict { conflicts, .. } => {
                conflicts.iter().map(ToString::to_string).collect()
            }
            _ => Vec::new(),
        }
    }
}

/// What validation learnt about one image file.
#[derive(Debug, Clone)]
struct FrameFacts {
    sha256: String,
    width: u32,
    height: u32,
    /// Size of the file.
    bytes: u64,
}

struct ValidRow {
    line: usize,
    item: QaItem,
    frames: Vec<FrameFacts>,
    semantics: Option<ItemSemantics>,
}

/// One batch of the QA file, validated.
struct Validated {
    valid: Vec<ValidRow>,
    invalid: Vec<SkippedLine>,
}

/// How many lines are validated and written at a time: memory holds one batch, whatever the
/// size of the file, and a running server's writers wait for one batch's transaction at most.
pub const BATCH_LINES: usize = 64;

/// A path from the QA file, checked to stay inside the release root.
fn image_path(root: &Path, relative: &str) -> Result<PathBuf, String> {
    let rel = Path::new(relative);
    let escapes = rel.components().any(|c| {
        matches!(
            c,
            Component::ParentDir | Component::RootDir | Component::Prefix(_)
        )
    });
    if escapes {
        return Err(format!(
            "{relative:?} must be a relative path inside the release folder"
        ));
    }
    Ok(root.join(rel))
}

fn inspect_image(path: &Path) -> Result<FrameFacts, String> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(format!("image file not found: {}", path.display()));
        }
        Err(e) => return Err(format!("cannot read image {}: {e}", path.display())),
    };
    let image = image::load_from_memory(&bytes)
        .map_err(|e| format!("not a decodable image: {}: {e}", path.display()))?;
    Ok(FrameFacts {
        sha256: hex::encode(Sha256::digest(&bytes)),
        width: image.width(),
        height: image.height(),
        bytes: bytes.len() as u64,
    })
}

/// Reads and validates the QA file a batch at a time: every line, every image it names and
/// the scene graphs, with every problem found. Keeps across batches only what later lines are
/// checked against (each id's first line).
struct Validator {
    location: ReleaseLocation,
    scene_graphs: Option<PathBuf>,
    lines: std::io::Lines<BufReader<std::fs::File>>,
    /// Lines read so far (blank ones included), records among them, bytes of the file read.
    lines_read: usize,
    rows: usize,
    bytes_read: u64,
    /// Image bytes read so far.
    image_bytes: u64,
    first_line: HashMap<String, usize>,
    batch_lines: usize,
}

impl Validator {
    fn open(
        location: &ReleaseLocation,
        scene_graphs: Option<&Path>,
        batch_lines: usize,
    ) -> Result<Self, ImportError> {
        let file = std::fs::File::open(&location.qa_file).map_err(|source| ImportError::Io {
            path: location.qa_file.display().to_string(),
            source,
        })?;
        Ok(Validator {
            location: location.clone(),
            scene_graphs: scene_graphs.map(Path::to_path_buf),
            lines: BufReader::new(file).lines(),
            lines_read: 0,
            rows: 0,
            bytes_read: 0,
            image_bytes: 0,
            first_line: HashMap::new(),
            batch_lines,
        })
    }

    /// The next record of the file (blank lines are counted and passed over), `None` at its
    /// end.
    fn next_record(&mut self) -> Result<Option<String>, ImportError> {
        for line in self.lines.by_ref() {
            let line = line.map_err(|source| ImportError::Io {
                path: self.location.qa_file.display().to_string(),
                source,
            })?;
            self.lines_read += 1;
            self.bytes_read += line.len() as u64 + 1;
            if !line.trim().is_empty() {
                self.rows += 1;
                return Ok(Some(line));
            }
        }
        Ok(None)
    }

    /// Moves past the first `lines` lines (written by an earlier run), remembering each valid
    /// id's first line as [`Validator::next_batch`] would; returns the image paths of the
    /// valid records among them (`skipped` lists the lines that were invalid).
    fn skip_lines(
        &mut self,
        lines: usize,
        skipped: &HashSet<usize>,
    ) -> Result<HashSet<String>, ImportError> {
        let mut paths = HashSet::new();
        while self.lines_read < lines {
            let Some(line) = self.next_record()? else {
                break;
            };
            if let Ok(item) = parse_release_line(&line) {
                self.first_line
                    .entry(item.id.clone())
                    .or_insert(self.lines_read);
                if !skipped.contains(&self.lines_read) {
                    paths.extend(item.images);
                }
            }
        }
        Ok(paths)
    }

    /// The next batch of up to [`BATCH_LINES`] records, `None` at the end of the file.
    fn next_batch(&mut self) -> Result<Option<Validated>, ImportError> {
        let mut parsed: Vec<(usize, Result<QaItem, Vec<FieldProblem>>)> = Vec::new();
        // The size of the images the batch names, from the file system (the images are read
        // later): a batch of large images is cut short, so its transaction stays short.
        let mut named_bytes = 0u64;
        while parsed.len() < self.batch_lines && named_bytes < BATCH_IMAGE_BYTES {
            let Some(line) = self.next_record()? else {
                break;
            };
            let item = parse_release_line(&line);
            if let Ok(item) = &item {
                named_bytes += item
                    .images
                    .iter()
                    .filter_map(|p| image_path(&self.location.root, p).ok())
                    .filter_map(|p| std::fs::metadata(p).ok())
                    .map(|m| m.len())
                    .sum::<u64>();
            }
            parsed.push((self.lines_read, item));
        }
        if parsed.is_empty() {
            return Ok(None);
        }

        // Duplicate ids: the first occurrence stands, later ones are problems.
        for (line, result) in &mut parsed {
            if let Ok(item) = result {
                if let Some(first) = self.first_line.get(&item.id) {
                    *result = Err(vec![FieldProblem::new(
                        "id",
                        format!("duplicate id {:?}, first seen on line {first}", item.id),
                    )]);
                } else {
                    self.first_line.insert(item.id.clone(), *line);
                }
            }
        }

        let paths: HashSet<&str> = parsed
            .iter()
            .filter_map(|(_, r)| r.as_ref().ok())
            .flat_map(|item| item.images.iter().map(String::as_str))
            .collect();
        let root = &self.location.root;
        let facts: HashMap<String, Result<FrameFacts, String>> = paths
            .into_par_iter()
            .map(|p| {
                let result = image_path(root, p).and_then(|full| inspect_image(&full));
                (p.to_owned(), result)
            })
            .collect();
        self.image_bytes += facts
            .values()
            .filter_map(|f| f.as_ref().ok())
            .map(|f| f.bytes)
            .sum::<u64>();

        let mut valid = Vec::new();
        let mut invalid = Vec::new();
        for (line, result) in parsed {
            match result {
                Err(problems) => invalid.push(SkippedLine {
                    line,
                    item_id: None,
                    problems,
                }),
                Ok(item) => {
                    let mut frames = Vec::with_capacity(item.images.len());
                    let mut problems = Vec::new();
                    for (i, path) in item.images.iter().enumerate() {
                        match facts.get(path.as_str()) {
                            Some(Ok(f)) => frames.push(f.clone()),
                            Some(Err(message)) => {
                                problems.push(FieldProblem::new(format!("images[{i}]"), message))
                            }
                            None => problems.push(FieldProblem::new(
                                format!("images[{i}]"),
                                "image was not checked",
                            )),
                        }
                    }
                    if problems.is_empty() {
                        valid.push(ValidRow {
                            line,
                            item,
                            frames,
                            semantics: None,
                        });
                    } else {
                        invalid.push(SkippedLine {
                            line,
                            item_id: Some(item.id),
                            problems,
                        });
                    }
                }
            }
        }

        let items: Vec<&QaItem> = valid.iter().map(|r| &r.item).collect();
        let semantics = semantics::for_items(self.scene_graphs.as_deref(), &items);
        let mut kept = Vec::with_capacity(valid.len());
        for (mut row, result) in valid.into_iter().zip(semantics) {
            match result {
                Ok(s) => {
                    row.semantics = s;
                    kept.push(row);
                }
                Err(problems) => invalid.push(SkippedLine {
                    line: row.line,
                    item_id: Some(row.item.id),
                    problems,
                }),
            }
        }
        invalid.sort_by_key(|s| s.line);
        Ok(Some(Validated {
            valid: kept,
            invalid,
        }))
    }
}

/// Identity of an item's content: its fields and the bytes of its images.
fn content_hash(row: &ValidRow) -> String {
    let item = &row.item;
    let canonical = serde_json::json!({
        "id": item.id,
        "type": item.item_type,
        "task_name": item.task_name,
        "key_frame_ids": item.key_frame_ids,
        "images": item.images,
        "frames": row.frames.iter().map(|f| f.sha256.as_str()).collect::<Vec<_>>(),
        "question": item.question,
        "gt_answer": item.gt_answer,
    });
    hex::encode(Sha256::digest(canonical.to_string().as_bytes()))
}

/// Imports a release into `options.dataset`, staged: each batch of lines is validated, then
/// its new and changed items are written in their own short transaction under a hidden
/// staging row that no reader sees (`store::staged`), with how far the import got; when every
/// line is written and checked, one short transaction moves them into the dataset. A failed
/// import (invalid lines without `skip_invalid`, conflicts without `replace`) leaves nothing
/// visible and removes what it staged; a killed one is resumed by running it again with the
/// same file and options. After the first invalid line or conflicting item nothing more is
/// written, but every line is still checked so the error lists every problem.
pub async fn import_release(
    hub: &super::Hub,
    actor: &Actor,
    path: &Path,
    options: &ImportOptions,
) -> Result<ImportReport, ImportError> {
    let started = Instant::now();
    let location = ReleaseLocation::resolve(path)?;
    let file = location.qa_file.display().to_string();
    let qa_bytes = std::fs::metadata(&location.qa_file)
        .map(|m| m.len())
        .unwrap_or(0);
    let file_sha256 = file_sha256(hub.heavy(), &location.qa_file).await?;
    let run_token = random_token();
    let batch_lines = options.batch_lines.max(1);
    let (staged, discarded) =
        start_staged(hub, options, &location, &file_sha256, &run_token).await?;

    let mut report = if staged.lines_done > 0 {
        let mut report: ImportReport =
            serde_json::from_str(&staged.report).map_err(|e| ImportError::Staged {
                dataset: options.dataset.clone(),
                message: format!("its recorded progress cannot be read ({e}); abandon it"),
            })?;
        report.items_written = 0;
        report.resumed_rows = usize::try_from(staged.rows_done).unwrap_or(0);
        report
    } else {
        ImportReport::default()
    };
    report.dataset = options.dataset.clone();
    report.qa_file = file.clone();
    report.discarded_staged = discarded;

    // The first batch is small; later ones grow while they hold the lock briefly.
    let mut validator = Validator::open(
        &location,
        options.scene_graphs.as_deref(),
        batch_lines.min(FIRST_BATCH_LINES),
    )?;
    let mut distinct_frames: HashSet<String> = HashSet::new();
    if staged.lines_done > 0 {
        let lines = usize::try_from(staged.lines_done).unwrap_or(0);
        let skipped: HashSet<usize> = report.skipped.iter().map(|s| s.line).collect();
        (validator, distinct_frames) = skim(hub.heavy(), validator, lines, skipped).await?;
    }
    let observer = options.progress.as_ref();
    let told = |validator: &Validator, finished: bool| ImportProgress {
        qa_bytes_read: validator.bytes_read,
        qa_bytes,
        rows: validator.rows,
        image_bytes: validator.image_bytes,
        finished,
    };
    ImportObserver::tell(observer, told(&validator, false));

    // What the file is checked against: the dataset as it is now (the cut-over refuses if it
    // changed meanwhile).
    let stored_hashes = match staged.target {
        Some(id) => store::items::content_hashes(&mut hub.pool().acquire().await?, id).await?,
        None => HashMap::new(),
    };
    let mut invalid: Vec<SkippedLine> = std::mem::take(&mut report.skipped);
    let mut conflicts: Vec<LineProblem> = Vec::new();
    let mut lines_done = staged.lines_done;
    let frame_store = hub.frame_store();

    let (mut validator_slot, mut next) = next_batch(hub.heavy(), validator).await?;
    while let Some(batch) = next {
        invalid.extend(batch.invalid);
        let refused = !options.skip_invalid && !invalid.is_empty();

        let mut to_write = Vec::new();
        for row in &batch.valid {
            distinct_frames.extend(row.frames.iter().map(|f| f.sha256.clone()));
            match row.semantics.as_ref().map(|s| s.source) {
                Some(SignatureSource::SceneGraph) => report.scene_graph_items += 1,
                Some(SignatureSource::ActionText) => report.action_text_items += 1,
                None => report.exact_only_items += 1,
            }
            let hash = content_hash(row);
            match stored_hashes.get(&row.item.id) {
                Some(stored) if *stored == hash => report.unchanged_items += 1,
                Some(_) if !options.replace => conflicts.push(LineProblem {
                    line: row.line,
                    item_id: Some(row.item.id.clone()),
                    problem: FieldProblem::new(
                        "",
                        "an item with this id is stored with different content",
                    ),
                }),
                Some(_) => to_write.push((row, hash, true)),
                None => to_write.push((row, hash, false)),
            }
        }
        // Once the import is bound to fail, the rest of the file is only checked.
        if !refused && conflicts.is_empty() {
            let refreshes = match staged.target {
                Some(id) => signature_refreshes(hub, id, &batch.valid, &stored_hashes).await?,
                None => Vec::new(),
            };
            let frames = read_new_frames(hub, frame_store, &location.root, &to_write).await?;
            let began = Instant::now();
            let mut tx = hub.begin_in(Lane::Bulk).await?;
            // Timed from when the lock is held.
            let held = Instant::now();
            write_items(&mut tx, staged.staging, &to_write, &frames, &mut report).await?;
            for (item_id, semantics) in &refreshes {
                let json = signatures_json(item_id, semantics)?;
                store::staged::stage_signatures(
                    &mut tx,
                    staged.id,
                    item_id,
                    semantics.source,
                    &json,
                )
                .await?;
            }
            report.signatures_updated += refreshes.len();
            report.items_written += to_write.len();
            let mut recorded = report.clone();
            recorded.skipped.clone_from(&invalid);
            let recorded = serde_json::to_string(&recorded).map_err(|e| ImportError::Staged {
                dataset: options.dataset.clone(),
                message: format!("cannot record its progress: {e}"),
            })?;
            let validator = &validator_slot;
            let progress = store::staged::StagedProgress {
                lines_done: to_i64(validator.lines_read),
                rows_done: to_i64(validator.rows),
                bytes_done: to_i64(validator.bytes_read as usize),
                report: &recorded,
            };
            if !store::staged::record_batch(&mut tx, staged.id, &run_token, lines_done, &progress)
                .await?
            {
                return Err(ImportError::TakenOver {
                    dataset: options.dataset.clone(),
                });
            }
            tx.commit().await?;
            let held = held.elapsed().as_secs_f64() * 1000.0;
            report.longest_transaction_ms = report.longest_transaction_ms.max(held);
            validator_slot.batch_lines =
                next_batch_lines(validator_slot.batch_lines, batch_lines, held);
            tracing::debug!(
                lines = lines_done,
                waited_ms = (began.elapsed().as_secs_f64() * 1000.0 - held),
                held_ms = held,
                "import batch committed"
            );
            lines_done = progress.lines_done;
        }
        ImportObserver::tell(observer, told(&validator_slot, false));
        if options.stop.as_ref().is_some_and(|stop| (stop.0)()) {
            return Err(ImportError::Stopped {
                dataset: options.dataset.clone(),
                lines: lines_done,
            });
        }
        (validator_slot, next) = next_batch(hub.heavy(), validator_slot).await?;
    }
    let validator = validator_slot;
    ImportObserver::tell(observer, told(&validator, true));
    report.rows = validator.rows;
    invalid.sort_by_key(|s| s.line);
    if !invalid.is_empty() && !options.skip_invalid {
        discard(hub, &staged).await?;
        return Err(ImportError::Invalid {
            file,
            rows: report.rows,
            lines: invalid,
        });
    }
    if !conflicts.is_empty() {
        discard(hub, &staged).await?;
        return Err(ImportError::Conflict {
            file,
            dataset: options.dataset.clone(),
            conflicts,
        });
    }
    report.skipped = invalid;
    report.frames = distinct_frames.len();
    // Frames of unchanged items are reused as well.
    report.reused_frames = report.frames.saturating_sub(report.new_frames);
    let real_scene = options.scene_graphs.as_deref().and_then(real_world_scene);
    report.cut_over_ms = publish(
        hub,
        actor,
        &staged,
        &run_token,
        &location,
        &report,
        real_scene.as_deref(),
    )
    .await?;
    report.longest_transaction_ms = report.longest_transaction_ms.max(report.cut_over_ms);
    // The import is in: a sweep that fails is logged, never turned into a failed import (the
    // next import or server start finishes it).
    match sweep_replaced_verdicts(hub).await {
        Ok(swept) => {
            report.swept_verdicts = swept.verdicts;
            report.longest_sweep_ms = swept.longest_ms;
            report.longest_transaction_ms = report.longest_transaction_ms.max(swept.longest_ms);
        }
        Err(e) => {
            tracing::warn!(dataset = %options.dataset, error = %e, "sweeping the replaced items' verdicts failed; the next import or server start finishes it");
        }
    }
    match delete_retired_datasets(hub).await {
        Ok(deleted) => {
            report.retired_items = deleted.items;
            report.longest_sweep_ms = report.longest_sweep_ms.max(deleted.longest_ms);
            report.longest_transaction_ms = report.longest_transaction_ms.max(deleted.longest_ms);
        }
        Err(e) => {
            tracing::warn!(dataset = %options.dataset, error = %e, "deleting the replaced items failed; the next import or server start finishes it");
        }
    }
    // The import is in: a failed check is logged, never turned into a failed import.
    match super::red_flags::leak_at_import(hub, actor, &options.dataset).await {
        Ok(leaks) => report.leaks = leaks,
        Err(e) => {
            tracing::warn!(dataset = %options.dataset, error = %e, "the leak check after an import failed");
        }
    }
    report.seconds = started.elapsed().as_secs_f64();
    Ok(report)
}

/// Image bytes a batch names at most (one line's may exceed it): with new frames they are
/// what its transaction writes.
const BATCH_IMAGE_BYTES: u64 = 4 << 20;

/// Lines of an import's first batch (at most), before it knows how fast the database writes.
const FIRST_BATCH_LINES: usize = 16;

/// How long one batch's transaction should hold the write lock at most: a running server's
/// writers wait for it.
const BATCH_TARGET_MS: f64 = 100.0;

/// The lines of the next batch: halved after a batch that held the lock longer than
/// [`BATCH_TARGET_MS`] (a slow database, or a busy machine), grown back towards `most` after
/// one that held it under a quarter of it.
fn next_batch_lines(lines: usize, most: usize, held_ms: f64) -> usize {
    if held_ms > BATCH_TARGET_MS {
        (lines / 2).max(1)
    } else if held_ms < BATCH_TARGET_MS / 4.0 {
        (lines * 2).min(most)
    } else {
        lines
    }
}

fn to_i64(n: usize) -> i64 {
    i64::try_from(n).unwrap_or(i64::MAX)
}

/// Finds the staged import of `options.dataset` to resume (same file, same options, the
/// dataset as it was) and takes it over, or discards a stale one and starts afresh. Returns
/// the staged import and whether a stale one was discarded.
async fn start_staged(
    hub: &super::Hub,
    options: &ImportOptions,
    location: &ReleaseLocation,
    file_sha256: &str,
    run_token: &str,
) -> Result<(store::staged::StagedImport, bool), ImportError> {
    let fingerprint = options_fingerprint(options);
    let source = location.root.display().to_string();
    let mut discarded = false;
    loop {
        let mut tx = hub.begin_in(Lane::Bulk).await?;
        let target = store::datasets::by_name(&mut tx, &options.dataset)
            .await?
            .map(|d| d.id);
        match store::staged::for_dataset(&mut tx, &options.dataset).await? {
            Some(staged)
                if staged.file_sha256 == file_sha256
                    && staged.options == fingerprint
                    && staged.target == target =>
            {
                store::staged::claim(&mut tx, staged.id, run_token).await?;
                tx.commit().await?;
                return Ok((staged, discarded));
            }
            Some(stale) => {
                tx.rollback().await?;
                discard(hub, &stale).await?;
                discarded = true;
            }
            None => {
                let staged = store::staged::create(
                    &mut tx,
                    &options.dataset,
                    &source,
                    target,
                    file_sha256,
                    &fingerprint,
                    run_token,
                )
                .await?;
                tx.commit().await?;
                return Ok((staged, discarded));
            }
        }
    }
}

/// What of the options changes what an import writes; a resumed import must match it.
fn options_fingerprint(options: &ImportOptions) -> String {
    serde_json::json!({
        "replace": options.replace,
        "skip_invalid": options.skip_invalid,
        "scene_graphs": options.scene_graphs.as_ref().map(|p| p.display().to_string()),
    })
    .to_string()
}

/// sha256 of a file, read on the heavy-work pool.
async fn file_sha256(heavy: &HeavyPool, path: &Path) -> Result<String, ImportError> {
    let path = path.to_path_buf();
    heavy
        .run_waiting(move || {
            let mut file = std::fs::File::open(&path).map_err(|source| ImportError::Io {
                path: path.display().to_string(),
                source,
            })?;
            let mut hasher = Sha256::new();
            std::io::copy(&mut file, &mut hasher).map_err(|source| ImportError::Io {
                path: path.display().to_string(),
                source,
            })?;
            Ok(hex::encode(hasher.finalize()))
        })
        .await
}

/// The scene(s) of a release made from exported real-world episodes: `Some` when every task
/// folder of its scene graphs holds the marker of hand-marked key frames (scenes joined by
/// ", " when they differ), `None` for anything else (a simulator's replays).
fn real_world_scene(replayed: &Path) -> Option<String> {
    let mut scenes = std::collections::BTreeSet::new();
    let mut tasks = 0;
    for entry in std::fs::read_dir(replayed).ok()?.flatten() {
        if !entry.path().is_dir() {
            continue;
        }
        tasks += 1;
        let marker = entry
            .path()
            .join(crate::core::pipeline::marked::MARKED_KEY_FRAMES_FILE);
        let text = std::fs::read(marker).ok()?;
        let marked: crate::core::pipeline::marked::MarkedKeyFrames =
            serde_json::from_slice(&text).ok()?;
        if marked.origin != "real" {
            return None;
        }
        if !marked.scene.is_empty() {
            scenes.insert(marked.scene);
        }
    }
    (tasks > 0).then(|| scenes.into_iter().collect::<Vec<_>>().join(", "))
}

/// The one short transaction that makes a fully written staged import the dataset's current
/// version (or, if it wrote nothing, just removes it). Returns how long it held the write
/// lock, in milliseconds.
async fn publish(
    hub: &super::Hub,
    actor: &Actor,
    staged: &store::staged::StagedImport,
    run_token: &str,
    location: &ReleaseLocation,
    report: &ImportReport,
    real_scene: Option<&str>,
) -> Result<f64, ImportError> {
    let dataset = &report.dataset;
    let mut tx = hub.begin_in(Lane::Bulk).await?;
    let held = Instant::now();
    match store::staged::for_dataset(&mut tx, dataset).await? {
        Some(current) if current.id == staged.id && current.run_token == run_token => {}
        _ => {
            return Err(ImportError::TakenOver {
                dataset: dataset.clone(),
            });
        }
    }
    let target = store::datasets::by_name(&mut tx, dataset).await?;
    if target.as_ref().map(|d| d.id) != staged.target {
        return Err(ImportError::Staged {
            dataset: dataset.clone(),
            message: "the dataset was created or removed while the import ran; run it again"
                .to_owned(),
        });
    }
    let wrote_items = report.new_items + report.replaced_items > 0;
    match &target {
        None if wrote_items => store::staged::publish_as_new(&mut tx, staged).await?,
        None => store::staged::remove(&mut tx, staged).await?,
        Some(target) => {
            let source = location.root.display().to_string();
            let published =
                store::staged::publish_into(&mut tx, staged, target.id, &source).await?;
            tracing::info!(
                dataset = %dataset,
                replaced = published.replaced,
                kept = published.kept,
                swapped = published.swapped,
                "cut-over"
            );
            // Stored error analyses were computed from the old items or signatures.
            if report.signatures_updated + report.replaced_items > 0 {
                store::submissions::clear_error_analyses(&mut tx, published.dataset).await?;
            }
            // Human verdicts were judged with the old signatures (answers on replaced items
            // went with them): judged again here, in the same transaction.
            if report.signatures_updated > 0 {
                super::rescore::rejudge_dataset(&mut tx, published.dataset).await?;
            }
        }
    }
    if let Some(scene) = real_scene {
        store::datasets::set_origin(&mut tx, dataset, "real", scene).await?;
    }
    if wrote_items || report.signatures_updated > 0 {
        store::bump_content_generation(&mut tx).await?;
    }
    let detail = format!(
        "{}: {} new, {} replaced, {} unchanged items; {} signature tables updated; {} lines \
         skipped",
        report.qa_file,
        report.new_items,
        report.replaced_items,
        report.unchanged_items,
        report.signatures_updated,
        report.skipped.len()
    );
    log_import(&mut tx, actor, dataset, detail).await?;
    tx.commit().await?;
    Ok(held.elapsed().as_secs_f64() * 1000.0)
}

/// The audit log's entry for what an import did to `dataset`.
async fn log_import(
    tx: &mut store::Tx,
    actor: &Actor,
    dataset: &str,
    detail: String,
) -> Result<(), sqlx::Error> {
    let record = AuditRecord {
        actor,
        action: AuditAction::DatasetImport,
        target: format!("dataset {dataset}"),
        dataset: Some(dataset),
        detail,
    };
    store::audit::insert(tx, &record).await
}

/// What [`sweep_replaced_verdicts`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Swept {
    pub submissions: u64,
    pub verdicts: u64,
    /// The longest of its transactions, in milliseconds.
    pub longest_ms: f64,
}

/// Deletes the verdicts replacing imports left naming no item (`store::staged::publish_into`),
/// one submission per short bulk transaction, until no sweep is pending. Run after every
/// cut-over and when a server starts, so a sweep a killed process left is finished by the
/// next; two processes sweeping at once delete nothing twice.
pub async fn sweep_replaced_verdicts(hub: &super::Hub) -> Result<Swept, sqlx::Error> {
    let mut swept = Swept::default();
    let pending = {
        let mut conn = hub.pool().acquire().await?;
        store::staged::verdict_sweeps(&mut conn).await?
    };
    for sweep in pending {
        loop {
            let mut tx = hub.begin_in(Lane::Bulk).await?;
            let held = Instant::now();
            let (deleted, more) = store::staged::sweep_submission(&mut tx, &sweep).await?;
            tx.commit().await?;
            swept.longest_ms = swept.longest_ms.max(held.elapsed().as_secs_f64() * 1000.0);
            swept.verdicts += deleted;
            if !more {
                break;
            }
            swept.submissions += 1;
        }
    }
    Ok(swept)
}

/// How many rows one cleanup transaction deletes.
const DELETE_BATCH: i64 = 256;

/// What [`delete_retired_datasets`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RetiredDeleted {
    pub datasets: u64,
    pub items: u64,
    /// Rows written to a retired row after its cut-over, pointed at its successor.
    pub repointed: u64,
    /// The longest of its transactions, in milliseconds.
    pub longest_ms: f64,
}

/// Deletes the rows swapping cut-overs retired (`store::staged::publish_into`): their items a
/// few hundred per short bulk transaction, then the row, then the frames nothing uses any
/// more. Run after every cut-over and when a server starts, so what a killed process left is
/// finished by the next; two processes at it at once delete nothing twice.
pub async fn delete_retired_datasets(hub: &super::Hub) -> Result<RetiredDeleted, sqlx::Error> {
    let mut done = RetiredDeleted::default();
    let pending = {
        let mut conn = hub.pool().acquire().await?;
        store::staged::retired(&mut conn).await?
    };
    if pending.is_empty() {
        return Ok(done);
    }
    for retired in pending {
        let (items, longest_ms) = delete_items_in_batches(hub, retired.dataset).await?;
        done.items += items;
        done.longest_ms = done.longest_ms.max(longest_ms);
        let mut tx = hub.begin_in(Lane::Bulk).await?;
        let held = Instant::now();
        done.repointed += store::staged::delete_retired(&mut tx, &retired).await?;
        tx.commit().await?;
        done.longest_ms = done.longest_ms.max(held.elapsed().as_secs_f64() * 1000.0);
        done.datasets += 1;
    }
    if done.repointed > 0 {
        tracing::warn!(
            rows = done.repointed,
            "rows written to a replaced dataset's retired row after its cut-over were moved to the dataset"
        );
    }
    delete_unused_frames(hub).await?;
    Ok(done)
}

/// Deletes every item of a hidden `datasets` row (a staged import's or a retired one's),
/// [`DELETE_BATCH`] per short bulk transaction; returns how many, and the longest of those
/// transactions in milliseconds.
async fn delete_items_in_batches(
    hub: &super::Hub,
    dataset: i64,
) -> Result<(u64, f64), sqlx::Error> {
    let (mut items, mut longest_ms) = (0, 0.0_f64);
    loop {
        let mut tx = hub.begin_in(Lane::Bulk).await?;
        let held = Instant::now();
        let deleted = store::staged::delete_items(&mut tx, dataset, DELETE_BATCH).await?;
        tx.commit().await?;
        longest_ms = longest_ms.max(held.elapsed().as_secs_f64() * 1000.0);
        items += deleted;
        if deleted == 0 {
            return Ok((items, longest_ms));
        }
    }
}

/// Removes a staged import and everything it wrote, a few hundred rows per transaction.
async fn discard(
    hub: &super::Hub,
    staged: &store::staged::StagedImport,
) -> Result<(), sqlx::Error> {
    // Its rows go in many short transactions: first, in one, it stops being resumable, or a
    // run killed half-way through the deletes would leave a staged import that a later run of
    // the same file takes over and publishes with part of its rows gone.
    let mut tx = hub.begin_in(Lane::Bulk).await?;
    store::staged::forget(&mut tx, staged.id).await?;
    tx.commit().await?;
    delete_items_in_batches(hub, staged.staging).await?;
    let mut tx = hub.begin_in(Lane::Bulk).await?;
    store::staged::remove(&mut tx, staged).await?;
    tx.commit().await?;
    delete_unused_frames(hub).await
}

/// Deletes every stored frame that no item or episode uses (left by a discarded import, or by
/// an incomplete episode removed), a few hundred per transaction.
pub(super) async fn delete_unused_frames(hub: &super::Hub) -> Result<(), sqlx::Error> {
    loop {
        let mut tx = hub.begin_in(Lane::Bulk).await?;
        let deleted = store::staged::delete_unused_frames(&mut tx, DELETE_BATCH).await?;
        tx.commit().await?;
        if deleted == 0 {
            return Ok(());
        }
    }
}

/// A staged import, as `import --abandon` and the list of stale ones show it.
#[derive(Debug, Clone, Serialize)]
pub struct StagedSummary {
    pub dataset: String,
    pub qa_file_sha256: String,
    /// Records of the file written by committed batches.
    pub rows_done: i64,
    pub started_at: String,
    pub updated_at: String,
}

impl From<&store::staged::StagedImport> for StagedSummary {
    fn from(s: &store::staged::StagedImport) -> Self {
        StagedSummary {
            dataset: s.dataset.clone(),
            qa_file_sha256: s.file_sha256.clone(),
            rows_done: s.rows_done,
            started_at: s.started_at.clone(),
            updated_at: s.updated_at.clone(),
        }
    }
}

/// Discards the staged (unfinished) import of `dataset`; `None` if there is none. The
/// dataset itself is untouched.
pub async fn abandon(
    hub: &super::Hub,
    actor: &Actor,
    dataset: &str,
) -> Result<Option<StagedSummary>, ImportError> {
    let staged = store::staged::for_dataset(&mut hub.pool().acquire().await?, dataset).await?;
    let Some(staged) = staged else {
        return Ok(None);
    };
    discard(hub, &staged).await?;
    let summary = StagedSummary::from(&staged);
    let mut tx = hub.begin_in(Lane::Bulk).await?;
    let detail = format!(
        "abandoned the unfinished import of {} records (file sha256 {})",
        summary.rows_done, summary.qa_file_sha256
    );
    log_import(&mut tx, actor, dataset, detail).await?;
    tx.commit().await?;
    Ok(Some(summary))
}

/// Staged imports no batch was written to for `hours` hours (killed and never resumed).
pub async fn stale(hub: &super::Hub, hours: u32) -> Result<Vec<StagedSummary>, ImportError> {
    let mut conn = hub.pool().acquire().await?;
    let staged = store::staged::idle_for_hours(&mut conn, i64::from(hours)).await?;
    Ok(staged.iter().map(StagedSummary::from).collect())
}

/// The validator moved past the first `lines` lines of the file, which committed batches of
/// an earlier run wrote: each line is parsed again (for duplicate ids) and the images of its
/// valid items hashed (for the report's count of distinct frames), but nothing is decoded
/// or written.
async fn skim(
    heavy: &HeavyPool,
    mut validator: Validator,
    lines: usize,
    skipped: HashSet<usize>,
) -> Result<(Validator, HashSet<String>), ImportError> {
    heavy
        .run_waiting(move || {
            let paths = validator.skip_lines(lines, &skipped)?;
            let root = validator.location.root.clone();
            let hashed: Vec<(String, u64)> = paths
                .into_par_iter()
                .filter_map(|p| {
                    let bytes = std::fs::read(image_path(&root, &p).ok()?).ok()?;
                    Some((hex::encode(Sha256::digest(&bytes)), bytes.len() as u64))
                })
                .collect();
            validator.image_bytes += hashed.iter().map(|(_, n)| n).sum::<u64>();
            let frames = hashed.into_iter().map(|(h, _)| h).collect();
            Ok((validator, frames))
        })
        .await
}

/// The validator's next batch, validated on the heavy-work pool (an import under way waits for
/// a place there rather than failing halfway).
async fn next_batch(
    heavy: &HeavyPool,
    mut validator: Validator,
) -> Result<(Validator, Option<Validated>), ImportError> {
    let (validator, batch) = heavy
        .run_waiting(move || {
            let batch = validator.next_batch();
            (validator, batch)
        })
        .await;
    Ok((validator, batch?))
}

/// The bytes of a batch's frames not stored yet, read from disk (and checked against what was
/// validated) before its transaction begins, so the transaction only writes. With an object
/// store they are written there now, several at a time, and their rows will hold no bytes; if
/// the import then fails the objects stay (named by their content, a later import finds them).
async fn read_new_frames(
    hub: &super::Hub,
    frame_store: &FrameStore,
    root: &Path,
    rows: &[(&ValidRow, String, bool)],
) -> Result<HashMap<String, Vec<u8>>, ImportError> {
    let mut conn = hub.pool().acquire().await?;
    let mut missing = Vec::new();
    let mut seen = HashSet::new();
    for (row, _, _) in rows {
        for (facts, path) in row.frames.iter().zip(&row.item.images) {
            if seen.insert(facts.sha256.as_str())
                && store::frames::id_by_hash(&mut conn, &facts.sha256)
                    .await?
                    .is_none()
            {
                missing.push((facts, path));
            }
        }
    }
    drop(conn);
    let mut bytes_by_hash = HashMap::new();
    match frame_store.objects() {
        Some(objects) => {
            // A few frames in memory at a time, written concurrently.
            for chunk in missing.chunks(frames::PUTS_IN_FLIGHT) {
                let mut uploads = Vec::with_capacity(chunk.len());
                for (facts, path) in chunk {
                    let bytes = read_frame(root, path, facts).await?;
                    uploads.push((facts.sha256.clone(), bytes::Bytes::from(bytes)));
                }
                frames::put_all(objects, uploads.into_iter())
                    .await
                    .map_err(|e| ImportError::FrameStorage(e.to_string()))?;
            }
        }
        None => {
            for (facts, path) in missing {
                let bytes = read_frame(root, path, facts).await?;
                bytes_by_hash.insert(facts.sha256.clone(), bytes);
            }
        }
    }
    Ok(bytes_by_hash)
}

/// Writes a batch's new and replaced items under the staging row, storing each frame not
/// stored yet. `frames` holds the bytes [`read_new_frames`] read; a frame another import
/// stored meanwhile is found by its hash, one it did not read (held in an object store) gets
/// a row without bytes.
async fn write_items(
    tx: &mut store::Tx,
    staging: i64,
    rows: &[(&ValidRow, String, bool)],
    frames: &HashMap<String, Vec<u8>>,
    report: &mut ImportReport,
) -> Result<(), ImportError> {
    for (row, hash, replacing) in rows {
        let mut ids = Vec::with_capacity(row.frames.len());
        for facts in &row.frames {
            let id = match store::frames::id_by_hash(&mut *tx, &facts.sha256).await? {
                Some(id) => id,
                None => {
                    let bytes = frames.get(&facts.sha256).map_or(&[][..], Vec::as_slice);
                    report.new_frames += 1;
                    store::frames::insert(&mut *tx, &facts.sha256, facts.width, facts.height, bytes)
                        .await?
                }
            };
            ids.push(id);
        }
        if *replacing {
            report.replaced_items += 1;
        } else {
            report.new_items += 1;
        }
        store::items::insert(&mut *tx, staging, &row.item, hash, row.line, &ids).await?;
        if let Some(semantics) = &row.semantics {
            let json = signatures_json(&row.item.id, semantics)?;
            store::items::set_semantics(&mut *tx, staging, &row.item.id, semantics.source, &json)
                .await?;
        }
    }
    Ok(())
}

fn signatures_json(item_id: &str, semantics: &ItemSemantics) -> Result<String, ImportError> {
    serde_json::to_string(&semantics.signatures).map_err(|e| ImportError::Signatures {
        item_id: item_id.to_owned(),
        message: e.to_string(),
    })
}

/// The items stored unchanged whose signatures the file adds or refreshes: a re-import with
/// `--scene-graphs` upgrades action-text or exact-only items; a re-import without it never
/// downgrades scene-graph signatures. Staged, and applied at the cut-over.
async fn signature_refreshes<'r>(
    hub: &super::Hub,
    dataset_id: i64,
    rows: &'r [ValidRow],
    stored_hashes: &HashMap<String, String>,
) -> Result<Vec<(&'r str, &'r ItemSemantics)>, ImportError> {
    let mut conn = hub.pool().acquire().await?;
    let mut wanted = Vec::new();
    for row in rows {
        let Some(semantics) = &row.semantics else {
            continue;
        };
        if stored_hashes.get(&row.item.id) != Some(&content_hash(row)) {
            continue; // new or replaced: written with the item
        }
        let stored = store::items::semantics_json(&mut conn, dataset_id, &row.item.id).await?;
        let json = serde_json::to_string(&semantics.signatures).unwrap_or_default();
        let refresh = match &stored {
            None => true,
            Some((source, stored_json)) => {
                semantics.source == SignatureSource::SceneGraph
                    && (*source != SignatureSource::SceneGraph || *stored_json != json)
            }
        };
        if refresh {
            wanted.push((row.item.id.as_str(), semantics));
        }
    }
    Ok(wanted)
}

/// Reads a frame again for writing, checking it is still the file that was validated.
async fn read_frame(
    root: &Path,
    relative: &str,
    facts: &FrameFacts,
) -> Result<Vec<u8>, ImportError> {
    let path = image_path(root, relative).map_err(ImportError::Location)?;
    let bytes = tokio::fs::read(&path)
        .await
        .map_err(|source| ImportError::Io {
            path: path.display().to_string(),
            source,
        })?;
    if hex::encode(Sha256::digest(&bytes)) != facts.sha256 {
        return Err(ImportError::ImageChanged {
            path: path.display().to_string(),
        });
    }
    Ok(bytes)
}
