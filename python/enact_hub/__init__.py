"""enact-hub for Python: the ``enact-hub`` binary and a typed client for its API.

Installing the wheel puts the ``enact-hub`` command on the PATH (``python -m enact_hub`` runs
the same binary). The client reads datasets, downloads them in ENACT's release layout, submits
answers and reads scores, leaderboards, error analyses and study reports::

    from enact_hub import Hub

    hub = Hub("http://127.0.0.1:8080", token="ehub_...")
    for item in hub.items("enact", limit=5):
        print(item.id, item.question, [image.label for image in item.images])
    scores = hub.submit("enact", "my-model", {"item-id": "[2, 1, 3]"}).scores
    print(scores.overall.task_accuracy, scores.coverage.coverage)

Every failure raises :class:`HubError`, which carries the hub's own message and problems.
"""

from __future__ import annotations


def _installed_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("enact-hub")
    except PackageNotFoundError:
        # Imported from a checkout (PYTHONPATH=python) rather than installed.
        return "0+unknown"


#: The package's version: the binary's (``enact-hub --version``), both taken from Cargo.toml.
__version__ = _installed_version()

from ._binary import find_enact_hub_bin  # noqa: E402
from .client import Answer, Hub  # noqa: E402
from .errors import HubError  # noqa: E402
from .types import (  # noqa: E402
    Action,
    Coverage,
    Dataset,
    Download,
    Image,
    Interval,
    Item,
    Performance,
    RunResult,
    Scores,
    Submission,
)

__all__ = [
    "Action",
    "Answer",
    "Coverage",
    "Dataset",
    "Download",
    "Hub",
    "HubError",
    "Image",
    "Interval",
    "Item",
    "Performance",
    "RunResult",
    "Scores",
    "Submission",
    "__version__",
    "find_enact_hub_bin",
]
