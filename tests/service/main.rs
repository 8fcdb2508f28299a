//! Integration tests: the importer, the HTTP service on 127.0.0.1:0 and the command line, each
//! test with a fresh database. Built as one test binary.

mod admin_tokens;
mod agreement;
mod annotate;
mod api;
mod app_layer;
mod archive;
mod audit;
mod authorization;
mod backup;
mod browser;
mod busy;
mod cli;
mod client;
mod compare;
mod constraints;
mod demo_link;
mod episode_browser;
mod episode_pages;
mod episodes;
mod errors;
mod escaping;
#[path = "../support/fixtures.rs"]
mod fixtures;
mod frames;
mod heavy;
mod helpers;
mod hostile;
mod i18n;
mod import;
mod import_jobs;
mod instances;
mod item_answers;
mod jobs;
mod leaderboard;
mod live_import;
mod metrics;
mod migrate_db;
mod openapi;
mod pages;
mod paper;
mod quality;
mod remote_runs;
mod reported;
mod rescore;
mod run_instances;
mod run_pages;
mod runs;
mod score;
mod server_runs;
mod staged;
#[path = "../support/standin.rs"]
mod standin;
mod studies;
mod submissions;
mod world;
