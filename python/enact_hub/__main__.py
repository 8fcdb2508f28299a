"""``python -m enact_hub ARGS`` runs the ``enact-hub`` binary installed with this package."""

from __future__ import annotations

import os
import subprocess
import sys

from ._binary import find_enact_hub_bin


def main() -> int:
    """Runs the binary with this process's arguments; its exit status is returned."""
    try:
        binary = find_enact_hub_bin()
    except FileNotFoundError as error:
        print("error: {}".format(error), file=sys.stderr)
        return 1
    args = [binary, *sys.argv[1:]]
    if sys.platform == "win32":
        # Windows has no exec that replaces the process: wait for the child instead.
        return subprocess.run(args).returncode
    os.execv(binary, args)
    return 0  # not reached: execv replaces this process


if __name__ == "__main__":
    sys.exit(main())
