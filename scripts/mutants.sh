#!/usr/bin/env bash
# Mutation testing of the benchmark core (TESTING.md, "Mutation testing"). cargo-mutants
# changes the verifier, the agreement statistics, scoring and error analysis one mutant at a
# time (.cargo/mutants.toml names the files) and runs enact-core's tests against each; a mutant
# that no test notices is "missed". Not part of the test command: every mutant is one
# incremental build and one test run, 9 to 13 s on two cores, and there are 2,155: a whole run
# takes six to seven hours (TESTING.md has the measured figures).
#
# Arguments go to cargo mutants: `--shard 1/10 --sharding round-robin` for a sample of every
# tenth mutant, `-F 'agreement/alpha\.rs'` for one file, `--list` to see them. The outcomes
# are in target/mutants/mutants.out (outcomes.json, missed.txt, a diff and log per mutant);
# the per-module table TESTING.md quotes is printed at the end.
set -euo pipefail
cd "$(dirname "$0")/.."

VERSION=27.1.0
if ! cargo mutants --version 2>/dev/null | grep -qF "$VERSION"; then
  echo "== installing cargo-mutants $VERSION (crates.io)"
  cargo install --locked cargo-mutants --version "$VERSION"
fi
# Each mutant is built in a copy of the tree, which has no ../shared beside it: the tests that
# compare with ENACT's outputs find the fixtures through ENACT_FIXTURES instead.
if [ -z "${ENACT_FIXTURES:-}" ] && [ -d ../shared/fixtures ]; then
  ENACT_FIXTURES="$(realpath ../shared/fixtures)"
  export ENACT_FIXTURES
fi
OUT="${MUTANTS_OUT:-target/mutants}"
mkdir -p "$OUT"
status=0
cargo mutants -p enact-core --output "$OUT" "$@" || status=$?
if [ -f "$OUT/mutants.out/outcomes.json" ]; then
  python3 scripts/mutants-summary.py "$OUT/mutants.out/outcomes.json"
fi
# cargo-mutants exits 2 when a mutant was missed, 3 when one timed out, 4 when the tree fails
# its tests unmutated.
exit "$status"
