//! Moving a whole database to the other backend (`enact-hub migrate-db`): SQLite into
//! PostgreSQL when a deployment outgrows one machine, or back.

use std::time::Instant;

use super::{AppError, Hub};
use crate::Lane;
use crate::store::copy::{self, TABLES};

/// Rows copied, table by table.
#[derive(Debug, Clone, serde::Serialize)]
pub struct MigrateDbReport {
    pub tables: Vec<(String, u64)>,
    pub seconds: f64,
}

/// Copies every table of `from` into `to`, which must be empty (just created), in one
/// transaction on each side: `from` is read in one snapshot transaction (every table as it was
/// at one moment, while writers carry on: a backup of a running PostgreSQL server blocks no
/// one), and `to` holds all of it or none. Ids are kept; frames held in an object store
/// stay there (their rows are copied). `progress` hears of each table when it is done.
pub async fn migrate_db(
    from: &Hub,
    to: &Hub,
    progress: impl Fn(&str, u64),
) -> Result<MigrateDbReport, AppError> {
    let started = Instant::now();
    let mut target = to.write(Lane::Bulk).await?;
    for table in TABLES.iter().filter(|t| t.name != "content_generation") {
        let rows = table.count(&mut target).await?;
        if rows > 0 {
            return Err(AppError::Conflict(format!(
                "the target database already holds {rows} rows of {}: a whole database is only \
                 copied into an empty one",
                table.name
            )));
        }
    }
    let mut source = from.pool().begin_snapshot().await?;
    copy::clear_generation(&mut target).await?;
    let mut tables = Vec::with_capacity(TABLES.len());
    for table in TABLES {
        let rows = table.copy(&mut source, &mut target).await?;
        progress(table.name, rows);
        tables.push((table.name.to_owned(), rows));
    }
    target.commit().await?;
    source.rollback().await?;
    Ok(MigrateDbReport {
        tables,
        seconds: started.elapsed().as_secs_f64(),
    })
}
