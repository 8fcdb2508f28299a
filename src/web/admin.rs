//! The admin page: annotator accounts and invites, assignments, skipped and flagged items, and
//! human performance per dataset.

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::Html;
use axum::routing::{get, post};
use serde::Deserialize;

use super::error::PageError;
use super::session::{Admin, Protected};
use super::{AppError, AppState, dataset_or_404};
use crate::core::annotation::{balanced_split, new_token, token_hash};
use crate::core::dataset::StepLength;
use crate::core::verifier::{GroupPerformance, PerformanceReport};
use crate::store;

pub fn router() -> Router<AppState> {
    Router::new()
        .route("/admin", get(admin_page))
        .route("/admin/annotators", post(create_annotator))
        .route("/admin/assign", post(assign))
}

/// The invite link an annotator opens to set a password.
pub fn invite_url(base: &str, token: &str) -> String {
    format!("{}/invite/{token}", base.trim_end_matches('/'))
}

/// `scheme://host` the request was made to, for links shown to the admin.
fn request_base(headers: &HeaderMap) -> String {
    let host = headers
        .get(axum::http::header::HOST)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("127.0.0.1:8080");
    let scheme = if headers
        .get("x-forwarded-proto")
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.eq_ignore_ascii_case("https"))
    {
        "https"
    } else {
        "http"
    };
    format!("{scheme}://{host}")
}

struct AnnotatorRow {
    id: i64,
    name: String,
    role: &'static str,
    status: &'static str,
    assigned: i64,
    finished: i64,
    answered: i64,
}

struct FlagRow {
    annotator: String,
    dataset: String,
    item_id: String,
    outcome: String,
    reason: String,
    finished_at: String,
}

struct PerformanceRow {
    group: &'static str,
    count: usize,
    ta: String,
    pa: String,
    cells: Vec<String>,
}

struct HumanTable {
    dataset: String,
    rows: Vec<PerformanceRow>,
}

#[derive(Template)]
#[template(path = "admin.html")]
struct AdminPage {
    name: String,
    csrf: String,
    annotators: Vec<AnnotatorRow>,
    datasets: Vec<String>,
    flags: Vec<FlagRow>,
    human: Vec<HumanTable>,
    step_lengths: Vec<u8>,
    /// What the last action did, shown on top.
    notice: Option<String>,
    /// A new account's invite link, shown once.
    invite: Option<(String, String)>,
}

fn percent(v: f64) -> String {
    format!("{:.1}", v * 100.0)
}

fn performance_rows(report: &PerformanceReport) -> Vec<PerformanceRow> {
    let groups: [(&'static str, Option<&GroupPerformance>); 3] = [
        ("overall", report.overall.as_ref()),
        ("forward", report.forward_world_modeling.as_ref()),
        ("inverse", report.inverse_world_modeling.as_ref()),
    ];
    groups
        .into_iter()
        .filter_map(|(group, g)| {
            let g = g?;
            Some(PerformanceRow {
                group,
                count: g.totals.count,
                ta: percent(g.totals.task_accuracy),
                pa: g
                    .totals
                    .pairwise_accuracy
                    .map_or_else(|| "n/a".to_owned(), percent),
                cells: StepLength::all()
                    .map(|l| match g.per_step.get(&l.states()) {
                        None => "–".to_owned(),
                        Some(s) => format!(
                            "{} / {} (n={})",
                            percent(s.task_accuracy),
                            s.pairwise_accuracy
                                .map_or_else(|| "n/a".to_owned(), percent),
                            s.count
                        ),
                    })
                    .collect(),
            })
        })
        .collect()
}

pub(super) async fn render_admin(
    state: &AppState,
    session: store::annotations::Session,
    notice: Option<String>,
    invite: Option<(String, String)>,
) -> Result<Html<String>, PageError> {
    let mut conn = state.pool.acquire().await?;
    let accounts = store::annotations::annotators(&mut conn).await?;
    let progress = store::annotations::progress_by_annotator(&mut conn).await?;
    let overview = store::datasets::overview(&mut conn).await?;
    let mut human = Vec::new();
    for o in &overview {
        if let Some(report) = store::annotations::human_performance(&mut conn, o.dataset.id).await?
        {
            human.push(HumanTable {
                dataset: o.dataset.name.clone(),
                rows: performance_rows(&report),
            });
        }
    }
    let flags = store::annotations::flags(&mut conn).await?;
    let page = AdminPage {
        name: session.name,
        csrf: session.csrf_token,
        annotators: accounts
            .into_iter()
            .map(|a| {
                let (assigned, finished, answered) = progress
                    .iter()
                    .find(|p| p.0 == a.id)
                    .map_or((0, 0, 0), |p| (p.1, p.2, p.3));
                AnnotatorRow {
                    id: a.id,
                    name: a.name,
                    role: if a.is_admin { "admin" } else { "annotator" },
                    status: if a.active { "active" } else { "invite pending" },
                    assigned,
                    finished,
                    answered,
                }
            })
            .collect(),
        datasets: overview.into_iter().map(|o| o.dataset.name).collect(),
        flags: flags
            .into_iter()
            .map(|f| FlagRow {
                annotator: f.annotator,
                dataset: f.dataset,
                item_id: f.item_id,
                outcome: f.outcome,
                reason: f.reason,
                finished_at: f.finished_at,
            })
            .collect(),
        human,
        step_lengths: StepLength::all().map(StepLength::get).collect(),
        notice,
        invite,
    };
    Ok(Html(page.render()?))
}

async fn admin_page(
    State(state): State<AppState>,
    Admin(session): Admin,
) -> Result<Html<String>, PageError> {
    render_admin(&state, session, None, None).await
}

#[derive(Deserialize)]
struct NewAnnotator {
    #[serde(default)]
    name: String,
    #[serde(default)]
    admin: Option<String>,
}

/// Names are shown on pages and typed at login: keep them plain.
pub fn check_annotator_name(name: &str) -> Result<(), String> {
    if name.is_empty() || name.chars().count() > 64 {
        return Err("an annotator name has 1 to 64 characters".to_owned());
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_alphanumeric() || matches!(c, '.' | '_' | '-')))
    {
        return Err(format!(
            "annotator name '{name}': character {c:?} is not allowed (letters, digits, . _ -)"
        ));
    }
    Ok(())
}

async fn create_annotator(
    State(state): State<AppState>,
    headers: HeaderMap,
    request: Protected<NewAnnotator>,
) -> Result<Html<String>, PageError> {
    require_admin(&request.session)?;
    let name = request.body.name.trim().to_owned();
    check_annotator_name(&name).map_err(AppError::BadRequest)?;
    let token = new_token();
    let mut conn = state.pool.acquire().await?;
    let created = store::annotations::create_annotator(
        &mut conn,
        &name,
        request.body.admin.is_some(),
        &token_hash(&token),
    )
    .await?;
    drop(conn);
    if created.is_none() {
        return Err(
            AppError::Conflict(format!("an annotator named '{name}' already exists")).into(),
        );
    }
    let url = invite_url(&request_base(&headers), &token);
    render_admin(
        &state,
        request.session,
        Some(format!("Created '{name}'. The invite link works once.")),
        Some((name, url)),
    )
    .await
}

pub(super) fn require_admin(session: &store::annotations::Session) -> Result<(), AppError> {
    if session.is_admin {
        Ok(())
    } else {
        Err(AppError::Forbidden(format!(
            "only admins may do this; '{}' is an annotator",
            session.name
        )))
    }
}

/// The assignment form: either a balanced split of the dataset's unassigned items over the
/// chosen annotators (`mode=split`, one `annotator` field per annotator id), or an explicit
/// list of item ids for one annotator (`mode=list`, `items` one per line or separated by spaces
/// or commas).
struct AssignForm {
    dataset: String,
    mode: String,
    annotators: Vec<String>,
    items: String,
}

impl AssignForm {
    fn from_fields(fields: Vec<(String, String)>) -> AssignForm {
        let mut form = AssignForm {
            dataset: String::new(),
            mode: String::new(),
            annotators: Vec::new(),
            items: String::new(),
        };
        for (key, value) in fields {
            match key.as_str() {
                "dataset" => form.dataset = value,
                "mode" => form.mode = value,
                "annotator" => form.annotators.push(value),
                "items" => form.items = value,
                _ => {}
            }
        }
        form
    }
}

async fn assign(
    State(state): State<AppState>,
    request: Protected<Vec<(String, String)>>,
) -> Result<Html<String>, PageError> {
    require_admin(&request.session)?;
    let form = &AssignForm::from_fields(request.body);
    let dataset = dataset_or_404(&state.pool, form.dataset.trim()).await?;
    let mut annotators = Vec::new();
    for part in &form.annotators {
        annotators.push(part.trim().parse::<i64>().map_err(|_| {
            AppError::BadRequest(format!("annotator: '{part}' is not an annotator id"))
        })?);
    }
    let mut conn = state.pool.acquire().await?;
    let known: Vec<i64> = store::annotations::annotators(&mut conn)
        .await?
        .iter()
        .map(|a| a.id)
        .collect();
    if let Some(unknown) = annotators.iter().find(|a| !known.contains(a)) {
        return Err(
            AppError::BadRequest(format!("annotator: no annotator has id {unknown}")).into(),
        );
    }
    let pairs = match form.mode.as_str() {
        "split" => {
            if annotators.is_empty() {
                return Err(AppError::BadRequest(
                    "choose at least one annotator to split the dataset over".to_owned(),
                )
                .into());
            }
            let items = store::annotations::unassigned_items(&mut conn, dataset.id).await?;
            balanced_split(&items, &annotators)
        }
        "list" => {
            let [annotator] = annotators[..] else {
                return Err(AppError::BadRequest(format!(
                    "an id list goes to exactly one annotator; {} were chosen",
                    annotators.len()
                ))
                .into());
            };
            let ids: Vec<String> = form
                .items
                .split(|c: char| c.is_whitespace() || c == ',')
                .filter(|s| !s.is_empty())
                .map(str::to_owned)
                .collect();
            if ids.is_empty() {
                return Err(
                    AppError::BadRequest("items: give at least one item id".to_owned()).into(),
                );
            }
            match store::annotations::item_rowids(&mut conn, dataset.id, &ids).await? {
                Ok(rows) => rows.into_iter().map(|r| (annotator, r)).collect(),
                Err(missing) => {
                    return Err(AppError::BadRequest(format!(
                        "items: not in dataset '{}': {}",
                        dataset.name,
                        missing.join(", ")
                    ))
                    .into());
                }
            }
        }
        other => {
            return Err(AppError::BadRequest(format!(
                "form field `mode` is {other:?}; expected \"split\" or \"list\""
            ))
            .into());
        }
    };
    drop(conn);
    let mut tx = state.pool.begin().await?;
    let added = store::annotations::assign(&mut tx, &pairs).await?;
    tx.commit().await?;
    render_admin(
        &state,
        request.session,
        Some(format!(
            "Assigned {added} items of '{}' ({} already assigned were left as they were).",
            dataset.name,
            pairs.len() as u64 - added
        )),
        None,
    )
    .await
}
