#!/usr/bin/env bash
# Model runs, for BENCHMARKS.md: `enact-hub run` against a stand-in chat-completions server
# (scripts/lib/standin_chat.py) that answers every request after LATENCY_MS (200 by default).
#
#   1. throughput: 1,000 six-image items at --concurrency 64, database mode (`--db`);
#   2. the same against a served hub (`--hub`, replies in a cache file);
#   3. the Python example client (clients/enact_client.py, one item at a time) on the same
#      1,000 items through the same hub;
#   4. peak resident memory (VmHWM, from /usr/bin/time) of `run` over a full-size dataset of
#      8,972 items at --concurrency 64.
#
#   scripts/bench-runs.sh [RELEASE_DIR]
#
# Items come from RELEASE_DIR when given, else from a world release generated here with 512 ×
# 512 frames (the size of ENACT's; the parity fixture's frames are 2 KB stand-ins, too small to
# load a run like real images); they are replicated in SQL (scripts/lib/replicate_items.py)
# up to each size. ENACT_HUB_BIN: a built binary to measure instead of building one. Needs
# python3 (with `requests`) and /usr/bin/time; loopback only.
set -euo pipefail
cd "$(dirname "$0")/.."

LATENCY_MS=${LATENCY_MS:-200}
PORT=${PORT:-18095}
OUT=bench-out/runs
mkdir -p "$OUT"
if [ -n "${ENACT_HUB_BIN:-}" ]; then
  BIN=$ENACT_HUB_BIN
else
  cargo build --release --locked --bin enact-hub >&2
  BIN=${CARGO_TARGET_DIR:-target}/release/enact-hub
fi

release=${1:-}
if [ -z "$release" ]; then
  release="$OUT/world"
  if [ ! -f "$release/QA/enact_ordering.jsonl" ]; then
    rm -rf "$OUT/replay" "$release"
    "$BIN" simulate --seed 3 --activity all --out "$OUT/replay" >&2
    "$BIN" generate "$OUT/replay" --out "$release" >&2
  fi
fi
echo "frames: $(find "$release" -name '*.png' | wc -l) PNGs, $(du -sh "$release" | cut -f1) in all"

pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; }
trap cleanup EXIT

coproc STANDIN { exec python3 scripts/lib/standin_chat.py "$LATENCY_MS"; }
pids+=("$STANDIN_PID")
read -r standin_port <&"${STANDIN[0]}"
ENDPOINT="http://127.0.0.1:$standin_port/v1"
requests_so_far() { curl -sf "http://127.0.0.1:$standin_port/stats" | python3 -c 'import json,sys; print(json.load(sys.stdin)["requests"])'; }

fresh_db() { rm -f "$1" "$1-wal" "$1-shm"; "$BIN" import "$release" --db "$1" --dataset bench --json >/dev/null 2>&1; }

# Six-image items only (L = 6), replicated to 1,000.
SIX="$OUT/six.db"
fresh_db "$SIX"
python3 - "$SIX" <<'PY'
import sqlite3, sys
con = sqlite3.connect(sys.argv[1])
con.execute("PRAGMA foreign_keys=ON")
con.execute("DELETE FROM items WHERE step_length != 6")
con.execute("UPDATE content_generation SET value = value + 1")
con.commit()
PY
python3 scripts/lib/replicate_items.py "$SIX" bench 1000
FULL="$OUT/full.db"
fresh_db "$FULL"
python3 scripts/lib/replicate_items.py "$FULL" bench 8972

# `run` at concurrency 64; prints "seconds items/s peak-RSS-MiB requests".
timed_run() {
  local label=$1; shift
  local before after
  before=$(requests_so_far)
  /usr/bin/time -f "%e %M" -o "$OUT/$label.time" "$BIN" run bench --endpoint "$ENDPOINT" \
    --model standin --concurrency 64 --no-submit --json "$@" >"$OUT/$label.json" 2>"$OUT/$label.log"
  after=$(requests_so_far)
  python3 - "$OUT/$label.time" "$OUT/$label.json" "$label" "$((after - before))" <<'PY'
import json, sys
seconds, rss_kib = open(sys.argv[1]).read().split()[-2:]
report = json.load(open(sys.argv[2]))
p = report["progress"]
print(f"{sys.argv[3]}: {p['answered']} answered, {p['failed']} failed in {float(seconds):.2f} s "
      f"= {p['answered'] / float(seconds):.1f} items/s; peak RSS {int(rss_kib) / 1024:.1f} MiB; "
      f"{sys.argv[4]} requests ({p['refused']} refused)")
PY
}

echo "== 1,000 six-image items, --concurrency 64, stand-in latency ${LATENCY_MS} ms (ideal: $((64 * 1000 / LATENCY_MS)) items/s)"
timed_run six-db --db "$SIX"

echo "== the same through a served hub (--hub, replies in a cache file)"
cp "$SIX" "$OUT/served.db"
TOKEN=$("$BIN" token create --db "$OUT/served.db" --name bench | tail -n 1)
"$BIN" serve --db "$OUT/served.db" --addr "127.0.0.1:$PORT" >"$OUT/serve.log" 2>&1 &
pids+=("$!")
for _ in $(seq 100); do curl -sf "http://127.0.0.1:$PORT/healthz" >/dev/null && break; sleep 0.1; done
rm -f "$OUT/six-hub.cache"
ENACT_HUB_TOKEN=$TOKEN timed_run six-hub --hub "http://127.0.0.1:$PORT" --cache "$OUT/six-hub.cache"

echo "== the Python example client (clients/enact_client.py) on the same items through the same hub"
before=$(requests_so_far)
start=$(date +%s.%N)
ENACT_HUB_TOKEN=$TOKEN PYTHONPATH=python /usr/bin/time -f "%e %M" -o "$OUT/python.time" \
  python3 clients/enact_client.py --hub "http://127.0.0.1:$PORT" --dataset bench \
  --model-url "$ENDPOINT" --model standin --name python-example >"$OUT/python.log" 2>&1
after=$(requests_so_far)
read -r seconds rss < "$OUT/python.time"
python3 -c "import sys; s=float('$seconds'); print(f'python example: 1000 items in {s:.2f} s = {1000/s:.1f} items/s; peak RSS {int($rss)/1024:.1f} MiB; $((after - before)) requests')"

echo "== 8,972 items (the full ENACT size), --concurrency 64: peak memory"
timed_run full-db --db "$FULL"
