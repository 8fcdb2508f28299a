//! Welch's unequal-variance two-sample t-test, for comparing per-item scores of two model runs
//! (a probing setting against its baseline).

use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, StudentsT};

/// Which of the two samples a message is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Sample {
    A,
    B,
}

impl std::fmt::Display for Sample {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Sample::A => "a",
            Sample::B => "b",
        })
    }
}

/// A sample value that no test can use.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("sample {sample}, value {index}: {value} is not a finite number")]
pub struct NonFiniteSampleValue {
    pub sample: Sample,
    pub index: usize,
    pub value: f64,
}

/// Why the test statistic has no value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, thiserror::Error)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum WelchUndefined {
    #[error("sample {sample} has {n} values; a variance needs at least 2")]
    TooFewValues { sample: Sample, n: usize },
    #[error("both samples have zero variance, so the standard error is zero")]
    ZeroVariance,
    #[error("no Student-t distribution with {df} degrees of freedom")]
    DegreesOfFreedom { df: f64 },
}

/// Welch's test of mean(a) − mean(b) = 0, two-sided.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WelchComparison {
    /// mean_a − mean_b, when both samples are non-empty.
    pub delta: Option<f64>,
    /// √(s²_a / n_a + s²_b / n_b).
    pub se: Option<f64>,
    pub t: Option<f64>,
    /// Welch–Satterthwaite degrees of freedom.
    pub df: Option<f64>,
    /// Two-sided p-value from Student's t with `df` degrees of freedom.
    pub p: Option<f64>,
    pub n_a: usize,
    pub n_b: usize,
    pub mean_a: Option<f64>,
    pub mean_b: Option<f64>,
    /// Set exactly when `t`, `df` and `p` are `None`.
    pub reason: Option<WelchUndefined>,
}

/// Compares sample `a` with sample `b` (for probing: `a` = setting, `b` = baseline, so
/// `delta` = setting − baseline).
pub fn welch_t_test(a: &[f64], b: &[f64]) -> Result<WelchComparison, NonFiniteSampleValue> {
    check_finite(Sample::A, a)?;
    check_finite(Sample::B, b)?;
    let mean_a = mean(a);
    let mean_b = mean(b);
    let mut comparison = WelchComparison {
        delta: mean_a.zip(mean_b).map(|(mean_a, mean_b)| mean_a - mean_b),
        se: None,
        t: None,
        df: None,
        p: None,
        n_a: a.len(),
        n_b: b.len(),
        mean_a,
        mean_b,
        reason: None,
    };
    let (Some(mean_a), Some(mean_b), Some(delta)) = (mean_a, mean_b, comparison.delta) else {
        comparison.reason = Some(too_few(a, b));
        return Ok(comparison);
    };
    if a.len() < 2 || b.len() < 2 {
        comparison.reason = Some(too_few(a, b));
        return Ok(comparison);
    }
    // Squared standard errors of the two means.
    let share_a = sample_variance(a, mean_a) / a.len() as f64;
    let share_b = sample_variance(b, mean_b) / b.len() as f64;
    let se_squared = share_a + share_b;
    if se_squared == 0.0 {
        comparison.reason = Some(WelchUndefined::ZeroVariance);
        return Ok(comparison);
    }
    let se = se_squared.sqrt();
    let t = delta / se;
    let df = se_squared * se_squared
        / (share_a * share_a / (a.len() - 1) as f64 + share_b * share_b / (b.len() - 1) as f64);
    comparison.se = Some(se);
    match StudentsT::new(0.0, 1.0, df) {
        Ok(distribution) => {
            comparison.t = Some(t);
            comparison.df = Some(df);
            // The survival function keeps precision for large |t| where 1 − cdf would not.
            comparison.p = Some((2.0 * distribution.sf(t.abs())).min(1.0));
        }
        Err(_) => comparison.reason = Some(WelchUndefined::DegreesOfFreedom { df }),
    }
    Ok(comparison)
}

fn too_few(a: &[f64], b: &[f64]) -> WelchUndefined {
    if a.len() < 2 {
        WelchUndefined::TooFewValues {
            sample: Sample::A,
            n: a.len(),
        }
    } else {
        WelchUndefined::TooFewValues {
            sample: Sample::B,
            n: b.len(),
        }
    }
}

fn check_finite(sample: Sample, values: &[f64]) -> Result<(), NonFiniteSampleValue> {
    match values.iter().position(|value| !value.is_finite()) {
        Some(index) => Err(NonFiniteSampleValue {
            sample,
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}

fn mean(values: &[f64]) -> Option<f64> {
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

fn sample_variance(values: &[f64], mean: f64) -> f64 {
    values
        .iter()
        .map(|value| (value - mean) * (value - mean))
        .sum::<f64>()
        / (values.len() - 1) as f64
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Asserts `actual` is defined and within `tolerance` of `expected` (shared by the
    /// statistics tests).
    pub(crate) fn close(actual: Option<f64>, expected: f64, tolerance: f64) {
        let actual = actual.expect("value should be defined");
        assert!(
            (actual - expected).abs() <= tolerance,
            "{actual} differs from {expected}"
        );
    }

    #[test]
    fn hand_computed_case() {
        // a: mean 2.5, s² = 5/3; b: mean 5, s² = 20/3; n = 4 each.
        // se² = 5/12 + 20/12 = 25/12, t = −2.5 / √(25/12) = −√3,
        // df = (25/12)² / ((5/12)² / 3 + (20/12)² / 3) = 75/17.
        // p = 2 P(T > √3) for 75/17 df, by numerical integration of the t density: 0.151580505.
        let result = welch_t_test(&[1.0, 2.0, 3.0, 4.0], &[2.0, 4.0, 6.0, 8.0]).unwrap();
        close(result.delta, -2.5, 1e-15);
        close(result.se, (25.0f64 / 12.0).sqrt(), 1e-15);
        close(result.t, -(3.0f64.sqrt()), 1e-14);
        close(result.df, 75.0 / 17.0, 1e-13);
        close(result.p, 0.151_580_504_845, 1e-9);
        assert_eq!((result.n_a, result.n_b), (4, 4));
        assert_eq!(result.reason, None);
    }

    #[test]
    fn samples_far_from_zero_give_the_same_test_as_near_it() {
        // Moved up by 10⁹, the means are no longer exact: the variances, summed around them,
        // keep the digits that Σ(x − m)(x + m) = Σx² − n·m² would lose (a's s² of 1/3 came
        // out 119.5 that way). Only the means' rounding (10⁻⁷) is left.
        let (a, b) = ([1.0, 2.0, 2.0], [1.0, 1.0, 4.0]);
        let near = welch_t_test(&a, &b).unwrap();
        let far = welch_t_test(&a.map(|v| v + 1e9), &b.map(|v| v + 1e9)).unwrap();
        close(near.se, (10.0f64 / 9.0).sqrt(), 1e-15);
        close(near.df, 100.0 / 41.0, 1e-12);
        close(far.se, near.se.unwrap(), 1e-9);
        close(far.t, near.t.unwrap(), 1e-6);
        close(far.df, near.df.unwrap(), 1e-9);
    }

    #[test]
    fn unequal_sizes_and_variances() {
        // a: mean 0.7, s² = 0.025 (n 5); b: mean 0.25, s² = 0.0025 (n 3).
        // se² = 7/1200, df = 98/19, p by numerical integration: 0.00180117936.
        let result = welch_t_test(&[0.5, 0.7, 0.9, 0.6, 0.8], &[0.2, 0.3, 0.25]).unwrap();
        close(result.delta, 0.45, 1e-15);
        close(result.se, (7.0f64 / 1200.0).sqrt(), 1e-15);
        close(result.df, 98.0 / 19.0, 1e-12);
        close(result.p, 0.001_801_179_356, 1e-10);
    }

    #[test]
    fn one_constant_sample_is_still_defined() {
        let result = welch_t_test(&[1.0, 1.0, 1.0], &[0.0, 1.0, 0.0, 1.0]).unwrap();
        // Only b contributes to se², so df = n_b − 1.
        close(result.df, 3.0, 1e-12);
        assert!(result.p.unwrap() > 0.0 && result.p.unwrap() < 1.0);
    }

    #[test]
    fn degenerate_inputs_have_reasons() {
        let short = welch_t_test(&[1.0], &[1.0, 2.0]).unwrap();
        assert_eq!(
            short.reason,
            Some(WelchUndefined::TooFewValues {
                sample: Sample::A,
                n: 1
            })
        );
        assert_eq!(short.delta, Some(-0.5));
        assert_eq!(short.p, None);
        let empty = welch_t_test(&[1.0, 2.0], &[]).unwrap();
        assert_eq!(empty.delta, None);
        assert_eq!(
            empty.reason,
            Some(WelchUndefined::TooFewValues {
                sample: Sample::B,
                n: 0
            })
        );
        // The second sample is checked on its own: one value is too few, two are enough.
        let single_b = welch_t_test(&[1.0, 2.0, 3.0], &[4.0]).unwrap();
        assert_eq!(
            single_b.reason,
            Some(WelchUndefined::TooFewValues {
                sample: Sample::B,
                n: 1
            })
        );
        assert_eq!((single_b.t, single_b.p), (None, None));
        let pair_b = welch_t_test(&[1.0, 2.0, 3.0], &[4.0, 6.0]).unwrap();
        assert_eq!(pair_b.reason, None);
        assert!(pair_b.p.is_some_and(|p| p > 0.0 && p < 1.0), "{pair_b:?}");
        let flat = welch_t_test(&[1.0, 1.0], &[0.5, 0.5, 0.5]).unwrap();
        assert_eq!(flat.reason, Some(WelchUndefined::ZeroVariance));
        assert_eq!((flat.t, flat.p, flat.se), (None, None, None));
        close(flat.delta, 0.5, 0.0);
    }

    #[test]
    fn non_finite_values_are_refused() {
        let err = welch_t_test(&[1.0, 2.0], &[1.0, f64::INFINITY]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "sample b, value 1: inf is not a finite number"
        );
    }

    #[test]
    fn identical_samples_give_p_one() {
        let result = welch_t_test(&[0.1, 0.4, 0.9], &[0.1, 0.4, 0.9]).unwrap();
        close(result.t, 0.0, 0.0);
        close(result.p, 1.0, 1e-12);
    }
}
