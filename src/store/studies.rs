//! Rows of studies and their variants.

use sqlx::{Row, SqliteConnection};

use crate::core::study::VariantSpec;

/// A stored study, with its datasets by name and id.
#[derive(Debug, Clone)]
pub struct StudyRow {
    pub id: i64,
    pub name: String,
    pub baseline: String,
    pub baseline_id: i64,
    pub created_at: String,
    pub created_by: String,
    pub variants: Vec<(VariantSpec, i64)>,
}

/// Writes a study and its variants (`dataset id` beside each); `None` when the name is taken.
pub async fn insert(
    conn: &mut SqliteConnection,
    name: &str,
    baseline: i64,
    created_by: &str,
    variants: &[(VariantSpec, i64)],
) -> Result<Option<i64>, sqlx::Error> {
    let inserted = sqlx::query("INSERT INTO studies (name, baseline, created_by) VALUES (?, ?, ?)")
        .bind(name)
        .bind(baseline)
        .bind(created_by)
        .execute(&mut *conn)
        .await;
    let id = match inserted {
        Ok(done) => done.last_insert_rowid(),
        Err(sqlx::Error::Database(e)) if e.is_unique_violation() => return Ok(None),
        Err(e) => return Err(e),
    };
    for (position, (spec, dataset)) in variants.iter().enumerate() {
        sqlx::query(
            "INSERT INTO study_variants (study, position, family, label, dataset) \
             VALUES (?, ?, ?, ?, ?)",
        )
        .bind(id)
        .bind(position as i64)
        .bind(&spec.family)
        .bind(&spec.label)
        .bind(dataset)
        .execute(&mut *conn)
        .await?;
    }
    Ok(Some(id))
}

async fn variants_of(
    conn: &mut SqliteConnection,
    study: i64,
) -> Result<Vec<(VariantSpec, i64)>, sqlx::Error> {
    let rows = sqlx::query(
        "SELECT v.family, v.label, d.name, d.id FROM study_variants v \
         JOIN datasets d ON d.id = v.dataset WHERE v.study = ? ORDER BY v.position",
    )
    .bind(study)
    .fetch_all(conn)
    .await?;
    rows.iter()
        .map(|row| {
            Ok((
                VariantSpec {
                    family: row.try_get(0)?,
                    label: row.try_get(1)?,
                    dataset: row.try_get(2)?,
                },
                row.try_get(3)?,
            ))
        })
        .collect()
}

const STUDY_COLUMNS: &str = "s.id, s.name, d.name AS baseline_name, d.id AS baseline_id, \
    s.created_at, s.created_by FROM studies s JOIN datasets d ON d.id = s.baseline";

async fn from_row(
    conn: &mut SqliteConnection,
    row: &sqlx::sqlite::SqliteRow,
) -> Result<StudyRow, sqlx::Error> {
    let id: i64 = row.try_get("id")?;
    Ok(StudyRow {
        id,
        name: row.try_get("name")?,
        baseline: row.try_get("baseline_name")?,
        baseline_id: row.try_get("baseline_id")?,
        created_at: row.try_get("created_at")?,
        created_by: row.try_get("created_by")?,
        variants: variants_of(conn, id).await?,
    })
}

pub async fn by_name(
    conn: &mut SqliteConnection,
    name: &str,
) -> Result<Option<StudyRow>, sqlx::Error> {
    let row = sqlx::query(&format!("SELECT {STUDY_COLUMNS} WHERE s.name = ?"))
        .bind(name)
        .fetch_optional(&mut *conn)
        .await?;
    match row {
        Some(row) => Ok(Some(from_row(conn, &row).await?)),
        None => Ok(None),
    }
}

/// Every study, by name.
pub async fn list(conn: &mut SqliteConnection) -> Result<Vec<StudyRow>, sqlx::Error> {
    let rows = sqlx::query(&format!("SELECT {STUDY_COLUMNS} ORDER BY s.name"))
        .fetch_all(&mut *conn)
        .await?;
    let mut studies = Vec::with_capacity(rows.len());
    for row in &rows {
        studies.push(from_row(conn, row).await?);
    }
    Ok(studies)
}

/// Deletes a study (its variants go with it); whether it existed.
pub async fn delete(conn: &mut SqliteConnection, name: &str) -> Result<bool, sqlx::Error> {
    let done = sqlx::query("DELETE FROM studies WHERE name = ?")
        .bind(name)
        .execute(conn)
        .await?;
    Ok(done.rows_affected() > 0)
}
