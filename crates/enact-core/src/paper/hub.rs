//! The hub's own rows in a paper table: a leaderboard row's figures as the paper prints them,
//! where every cell came from ([`CellProvenance`]), which rows a table holds and in what order
//! ([`assemble`]), and the reproduction check of a published model against the hub's own run
//! of it ([`reproduction`]).

use std::collections::BTreeMap;

use serde::Serialize;

use super::mark::mark;
use super::{Category, Cell, CellKey, Metric, PaperRow, PaperTable, ReportedModel};
use crate::dataset::{Direction, StepLength};
use crate::leaderboard::{AccuracyCell, LeaderboardRow, RowSource};
use crate::submission::Provenance;
use crate::verifier::{Resampling, leaderboard_ci};

/// The category the hub's own model rows are marked within unless their metadata names one:
/// the paper marks best and second-best per category, and a hub run is neither of the paper's.
pub const HUB_CATEGORY: &str = "enact-hub";

/// Where a row's figures came from.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Origin {
    /// A scored submission of this hub (an upload or a model run's answers).
    Submission {
        submission: i64,
        /// `run` when this hub asked the model itself, else `submitted`.
        provenance: Provenance,
        account: String,
        metric_version: u32,
        hub_version: String,
    },
    /// The annotators' answers on this hub (the leaderboard's Human row).
    Annotations {
        answers: usize,
        annotators: usize,
        metric_version: u32,
        hub_version: String,
    },
    /// A number a paper published.
    Reported { source: String },
}

/// One of the hub's rows, its figures in percent as the paper prints them.
#[derive(Debug, Clone, PartialEq)]
pub struct HubRow {
    pub model: String,
    pub category: Category,
    pub family: Option<String>,
    pub size: Option<String>,
    pub origin: Origin,
    pub task_accuracy: BTreeMap<CellKey, f64>,
    pub pairwise_accuracy: BTreeMap<CellKey, f64>,
    /// Bootstrap intervals in percent, per metric and column, where computed.
    pub intervals: BTreeMap<(Metric, CellKey), (f64, f64)>,
    /// What the intervals' bootstrap resampled, once computed.
    pub interval_resampling: Option<Resampling>,
}

/// One item's result in a hub row, for its intervals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ItemResult {
    pub column: CellKey,
    /// The item's activity (ENACT's `task_name`) as a number: the bootstrap's cluster.
    pub activity: u32,
    pub task_correct: bool,
    pub pairwise_accuracy: Option<f64>,
}

/// What the metadata says of a hub row's model.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RowMetadata {
    pub category: Option<Category>,
    pub family: Option<String>,
    pub size: Option<String>,
}

/// A fraction as the paper prints it: percent with two decimals.
pub fn percent(fraction: f64) -> f64 {
    (fraction * 10_000.0).round() / 100.0
}

fn per_step(row: &LeaderboardRow, direction: Direction) -> &[(u8, AccuracyCell)] {
    match direction {
        Direction::Forward => &row.forward.per_step,
        Direction::Inverse => &row.inverse.per_step,
    }
}

impl HubRow {
    /// A leaderboard row (a submission or the Human row) as a paper row: its per-step-length
    /// figures, stamped with `hub_version`. Columns without items stay empty.
    pub fn of_leaderboard(row: &LeaderboardRow, metadata: RowMetadata, hub_version: &str) -> Self {
        let mut task_accuracy = BTreeMap::new();
        let mut pairwise_accuracy = BTreeMap::new();
        for direction in Direction::ALL {
            for (length, cell) in per_step(row, direction) {
                let Some(step_length) = StepLength::new(usize::from(*length)) else {
                    continue;
                };
                let key = CellKey {
                    direction,
                    step_length,
                };
                if let Some(ta) = cell.task_accuracy {
                    task_accuracy.insert(key, percent(ta));
                }
                if let Some(pa) = cell.pairwise_accuracy {
                    pairwise_accuracy.insert(key, percent(pa));
                }
            }
        }
        let human = row.source == RowSource::Human;
        let origin = match (human, row.submission) {
            (false, Some(submission)) => Origin::Submission {
                submission,
                provenance: row.provenance.unwrap_or(Provenance::Submitted),
                account: row.account.clone(),
                metric_version: row.metric.metric_version,
                hub_version: hub_version.to_owned(),
            },
            _ => Origin::Annotations {
                answers: row.human.map_or(0, |h| h.answers),
                annotators: row.human.map_or(0, |h| h.annotators),
                metric_version: row.metric.metric_version,
                hub_version: hub_version.to_owned(),
            },
        };
        let category = if human {
            Category::Human
        } else {
            metadata
                .category
                .unwrap_or_else(|| Category::Named(HUB_CATEGORY.to_owned()))
        };
        HubRow {
            model: if human {
                "Human (this hub)".to_owned()
            } else {
                row.model.clone()
            },
            category,
            family: metadata.family,
            size: metadata.size,
            origin,
            task_accuracy,
            pairwise_accuracy,
            intervals: BTreeMap::new(),
            interval_resampling: None,
        }
    }

    /// This row with bootstrap intervals per column, from its per-item results, resampling
    /// what `resampling` says within each column. The leaderboard's resamples, seed and level.
    pub fn with_intervals(mut self, items: &[ItemResult], resampling: Resampling) -> Self {
        // Per column, (activity, value) of task success and of pairwise accuracy.
        type Clustered = Vec<(u32, f64)>;
        let mut by_column: BTreeMap<CellKey, (Clustered, Clustered)> = BTreeMap::new();
        for item in items {
            let (ta, pa) = by_column.entry(item.column).or_default();
            ta.push((item.activity, if item.task_correct { 1.0 } else { 0.0 }));
            pa.extend(item.pairwise_accuracy.map(|p| (item.activity, p)));
        }
        let interval = |values: &[(u32, f64)]| {
            leaderboard_ci(values, resampling).map(|ci| (percent(ci.low), percent(ci.high)))
        };
        self.interval_resampling = Some(resampling);
        for (key, (ta, pa)) in by_column {
            if let Some(ci) = interval(&ta) {
                self.intervals.insert((Metric::TaskAccuracy, key), ci);
            }
            if let Some(ci) = interval(&pa) {
                self.intervals.insert((Metric::PairwiseAccuracy, key), ci);
            }
        }
        self
    }

    fn values(&self, metric: Metric) -> &BTreeMap<CellKey, f64> {
        match metric {
            Metric::TaskAccuracy => &self.task_accuracy,
            Metric::PairwiseAccuracy => &self.pairwise_accuracy,
        }
    }

    fn row(&self, metric: Metric, intervals: bool) -> PaperRow {
        PaperRow {
            model: self.model.clone(),
            category: self.category.clone(),
            source: self.source(),
            family: self.family.clone(),
            size: self.size.clone(),
            cells: self
                .values(metric)
                .iter()
                .map(|(key, value)| {
                    let interval = intervals
                        .then(|| self.intervals.get(&(metric, *key)).copied())
                        .flatten();
                    (
                        *key,
                        Cell {
                            interval,
                            ..Cell::value(*value)
                        },
                    )
                })
                .collect(),
        }
    }

    /// The row's source as a table prints it.
    pub fn source(&self) -> String {
        match &self.origin {
            Origin::Submission {
                submission,
                provenance: Provenance::Run,
                ..
            } => format!("enact-hub model run (submission {submission})"),
            Origin::Submission { submission, .. } => format!("enact-hub submission {submission}"),
            Origin::Annotations { answers, .. } => {
                format!("enact-hub annotations ({answers} answers)")
            }
            Origin::Reported { source } => source.clone(),
        }
    }
}

/// Where one printed cell came from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CellProvenance {
    pub table: Metric,
    pub model: String,
    pub category: Category,
    pub cell: CellKey,
    pub value: f64,
    pub from: Origin,
}

/// A table with where each of its cells came from.
#[derive(Debug, Clone, PartialEq)]
pub struct AssembledTable {
    pub table: PaperTable,
    pub provenance: Vec<CellProvenance>,
}

/// A `--models` name that no row has.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("no row is named '{name}' (rows: {known})")]
pub struct UnknownModel {
    pub name: String,
    pub known: String,
}

/// Where a category goes in a table: the paper's two, then any other in order of first
/// appearance, the Human rows last.
fn group_order(rows: &[(Category, usize)]) -> Vec<usize> {
    let rank = |c: &Category, first_seen: usize| match c {
        Category::Proprietary => (0, 0),
        Category::OpenWeight => (1, 0),
        Category::Named(_) => (2, first_seen),
        Category::Human => (3, 0),
    };
    let mut first_seen: BTreeMap<&Category, usize> = BTreeMap::new();
    for (i, (category, _)) in rows.iter().enumerate() {
        first_seen.entry(category).or_insert(i);
    }
    let mut order: Vec<usize> = (0..rows.len()).collect();
    order.sort_by_key(|i| {
        let (category, position) = &rows[*i];
        (rank(category, first_seen[category]), *position)
    });
    order
}

/// The `metric` table of `reported` rows and the hub's `own` rows, marked by the paper's rule.
///
/// Without `models`, every row: the published ones in their order, then the hub's. With
/// `models` (a main-text table like the paper's Table 1), the rows named, in that order, each
/// name taking every row of that model (a published row and the hub's own run of it both
/// stay); a name no row has is refused. Either way rows are grouped by category (proprietary,
/// open-weight, the others, Human last), keeping their order within each group. `intervals`
/// prints the hub rows' bootstrap intervals.
pub fn assemble(
    metric: Metric,
    reported: &[ReportedModel],
    own: &[HubRow],
    models: Option<&[String]>,
    intervals: bool,
) -> Result<AssembledTable, UnknownModel> {
    struct Candidate {
        row: PaperRow,
        from: Origin,
    }
    let mut candidates: Vec<Candidate> = reported
        .iter()
        .map(|m| Candidate {
            row: m.row(metric),
            from: Origin::Reported {
                source: m.source.clone(),
            },
        })
        .collect();
    candidates.extend(own.iter().map(|h| Candidate {
        row: h.row(metric, intervals),
        from: h.origin.clone(),
    }));
    let chosen: Vec<(usize, usize)> = match models {
        None => (0..candidates.len()).map(|i| (i, i)).collect(),
        Some(names) => {
            let mut chosen = Vec::new();
            for (position, name) in names.iter().enumerate() {
                let matching: Vec<usize> = (0..candidates.len())
                    .filter(|i| candidates[*i].row.model == *name)
                    .collect();
                if matching.is_empty() {
                    let mut known: Vec<&str> =
                        candidates.iter().map(|c| c.row.model.as_str()).collect();
                    known.dedup();
                    return Err(UnknownModel {
                        name: name.clone(),
                        known: known.join(", "),
                    });
                }
                chosen.extend(matching.into_iter().map(|i| (i, position)));
            }
            chosen
        }
    };
    let keyed: Vec<(Category, usize)> = chosen
        .iter()
        .map(|(i, position)| (candidates[*i].row.category.clone(), *position))
        .collect();
    let order = group_order(&keyed);
    let picked: Vec<&Candidate> = order.iter().map(|k| &candidates[chosen[*k].0]).collect();
    let mut table = PaperTable {
        metric,
        rows: picked.iter().map(|c| c.row.clone()).collect(),
        intervals: None,
    };
    if intervals {
        table.intervals = own
            .iter()
            .filter(|h| picked.iter().any(|c| c.row.model == h.model))
            .find_map(|h| h.interval_resampling.filter(|_| !h.intervals.is_empty()));
    }
    mark(&mut table);
    let provenance = picked
        .iter()
        .flat_map(|c| {
            c.row.cells.iter().filter_map(|(key, cell)| {
                cell.value.map(|value| CellProvenance {
                    table: metric,
                    model: c.row.model.clone(),
                    category: c.row.category.clone(),
                    cell: *key,
                    value,
                    from: c.from.clone(),
                })
            })
        })
        .collect();
    Ok(AssembledTable { table, provenance })
}

/// One cell of the reproduction check: a published value beside the hub's for the same model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReproducedCell {
    pub model: String,
    pub metric: Metric,
    pub cell: CellKey,
    pub reported: f64,
    pub hub: f64,
    /// The hub's value minus the published one, in percentage points.
    pub difference: f64,
    /// The hub's bootstrap interval, when computed.
    pub interval: Option<(f64, f64)>,
    /// Whether the published value lies inside that interval.
    pub inside: Option<bool>,
    /// The hub's row: its submission.
    pub submission: Option<i64>,
    pub source: String,
}

/// Every published model that the hub also ran or was sent (same model name, ignoring case),
/// cell by cell where both have a value.
pub fn reproduction(reported: &[ReportedModel], own: &[HubRow]) -> Vec<ReproducedCell> {
    let mut cells = Vec::new();
    for published in reported {
        for hub in own
            .iter()
            .filter(|h| h.model.eq_ignore_ascii_case(&published.model))
        {
            let submission = match hub.origin {
                Origin::Submission { submission, .. } => Some(submission),
                _ => None,
            };
            for metric in Metric::ALL {
                for (key, reported_value) in published.values(metric) {
                    let Some(hub_value) = hub.values(metric).get(key) else {
                        continue;
                    };
                    let interval = hub.intervals.get(&(metric, *key)).copied();
                    cells.push(ReproducedCell {
                        model: published.model.clone(),
                        metric,
                        cell: *key,
                        reported: *reported_value,
                        hub: *hub_value,
                        difference: percent((hub_value - reported_value) / 100.0),
                        interval,
                        inside: interval.map(|(low, high)| (low..=high).contains(reported_value)),
                        submission,
                        source: published.source.clone(),
                    });
                }
            }
        }
    }
    cells
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(direction: Direction, l: usize) -> CellKey {
        CellKey {
            direction,
            step_length: StepLength::new(l).unwrap(),
        }
    }

    fn hub(model: &str, submission: i64, ta: f64) -> HubRow {
        HubRow {
            model: model.to_owned(),
            category: Category::Named(HUB_CATEGORY.to_owned()),
            family: None,
            size: None,
            origin: Origin::Submission {
                submission,
                provenance: Provenance::Submitted,
                account: "alice".to_owned(),
                metric_version: 3,
                hub_version: "0.1.0+abc".to_owned(),
            },
            task_accuracy: BTreeMap::from([(key(Direction::Forward, 3), ta)]),
            pairwise_accuracy: BTreeMap::new(),
            intervals: BTreeMap::new(),
            interval_resampling: None,
        }
    }

    fn published(model: &str, category: Category, ta: f64) -> ReportedModel {
        ReportedModel {
            model: model.to_owned(),
            category,
            family: None,
            size: None,
            source: "A paper, Table 2".to_owned(),
            task_accuracy: BTreeMap::from([(key(Direction::Forward, 3), ta)]),
            pairwise_accuracy: BTreeMap::new(),
        }
    }

    #[test]
    fn percent_is_two_decimals_of_the_fraction() {
        assert_eq!(percent(0.846_153_8), 84.62);
        assert_eq!(percent(1.0), 100.0);
        assert_eq!(percent(0.0), 0.0);
    }

    #[test]
    fn rows_are_grouped_by_category_with_humans_last_and_marked_within_each() {
        let reported = vec![
            published("Human Performance", Category::Human, 93.0),
            published("Open A", Category::OpenWeight, 40.0),
            published("Open C", Category::OpenWeight, 30.0),
            published("Closed A", Category::Proprietary, 70.0),
            published("Closed B", Category::Proprietary, 60.0),
            published("Open B", Category::OpenWeight, 50.0),
        ];
        let own = vec![hub("Ours", 7, 45.0), hub("Ours 2", 8, 20.0)];
        let out = assemble(Metric::TaskAccuracy, &reported, &own, None, false).unwrap();
        let models: Vec<&str> = out.table.rows.iter().map(|r| r.model.as_str()).collect();
        assert_eq!(
            models,
            [
                "Closed A",
                "Closed B",
                "Open A",
                "Open C",
                "Open B",
                "Ours",
                "Ours 2",
                "Human Performance"
            ]
        );
        let marks: Vec<Option<super::super::Mark>> = out
            .table
            .rows
            .iter()
            .map(|r| r.cells[&key(Direction::Forward, 3)].mark)
            .collect();
        use super::super::Mark::{First, Second};
        assert_eq!(
            marks,
            [
                Some(First),
                None,
                Some(Second),
                None,
                Some(First),
                Some(First),
                None,
                None
            ]
        );
        // Every printed cell says where it came from.
        assert_eq!(out.provenance.len(), 8);
        let ours = out.provenance.iter().find(|p| p.model == "Ours").unwrap();
        assert_eq!(ours.value, 45.0);
        assert!(matches!(
            ours.from,
            Origin::Submission { submission: 7, .. }
        ));
        let closed = out
            .provenance
            .iter()
            .find(|p| p.model == "Closed B")
            .unwrap();
        assert_eq!(
            closed.from,
            Origin::Reported {
                source: "A paper, Table 2".to_owned()
            }
        );
    }

    #[test]
    fn named_models_keep_their_order_and_an_unknown_name_is_refused() {
        let reported = vec![
            published("B", Category::Proprietary, 70.0),
            published("A", Category::Proprietary, 60.0),
        ];
        let own = vec![hub("A", 1, 61.0)];
        let names = ["A".to_owned(), "B".to_owned()];
        let out = assemble(Metric::TaskAccuracy, &reported, &own, Some(&names), false).unwrap();
        let rows: Vec<(&str, String)> = out
            .table
            .rows
            .iter()
            .map(|r| (r.model.as_str(), r.source.clone()))
            .collect();
        assert_eq!(
            rows,
            [
                ("A", "A paper, Table 2".to_owned()),
                ("B", "A paper, Table 2".to_owned()),
                ("A", "enact-hub submission 1".to_owned()),
            ]
        );
        let missing = ["C".to_owned()];
        let err =
            assemble(Metric::TaskAccuracy, &reported, &own, Some(&missing), false).unwrap_err();
        assert_eq!(err.name, "C");
        assert!(err.to_string().contains("no row is named 'C'"), "{err}");
    }

    #[test]
    fn intervals_come_from_the_items_of_each_column_and_print_only_when_asked() {
        let f3 = key(Direction::Forward, 3);
        let items: Vec<ItemResult> = (0..40)
            .map(|i| ItemResult {
                column: f3,
                activity: i / 10,
                task_correct: i % 4 == 0,
                pairwise_accuracy: Some(if i % 3 == 0 { 1.0 } else { 0.5 }),
            })
            .collect();
        let by_items = hub("Ours", 1, 25.0).with_intervals(&items, Resampling::Items);
        assert_eq!(by_items.interval_resampling, Some(Resampling::Items));
        let row = hub("Ours", 1, 25.0).with_intervals(&items, Resampling::Activities);
        assert_ne!(row.intervals, by_items.intervals);
        let (low, high) = row.intervals[&(Metric::TaskAccuracy, f3)];
        assert!(low < 25.0 && 25.0 < high, "{low}..{high}");
        let (low, high) = row.intervals[&(Metric::PairwiseAccuracy, f3)];
        assert!(low < 67.5 && 67.5 < high, "{low}..{high}");
        let plain = assemble(
            Metric::TaskAccuracy,
            &[],
            std::slice::from_ref(&row),
            None,
            false,
        )
        .unwrap();
        assert_eq!(plain.table.rows[0].cells[&f3].interval, None);
        assert_eq!(plain.table.intervals, None);
        let shown = assemble(Metric::TaskAccuracy, &[], &[row], None, true).unwrap();
        assert!(shown.table.rows[0].cells[&f3].interval.is_some());
        assert_eq!(shown.table.intervals, Some(Resampling::Activities));
    }

    #[test]
    fn reproduction_pairs_a_published_model_with_the_hubs_run_of_it() {
        let f3 = key(Direction::Forward, 3);
        let reported = vec![
            published("GPT-5", Category::Proprietary, 84.62),
            published("Other", Category::Proprietary, 10.0),
        ];
        let mut ours = hub("gpt-5", 4, 80.0);
        ours.intervals
            .insert((Metric::TaskAccuracy, f3), (76.5, 85.25));
        let cells = reproduction(&reported, &[ours, hub("Mine", 5, 1.0)]);
        assert_eq!(cells.len(), 1);
        let cell = &cells[0];
        assert_eq!(cell.model, "GPT-5");
        assert_eq!(cell.difference, -4.62);
        assert_eq!(cell.inside, Some(true));
        assert_eq!(cell.submission, Some(4));
        let mut far = hub("GPT-5", 6, 50.0);
        far.intervals
            .insert((Metric::TaskAccuracy, f3), (45.0, 55.0));
        assert_eq!(reproduction(&reported, &[far])[0].inside, Some(false));
    }
}
