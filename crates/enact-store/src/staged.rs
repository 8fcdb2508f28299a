//! Staged imports: a dataset's next version written batch by batch under a hidden `datasets`
//! row, and the cut-over that moves it into the dataset. Maps rows only; the import use case
//! (`app::import`) decides when each runs.

use super::db::{Conn, Dialect, Fields, WriteConn, on};
use enact_core::semantics::SignatureSource;

/// One import in progress.
#[derive(Debug, Clone)]
pub struct StagedImport {
    pub id: i64,
    pub dataset: String,
    /// The hidden `datasets` row the staged items belong to.
    pub staging: i64,
    /// The dataset's id when the import started; `None` if it did not exist.
    pub target: Option<i64>,
    pub file_sha256: String,
    pub options: String,
    pub run_token: String,
    pub lines_done: i64,
    pub rows_done: i64,
    pub bytes_done: i64,
    pub report: String,
    pub started_at: String,
    pub updated_at: String,
}

/// Where a staged import has got, written with each batch.
#[derive(Debug, Clone)]
pub struct StagedProgress<'a> {
    pub lines_done: i64,
    pub rows_done: i64,
    pub bytes_done: i64,
    pub report: &'a str,
}

const COLUMNS: &str = "id, dataset, staging, target, file_sha256, options, run_token, lines_done, \
     rows_done, bytes_done, report, started_at, updated_at";

fn from_row(row: &impl Fields) -> Result<StagedImport, sqlx::Error> {
    Ok(StagedImport {
        id: row.try_get("id")?,
        dataset: row.try_get("dataset")?,
        staging: row.try_get("staging")?,
        target: row.try_get("target")?,
        file_sha256: row.try_get("file_sha256")?,
        options: row.try_get("options")?,
        run_token: row.try_get("run_token")?,
        lines_done: row.try_get("lines_done")?,
        rows_done: row.try_get("rows_done")?,
        bytes_done: row.try_get("bytes_done")?,
        report: row.try_get("report")?,
        started_at: row.try_get("started_at")?,
        updated_at: row.try_get("updated_at")?,
    })
}

/// The staged import of `dataset`, if one is in progress.
pub async fn for_dataset(
    conn: &mut Conn,
    dataset: &str,
) -> Result<Option<StagedImport>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(&format!(
            "SELECT {COLUMNS} FROM staged_imports WHERE dataset = $1"
        ))
        .bind(dataset)
        .fetch_optional(&mut *c)
        .await?;
        row.as_ref().map(from_row).transpose()
    })
}

/// Every staged import, oldest first.
pub async fn all(conn: &mut Conn) -> Result<Vec<StagedImport>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!(
            "SELECT {COLUMNS} FROM staged_imports ORDER BY updated_at, id"
        ))
        .fetch_all(&mut *c)
        .await?;
        rows.iter().map(from_row).collect()
    })
}

/// Every staged import no batch was written to for `hours` hours, oldest first.
pub async fn idle_for_hours(conn: &mut Conn, hours: i64) -> Result<Vec<StagedImport>, sqlx::Error> {
    // The cutoff in each database's own date arithmetic, in the timestamp columns' format.
    match super::db::Connection::handle(conn) {
        super::db::Handle::Sqlite(c) => {
            let rows = sqlx::query(&format!(
                "SELECT {COLUMNS} FROM staged_imports WHERE updated_at < \
                 strftime('%Y-%m-%dT%H:%M:%SZ', 'now', '-' || $1 || ' hours') \
                 ORDER BY updated_at, id"
            ))
            .bind(hours)
            .fetch_all(&mut *c)
            .await?;
            rows.iter().map(from_row).collect()
        }
        super::db::Handle::Pg(c) => {
            let rows = sqlx::query(&format!(
                "SELECT {COLUMNS} FROM staged_imports WHERE updated_at < \
                 to_char(now() AT TIME ZONE 'UTC' - make_interval(hours => $1::int), \
                 'YYYY-MM-DD\"T\"HH24:MI:SS\"Z\"') ORDER BY updated_at, id"
            ))
            .bind(hours)
            .fetch_all(&mut *c)
            .await?;
            rows.iter().map(from_row).collect()
        }
    }
}

/// The hidden `datasets` row a staged import of `dataset` writes under: a name no import
/// gives (it starts with a control character), unique per dataset.
fn staging_name(dataset: &str) -> String {
    format!("\u{1}staged {dataset}")
}

/// Starts a staged import of `dataset`: its hidden dataset row and its record.
pub async fn create(
    conn: &mut WriteConn,
    dataset: &str,
    source: &str,
    target: Option<i64>,
    file_sha256: &str,
    options: &str,
    run_token: &str,
) -> Result<StagedImport, sqlx::Error> {
    on!(conn, |c| {
        let staging: i64 =
            sqlx::query_scalar("INSERT INTO datasets (name, source) VALUES ($1, $2) RETURNING id")
                .bind(staging_name(dataset))
                .bind(source)
                .fetch_one(&mut *c)
                .await?;
        let row = sqlx::query(&format!(
            "INSERT INTO staged_imports (dataset, staging, target, file_sha256, options, \
             run_token) VALUES ($1, $2, $3, $4, $5, $6) RETURNING {COLUMNS}"
        ))
        .bind(dataset)
        .bind(staging)
        .bind(target)
        .bind(file_sha256)
        .bind(options)
        .bind(run_token)
        .fetch_one(&mut *c)
        .await?;
        from_row(&row)
    })
}

/// Makes `run_token` the run that writes the staged import's batches from now on.
pub async fn claim(conn: &mut WriteConn, id: i64, run_token: &str) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let now = c.utc_now();
        let done = sqlx::query(&format!(
            "UPDATE staged_imports SET run_token = $1, updated_at = {now} WHERE id = $2"
        ))
        .bind(run_token)
        .bind(id)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() == 1)
    })
}

/// Makes the staged import impossible to resume or to write to (its file hash and run token
/// emptied): the first step of discarding it, so that a run killed while its rows are deleted
/// leaves nothing another run could take over and publish half of.
pub async fn forget(conn: &mut WriteConn, id: i64) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        let now = c.utc_now();
        sqlx::query(&format!(
            "UPDATE staged_imports SET file_sha256 = '', run_token = '', updated_at = {now} \
             WHERE id = $1"
        ))
        .bind(id)
        .execute(&mut *c)
        .await?;
        Ok(())
    })
}

/// Records a committed batch, if `run_token` still owns the staged import and it had got to
/// `lines_before`; `false` when another run took it over or it was abandoned.
pub async fn record_batch(
    conn: &mut WriteConn,
    id: i64,
    run_token: &str,
    lines_before: i64,
    progress: &StagedProgress<'_>,
) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let now = c.utc_now();
        let done = sqlx::query(&format!(
            "UPDATE staged_imports SET lines_done = $1, rows_done = $2, bytes_done = $3, \
             report = $4, updated_at = {now} \
             WHERE id = $5 AND run_token = $6 AND lines_done = $7"
        ))
        .bind(progress.lines_done)
        .bind(progress.rows_done)
        .bind(progress.bytes_done)
        .bind(progress.report)
        .bind(id)
        .bind(run_token)
        .bind(lines_before)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected() == 1)
    })
}

/// Stages a new signature table for an item the dataset holds unchanged.
pub async fn stage_signatures(
    conn: &mut WriteConn,
    staged: i64,
    item_id: &str,
    source: SignatureSource,
    signatures_json: &str,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query(
            "INSERT INTO staged_signatures (staged, item_id, source, signatures) \
             VALUES ($1, $2, $3, $4) ON CONFLICT (staged, item_id) DO UPDATE \
             SET source = excluded.source, signatures = excluded.signatures",
        )
        .bind(staged)
        .bind(item_id)
        .bind(source)
        .bind(signatures_json)
        .execute(&mut *c)
        .await?;
        Ok(())
    })
}

/// Deletes up to `limit` of the items of a staged import's hidden row or of a retired row
/// (their images and signatures, and anything made on them, go with them); returns how many.
pub async fn delete_items(
    conn: &mut WriteConn,
    staging: i64,
    limit: i64,
) -> Result<u64, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query(
            "DELETE FROM items WHERE id IN \
             (SELECT id FROM items WHERE dataset_id = $1 LIMIT $2)",
        )
        .bind(staging)
        .bind(limit)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected())
    })
}

/// Deletes up to `limit` stored frames that no item or episode uses (left by a discarded
/// staged import); returns how many. Every import (of a release or of an episode) inserts a
/// frame in the transaction that links it, so between transactions an unused frame is one
/// nothing will link.
pub async fn delete_unused_frames(conn: &mut WriteConn, limit: i64) -> Result<u64, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query(
            "DELETE FROM frames WHERE id IN (SELECT f.id FROM frames f WHERE NOT EXISTS \
             (SELECT 1 FROM item_images ii WHERE ii.frame = f.id) AND NOT EXISTS \
             (SELECT 1 FROM episode_frames e WHERE e.frame = f.id) AND NOT EXISTS \
             (SELECT 1 FROM episode_frames e WHERE e.thumbnail = f.id) LIMIT $1)",
        )
        .bind(limit)
        .execute(&mut *c)
        .await?;
        Ok(done.rows_affected())
    })
}

/// Removes a staged import's record and its (emptied) hidden dataset row.
pub async fn remove(conn: &mut WriteConn, staged: &StagedImport) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("DELETE FROM staged_imports WHERE id = $1")
            .bind(staged.id)
            .execute(&mut *c)
            .await?;
        sqlx::query("DELETE FROM datasets WHERE id = $1")
            .bind(staged.staging)
            .execute(&mut *c)
            .await?;
        Ok(())
    })
}

/// Cut-over into a dataset that does not exist yet: the hidden row becomes the dataset.
pub async fn publish_as_new(
    conn: &mut WriteConn,
    staged: &StagedImport,
) -> Result<(), sqlx::Error> {
    on!(conn, |c| {
        sqlx::query("DELETE FROM staged_imports WHERE id = $1")
            .bind(staged.id)
            .execute(&mut *c)
            .await?;
        let now = c.utc_now();
        sqlx::query(&format!(
            "UPDATE datasets SET name = $1, created_at = {now} WHERE id = $2"
        ))
        .bind(&staged.dataset)
        .bind(staged.staging)
        .execute(&mut *c)
        .await?;
        Ok(())
    })
}

/// What a cut-over into an existing dataset did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Published {
    /// The `datasets` row that is the dataset now: the target's, or (when the staged version
    /// replaced most of it) the staged import's hidden row, which took the target's place.
    pub dataset: i64,
    /// Items of the dataset the staged version replaced.
    pub replaced: u64,
    /// Items of the dataset the staged version left as they were.
    pub kept: u64,
    /// Whether the staged row took the target's place (the target then retired, its replaced
    /// items deleted afterwards), rather than the staged items moving into the target.
    pub swapped: bool,
}

/// Every table that names a dataset by its `datasets` row, besides `items` (moved item by item),
/// a staged import's record and the list of retired rows; and the columns that, with the
/// dataset, make a row unique (`None`: nothing does). A cut-over that swaps rows points all of
/// them at the new row; a retired row's late writes are pointed at its successor where that
/// does not collide with one of its own rows. A test compares this with the schema.
pub const DATASET_REFERENCES: &[(&str, &str, Option<&[&str]>)] = &[
    ("agreement_rounds", "dataset", Some(&[])),
    ("annotator_exclusions", "dataset", Some(&["annotator"])),
    ("attention_sets", "dataset", Some(&[])),
    ("challenges", "dataset", Some(&[])),
    ("dataset_settings", "dataset", Some(&[])),
    ("gold_sets", "dataset", Some(&[])),
    ("model_metadata", "dataset", Some(&["model"])),
    ("model_runs", "dataset", None),
    ("reported_results", "dataset", Some(&["model", "source"])),
    ("studies", "baseline", None),
    ("study_variants", "dataset", Some(&["study"])),
    ("submissions", "dataset", None),
    ("verdict_sweeps", "dataset", Some(&[])),
];

/// Every table of what people and models made on an item (besides its images and signatures,
/// which are part of it), deleted with the item. A swapping cut-over deletes these rows of the
/// replaced items at once, as deleting the items would, and leaves the items for later. A test
/// compares this with the schema.
pub const MADE_ON_ITEMS: &[&str] = &[
    "agreement_samples",
    "annotations",
    "assignments",
    "attention_items",
    "challenge_items",
    "drafts",
    "gold_items",
    "model_run_items",
];

/// The hidden name a retired `datasets` row is given: a name no import gives (it starts with a
/// control character), unique per row.
fn retired_name(dataset: &str, id: i64) -> String {
    format!("\u{2}retired {dataset} {id}")
}

/// Cut-over into an existing dataset. Whichever moves fewer rows:
/// - the staged items move into the dataset, keeping their row ids, and the items they replace
///   are deleted (with what was made on them);
/// - or, when the staged version replaces most of the dataset, its hidden row takes the
///   dataset's place: the kept items move to it, it takes the name and everything that names
///   the dataset ([`DATASET_REFERENCES`]) is pointed at it, and the old row is retired under a
///   hidden name. What was made on the replaced items is deleted now ([`MADE_ON_ITEMS`]); the
///   items themselves, with their images and signatures, afterwards, a few hundred per
///   transaction (see [`retired`]), so that the cut-over does not hold the write lock for
///   seconds at full size.
///
/// Either way the replaced items' verdicts are left for [`sweep_submission`], the staged
/// signature tables are applied, and the staged import's record is removed.
pub async fn publish_into(
    conn: &mut WriteConn,
    staged: &StagedImport,
    target: i64,
    source: &str,
) -> Result<Published, sqlx::Error> {
    on!(conn, |c| {
        let staged_items: i64 =
            sqlx::query_scalar("SELECT count(*) FROM items WHERE dataset_id = $1")
                .bind(staged.staging)
                .fetch_one(&mut *c)
                .await?;
        let target_items: i64 =
            sqlx::query_scalar("SELECT count(*) FROM items WHERE dataset_id = $1")
                .bind(target)
                .fetch_one(&mut *c)
                .await?;
        let replaced: i64 = sqlx::query_scalar(
            "SELECT count(*) FROM items o JOIN items n ON n.dataset_id = $2 \
             AND n.item_id = o.item_id WHERE o.dataset_id = $1",
        )
        .bind(target)
        .bind(staged.staging)
        .fetch_one(&mut *c)
        .await?;
        let kept = target_items - replaced;
        // Deleting an item row with its cascade costs about 2.7 times moving one (measured at
        // full size, BENCHMARKS.md), so the swap wins once the kept items are fewer than the
        // staged ones plus twice the replaced.
        let swapped = kept < staged_items + 2 * replaced;
        let dataset = if swapped {
            for table in MADE_ON_ITEMS {
                sqlx::query(&format!(
                    "DELETE FROM {table} WHERE item IN (SELECT o.id FROM items o \
                     JOIN items n ON n.dataset_id = $2 AND n.item_id = o.item_id \
                     WHERE o.dataset_id = $1)"
                ))
                .bind(target)
                .bind(staged.staging)
                .execute(&mut *c)
                .await?;
            }
            sqlx::query(
                "UPDATE items SET dataset_id = $2 WHERE dataset_id = $1 AND item_id NOT IN \
                 (SELECT item_id FROM items WHERE dataset_id = $2)",
            )
            .bind(target)
            .bind(staged.staging)
            .execute(&mut *c)
            .await?;
            let (name, created_at, origin, scene): (String, String, String, String) =
                sqlx::query_as(
                    "SELECT name, created_at, origin, scene FROM datasets WHERE id = $1",
                )
                .bind(target)
                .fetch_one(&mut *c)
                .await?;
            sqlx::query("UPDATE datasets SET name = $1 WHERE id = $2")
                .bind(retired_name(&name, target))
                .bind(target)
                .execute(&mut *c)
                .await?;
            sqlx::query("INSERT INTO retired_datasets (dataset, name) VALUES ($1, $2)")
                .bind(target)
                .bind(&name)
                .execute(&mut *c)
                .await?;
            sqlx::query(
                "UPDATE datasets SET name = $1, created_at = $2, origin = $3, scene = $4 \
                 WHERE id = $5",
            )
            .bind(&name)
            .bind(&created_at)
            .bind(&origin)
            .bind(&scene)
            .bind(staged.staging)
            .execute(&mut *c)
            .await?;
            for (table, column, _) in DATASET_REFERENCES {
                sqlx::query(&format!(
                    "UPDATE {table} SET {column} = $1 WHERE {column} = $2"
                ))
                .bind(staged.staging)
                .bind(target)
                .execute(&mut *c)
                .await?;
            }
            staged.staging
        } else {
            sqlx::query(
                "DELETE FROM items WHERE dataset_id = $1 AND item_id IN \
                 (SELECT item_id FROM items WHERE dataset_id = $2)",
            )
            .bind(target)
            .bind(staged.staging)
            .execute(&mut *c)
            .await?;
            sqlx::query("UPDATE items SET dataset_id = $1 WHERE dataset_id = $2")
                .bind(target)
                .bind(staged.staging)
                .execute(&mut *c)
                .await?;
            target
        };
        // Verdicts do not reference items (they are written by the thousand per submission,
        // and an index by item to delete by would cost every submission a write per item): the
        // replaced items' verdicts now name none of the dataset's items, and are deleted after
        // the cut-over, a submission per transaction, rather than by the million in this one.
        if replaced > 0 {
            sqlx::query(
                "INSERT INTO verdict_sweeps (dataset, generation, swept_through) \
                 VALUES ($1, 1, 0) ON CONFLICT (dataset) DO UPDATE SET \
                 generation = verdict_sweeps.generation + 1, swept_through = 0",
            )
            .bind(dataset)
            .execute(&mut *c)
            .await?;
        }
        sqlx::query(
            "INSERT INTO item_signatures (item, source, signatures) \
             SELECT i.id, s.source, s.signatures FROM staged_signatures s \
             JOIN items i ON i.dataset_id = $1 AND i.item_id = s.item_id WHERE s.staged = $2 \
             ON CONFLICT (item) DO UPDATE SET source = excluded.source, \
             signatures = excluded.signatures",
        )
        .bind(dataset)
        .bind(staged.id)
        .execute(&mut *c)
        .await?;
        sqlx::query("UPDATE datasets SET source = $1 WHERE id = $2")
            .bind(source)
            .bind(dataset)
            .execute(&mut *c)
            .await?;
        // The record last: its staged signatures go with it. When the hidden row is the
        // dataset now, only the record goes.
        sqlx::query("DELETE FROM staged_imports WHERE id = $1")
            .bind(staged.id)
            .execute(&mut *c)
            .await?;
        if !swapped {
            sqlx::query("DELETE FROM datasets WHERE id = $1")
                .bind(staged.staging)
                .execute(&mut *c)
                .await?;
        }
        let count = |n: i64| u64::try_from(n).unwrap_or(0);
        Ok(Published {
            dataset,
            replaced: count(replaced),
            kept: count(kept),
            swapped,
        })
    })
}

/// A `datasets` row a swapping cut-over retired, with the name its dataset had.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Retired {
    pub dataset: i64,
    pub name: String,
}

/// Every retired row still to delete, oldest first.
pub async fn retired(conn: &mut Conn) -> Result<Vec<Retired>, sqlx::Error> {
    on!(conn, |c| {
        let rows: Vec<(i64, String)> = sqlx::query_as(
            "SELECT dataset, name FROM retired_datasets ORDER BY retired_at, dataset",
        )
        .fetch_all(&mut *c)
        .await?;
        Ok(rows
            .into_iter()
            .map(|(dataset, name)| Retired { dataset, name })
            .collect())
    })
}

/// Deletes a retired row whose items are deleted (any left go with it). Rows written to it
/// after its cut-over, by a write that had resolved the dataset just before, are first pointed
/// at the dataset now holding its name, unless one of that dataset's own rows has their key;
/// returns how many were.
pub async fn delete_retired(conn: &mut WriteConn, retired: &Retired) -> Result<u64, sqlx::Error> {
    on!(conn, |c| {
        // Hidden rows (staged, retired) have names no dataset has.
        let successor: Option<i64> = sqlx::query_scalar("SELECT id FROM datasets WHERE name = $1")
            .bind(&retired.name)
            .fetch_optional(&mut *c)
            .await?;
        let mut repointed = 0;
        if let Some(successor) = successor {
            for (table, column, unique_with) in DATASET_REFERENCES {
                let collision = match unique_with {
                    None => String::new(),
                    Some(columns) => {
                        let same: String = columns
                            .iter()
                            .map(|k| format!(" AND o.{k} = {table}.{k}"))
                            .collect();
                        format!(
                            " AND NOT EXISTS (SELECT 1 FROM {table} o WHERE o.{column} = $1{same})"
                        )
                    }
                };
                repointed += sqlx::query(&format!(
                    "UPDATE {table} SET {column} = $1 WHERE {column} = $2{collision}"
                ))
                .bind(successor)
                .bind(retired.dataset)
                .execute(&mut *c)
                .await?
                .rows_affected();
            }
        }
        sqlx::query("DELETE FROM datasets WHERE id = $1")
            .bind(retired.dataset)
            .execute(&mut *c)
            .await?;
        Ok(repointed)
    })
}

/// A dataset whose replaced items' verdicts are still to be deleted, and how far that got.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VerdictSweep {
    pub dataset: i64,
    pub generation: i64,
    /// Submissions with ids up to this one are swept.
    pub swept_through: i64,
}

/// Every pending sweep of replaced items' verdicts.
pub async fn verdict_sweeps(conn: &mut Conn) -> Result<Vec<VerdictSweep>, sqlx::Error> {
    on!(conn, |c| {
        let rows: Vec<(i64, i64, i64)> = sqlx::query_as(
            "SELECT dataset, generation, swept_through FROM verdict_sweeps ORDER BY dataset",
        )
        .fetch_all(&mut *c)
        .await?;
        Ok(rows
            .into_iter()
            .map(|(dataset, generation, swept_through)| VerdictSweep {
                dataset,
                generation,
                swept_through,
            })
            .collect())
    })
}

/// Deletes the verdicts of the sweep's next submission that name none of the dataset's items,
/// and records it as swept; returns (rows deleted, whether a submission was left to sweep).
/// When none is left, or a newer cut-over restarted the sweep (another generation), nothing is
/// deleted; a finished sweep's row is removed.
pub async fn sweep_submission(
    conn: &mut WriteConn,
    sweep: &VerdictSweep,
) -> Result<(u64, bool), sqlx::Error> {
    on!(conn, |c| {
        let current: Option<(i64, i64)> = sqlx::query_as(
            "SELECT generation, swept_through FROM verdict_sweeps WHERE dataset = $1",
        )
        .bind(sweep.dataset)
        .fetch_optional(&mut *c)
        .await?;
        let Some((generation, swept_through)) = current else {
            return Ok((0, false));
        };
        if generation != sweep.generation {
            return Ok((0, false));
        }
        let next: Option<i64> =
            sqlx::query_scalar("SELECT min(id) FROM submissions WHERE dataset = $1 AND id > $2")
                .bind(sweep.dataset)
                .bind(swept_through)
                .fetch_one(&mut *c)
                .await?;
        let Some(submission) = next else {
            sqlx::query("DELETE FROM verdict_sweeps WHERE dataset = $1 AND generation = $2")
                .bind(sweep.dataset)
                .bind(generation)
                .execute(&mut *c)
                .await?;
            return Ok((0, false));
        };
        let deleted = sqlx::query(
            "DELETE FROM submission_items WHERE submission = $1 AND item NOT IN \
             (SELECT id FROM items WHERE dataset_id = $2)",
        )
        .bind(submission)
        .bind(sweep.dataset)
        .execute(&mut *c)
        .await?
        .rows_affected();
        // Only for this generation: a cut-over committed meanwhile (PostgreSQL reads committed
        // rows per statement) restarted the sweep, and its progress is not this one's.
        sqlx::query(
            "UPDATE verdict_sweeps SET swept_through = $1 WHERE dataset = $2 AND generation = $3",
        )
        .bind(submission)
        .bind(sweep.dataset)
        .bind(generation)
        .execute(&mut *c)
        .await?;
        Ok((deleted, true))
    })
}
