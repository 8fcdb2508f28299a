#!/usr/bin/env bash
# End-to-end submission timing for BENCHMARKS.md: a full-size (8,972-item) dataset, one
# ENACT-format submission (QA record + answer per line, ~27 MB) and one compact submission
# ({"id","answer"} lines), each POSTed over loopback and timed until the scored 201 arrives.
#
#   scripts/bench-submissions.sh            # needs ../shared/fixtures/enact-parity
#   PROFILE=debug scripts/bench-submissions.sh
#
# The 96 parity items (imported with their scene graphs) are replicated in SQL to 8,972 items
# (ids suffixed `_rN`, same frames and signatures); prediction files are replicated the same
# way. Each POST is repeated RUNS times (default 5) with a fresh token; the first run includes
# loading the dataset's scoring targets, later ones hit the server's cache.
set -euo pipefail
cd "$(dirname "$0")/.."

PARITY=${ENACT_FIXTURES:-../shared/fixtures}/enact-parity
PROFILE=${PROFILE:-release}
RUNS=${RUNS:-5}
PORT=${PORT:-18091}
ITEMS=8972
OUT=bench-out/submissions
[ -d "$PARITY" ] || { echo "error: $PARITY not found" >&2; exit 1; }
mkdir -p "$OUT"

# ENACT_HUB_BIN: a built binary to measure instead of building one (e.g. target/dist/enact-hub).
if [ -n "${ENACT_HUB_BIN:-}" ]; then
  BIN=$ENACT_HUB_BIN
elif [ "$PROFILE" = release ]; then
  cargo build --release --locked --bin enact-hub >&2
  BIN=${CARGO_TARGET_DIR:-target}/release/enact-hub
else
  cargo build --locked --bin enact-hub >&2
  BIN=${CARGO_TARGET_DIR:-target}/debug/enact-hub
fi
DB="$OUT/bench.db"
rm -f "$DB" "$DB-wal" "$DB-shm"

"$BIN" import "$PARITY" --db "$DB" --dataset full --scene-graphs "$PARITY/replayed_activities" 2>/dev/null

python3 scripts/lib/replicate_items.py "$DB" full "$ITEMS"
python3 - "$PARITY" "$OUT" "$ITEMS" <<'PY'
import json, sys
parity, out, target = sys.argv[1], sys.argv[2], int(sys.argv[3])

def replicate(lines, compact):
    rows = [json.loads(l) for l in lines if l.strip()]
    result, total, copy = [], 0, 0
    while total < target:
        for r in rows:
            if total >= target:
                break
            r = dict(r)
            if copy:
                r["id"] = f"{r['id']}_r{copy}"
            result.append(json.dumps({"id": r["id"], "answer": r["answer"]} if compact else r))
            total += 1
        copy += 1
    return "\n".join(result) + "\n"

lines = open(f"{parity}/predictions/enact_ordering_random.jsonl").read().splitlines()
open(f"{out}/enact_format.jsonl", "w").write(replicate(lines, False))
open(f"{out}/compact.jsonl", "w").write(replicate(lines, True))
PY
ls -l "$OUT"/*.jsonl >&2

"$BIN" serve --db "$DB" --addr "127.0.0.1:$PORT" --daily-quota 1000 >"$OUT/serve.out" 2>"$OUT/serve.err" &
SERVER=$!
trap 'kill $SERVER 2>/dev/null || true' EXIT
for _ in $(seq 50); do curl -sf "http://127.0.0.1:$PORT/healthz" >/dev/null && break; sleep 0.2; done
TOKEN=$("$BIN" token create --db "$DB" --name bench | tail -n 1)

for file in enact_format compact; do
  times=()
  for run in $(seq "$RUNS"); do
    t=$(curl -s -o "$OUT/response.json" -w '%{http_code} %{time_total}' \
      -H "Authorization: Bearer $TOKEN" --data-binary "@$OUT/$file.jsonl" \
      "http://127.0.0.1:$PORT/api/v1/datasets/full/submissions?model=bench-$file-$run")
    code=${t% *}
    [ "$code" = 201 ] || { echo "error: $file run $run: HTTP $code: $(head -c 300 "$OUT/response.json")" >&2; exit 1; }
    times+=("${t#* }")
  done
  python3 - "$file" "$(stat -c %s "$OUT/$file.jsonl")" "${times[@]}" <<'PY'
import statistics, sys
name, size, times = sys.argv[1], int(sys.argv[2]), [float(t) for t in sys.argv[3:]]
print(f"{name}: {size/1e6:.1f} MB, {len(times)} runs: first {times[0]*1000:.0f} ms, "
      f"median {statistics.median(times)*1000:.0f} ms, max {max(times)*1000:.0f} ms")
PY
done
python3 -c "import json,sys; s=json.load(open('$OUT/response.json'))['scores']; print('last response: items', s['coverage']['dataset_items'], 'TA', s['report']['overall']['task_accuracy'])"
