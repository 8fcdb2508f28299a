//! Where the shared ENACT fixtures are, for the tests and benchmarks that compare with them, and
//! what a test does when they are missing: on a developer's machine it says so and skips; under
//! CI (`CI` set, as CI services do) it fails, since CI runs with `shared/fixtures` beside the
//! clone and a skip there would pass without having compared anything.
//!
//! [`must_not_skip`] is the one rule for every test that would otherwise skip for want of
//! something outside the crate (fixtures, Chromium, python3 with `requests`, an S3 server).

// Every test binary includes this file and uses its own share of it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// `$ENACT_FIXTURES` (the `fixtures` directory itself), else the first `shared/fixtures` found
/// walking up from the crate (at most three levels). `None` when neither exists: comparisons
/// with ENACT's outputs then say so and skip; everything else runs on generated data.
pub fn shared_fixtures() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("ENACT_FIXTURES") {
        let dir = PathBuf::from(dir);
        return dir.is_dir().then_some(dir);
    }
    let mut dir = Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf();
    for _ in 0..=3 {
        let candidate = dir.join("shared").join("fixtures");
        if candidate.is_dir() {
            return Some(candidate);
        }
        if !dir.pop() {
            break;
        }
    }
    None
}

/// Whether this run must not skip: `CI` is set to anything but empty, `0` or `false` (any
/// case). `.ci/run` sets `CI=true` when its caller has not. A test missing a prerequisite
/// panics when this holds and skips (saying so) otherwise.
pub fn must_not_skip() -> bool {
    std::env::var("CI").is_ok_and(|v| {
        let v = v.trim();
        !(v.is_empty() || v == "0" || v.eq_ignore_ascii_case("false"))
    })
}

/// Says that `what` is missing and the test skips, or panics when [`must_not_skip`].
pub fn missing(what: &str) {
    assert!(
        !must_not_skip(),
        "{what} is missing and CI is set: CI runs with shared/fixtures beside the clone \
         (or ENACT_FIXTURES naming it), so this test must not skip"
    );
    eprintln!("skipping: {what} is missing (put shared/fixtures beside the clone)");
}

/// `relative` inside the shared fixtures when it exists; otherwise [`missing`] and `None`.
pub fn fixture(relative: &str) -> Option<PathBuf> {
    let path = shared_fixtures().map(|dir| dir.join(relative));
    match path {
        Some(path) if path.exists() => Some(path),
        Some(path) => {
            missing(&path.display().to_string());
            None
        }
        None => {
            missing(&format!("shared/fixtures/{relative}"));
            None
        }
    }
}

/// The whole fixtures directory, as [`fixture`].
pub fn fixtures_dir() -> Option<PathBuf> {
    fixture("")
}

/// ENACT's parity fixtures (`enact-parity`: the reference outputs of its own code), as
/// [`fixture`].
pub fn parity_dir() -> Option<PathBuf> {
    fixture("enact-parity")
}
