#!/usr/bin/env bash
# Screenshots of the annotation item pages for the README: forward and inverse at L = 3 and
# L = 10 on the demo, and on ENACT's own sample items (forward L = 3, inverse L = 5, forward
# L = 10) when ../shared/fixtures/enact-sample is beside the checkout; headless Chromium at
# 1280x800, written to docs/.
#
#   scripts/screenshots.sh
#
# Serves the demo dataset from a fresh database, creates an admin and an annotator with the
# CLI, assigns four demo items to the annotator through the admin page (curl), and has
# tests/browser/annotate.mjs log in through the annotator's invite and shoot the pages with a
# few cards placed. Needs chromium and tests/browser/node_modules (scripts/test.sh installs both).
set -euo pipefail
cd "$(dirname "$0")/.."

PORT=${PORT:-18082}
OUT=bench-out/screenshots
DB_NAME=shots.db
mkdir -p docs
# shellcheck source=scripts/lib/demo-server.sh
source scripts/lib/demo-server.sh

ADMIN_INVITE=$("$BIN" annotator create --db "$DB" --name admin --admin --base-url "$BASE" | tail -n 1)
INVITE=$("$BIN" annotator create --db "$DB" --name annotator --base-url "$BASE" | tail -n 1)
jar="$OUT/jar.txt"
accept_invite "$ADMIN_INVITE" "screenshot admin" "$jar"
admin_page=$(curl -fsS -b "$jar" "$BASE/admin")
admin_csrf=$(echo "$admin_page" | csrf_of)
annotator_id=$(echo "$admin_page" | sed -n 's/.*<tr><td>\([0-9]*\)<\/td><td>annotator<\/td>.*/\1/p')
item() {
  curl -fsS "$BASE/api/v1/datasets/${3:-demo}/items?direction=$1&step_length=$2&per_page=1" \
    | python3 -c 'import json,sys; print(json.load(sys.stdin)["items"][0]["id"])'
}
F3=$(item forward 3); I3=$(item inverse 3); F10=$(item forward 10); I10=$(item inverse 10)
curl -fsS -b "$jar" -o /dev/null --data-urlencode "csrf=$admin_csrf" -d dataset=demo -d mode=list \
  -d "annotator=$annotator_id" --data-urlencode "items=$F3 $I3 $F10 $I10" "$BASE/admin/assign"

# ENACT's real frames (512x512 photoreal scenes), when the shared fixtures are here.
SAMPLE=../shared/fixtures/enact-sample
SF3=""; SI5=""; SF10=""
if [ -d "$SAMPLE/QA" ]; then
  "$BIN" import "$SAMPLE" --db "$DB" --dataset sample >&2
  sleep 1 # the server notices the import within half a second
  SF3=$(item forward 3 sample); SI5=$(item inverse 5 sample); SF10=$(item forward 10 sample)
  curl -fsS -b "$jar" -o /dev/null --data-urlencode "csrf=$admin_csrf" -d dataset=sample -d mode=list \
    -d "annotator=$annotator_id" --data-urlencode "items=$SF3 $SI5 $SF10" "$BASE/admin/assign"
fi

node tests/browser/annotate.mjs "$(python3 - "$BASE" "$INVITE" "$F3" "$I3" "$F10" "$I10" "$SF3" "$SI5" "$SF10" <<'PY'
import json, sys
base, invite, f3, i3, f10, i10, sf3, si5, sf10 = sys.argv[1:]
sample = [
    {"dataset": "sample", "item": sf3, "file": "annotate-sample-forward-L3.png", "place": [[1, 1]]},
    {"dataset": "sample", "item": si5, "file": "annotate-sample-inverse-L5.png", "place": [[2, 1]]},
    {"dataset": "sample", "item": sf10, "file": "annotate-sample-forward-L10.png", "place": [[3, 1], [5, 2]]},
] if sf3 else []
print(json.dumps({
    "mode": "screenshots", "base": base, "invite": invite[len(base):], "out": "docs",
    "failure_dir": "bench-out/screenshots",
    "shots": [
        {"dataset": "demo", "item": f3, "file": "annotate-forward-L3.png", "place": [[2, 1]]},
        {"dataset": "demo", "item": i3, "file": "annotate-inverse-L3.png", "place": [[1, 2]]},
        {"dataset": "demo", "item": f10, "file": "annotate-forward-L10.png", "place": [[4, 1], [7, 2], [1, 3]]},
        {"dataset": "demo", "item": i10, "file": "annotate-inverse-L10.png", "place": [[5, 1], [2, 2]]},
    ] + sample,
}))
PY
)"
ls -l docs/annotate-*.png
