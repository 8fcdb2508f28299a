#!/usr/bin/env python3
"""Time python `krippendorff` on the cases `cargo bench --bench agreement` times in Rust.

For each case: one alpha call, then alpha + B percentile-bootstrap resamples over units
(numpy default_rng(seed), X[:, rng.integers(0, N, N)]), repeated and reported as medians.

Input is either
  * a reliability-data file `{"data": [[...], ...], "level": "ordinal"}` (one list per coder,
    numbers or null; "level" optional, --level otherwise), or
  * the shared vectors file (a JSON list); pick entries with --name (repeatable). Without
    --name the two data sets the Rust bench uses are taken:
    synthetic_3x240_values_1_to_10_ordinal and synthetic_3x10000_values_1_to_10_ordinal.

Needs numpy and krippendorff, e.g.
  python3 -m venv /tmp/kvenv && /tmp/kvenv/bin/pip install krippendorff numpy
  /tmp/kvenv/bin/python bench_python.py ../../shared/fixtures/kalpha/vectors.json
"""

import argparse
import json
import statistics
import sys
import time
import warnings

import krippendorff
import numpy as np

DEFAULT_NAMES = [
    "synthetic_3x240_values_1_to_10_ordinal",
    "synthetic_3x10000_values_1_to_10_ordinal",
]


def to_matrix(rows):
    """Coders x units float matrix with NaN for missing values."""
    return np.array(
        [[np.nan if value is None else float(value) for value in row] for row in rows],
        dtype=float,
    )


def load_cases(path, names, level):
    with open(path, encoding="utf-8") as handle:
        document = json.load(handle)
    if isinstance(document, dict):
        if "data" not in document:
            sys.exit(f"{path}: expected an object with a \"data\" field")
        return [(path, to_matrix(document["data"]), document.get("level", level))]
    by_name = {entry["name"]: entry for entry in document}
    wanted = names or [name for name in DEFAULT_NAMES if name in by_name]
    missing = [name for name in wanted if name not in by_name]
    if missing:
        sys.exit(f"{path}: no vector named {', '.join(missing)}")
    return [(name, to_matrix(by_name[name]["data"]), by_name[name]["level"]) for name in wanted]


def alpha_or_none(matrix, level):
    """Alpha, or None where krippendorff raises or returns NaN (undefined)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            value = krippendorff.alpha(reliability_data=matrix, level_of_measurement=level)
    except ValueError:
        return None
    return None if np.isnan(value) else float(value)


def alpha_with_bootstrap(matrix, level, replicates, seed, confidence):
    estimate = alpha_or_none(matrix, level)
    rng = np.random.default_rng(seed)
    units = matrix.shape[1]
    alphas = []
    for _ in range(replicates):
        value = alpha_or_none(matrix[:, rng.integers(0, units, size=units)], level)
        if value is not None:
            alphas.append(value)
    tail = (1.0 - confidence) / 2.0 * 100.0
    low, high = np.percentile(alphas, [tail, 100.0 - tail]) if alphas else (None, None)
    return estimate, low, high, replicates - len(alphas)


def median_seconds(function, repeats):
    times = []
    result = None
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times), max(times), result


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("path", help="reliability-data JSON or the shared vectors.json")
    parser.add_argument("--name", action="append", default=[], help="vector name (repeatable)")
    parser.add_argument("--level", default="ordinal",
                        choices=["nominal", "ordinal", "interval", "ratio"],
                        help="level for a data file without one (default ordinal)")
    parser.add_argument("--replicates", type=int, default=1000)
    parser.add_argument("--confidence", type=float, default=0.95)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeats", type=int, default=5,
                        help="timed runs of alpha + bootstrap per case (default 5)")
    parser.add_argument("--alpha-calls", type=int, default=20,
                        help="timed single alpha calls per case (default 20)")
    parser.add_argument("--json", action="store_true", help="print one JSON object per case")
    args = parser.parse_args()

    for name, matrix, level in load_cases(args.path, args.name, args.level):
        alpha_time, _, _, estimate = median_seconds(
            lambda: alpha_or_none(matrix, level), args.alpha_calls
        )
        boot_time, boot_min, boot_max, (_, low, high, undefined) = median_seconds(
            lambda: alpha_with_bootstrap(
                matrix, level, args.replicates, args.seed, args.confidence
            ),
            args.repeats,
        )
        row = {
            "case": name,
            "coders": matrix.shape[0],
            "units": matrix.shape[1],
            "level": level,
            "alpha": estimate,
            "ci_low": None if low is None else float(low),
            "ci_high": None if high is None else float(high),
            "undefined_replicates": undefined,
            "replicates": args.replicates,
            "alpha_median_s": alpha_time,
            "alpha_plus_bootstrap_median_s": boot_time,
            "alpha_plus_bootstrap_min_s": boot_min,
            "alpha_plus_bootstrap_max_s": boot_max,
            "repeats": args.repeats,
            "numpy": np.__version__,
            "krippendorff": getattr(krippendorff, "__version__", "unknown"),
        }
        if args.json:
            print(json.dumps(row))
        else:
            print(
                f"{name}: {matrix.shape[0]}x{matrix.shape[1]} {level}, alpha {estimate}, "
                f"{args.confidence:.0%} CI [{row['ci_low']}, {row['ci_high']}]\n"
                f"  alpha: {alpha_time * 1e3:.3f} ms (median of {args.alpha_calls})\n"
                f"  alpha + {args.replicates} bootstrap: {boot_time:.3f} s median "
                f"(min {boot_min:.3f}, max {boot_max:.3f}, {args.repeats} runs)"
            )


if __name__ == "__main__":
    main()
