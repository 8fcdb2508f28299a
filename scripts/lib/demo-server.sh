# Shared by the scripts that need a running demo server and a logged-in admin (sourced, not run).
#
#   OUT=bench-out/x PORT=18081 DB_NAME=x.db source scripts/lib/demo-server.sh
#
# Builds the release binary unless BIN is set, serves the demo dataset from a fresh database
# $OUT/$DB_NAME on 127.0.0.1:$PORT (stopped on exit), and defines BASE, DB, csrf_of and
# accept_invite.

mkdir -p "$OUT"
# BIN=path/to/enact-hub uses an existing binary instead of building the release one.
if [ -z "${BIN:-}" ]; then
  cargo build --release --locked --bin enact-hub >&2
  BIN=${CARGO_TARGET_DIR:-target}/release/enact-hub
fi
DB="$OUT/$DB_NAME"
rm -f "$DB" "$DB-wal" "$DB-shm"
BASE="http://127.0.0.1:$PORT"

RUST_LOG=warn "$BIN" serve --demo --db "$DB" --addr "127.0.0.1:$PORT" >"$OUT/server.log" 2>&1 &
SERVER=$!
trap 'kill $SERVER 2>/dev/null || true' EXIT
for _ in $(seq 300); do
  curl -fsS "$BASE/healthz" >/dev/null 2>&1 && break
  sleep 0.2
done

# The CSRF token of the first form on an HTML page read from standard input.
csrf_of() { sed -n 's/.*name="csrf" value="\([0-9a-f]*\)".*/\1/p' | head -n 1; }

# accept_invite URL PASSWORD JAR: sets the password through the invite; JAR holds the session.
accept_invite() {
  local token
  rm -f "$3"
  token=$(curl -fsS -c "$3" "$1" | csrf_of)
  curl -fsS -b "$3" -c "$3" -o /dev/null --data-urlencode "csrf=$token" \
    --data-urlencode "password=$2" --data-urlencode "repeat=$2" "$1"
}
