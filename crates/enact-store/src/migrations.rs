//! Each backend's migrations, embedded in the binary by the build script and read the way sqlx
//! reads a migrations folder, so that a database migrated by an earlier build (through sqlx's
//! `migrate!`) sees the same versions, descriptions and checksums.

use std::borrow::Cow;
use std::future::Future;
use std::pin::Pin;

use sqlx::error::BoxDynError;
use sqlx::migrate::{Migration, MigrationSource, MigrationType, Migrator};

/// The SQLite migrations: each file's name and text, sorted by name.
pub const SQLITE: Embedded = Embedded(include!(concat!(env!("OUT_DIR"), "/sqlite_migrations.rs")));

/// The PostgreSQL migrations: each file's name and text, sorted by name.
pub const POSTGRES: Embedded = Embedded(include!(concat!(
    env!("OUT_DIR"),
    "/postgres_migrations.rs"
)));

/// One backend's migration files as (file name, SQL).
#[derive(Debug, Clone, Copy)]
pub struct Embedded(pub &'static [(&'static str, &'static str)]);

impl Embedded {
    /// The migrator that runs these migrations.
    pub async fn migrator(self) -> Result<Migrator, sqlx::migrate::MigrateError> {
        Migrator::new(self).await
    }

    /// The migrations, as sqlx's folder source makes them: `<version>_<description>.sql`, the
    /// description with `_` read as a space, no transaction when the file starts with
    /// `-- no-transaction`, ordered by version.
    pub fn migrations(self) -> Result<Vec<Migration>, String> {
        let mut migrations = Vec::with_capacity(self.0.len());
        for &(name, sql) in self.0 {
            let Some((version, rest)) = name.split_once('_') else {
                continue;
            };
            let version: i64 = version
                .parse()
                .map_err(|_| format!("migration {name:?}: the name must start with a number"))?;
            let migration_type = MigrationType::from_filename(rest);
            let description = rest
                .trim_end_matches(migration_type.suffix())
                .replace('_', " ");
            migrations.push(Migration::new(
                version,
                Cow::Owned(description),
                migration_type,
                Cow::Borrowed(sql),
                sql.starts_with("-- no-transaction"),
            ));
        }
        migrations.sort_by_key(|m| m.version);
        Ok(migrations)
    }
}

impl MigrationSource<'static> for Embedded {
    fn resolve(
        self,
    ) -> Pin<Box<dyn Future<Output = Result<Vec<Migration>, BoxDynError>> + Send + 'static>> {
        Box::pin(async move { self.migrations().map_err(BoxDynError::from) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_file_is_a_migration_numbered_in_order_from_one() {
        for (backend, embedded, latest) in [
            ("sqlite", SQLITE, super::super::SQLITE_SCHEMA),
            ("postgres", POSTGRES, super::super::POSTGRES_SCHEMA),
        ] {
            let migrations = embedded.migrations().expect("well named");
            assert_eq!(migrations.len(), embedded.0.len(), "{backend}");
            let versions: Vec<i64> = migrations.iter().map(|m| m.version).collect();
            assert_eq!(versions, (1..=latest).collect::<Vec<_>>(), "{backend}");
        }
    }

    #[test]
    fn a_migration_reads_as_sqlx_reads_its_file() {
        let first = SQLITE.migrations().expect("well named").remove(0);
        let (name, sql) = SQLITE.0[0];
        assert_eq!(name, "0001_foundation.sql");
        assert_eq!(first.description, "foundation");
        assert_eq!(first.migration_type, MigrationType::Simple);
        assert!(!first.no_tx);
        assert_eq!(first.sql, sql);
        // The checksum sqlx stores in `_sqlx_migrations` and compares on every start.
        use sha2::{Digest, Sha384};
        assert_eq!(&*first.checksum, Sha384::digest(sql.as_bytes()).as_slice());
        let two_words = Embedded(&[("0007_two_words.up.sql", "SELECT 1;")])
            .migrations()
            .expect("well named");
        assert_eq!(two_words[0].description, "two words");
        assert_eq!(two_words[0].migration_type, MigrationType::ReversibleUp);
        let unnumbered = Embedded(&[("first_things.sql", "SELECT 1;")]).migrations();
        assert!(unnumbered.unwrap_err().contains("first_things.sql"));
    }
}
