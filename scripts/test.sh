#!/usr/bin/env bash
# Runs the whole test suite as CI does: formatting, lints, then every test target.
# Anything a test needs that a fresh machine lacks is installed here, never at build or run time.
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v cargo >/dev/null 2>&1; then
  echo "error: cargo is not installed (https://rustup.rs)" >&2
  exit 1
fi

# The annotation end-to-end test drives headless Chromium through playwright-core (Node).
if ! command -v chromium >/dev/null 2>&1; then
  echo "== installing chromium and chromium-driver (Debian packages)"
  apt-get update && apt-get install -y chromium chromium-driver
fi
if ! command -v node >/dev/null 2>&1; then
  echo "== installing nodejs and npm (Debian packages)"
  apt-get update && apt-get install -y nodejs npm
fi
if [ ! -d tests/browser/node_modules/playwright-core ]; then
  echo "== npm ci (tests/browser: playwright-core, which downloads no browser)"
  (cd tests/browser && npm ci --no-audit --no-fund)
fi

# The example client's end-to-end test runs clients/enact_client.py with python3 and requests.
if ! command -v python3 >/dev/null 2>&1 || ! python3 -c 'import requests' >/dev/null 2>&1; then
  echo "== installing python3 and python3-requests (Debian packages)"
  apt-get update && apt-get install -y python3 python3-requests
  # A python3 earlier on PATH (pyenv, a venv) does not see Debian's package: take it from PyPI.
  if ! python3 -c 'import requests' >/dev/null 2>&1; then
    python3 -m pip install --quiet requests
  fi
fi

echo "== cargo fmt --check"
cargo fmt --all -- --check

echo "== cargo clippy --all-targets -- -D warnings"
cargo clippy --all-targets --locked -- -D warnings

echo "== cargo test --all-targets"
cargo test --all-targets --locked
