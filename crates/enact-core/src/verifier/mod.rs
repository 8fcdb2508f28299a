//! ENACT scoring: answer parsing, per-item verification (exact / semantic match, pairwise
//! accuracy), aggregation, and whole-file scoring under two policies.
//!
//! Pure and synchronous. Signature sets come in precomputed ([`ItemSignatures`]); prediction
//! files come in as (line number, text) pairs.
//!
//! - [`answer`]: item vocabulary ([`Direction`], [`StepLength`], [`Permutation`]) and the two
//!   answer readers: ENACT's lenient one and the strict one.
//! - [`signatures`]: per-item signature tables interned to bitsets.
//! - [`verify`]: ENACT's forward/inverse verifiers with their Python semantics → [`Verdict`].
//! - [`bootstrap`]: percentile bootstrap intervals for the leaderboard.
//! - [`report`]: aggregation into ENACT's report and `meta_performance` file.
//! - [`enact_policy`]: ENACT's evaluator loop over a file, its skips and output files.
//! - [`strict_policy`]: the leaderboard policy over a dataset.
//! - [`pyjson`], [`pyint`], [`unicode`]: the slices of Python (json, int, `\d`/`\s`) that ENACT's
//!   numbers depend on.
//!
//! Every ENACT quirk lives in one function or constant whose doc comment starts "ENACT quirk:".

pub mod answer;
pub mod bootstrap;
pub mod enact_policy;
pub mod pyint;
pub mod pyjson;
pub mod report;
pub mod signatures;
pub mod strict_policy;
pub mod unicode;
pub mod verify;

pub use answer::{
    Direction, ParsedAnswer, Permutation, PermutationError, StepLength, StrictParseFailure,
    enact_report_group, enact_verifier_direction, parse_answer_enact, parse_answer_strict,
    parse_answer_text_strict,
};
pub use bootstrap::{
    BOOTSTRAP_LEVEL, BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED, ConfidenceInterval, Resampling,
    bootstrap_mean_ci, cluster_ids, clustered_mean_ci, leaderboard_ci,
};
pub use enact_policy::{
    EnactEvaluation, EnactRunError, EnactSignatureSource, EvaluatedRecord, SkipReason, SkippedLine,
    enact_model_name, python_text_lines, score_enact_predictions,
};
pub use pyjson::{PyValue, parse_python_json};
pub use report::{
    GroupPerformance, PerformanceReport, ScoredEntry, StepPerformance, enact_meta_performance_json,
};
pub use signatures::{ItemSignatures, ItemSignaturesError, View, VisibleCoverage};
pub use strict_policy::{
    Coverage, ScoringPolicy, StrictItem, StrictItemResult, StrictOutcome, StrictScoring,
    StrictScoringError, SubmissionProblem, score_strict_predictions,
};
pub use verify::{
    GroundTruthView, KeyFrameShape, PairwiseAccuracy, Verdict, VerifyError, verify,
    verify_enact_record,
};
