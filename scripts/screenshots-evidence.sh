#!/usr/bin/env bash
# Screenshots of the evidence behind a number, for the README: one item with every answer, the
# explorer (items × rows, hardest first) and the comparison of the demo's two reference rows;
# headless Chromium, written to docs/ (English: the browser tests check both languages).
#
#   scripts/screenshots-evidence.sh          # BIN=path/to/enact-hub to skip the release build
#
# Serves the demo from a fresh database with a known admin token, makes the demo's answers
# public through the admin API (hidden answers show none of this to readers), and shoots the
# pages as a reader sees them. Needs chromium (scripts/test.sh installs it).
set -euo pipefail
cd "$(dirname "$0")/.."

PORT=${PORT:-18083}
OUT=bench-out/screenshots-evidence
DB_NAME=evidence.db
export ENACT_HUB_ADMIN_TOKEN=screenshots-admin-token-0123456789
mkdir -p docs
# shellcheck source=scripts/lib/demo-server.sh
source scripts/lib/demo-server.sh

curl -fsS -o /dev/null -X PUT -H "Authorization: Bearer $ENACT_HUB_ADMIN_TOKEN" \
  -H 'Content-Type: application/json' -d '{"answers": "public"}' \
  "$BASE/api/v1/admin/datasets/demo/answers"

# An inverse item of L = 5 the heuristic gets wrong, so the page shows why.
ITEM=$(curl -fsS "$BASE/api/v1/datasets/demo/explore?direction=inverse&step_length=5&sort=difficulty&format=json" \
  | python3 -c '
import json, sys
view = json.load(sys.stdin)
print(view["items"][0]["id"])')
CHANCE="chance (uniformly random order)"
HEURISTIC="heuristic: grasp before release (not a model)"
COMPARE=$(python3 -c 'import sys, urllib.parse as u; print(u.urlencode({"a": sys.argv[1], "b": sys.argv[2]}))' \
  "$HEURISTIC" "$CHANCE")

shoot() { # FILE PATH LANGUAGE HEIGHT
  chromium --headless --no-sandbox --disable-gpu --hide-scrollbars --lang="$3" \
    --accept-lang="$3" --window-size="1280,$4" --screenshot="docs/$1" "$BASE$2" \
    >>"$OUT/chromium.log" 2>&1
  echo "docs/$1"
}
shoot item-answers.png "/datasets/demo/items/$ITEM" en 1400
shoot explore.png "/datasets/demo/explore?sort=difficulty" en 1000
shoot compare.png "/datasets/demo/compare?$COMPARE" en 1200
