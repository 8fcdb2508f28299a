"""Prints how long the server's write transactions waited for their turn, per lane, and its
use cases for a pooled connection, from its `/metrics` text (the
`enact_hub_db_write_wait_seconds` and `enact_hub_db_connection_wait_seconds` histograms):
count, and the upper bound of the bucket holding the 50th, 99th and 99.9th percentile and the
largest wait.

    python3 scripts/lib/write_waits.py METRICS_FILE
"""
import re
import sys

buckets = {}
for line in open(sys.argv[1], encoding="utf-8"):
    m = re.match(r'enact_hub_db_(write|connection)_wait_seconds_bucket\{(.*)\} (\S+)', line)
    if not m:
        continue
    labels = dict(re.findall(r'(\w+)="([^"]*)"', m.group(2)))
    le = float("inf") if labels["le"] == "+Inf" else float(labels["le"])
    what = (f"write waits, {labels['lane']} lane" if m.group(1) == "write"
            else "connection waits (every use case)")
    buckets.setdefault(what, []).append((le, float(m.group(3))))


def bound(rows, share):
    total = rows[-1][1]
    for le, cumulative in rows:
        if cumulative >= share * total:
            return le
    return float("inf")


def ms(seconds):
    return "over the last bucket" if seconds == float("inf") else f"≤ {seconds * 1000:g} ms"


for what, rows in sorted(buckets.items()):
    rows.sort()
    total = int(rows[-1][1])
    if total == 0:
        continue
    print(f"{what}: {total}; p50 {ms(bound(rows, 0.5))}, "
          f"p99 {ms(bound(rows, 0.99))}, p99.9 {ms(bound(rows, 0.999))}, max {ms(bound(rows, 1.0))}")
