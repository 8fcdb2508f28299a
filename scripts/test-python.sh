#!/usr/bin/env bash
# The Python package and the installed binary, as a user gets them (part of scripts/test.sh; runs
# alone too). Builds the wheel with maturin, checks what it holds, installs it into a fresh
# virtualenv and, from a directory outside the checkout, runs `enact-hub --version`,
# `python -m enact_hub --version`, `enact-hub serve --demo` answering /healthz and the client's
# pytest suite against a real server; then `cargo install --path . --locked` into an empty root
# and the same serve check from an empty directory.
#
# The wheel and the install are built with the `dev` profile in the test suite's own target dir,
# so they reuse the dependencies `cargo test` just built (an optimised build of the whole tree
# would add more than ten minutes on CI's two cores); ENACT_HUB_WHEEL_PROFILE=dist builds what
# ships instead. What is checked here is the packaging, not the optimiser.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
START=$(date +%s)

export CARGO_TARGET_DIR
CARGO_TARGET_DIR="$(realpath -m "${CARGO_TARGET_DIR:-target}")"
TOOLS="$CARGO_TARGET_DIR/test-tools"
PROFILE="${ENACT_HUB_WHEEL_PROFILE:-dev}"
# The wheel's platform tag. The default, manylinux_2_34, is what a build on this system's glibc
# gives. ENACT_HUB_WHEEL_COMPAT=manylinux2014 builds for glibc 2.17 instead, linking with zig
# (`ziglang` from PyPI) through maturin's --zig; that build compiles every dependency again for an
# explicit --target, so the default suite does not do it; README "Wheels and platforms" shows
# the command.
COMPAT="${ENACT_HUB_WHEEL_COMPAT:-manylinux_2_34}"
ZIG_ARGS=()
case "$COMPAT" in
  manylinux_2_34) ;;
  manylinux2014) ZIG_ARGS=(--zig) ;;
  *) echo "error: ENACT_HUB_WHEEL_COMPAT must be manylinux_2_34 or manylinux2014, not $COMPAT" >&2; exit 2 ;;
esac
VERSION=$(sed -n 's/^version = "\(.*\)"$/\1/p' Cargo.toml | head -n 1)

# Pinned tools from PyPI: maturin and its build in one virtualenv, and a wheelhouse of what the
# fresh virtualenv installs besides the wheel (the package's dependencies, requests and
# cryptography, Pillow for its `pil` extra, pytest), so later runs install offline.
TOOLS_VENV="$TOOLS/maturin-venv"
WHEELHOUSE="$TOOLS/wheelhouse"
PINNED=(requests==2.34.2 cryptography==48.0.0 pillow==11.3.0 pytest==9.2.0)
if [ ! -x "$TOOLS_VENV/bin/maturin" ] || [ ! -f "$WHEELHOUSE/.complete" ]; then
  echo "== installing maturin 1.16.0 (PyPI) into $TOOLS_VENV; ${PINNED[*]} into $WHEELHOUSE"
  mkdir -p "$TOOLS"
  if ! python3 -m venv "$TOOLS_VENV" >/dev/null 2>&1; then
    apt-get update && apt-get install -y python3-venv
    python3 -m venv "$TOOLS_VENV"
  fi
  "$TOOLS_VENV/bin/pip" install --quiet --disable-pip-version-check 'maturin==1.16.0'
  "$TOOLS_VENV/bin/pip" download --quiet --disable-pip-version-check --dest "$WHEELHOUSE" "${PINNED[@]}"
  touch "$WHEELHOUSE/.complete"
fi
# A wheelhouse made before the package needed cryptography (signed statements) gets it now.
if ! ls "$WHEELHOUSE"/cryptography-*.whl >/dev/null 2>&1; then
  echo "== adding cryptography (PyPI) to $WHEELHOUSE"
  "$TOOLS_VENV/bin/pip" download --quiet --disable-pip-version-check --dest "$WHEELHOUSE" 'cryptography==48.0.0'
fi
if [ ${#ZIG_ARGS[@]} -gt 0 ] && ! "$TOOLS_VENV/bin/python" -c 'import ziglang' 2>/dev/null; then
  echo "== installing ziglang 0.13.0 (PyPI) into $TOOLS_VENV, the linker for a glibc 2.17 wheel"
  "$TOOLS_VENV/bin/pip" install --quiet --disable-pip-version-check 'ziglang==0.13.0'
fi

WORK=$(mktemp -d)
SERVER=""
cleanup() {
  if [ -n "$SERVER" ]; then kill "$SERVER" 2>/dev/null || true; fi
  rm -rf "$WORK"
}
trap cleanup EXIT

# serve_demo BINARY: `serve --demo` from an empty directory until /healthz answers, then stops it.
serve_demo() {
  local port dir
  port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  dir=$(mktemp -d -p "$WORK")
  (cd "$dir" && exec env RUST_LOG=warn "$1" serve --demo --addr "127.0.0.1:$port" >"$dir/serve.log" 2>&1) &
  SERVER=$!
  for _ in $(seq 1 600); do
    if curl -fsS "http://127.0.0.1:$port/healthz" >/dev/null 2>&1; then
      echo "   $1 serve --demo answers /healthz on 127.0.0.1:$port"
      kill "$SERVER"
      wait "$SERVER" 2>/dev/null || true
      SERVER=""
      return 0
    fi
    if ! kill -0 "$SERVER" 2>/dev/null; then break; fi
    sleep 0.2
  done
  echo "error: $1 serve --demo did not answer /healthz:" >&2
  cat "$dir/serve.log" >&2
  return 1
}

echo "== maturin build --profile $PROFILE (the wheel)"
WHEELS="$WORK/wheels"
BUILD_START=$(date +%s)
# maturin finds zig through the virtualenv's python (`python -m ziglang`), so its bin goes first.
PATH="$TOOLS_VENV/bin:$PATH" "$TOOLS_VENV/bin/maturin" build --locked --profile "$PROFILE" \
  --compatibility "$COMPAT" "${ZIG_ARGS[@]}" --out "$WHEELS"
WHEEL=$(ls "$WHEELS"/enact_hub-"$VERSION"-*.whl 2>/dev/null | head -n 1 || true)
if [ -z "$WHEEL" ]; then
  echo "error: maturin built no wheel for version $VERSION in $WHEELS" >&2
  exit 1
fi
echo "   $(basename "$WHEEL"): $(du -h "$WHEEL" | cut -f1) in $(( $(date +%s) - BUILD_START )) s"

echo "== the wheel's contents"
"$TOOLS_VENV/bin/python" - "$WHEEL" "$VERSION" <<'PY'
import re, sys, zipfile
wheel, version = sys.argv[1], sys.argv[2]
names = zipfile.ZipFile(wheel).namelist()
for name in names:
    print("   " + name)
metadata_name = "enact_hub-{}.dist-info/METADATA".format(version)
info = re.escape("enact_hub-{}.dist-info/".format(version))
data = re.escape("enact_hub-{}.data/".format(version))
allowed = [
    r"enact_hub/[a-z_]+\.py", r"enact_hub/py\.typed",
    info + r"(METADATA|WHEEL|RECORD)", info + r"licenses/.+",
    # The dependency tree's SBOM (PEP 770), which maturin writes into the metadata.
    info + r"sboms/[a-z_-]+\.cyclonedx\.json",
    data + r"scripts/enact-hub",
]
required = [
    data + "scripts/enact-hub", "enact_hub/__init__.py", "enact_hub/__main__.py",
    "enact_hub/client.py", "enact_hub/verify.py", "enact_hub/py.typed", info + "METADATA", info + "WHEEL", info + "RECORD",
]
stray = [n for n in names if not any(re.fullmatch(p, n) for p in allowed)]
missing = [r for r in required if not any(re.fullmatch(r, n) for n in names)]
metadata = zipfile.ZipFile(wheel).read(metadata_name).decode()
problems = ["not expected in the wheel: " + n for n in stray] + ["missing from the wheel: " + m for m in missing]
if "\nVersion: {}\n".format(version) not in metadata:
    problems.append("METADATA does not give Version: " + version)
if not re.search(r"^Requires-Dist: requests", metadata, re.M):
    problems.append("METADATA does not require requests")
if not re.search(r"^Requires-Dist: cryptography", metadata, re.M):
    problems.append("METADATA does not require cryptography")
# The platform tag is a promise about glibc: no symbol of the binary may need a newer version.
tag = re.search(r"manylinux_(\d+)_(\d+)_x86_64", wheel)
if tag is None:
    problems.append("the wheel's name has no manylinux_X_Y tag: " + wheel)
else:
    import subprocess, tempfile
    promised = (int(tag.group(1)), int(tag.group(2)))
    with tempfile.TemporaryDirectory() as scratch:
        binary = zipfile.ZipFile(wheel).extract(
            "enact_hub-{}.data/scripts/enact-hub".format(version), scratch)
        symbols = subprocess.run(["objdump", "-T", binary], check=True, capture_output=True,
                                 text=True).stdout
    needed = max({tuple(int(p) for p in v.split(".")) for v in re.findall(r"GLIBC_(\d+(?:\.\d+)+)", symbols)})
    print("   the binary needs glibc {}; the tag promises {}.{}".format(
        ".".join(map(str, needed)), *promised))
    if needed[:2] > promised:
        problems.append("the binary needs glibc {} but the tag says {}.{}".format(
            ".".join(map(str, needed)), *promised))
if problems:
    sys.exit("error: " + "\n  ".join(problems))
print("   {} entries: the binary, the enact_hub package and its metadata".format(len(names)))
PY

echo "== a fresh virtualenv with the wheel (and pytest), used from outside the checkout"
VENV="$WORK/venv"
python3 -m venv "$VENV"
"$VENV/bin/pip" install --quiet --disable-pip-version-check --no-index --find-links "$WHEELHOUSE" \
  "$WHEEL[pil]" pytest
OUTSIDE=$(mktemp -d -p "$WORK")
cd "$OUTSIDE"
BINARY_VERSION=$("$VENV/bin/enact-hub" --version)
MODULE_VERSION=$("$VENV/bin/python" -m enact_hub --version)
PACKAGE_VERSION=$("$VENV/bin/python" -c 'import enact_hub; print(enact_hub.__version__)')
echo "   enact-hub --version:           $BINARY_VERSION"
echo "   python -m enact_hub --version: $MODULE_VERSION"
echo "   enact_hub.__version__:         $PACKAGE_VERSION"
case "$BINARY_VERSION" in
  "enact-hub $VERSION (commit "*) ;;
  *) echo "error: enact-hub --version does not say $VERSION" >&2; exit 1 ;;
esac
if [ "$MODULE_VERSION" != "$BINARY_VERSION" ] || [ "$PACKAGE_VERSION" != "$VERSION" ]; then
  echo "error: the package's versions differ from the binary's" >&2
  exit 1
fi
serve_demo "$VENV/bin/enact-hub"

echo "== pytest python/tests (the client against a real server)"
# PATH holds only the virtualenv's bin first, so the tests use what the wheel installed.
PATH="$VENV/bin:$PATH" "$VENV/bin/python" -m pytest -p no:cacheprovider -rs -q \
  --rootdir "$ROOT/python/tests" "$ROOT/python/tests"
cd "$ROOT"

echo "== cargo install --path . --locked --profile $PROFILE, then serve --demo from an empty directory"
INSTALL_START=$(date +%s)
cargo install --quiet --path . --locked --profile "$PROFILE" --root "$WORK/cargo-root" --bin enact-hub
echo "   installed in $(( $(date +%s) - INSTALL_START )) s: $("$WORK/cargo-root/bin/enact-hub" --version)"
serve_demo "$WORK/cargo-root/bin/enact-hub"

echo "== the Python package checks took $(( $(date +%s) - START )) s"
