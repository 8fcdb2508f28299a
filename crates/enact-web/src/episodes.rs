//! The curator's pages for real-world episodes (issue 28): the list, the admin's upload, the
//! episode page (filmstrip, key frames, the scene-graph editor and the live transition beside
//! it), drafts, saving, and the admin's comparison of two curators and resolution.
//!
//! The page's script sends the whole graphs file (`{"key_frames": [...]}`) on every change:
//! `describe` answers with each transition as ENACT will see it and every problem
//! [`crate::core::episode::validate`] finds, without storing anything; `draft` keeps it as the
//! curator's draft; `graphs` validates and stores it as the curator's graphs.

use askama::Template;
use axum::Router;
use axum::extract::{Multipart, Query, State};
use axum::response::{Html, IntoResponse, Redirect, Response};
use axum::routing::{get, post};
use serde::{Deserialize, Serialize};

use super::api::frame_url;
use super::error::{ApiError, PageError, RenderPage};
use super::extract::{Json, Path};
use super::session::{Admin, LoggedIn, Protected};
use super::{AppError, AppState};
use crate::app::refusal::Refusal;
use crate::app::{episode_curation, episodes};
use crate::core::episode::{EpisodeGraphs, GraphProblem, TransitionView};
use crate::core::scene_graph::signature::{STATE_PHRASES, StateArity};

/// The curators' routes: anyone logged in may draw graphs of an episode, under their own name.
pub fn router() -> Router<AppState> {
    Router::new()
        .route("/episodes", get(list_page))
        .route("/episodes/{name}", get(episode_page))
        .route("/episodes/{name}/describe", post(describe))
        .route("/episodes/{name}/draft", post(save_draft))
        .route("/episodes/{name}/graphs", post(save_graphs))
}

/// The admin's routes, behind the admin gate.
pub fn admin_router() -> Router<AppState> {
    Router::new()
        .route("/admin/episodes/new", get(upload_page))
        .route("/admin/episodes", post(upload))
        .route("/admin/episodes/folder", post(import_folder))
        .route("/admin/episodes/{name}/compare", get(compare_page))
        .route("/admin/episodes/{name}/resolve", post(resolve))
        .route("/admin/episodes/{name}/export", get(export))
}

fn episode_href(name: &str) -> String {
    format!("/episodes/{name}")
}

/// The states of one arity the editor offers: ENACT's sentence vocabulary, the same table
/// `validate` checks against.
fn states_of(arity: StateArity) -> Vec<&'static str> {
    STATE_PHRASES
        .iter()
        .filter(|(_, _, a)| *a == arity)
        .map(|(name, _, _)| *name)
        .collect()
}

struct EpisodeRow {
    name: String,
    scene: String,
    frames: usize,
    curators: Vec<String>,
}

#[derive(Template)]
#[template(path = "episodes.html")]
struct ListPage {
    is_admin: bool,
    episodes: Vec<EpisodeRow>,
}

async fn list_page(
    State(state): State<AppState>,
    LoggedIn(session): LoggedIn,
) -> Result<Html<String>, PageError> {
    let episodes = episodes::list(&state.hub).await?;
    let page = ListPage {
        is_admin: session.is_admin,
        episodes: episodes
            .into_iter()
            .map(|e| EpisodeRow {
                name: e.name,
                scene: e.scene,
                frames: e.frame_count,
                curators: e.curators,
            })
            .collect(),
    };
    Ok(Html(page.render_page()?))
}

/// A frame of the filmstrip. Frames are named by their 0-based position everywhere (the
/// graphs file's `frame`, the problems `validate` names), so the page does too.
struct StripFrame {
    position: usize,
    thumb: String,
}

/// What the script needs of each frame: the large image.
#[derive(Serialize)]
struct FrameSource {
    src: String,
}

#[derive(Template)]
#[template(path = "episode.html")]
struct EpisodePage {
    csrf: String,
    /// Admins see the export button (the export is theirs).
    is_admin: bool,
    name: String,
    scene: String,
    curator: String,
    base: String,
    frame_count: usize,
    frames: Vec<StripFrame>,
    frames_json: String,
    graphs_json: String,
    /// Whether the graphs shown are the curator's draft rather than their saved graphs.
    draft: bool,
    vocabulary_json: String,
    unary_states: Vec<&'static str>,
    binary_states: Vec<&'static str>,
}

async fn episode_page(
    State(state): State<AppState>,
    LoggedIn(session): LoggedIn,
    Path(name): Path<String>,
) -> Result<Html<String>, PageError> {
    let opened = episode_curation::open(&state.hub, &session.name, &name).await?;
    let unary_states = states_of(StateArity::Unary);
    let binary_states = states_of(StateArity::Binary);
    let frames: Vec<FrameSource> = opened
        .episode
        .frames
        .iter()
        .map(|f| FrameSource {
            src: frame_url(&f.sha256),
        })
        .collect();
    let page = EpisodePage {
        csrf: session.csrf_token,
        is_admin: session.is_admin,
        base: episode_href(&opened.episode.summary.name),
        scene: opened.episode.summary.scene.clone(),
        name: opened.episode.summary.name.clone(),
        curator: session.name,
        frame_count: opened.episode.frames.len(),
        frames: opened
            .episode
            .frames
            .iter()
            .enumerate()
            .map(|(position, f)| StripFrame {
                position,
                thumb: frame_url(&f.thumbnail_sha256),
            })
            .collect(),
        frames_json: serde_json::to_string(&frames)?,
        graphs_json: serde_json::to_string(&opened.graphs)?,
        draft: opened.from_draft,
        vocabulary_json: serde_json::to_string(&serde_json::json!({
            "unary": unary_states,
            "binary": binary_states,
        }))?,
        unary_states,
        binary_states,
    };
    Ok(Html(page.render_page()?))
}

/// One transition as the editor shows it.
#[derive(Serialize)]
struct TransitionJson {
    from_key_frame: usize,
    to_key_frame: usize,
    from_frame: usize,
    to_frame: usize,
    /// The action text split into its sentences, each with its final period.
    sentences: Vec<String>,
    /// The visible diff's signature components (what the verifier compares).
    components: Vec<String>,
    /// The full diff's components (ENACT's F set).
    full_components: Vec<String>,
    error: Option<String>,
}

impl From<TransitionView> for TransitionJson {
    fn from(t: TransitionView) -> Self {
        TransitionJson {
            from_key_frame: t.from_key_frame,
            to_key_frame: t.to_key_frame,
            from_frame: t.from_frame,
            to_frame: t.to_frame,
            sentences: t.action.as_deref().map(split_sentences).unwrap_or_default(),
            components: t.visible_signatures,
            full_components: t.full_signatures,
            error: t.error,
        }
    }
}

/// ENACT's action text is its sentences joined by ". " with a final "." (object names hold
/// no period), so splitting there gives them back.
fn split_sentences(action: &str) -> Vec<String> {
    action
        .trim_end_matches('.')
        .split(". ")
        .filter(|s| !s.is_empty())
        .map(|s| format!("{s}."))
        .collect()
}

#[derive(Serialize)]
struct Described {
    transitions: Vec<TransitionJson>,
    /// Every problem `validate` finds; each names its key frame (index) and field.
    problems: Vec<ProblemJson>,
}

#[derive(Serialize)]
struct ProblemJson {
    key_frame: Option<usize>,
    field: String,
    /// The whole problem as one line, key frame and field included.
    message: String,
}

impl From<GraphProblem> for ProblemJson {
    fn from(p: GraphProblem) -> Self {
        ProblemJson {
            message: p.to_string(),
            key_frame: p.key_frame,
            field: p.field,
        }
    }
}

fn described(transitions: Vec<TransitionView>, problems: Vec<GraphProblem>) -> Described {
    Described {
        transitions: transitions.into_iter().map(TransitionJson::from).collect(),
        problems: problems.into_iter().map(ProblemJson::from).collect(),
    }
}

async fn describe(
    State(state): State<AppState>,
    Path(name): Path<String>,
    request: Protected<EpisodeGraphs>,
) -> Result<Json<Described>, ApiError> {
    let (transitions, problems) =
        episode_curation::describe(&state.hub, &name, &request.body).await?;
    Ok(Json(described(transitions, problems)))
}

#[derive(Serialize)]
struct Saved {
    saved: bool,
}

async fn save_draft(
    State(state): State<AppState>,
    Path(name): Path<String>,
    request: Protected<EpisodeGraphs>,
) -> Result<Json<Saved>, ApiError> {
    episode_curation::save_draft(&state.hub, &request.session.name, &name, &request.body).await?;
    Ok(Json(Saved { saved: true }))
}

/// Validates and stores the curator's graphs; refused (422, every problem listed) when a
/// graph is invalid. Answers with the description of what was stored.
async fn save_graphs(
    State(state): State<AppState>,
    Path(name): Path<String>,
    request: Protected<EpisodeGraphs>,
) -> Result<Json<Described>, ApiError> {
    let session = &request.session;
    let transitions = episode_curation::save(
        &state.hub,
        &session.actor(),
        &session.name,
        &name,
        &request.body,
    )
    .await?;
    Ok(Json(described(transitions, Vec::new())))
}

#[derive(Template)]
#[template(path = "episode_upload.html")]
struct UploadPage {
    csrf: String,
    error: Option<String>,
}

async fn upload_page(Admin(session): Admin) -> Result<Html<String>, PageError> {
    Ok(Html(
        UploadPage {
            csrf: session.csrf_token,
            error: None,
        }
        .render_page()?,
    ))
}

/// The upload form, read field by field: the CSRF token must come before the frames, so a
/// forged request is refused before any frame is read. A body that is not multipart is
/// checked for its token all the same (403 without it) and then refused as malformed.
async fn upload(
    State(state): State<AppState>,
    Admin(session): Admin,
    request: axum::extract::Request,
) -> Result<Response, PageError> {
    let multipart = request
        .headers()
        .get(axum::http::header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.starts_with("multipart/form-data"));
    if !multipart {
        use axum::extract::FromRequest;
        if let Err(refused) = Protected::<IgnoredForm>::from_request(request, &state).await {
            return Ok(refused);
        }
        return Err(PageError(AppError::Invalid(
            "the upload must be sent as multipart/form-data with its frames".to_owned(),
        )));
    }
    let mut form = {
        use axum::extract::FromRequest;
        Multipart::from_request(request, &state)
            .await
            .map_err(|e| PageError(AppError::Invalid(format!("upload form: {}", e.body_text()))))?
    };
    let mut name = String::new();
    let mut scene = String::new();
    let mut csrf_ok = false;
    let mut frames = Vec::new();
    while let Some(field) = form.next_field().await.map_err(multipart_error)? {
        let field_name = field.name().unwrap_or_default().to_owned();
        match field_name.as_str() {
            "csrf" => {
                let token = field.text().await.map_err(multipart_error)?;
                csrf_ok = crate::core::credentials::constant_time_eq(
                    token.as_bytes(),
                    session.csrf_token.as_bytes(),
                );
            }
            _ if !csrf_ok => {
                // The token must come first: the frames after it are read only for a form
                // known to be this page's.
                return Err(Refusal::StaleForm.into());
            }
            "name" => name = field.text().await.map_err(multipart_error)?,
            "scene" => scene = field.text().await.map_err(multipart_error)?,
            "frames" => {
                let file_name = field.file_name().unwrap_or_default().to_owned();
                let bytes = field.bytes().await.map_err(multipart_error)?;
                // A file input with no file chosen still sends an empty part.
                if !(file_name.is_empty() && bytes.is_empty()) {
                    frames.push(episode_curation::UploadedFrame { file_name, bytes });
                }
            }
            other => {
                return Err(PageError(AppError::Invalid(format!(
                    "upload form: unknown field '{other}'"
                ))));
            }
        }
    }
    episode_curation::import_upload(
        &state.hub,
        &session.actor(),
        name.trim(),
        scene.trim(),
        frames,
    )
    .await?;
    Ok(Redirect::to(&episode_href(name.trim())).into_response())
}

/// Any form, for its CSRF token only.
#[derive(Deserialize)]
struct IgnoredForm {}

fn multipart_error(e: axum::extract::multipart::MultipartError) -> PageError {
    PageError(AppError::Invalid(format!("upload form: {}", e.body_text())))
}

#[derive(Deserialize)]
struct FolderForm {
    name: String,
    #[serde(default)]
    scene: String,
    dir: String,
}

async fn import_folder(
    State(state): State<AppState>,
    request: Protected<FolderForm>,
) -> Result<Response, PageError> {
    let form = &request.body;
    let name = form.name.trim();
    episodes::import(
        &state.hub,
        &request.session.actor(),
        std::path::Path::new(form.dir.trim()),
        name,
        form.scene.trim(),
    )
    .await?;
    Ok(Redirect::to(&episode_href(name)).into_response())
}

#[derive(Deserialize)]
struct CompareQuery {
    a: Option<String>,
    b: Option<String>,
    notice: Option<String>,
}

struct TransitionRow {
    label: String,
    shared: usize,
    only_a: Vec<String>,
    only_b: Vec<String>,
}

struct KeyFrameRow {
    frame: usize,
    in_a: bool,
    in_b: bool,
    only_a: Vec<String>,
    only_b: Vec<String>,
    /// The curators with a graph at this frame.
    choices: Vec<String>,
    /// The curator whose graph the resolved graphs hold here ("" when left out).
    chosen: String,
}

#[derive(Template)]
#[template(path = "episode_compare.html")]
struct ComparePage {
    csrf: String,
    name: String,
    a: String,
    b: String,
    curators: Vec<String>,
    notice: Option<String>,
    shared: usize,
    only_a: usize,
    only_b: usize,
    agreement: String,
    alpha: String,
    transitions: Vec<TransitionRow>,
    key_frames: Vec<KeyFrameRow>,
}

async fn compare_page(
    State(state): State<AppState>,
    Admin(session): Admin,
    Path(name): Path<String>,
    Query(query): Query<CompareQuery>,
) -> Result<Html<String>, PageError> {
    let compared =
        episode_curation::compare(&state.hub, &name, query.a.as_deref(), query.b.as_deref())
            .await?;
    let c = &compared.comparison;
    let alpha = &c.transition_alpha;
    let page = ComparePage {
        csrf: session.csrf_token,
        name: compared.episode.clone(),
        shared: c.transition_components.shared,
        only_a: c.transition_components.only_a,
        only_b: c.transition_components.only_b,
        agreement: c
            .transition_agreement
            .map_or_else(|| "n/a".to_owned(), |r| format!("{:.1} %", r * 100.0)),
        alpha: match (alpha.alpha, &alpha.reason) {
            (Some(v), _) => format!("{v:.3} ({} units)", alpha.units_used),
            (None, Some(reason)) => format!("undefined: {reason}"),
            (None, None) => "undefined".to_owned(),
        },
        transitions: c
            .transitions
            .iter()
            .map(|t| TransitionRow {
                label: format!("{} → {}", t.from_frame, t.to_frame),
                shared: t.components.shared,
                only_a: t.only_a.clone(),
                only_b: t.only_b.clone(),
            })
            .collect(),
        key_frames: c
            .key_frames
            .iter()
            .map(|k| KeyFrameRow {
                frame: k.frame,
                in_a: k.in_a,
                in_b: k.in_b,
                only_a: k.only_a.clone(),
                only_b: k.only_b.clone(),
                choices: compared.curators_at(k.frame),
                chosen: compared.resolved_from(k.frame).unwrap_or_default(),
            })
            .collect(),
        a: compared.a.clone(),
        b: compared.b.clone(),
        curators: compared.curators.clone(),
        notice: query.notice,
    };
    Ok(Html(page.render_page()?))
}

/// The resolution form: `a`, `b` (to come back to the same comparison) and one
/// `frame_{position}` field per key frame naming the curator whose graph is kept there, or
/// empty to leave the frame out.
async fn resolve(
    State(state): State<AppState>,
    Path(name): Path<String>,
    request: Protected<Vec<(String, String)>>,
) -> Result<Response, PageError> {
    let mut back = (String::new(), String::new());
    let mut choices = Vec::new();
    for (field, value) in &request.body {
        match field.as_str() {
            "csrf" => {}
            "a" => back.0.clone_from(value),
            "b" => back.1.clone_from(value),
            _ => {
                let frame = field
                    .strip_prefix("frame_")
                    .and_then(|f| f.parse::<usize>().ok())
                    .ok_or_else(|| {
                        AppError::Invalid(format!("resolution form: unknown field '{field}'"))
                    })?;
                if !value.is_empty() {
                    choices.push((frame, value.clone()));
                }
            }
        }
    }
    let resolved = episode_curation::resolve_by_key_frame(
        &state.hub,
        &request.session.actor(),
        &name,
        &choices,
    )
    .await?;
    let notice = format!(
        "Resolved: {} key frames from {} curator(s).",
        resolved.key_frames.len(),
        choices
            .iter()
            .map(|(_, c)| c)
            .collect::<std::collections::BTreeSet<_>>()
            .len()
    );
    let query = serde_urlencoded::to_string([
        ("a", back.0.as_str()),
        ("b", back.1.as_str()),
        ("notice", notice.as_str()),
    ])
    .map_err(|e| AppError::Internal(e.into()))?;
    Ok(Redirect::to(&format!("/admin/episodes/{name}/compare?{query}")).into_response())
}

/// The export (resolved graphs, else the only curator's) as a tar of ENACT's layout.
async fn export(
    State(state): State<AppState>,
    Path(name): Path<String>,
) -> Result<Response, PageError> {
    let chunks = episode_curation::export_archive(&state.hub, &name).await?;
    let file_name = format!("{}-enact.tar", super::file_name_safe(&name));
    Ok(super::archive::tar_download(chunks, &file_name))
}
