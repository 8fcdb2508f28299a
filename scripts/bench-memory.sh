#!/usr/bin/env bash
# The server's memory under browsing, for BENCHMARKS.md: resident set size (RSS) of `serve`
# at start and after every item of a dataset has been fetched once through the JSON API, for
# a full-size dataset (8,972 items) and for 100,000 distinct items. The caches are bounded
# (`serve --item-cache-mib` and the others), so the second figure must stay near the first.
#
#   scripts/bench-memory.sh [RELEASE_DIR]
#
# Items come from ENACT's parity release (../shared/fixtures/enact-parity) when present, else
# from a world release generated here; they are replicated in SQL (distinct ids sharing frames,
# scripts/lib/replicate_items.py) up to each size. Needs curl and python3; loopback only.
set -euo pipefail
cd "$(dirname "$0")/.."

PORT=${PORT:-18090}
OUT=bench-out/memory
mkdir -p "$OUT"
cargo build --release --locked --bin enact-hub >&2
BIN=${CARGO_TARGET_DIR:-target}/release/enact-hub

release=${1:-../shared/fixtures/enact-parity}
if [ ! -d "$release" ]; then
  release="$OUT/world"
  rm -rf "$OUT/replay" "$release"
  "$BIN" simulate --seed 3 --activity all --image-size 256 --out "$OUT/replay" >&2
  "$BIN" generate "$OUT/replay" --out "$release" >&2
fi

rss_kib() { awk '/^VmRSS:/ {print $2}' "/proc/$1/status"; }
hwm_kib() { awk '/^VmHWM:/ {print $2}' "/proc/$1/status"; }

measure() {
  local items=$1 db="$OUT/memory-$1.db"
  rm -f "$db" "$db-wal" "$db-shm"
  "$BIN" import "$release" --db "$db" --dataset bench --json >/dev/null 2>&1
  python3 scripts/lib/replicate_items.py "$db" bench "$items"
  python3 - "$db" "$OUT/urls-$items.txt" "$PORT" <<'PY'
import sqlite3, sys, urllib.parse
db, out, port = sys.argv[1], sys.argv[2], sys.argv[3]
con = sqlite3.connect(db)
with open(out, "w") as f:
    for (item_id,) in con.execute(
        "SELECT item_id FROM items WHERE dataset_id = (SELECT id FROM datasets WHERE name = 'bench')"
    ):
        q = urllib.parse.quote(item_id, safe="")
        f.write(f'url = "http://127.0.0.1:{port}/api/v1/datasets/bench/items/{q}"\noutput = "/dev/null"\n')
PY
  # shellcheck disable=SC2086
  RUST_LOG=warn "$BIN" serve --db "$db" --addr "127.0.0.1:$PORT" ${SERVE_FLAGS:-} >"$OUT/server-$items.log" 2>&1 &
  local server=$!
  for _ in $(seq 100); do
    curl -fsS "http://127.0.0.1:$PORT/healthz" >/dev/null 2>&1 && break
    sleep 0.1
  done
  local start_rss
  start_rss=$(rss_kib $server)
  local started=$SECONDS
  # Twice over: the second pass reads what the bounded caches kept.
  curl -sS --fail --parallel --parallel-max 8 -K "$OUT/urls-$items.txt"
  curl -sS --fail --parallel --parallel-max 8 -K "$OUT/urls-$items.txt"
  local seconds=$((SECONDS - started))
  local end_rss peak
  end_rss=$(rss_kib $server)
  peak=$(hwm_kib $server)
  kill $server
  wait $server 2>/dev/null || true
  printf '%s items (each fetched twice, %s s): RSS %.1f MB at start, %.1f MB after, peak %.1f MB\n' \
    "$items" "$seconds" "$(echo "$start_rss/1024" | bc -l)" "$(echo "$end_rss/1024" | bc -l)" \
    "$(echo "$peak/1024" | bc -l)"
}

echo "## serve RSS while browsing (default cache bounds)"
measure 8972
measure 100000
