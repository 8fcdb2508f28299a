//! Reading reliability data from the command line's JSON form, `{"data": [[1, 2, null], …]}`
//! with one list per coder, and errors that point at the offending entry.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::agreement::reliability::{ReliabilityData, ReliabilityDataError};

/// What was wrong with a reliability-data JSON document, and where.
#[derive(Debug, thiserror::Error)]
pub enum ReliabilityJsonError {
    #[error("{path}: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("line {line}, column {column}: invalid JSON: {message}")]
    Syntax {
        line: usize,
        column: usize,
        message: String,
    },
    #[error("expected a JSON object with a \"data\" field, found {found}")]
    NotAnObject { found: String },
    #[error("the object has no \"data\" field")]
    MissingData,
    #[error("{path}: expected a list, found {found}")]
    NotAList { path: String, found: String },
    #[error("data: expected at least one coder list, found an empty list")]
    NoCoders,
    #[error("data[{coder}][{unit}]: expected a number or null, found {found}")]
    NotAValue {
        coder: usize,
        unit: usize,
        found: String,
    },
    #[error("data[{coder}] has {found} entries but data[0] has {expected}")]
    UnequalLength {
        coder: usize,
        found: usize,
        expected: usize,
    },
    #[error("data: {0}")]
    Invalid(ReliabilityDataError),
}

/// Reads and parses the file at `path`.
pub fn read_reliability_json(path: &Path) -> Result<ReliabilityData, ReliabilityJsonError> {
    let text = std::fs::read_to_string(path).map_err(|source| ReliabilityJsonError::Read {
        path: path.to_owned(),
        source,
    })?;
    parse_reliability_json(&text)
}

/// Parses `{"data": [[…], …]}`: one list per coder, each entry a number or `null` (missing).
/// Other top-level fields are ignored.
pub fn parse_reliability_json(text: &str) -> Result<ReliabilityData, ReliabilityJsonError> {
    let document: Value =
        serde_json::from_str(text).map_err(|error| ReliabilityJsonError::Syntax {
            line: error.line(),
            column: error.column(),
            message: error.to_string(),
        })?;
    let Value::Object(fields) = &document else {
        return Err(ReliabilityJsonError::NotAnObject {
            found: describe(&document),
        });
    };
    let data = fields
        .get("data")
        .ok_or(ReliabilityJsonError::MissingData)?;
    let Value::Array(coder_lists) = data else {
        return Err(ReliabilityJsonError::NotAList {
            path: "data".into(),
            found: describe(data),
        });
    };
    if coder_lists.is_empty() {
        return Err(ReliabilityJsonError::NoCoders);
    }
    let mut rows: Vec<Vec<Option<f64>>> = Vec::with_capacity(coder_lists.len());
    for (coder, list) in coder_lists.iter().enumerate() {
        let Value::Array(entries) = list else {
            return Err(ReliabilityJsonError::NotAList {
                path: format!("data[{coder}]"),
                found: describe(list),
            });
        };
        if let Some(first) = rows.first()
            && first.len() != entries.len()
        {
            return Err(ReliabilityJsonError::UnequalLength {
                coder,
                found: entries.len(),
                expected: first.len(),
            });
        }
        let row = entries
            .iter()
            .enumerate()
            .map(|(unit, entry)| match entry {
                Value::Null => Ok(None),
                Value::Number(number) => {
                    number
                        .as_f64()
                        .map(Some)
                        .ok_or_else(|| ReliabilityJsonError::NotAValue {
                            coder,
                            unit,
                            found: describe(entry),
                        })
                }
                other => Err(ReliabilityJsonError::NotAValue {
                    coder,
                    unit,
                    found: describe(other),
                }),
            })
            .collect::<Result<Vec<_>, _>>()?;
        rows.push(row);
    }
    ReliabilityData::from_coder_rows(rows).map_err(ReliabilityJsonError::Invalid)
}

/// A short rendering of a JSON value for error messages.
fn describe(value: &Value) -> String {
    const LIMIT: usize = 40;
    let text = value.to_string();
    if text.chars().count() <= LIMIT {
        text
    } else {
        let cut: String = text.chars().take(LIMIT).collect();
        format!("{cut}…")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_numbers_and_nulls() {
        let data = parse_reliability_json(r#"{"data": [[1, 2.5, null], [1, null, 3]], "note": 1}"#)
            .unwrap();
        assert_eq!(
            data.coder_rows(),
            vec![
                vec![Some(1.0), Some(2.5), None],
                vec![Some(1.0), None, Some(3.0)]
            ]
        );
    }

    #[test]
    fn a_bad_entry_is_named_by_coder_and_unit() {
        let err = parse_reliability_json(r#"{"data": [[1,2,3,4,5,6,7,8], [1,2,3,4,5,6,7,"x"]]}"#)
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "data[1][7]: expected a number or null, found \"x\""
        );
        let nested = parse_reliability_json(r#"{"data": [[[1]]]}"#).unwrap_err();
        assert_eq!(
            nested.to_string(),
            "data[0][0]: expected a number or null, found [1]"
        );
    }

    #[test]
    fn shape_errors_say_where() {
        let ragged = parse_reliability_json(r#"{"data": [[1, 2], [1]]}"#).unwrap_err();
        assert_eq!(
            ragged.to_string(),
            "data[1] has 1 entries but data[0] has 2"
        );
        let not_list = parse_reliability_json(r#"{"data": [[1], 5]}"#).unwrap_err();
        assert_eq!(not_list.to_string(), "data[1]: expected a list, found 5");
        let top = parse_reliability_json(r#"[[1, 2]]"#).unwrap_err();
        assert!(matches!(top, ReliabilityJsonError::NotAnObject { .. }));
        let missing = parse_reliability_json(r#"{"rows": []}"#).unwrap_err();
        assert!(matches!(missing, ReliabilityJsonError::MissingData));
        let empty = parse_reliability_json(r#"{"data": []}"#).unwrap_err();
        assert!(matches!(empty, ReliabilityJsonError::NoCoders));
        let data_string = parse_reliability_json(r#"{"data": "1,2"}"#).unwrap_err();
        assert_eq!(
            data_string.to_string(),
            "data: expected a list, found \"1,2\""
        );
    }

    #[test]
    fn syntax_errors_carry_line_and_column() {
        let err = parse_reliability_json("{\"data\": [[1, 2],\n [1, ]]}").unwrap_err();
        match err {
            ReliabilityJsonError::Syntax { line, .. } => assert_eq!(line, 2),
            other => panic!("unexpected {other:?}"),
        }
    }

    #[test]
    fn long_values_are_shortened() {
        let long = format!(r#"{{"data": [["{}"]]}}"#, "y".repeat(100));
        let message = parse_reliability_json(&long).unwrap_err().to_string();
        assert!(message.ends_with('…'));
        assert!(message.len() < 100);
    }

    #[test]
    fn reads_a_file_and_names_a_missing_one() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("data.json");
        std::fs::write(&path, r#"{"data": [[1, 2], [2, 2]]}"#).unwrap();
        assert_eq!(read_reliability_json(&path).unwrap().units(), 2);
        let missing = dir.path().join("absent.json");
        let err = read_reliability_json(&missing).unwrap_err();
        assert!(err.to_string().starts_with(&missing.display().to_string()));
    }
}
