#!/usr/bin/env bash
# Scoring from scene graphs against ENACT's own evaluator, side by side in one run, for
# BENCHMARKS.md: `enact eval FILE` (plain mode) and `enact-hub score FILE --scene-graphs …
# --policy enact --out …` on the parity fixture, alternating, whole process each, then the
# output files compared byte for byte.
#
#   ENACT_SRC=/path/to/ENACT scripts/bench-score.sh [RUNS] [PREDICTIONS]
#
# ENACT_SRC is a checkout of github.com/mll-lab-nu/ENACT (the fixtures were made at commit
# 87e323a); nothing of it is kept here. Its Python dependencies for `eval` (numpy, Pillow,
# tqdm) are installed from PyPI into bench-out/enact-venv when missing. RUNS defaults to 5,
# PREDICTIONS to the fixture's enact_ordering_perfect.jsonl (the file its README times).
set -euo pipefail
cd "$(dirname "$0")/.."

RUNS=${1:-5}
FIXTURE=${ENACT_PARITY:-../shared/fixtures/enact-parity}
PREDICTIONS=${2:-$FIXTURE/predictions/enact_ordering_perfect.jsonl}
: "${ENACT_SRC:?set ENACT_SRC to a checkout of github.com/mll-lab-nu/ENACT}"
[ -f "$ENACT_SRC/scripts/enact/cli.py" ] || {
  echo "error: $ENACT_SRC/scripts/enact/cli.py not found: is ENACT_SRC an ENACT checkout?" >&2
  exit 1
}
[ -d "$FIXTURE/replayed_activities" ] || {
  echo "error: $FIXTURE/replayed_activities not found (set ENACT_PARITY)" >&2
  exit 1
}
FIXTURE=$(realpath "$FIXTURE")
PREDICTIONS=$(realpath "$PREDICTIONS")
ENACT_SRC=$(realpath "$ENACT_SRC")

OUT=bench-out/score
VENV=bench-out/enact-venv
cargo build --release --locked --bin enact-hub >&2
BIN=$(realpath "${CARGO_TARGET_DIR:-target}/release/enact-hub")
if ! "$VENV/bin/python" -c 'import numpy, PIL, tqdm' 2>/dev/null; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet numpy pillow tqdm
fi
PY=$PWD/$VENV/bin/python # not realpath: the symlink is what makes it the venv's
rm -rf "$OUT"
mkdir -p "$OUT"
# ENACT reads its scene graphs from a working copy, as the fixture's timings were taken.
cp -r "$FIXTURE/replayed_activities" "$FIXTURE/segmented_activities" "$OUT/"

timed() {
  # Wall seconds of one whole process.
  local start end
  start=$(date +%s%N)
  "$@" >/dev/null 2>&1
  end=$(date +%s%N)
  printf '%d.%06d\n' $(((end - start) / 1000000000)) $(((end - start) % 1000000000 / 1000))
}

enact_times=()
hub_times=()
for run in $(seq "$RUNS"); do
  rm -rf "$OUT/enact-out" "$OUT/hub-out"
  enact_times+=("$(cd "$OUT" && timed env PYTHONHASHSEED=0 PYTHONPATH="$ENACT_SRC" "$PY" -m scripts.enact.cli \
    eval "$PREDICTIONS" --segmented-data segmented_activities --raw-data replayed_activities \
    --output-root enact-out)")
  hub_times+=("$(timed "$BIN" score "$PREDICTIONS" --data "$FIXTURE/QA" --scene-graphs "$OUT/replayed_activities" \
    --policy enact --out "$OUT/hub-out")")
  echo "run $run: enact eval ${enact_times[-1]} s, enact-hub score ${hub_times[-1]} s" >&2
done

model=$(basename "$PREDICTIONS" .jsonl)
for f in "meta_performance/$model.json" "detailed_eval/$model.jsonl"; do
  if ! cmp -s "$OUT/enact-out/$f" "$OUT/hub-out/$f"; then
    echo "error: $f differs between ENACT and enact-hub" >&2
    exit 1
  fi
done

python3 - "$RUNS" "${enact_times[*]}" "${hub_times[*]}" <<'PY'
import statistics, sys
runs, enact, hub = int(sys.argv[1]), [float(x) for x in sys.argv[2].split()], [float(x) for x in sys.argv[3].split()]
e, h = statistics.median(enact), statistics.median(hub)
print(f"enact eval:      median {e:.3f} s over {runs} runs ({', '.join(f'{x:.3f}' for x in enact)})")
print(f"enact-hub score: median {h:.4f} s over {runs} runs ({', '.join(f'{x:.4f}' for x in hub)})")
print(f"ratio: {e / h:.0f}x; meta_performance and detailed_eval byte-identical")
PY
