//! enact-hub: a self-hosted evaluation service for the ENACT benchmark.
//!
//! A tour, in reading order:
//! - `migrations/` holds the SQLite schema; start there.
//! - [`dataset`]: the ENACT QA record format, its validation and the item model (pure).
//! - [`accounts`]: API tokens (format, hashing, constant-time checks), roles and scopes (pure).
//! - [`submission`]: reading, refusing and scoring a leaderboard submission (pure).
//! - [`leaderboard`]: leaderboard rows (Table 1 layout) and the TA-vs-L chart geometry (pure).
//! - [`import`]: reading an ENACT release from disk into the store, all-or-nothing.
//! - [`store`]: SQLite access, one module per table family.
//! - [`web`]: the axum service: JSON API under `/api/v1`, HTML pages, frames.
//! - [`annotation`]: human annotation without I/O: credentials, the balanced split, drafts,
//!   scoring human answers; `store::annotations` and `web::{auth, annotate, admin}` serve it.
//! - [`world`]: a synthetic household world and its BEHAVIOR-format replays (pure but for the
//!   replay writer and the `simulate` command).
//! - [`demo`]: the built-in demo dataset, generated at start by `serve --demo`.
//! - [`cli`]: the command line; `src/main.rs` only calls [`cli::main`].

pub mod accounts;
pub mod agreement;
pub mod annotation;
pub mod cli;
pub mod dataset;
pub mod demo;
pub mod import;
pub mod leaderboard;
pub mod pipeline;
pub mod scene_graph;
pub mod scoring;
pub mod semantics;
pub mod store;
pub mod submission;
pub mod verifier;
pub mod web;
pub mod world;
