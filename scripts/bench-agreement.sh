#!/usr/bin/env bash
# Krippendorff's alpha + 1000 bootstrap resamples, enact-hub (criterion) and python
# `krippendorff` side by side on the same data, for BENCHMARKS.md.
#
#   scripts/bench-agreement.sh
#
# The python side runs in a throwaway venv (PyPI: krippendorff, numpy). Data: the 3x240 and
# 3x10000 ordinal vectors of ../shared/fixtures/kalpha/vectors.json (the Rust bench generates
# data of the same shape when the fixtures are absent; the python comparison then skips).
set -euo pipefail
cd "$(dirname "$0")/.."

echo "## enact-hub (cargo bench --bench agreement)"
cargo bench --locked --bench agreement 2>&1 | grep -B1 "time:" | grep -v "^--" || true

VECTORS=${ENACT_FIXTURES:-../shared/fixtures}/kalpha/vectors.json
if [ ! -f "$VECTORS" ]; then
  echo "no $VECTORS: python comparison skipped"
  exit 0
fi
VENV=$(mktemp -d)/venv
trap 'rm -rf "$(dirname "$VENV")"' EXIT
python3 -m venv "$VENV"
"$VENV/bin/pip" install --quiet krippendorff numpy
echo
echo "## python krippendorff $("$VENV/bin/python" -c 'import importlib.metadata as m; print(m.version("krippendorff"))')"
"$VENV/bin/python" scripts/bench_agreement.py "$VECTORS"
