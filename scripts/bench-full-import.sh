#!/usr/bin/env bash
# A full-size import, for BENCHMARKS.md: ENACT's real sample release (../shared/fixtures/
# enact-sample) replicated to 8,972 items, every image made distinct so that nothing
# deduplicates (scripts/lib/full_size_release.py), then imported into a fresh database.
# Reports the release's size, the import's time, images per second, peak RSS and the database
# size, the largest the write-ahead log grew (sampled every 50 ms) and the longest any of the
# import's write transactions held the lock (from its report). Needs about twice the release's
# size in free disk (~28 GB: the release and the database); all are deleted at the end
# unless KEEP=1. BIN=path runs another build (an A/B against an older commit); PROFILE=dev
# builds and runs the debug binary instead of the release one.
#
#   scripts/bench-full-import.sh [ITEMS]
set -euo pipefail
cd "$(dirname "$0")/.."

ITEMS=${1:-8972}
SAMPLE=../shared/fixtures/enact-sample
OUT=bench-out/full-import
[ -d "$SAMPLE" ] || { echo "$SAMPLE is missing: this benchmark replicates ENACT's real sample" >&2; exit 1; }
if [ -z "${BIN:-}" ]; then
  if [ "${PROFILE:-release}" = dev ]; then
    cargo build --locked --bin enact-hub >&2
    BIN=${CARGO_TARGET_DIR:-target}/debug/enact-hub
  else
    cargo build --release --locked --bin enact-hub >&2
    BIN=${CARGO_TARGET_DIR:-target}/release/enact-hub
  fi
fi
rm -rf "$OUT"
mkdir -p "$OUT"
cleanup() { [ "${KEEP:-0}" = 1 ] || rm -rf "$OUT/release" "$OUT"/full.db*; }
trap cleanup EXIT

started=$(date +%s.%N)
made=$(python3 scripts/lib/full_size_release.py "$SAMPLE" "$OUT/release" "$ITEMS")
written=$(date +%s.%N)
echo "release: $made, written in $(python3 -c "print(f'{$written - $started:.1f}')") s"

# The write-ahead log's largest size, sampled while the import runs.
( peak=0
  while [ ! -e "$OUT/import.done" ]; do
    size=$(stat -c %s "$OUT/full.db-wal" 2>/dev/null || echo 0)
    if [ "$size" -gt "$peak" ]; then peak=$size; echo "$peak" >"$OUT/wal.peak"; fi
    sleep 0.05
  done ) &
sampler=$!
/usr/bin/time -v "$BIN" import "$OUT/release" --db "$OUT/full.db" --dataset full --json \
  >"$OUT/import.json" 2>"$OUT/import.time" || { touch "$OUT/import.done"; wait "$sampler"; cat "$OUT/import.time" >&2; exit 1; }
touch "$OUT/import.done"
wait "$sampler"
python3 - "$OUT/import.json" "$OUT/import.time" "$OUT/full.db" "$OUT" <<'PY'
import json, os, re, sys
report = json.load(open(sys.argv[1]))
timing = open(sys.argv[2]).read()
peak_kib = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", timing).group(1))
wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", timing).group(1)
db_bytes = sum(os.path.getsize(sys.argv[3] + s) for s in ("", "-wal", "-shm") if os.path.exists(sys.argv[3] + s))
s = report["seconds"]
print(f"import: {report['new_items']} items, {report['frames']} images ({report['new_frames']} new) "
      f"in {s:.1f} s (process wall {wall}) = {report['new_items']/s:.0f} items/s, "
      f"{report['frames']/s:.0f} images/s; peak RSS {peak_kib/1024:.0f} MB; "
      f"database {db_bytes/1e9:.2f} GB")
out = sys.argv[4]
release = sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(os.path.join(out, "release")) for f in fs)
peak_path = os.path.join(out, "wal.peak")
wal = int(open(peak_path).read()) if os.path.exists(peak_path) else 0
longest = report.get("longest_transaction_ms")
print(f"release {release/1e6:.0f} MB; largest write-ahead log {wal/1e6:.1f} MB "
      f"({100*wal/release:.1f} % of the release); longest write transaction "
      + (f"{longest:.0f} ms, cut-over {report['cut_over_ms']:.1f} ms" if longest is not None
         else "not reported (a build before staged imports: the whole import is one)"))
PY
