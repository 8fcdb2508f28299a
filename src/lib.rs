//! enact-hub: a self-hosted evaluation service for the ENACT benchmark.
//!
//! A tour, in reading order:
//! - `migrations/` holds the SQLite schema; start there.
//! - [`dataset`]: the ENACT QA record format, its validation and the item model (pure).
//! - [`scene_graph`]: BEHAVIOR scene graphs: timelines, the transient filter, diffs, visibility,
//!   transition signatures and action sentences (pure).
//! - [`verifier`]: answer parsing and ENACT's verifier in its ENACT-compatible and strict
//!   policies, with TA/PA tables (pure); [`semantics`] and [`scoring`] say where an item's
//!   signatures come from and score a predictions file.
//! - [`pipeline`]: ENACT's data pipeline: key-frame segmentation, the transition graph, uniform
//!   path sampling and QA items.
//! - [`agreement`]: Krippendorff's alpha, item bootstrap, ordering encodings, Welch (pure).
//! - [`accounts`]: API tokens (format, hashing, constant-time checks), roles and scopes (pure).
//! - [`submission`]: reading, refusing and scoring a leaderboard submission (pure).
//! - [`leaderboard`]: leaderboard rows (Table 1 layout) and the TA-vs-L chart geometry (pure).
//! - [`import`]: reading an ENACT release from disk into the store, all-or-nothing.
//! - [`release`]: writing a stored dataset back out as a release archive (pure).
//! - [`store`]: SQLite access, one module per table family.
//! - [`web`]: the axum service: JSON API under `/api/v1`, HTML pages, frames.
//! - [`annotation`]: human annotation without I/O: credentials, the balanced split, drafts,
//!   scoring human answers; `store::annotations` and `web::{auth, annotate, admin}` serve it.
//! - [`agreement_protocol`]: the paper's cross-annotation protocol: which items go to whom (pure).
//! - [`agreement_report`]: the agreement report: alpha, pairs, exact agreement, TA/PA tables,
//!   Welch comparisons, heatmap and bundle files (pure); `store::agreement` feeds it.
//! - [`world`]: a synthetic household world and its BEHAVIOR-format replays (pure but for the
//!   replay writer and the `simulate` command).
//! - [`demo`]: the built-in demo dataset, generated at start by `serve --demo`.
//! - [`cli`]: the command line; `src/main.rs` only calls [`cli::main`].

pub mod accounts;
pub mod agreement;
pub mod agreement_protocol;
pub mod agreement_report;
pub mod annotation;
pub mod cli;
pub mod dataset;
pub mod demo;
pub mod import;
pub mod leaderboard;
pub mod pipeline;
pub mod release;
pub mod scene_graph;
pub mod scoring;
pub mod semantics;
pub mod store;
pub mod submission;
pub mod verifier;
pub mod web;
pub mod world;
