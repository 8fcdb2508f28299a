//! Python 3.11's notion of a digit and of whitespace (Unicode 14.0), for exact answer parsing.
//!
//! ENACT ran under Python 3.11, whose `re` module matches `\d` against Unicode category Nd and
//! `\s` (like `str.strip()`) against `Py_UNICODE_ISSPACE`. Rust's `char::is_whitespace` misses
//! U+001C..U+001F, and the `regex` crate follows a newer Unicode version with more Nd digits, so
//! both sets are spelled out here as Python 3.11 has them.

/// ENACT quirk: the first code point (the digit zero) of every run of ten Unicode decimal digits
/// known to Python 3.11. `\d` matched any of them, and `int()` read them by their value.
const PY311_DIGIT_ZEROS: [u32; 66] = [
    0x30, 0x660, 0x6f0, 0x7c0, 0x966, 0x9e6, 0xa66, 0xae6, 0xb66, 0xbe6, 0xc66, 0xce6, 0xd66,
    0xde6, 0xe50, 0xed0, 0xf20, 0x1040, 0x1090, 0x17e0, 0x1810, 0x1946, 0x19d0, 0x1a80, 0x1a90,
    0x1b50, 0x1bb0, 0x1c40, 0x1c50, 0xa620, 0xa8d0, 0xa900, 0xa9d0, 0xa9f0, 0xaa50, 0xabf0, 0xff10,
    0x104a0, 0x10d30, 0x11066, 0x110f0, 0x11136, 0x111d0, 0x112f0, 0x11450, 0x114d0, 0x11650,
    0x116c0, 0x11730, 0x118e0, 0x11950, 0x11c50, 0x11d50, 0x11da0, 0x16a60, 0x16ac0, 0x16b50,
    0x1d7ce, 0x1d7d8, 0x1d7e2, 0x1d7ec, 0x1d7f6, 0x1e140, 0x1e2f0, 0x1e950, 0x1fbf0,
];

/// ENACT quirk: the characters Python 3.11 treats as whitespace in `re`'s `\s` and in
/// `str.strip()` (they are the same set).
const PY311_SPACES: [char; 29] = [
    '\t', '\n', '\u{b}', '\u{c}', '\r', '\u{1c}', '\u{1d}', '\u{1e}', '\u{1f}', ' ', '\u{85}',
    '\u{a0}', '\u{1680}', '\u{2000}', '\u{2001}', '\u{2002}', '\u{2003}', '\u{2004}', '\u{2005}',
    '\u{2006}', '\u{2007}', '\u{2008}', '\u{2009}', '\u{200a}', '\u{2028}', '\u{2029}', '\u{202f}',
    '\u{205f}', '\u{3000}',
];

/// The decimal value of `c` if Python 3.11's `\d` matches it.
pub fn py_digit_value(c: char) -> Option<u8> {
    let cp = u32::from(c);
    if c.is_ascii() {
        return c.to_digit(10).map(|d| d as u8);
    }
    let run = match PY311_DIGIT_ZEROS.binary_search(&cp) {
        Ok(i) => i,
        Err(0) => return None,
        Err(i) => i - 1,
    };
    let offset = cp - PY311_DIGIT_ZEROS[run];
    (offset < 10).then_some(offset as u8)
}

/// Whether Python 3.11's `\s` (and `str.isspace`) accepts `c`.
pub fn is_py_space(c: char) -> bool {
    PY311_SPACES.contains(&c)
}

/// `str.strip()` with no arguments, as Python 3.11 does it.
pub fn py_strip(text: &str) -> &str {
    text.trim_matches(is_py_space)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn digits_include_full_width_and_other_scripts_with_their_values() {
        assert_eq!(py_digit_value('7'), Some(7));
        assert_eq!(py_digit_value('\u{ff12}'), Some(2)); // full-width 2
        assert_eq!(py_digit_value('\u{663}'), Some(3)); // Arabic-Indic 3
        assert_eq!(py_digit_value('\u{1d7d9}'), Some(1)); // mathematical double-struck 1
        assert_eq!(py_digit_value('\u{1d7ff}'), Some(9)); // last mathematical digit
        assert_eq!(py_digit_value('a'), None);
        assert_eq!(py_digit_value('\u{b2}'), None); // superscript two is No, not Nd
        // Kawi digits arrived in Unicode 15, after Python 3.11.
        assert_eq!(py_digit_value('\u{11f50}'), None);
    }

    #[test]
    fn whitespace_matches_python_not_rust() {
        assert!(is_py_space('\u{1c}'));
        assert!(!'\u{1c}'.is_whitespace());
        assert!(is_py_space('\u{3000}'));
        assert!(!is_py_space('\u{200b}'));
        assert_eq!(py_strip("\u{1f} {\"a\": 1}\u{85}\n"), "{\"a\": 1}");
    }
}
