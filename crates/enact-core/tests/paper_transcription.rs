//! The ENACT paper's results in `data/enact-paper-results.json` checked against the paper's
//! own LaTeX (`../shared/seed/*.txt` beside the workspace): every model of its three result
//! tables, every value, every best/second-best mark recomputed from the numbers, and every row
//! as `to_tex` writes it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use enact_core::paper::mark::mark;
use enact_core::paper::write::to_tex;
use enact_core::paper::{
    Category, CellKey, ENACT_PAPER_MAIN_TABLE_MODELS, Mark, Metric, PaperTable, ReportedModel,
    enact_paper_results, table_of,
};

/// The hub's one rule for tests that would otherwise skip (`tests/support/fixtures.rs`): under
/// a CI set to anything but empty, 0 or false, skipping is a failure.
fn must_not_skip() -> bool {
    std::env::var("CI").is_ok_and(|v| {
        let v = v.trim();
        !(v.is_empty() || v == "0" || v.eq_ignore_ascii_case("false"))
    })
}

/// The paper's LaTeX: the `.txt` of `../shared/seed/` that holds its appendix table.
fn paper_tex() -> Option<String> {
    let seed = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/seed");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&seed)
        .map(|dir| dir.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    files.sort();
    let found = files
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "txt"))
        .filter_map(|p| std::fs::read_to_string(p).ok())
        .find(|text| text.contains("\\label{tab:app_task_acc}"));
    if found.is_none() {
        assert!(
            !must_not_skip(),
            "the paper's LaTeX is missing from {} and CI is set: this test must not skip",
            seed.display()
        );
        eprintln!(
            "SKIPPING the paper transcription check: no paper LaTeX in {}",
            seed.display()
        );
    }
    found
}

/// One row of a LaTeX table: (model, category, 16 cells of (value as printed, mark)).
type TexRow = (String, Category, Vec<(String, Option<Mark>)>);

/// The rows of the tabular labelled `label`, with the category of the group they stand in.
fn tex_table(tex: &str, label: &str) -> Vec<TexRow> {
    let mut category = None;
    let mut rows = Vec::new();
    for line in tabular_lines(tex, label) {
        if let Some(heading) = line.split("\\footnotesize ").nth(1) {
            category = Some(match heading.split('}').next() {
                Some("Proprietary Models") => Category::Proprietary,
                Some("Open-Weight Models") => Category::OpenWeight,
                other => panic!("{label}: unknown group {other:?}"),
            });
            continue;
        }
        if !is_model_row(line) {
            continue;
        }
        let fields: Vec<&str> = line
            .trim_end_matches('\\')
            .split('&')
            .skip(1)
            .map(str::trim)
            .collect();
        assert_eq!(fields.len(), 17, "{label}: {line}");
        let (model, row_category) = match unwrap_command(fields[0], "\\textbf") {
            Some(name) => (name, Category::Human),
            None => (fields[0], category.clone().expect("a group before a row")),
        };
        let cells = fields[1..]
            .iter()
            .map(|field| {
                if let Some(v) = unwrap_command(field, "\\colorbox{firstgrey}") {
                    (v.to_owned(), Some(Mark::First))
                } else if let Some(v) = unwrap_command(field, "\\colorbox{secondgrey}") {
                    (v.to_owned(), Some(Mark::Second))
                } else if let Some(v) = unwrap_command(field, "\\textbf") {
                    (v.to_owned(), None)
                } else {
                    ((*field).to_owned(), None)
                }
            })
            .collect();
        rows.push((model.to_owned(), row_category, cells));
    }
    rows
}

/// The lines of the tabular labelled `label`, trimmed.
fn tabular_lines<'a>(tex: &'a str, label: &str) -> Vec<&'a str> {
    let end = tex
        .find(&format!("\\label{{{label}}}"))
        .unwrap_or_else(|| panic!("no table {label}"));
    let start = tex[..end].rfind("\\begin{tabular}").expect("a tabular");
    let body = &tex[start..start + tex[start..].find("\\end{tabular}").expect("its end")];
    body.lines().map(str::trim).collect()
}

/// A model's (or the humans') row, not the column headings.
fn is_model_row(line: &str) -> bool {
    line.starts_with("& ") && !line.starts_with("& &") && !line.contains("\\multirow")
}

/// A line without its white space, to compare LaTeX that differs only in spacing.
fn squash(line: &str) -> String {
    line.split_whitespace().collect()
}

/// Every model row of the paper's table `label` is a row that [`to_tex`] writes for `table`.
fn check_tex_rows(tex: &str, label: &str, table: &PaperTable) {
    let ours = to_tex(table, false);
    let ours: BTreeSet<String> = ours.lines().map(squash).collect();
    let paper: Vec<&str> = tabular_lines(tex, label)
        .into_iter()
        .filter(|l| is_model_row(l))
        .collect();
    assert_eq!(paper.len(), table.rows.len(), "{label}");
    for line in paper {
        assert!(
            ours.contains(&squash(line)),
            "{label}: to_tex writes no row\n{line}"
        );
    }
}

/// `inner` of `command{inner}`.
fn unwrap_command<'a>(field: &'a str, command: &str) -> Option<&'a str> {
    field
        .strip_prefix(command)?
        .strip_prefix('{')?
        .strip_suffix('}')
}

fn by_model(models: &[ReportedModel]) -> BTreeMap<&str, &ReportedModel> {
    models.iter().map(|m| (m.model.as_str(), m)).collect()
}

/// The data file holds exactly the rows of `label`, in its order, value for value.
fn check_values(tex: &[TexRow], models: &[ReportedModel], metric: Metric, label: &str) {
    let tex_names: Vec<&str> = tex.iter().map(|r| r.0.as_str()).collect();
    let data_names: Vec<&str> = models.iter().map(|m| m.model.as_str()).collect();
    assert_eq!(data_names, tex_names, "{label}: the models and their order");
    for ((model, category, cells), reported) in tex.iter().zip(models) {
        assert_eq!(&reported.category, category, "{label}: {model}'s category");
        let values = reported.values(metric);
        assert_eq!(values.len(), 16, "{label}: {model}");
        for (key, (printed, _)) in CellKey::all().zip(cells) {
            let value = values.get(&key).copied();
            assert_eq!(
                value.map(|v| format!("{v:.2}")).as_deref(),
                Some(printed.as_str()),
                "{label}: {model} {key}"
            );
        }
    }
}

/// The marks the rule gives `rows` of the data file equal the marks of the LaTeX table.
fn check_marks(
    tex: &[TexRow],
    models: &[ReportedModel],
    metric: Metric,
    label: &str,
) -> (usize, PaperTable) {
    let mut table = table_of(metric, models);
    mark(&mut table);
    let mut marks = 0;
    for ((model, _, cells), row) in tex.iter().zip(&table.rows) {
        assert_eq!(model, &row.model);
        for (key, (_, tex_mark)) in CellKey::all().zip(cells) {
            assert_eq!(
                row.cells[&key].mark, *tex_mark,
                "{label}: {model} {key} is marked {tex_mark:?} in the paper"
            );
            marks += usize::from(tex_mark.is_some());
        }
    }
    (marks, table)
}

#[test]
fn the_data_file_equals_the_papers_tables_and_the_rule_gives_their_marks() {
    let Some(tex) = paper_tex() else { return };
    let models = enact_paper_results();

    let task = tex_table(&tex, "tab:app_task_acc");
    check_values(&task, &models, Metric::TaskAccuracy, "tab:app_task_acc");
    let (task_marks, table) = check_marks(&task, &models, Metric::TaskAccuracy, "tab:app_task_acc");
    check_tex_rows(&tex, "tab:app_task_acc", &table);

    let pair = tex_table(&tex, "tab:app_pair_acc");
    check_values(&pair, &models, Metric::PairwiseAccuracy, "tab:app_pair_acc");
    let (pair_marks, table) =
        check_marks(&pair, &models, Metric::PairwiseAccuracy, "tab:app_pair_acc");
    check_tex_rows(&tex, "tab:app_pair_acc", &table);

    // The main table is a selection of the appendix's rows, marked within that selection.
    let main = tex_table(&tex, "tab:main_pair_acc");
    let main_names: Vec<&str> = main.iter().map(|r| r.0.as_str()).collect();
    assert_eq!(main_names, ENACT_PAPER_MAIN_TABLE_MODELS);
    let all = by_model(&models);
    let selected: Vec<ReportedModel> = main_names
        .iter()
        .map(|name| (*all.get(name).expect("a main-table model in the data file")).clone())
        .collect();
    check_values(
        &main,
        &selected,
        Metric::PairwiseAccuracy,
        "tab:main_pair_acc",
    );
    let (main_marks, table) = check_marks(
        &main,
        &selected,
        Metric::PairwiseAccuracy,
        "tab:main_pair_acc",
    );
    check_tex_rows(&tex, "tab:main_pair_acc", &table);

    // The checks above saw the paper's marks, not empty tables: 16 columns, two categories,
    // first and second each, give about 64 marks per table (ties add, all-zero columns remove).
    assert_eq!(
        (task.len(), pair.len(), main.len()),
        (31, 31, 20),
        "rows read from the LaTeX"
    );
    for (label, n) in [
        ("task", task_marks),
        ("pair", pair_marks),
        ("main", main_marks),
    ] {
        assert!(n > 50, "{label}: only {n} marks read from the LaTeX");
    }
}

/// The standalone `.tex` compiles with `pdflatex` (scripts/test.sh installs Debian's
/// texlive-latex-recommended when it is missing): both of the paper's tables, marked, plus a
/// row whose name holds every character LaTeX treats specially and cells with intervals.
#[test]
fn the_standalone_tables_compile_with_pdflatex() {
    let found = std::process::Command::new("pdflatex")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        assert!(
            !must_not_skip(),
            "pdflatex is missing and CI is set: install texlive-latex-recommended \
             (scripts/test.sh does)"
        );
        eprintln!("SKIPPING the pdflatex check: no pdflatex on PATH");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for metric in Metric::ALL {
        let mut table = table_of(metric, &enact_paper_results());
        let mut odd = table.rows[0].clone();
        odd.model = "Odd & 50% #1 $x$ _y_ {z} ~ ^ \\ model".to_owned();
        odd.category = Category::Named("enact-hub".to_owned());
        for cell in odd.cells.values_mut() {
            cell.interval = cell.value.map(|v| (v - 1.5, v + 1.5));
        }
        table.rows.insert(table.rows.len() - 1, odd);
        mark(&mut table);
        let name = format!("{}.tex", metric.as_str());
        std::fs::write(dir.path().join(&name), to_tex(&table, true)).unwrap();
        let run = std::process::Command::new("pdflatex")
            .args([
                "-interaction=nonstopmode",
                "-halt-on-error",
                "-no-shell-escape",
            ])
            .arg(&name)
            .current_dir(dir.path())
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "pdflatex refused {name}:\n{}",
            String::from_utf8_lossy(&run.stdout)
        );
        let pdf = dir.path().join(format!("{}.pdf", metric.as_str()));
        assert!(
            std::fs::metadata(&pdf).is_ok_and(|m| m.len() > 1000),
            "{pdf:?}"
        );
    }
}
