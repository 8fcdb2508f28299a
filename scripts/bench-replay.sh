#!/usr/bin/env bash
# Large replays, for BENCHMARKS.md: the world writes one task in ENACT's published format
# (`simulate --record-mode full`: every frame's scene graph a full record) of at least 1 GB,
# then `generate` and `import --scene-graphs` read it. Reports each one's time, throughput
# (MB of scene-graph JSON per second) and peak RSS (`/usr/bin/time -v`). Then checks that the
# same run written in mixed records (a small file, read whole) generates the same QA file as
# the large one (read as a stream).
#
#   scripts/bench-replay.sh [ACTIONS]     # default 1100 actions, about 1.1 GB
set -euo pipefail
cd "$(dirname "$0")/.."

ACTIONS=${1:-1100}
OUT=bench-out/replay
cargo build --release --locked --bin enact-hub >&2
BIN=target/release/enact-hub
rm -rf "$OUT"
mkdir -p "$OUT"
trap '[ "${KEEP:-0}" = 1 ] || rm -rf "$OUT/replay" "$OUT/data" "$OUT/mixed" "$OUT/mixed-data" "$OUT"/replay.db*' EXIT

"$BIN" simulate --out "$OUT/replay" --activity make_tea --length "$ACTIONS" --seed 2 \
  --image-size 64 --record-mode full >&2
graph=$(ls "$OUT"/replay/*/scene_graph_0.json)
bytes=$(stat -c %s "$graph")

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
      f"scene-graph JSON, peak RSS {peak:.0f} MB")
PY
}

echo "scene graph: $((bytes / 1000000)) MB, one task, every record full"
run generate "$BIN" generate "$OUT/replay" --out "$OUT/data"
run import "$BIN" import "$OUT/data" --db "$OUT/replay.db" --dataset replay --scene-graphs "$OUT/replay"

"$BIN" simulate --out "$OUT/mixed" --activity make_tea --length "$ACTIONS" --seed 2 \
  --image-size 64 --record-mode mixed >/dev/null
"$BIN" generate "$OUT/mixed" --out "$OUT/mixed-data" >/dev/null 2>&1
if cmp -s "$OUT/data/QA/enact_ordering.jsonl" "$OUT/mixed-data/QA/enact_ordering.jsonl"; then
  echo "the mixed-record replay ($(( $(stat -c %s "$OUT"/mixed/*/scene_graph_0.json) / 1000000 )) MB, read whole) generates the same QA file"
else
  echo "error: the streamed and the in-memory replay generated different QA files" >&2
  exit 1
fi
