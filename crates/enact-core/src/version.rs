//! Which build of enact-hub this is: the workspace's version and the git commit it was built
//! from (fixed at build time by this crate's `build.rs`). `--version`, `GET /api/v1/version`,
//! the Python package and every report stamp quote these, so a number can be traced to the code
//! that computed it. The schema versions are the store's (`enact_hub::store`).

use serde::Serialize;

/// The crate version (Cargo.toml), which the Python package's version also is.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The git commit (12 hex digits) the binary was built from, or "unknown" when it was built
/// outside a checkout and not from a published crate.
pub const COMMIT: &str = env!("ENACT_HUB_COMMIT");

/// The build as results record it: the version with the commit as semver build metadata.
pub const BUILD: &str = concat!(env!("CARGO_PKG_VERSION"), "+", env!("ENACT_HUB_COMMIT"));

/// What produced a result: carried by report stamps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, schemars::JsonSchema)]
pub struct HubBuild {
    pub version: &'static str,
    pub commit: &'static str,
}

/// This build.
pub const THIS_BUILD: HubBuild = HubBuild {
    version: VERSION,
    commit: COMMIT,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_build_is_the_version_and_a_commit() {
        assert_eq!(BUILD, format!("{VERSION}+{COMMIT}"));
        assert!(
            COMMIT == "unknown"
                || COMMIT.len() == 12 && COMMIT.bytes().all(|b| b.is_ascii_hexdigit())
        );
    }
}
