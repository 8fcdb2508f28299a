#!/usr/bin/env bash
# SQLite against PostgreSQL with one and with two server instances, in one run on loopback,
# for BENCHMARKS.md: submission scoring and item reads.
#
#   scripts/bench-postgres.sh        # needs ../shared/fixtures/enact-parity
#
# The 96 parity items (with their scene graphs) are imported into SQLite and replicated in SQL
# to 8,972 items, as scripts/bench-submissions.sh does; `enact-hub migrate-db` copies that
# database into a throwaway PostgreSQL cluster (Debian's server, started here). Then, for
# SQLite (one instance), PostgreSQL with one instance and PostgreSQL with two:
# - submissions: RUNS compact bodies (8,972 lines) POSTed one after another (alternating
#   between instances), median time to the scored 201; then 8 POSTed 4 at a time, as
#   submissions per second;
# - item JSON: wrk over 2,000 distinct items round-robin for DURATION, with the item cache
#   off (every read queries the database) and on; two instances get one wrk each, at half the
#   connections, and their rates are added.
set -euo pipefail
cd "$(dirname "$0")/.."

PARITY=${ENACT_FIXTURES:-../shared/fixtures}/enact-parity
RUNS=${RUNS:-5}
DURATION=${DURATION:-10s}
CONNECTIONS=${CONNECTIONS:-64}
ITEMS=8972
OUT=bench-out/postgres
[ -d "$PARITY" ] || { echo "error: $PARITY not found" >&2; exit 1; }
rm -rf "$OUT"
mkdir -p "$OUT"
command -v wrk >/dev/null 2>&1 || { apt-get update >/dev/null && apt-get install -y wrk >/dev/null; }

cargo build --release --locked --bin enact-hub >&2
BIN=${CARGO_TARGET_DIR:-target}/release/enact-hub

# PostgreSQL: a throwaway cluster, as scripts/test.sh starts it.
PG_BIN=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1 || true)
if [ -z "$PG_BIN" ]; then
  apt-get update && apt-get install -y postgresql
  PG_BIN=$(ls -d /usr/lib/postgresql/*/bin | sort -V | tail -n 1)
fi
PGDATA="$(realpath -m "$OUT/pgdata")"
PG_PORT=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
mkdir -p "$PGDATA"
as_pg() {
  if [ "$(id -u)" = 0 ]; then chown -R postgres "$PGDATA"; su postgres -s /bin/sh -c "$*"; else sh -c "$*"; fi
}
as_pg "'$PG_BIN/initdb' -D '$PGDATA' -A trust -U postgres" >/dev/null
# Durable settings (fsync on), unlike the test suite's cluster.
as_pg "'$PG_BIN/pg_ctl' -D '$PGDATA' -l '$PGDATA/server.log' -w -o \"-p $PG_PORT -k /tmp -c listen_addresses=127.0.0.1 -c max_connections=100\" start" >/dev/null
SERVERS=()
cleanup() {
  for pid in "${SERVERS[@]}"; do kill "$pid" 2>/dev/null || true; done
  as_pg "'$PG_BIN/pg_ctl' -D '$PGDATA' -m fast stop" >/dev/null 2>&1 || true
}
trap cleanup EXIT
"$PG_BIN/psql" -h 127.0.0.1 -p "$PG_PORT" -U postgres -qc "CREATE DATABASE bench" >/dev/null
PG_URL="postgres://postgres@127.0.0.1:$PG_PORT/bench"

DB="$OUT/bench.db"
"$BIN" import "$PARITY" --db "$DB" --dataset full --scene-graphs "$PARITY/replayed_activities" 2>/dev/null
python3 scripts/lib/replicate_items.py "$DB" full "$ITEMS"
"$BIN" migrate-db --from "$DB" --to "$PG_URL" 2>"$OUT/migrate.log"
tail -n 1 "$OUT/migrate.log" >&2
python3 - "$PARITY" "$OUT" "$ITEMS" <<'PY'
import json, sys
parity, out, target = sys.argv[1], sys.argv[2], int(sys.argv[3])
rows = [json.loads(l) for l in open(f"{parity}/predictions/enact_ordering_random.jsonl") if l.strip()]
lines, copy = [], 0
while len(lines) < target:
    for r in rows:
        if len(lines) >= target:
            break
        rid = r["id"] if copy == 0 else f"{r['id']}_r{copy}"
        lines.append(json.dumps({"id": rid, "answer": r["answer"]}))
    copy += 1
open(f"{out}/compact.jsonl", "w").write("\n".join(lines) + "\n")
PY

free_port() { python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }

# start DB N EXTRA...: N instances on DB; sets PORTS.
start() {
  local db=$1 n=$2
  shift 2
  PORTS=()
  for _ in $(seq "$n"); do
    local port
    port=$(free_port)
    RUST_LOG=warn "$BIN" serve --db "$db" --addr "127.0.0.1:$port" --daily-quota 100000 --total-quota 100000 "$@" \
      >>"$OUT/serve.out" 2>>"$OUT/serve.err" &
    SERVERS+=($!)
    PORTS+=("$port")
    for _ in $(seq 100); do curl -sf "http://127.0.0.1:$port/healthz" >/dev/null && break; sleep 0.1; done
  done
}
stop() {
  for pid in "${SERVERS[@]}"; do kill "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; done
  SERVERS=()
}

# The item URLs: 2,000 distinct items round-robin.
python3 - "$DB" "$OUT/items.lua" <<'PY'
import sqlite3, sys
db, out = sys.argv[1], sys.argv[2]
ids = [r[0] for r in sqlite3.connect(db).execute(
    "SELECT item_id FROM items WHERE dataset_id = (SELECT id FROM datasets WHERE name = 'full') ORDER BY id LIMIT 2000")]
paths = ", ".join(f'"/api/v1/datasets/full/items/{i}"' for i in ids)
open(out, "w").write(
    f"paths = {{{paths}}}\ni = 0\n"
    "request = function() i = i % #paths + 1; return wrk.format(\"GET\", paths[i]) end\n")
PY

bench() {
  local label=$1 db=$2 n=$3
  # Submissions.
  start "$db" "$n"
  local token
  token=$("$BIN" token create --db "$db" --name "bench-$label" 2>/dev/null | tail -n 1)
  local times=()
  for run in $(seq "$RUNS"); do
    local port=${PORTS[$(( (run - 1) % n ))]}
    t=$(curl -s -o "$OUT/response.json" -w '%{http_code} %{time_total}' -H "Authorization: Bearer $token" \
      --data-binary "@$OUT/compact.jsonl" "http://127.0.0.1:$port/api/v1/datasets/full/submissions?model=b-$run")
    [ "${t% *}" = 201 ] || { echo "error: HTTP ${t% *}: $(head -c 300 "$OUT/response.json")" >&2; exit 1; }
    times+=("${t#* }")
  done
  local began ended
  began=$(date +%s.%N)
  # (`wait` names its jobs: the servers run in the background of this shell too.)
  local posts=()
  for k in $(seq 8); do
    local port=${PORTS[$(( k % n ))]}
    curl -s -o /dev/null -H "Authorization: Bearer $token" --data-binary "@$OUT/compact.jsonl" \
      "http://127.0.0.1:$port/api/v1/datasets/full/submissions?model=p-$k" &
    posts+=($!)
    if [ $(( k % 4 )) = 0 ]; then wait "${posts[@]}"; posts=(); fi
  done
  ended=$(date +%s.%N)
  # Item reads, cache off then on (one restart each).
  stop
  local rates=()
  for cache in 0 64; do
    start "$db" "$n" --item-cache-mib "$cache"
    local per=$(( CONNECTIONS / n ))
    for port in "${PORTS[@]}"; do
      wrk -t1 -c8 -d2s -s "$OUT/items.lua" "http://127.0.0.1:$port" >/dev/null
    done
    local loads=()
    for port in "${PORTS[@]}"; do
      wrk -t"$(( 2 / n > 0 ? 2 / n : 1 ))" -c"$per" -d"$DURATION" --latency -s "$OUT/items.lua" \
        "http://127.0.0.1:$port" >"$OUT/wrk-$label-$cache-$port.txt" &
      loads+=($!)
    done
    wait "${loads[@]}"
    rates+=("$(cat "$OUT"/wrk-"$label"-"$cache"-*.txt | python3 -c '
import re, sys
text = sys.stdin.read()
total = sum(float(x) for x in re.findall(r"Requests/sec:\s+([\d.]+)", text))
print(f"{total:,.0f}")')")
    stop
  done
  python3 - "$label" "$began" "$ended" "${rates[@]}" "${times[@]}" <<'PY'
import statistics, sys
label, began, ended, off, on = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), sys.argv[4], sys.argv[5]
times = [float(t) for t in sys.argv[6:]]
print(f"| {label} | {statistics.median(times):.3f} s | {8 / (ended - began):.2f}/s | {off} req/s | {on} req/s |")
PY
}

echo "| database | submission, median of $RUNS | 8 submissions, 4 at a time | item JSON, cache off | item JSON, cache on |"
echo "|---|---|---|---|---|"
bench "SQLite, 1 instance" "$DB" 1
bench "PostgreSQL, 1 instance" "$PG_URL" 1
bench "PostgreSQL, 2 instances" "$PG_URL" 2
