//! Which build of enact-hub this is: the crate version, the git commit it was built from and
//! the schema version its migrations bring each backend to (all fixed at build time by
//! `build.rs`). `--version`, `GET /api/v1/version`, the Python package and every report stamp
//! quote these, so a number can be traced to the code that computed it.

use serde::Serialize;

/// The crate version (Cargo.toml), which the Python package's version also is.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The git commit (12 hex digits) the binary was built from, or "unknown" when it was built
/// outside a checkout and not from a published crate.
pub const COMMIT: &str = env!("ENACT_HUB_COMMIT");

/// The highest SQLite migration this build applies.
pub const SQLITE_SCHEMA: i64 = decimal(env!("ENACT_HUB_SCHEMA_SQLITE"));

/// The highest PostgreSQL migration this build applies.
pub const POSTGRES_SCHEMA: i64 = decimal(env!("ENACT_HUB_SCHEMA_POSTGRES"));

/// A build script's decimal number, read at compile time (a stray character fails the build).
const fn decimal(text: &str) -> i64 {
    let bytes = text.as_bytes();
    assert!(!bytes.is_empty(), "an empty schema version");
    let mut value = 0;
    let mut i = 0;
    while i < bytes.len() {
        assert!(
            bytes[i].is_ascii_digit(),
            "a schema version that is not a number"
        );
        value = value * 10 + (bytes[i] - b'0') as i64;
        i += 1;
    }
    value
}

/// The build as results record it: the version with the commit as semver build metadata.
pub const BUILD: &str = concat!(env!("CARGO_PKG_VERSION"), "+", env!("ENACT_HUB_COMMIT"));

/// What `enact-hub --version` prints after the program's name.
pub const VERSION_LINE: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (commit ",
    env!("ENACT_HUB_COMMIT"),
    ", schema sqlite ",
    env!("ENACT_HUB_SCHEMA_SQLITE"),
    ", postgres ",
    env!("ENACT_HUB_SCHEMA_POSTGRES"),
    ")"
);

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
    fn the_version_line_quotes_every_constant() {
        assert!(VERSION_LINE.starts_with(VERSION));
        assert!(VERSION_LINE.contains(&format!("commit {COMMIT}")));
        assert!(VERSION_LINE.contains(&format!("sqlite {SQLITE_SCHEMA}")));
        assert!(VERSION_LINE.contains(&format!("postgres {POSTGRES_SCHEMA}")));
        assert!(
            COMMIT == "unknown"
                || COMMIT.len() == 12 && COMMIT.bytes().all(|b| b.is_ascii_hexdigit())
        );
    }
}
