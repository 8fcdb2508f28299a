//! Where the shared ENACT fixtures are, for the tests and benchmarks that compare with them.

use std::path::{Path, PathBuf};

/// `$ENACT_FIXTURES` (the `fixtures` directory itself), else the first `shared/fixtures` found
/// walking up from the crate (at most three levels). `None` when neither exists: comparisons
/// with ENACT's outputs then say so and skip; everything else runs on generated data.
pub fn shared_fixtures() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("ENACT_FIXTURES") {
        let dir = PathBuf::from(dir);
        return dir.is_dir().then_some(dir);
    }
    let mut dir = Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf();
    for _ in 0..=3 {
        let candidate = dir.join("shared").join("fixtures");
        if candidate.is_dir() {
            return Some(candidate);
        }
        if !dir.pop() {
            break;
        }
    }
    None
}
