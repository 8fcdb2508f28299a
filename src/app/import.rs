//! Importing an ENACT release (`QA/enact_ordering.jsonl` + images) into the store.
//!
//! Three phases, a batch of lines at a time inside one transaction, so that a bad file never
//! leaves anything half-written and memory holds one batch whatever the release's size:
//! 1. read and validate the lines and every image they name (CPU work, on rayon threads);
//! 2. decide per item: new, unchanged, or changed (an error unless `replace`);
//! 3. write the batch, reading only the frames not stored yet.
//!
//! Kept across batches: each id's first line (duplicates) and each distinct frame's hash (the
//! report's count), a few dozen bytes per item.

use std::collections::{HashMap, HashSet};
use std::fmt;
use std::io::{BufRead, BufReader};
use std::path::{Component, Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;
use sha2::{Digest, Sha256};

use super::frames::{self, FrameStore};
use crate::core::audit::{Actor, AuditAction, AuditRecord};
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
#[derive(Debug, Clone, Serialize)]
pub struct SkippedLine {
    pub line: usize,
    pub item_id: Option<String>,
    pub problems: Vec<FieldProblem>,
}

#[derive(Debug, Clone, Default, Serialize)]
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
    pub seconds: f64,
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
    #[error("{file}: {} invalid rows of {rows}; nothing was imported (use --skip-invalid to import the valid rows)", lines.len())]
    Invalid {
        file: String,
        rows: usize,
        /// Every problem, grouped by line.
        lines: Vec<SkippedLine>,
    },
    #[error("{file}: {} items already exist in dataset '{dataset}' with different content; nothing was imported (use --replace to overwrite them)", conflicts.len())]
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
/// size of the file.
const BATCH_LINES: usize = 512;

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
}

impl Validator {
    fn open(location: &ReleaseLocation, scene_graphs: Option<&Path>) -> Result<Self, ImportError> {
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
        })
    }

    /// The next batch of up to [`BATCH_LINES`] records, `None` at the end of the file.
    fn next_batch(&mut self) -> Result<Option<Validated>, ImportError> {
        let mut parsed: Vec<(usize, Result<QaItem, Vec<FieldProblem>>)> = Vec::new();
        while parsed.len() < BATCH_LINES {
            let Some(line) = self.lines.next() else { break };
            let line = line.map_err(|source| ImportError::Io {
                path: self.location.qa_file.display().to_string(),
                source,
            })?;
            self.lines_read += 1;
            self.bytes_read += line.len() as u64 + 1;
            if line.trim().is_empty() {
                continue;
            }
            self.rows += 1;
            parsed.push((self.lines_read, parse_release_line(&line)));
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

/// Imports a release into `options.dataset`. See the module documentation for the phases;
/// they run a batch of lines at a time inside the one transaction, so memory holds a batch
/// whatever the size of the release. After the first invalid line (without `skip_invalid`) or
/// conflicting item, nothing more is written but every line is still checked, so the error
/// lists every problem; the transaction is then rolled back.
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
    let validator = Validator::open(&location, options.scene_graphs.as_deref())?;
    let observer = options.progress.as_ref();
    let told = |validator: &Validator, finished: bool| ImportProgress {
        qa_bytes_read: validator.bytes_read,
        qa_bytes,
        rows: validator.rows,
        image_bytes: validator.image_bytes,
        finished,
    };
    let (mut validator, mut next) = next_batch(validator).await?;

    // The write lock is taken now and kept to the end (later batches are validated while it is
    // held): SQLite's IMMEDIATE (a deferred transaction that read first and wrote a batch later
    // would fail at once if a running server wrote in between, instead of waiting), or
    // PostgreSQL's advisory write lock (`Pool::begin`).
    let mut tx = hub.pool.begin().await?;
    let existing_dataset = store::datasets::by_name(&mut tx, &options.dataset).await?;
    let stored_hashes = match &existing_dataset {
        Some(d) => store::items::content_hashes(&mut tx, d.id).await?,
        None => HashMap::new(),
    };
    let mut report = ImportReport {
        dataset: options.dataset.clone(),
        qa_file: file.clone(),
        ..ImportReport::default()
    };
    let mut invalid: Vec<SkippedLine> = Vec::new();
    let mut conflicts: Vec<LineProblem> = Vec::new();
    let mut distinct_frames: HashSet<String> = HashSet::new();
    let mut dataset_id: Option<i64> = None;
    let mut wrote_items = false;

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
            if !to_write.is_empty() {
                let id = match dataset_id {
                    Some(id) => id,
                    None => {
                        let id = store::datasets::ensure(
                            &mut tx,
                            &options.dataset,
                            &location.root.display().to_string(),
                        )
                        .await?;
                        dataset_id = Some(id);
                        id
                    }
                };
                let frames = hub.frame_store();
                write_items(&mut tx, frames, id, &location.root, &to_write, &mut report).await?;
                wrote_items = true;
            }
            if let Some(dataset) = &existing_dataset {
                report.signatures_updated +=
                    refresh_semantics(&mut tx, dataset.id, &batch.valid, &stored_hashes).await?;
            }
        }
        ImportObserver::tell(observer, told(&validator, false));
        (validator, next) = next_batch(validator).await?;
    }
    ImportObserver::tell(observer, told(&validator, true));
    report.rows = validator.rows;
    invalid.sort_by_key(|s| s.line);
    if !invalid.is_empty() && !options.skip_invalid {
        return Err(ImportError::Invalid {
            file,
            rows: report.rows,
            lines: invalid,
        });
    }
    if !conflicts.is_empty() {
        return Err(ImportError::Conflict {
            file,
            dataset: options.dataset.clone(),
            conflicts,
        });
    }
    report.skipped = invalid;
    report.frames = distinct_frames.len();

    if wrote_items || report.signatures_updated > 0 {
        store::bump_content_generation(&mut tx).await?;
    }
    if let Some(dataset) = &existing_dataset {
        // Stored error analyses were computed from the old items or signatures.
        if report.signatures_updated + report.replaced_items > 0 {
            store::submissions::clear_error_analyses(&mut tx, dataset.id).await?;
        }
        // Human verdicts were judged with the old signatures (answers on replaced items went
        // with them): judged again here, in the same transaction.
        if report.signatures_updated > 0 {
            super::rescore::rejudge_dataset(&mut tx, dataset.id).await?;
        }
    }
    // Frames of unchanged items are reused as well.
    report.reused_frames = report.frames - report.new_frames;
    let record = AuditRecord {
        actor,
        action: AuditAction::DatasetImport,
        target: format!("dataset {}", options.dataset),
        dataset: Some(&options.dataset),
        detail: format!(
            "{}: {} new, {} replaced, {} unchanged items; {} signature tables updated; {} \
             lines skipped",
            report.qa_file,
            report.new_items,
            report.replaced_items,
            report.unchanged_items,
            report.signatures_updated,
            report.skipped.len()
        ),
    };
    store::audit::insert(&mut tx, &record).await?;
    tx.commit().await?;
    report.seconds = started.elapsed().as_secs_f64();
    Ok(report)
}

/// The validator's next batch, validated on a blocking thread.
async fn next_batch(
    mut validator: Validator,
) -> Result<(Validator, Option<Validated>), ImportError> {
    let (validator, batch) = tokio::task::spawn_blocking(move || {
        let batch = validator.next_batch();
        (validator, batch)
    })
    .await
    .map_err(|e| ImportError::Location(format!("validation task failed: {e}")))?;
    Ok((validator, batch?))
}

/// Writes a batch's new and replaced items, storing each frame not stored yet (read again
/// from disk and checked against what was validated). Frames are looked up by hash in the
/// store (the transaction sees its own inserts), so nothing grows with the release here.
/// With an object store, the batch's new frames are written there first, several at a time,
/// and their rows hold no bytes; if the import then fails, the objects stay (they are named
/// by their content, and a later import of them finds them in place).
async fn write_items(
    tx: &mut store::Conn,
    frame_store: &FrameStore,
    dataset_id: i64,
    root: &Path,
    rows: &[(&ValidRow, String, bool)],
    report: &mut ImportReport,
) -> Result<(), ImportError> {
    if let Some(objects) = frame_store.objects() {
        let mut missing = Vec::new();
        let mut seen = HashSet::new();
        for (row, _, _) in rows {
            for (facts, path) in row.frames.iter().zip(&row.item.images) {
                if seen.insert(facts.sha256.as_str())
                    && store::frames::id_by_hash(&mut *tx, &facts.sha256)
                        .await?
                        .is_none()
                {
                    missing.push((facts, path));
                }
            }
        }
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
    for (row, hash, replacing) in rows {
        let mut ids = Vec::with_capacity(row.frames.len());
        for (facts, path) in row.frames.iter().zip(&row.item.images) {
            let id = match store::frames::id_by_hash(&mut *tx, &facts.sha256).await? {
                Some(id) => id,
                None => {
                    // Held in the object store (written above), or here.
                    let bytes = match frame_store {
                        FrameStore::Objects(_) => Vec::new(),
                        FrameStore::Database => read_frame(root, path, facts).await?,
                    };
                    report.new_frames += 1;
                    store::frames::insert(
                        &mut *tx,
                        &facts.sha256,
                        facts.width,
                        facts.height,
                        &bytes,
                    )
                    .await?
                }
            };
            ids.push(id);
        }
        if *replacing {
            store::items::delete(&mut *tx, dataset_id, &row.item.id).await?;
            report.replaced_items += 1;
        } else {
            report.new_items += 1;
        }
        store::items::insert(&mut *tx, dataset_id, &row.item, hash, row.line, &ids).await?;
        if let Some(semantics) = &row.semantics {
            store_semantics(&mut *tx, dataset_id, &row.item.id, semantics).await?;
        }
    }
    Ok(())
}

async fn store_semantics(
    conn: &mut store::Conn,
    dataset_id: i64,
    item_id: &str,
    semantics: &ItemSemantics,
) -> Result<(), ImportError> {
    let json =
        serde_json::to_string(&semantics.signatures).map_err(|e| ImportError::Signatures {
            item_id: item_id.to_owned(),
            message: e.to_string(),
        })?;
    store::items::set_semantics(conn, dataset_id, item_id, semantics.source, &json).await?;
    Ok(())
}

/// Adds or refreshes the signatures of items that were already stored unchanged: a re-import
/// with `--scene-graphs` upgrades action-text or exact-only items; a re-import without it never
/// downgrades scene-graph signatures. Returns how many items changed.
async fn refresh_semantics(
    conn: &mut store::Conn,
    dataset_id: i64,
    rows: &[ValidRow],
    stored_hashes: &HashMap<String, String>,
) -> Result<usize, ImportError> {
    let mut updated = 0;
    for row in rows {
        let Some(semantics) = &row.semantics else {
            continue;
        };
        if stored_hashes.get(&row.item.id) != Some(&content_hash(row)) {
            continue; // new or replaced: written above
        }
        let stored = store::items::semantics_json(conn, dataset_id, &row.item.id).await?;
        let json = serde_json::to_string(&semantics.signatures).unwrap_or_default();
        let wanted = match &stored {
            None => true,
            Some((source, stored_json)) => {
                semantics.source == SignatureSource::SceneGraph
                    && (*source != SignatureSource::SceneGraph || *stored_json != json)
            }
        };
        if wanted {
            store_semantics(conn, dataset_id, &row.item.id, semantics).await?;
            updated += 1;
        }
    }
    Ok(updated)
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
