//! Which build is serving, and which schema its database is at.

use serde::Serialize;

use super::{AppError, Hub};
use crate::core::version;
use crate::store::{self, POSTGRES_SCHEMA, SQLITE_SCHEMA};

/// The schema of the database a hub is serving from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, schemars::JsonSchema)]
pub struct DatabaseSchema {
    /// `sqlite` or `postgres`.
    pub backend: &'static str,
    /// The highest migration applied to the database.
    pub applied: i64,
    /// The highest migration this build knows for that backend; a newer database (another
    /// instance already upgraded) shows a larger `applied`.
    pub expected: i64,
}

/// This build and its database, as `GET /api/v1/version` reports them.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, schemars::JsonSchema)]
pub struct BuildReport {
    pub version: &'static str,
    pub commit: &'static str,
    pub database: DatabaseSchema,
}

/// The version, commit and the database's schema version.
pub async fn describe(hub: &Hub) -> Result<BuildReport, AppError> {
    let (backend, applied) = store::schema_version(hub.pool()).await?;
    let expected = if backend == "postgres" {
        POSTGRES_SCHEMA
    } else {
        SQLITE_SCHEMA
    };
    Ok(BuildReport {
        version: version::VERSION,
        commit: version::COMMIT,
        database: DatabaseSchema {
            backend,
            applied,
            expected,
        },
    })
}

/// What `enact-hub --version` prints after the program's name: the version, the commit and the
/// schema version of each backend.
pub fn version_line() -> &'static str {
    static LINE: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
        format!(
            "{} (commit {}, schema sqlite {SQLITE_SCHEMA}, postgres {POSTGRES_SCHEMA})",
            version::VERSION,
            version::COMMIT
        )
    });
    &LINE
}
