#!/usr/bin/env bash
# Loopback throughput/latency of the annotation item page for logged-in clients, for
# BENCHMARKS.md ("Annotation").
#
#   scripts/bench-annotate.sh
#
# Starts the release build on the demo dataset in a fresh database, creates an admin account
# with the CLI, accepts its invite and logs in SESSIONS times with curl (each login is a
# session of its own), assigns the demo dataset to the account, then loads one item page with
# wrk at CONNECTIONS connections, each request carrying one of the session cookies in turn.
# Installs Debian's `wrk` if missing. Only loopback traffic.
set -euo pipefail
cd "$(dirname "$0")/.."

DURATION=${DURATION:-10s}
CONNECTIONS=${CONNECTIONS:-64}
# wrk threads share the 2 cores with the server; one thread drives 64 connections easily.
WRK_THREADS=${WRK_THREADS:-1}
SESSIONS=${SESSIONS:-64}
PORT=${PORT:-18081}
OUT=bench-out/annotate
DB_NAME=bench.db

if ! command -v wrk >/dev/null 2>&1; then
  echo "installing wrk (Debian package)" >&2
  apt-get install -y wrk >/dev/null 2>&1 || { apt-get update >/dev/null && apt-get install -y wrk >/dev/null; }
fi
# shellcheck source=scripts/lib/demo-server.sh
source scripts/lib/demo-server.sh

INVITE=$("$BIN" annotator create --db "$DB" --name bench --admin --base-url "$BASE" | tail -n 1)
PASSWORD="benchmark password"
session_of() { sed -n 's/^[Ss]et-[Cc]ookie: enact_session=\([0-9a-f]*\);.*/\1/p' | tr -d '\r'; }

jar="$OUT/jar.txt"
accept_invite "$INVITE" "$PASSWORD" "$jar"
admin_csrf=$(curl -fsS -b "$jar" "$BASE/admin" | csrf_of)
annotator_id=$(curl -fsS -b "$jar" "$BASE/admin" | sed -n 's/.*<tr><td>\([0-9]*\)<\/td><td>bench<\/td>.*/\1/p')
curl -fsS -b "$jar" -o /dev/null --data-urlencode "csrf=$admin_csrf" \
  -d dataset=demo -d mode=split -d "annotator=$annotator_id" "$BASE/admin/assign"
ITEM=$(curl -fsS -b "$jar" -o /dev/null -w '%{redirect_url}' "$BASE/annotate/next")
ITEM=${ITEM#"$BASE"}
echo "item page: $ITEM" >&2

cookies=()
for _ in $(seq "$SESSIONS"); do
  ljar="$OUT/login-jar.txt"
  rm -f "$ljar"
  t=$(curl -fsS -c "$ljar" "$BASE/login" | csrf_of)
  s=$(curl -sS -b "$ljar" -D - -o /dev/null --data-urlencode "csrf=$t" \
      --data-urlencode "name=bench" --data-urlencode "password=$PASSWORD" "$BASE/login" | session_of)
  [ -n "$s" ] || { echo "login failed" >&2; exit 1; }
  cookies+=("\"enact_session=$s\"")
done
status=$(curl -sS -o "$OUT/item.html" -w '%{http_code}' -H "Cookie: ${cookies[0]//\"/}" "$BASE$ITEM")
[ "$status" = 200 ] || { echo "item page answered $status" >&2; exit 1; }

cat >"$OUT/sessions.lua" <<LUA
cookies = { $(IFS=,; echo "${cookies[*]}") }
i = 0
request = function()
  i = i % #cookies + 1
  return wrk.format("GET", "$ITEM", { ["Cookie"] = cookies[i] })
end
LUA

wrk -t2 -c8 -d2s -s "$OUT/sessions.lua" "$BASE" >/dev/null
echo "## item page: GET $ITEM, ${#cookies[@]} sessions, ${CONNECTIONS} connections, ${WRK_THREADS} wrk thread(s), $DURATION"
wrk -t"$WRK_THREADS" -c"$CONNECTIONS" -d"$DURATION" --latency -s "$OUT/sessions.lua" "$BASE" | tee "$OUT/wrk-item-page.txt"
