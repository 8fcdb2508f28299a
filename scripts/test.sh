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
if [ ! -d tests/browser/node_modules/playwright-core ] || [ ! -d tests/browser/node_modules/axe-core ]; then
  echo "== npm ci (tests/browser: playwright-core, which downloads no browser, and axe-core)"
  (cd tests/browser && npm ci --no-audit --no-fund)
fi

# The paper's tables are checked by compiling their standalone .tex with pdflatex (Debian's
# texlive-latex-recommended; the tables do without texlive-latex-extra's multirow).
if ! command -v pdflatex >/dev/null 2>&1; then
  echo "== installing texlive-latex-recommended (Debian package, for pdflatex)"
  apt-get update && apt-get install -y --no-install-recommends texlive-latex-recommended
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

# The frame tests run against a real S3-compatible server: moto (PyPI) in server mode on
# loopback, for this run only. Installing it takes a minute of a fresh clone's run, so it is
# installed beside the build and waited for after it (start_moto).
TOOLS="${CARGO_TARGET_DIR:-target}/test-tools"
MOTO_VENV="$TOOLS/moto-venv"
MOTO_INSTALL_LOG="$TOOLS/moto-install.log"
MOTO_INSTALL_PID=""
MOTO_PID=""
if [ ! -x "$MOTO_VENV/bin/moto_server" ]; then
  echo "== installing moto[server] 5.2.5 (PyPI) into $MOTO_VENV, beside the build"
  mkdir -p "$TOOLS"
  if ! python3 -m venv "$MOTO_VENV" >/dev/null 2>&1; then
    apt-get update && apt-get install -y python3-venv
    python3 -m venv "$MOTO_VENV"
  fi
  "$MOTO_VENV/bin/pip" install --quiet --disable-pip-version-check 'moto[server]==5.2.5' \
    >"$MOTO_INSTALL_LOG" 2>&1 &
  MOTO_INSTALL_PID=$!
fi
trap 'kill $MOTO_INSTALL_PID 2>/dev/null || true' EXIT
start_moto() {
  if [ -n "$MOTO_INSTALL_PID" ] && ! wait "$MOTO_INSTALL_PID"; then
    echo "error: installing moto[server] failed:" >&2
    cat "$MOTO_INSTALL_LOG" >&2
    exit 1
  fi
  MOTO_INSTALL_PID=""
  local log="$TOOLS/moto.log" url=""
  "$MOTO_VENV/bin/moto_server" -H 127.0.0.1 -p 0 >"$log" 2>&1 &
  MOTO_PID=$!
  for _ in $(seq 1 300); do
    url=$(grep -o 'http://127\.0\.0\.1:[0-9]*' "$log" | head -n 1 || true)
    [ -n "$url" ] && break
    sleep 0.1
  done
  if [ -z "$url" ]; then
    echo "error: moto did not start:" >&2
    cat "$log" >&2
    exit 1
  fi
  echo "== S3 (moto) on $url"
  export AWS_ENDPOINT="$url" AWS_ALLOW_HTTP=true AWS_REGION=us-east-1
  export AWS_ACCESS_KEY_ID=enact-hub-test AWS_SECRET_ACCESS_KEY=enact-hub-test
  export ENACT_HUB_REQUIRE_S3=1
}

# The service suite runs a second time against PostgreSQL: Debian's server, a throwaway cluster
# on loopback for this run only.
PG_BIN=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1 || true)
if [ -z "$PG_BIN" ]; then
  echo "== installing postgresql (Debian package)"
  apt-get update && apt-get install -y postgresql
  PG_BIN=$(ls -d /usr/lib/postgresql/*/bin | sort -V | tail -n 1)
fi
PGDATA="$(realpath -m "$TOOLS/pgdata")"
PG_PORT=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
rm -rf "$PGDATA" && mkdir -p "$PGDATA"
# PostgreSQL refuses to run as root: the cluster belongs to the postgres user then.
as_pg() {
  if [ "$(id -u)" = 0 ]; then
    chown -R postgres "$PGDATA"
    su postgres -s /bin/sh -c "$*"
  else
    sh -c "$*"
  fi
}
as_pg "'$PG_BIN/initdb' -D '$PGDATA' -A trust -U postgres" >"$TOOLS/initdb.log" 2>&1 || { cat "$TOOLS/initdb.log" >&2; exit 1; }
# max_wal_size: each test's CREATE DATABASE copies its template through the WAL, which grew to
# the default 1 GB of a disk CI shares with the build.
as_pg "'$PG_BIN/pg_ctl' -D '$PGDATA' -l '$PGDATA/server.log' -w -o \"-p $PG_PORT -k /tmp -c listen_addresses=127.0.0.1 -c fsync=off -c max_connections=400 -c max_wal_size=128MB -c min_wal_size=32MB\" start" >/dev/null
cleanup() {
  kill $MOTO_INSTALL_PID $MOTO_PID 2>/dev/null || true
  as_pg "'$PG_BIN/pg_ctl' -D '$PGDATA' -m immediate stop" >/dev/null 2>&1 || true
}
trap cleanup EXIT
# A PostgreSQL pass that fails says whether the server still runs and what it logged last: a
# server gone mid-run fails every later test with "Connection refused" and nothing else.
postgres_failed() {
  echo "== a PostgreSQL pass failed; the server's status, disk and log:" >&2
  as_pg "'$PG_BIN/pg_ctl' -D '$PGDATA' status" >&2 || true
  df -h "$PGDATA" >&2 || true
  free -m >&2 || true
  tail -n 80 "$PGDATA/server.log" >&2 || true
  exit 1
}
echo "== PostgreSQL $("$PG_BIN/postgres" --version | awk '{print $3}') on 127.0.0.1:$PG_PORT"
# Every test makes a database of its own (about 10 MB each, some 300 a pass) and leaves it: the
# cluster is removed after the last pass, so that the disk the PostgreSQL passes take is free
# again for the wheel and `cargo install` that follow. (Dropping them between the passes took
# 25 s and did not lower the peak, which is at the end of the service pass.)
# What the disk holds now: a run that fills it fails wherever it happens to be.
disk() {
  echo "   disk: $(df -h --output=avail "$TOOLS" | tail -n 1 | tr -d ' ') free; $(du -sh "${CARGO_TARGET_DIR:-target}" 2>/dev/null | cut -f1) in the target dir"
}

echo "== cargo fmt --check"
cargo fmt --all -- --check

# Cargo.toml's rust-version is what `cargo install` users are promised. Cargo refuses a toolchain
# older than it; here no dependency may need a newer one, and clippy's `incompatible_msrv` lint
# (on by default, so under -D warnings below) refuses standard-library items newer than it.
echo "== rust-version: no dependency needs a newer Rust"
cargo metadata --format-version 1 --locked | python3 -c '
import json, sys
packages = json.load(sys.stdin)["packages"]
ours = next(p for p in packages if p["name"] == "enact-hub")["rust_version"]
def key(v): return tuple(int(x) for x in v.split("."))
newer = ["%s %s needs %s" % (p["name"], p["version"], p["rust_version"]) for p in packages
         if p.get("rust_version") and key(p["rust_version"]) > key(ours)]
if newer:
    sys.exit("error: rust-version is %s, but %s" % (ours, "; ".join(newer)))
print("   rust-version %s" % ours)
'

# Lints and the test build in one compilation: the workspace's own crates go through
# clippy-driver (what `cargo clippy` runs, here with code generation), so `cargo test
# --all-targets` denies every clippy warning `cargo clippy --workspace --all-targets -- -D
# warnings` would, and the dependencies are compiled once instead of once more for a check
# build (8.5 minutes of a fresh clone's run). Exported, so that every later cargo command of
# this run, test-python.sh's wheel and install included, sees the same compiler and reuses the
# build.
CLIPPY_DRIVER=$(rustup which clippy-driver 2>/dev/null || command -v clippy-driver || true)
if [ -z "$CLIPPY_DRIVER" ]; then
  echo "error: clippy-driver not found (rustup component add clippy)" >&2
  exit 1
fi
export RUSTC_WORKSPACE_WRAPPER="$CLIPPY_DRIVER"
export CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__"

# The live-import test bounds how long any write waits while an import runs (1 s): it is
# marked ignored and run alone, after the rest, so that what it measures is the import's
# locking, not two cores shared with every other test of the suite.
LIVE=live_import::
PG_URL="postgres://postgres@127.0.0.1:$PG_PORT"
echo "== cargo test --workspace --all-targets: the build, linted by clippy -D warnings"
cargo test --workspace --all-targets --locked --no-run
start_moto

# Two test binaries at a time, each with four test threads: most of the suite waits (on its
# servers, Chromium, the processes the kill trials kill) as much as it computes, and one binary
# after another left a third of CI's two cores idle (this pass took 497 s so, 333 s two at a time).
# The longest binaries are started first.
export RUST_TEST_THREADS=4
echo "== cargo test --workspace --all-targets, on SQLite (scripts/test-binaries.py, two binaries at a time)"
./scripts/test-binaries.py --first service --first crash --first pipeline --first demo \
  --first pipeline_parity --first paper_experiments --first scene_graph_parity --first world \
  -- --workspace --all-targets --locked
echo "== $LIVE alone"
cargo test --locked --test service -- --ignored "$LIVE"

# One service suite at a time: run beside the SQLite one, the PostgreSQL suite took 3.4 times
# as long (636 s against 186 s) and slowed the SQLite tests as much, on CI's two cores. The
# server-side jobs' kill trials, which mostly wait for the processes they kill, run beside it.
# The Chromium tests (browser::, episode_browser::) run on SQLite only: they check what the
# pages do in a browser, and every read and write behind those pages is in the rest of the
# suite, which runs on both backends.
disk
echo "== the service suite again, on PostgreSQL, beside the server-side jobs' kill trials"
CRASH_LOG="$TOOLS/crash-postgres.log"
ENACT_HUB_TEST_POSTGRES="$PG_URL" cargo test --locked --test crash -- \
  a_model_run_killed_at_random a_rescore_killed_at_random an_import_job_killed_at_random \
  >"$CRASH_LOG" 2>&1 &
CRASH_PID=$!
ENACT_HUB_TEST_POSTGRES="$PG_URL" cargo test --locked --test service -- --skip browser:: ||
  postgres_failed
echo "== the server-side jobs' kill trials, on PostgreSQL"
if ! wait "$CRASH_PID"; then
  cat "$CRASH_LOG"
  postgres_failed
fi
cat "$CRASH_LOG"
disk
ENACT_HUB_TEST_POSTGRES="$PG_URL" cargo test --locked --test service -- --ignored "$LIVE" ||
  postgres_failed
as_pg "'$PG_BIN/pg_ctl' -D '$PGDATA' -m fast -w stop" >/dev/null
rm -rf "$PGDATA"
disk

echo "== the Python package, the wheel and cargo install (scripts/test-python.sh)"
./scripts/test-python.sh
