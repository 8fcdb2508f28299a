#!/usr/bin/env python3
"""Tallies cargo-mutants runs (their outcomes.json) by benchmark-core module and file: caught,
missed, timed out and unviable mutants, and the share caught of the viable ones (caught, missed
and timed out: a timeout counts as noticed, since the mutant made a test hang). Lists every
missed mutant. Prints Markdown, the form TESTING.md quotes.

Given several outcome files (a run, then `--iterate` runs that test again what it missed), a
mutant's last outcome counts."""
import json
import sys
from collections import Counter, defaultdict

KINDS = {"CaughtMutant": "caught", "MissedMutant": "missed", "Timeout": "timeout", "Unviable": "unviable"}
PREFIX = "crates/enact-core/src/"


def module_of(path):
    rest = path[len(PREFIX):] if path.startswith(PREFIX) else path
    return rest.split("/")[0].removesuffix(".rs")


def row(name, counts):
    viable = counts["caught"] + counts["missed"] + counts["timeout"]
    share = f"{100 * (counts['caught'] + counts['timeout']) / viable:.1f} %" if viable else "–"
    return f"| {name} | {counts['caught']} | {counts['missed']} | {counts['timeout']} | {counts['unviable']} | {share} |"


def main(paths):
    latest = {}
    for path in paths:
        with open(path, encoding="utf-8") as f:
            outcomes = json.load(f)["outcomes"]
        for outcome in outcomes:
            scenario = outcome["scenario"]
            mutant = scenario.get("Mutant") if isinstance(scenario, dict) else None
            if mutant is None:
                continue  # the unmutated baseline
            kind = KINDS.get(outcome["summary"])
            if kind is None:
                sys.exit(f"{path}: unknown outcome {outcome['summary']!r} for {mutant['name']}")
            latest[mutant["name"]] = (mutant["file"], kind)
    by_module = defaultdict(Counter)
    by_file = defaultdict(Counter)
    missed = []
    for name, (file, kind) in latest.items():
        by_module[module_of(file)][kind] += 1
        by_file[file[len(PREFIX):]][kind] += 1
        if kind == "missed":
            missed.append(name)
    header = "| {} | caught | missed | timed out | unviable | caught of viable |\n|---|---|---|---|---|---|"
    print(header.format("module"))
    total = Counter()
    for module in sorted(by_module):
        print(row(module, by_module[module]))
        total.update(by_module[module])
    print(row("**all**", total))
    print()
    print(header.format("file"))
    for file in sorted(by_file):
        print(row(file, by_file[file]))
    print()
    print(f"missed ({len(missed)}):")
    for name in sorted(missed):
        print(f"- {name}")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: mutants-summary.py OUTCOMES_JSON [LATER_OUTCOMES_JSON ...]")
    main(sys.argv[1:])
