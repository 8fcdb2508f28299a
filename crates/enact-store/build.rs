//! The schema version this build's migrations bring each backend to, which `--version` and
//! `GET /api/v1/version` report (`SQLITE_SCHEMA`, `POSTGRES_SCHEMA`), and the migrations
//! themselves, embedded in the binary (`migrations`). They are read from the workspace's
//! top-level `migrations/` folder, where the schema lives beside the code that uses it.

use std::path::{Path, PathBuf};

fn main() {
    let manifest_dir = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    println!("cargo:rerun-if-changed=build.rs");
    for backend in ["sqlite", "postgres"] {
        let dir = manifest_dir.join("../../migrations").join(backend);
        println!("cargo:rerun-if-changed={}", dir.display());
        let version = latest_migration(&dir).unwrap_or(0);
        println!(
            "cargo:rustc-env=ENACT_HUB_SCHEMA_{}={version}",
            backend.to_uppercase()
        );
        write_embedded(&dir, backend);
    }
}

/// Writes `$OUT_DIR/<backend>_migrations.rs`: a slice of every `*.sql` file's name and text
/// (`include_str!`, so that an edited migration rebuilds the crate), sorted by name. sqlx's
/// `migrate!` did this before; its proc-macro crates were the longest chain of a cold build.
fn write_embedded(dir: &Path, backend: &str) {
    // A binary without its migrations would open no database: no folder is a build error.
    let mut files: Vec<(String, PathBuf)> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("read the migrations in {}: {e}", dir.display()))
        .filter_map(Result::ok)
        .filter(|entry| entry.path().is_file())
        .filter_map(|entry| Some((entry.file_name().into_string().ok()?, entry.path())))
        .filter(|(name, _)| name.ends_with(".sql"))
        .collect();
    files.sort();
    let mut code = String::from("&[\n");
    for (name, path) in files {
        code.push_str(&format!(
            "    ({name:?}, include_str!({:?})),\n",
            path.display().to_string()
        ));
    }
    code.push_str("]\n");
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("OUT_DIR"))
        .join(format!("{backend}_migrations.rs"));
    std::fs::write(&out, code).expect("write the embedded migrations");
}

/// The highest number among `NNNN_*.sql` files in `dir`.
fn latest_migration(dir: &Path) -> Option<i64> {
    std::fs::read_dir(dir)
        .ok()?
        .filter_map(Result::ok)
        .filter_map(|entry| {
            let name = entry.file_name().into_string().ok()?;
            let stem = name.strip_suffix(".sql")?;
            stem.split('_').next()?.parse::<i64>().ok()
        })
        .max()
}
