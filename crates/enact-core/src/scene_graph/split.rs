//! Splitting `scene_graph_0.json` into its frame records without parsing them: a scan over
//! the bytes finds where each `"frame": {record}` entry of the top-level object starts and
//! ends, so each record can be parsed from a slice (much faster than through a reader), or
//! not parsed at all, and a file of any size is read in bounded memory.
//!
//! The scan checks the top level (an object, keys as strings, `:` and `,` in their places) and
//! only counts brackets inside a record: whether a record is well-formed JSON is for whoever
//! reads it to find out (with the record's position, for the error).

use std::io::Read;

/// How much is read from the file at a time.
const CHUNK: usize = 1 << 20;

/// A syntax error in the top level of the file, with its 1-based position.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct SplitError {
    pub message: String,
    pub line: usize,
    pub column: usize,
    /// The frame whose record was being scanned, when the file ends inside one.
    pub frame: Option<String>,
}

/// Where a record's text starts in the file (1-based), to place errors found inside it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Position {
    pub line: usize,
    pub column: usize,
}

impl Position {
    /// The file position of an error that `serde_json` reports at `line`/`column` of a record
    /// parsed on its own from this position.
    pub fn of_error_in_record(self, err: &serde_json::Error) -> Position {
        if err.line() <= 1 {
            Position {
                line: self.line,
                column: self.column + err.column().saturating_sub(1),
            }
        } else {
            Position {
                line: self.line + err.line() - 1,
                column: err.column(),
            }
        }
    }
}

/// One entry of the top-level object: the frame key as written and the record's JSON text.
pub(crate) struct RawRecord<'a> {
    pub key: String,
    pub json: &'a [u8],
    pub at: Position,
    /// Whether the text is the same as the record before's, byte for byte.
    pub repeats_previous: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    /// Before the opening `{`.
    Start,
    /// After `{`: a key or `}`.
    FirstKey,
    /// After a record: `,` or `}`.
    AfterRecord,
    /// After the closing `}`: only whitespace may follow.
    Done,
}

/// Reads the records of a scene-graph object one by one from `reader`.
pub(crate) struct RecordSplitter<R> {
    reader: R,
    buf: Vec<u8>,
    /// Bytes of `buf` already consumed.
    pos: usize,
    eof: bool,
    /// Position of `buf[pos]` in the file.
    line: usize,
    column: usize,
    state: State,
    /// The text of the record before.
    previous: Vec<u8>,
}

impl<R: Read> RecordSplitter<R> {
    pub fn new(reader: R) -> Self {
        RecordSplitter {
            reader,
            buf: Vec::with_capacity(CHUNK),
            pos: 0,
            eof: false,
            line: 1,
            column: 1,
            state: State::Start,
            previous: Vec::new(),
        }
    }

    /// The next record, or `None` after the closing brace (and nothing but whitespace after it).
    pub fn next_record(&mut self) -> Result<Option<RawRecord<'_>>, SplitError> {
        loop {
            let Some(byte) = self.next_token()? else {
                return match self.state {
                    State::Done => Ok(None),
                    _ => Err(self.error("EOF while parsing an object", None)),
                };
            };
            match (self.state, byte) {
                (State::Start, b'{') => {
                    self.advance(1);
                    self.state = State::FirstKey;
                }
                (State::Start, _) => {
                    return Err(self.error("expected an object keyed by frame id", None));
                }
                (State::FirstKey | State::AfterRecord, b'}') => {
                    self.advance(1);
                    self.state = State::Done;
                }
                (State::AfterRecord, b',') => {
                    self.advance(1);
                    self.next_token()?;
                    return self.entry().map(Some);
                }
                (State::FirstKey, b'"') => return self.entry().map(Some),
                (State::FirstKey, _) => return Err(self.error("expected a frame key", None)),
                (State::AfterRecord, _) => {
                    return Err(self.error("expected `,` or `}` after a record", None));
                }
                (State::Done, _) => {
                    return Err(self.error("trailing characters after the object", None));
                }
            }
        }
    }

    /// Reads `"key": value` starting at the key's opening quote.
    fn entry(&mut self) -> Result<RawRecord<'_>, SplitError> {
        if self.peek() != Some(b'"') {
            return Err(self.error("expected a frame key", None));
        }
        let Some(key_end) = self.complete(|bytes| string_end(bytes, 0))? else {
            return Err(self.error("EOF while parsing a frame key", None));
        };
        let key: String = serde_json::from_slice(&self.buf[self.pos..self.pos + key_end])
            .map_err(|e| self.error(&format!("bad frame key: {e}"), None))?;
        self.advance(key_end);
        if self.next_token()? != Some(b':') {
            return Err(self.error("expected `:` after a frame key", Some(&key)));
        }
        self.advance(1);
        if self.next_token()?.is_none() {
            return Err(self.error("EOF while parsing a record", Some(&key)));
        }
        let at = Position {
            line: self.line,
            column: self.column,
        };
        let repeats_previous = self.repeats_previous()?;
        let len = if repeats_previous {
            self.previous.len()
        } else {
            let Some(len) = self.complete(value_end)? else {
                return Err(self.error("EOF while parsing a record", Some(&key)));
            };
            self.previous.clear();
            self.previous
                .extend_from_slice(&self.buf[self.pos..self.pos + len]);
            len
        };
        let start = self.pos;
        self.advance(len);
        self.state = State::AfterRecord;
        Ok(RawRecord {
            key,
            json: &self.buf[start..start + len],
            at,
            repeats_previous,
        })
    }

    /// Whether the value at `pos` is the record before's text again. ENACT's replays write
    /// every frame in full and a scene often holds still for many frames: comparing bytes is
    /// much cheaper than scanning them. The previous text is a whole JSON value, so when the
    /// input starts with it and a delimiter follows, the value here ends exactly there.
    fn repeats_previous(&mut self) -> Result<bool, SplitError> {
        let n = self.previous.len();
        if n == 0 {
            return Ok(false);
        }
        while self.buf.len() - self.pos <= n {
            if !self.fill()? {
                return Ok(false);
            }
        }
        let here = &self.buf[self.pos..];
        Ok(here[..n] == self.previous[..]
            && matches!(here[n], b',' | b'}' | b' ' | b'\t' | b'\r' | b'\n'))
    }

    /// Skips whitespace and returns the next byte without consuming it (`None` at the end).
    fn next_token(&mut self) -> Result<Option<u8>, SplitError> {
        loop {
            while let Some(&b) = self.buf.get(self.pos) {
                if matches!(b, b' ' | b'\t' | b'\r' | b'\n') {
                    self.advance(1);
                } else {
                    return Ok(Some(b));
                }
            }
            if !self.fill()? {
                return Ok(None);
            }
        }
    }

    fn peek(&self) -> Option<u8> {
        self.buf.get(self.pos).copied()
    }

    /// The length of the item at `pos` as `end` measures it in the buffered bytes, reading
    /// more until it is complete; `None` if the file ends first.
    fn complete(
        &mut self,
        end: impl Fn(&[u8]) -> Option<usize>,
    ) -> Result<Option<usize>, SplitError> {
        loop {
            if let Some(len) = end(&self.buf[self.pos..]) {
                return Ok(Some(len));
            }
            if !self.fill()? {
                return Ok(None);
            }
        }
    }

    /// Reads another chunk, dropping what was consumed; `false` at the end of the file.
    fn fill(&mut self) -> Result<bool, SplitError> {
        if self.eof {
            return Ok(false);
        }
        if self.pos > 0 {
            self.buf.drain(..self.pos);
            self.pos = 0;
        }
        // Growing by what is held already keeps a record of any size to a few reads (and
        // rescans of it, see `complete`): the work stays linear in its size.
        let have = self.buf.len();
        self.buf.resize(have + CHUNK.max(have), 0);
        let read = loop {
            match self.reader.read(&mut self.buf[have..]) {
                Ok(n) => break n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => {
                    self.buf.truncate(have);
                    return Err(self.error(&format!("read failed: {e}"), None));
                }
            }
        };
        self.buf.truncate(have + read);
        if read == 0 {
            self.eof = true;
        }
        Ok(read > 0)
    }

    /// Consumes `n` bytes, keeping the line and column of the next one.
    fn advance(&mut self, n: usize) {
        let consumed = &self.buf[self.pos..self.pos + n];
        match memchr::memrchr(b'\n', consumed) {
            Some(last) => {
                self.line += memchr::memchr_iter(b'\n', consumed).count();
                self.column = n - last;
            }
            None => self.column += n,
        }
        self.pos += n;
    }

    fn error(&self, message: &str, frame: Option<&str>) -> SplitError {
        SplitError {
            message: message.to_owned(),
            line: self.line,
            column: self.column,
            frame: frame.map(str::to_owned),
        }
    }
}

/// The length of the string starting with the quote at `bytes[from]`, up to and including
/// its closing quote, or `None` if it does not end within `bytes`.
fn string_end(bytes: &[u8], from: usize) -> Option<usize> {
    let mut i = from + 1;
    loop {
        i += memchr::memchr2(b'"', b'\\', bytes.get(i..)?)?;
        match bytes[i] {
            b'\\' => i += 2,
            _ => return Some(i + 1 - from),
        }
    }
}

/// The length of the JSON value at the start of `bytes` (an object, array, string or scalar)
/// by counting its brackets outside strings, or `None` if it does not end within `bytes`. A
/// scalar ends at the next `,`, `}`, `]` or whitespace, which must then be present.
fn value_end(bytes: &[u8]) -> Option<usize> {
    match *bytes.first()? {
        // In well-formed JSON the value's own kind of bracket balances by itself, so only
        // that kind is counted (and found with `memchr3`, which is what makes this fast).
        open @ (b'{' | b'[') => {
            let close = if open == b'{' { b'}' } else { b']' };
            let mut depth = 0usize;
            let mut i = 0;
            loop {
                i += memchr::memchr3(b'"', open, close, bytes.get(i..)?)?;
                match bytes[i] {
                    b'"' => i += string_end(bytes, i)?,
                    b if b == open => {
                        depth += 1;
                        i += 1;
                    }
                    _ => {
                        depth -= 1;
                        i += 1;
                        if depth == 0 {
                            return Some(i);
                        }
                    }
                }
            }
        }
        b'"' => string_end(bytes, 0),
        _ => bytes
            .iter()
            .position(|b| matches!(b, b',' | b'}' | b']' | b' ' | b'\t' | b'\r' | b'\n')),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn split(text: &str) -> Result<Vec<(String, String, usize, usize)>, SplitError> {
        // A tiny reader buffer would not test more: chunks are 1 MiB; records crossing a chunk
        // boundary are tested with `slow` below.
        let mut s = RecordSplitter::new(text.as_bytes());
        let mut out = Vec::new();
        while let Some(r) = s.next_record()? {
            out.push((
                r.key,
                String::from_utf8(r.json.to_vec()).unwrap(),
                r.at.line,
                r.at.column,
            ));
        }
        Ok(out)
    }

    /// A reader that hands out one byte at a time, so every item crosses a read boundary.
    struct Slow<'a>(&'a [u8]);

    impl Read for Slow<'_> {
        fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
            match (self.0.first(), out.first_mut()) {
                (Some(&b), Some(slot)) => {
                    *slot = b;
                    self.0 = &self.0[1..];
                    Ok(1)
                }
                _ => Ok(0),
            }
        }
    }

    #[test]
    fn splits_records_with_their_positions() {
        let text = "{\"0\": {\"a\": \"}{\\\"\", \"b\": [1, {\"c\": 2}]},\n \"1\" :{\"type\": \"empty\"} ,\"2\":3 }\n";
        let got = split(text).unwrap();
        assert_eq!(
            got,
            vec![
                (
                    "0".into(),
                    "{\"a\": \"}{\\\"\", \"b\": [1, {\"c\": 2}]}".into(),
                    1,
                    7
                ),
                ("1".into(), "{\"type\": \"empty\"}".into(), 2, 7),
                ("2".into(), "3".into(), 2, 30),
            ]
        );
        let mut slow = RecordSplitter::new(Slow(text.as_bytes()));
        let mut keys = Vec::new();
        while let Some(r) = slow.next_record().unwrap() {
            keys.push((r.key, r.json.len()));
        }
        assert_eq!(
            keys,
            vec![("0".into(), 33), ("1".into(), 17), ("2".into(), 1)]
        );
        assert_eq!(split("{}").unwrap(), vec![]);
        // Records larger than a read, on both sides of one.
        let big = format!("{{\"s\": \"{}\"}}", "x".repeat(3 * CHUNK));
        let text = format!("{{\"0\": 1, \"1\": {big}, \"2\": {big}, \"3\": 2}}");
        let got = split(&text).unwrap();
        assert_eq!(got.len(), 4);
        assert_eq!((got[1].1.len(), got[2].1.len()), (big.len(), big.len()));
        assert_eq!(got[3].1, "2");
        assert_eq!(split(" { } ").unwrap(), vec![]);
    }

    #[test]
    fn a_record_repeating_the_one_before_is_told_apart() {
        let text = "{\"0\": {\"a\": [1]}, \"1\": {\"a\": [1]}\n, \"2\": {\"a\": [1]}, \"3\": 1, \"4\": 12, \"5\": 12}";
        for slow in [false, true] {
            let reader: Box<dyn Read> = if slow {
                Box::new(Slow(text.as_bytes()))
            } else {
                Box::new(text.as_bytes())
            };
            let mut s = RecordSplitter::new(reader);
            let mut got = Vec::new();
            while let Some(r) = s.next_record().unwrap() {
                got.push((
                    r.key,
                    String::from_utf8(r.json.to_vec()).unwrap(),
                    r.repeats_previous,
                ));
            }
            let want = [
                ("0", "{\"a\": [1]}", false),
                ("1", "{\"a\": [1]}", true),
                ("2", "{\"a\": [1]}", true),
                ("3", "1", false),
                // "1" is a prefix of "12" but not the whole value.
                ("4", "12", false),
                ("5", "12", true),
            ];
            let want: Vec<(String, String, bool)> = want
                .iter()
                .map(|(k, j, r)| (k.to_string(), j.to_string(), *r))
                .collect();
            assert_eq!(got, want, "slow reader: {slow}");
        }
    }

    #[test]
    fn top_level_mistakes_are_placed() {
        let e = split("[1]").unwrap_err();
        assert_eq!((e.line, e.column), (1, 1));
        let e = split("{\"0\": {} \"1\": {}}").unwrap_err();
        assert!(e.message.contains("expected `,`"), "{e:?}");
        assert_eq!((e.line, e.column), (1, 10));
        let e = split("{\"0\" {}}").unwrap_err();
        assert!(e.message.contains("`:`") && e.frame.as_deref() == Some("0"));
        let e = split("{\"0\": {\"nodes\": [").unwrap_err();
        assert!(e.message.contains("EOF") && e.frame.as_deref() == Some("0"));
        let e = split("{\"0\": {}} x").unwrap_err();
        assert!(e.message.contains("trailing"));
        let e = split("{\"0\": {}").unwrap_err();
        assert!(e.message.contains("EOF"));
        let e = split("{7: {}}").unwrap_err();
        assert!(e.message.contains("frame key"));
    }

    /// A reader that fails after handing out its bytes.
    struct Failing<'a>(&'a [u8]);

    impl Read for Failing<'_> {
        fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
            if self.0.is_empty() {
                return Err(std::io::Error::other("disk gone"));
            }
            let n = self.0.len().min(out.len());
            out[..n].copy_from_slice(&self.0[..n]);
            self.0 = &self.0[n..];
            Ok(n)
        }
    }

    #[test]
    fn a_read_failure_inside_a_record_is_not_called_the_end_of_the_file() {
        let mut s = RecordSplitter::new(Failing(b"{\"0\": {\"nodes\": ["));
        let e = s.next_record().err().expect("the read fails");
        assert!(e.message.contains("disk gone"), "{e:?}");
    }

    #[test]
    fn errors_inside_a_record_map_to_file_positions() {
        let at = Position { line: 3, column: 8 };
        let first_line = serde_json::from_str::<serde_json::Value>("{\"a\" 1}").unwrap_err();
        assert_eq!(
            at.of_error_in_record(&first_line),
            Position {
                line: 3,
                column: 8 + first_line.column() - 1
            }
        );
        let later = serde_json::from_str::<serde_json::Value>("{\n\"a\" 1}").unwrap_err();
        assert_eq!(
            at.of_error_in_record(&later),
            Position {
                line: 4,
                column: later.column()
            }
        );
    }
}
