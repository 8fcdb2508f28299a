//! Importing an ENACT release (`QA/enact_ordering.jsonl` + images) into the store.
//!
//! Three phases, so that a bad file never leaves anything half-written:
//! 1. read and validate every line and every image it names (CPU work, on rayon threads);
//! 2. decide per item: new, unchanged, or changed (an error unless `replace`);
//! 3. write everything in one transaction, reading only the frames not stored yet.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::fmt;
use std::io::{BufRead, BufReader};
use std::path::{Component, Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::Serialize;
use sha2::{Digest, Sha256};

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
    /// Draw progress bars (only when attached to a terminal).
    pub progress: bool,
    /// ENACT's `replayed_activities` folder: compute each item's transition signatures from
    /// `{task}/scene_graph_0.json`. Without it, inverse items get signatures parsed from their
    /// action text where possible (see `semantics`).
    pub scene_graphs: Option<PathBuf>,
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
}

struct ValidRow {
    line: usize,
    item: QaItem,
    frames: Vec<FrameFacts>,
    semantics: Option<ItemSemantics>,
}

struct Validated {
    rows: usize,
    valid: Vec<ValidRow>,
    invalid: Vec<SkippedLine>,
}

fn progress_bar(enabled: bool, len: usize, what: &str) -> ProgressBar {
    if !enabled {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len as u64);
    if let Ok(style) =
        ProgressStyle::with_template("{msg:>16} [{bar:40}] {pos}/{len} ({per_sec}, eta {eta})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_owned());
    bar
}

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
    })
}

/// Phase 1: every line, every image and the scene graphs, with every problem found.
fn validate(
    location: &ReleaseLocation,
    scene_graphs: Option<&Path>,
    progress: bool,
) -> Result<Validated, ImportError> {
    let io_error = |source| ImportError::Io {
        path: location.qa_file.display().to_string(),
        source,
    };
    let file = std::fs::File::open(&location.qa_file).map_err(io_error)?;
    let mut rows = 0;
    let mut parsed: Vec<(usize, Result<QaItem, Vec<FieldProblem>>)> = Vec::new();
    for (index, line) in BufReader::new(file).lines().enumerate() {
        let line = line.map_err(io_error)?;
        if line.trim().is_empty() {
            continue;
        }
        rows += 1;
        parsed.push((index + 1, parse_release_line(&line)));
    }

    // Duplicate ids: the first occurrence stands, later ones are problems.
    let mut first_line: HashMap<String, usize> = HashMap::new();
    for (line, result) in &mut parsed {
        if let Ok(item) = result {
            if let Some(first) = first_line.get(&item.id) {
                *result = Err(vec![FieldProblem::new(
                    "id",
                    format!("duplicate id {:?}, first seen on line {first}", item.id),
                )]);
            } else {
                first_line.insert(item.id.clone(), *line);
            }
        }
    }

    let mut paths: Vec<String> = parsed
        .iter()
        .filter_map(|(_, r)| r.as_ref().ok())
        .flat_map(|item| item.images.iter().cloned())
        .collect::<HashSet<_>>()
        .into_iter()
        .collect();
    paths.sort_unstable();
    let bar = progress_bar(progress, paths.len(), "checking images");
    let facts: HashMap<String, Result<FrameFacts, String>> = paths
        .into_par_iter()
        .map(|p| {
            let result = image_path(&location.root, &p).and_then(|full| inspect_image(&full));
            bar.inc(1);
            (p, result)
        })
        .collect();
    bar.finish_and_clear();

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
    let semantics = semantics::for_items(scene_graphs, &items);
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
    let valid = kept;

    invalid.sort_by_key(|s| s.line);
    Ok(Validated {
        rows,
        valid,
        invalid,
    })
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

/// Imports a release into `options.dataset`. See the module documentation for the phases.
pub async fn import_release(
    hub: &super::Hub,
    actor: &Actor,
    path: &Path,
    options: &ImportOptions,
) -> Result<ImportReport, ImportError> {
    let started = Instant::now();
    let location = ReleaseLocation::resolve(path)?;
    let validated = {
        let location = location.clone();
        let progress = options.progress;
        let scene_graphs = options.scene_graphs.clone();
        tokio::task::spawn_blocking(move || validate(&location, scene_graphs.as_deref(), progress))
            .await
            .map_err(|e| ImportError::Location(format!("validation task failed: {e}")))??
    };
    let file = location.qa_file.display().to_string();
    if !validated.invalid.is_empty() && !options.skip_invalid {
        return Err(ImportError::Invalid {
            file,
            rows: validated.rows,
            lines: validated.invalid,
        });
    }

    let mut tx = hub.pool.begin().await?;
    let existing_dataset = store::datasets::by_name(&mut tx, &options.dataset).await?;
    let stored_hashes = match &existing_dataset {
        Some(d) => store::items::content_hashes(&mut tx, d.id).await?,
        None => HashMap::new(),
    };

    let mut to_write = Vec::new();
    let mut conflicts = Vec::new();
    let mut unchanged = 0;
    for row in &validated.valid {
        let hash = content_hash(row);
        match stored_hashes.get(&row.item.id) {
            Some(stored) if *stored == hash => unchanged += 1,
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
    if !conflicts.is_empty() {
        return Err(ImportError::Conflict {
            file,
            dataset: options.dataset.clone(),
            conflicts,
        });
    }

    let mut report = ImportReport {
        dataset: options.dataset.clone(),
        qa_file: file,
        rows: validated.rows,
        unchanged_items: unchanged,
        skipped: validated.invalid,
        ..ImportReport::default()
    };
    for row in &validated.valid {
        match row.semantics.as_ref().map(|s| s.source) {
            Some(SignatureSource::SceneGraph) => report.scene_graph_items += 1,
            Some(SignatureSource::ActionText) => report.action_text_items += 1,
            None => report.exact_only_items += 1,
        }
    }
    let distinct: BTreeMap<&str, &FrameFacts> = validated
        .valid
        .iter()
        .flat_map(|r| r.frames.iter().map(|f| (f.sha256.as_str(), f)))
        .collect();
    report.frames = distinct.len();

    if !to_write.is_empty() {
        let dataset_id = store::datasets::ensure(
            &mut tx,
            &options.dataset,
            &location.root.display().to_string(),
        )
        .await?;
        let bar = progress_bar(options.progress, to_write.len(), "writing items");
        let mut frame_ids: HashMap<String, i64> = HashMap::new();
        for (row, hash, replacing) in &to_write {
            let mut ids = Vec::with_capacity(row.frames.len());
            for (facts, path) in row.frames.iter().zip(&row.item.images) {
                if let Some(id) = frame_ids.get(&facts.sha256) {
                    ids.push(*id);
                    continue;
                }
                let id = match store::frames::id_by_hash(&mut tx, &facts.sha256).await? {
                    Some(id) => id,
                    None => {
                        let bytes = read_frame(&location.root, path, facts).await?;
                        report.new_frames += 1;
                        store::frames::insert(
                            &mut tx,
                            &facts.sha256,
                            facts.width,
                            facts.height,
                            &bytes,
                        )
                        .await?
                    }
                };
                frame_ids.insert(facts.sha256.clone(), id);
                ids.push(id);
            }
            if *replacing {
                store::items::delete(&mut tx, dataset_id, &row.item.id).await?;
                report.replaced_items += 1;
            } else {
                report.new_items += 1;
            }
            store::items::insert(&mut tx, dataset_id, &row.item, hash, row.line, &ids).await?;
            if let Some(semantics) = &row.semantics {
                store_semantics(&mut tx, dataset_id, &row.item.id, semantics).await?;
            }
            bar.inc(1);
        }
        bar.finish_and_clear();
        store::bump_content_generation(&mut tx).await?;
    }
    if let Some(dataset) = &existing_dataset {
        report.signatures_updated =
            refresh_semantics(&mut tx, dataset.id, &validated.valid, &stored_hashes).await?;
        if report.signatures_updated > 0 {
            store::bump_content_generation(&mut tx).await?;
        }
        // Stored error analyses were computed from the old items or signatures.
        if report.signatures_updated + report.replaced_items > 0 {
            store::submissions::clear_error_analyses(&mut tx, dataset.id).await?;
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

async fn store_semantics(
    conn: &mut sqlx::SqliteConnection,
    dataset_id: i64,
    item_id: &str,
    semantics: &ItemSemantics,
) -> Result<(), ImportError> {
    let json =
        serde_json::to_string(&semantics.signatures).map_err(|e| ImportError::Signatures {
            item_id: item_id.to_owned(),
            message: e.to_string(),
        })?;
    store::items::set_semantics(conn, dataset_id, item_id, semantics.source.as_str(), &json)
        .await?;
    Ok(())
}

/// Adds or refreshes the signatures of items that were already stored unchanged: a re-import
/// with `--scene-graphs` upgrades action-text or exact-only items; a re-import without it never
/// downgrades scene-graph signatures. Returns how many items changed.
async fn refresh_semantics(
    conn: &mut sqlx::SqliteConnection,
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
                    && (source != SignatureSource::SceneGraph.as_str() || *stored_json != json)
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
