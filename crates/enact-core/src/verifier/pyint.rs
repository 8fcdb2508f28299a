//! Python's unbounded `int`, as far as ENACT's evaluator needs it.
//!
//! Answers can carry integers of any size (a raw JSON list with `100000000000000000000`, a
//! bracketed list with a 30-digit label). ENACT keeps them as Python ints, subtracts 1 from them,
//! re-bases them, compares them and writes them back out digit for digit, so an `i64` is not
//! enough. Values that fit in an `i64` stay in the fast variant; the rest use base-10^9 limbs.

use std::cmp::Ordering;
use std::fmt;

const LIMB_BASE: u64 = 1_000_000_000;

/// An integer with Python semantics: unbounded, compared exactly with floats.
#[derive(Debug, Clone)]
pub enum PyInt {
    Small(i64),
    /// Invariant: the value does not fit in an `i64` (so it is never zero) and the
    /// magnitude has no most-significant zero limbs.
    Big(BigMagnitude),
}

/// Sign and magnitude of a large integer; limbs are base 10^9, least significant first.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BigMagnitude {
    negative: bool,
    limbs: Vec<u32>,
}

impl PyInt {
    pub const ZERO: PyInt = PyInt::Small(0);
    pub const ONE: PyInt = PyInt::Small(1);

    /// Builds a non-negative integer from decimal digit values (0..=9), most significant first.
    pub fn from_decimal_digits(digits: &[u8]) -> PyInt {
        let mut limbs: Vec<u32> = Vec::with_capacity(digits.len() / 9 + 1);
        let mut end = digits.len();
        while end > 0 {
            let start = end.saturating_sub(9);
            let mut limb: u32 = 0;
            for &d in &digits[start..end] {
                limb = limb * 10 + u32::from(d);
            }
            limbs.push(limb);
            end = start;
        }
        PyInt::from_sign_magnitude(false, limbs)
    }

    /// Parses an optionally `-`-signed run of ASCII digits (the JSON integer grammar).
    pub fn parse_ascii(text: &str) -> Option<PyInt> {
        let (negative, digits) = match text.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, text),
        };
        if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        let values: Vec<u8> = digits.bytes().map(|b| b - b'0').collect();
        let magnitude = PyInt::from_decimal_digits(&values);
        Some(if negative {
            magnitude.negate()
        } else {
            magnitude
        })
    }

    /// The exact integer value of an integral, finite float.
    pub fn from_integral_f64(value: f64) -> Option<PyInt> {
        if !value.is_finite() || value.fract() != 0.0 {
            return None;
        }
        if value.abs() < 9.0e15 {
            // Exactly representable and well inside the i64 range.
            return Some(PyInt::Small(value as i64));
        }
        // `{:.0}` prints the exact decimal expansion of the binary value.
        PyInt::parse_ascii(&format!("{value:.0}"))
    }

    pub fn to_i64(&self) -> Option<i64> {
        match self {
            PyInt::Small(v) => Some(*v),
            PyInt::Big(_) => None,
        }
    }

    pub fn is_zero(&self) -> bool {
        matches!(self, PyInt::Small(0))
    }

    pub fn is_negative(&self) -> bool {
        match self {
            PyInt::Small(v) => *v < 0,
            PyInt::Big(m) => m.negative,
        }
    }

    pub fn negate(&self) -> PyInt {
        match self {
            PyInt::Small(v) => match v.checked_neg() {
                Some(n) => PyInt::Small(n),
                None => {
                    let (neg, limbs) = self.sign_magnitude();
                    PyInt::from_sign_magnitude(!neg, limbs)
                }
            },
            PyInt::Big(m) => PyInt::from_sign_magnitude(!m.negative, m.limbs.clone()),
        }
    }

    pub fn add(&self, other: &PyInt) -> PyInt {
        if let (PyInt::Small(a), PyInt::Small(b)) = (self, other)
            && let Some(sum) = a.checked_add(*b)
        {
            return PyInt::Small(sum);
        }
        let (an, am) = self.sign_magnitude();
        let (bn, bm) = other.sign_magnitude();
        if an == bn {
            return PyInt::from_sign_magnitude(an, add_magnitudes(&am, &bm));
        }
        match cmp_magnitudes(&am, &bm) {
            Ordering::Equal => PyInt::ZERO,
            Ordering::Greater => PyInt::from_sign_magnitude(an, sub_magnitudes(&am, &bm)),
            Ordering::Less => PyInt::from_sign_magnitude(bn, sub_magnitudes(&bm, &am)),
        }
    }

    pub fn sub(&self, other: &PyInt) -> PyInt {
        self.add(&other.negate())
    }

    /// Exact comparison with a float, as Python's `int < float` does it; `None` for NaN.
    pub fn cmp_f64(&self, other: f64) -> Option<Ordering> {
        if other.is_nan() {
            return None;
        }
        if other == f64::INFINITY {
            return Some(Ordering::Less);
        }
        if other == f64::NEG_INFINITY {
            return Some(Ordering::Greater);
        }
        let floor = other.floor();
        let floor_int = PyInt::from_integral_f64(floor)?;
        match self.cmp(&floor_int) {
            Ordering::Equal if other != floor => Some(Ordering::Less),
            ordering => Some(ordering),
        }
    }

    fn sign_magnitude(&self) -> (bool, Vec<u32>) {
        match self {
            PyInt::Small(v) => {
                let negative = *v < 0;
                let mut rest = v.unsigned_abs();
                let mut limbs = Vec::with_capacity(3);
                while rest > 0 {
                    limbs.push((rest % LIMB_BASE) as u32);
                    rest /= LIMB_BASE;
                }
                (negative, limbs)
            }
            PyInt::Big(m) => (m.negative, m.limbs.clone()),
        }
    }

    fn from_sign_magnitude(negative: bool, mut limbs: Vec<u32>) -> PyInt {
        while limbs.last() == Some(&0) {
            limbs.pop();
        }
        if limbs.len() <= 3 {
            let mut value: i128 = 0;
            for &limb in limbs.iter().rev() {
                value = value * i128::from(LIMB_BASE as u32) + i128::from(limb);
            }
            if negative {
                value = -value;
            }
            if let Ok(small) = i64::try_from(value) {
                return PyInt::Small(small);
            }
        }
        PyInt::Big(BigMagnitude { negative, limbs })
    }
}

fn cmp_magnitudes(a: &[u32], b: &[u32]) -> Ordering {
    a.len()
        .cmp(&b.len())
        .then_with(|| a.iter().rev().cmp(b.iter().rev()))
}

fn add_magnitudes(a: &[u32], b: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(a.len().max(b.len()) + 1);
    let mut carry = 0u64;
    for i in 0..a.len().max(b.len()) {
        let sum = u64::from(a.get(i).copied().unwrap_or(0))
            + u64::from(b.get(i).copied().unwrap_or(0))
            + carry;
        out.push((sum % LIMB_BASE) as u32);
        carry = sum / LIMB_BASE;
    }
    if carry > 0 {
        out.push(carry as u32);
    }
    out
}

/// `a - b` for magnitudes with `a >= b`.
fn sub_magnitudes(a: &[u32], b: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(a.len());
    let mut borrow = 0i64;
    for (i, &limb) in a.iter().enumerate() {
        let mut diff = i64::from(limb) - i64::from(b.get(i).copied().unwrap_or(0)) - borrow;
        if diff < 0 {
            diff += LIMB_BASE as i64;
            borrow = 1;
        } else {
            borrow = 0;
        }
        out.push(diff as u32);
    }
    out
}

impl PartialEq for PyInt {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for PyInt {}

impl PartialOrd for PyInt {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for PyInt {
    fn cmp(&self, other: &Self) -> Ordering {
        match (self, other) {
            (PyInt::Small(a), PyInt::Small(b)) => a.cmp(b),
            _ => {
                let (an, am) = self.sign_magnitude();
                let (bn, bm) = other.sign_magnitude();
                match (an, bn) {
                    (false, true) => Ordering::Greater,
                    (true, false) => Ordering::Less,
                    (false, false) => cmp_magnitudes(&am, &bm),
                    (true, true) => cmp_magnitudes(&bm, &am),
                }
            }
        }
    }
}

impl fmt::Display for PyInt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PyInt::Small(v) => write!(f, "{v}"),
            PyInt::Big(m) => {
                if m.negative {
                    f.write_str("-")?;
                }
                let mut limbs = m.limbs.iter().rev();
                if let Some(first) = limbs.next() {
                    write!(f, "{first}")?;
                }
                for limb in limbs {
                    write!(f, "{limb:09}")?;
                }
                Ok(())
            }
        }
    }
}

impl From<i64> for PyInt {
    fn from(v: i64) -> Self {
        PyInt::Small(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn big(text: &str) -> PyInt {
        PyInt::parse_ascii(text).expect("test literal")
    }

    #[test]
    fn zero_is_zero_and_not_negative_whatever_its_sign() {
        assert!(!PyInt::Small(0).is_negative());
        assert!(PyInt::Small(0).is_zero());
        assert!(PyInt::Small(-1).is_negative());
        assert!(!PyInt::Small(1).is_negative());
        assert!(big("-0").is_zero() && !big("-0").is_negative());
        assert!(big("-123456789012345678901234567890").is_negative());
    }

    /// Only an optionally signed, non-empty run of ASCII digits is an integer.
    #[test]
    fn parse_ascii_takes_digits_and_nothing_else() {
        assert_eq!(PyInt::parse_ascii("-42"), Some(PyInt::Small(-42)));
        for text in ["", "-", "1a", "a1", "-x", "1.5", " 1"] {
            assert_eq!(PyInt::parse_ascii(text), None, "{text:?}");
        }
    }

    #[test]
    fn only_integral_finite_floats_are_integers() {
        assert_eq!(PyInt::from_integral_f64(-3.0), Some(PyInt::Small(-3)));
        for value in [1.5, -2.5, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(PyInt::from_integral_f64(value), None, "{value}");
        }
    }

    #[test]
    fn small_values_stay_small_and_big_values_print_exactly() {
        assert_eq!(big("42").to_i64(), Some(42));
        assert_eq!(big("-0").to_i64(), Some(0));
        let huge = big("100000000000000000000");
        assert!(huge.to_i64().is_none());
        assert_eq!(huge.to_string(), "100000000000000000000");
        assert_eq!(
            big("-123456789012345678901234567890").to_string(),
            "-123456789012345678901234567890"
        );
        assert_eq!(big("9223372036854775807").to_i64(), Some(i64::MAX));
        assert!(big("9223372036854775808").to_i64().is_none());
        assert_eq!(big("-9223372036854775808").to_i64(), Some(i64::MIN));
    }

    #[test]
    fn arithmetic_crosses_the_i64_boundary_both_ways() {
        let max = PyInt::Small(i64::MAX);
        let over = max.add(&PyInt::ONE);
        assert_eq!(over.to_string(), "9223372036854775808");
        assert_eq!(over.sub(&PyInt::ONE).to_i64(), Some(i64::MAX));
        let huge = big("100000000000000000000");
        assert_eq!(huge.sub(&PyInt::ONE).to_string(), "99999999999999999999");
        // A carry out of the top limb (10⁹ a limb) makes a limb of its own.
        let nines = big(&"9".repeat(27));
        assert_eq!(
            nines.add(&PyInt::ONE).to_string(),
            format!("1{}", "0".repeat(27))
        );
        assert_eq!(
            nines.add(&nines).to_string(),
            format!("1{}8", "9".repeat(26))
        );
        assert_eq!(huge.sub(&huge).to_i64(), Some(0));
        assert_eq!(
            PyInt::Small(5).sub(&huge).to_string(),
            "-99999999999999999995"
        );
        assert_eq!(
            PyInt::Small(i64::MIN).negate().to_string(),
            "9223372036854775808"
        );
    }

    #[test]
    fn ordering_and_float_comparison_are_exact() {
        let huge = big("100000000000000000000");
        assert!(huge > PyInt::Small(i64::MAX));
        assert!(huge.negate() < PyInt::Small(i64::MIN));
        assert_eq!(huge.cmp_f64(1e20), Some(Ordering::Equal));
        assert_eq!(
            big("99999999999999999999").cmp_f64(1e20),
            Some(Ordering::Less)
        );
        assert_eq!(PyInt::Small(1).cmp_f64(1.5), Some(Ordering::Less));
        assert_eq!(PyInt::Small(2).cmp_f64(1.5), Some(Ordering::Greater));
        assert_eq!(PyInt::Small(-2).cmp_f64(-1.5), Some(Ordering::Less));
        assert_eq!(PyInt::Small(0).cmp_f64(f64::NAN), None);
        assert_eq!(huge.cmp_f64(f64::INFINITY), Some(Ordering::Less));
        // Equality is the ordering's: equal values are equal, others are not.
        assert_eq!(huge, big("100000000000000000000"));
        assert_ne!(huge, huge.negate());
        assert_ne!(huge, PyInt::Small(i64::MAX));
        assert_ne!(PyInt::Small(1), PyInt::Small(2));
    }

    #[test]
    fn decimal_digits_build_values() {
        assert_eq!(PyInt::from_decimal_digits(&[0, 0, 7]).to_i64(), Some(7));
        assert_eq!(PyInt::from_decimal_digits(&[]).to_i64(), Some(0));
        let digits = [1u8; 30];
        assert_eq!(
            PyInt::from_decimal_digits(&digits).to_string(),
            "1".repeat(30)
        );
    }
}
