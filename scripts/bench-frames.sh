#!/usr/bin/env bash
# Frame GET throughput by where the bytes are, in one run on loopback, for BENCHMARKS.md.
#
#   scripts/bench-frames.sh [RELEASE_DIR]
#
# Imports the release (default: ENACT's real sample from ../shared/fixtures, else the demo
# dataset) into a fresh database, then serves its frames from: the database; a local folder
# (`file://`); S3 (moto in server mode on loopback, from PyPI, as scripts/test.sh installs it);
# and S3 with presigned redirects. Each with the frame cache off (every request reads the
# store) and on (the default 128 MiB, warmed). wrk (Debian package) at 64 connections.
set -euo pipefail
cd "$(dirname "$0")/.."

DURATION=${DURATION:-10s}
CONNECTIONS=${CONNECTIONS:-64}
PORT=${PORT:-18090}
OUT=bench-out/frames
rm -rf "$OUT"
mkdir -p "$OUT"

if ! command -v wrk >/dev/null 2>&1; then
  echo "installing wrk (Debian package)" >&2
  apt-get install -y wrk >/dev/null 2>&1 || { apt-get update >/dev/null && apt-get install -y wrk >/dev/null; }
fi
TOOLS="${CARGO_TARGET_DIR:-target}/test-tools"
MOTO_VENV="$TOOLS/moto-venv"
if [ ! -x "$MOTO_VENV/bin/moto_server" ]; then
  mkdir -p "$TOOLS"
  python3 -m venv "$MOTO_VENV"
  "$MOTO_VENV/bin/pip" install --quiet --disable-pip-version-check 'moto[server]==5.2.5'
fi

cargo build --release --locked --bin enact-hub >&2
BIN=${CARGO_TARGET_DIR:-target}/release/enact-hub
DB="$OUT/bench.db"

RELEASE=${1:-../shared/fixtures/enact-sample}
if [ -d "$RELEASE" ]; then
  DATASET=$(basename "$RELEASE")
  "$BIN" import "$RELEASE" --db "$DB" --dataset "$DATASET" >/dev/null 2>&1
else
  DATASET=demo
  timeout 20 "$BIN" serve --demo --db "$DB" --addr "127.0.0.1:$PORT" >/dev/null 2>&1 || true
fi

"$MOTO_VENV/bin/moto_server" -H 127.0.0.1 -p 0 >"$OUT/moto.log" 2>&1 &
MOTO=$!
SERVER=""
trap 'kill $MOTO $SERVER 2>/dev/null || true' EXIT
for _ in $(seq 300); do
  MOTO_URL=$(grep -o 'http://127\.0\.0\.1:[0-9]*' "$OUT/moto.log" | head -n 1 || true)
  [ -n "$MOTO_URL" ] && break
  sleep 0.1
done
export AWS_ENDPOINT="$MOTO_URL" AWS_ALLOW_HTTP=true AWS_REGION=us-east-1
export AWS_ACCESS_KEY_ID=bench AWS_SECRET_ACCESS_KEY=bench
curl -fsS -X PUT "$MOTO_URL/frames" >/dev/null
S3=s3://frames/bench
FOLDER="file://$(realpath "$OUT")/objects"
"$BIN" frames migrate --db "$DB" --to "$FOLDER" >/dev/null 2>&1
"$BIN" frames migrate --db "$DB" --to "$S3" --from "$FOLDER" >/dev/null 2>&1
"$BIN" frames migrate --db "$DB" --to database --from "$FOLDER" >/dev/null 2>&1

BASE="http://127.0.0.1:$PORT"
start() {
  RUST_LOG=warn "$BIN" serve --db "$DB" --addr "127.0.0.1:$PORT" "$@" >"$OUT/server.log" 2>&1 &
  SERVER=$!
  for _ in $(seq 100); do
    curl -fsS "$BASE/healthz" >/dev/null 2>&1 && break
    sleep 0.2
  done
}
stop() {
  kill "$SERVER" 2>/dev/null || true
  wait "$SERVER" 2>/dev/null || true
  SERVER=""
}

# Every frame URL of the dataset's first 50 items, requested round-robin.
start
python3 scripts/lib/frame_paths.py "$BASE" "$DATASET" >"$OUT/frames.lua"
stop
FRAMES=$(grep -o '"/api' "$OUT/frames.lua" | wc -l)
echo "dataset $DATASET: $FRAMES frames round-robin, $CONNECTIONS connections, $DURATION each"

run() {
  local label=$1
  shift
  start "$@"
  wrk -t2 -c8 -d2s -s "$OUT/frames.lua" "$BASE" >/dev/null
  wrk -t2 -c"$CONNECTIONS" -d"$DURATION" --latency -s "$OUT/frames.lua" "$BASE" >"$OUT/$label.txt"
  stop
  python3 - "$label" "$OUT/$label.txt" <<'PY'
import re, sys
label, text = sys.argv[1], open(sys.argv[2]).read()
rps = re.search(r"Requests/sec:\s+([\d.]+)", text).group(1)
lat = dict(re.findall(r"^\s+(50|99)%\s+(\S+)", text, re.M))
errors = re.search(r"Non-2xx or 3xx responses: (\d+)", text)
print(f"| {label} | {float(rps):,.0f} req/s | p50 {lat.get('50')} | p99 {lat.get('99')} |"
      + (f" {errors.group(1)} non-2xx/3xx |" if errors else ""))
PY
}

echo "| store | throughput | p50 | p99 |"
echo "|---|---|---|---|"
run database-nocache --frame-cache-mib 0
run database-cached
"$BIN" frames migrate --db "$DB" --to "$FOLDER" >/dev/null 2>&1
run folder-nocache --frames "$FOLDER" --frame-cache-mib 0
run folder-cached --frames "$FOLDER"
run s3-nocache --frames "$S3" --frame-cache-mib 0
run s3-cached --frames "$S3"
run s3-redirect --frames "$S3" --frame-redirect 600
