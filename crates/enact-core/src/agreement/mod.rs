//! Agreement statistics: Krippendorff's alpha with item-level bootstrap intervals, the
//! encodings that turn ordering answers into reliability data, and Welch's t-test for comparing
//! two runs.
//!
//! Start with [`reliability`] (the coders × units input), then [`alpha`] (the statistic and its
//! per-item tallies), [`bootstrap`] (intervals) and [`ordering`] (annotated permutations and the
//! combined report). [`welch`] is independent of the rest; [`reliability_json`] is the one place
//! that reads files.

pub mod alpha;
pub mod bootstrap;
pub mod ordering;
pub mod protocol;
pub mod reliability;
pub mod reliability_json;
pub mod report;
pub mod welch;

pub use alpha::{
    AlphaResult, AlphaUndefined, ItemOutOfRange, MeasurementLevel, PairwiseAlpha, PreparedAlpha,
    UnknownMeasurementLevel, krippendorff_alpha, mean_pairwise_alpha, pairwise_alphas,
};
pub use bootstrap::{
    BOOTSTRAP_RNG, BootstrapAlpha, BootstrapConfig, BootstrapError, DEFAULT_BOOTSTRAP_SEED,
    DEFAULT_CONFIDENCE_LEVEL, DEFAULT_REPLICATES, bootstrap_alpha, percentile,
};
pub use ordering::{
    AnnotatedOrdering, EncodedOrderings, ExactAgreement, OrderingAgreement, OrderingAnnotations,
    OrderingEncoding, OrderingError, OrderingUnit, PAPER_COMPARABLE_ENCODING, UnitSlot,
    UnknownOrderingEncoding, ordering_agreement,
};
pub use reliability::{
    KeyedReliability, ReliabilityData, ReliabilityDataError, UnitItems, UnitItemsError,
};
pub use reliability_json::{ReliabilityJsonError, parse_reliability_json, read_reliability_json};
pub use welch::{NonFiniteSampleValue, Sample, WelchComparison, WelchUndefined, welch_t_test};
