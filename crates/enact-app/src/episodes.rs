//! Real-world episodes: importing a folder of recorded frames, each curator's key frames and
//! scene graphs, the admin's resolved graphs, the two-curator comparison, and the export in
//! ENACT's replay layout that `generate` makes items from.

use std::cmp::Ordering;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use bytes::Bytes;
use serde::Serialize;
use sha2::{Digest, Sha256};

use super::refusal::{Expected, Refusal};
use super::{AppError, Hub, audit};
use crate::Lane;
use crate::core::audit::{Actor, AuditAction};
use crate::core::episode::{self, Comparison, EpisodeGraphs, GraphProblem};
use crate::store::{self, db::UniqueKey};

/// The longest side of a filmstrip copy, in pixels.
pub const THUMBNAIL_SIDE: u32 = 192;

/// An episode as listed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EpisodeSummary {
    pub name: String,
    pub scene: String,
    pub created_by: String,
    pub created_at: String,
    pub frame_count: usize,
    /// Curators who stored graphs, by name.
    pub curators: Vec<String>,
    /// Who chose the graphs the export uses, when someone did.
    pub resolved_by: Option<String>,
}

/// One frame of an episode: where it came from and the hashes its image and filmstrip copy
/// are served by (`/frames/{sha256}`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EpisodeFrame {
    pub position: usize,
    pub file_name: String,
    pub sha256: String,
    pub width: u32,
    pub height: u32,
    pub thumbnail_sha256: String,
}

/// An episode with its frames in order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Episode {
    #[serde(flatten)]
    pub summary: EpisodeSummary,
    pub frames: Vec<EpisodeFrame>,
}

/// Compares file names the way people number frames: runs of digits by value
/// (`frame2.png` before `frame10.png`), everything else by character.
pub fn natural_order(a: &str, b: &str) -> Ordering {
    fn chunks(s: &str) -> Vec<(bool, &str)> {
        let mut out = Vec::new();
        let mut start = 0;
        let mut digits = None;
        for (i, c) in s.char_indices() {
            let d = c.is_ascii_digit();
            if digits.is_some_and(|prev| prev != d) {
                out.push((digits == Some(true), &s[start..i]));
                start = i;
            }
            digits = Some(d);
        }
        if start < s.len() {
            out.push((digits == Some(true), &s[start..]));
        }
        out
    }
    let (ca, cb) = (chunks(a), chunks(b));
    for ((da, xa), (db, xb)) in ca.iter().zip(&cb) {
        let order = if *da && *db {
            let (ta, tb) = (xa.trim_start_matches('0'), xb.trim_start_matches('0'));
            ta.len().cmp(&tb.len()).then_with(|| ta.cmp(tb))
        } else {
            xa.cmp(xb)
        };
        if order != Ordering::Equal {
            return order;
        }
    }
    ca.len().cmp(&cb.len()).then_with(|| a.cmp(b))
}

/// The frame files of `dir` in natural order; anything else in it is refused by name.
fn frame_files(dir: &Path) -> Result<Vec<(String, PathBuf)>, AppError> {
    let unreadable = |e: std::io::Error| {
        AppError::Invalid(format!(
            "cannot read the frame folder {}: {e}",
            dir.display()
        ))
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(unreadable)? {
        let entry = entry.map_err(unreadable)?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let path = entry.path();
        let lower = name.to_ascii_lowercase();
        let is_image = [".png", ".jpg", ".jpeg"]
            .iter()
            .any(|ext| lower.ends_with(ext));
        if !path.is_file() || !is_image {
            return Err(AppError::Invalid(format!(
                "{}: only PNG and JPEG frames (.png, .jpg, .jpeg) may be in the frame folder",
                path.display()
            )));
        }
        files.push((name, path));
    }
    if files.is_empty() {
        return Err(AppError::Invalid(format!(
            "{} holds no frame (PNG or JPEG files)",
            dir.display()
        )));
    }
    files.sort_by(|a, b| natural_order(&a.0, &b.0));
    Ok(files)
}

/// A frame as stored: PNG bytes (JPEG inputs converted, PNG kept byte for byte) and a
/// filmstrip copy.
struct PreparedFrame {
    png: Vec<u8>,
    width: u32,
    height: u32,
    thumbnail: Vec<u8>,
    thumbnail_size: (u32, u32),
}

fn encode_png(image: &image::DynamicImage) -> Result<Vec<u8>, image::ImageError> {
    let mut out = Cursor::new(Vec::new());
    image.write_to(&mut out, image::ImageFormat::Png)?;
    Ok(out.into_inner())
}

fn prepare_frame(path: &Path) -> Result<PreparedFrame, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let format = image::guess_format(&bytes)
        .map_err(|_| format!("{}: not a PNG or JPEG image", path.display()))?;
    if !matches!(format, image::ImageFormat::Png | image::ImageFormat::Jpeg) {
        return Err(format!(
            "{}: a {format:?} image; frames must be PNG or JPEG",
            path.display()
        ));
    }
    let image = image::load_from_memory_with_format(&bytes, format)
        .map_err(|e| format!("{}: cannot decode the image: {e}", path.display()))?;
    let png = match format {
        image::ImageFormat::Png => bytes,
        _ => encode_png(&image).map_err(|e| format!("{}: {e}", path.display()))?,
    };
    let small = image.thumbnail(THUMBNAIL_SIDE, THUMBNAIL_SIDE);
    let thumbnail = encode_png(&small).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(PreparedFrame {
        png,
        width: image.width(),
        height: image.height(),
        thumbnail,
        thumbnail_size: (small.width(), small.height()),
    })
}

/// Stores a PNG as a frame (once per content), in the object store when there is one.
async fn store_frame(
    hub: &Hub,
    tx: &mut store::Tx,
    png: Vec<u8>,
    (width, height): (u32, u32),
) -> Result<i64, AppError> {
    let sha256 = hex::encode(Sha256::digest(&png));
    if let Some(id) = store::frames::id_by_hash(&mut *tx, &sha256).await? {
        return Ok(id);
    }
    let held_here = match hub.frame_store().objects() {
        Some(objects) => {
            objects.put(&sha256, Bytes::from(png)).await?;
            Vec::new()
        }
        None => png,
    };
    Ok(store::frames::insert(&mut *tx, &sha256, width, height, &held_here).await?)
}

/// Imports the PNG and JPEG frames of `dir`, ordered by file name naturally, as episode
/// `name`. Every file is checked before anything is stored: another kind of file or an
/// image that does not decode is refused by name, and nothing is written. One import of a
/// name runs at a time ([`claim_name`]): a second one is refused while the first is alive.
pub async fn import(
    hub: &Hub,
    actor: &Actor,
    dir: &Path,
    name: &str,
    scene: &str,
) -> Result<EpisodeSummary, AppError> {
    check_name(name)?;
    let files = {
        let dir = dir.to_path_buf();
        hub.heavy()
            .run_waiting(move || {
                let files = frame_files(&dir)?;
                // Decode every frame once before storing any, so a bad one refuses the import.
                for (_, path) in &files {
                    image::ImageReader::open(path)
                        .and_then(|r| r.with_guessed_format())
                        .map_err(|e| AppError::Invalid(format!("{}: {e}", path.display())))?
                        .decode()
                        .map_err(|e| {
                            AppError::Invalid(format!(
                                "{}: cannot decode the image: {e}",
                                path.display()
                            ))
                        })?;
                }
                Ok::<_, AppError>(files)
            })
            .await?
    };
    let episode = claim_name(hub, actor, name, scene).await?;
    // The frames are converted outside any transaction and written a few per transaction, so
    // a long recording never holds the write lock for long; the episode stays hidden until
    // the last is written. A failure removes what was written.
    if let Err(e) = write_frames(hub, name, episode, &files).await {
        if let Err(cleanup) = remove_incomplete(hub, episode).await {
            tracing::warn!(episode = name, error = %cleanup, "an incomplete episode was left");
        }
        return Err(e);
    }
    let mut tx = hub.write(Lane::Interactive).await?;
    if !store::episodes::mark_complete(&mut tx, episode).await? {
        return Err(taken_over(name));
    }
    audit::record(
        &mut tx,
        actor,
        AuditAction::EpisodeImport,
        format!("episode {name}"),
        None,
        format!(
            "{} frames from {}{}",
            files.len(),
            dir.display(),
            if scene.is_empty() {
                String::new()
            } else {
                format!(", scene {scene}")
            }
        ),
    )
    .await?;
    tx.commit().await?;
    Ok(get(hub, name).await?.summary)
}

/// Frames of an episode written per transaction.
const FRAMES_PER_BATCH: usize = 8;

/// How long an import's claim on its episode name lasts past its last batch of frames
/// ([`claim_name`]). A batch is 8 frames converted on the heavy pool, then a wait for the
/// turn to write (at most 10 s): far less than this, unless the import was killed or stalled.
pub const IMPORT_CLAIM_LIFE: std::time::Duration = std::time::Duration::from_secs(60);

fn claim_until() -> i64 {
    super::annotators::now_ms() + i64::try_from(IMPORT_CLAIM_LIFE.as_millis()).unwrap_or(i64::MAX)
}

/// The refusal of an import whose claim another import took over after it had said nothing
/// for [`IMPORT_CLAIM_LIFE`].
fn taken_over(name: &str) -> AppError {
    Refusal::EpisodeTakenOver {
        episode: name.to_owned(),
        after: IMPORT_CLAIM_LIFE.as_secs(),
    }
    .into()
}

/// Claims `name` for this import: writes its incomplete episode, in one write transaction
/// with the decision. Another import's incomplete episode refuses the claim while that
/// import is alive (it renews its claim with every batch), and is removed, with the frames only
/// it used, once its claim has lapsed: that import was killed or stalled.
async fn claim_name(hub: &Hub, actor: &Actor, name: &str, scene: &str) -> Result<i64, AppError> {
    let mut tx = hub.write(Lane::Bulk).await?;
    let now = super::annotators::now_ms();
    let left = match store::episodes::incomplete(&mut tx, name).await? {
        Some(claim) => match claim.alive_until_ms {
            Some(until) if until > now => {
                return Err(Refusal::EpisodeImporting {
                    episode: name.to_owned(),
                    since: claim.created_at,
                    by: claim.created_by,
                    lapses_in: ((until - now + 999) / 1000).unsigned_abs(),
                }
                .into());
            }
            _ => {
                store::episodes::delete_incomplete(&mut tx, claim.episode).await?;
                true
            }
        },
        None => false,
    };
    let inserted =
        store::episodes::insert(&mut tx, name, scene, &actor.to_string(), claim_until()).await;
    let episode = match inserted {
        Ok(id) => id,
        Err(e) if UniqueKey::EPISODE_NAME.is_violated_by(&e) => {
            return Err(Refusal::EpisodeExists {
                episode: name.to_owned(),
            }
            .into());
        }
        Err(e) => return Err(e.into()),
    };
    tx.commit().await?;
    if left {
        super::import::delete_unused_frames(hub).await?;
    }
    Ok(episode)
}

/// Converts and stores the frames of an incomplete episode, [`FRAMES_PER_BATCH`] per
/// transaction.
async fn write_frames(
    hub: &Hub,
    name: &str,
    episode: i64,
    files: &[(String, PathBuf)],
) -> Result<(), AppError> {
    for (batch, chunk) in files.chunks(FRAMES_PER_BATCH).enumerate() {
        let mut prepared = Vec::with_capacity(chunk.len());
        for (_, path) in chunk {
            let path = path.clone();
            prepared.push(
                hub.heavy()
                    .run_waiting(move || prepare_frame(&path))
                    .await
                    .map_err(AppError::Invalid)?,
            );
        }
        let mut tx = hub.write(Lane::Bulk).await?;
        if !store::episodes::renew_claim(&mut tx, episode, claim_until()).await? {
            return Err(taken_over(name));
        }
        for (offset, ((file_name, _), frame)) in chunk.iter().zip(prepared).enumerate() {
            let size = (frame.width, frame.height);
            let stored = store_frame(hub, &mut tx, frame.png, size).await?;
            let thumbnail =
                store_frame(hub, &mut tx, frame.thumbnail, frame.thumbnail_size).await?;
            let position = (batch * FRAMES_PER_BATCH + offset) as i64;
            store::episodes::insert_frame(&mut tx, episode, position, file_name, stored, thumbnail)
                .await?;
        }
        tx.commit().await?;
    }
    Ok(())
}

/// Deletes an incomplete episode and the frames only it used, a batch per transaction.
async fn remove_incomplete(hub: &Hub, episode: i64) -> Result<(), AppError> {
    let mut tx = hub.write(Lane::Bulk).await?;
    store::episodes::delete_incomplete(&mut tx, episode).await?;
    tx.commit().await?;
    Ok(super::import::delete_unused_frames(hub).await?)
}

/// Episode names become task folder names in the export: letters, digits, `_` and `-`.
fn check_name(name: &str) -> Result<(), AppError> {
    let ok = !name.is_empty()
        && name.len() <= 100
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if ok {
        Ok(())
    } else {
        Err(Refusal::bad_value("episode", name, Expected::PlainName { most: 100 }).into())
    }
}

async fn summary(
    conn: &mut store::Conn,
    row: store::episodes::EpisodeRow,
) -> Result<EpisodeSummary, AppError> {
    let curators = store::episodes::graphs(conn, row.id)
        .await?
        .into_iter()
        .map(|g| g.curator)
        .collect();
    Ok(EpisodeSummary {
        name: row.name,
        scene: row.scene,
        created_by: row.created_by,
        created_at: row.created_at,
        frame_count: usize::try_from(row.frame_count).unwrap_or_default(),
        curators,
        resolved_by: row.resolved_by,
    })
}

/// Every episode, by name.
pub async fn list(hub: &Hub) -> Result<Vec<EpisodeSummary>, AppError> {
    let mut conn = hub.conn().await?;
    let rows = store::episodes::list(&mut conn).await?;
    let mut out = Vec::with_capacity(rows.len());
    for row in rows {
        out.push(summary(&mut conn, row).await?);
    }
    Ok(out)
}

async fn row(conn: &mut store::Conn, name: &str) -> Result<store::episodes::EpisodeRow, AppError> {
    store::episodes::by_name(conn, name).await?.ok_or_else(|| {
        AppError::from(Refusal::NoEpisode {
            episode: name.to_owned(),
        })
    })
}

/// An episode and its frames in order.
pub async fn get(hub: &Hub, name: &str) -> Result<Episode, AppError> {
    let mut conn = hub.conn().await?;
    let row = row(&mut conn, name).await?;
    let frames = store::episodes::frames(&mut conn, row.id)
        .await?
        .into_iter()
        .map(|f| EpisodeFrame {
            position: usize::try_from(f.position).unwrap_or_default(),
            file_name: f.file_name,
            sha256: f.sha256,
            width: u32::try_from(f.width).unwrap_or_default(),
            height: u32::try_from(f.height).unwrap_or_default(),
            thumbnail_sha256: f.thumbnail_sha256,
        })
        .collect();
    Ok(Episode {
        summary: summary(&mut conn, row).await?,
        frames,
    })
}

/// Reads a stored graphs file back into the struct that wrote it.
fn parse_stored(json: &str, what: &str) -> Result<EpisodeGraphs, AppError> {
    serde_json::from_str(json)
        .map_err(|e| AppError::internal(format!("the stored {what} do not read back: {e}")))
}

/// A curator's graphs of an episode; `None` when the curator stored none.
pub async fn graphs(
    hub: &Hub,
    name: &str,
    curator: &str,
) -> Result<Option<EpisodeGraphs>, AppError> {
    let mut conn = hub.conn().await?;
    let row = row(&mut conn, name).await?;
    store::episodes::graphs(&mut conn, row.id)
        .await?
        .into_iter()
        .find(|g| g.curator == curator)
        .map(|g| parse_stored(&g.graphs, &format!("graphs of {curator}")))
        .transpose()
}

/// The refusal of a graphs file, every problem on its own line.
fn refusal(name: &str, problems: &[GraphProblem]) -> AppError {
    let lines: Vec<String> = problems.iter().map(|p| format!("  {p}")).collect();
    AppError::Invalid(format!(
        "the graphs of episode '{name}' were refused ({} problem{}):\n{}",
        problems.len(),
        if problems.len() == 1 { "" } else { "s" },
        lines.join("\n")
    ))
}

/// Replaces `curator`'s key frames and graphs of episode `name` with `graphs`, after checking
/// them against the episode; refused whole (nothing stored) when any problem is found.
pub async fn set_graphs(
    hub: &Hub,
    actor: &Actor,
    name: &str,
    curator: &str,
    graphs: &EpisodeGraphs,
) -> Result<(), AppError> {
    if curator.trim().is_empty() {
        return Err(Refusal::FieldsRequired {
            fields: vec!["curator"],
        }
        .into());
    }
    let mut tx = hub.write(Lane::Interactive).await?;
    let row = row(&mut tx, name).await?;
    let frame_count = usize::try_from(row.frame_count).unwrap_or_default();
    episode::validate(graphs, frame_count).map_err(|p| refusal(name, &p))?;
    let json = serde_json::to_string(graphs)?;
    store::episodes::set_graphs(&mut tx, row.id, curator, &json).await?;
    audit::record(
        &mut tx,
        actor,
        AuditAction::EpisodeGraphs,
        format!("episode {name}"),
        None,
        format!(
            "graphs of curator {curator}: {} key frames",
            graphs.key_frames.len()
        ),
    )
    .await?;
    tx.commit().await?;
    Ok(())
}

/// Where the graphs an admin resolves to come from.
#[derive(Debug, Clone)]
pub enum Resolution {
    /// One curator's stored graphs, as they are.
    Curator(String),
    /// Graphs the admin merged by hand.
    Graphs(EpisodeGraphs),
}

/// Chooses the graphs episode `name` exports (checked like a curator's).
pub async fn resolve(
    hub: &Hub,
    actor: &Actor,
    name: &str,
    resolution: Resolution,
) -> Result<(), AppError> {
    let mut tx = hub.write(Lane::Interactive).await?;
    let row = row(&mut tx, name).await?;
    let (graphs, from) = match resolution {
        Resolution::Curator(curator) => {
            let stored = store::episodes::graphs(&mut tx, row.id)
                .await?
                .into_iter()
                .find(|g| g.curator == curator)
                .ok_or_else(|| Refusal::NoCuratorGraphs {
                    episode: name.to_owned(),
                    curator: curator.clone(),
                })?;
            (
                parse_stored(&stored.graphs, "graphs")?,
                format!("the graphs of curator {curator}"),
            )
        }
        Resolution::Graphs(graphs) => (graphs, "merged graphs".to_string()),
    };
    let frame_count = usize::try_from(row.frame_count).unwrap_or_default();
    episode::validate(&graphs, frame_count).map_err(|p| refusal(name, &p))?;
    let json = serde_json::to_string(&graphs)?;
    store::episodes::set_resolved(&mut tx, row.id, &json, &actor.to_string()).await?;
    audit::record(
        &mut tx,
        actor,
        AuditAction::EpisodeResolve,
        format!("episode {name}"),
        None,
        format!("{from}: {} key frames", graphs.key_frames.len()),
    )
    .await?;
    tx.commit().await?;
    Ok(())
}

/// Where curators `a` and `b` differ on episode `name`.
pub async fn compare(hub: &Hub, name: &str, a: &str, b: &str) -> Result<Comparison, AppError> {
    let missing = |curator: &str| Refusal::NoCuratorGraphs {
        episode: name.to_owned(),
        curator: curator.to_owned(),
    };
    let ga = graphs(hub, name, a).await?.ok_or_else(|| missing(a))?;
    let gb = graphs(hub, name, b).await?.ok_or_else(|| missing(b))?;
    Ok(episode::compare(&ga, &gb))
}

/// The graphs an export uses: the resolved ones, else the only curator's.
async fn export_graphs(
    conn: &mut store::Conn,
    row: &store::episodes::EpisodeRow,
) -> Result<EpisodeGraphs, AppError> {
    if let Some(resolved) = &row.resolved_graphs {
        return parse_stored(resolved, "resolved graphs");
    }
    let stored = store::episodes::graphs(conn, row.id).await?;
    match stored.as_slice() {
        [only] => parse_stored(&only.graphs, "graphs"),
        [] => Err(Refusal::EpisodeHasNoGraphs {
            episode: row.name.clone(),
        }
        .into()),
        several => Err(Refusal::EpisodeNotResolved {
            episode: row.name.clone(),
            curators: several
                .iter()
                .map(|g| g.curator.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        }
        .into()),
    }
}

/// What [`export`] wrote.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExportReport {
    /// `OUT/replayed_activities`: what `generate` reads.
    pub replayed_dir: PathBuf,
    /// The task folder's name (the episode's).
    pub task: String,
    pub frames: usize,
    pub key_frames: Vec<String>,
}

/// Writes episode `name` under `out` in ENACT's layout: `replayed_activities/{name}/` with
/// `scene_graph_0.json` (a full record per key frame), the marker of the curator's key frames
/// and every frame as `external_sensor1/{position:05}.png`, and
/// `segmented_activities/{name}/segmented_scene_graph_0.json`. The graphs are the resolved
/// ones, else the only curator's; they are checked again (at least four key frames, the
/// fewest a step length of 3 needs).
pub async fn export(hub: &Hub, name: &str, out: &Path) -> Result<ExportReport, AppError> {
    let episode = get(hub, name).await?;
    let graphs = {
        let mut conn = hub.conn().await?;
        let row = row(&mut conn, name).await?;
        export_graphs(&mut conn, &row).await?
    };
    episode::validate(&graphs, episode.frames.len()).map_err(|p| refusal(name, &p))?;
    if graphs.key_frames.len() < episode::MIN_EXPORT_KEY_FRAMES {
        return Err(Refusal::TooFewKeyFrames {
            episode: name.to_owned(),
            key_frames: graphs.key_frames.len() as u64,
            least: episode::MIN_EXPORT_KEY_FRAMES as u64,
        }
        .into());
    }
    let size_of = |frame: usize| {
        episode
            .frames
            .get(frame)
            .map_or(episode::FrameSize::NOMINAL, |f| episode::FrameSize {
                width: f.width,
                height: f.height,
            })
    };
    let task = episode::export_task(name, &episode.summary.scene, &graphs, size_of);
    let replayed_dir = out.join("replayed_activities");
    let task_dir = replayed_dir.join(name);
    let images = task_dir.join("external_sensor1");
    let segmented_dir = out.join("segmented_activities").join(name);
    let write_error = |path: &Path, e: std::io::Error| {
        AppError::Invalid(format!("cannot write {}: {e}", path.display()))
    };
    for dir in [&images, &segmented_dir] {
        tokio::fs::create_dir_all(dir)
            .await
            .map_err(|e| write_error(dir, e))?;
    }
    let files = [
        (task_dir.join("scene_graph_0.json"), &task.scene_graph),
        (
            segmented_dir.join("segmented_scene_graph_0.json"),
            &task.segmented,
        ),
    ];
    for (path, value) in files {
        let text = serde_json::to_vec_pretty(value)?;
        tokio::fs::write(&path, text)
            .await
            .map_err(|e| write_error(&path, e))?;
    }
    let marker = task_dir.join(crate::core::pipeline::marked::MARKED_KEY_FRAMES_FILE);
    tokio::fs::write(&marker, serde_json::to_vec_pretty(&task.marked)?)
        .await
        .map_err(|e| write_error(&marker, e))?;
    for frame in &episode.frames {
        let png = super::frames::png(hub, &frame.sha256).await?;
        let path = images.join(format!("{:05}.png", frame.position));
        tokio::fs::write(&path, &png)
            .await
            .map_err(|e| write_error(&path, e))?;
    }
    Ok(ExportReport {
        replayed_dir,
        task: name.to_string(),
        frames: episode.frames.len(),
        key_frames: task.marked.key_frames,
    })
}
