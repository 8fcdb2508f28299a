//! A [`PaperTable`] as the files `paper` writes: LaTeX in the paper's layout, CSV, Markdown and
//! JSON.
//!
//! LaTeX, CSV and Markdown group the rows by category in the order the categories first appear,
//! the Human row(s) last; JSON keeps the table's own order so that
//! [`PaperTable::from_json`] reads it back equal. Values have two decimals; a cell with an
//! interval (the hub's own rows under `--intervals`) prints it with the value.
//!
//! Marks: LaTeX uses the paper's own `\colorbox{firstgrey}` / `\colorbox{secondgrey}` (dark and
//! light grey, the paper's colours); Markdown, which has neither colour nor underline, bold for
//! first and italics for second; CSV and JSON name them (`first`, `second`).

use super::{Category, Cell, CellKey, Mark, PaperRow, PaperTable};
use crate::bundle::{csv_field, tex_escape};
use crate::verifier::Resampling;

/// The rows grouped by category, groups in order of first appearance, humans last.
pub fn grouped(table: &PaperTable) -> Vec<(&Category, Vec<&PaperRow>)> {
    let mut groups: Vec<(&Category, Vec<&PaperRow>)> = Vec::new();
    for row in &table.rows {
        match groups.iter_mut().find(|(c, _)| **c == row.category) {
            Some((_, rows)) => rows.push(row),
            None => groups.push((&row.category, vec![row])),
        }
    }
    // A stable sort keeps the other groups in their order.
    groups.sort_by_key(|(c, _)| **c == Category::Human);
    groups
}

/// The sentence that says how the table's intervals were drawn; empty without intervals.
fn intervals_note(table: &PaperTable) -> String {
    if !has_intervals(table) {
        return String::new();
    }
    match table.intervals {
        Some(Resampling::Items) => {
            " Intervals: 95 % percentile bootstrap, resampling items one by one.".to_owned()
        }
        Some(Resampling::Activities) | None => {
            " Intervals: 95 % percentile bootstrap, resampling activities (ENACT's task_name) \
             with all their items."
                .to_owned()
        }
    }
}

fn number(value: f64) -> String {
    format!("{value:.2}")
}

fn interval_text((low, high): (f64, f64)) -> String {
    format!("[{}, {}]", number(low), number(high))
}

/// The cell of `row` in column `key`, or an empty one.
fn cell(row: &PaperRow, key: CellKey) -> Cell {
    row.cells.get(&key).copied().unwrap_or(Cell {
        value: None,
        mark: None,
        interval: None,
    })
}

fn tex_cell(cell: Cell, human: bool) -> String {
    let Some(value) = cell.value else {
        return "--".to_owned();
    };
    let printed = number(value);
    let shown = match (human, cell.mark) {
        (true, _) => format!("\\textbf{{{printed}}}"),
        (false, Some(Mark::First)) => format!("\\colorbox{{firstgrey}}{{{printed}}}"),
        (false, Some(Mark::Second)) => format!("\\colorbox{{secondgrey}}{{{printed}}}"),
        (false, None) => printed,
    };
    match cell.interval {
        Some(interval) => format!(
            "\\shortstack{{{shown}\\\\\\scriptsize {}}}",
            interval_text(interval)
        ),
        None => shown,
    }
}

fn tex_heading(category: &Category) -> String {
    format!(
        "\\multicolumn{{18}}{{l}}{{\\textit{{\\footnotesize {}}}}}\\\\\n",
        tex_escape(&category.heading())
    )
}

/// The table in the paper's booktabs layout: a column for the model, forward L=3..10, then
/// inverse L=3..10; a heading per category; the Human row last and in bold; marks as the
/// paper's grey boxes. `standalone`: a whole document that compiles with `pdflatex`;
/// otherwise a `table*` to paste into a paper loading booktabs, multirow, graphicx and xcolor.
pub fn to_tex(table: &PaperTable, standalone: bool) -> String {
    let metric = table.metric;
    let mut out = String::new();
    if standalone {
        out.push_str(
            // multirow is in Debian's large texlive-latex-extra: without it the heading's
            // "Model" simply is not centred over its three rows, and the document still
            // compiles with texlive-latex-recommended alone.
            "\\documentclass{article}\n\\usepackage[T1]{fontenc}\n\\usepackage{booktabs}\n\
             \\IfFileExists{multirow.sty}{\\usepackage{multirow}}\
             {\\providecommand{\\multirow}[3]{##3}}\n\\usepackage{graphicx}\n\\usepackage{xcolor}\n\
             \\usepackage[landscape,margin=1cm]{geometry}\n\\begin{document}\n",
        );
    }
    out.push_str("\\providecolor{firstgrey}{gray}{0.66}\n\\providecolor{secondgrey}{gray}{0.88}\n");
    out.push_str("\\begin{table*}[!htbp]\n\\centering\n\\setlength{\\tabcolsep}{2pt}\n");
    out.push_str("\\resizebox{\\textwidth}{!}{\n");
    out.push_str("\\begin{tabular}{@{}p{3mm} l cccccccc cccccccc@{}}\n\\toprule\n");
    out.push_str(
        "& \\multirow{3}{*}{\\textbf{Model}} & \\multicolumn{8}{c}{\\textbf{Forward World \
         Modeling}} & \\multicolumn{8}{c}{\\textbf{Inverse World Modeling}} \\\\\n",
    );
    out.push_str(
        "\\addlinespace[0.5ex]\n\\cmidrule(l){3-10}\\cmidrule(r){11-18}\n\\addlinespace[0.5ex]\n",
    );
    out.push_str("& ");
    for key in CellKey::all() {
        out.push_str(&format!("& \\bf {} ", key.step_length));
    }
    out.push_str("\\\\\n");
    for (category, rows) in grouped(table) {
        let human = *category == Category::Human;
        out.push_str("\\midrule\n");
        if !human {
            out.push_str(&tex_heading(category));
        }
        for row in rows {
            let name = tex_escape(&row.model);
            if human {
                out.push_str(&format!("& \\textbf{{{name}}}"));
            } else {
                out.push_str(&format!("& {name}"));
            }
            for key in CellKey::all() {
                out.push_str(" & ");
                out.push_str(&tex_cell(cell(row, key), human));
            }
            out.push_str(" \\\\\n");
        }
    }
    out.push_str("\\bottomrule\n\\end{tabular}\n}\n");
    out.push_str(&format!(
        "\\caption{{\\textbf{{Evaluation on ENACT ({}).}} \\colorbox{{firstgrey}}{{Dark grey}}: \
         the best result within each category; \\colorbox{{secondgrey}}{{light grey}}: the \
         second best.{}}}\n\\label{{tab:enact_{}}}\n\\end{{table*}}\n",
        metric.title(),
        tex_escape(&intervals_note(table)),
        metric.as_str()
    ));
    if standalone {
        out.push_str("\\end{document}\n");
    }
    out
}

fn mark_name(mark: Option<Mark>) -> &'static str {
    match mark {
        Some(Mark::First) => "first",
        Some(Mark::Second) => "second",
        None => "",
    }
}

/// The table as CSV: `model, category, family, size, source`, then for each column
/// `forward_3` (the value), `forward_3_mark` and, when any cell has an interval,
/// `forward_3_low` and `forward_3_high`. Empty fields where there is nothing.
pub fn to_csv(table: &PaperTable) -> String {
    let intervals = has_intervals(table);
    let mut header: Vec<String> = ["model", "category", "family", "size", "source"]
        .map(str::to_owned)
        .to_vec();
    if intervals {
        header.push("interval_resampling".to_owned());
    }
    for key in CellKey::all() {
        header.push(key.to_string());
        header.push(format!("{key}_mark"));
        if intervals {
            header.push(format!("{key}_low"));
            header.push(format!("{key}_high"));
        }
    }
    let mut out = header.join(",");
    out.push('\n');
    for (_, rows) in grouped(table) {
        for row in rows {
            let mut fields = vec![
                row.model.clone(),
                row.category.to_string(),
                row.family.clone().unwrap_or_default(),
                row.size.clone().unwrap_or_default(),
                row.source.clone(),
            ];
            if intervals {
                let printed = row.cells.values().any(|c| c.interval.is_some());
                fields.push(match (printed, table.intervals) {
                    (false, _) => String::new(),
                    (true, r) => r.unwrap_or_default().as_str().to_owned(),
                });
            }
            for key in CellKey::all() {
                let c = cell(row, key);
                fields.push(c.value.map(number).unwrap_or_default());
                fields.push(mark_name(c.mark).to_owned());
                if intervals {
                    fields.push(c.interval.map(|i| number(i.0)).unwrap_or_default());
                    fields.push(c.interval.map(|i| number(i.1)).unwrap_or_default());
                }
            }
            let fields: Vec<String> = fields.iter().map(|f| csv_field(f)).collect();
            out.push_str(&fields.join(","));
            out.push('\n');
        }
    }
    out
}

fn has_intervals(table: &PaperTable) -> bool {
    table
        .rows
        .iter()
        .any(|r| r.cells.values().any(|c| c.interval.is_some()))
}

/// Text in a Markdown table cell: what Markdown or HTML would read as markup, escaped.
fn markdown_escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if matches!(
            c,
            '\\' | '|' | '*' | '_' | '`' | '[' | ']' | '<' | '>' | '#'
        ) {
            out.push('\\');
        }
        out.push(if c.is_control() { ' ' } else { c });
    }
    out
}

fn markdown_cell(cell: Cell) -> String {
    let Some(value) = cell.value else {
        return "–".to_owned();
    };
    let printed = number(value);
    let shown = match cell.mark {
        Some(Mark::First) => format!("**{printed}**"),
        Some(Mark::Second) => format!("_{printed}_"),
        None => printed,
    };
    match cell.interval {
        Some(interval) => format!("{shown} {}", markdown_escape(&interval_text(interval))),
        None => shown,
    }
}

/// The table as Markdown: a caption line, then one table with a row per model under its
/// category's heading row, the Human row last; bold is best within the category, italics
/// second best.
pub fn to_markdown(table: &PaperTable) -> String {
    let mut out = format!(
        "{} (%) by direction and step length L. **Bold**: best within its category; \
         _italics_: second best.{}\n\n",
        table.metric.title(),
        markdown_escape(&intervals_note(table))
    );
    out.push_str("| Model |");
    for key in CellKey::all() {
        let d = match key.direction {
            crate::dataset::Direction::Forward => "Forward",
            crate::dataset::Direction::Inverse => "Inverse",
        };
        out.push_str(&format!(" {d} {} |", key.step_length));
    }
    out.push_str("\n|:--|");
    out.push_str(&"--:|".repeat(16));
    out.push('\n');
    for (category, rows) in grouped(table) {
        if *category != Category::Human {
            out.push_str(&format!(
                "| *{}* |{}\n",
                markdown_escape(&category.heading()),
                " |".repeat(16)
            ));
        }
        for row in rows {
            out.push_str(&format!("| {} |", markdown_escape(&row.model)));
            for key in CellKey::all() {
                out.push_str(&format!(" {} |", markdown_cell(cell(row, key))));
            }
            out.push('\n');
        }
    }
    out
}

/// The table as JSON, in its own row order: `{"metric", "rows": [{"model", "category",
/// "source", "cells": {"forward_3": {"value", "mark"}, …}}]}` (with `family`, `size` and a
/// cell's `interval` when there are any).
pub fn to_json(table: &PaperTable) -> String {
    // Strings, numbers and maps keyed by strings only: serialising cannot fail.
    let mut out = serde_json::to_string_pretty(table).expect("a paper table is plain JSON");
    out.push('\n');
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper::{Metric, mark::mark};
    use std::collections::BTreeMap;

    /// Two columns filled (forward_3, inverse_10), the rest empty.
    fn row(model: &str, category: Category, f3: f64, i10: Option<f64>) -> PaperRow {
        let mut cells = BTreeMap::new();
        cells.insert(CellKey::parse("forward_3").unwrap(), Cell::value(f3));
        if let Some(v) = i10 {
            cells.insert(CellKey::parse("inverse_10").unwrap(), Cell::value(v));
        }
        PaperRow {
            model: model.to_owned(),
            category,
            source: "Paper, Table 1".to_owned(),
            family: None,
            size: None,
            cells,
        }
    }

    fn small() -> PaperTable {
        let mut table = PaperTable {
            metric: Metric::TaskAccuracy,
            rows: vec![
                row("Human", Category::Human, 90.384, Some(85.0)),
                row("A_1", Category::Proprietary, 80.5, Some(5.0)),
                row("B", Category::Proprietary, 70.0, Some(3.6)),
                row("C", Category::Proprietary, 60.0, None),
            ],
            intervals: None,
        };
        table.rows[1].family = Some("Fam".to_owned());
        mark(&mut table);
        table
    }

    #[test]
    fn groups_keep_their_order_and_the_humans_go_last() {
        let table = small();
        let order: Vec<&str> = grouped(&table)
            .iter()
            .flat_map(|(_, rows)| rows.iter().map(|r| r.model.as_str()))
            .collect();
        assert_eq!(order, ["A_1", "B", "C", "Human"]);
    }

    const EMPTY14: &str = " & -- & -- & -- & -- & -- & -- & -- & -- & -- & -- & -- & -- & -- & --";

    #[test]
    fn latex_is_the_papers_layout() {
        let tex = to_tex(&small(), false);
        let expected = format!(
            "\\providecolor{{firstgrey}}{{gray}}{{0.66}}\n\
             \\providecolor{{secondgrey}}{{gray}}{{0.88}}\n\
             \\begin{{table*}}[!htbp]\n\\centering\n\\setlength{{\\tabcolsep}}{{2pt}}\n\
             \\resizebox{{\\textwidth}}{{!}}{{\n\
             \\begin{{tabular}}{{@{{}}p{{3mm}} l cccccccc cccccccc@{{}}}}\n\\toprule\n\
             & \\multirow{{3}}{{*}}{{\\textbf{{Model}}}} & \\multicolumn{{8}}{{c}}{{\\textbf{{Forward World Modeling}}}} & \\multicolumn{{8}}{{c}}{{\\textbf{{Inverse World Modeling}}}} \\\\\n\
             \\addlinespace[0.5ex]\n\\cmidrule(l){{3-10}}\\cmidrule(r){{11-18}}\n\\addlinespace[0.5ex]\n\
             & & \\bf 3 & \\bf 4 & \\bf 5 & \\bf 6 & \\bf 7 & \\bf 8 & \\bf 9 & \\bf 10 & \\bf 3 & \\bf 4 & \\bf 5 & \\bf 6 & \\bf 7 & \\bf 8 & \\bf 9 & \\bf 10 \\\\\n\
             \\midrule\n\
             \\multicolumn{{18}}{{l}}{{\\textit{{\\footnotesize Proprietary Models}}}}\\\\\n\
             & A\\_1 & \\colorbox{{firstgrey}}{{80.50}}{EMPTY14} & \\colorbox{{firstgrey}}{{5.00}} \\\\\n\
             & B & \\colorbox{{secondgrey}}{{70.00}}{EMPTY14} & 3.60 \\\\\n\
             & C & 60.00{EMPTY14} & -- \\\\\n\
             \\midrule\n\
             & \\textbf{{Human}} & \\textbf{{90.38}}{EMPTY14} & \\textbf{{85.00}} \\\\\n\
             \\bottomrule\n\\end{{tabular}}\n}}\n\
             \\caption{{\\textbf{{Evaluation on ENACT (Task Accuracy).}} \\colorbox{{firstgrey}}{{Dark grey}}: the best result within each category; \\colorbox{{secondgrey}}{{light grey}}: the second best.}}\n\
             \\label{{tab:enact_task_accuracy}}\n\\end{{table*}}\n"
        );
        assert_eq!(tex, expected);
        let doc = to_tex(&small(), true);
        assert!(doc.starts_with("\\documentclass{article}\n"));
        assert!(doc.ends_with(&format!("{expected}\\end{{document}}\n")));
        assert!(doc.contains("\\usepackage{booktabs}\n"));
    }

    #[test]
    fn latex_prints_an_interval_under_its_value() {
        let mut table = small();
        let key = CellKey::parse("forward_3").unwrap();
        table.rows[2].cells.get_mut(&key).unwrap().interval = Some((65.0, 74.25));
        let tex = to_tex(&table, false);
        assert!(
            tex.contains(
                "& B & \\shortstack{\\colorbox{secondgrey}{70.00}\\\\\\scriptsize [65.00, 74.25]} & --"
            ),
            "{tex}"
        );
    }

    #[test]
    fn csv_names_values_and_marks() {
        let csv = to_csv(&small());
        let mut lines = csv.lines();
        let header = lines.next().unwrap();
        assert!(header.starts_with(
            "model,category,family,size,source,forward_3,forward_3_mark,forward_4,forward_4_mark,"
        ));
        assert!(header.ends_with(",inverse_10,inverse_10_mark"));
        let empty14 = ",,".repeat(14);
        assert_eq!(
            lines.collect::<Vec<_>>(),
            [
                format!("A_1,proprietary,Fam,,\"Paper, Table 1\",80.50,first,{empty14}5.00,first"),
                format!("B,proprietary,,,\"Paper, Table 1\",70.00,second,{empty14}3.60,"),
                format!("C,proprietary,,,\"Paper, Table 1\",60.00,,{empty14},"),
                format!("Human,human,,,\"Paper, Table 1\",90.38,,{empty14}85.00,"),
            ]
        );
    }

    #[test]
    fn csv_adds_interval_columns_when_a_cell_has_one() {
        let mut table = small();
        let key = CellKey::parse("inverse_10").unwrap();
        table.rows[2].cells.get_mut(&key).unwrap().interval = Some((1.0, 6.5));
        let csv = to_csv(&table);
        assert!(
            csv.lines()
                .next()
                .unwrap()
                .ends_with(",inverse_10,inverse_10_mark,inverse_10_low,inverse_10_high")
        );
        assert!(csv.lines().nth(2).unwrap().ends_with(",3.60,,1.00,6.50"));
        assert!(csv.lines().nth(1).unwrap().ends_with(",5.00,first,,"));
    }

    #[test]
    fn markdown_bolds_the_best_and_italicises_the_second() {
        let md = to_markdown(&small());
        let empty14 = " – |".repeat(14);
        let blank16 = " |".repeat(16);
        let expected = format!(
            "Task Accuracy (%) by direction and step length L. **Bold**: best within its \
             category; _italics_: second best.\n\n\
             | Model | Forward 3 | Forward 4 | Forward 5 | Forward 6 | Forward 7 | Forward 8 | Forward 9 | Forward 10 | Inverse 3 | Inverse 4 | Inverse 5 | Inverse 6 | Inverse 7 | Inverse 8 | Inverse 9 | Inverse 10 |\n\
             |:--|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n\
             | *Proprietary Models* |{blank16}\n\
             | A\\_1 | **80.50** |{empty14} **5.00** |\n\
             | B | _70.00_ |{empty14} 3.60 |\n\
             | C | 60.00 |{empty14} – |\n\
             | Human | 90.38 |{empty14} 85.00 |\n"
        );
        assert_eq!(md, expected);
    }

    #[test]
    fn json_is_the_issues_shape_and_reads_back_equal() {
        let table = small();
        let json = to_json(&table);
        let value: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert_eq!(value["metric"], "task_accuracy");
        let a = &value["rows"][1];
        assert_eq!(
            a,
            &serde_json::json!({
                "model": "A_1", "category": "proprietary", "source": "Paper, Table 1",
                "family": "Fam",
                "cells": {
                    "forward_3": {"value": 80.5, "mark": "first"},
                    "inverse_10": {"value": 5.0, "mark": "first"},
                }
            })
        );
        assert_eq!(
            value["rows"][2]["cells"]["inverse_10"]["mark"],
            serde_json::Value::Null
        );
        assert_eq!(PaperTable::from_json(&json), Ok(table));
    }

    /// What `pdflatex` would refuse first, checked without TeX (none is installed here):
    /// braces balance (escaped ones aside), every `\begin{x}` meets its `\end{x}` in order,
    /// and every row of the tabular has 18 columns.
    fn check_structure(doc: &str) {
        let mut depth = 0i32;
        let mut chars = doc.chars();
        while let Some(c) = chars.next() {
            match c {
                // `\{`, `\}` and `\\` are not braces.
                '\\' => {
                    chars.next();
                }
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    assert!(depth >= 0, "a }} closes nothing");
                }
                _ => {}
            }
        }
        assert_eq!(depth, 0, "unbalanced braces");
        let mut environments: Vec<(usize, bool)> = doc
            .match_indices("\\begin{")
            .map(|(i, _)| (i, true))
            .chain(doc.match_indices("\\end{").map(|(i, _)| (i, false)))
            .collect();
        environments.sort_unstable();
        let mut open: Vec<&str> = Vec::new();
        for (i, begins) in environments {
            let rest = &doc[i..];
            let name_start = rest.find('{').unwrap() + 1;
            let name = &rest[name_start..name_start + rest[name_start..].find('}').unwrap()];
            if begins {
                open.push(name);
            } else {
                assert_eq!(
                    open.pop(),
                    Some(name),
                    "\\end{{{name}}} closes the wrong environment"
                );
            }
        }
        assert!(open.is_empty(), "unclosed: {open:?}");
        let tabular = doc
            .split("\\begin{tabular}")
            .nth(1)
            .and_then(|t| t.split("\\end{tabular}").next())
            .expect("a tabular");
        let rows: Vec<&str> = tabular.lines().filter(|l| l.starts_with("& ")).collect();
        assert!(!rows.is_empty());
        for row in rows {
            assert_eq!(columns(row), 18, "{row}");
            assert!(row.ends_with("\\\\"), "{row}");
        }
    }

    /// The columns a tabular row spans: its `&`-separated fields (escaped `\&` and those
    /// inside braces aside), a `\multicolumn{n}` counting n.
    fn columns(row: &str) -> usize {
        let mut fields = vec![String::new()];
        let mut depth = 0;
        let mut chars = row.chars();
        while let Some(c) = chars.next() {
            match c {
                '\\' => {
                    fields.last_mut().unwrap().push(c);
                    if let Some(next) = chars.next() {
                        fields.last_mut().unwrap().push(next);
                    }
                    continue;
                }
                '{' => depth += 1,
                '}' => depth -= 1,
                '&' if depth == 0 => {
                    fields.push(String::new());
                    continue;
                }
                _ => {}
            }
            fields.last_mut().unwrap().push(c);
        }
        fields
            .iter()
            .map(|f| {
                f.trim()
                    .strip_prefix("\\multicolumn{")
                    .and_then(|rest| rest.split('}').next())
                    .map_or(1, |n| n.parse().unwrap())
            })
            .sum()
    }

    #[test]
    fn the_standalone_document_of_the_papers_tables_is_well_formed() {
        for metric in Metric::ALL {
            let mut table = crate::paper::table_of(metric, &crate::paper::enact_paper_results());
            mark(&mut table);
            let doc = to_tex(&table, true);
            check_structure(&doc);
            assert!(doc.contains("\\begin{document}") && doc.ends_with("\\end{document}\n"));
        }
        let mut odd = small();
        odd.rows[1].model = "A {weird} & 100% #1 \\ name".to_owned();
        odd.rows[2]
            .cells
            .values_mut()
            .for_each(|c| c.interval = Some((1.0, 2.0)));
        check_structure(&to_tex(&odd, true));
    }

    #[test]
    #[should_panic(expected = "unbalanced braces")]
    fn the_structure_check_finds_a_missing_brace() {
        check_structure("\\begin{tabular}{ll}\n& a \\\\\n\\end{tabular}{");
    }

    #[test]
    #[should_panic(expected = "closes the wrong environment")]
    fn the_structure_check_finds_crossed_environments() {
        check_structure("\\begin{table}\\begin{tabular}{l}\n\\end{table}\\end{tabular}");
    }
}
