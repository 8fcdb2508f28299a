#!/usr/bin/env bash
# API conformance: schemathesis (PyPI) against /api/v1/openapi.json on a demo server, once as
# each kind of caller: an admin token, a submitter token, an annotator's browser session, and
# no credential at all.
# Fails on any server error or any response that the document does not describe (status,
# content type, headers, body schema).
#
#   scripts/schemathesis.sh            # MAX_EXAMPLES=100 per operation by default
#
# Installs schemathesis into bench-out/schemathesis/venv when missing. Only loopback traffic.
set -euo pipefail
cd "$(dirname "$0")/.."

OUT=bench-out/schemathesis
PORT=${PORT:-18095}
DB_NAME=schemathesis.db
MAX_EXAMPLES=${MAX_EXAMPLES:-100}
mkdir -p "$OUT"
VENV="$OUT/venv"
if [ ! -x "$VENV/bin/schemathesis" ]; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet schemathesis
fi

export ENACT_HUB_ADMIN_TOKEN="ehub_schemathesisadmin$(head -c 16 /dev/urandom | od -An -tx1 | tr -d ' \n')"
# shellcheck source=scripts/lib/demo-server.sh
source scripts/lib/demo-server.sh

SUBMITTER=$(curl -fsS -H "Authorization: Bearer $ENACT_HUB_ADMIN_TOKEN" -H 'content-type: application/json' \
  -d '{"name": "schemathesis", "daily_quota": 1000000, "total_quota": 1000000}' \
  "$BASE/api/v1/admin/tokens" | python3 -c 'import json,sys; print(json.load(sys.stdin)["token"])')
LINK=$(grep -o 'http://[^ ]*/login/link/[0-9a-f]*' "$OUT/server.log" | head -n 1)
SESSION=$(curl -sS -D - -o /dev/null "$LINK" | sed -n 's/^[Ss]et-[Cc]ookie: \(enact_session=[0-9a-f]*\);.*/\1/p' | tr -d '\r')
[ -n "$SESSION" ] || { echo "error: no annotator session from $LINK" >&2; exit 1; }

status=0
for who in admin submitter annotator anonymous; do
  case $who in
    admin) header=(--header "Authorization: Bearer $ENACT_HUB_ADMIN_TOKEN") ;;
    submitter) header=(--header "Authorization: Bearer $SUBMITTER") ;;
    annotator) header=(--header "Cookie: $SESSION") ;;
    anonymous) header=() ;;
  esac
  echo "== schemathesis as $who" >&2
  "$VENV/bin/schemathesis" --config-file scripts/schemathesis.toml run "$BASE/api/v1/openapi.json" \
    --checks all --max-examples "$MAX_EXAMPLES" --seed 1 "${header[@]}" \
    --report junit --report-junit-path "$OUT/$who.xml" \
    2>&1 | tee "$OUT/$who.txt" | tail -n 40 || status=1
done
exit $status
