//! Best and second-best within each category, exactly as ENACT's paper marks its three result
//! tables (`tab:main_pair_acc`, `tab:app_task_acc`, `tab:app_pair_acc`).
//!
//! The rule, per column and per category (the Human row is never marked; every other category,
//! the hub's own included, is marked on its own):
//! 1. Values are compared as printed, to the hundredth of a percent.
//! 2. A row's rank is one plus the number of rows of its category with a larger value
//!    (competition ranking: equal values share a rank, and the ranks they cover are used up).
//! 3. Rank 1 is marked first, rank 2 second. So three rows tied for best are all first and
//!    nothing is second (the paper's task accuracy, proprietary, forward L=4: 62.72 three
//!    times), and two tied for second are both second.
//! 4. A mark that would go to every row of the category singles nothing out and is not given:
//!    a column where the whole category ties (open-weight task accuracy at forward L=10, all
//!    0.00) is unmarked, and so is second place when everyone not first shares it.
//! 5. A row without a value in the column takes no part.
//!
//! Rules 1 to 3 and the first half of 4 are what the paper's numbers require (the transcription
//! test recomputes all three tables' marks from their numbers); the second half of 4 is the
//! same principle applied to second place, which the paper's tables never put to the test.

use std::collections::BTreeSet;

use super::{Category, CellKey, Mark, PaperTable};

/// A percentage as printed with two decimals, in hundredths, so that 62.72 equals 62.72
/// whatever arithmetic produced either.
fn as_printed(value: f64) -> i64 {
    // Percentages lie in 0..100, so hundredths fit an i64 exactly.
    (value * 100.0).round() as i64
}

/// The marks of `values` (one category's cells of one column, `None` where a row has none),
/// in the same order.
pub fn marks_of(values: &[Option<f64>]) -> Vec<Option<Mark>> {
    let printed: Vec<Option<i64>> = values.iter().map(|v| v.map(as_printed)).collect();
    let present: Vec<i64> = printed.iter().flatten().copied().collect();
    let rank = |v: i64| 1 + present.iter().filter(|w| **w > v).count();
    let ranks: Vec<Option<usize>> = printed.iter().map(|v| v.map(rank)).collect();
    let count_up_to = |r: usize| ranks.iter().flatten().filter(|k| **k <= r).count();
    let first_singles_out = count_up_to(1) < present.len();
    let second_singles_out = count_up_to(2) < present.len();
    ranks
        .iter()
        .map(|rank| match rank {
            Some(1) if first_singles_out => Some(Mark::First),
            Some(2) if second_singles_out => Some(Mark::Second),
            _ => None,
        })
        .collect()
}

/// Marks every cell of `table` by the rule above, replacing any marks it had.
pub fn mark(table: &mut PaperTable) {
    let categories: BTreeSet<Category> = table.rows.iter().map(|r| r.category.clone()).collect();
    for row in &mut table.rows {
        for cell in row.cells.values_mut() {
            cell.mark = None;
        }
    }
    for category in categories.iter().filter(|c| **c != Category::Human) {
        let members: Vec<usize> = (0..table.rows.len())
            .filter(|i| table.rows[*i].category == *category)
            .collect();
        for key in CellKey::all() {
            let values: Vec<Option<f64>> =
                members.iter().map(|i| table.rows[*i].value(key)).collect();
            for (i, mark) in members.iter().zip(marks_of(&values)) {
                if let Some(cell) = table.rows[*i].cells.get_mut(&key) {
                    cell.mark = mark;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper::{Cell, Metric, PaperRow};
    use Mark::{First, Second};

    fn marks(values: &[f64]) -> Vec<Option<Mark>> {
        marks_of(&values.iter().map(|v| Some(*v)).collect::<Vec<_>>())
    }

    #[test]
    fn the_best_is_first_and_the_next_second() {
        assert_eq!(
            marks(&[84.62, 87.50, 67.83, 86.10]),
            [None, Some(First), None, Some(Second)]
        );
    }

    #[test]
    fn a_tie_for_best_uses_up_second_place() {
        // The paper's task accuracy, proprietary models, forward L=4.
        assert_eq!(
            marks(&[62.72, 62.72, 30.66, 62.72, 50.52]),
            [Some(First), Some(First), None, Some(First), None]
        );
        // Two tied for best: the third is not second either.
        assert_eq!(
            marks(&[10.0, 10.0, 9.0, 8.0]),
            [Some(First), Some(First), None, None]
        );
    }

    #[test]
    fn a_tie_for_second_marks_both() {
        assert_eq!(
            marks(&[5.0, 3.6, 3.6, 0.2]),
            [Some(First), Some(Second), Some(Second), None]
        );
    }

    #[test]
    fn values_are_compared_as_printed() {
        assert_eq!(
            marks(&[0.1 + 0.2, 0.3, 0.0]),
            [Some(First), Some(First), None]
        );
        assert_eq!(
            marks(&[33.333, 33.334, 1.0]),
            [Some(First), Some(First), None]
        );
    }

    #[test]
    fn a_mark_that_would_go_to_everyone_is_not_given() {
        // Open-weight task accuracy, forward L=10: all 0.00.
        assert_eq!(marks(&[0.0, 0.0, 0.0]), [None, None, None]);
        // A category of one row.
        assert_eq!(marks(&[42.0]), [None]);
        // Everyone not first shares second place.
        assert_eq!(marks(&[2.0, 0.0, 0.0]), [Some(First), None, None]);
        assert_eq!(marks(&[2.0, 1.0]), [Some(First), None]);
    }

    #[test]
    fn rows_without_a_value_take_no_part() {
        assert_eq!(
            marks_of(&[None, Some(3.0), Some(2.0), Some(1.0)]),
            [None, Some(First), Some(Second), None]
        );
        assert_eq!(marks_of(&[None, None]), [None, None]);
    }

    fn row(model: &str, category: Category, values: &[f64]) -> PaperRow {
        PaperRow {
            model: model.to_owned(),
            category,
            source: "test".to_owned(),
            family: None,
            size: None,
            cells: CellKey::all()
                .zip(values)
                .map(|(k, v)| (k, Cell::value(*v)))
                .collect(),
        }
    }

    #[test]
    fn each_category_is_marked_on_its_own_and_the_humans_never() {
        let hub = Category::Named("This hub".to_owned());
        let mut table = PaperTable {
            metric: Metric::TaskAccuracy,
            rows: vec![
                row("a", Category::Proprietary, &[50.0, 1.0]),
                row("x", hub.clone(), &[10.0, 9.0]),
                row("b", Category::Proprietary, &[40.0, 2.0]),
                row("c", Category::Proprietary, &[30.0, 3.0]),
                row("y", hub, &[20.0, 8.0]),
                row("Human", Category::Human, &[90.0, 90.0]),
            ],
            intervals: None,
        };
        // Stale marks are replaced.
        table.rows[5]
            .cells
            .values_mut()
            .for_each(|c| c.mark = Some(First));
        mark(&mut table);
        let got: Vec<Vec<Option<Mark>>> = table
            .rows
            .iter()
            .map(|r| r.cells.values().map(|c| c.mark).collect())
            .collect();
        assert_eq!(
            got,
            [
                vec![Some(First), None],
                vec![None, Some(First)],
                vec![Some(Second), Some(Second)],
                vec![None, Some(First)],
                vec![Some(First), None],
                vec![None, None],
            ]
        );
    }
}
