//! Error analyses as text: the CLI's table and the report bundle's CSV lines.

use std::fmt::Write as _;

use super::{ErrorAnalysis, ErrorFigures, Hand, HandFigures, SemanticCategory, StructuralClass};

fn percent(part: usize, whole: usize) -> String {
    if whole == 0 {
        "-".to_owned()
    } else {
        format!("{:.1}%", 100.0 * part as f64 / whole as f64)
    }
}

fn with_se(value: Option<f64>, se: Option<f64>) -> String {
    match (value, se) {
        (Some(v), Some(se)) => format!("{v:.3} ± {se:.3}"),
        _ => "-".to_owned(),
    }
}

fn hand(figures: &ErrorFigures, hand: Hand) -> &HandFigures {
    match hand {
        Hand::Left => &figures.handedness.left,
        Hand::Right => &figures.handedness.right,
    }
}

/// The readable table `enact-hub errors` prints: overall, forward and inverse side by side.
pub fn text_table(analysis: &ErrorAnalysis) -> String {
    let groups = [
        ("overall", &analysis.overall),
        ("forward", &analysis.by_direction.forward),
        ("inverse", &analysis.by_direction.inverse),
    ];
    let o = &analysis.overall;
    let mut out = String::new();
    let excluded = o.excluded_unequal_length
        + o.excluded_unreadable
        + o.excluded_missing
        + o.excluded_without_signatures;
    let _ = writeln!(
        out,
        "{} answers analysed ({} steps); {excluded} not analysed: {} of another length, {} \
         unreadable, {} missing, {} without signature sets",
        o.analysed_answers,
        o.analysed_steps,
        o.excluded_unequal_length,
        o.excluded_unreadable,
        o.excluded_missing,
        o.excluded_without_signatures
    );
    let _ = writeln!(
        out,
        "components: {} true, {} predicted, {} matched\n",
        o.components.truth, o.components.predicted, o.components.matched
    );
    let row = |out: &mut String, name: &str, cells: [String; 3]| {
        let _ = writeln!(
            out,
            "{name:<28}{:>18}{:>18}{:>18}",
            cells[0], cells[1], cells[2]
        );
    };
    row(
        &mut out,
        "structural errors",
        groups.map(|(n, _)| n.to_owned()),
    );
    for class in StructuralClass::ALL {
        row(
            &mut out,
            &format!("  {}", class.label().to_lowercase()),
            groups.map(|(_, g)| {
                let n = g.structural.get(class);
                format!("{n} ({})", percent(n, g.errors))
            }),
        );
    }
    row(&mut out, "  all", groups.map(|(_, g)| g.errors.to_string()));
    out.push('\n');
    row(
        &mut out,
        "semantic errors",
        groups.map(|(n, _)| n.to_owned()),
    );
    for category in SemanticCategory::ALL {
        row(
            &mut out,
            &format!("  {}", category.label().to_lowercase()),
            groups.map(|(_, g)| {
                let n = g.semantic.get(category).total;
                format!("{n} ({})", percent(n, g.errors))
            }),
        );
    }
    out.push('\n');
    for h in Hand::BOTH {
        type Pick = fn(&HandFigures) -> (Option<f64>, Option<f64>);
        let picks: [(&str, Pick); 3] = [
            ("precision", |f: &HandFigures| (f.precision, f.precision_se)),
            ("recall", |f: &HandFigures| (f.recall, f.recall_se)),
            ("mixing", |f: &HandFigures| (f.mixing, f.mixing_se)),
        ];
        for (name, value) in picks {
            row(
                &mut out,
                &format!("{} hand {name}", h.as_str()),
                groups.map(|(_, g)| {
                    let (v, se) = value(hand(g, h));
                    with_se(v, se)
                }),
            );
        }
    }
    out.push('\n');
    let a = &o.accepted_incomplete;
    let _ = writeln!(
        out,
        "accepted but incomplete: data level {} ({} of {} accepted answers), pair level {} ({} \
         of {} accepted steps)",
        percent(a.incomplete_answers, a.accepted_answers),
        a.incomplete_answers,
        a.accepted_answers,
        percent(a.incomplete_steps, a.accepted_steps),
        a.incomplete_steps,
        a.accepted_steps
    );
    out
}

fn number(value: Option<f64>) -> String {
    value.map(|v| format!("{v}")).unwrap_or_default()
}

/// One table line per row × group (overall, forward, inverse): counts per structural class
/// and semantic category, hand figures with standard errors, and the accepted-but-incomplete
/// rates. Returns the header and the lines, unquoted.
pub fn table(rows: &[(&str, &ErrorAnalysis)]) -> (Vec<String>, Vec<Vec<String>>) {
    let mut header = vec!["row".to_owned(), "group".to_owned()];
    header.extend(
        [
            "analysed_answers",
            "analysed_steps",
            "excluded_unequal_length",
            "excluded_unreadable",
            "excluded_missing",
            "excluded_without_signatures",
            "truth_components",
            "predicted_components",
            "matched_components",
            "errors",
        ]
        .map(str::to_owned),
    );
    header.extend(StructuralClass::ALL.map(|c| c.as_str().to_owned()));
    header.extend(SemanticCategory::ALL.map(|c| c.as_str().to_owned()));
    for h in Hand::BOTH {
        for f in [
            "precision",
            "precision_se",
            "recall",
            "recall_se",
            "mixing",
            "mixing_se",
        ] {
            header.push(format!("{}_{f}", h.as_str()));
        }
    }
    header.extend(["data_level_incomplete", "pair_level_incomplete"].map(str::to_owned));
    let mut lines = Vec::new();
    for (label, analysis) in rows {
        for (group, g) in [
            ("overall", &analysis.overall),
            ("forward", &analysis.by_direction.forward),
            ("inverse", &analysis.by_direction.inverse),
        ] {
            let mut cells = vec![(*label).to_owned(), group.to_owned()];
            cells.extend(
                [
                    g.analysed_answers,
                    g.analysed_steps,
                    g.excluded_unequal_length,
                    g.excluded_unreadable,
                    g.excluded_missing,
                    g.excluded_without_signatures,
                    g.components.truth,
                    g.components.predicted,
                    g.components.matched,
                    g.errors,
                ]
                .map(|n| n.to_string()),
            );
            cells.extend(StructuralClass::ALL.map(|c| g.structural.get(c).to_string()));
            cells.extend(SemanticCategory::ALL.map(|c| g.semantic.get(c).total.to_string()));
            for h in Hand::BOTH {
                let f = hand(g, h);
                for v in [
                    f.precision,
                    f.precision_se,
                    f.recall,
                    f.recall_se,
                    f.mixing,
                    f.mixing_se,
                ] {
                    cells.push(number(v));
                }
            }
            cells.push(number(g.accepted_incomplete.data_level));
            cells.push(number(g.accepted_incomplete.pair_level));
            lines.push(cells);
        }
    }
    (header, lines)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error_analysis::analyse;

    #[test]
    fn an_empty_analysis_prints_dashes_not_nan() {
        let a = analyse([]);
        let table = text_table(&a);
        assert!(table.contains("0 answers analysed"));
        assert!(!table.contains("NaN"));
        let (header, lines) = super::table(&[("m", &a)]);
        assert_eq!(lines.len(), 3);
        assert_eq!(lines[0][..3], ["m", "overall", "0"]);
        assert!(lines.iter().all(|l| l.len() == header.len()));
    }

    /// The table export writes each figure as Rust prints the number, and nothing for one
    /// that cannot be computed.
    #[test]
    fn the_table_writes_figures_in_their_columns() {
        let mut a = analyse([]);
        a.overall.handedness.left.precision = Some(0.5);
        a.overall.accepted_incomplete.data_level = Some(0.25);
        let (header, lines) = super::table(&[("m", &a)]);
        let cell = |name: &str| {
            let at = header.iter().position(|h| h == name).expect(name);
            lines[0][at].clone()
        };
        assert_eq!(cell("left_precision"), "0.5");
        assert_eq!(cell("data_level_incomplete"), "0.25");
        assert_eq!(cell("pair_level_incomplete"), "");
    }

    #[test]
    fn the_text_table_gives_the_hands_figures_with_their_standard_errors() {
        let mut a = analyse([]);
        a.overall.handedness.left.precision = Some(0.5);
        a.overall.handedness.left.precision_se = Some(0.125);
        a.overall.handedness.right.recall = Some(0.75);
        let table = text_table(&a);
        let line = |name: &str| {
            table
                .lines()
                .find(|l| l.starts_with(name))
                .unwrap_or_else(|| panic!("no {name} line in {table}"))
                .to_owned()
        };
        assert!(
            line("left hand precision").contains("0.500 ± 0.125"),
            "{table}"
        );
        // A figure without its standard error is not printed as if it had none.
        assert!(!line("right hand recall").contains("0.750"), "{table}");
        assert!(line("right hand recall").contains('-'), "{table}");
    }

    #[test]
    fn the_text_table_adds_up_what_was_not_analysed() {
        let mut a = analyse([]);
        a.overall.excluded_unequal_length = 3;
        a.overall.excluded_unreadable = 2;
        a.overall.excluded_missing = 1;
        a.overall.excluded_without_signatures = 4;
        let table = text_table(&a);
        assert!(
            table.contains(
                "10 not analysed: 3 of another length, 2 unreadable, 1 missing, 4 without \
                 signature sets"
            ),
            "{table}"
        );
    }

    #[test]
    fn the_text_table_gives_each_class_its_share_of_the_errors() {
        let mut a = analyse([]);
        a.overall.errors = 4;
        a.overall.structural.omission = 3;
        a.overall.structural.hallucination = 1;
        let table = text_table(&a);
        let line = |name: &str| {
            table
                .lines()
                .find(|l| l.trim_start().starts_with(name))
                .unwrap_or_else(|| panic!("no {name} line in {table}"))
                .to_owned()
        };
        assert!(line("omission").contains("3 (75.0%)"), "{table}");
        assert!(line("hallucination").contains("1 (25.0%)"), "{table}");
        // The directions had no errors: a dash, not a share of nothing.
        assert!(line("omission").contains("0 (-)"), "{table}");
    }

    #[test]
    fn the_table_names_its_columns_by_class_and_category() {
        let (header, _) = super::table(&[]);
        for name in [
            "polarity_inversion",
            "spatial_relations",
            "functional_states",
            "material_states",
            "agent_interaction",
            "left_precision_se",
            "pair_level_incomplete",
        ] {
            assert!(header.iter().any(|h| h == name), "{name}: {header:?}");
        }
    }
}
