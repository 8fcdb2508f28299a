#!/usr/bin/env bash
# Mixed load over loopback for BENCHMARKS.md ("Mixed load"): 50 annotators (log in, open the
# next item, save drafts, submit), 10 submitters posting full-size submissions (8,972 items
# each) and 10 readers (leaderboard, item lists, item pages and JSON, frames), for LOAD_SECONDS
# (default 60). Fails if any reply is a 5xx or says `database is locked`. Prints the load
# average before and after, then per route the requests, req/s and p50/p99/max latency, and the
# submissions scored per second.
#
#   scripts/load-mixed.sh
#   IMPORT_MIDWAY=1 scripts/load-mixed.sh
#
# IMPORT_MIDWAY=1: a world release of 2,628 items (`enact-hub simulate --activity all` then
# `generate --num-to-sample 43`, kept in bench-out/mixed/world-2628 for the next run) is
# imported as dataset "world" with the command line into the served database, IMPORT_AFTER
# seconds (default 10) into the load; the table is printed again for the requests sent while
# the import ran, with the annotators' writes together. ENACT_HUB_BIN: a server binary to measure instead of this checkout's (e.g. a build
# of main, for before/after); the load client is always this checkout's. SERVE_ARGS: more
# `serve` flags (e.g. `--heavy-nice 19`).
#
# The demo dataset is generated into a fresh database, replicated in SQL to 8,972 items, and
# the accounts are made with the library (examples/mixed_load.rs setup) before the server
# starts; then the release server runs alone on it and examples/mixed_load.rs plays the load.
set -euo pipefail
cd "$(dirname "$0")/.."

SECONDS_TO_RUN=${LOAD_SECONDS:-60}
PORT=${PORT:-18093}
ITEMS=${ITEMS:-8972}
OUT=bench-out/mixed
BASE="http://127.0.0.1:$PORT"
mkdir -p "$OUT"
cargo build --release --locked --bin enact-hub --example mixed_load >&2
BIN=${ENACT_HUB_BIN:-${CARGO_TARGET_DIR:-target}/release/enact-hub}
# The command-line import and the release generation: this checkout's build.
OWN_BIN=${CARGO_TARGET_DIR:-target}/release/enact-hub
LOAD=${CARGO_TARGET_DIR:-target}/release/examples/mixed_load
echo "server: $BIN; load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
WORLD=$OUT/world-2628
if [ "${IMPORT_MIDWAY:-0}" = 1 ] && [ ! -f "$WORLD/QA/enact_ordering.jsonl" ]; then
  rm -rf "$OUT/world-replay" "$WORLD"
  "$OWN_BIN" simulate --seed 3 --activity all --out "$OUT/world-replay" >&2
  "$OWN_BIN" generate "$OUT/world-replay" --num-to-sample 43 --out "$WORLD" >&2
fi
DB="$OUT/mixed.db"
rm -f "$DB" "$DB-wal" "$DB-shm"

wait_ready() {
  for _ in $(seq 300); do
    curl -fsS "$BASE/healthz" >/dev/null 2>&1 && return 0
    sleep 0.2
  done
  echo "error: the server did not start (see $OUT/server.log)" >&2
  exit 1
}

# The demo, generated and imported by a first start.
RUST_LOG=warn "$BIN" serve --demo --db "$DB" --addr "127.0.0.1:$PORT" >"$OUT/server.log" 2>&1 &
SERVER=$!
trap 'kill $SERVER 2>/dev/null || true' EXIT
wait_ready
kill "$SERVER"
wait "$SERVER" || true

python3 scripts/lib/replicate_items.py "$DB" demo "$ITEMS"
"$LOAD" setup --db "$DB" --dataset demo --out "$OUT/accounts.json"

# shellcheck disable=SC2086 # SERVE_ARGS is a list of flags
METRICS_TOKEN=load-mixed-metrics
RUST_LOG=warn "$BIN" serve --db "$DB" --addr "127.0.0.1:$PORT" --metrics-token "$METRICS_TOKEN" \
  --daily-quota 100000 --total-quota 100000 ${SERVE_ARGS:-} >>"$OUT/server.log" 2>&1 &
SERVER=$!
wait_ready
WINDOW=()
if [ "${IMPORT_MIDWAY:-0}" = 1 ]; then
  rm -f "$OUT/import.window"
  (
    sleep "${IMPORT_AFTER:-10}"
    date +%s%3N >"$OUT/import.window"
    "$OWN_BIN" import "$WORLD" --db "$DB" --dataset world >"$OUT/import.log" 2>&1
    date +%s%3N >>"$OUT/import.window"
  ) &
  IMPORTER=$!
  trap 'kill $SERVER $IMPORTER 2>/dev/null || true' EXIT
  WINDOW=(--window "$OUT/import.window")
fi
status=0
"$LOAD" run --base "$BASE" --accounts "$OUT/accounts.json" --seconds "$SECONDS_TO_RUN" "${WINDOW[@]}" || status=$?
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
# How long writes waited for their turn, by lane (the server's histogram: each figure is the
# upper bound of the bucket the quantile falls in); the bulk lane's is the write gate's bound
# at work.
if curl -fsS -H "Authorization: Bearer $METRICS_TOKEN" "$BASE/metrics" >"$OUT/metrics.txt" 2>/dev/null; then
  python3 scripts/lib/write_waits.py "$OUT/metrics.txt"
fi
if [ "${IMPORT_MIDWAY:-0}" = 1 ]; then
  wait "$IMPORTER" || { echo "error: the import failed (see $OUT/import.log)" >&2; status=1; }
  tail -n 3 "$OUT/import.log"
fi
exit "$status"
