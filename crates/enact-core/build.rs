//! The git commit this build comes from, which `--version`, `GET /api/v1/version` and every
//! report stamp quote (`version::COMMIT`).
//!
//! Nothing here touches the network. The commit comes from `git rev-parse` when the crate is
//! built from the enact-hub workspace's own checkout, else from the `.cargo_vcs_info.json` that
//! `cargo package` writes into a published crate, else it is "unknown" (an sdist, a tarball, no
//! git installed).

use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    let manifest_dir = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    println!("cargo:rerun-if-changed=build.rs");

    let commit = match checkout_commit(&manifest_dir) {
        Some(commit) => commit,
        None => packaged_commit(&manifest_dir).unwrap_or_else(|| "unknown".to_owned()),
    };
    println!("cargo:rustc-env=ENACT_HUB_COMMIT={commit}");
}

fn git(dir: &Path, args: &[&str]) -> Option<String> {
    let output = Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(args)
        .output()
        .ok()?;
    if !output.status.success() {
        return None;
    }
    let text = String::from_utf8(output.stdout).ok()?.trim().to_owned();
    (!text.is_empty()).then_some(text)
}

/// HEAD's commit when `dir` is `crates/enact-core` at the top of a git work tree (the
/// workspace's checkout), not merely somewhere inside another repository, as an unpacked sdist
/// or `target/package/` may be.
fn checkout_commit(dir: &Path) -> Option<String> {
    let top = git(dir, &["rev-parse", "--show-toplevel"])?;
    let workspace = dir.parent()?.parent()?;
    let same = Path::new(&top).canonicalize().ok()? == workspace.canonicalize().ok()?;
    if !same {
        return None;
    }
    let commit = git(dir, &["rev-parse", "--short=12", "HEAD"])?;
    // Rebuild when HEAD moves: HEAD itself (a checkout, a detached commit) and the branch it
    // points at (a commit). Only existing files are named: cargo reruns the script every build
    // for a missing one.
    let mut watched = vec!["HEAD".to_owned()];
    if let Some(branch) = git(dir, &["symbolic-ref", "-q", "HEAD"]) {
        watched.push(branch);
    }
    watched.push("packed-refs".to_owned());
    for name in watched {
        if let Some(path) = git(dir, &["rev-parse", "--git-path", &name]) {
            let path = dir.join(path);
            if path.exists() {
                println!("cargo:rerun-if-changed={}", path.display());
            }
        }
    }
    Some(commit)
}

/// The commit `cargo package` recorded (`{"git": {"sha1": "…"}}`), shortened as above.
fn packaged_commit(dir: &Path) -> Option<String> {
    let text = std::fs::read_to_string(dir.join(".cargo_vcs_info.json")).ok()?;
    let after = text.split("\"sha1\"").nth(1)?;
    let sha: String = after
        .trim_start_matches([' ', ':', '"'])
        .chars()
        .take_while(char::is_ascii_hexdigit)
        .collect();
    (sha.len() >= 12).then(|| sha[..12].to_owned())
}
