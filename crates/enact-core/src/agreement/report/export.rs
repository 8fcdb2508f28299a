//! The report bundle: the same report as JSON, CSV, Markdown, LaTeX (booktabs tables in the
//! layout of the paper's Tables 1 and 3) and SVG figures, every file stamped with the dataset
//! hash, metric version, bootstrap seed and the submission and annotator ids; and the tar
//! archive that carries them in one download.

use askama::Template;

use crate::agreement::WelchComparison;
use crate::agreement::report::heatmap::comparison_heatmap;
use crate::agreement::report::{AgreementReport, ReportStamp};
use crate::audit::AuditEntry;
use crate::bundle::{
    BundleFile, Stamp, csv_document, fixed, stamp_lines, stamp_text, tex_escape, tex_stamp,
};
use crate::dataset::Direction;
use crate::error_analysis::{ErrorAnalysis, present};
use crate::leaderboard::{
    AccuracyCell, AccuracyChart, LeaderboardRow, MIN_HUMAN_ANSWERS, RowSource,
};

impl Stamp for ReportStamp {
    fn stamp_fields(&self) -> Vec<String> {
        let stamp = self;
        let ids = |ids: &[i64]| {
            if ids.is_empty() {
                "none".to_owned()
            } else {
                ids.iter().map(i64::to_string).collect::<Vec<_>>().join(" ")
            }
        };
        let mut lines = vec![
            format!("dataset: {}", stamp.dataset),
            format!("dataset_hash: sha256:{}", stamp.dataset_hash),
            format!("metric_version: {}", stamp.metric_version),
            format!(
                "hub: enact-hub {} (commit {})",
                stamp.hub.version, stamp.hub.commit
            ),
            format!("encoding: {} ({} alpha)", stamp.encoding, stamp.level),
            format!(
                "bootstrap: seed {}, {} replicates over items, {}% percentile interval",
                stamp.bootstrap_seed,
                stamp.bootstrap_replicates,
                stamp.confidence_level * 100.0
            ),
            format!("submission_ids: {}", ids(&stamp.submission_ids)),
            format!("annotator_ids: {}", ids(&stamp.annotator_ids)),
        ];
        if let Some(protocol) = stamp.protocol {
            lines.push(format!(
                "agreement_protocol: k = {} per annotator, direction and step length, seed {}",
                protocol.items_per_cell, protocol.seed
            ));
        }
        lines
    }
}

#[derive(Template)]
#[template(path = "report/accuracy_chart.svg")]
struct AccuracyChartSvg<'a> {
    chart: &'a AccuracyChart,
    stamp: String,
}

/// The heatmap of every comparison, as a standalone SVG file.
pub fn heatmap_svg(report: &AgreementReport) -> Result<String, askama::Error> {
    comparison_heatmap(&report.comparisons).svg(&stamp_text(&report.stamp))
}

/// Task accuracy against step length for every row of the tables, as a standalone SVG file.
pub fn accuracy_chart_svg(report: &AgreementReport) -> Result<String, askama::Error> {
    AccuracyChartSvg {
        chart: &AccuracyChart::task_accuracy_by_step_length(&report.rows),
        stamp: stamp_text(&report.stamp),
    }
    .render()
}

fn percent(value: Option<f64>) -> String {
    value.map_or_else(String::new, |v| format!("{:.2}", v * 100.0))
}

fn row_label(row: &LeaderboardRow) -> String {
    match row.source {
        RowSource::Human => "Human".to_owned(),
        RowSource::Submission => row.model.clone(),
    }
}

/// The cell of a row for one direction and step length.
fn step_cell(row: &LeaderboardRow, direction: Direction, length: u8) -> AccuracyCell {
    let columns = match direction {
        Direction::Forward => &row.forward,
        Direction::Inverse => &row.inverse,
    };
    columns
        .per_step
        .iter()
        .find(|(l, _)| *l == length)
        .map(|(_, cell)| *cell)
        .unwrap_or_default()
}

fn agreement_rows(report: &AgreementReport) -> Vec<Vec<String>> {
    let Some(agreement) = &report.agreement else {
        return Vec::new();
    };
    let alpha = &agreement.alpha;
    let mut rows = vec![vec![
        "all annotators".to_owned(),
        String::new(),
        fixed(alpha.estimate.alpha, 4),
        fixed(alpha.ci_low, 4),
        fixed(alpha.ci_high, 4),
        alpha.estimate.units_used.to_string(),
        alpha
            .estimate
            .reason
            .as_ref()
            .map_or_else(String::new, ToString::to_string),
    ]];
    for pair in &agreement.pairwise {
        rows.push(vec![
            pair.a.name.clone(),
            pair.b.name.clone(),
            fixed(pair.alpha, 4),
            String::new(),
            String::new(),
            pair.shared_units.to_string(),
            pair.reason.clone().unwrap_or_default(),
        ]);
    }
    rows
}

fn welch_fields(w: &WelchComparison) -> Vec<String> {
    vec![
        w.n_a.to_string(),
        fixed(w.mean_a, 4),
        fixed(w.mean_b, 4),
        fixed(w.delta, 4),
        fixed(w.se, 4),
        fixed(w.t, 3),
        fixed(w.df, 1),
        w.p.map_or_else(String::new, |p| format!("{p:.3e}")),
        w.reason
            .as_ref()
            .map_or_else(String::new, ToString::to_string),
    ]
}

/// Every CSV file of the bundle: (name, text).
pub fn csv_files(report: &AgreementReport) -> Vec<(&'static str, String)> {
    let stamp = &report.stamp;
    let mut files = Vec::new();
    files.push((
        "agreement.csv",
        csv_document(
            stamp,
            &[
                "annotator_a",
                "annotator_b",
                "alpha",
                "ci_low",
                "ci_high",
                "units",
                "undefined_because",
            ],
            &agreement_rows(report),
        ),
    ));
    let mut counts = Vec::new();
    if let Some(agreement) = &report.agreement {
        counts.push(vec![
            "all".to_owned(),
            "all".to_owned(),
            agreement.items.to_string(),
            agreement.answers.to_string(),
            agreement.exact_agreement.agreeing_items.to_string(),
            fixed(agreement.exact_agreement.rate, 4),
        ]);
        for cell in &agreement.counts {
            counts.push(vec![
                cell.direction.to_string(),
                cell.step_length.to_string(),
                cell.items.to_string(),
                cell.answers.to_string(),
                cell.all_agree.to_string(),
                fixed(Some(cell.all_agree as f64 / cell.items.max(1) as f64), 4),
            ]);
        }
    }
    files.push((
        "agreement_counts.csv",
        csv_document(
            stamp,
            &[
                "direction",
                "step_length",
                "items",
                "answers",
                "all_agree",
                "exact_agreement_rate",
            ],
            &counts,
        ),
    ));
    let mut accuracy = Vec::new();
    for row in &report.rows {
        let id = row.submission.map_or_else(String::new, |id| id.to_string());
        let mut push = |direction: &str, length: String, cell: &AccuracyCell| {
            accuracy.push(vec![
                row_label(row),
                id.clone(),
                direction.to_owned(),
                length,
                cell.count.to_string(),
                fixed(cell.task_accuracy, 6),
                fixed(cell.pairwise_accuracy, 6),
            ]);
        };
        push("all", "all".to_owned(), &row.overall);
        push("forward", "all".to_owned(), &row.forward.total);
        push("inverse", "all".to_owned(), &row.inverse.total);
        for (direction, columns) in [("forward", &row.forward), ("inverse", &row.inverse)] {
            for (length, cell) in &columns.per_step {
                push(direction, length.to_string(), cell);
            }
        }
    }
    files.push((
        "accuracy.csv",
        csv_document(
            stamp,
            &[
                "row",
                "submission",
                "direction",
                "step_length",
                "count",
                "task_accuracy",
                "pairwise_accuracy",
            ],
            &accuracy,
        ),
    ));
    let mut comparisons = Vec::new();
    for comparison in &report.comparisons {
        let mut push = |direction: String, length: String, welch: &WelchComparison| {
            let mut row = vec![
                comparison.a.label.clone(),
                comparison.b.label.clone(),
                direction,
                length,
            ];
            row.extend(welch_fields(welch));
            comparisons.push(row);
        };
        push("all".to_owned(), "all".to_owned(), &comparison.overall);
        for cell in &comparison.cells {
            push(
                cell.direction.to_string(),
                cell.step_length.to_string(),
                &cell.welch,
            );
        }
    }
    files.push((
        "comparisons.csv",
        csv_document(
            stamp,
            &[
                "a",
                "b",
                "direction",
                "step_length",
                "items",
                "mean_pa_a",
                "mean_pa_b",
                "delta",
                "se",
                "t",
                "df",
                "p",
                "undefined_because",
            ],
            &comparisons,
        ),
    ));
    files
}

/// One comparison's overall row (a, b, items, Δ, SE, t, df, p) for the Markdown and LaTeX
/// tables: labels through `escape`, an undefined p as `no_p`.
fn welch_cells(c: &super::Comparison, escape: fn(&str) -> String, no_p: &str) -> [String; 8] {
    let w = &c.overall;
    [
        escape(&c.a.label),
        escape(&c.b.label),
        c.items.to_string(),
        fixed(w.delta, 4),
        fixed(w.se, 4),
        fixed(w.t, 3),
        fixed(w.df, 1),
        w.p.map_or_else(|| no_p.to_owned(), |p| format!("{p:.3e}")),
    ]
}

/// Text for a Markdown cell or line: HTML characters as entities (Markdown renders raw HTML,
/// and model names come from submitters) and Markdown's own punctuation backslash-escaped.
fn md_escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '&' => out.push_str("&amp;"),
            '|' | '\\' | '`' | '*' | '_' | '[' | ']' => {
                out.push('\\');
                out.push(c);
            }
            _ => out.push(c),
        }
    }
    out
}

/// The report as Markdown.
pub fn markdown(report: &AgreementReport) -> String {
    let stamp = &report.stamp;
    let mut out = format!("# Agreement report: {}\n\n", md_escape(&stamp.dataset));
    for line in stamp_lines(stamp) {
        out.push_str(&format!("- {}\n", md_escape(&line)));
    }
    out.push_str("\n## Inter-annotator agreement\n\n");
    match &report.agreement {
        None => out.push_str(&format!(
            "{}\n",
            report.agreement_unavailable.as_deref().unwrap_or("")
        )),
        Some(agreement) => {
            let alpha = &agreement.alpha;
            out.push_str(&format!(
                "Krippendorff's alpha ({} encoding, {}): **{}**, {}% CI [{}, {}] ({} items, {} \
                 answers, {} annotators). All annotators gave the same answer on {} of {} items \
                 ({}%).\n\n",
                agreement.encoding,
                agreement.level,
                alpha
                    .estimate
                    .alpha
                    .map_or_else(|| "undefined".to_owned(), |a| format!("{a:.4}")),
                stamp.confidence_level * 100.0,
                fixed(alpha.ci_low, 4),
                fixed(alpha.ci_high, 4),
                agreement.items,
                agreement.answers,
                agreement.annotators.len(),
                agreement.exact_agreement.agreeing_items,
                agreement.exact_agreement.compared_items,
                percent(agreement.exact_agreement.rate),
            ));
            out.push_str("| annotators | alpha | shared units |\n|---|---|---|\n");
            for pair in &agreement.pairwise {
                out.push_str(&format!(
                    "| {} – {} | {} | {} |\n",
                    md_escape(&pair.a.name),
                    md_escape(&pair.b.name),
                    pair.alpha.map_or_else(
                        || format!("undefined: {}", pair.reason.clone().unwrap_or_default()),
                        |a| format!("{a:.4}")
                    ),
                    pair.shared_units
                ));
            }
            out.push_str(
                "\n| direction | L | items | answers | all agree |\n|---|---|---|---|---|\n",
            );
            for cell in &agreement.counts {
                out.push_str(&format!(
                    "| {} | {} | {} | {} | {} |\n",
                    cell.direction, cell.step_length, cell.items, cell.answers, cell.all_agree
                ));
            }
        }
    }
    for (title, pick) in [
        ("Task accuracy (%)", true),
        ("Pairwise accuracy (%)", false),
    ] {
        out.push_str(&format!("\n## {title}\n\n| model |"));
        for direction in ["F", "I"] {
            for l in 3..=10 {
                out.push_str(&format!(" {direction}{l} |"));
            }
        }
        out.push_str("\n|---|");
        out.push_str(&"---|".repeat(16));
        out.push('\n');
        for row in &report.rows {
            out.push_str(&format!("| {} |", md_escape(&row_label(row))));
            for direction in Direction::ALL {
                for l in 3..=10 {
                    let cell = step_cell(row, direction, l);
                    let v = if pick {
                        cell.task_accuracy
                    } else {
                        cell.pairwise_accuracy
                    };
                    // A Human cell on too few answers says so instead of a bare figure.
                    let few =
                        row.human.is_some() && cell.count > 0 && cell.count < MIN_HUMAN_ANSWERS;
                    let mark = if few { "†" } else { "" };
                    out.push_str(&format!(" {}{mark} |", percent(v)));
                }
            }
            out.push('\n');
        }
        if let Some(h) = report.rows.iter().find_map(|r| r.human) {
            out.push_str(&format!(
                "\nHuman: {} of {} items answered by {} annotators ({} answers); not ranked. \
                 † fewer than {MIN_HUMAN_ANSWERS} answers.\n",
                h.items, h.dataset_items, h.annotators, h.answers
            ));
        }
    }
    out.push_str(
        "\n## Comparisons (per-item pairwise accuracy, Welch's t-test, all items)\n\n\
         | a | b | items | Δ | SE | t | df | p |\n|---|---|---|---|---|---|---|---|\n",
    );
    for c in &report.comparisons {
        let cells = welch_cells(c, md_escape, "n/a");
        out.push_str(&format!("| {} |\n", cells.join(" | ")));
    }
    out.push_str("\nPer direction and step length: `comparisons.csv` and `heatmap.svg`.\n");
    out
}

/// One accuracy table in the layout of the paper's Tables 1 (PA) and 3 (TA): a row per
/// model, forward then inverse columns for L = 3..10, the Human row last and in bold.
fn latex_accuracy_table(report: &AgreementReport, task: bool) -> String {
    let (what, label) = if task {
        ("Task Accuracy", "task_acc")
    } else {
        ("Pairwise Accuracy", "pair_acc")
    };
    let mut out = String::from(
        "\\begin{table*}[t]\n\\centering\n\\setlength{\\tabcolsep}{2pt}\n\\small\n\
         \\resizebox{\\textwidth}{!}{\n\\begin{tabular}{@{}l cccccccc cccccccc@{}}\n\\toprule\n\
         \\multirow{2}{*}{\\textbf{Model}} & \\multicolumn{8}{c}{\\textbf{Forward World Modeling}} \
         & \\multicolumn{8}{c}{\\textbf{Inverse World Modeling}} \\\\\n\
         \\cmidrule(lr){2-9}\\cmidrule(lr){10-17}\n",
    );
    out.push_str(" &");
    let headers: Vec<String> = (0..2)
        .flat_map(|_| (3..=10).map(|l| format!(" \\bf {l}")))
        .collect();
    out.push_str(&headers.join(" &"));
    out.push_str(" \\\\\n\\midrule\n");
    for row in &report.rows {
        let human = row.source == RowSource::Human;
        if human {
            out.push_str("\\midrule\n");
        }
        let bold = |text: String| {
            if human && !text.is_empty() {
                format!("\\textbf{{{text}}}")
            } else {
                text
            }
        };
        let name = if human {
            "Human Performance".to_owned()
        } else {
            tex_escape(&row.model)
        };
        let mut cells = vec![bold(name)];
        for direction in Direction::ALL {
            for l in 3..=10 {
                let cell = step_cell(row, direction, l);
                let v = if task {
                    cell.task_accuracy
                } else {
                    cell.pairwise_accuracy
                };
                cells.push(bold(percent(v).replace('%', "")));
            }
        }
        out.push_str(&cells.join(" & "));
        out.push_str(" \\\\\n");
    }
    out.push_str(&format!(
        "\\bottomrule\n\\end{{tabular}}\n}}\n\\caption{{\\textbf{{Evaluation on {} ({what}, \\%).}}}}\n\
         \\label{{tab:enact_hub_{label}}}\n\\end{{table*}}\n",
        tex_escape(&report.stamp.dataset)
    ));
    out
}

/// The report's tables in LaTeX (needs `booktabs`, `multirow` and `graphicx`).
pub fn latex(report: &AgreementReport) -> String {
    let stamp = &report.stamp;
    let mut out = tex_stamp(stamp);
    out.push_str("% needs \\usepackage{booktabs,multirow,graphicx}\n\n");
    out.push_str(&latex_accuracy_table(report, false));
    out.push('\n');
    out.push_str(&latex_accuracy_table(report, true));
    if let Some(agreement) = &report.agreement {
        let alpha = &agreement.alpha;
        out.push_str(&format!(
            "\n\\begin{{table}}[t]\n\\centering\n\\small\n\\begin{{tabular}}{{@{{}}lcc@{{}}}}\n\\toprule\n\
             \\textbf{{Annotators}} & $\\alpha$ & {}\\% CI \\\\\n\\midrule\nAll & {} & [{}, {}] \\\\\n",
            stamp.confidence_level * 100.0,
            fixed(alpha.estimate.alpha, 4),
            fixed(alpha.ci_low, 4),
            fixed(alpha.ci_high, 4),
        ));
        for pair in &agreement.pairwise {
            out.push_str(&format!(
                "{} -- {} & {} & \\\\\n",
                tex_escape(&pair.a.name),
                tex_escape(&pair.b.name),
                fixed(pair.alpha, 4)
            ));
        }
        out.push_str(&format!(
            "\\midrule\nExact agreement & \\multicolumn{{2}}{{c}}{{{}/{} ({}\\%)}} \\\\\n\
             \\bottomrule\n\\end{{tabular}}\n\\caption{{Inter-annotator agreement on {} \
             (Krippendorff's $\\alpha$, {} encoding, {} level; percentile bootstrap over {} \
             items, {} resamples, seed {}).}}\n\\label{{tab:enact_hub_iaa}}\n\\end{{table}}\n",
            agreement.exact_agreement.agreeing_items,
            agreement.exact_agreement.compared_items,
            percent(agreement.exact_agreement.rate),
            tex_escape(&stamp.dataset),
            agreement.encoding,
            agreement.level,
            alpha.items,
            alpha.replicates,
            stamp.bootstrap_seed,
        ));
    }
    if !report.comparisons.is_empty() {
        out.push_str(
            "\n\\begin{table}[t]\n\\centering\n\\small\n\\begin{tabular}{@{}llrrrrrr@{}}\n\\toprule\n\
             \\textbf{a} & \\textbf{b} & $n$ & $\\Delta$ & SE & $t$ & df & $p$ \\\\\n\\midrule\n",
        );
        for c in &report.comparisons {
            let cells = welch_cells(c, tex_escape, "--");
            out.push_str(&format!("{} \\\\\n", cells.join(" & ")));
        }
        out.push_str(
            "\\bottomrule\n\\end{tabular}\n\\caption{Per-item pairwise accuracy, two-tailed \
             Welch's $t$-test over the items both sides answered; $\\Delta$ = a $-$ b.}\n\
             \\label{tab:enact_hub_welch}\n\\end{table}\n",
        );
    }
    out
}

/// Every file of the bundle, in a fixed order.
pub fn bundle_files(report: &AgreementReport) -> Result<Vec<BundleFile>, askama::Error> {
    let json = serde_json::to_string_pretty(report).map_err(|e| askama::Error::Custom(e.into()))?;
    let mut files = vec![BundleFile {
        name: "report.json".into(),
        bytes: (json + "\n").into_bytes(),
    }];
    for (name, text) in csv_files(report) {
        files.push(BundleFile {
            name: name.into(),
            bytes: text.into_bytes(),
        });
    }
    files.push(BundleFile {
        name: "report.md".into(),
        bytes: markdown(report).into_bytes(),
    });
    files.push(BundleFile {
        name: "tables.tex".into(),
        bytes: latex(report).into_bytes(),
    });
    files.push(BundleFile {
        name: "heatmap.svg".into(),
        bytes: heatmap_svg(report)?.into_bytes(),
    });
    files.push(BundleFile {
        name: "task_accuracy.svg".into(),
        bytes: accuracy_chart_svg(report)?.into_bytes(),
    });
    Ok(files)
}

/// A row of the error-analysis files: its label and analysis.
pub struct ErrorRow<'a> {
    pub label: String,
    pub submission: Option<i64>,
    pub analysis: &'a ErrorAnalysis,
}

/// `errors.json` and `errors.csv`: the error analysis of each row, stamped like every file.
pub fn error_files(
    stamp: &ReportStamp,
    rows: &[ErrorRow<'_>],
) -> Result<Vec<BundleFile>, askama::Error> {
    let json = serde_json::json!({
        "stamp": stamp_lines(stamp),
        "rows": rows
            .iter()
            .map(|r| serde_json::json!({
                "label": r.label,
                "submission": r.submission,
                "analysis": r.analysis,
            }))
            .collect::<Vec<_>>(),
    });
    let json = serde_json::to_string_pretty(&json).map_err(|e| askama::Error::Custom(e.into()))?;
    let labelled: Vec<(&str, &ErrorAnalysis)> = rows
        .iter()
        .map(|r| (r.label.as_str(), r.analysis))
        .collect();
    let (header, lines) = present::table(&labelled);
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    Ok(vec![
        BundleFile {
            name: "errors.json".into(),
            bytes: (json + "\n").into_bytes(),
        },
        BundleFile {
            name: "errors.csv".into(),
            bytes: csv_document(stamp, &header, &lines).into_bytes(),
        },
    ])
}

/// `audit.csv`: the audit entries that concern the dataset, oldest first, stamped like every
/// file.
pub fn audit_file(stamp: &ReportStamp, entries: &[AuditEntry]) -> BundleFile {
    let header = [
        "id",
        "at",
        "actor_kind",
        "actor",
        "action",
        "target",
        "dataset",
        "detail",
    ];
    let rows: Vec<Vec<String>> = entries
        .iter()
        .rev()
        .map(|e| {
            vec![
                e.id.to_string(),
                e.at.clone(),
                e.actor_kind.clone(),
                e.actor.clone(),
                e.action.clone(),
                e.target.clone(),
                e.dataset.clone().unwrap_or_default(),
                e.detail.clone(),
            ]
        })
        .collect();
    BundleFile {
        name: "audit.csv".into(),
        bytes: csv_document(stamp, &header, &rows).into_bytes(),
    }
}
