//! The schema version this build's migrations bring each backend to, which `--version` and
//! `GET /api/v1/version` report (`store::SQLITE_SCHEMA`, `store::POSTGRES_SCHEMA`). The git
//! commit is enact-core's build script's (`core::version::COMMIT`).

use std::path::{Path, PathBuf};

fn main() {
    let manifest_dir = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    println!("cargo:rerun-if-changed=build.rs");
    for backend in ["sqlite", "postgres"] {
        let dir = manifest_dir.join("migrations").join(backend);
        println!("cargo:rerun-if-changed={}", dir.display());
        let version = latest_migration(&dir).unwrap_or(0);
        println!(
            "cargo:rustc-env=ENACT_HUB_SCHEMA_{}={version}",
            backend.to_uppercase()
        );
    }
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
