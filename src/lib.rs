//! enact-hub: a self-hosted evaluation service for the ENACT benchmark.
//!
//! Six layers, each allowed to use only the ones below it. The five lowest are crates of their
//! own (with the outbound clients in a crate beside the service kit), so Cargo keeps them from
//! naming anything above them (and the web, which does not depend on the store, from reaching
//! past the use cases into it); within this crate a test,
//! `tests/layers.rs`, reads every `crate::` path and fails when the command line reaches into the
//! store, or on a cycle:
//!
//! | where         | what lives there                                                     |
//! |---------------|----------------------------------------------------------------------|
//! | `src/cli/` ([`cli`]) | the command line: parse arguments, call one [`app`] use case (or serve [`web`]), print text or JSON; never names the store |
//! | `crates/enact-web/` ([`web`]) | the HTTP adapter: parse requests, call one [`app`] use case, render JSON or HTML |
//! | `crates/enact-app/` ([`app`]) | use cases: import, submit, tokens, annotators, assignment, drafts and answers, the agreement protocol and report, error analyses, leaderboards, the demo |
//! | `crates/enact-outbound/` (used by [`app`]'s runs) | the outbound clients: a model's OpenAI-compatible endpoint, another hub's API |
//! | `crates/enact-service/` (re-exported by [`app`]) | the service every use case shares and none is named in: `Hub`, the unit of work, the change feed, the job runner, the heavy pool, metrics, the frame store, `AppError` |
//! | `crates/enact-store/` ([`store`]) | SQLite or PostgreSQL: connection setup, migrations, the write gate, rows in and rows out, no decisions |
//! | `crates/enact-core/` ([`core`]) | the benchmark, pure: dataset, scene graphs, verifier, error analysis, pipeline, agreement statistics, world; no database, HTTP, async or command line |
//!
//! Start with `migrations/` for the schema, then [`core`] for the benchmark, then [`app`] for
//! what the service does with it. `src/main.rs` only calls [`cli::main`].

pub mod cli;

/// The benchmark (the `enact-core` crate), named `core` here as every layer above it calls it.
pub use enact_core as core;

/// Rows on SQLite or PostgreSQL (the `enact-store` crate), named `store` here as the use cases
/// call it.
pub use enact_store as store;

/// The use cases (the `enact-app` crate, which re-exports the service kit they share,
/// `enact-service`), named `app` here as the adapters call it.
pub use enact_app as app;

/// The HTTP service: the API, the pages and the server (the `enact-web` crate), named `web`
/// here as the command line calls it.
pub use enact_web as web;
