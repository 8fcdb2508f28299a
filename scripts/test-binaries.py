#!/usr/bin/env python3
"""Runs cargo's test binaries two at a time, as `cargo test` would run them one after another.

`cargo test` runs one test binary at a time, and most of ours keep both cores busy only part
of the time: the service suite waits on its servers and its Chromium, the crash trials on the
processes they kill. Run side by side, the waiting of one is the other's CPU time.

    scripts/test-binaries.py [--lanes N] [--first NAME]... -- CARGO_TEST_ARGS...

builds with `cargo test CARGO_TEST_ARGS --no-run`, then runs every test executable it built in
its package's directory (as cargo does), N at a time: the binaries named by --first before the
rest (name them longest first), the rest in cargo's order. Each binary's output is printed
whole when it ends, under the same "Running" line cargo prints. Every binary runs even when one
fails; the exit status is 1 if any failed, and the failed ones are named last.
"""

import argparse
import json
import os
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor


def test_executables(cargo_args):
    command = ["cargo", "test", *cargo_args, "--no-run"]
    command.append("--message-format=json-render-diagnostics")
    build = subprocess.run(command, stdout=subprocess.PIPE, text=True)
    if build.returncode != 0:
        # json-render-diagnostics: the compiler's messages went to stderr as cargo prints them.
        sys.exit(f"error: the test build failed (exit {build.returncode}): {' '.join(command)}")
    out = build.stdout
    found = []
    for line in out.splitlines():
        if not line.startswith("{"):
            continue
        message = json.loads(line)
        if message.get("reason") != "compiler-artifact" or not message.get("executable"):
            continue
        if not message["profile"]["test"]:
            continue
        target = message["target"]
        found.append(
            {
                "name": target["name"],
                "kind": target["kind"][0],
                "src": target["src_path"],
                "exe": message["executable"],
                "dir": os.path.dirname(message["manifest_path"]),
            }
        )
    return found


def describe(binary, root):
    src = os.path.relpath(binary["src"], binary["dir"])
    exe = os.path.relpath(binary["exe"], root)
    what = "unittests " if binary["kind"] in ("lib", "bin", "example") else ""
    return f"{what}{src} ({exe})"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lanes", type=int, default=2, help="binaries run at once (2)")
    parser.add_argument(
        "--first", action="append", default=[], help="a binary to start before the rest"
    )
    parser.add_argument("cargo_args", nargs="*", help="arguments of `cargo test`")
    args = parser.parse_args()

    root = os.getcwd()
    binaries = test_executables(args.cargo_args)
    if not binaries:
        sys.exit("error: cargo built no test binary for: cargo test " + " ".join(args.cargo_args))
    unknown = [name for name in args.first if name not in {b["name"] for b in binaries}]
    if unknown:
        sys.exit("error: --first names no test binary that cargo built: " + ", ".join(unknown))
    rank = {name: i for i, name in enumerate(args.first)}
    binaries.sort(key=lambda b: rank.get(b["name"], len(rank)))

    print_lock = threading.Lock()
    failed = []
    started = time.monotonic()

    def run(binary):
        begin = time.monotonic()
        result = subprocess.run(
            [binary["exe"]],
            cwd=binary["dir"],
            env={**os.environ, "CARGO_MANIFEST_DIR": binary["dir"]},
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            errors="replace",
        )
        took = time.monotonic() - begin
        with print_lock:
            print(f"     Running {describe(binary, root)}", flush=True)
            sys.stdout.write(result.stdout)
            verdict = "ok" if result.returncode == 0 else f"FAILED (exit {result.returncode})"
            print(
                f"     {verdict}: {binary['name']} in {took:.0f} s "
                f"({time.monotonic() - started:.0f} s since the first binary started)",
                flush=True,
            )
            if result.returncode != 0:
                failed.append(describe(binary, root))

    with ThreadPoolExecutor(max_workers=args.lanes) as pool:
        list(pool.map(run, binaries))

    if failed:
        print("error: test binaries failed:", file=sys.stderr)
        for name in failed:
            print(f"  {name}", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
