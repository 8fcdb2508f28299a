//! The benchmark itself: plain synchronous Rust with no database, HTTP, async runtime or
//! command line in it. Everything else calls in; nothing here calls out.
//!
//! - [`dataset`]: ENACT's QA record format, its validation, and the item model.
//! - [`scene_graph`]: BEHAVIOR scene graphs: timelines, the transient filter, diffs,
//!   visibility, transition signatures and action sentences.
//! - [`verifier`]: answer parsing and ENACT's verifier in its ENACT-compatible and strict
//!   policies, with TA/PA tables.
//! - [`semantics`]: where an item's transition signatures come from (scene graphs or action
//!   text); [`scoring`]: scoring whole prediction files and ENACT's output files.
//! - [`error_analysis`]: the paper's structural and semantic error taxonomy, handedness and
//!   accepted-but-incomplete answers, per step of every analysed answer.
//! - [`metric`]: the metric's version, recorded with every stored result it computed.
//! - [`submission`]: reading, refusing and scoring a leaderboard submission.
//! - [`paper`]: the paper's result tables and figures, its published results as data, and
//!   other papers' numbers in the same shape.
//! - [`paired`]: two leaderboard rows compared item by item: McNemar's exact test and a paired
//!   bootstrap of the difference, resampling activities.
//! - [`explorer`]: a dataset's items × its leaderboard rows as a grid of verdicts, with the
//!   explorer's filters (direction, step length, activity, pattern), orders and counts.
//! - [`heatmap`]: the significance heatmap both reports draw (the paper's ablation figures).
//! - [`leaderboard`]: leaderboard rows (Table 1 layout) and the TA-vs-L chart geometry.
//! - [`challenge`]: hidden test sets split into a public and a private part: the seeded
//!   stratified draw, figures per part, the selection rule and the rank change at the reveal.
//! - [`model_run`]: asking a model an item: the versioned prompt, reading replies, retry
//!   delays and the in-flight window of a model run.
//! - [`pipeline`]: ENACT's data pipeline: key-frame segmentation, the transition graph, path
//!   sampling and QA items in the release layout.
//! - [`agreement`]: Krippendorff's alpha, bootstrap, ordering encodings, Welch; the paper's
//!   cross-annotation [`agreement::protocol`] and the agreement [`agreement::report`].
//! - [`annotation`]: human annotation without I/O: the balanced split (and the split of a
//!   handover), drafts, queue standing, telemetry, and human answers scored like model answers.
//! - [`gold`]: gold items: choosing a dataset's gold set and mixing it into every queue.
//! - [`attention`]: attention checks: the instruction an item's question carries, the answer
//!   it expects, and each check judged as passed, failed or pending.
//! - [`quality`]: each annotator's figures: gold accuracy, agreement with the others, time
//!   per item, skip and flag rates.
//! - [`audit`]: the audit log's actors, actions, entries and filters.
//! - [`bundle`]: the files a report downloads as: stamps, CSV, LaTeX escaping, tar archives.
//! - [`credentials`]: API tokens, session and invite tokens, passwords, roles, scopes and the
//!   naming rules of accounts.
//! - [`release`]: a stored dataset written back out as an ENACT release archive.
//! - [`statement`]: signed statements of scored submissions: DSSE envelopes, Ed25519 signing
//!   and verification, and the digests a statement names.
//! - [`study`]: ablation studies: variant datasets aligned with a baseline, the Welch, paired t
//!   and sign tests per variant and direction, the paper's heatmap and handedness panel.
//! - `sql_text` (with the `sqlx` feature, which the hub turns on): the enums above as the
//!   store's text columns; conversions only, no query.
//! - [`version`]: this build's version, git commit and schema versions.
//! - [`world`]: a synthetic household world and its BEHAVIOR-format replays; [`demo`] plays it
//!   through the pipeline for `serve --demo`.

pub mod agreement;
pub mod annotation;
pub mod attention;
pub mod audit;
pub mod bundle;
pub mod challenge;
pub mod credentials;
pub mod dataset;
pub mod demo;
pub mod episode;
pub mod error_analysis;
pub mod explorer;
pub mod gold;
pub mod heatmap;
pub mod leaderboard;
pub mod metric;
pub mod model_run;
pub mod paired;
pub mod paper;
pub mod pipeline;
pub mod quality;
pub mod red_flags;
pub mod release;
pub mod scene_graph;
pub mod scoring;
pub mod semantics;
#[cfg(feature = "sqlx")]
pub mod sql_text;
pub mod statement;
pub mod study;
pub mod submission;
pub mod verifier;
pub mod version;
pub mod world;
