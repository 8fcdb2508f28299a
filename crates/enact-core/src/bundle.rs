//! The files a report is downloaded as, whatever the report: every file stamped with what it
//! was computed from ([`Stamp`], [`stamp_lines`]), CSV documents safe to open in a
//! spreadsheet, text escaped for LaTeX, and the tar archive that carries a bundle in one
//! download. The agreement report and the study report both write through these.

/// One file of a bundle.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BundleFile {
    /// The file's name in the folder (a study's heat map carries the study's name).
    pub name: String,
    pub bytes: Vec<u8>,
}

/// What a report's files are stamped with (dataset hashes, metric version, ids…), as
/// `key: value` lines.
pub trait Stamp {
    /// The lines as composed; they may hold anyone's text (dataset, model and variant names).
    fn stamp_fields(&self) -> Vec<String>;
}

/// The stamp as `key: value` lines, the same in every file. Control characters, line breaks
/// among them, become spaces: a name holding one would otherwise end a comment line early and
/// leave the rest as a CSV row, a LaTeX command or an SVG element's text.
pub fn stamp_lines(stamp: &impl Stamp) -> Vec<String> {
    stamp
        .stamp_fields()
        .iter()
        .map(|line| {
            line.chars()
                .map(|c| if c.is_control() { ' ' } else { c })
                .collect()
        })
        .collect()
}

/// The stamp on one line (an SVG's `<metadata>`, a page's footer).
pub fn stamp_text(stamp: &impl Stamp) -> String {
    stamp_lines(stamp).join("; ")
}

/// `value` with `decimals` decimals; empty when there is none.
pub fn fixed(value: Option<f64>, decimals: usize) -> String {
    value.map_or_else(String::new, |v| format!("{v:.decimals$}"))
}

/// One CSV field, quoted when it must be.
pub(crate) fn csv_field(text: &str) -> String {
    // A spreadsheet runs a cell that starts with = + - @ (or a tab or CR) as a formula, and
    // model names, descriptions and reasons are anyone's text: such a cell gets a leading `'`
    // (OWASP's advice), unless it is a number or the lone `-` of a missing value.
    let formula = text.starts_with(['=', '+', '-', '@', '\t', '\r'])
        && text != "-"
        && text.parse::<f64>().is_err();
    let text: std::borrow::Cow<'_, str> = if formula {
        format!("'{text}").into()
    } else {
        text.into()
    };
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.into_owned()
    }
}

/// A CSV file: the stamp as `# ` comment lines, the header, the rows.
pub fn csv_document(stamp: &impl Stamp, header: &[&str], rows: &[Vec<String>]) -> String {
    let mut out: String = stamp_lines(stamp)
        .iter()
        .map(|line| format!("# {line}\n"))
        .collect();
    out.push_str(&header.join(","));
    out.push('\n');
    for row in rows {
        let fields: Vec<String> = row.iter().map(|f| csv_field(f)).collect();
        out.push_str(&fields.join(","));
        out.push('\n');
    }
    out
}

/// The stamp as LaTeX `% ` comment lines.
pub fn tex_stamp(stamp: &impl Stamp) -> String {
    stamp_lines(stamp)
        .iter()
        .map(|line| format!("% {line}\n"))
        .collect()
}

/// Text for a LaTeX document: its special characters as commands or escapes.
pub fn tex_escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '\\' => out.push_str("\\textbackslash{}"),
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                out.push('\\');
                out.push(c);
            }
            '~' => out.push_str("\\textasciitilde{}"),
            // In LaTeX's default font encoding `<` and `>` print as ¡ and ¿.
            '<' => out.push_str("\\textless{}"),
            '>' => out.push_str("\\textgreater{}"),
            '^' => out.push_str("\\textasciicircum{}"),
            _ => out.push(c),
        }
    }
    out
}

/// The files as one tar archive under `folder/`, with a fixed mtime so the same report gives
/// the same bytes.
pub fn tar_archive(folder: &str, files: &[BundleFile]) -> std::io::Result<Vec<u8>> {
    let mut builder = tar::Builder::new(Vec::new());
    for file in files {
        let mut header = tar::Header::new_ustar();
        header.set_size(file.bytes.len() as u64);
        header.set_mode(0o644);
        header.set_mtime(0);
        header.set_entry_type(tar::EntryType::Regular);
        builder.append_data(
            &mut header,
            format!("{folder}/{}", file.name),
            file.bytes.as_slice(),
        )?;
    }
    builder.into_inner()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_fields_that_a_spreadsheet_would_run_are_made_text() {
        assert_eq!(csv_field("=HYPERLINK(\"x\")"), "\"'=HYPERLINK(\"\"x\"\")\"");
        assert_eq!(csv_field("+cmd|' /C calc'!A0"), "'+cmd|' /C calc'!A0");
        assert_eq!(csv_field("@SUM(A1)"), "'@SUM(A1)");
        assert_eq!(csv_field("-2+3"), "'-2+3");
        // Numbers, the missing-value dash and ordinary text stay as they are.
        assert_eq!(csv_field("-0.125"), "-0.125");
        assert_eq!(csv_field("+1e-3"), "+1e-3");
        assert_eq!(csv_field("-"), "-");
        assert_eq!(csv_field("gpt, mini"), "\"gpt, mini\"");
        assert_eq!(csv_field("model-1"), "model-1");
    }

    struct Lines(Vec<&'static str>);

    impl Stamp for Lines {
        fn stamp_fields(&self) -> Vec<String> {
            self.0.iter().map(|l| (*l).to_owned()).collect()
        }
    }

    #[test]
    fn a_name_with_a_line_break_stays_inside_its_stamp_line() {
        let stamp = Lines(vec!["dataset: evil\nname,1,2\r\tx", "metric_version: 1"]);
        assert_eq!(
            stamp_lines(&stamp),
            ["dataset: evil name,1,2  x", "metric_version: 1"]
        );
        let csv = csv_document(&stamp, &["a", "b"], &[vec!["1".into(), "2".into()]]);
        assert_eq!(
            csv,
            "# dataset: evil name,1,2  x\n# metric_version: 1\na,b\n1,2\n"
        );
        assert_eq!(
            tex_stamp(&stamp),
            "% dataset: evil name,1,2  x\n% metric_version: 1\n"
        );
        assert_eq!(
            stamp_text(&stamp),
            "dataset: evil name,1,2  x; metric_version: 1"
        );
    }
}
