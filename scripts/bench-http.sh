#!/usr/bin/env bash
# Import rate and loopback HTTP throughput/latency of enact-hub, for BENCHMARKS.md.
#
#   scripts/bench-http.sh [RELEASE_DIR ...]
#
# Imports each release into a fresh database (timing the import), starts the service on
# 127.0.0.1, and loads it with wrk (Debian package `wrk`, installed if missing) at 64
# connections: item JSON and frame GET. Defaults to ENACT's real sample and parity releases
# from ../shared/fixtures, or to the demo dataset when they are absent. Only loopback traffic.
set -euo pipefail
cd "$(dirname "$0")/.."

DURATION=${DURATION:-10s}
CONNECTIONS=${CONNECTIONS:-64}
PORT=${PORT:-18080}
OUT=bench-out
mkdir -p "$OUT"

if ! command -v wrk >/dev/null 2>&1; then
  echo "installing wrk (Debian package)" >&2
  apt-get install -y wrk >/dev/null 2>&1 || { apt-get update >/dev/null && apt-get install -y wrk >/dev/null; }
fi

# ENACT_HUB_BIN: a built binary to measure instead of this checkout's release build (e.g. the
# `dist` profile's, target/dist/enact-hub).
if [ -n "${ENACT_HUB_BIN:-}" ]; then
  BIN=$ENACT_HUB_BIN
else
  cargo build --release --locked --bin enact-hub >&2
  BIN=${CARGO_TARGET_DIR:-target}/release/enact-hub
fi
DB="$OUT/bench.db"
rm -f "$DB" "$DB-wal" "$DB-shm"

releases=("$@")
if [ ${#releases[@]} -eq 0 ]; then
  for r in ../shared/fixtures/enact-parity ../shared/fixtures/enact-sample; do
    [ -d "$r" ] && releases+=("$r")
  done
fi

echo "## import"
for r in "${releases[@]}"; do
  name=$(basename "$r")
  "$BIN" import "$r" --db "$DB" --dataset "$name" --json >"$OUT/import-$name.json" 2>/dev/null
  python3 - "$OUT/import-$name.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
s = r["seconds"]
items = r["new_items"]
print(f"{r['dataset']}: {items} items, {r['frames']} frames ({r['new_frames']} new) in {s:.3f} s "
      f"= {items/s:.0f} items/s, {r['frames']/s:.0f} frames/s")
PY
done

if [ ${#releases[@]} -eq 0 ]; then
  DATASET=demo
  "$BIN" serve --demo --db "$DB" --addr "127.0.0.1:$PORT" >"$OUT/server.log" 2>&1 &
else
  DATASET=$(basename "${releases[-1]}")
  RUST_LOG=warn "$BIN" serve --db "$DB" --addr "127.0.0.1:$PORT" >"$OUT/server.log" 2>&1 &
fi
SERVER=$!
trap 'kill $SERVER 2>/dev/null || true' EXIT
for _ in $(seq 100); do
  curl -fsS "http://127.0.0.1:$PORT/healthz" >/dev/null 2>&1 && break
  sleep 0.2
done

BASE="http://127.0.0.1:$PORT"
ITEM_URL=$(curl -fsS "$BASE/api/v1/datasets/$DATASET/items?per_page=1" | python3 -c 'import json,sys; print(json.load(sys.stdin)["items"][0]["url"])')
# Every frame URL of the dataset's first 50 items, requested round-robin.
python3 scripts/lib/frame_paths.py "$BASE" "$DATASET" >"$OUT/frames.lua"
FRAME_BYTES=$(curl -fsS "$BASE$(sed -n 's/^paths = {"\([^"]*\)".*/\1/p' "$OUT/frames.lua")" | wc -c)

# Warm the frame cache once.
wrk -t2 -c8 -d2s -s "$OUT/frames.lua" "$BASE" >/dev/null

echo
echo "## item JSON: GET $ITEM_URL (${CONNECTIONS} connections, $DURATION)"
wrk -t2 -c"$CONNECTIONS" -d"$DURATION" --latency "$BASE$ITEM_URL" | tee "$OUT/wrk-item.txt"
echo
echo "## frame GET: $(grep -o '"/api' "$OUT/frames.lua" | wc -l) frames round-robin, first one $FRAME_BYTES bytes (${CONNECTIONS} connections, $DURATION)"
wrk -t2 -c"$CONNECTIONS" -d"$DURATION" --latency -s "$OUT/frames.lua" "$BASE" | tee "$OUT/wrk-frame.txt"
