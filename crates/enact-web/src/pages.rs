//! The HTML site: datasets on the home page, a browsable item list, and a read-only item view.

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::response::Html;
use axum::routing::get;

use super::AppState;
use super::annotate::direction_key;
use super::api::{ItemQuery, frame_url};
use super::error::{PageError, RenderPage};
use super::extract::{Path, Query};
use super::i18n::{Tr, msg};
use super::session::ReaderIsAdmin;
use crate::app::datasets;
use crate::app::item_answers::{self, ItemAnswers};
use crate::app::items::{self, StoredItem};
use crate::core::dataset::{AnswerVisibility, Direction, StepLength};
use crate::core::error_analysis::why::AnswerWhy;
use crate::core::submission::AnswerVerdict;

pub fn router() -> Router<AppState> {
    Router::new()
        .route("/", get(home))
        .route("/datasets/{dataset}", get(browse))
        .route("/datasets/{dataset}/items/{item_id}", get(item))
}

/// One cell of a direction × step-length count table, with the link that lists those items.
struct CountCell {
    count: i64,
    href: String,
}

struct CountRow {
    direction: String,
    cells: Vec<CountCell>,
    total: i64,
    href: String,
}

struct DatasetCard {
    name: String,
    created_at: String,
    total: i64,
    tasks: i64,
    href: String,
    rows: Vec<CountRow>,
}

#[derive(Template)]
#[template(path = "home.html")]
struct HomePage {
    tr: Tr,
    datasets: Vec<DatasetCard>,
    step_lengths: Vec<u8>,
}

async fn home(State(state): State<AppState>, tr: Tr) -> Result<Html<String>, PageError> {
    let overview = datasets::overview(&state.hub).await?;
    let datasets = overview
        .into_iter()
        .map(|o| {
            let base = format!("/datasets/{}", o.dataset.name);
            let rows = Direction::ALL
                .into_iter()
                .map(|d| CountRow {
                    direction: tr.t(direction_key(d)),
                    cells: StepLength::all()
                        .map(|l| CountCell {
                            count: o.items.get(d, l),
                            href: format!("{base}?direction={d}&step_length={l}"),
                        })
                        .collect(),
                    total: match d {
                        Direction::Forward => o.items.forward,
                        Direction::Inverse => o.items.inverse,
                    },
                    href: format!("{base}?direction={d}"),
                })
                .collect();
            DatasetCard {
                name: o.dataset.name,
                created_at: o.dataset.created_at,
                total: o.items.total,
                tasks: o.tasks,
                href: base,
                rows,
            }
        })
        .collect();
    let page = HomePage {
        tr,
        datasets,
        step_lengths: StepLength::all().map(StepLength::get).collect(),
    };
    Ok(Html(page.render_page()?))
}

struct ItemRow {
    id: String,
    direction: String,
    step_length: u8,
    task_name: String,
    href: String,
}

struct Choice {
    value: String,
    /// What the option shows (the value unless it is translated).
    label: String,
    selected: bool,
}

#[derive(Template)]
#[template(path = "dataset.html")]
struct BrowsePage {
    tr: Tr,
    dataset: String,
    items: Vec<ItemRow>,
    total: i64,
    first_shown: i64,
    last_shown: i64,
    directions: Vec<Choice>,
    step_lengths: Vec<Choice>,
    tasks: Vec<Choice>,
    previous: Option<String>,
    next: Option<String>,
    /// Model runs whose replies anyone may read (the dataset's answers are public): id, name,
    /// model.
    runs: Vec<(i64, String, String)>,
}

async fn browse(
    State(state): State<AppState>,
    Path(name): Path<String>,
    Query(query): Query<ItemQuery>,
    tr: Tr,
) -> Result<Html<String>, PageError> {
    let selection = query.selection()?;
    let (items, total) = selection.fetch(&state, &name).await?;
    let dataset = datasets::by_name(&state.hub, &name).await?;
    let task_names = datasets::task_names(&state.hub, &dataset).await?;
    let runs = crate::app::runs::public_runs(&state.hub, &dataset)
        .await?
        .into_iter()
        .map(|r| (r.id, r.name, r.model))
        .collect();
    let filter = &selection.filter;
    let offset = selection.offset();
    let page_href = |page: u32| format!("/datasets/{name}?{}", selection.query_string(page));
    let shown_to = i64::from(offset) + items.len() as i64;
    let page = BrowsePage {
        tr: tr.clone(),
        items: items
            .into_iter()
            .map(|i| ItemRow {
                href: format!("/datasets/{name}/items/{}", i.item_id),
                id: i.item_id,
                direction: tr.t(direction_key(i.direction)),
                step_length: i.step_length.get(),
                task_name: i.task_name,
            })
            .collect(),
        total,
        first_shown: if shown_to == 0 {
            0
        } else {
            i64::from(offset) + 1
        },
        last_shown: shown_to,
        directions: Direction::ALL
            .into_iter()
            .map(|d| Choice {
                label: tr.t(direction_key(d)),
                value: d.as_str().to_owned(),
                selected: filter.direction == Some(d),
            })
            .collect(),
        step_lengths: StepLength::all()
            .map(|l| Choice {
                label: l.to_string(),
                value: l.to_string(),
                selected: filter.step_length == Some(l),
            })
            .collect(),
        tasks: task_names
            .into_iter()
            .map(|t| Choice {
                selected: filter.task.as_deref() == Some(t.as_str()),
                label: t.clone(),
                value: t,
            })
            .collect(),
        previous: (selection.page > 1).then(|| page_href(selection.page - 1)),
        next: (shown_to < total).then(|| page_href(selection.page + 1)),
        dataset: name,
        runs,
    };
    Ok(Html(page.render_page()?))
}

struct ImageCard {
    label: String,
    src: String,
}

struct ActionLine {
    label: usize,
    text: String,
}

#[derive(Template)]
#[template(path = "item.html")]
struct ItemPage {
    tr: Tr,
    direction_name: String,
    dataset: String,
    id: String,
    item_type: String,
    direction: &'static str,
    step_length: u8,
    task_name: String,
    question: String,
    actions: Vec<ActionLine>,
    images: Vec<ImageCard>,
    dataset_href: String,
    /// Every answer to the item; `None` where they are not shown to this reader.
    answers: Option<AnswersView>,
}

/// A judged answer on the item page.
struct AnswerLine {
    /// The row (model and account) or the annotator.
    who: String,
    /// The order as read ("2 → 1 → 3"), or the raw answer when it could not be read.
    answer: String,
    verdict: &'static str,
    verdict_name: String,
    pairwise: String,
    why: Option<WhyView>,
    /// A note for admins: excluded annotator, baseline row.
    note: String,
}

struct WhyStep {
    heading: String,
    implied: Vec<String>,
    missed: Vec<String>,
}

struct WhyView {
    steps: Vec<WhyStep>,
    pairs: String,
}

/// The rows' answers or the annotators'.
struct AnswerSection {
    id: &'static str,
    heading: String,
    lines: Vec<AnswerLine>,
    /// Said when there is no line.
    none: String,
}

struct AnswersView {
    truth: String,
    sections: Vec<AnswerSection>,
    gold: bool,
    json: String,
}

fn order(labels: &[u8]) -> String {
    labels
        .iter()
        .map(u8::to_string)
        .collect::<Vec<_>>()
        .join(" → ")
}

/// A verdict's class name and its name in the page's language (the item page and the
/// explorer show them alike).
pub(super) fn verdict_view(tr: &Tr, verdict: AnswerVerdict) -> (&'static str, String) {
    let key = match verdict {
        AnswerVerdict::Exact => msg("item-verdict-exact"),
        AnswerVerdict::Equivalent => msg("item-verdict-equivalent"),
        AnswerVerdict::Wrong => msg("item-verdict-wrong"),
        AnswerVerdict::Unparseable => msg("item-verdict-unparseable"),
        AnswerVerdict::Missing => msg("item-verdict-missing"),
    };
    (verdict.as_str(), tr.t(key))
}

fn why_view(tr: &Tr, why: &AnswerWhy) -> WhyView {
    WhyView {
        steps: why
            .steps
            .iter()
            .filter(|s| !s.accepted)
            .map(|s| WhyStep {
                heading: tr.t_nn("item-why-step", "step", s.step, "label", s.label),
                implied: s.implied.clone(),
                missed: s.missed.clone(),
            })
            .collect(),
        pairs: why
            .pairs_out_of_order
            .iter()
            .map(|[x, y]| format!("{x} ↔ {y}"))
            .collect::<Vec<_>>()
            .join(", "),
    }
}

fn pairwise_text(value: Option<f64>) -> String {
    value.map_or_else(|| "–".to_owned(), |v| format!("{:.2}", 100.0 * v))
}

fn answers_view(tr: &Tr, answers: &ItemAnswers) -> AnswersView {
    let models = answers
        .models
        .iter()
        .map(|m| {
            let (verdict, verdict_name) = verdict_view(tr, m.verdict);
            AnswerLine {
                who: format!("{} (#{}, {})", m.model, m.submission, m.account),
                answer: match (&m.parsed, &m.answer) {
                    (Some(p), _) => order(p),
                    (None, Some(raw)) => raw.clone(),
                    (None, None) => "–".to_owned(),
                },
                verdict,
                verdict_name,
                pairwise: pairwise_text(m.pairwise_accuracy),
                why: m.why.as_ref().map(|w| why_view(tr, w)),
                note: if m.baseline {
                    tr.t("item-answer-baseline")
                } else {
                    String::new()
                },
            }
        })
        .collect();
    let humans = answers
        .humans
        .iter()
        .map(|h| {
            let (verdict, verdict_name) = verdict_view(tr, h.verdict);
            AnswerLine {
                who: h.annotator.clone(),
                answer: order(&h.answer),
                verdict,
                verdict_name,
                pairwise: pairwise_text(h.pairwise_accuracy),
                why: h.why.as_ref().map(|w| why_view(tr, w)),
                note: if h.excluded == Some(true) {
                    tr.t("item-answer-excluded")
                } else {
                    String::new()
                },
            }
        })
        .collect();
    AnswersView {
        truth: order(&answers.truth),
        sections: vec![
            AnswerSection {
                id: "models",
                heading: tr.t("item-answers-models"),
                lines: models,
                none: tr.t("item-answers-no-models"),
            },
            AnswerSection {
                id: "humans",
                heading: tr.t("item-answers-humans"),
                lines: humans,
                none: tr.t("item-answers-no-humans"),
            },
        ],
        gold: answers.gold == Some(true),
        json: format!(
            "/api/v1/datasets/{}/items/{}/answers",
            answers.dataset, answers.item.id
        ),
    }
}

async fn item(
    State(state): State<AppState>,
    Path((name, item_id)): Path<(String, String)>,
    ReaderIsAdmin(admin): ReaderIsAdmin,
    tr: Tr,
) -> Result<Html<String>, PageError> {
    let item = StoredItem::clone(&*items::get(&state.hub, &name, &item_id).await?);
    let dataset = datasets::by_name(&state.hub, &name).await?;
    let shown = admin
        || datasets::answer_visibility(&state.hub, &dataset).await? == AnswerVisibility::Public;
    let answers = if shown {
        let answers = item_answers::of(&state.hub, &name, &item_id, admin).await?;
        Some(answers_view(&tr, &answers))
    } else {
        None
    };
    let page = ItemPage {
        answers,
        direction_name: tr.t(direction_key(item.summary.direction)),
        tr,
        dataset_href: format!(
            "/datasets/{name}?direction={}&step_length={}",
            item.summary.direction, item.summary.step_length
        ),
        dataset: name,
        id: item.summary.item_id,
        item_type: item.summary.item_type,
        direction: item.summary.direction.as_str(),
        step_length: item.summary.step_length.get(),
        task_name: item.summary.task_name,
        question: item.question,
        actions: item
            .actions
            .into_iter()
            .enumerate()
            .map(|(i, text)| ActionLine { label: i + 1, text })
            .collect(),
        images: item
            .images
            .iter()
            .map(|img| ImageCard {
                label: img.label(),
                src: frame_url(&img.sha256),
            })
            .collect(),
    };
    Ok(Html(page.render_page()?))
}
