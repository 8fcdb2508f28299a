#!/usr/bin/env bash
# A replacing import at full size, for BENCHMARKS.md ("A replacing import's cut-over"): ENACT's
# real sample (../shared/fixtures/enact-sample) replicated to ITEMS items (default 8,972; the
# copies share the sample's images, which do not matter here), imported, SUBMISSIONS full-size
# submissions stored (default 300: one scored through the API, the rest copied in SQL, for
# ITEMS × SUBMISSIONS verdicts), then the same items with every ground truth changed imported
# with --replace. Prints the import's cut-over, its longest write transaction, the replaced
# items and verdicts deleted after the cut-over and the longest of those transactions, from the
# import's report.
# BIN=path runs another build (an A/B against an older commit).
#
#   scripts/bench-cut-over.sh
#   ITEMS=2000 SUBMISSIONS=50 scripts/bench-cut-over.sh
set -euo pipefail
cd "$(dirname "$0")/.."

ITEMS=${ITEMS:-8972}
SUBMISSIONS=${SUBMISSIONS:-300}
PORT=${PORT:-18097}
SAMPLE=../shared/fixtures/enact-sample
OUT=bench-out/cut-over
[ -d "$SAMPLE" ] || { echo "$SAMPLE is missing: this benchmark replicates ENACT's real sample" >&2; exit 1; }
if [ -z "${BIN:-}" ]; then
  cargo build --release --locked --bin enact-hub >&2
  BIN=${CARGO_TARGET_DIR:-target}/release/enact-hub
fi
rm -rf "$OUT"
mkdir -p "$OUT"
cp -r "$SAMPLE" "$OUT/release"
DB="$OUT/cut.db"

# The release twice over the same images: as first imported, and with every answer reversed.
python3 - "$OUT/release/QA" "$ITEMS" <<'PY'
import json, os, sys
qa, target = sys.argv[1], int(sys.argv[2])
records = [json.loads(l) for l in open(os.path.join(qa, "enact_ordering.jsonl")) if l.strip()]
records = [r for r in records if r.get("images")]
made = []
copy = 0
while len(made) < target:
    for r in records:
        if len(made) == target:
            break
        made.append(dict(r, id=f"{r['id']}_r{copy}"))
    copy += 1
with open(os.path.join(qa, "enact_ordering.jsonl"), "w") as v1, \
     open(os.path.join(qa, "replaced.jsonl"), "w") as v2, \
     open(os.path.join(qa, "..", "answers.jsonl"), "w") as answers:
    for r in made:
        v1.write(json.dumps(r) + "\n")
        v2.write(json.dumps(dict(r, gt_answer=list(reversed(r["gt_answer"])))) + "\n")
        answers.write(json.dumps({"id": r["id"], "answer": r["gt_answer"]}) + "\n")
PY
"$BIN" import "$OUT/release" --db "$DB" --dataset full --json >"$OUT/first.json"

# One submission scored and stored by the server, then copied in SQL (verdicts and all).
TOKEN=$("$BIN" token create --db "$DB" --name bench | tail -n 1)
RUST_LOG=warn "$BIN" serve --db "$DB" --addr "127.0.0.1:$PORT" >"$OUT/server.log" 2>&1 &
SERVER=$!
trap 'kill $SERVER 2>/dev/null || true' EXIT
for _ in $(seq 300); do curl -fsS "http://127.0.0.1:$PORT/healthz" >/dev/null 2>&1 && break; sleep 0.2; done
curl -fsS -X POST -H "Authorization: Bearer $TOKEN" \
  --data-binary "@$OUT/release/answers.jsonl" \
  "http://127.0.0.1:$PORT/api/v1/datasets/full/submissions?model=m0" >/dev/null
kill $SERVER; wait $SERVER 2>/dev/null || true
python3 - "$DB" "$SUBMISSIONS" <<'PY'
import sqlite3, sys
db, total = sqlite3.connect(sys.argv[1]), int(sys.argv[2])
columns = [r[1] for r in db.execute("PRAGMA table_info(submissions)") if r[1] != "id"]
verdicts = [r[1] for r in db.execute("PRAGMA table_info(submission_items)") if r[1] != "submission"]
(first,) = db.execute("SELECT min(id) FROM submissions").fetchone()
for n in range(1, total):
    values = ", ".join(f"'m{n}'" if c == "model" else ("NULL" if c == "idempotency_key" else c) for c in columns)
    cur = db.execute(f"INSERT INTO submissions ({', '.join(columns)}) SELECT {values} FROM submissions WHERE id = ?", (first,))
    db.execute(f"INSERT INTO submission_items (submission, {', '.join(verdicts)}) "
               f"SELECT ?, {', '.join(verdicts)} FROM submission_items WHERE submission = ?", (cur.lastrowid, first))
db.commit()
(n,) = db.execute("SELECT count(*) FROM submission_items").fetchone()
print(f"stored: {total} submissions, {n} verdicts", file=sys.stderr)
PY

/usr/bin/time -v "$BIN" import "$OUT/release/QA/replaced.jsonl" --db "$DB" --dataset full --replace --json \
  >"$OUT/replace.json" 2>"$OUT/replace.time"
python3 - "$OUT/replace.json" "$OUT/replace.time" "$DB" <<'PY'
import json, re, sqlite3, sys
report = json.load(open(sys.argv[1]))
wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", open(sys.argv[2]).read()).group(1)
db = sqlite3.connect(sys.argv[3])
(left,) = db.execute(
    "SELECT count(*) FROM submission_items v WHERE NOT EXISTS (SELECT 1 FROM items i WHERE i.id = v.item)").fetchone()
(rows,) = db.execute("SELECT count(*) FROM datasets").fetchone()
print(f"replacing import: {report['replaced_items']} items replaced in {report['seconds']:.1f} s "
      f"(process wall {wall}); cut-over {report['cut_over_ms']:.1f} ms; "
      f"{report['retired_items']} replaced items deleted after it; "
      f"{report['swept_verdicts']} verdicts swept after it, longest sweep transaction "
      f"{report['longest_sweep_ms']:.1f} ms; longest write transaction of the import "
      f"{report['longest_transaction_ms']:.1f} ms; verdicts naming no item left: {left}; "
      f"dataset rows left: {rows}")
PY
