#!/usr/bin/env bash
# Runs the whole test suite as CI does: formatting, lints, then every test target.
# Anything a test needs that a fresh machine lacks is installed here, never at build or run time.
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v cargo >/dev/null 2>&1; then
  echo "error: cargo is not installed (https://rustup.rs)" >&2
  exit 1
fi

echo "== cargo fmt --check"
cargo fmt --all -- --check

echo "== cargo clippy --all-targets -- -D warnings"
cargo clippy --all-targets --locked -- -D warnings

echo "== cargo test --all-targets"
cargo test --all-targets --locked
