#!/usr/bin/env bash
# A full-size import, for BENCHMARKS.md: ENACT's real sample release (../shared/fixtures/
# enact-sample) replicated to 8,972 items, every image made distinct so that nothing
# deduplicates (scripts/lib/full_size_release.py), then imported into a fresh database.
# Reports the release's size, the import's time, images per second, peak RSS and the database
# size. Needs about three times the release's size in free disk (~42 GB: the release, the
# import's write-ahead log and the database); all are deleted at the end
# unless KEEP=1.
#
#   scripts/bench-full-import.sh [ITEMS]
set -euo pipefail
cd "$(dirname "$0")/.."

ITEMS=${1:-8972}
SAMPLE=../shared/fixtures/enact-sample
OUT=bench-out/full-import
[ -d "$SAMPLE" ] || { echo "$SAMPLE is missing: this benchmark replicates ENACT's real sample" >&2; exit 1; }
cargo build --release --locked --bin enact-hub >&2
BIN=${CARGO_TARGET_DIR:-target}/release/enact-hub
rm -rf "$OUT"
mkdir -p "$OUT"
cleanup() { [ "${KEEP:-0}" = 1 ] || rm -rf "$OUT/release" "$OUT"/full.db*; }
trap cleanup EXIT

started=$(date +%s.%N)
made=$(python3 scripts/lib/full_size_release.py "$SAMPLE" "$OUT/release" "$ITEMS")
written=$(date +%s.%N)
echo "release: $made, written in $(python3 -c "print(f'{$written - $started:.1f}')") s"

/usr/bin/time -v "$BIN" import "$OUT/release" --db "$OUT/full.db" --dataset full --json \
  >"$OUT/import.json" 2>"$OUT/import.time"
python3 - "$OUT/import.json" "$OUT/import.time" "$OUT/full.db" <<'PY'
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
PY
