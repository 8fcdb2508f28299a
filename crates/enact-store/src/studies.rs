//! Rows of studies and their variants.

use super::db::{Conn, Fields, WriteConn, on};

use enact_core::study::VariantSpec;

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

/// Writes a study and its variants (`dataset id` beside each). A name in use refuses the
/// insert with a violation of [`UniqueKey::STUDY_NAME`](super::db::UniqueKey::STUDY_NAME).
pub async fn insert(
    conn: &mut WriteConn,
    name: &str,
    baseline: i64,
    created_by: &str,
    variants: &[(VariantSpec, i64)],
) -> Result<i64, sqlx::Error> {
    on!(conn, |c| {
        let id: i64 = sqlx::query_scalar(
            "INSERT INTO studies (name, baseline, created_by) VALUES ($1, $2, $3) RETURNING id",
        )
        .bind(name)
        .bind(baseline)
        .bind(created_by)
        .fetch_one(&mut *c)
        .await?;
        for (position, (spec, dataset)) in variants.iter().enumerate() {
            sqlx::query(
                "INSERT INTO study_variants (study, position, family, label, dataset) \
             VALUES ($1, $2, $3, $4, $5)",
            )
            .bind(id)
            .bind(position as i64)
            .bind(&spec.family)
            .bind(&spec.label)
            .bind(dataset)
            .execute(&mut *c)
            .await?;
        }
        Ok(id)
    })
}

async fn variants_of(conn: &mut Conn, study: i64) -> Result<Vec<(VariantSpec, i64)>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(
            "SELECT v.family, v.label, d.name, d.id FROM study_variants v \
         JOIN datasets d ON d.id = v.dataset WHERE v.study = $1 ORDER BY v.position",
        )
        .bind(study)
        .fetch_all(&mut *c)
        .await?;
        rows.iter()
            .map(|row| {
                Ok((
                    VariantSpec {
                        family: row.try_get("family")?,
                        label: row.try_get("label")?,
                        dataset: row.try_get("name")?,
                    },
                    row.try_get("id")?,
                ))
            })
            .collect()
    })
}

const STUDY_COLUMNS: &str = "s.id, s.name, d.name AS baseline_name, d.id AS baseline_id, \
    s.created_at, s.created_by FROM studies s JOIN datasets d ON d.id = s.baseline";

async fn from_row(conn: &mut Conn, row: &impl Fields) -> Result<StudyRow, sqlx::Error> {
    on!(conn, |c| {
        let id: i64 = row.try_get("id")?;
        Ok(StudyRow {
            id,
            name: row.try_get("name")?,
            baseline: row.try_get("baseline_name")?,
            baseline_id: row.try_get("baseline_id")?,
            created_at: row.try_get("created_at")?,
            created_by: row.try_get("created_by")?,
            variants: variants_of(&mut *c, id).await?,
        })
    })
}

pub async fn by_name(conn: &mut Conn, name: &str) -> Result<Option<StudyRow>, sqlx::Error> {
    on!(conn, |c| {
        let row = sqlx::query(&format!("SELECT {STUDY_COLUMNS} WHERE s.name = $1"))
            .bind(name)
            .fetch_optional(&mut *c)
            .await?;
        match row {
            Some(row) => Ok(Some(from_row(&mut *c, &row).await?)),
            None => Ok(None),
        }
    })
}

/// Every study, by name.
pub async fn list(conn: &mut Conn) -> Result<Vec<StudyRow>, sqlx::Error> {
    on!(conn, |c| {
        let rows = sqlx::query(&format!("SELECT {STUDY_COLUMNS} ORDER BY s.name"))
            .fetch_all(&mut *c)
            .await?;
        let mut studies = Vec::with_capacity(rows.len());
        for row in &rows {
            studies.push(from_row(&mut *c, row).await?);
        }
        Ok(studies)
    })
}

/// Deletes a study (its variants go with it); whether it existed.
pub async fn delete(conn: &mut WriteConn, name: &str) -> Result<bool, sqlx::Error> {
    on!(conn, |c| {
        let done = sqlx::query("DELETE FROM studies WHERE name = $1")
            .bind(name)
            .execute(&mut *c)
            .await?;
        Ok(done.rows_affected() > 0)
    })
}
