"""Finding the ``enact-hub`` binary that was installed with this package."""

from __future__ import annotations

import os
import shutil
import sys
import sysconfig
from typing import List

__all__ = ["find_enact_hub_bin"]

_EXE = "enact-hub" + (sysconfig.get_config_var("EXE") or "")


def _user_scheme() -> str:
    """The install scheme ``pip install --user`` uses on this interpreter."""
    if sys.version_info >= (3, 10):
        return sysconfig.get_preferred_scheme("user")
    if os.name == "nt":
        return "nt_user"
    if sys.platform == "darwin" and getattr(sys, "_framework", None):
        return "osx_framework_user"
    return "posix_user"


def _candidates() -> List[str]:
    """Where pip may have put the binary, most likely first."""
    places = []
    override = os.environ.get("ENACT_HUB_BIN")
    if override:
        places.append(override)
    # The interpreter's own scripts folder: a virtualenv's or the system's `bin`.
    places.append(os.path.join(sysconfig.get_path("scripts"), _EXE))
    # `pip install --user`.
    try:
        places.append(os.path.join(sysconfig.get_path("scripts", scheme=_user_scheme()), _EXE))
    except KeyError:
        pass
    # `pip install --prefix DIR` and `--target DIR`: `bin` beside the package's root, or under
    # the prefix the package sits in (`DIR/lib/pythonX.Y/site-packages/enact_hub`).
    package_root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    places.append(os.path.join(package_root, "bin", _EXE))
    if os.path.basename(package_root) in ("site-packages", "dist-packages"):
        # PREFIX/lib/pythonX.Y/site-packages -> PREFIX/bin
        prefix = os.path.dirname(os.path.dirname(os.path.dirname(package_root)))
        places.append(os.path.join(prefix, "Scripts" if os.name == "nt" else "bin", _EXE))
    places.append(os.path.join(sys.prefix, "Scripts" if os.name == "nt" else "bin", _EXE))
    # Keep the first of each place: several schemes often name the same folder.
    return list(dict.fromkeys(places))


def find_enact_hub_bin() -> str:
    """The path of the ``enact-hub`` binary installed with this package.

    Looks where pip installs scripts: the interpreter's scripts folder, the user scheme's
    (``pip install --user``), beside the package (``pip install --target``) and under its
    prefix (``pip install --prefix``), then on ``PATH``. ``ENACT_HUB_BIN`` names one
    explicitly.

    Raises:
        FileNotFoundError: when none of those places holds it; the message lists them.
    """
    places = _candidates()
    for path in places:
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return path
    on_path = shutil.which(_EXE)
    if on_path:
        return on_path
    raise FileNotFoundError(
        "the enact-hub binary was not found; looked in " + ", ".join(places) + " and on PATH"
    )
