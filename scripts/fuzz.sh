#!/usr/bin/env bash
# Runs the four fuzz targets one after another, SECONDS_PER_TARGET each (default 600), on the
# nightly toolchain. Installs cargo-fuzz from crates.io when it is missing. New inputs go to
# fuzz/corpus/<target> (ignored by git); crashes to fuzz/artifacts/<target>. Prints one summary
# line per target: runs, seconds, and whether it crashed.
#   scripts/fuzz.sh [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
seconds="${SECONDS_PER_TARGET:-600}"
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(answer submission scene_graph sentence)
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
cargo +nightly fuzz build
status=0
for target in "${targets[@]}"; do
  mkdir -p "corpus/$target"
  log="$(mktemp)"
  if cargo +nightly fuzz run "$target" "corpus/$target" "seeds/$target" -- \
      -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 >"$log" 2>&1; then
    outcome="no crash"
  else
    outcome="CRASH (see fuzz/artifacts/$target)"
    status=1
    tail -40 "$log" >&2
  fi
  runs="$(grep -Eo '^Done [0-9]+ runs in [0-9]+ second' "$log" | tail -1 || true)"
  echo "$target: ${runs:-no summary}; $outcome"
  rm -f "$log"
done
exit $status
