//! `SceneGraphTimeline`: the scene graphs of one replayed task, frame by frame (our name for
//! ENACT's `SceneGraphReader`), and the loader for `scene_graph_0.json`.
//!
//! A frame's graph is the nearest `full` record at or before it plus every `diff` record after
//! that full record up to and including the frame (frame ids in numeric order; `empty` records
//! change nothing). The loader can keep just what some frames need, because the evaluator only
//! ever looks at key frames while the file can be hundreds of MB.

use std::borrow::Cow;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::{Path, PathBuf};

use std::io::Read;

use serde::de::{self, DeserializeSeed, IgnoredAny, MapAccess, Visitor};

use crate::scene_graph::record::{FrameRecord, SceneGraph};
use crate::scene_graph::record::{SceneEdge, SceneNode, apply_delta_to};
use crate::scene_graph::split::{RawRecord, RecordSplitter};
use crate::scene_graph::transient::{Windows, for_each_filtered_graph};

/// Scene-graph files larger than this are streamed when only some frames are wanted (smaller
/// ones are read whole: parsing from memory is faster).
pub const STREAM_THRESHOLD_BYTES: u64 = 64 * 1024 * 1024;

/// Which frames a loaded timeline can answer for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FrameSelection {
    /// Every frame of the file.
    All,
    /// Only these frame ids (decimal strings as in the file, e.g. the key frames of a task).
    /// Ids that are not in the file are not an error at load time: asking for them later
    /// gives [`TimelineError::FrameNotInSceneGraph`], so one bad item cannot stop a task.
    Only(BTreeSet<String>),
}

/// Whether to apply ENACT's oscillation filter (`SceneGraphReader(filter_transients=True)`).
///
/// ENACT uses it only in segmentation (`FrameSegmentManager`); the evaluator and the QA
/// generator read the raw graphs. The filter walks overlapping windows from the first frame
/// to the last and each window reads graphs that earlier windows already changed, so a single
/// frame's filtered graph depends on every frame before it: a filtered timeline is always
/// built from the whole file, whatever the [`FrameSelection`] (the selection then only decides
/// which filtered frames are kept afterwards).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TransientFilter {
    #[default]
    Off,
    Enact,
}

/// Errors from loading a scene-graph file or asking a timeline for a frame.
#[derive(Debug, thiserror::Error)]
pub enum TimelineError {
    #[error("cannot read scene graph {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: invalid scene-graph JSON {place}: {message}")]
    Json {
        path: PathBuf,
        /// Where in the file: "in frame 123 (line 5, column 9)" or similar.
        place: JsonPlace,
        message: String,
    },
    #[error("{path}: frame key {key:?} is not a decimal frame number")]
    FrameKey { path: PathBuf, key: String },
    #[error("frame {frame} is not in scene graph {path}")]
    FrameNotInSceneGraph { path: PathBuf, frame: String },
    #[error("frame {frame} is in scene graph {path} but was not selected when it was loaded")]
    FrameNotLoaded { path: PathBuf, frame: String },
    #[error("{path}: no `full` record at or before frame {frame}")]
    NoFullRecordBefore { path: PathBuf, frame: String },
}

/// Location of a JSON error in a scene-graph file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct JsonPlace {
    /// The frame whose record was being read, if the error is inside one.
    pub frame: Option<String>,
    /// The last frame read completely before the error, when not inside a record.
    pub after_frame: Option<String>,
    /// 1-based line and column as reported by serde_json (0 when it has none).
    pub line: usize,
    pub column: usize,
}

impl fmt::Display for JsonPlace {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.frame, &self.after_frame) {
            (Some(frame), _) => write!(f, "in frame {frame}")?,
            (None, Some(prev)) => write!(f, "after frame {prev}")?,
            (None, None) => write!(f, "at top level")?,
        }
        if self.line > 0 {
            write!(f, " (line {}, column {})", self.line, self.column)?;
        }
        Ok(())
    }
}

/// The per-frame scene graphs of one task.
#[derive(Debug, Clone)]
pub struct SceneGraphTimeline {
    source: PathBuf,
    /// Every frame id of the file, including those not loaded.
    known: BTreeSet<u64>,
    /// The records kept. With [`FrameSelection::Only`] the selected frames are stored as
    /// reconstructed `full` graphs, so lookups never rebuild anything.
    records: BTreeMap<u64, FrameRecord>,
}

impl SceneGraphTimeline {
    /// Loads `scene_graph_0.json` without the transient filter (what ENACT's evaluator and QA
    /// generator read).
    pub fn load(path: &Path, selection: FrameSelection) -> Result<Self, TimelineError> {
        Self::load_with(path, selection, TransientFilter::Off)
    }

    /// Loads `scene_graph_0.json`, optionally through ENACT's transient filter.
    ///
    /// A file over [`STREAM_THRESHOLD_BYTES`] loaded for a frame selection without the filter
    /// is read as a stream, twice (record kinds, then the records needed), so memory holds
    /// only what the selected frames are rebuilt from, never the text.
    pub fn load_with(
        path: &Path,
        selection: FrameSelection,
        filter: TransientFilter,
    ) -> Result<Self, TimelineError> {
        let io = |source| TimelineError::Io {
            path: path.to_path_buf(),
            source,
        };
        let size = std::fs::metadata(path).map_err(io)?.len();
        if size > STREAM_THRESHOLD_BYTES
            && let Some(timeline) = Self::load_streamed(path, &selection, filter)?
        {
            return Ok(timeline);
        }
        let bytes = std::fs::read(path).map_err(io)?;
        Self::from_json_slice(&bytes, path, selection, filter)
    }

    /// Loads `scene_graph_0.json` as a stream, never holding its text: a selection without
    /// the filter keeps only the records its frames are rebuilt from (two passes); with the
    /// filter, frames go through it one at a time and only the filtered graphs where they
    /// change are kept. `None` for a file whose frame ids are not in ascending order (a
    /// stream cannot sort them; read it whole instead) or, without the filter, a request for
    /// every frame (which holds every record anyway).
    pub fn load_streamed(
        path: &Path,
        selection: &FrameSelection,
        filter: TransientFilter,
    ) -> Result<Option<Self>, TimelineError> {
        match (selection, filter) {
            (FrameSelection::All, TransientFilter::Off) => Ok(None),
            (FrameSelection::Only(ids), TransientFilter::Off) => {
                Self::stream_selected(path, ids).map(Some)
            }
            (_, TransientFilter::Enact) => {
                let Some(filtered) = Self::stream_filtered(path)? else {
                    return Ok(None);
                };
                Ok(Some(match selection {
                    FrameSelection::All => filtered,
                    FrameSelection::Only(ids) => {
                        let selected: BTreeSet<u64> =
                            ids.iter().filter_map(|id| canonical_frame(id)).collect();
                        filtered.keep_only(&selected)
                    }
                }))
            }
        }
    }

    /// Every frame of the file through ENACT's transient filter, read as a stream; `None`
    /// when the frame ids are not in ascending order.
    fn stream_filtered(path: &Path) -> Result<Option<Self>, TimelineError> {
        let mut state = FilterStream::default();
        match each_record(open_file(path)?, path, |n, json| state.push(n, json))? {
            Some(Stop::OutOfOrder) => Ok(None),
            Some(Stop::NoFullRecordBefore(frame)) => Err(TimelineError::NoFullRecordBefore {
                path: path.to_path_buf(),
                frame: frame.to_string(),
            }),
            None => {
                let FilterStream {
                    windows,
                    mut kept,
                    known,
                    ..
                } = state;
                windows.finish(&mut |id, graph| kept.keep(id, graph));
                Ok(Some(SceneGraphTimeline {
                    source: path.to_path_buf(),
                    known,
                    records: kept.records,
                }))
            }
        }
    }

    /// Reads the selected frames of the file at `path` as a stream, in two passes.
    fn stream_selected(path: &Path, ids: &BTreeSet<String>) -> Result<Self, TimelineError> {
        let kinds = scan_record_kinds(open_file(path)?, path)?;
        let selected: BTreeSet<u64> = ids.iter().filter_map(|id| canonical_frame(id)).collect();
        let needed = records_needed(&kinds, &selected);
        let (known, records) = parse_records(open_file(path)?, path, &KeepRecords::Only(&needed))?;
        let loaded = SceneGraphTimeline {
            source: path.to_path_buf(),
            known,
            records,
        };
        Ok(loaded.keep_only(&selected))
    }

    /// Parses scene-graph JSON already in memory; `source` names it in errors.
    ///
    /// With [`FrameSelection::Only`] (and no filter) the bytes are scanned twice: first for
    /// each record's `type` only, then parsing just the records the selected frames are built
    /// from (the nearest full record before each and the diff records up to it). Every record
    /// that is parsed must be well formed (e.g. a node without `name` is an error here, where
    /// ENACT would fail only once that frame is used); records that are skipped need only be
    /// valid JSON.
    pub fn from_json_slice(
        bytes: &[u8],
        source: &Path,
        selection: FrameSelection,
        filter: TransientFilter,
    ) -> Result<Self, TimelineError> {
        let wanted = match (&selection, filter) {
            (FrameSelection::All, _) | (_, TransientFilter::Enact) => None,
            (FrameSelection::Only(ids), TransientFilter::Off) => Some(ids),
        };
        let timeline = match wanted {
            None => {
                let (known, records) = parse_records(bytes, source, &KeepRecords::All)?;
                SceneGraphTimeline {
                    source: source.to_path_buf(),
                    known,
                    records,
                }
            }
            Some(ids) => {
                // Pass 1 reads only each record's type; pass 2 parses just the records the
                // selected frames are rebuilt from.
                let kinds = scan_record_kinds(bytes, source)?;
                let selected: BTreeSet<u64> =
                    ids.iter().filter_map(|id| canonical_frame(id)).collect();
                let needed = records_needed(&kinds, &selected);
                let (known, records) = parse_records(bytes, source, &KeepRecords::Only(&needed))?;
                let loaded = SceneGraphTimeline {
                    source: source.to_path_buf(),
                    known,
                    records,
                };
                loaded.keep_only(&selected)
            }
        };
        match filter {
            TransientFilter::Off => Ok(timeline),
            TransientFilter::Enact => {
                let filtered = timeline.with_transients_filtered()?;
                match selection {
                    FrameSelection::All => Ok(filtered),
                    FrameSelection::Only(ids) => {
                        let selected: BTreeSet<u64> =
                            ids.iter().filter_map(|id| canonical_frame(id)).collect();
                        Ok(filtered.keep_only(&selected))
                    }
                }
            }
        }
    }

    /// Builds a timeline from records in memory (tests, generated data).
    pub fn from_records(
        source: impl Into<PathBuf>,
        records: impl IntoIterator<Item = (u64, FrameRecord)>,
    ) -> Self {
        let records: BTreeMap<u64, FrameRecord> = records.into_iter().collect();
        SceneGraphTimeline {
            source: source.into(),
            known: records.keys().copied().collect(),
            records,
        }
    }

    /// The file (or label) this timeline was read from.
    pub fn source(&self) -> &Path {
        &self.source
    }

    /// Every frame id of the file in numeric order, loaded or not.
    pub fn frame_ids(&self) -> impl Iterator<Item = String> + '_ {
        self.known.iter().map(|n| n.to_string())
    }

    /// The frame ids this timeline can reconstruct, in numeric order.
    pub fn loaded_frame_ids(&self) -> impl Iterator<Item = String> + '_ {
        self.records.keys().map(|n| n.to_string())
    }

    /// The stored record of a frame, if it was kept.
    pub fn record(&self, frame: &str) -> Option<&FrameRecord> {
        canonical_frame(frame).and_then(|n| self.records.get(&n))
    }

    /// The scene graph at `frame` (ENACT's `get_scene_graph`). Borrowed when the frame is
    /// stored as a full record, which is every frame of a selection-loaded timeline.
    pub fn scene_graph(&self, frame: &str) -> Result<Cow<'_, SceneGraph>, TimelineError> {
        let n = self.frame_number(frame)?;
        self.scene_graph_at(n, frame)
    }

    fn frame_number(&self, frame: &str) -> Result<u64, TimelineError> {
        let n = canonical_frame(frame).ok_or_else(|| self.not_found(frame))?;
        if self.records.contains_key(&n) {
            Ok(n)
        } else if self.known.contains(&n) {
            Err(TimelineError::FrameNotLoaded {
                path: self.source.clone(),
                frame: frame.to_string(),
            })
        } else {
            Err(self.not_found(frame))
        }
    }

    fn not_found(&self, frame: &str) -> TimelineError {
        TimelineError::FrameNotInSceneGraph {
            path: self.source.clone(),
            frame: frame.to_string(),
        }
    }

    fn scene_graph_at(&self, n: u64, frame: &str) -> Result<Cow<'_, SceneGraph>, TimelineError> {
        if let Some(FrameRecord::Full(graph)) = self.records.get(&n) {
            return Ok(Cow::Borrowed(graph));
        }
        let (base_id, base) = self
            .records
            .range(..n)
            .rev()
            .find_map(|(id, rec)| match rec {
                FrameRecord::Full(g) => Some((*id, g)),
                _ => None,
            })
            .ok_or_else(|| TimelineError::NoFullRecordBefore {
                path: self.source.clone(),
                frame: frame.to_string(),
            })?;
        let mut graph = base.clone();
        for (_, rec) in self.records.range(base_id + 1..=n) {
            if let FrameRecord::Diff(delta) = rec {
                graph.apply_delta(delta);
            }
        }
        Ok(Cow::Owned(graph))
    }

    /// A copy of this timeline with ENACT's transient filter applied to every frame (as ENACT's
    /// `_rebuild_data_from_graphs` does); a frame is stored as a full record where its graph
    /// differs from the frame before, as an empty (unchanged) record where it does not.
    /// Needs every frame, see [`TransientFilter`]; on a selection-loaded timeline it fails
    /// with [`TimelineError::FrameNotLoaded`] naming the first missing frame.
    pub fn with_transients_filtered(&self) -> Result<SceneGraphTimeline, TimelineError> {
        if let Some(missing) = self.known.iter().find(|n| !self.records.contains_key(n)) {
            return Err(TimelineError::FrameNotLoaded {
                path: self.source.clone(),
                frame: missing.to_string(),
            });
        }
        // A frame whose filtered graph equals the one before it is kept as an empty record
        // (no change), so memory grows with the number of distinct states rather than frames:
        // replays hold each state for hundreds of frames.
        let mut kept = KeptChanges::default();
        for_each_filtered_graph(&self.records, |id, graph| kept.keep(id, graph)).map_err(
            |frame| TimelineError::NoFullRecordBefore {
                path: self.source.clone(),
                frame: frame.to_string(),
            },
        )?;
        Ok(SceneGraphTimeline {
            source: self.source.clone(),
            known: self.known.clone(),
            records: kept.records,
        })
    }

    /// Keeps just the selected frames, each stored as its reconstructed full graph. A selected
    /// frame that cannot be rebuilt keeps its raw record so that asking for it reports why.
    fn keep_only(self, selected: &BTreeSet<u64>) -> SceneGraphTimeline {
        let mut kept = BTreeMap::new();
        for &n in selected {
            if !self.records.contains_key(&n) {
                continue;
            }
            let record = match self.scene_graph_at(n, &n.to_string()) {
                Ok(graph) => FrameRecord::Full(graph.into_owned()),
                Err(_) => self.records[&n].clone(),
            };
            kept.insert(n, record);
        }
        SceneGraphTimeline {
            source: self.source,
            known: self.known,
            records: kept,
        }
    }
}

/// Filtered graphs as a timeline stores them: a frame whose graph equals the one before it is
/// an empty (unchanged) record, so memory grows with the number of distinct states rather than
/// frames (replays hold each state for hundreds of frames).
#[derive(Default)]
struct KeptChanges {
    records: BTreeMap<u64, FrameRecord>,
    last_full: Option<u64>,
}

impl KeptChanges {
    fn keep(&mut self, id: u64, graph: SceneGraph) {
        let unchanged = self
            .last_full
            .and_then(|n| self.records.get(&n))
            .is_some_and(|r| matches!(r, FrameRecord::Full(g) if *g == graph));
        if unchanged {
            self.records.insert(id, FrameRecord::Empty);
        } else {
            self.records.insert(id, FrameRecord::Full(graph));
            self.last_full = Some(id);
        }
    }
}

/// Why a streamed read stopped early.
enum Stop {
    /// A frame id not above the one before: the file must be read whole and sorted.
    OutOfOrder,
    NoFullRecordBefore(u64),
}

/// What the streamed filtered read holds: the graph under reconstruction (record entries
/// shared, not copied, between frames), the filter's windows and the kept changes.
#[derive(Default)]
struct FilterStream {
    current: Option<(Vec<std::sync::Arc<SceneNode>>, Vec<SceneEdge>)>,
    windows: Windows<std::sync::Arc<SceneNode>>,
    kept: KeptChanges,
    known: BTreeSet<u64>,
    /// Whether the record before was a full record (or repeated one): a frame whose text
    /// repeats such a record has the same graph, which is already built.
    previous_full: bool,
}

impl FilterStream {
    /// Takes frame `n`'s record: rebuilds its graph and passes it through the filter.
    fn push(&mut self, n: u64, record: &RawRecord<'_>) -> Result<(), RecordFailure> {
        if self.known.last().is_some_and(|&last| n <= last) {
            return Err(RecordFailure::Stop(Stop::OutOfOrder));
        }
        let repeated = record.repeats_previous && self.previous_full;
        let record = if repeated {
            FrameRecord::Empty
        } else {
            serde_json::from_slice::<FrameRecord>(record.json)?
        };
        self.previous_full = repeated || matches!(record, FrameRecord::Full(_));
        match record {
            FrameRecord::Full(graph) => {
                self.current = Some((
                    graph.nodes.into_iter().map(std::sync::Arc::new).collect(),
                    graph.edges,
                ));
            }
            FrameRecord::Diff(delta) => {
                if let Some((nodes, edges)) = self.current.as_mut() {
                    apply_delta_to(nodes, edges, &delta);
                }
            }
            FrameRecord::Empty => {}
        }
        let Some((nodes, edges)) = self.current.as_ref() else {
            return Err(RecordFailure::Stop(Stop::NoFullRecordBefore(n)));
        };
        let kept = &mut self.kept;
        self.windows
            .push(n, nodes.iter().cloned(), edges.iter(), &mut |id, graph| {
                kept.keep(id, graph)
            });
        self.known.insert(n);
        Ok(())
    }
}

/// A frame id as ENACT looks it up (`str(int(id))` must be the key itself): plain decimal
/// digits without leading zeros.
pub(crate) fn canonical_frame(id: &str) -> Option<u64> {
    let n: u64 = id.parse().ok()?;
    (n.to_string() == id).then_some(n)
}

/// The record kind of each frame, read without building any graph.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum RecordKind {
    Full,
    Diff,
    Other,
}

/// For each selected frame present in the file: its nearest full record at or before it, the
/// diff records after that up to it, and the frame itself.
fn records_needed(kinds: &BTreeMap<u64, RecordKind>, selected: &BTreeSet<u64>) -> BTreeSet<u64> {
    let mut needed = BTreeSet::new();
    for &n in selected {
        if !kinds.contains_key(&n) {
            continue;
        }
        needed.insert(n);
        let base = kinds
            .range(..=n)
            .rev()
            .find(|(_, k)| **k == RecordKind::Full)
            .map(|(id, _)| *id);
        if let Some(base) = base {
            needed.extend(
                kinds
                    .range(base..=n)
                    .filter(|(id, k)| **id == base || **k == RecordKind::Diff)
                    .map(|(id, _)| *id),
            );
        }
    }
    needed
}

enum KeepRecords<'a> {
    All,
    Only(&'a BTreeSet<u64>),
}

/// Why a record handler stopped a read.
enum RecordFailure {
    /// The record is not what it should be; the error's position is within the record.
    Json(serde_json::Error),
    Stop(Stop),
}

impl From<serde_json::Error> for RecordFailure {
    fn from(e: serde_json::Error) -> Self {
        RecordFailure::Json(e)
    }
}

fn open_file(path: &Path) -> Result<std::fs::File, TimelineError> {
    std::fs::File::open(path).map_err(|source| TimelineError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// `serde_json`'s message without its " at line L column C" (positions within a record mean
/// nothing to a reader of the file; [`JsonPlace`] gives the position in the file).
fn message_of(err: &serde_json::Error) -> String {
    let text = err.to_string();
    let suffix = format!(" at line {} column {}", err.line(), err.column());
    text.strip_suffix(&suffix).unwrap_or(&text).to_owned()
}

/// Calls `f(frame, record JSON)` for every record of the file, in file order. A JSON error
/// names the frame (or the last frame read, between records) and its line and column in the
/// file; `Some(stop)` when `f` stopped the read.
fn each_record(
    reader: impl Read,
    source: &Path,
    mut f: impl FnMut(u64, &RawRecord<'_>) -> Result<(), RecordFailure>,
) -> Result<Option<Stop>, TimelineError> {
    let mut splitter = RecordSplitter::new(reader);
    let mut last_done: Option<String> = None;
    loop {
        let record = match splitter.next_record() {
            Ok(Some(record)) => record,
            Ok(None) => return Ok(None),
            Err(e) => {
                return Err(TimelineError::Json {
                    path: source.to_path_buf(),
                    place: JsonPlace {
                        after_frame: if e.frame.is_none() { last_done } else { None },
                        frame: e.frame,
                        line: e.line,
                        column: e.column,
                    },
                    message: e.message,
                });
            }
        };
        let Some(n) = canonical_frame(&record.key) else {
            return Err(TimelineError::FrameKey {
                path: source.to_path_buf(),
                key: record.key,
            });
        };
        match f(n, &record) {
            Ok(()) => {}
            Err(RecordFailure::Stop(stop)) => return Ok(Some(stop)),
            Err(RecordFailure::Json(e)) => {
                let at = record.at.of_error_in_record(&e);
                return Err(TimelineError::Json {
                    path: source.to_path_buf(),
                    place: JsonPlace {
                        frame: Some(record.key),
                        after_frame: None,
                        line: at.line,
                        column: at.column,
                    },
                    message: message_of(&e),
                });
            }
        }
        last_done = Some(record.key);
    }
}

type ParsedRecords = (BTreeSet<u64>, BTreeMap<u64, FrameRecord>);

/// Every frame id of the file and the records `keep` asks for. Records left out are not
/// checked beyond their brackets: [`KeepRecords::Only`] follows [`scan_record_kinds`], which
/// has read them all.
fn parse_records(
    reader: impl Read,
    source: &Path,
    keep: &KeepRecords<'_>,
) -> Result<ParsedRecords, TimelineError> {
    let mut known = BTreeSet::new();
    let mut records = BTreeMap::new();
    each_record(reader, source, |n, record| {
        let wanted = match keep {
            KeepRecords::All => true,
            KeepRecords::Only(set) => set.contains(&n),
        };
        if wanted {
            // A repeated key replaces the earlier record, as Python's json.load does.
            records.insert(n, serde_json::from_slice::<FrameRecord>(record.json)?);
        }
        known.insert(n);
        Ok(())
    })?;
    Ok((known, records))
}

/// Each record's kind, reading only its `type` (the rest is checked for syntax and skipped).
fn scan_record_kinds(
    reader: impl Read,
    source: &Path,
) -> Result<BTreeMap<u64, RecordKind>, TimelineError> {
    let mut kinds = BTreeMap::new();
    let mut previous = RecordKind::Other;
    each_record(reader, source, |n, record| {
        if !record.repeats_previous {
            let mut de = serde_json::Deserializer::from_slice(record.json);
            previous = KindSeed.deserialize(&mut de)?;
        }
        kinds.insert(n, previous);
        Ok(())
    })?;
    Ok(kinds)
}

/// Reads one record, keeping only its `type` and skipping everything else unparsed.
struct KindSeed;

impl<'de> DeserializeSeed<'de> for KindSeed {
    type Value = RecordKind;

    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
        d.deserialize_map(self)
    }
}

impl<'de> Visitor<'de> for KindSeed {
    type Value = RecordKind;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a scene-graph record object")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        let mut kind = RecordKind::Other;
        while let Some(field) = map.next_key::<Cow<'de, str>>()? {
            if field == "type" {
                let value: Option<Cow<'de, str>> = map.next_value()?;
                kind = match value.as_deref() {
                    Some("full") => RecordKind::Full,
                    Some("diff") => RecordKind::Diff,
                    _ => RecordKind::Other,
                };
            } else {
                map.next_value::<IgnoredAny>()?;
            }
        }
        Ok(kind)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILE: &str = r#"{
  "0": {"nodes": [{"name": "robot_r1", "category": "agent", "states": [], "visibility": {}}],
        "edges": [], "type": "full"},
  "1": {"type": "empty"},
  "2": {"type": "diff",
        "add": {"nodes": [{"name": "apple_1", "category": "apple", "states": [], "visibility": {}}],
                "edges": [{"from": "robot_r1", "to": "apple_1", "states": ["LeftGrasping"]}]},
        "remove": {"nodes": [], "edges": []},
        "update": {"nodes": [], "edges": []}},
  "3": {"type": "diff", "add": {"nodes": [], "edges": []},
        "remove": {"nodes": [], "edges": []},
        "update": {"nodes": [{"name": "apple_1", "category": "apple", "states": ["Cooked"], "visibility": {}}],
                   "edges": []}},
  "10": {"nodes": [], "edges": [], "type": "full"},
  "11": {"type": "diff", "add": {"nodes": [{"name": "pan", "category": "pan", "states": [], "visibility": {}}], "edges": []}}
}"#;

    fn load(selection: FrameSelection) -> SceneGraphTimeline {
        SceneGraphTimeline::from_json_slice(
            FILE.as_bytes(),
            Path::new("t.json"),
            selection,
            TransientFilter::Off,
        )
        .unwrap()
    }

    fn only(ids: &[&str]) -> FrameSelection {
        FrameSelection::Only(ids.iter().map(|s| s.to_string()).collect())
    }

    fn names(t: &SceneGraphTimeline, frame: &str) -> Vec<String> {
        t.scene_graph(frame)
            .unwrap()
            .nodes
            .iter()
            .map(|n| format!("{}{:?}", n.name, n.states))
            .collect()
    }

    #[test]
    fn reconstructs_from_full_plus_diffs_skipping_empty() {
        let t = load(FrameSelection::All);
        assert_eq!(names(&t, "1"), ["robot_r1[]"]);
        assert_eq!(names(&t, "2"), ["robot_r1[]", "apple_1[]"]);
        assert_eq!(names(&t, "3"), ["robot_r1[]", "apple_1[\"Cooked\"]"]);
        assert_eq!(t.scene_graph("3").unwrap().edges.len(), 1);
        // Frame 10 is a full record again: earlier diffs no longer apply.
        assert!(names(&t, "10").is_empty());
        assert_eq!(names(&t, "11"), ["pan[]"]);
        assert!(matches!(t.scene_graph("10").unwrap(), Cow::Borrowed(_)));
        let ids: Vec<String> = t.frame_ids().collect();
        assert_eq!(ids, ["0", "1", "2", "3", "10", "11"]);
    }

    #[test]
    fn selection_keeps_the_same_graphs() {
        let all = load(FrameSelection::All);
        let sel = load(only(&["3", "11", "999"]));
        for f in ["3", "11"] {
            assert_eq!(*all.scene_graph(f).unwrap(), *sel.scene_graph(f).unwrap());
            assert!(matches!(sel.scene_graph(f).unwrap(), Cow::Borrowed(_)));
        }
        assert!(matches!(
            sel.scene_graph("2"),
            Err(TimelineError::FrameNotLoaded { ref frame, .. }) if frame == "2"
        ));
        let err = sel.scene_graph("999").unwrap_err();
        assert!(matches!(err, TimelineError::FrameNotInSceneGraph { .. }));
        assert_eq!(err.to_string(), "frame 999 is not in scene graph t.json");
        // Non-canonical ids are not ENACT keys either.
        assert!(matches!(
            all.scene_graph("03"),
            Err(TimelineError::FrameNotInSceneGraph { .. })
        ));
        assert!(matches!(
            sel.with_transients_filtered(),
            Err(TimelineError::FrameNotLoaded { .. })
        ));
    }

    #[test]
    fn a_streamed_selection_equals_one_read_from_memory() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene_graph_0.json");
        std::fs::write(&path, FILE).unwrap();
        let FrameSelection::Only(ids) = only(&["3", "11", "999"]) else {
            unreachable!()
        };
        let streamed = SceneGraphTimeline::stream_selected(&path, &ids).unwrap();
        let in_memory = load(only(&["3", "11", "999"]));
        for f in ["3", "11"] {
            assert_eq!(
                *streamed.scene_graph(f).unwrap(),
                *in_memory.scene_graph(f).unwrap()
            );
        }
        assert_eq!(
            streamed.frame_ids().collect::<Vec<_>>(),
            in_memory.frame_ids().collect::<Vec<_>>()
        );
        assert_eq!(
            streamed.loaded_frame_ids().collect::<Vec<_>>(),
            in_memory.loaded_frame_ids().collect::<Vec<_>>()
        );
        // Errors name the frame and place as the in-memory reader does.
        let broken = FILE.replace(r#""3": {"type": "diff""#, r#""3": {"type": "diff" ,,"#);
        std::fs::write(&path, &broken).unwrap();
        let streamed = SceneGraphTimeline::stream_selected(&path, &ids).unwrap_err();
        let in_memory = SceneGraphTimeline::from_json_slice(
            broken.as_bytes(),
            &path,
            only(&["3", "11", "999"]),
            TransientFilter::Off,
        )
        .unwrap_err();
        assert_eq!(streamed.to_string(), in_memory.to_string());
        assert!(streamed.to_string().contains("in frame 3"), "{streamed}");
    }

    /// Every frame of `a` and `b` has the same graph.
    fn same_graphs(a: &SceneGraphTimeline, b: &SceneGraphTimeline) {
        let ids: Vec<String> = a.frame_ids().collect();
        assert_eq!(ids, b.frame_ids().collect::<Vec<_>>());
        for f in &ids {
            assert_eq!(
                *a.scene_graph(f).unwrap(),
                *b.scene_graph(f).unwrap(),
                "frame {f}"
            );
        }
    }

    #[test]
    fn a_streamed_filtered_read_equals_one_from_memory() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene_graph_0.json");
        // A flicker every few frames, long enough to span several window starts.
        let frames: Vec<String> = (0..47)
            .map(|i| {
                let fridge = if i % 7 == 3 { "[]" } else { r#"["Open"]"# };
                let apple = if i % 11 < 2 {
                    ""
                } else {
                    r#", {"name": "apple_1", "category": "apple", "states": ["Cooked"]}"#
                };
                let edges = if i % 13 == 5 {
                    "[]"
                } else {
                    r#"[{"from": "robot_r1", "to": "fridge_1", "states": ["LeftGrasping"]}]"#
                };
                format!(
                    r#""{i}": {{"type": "full", "edges": {edges}, "nodes": [
                        {{"name": "robot_r1", "category": "agent", "states": []}},
                        {{"name": "fridge_1", "category": "fridge", "states": {fridge}}}{apple}]}}"#
                )
            })
            .collect();
        for text in [format!("{{{}}}", frames.join(",")), FILE.to_owned()] {
            std::fs::write(&path, &text).unwrap();
            let in_memory = SceneGraphTimeline::from_json_slice(
                text.as_bytes(),
                &path,
                FrameSelection::All,
                TransientFilter::Enact,
            )
            .unwrap();
            let streamed = SceneGraphTimeline::load_streamed(
                &path,
                &FrameSelection::All,
                TransientFilter::Enact,
            )
            .unwrap()
            .expect("ids in order");
            same_graphs(&in_memory, &streamed);
            let some = SceneGraphTimeline::load_streamed(
                &path,
                &only(&["3", "11"]),
                TransientFilter::Enact,
            )
            .unwrap()
            .unwrap();
            for f in ["3", "11"] {
                assert_eq!(
                    *some.scene_graph(f).unwrap(),
                    *in_memory.scene_graph(f).unwrap()
                );
            }
        }
        // Ids out of order: a stream cannot sort them, so the caller reads the file whole.
        std::fs::write(
            &path,
            r#"{"1": {"type": "full", "nodes": [], "edges": []}, "0": {"type": "empty"}}"#,
        )
        .unwrap();
        assert!(
            SceneGraphTimeline::load_streamed(&path, &FrameSelection::All, TransientFilter::Enact)
                .unwrap()
                .is_none()
        );
        // No full record before a frame: the same error as in memory.
        std::fs::write(&path, r#"{"0": {"type": "empty"}}"#).unwrap();
        let err =
            SceneGraphTimeline::load_streamed(&path, &FrameSelection::All, TransientFilter::Enact)
                .unwrap_err();
        assert!(
            matches!(err, TimelineError::NoFullRecordBefore { ref frame, .. } if frame == "0"),
            "{err}"
        );
    }

    #[test]
    fn filtered_selection_is_filtered_from_the_whole_file() {
        // Frames 0..=11 full; "Open" drops out of the fridge at frame 6 only.
        let frames: Vec<String> = (0..12)
            .map(|i| {
                let states = if i == 6 { "[]" } else { r#"["Open"]"# };
                format!(
                    r#""{i}": {{"type": "full", "edges": [], "nodes": [
                        {{"name": "robot_r1", "category": "agent", "states": []}},
                        {{"name": "fridge_1", "category": "fridge", "states": {states}}}]}}"#
                )
            })
            .collect();
        let text = format!("{{{}}}", frames.join(","));
        let load = |sel, filter| {
            SceneGraphTimeline::from_json_slice(text.as_bytes(), Path::new("f.json"), sel, filter)
                .unwrap()
        };
        let raw = load(only(&["6"]), TransientFilter::Off);
        assert!(raw.scene_graph("6").unwrap().nodes[1].states.is_empty());
        let all = load(FrameSelection::All, TransientFilter::Enact);
        let some = load(only(&["6", "8"]), TransientFilter::Enact);
        assert_eq!(some.scene_graph("6").unwrap().nodes[1].states, ["Open"]);
        for f in ["6", "8"] {
            assert_eq!(*all.scene_graph(f).unwrap(), *some.scene_graph(f).unwrap());
        }
        assert!(matches!(
            some.scene_graph("7"),
            Err(TimelineError::FrameNotLoaded { .. })
        ));
        assert_eq!(all.loaded_frame_ids().count(), 12);
        // Repaired, every frame equals the first, so only frame 0 holds a graph.
        assert!(matches!(all.record("0"), Some(FrameRecord::Full(_))));
        for f in (1..12).map(|f| f.to_string()) {
            assert!(matches!(all.record(&f), Some(FrameRecord::Empty)), "{f}");
            assert_eq!(
                *all.scene_graph(&f).unwrap(),
                *all.scene_graph("0").unwrap()
            );
        }
    }

    #[test]
    fn a_filtered_timeline_stores_a_graph_only_where_the_state_changes() {
        // The fridge opens at frame 6 and stays open: a real change, not a transient.
        let frames: Vec<String> = (0..12)
            .map(|i| {
                let states = if i >= 6 { r#"["Open"]"# } else { "[]" };
                format!(
                    r#""{i}": {{"type": "full", "edges": [], "nodes": [
                        {{"name": "fridge_1", "category": "fridge", "states": {states}}}]}}"#
                )
            })
            .collect();
        let text = format!("{{{}}}", frames.join(","));
        let t = SceneGraphTimeline::from_json_slice(
            text.as_bytes(),
            Path::new("f.json"),
            FrameSelection::All,
            TransientFilter::Enact,
        )
        .unwrap();
        for f in 0..12 {
            let id = f.to_string();
            let full = matches!(t.record(&id), Some(FrameRecord::Full(_)));
            assert_eq!(full, f == 0 || f == 6, "frame {f}");
            assert_eq!(
                t.scene_graph(&id).unwrap().nodes[0].states.len(),
                usize::from(f >= 6)
            );
        }
    }

    #[test]
    fn frame_without_earlier_full_record_is_an_error() {
        let text = r#"{"0": {"type": "empty"}, "1": {"nodes": [], "edges": [], "type": "full"}}"#;
        for sel in [FrameSelection::All, only(&["0", "1"])] {
            let t = SceneGraphTimeline::from_json_slice(
                text.as_bytes(),
                Path::new("x.json"),
                sel,
                TransientFilter::Off,
            )
            .unwrap();
            assert!(matches!(
                t.scene_graph("0"),
                Err(TimelineError::NoFullRecordBefore { ref frame, .. }) if frame == "0"
            ));
            assert!(t.scene_graph("1").is_ok());
        }
    }

    #[test]
    fn malformed_json_names_file_frame_and_position() {
        let text = "{\"0\": {\"nodes\": [], \"edges\": [], \"type\": \"full\"},\n \"1\": {\"type\": \"diff\", \"add\": {\"nodes\": [{\"name\": 5}]}}}";
        for sel in [FrameSelection::All, only(&["1"])] {
            let err = SceneGraphTimeline::from_json_slice(
                text.as_bytes(),
                Path::new("bad.json"),
                sel,
                TransientFilter::Off,
            )
            .unwrap_err();
            match &err {
                TimelineError::Json { path, place, .. } => {
                    assert_eq!(path, Path::new("bad.json"));
                    assert_eq!(place.frame.as_deref(), Some("1"));
                    // The position in the file: where serde_json reading the whole text stops.
                    let whole =
                        serde_json::from_str::<BTreeMap<String, FrameRecord>>(text).unwrap_err();
                    assert_eq!((place.line, place.column), (whole.line(), whole.column()));
                }
                other => panic!("unexpected {other:?}"),
            }
            assert!(err.to_string().contains("in frame 1 (line 2"), "{err}");
            // Without the record-relative position serde_json would add.
            assert!(!err.to_string().contains(" at line "), "{err}");
        }
        // A syntax error that the type-only scan already meets.
        let err = SceneGraphTimeline::from_json_slice(
            b"{\"0\": {\"type\": \"full\", \"nodes\": [,]}}",
            Path::new("s.json"),
            only(&["0"]),
            TransientFilter::Off,
        )
        .unwrap_err();
        assert!(err.to_string().contains("s.json") && err.to_string().contains("in frame 0"));
        let err = SceneGraphTimeline::from_json_slice(
            b"{\"0\": {\"type\": \"empty\"} \"1\": {}}",
            Path::new("s.json"),
            FrameSelection::All,
            TransientFilter::Off,
        )
        .unwrap_err();
        assert!(err.to_string().contains("after frame 0"), "{err}");
        let err = SceneGraphTimeline::from_json_slice(
            b"{\"x7\": {\"type\": \"empty\"}}",
            Path::new("k.json"),
            FrameSelection::All,
            TransientFilter::Off,
        )
        .unwrap_err();
        assert!(matches!(err, TimelineError::FrameKey { ref key, .. } if key == "x7"));
        let err = SceneGraphTimeline::from_json_slice(
            b"[1, 2]",
            Path::new("k.json"),
            FrameSelection::All,
            TransientFilter::Off,
        )
        .unwrap_err();
        assert!(err.to_string().contains("at top level"), "{err}");
    }

    #[test]
    fn load_reads_files_and_reports_missing_ones() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene_graph_0.json");
        std::fs::write(&path, FILE).unwrap();
        let t = SceneGraphTimeline::load(&path, only(&["2"])).unwrap();
        assert_eq!(t.scene_graph("2").unwrap().nodes.len(), 2);
        let err = SceneGraphTimeline::load(&dir.path().join("nope.json"), FrameSelection::All)
            .unwrap_err();
        assert!(matches!(err, TimelineError::Io { .. }));
        assert!(err.to_string().contains("nope.json"));
    }
}
