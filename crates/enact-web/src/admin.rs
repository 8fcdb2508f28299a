//! The admin page: annotator accounts and invites, assignments, skipped and flagged items, and
//! human performance per dataset.

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::Html;
use axum::routing::{get, post};
use serde::Deserialize;

use super::error::{PageError, RenderPage};
use super::session::{Admin, Protected};
use super::{AppError, AppState};
use crate::app::annotation::{self, Assignment};
use crate::app::refusal::{Expected, Refusal};
use crate::app::{annotators, datasets, leaderboard};
use crate::core::annotation::Session;
use crate::core::dataset::StepLength;
use crate::core::verifier::{GroupPerformance, PerformanceReport};

pub fn router() -> Router<AppState> {
    Router::new()
        .route("/admin", get(admin_page))
        .route("/admin/annotators", post(create_annotator))
        .route("/admin/assign", post(assign))
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
    metric_version: u32,
    /// The folder releases are imported from (`serve --import-dir`), when there is one.
    import_dir: Option<String>,
    imports: Vec<crate::app::import_jobs::ImportJobSummary>,
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
    session: Session,
    notice: Option<String>,
    invite: Option<(String, String)>,
) -> Result<Html<String>, PageError> {
    let accounts = annotators::with_progress(&state.hub).await?;
    let overview = datasets::overview(&state.hub).await?;
    let mut human = Vec::new();
    for o in &overview {
        if let Some(report) = leaderboard::human_performance(&state.hub, &o.dataset).await? {
            human.push(HumanTable {
                dataset: o.dataset.name.clone(),
                rows: performance_rows(&report),
            });
        }
    }
    let flags = annotation::flags(&state.hub).await?;
    let imports = crate::app::import_jobs::recent(&state.hub, 10).await?;
    let page = AdminPage {
        metric_version: crate::core::metric::METRIC_VERSION,
        import_dir: crate::app::import_jobs::folder(&state.hub).map(|d| d.display().to_string()),
        imports,
        name: session.name,
        csrf: session.csrf_token,
        annotators: accounts
            .into_iter()
            .map(|a| AnnotatorRow {
                id: a.annotator.id,
                name: a.annotator.name,
                role: if a.annotator.is_admin {
                    "admin"
                } else {
                    "annotator"
                },
                status: if a.annotator.active {
                    "active"
                } else {
                    "invite pending"
                },
                assigned: a.assigned,
                finished: a.finished,
                answered: a.answered,
            })
            .collect(),
        datasets: overview.into_iter().map(|o| o.dataset.name).collect(),
        flags: flags
            .into_iter()
            .map(|f| FlagRow {
                annotator: f.annotator,
                dataset: f.dataset,
                item_id: f.item_id,
                outcome: f.outcome.as_str().to_owned(),
                reason: f.reason,
                finished_at: f.finished_at,
            })
            .collect(),
        human,
        step_lengths: StepLength::all().map(StepLength::get).collect(),
        notice,
        invite,
    };
    Ok(Html(page.render_page()?))
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

async fn create_annotator(
    State(state): State<AppState>,
    headers: HeaderMap,
    request: Protected<NewAnnotator>,
) -> Result<Html<String>, PageError> {
    let invited = annotators::create(
        &state.hub,
        &request.session.actor(),
        &request.body.name,
        request.body.admin.is_some(),
    )
    .await?;
    let url = annotators::invite_url(&request_base(&headers), &invited.invite_token);
    render_admin(
        &state,
        request.session,
        Some(format!(
            "Created '{}'. The invite link works once.",
            invited.name
        )),
        Some((invited.name, url)),
    )
    .await
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
    let form = &AssignForm::from_fields(request.body);
    let mut chosen = Vec::new();
    for part in &form.annotators {
        chosen.push(part.trim().parse::<i64>().map_err(|_| {
            Refusal::bad_value(
                "annotator",
                part.trim(),
                Expected::WholeNumberFrom { least: 1 },
            )
        })?);
    }
    let how = match form.mode.as_str() {
        "split" => Assignment::Split(chosen),
        "list" => {
            let [annotator] = chosen[..] else {
                return Err(AppError::Invalid(format!(
                    "an id list goes to exactly one annotator; {} were chosen",
                    chosen.len()
                ))
                .into());
            };
            let item_ids = form
                .items
                .split(|c: char| c.is_whitespace() || c == ',')
                .filter(|s| !s.is_empty())
                .map(str::to_owned)
                .collect();
            Assignment::List {
                annotator,
                item_ids,
            }
        }
        other => {
            return Err(
                Refusal::bad_value("mode", other, Expected::OneOf(vec!["split", "list"])).into(),
            );
        }
    };
    let dataset = form.dataset.trim();
    let done = annotation::assign(&state.hub, &request.session.actor(), dataset, &how).await?;
    let added = done.added;
    render_admin(
        &state,
        request.session,
        Some(format!(
            "Assigned {added} items of '{dataset}' ({} already assigned were left as they \
             were).{}",
            done.requested - added,
            if done.paused.is_empty() {
                String::new()
            } else {
                format!(" Paused queues left out: {}.", done.paused.join(", "))
            }
        )),
        None,
    )
    .await
}
