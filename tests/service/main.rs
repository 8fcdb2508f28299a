//! Integration tests: the importer, the HTTP service on 127.0.0.1:0 and the command line, each
//! test with a fresh database. Built as one test binary.

mod annotate;
mod api;
mod browser;
mod cli;
#[path = "../support/fixtures.rs"]
mod fixtures;
mod helpers;
mod import;
mod pages;
mod score;
mod submissions;
mod world;
