#!/usr/bin/env bash
# Loopback throughput/latency of the leaderboard JSON and page with 1,000 published
# submissions from 50 accounts, and the time to rebuild the board after a new submission, for
# BENCHMARKS.md ("Leaderboard").
#
#   scripts/bench-leaderboard.sh
#
# Starts the release build on the demo dataset in a fresh database (ENACT_HUB_ADMIN_TOKEN set),
# issues 50 submitter tokens over the API, posts four real submissions (right, and wrong on a
# quarter, a half and all of the items), copies them in SQL to 1,000 submissions of 50
# accounts with distinct models (before the board is first read), then loads
# GET /api/v1/datasets/demo/leaderboard and GET /leaderboard/demo with wrk, then the JSON again
# while an admin changes a listing every CHANGE_EVERY seconds (each change drops the board, so
# the readers in flight need it rebuilt). Installs Debian's `wrk` if missing. Only loopback
# traffic.
set -euo pipefail
cd "$(dirname "$0")/.."

DURATION=${DURATION:-10s}
CHANGE_EVERY=${CHANGE_EVERY:-0.5}
CONNECTIONS=${CONNECTIONS:-64}
WRK_THREADS=${WRK_THREADS:-1}
PORT=${PORT:-18082}
OUT=bench-out/leaderboard
DB_NAME=bench.db
SUBMISSIONS=1000
ACCOUNTS=50
export ENACT_HUB_ADMIN_TOKEN=bench-admin-token-0123456789

if ! command -v wrk >/dev/null 2>&1; then
  echo "installing wrk (Debian package)" >&2
  apt-get install -y wrk >/dev/null 2>&1 || { apt-get update >/dev/null && apt-get install -y wrk >/dev/null; }
fi
# shellcheck source=scripts/lib/demo-server.sh
source scripts/lib/demo-server.sh

api() { curl -fsS -H "Authorization: Bearer $ENACT_HUB_ADMIN_TOKEN" "$@"; }

# The demo's items: every id and its number of labels (the answer length), from the item API.
python3 - "$BASE" "$OUT/answers" <<'PY'
import json, sys, urllib.request
base, out = sys.argv[1], sys.argv[2]
items, page = [], 1
while True:
    with urllib.request.urlopen(f"{base}/api/v1/datasets/demo/items?per_page=500&page={page}") as r:
        listing = json.load(r)
    items += [i["url"] for i in listing["items"]]
    if not listing["next"]:
        break
    page += 1
lengths = []
for url in items:
    with urllib.request.urlopen(base + url) as r:
        item = json.load(r)
    lengths.append((item["id"], len(item["images"]) - 1))
# Four bodies: ascending answers on none, a quarter, half and all of the items, descending
# elsewhere: four distinct scores to copy.
for k, share in enumerate([0.0, 0.25, 0.5, 1.0]):
    cut = int(len(lengths) * share)
    with open(f"{out}-{k}.jsonl", "w") as f:
        for i, (id_, n) in enumerate(lengths):
            answer = list(range(1, n + 1))
            if i >= cut:
                answer.reverse()
            f.write(json.dumps({"id": id_, "answer": answer}) + "\n")
PY

tokens=()
for a in $(seq -w 1 "$ACCOUNTS"); do
  tokens+=("$(api -H 'Content-Type: application/json' -d "{\"name\": \"team-$a\"}" \
    "$BASE/api/v1/admin/tokens" | python3 -c 'import json,sys; print(json.load(sys.stdin)["token"])')")
done
templates=()
for k in 0 1 2 3; do
  templates+=("$(curl -fsS -H "Authorization: Bearer ${tokens[$k]}" --data-binary @"$OUT/answers-$k.jsonl" \
    "$BASE/api/v1/datasets/demo/submissions?model=model-000$k" \
    | python3 -c 'import json,sys; print(json.load(sys.stdin)["id"])')")
done

python3 - "$DB" "$SUBMISSIONS" "$ACCOUNTS" "${templates[@]}" <<'PY'
import sqlite3, sys
db, total, accounts, templates = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), [int(t) for t in sys.argv[4:]]
con = sqlite3.connect(db, timeout=30)
tokens = [r[0] for r in con.execute(
    "SELECT t.id FROM api_tokens t JOIN accounts a ON a.id = t.account "
    "WHERE a.name LIKE 'team-%' ORDER BY a.name")]
with con:
    for i in range(len(templates), total):
        con.execute(
            "INSERT INTO submissions (dataset, account, token, body_sha256, model, scores) "
            "SELECT s.dataset, t.account, t.id, s.body_sha256, ?, s.scores "
            "FROM submissions s, api_tokens t WHERE s.id = ? AND t.id = ?",
            (f"model-{i:04}", templates[i % len(templates)], tokens[i % accounts]))
n = con.execute("SELECT count(*) FROM submissions WHERE visibility = 'published'").fetchone()[0]
print(f"published submissions: {n}", file=sys.stderr)
PY

JSON_URL="$BASE/api/v1/datasets/demo/leaderboard"
PAGE_URL="$BASE/leaderboard/demo"
first=$(curl -fsS -o "$OUT/board.json" -w '%{time_total}' "$JSON_URL")
cached=$(curl -fsS -o /dev/null -w '%{time_total}' "$JSON_URL")
python3 -c "import json; b=json.load(open('$OUT/board.json')); print('entries', b['entries'], 'rows on page 1', len(b['rows']), 'bytes', len(open('$OUT/board.json').read()))" >&2
echo "first read (builds the board): ${first}s; next read: ${cached}s"

for name in json page; do
  url=$JSON_URL; [ $name = page ] && url=$PAGE_URL
  wrk -t2 -c8 -d2s "$url" >/dev/null
  echo "## leaderboard $name: GET ${url#"$BASE"}, ${CONNECTIONS} connections, ${WRK_THREADS} wrk thread(s), $DURATION"
  wrk -t"$WRK_THREADS" -c"$CONNECTIONS" -d"$DURATION" --latency "$url" | tee "$OUT/wrk-$name.txt"
done

# Rebuild after a new submission: the submission, then the first read (which rebuilds the
# board from 1,000 stored score sets) against a cached read.
for run in 1 2 3; do
  curl -fsS -o /dev/null -H "Authorization: Bearer ${tokens[4]}" --data-binary @"$OUT/answers-1.jsonl" \
    "$BASE/api/v1/datasets/demo/submissions?model=rebuild-$run"
  rebuilt=$(curl -fsS -o /dev/null -w '%{time_total}' "$JSON_URL")
  cached=$(curl -fsS -o /dev/null -w '%{time_total}' "$JSON_URL")
  echo "after a new submission: first read ${rebuilt}s, next read ${cached}s"
done

# Reads while the board keeps changing: a listing flipped (baseline on, off) every
# CHANGE_EVERY seconds during the wrk run.
target=${templates[1]}
(
  flag=true
  while :; do
    api -X PATCH -H 'Content-Type: application/json' -d "{\"baseline\": $flag}" \
      "$BASE/api/v1/admin/submissions/$target" >/dev/null
    if [ "$flag" = true ]; then flag=false; else flag=true; fi
    sleep "$CHANGE_EVERY"
  done
) &
CHANGER=$!
echo "## leaderboard json under changes: GET ${JSON_URL#"$BASE"}, a listing change every ${CHANGE_EVERY}s, ${CONNECTIONS} connections, ${WRK_THREADS} wrk thread(s), $DURATION"
wrk -t"$WRK_THREADS" -c"$CONNECTIONS" -d"$DURATION" --latency "$JSON_URL" | tee "$OUT/wrk-changing.txt"
kill "$CHANGER" 2>/dev/null || true
wait "$CHANGER" 2>/dev/null || true
