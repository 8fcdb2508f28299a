//! The paired tests a study reports beside the paper's unpaired Welch test: because a variant
//! keeps the baseline's items, each item gives one difference (variant − baseline), and the
//! item-to-item spread that Welch's test counts as noise cancels out.
//!
//! - [`paired_t_test`]: Student's t on the mean difference, n − 1 degrees of freedom.
//! - [`sign_test`]: the exact two-sided binomial sign test on the differences' signs (ties
//!   dropped), which assumes nothing about their distribution.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use statrs::distribution::{Binomial, ContinuousCDF, DiscreteCDF, StudentsT};

/// Why the paired t statistic has no value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, thiserror::Error)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PairedUndefined {
    #[error("{n} paired items; a variance needs at least 2")]
    TooFewPairs { n: usize },
    #[error("every paired difference is the same ({difference}), so the standard error is zero")]
    ConstantDifference { difference: f64 },
}

/// Student's paired t-test of mean(variant − baseline) = 0, two-sided.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PairedT {
    pub n: usize,
    /// Mean of the per-item differences (equal to Δ of the means over the same items).
    pub mean_difference: Option<f64>,
    /// Standard error of the mean difference, sd / √n.
    pub se: Option<f64>,
    pub t: Option<f64>,
    pub df: Option<f64>,
    pub p: Option<f64>,
    /// Set exactly when `t`, `df` and `p` are `None`.
    pub reason: Option<PairedUndefined>,
}

/// The exact sign test on the differences' signs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SignTest {
    /// Items where the variant scored higher.
    pub positive: usize,
    /// Items where the variant scored lower.
    pub negative: usize,
    /// Items with equal scores: left out of the test.
    pub ties: usize,
    /// Two-sided: 2 · P(X ≤ min(positive, negative)) for X ~ Binomial(positive + negative, ½),
    /// at most 1. With no untied item it is 1: nothing departs from the null.
    pub p: f64,
}

/// Student's paired t-test on per-item differences. The caller checks the values are finite.
pub fn paired_t_test(differences: &[f64]) -> PairedT {
    let n = differences.len();
    let mean = (n > 0).then(|| differences.iter().sum::<f64>() / n as f64);
    let mut result = PairedT {
        n,
        mean_difference: mean,
        se: None,
        t: None,
        df: None,
        p: None,
        reason: None,
    };
    let Some(mean) = mean.filter(|_| n >= 2) else {
        result.reason = Some(PairedUndefined::TooFewPairs { n });
        return result;
    };
    let variance = differences
        .iter()
        .map(|d| (d - mean) * (d - mean))
        .sum::<f64>()
        / (n - 1) as f64;
    // Differences equal up to rounding (sums of the same floats in another order) are equal.
    if variance <= f64::EPSILON * f64::EPSILON * mean.abs().max(1.0) {
        result.reason = Some(PairedUndefined::ConstantDifference { difference: mean });
        return result;
    }
    let se = (variance / n as f64).sqrt();
    let t = mean / se;
    let df = (n - 1) as f64;
    let distribution = StudentsT::new(0.0, 1.0, df).expect("n ≥ 2 gives df ≥ 1");
    result.se = Some(se);
    result.t = Some(t);
    result.df = Some(df);
    // The survival function keeps precision for large |t| where 1 − cdf would not.
    result.p = Some((2.0 * distribution.sf(t.abs())).min(1.0));
    result
}

/// The exact two-sided sign test.
pub fn sign_test(differences: &[f64]) -> SignTest {
    let positive = differences.iter().filter(|d| **d > 0.0).count();
    let negative = differences.iter().filter(|d| **d < 0.0).count();
    let ties = differences.len() - positive - negative;
    let untied = (positive + negative) as u64;
    let p = if untied == 0 {
        1.0
    } else {
        let binomial = Binomial::new(0.5, untied).expect("p = ½ is a probability");
        (2.0 * binomial.cdf(positive.min(negative) as u64)).min(1.0)
    };
    SignTest {
        positive,
        negative,
        ties,
        p,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::agreement::welch::tests::close;

    #[test]
    fn hand_computed_paired_t() {
        // d = 1, 2, 3, 4, 5, 3: mean 3, s² = (4+1+0+1+4+0)/5 = 2, se = √(2/6) = √(1/3),
        // t = 3√3, df 5. With θ = atan(t/√5), the closed form for 5 degrees of freedom gives
        // p = 1 − (2/π)(θ + sin θ cos θ (1 + ⅔ cos² θ)) = 0.00347816511529.
        let d = [1.0, 2.0, 3.0, 4.0, 5.0, 3.0];
        let r = paired_t_test(&d);
        close(r.mean_difference, 3.0, 1e-15);
        close(r.se, (1.0f64 / 3.0).sqrt(), 1e-15);
        close(r.t, 3.0 * 3.0f64.sqrt(), 1e-13);
        close(r.df, 5.0, 0.0);
        close(r.p, 0.003_478_165_115_29, 1e-11);
        assert_eq!(r.reason, None);
    }

    #[test]
    fn paired_t_degenerate_cases_say_why() {
        assert_eq!(
            paired_t_test(&[0.5]).reason,
            Some(PairedUndefined::TooFewPairs { n: 1 })
        );
        assert_eq!(paired_t_test(&[]).mean_difference, None);
        let zero = paired_t_test(&[0.0, 0.0, 0.0]);
        assert_eq!(
            zero.reason,
            Some(PairedUndefined::ConstantDifference { difference: 0.0 })
        );
        assert_eq!((zero.t, zero.p), (None, None));
        let shifted = paired_t_test(&[0.25, 0.25]);
        assert_eq!(shifted.mean_difference, Some(0.25));
        assert!(shifted.p.is_none());
    }

    #[test]
    fn hand_computed_sign_tests() {
        // 9 up, 1 down, 2 ties: p = 2·(C(10,0) + C(10,1)) / 2¹⁰ = 22/1024.
        let mut d = vec![0.5; 9];
        d.extend([-0.25, 0.0, 0.0]);
        let s = sign_test(&d);
        assert_eq!((s.positive, s.negative, s.ties), (9, 1, 2));
        assert!((s.p - 22.0 / 1024.0).abs() < 1e-12, "{}", s.p);
        // Balanced signs: p is capped at 1.
        assert_eq!(sign_test(&[1.0, -1.0]).p, 1.0);
        // Nothing untied.
        let none = sign_test(&[0.0, 0.0]);
        assert_eq!((none.ties, none.p), (2, 1.0));
        // 20 of 20 up: 2 / 2²⁰.
        assert!((sign_test(&[0.1; 20]).p - 2.0 / 1_048_576.0).abs() < 1e-15);
    }
}
