#!/usr/bin/env bash
# Large replays, for BENCHMARKS.md: the world writes its five activities in ENACT's published
# format (`simulate --record-mode full`: every frame's scene graph a full record), about 1.07 GB
# of JSON in all, then `generate` and `import --scene-graphs` read them. Reports each one's
# time, throughput (MB of scene-graph JSON per second of wall time, and per CPU-second) and
# peak RSS (`/usr/bin/time -v`). Then checks that the same runs written in mixed records
# (small files, read whole) generate the same QA file as the large ones (read as streams).
#
#   scripts/bench-replay.sh [ACTIONS] [ACTIVITY]   # default 220 actions of each activity ("all")
set -euo pipefail
cd "$(dirname "$0")/.."

ACTIONS=${1:-220}
ACTIVITY=${2:-all}
OUT=bench-out/replay
cargo build --release --locked --bin enact-hub >&2
BIN=${CARGO_TARGET_DIR:-target}/release/enact-hub
rm -rf "$OUT"
mkdir -p "$OUT"
trap '[ "${KEEP:-0}" = 1 ] || rm -rf "$OUT/replay" "$OUT/data" "$OUT/mixed" "$OUT/mixed-data" "$OUT"/replay.db*' EXIT

"$BIN" simulate --out "$OUT/replay" --activity "$ACTIVITY" --length "$ACTIONS" --seed 2 \
  --image-size 64 --record-mode full >&2
bytes=$(cat "$OUT"/replay/*/scene_graph_0.json | wc -c)
tasks=$(ls "$OUT"/replay | wc -l)

run() {
  local what=$1
  shift
  /usr/bin/time -v "$@" >"$OUT/$what.out" 2>"$OUT/$what.time" || {
    cat "$OUT/$what.time" >&2
    exit 1
  }
  python3 - "$what" "$OUT/$what.time" "$bytes" <<'PY'
import re, sys
what, timing, size = sys.argv[1], open(sys.argv[2]).read(), int(sys.argv[3])
peak = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", timing).group(1)) / 1024
wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", timing).group(1)
parts = [float(p) for p in wall.split(":")]
seconds = sum(p * 60 ** i for i, p in enumerate(reversed(parts)))
user = float(re.search(r"User time \(seconds\): (\S+)", timing).group(1))
print(f"{what}: {seconds:.1f} s wall ({user:.1f} s user), {size / 1e6 / seconds:.0f} MB/s of "
      f"scene-graph JSON ({size / 1e6 / user:.0f} MB per CPU-second), peak RSS {peak:.0f} MB")
PY
}

echo "scene graphs: $((bytes / 1000000)) MB in $tasks tasks, every record full"
run generate "$BIN" generate "$OUT/replay" --out "$OUT/data"
run import "$BIN" import "$OUT/data" --db "$OUT/replay.db" --dataset replay --scene-graphs "$OUT/replay"

"$BIN" simulate --out "$OUT/mixed" --activity "$ACTIVITY" --length "$ACTIONS" --seed 2 \
  --image-size 64 --record-mode mixed >/dev/null
"$BIN" generate "$OUT/mixed" --out "$OUT/mixed-data" >/dev/null 2>&1
if cmp -s "$OUT/data/QA/enact_ordering.jsonl" "$OUT/mixed-data/QA/enact_ordering.jsonl"; then
  echo "the mixed-record replays ($(( $(cat "$OUT"/mixed/*/scene_graph_0.json | wc -c) / 1000000 )) MB, read whole) generate the same QA file"
else
  echo "error: the streamed and the in-memory replay generated different QA files" >&2
  exit 1
fi
