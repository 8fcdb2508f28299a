//! Copying a whole database into another, table by table, between SQLite and PostgreSQL
//! (`enact-hub migrate-db`). Every table of the schema is listed here with its columns' kinds,
//! in an order that inserts referenced rows first; rows keep their ids.

use sqlx::QueryBuilder;
use tokio_stream::StreamExt;

use super::db::{Conn, Fields, Handle, WriteConn, on};

/// How a column is read and written.
#[derive(Debug, Clone, Copy)]
enum Kind {
    Int,
    Bool,
    Text,
    Real,
    Blob,
}

/// A table of the schema (both databases have the same ones).
pub struct Table {
    pub name: &'static str,
    columns: &'static [(&'static str, Kind)],
    /// Its `id` is generated (PostgreSQL's sequence is moved past the copied ids).
    generated_id: bool,
}

use Kind::{Blob, Bool, Int, Real, Text};

const fn table(
    name: &'static str,
    columns: &'static [(&'static str, Kind)],
    generated_id: bool,
) -> Table {
    Table {
        name,
        columns,
        generated_id,
    }
}

/// Every table, referenced tables first.
pub const TABLES: &[Table] = &[
    table(
        "datasets",
        &[
            ("id", Int),
            ("name", Text),
            ("created_at", Text),
            ("source", Text),
            ("origin", Text),
            ("scene", Text),
        ],
        true,
    ),
    table(
        "frames",
        &[
            ("id", Int),
            ("sha256", Text),
            ("width", Int),
            ("height", Int),
            ("png", Blob),
        ],
        true,
    ),
    table(
        "items",
        &[
            ("id", Int),
            ("dataset_id", Int),
            ("item_id", Text),
            ("item_type", Text),
            ("direction", Text),
            ("step_length", Int),
            ("task_name", Text),
            ("key_frame_ids", Text),
            ("question", Text),
            ("actions", Text),
            ("gt_answer", Text),
            ("content_hash", Text),
            ("source_line", Int),
        ],
        true,
    ),
    table(
        "item_images",
        &[
            ("item", Int),
            ("position", Int),
            ("path", Text),
            ("frame", Int),
        ],
        false,
    ),
    table("content_generation", &[("id", Int), ("value", Int)], false),
    table(
        "change_feed",
        &[("id", Int), ("origin", Text), ("payload", Text)],
        true,
    ),
    table(
        "item_signatures",
        &[("item", Int), ("source", Text), ("signatures", Text)],
        false,
    ),
    table(
        "accounts",
        &[
            ("id", Int),
            ("name", Text),
            ("role", Text),
            ("created_at", Text),
        ],
        true,
    ),
    table(
        "api_tokens",
        &[
            ("id", Int),
            ("account", Int),
            ("prefix", Text),
            ("token_hash", Text),
            ("scopes", Text),
            ("daily_quota", Int),
            ("total_quota", Int),
            ("created_at", Text),
            ("revoked_at", Text),
        ],
        true,
    ),
    table(
        "submission_attempts",
        &[("id", Int), ("token", Int), ("created_at", Text)],
        true,
    ),
    table(
        "dataset_settings",
        &[("dataset", Int), ("answers", Text)],
        false,
    ),
    table(
        "submissions",
        &[
            ("id", Int),
            ("dataset", Int),
            ("account", Int),
            ("token", Int),
            ("idempotency_key", Text),
            ("body_sha256", Text),
            ("model", Text),
            ("description", Text),
            ("url", Text),
            ("prompt_version", Text),
            ("notes", Text),
            ("policy", Text),
            ("status", Text),
            ("visibility", Text),
            ("baseline", Bool),
            ("scores", Text),
            ("created_at", Text),
            ("error_analysis", Text),
            ("metric_version", Int),
            ("scored_by", Text),
            ("provenance", Text),
        ],
        true,
    ),
    table(
        "submission_items",
        &[
            ("submission", Int),
            ("item", Int),
            ("line", Int),
            ("raw_answer", Text),
            ("permutation", Text),
            ("outcome", Text),
            ("failure", Text),
            ("exact_match", Bool),
            ("semantic_match", Bool),
            ("task_accuracy", Bool),
            ("pairwise_accuracy", Real),
        ],
        false,
    ),
    table(
        "challenges",
        &[
            ("dataset", Int),
            ("seed", Int),
            ("public_share", Real),
            ("reveal_at", Text),
            ("revealed_at", Text),
            ("revealed_by", Text),
            ("selection_limit", Int),
            ("split_by", Text),
            ("created_at", Text),
        ],
        false,
    ),
    table(
        "challenge_items",
        &[("item", Int), ("dataset", Int), ("part", Text)],
        false,
    ),
    table(
        "challenge_selections",
        &[("id", Int), ("submission", Int), ("selected_at", Text)],
        true,
    ),
    table(
        "annotators",
        &[
            ("id", Int),
            ("name", Text),
            ("is_admin", Bool),
            ("password_hash", Text),
            ("invite_hash", Text),
            ("created_at", Text),
            ("locale", Text),
        ],
        true,
    ),
    table(
        "sessions",
        &[
            ("token_hash", Text),
            ("annotator", Int),
            ("csrf_token", Text),
            ("expires_at_ms", Int),
        ],
        false,
    ),
    table(
        "assignments",
        &[
            ("annotator", Int),
            ("item", Int),
            ("position", Int),
            ("kind", Text),
            ("gold", Bool),
            ("attention", Bool),
        ],
        false,
    ),
    table(
        "gold_sets",
        &[
            ("dataset", Int),
            ("rate", Int),
            ("chosen_by", Text),
            ("share", Real),
            ("seed", Int),
            ("set_by", Text),
            ("created_at", Text),
        ],
        false,
    ),
    table("gold_items", &[("item", Int), ("dataset", Int)], false),
    table(
        "attention_sets",
        &[
            ("dataset", Int),
            ("rate", Int),
            ("set_by", Text),
            ("created_at", Text),
        ],
        false,
    ),
    table(
        "attention_items",
        &[("item", Int), ("dataset", Int), ("instruction", Text)],
        false,
    ),
    table(
        "reported_results",
        &[
            ("id", Int),
            ("dataset", Int),
            ("model", Text),
            ("source", Text),
            ("category", Text),
            ("family", Text),
            ("size", Text),
            ("task_accuracy", Text),
            ("pairwise_accuracy", Text),
            ("added_by", Text),
            ("created_at", Text),
        ],
        true,
    ),
    table(
        "model_metadata",
        &[
            ("dataset", Int),
            ("model", Text),
            ("category", Text),
            ("family", Text),
            ("size", Text),
            ("link", Text),
            ("updated_by", Text),
            ("updated_at", Text),
        ],
        false,
    ),
    table(
        "annotator_pauses",
        &[
            ("annotator", Int),
            ("paused_by", Text),
            ("created_at", Text),
        ],
        false,
    ),
    table(
        "annotator_exclusions",
        &[
            ("dataset", Int),
            ("annotator", Int),
            ("excluded_by", Text),
            ("created_at", Text),
        ],
        false,
    ),
    table(
        "drafts",
        &[
            ("annotator", Int),
            ("item", Int),
            ("slots", Text),
            ("state", Text),
            ("started_at_ms", Int),
            ("first_placement_at_ms", Int),
            ("updated_at_ms", Int),
        ],
        false,
    ),
    table(
        "annotations",
        &[
            ("annotator", Int),
            ("item", Int),
            ("outcome", Text),
            ("answer", Text),
            ("reason", Text),
            ("time_on_item_ms", Int),
            ("time_to_first_placement_ms", Int),
            ("placements", Int),
            ("swaps", Int),
            ("clears", Int),
            ("undos", Int),
            ("finished_at", Text),
            ("exact_match", Bool),
            ("semantic_match", Bool),
            ("task_accuracy", Bool),
            ("pairwise_accuracy", Real),
            ("metric_version", Int),
        ],
        false,
    ),
    table(
        "agreement_rounds",
        &[
            ("dataset", Int),
            ("items_per_cell", Int),
            ("seed", Int),
            ("started_by", Int),
            ("created_at", Text),
        ],
        false,
    ),
    table(
        "agreement_samples",
        &[("dataset", Int), ("item", Int), ("source_annotator", Int)],
        false,
    ),
    table(
        "login_links",
        &[("hash", Text), ("annotator", Int), ("created_at", Text)],
        false,
    ),
    table(
        "audit_log",
        &[
            ("id", Int),
            ("at", Text),
            ("actor_kind", Text),
            ("actor", Text),
            ("action", Text),
            ("target", Text),
            ("dataset", Text),
            ("detail", Text),
        ],
        true,
    ),
    table(
        "studies",
        &[
            ("id", Int),
            ("name", Text),
            ("baseline", Int),
            ("created_at", Text),
            ("created_by", Text),
        ],
        true,
    ),
    table(
        "study_variants",
        &[
            ("study", Int),
            ("position", Int),
            ("family", Text),
            ("label", Text),
            ("dataset", Int),
        ],
        false,
    ),
    table(
        "jobs",
        &[
            ("id", Int),
            ("kind", Text),
            ("payload", Text),
            ("state", Text),
            ("progress", Text),
            ("attempts", Int),
            ("last_error", Text),
            ("run_after_ms", Int),
            ("lease_owner", Text),
            ("lease_until_ms", Int),
            ("created_by", Text),
            ("created_at", Text),
            ("updated_at", Text),
            ("finished_at", Text),
        ],
        true,
    ),
    table(
        "model_runs",
        &[
            ("id", Int),
            ("name", Text),
            ("dataset", Int),
            ("endpoint", Text),
            ("model", Text),
            ("params", Text),
            ("prompt_version", Text),
            ("prompt_hash", Text),
            ("token", Int),
            ("submission", Int),
            ("stamp", Text),
            ("created_by", Text),
            ("created_at", Text),
            ("job", Int),
        ],
        true,
    ),
    table(
        "model_run_items",
        &[
            ("run", Int),
            ("item", Int),
            ("state", Text),
            ("failure", Text),
            ("response", Text),
            ("finish_reason", Text),
            ("prompt_tokens", Int),
            ("completion_tokens", Int),
            ("latency_ms", Int),
            ("attempts", Int),
            ("error", Text),
            ("done_at", Text),
        ],
        false,
    ),
    table(
        "staged_imports",
        &[
            ("id", Int),
            ("dataset", Text),
            ("staging", Int),
            ("target", Int),
            ("file_sha256", Text),
            ("options", Text),
            ("run_token", Text),
            ("lines_done", Int),
            ("rows_done", Int),
            ("bytes_done", Int),
            ("report", Text),
            ("started_at", Text),
            ("updated_at", Text),
        ],
        true,
    ),
    table(
        "staged_signatures",
        &[
            ("staged", Int),
            ("item_id", Text),
            ("source", Text),
            ("signatures", Text),
        ],
        false,
    ),
    table(
        "verdict_sweeps",
        &[
            ("dataset", Int),
            ("generation", Int),
            ("swept_through", Int),
        ],
        false,
    ),
    table(
        "retired_datasets",
        &[("dataset", Int), ("name", Text), ("retired_at", Text)],
        false,
    ),
    table(
        "episodes",
        &[
            ("id", Int),
            ("name", Text),
            ("scene", Text),
            ("created_by", Text),
            ("created_at", Text),
            ("resolved_graphs", Text),
            ("resolved_by", Text),
            ("complete", Int),
            ("import_alive_until_ms", Int),
        ],
        true,
    ),
    table(
        "episode_frames",
        &[
            ("episode", Int),
            ("position", Int),
            ("file_name", Text),
            ("frame", Int),
            ("thumbnail", Int),
        ],
        false,
    ),
    table(
        "episode_graphs",
        &[
            ("episode", Int),
            ("curator", Text),
            ("graphs", Text),
            ("updated_at", Text),
        ],
        false,
    ),
    table(
        "episode_drafts",
        &[
            ("episode", Int),
            ("curator", Text),
            ("graphs", Text),
            ("updated_at_ms", Int),
        ],
        false,
    ),
    table(
        "signing_keys",
        &[
            ("id", Int),
            ("keyid", Text),
            ("algorithm", Text),
            ("public_key", Text),
            ("created_at", Text),
            ("retired_at", Text),
        ],
        true,
    ),
    table(
        "submission_statements",
        &[
            ("id", Int),
            ("submission", Int),
            ("keyid", Text),
            ("envelope", Text),
            ("made_at", Text),
        ],
        true,
    ),
];

/// One column's value.
enum Value {
    Int(Option<i64>),
    Bool(Option<bool>),
    Text(Option<String>),
    Real(Option<f64>),
    Blob(Option<Vec<u8>>),
}

impl Value {
    fn read(row: &impl Fields, column: &str, kind: Kind) -> Result<Value, sqlx::Error> {
        Ok(match kind {
            Int => Value::Int(row.try_get(column)?),
            Bool => Value::Bool(row.try_get(column)?),
            Text => Value::Text(row.try_get(column)?),
            Real => Value::Real(row.try_get(column)?),
            Blob => Value::Blob(row.try_get(column)?),
        })
    }

    fn bytes(&self) -> usize {
        match self {
            Value::Text(Some(t)) => t.len(),
            Value::Blob(Some(b)) => b.len(),
            _ => 8,
        }
    }
}

/// Rows of a table written per statement, at most (and fewer when they hold many bytes).
const BATCH_ROWS: usize = 500;
const BATCH_BYTES: usize = 32 * 1024 * 1024;

impl Table {
    /// Its columns' names, as the copy reads and writes them.
    pub fn columns(&self) -> impl Iterator<Item = &'static str> {
        self.columns.iter().map(|(name, _)| *name)
    }

    fn column_list(&self) -> String {
        self.columns().collect::<Vec<_>>().join(", ")
    }

    /// Its rows.
    pub async fn count(&self, conn: &mut Conn) -> Result<i64, sqlx::Error> {
        let sql = format!("SELECT count(*) FROM {}", self.name);
        on!(conn, |c| sqlx::query_scalar(&sql).fetch_one(&mut *c).await)
    }

    /// Copies every row of this table from `from` into `to` (which has none), reading them as
    /// a stream and writing them in batches. Returns the rows copied.
    pub async fn copy(&self, from: &mut Conn, to: &mut WriteConn) -> Result<u64, sqlx::Error> {
        let select = format!("SELECT {} FROM {}", self.column_list(), self.name);
        let mut copied = 0;
        let mut batch: Vec<Vec<Value>> = Vec::new();
        let mut bytes = 0;
        on!(from, |c| {
            let mut rows = sqlx::query(&select).fetch(&mut *c);
            while let Some(row) = rows.try_next().await? {
                let values = self
                    .columns
                    .iter()
                    .map(|(name, kind)| Value::read(&row, name, *kind))
                    .collect::<Result<Vec<_>, _>>()?;
                bytes += values.iter().map(Value::bytes).sum::<usize>();
                batch.push(values);
                if batch.len() >= BATCH_ROWS || bytes >= BATCH_BYTES {
                    copied += self.insert(to, &batch).await?;
                    batch.clear();
                    bytes = 0;
                }
            }
        });
        copied += self.insert(to, &batch).await?;
        if self.generated_id
            && let Handle::Pg(c) = super::db::Connection::handle(to)
        {
            // The next generated id follows the copied ones.
            sqlx::query(&format!(
                "SELECT setval(pg_get_serial_sequence('{0}', 'id'), \
                 COALESCE((SELECT max(id) FROM {0}), 0) + 1, false)",
                self.name
            ))
            .execute(c)
            .await?;
        }
        Ok(copied)
    }

    async fn insert(&self, to: &mut WriteConn, rows: &[Vec<Value>]) -> Result<u64, sqlx::Error> {
        if rows.is_empty() {
            return Ok(0);
        }
        let head = format!("INSERT INTO {} ({}) ", self.name, self.column_list());
        on!(to, |c| {
            let mut builder = QueryBuilder::new(&head);
            builder.push_values(rows, |mut b, row| {
                for value in row {
                    match value {
                        Value::Int(v) => b.push_bind(*v),
                        Value::Bool(v) => b.push_bind(*v),
                        Value::Text(v) => b.push_bind(v.clone()),
                        Value::Real(v) => b.push_bind(*v),
                        Value::Blob(v) => b.push_bind(v.clone()),
                    };
                }
            });
            Ok(builder.build().execute(&mut *c).await?.rows_affected())
        })
    }
}

/// Empties `content_generation`, the one table a new database is not created empty with.
pub async fn clear_generation(to: &mut WriteConn) -> Result<(), sqlx::Error> {
    on!(to, |c| {
        sqlx::query("DELETE FROM content_generation")
            .execute(&mut *c)
            .await?;
        Ok(())
    })
}
