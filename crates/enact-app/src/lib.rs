//! The use cases: one function each, called alike by the web handlers and the command line.
//! They own the transactions and the decisions; [`enact_store`] only maps rows,
//! [`enact_core`] holds the benchmark's logic, and [`enact_service`] is the service they all
//! share ([`Hub`], the unit of work, the change feed, the job runner, the heavy pool, metrics,
//! the frame store, [`AppError`]), re-exported here under the same names. None of them may
//! name this crate; the adapters (the hub's `web` and `cli`) call it.
//!
//! What a use case keeps on the hub is a type of its own, [`Kept`] by the hub without the hub
//! naming it: the leaderboards ([`leaderboard::BoardCache`]), annotators' standings
//! ([`standings`]), scoring targets and the submission [`Quotas`] ([`submissions`]), the
//! signing key ([`signing::Signer`]), item digests ([`statements`]), the endpoint keys of model
//! runs and the import folder. The job kinds' handlers are registered here ([`job_handlers`]).
//!
//! - [`datasets`] and [`items`]: reading what is stored, frames and release archives included;
//!   [`import`]: an ENACT release read from disk, all or nothing.
//! - [`scoring`]: a prediction file scored against a stored dataset or a release folder.
//! - [`submissions`]: submit, read and list a leaderboard submission; [`leaderboard`] builds
//!   the rows, the Human row included, and keeps each dataset's board in memory;
//!   [`challenge`]: a hidden dataset split into a public and a private part, its deadline,
//!   reveal and selections, and what the board shows of it.
//! - [`tokens`]: API tokens and the accounts behind them; [`annotators`]: annotator accounts,
//!   invites and login sessions.
//! - [`annotation`]: assignments, the queue, drafts, answers, skips and flags; [`gold`]: gold
//!   items mixed into the queues, and annotators excluded from the Human row; [`attention`]:
//!   attention checks mixed in like gold items and judged against their instruction;
//!   [`controls`]: pausing an annotator's queue and handing their unfinished items to others;
//!   [`quality`]: each annotator's figures on a dataset.
//! - [`agreement`]: the cross-annotation protocol, agreement statistics and the report.
//! - [`explore`]: the explorer's grid of every item × every leaderboard row's verdict, kept
//!   with the board, and the views cut from it.
//! - [`error_analysis`]: the paper's error taxonomy of a submission, the Human row, a file, or
//!   a whole leaderboard.
//! - [`studies`]: ablation studies (a baseline and variant datasets) and their reports.
//! - [`rescore`]: stored results (submissions' scores, human verdicts) computed again under
//!   the current metric version, in the foreground or as a job.
//! - [`demo`]: the built-in demo dataset, its chance baseline and its login link.
//! - [`backup`]: online snapshots of the database, and restoring one.
//! - [`signing`]: the hub's statement-signing key (in a key file, never in the database),
//!   made on first need and rotated; [`statements`]: each scored submission's signed
//!   statement, and checking one offline.
//! - [`pipeline`]: new items from replays, and simulated replays; [`import_jobs`]: an import
//!   run as a job on the server.
//! - [`runs`]: model runs: the hub asks an OpenAI-compatible endpoint every item, keeps each
//!   reply as it arrives, resumes where it stopped, and submits the answers.
//!
//! Errors are [`AppError`]: each kind says what was wrong, in words a person can act on.

pub mod agreement;
pub mod annotation;
pub mod annotators;
pub mod attention;
pub mod backup;
pub mod challenge;
pub mod compare;
pub mod controls;
pub mod datasets;
pub mod demo;
pub mod doctor;
pub mod episode_curation;
pub mod episodes;
pub mod error_analysis;
pub mod explore;
pub mod gold;
pub mod import;
pub mod import_jobs;
pub mod item_answers;
pub mod items;
pub mod leaderboard;
pub mod migrate_db;
pub mod models;
pub mod paper;
pub mod pipeline;
pub mod quality;
pub mod red_flags;
pub mod reported;
pub mod rescore;
pub mod runs;
pub mod scoring;
pub mod signing;
pub mod standings;
pub mod statements;
pub mod studies;
pub mod submissions;
pub mod tokens;
pub mod version;

/// The service kit's modules, under the paths the use cases and the adapters name them by.
pub use enact_service::{
    AppError, Hub, Kept, Lane, Write, audit, cache, changes, describe_location, frames, heavy,
    jobs, kept, metrics, refusal, store_location, watch,
};
pub use submissions::Quotas;

/// The benchmark and the store, under the names every use case calls them by (`crate::core::…`,
/// `crate::store::…`).
use enact_core as core;
use enact_store as store;

/// The code of every kind of job this version knows, as a serving instance's worker runs it
/// (here, above both the job mechanism and the modules owning each kind, so neither uses the
/// other both ways). A model run's key comes from the hub's allowlist (`serve
/// --endpoint-key`), so the hub it is handed is enough.
pub fn job_handlers() -> jobs::JobHandlers {
    jobs::JobHandlers::default()
        .with(jobs::JobKind::Rescore, |hub, job| {
            Box::pin(async move { rescore::work(&hub, &job).await })
        })
        .with(jobs::JobKind::ModelRun, |hub, job| {
            Box::pin(async move { runs::work(&hub, &job).await })
        })
        .with(jobs::JobKind::Import, |hub, job| {
            Box::pin(async move { import_jobs::work(&hub, &job).await })
        })
}

/// Makes every cache the use cases keep on `hub` (each is otherwise made on first use), so
/// that a server's metrics and cache log list them all from its start.
pub fn make_caches(hub: &Hub) {
    hub.kept::<leaderboard::BoardCache>();
    hub.kept::<standings::StandingCache>();
    hub.kept::<submissions::TargetCache>();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn a_server_s_metrics_list_every_kept_cache_from_its_start() {
        let dir = tempfile::tempdir().expect("tempdir");
        let hub = Hub::open(&dir.path().join("hub.db")).await.expect("open");
        let kept = ["boards", "standings", "scoring_targets"];
        let before = metrics::exposition(&hub).await.expect("metrics");
        assert!(before.contains(r#"cache="item_json""#), "{before}");
        for name in kept {
            assert!(!before.contains(&format!(r#"cache="{name}""#)), "{name}");
        }
        make_caches(&hub);
        let after = metrics::exposition(&hub).await.expect("metrics");
        for name in kept {
            assert!(
                after.contains(&format!(r#"enact_hub_cache_entries{{cache="{name}"}} 0"#)),
                "{name}: {after}"
            );
        }
    }
}
