//! The explorer (`app::explore`): the page `/datasets/{dataset}/explore` (a GET form of
//! filters, the grid of verdicts a page at a time, a permalink per view) and
//! `GET /api/v1/datasets/{dataset}/explore` (the same page as JSON, or every matching item as
//! CSV with `format=csv`). Public where the dataset's answers are; otherwise admins only (a
//! logged-in admin, or an admin token on the API), and 404 for everyone else.

use askama::Template;
use axum::Router;
use axum::extract::State;
use axum::http::{HeaderValue, header};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::get;
use serde::Deserialize;
use serde_json::json;

use super::annotate::direction_key;
use super::error::{ApiError, PageError, RenderPage};
use super::extract::{Path, Query, whole_number_between};
use super::i18n::{Tr, msg};
use super::openapi::{ApiRoute, Verb};
use super::pages::verdict_view;
use super::session::ReaderIsAdmin;
use super::{AppError, AppState};
use crate::app::explore::{self, Explored, ExplorerPage};
use crate::app::refusal::{Expected, Refusal};
use crate::core::dataset::Direction;
use crate::core::explorer::{
    DEFAULT_PER_PAGE, Grid, MAX_PER_PAGE, Pattern, RowRef, Sort, ViewText,
};
use crate::core::submission::AnswerVerdict;

pub fn page_router() -> Router<AppState> {
    Router::new().route("/datasets/{dataset}/explore", get(explore_page))
}

pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Get,
            "/datasets/{dataset}/explore",
            explore_api,
            "Explore every item's verdicts",
        )
        .describe(
            "The dataset's items × its leaderboard rows (each account's latest published \
             submission of a model, in the board's order) and the Human column, as a grid of \
             verdicts (`exact`, `equivalent`, `wrong`, `unparseable`, `missing`). The Human \
             column pools the answers the Human row counts on the item (no excluded \
             annotator's, none on gold items): right when more than half are task-correct. \
             Filtered by `direction`, `step_length`, `activity` and `pattern`, ordered by \
             `sort`, a page at a time; `counts` gives, for every value of each filter, the \
             items it would show with the other filters kept, and each row's right answers \
             among the matching items. With `format=csv`, every matching item in the view's \
             order as CSV. Only for a dataset whose answers are public (404 otherwise, as for \
             an item's answers), unless the caller is an admin (an admin token in \
             `Authorization: Bearer`, or a logged-in admin's session).",
        )
        .query_with(
            "direction",
            false,
            json!({"enum": ["", "forward", "inverse"]}),
            "Only items of this direction.",
        )
        .query_with(
            "step_length",
            false,
            json!({"anyOf": [{"type": "integer", "minimum": 3, "maximum": 10}, {"const": ""}]}),
            "Only items of this step length (3 to 10).",
        )
        .query(
            "activity",
            false,
            "Only items of this activity (ENACT's `task_name`); one the dataset lacks is 400.",
        )
        .query_with(
            "pattern",
            false,
            json!({"type": "string", "pattern":
                "^(|humans-right-models-wrong|models-disagree|unparseable|only:[0-9]+)$"}),
            "`humans-right-models-wrong`: the Human column right, no model row right; \
             `models-disagree`: some model row right and some not; `unparseable`: some model \
             row's answer could not be read; `only:<submission id>`: that row right and no \
             other model row.",
        )
        .query_with(
            "sort",
            false,
            json!({"type": "string", "pattern": "^(|difficulty|(wrong|right):([0-9]+|human))$"}),
            "`difficulty` (the default): the largest share of judged rows wrong first; \
             `wrong:<row>` or `right:<row>`: that row's wrong (or right) items first, a row \
             being a submission id or `human`. Ties keep the dataset's order.",
        )
        .query_with(
            "page",
            false,
            json!({"anyOf": [{"type": "integer", "minimum": 1, "maximum": 1_000_000}, {"const": ""}]}),
            "1-based page number (default 1).",
        )
        .query_with(
            "per_page",
            false,
            json!({"anyOf": [{"type": "integer", "minimum": 1, "maximum": MAX_PER_PAGE}, {"const": ""}]}),
            "Items per page, 1 to 500 (default 50).",
        )
        .query_with(
            "format",
            false,
            json!({"enum": ["", "json", "csv"]}),
            "`json` (the default): one page; `csv`: every matching item.",
        )
        .responds_json::<ExplorerPage>(200, "A page of the grid, or the CSV.")
        .responds(
            200,
            Some("text/csv"),
            "With `format=csv`: every matching item, one line each.",
        )
        .errors(&[400, 404, 503]),
    ]
}

/// The explorer's query parameters, as typed by people: read by hand for clear messages.
#[derive(Debug, Default, Deserialize)]
struct ExploreQuery {
    direction: Option<String>,
    step_length: Option<String>,
    activity: Option<String>,
    pattern: Option<String>,
    sort: Option<String>,
    page: Option<String>,
    per_page: Option<String>,
    format: Option<String>,
}

impl ExploreQuery {
    fn text(&self) -> ViewText<'_> {
        fn text(v: &Option<String>) -> &str {
            v.as_deref().unwrap_or_default()
        }
        ViewText {
            direction: text(&self.direction),
            step_length: text(&self.step_length),
            activity: text(&self.activity),
            pattern: text(&self.pattern),
            sort: text(&self.sort),
        }
    }

    /// The page and the items per page.
    fn paging(&self) -> Result<(usize, usize), ApiError> {
        let number = |name: &str, v: &Option<String>, default: usize, max: usize| match v
            .as_deref()
            .map(str::trim)
            .filter(|s| !s.is_empty())
        {
            None => Ok(default),
            Some(s) => whole_number_between(name, s, 1, max as u64).map(|n| n as usize),
        };
        Ok((
            number("page", &self.page, 1, 1_000_000)?,
            number("per_page", &self.per_page, DEFAULT_PER_PAGE, MAX_PER_PAGE)?,
        ))
    }
}

async fn explore_api(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    Query(query): Query<ExploreQuery>,
    ReaderIsAdmin(admin): ReaderIsAdmin,
) -> Result<Response, ApiError> {
    let csv = match query.format.as_deref().map(str::trim).unwrap_or_default() {
        "" | "json" => false,
        "csv" => true,
        other => {
            return Err(
                Refusal::bad_value("format", other, Expected::OneOf(vec!["json", "csv"])).into(),
            );
        }
    };
    let (page, per_page) = query.paging()?;
    let explored = explore::view(&state.hub, &dataset, &query.text(), admin).await?;
    if !csv {
        return Ok(axum::Json(explored.page(page, per_page)).into_response());
    }
    let file = format!(
        "attachment; filename=\"enact-hub-explore-{}.csv\"",
        super::file_name_safe(&explored.dataset)
    );
    let disposition = HeaderValue::from_str(&file)
        .map_err(|e| AppError::internal(format!("a CSV's file name: {e}")))?;
    Ok((
        [
            (
                header::CONTENT_TYPE,
                HeaderValue::from_static("text/csv; charset=utf-8"),
            ),
            (header::CONTENT_DISPOSITION, disposition),
        ],
        explored.csv(),
    )
        .into_response())
}

/// An option of one of the form's lists.
struct Choice {
    value: String,
    label: String,
    selected: bool,
}

/// A column's heading: the row, and its right answers among the matching items.
struct ColumnHead {
    label: String,
    detail: String,
    right: String,
}

/// One cell: what it shows (a symbol, so that colour is never the only sign), what a screen
/// reader says, and its class.
struct CellView {
    class: &'static str,
    symbol: &'static str,
    name: String,
    /// The Human column's answers: "2/3".
    tally: String,
}

/// One item's line.
struct LineView {
    id: String,
    href: String,
    kind: String,
    activity: String,
    wrong: String,
    cells: Vec<CellView>,
}

#[derive(Template)]
#[template(path = "explore.html")]
struct ExplorePage {
    tr: Tr,
    dataset: String,
    directions: Vec<Choice>,
    step_lengths: Vec<Choice>,
    activities: Vec<Choice>,
    patterns: Vec<Choice>,
    sorts: Vec<Choice>,
    /// The form's `per_page` when it is not the default.
    per_page: Option<usize>,
    matching: usize,
    total: usize,
    permalink: String,
    json: String,
    csv: String,
    heads: Vec<ColumnHead>,
    lines: Vec<LineView>,
    page: usize,
    pages: usize,
    previous: Option<String>,
    next: Option<String>,
    /// Each verdict's symbol and name.
    legend: Vec<(&'static str, String)>,
}

const VERDICTS: [AnswerVerdict; 5] = [
    AnswerVerdict::Exact,
    AnswerVerdict::Equivalent,
    AnswerVerdict::Wrong,
    AnswerVerdict::Unparseable,
    AnswerVerdict::Missing,
];

fn symbol(verdict: AnswerVerdict) -> &'static str {
    match verdict {
        AnswerVerdict::Exact => "✓",
        AnswerVerdict::Equivalent => "≈",
        AnswerVerdict::Wrong => "✗",
        AnswerVerdict::Unparseable => "?",
        AnswerVerdict::Missing => "–",
    }
}

/// An option's label with the items it would show.
fn counted(tr: &Tr, label: &str, items: usize) -> String {
    tr.t_ns("explore-option-count", "count", items, "label", label)
}

/// Every column of the grid, model rows first, with how the page names it.
fn columns(tr: &Tr, grid: &Grid) -> Vec<(RowRef, String)> {
    grid.rows()
        .iter()
        .enumerate()
        .map(|(r, row)| (RowRef::Model(r), row.label()))
        .chain(std::iter::once((RowRef::Human, tr.t("explore-human"))))
        .collect()
}

/// The choices of the form, each option labelled with the items it would show.
fn choices(tr: &Tr, explored: &Explored) -> [Vec<Choice>; 5] {
    let grid = &explored.grid;
    let view = &explored.view;
    let counts = &explored.exploration.counts;
    let any = |selected: bool| Choice {
        value: String::new(),
        label: tr.t("dataset-any"),
        selected,
    };
    let mut directions = vec![any(view.direction.is_none())];
    directions.extend(counts.directions.iter().map(|f| Choice {
        value: f.value.as_str().to_owned(),
        label: counted(tr, &tr.t(direction_key(f.value)), f.items),
        selected: view.direction == Some(f.value),
    }));
    let mut step_lengths = vec![any(view.step_length.is_none())];
    step_lengths.extend(counts.step_lengths.iter().map(|f| Choice {
        value: f.value.to_string(),
        label: counted(tr, &format!("L={}", f.value), f.items),
        selected: view.step_length == Some(f.value),
    }));
    let mut activities = vec![any(view.activity.is_none())];
    activities.extend(counts.activities.iter().enumerate().map(|(a, f)| Choice {
        value: f.value.clone(),
        label: counted(tr, &f.value, f.items),
        selected: view.activity == Some(a),
    }));
    let p = &counts.patterns;
    let mut patterns = vec![Choice {
        value: String::new(),
        label: counted(tr, &tr.t("explore-pattern-any"), p.any),
        selected: view.pattern.is_none(),
    }];
    for (pattern, key, items) in [
        (
            Pattern::HumansRightModelsWrong,
            msg("explore-pattern-humans-right"),
            p.humans_right_models_wrong,
        ),
        (
            Pattern::ModelsDisagree,
            msg("explore-pattern-disagree"),
            p.models_disagree,
        ),
        (
            Pattern::UnparseableByAny,
            msg("explore-pattern-unparseable"),
            p.unparseable,
        ),
    ] {
        patterns.push(Choice {
            value: grid.pattern_text(pattern),
            label: counted(tr, &tr.t(key), items),
            selected: view.pattern == Some(pattern),
        });
    }
    for (r, (row, only)) in grid.rows().iter().zip(&p.only_right).enumerate() {
        let pattern = Pattern::OnlyRight(r);
        patterns.push(Choice {
            value: grid.pattern_text(pattern),
            label: counted(
                tr,
                &tr.t_s("explore-pattern-only", "row", row.label()),
                only.items,
            ),
            selected: view.pattern == Some(pattern),
        });
    }
    let mut sorts = vec![Choice {
        value: grid.sort_text(Sort::Difficulty),
        label: tr.t("explore-sort-difficulty"),
        selected: view.sort == Sort::Difficulty,
    }];
    for (row, name) in columns(tr, grid) {
        for (sort, key) in [
            (Sort::WrongFirst(row), msg("explore-sort-wrong")),
            (Sort::RightFirst(row), msg("explore-sort-right")),
        ] {
            sorts.push(Choice {
                value: grid.sort_text(sort),
                label: tr.t_s(key, "row", &name),
                selected: view.sort == sort,
            });
        }
    }
    [directions, step_lengths, activities, patterns, sorts]
}

/// The page's address with the view's parameters and `extra` ones.
fn address(
    base: &str,
    view: &[(&'static str, String)],
    extra: &[(&'static str, String)],
) -> String {
    let pairs: Vec<&(&str, String)> = view.iter().chain(extra).collect();
    if pairs.is_empty() {
        return base.to_owned();
    }
    format!(
        "{base}?{}",
        serde_urlencoded::to_string(pairs).unwrap_or_default()
    )
}

fn page_view(tr: Tr, explored: &Explored, page: usize, per_page: usize) -> ExplorePage {
    let grid = &explored.grid;
    let dataset = explored.dataset.clone();
    let view = grid.view_query(&explored.view);
    let base = format!("/datasets/{dataset}/explore");
    let api = format!("/api/v1/datasets/{dataset}/explore");
    let sized: Vec<(&'static str, String)> = if per_page == DEFAULT_PER_PAGE {
        Vec::new()
    } else {
        vec![("per_page", per_page.to_string())]
    };
    let at_page = |n: usize| {
        let mut extra = sized.clone();
        if n > 1 {
            extra.push(("page", n.to_string()));
        }
        address(&base, &view, &extra)
    };
    let pages = explored.exploration.pages(per_page);
    let counts = &explored.exploration.counts;
    // Each verdict's name once per page rather than once per cell.
    let names: Vec<String> = VERDICTS.iter().map(|v| verdict_view(&tr, *v).1).collect();
    let name = |v: AnswerVerdict| {
        VERDICTS
            .iter()
            .position(|x| *x == v)
            .map_or_else(String::new, |i| names[i].clone())
    };
    let cell = |v: AnswerVerdict, tally: String| CellView {
        class: v.as_str(),
        symbol: symbol(v),
        name: name(v),
        tally,
    };
    let directions = [
        tr.t(direction_key(Direction::Forward)),
        tr.t(direction_key(Direction::Inverse)),
    ];
    let lines = explored
        .exploration
        .page(page, per_page)
        .iter()
        .map(|&i| {
            let (wrong, judged) = grid.wrong_of_judged(i);
            let human = grid.human(i);
            let mut cells: Vec<CellView> = grid
                .verdicts(i)
                .iter()
                .map(|v| cell(*v, String::new()))
                .collect();
            cells.push(cell(
                human.verdict(),
                if human.answers == 0 {
                    String::new()
                } else {
                    format!("{}/{}", human.right, human.answers)
                },
            ));
            let direction = match grid.direction(i) {
                Direction::Forward => &directions[0],
                Direction::Inverse => &directions[1],
            };
            LineView {
                id: grid.id(i).to_owned(),
                href: format!("/datasets/{dataset}/items/{}", grid.id(i)),
                kind: format!("{direction} L={}", grid.step_length(i)),
                activity: grid.activity(i).to_owned(),
                wrong: format!("{wrong}/{judged}"),
                cells,
            }
        })
        .collect();
    let heads = columns(&tr, grid)
        .into_iter()
        .enumerate()
        .map(|(c, (row, label))| {
            let detail = match row {
                RowRef::Model(r) => {
                    let row = &grid.rows()[r];
                    if row.baseline {
                        format!("{} · {}", row.account, tr.t("explore-baseline"))
                    } else {
                        row.account.clone()
                    }
                }
                RowRef::Human => String::new(),
            };
            ColumnHead {
                right: tr.t_n(
                    "explore-right-count",
                    "count",
                    counts.right.get(c).copied().unwrap_or_default(),
                ),
                label,
                detail,
            }
        })
        .collect();
    let [directions, step_lengths, activities, patterns, sorts] = choices(&tr, explored);
    ExplorePage {
        directions,
        step_lengths,
        activities,
        patterns,
        sorts,
        per_page: (per_page != DEFAULT_PER_PAGE).then_some(per_page),
        matching: counts.matching,
        total: counts.items,
        permalink: at_page(page),
        json: address(&api, &view, &[]),
        csv: address(&api, &view, &[("format", "csv".to_owned())]),
        heads,
        lines,
        page,
        pages,
        previous: (page > 1).then(|| at_page((page - 1).min(pages))),
        next: (page < pages).then(|| at_page(page + 1)),
        legend: VERDICTS.iter().map(|v| (symbol(*v), name(*v))).collect(),
        dataset,
        tr,
    }
}

async fn explore_page(
    State(state): State<AppState>,
    Path(dataset): Path<String>,
    Query(query): Query<ExploreQuery>,
    ReaderIsAdmin(admin): ReaderIsAdmin,
    tr: Tr,
) -> Result<Html<String>, PageError> {
    let (page, per_page) = query.paging()?;
    let explored = explore::view(&state.hub, &dataset, &query.text(), admin).await?;
    let page = page_view(tr, &explored, page, per_page);
    Ok(Html(page.render_page()?))
}
