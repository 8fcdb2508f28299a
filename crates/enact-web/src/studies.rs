//! Ablation studies over HTTP: the JSON API (create and delete for admins; list, show and
//! report for everyone, since reports use published submissions only), the public pages
//! (`/studies`, `/studies/{study}` with the report of a chosen row) and the admin page
//! (`/admin/studies`: create and delete).

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::{get, post};
use schemars::JsonSchema;
use serde::Deserialize;
use serde_json::json;

use super::agreement::fixed;
use super::auth::TokenCaller;
use super::error::{ApiError, PageError, RenderPage};
use super::extract::{Json, Path, Query};
use super::i18n::Tr;
use super::openapi::{ApiRoute, Verb};
use super::session::{Admin, Protected};
use super::{AppError, AppState};
use crate::app::refusal::{Expected, Refusal};
use crate::app::studies::{self, StudyRowChoice, StudyView};
use crate::app::{datasets, studies::files};
use crate::core::annotation::Session;
use crate::core::credentials::Scope;
use crate::core::study::VariantSpec;
use crate::core::study::export::{cells_csv, cells_tex, handedness_svg, heatmap_svg};
use crate::core::study::figure::p_text;
use crate::core::study::report::StudyReport;

pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(Verb::Post, "/admin/studies", create_study, "Create an ablation study")
            .describe(
                "A baseline dataset and variant datasets grouped in families (the paper's \
                 image realism, camera and embodiment ablations). Each variant is \
                 `\"FAMILY/LABEL=DATASET\"` or `{family, label, dataset}`. Items are aligned \
                 by id, or by task, type and key frames where ids differ; a variant with no \
                 aligned item is refused. The response says how many aligned.",
            )
            .bearer(Scope::Admin)
            .body_json::<StudyRequest>(
                "`name` (letters, digits, `.`, `_`, `-`), `baseline` (a dataset) and \
                 `variants`.",
                "{\"name\": \"camera\", \"baseline\": \"enact\", \"variants\": \
                 [\"Camera FOV/Aperture 30=enact-fov30\", {\"family\": \"Camera FOV\", \
                 \"label\": \"Fisheye\", \"dataset\": \"enact-fisheye\"}]}",
            )
            .responds_json::<StudyView>(201, "The study, with each variant's alignment.")
            .errors(&[400, 401, 403, 409, 415, 422]),
        ApiRoute::new(Verb::Delete, "/admin/studies/{study}", delete_study, "Delete a study")
            .describe("The datasets and submissions stay.")
            .bearer(Scope::Admin)
            .responds(204, None, "Deleted.")
            .errors(&[401, 403, 404]),
        ApiRoute::new(Verb::Get, "/studies", list_studies, "List ablation studies")
            .describe("Every study with its baseline and variants (alignments: see one study).")
            .responds_json::<Vec<StudyView>>(200, "The studies, by name.")
            .errors(&[]),
        ApiRoute::new(Verb::Get, "/studies/{study}", get_study, "An ablation study")
            .describe("The study with how each variant's items align with the baseline's.")
            .responds_json::<StudyView>(200, "The study.")
            .errors(&[404]),
        ApiRoute::new(
            Verb::Get,
            "/studies/{study}/report",
            study_report,
            "A study report for a model or the Human row",
        )
        .describe(
            "For each family, variant and direction (and step length with \
             `by_step_length=true`): Δ of mean pairwise accuracy (variant − baseline) over the \
             aligned items with the paper's two-tailed Welch test (`t`, `df`, `p`, \
             `n_baseline`, `n_variant`), the paired t-test and exact sign test on per-item \
             differences, and left/right-hand figures per dataset (the paper's panel C.2). The \
             row is the latest published submission of `model` on each dataset, or the \
             annotators' answers with `human=true`. `format`: `json` (default), `csv`, `tex`, \
             `svg` (the heatmap), `handedness-svg`, or `tar` (every file). Every file is \
             stamped with the datasets' content hashes and the submissions.",
        )
        .query_with(
            "model",
            false,
            json!({"type": "string"}),
            "The model name (required unless `human=true`).",
        )
        .query_with(
            "account",
            false,
            json!({"type": "string"}),
            "The account, when several publish a model of that name.",
        )
        .query_with(
            "human",
            false,
            json!({"type": "boolean"}),
            "Report the Human row instead of a model.",
        )
        .query_with(
            "by_step_length",
            false,
            json!({"type": "boolean"}),
            "Add a cell per step length under each direction.",
        )
        .query_with(
            "format",
            false,
            json!({"type": "string", "enum": ["json", "csv", "tex", "svg", "handedness-svg", "tar"]}),
            "The representation (default `json`).",
        )
        .responds_json::<StudyReport>(200, "The report (other formats as their media types).")
        .errors(&[400, 404]),
    ]
}

pub fn page_router() -> Router<AppState> {
    Router::new()
        .route("/studies", get(studies_page))
        .route("/studies/{study}", get(study_page))
}

/// The admin's page (mounted behind the admin gate, [`super::admin_pages`]).
pub fn admin_router() -> Router<AppState> {
    Router::new()
        .route("/admin/studies", get(admin_page).post(admin_create))
        .route("/admin/studies/delete", post(admin_delete))
}

/// A variant in a request: `"FAMILY/LABEL=DATASET"` or its three parts.
#[derive(JsonSchema)]
#[serde(untagged)]
enum VariantBody {
    Text(String),
    Parts(VariantParts),
}

/// A variant given as its three parts. The type both reads and documents them, so the
/// document's `additionalProperties: false` is exactly the refusal of unknown fields.
#[derive(Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct VariantParts {
    family: String,
    label: String,
    dataset: String,
}

/// Read by hand so that a wrong variant is told what a variant is (an untagged enum only says
/// that nothing matched).
impl<'de> Deserialize<'de> for VariantBody {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        match serde_json::Value::deserialize(d)? {
            serde_json::Value::String(text) => Ok(VariantBody::Text(text)),
            object @ serde_json::Value::Object(_) => serde_json::from_value::<VariantParts>(object)
                .map(VariantBody::Parts)
                .map_err(|e| {
                    D::Error::custom(format!(
                        "a variant object has string fields `family`, `label` and `dataset` \
                         ({e})"
                    ))
                }),
            other => Err(D::Error::custom(format!(
                "a variant is \"FAMILY/LABEL=DATASET\" or {{\"family\", \"label\", \
                 \"dataset\"}}, not {other}"
            ))),
        }
    }
}

#[derive(Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct StudyRequest {
    name: String,
    baseline: String,
    variants: Vec<VariantBody>,
}

fn variant_specs(variants: &[VariantBody]) -> Result<Vec<VariantSpec>, AppError> {
    variants
        .iter()
        .enumerate()
        .map(|(i, v)| {
            match v {
                VariantBody::Text(text) => VariantSpec::parse(text),
                VariantBody::Parts(p) => VariantSpec::new(&p.family, &p.label, &p.dataset),
            }
            .map_err(|e| AppError::Invalid(format!("variants[{i}]: {e}")))
        })
        .collect()
}

async fn create_study(
    State(state): State<AppState>,
    TokenCaller(caller): TokenCaller,
    Json(request): Json<StudyRequest>,
) -> Result<(StatusCode, Json<StudyView>), ApiError> {
    let variants = variant_specs(&request.variants)?;
    let view = studies::create(
        &state.hub,
        &caller.actor(),
        &request.name,
        &request.baseline,
        &variants,
    )
    .await?;
    Ok((StatusCode::CREATED, Json(view)))
}

async fn delete_study(
    State(state): State<AppState>,
    Path(name): Path<String>,
    TokenCaller(caller): TokenCaller,
) -> Result<StatusCode, ApiError> {
    studies::delete(&state.hub, &caller.actor(), &name).await?;
    Ok(StatusCode::NO_CONTENT)
}

async fn list_studies(State(state): State<AppState>) -> Result<Json<Vec<StudyView>>, ApiError> {
    Ok(Json(studies::list(&state.hub).await?))
}

async fn get_study(
    State(state): State<AppState>,
    Path(name): Path<String>,
) -> Result<Json<StudyView>, ApiError> {
    Ok(Json(studies::show(&state.hub, &name).await?))
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct ReportQuery {
    model: Option<String>,
    account: Option<String>,
    human: Option<bool>,
    by_step_length: Option<bool>,
    format: Option<String>,
}

impl ReportQuery {
    fn choice(&self) -> Result<StudyRowChoice, ApiError> {
        let model = self
            .model
            .as_deref()
            .map(str::trim)
            .filter(|m| !m.is_empty());
        match (model, self.human.unwrap_or(false)) {
            (Some(_), true) | (None, false) => Err(Refusal::ExactlyOneOf {
                fields: vec!["model", "human"],
            }
            .into()),
            (None, true) => Ok(StudyRowChoice::Human),
            (Some(model), false) => Ok(StudyRowChoice::Model {
                model: model.to_owned(),
                account: self
                    .account
                    .as_deref()
                    .map(str::trim)
                    .filter(|a| !a.is_empty())
                    .map(str::to_owned),
            }),
        }
    }
}

fn typed(media_type: &'static str, body: impl IntoResponse) -> Response {
    (
        [(header::CONTENT_TYPE, HeaderValue::from_static(media_type))],
        body,
    )
        .into_response()
}

/// `enact-hub-study-{study}-{row}`, safe as a file name and header value.
fn bundle_folder(report: &StudyReport) -> String {
    format!(
        "enact-hub-study-{}-{}",
        super::file_name_safe(&report.stamp.study),
        super::file_name_safe(&report.stamp.row)
    )
}

async fn study_report(
    State(state): State<AppState>,
    Path(name): Path<String>,
    Query(query): Query<ReportQuery>,
) -> Result<Response, ApiError> {
    let choice = query.choice()?;
    let format = query.format.as_deref().unwrap_or("json");
    let formats = vec!["json", "csv", "tex", "svg", "handedness-svg", "tar"];
    if !formats.contains(&format) {
        return Err(Refusal::bad_value("format", format, Expected::OneOf(formats)).into());
    }
    let report = studies::report(
        &state.hub,
        &name,
        &choice,
        query.by_step_length.unwrap_or(false),
    )
    .await?;
    let render = |e: askama::Error| AppError::internal(format!("study '{name}': {e}"));
    Ok(match format {
        "csv" => typed("text/csv; charset=utf-8", cells_csv(&report)),
        "tex" => typed("application/x-tex; charset=utf-8", cells_tex(&report)),
        "svg" => typed("image/svg+xml", heatmap_svg(&report).map_err(render)?),
        "handedness-svg" => match handedness_svg(&report).map_err(render)? {
            Some(svg) => typed("image/svg+xml", svg),
            None => {
                return Err(ApiError(AppError::NotFound(format!(
                    "study '{name}': no dataset has an error analysis for {}",
                    report.stamp.row
                ))));
            }
        },
        "tar" => {
            let folder = bundle_folder(&report);
            super::archive::bundle_download(&folder, &files(&report)?)?
        }
        _ => Json(report).into_response(),
    })
}

#[derive(Template)]
#[template(path = "studies.html")]
struct StudiesPage {
    tr: Tr,
    studies: Vec<StudyView>,
}

async fn studies_page(State(state): State<AppState>, tr: Tr) -> Result<Html<String>, PageError> {
    let page = StudiesPage {
        tr,
        studies: studies::list(&state.hub).await?,
    };
    Ok(Html(page.render_page()?))
}

/// A cell as the page's table shows it.
struct CellText {
    family: String,
    variant: String,
    direction: String,
    step_length: String,
    delta: String,
    t: String,
    df: String,
    p: String,
    n: String,
    undefined: String,
    paired_t: String,
    paired_p: String,
    /// Why the paired t has no value, when it has none.
    paired_undefined: String,
    sign: String,
    sign_title: String,
    sign_p: String,
}

fn cell_texts(report: &StudyReport) -> Vec<CellText> {
    report
        .cells
        .iter()
        .map(|c| CellText {
            family: c.family.clone(),
            variant: c.variant.clone(),
            direction: c.direction.to_string(),
            step_length: c
                .step_length
                .map_or_else(|| "all".to_owned(), |l| l.to_string()),
            delta: c
                .delta
                .map_or_else(|| "–".to_owned(), |d| format!("{d:+.3}")),
            t: fixed(c.t, 2),
            df: fixed(c.df, 1),
            p: p_text(c.p),
            n: format!("{} / {}", c.n_baseline, c.n_variant),
            undefined: c.undefined.clone().unwrap_or_default(),
            paired_t: fixed(c.paired_t.t, 2),
            paired_p: c
                .paired_t
                .p
                .map_or_else(|| "no test".to_owned(), |p| p_text(Some(p))),
            paired_undefined: c
                .paired_t
                .reason
                .as_ref()
                .map_or_else(String::new, ToString::to_string),
            sign: format!(
                "{} {} {}",
                c.sign_test.positive, c.sign_test.negative, c.sign_test.ties
            ),
            sign_title: format!(
                "variant higher on {}, lower on {}, tied on {} items",
                c.sign_test.positive, c.sign_test.negative, c.sign_test.ties
            ),
            sign_p: p_text(Some(c.sign_test.p)),
        })
        .collect()
}

/// The rendered report part of the study page.
struct ReportView {
    row: String,
    heatmap: String,
    handedness: Option<String>,
    cells: Vec<CellText>,
    missing: Vec<String>,
    /// The API's query for this report, without `format`.
    api_query: String,
}

#[derive(Template)]
#[template(path = "study.html")]
struct StudyPage {
    tr: Tr,
    study: StudyView,
    models: Vec<String>,
    /// The picker's current value: `human`, `model:NAME`, or empty.
    chosen: String,
    by_step_length: bool,
    report: Option<ReportView>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct PageQuery {
    /// `human` or `model:NAME`.
    row: Option<String>,
    account: Option<String>,
    by_step_length: Option<String>,
}

async fn study_page(
    State(state): State<AppState>,
    Path(name): Path<String>,
    Query(query): Query<PageQuery>,
    tr: Tr,
) -> Result<Html<String>, PageError> {
    let models = studies::models(&state.hub, &name).await?;
    let chosen = query.row.clone().unwrap_or_default();
    let by_step_length = query
        .by_step_length
        .as_deref()
        .is_some_and(|v| !v.is_empty());
    let account = query.account.clone().filter(|a| !a.trim().is_empty());
    let choice = match chosen.as_str() {
        "" => None,
        "human" => Some(StudyRowChoice::Human),
        other => match other.strip_prefix("model:") {
            Some(model) => Some(StudyRowChoice::Model {
                model: model.to_owned(),
                account: account.clone(),
            }),
            None => {
                return Err(Refusal::bad_value(
                    "row",
                    other,
                    Expected::OneOf(vec!["human", "model:NAME"]),
                )
                .into());
            }
        },
    };
    // Alignment reads every item's signature table: computed once, by the report when there
    // is one.
    let (mut study, report) = match choice {
        None => (studies::show(&state.hub, &name).await?, None),
        Some(choice) => {
            let study = studies::get(&state.hub, &name).await?;
            let report = studies::report(&state.hub, &name, &choice, by_step_length).await?;
            let render = |e: askama::Error| AppError::internal(format!("study '{name}': {e}"));
            let mut api_query = match &choice {
                StudyRowChoice::Human => "human=true".to_owned(),
                StudyRowChoice::Model { model, account } => {
                    let mut pairs = vec![("model", model.as_str())];
                    if let Some(a) = account {
                        pairs.push(("account", a.as_str()));
                    }
                    serde_urlencoded::to_string(pairs).map_err(AppError::internal)?
                }
            };
            if by_step_length {
                api_query.push_str("&by_step_length=true");
            }
            let view = ReportView {
                row: report.stamp.row.clone(),
                heatmap: heatmap_svg(&report).map_err(render)?,
                handedness: handedness_svg(&report).map_err(render)?,
                cells: cell_texts(&report),
                missing: report
                    .variants
                    .iter()
                    .filter_map(|v| {
                        v.missing
                            .as_ref()
                            .map(|why| format!("{}/{}: {why}", v.family, v.variant))
                    })
                    .collect(),
                api_query,
            };
            (study, Some((view, report.variants)))
        }
    };
    let report = report.map(|(view, variants)| {
        // The report's variants are the study's, in the same order.
        for (shown, reported) in study.variants.iter_mut().zip(variants) {
            shown.aligned = Some(reported.aligned);
            shown.alignment = Some(reported.alignment);
        }
        view
    });
    let page = StudyPage {
        tr,
        study,
        models,
        chosen,
        by_step_length,
        report,
    };
    Ok(Html(page.render_page()?))
}

#[derive(Template)]
#[template(path = "admin_studies.html")]
struct AdminStudiesPage {
    name: String,
    csrf: String,
    studies: Vec<StudyView>,
    datasets: Vec<String>,
    notice: Option<String>,
}

async fn render_admin(
    state: &AppState,
    session: Session,
    notice: Option<String>,
) -> Result<Html<String>, PageError> {
    let page = AdminStudiesPage {
        name: session.name,
        csrf: session.csrf_token,
        studies: studies::list(&state.hub).await?,
        datasets: datasets::overview(&state.hub)
            .await?
            .into_iter()
            .map(|o| o.dataset.name)
            .collect(),
        notice,
    };
    Ok(Html(page.render_page()?))
}

async fn admin_page(
    State(state): State<AppState>,
    Admin(session): Admin,
) -> Result<Html<String>, PageError> {
    render_admin(&state, session, None).await
}

#[derive(Deserialize)]
struct NewStudyForm {
    #[serde(default)]
    name: String,
    #[serde(default)]
    baseline: String,
    /// One `FAMILY/LABEL=DATASET` per line.
    #[serde(default)]
    variants: String,
}

async fn admin_create(
    State(state): State<AppState>,
    request: Protected<NewStudyForm>,
) -> Result<Html<String>, PageError> {
    let form = &request.body;
    let mut variants = Vec::new();
    for (i, line) in form.variants.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        variants.push(
            VariantSpec::parse(line)
                .map_err(|e| AppError::Invalid(format!("variants, line {}: {e}", i + 1)))?,
        );
    }
    let view = studies::create(
        &state.hub,
        &request.session.actor(),
        &form.name,
        &form.baseline,
        &variants,
    )
    .await?;
    let aligned: Vec<String> = view
        .variants
        .iter()
        .map(|v| {
            let differently = v.alignment.as_ref().map_or(0, |a| a.verified_differently);
            let warning = if differently > 0 {
                format!(", {differently} of them judged by other rules than the baseline's")
            } else {
                String::new()
            };
            format!(
                "{}/{}: {} aligned{warning}",
                v.spec.family,
                v.spec.label,
                v.aligned.unwrap_or(0)
            )
        })
        .collect();
    let notice = format!(
        "Created study '{}' over baseline '{}' ({}).",
        view.name,
        view.baseline,
        aligned.join("; ")
    );
    render_admin(&state, request.session, Some(notice)).await
}

#[derive(Deserialize)]
struct DeleteForm {
    #[serde(default)]
    study: String,
}

async fn admin_delete(
    State(state): State<AppState>,
    request: Protected<DeleteForm>,
) -> Result<Html<String>, PageError> {
    let name = request.body.study.trim().to_owned();
    studies::delete(&state.hub, &request.session.actor(), &name).await?;
    render_admin(
        &state,
        request.session,
        Some(format!("Deleted study '{name}'; its datasets stay.")),
    )
    .await
}
