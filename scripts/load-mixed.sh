#!/usr/bin/env bash
# Mixed load over loopback for BENCHMARKS.md ("Mixed load"): 50 annotators (log in, open the
# next item, save drafts, submit), 10 submitters posting full-size submissions (8,972 items
# each) and 10 readers (leaderboard, item lists, item pages and JSON, frames), for LOAD_SECONDS
# (default 60). Fails if any reply is a 5xx or says `database is locked`.
#
#   scripts/load-mixed.sh
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
BIN=${CARGO_TARGET_DIR:-target}/release/enact-hub
LOAD=${CARGO_TARGET_DIR:-target}/release/examples/mixed_load
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

RUST_LOG=warn "$BIN" serve --db "$DB" --addr "127.0.0.1:$PORT" \
  --daily-quota 100000 --total-quota 100000 >>"$OUT/server.log" 2>&1 &
SERVER=$!
wait_ready
"$LOAD" run --base "$BASE" --accounts "$OUT/accounts.json" --seconds "$SECONDS_TO_RUN"
