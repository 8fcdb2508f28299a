//! The episode pages' use cases, over [`crate::episodes`]: what a curator's editor opens
//! with (their draft, else their stored graphs), the live description of unsaved graphs,
//! drafts, saving, frames uploaded through the browser, and the admin's comparison of two
//! curators and resolution key frame by key frame.

use std::collections::BTreeMap;

use bytes::Bytes;

use super::refusal::Refusal;
use crate::Lane;
use crate::annotators::now_ms;
use crate::core::audit::Actor;
use crate::core::episode::{
    self, Comparison, EpisodeGraphs, GraphProblem, KeyFrameGraph, TransitionView,
};
use crate::episodes::{self, Episode, EpisodeSummary, Resolution};
use crate::store;
use crate::{AppError, Hub};

/// What a curator's episode page opens with.
#[derive(Debug, Clone)]
pub struct CuratorView {
    pub episode: Episode,
    pub graphs: EpisodeGraphs,
    /// Whether `graphs` is the curator's unsaved draft (else their stored graphs, or none).
    pub from_draft: bool,
}

async fn episode_id(conn: &mut store::Conn, name: &str) -> Result<i64, AppError> {
    Ok(store::episodes::by_name(conn, name)
        .await?
        .ok_or_else(|| {
            AppError::from(Refusal::NoEpisode {
                episode: name.to_owned(),
            })
        })?
        .id)
}

/// Episode `name` for `curator`: their draft if they left one, else the graphs they stored.
pub async fn open(hub: &Hub, curator: &str, name: &str) -> Result<CuratorView, AppError> {
    let episode = episodes::get(hub, name).await?;
    let draft = {
        let mut conn = hub.conn().await?;
        let id = episode_id(&mut conn, name).await?;
        store::episode_drafts::get(&mut conn, id, curator).await?
    };
    if let Some(json) = draft {
        let graphs = serde_json::from_str(&json)
            .map_err(|e| AppError::internal(format!("the stored draft does not read back: {e}")))?;
        return Ok(CuratorView {
            episode,
            graphs,
            from_draft: true,
        });
    }
    let graphs = episodes::graphs(hub, name, curator)
        .await?
        .unwrap_or_default();
    Ok(CuratorView {
        episode,
        graphs,
        from_draft: false,
    })
}

/// Each transition of `graphs` as ENACT will see it, and every problem saving them would
/// meet, for episode `name`. Stores nothing.
pub async fn describe(
    hub: &Hub,
    name: &str,
    graphs: &EpisodeGraphs,
) -> Result<(Vec<TransitionView>, Vec<GraphProblem>), AppError> {
    let frame_count = {
        let mut conn = hub.conn().await?;
        store::episodes::by_name(&mut conn, name)
            .await?
            .ok_or_else(|| {
                AppError::from(Refusal::NoEpisode {
                    episode: name.to_owned(),
                })
            })?
            .frame_count
    };
    let problems = episode::validate(graphs, usize::try_from(frame_count).unwrap_or_default())
        .err()
        .unwrap_or_default();
    Ok((episode::describe(graphs), problems))
}

/// Keeps `graphs` as `curator`'s draft of episode `name`, unchecked (a draft may be half
/// drawn). Drafts are not audited, as annotation drafts are not: saving is.
pub async fn save_draft(
    hub: &Hub,
    curator: &str,
    name: &str,
    graphs: &EpisodeGraphs,
) -> Result<(), AppError> {
    let json = serde_json::to_string(graphs)?;
    let mut tx = hub.write(Lane::Interactive).await?;
    let id = episode_id(&mut tx, name).await?;
    store::episode_drafts::save(&mut tx, id, curator, &json, now_ms()).await?;
    tx.commit().await?;
    Ok(())
}

/// Checks and stores `graphs` as `curator`'s graphs of episode `name` (audited, refused whole
/// with every problem named), then drops their draft. Returns the stored transitions.
pub async fn save(
    hub: &Hub,
    actor: &Actor,
    curator: &str,
    name: &str,
    graphs: &EpisodeGraphs,
) -> Result<Vec<TransitionView>, AppError> {
    episodes::set_graphs(hub, actor, name, curator, graphs).await?;
    // After the graphs are stored: if this fails the draft stays, equal to what was saved.
    let mut tx = hub.write(Lane::Interactive).await?;
    let id = episode_id(&mut tx, name).await?;
    store::episode_drafts::remove(&mut tx, id, curator).await?;
    tx.commit().await?;
    Ok(episode::describe(graphs))
}

/// One frame file sent through the upload form.
#[derive(Debug, Clone)]
pub struct UploadedFrame {
    pub file_name: String,
    pub bytes: Bytes,
}

/// The last component of an uploaded file's name (browsers may send a path), refused when
/// nothing usable is left.
fn upload_file_name(sent: &str) -> Result<&str, AppError> {
    let base = sent.rsplit(['/', '\\']).next().unwrap_or_default().trim();
    if base.is_empty() || base == "." || base == ".." {
        return Err(Refusal::FrameNameUnusable {
            name: sent.to_owned(),
        }
        .into());
    }
    Ok(base)
}

/// Imports frames uploaded through the browser as episode `name`, exactly as
/// [`episodes::import`] imports a folder: they are written to a temporary folder under their
/// own names first (two files of one name are refused), so the order and the checks are the
/// same.
pub async fn import_upload(
    hub: &Hub,
    actor: &Actor,
    name: &str,
    scene: &str,
    frames: Vec<UploadedFrame>,
) -> Result<EpisodeSummary, AppError> {
    if frames.is_empty() {
        return Err(Refusal::EmptyList { field: "frames" }.into());
    }
    let dir = tempfile::tempdir().map_err(AppError::internal)?;
    let mut seen = std::collections::BTreeSet::new();
    for frame in &frames {
        let file = upload_file_name(&frame.file_name)?;
        if !seen.insert(file.to_owned()) {
            return Err(Refusal::ListedTwice {
                field: "frames",
                item: file.to_owned(),
            }
            .into());
        }
        tokio::fs::write(dir.path().join(file), &frame.bytes)
            .await
            .map_err(AppError::internal)?;
    }
    episodes::import(hub, actor, dir.path(), name, scene).await
}

/// Two curators' graphs of an episode compared, with what the resolution form needs.
#[derive(Debug, Clone)]
pub struct CuratorComparison {
    pub episode: String,
    pub a: String,
    pub b: String,
    /// Every curator who stored graphs of the episode.
    pub curators: Vec<String>,
    pub comparison: Comparison,
    /// Each curator's key frames, by frame position.
    key_frames: BTreeMap<String, BTreeMap<usize, KeyFrameGraph>>,
    /// The resolved graphs' key frames, by frame position.
    resolved: BTreeMap<usize, KeyFrameGraph>,
}

impl CuratorComparison {
    /// The curators with a key frame at `frame`.
    pub fn curators_at(&self, frame: usize) -> Vec<String> {
        self.key_frames
            .iter()
            .filter(|(_, frames)| frames.contains_key(&frame))
            .map(|(curator, _)| curator.clone())
            .collect()
    }

    /// Whose key frame the resolved graphs hold at `frame` (curator A first when several
    /// drew it alike); `None` when nothing is resolved there.
    pub fn resolved_from(&self, frame: usize) -> Option<String> {
        let resolved = self.resolved.get(&frame)?;
        let mut order = vec![self.a.clone(), self.b.clone()];
        order.extend(self.curators.iter().cloned());
        order
            .into_iter()
            .find(|c| self.key_frames.get(c).and_then(|f| f.get(&frame)) == Some(resolved))
    }
}

fn by_frame(graphs: EpisodeGraphs) -> BTreeMap<usize, KeyFrameGraph> {
    graphs
        .key_frames
        .into_iter()
        .map(|k| (k.frame, k))
        .collect()
}

/// Curators `a` and `b` (by default the first two by name) of episode `name` compared.
pub async fn compare(
    hub: &Hub,
    name: &str,
    a: Option<&str>,
    b: Option<&str>,
) -> Result<CuratorComparison, AppError> {
    let summary = episodes::get(hub, name).await?.summary;
    let mut curators = summary.curators.clone();
    curators.sort();
    let pick = |chosen: Option<&str>, index: usize| {
        chosen
            .map(str::to_owned)
            .or_else(|| curators.get(index).cloned())
            .ok_or_else(|| Refusal::TooFewCurators {
                episode: name.to_owned(),
                curators: curators.len() as u64,
            })
    };
    let (a, b) = (pick(a, 0)?, pick(b, 1)?);
    let comparison = episodes::compare(hub, name, &a, &b).await?;
    let mut key_frames = BTreeMap::new();
    for curator in &curators {
        if let Some(graphs) = episodes::graphs(hub, name, curator).await? {
            key_frames.insert(curator.clone(), by_frame(graphs));
        }
    }
    let resolved = {
        let mut conn = hub.conn().await?;
        let row = store::episodes::by_name(&mut conn, name)
            .await?
            .ok_or_else(|| {
                AppError::from(Refusal::NoEpisode {
                    episode: name.to_owned(),
                })
            })?;
        match row.resolved_graphs {
            Some(json) => by_frame(serde_json::from_str(&json).map_err(|e| {
                AppError::internal(format!("the resolved graphs do not read back: {e}"))
            })?),
            None => BTreeMap::new(),
        }
    };
    Ok(CuratorComparison {
        episode: summary.name,
        a,
        b,
        curators,
        comparison,
        key_frames,
        resolved,
    })
}

/// Resolves episode `name` key frame by key frame: `choices` names, per frame position, the
/// curator whose key frame (graph and visibility) the resolved graphs take; frames not
/// chosen are left out. Checked and audited as [`episodes::resolve`] does.
pub async fn resolve_by_key_frame(
    hub: &Hub,
    actor: &Actor,
    name: &str,
    choices: &[(usize, String)],
) -> Result<EpisodeGraphs, AppError> {
    let mut drawn: BTreeMap<&str, BTreeMap<usize, KeyFrameGraph>> = BTreeMap::new();
    let mut key_frames = BTreeMap::new();
    for (frame, curator) in choices {
        if !drawn.contains_key(curator.as_str()) {
            let graphs = episodes::graphs(hub, name, curator).await?.ok_or_else(|| {
                Refusal::NoCuratorGraphs {
                    episode: name.to_owned(),
                    curator: curator.clone(),
                }
            })?;
            drawn.insert(curator, by_frame(graphs));
        }
        let key_frame = drawn
            .get(curator.as_str())
            .and_then(|frames| frames.get(frame))
            .ok_or_else(|| Refusal::NoKeyFrame {
                episode: name.to_owned(),
                curator: curator.clone(),
                frame: *frame as u64,
            })?;
        key_frames.insert(*frame, key_frame.clone());
    }
    let graphs = EpisodeGraphs {
        key_frames: key_frames.into_values().collect(),
    };
    // All from one curator: recorded as that curator's graphs, which they are.
    let resolution = match drawn.keys().collect::<Vec<_>>().as_slice() {
        [only] if drawn[*only].len() == graphs.key_frames.len() => {
            Resolution::Curator((**only).to_owned())
        }
        _ => Resolution::Graphs(graphs.clone()),
    };
    episodes::resolve(hub, actor, name, resolution).await?;
    Ok(graphs)
}

type Chunk = Result<Bytes, std::io::Error>;

/// Episode `name` exported (as [`episodes::export`] writes it) and sent as a tar stream of
/// ENACT's layout, for the export button. The export is written to a temporary folder first,
/// so a refusal (no graphs, too few key frames) comes before any byte; a failure later ends
/// the stream with an error, never with a short archive that looks complete.
pub async fn export_archive(
    hub: &Hub,
    name: &str,
) -> Result<tokio::sync::mpsc::Receiver<Chunk>, AppError> {
    let dir = tempfile::tempdir().map_err(AppError::internal)?;
    episodes::export(hub, name, dir.path()).await?;
    let (tx, rx) = tokio::sync::mpsc::channel(4);
    tokio::task::spawn_blocking(move || {
        let mut writer = crate::core::release::ArchiveWriter::default();
        let sent = (|| -> std::io::Result<()> {
            for path in files_under(dir.path())? {
                let relative = path
                    .strip_prefix(dir.path())
                    .map_err(std::io::Error::other)?
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy())
                    .collect::<Vec<_>>()
                    .join("/");
                let entry = writer.file(&relative, &std::fs::read(&path)?)?;
                if tx.blocking_send(Ok(Bytes::from(entry))).is_err() {
                    return Ok(()); // the client went away
                }
            }
            let end = std::mem::take(&mut writer).finish()?;
            let _ = tx.blocking_send(Ok(Bytes::from(end)));
            Ok(())
        })();
        if let Err(e) = sent {
            let _ = tx.blocking_send(Err(e));
        }
        drop(dir);
    });
    Ok(rx)
}

/// Every file under `dir`, in path order.
fn files_under(dir: &std::path::Path) -> std::io::Result<Vec<std::path::PathBuf>> {
    let mut out = Vec::new();
    let mut pending = vec![dir.to_path_buf()];
    while let Some(next) = pending.pop() {
        for entry in std::fs::read_dir(&next)? {
            let entry = entry?;
            if entry.file_type()?.is_dir() {
                pending.push(entry.path());
            } else {
                out.push(entry.path());
            }
        }
    }
    out.sort();
    Ok(out)
}
