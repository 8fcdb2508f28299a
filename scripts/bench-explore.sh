#!/usr/bin/env bash
# Latency of the explorer (/datasets/{d}/explore, its JSON and CSV) and of the comparison API
# (GET /api/v1/datasets/{d}/compare) on a full-size dataset with 30 leaderboard rows and human
# answers, for BENCHMARKS.md ("Explorer and compare"). The issue's target: a page of the
# explorer at 8,972 items × 30 rows in under 100 ms.
#
#   scripts/bench-explore.sh                 # needs ../shared/fixtures/enact-parity
#   ENACT_HUB_BIN=target/dist/enact-hub scripts/bench-explore.sh
#
# The 96 parity items (with their scene graphs) are replicated in SQL to 8,972 items (as
# bench-submissions.sh does). 30 submissions of seeded answers (from 10 % to 95 % right, with
# some unreadable and some missing replies) are POSTed and scored by the server; then three
# annotators' answers on about a third of the items each are written in SQL with their verdicts
# (before anything reads the board). Then, over loopback, one request at a time (curl's
# time_total): the first read of the explorer (it builds the board and the grid), RUNS reads of
# each of several views (p50, p99, max), the first read after a listing change (the board and
# the grid are built again), and the comparison of two rows. Only loopback traffic.
set -euo pipefail
cd "$(dirname "$0")/.."

PARITY=${ENACT_FIXTURES:-../shared/fixtures}/enact-parity
RUNS=${RUNS:-200}
COMPARE_RUNS=${COMPARE_RUNS:-20}
PORT=${PORT:-18093}
ITEMS=8972
ROWS=30
OUT=bench-out/explore
[ -d "$PARITY" ] || { echo "error: $PARITY not found" >&2; exit 1; }
mkdir -p "$OUT"

# ENACT_HUB_BIN: a built binary to measure instead of building one (e.g. target/dist/enact-hub).
if [ -n "${ENACT_HUB_BIN:-}" ]; then
  BIN=$ENACT_HUB_BIN
else
  cargo build --release --locked --bin enact-hub >&2
  BIN=${CARGO_TARGET_DIR:-target}/release/enact-hub
fi
DB="$OUT/bench.db"
rm -f "$DB" "$DB-wal" "$DB-shm"
BASE="http://127.0.0.1:$PORT"

"$BIN" import "$PARITY" --db "$DB" --dataset full --scene-graphs "$PARITY/replayed_activities" 2>/dev/null
python3 scripts/lib/replicate_items.py "$DB" full "$ITEMS"

# Seeded bodies: row k answers right with probability 0.10 + 0.85·k/29, an unreadable reply
# at 2 %, no reply at 1 %, and a shuffled order otherwise.
python3 - "$DB" "$OUT" "$ROWS" <<'PY'
import json, random, sqlite3, sys
db, out, rows = sys.argv[1], sys.argv[2], int(sys.argv[3])
con = sqlite3.connect(db)
items = [(i, json.loads(gt)) for i, gt in con.execute(
    "SELECT item_id, gt_answer FROM items i JOIN datasets d ON d.id = i.dataset_id "
    "WHERE d.name = 'full' ORDER BY i.id")]
for k in range(rows):
    rng = random.Random(k)
    right = 0.10 + 0.85 * k / (rows - 1)
    with open(f"{out}/row-{k:02}.jsonl", "w") as f:
        for item_id, gt in items:
            r = rng.random()
            if r < right:
                answer = gt
            elif r < right + 0.02:
                answer = "I cannot tell"
            elif r < right + 0.03:
                continue
            else:
                answer = gt[:]
                rng.shuffle(answer)
            f.write(json.dumps({"id": item_id, "answer": answer}) + "\n")
PY

RUST_LOG=warn "$BIN" serve --db "$DB" --addr "127.0.0.1:$PORT" --daily-quota 1000 \
  >"$OUT/serve.out" 2>"$OUT/serve.err" &
SERVER=$!
trap 'kill $SERVER 2>/dev/null || true' EXIT
for _ in $(seq 300); do curl -fsS "$BASE/healthz" >/dev/null 2>&1 && break; sleep 0.2; done
TOKEN=$("$BIN" token create --db "$DB" --name bench | tail -n 1)
ADMIN=$("$BIN" token create --db "$DB" --name bench-admin --role admin | tail -n 1)

ids=()
for k in $(seq -w 0 $((ROWS - 1))); do
  ids+=("$(curl -fsS -H "Authorization: Bearer $TOKEN" --data-binary "@$OUT/row-$k.jsonl" \
    "$BASE/api/v1/datasets/full/submissions?model=bench-model-$k" \
    | python3 -c 'import json,sys; print(json.load(sys.stdin)["id"])')")
done
echo "submissions: ${#ids[@]} (ids ${ids[0]}..${ids[-1]})" >&2
curl -fsS -o /dev/null -X PUT -H "Authorization: Bearer $ADMIN" -H 'Content-Type: application/json' \
  -d '{"answers": "public"}' "$BASE/api/v1/admin/datasets/full/answers"

# Three annotators, each answering a seeded third of the items (85 % right), with verdicts as a
# finished answer stores them; written before anything reads the board.
python3 - "$DB" <<'PY'
import json, random, sqlite3, sys
con = sqlite3.connect(sys.argv[1], timeout=30)
version = con.execute("SELECT max(metric_version) FROM submissions").fetchone()[0]
items = con.execute(
    "SELECT i.id, i.gt_answer FROM items i JOIN datasets d ON d.id = i.dataset_id "
    "WHERE d.name = 'full' ORDER BY i.id").fetchall()
with con:
    for a in range(3):
        cur = con.execute("INSERT INTO annotators (name) VALUES (?)", (f"bench-annotator-{a}",))
        annotator = cur.lastrowid
        rng = random.Random(100 + a)
        for row, gt in items:
            if rng.random() >= 1 / 3:
                continue
            truth = json.loads(gt)
            answer = truth if rng.random() < 0.85 else rng.sample(truth, len(truth))
            right = answer == truth
            con.execute(
                "INSERT INTO annotations (annotator, item, outcome, answer, time_on_item_ms, "
                "placements, swaps, clears, undos, exact_match, semantic_match, task_accuracy, "
                "pairwise_accuracy, metric_version) "
                "VALUES (?, ?, 'answered', ?, 30000, ?, 0, 0, 0, ?, ?, ?, ?, ?)",
                (annotator, row, json.dumps(answer), len(answer), right, right, right,
                 1.0 if right else 0.5, version))
n = con.execute("SELECT count(*) FROM annotations").fetchone()[0]
print(f"human answers: {n}", file=sys.stderr)
PY

# time URL: one request's seconds (fails on an error status).
time_of() { curl -fsS -o /dev/null -w '%{time_total}\n' "$1"; }
# measure NAME URL [RUNS]: RUNS sequential reads after two warm-ups; p50, p99 and max in ms.
measure() {
  local name=$1 url=$2 runs=${3:-$RUNS}
  time_of "$url" >/dev/null
  time_of "$url" >/dev/null
  for _ in $(seq "$runs"); do time_of "$url"; done >"$OUT/times-$name.txt"
  python3 - "$name" "$url" "$OUT/times-$name.txt" "$(curl -fsS "$url" | wc -c)" <<'PY'
import sys
name, url, path, size = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
t = sorted(float(x) * 1000 for x in open(path) if x.strip())
pick = lambda q: t[min(len(t) - 1, int(q * len(t)))]
print(f"{name:<28} p50 {pick(0.50):7.1f} ms  p99 {pick(0.99):7.1f} ms  max {t[-1]:7.1f} ms"
      f"  ({len(t)} reads, {size / 1024:.0f} KiB)  {url.split('127.0.0.1', 1)[1].split('/', 1)[1]}")
PY
}

A=${ids[-1]}
B=${ids[-2]}
ACTIVITY=$(python3 -c "import sqlite3; print(sqlite3.connect('$DB').execute(\"SELECT task_name FROM items ORDER BY id LIMIT 1\").fetchone()[0])")
PAGE="$BASE/datasets/full/explore"
first=$(time_of "$PAGE")
echo "## explorer: $ITEMS items × $ROWS rows + Human, one request at a time"
echo "first read (builds the board and the grid): $(python3 -c "print(f'{$first*1000:.0f} ms')")"
first_again=$(time_of "$PAGE")
echo "second read (cached grid): $(python3 -c "print(f'{$first_again*1000:.1f} ms')")"
python3 -c "
import json, urllib.request
p = json.load(urllib.request.urlopen('$BASE/api/v1/datasets/full/explore'))
c = p['counts']
print('grid:', c['items'], 'items,', len(p['rows']), 'rows; patterns:', {k: v for k, v in c['patterns'].items() if k != 'only_right'})
"

measure page-default "$PAGE"
measure page-100 "$PAGE?page=100"
measure page-inverse-L7 "$PAGE?direction=inverse&step_length=7"
measure page-humans-right "$PAGE?pattern=humans-right-models-wrong"
measure page-only-A-sort-human "$PAGE?pattern=only:$A&sort=right:human"
measure page-activity-sort-B "$PAGE?activity=$ACTIVITY&sort=wrong:$B"
measure json-disagree "$BASE/api/v1/datasets/full/explore?pattern=models-disagree"
measure csv-all "$BASE/api/v1/datasets/full/explore?format=csv" 20

# After a change: each listing change drops the board (and the grid kept with it). The next
# read builds both; then, separately, the board alone (the leaderboard's JSON) and the grid
# alone (the explorer after it).
for run in 1 2 3 4; do
  flag=$([ $((run % 2)) = 1 ] && echo true || echo false)
  curl -fsS -o /dev/null -X PATCH -H "Authorization: Bearer $ADMIN" -H 'Content-Type: application/json' \
    -d "{\"baseline\": $flag}" "$BASE/api/v1/admin/submissions/${ids[0]}"
  if [ $((run % 2)) = 1 ]; then
    rebuilt=$(time_of "$PAGE")
    cached=$(time_of "$PAGE")
    echo "after a listing change: first explorer read (board and grid) $(python3 -c "print(f'{$rebuilt*1000:.0f} ms')"), next $(python3 -c "print(f'{$cached*1000:.1f} ms')")"
  else
    board=$(time_of "$BASE/api/v1/datasets/full/leaderboard")
    grid=$(time_of "$PAGE")
    echo "after a listing change: leaderboard JSON (the board) $(python3 -c "print(f'{$board*1000:.0f} ms')"), then the explorer (the grid) $(python3 -c "print(f'{$grid*1000:.0f} ms')")"
  fi
done

echo "## compare: GET /api/v1/datasets/full/compare, rows #$A and #$B"
COMPARE="$BASE/api/v1/datasets/full/compare?a=$A&b=$B"
first=$(time_of "$COMPARE")
echo "first read: $(python3 -c "print(f'{$first*1000:.0f} ms')")"
measure compare-activities "$COMPARE" "$COMPARE_RUNS"
measure compare-items "$COMPARE&resample=items" "$COMPARE_RUNS"
