//! A synthetic household world: a small deterministic simulator of a robot with two grippers
//! doing chores in a kitchen and a living room, written out as BEHAVIOR-format replays
//! (`{task}/scene_graph_0.json`, `{task}/external_sensor1/{frame:05}.png`) for the data
//! pipeline.
//!
//! [`things`] is the house, [`state`] its predicates and the robot's actions, [`activity`] the
//! chores, [`render`] the head camera (drawings and visibility). [`simulate`] plays one
//! activity at a realistic frame cadence: every state change is held for more than ENACT's
//! 200-frame gap, so segmentation keeps exactly one key frame per action (10 frames after it),
//! and short glitches are added that only ENACT's transient filter removes.
//! [`Simulation::write_replay`] writes the files. `command` is the `simulate` subcommand.

pub mod activity;
pub mod render;
pub mod state;
pub mod things;

use std::collections::{BTreeMap, HashMap};
use std::io::Write;
use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::scene_graph::record::DeltaSide;
use crate::scene_graph::{FrameRecord, GraphDelta, SceneEdge, SceneGraph, SceneNode};

pub use activity::Activity;
pub use render::{CameraRig, parse_colour};
pub use state::{Action, Hand, Relation, WorldState};

/// The first key frame ENACT's default segmentation keeps: it drops 10 frames and starts at
/// the 50th of the rest.
pub const FIRST_KEY_FRAME: u64 = 59;
/// Frames between a key frame and the next action: ENACT wants more than 200.
const MIN_HOLD: u64 = 201;
/// The key frame of an action is this many frames after it (ENACT's stability interval).
pub const SETTLE_FRAMES: u64 = 10;
/// BEHAVIOR's scene-graph writer stores a `full` record every this many frames.
const FULL_RECORD_INTERVAL: u64 = 200;

/// What to simulate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SimulateOptions {
    pub seed: u64,
    pub activity: Activity,
    /// Number of actions; `None` plays the activity's own script.
    pub length: Option<usize>,
    pub camera: CameraRig,
}

/// A short glitch in the recorded scene graph (physics jitter, a missed contact), of the kind
/// ENACT's transient filter exists to remove.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Flicker {
    pub start: u64,
    pub frames: u64,
    #[serde(flatten)]
    pub kind: FlickerKind,
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FlickerKind {
    /// A node state appears (or disappears) for a few frames.
    NodeState { node: String, state: String },
    /// An edge loses its states for a few frames.
    EdgeDropout { from: String, to: String },
    /// A node is not seen by the camera for a few frames.
    Unseen { node: String },
}

/// One action and the frame at which its effects appear.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TimedAction {
    pub frame: u64,
    pub action: String,
}

/// A simulated replay: what happened, when, and the frames it gives.
pub struct Simulation {
    pub task_name: String,
    pub options: SimulateOptions,
    pub num_frames: u64,
    pub actions: Vec<TimedAction>,
    /// The key frames ENACT's default segmentation should find: [`FIRST_KEY_FRAME`], then each
    /// action's frame plus [`SETTLE_FRAMES`].
    pub key_frames: Vec<u64>,
    pub flickers: Vec<Flicker>,
    /// Frame at which each state starts: state `i` holds after `i` actions.
    starts: Vec<u64>,
    /// Per state: the scene graph (with visibility) and the camera frame.
    views: Vec<(SceneGraph, image::RgbImage)>,
}

/// Why a replay could not be simulated or written.
#[derive(Debug, thiserror::Error)]
pub enum WorldError {
    #[error("invalid simulation options: {0}")]
    Options(String),
    #[error("cannot write {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot encode {path}: {source}")]
    Png {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    #[error("cannot serialise {what}: {source}")]
    Json {
        what: String,
        #[source]
        source: serde_json::Error,
    },
}

/// `{activity}_{16 digits}`, like ENACT's task names; the digits come from the seed so that
/// renderings of the same run under other camera rigs share the task name.
pub fn task_name(activity: Activity, seed: u64) -> String {
    format!(
        "{}_{}",
        activity.name(),
        1_700_000_000_000_000 + seed % 100_000_000_000_000
    )
}

fn check_options(options: &SimulateOptions) -> Result<(), WorldError> {
    let rig = &options.camera;
    if !(rig.fov_deg.is_finite() && (10.0..=150.0).contains(&rig.fov_deg)) {
        return Err(WorldError::Options(format!(
            "field of view {} is outside 10..=150 degrees",
            rig.fov_deg
        )));
    }
    if !(rig.height_m.is_finite() && (0.5..=2.5).contains(&rig.height_m)) {
        return Err(WorldError::Options(format!(
            "camera height {} is outside 0.5..=2.5 m",
            rig.height_m
        )));
    }
    if !(64..=2048).contains(&rig.image_size) {
        return Err(WorldError::Options(format!(
            "image size {} is outside 64..=2048 pixels",
            rig.image_size
        )));
    }
    if options.length == Some(0) {
        return Err(WorldError::Options(
            "length must be at least 1 action".into(),
        ));
    }
    Ok(())
}

/// Plays one activity. The same options always give the same simulation.
pub fn simulate(options: &SimulateOptions) -> Result<Simulation, WorldError> {
    check_options(options)?;
    let activity = options.activity;
    // One stream per (seed, activity), so activities of one seed are not timed alike.
    let mut rng = ChaCha8Rng::seed_from_u64(
        options.seed ^ (activity as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15),
    );
    let plan = activity.plan(options.length, &mut rng);
    let room = activity.room();

    let mut state = WorldState::initial();
    let mut states = vec![state.clone()];
    // `plan` only holds actions possible in turn; `played` keeps states and timing aligned
    // even if one were not.
    let mut played = Vec::with_capacity(plan.len());
    for action in plan {
        if state.apply(&action).is_ok() {
            states.push(state.clone());
            played.push(action);
        }
    }
    // Renders once per distinct state (an action can bring an earlier state back).
    let mut rendered: HashMap<WorldState, usize> = HashMap::new();
    let mut views: Vec<(SceneGraph, image::RgbImage)> = Vec::new();
    let mut view_of = Vec::with_capacity(states.len());
    for s in &states {
        let index = *rendered.entry(s.clone()).or_insert_with(|| {
            let view = render::render(s, room, &options.camera);
            let mut graph = s.scene_graph();
            for node in &mut graph.nodes {
                if let Some(v) = view.visibility.get(&node.name) {
                    node.visibility = v.clone();
                }
            }
            views.push((graph, view.image));
            views.len() - 1
        });
        view_of.push(index);
    }
    let views: Vec<(SceneGraph, image::RgbImage)> =
        view_of.iter().map(|&i| views[i].clone()).collect();

    let mut starts = vec![0];
    let mut key_frames = vec![FIRST_KEY_FRAME];
    let mut actions = Vec::with_capacity(played.len());
    let mut previous_key = FIRST_KEY_FRAME;
    for action in &played {
        let frame = previous_key + MIN_HOLD + rng.random_range(20..=170);
        starts.push(frame);
        actions.push(TimedAction {
            frame,
            action: action.to_string(),
        });
        previous_key = frame + SETTLE_FRAMES;
        key_frames.push(previous_key);
    }
    let num_frames = previous_key + rng.random_range(60..=140);

    let flickers = plan_flickers(&starts, num_frames, &views, &mut rng);
    Ok(Simulation {
        task_name: task_name(activity, options.seed),
        options: options.clone(),
        num_frames,
        actions,
        key_frames,
        flickers,
        starts,
        views,
    })
}

/// Glitches in the quiet stretches between actions, at least 25 frames from any change and
/// from each other, each 1 to 3 frames long.
fn plan_flickers(
    starts: &[u64],
    num_frames: u64,
    views: &[(SceneGraph, image::RgbImage)],
    rng: &mut ChaCha8Rng,
) -> Vec<Flicker> {
    let mut flickers = Vec::new();
    for (i, &from) in starts.iter().enumerate() {
        let to = starts.get(i + 1).copied().unwrap_or(num_frames);
        let graph = &views[i].0;
        let mut at = from + 25;
        for _ in 0..rng.random_range(0..=2) {
            let frames = rng.random_range(1..=3);
            let latest = to.saturating_sub(25 + frames);
            if at >= latest {
                break;
            }
            let start = rng.random_range(at..latest);
            let kind = match rng.random_range(0..3) {
                0 => {
                    let node = &graph.nodes[rng.random_range(1..graph.nodes.len())];
                    let state = ["Open", "ToggledOn", "Cooked"][rng.random_range(0..3)];
                    FlickerKind::NodeState {
                        node: node.name.clone(),
                        state: state.to_string(),
                    }
                }
                1 if !graph.edges.is_empty() => {
                    let edge = &graph.edges[rng.random_range(0..graph.edges.len())];
                    FlickerKind::EdgeDropout {
                        from: edge.from.clone(),
                        to: edge.to.clone(),
                    }
                }
                _ => FlickerKind::Unseen {
                    node: graph.nodes[rng.random_range(0..graph.nodes.len())]
                        .name
                        .clone(),
                },
            };
            flickers.push(Flicker {
                start,
                frames,
                kind,
            });
            at = start + frames + 25;
        }
    }
    flickers
}

impl Flicker {
    fn covers(&self, frame: u64) -> bool {
        (self.start..self.start + self.frames).contains(&frame)
    }

    fn apply(&self, graph: &mut SceneGraph) {
        match &self.kind {
            FlickerKind::NodeState { node, state } => {
                if let Some(n) = graph.nodes.iter_mut().find(|n| &n.name == node) {
                    if let Some(i) = n.states.iter().position(|s| s == state) {
                        n.states.remove(i);
                    } else {
                        n.states.push(state.clone());
                    }
                }
            }
            FlickerKind::EdgeDropout { from, to } => {
                if let Some(e) = graph
                    .edges
                    .iter_mut()
                    .find(|e| &e.from == from && &e.to == to)
                {
                    e.states.clear();
                }
            }
            FlickerKind::Unseen { node } => {
                if let Some(n) = graph.nodes.iter_mut().find(|n| &n.name == node) {
                    n.visibility.clear();
                }
            }
        }
    }
}

/// Which camera frames [`Simulation::write_replay`] writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FrameImages {
    /// Only the intended key frames: the only images ENACT's pipeline opens.
    #[default]
    KeyFrames,
    /// Every frame, as BEHAVIOR's frame extraction would.
    All,
}

/// How `scene_graph_0.json` stores the frames, as BEHAVIOR's writer can.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RecordMode {
    /// A `full` record every 200 frames, `diff` records where the graph changes between
    /// them, `empty` records elsewhere: compact.
    #[default]
    Mixed,
    /// Every frame's record `full`, as ENACT's published replays are written: as large as a
    /// replay gets.
    Full,
}

impl RecordMode {
    pub fn parse(text: &str) -> Option<RecordMode> {
        match text {
            "mixed" => Some(RecordMode::Mixed),
            "full" => Some(RecordMode::Full),
            _ => None,
        }
    }
}

/// What [`Simulation::write_replay`] wrote.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WrittenReplay {
    pub task_dir: PathBuf,
    pub images: usize,
}

#[derive(Serialize)]
struct WorldLog<'a> {
    task_name: &'a str,
    options: &'a SimulateOptions,
    num_frames: u64,
    actions: &'a [TimedAction],
    key_frames: &'a [u64],
    flickers: &'a [Flicker],
}

impl Simulation {
    /// Index of the state shown at `frame`.
    fn state_at(&self, frame: u64) -> usize {
        self.starts
            .partition_point(|&s| s <= frame)
            .saturating_sub(1)
    }

    /// The recorded scene graph of a frame (glitches included).
    pub fn scene_graph(&self, frame: u64) -> SceneGraph {
        let mut graph = self.views[self.state_at(frame)].0.clone();
        for flicker in self.flickers.iter().filter(|f| f.covers(frame)) {
            flicker.apply(&mut graph);
        }
        graph
    }

    /// The camera frame of a frame (glitches are in the record only, not in the picture).
    pub fn image(&self, frame: u64) -> &image::RgbImage {
        &self.views[self.state_at(frame)].1
    }

    /// The `scene_graph_0.json` records: `full` at frame 0 and every 200th frame (as
    /// BEHAVIOR's writer), otherwise a `diff` of whole nodes and edges when anything changed,
    /// or `empty`.
    pub fn records(&self) -> impl Iterator<Item = (u64, FrameRecord)> + '_ {
        self.records_in(RecordMode::Mixed)
    }

    /// Every frame's record, stored as `mode` says.
    pub fn records_in(&self, mode: RecordMode) -> impl Iterator<Item = (u64, FrameRecord)> + '_ {
        // The recorded graph only changes where a state or a glitch starts or ends.
        let mut changes: std::collections::BTreeSet<u64> = self.starts.iter().copied().collect();
        for f in &self.flickers {
            changes.insert(f.start);
            changes.insert(f.start + f.frames);
        }
        let mut previous: Option<SceneGraph> = None;
        (0..self.num_frames).map(move |frame| {
            let full = mode == RecordMode::Full
                || frame % FULL_RECORD_INTERVAL == FULL_RECORD_INTERVAL - 1;
            if previous.is_some() && !full && !changes.contains(&frame) {
                return (frame, FrameRecord::Empty);
            }
            let graph = self.scene_graph(frame);
            let record = match &previous {
                Some(prev) if !full => {
                    whole_entry_delta(prev, &graph).map_or(FrameRecord::Empty, FrameRecord::Diff)
                }
                _ => FrameRecord::Full(graph.clone()),
            };
            previous = Some(graph);
            (frame, record)
        })
    }

    /// Writes `{replayed_dir}/{task}/scene_graph_0.json`, the camera frames under
    /// `external_sensor1/`, and `world_log.json` (actions, intended key frames, glitches).
    pub fn write_replay(
        &self,
        replayed_dir: &Path,
        images: FrameImages,
    ) -> Result<WrittenReplay, WorldError> {
        self.write_replay_with(replayed_dir, images, RecordMode::Mixed)
    }

    /// [`Simulation::write_replay`] with the scene graphs stored as `mode` says.
    pub fn write_replay_with(
        &self,
        replayed_dir: &Path,
        images: FrameImages,
        mode: RecordMode,
    ) -> Result<WrittenReplay, WorldError> {
        let task_dir = replayed_dir.join(&self.task_name);
        let sensor_dir = task_dir.join(render::SENSOR);
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| WorldError::Io { path, source }
        };
        std::fs::create_dir_all(&sensor_dir).map_err(io(&sensor_dir))?;

        let graph_path = task_dir.join("scene_graph_0.json");
        let file = std::fs::File::create(&graph_path).map_err(io(&graph_path))?;
        let mut out = std::io::BufWriter::new(file);
        out.write_all(b"{").map_err(io(&graph_path))?;
        for (frame, record) in self.records_in(mode) {
            if frame > 0 {
                out.write_all(b", ").map_err(io(&graph_path))?;
            }
            write!(out, "\"{frame}\": ").map_err(io(&graph_path))?;
            serde_json::to_writer(&mut out, &record).map_err(|source| WorldError::Json {
                what: format!("frame {frame}"),
                source,
            })?;
        }
        out.write_all(b"}").map_err(io(&graph_path))?;
        out.flush().map_err(io(&graph_path))?;

        let frames: Vec<u64> = match images {
            FrameImages::KeyFrames => self.key_frames.clone(),
            FrameImages::All => (0..self.num_frames).collect(),
        };
        // One encoding per state, copied to every frame showing it.
        let mut encoded: BTreeMap<usize, Vec<u8>> = BTreeMap::new();
        for &frame in &frames {
            let path = sensor_dir.join(format!("{frame:05}.png"));
            let state = self.state_at(frame);
            if let std::collections::btree_map::Entry::Vacant(slot) = encoded.entry(state) {
                let mut bytes = Vec::new();
                self.views[state]
                    .1
                    .write_to(
                        &mut std::io::Cursor::new(&mut bytes),
                        image::ImageFormat::Png,
                    )
                    .map_err(|source| WorldError::Png {
                        path: path.clone(),
                        source,
                    })?;
                slot.insert(bytes);
            }
            std::fs::write(&path, &encoded[&state]).map_err(io(&path))?;
        }

        let log_path = task_dir.join("world_log.json");
        let log = WorldLog {
            task_name: &self.task_name,
            options: &self.options,
            num_frames: self.num_frames,
            actions: &self.actions,
            key_frames: &self.key_frames,
            flickers: &self.flickers,
        };
        let text = serde_json::to_vec_pretty(&log).map_err(|source| WorldError::Json {
            what: "world_log.json".into(),
            source,
        })?;
        std::fs::write(&log_path, text).map_err(io(&log_path))?;
        Ok(WrittenReplay {
            task_dir,
            images: frames.len(),
        })
    }
}

/// A diff record that replaces whole nodes and edges (visibility included), unlike
/// [`GraphDelta::between`], which only carries state lists.
fn whole_entry_delta(prev: &SceneGraph, next: &SceneGraph) -> Option<GraphDelta> {
    let mut add = DeltaSide::default();
    let mut remove = DeltaSide::default();
    let mut update = DeltaSide::default();
    let find_node = |g: &SceneGraph, name: &str| -> Option<SceneNode> {
        g.nodes.iter().find(|n| n.name == name).cloned()
    };
    for node in &next.nodes {
        match find_node(prev, &node.name) {
            None => add.nodes.push(node.clone()),
            Some(old) if old != *node => update.nodes.push(node.clone()),
            Some(_) => {}
        }
    }
    for node in &prev.nodes {
        if find_node(next, &node.name).is_none() {
            remove.nodes.push(node.clone());
        }
    }
    let find_edge = |g: &SceneGraph, e: &SceneEdge| -> Option<SceneEdge> {
        g.edges
            .iter()
            .find(|x| x.from == e.from && x.to == e.to)
            .cloned()
    };
    for edge in &next.edges {
        match find_edge(prev, edge) {
            None => add.edges.push(edge.clone()),
            Some(old) if old != *edge => update.edges.push(edge.clone()),
            Some(_) => {}
        }
    }
    for edge in &prev.edges {
        if find_edge(next, edge).is_none() {
            remove.edges.push(edge.clone());
        }
    }
    let empty = |s: &DeltaSide| s.nodes.is_empty() && s.edges.is_empty();
    if empty(&add) && empty(&remove) && empty(&update) {
        return None;
    }
    Some(GraphDelta {
        add: Some(add),
        remove: Some(remove),
        update: Some(update),
    })
}
