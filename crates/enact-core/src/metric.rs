//! The metric's version: which rules computed a stored result. Everything the service keeps
//! that the metric computed (a submission's scores, per-item verdicts and error analysis; a
//! human answer's verdict) records the version it was computed with, and leaderboards,
//! reports and exports say it, so results of different rules are never mixed silently. A
//! result of an older version is marked until `rescore` computes it again.
//!
//! Raise [`METRIC_VERSION`] whenever a change to answer parsing, the verifier, the scores or
//! the error analysis can change a stored result, and add a line below saying what changed.
//!
//! | version | what changed |
//! |---------|--------------|
//! | 1 | every result stored before versions were recorded (the rules up to this change) |
//! | 2 | entity substitution as the paper defines it: the same kind, operation and predicate applied to the wrong entity or entities (both ends of an edge may differ); before, only components with exactly one entity different counted, and the rest became an omission plus a hallucination |

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The version of the rules this build computes with.
pub const METRIC_VERSION: u32 = 2;

/// The metric version a result was computed with, and whether it is the current one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct MetricStamp {
    pub metric_version: u32,
    /// Computed with an older version than this build's: shown marked until rescored.
    pub outdated: bool,
}

impl MetricStamp {
    /// The stamp of a result computed with `version`.
    pub fn of(version: u32) -> MetricStamp {
        MetricStamp {
            metric_version: version,
            outdated: version < METRIC_VERSION,
        }
    }

    /// The stamp of a result computed now.
    pub fn current() -> MetricStamp {
        MetricStamp::of(METRIC_VERSION)
    }

    /// The stamp of a result drawn from several: the oldest version among them.
    pub fn oldest(versions: impl IntoIterator<Item = u32>) -> MetricStamp {
        MetricStamp::of(versions.into_iter().min().unwrap_or(METRIC_VERSION))
    }
}

impl MetricStamp {
    /// How a report's stamp names the rules behind it: the report's own version and the metric
    /// version of its figures, e.g. `enact-hub-study-report/1; metric 2`, with a warning when
    /// some were computed with an older one.
    pub fn with_report(&self, report_version: &str) -> String {
        if self.outdated {
            format!(
                "{report_version}; metric {} (older than the current {METRIC_VERSION}: some \
                 stored scores are not rescored yet)",
                self.metric_version
            )
        } else {
            format!("{report_version}; metric {}", self.metric_version)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn older_versions_are_outdated() {
        assert!(!MetricStamp::current().outdated);
        assert!(MetricStamp::of(METRIC_VERSION - 1).outdated);
        assert_eq!(
            MetricStamp::oldest([METRIC_VERSION, 1, METRIC_VERSION]),
            MetricStamp::of(1)
        );
        assert_eq!(MetricStamp::oldest([]), MetricStamp::current());
        assert_eq!(
            MetricStamp::current().with_report("r/1"),
            format!("r/1; metric {METRIC_VERSION}")
        );
        assert!(MetricStamp::of(1).with_report("r/1").contains("older than"));
    }
}
