//! JSON values as ENACT's Python code sees them: `json.loads` in, `json.dumps` out.
//!
//! ENACT's evaluator reads each prediction line with Python's `json.loads` and writes its results
//! with `json.dump`. Reproducing its output byte for byte needs Python's view of the data, which
//! `serde_json::Value` cannot hold: integers of any size (`100000000000000000000` stays an int),
//! `NaN`/`Infinity` literals, ints and floats kept apart (`1` vs `1.0`), duplicate keys (the last
//! value wins at the first key's position), Python float `repr`, Python's `", "`/`": "`
//! separators and `ensure_ascii`. This module is that small JSON dialect plus the handful of
//! Python operations (truthiness, `==`, `str()`, dict-key identity) the evaluator applies.

use std::cmp::Ordering;
use std::fmt::Write as _;

use crate::verifier::pyint::PyInt;

/// A decoded JSON value with Python semantics.
#[derive(Debug, Clone)]
pub enum PyValue {
    None,
    Bool(bool),
    Int(PyInt),
    Float(f64),
    Str(String),
    List(Vec<PyValue>),
    /// Keys in first-insertion order, each key once (Python dict semantics).
    Dict(Vec<(String, PyValue)>),
}

/// Why `json.loads` rejected a line.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PyJsonError {
    /// `json.JSONDecodeError`: ENACT skips such a line as `invalid_json_format`.
    #[error("invalid JSON: {message} (char {position})")]
    Decode { message: String, position: usize },
    /// Another exception out of `json.loads` (an integer over Python's 4300-digit limit, nesting
    /// deeper than Python's recursion limit). ENACT does not catch these in its first pass over
    /// the file, so the whole file fails.
    #[error("{message}")]
    Fatal { message: String },
}

/// ENACT quirk: Python refuses to convert integers with more than 4300 decimal digits
/// (`sys.int_info.default_max_str_digits`), in `json.loads`, `int()` and integer literals.
pub const PY_INT_MAX_STR_DIGITS: usize = 4300;

/// Nesting depth at which CPython's JSON decoder hits the default recursion limit (1000 frames,
/// minus the frames of ENACT's own call stack). Approximate by a few levels; only absurd inputs
/// come near it.
const PY_JSON_MAX_DEPTH: usize = 980;

impl PyValue {
    /// Python's type name, as it appears in exception messages.
    pub fn type_name(&self) -> &'static str {
        match self {
            PyValue::None => "NoneType",
            PyValue::Bool(_) => "bool",
            PyValue::Int(_) => "int",
            PyValue::Float(_) => "float",
            PyValue::Str(_) => "str",
            PyValue::List(_) => "list",
            PyValue::Dict(_) => "dict",
        }
    }

    /// Python truthiness (`if value:`).
    pub fn truthy(&self) -> bool {
        match self {
            PyValue::None => false,
            PyValue::Bool(b) => *b,
            PyValue::Int(i) => !i.is_zero(),
            PyValue::Float(f) => *f != 0.0,
            PyValue::Str(s) => !s.is_empty(),
            PyValue::List(items) => !items.is_empty(),
            PyValue::Dict(entries) => !entries.is_empty(),
        }
    }

    pub fn as_str(&self) -> Option<&str> {
        match self {
            PyValue::Str(s) => Some(s),
            _ => None,
        }
    }

    /// `dict.get(key)`; `None` for a missing key or a value that is not a dict.
    pub fn get(&self, key: &str) -> Option<&PyValue> {
        match self {
            PyValue::Dict(entries) => entries.iter().find(|(k, _)| k == key).map(|(_, v)| v),
            _ => None,
        }
    }

    /// The integer value of a Python int or bool (bool is an int subclass).
    pub fn as_int(&self) -> Option<PyInt> {
        match self {
            PyValue::Int(i) => Some(i.clone()),
            PyValue::Bool(b) => Some(PyInt::Small(i64::from(*b))),
            _ => None,
        }
    }

    /// Python `==`. Numbers compare by value across bool/int/float (`[1.0] == [1]` is true,
    /// NaN equals nothing), dicts ignore key order, other types never equal each other.
    pub fn py_eq(&self, other: &PyValue) -> bool {
        if let (Some(a), Some(b)) = (Number::of(self), Number::of(other)) {
            return a.cmp(&b) == Some(Ordering::Equal);
        }
        match (self, other) {
            (PyValue::None, PyValue::None) => true,
            (PyValue::Str(a), PyValue::Str(b)) => a == b,
            (PyValue::List(a), PyValue::List(b)) => py_list_eq(a, b),
            (PyValue::Dict(a), PyValue::Dict(b)) => {
                a.len() == b.len()
                    && a.iter().all(|(k, v)| {
                        b.iter()
                            .find(|(bk, _)| bk == k)
                            .is_some_and(|(_, bv)| v.py_eq(bv))
                    })
            }
            _ => false,
        }
    }

    /// Python `str(value)`: how ENACT turns a key frame id into a scene-graph lookup key.
    /// Strings, numbers, bools and None are exact; lists and dicts use a simplified `repr`
    /// (no scene graph has such a frame, so only "not found" matters for them).
    pub fn py_str(&self) -> String {
        match self {
            PyValue::Str(s) => s.clone(),
            other => {
                let mut out = String::new();
                write_repr(other, &mut out);
                out
            }
        }
    }

    /// `json.dumps(value, ensure_ascii=...)` with Python's default separators `", "` / `": "`.
    pub fn to_json(&self, ensure_ascii: bool) -> String {
        let mut out = String::new();
        write_json(self, ensure_ascii, None, 0, &mut out);
        out
    }

    /// `json.dumps(value, indent=indent)` (ensure_ascii on, as ENACT's meta file has it).
    pub fn to_json_indented(&self, indent: usize) -> String {
        let mut out = String::new();
        write_json(self, true, Some(indent), 0, &mut out);
        out
    }
}

/// Python list `==`: same length and pairwise `==`.
pub fn py_list_eq(a: &[PyValue], b: &[PyValue]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.py_eq(y))
}

/// A numeric view of bool/int/float for Python's cross-type comparisons.
#[derive(Debug, Clone)]
pub(crate) enum Number {
    Int(PyInt),
    Float(f64),
}

impl Number {
    pub(crate) fn of(value: &PyValue) -> Option<Number> {
        match value {
            PyValue::Bool(b) => Some(Number::Int(PyInt::Small(i64::from(*b)))),
            PyValue::Int(i) => Some(Number::Int(i.clone())),
            PyValue::Float(f) => Some(Number::Float(*f)),
            _ => None,
        }
    }

    /// Python's exact numeric ordering; `None` when NaN is involved.
    pub(crate) fn cmp(&self, other: &Number) -> Option<Ordering> {
        match (self, other) {
            (Number::Int(a), Number::Int(b)) => Some(a.cmp(b)),
            (Number::Int(a), Number::Float(b)) => a.cmp_f64(*b),
            (Number::Float(a), Number::Int(b)) => b.cmp_f64(*a).map(Ordering::reverse),
            (Number::Float(a), Number::Float(b)) => a.partial_cmp(b),
        }
    }
}

/// A Python dict key with Python's key identity: `1`, `1.0` and `True` are one key, NaN is never
/// found again, lists and dicts cannot be keys at all.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum PyHashKey {
    None,
    Str(String),
    /// bool, int, or an integral float.
    Int(String),
    /// A non-integral float (or an infinity), by its bits.
    Float(u64),
    /// A NaN: each parsed NaN is a distinct object that compares unequal to everything.
    Nan(usize),
}

impl PyHashKey {
    /// The key for `value`, or `Err(type name)` for an unhashable value. `nan_serial` makes each
    /// NaN key unique.
    pub fn of(value: &PyValue, nan_serial: usize) -> Result<PyHashKey, &'static str> {
        Ok(match value {
            PyValue::None => PyHashKey::None,
            PyValue::Str(s) => PyHashKey::Str(s.clone()),
            PyValue::Bool(b) => PyHashKey::Int(i64::from(*b).to_string()),
            PyValue::Int(i) => PyHashKey::Int(i.to_string()),
            PyValue::Float(f) if f.is_nan() => PyHashKey::Nan(nan_serial),
            PyValue::Float(f) => match PyInt::from_integral_f64(*f) {
                Some(i) => PyHashKey::Int(i.to_string()),
                None => PyHashKey::Float(f.to_bits()),
            },
            PyValue::List(_) | PyValue::Dict(_) => return Err(value.type_name()),
        })
    }
}

/// Python's `repr(float)`: shortest round-trip digits, exponent form when the decimal exponent
/// is below -4 or above 16 (`1e-05`, `1e+16`), `.0` on integral values.
pub fn py_float_repr(value: f64) -> String {
    if value.is_nan() {
        return "nan".to_owned();
    }
    if value.is_infinite() {
        return if value > 0.0 { "inf" } else { "-inf" }.to_owned();
    }
    if value == 0.0 {
        return if value.is_sign_negative() {
            "-0.0"
        } else {
            "0.0"
        }
        .to_owned();
    }
    let sign = if value < 0.0 { "-" } else { "" };
    // Rust's `{:e}` gives the shortest round-trip digits, e.g. "8.859786000891663e-1".
    let scientific = format!("{:e}", value.abs());
    let (mantissa, exponent) = scientific
        .split_once('e')
        .unwrap_or((scientific.as_str(), "0"));
    let digits: String = mantissa.chars().filter(|c| *c != '.').collect();
    let exponent: i32 = exponent.parse().unwrap_or(0);
    // Python's decpt: the value is 0.DIGITS x 10^decpt.
    let decpt = exponent + 1;
    let k = digits.len() as i32;
    let body = if decpt > -4 && decpt <= 16 {
        if decpt <= 0 {
            format!("0.{}{}", "0".repeat((-decpt) as usize), digits)
        } else if decpt >= k {
            format!("{}{}.0", digits, "0".repeat((decpt - k) as usize))
        } else {
            let (int_part, frac_part) = digits.split_at(decpt as usize);
            format!("{int_part}.{frac_part}")
        }
    } else {
        let (first, rest) = digits.split_at(1);
        let exp = decpt - 1;
        let exp_sign = if exp < 0 { '-' } else { '+' };
        if rest.is_empty() {
            format!("{first}e{exp_sign}{:02}", exp.abs())
        } else {
            format!("{first}.{rest}e{exp_sign}{:02}", exp.abs())
        }
    };
    format!("{sign}{body}")
}

/// How Python's `json` module writes a float (`allow_nan=True`).
fn json_float(value: f64) -> String {
    if value.is_nan() {
        "NaN".to_owned()
    } else if value == f64::INFINITY {
        "Infinity".to_owned()
    } else if value == f64::NEG_INFINITY {
        "-Infinity".to_owned()
    } else {
        py_float_repr(value)
    }
}

fn write_json_string(s: &str, ensure_ascii: bool, out: &mut String) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            '\u{8}' => out.push_str("\\b"),
            '\u{c}' => out.push_str("\\f"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c if ensure_ascii && (c as u32) >= 0x7f => {
                let mut units = [0u16; 2];
                for unit in c.encode_utf16(&mut units) {
                    let _ = write!(out, "\\u{unit:04x}");
                }
            }
            c => out.push(c),
        }
    }
    out.push('"');
}

fn write_json(
    value: &PyValue,
    ensure_ascii: bool,
    indent: Option<usize>,
    level: usize,
    out: &mut String,
) {
    let newline = |out: &mut String, level: usize| {
        if let Some(width) = indent {
            out.push('\n');
            out.push_str(&" ".repeat(width * level));
        }
    };
    let item_separator = if indent.is_some() { "," } else { ", " };
    match value {
        PyValue::None => out.push_str("null"),
        PyValue::Bool(true) => out.push_str("true"),
        PyValue::Bool(false) => out.push_str("false"),
        PyValue::Int(i) => {
            let _ = write!(out, "{i}");
        }
        PyValue::Float(f) => out.push_str(&json_float(*f)),
        PyValue::Str(s) => write_json_string(s, ensure_ascii, out),
        PyValue::List(items) => {
            if items.is_empty() {
                out.push_str("[]");
                return;
            }
            out.push('[');
            for (i, item) in items.iter().enumerate() {
                if i > 0 {
                    out.push_str(item_separator);
                }
                newline(out, level + 1);
                write_json(item, ensure_ascii, indent, level + 1, out);
            }
            newline(out, level);
            out.push(']');
        }
        PyValue::Dict(entries) => {
            if entries.is_empty() {
                out.push_str("{}");
                return;
            }
            out.push('{');
            for (i, (key, item)) in entries.iter().enumerate() {
                if i > 0 {
                    out.push_str(item_separator);
                }
                newline(out, level + 1);
                write_json_string(key, ensure_ascii, out);
                out.push_str(": ");
                write_json(item, ensure_ascii, indent, level + 1, out);
            }
            newline(out, level);
            out.push('}');
        }
    }
}

fn write_str_repr(s: &str, out: &mut String) {
    let quote = if s.contains('\'') && !s.contains('"') {
        '"'
    } else {
        '\''
    };
    out.push(quote);
    for c in s.chars() {
        match c {
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c == quote => {
                out.push('\\');
                out.push(c);
            }
            c if (c as u32) < 0x20 || (0x7f..0xa0).contains(&(c as u32)) => {
                let _ = write!(out, "\\x{:02x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push(quote);
}

fn write_repr(value: &PyValue, out: &mut String) {
    match value {
        PyValue::None => out.push_str("None"),
        PyValue::Bool(true) => out.push_str("True"),
        PyValue::Bool(false) => out.push_str("False"),
        PyValue::Int(i) => {
            let _ = write!(out, "{i}");
        }
        PyValue::Float(f) => out.push_str(&py_float_repr(*f)),
        PyValue::Str(s) => write_str_repr(s, out),
        PyValue::List(items) => {
            out.push('[');
            for (i, item) in items.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                write_repr(item, out);
            }
            out.push(']');
        }
        PyValue::Dict(entries) => {
            out.push('{');
            for (i, (key, item)) in entries.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                write_str_repr(key, out);
                out.push_str(": ");
                write_repr(item, out);
            }
            out.push('}');
        }
    }
}

/// `json.loads(text)` with CPython's C decoder rules (strict mode).
pub fn parse_python_json(text: &str) -> Result<PyValue, PyJsonError> {
    if text.starts_with('\u{feff}') {
        return Err(decode_error(
            "Unexpected UTF-8 BOM (decode using utf-8-sig)",
            0,
        ));
    }
    let mut parser = Parser {
        bytes: text.as_bytes(),
        text,
        pos: 0,
    };
    parser.skip_ws();
    let value = parser.value(0)?;
    parser.skip_ws();
    if parser.pos != parser.bytes.len() {
        return Err(decode_error("Extra data", parser.pos));
    }
    Ok(value)
}

fn decode_error(message: &str, position: usize) -> PyJsonError {
    PyJsonError::Decode {
        message: message.to_owned(),
        position,
    }
}

struct Parser<'a> {
    bytes: &'a [u8],
    text: &'a str,
    pos: usize,
}

impl Parser<'_> {
    fn skip_ws(&mut self) {
        while let Some(b' ' | b'\t' | b'\n' | b'\r') = self.bytes.get(self.pos) {
            self.pos += 1;
        }
    }

    fn starts_with(&self, literal: &str) -> bool {
        self.bytes[self.pos..].starts_with(literal.as_bytes())
    }

    fn value(&mut self, depth: usize) -> Result<PyValue, PyJsonError> {
        let Some(&byte) = self.bytes.get(self.pos) else {
            return Err(decode_error("Expecting value", self.pos));
        };
        match byte {
            b'"' => {
                self.pos += 1;
                self.string().map(PyValue::Str)
            }
            b'{' | b'[' => {
                if depth >= PY_JSON_MAX_DEPTH {
                    return Err(PyJsonError::Fatal {
                        message: "maximum recursion depth exceeded while decoding a JSON document"
                            .to_owned(),
                    });
                }
                self.pos += 1;
                if byte == b'{' {
                    self.object(depth + 1)
                } else {
                    self.array(depth + 1)
                }
            }
            b'n' if self.starts_with("null") => {
                self.pos += 4;
                Ok(PyValue::None)
            }
            b't' if self.starts_with("true") => {
                self.pos += 4;
                Ok(PyValue::Bool(true))
            }
            b'f' if self.starts_with("false") => {
                self.pos += 5;
                Ok(PyValue::Bool(false))
            }
            b'N' if self.starts_with("NaN") => {
                self.pos += 3;
                Ok(PyValue::Float(f64::NAN))
            }
            b'I' if self.starts_with("Infinity") => {
                self.pos += 8;
                Ok(PyValue::Float(f64::INFINITY))
            }
            b'-' if self.starts_with("-Infinity") => {
                self.pos += 9;
                Ok(PyValue::Float(f64::NEG_INFINITY))
            }
            b'-' | b'0'..=b'9' => self.number(),
            _ => Err(decode_error("Expecting value", self.pos)),
        }
    }

    fn number(&mut self) -> Result<PyValue, PyJsonError> {
        let start = self.pos;
        let mut end = self.pos;
        if self.bytes.get(end) == Some(&b'-') {
            end += 1;
        }
        match self.bytes.get(end) {
            Some(b'0') => end += 1,
            Some(b'1'..=b'9') => {
                while self.bytes.get(end).is_some_and(u8::is_ascii_digit) {
                    end += 1;
                }
            }
            _ => return Err(decode_error("Expecting value", start)),
        }
        let int_end = end;
        let mut is_float = false;
        if self.bytes.get(end) == Some(&b'.')
            && self.bytes.get(end + 1).is_some_and(u8::is_ascii_digit)
        {
            end += 1;
            while self.bytes.get(end).is_some_and(u8::is_ascii_digit) {
                end += 1;
            }
            is_float = true;
        }
        if let Some(b'e' | b'E') = self.bytes.get(end) {
            let mut exp_end = end + 1;
            if let Some(b'+' | b'-') = self.bytes.get(exp_end) {
                exp_end += 1;
            }
            if self.bytes.get(exp_end).is_some_and(u8::is_ascii_digit) {
                while self.bytes.get(exp_end).is_some_and(u8::is_ascii_digit) {
                    exp_end += 1;
                }
                end = exp_end;
                is_float = true;
            }
        }
        let literal = &self.text[start..end];
        self.pos = end;
        if is_float {
            // Rust's float parsing is correctly rounded, as CPython's is; overflow gives inf.
            let value: f64 = literal.parse().unwrap_or(f64::NAN);
            return Ok(PyValue::Float(value));
        }
        let digit_count = int_end - start - usize::from(literal.starts_with('-'));
        if digit_count > PY_INT_MAX_STR_DIGITS {
            return Err(PyJsonError::Fatal {
                message: format!(
                    "Exceeds the limit ({PY_INT_MAX_STR_DIGITS} digits) for integer string \
                     conversion: value has {digit_count} digits; use sys.set_int_max_str_digits() \
                     to increase the limit"
                ),
            });
        }
        PyInt::parse_ascii(literal)
            .map(PyValue::Int)
            .ok_or_else(|| decode_error("Expecting value", start))
    }

    fn hex4(&self, at: usize) -> Option<u32> {
        let chunk = self.bytes.get(at..at + 4)?;
        let text = std::str::from_utf8(chunk).ok()?;
        if !text.bytes().all(|b| b.is_ascii_hexdigit()) {
            return None;
        }
        u32::from_str_radix(text, 16).ok()
    }

    /// A string body after the opening quote.
    fn string(&mut self) -> Result<String, PyJsonError> {
        let begin = self.pos - 1;
        let mut out = String::new();
        loop {
            let chunk_start = self.pos;
            while let Some(&b) = self.bytes.get(self.pos) {
                if b == b'"' || b == b'\\' || b < 0x20 {
                    break;
                }
                self.pos += 1;
            }
            out.push_str(&self.text[chunk_start..self.pos]);
            let Some(&b) = self.bytes.get(self.pos) else {
                return Err(decode_error("Unterminated string starting at", begin));
            };
            match b {
                b'"' => {
                    self.pos += 1;
                    return Ok(out);
                }
                b'\\' => {
                    let escape = self.bytes.get(self.pos + 1).copied();
                    let simple = match escape {
                        Some(b'"') => Some('"'),
                        Some(b'\\') => Some('\\'),
                        Some(b'/') => Some('/'),
                        Some(b'b') => Some('\u{8}'),
                        Some(b'f') => Some('\u{c}'),
                        Some(b'n') => Some('\n'),
                        Some(b'r') => Some('\r'),
                        Some(b't') => Some('\t'),
                        _ => None,
                    };
                    if let Some(c) = simple {
                        out.push(c);
                        self.pos += 2;
                        continue;
                    }
                    if escape != Some(b'u') {
                        return Err(decode_error("Invalid \\escape", self.pos));
                    }
                    let Some(unit) = self.hex4(self.pos + 2) else {
                        return Err(decode_error("Invalid \\uXXXX escape", self.pos + 1));
                    };
                    self.pos += 6;
                    let mut code = unit;
                    if (0xd800..0xdc00).contains(&unit)
                        && self.bytes.get(self.pos) == Some(&b'\\')
                        && self.bytes.get(self.pos + 1) == Some(&b'u')
                        && let Some(low) = self.hex4(self.pos + 2)
                        && (0xdc00..0xe000).contains(&low)
                    {
                        code = 0x10000 + ((unit - 0xd800) << 10) + (low - 0xdc00);
                        self.pos += 6;
                    }
                    // A lone surrogate is a valid Python str but not a Rust one; it becomes
                    // U+FFFD (ENACT would fail later when writing it as UTF-8).
                    out.push(char::from_u32(code).unwrap_or('\u{fffd}'));
                }
                _ => return Err(decode_error("Invalid control character at", self.pos)),
            }
        }
    }

    fn array(&mut self, depth: usize) -> Result<PyValue, PyJsonError> {
        let mut items = Vec::new();
        self.skip_ws();
        if self.bytes.get(self.pos) == Some(&b']') {
            self.pos += 1;
            return Ok(PyValue::List(items));
        }
        loop {
            items.push(self.value(depth)?);
            self.skip_ws();
            match self.bytes.get(self.pos) {
                Some(b']') => {
                    self.pos += 1;
                    return Ok(PyValue::List(items));
                }
                Some(b',') => {
                    self.pos += 1;
                    self.skip_ws();
                }
                _ => return Err(decode_error("Expecting ',' delimiter", self.pos)),
            }
        }
    }

    fn object(&mut self, depth: usize) -> Result<PyValue, PyJsonError> {
        let mut entries: Vec<(String, PyValue)> = Vec::new();
        self.skip_ws();
        if self.bytes.get(self.pos) == Some(&b'}') {
            self.pos += 1;
            return Ok(PyValue::Dict(entries));
        }
        loop {
            if self.bytes.get(self.pos) != Some(&b'"') {
                return Err(decode_error(
                    "Expecting property name enclosed in double quotes",
                    self.pos,
                ));
            }
            self.pos += 1;
            let key = self.string()?;
            self.skip_ws();
            if self.bytes.get(self.pos) != Some(&b':') {
                return Err(decode_error("Expecting ':' delimiter", self.pos));
            }
            self.pos += 1;
            self.skip_ws();
            let value = self.value(depth)?;
            // Python dicts keep the first position of a repeated key and its last value.
            match entries.iter_mut().find(|(k, _)| *k == key) {
                Some(slot) => slot.1 = value,
                None => entries.push((key, value)),
            }
            self.skip_ws();
            match self.bytes.get(self.pos) {
                Some(b'}') => {
                    self.pos += 1;
                    return Ok(PyValue::Dict(entries));
                }
                Some(b',') => {
                    self.pos += 1;
                    self.skip_ws();
                }
                _ => return Err(decode_error("Expecting ',' delimiter", self.pos)),
            }
        }
    }
}

/// The labels as `i64` when every one is an int or bool well inside the `i64` range; the
/// verifier then runs on machine integers, with the same results as on Python values.
pub(crate) fn small_labels(labels: &[PyValue]) -> Option<Vec<i64>> {
    labels
        .iter()
        .map(|label| match label {
            PyValue::Bool(b) => Some(i64::from(*b)),
            PyValue::Int(i) => i
                .to_i64()
                .filter(|v| *v > i64::MIN / 2 && *v < i64::MAX / 2),
            _ => None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> PyValue {
        parse_python_json(text).expect("valid test JSON")
    }

    #[test]
    fn float_repr_matches_python() {
        let cases = [
            (1.0, "1.0"),
            (0.8859786000891663, "0.8859786000891663"),
            (0.30555555555555564, "0.30555555555555564"),
            (1e-5, "1e-05"),
            (0.0001, "0.0001"),
            (1e16, "1e+16"),
            (1e15, "1000000000000000.0"),
            (123456789012345678.0, "1.2345678901234568e+17"),
            (1e20, "1e+20"),
            (1.5e300, "1.5e+300"),
            (5e-324, "5e-324"),
            (-0.0, "-0.0"),
            (-2.5, "-2.5"),
            (0.1, "0.1"),
            (f64::INFINITY, "inf"),
            (f64::NEG_INFINITY, "-inf"),
            (f64::NAN, "nan"),
        ];
        for (value, expected) in cases {
            assert_eq!(py_float_repr(value), expected, "repr of {value:e}");
        }
    }

    #[test]
    fn ints_and_floats_stay_apart_and_big_ints_survive() {
        let value = parse("[1, 1.0, 100000000000000000000, -0, 1e400, NaN, -Infinity, Infinity]");
        assert_eq!(
            value.to_json(false),
            "[1, 1.0, 100000000000000000000, 0, Infinity, NaN, -Infinity, Infinity]"
        );
    }

    /// An exponent's sign is part of the number, as in `json.loads` (Python 3.11: `100.0`,
    /// `0.02`, `[100.0, 0.5]`).
    #[test]
    fn signed_exponents_are_read_whole() {
        assert_eq!(parse("1e+2").to_json(false), "100.0");
        assert_eq!(parse("2E-2").to_json(false), "0.02");
        assert_eq!(parse("[1e+2, 5e-1]").to_json(false), "[100.0, 0.5]");
    }

    #[test]
    fn duplicate_keys_keep_first_position_and_last_value() {
        let value = parse(r#"{"a": 1, "b": 2, "a": 3}"#);
        assert_eq!(value.to_json(false), r#"{"a": 3, "b": 2}"#);
    }

    #[test]
    fn rejects_what_python_rejects() {
        for bad in [
            "",
            "[1,]",
            "{\"a\":1,}",
            "01",
            "1.",
            "[1 2]",
            "\"a\u{1}\"",
            "'a'",
            "\u{feff}1",
            "[\"\\x\"]",
            "Infinite",
            "[Infinit]",
            "fals",
            "[fx]",
            "nul",
            "tru",
            // As long as the word they start: only the word itself is a value.
            "fxxxx",
            "[fxxxx]",
            "[nxxx]",
            "[txxx]",
            "[Nxx]",
            "[Ixxxxxxx]",
            "[-Ixxxxxxx]",
        ] {
            assert!(
                matches!(parse_python_json(bad), Err(PyJsonError::Decode { .. })),
                "should reject {bad:?}"
            );
        }
        let long = "1".repeat(4301);
        assert!(matches!(
            parse_python_json(&long),
            Err(PyJsonError::Fatal { .. })
        ));
        assert!(parse_python_json(&"1".repeat(4300)).is_ok());
        // The limit counts digits, not the sign.
        assert!(parse_python_json(&format!("-{}", "1".repeat(4300))).is_ok());
        assert!(matches!(
            parse_python_json(&format!("-{}", "1".repeat(4301))),
            Err(PyJsonError::Fatal { .. })
        ));
        let deep = format!("{}{}", "[".repeat(2000), "]".repeat(2000));
        assert!(matches!(
            parse_python_json(&deep),
            Err(PyJsonError::Fatal { .. })
        ));
    }

    #[test]
    fn decode_errors_are_placed_where_python_places_them() {
        // Positions as Python 3.11's json.loads reports them ("… (char N)").
        for (bad, message, position) in [
            ("\"abc", "Unterminated string starting at", 0),
            ("[1, \"ab", "Unterminated string starting at", 4),
            ("\"\\u12\"", "Invalid \\uXXXX escape", 2),
            ("[\"x\", \"\\u12G4\"]", "Invalid \\uXXXX escape", 8),
        ] {
            match parse_python_json(bad) {
                Err(PyJsonError::Decode {
                    message: m,
                    position: p,
                }) => assert_eq!((m.as_str(), p), (message, position), "{bad:?}"),
                other => panic!("{bad:?}: {other:?}"),
            }
        }
    }

    #[test]
    fn strings_escape_like_python() {
        let value = parse(r#""é\u2028\u007f\u001f\"\\\ud834\udd1e""#);
        assert_eq!(
            value.to_json(false),
            "\"é\u{2028}\u{7f}\\u001f\\\"\\\\\u{1d11e}\""
        );
        assert_eq!(
            value.to_json(true),
            "\"\\u00e9\\u2028\\u007f\\u001f\\\"\\\\\\ud834\\udd1e\""
        );
        let escapes = parse(r#""\b\f\n\r\t\/""#);
        assert_eq!(escapes.as_str(), Some("\u{8}\u{c}\n\r\t/"));
        let lone = parse(r#""\ud800x""#);
        assert_eq!(lone.as_str(), Some("\u{fffd}x"));
    }

    #[test]
    fn indented_output_matches_json_dump_indent_2() {
        let value = parse(r#"{"a": [], "b": {}, "c": {"d": 1.0, "e": [1, 2]}}"#);
        assert_eq!(
            value.to_json_indented(2),
            "{\n  \"a\": [],\n  \"b\": {},\n  \"c\": {\n    \"d\": 1.0,\n    \"e\": [\n      1,\n      2\n    ]\n  }\n}"
        );
        // Lists inside lists indent one level deeper each, as json.dumps(indent=2) writes
        // [[1, 2], [], [[3]], {"a": [4]}].
        assert_eq!(
            parse(r#"[[1, 2], [], [[3]], {"a": [4]}]"#).to_json_indented(2),
            "[\n  [\n    1,\n    2\n  ],\n  [],\n  [\n    [\n      3\n    ]\n  ],\n  {\n    \"a\": [\n      4\n    ]\n  }\n]"
        );
    }

    #[test]
    fn python_equality_and_truthiness() {
        assert!(parse("[1.0, true]").py_eq(&parse("[1, 1]")));
        assert!(!parse("[NaN]").py_eq(&parse("[NaN]")));
        assert!(parse("{\"a\": 1, \"b\": 2}").py_eq(&parse("{\"b\": 2, \"a\": 1}")));
        assert!(!parse("\"1\"").py_eq(&parse("1")));
        // `None == None` is true; None equals no number, not even 0.
        assert!(parse("[null, 1]").py_eq(&parse("[null, 1.0]")));
        assert!(!parse("null").py_eq(&parse("0")));
        assert!(parse("100000000000000000000").py_eq(&parse("1e20")));
        assert!(!parse("99999999999999999999").py_eq(&parse("1e20")));
        for falsy in ["null", "false", "0", "0.0", "\"\"", "[]", "{}"] {
            assert!(!parse(falsy).truthy(), "{falsy} is falsy");
        }
        for truthy in ["NaN", "\" \"", "[0]", "-1"] {
            assert!(parse(truthy).truthy(), "{truthy} is truthy");
        }
    }

    #[test]
    fn strings_are_equal_exactly_when_their_text_is() {
        assert!(parse("[\"1\", \"2\"]").py_eq(&parse("[\"1\", \"2\"]")));
        assert!(!parse("\"1\"").py_eq(&parse("\"2\"")));
    }

    #[test]
    fn nested_objects_count_toward_the_recursion_limit_as_lists_do() {
        // CPython's decoder recurses for `{` as for `[`: 1000 nested objects raise RecursionError.
        let deep = format!("{}1{}", "{\"a\": ".repeat(1000), "}".repeat(1000));
        assert!(matches!(
            parse_python_json(&deep),
            Err(PyJsonError::Fatal { .. })
        ));
    }

    #[test]
    fn python_str_of_frame_ids() {
        assert_eq!(parse("2691").py_str(), "2691");
        assert_eq!(parse("2691.0").py_str(), "2691.0");
        assert_eq!(parse("true").py_str(), "True");
        assert_eq!(parse("null").py_str(), "None");
        assert_eq!(parse("[1, \"a\"]").py_str(), "[1, 'a']");
        assert_eq!(
            parse(r#"{"k": [1, "b"], "n": null}"#).py_str(),
            "{'k': [1, 'b'], 'n': None}"
        );
        // Control characters, C1 ones too, are escaped; a quote picks the other quote.
        assert_eq!(
            parse(r#"["a\u0001\u0085\t'"]"#).py_str(),
            r#"["a\x01\x85\t'"]"#
        );
        // A space and DEL's neighbours below it are printable, as Python prints them.
        assert_eq!(parse(r#"["a b~"]"#).py_str(), "['a b~']");
        // With both quotes in it, the string keeps the single quote and escapes its own.
        assert_eq!(parse(r#"["it's \"x\""]"#).py_str(), r#"['it\'s "x"']"#);
    }

    #[test]
    fn dicts_are_equal_with_the_same_keys_and_equal_values() {
        let eq = |a: &str, b: &str| parse(a).py_eq(&parse(b));
        assert!(eq(r#"{"a": 1, "b": [2]}"#, r#"{"b": [2.0], "a": true}"#));
        assert!(!eq(r#"{"a": 1}"#, r#"{"a": 1, "b": 2}"#));
        assert!(!eq(r#"{"a": 1, "b": 2}"#, r#"{"a": 1}"#));
        assert!(!eq(r#"{"a": 1}"#, r#"{"a": 2}"#));
    }

    #[test]
    fn hash_keys_follow_python_dict_identity() {
        let key = |text: &str| PyHashKey::of(&parse(text), 0);
        assert_eq!(key("1"), key("1.0"));
        assert_eq!(key("1"), key("true"));
        assert_ne!(key("1"), key("\"1\""));
        assert_eq!(key("[1]"), Err("list"));
        assert_ne!(
            PyHashKey::of(&parse("NaN"), 1),
            PyHashKey::of(&parse("NaN"), 2)
        );
    }
}
