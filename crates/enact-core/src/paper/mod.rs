//! The paper regenerated: result tables in the layout of ENACT's paper (task and pairwise
//! accuracy by direction and step length, rows grouped by category, the Human row last), the
//! results the paper published as data ([`enact_paper_results`]), and any other paper's numbers
//! read from the same JSON ([`PaperTable::from_json`]).
//!
//! - this file: the types ([`Metric`], [`Category`], [`CellKey`], [`ReportedModel`],
//!   [`PaperTable`]) and reading them;
//! - [`mark`]: best and second-best within each category, the paper's rule;
//! - [`hub`]: the hub's own rows, where each cell came from, and the reproduction check;
//! - [`export`]: the folder `enact-hub paper` writes;
//! - [`write`]: the table as LaTeX (booktabs), CSV, Markdown and JSON;
//! - [`figure`]: accuracy by step length per direction, the paper's teaser style, as SVG and PNG;
//! - [`error_figure`]: the shares of structural error classes per hub row and direction (the
//!   paper's error-distribution figure), as SVG and PNG;
//! - [`heatmap_png`]: a study heat map (or any [`crate::heatmap::Heatmap`]) painted as a PNG.
//!
//! Values are percentages as printed (84.62), never fractions.

mod canvas;
pub mod error_figure;
pub mod export;
pub mod figure;
pub mod heatmap_png;
pub mod hub;
pub mod mark;
pub mod write;

use std::collections::BTreeMap;
use std::fmt;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::dataset::{Direction, StepLength};
use crate::verifier::Resampling;

/// Which accuracy a table reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Metric {
    TaskAccuracy,
    PairwiseAccuracy,
}

impl Metric {
    pub const ALL: [Metric; 2] = [Metric::TaskAccuracy, Metric::PairwiseAccuracy];

    /// The name in files and on the command line: `task_accuracy`, `pairwise_accuracy`.
    pub fn as_str(self) -> &'static str {
        match self {
            Metric::TaskAccuracy => "task_accuracy",
            Metric::PairwiseAccuracy => "pairwise_accuracy",
        }
    }

    /// The name a reader sees: "Task Accuracy", "Pairwise Accuracy".
    pub fn title(self) -> &'static str {
        match self {
            Metric::TaskAccuracy => "Task Accuracy",
            Metric::PairwiseAccuracy => "Pairwise Accuracy",
        }
    }
}

/// The group a row is marked within. The paper has proprietary and open-weight models and the
/// Human row; an admin may name any other (the hub's own rows get one of their own).
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum Category {
    Proprietary,
    OpenWeight,
    /// Human performance: never marked, always last.
    Human,
    /// Any other name, never one of the three above, never blank.
    Named(String),
}

impl Category {
    /// The category called `name`; the three known names map to their variants.
    pub fn new(name: &str) -> Result<Category, String> {
        let name = name.trim();
        Ok(match name {
            "proprietary" => Category::Proprietary,
            "open-weight" => Category::OpenWeight,
            "human" => Category::Human,
            "" => return Err("a category must have a name".to_owned()),
            _ => Category::Named(name.to_owned()),
        })
    }

    pub fn as_str(&self) -> &str {
        match self {
            Category::Proprietary => "proprietary",
            Category::OpenWeight => "open-weight",
            Category::Human => "human",
            Category::Named(name) => name,
        }
    }

    /// The heading of the category's group in a table, as in the paper.
    pub fn heading(&self) -> String {
        match self {
            Category::Proprietary => "Proprietary Models".to_owned(),
            Category::OpenWeight => "Open-Weight Models".to_owned(),
            Category::Human => "Human".to_owned(),
            Category::Named(name) => name.clone(),
        }
    }
}

impl TryFrom<String> for Category {
    type Error = String;
    fn try_from(name: String) -> Result<Self, Self::Error> {
        Category::new(&name)
    }
}

impl From<Category> for String {
    fn from(c: Category) -> String {
        c.as_str().to_owned()
    }
}

impl fmt::Display for Category {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One column of a table: a direction and a step length, written `forward_3` … `inverse_10`.
/// Ordered as the paper's columns: forward L=3..10, then inverse L=3..10.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub struct CellKey {
    pub direction: Direction,
    pub step_length: StepLength,
}

impl CellKey {
    /// The 16 columns in the paper's order.
    pub fn all() -> impl Iterator<Item = CellKey> {
        Direction::ALL.into_iter().flat_map(|direction| {
            StepLength::all().map(move |step_length| CellKey {
                direction,
                step_length,
            })
        })
    }

    /// `forward_3` … `inverse_10`, with what is wrong when it is not one of them.
    pub fn parse(key: &str) -> Result<CellKey, String> {
        let (direction, length) = key
            .split_once('_')
            .ok_or_else(|| "a cell is named direction_L, e.g. forward_3".to_owned())?;
        let direction = Direction::parse(direction)
            .ok_or_else(|| format!("direction must be forward or inverse, not {direction:?}"))?;
        let step_length = length
            .parse::<usize>()
            .ok()
            .and_then(StepLength::new)
            .ok_or_else(|| "step length must be 3..10".to_owned())?;
        Ok(CellKey {
            direction,
            step_length,
        })
    }
}

impl TryFrom<String> for CellKey {
    type Error = String;
    fn try_from(key: String) -> Result<Self, Self::Error> {
        CellKey::parse(&key)
    }
}

impl From<CellKey> for String {
    fn from(k: CellKey) -> String {
        k.to_string()
    }
}

impl fmt::Display for CellKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}_{}", self.direction, self.step_length)
    }
}

/// A model's results as a paper published them (values in percent as printed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReportedModel {
    pub model: String,
    pub category: Category,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub family: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<String>,
    /// Where the numbers were published: paper and table labels, or a URL.
    pub source: String,
    #[serde(default)]
    pub task_accuracy: BTreeMap<CellKey, f64>,
    #[serde(default)]
    pub pairwise_accuracy: BTreeMap<CellKey, f64>,
}

impl ReportedModel {
    /// The values of `metric`.
    pub fn values(&self, metric: Metric) -> &BTreeMap<CellKey, f64> {
        match metric {
            Metric::TaskAccuracy => &self.task_accuracy,
            Metric::PairwiseAccuracy => &self.pairwise_accuracy,
        }
    }

    /// This model as an unmarked row of a `metric` table.
    pub fn row(&self, metric: Metric) -> PaperRow {
        PaperRow {
            model: self.model.clone(),
            category: self.category.clone(),
            source: self.source.clone(),
            family: self.family.clone(),
            size: self.size.clone(),
            cells: self
                .values(metric)
                .iter()
                .map(|(key, value)| (*key, Cell::value(*value)))
                .collect(),
        }
    }
}

/// The paper's results, as transcribed in `data/enact-paper-results.json` (checked against the
/// paper's LaTeX by `tests/paper_transcription.rs`).
const ENACT_PAPER_RESULTS: &str = include_str!("../../data/enact-paper-results.json");

/// Every model of the ENACT paper's appendix tables (`tab:app_task_acc`, `tab:app_pair_acc`)
/// and its Human row, in the paper's order.
pub fn enact_paper_results() -> Vec<ReportedModel> {
    // The file is part of the crate and a test reads it: failing here is a build defect.
    serde_json::from_str(ENACT_PAPER_RESULTS)
        .expect("data/enact-paper-results.json is a list of reported models")
}

/// The rows of the paper's main-text table (`tab:main_pair_acc`, pairwise accuracy), in its
/// order: the models a `--models` list names to regenerate it.
pub const ENACT_PAPER_MAIN_TABLE_MODELS: [&str; 20] = [
    "GPT-5",
    "GPT-5 mini",
    "GPT-5 nano",
    "Gemini 2.5 Pro",
    "Gemini 2.5 Flash",
    "Gemini 2.5 Flash-Lite",
    "Claude Sonnet 4",
    "GLM-4.5V",
    "Llama-4-Mav-17B-128E-Ins",
    "InternVL3.5-241B-A28B",
    "Gemma-3-27b-it",
    "QVQ-72B-Preview",
    "Qwen2.5-VL-72B-Ins",
    "Qwen2.5-VL-32B-Ins",
    "Ovis2.5-9B",
    "MiniCPM-V-4.5",
    "Idefics3-8B-Llama3",
    "Cosmos-Reason1",
    "BAGEL",
    "Human Performance",
];

/// A `metric` table of `models` (unmarked; see [`mark::mark`]).
pub fn table_of(metric: Metric, models: &[ReportedModel]) -> PaperTable {
    PaperTable {
        metric,
        rows: models.iter().map(|m| m.row(metric)).collect(),
        intervals: None,
    }
}

/// The reported models that `tables` hold (e.g. another paper's task- and pairwise-accuracy
/// tables, as [`PaperTable::from_json`] reads them): one per model name, in order of first
/// appearance, with each table's values under its metric. The same model in two tables must
/// agree on category, family, size and source, and a metric may come from one table only.
pub fn reported_models(tables: &[PaperTable]) -> Result<Vec<ReportedModel>, PaperError> {
    let mut models: Vec<ReportedModel> = Vec::new();
    let mut filled: Vec<Vec<Metric>> = Vec::new();
    for table in tables {
        for (i, row) in table.rows.iter().enumerate() {
            let problem = |field: &str, message: String| PaperError::Row {
                row: i + 1,
                model: row.model.clone(),
                field: field.to_owned(),
                message,
            };
            let position = match models.iter().position(|m| m.model == row.model) {
                Some(position) => position,
                None => {
                    models.push(ReportedModel {
                        model: row.model.clone(),
                        category: row.category.clone(),
                        family: row.family.clone(),
                        size: row.size.clone(),
                        source: row.source.clone(),
                        task_accuracy: BTreeMap::new(),
                        pairwise_accuracy: BTreeMap::new(),
                    });
                    filled.push(Vec::new());
                    models.len() - 1
                }
            };
            let model = &mut models[position];
            let disagree = |field: &str, earlier: String, now: String| {
                problem(
                    field,
                    format!("{now:?} here, {earlier:?} in an earlier row"),
                )
            };
            if model.category != row.category {
                return Err(disagree(
                    "category",
                    model.category.to_string(),
                    row.category.to_string(),
                ));
            }
            for (field, earlier, now) in [
                ("family", &model.family, &row.family),
                ("size", &model.size, &row.size),
            ] {
                if earlier != now {
                    return Err(disagree(
                        field,
                        earlier.clone().unwrap_or_default(),
                        now.clone().unwrap_or_default(),
                    ));
                }
            }
            if model.source != row.source {
                return Err(disagree("source", model.source.clone(), row.source.clone()));
            }
            if filled[position].contains(&table.metric) {
                return Err(problem(
                    "model",
                    format!("has {} twice", table.metric.as_str()),
                ));
            }
            filled[position].push(table.metric);
            let values = match table.metric {
                Metric::TaskAccuracy => &mut model.task_accuracy,
                Metric::PairwiseAccuracy => &mut model.pairwise_accuracy,
            };
            values.extend(
                row.cells
                    .iter()
                    .filter_map(|(key, cell)| cell.value.map(|v| (*key, v))),
            );
        }
    }
    Ok(models)
}

/// Best or second-best within its category.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mark {
    First,
    Second,
}

/// One printed cell.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cell {
    /// Percent; `None` when the row has no figure for this column.
    pub value: Option<f64>,
    pub mark: Option<Mark>,
    /// A confidence interval in percent, for the hub's own rows (`--intervals`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interval: Option<(f64, f64)>,
}

impl Cell {
    /// An unmarked cell holding `value`.
    pub fn value(value: f64) -> Cell {
        Cell {
            value: Some(value),
            mark: None,
            interval: None,
        }
    }
}

/// One row: a model (or the humans) with its cells.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PaperRow {
    pub model: String,
    pub category: Category,
    pub source: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub family: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<String>,
    pub cells: BTreeMap<CellKey, Cell>,
}

impl PaperRow {
    /// The value in column `key`, if any.
    pub fn value(&self, key: CellKey) -> Option<f64> {
        self.cells.get(&key).and_then(|c| c.value)
    }
}

/// A result table: one metric, rows in the order given.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PaperTable {
    pub metric: Metric,
    pub rows: Vec<PaperRow>,
    /// What the printed intervals' bootstrap resampled; `None` when none is printed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub intervals: Option<Resampling>,
}

/// What is wrong with a table's JSON, naming the row and field.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PaperError {
    #[error("not a table: {0}")]
    Table(String),
    /// `row` counts from 1; `model` is empty when the row has none.
    #[error("row {row} ({model}): {field}: {message}")]
    Row {
        row: usize,
        model: String,
        field: String,
        message: String,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TableJson {
    metric: Metric,
    rows: Vec<Value>,
    #[serde(default)]
    intervals: Option<Resampling>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RowJson {
    model: String,
    category: Value,
    source: String,
    #[serde(default)]
    family: Option<String>,
    #[serde(default)]
    size: Option<String>,
    cells: serde_json::Map<String, Value>,
}

impl PaperTable {
    /// A table in the shape [`write::to_json`] writes, e.g. another paper's numbers. Every
    /// error names the row (from 1), its model and the field: `row 3 (GPT-5):
    /// cells.forward_11: step length must be 3..10`.
    pub fn from_json(text: &str) -> Result<PaperTable, PaperError> {
        let table: TableJson =
            serde_json::from_str(text).map_err(|e| PaperError::Table(e.to_string()))?;
        let rows = table
            .rows
            .into_iter()
            .enumerate()
            .map(|(i, row)| row_from_json(i + 1, row))
            .collect::<Result<_, _>>()?;
        Ok(PaperTable {
            metric: table.metric,
            rows,
            intervals: table.intervals,
        })
    }
}

fn row_from_json(row: usize, json: Value) -> Result<PaperRow, PaperError> {
    let model = json
        .get("model")
        .and_then(Value::as_str)
        .unwrap_or_default()
        .to_owned();
    let problem = |field: &str, message: String| PaperError::Row {
        row,
        model: model.clone(),
        field: field.to_owned(),
        message,
    };
    let raw: RowJson = serde_json::from_value(json).map_err(|e| problem("row", e.to_string()))?;
    if raw.model.trim().is_empty() {
        return Err(problem("model", "must not be blank".to_owned()));
    }
    let category = match raw.category {
        Value::String(name) => Category::new(&name).map_err(|m| problem("category", m))?,
        other => {
            return Err(problem(
                "category",
                format!("must be a string, not {other}"),
            ));
        }
    };
    let mut cells = BTreeMap::new();
    for (key, cell) in raw.cells {
        let field = format!("cells.{key}");
        let parsed = CellKey::parse(&key).map_err(|m| problem(&field, m))?;
        let cell: Cell =
            serde_json::from_value(cell).map_err(|e| problem(&field, e.to_string()))?;
        check_percent(cell.value).map_err(|m| problem(&format!("{field}.value"), m))?;
        if let Some((low, high)) = cell.interval {
            check_percent(Some(low))
                .and(check_percent(Some(high)))
                .and(if low <= high {
                    Ok(())
                } else {
                    Err(format!("{low} is above {high}"))
                })
                .map_err(|m| problem(&format!("{field}.interval"), m))?;
        }
        cells.insert(parsed, cell);
    }
    Ok(PaperRow {
        model: raw.model,
        category,
        source: raw.source,
        family: raw.family,
        size: raw.size,
        cells,
    })
}

fn check_percent(value: Option<f64>) -> Result<(), String> {
    match value {
        Some(v) if !(0.0..=100.0).contains(&v) => Err(format!("{v} is not a percentage (0..100)")),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_keys_are_the_papers_sixteen_columns_in_order() {
        let keys: Vec<String> = CellKey::all().map(|k| k.to_string()).collect();
        assert_eq!(keys.len(), 16);
        assert_eq!(keys[0], "forward_3");
        assert_eq!(keys[7], "forward_10");
        assert_eq!(keys[8], "inverse_3");
        assert_eq!(keys[15], "inverse_10");
        let mut sorted: Vec<CellKey> = CellKey::all().collect();
        sorted.sort();
        assert_eq!(sorted, CellKey::all().collect::<Vec<_>>());
        for k in CellKey::all() {
            assert_eq!(CellKey::parse(&k.to_string()), Ok(k));
        }
        assert!(CellKey::parse("forward_11").is_err());
        assert!(CellKey::parse("sideways_3").is_err());
        assert!(CellKey::parse("forward3").is_err());
    }

    #[test]
    fn categories_read_their_three_names_and_any_other() {
        assert_eq!(Category::new("open-weight"), Ok(Category::OpenWeight));
        assert_eq!(Category::new("human"), Ok(Category::Human));
        assert_eq!(
            Category::new("This hub"),
            Ok(Category::Named("This hub".to_owned()))
        );
        assert!(Category::new("  ").is_err());
        let json = serde_json::to_string(&Category::OpenWeight).unwrap();
        assert_eq!(json, "\"open-weight\"");
    }

    #[test]
    fn the_papers_results_hold_thirty_models_and_the_humans_with_every_cell() {
        let models = enact_paper_results();
        assert_eq!(models.len(), 31);
        assert_eq!(
            models
                .iter()
                .filter(|m| m.category == Category::Human)
                .count(),
            1
        );
        for m in &models {
            for metric in Metric::ALL {
                assert_eq!(m.values(metric).len(), 16, "{} {metric:?}", m.model);
            }
        }
    }

    #[test]
    fn a_table_reads_back_what_it_is_and_names_the_row_of_a_mistake() {
        let good = r#"{"metric": "pairwise_accuracy", "rows": [
            {"model": "GPT-5", "category": "proprietary", "source": "p",
             "cells": {"forward_3": {"value": 84.62, "mark": "first"},
                       "inverse_10": {"value": null, "mark": null}}}]}"#;
        let table = PaperTable::from_json(good).unwrap();
        assert_eq!(table.metric, Metric::PairwiseAccuracy);
        let key = CellKey::parse("forward_3").unwrap();
        assert_eq!(table.rows[0].cells[&key].mark, Some(Mark::First));
        assert_eq!(table.rows[0].value(key), Some(84.62));

        let row = |cells: &str| {
            format!(
                r#"{{"metric": "task_accuracy", "rows": [
                {{"model": "A", "category": "human", "source": "s", "cells": {{}}}},
                {{"model": "GPT-5", "category": "proprietary", "source": "s", "cells": {cells}}}]}}"#
            )
        };
        let err = |cells: &str| PaperTable::from_json(&row(cells)).unwrap_err().to_string();
        assert_eq!(
            err(r#"{"forward_11": {"value": 1.0, "mark": null}}"#),
            "row 2 (GPT-5): cells.forward_11: step length must be 3..10"
        );
        assert_eq!(
            err(r#"{"forward_3": {"value": 184.0, "mark": null}}"#),
            "row 2 (GPT-5): cells.forward_3.value: 184 is not a percentage (0..100)"
        );
        assert!(
            err(r#"{"forward_3": {"value": 1.0, "mark": "third"}}"#)
                .starts_with("row 2 (GPT-5): cells.forward_3: unknown variant `third`")
        );
        assert_eq!(
            err(r#"{"forward_3": {"value": 50.0, "mark": null, "interval": [60.0, 40.0]}}"#),
            "row 2 (GPT-5): cells.forward_3.interval: 60 is above 40"
        );
        let no_source = r#"{"metric": "task_accuracy", "rows": [
            {"model": "GPT-5", "category": "proprietary", "cells": {}}]}"#;
        assert_eq!(
            PaperTable::from_json(no_source).unwrap_err().to_string(),
            "row 1 (GPT-5): row: missing field `source`"
        );
        assert!(matches!(
            PaperTable::from_json(r#"{"metric": "accuracy", "rows": []}"#),
            Err(PaperError::Table(_))
        ));
    }

    #[test]
    fn tables_give_back_the_reported_models_they_were_made_of() {
        let models = enact_paper_results();
        let tables: Vec<PaperTable> = Metric::ALL.map(|m| table_of(m, &models)).to_vec();
        assert_eq!(reported_models(&tables), Ok(models.clone()));
        // Through JSON, as another paper's numbers arrive.
        let read: Vec<PaperTable> = tables
            .iter()
            .map(|t| PaperTable::from_json(&write::to_json(t)).unwrap())
            .collect();
        assert_eq!(reported_models(&read), Ok(models));
    }

    #[test]
    fn tables_that_disagree_about_a_model_are_refused() {
        let models = enact_paper_results();
        let task = table_of(Metric::TaskAccuracy, &models);
        let mut pair = table_of(Metric::PairwiseAccuracy, &models);
        pair.rows[2].category = Category::OpenWeight;
        assert_eq!(
            reported_models(&[task.clone(), pair])
                .unwrap_err()
                .to_string(),
            "row 3 (GPT-5 nano): category: \"open-weight\" here, \"proprietary\" in an earlier row"
        );
        assert_eq!(
            reported_models(&[task.clone(), task])
                .unwrap_err()
                .to_string(),
            "row 1 (GPT-5): model: has task_accuracy twice"
        );
    }
}
