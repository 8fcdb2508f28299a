"""A real enact-hub server for the client's tests: the installed binary serving the demo.

The binary is the one the package finds (`enact_hub.find_enact_hub_bin`), so these tests run
against what `pip install` put on disk. `scripts/test-python.sh` runs them from a directory
outside the checkout, in a virtualenv holding only the wheel and pytest.
"""

from __future__ import annotations

import os
import socket
import subprocess
import time
from dataclasses import dataclass
from typing import Iterator, List, Optional

import pytest
import requests

import enact_hub

ADMIN_TOKEN = "enact-hub-python-tests-admin-token"


def must_not_skip() -> bool:
    """The suite's one rule (tests/support/fixtures.rs, `must_not_skip`): under CI, `CI` set to
    anything but empty, `0` or `false`, nothing may skip for want of a prerequisite."""
    value = os.environ.get("CI", "").strip()
    return value not in ("", "0") and value.lower() != "false"


def import_or_skip(module: str):
    """`pytest.importorskip`, except that a missing module fails the test when
    `must_not_skip()`."""
    if must_not_skip():
        import importlib

        return importlib.import_module(module)
    return pytest.importorskip(module)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@dataclass
class Server:
    url: str
    process: "subprocess.Popen[bytes]"
    log: str

    def stop(self) -> None:
        self.process.terminate()
        try:
            self.process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


def serve(db: str, log: str, extra: Optional[List[str]] = None) -> Server:
    """Starts `enact-hub serve` on a free loopback port and waits for `/healthz`."""
    url = ""
    for _ in range(5):  # another process may take the port between choosing and binding
        port = free_port()
        url = "http://127.0.0.1:{}".format(port)
        env = dict(os.environ, ENACT_HUB_ADMIN_TOKEN=ADMIN_TOKEN, RUST_LOG="warn")
        with open(log, "ab") as out:
            process = subprocess.Popen(
                [enact_hub.find_enact_hub_bin(), "serve", "--db", db, "--addr", "127.0.0.1:{}".format(port)]
                + (extra or []),
                stdout=out,
                stderr=subprocess.STDOUT,
                env=env,
            )
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and process.poll() is None:
            try:
                if requests.get(url + "/healthz", timeout=2).status_code == 200:
                    return Server(url=url, process=process, log=log)
            except requests.RequestException:
                pass
            time.sleep(0.2)
        if process.poll() is None:
            process.kill()
            process.wait()
            break
    with open(log, encoding="utf-8", errors="replace") as f:
        raise RuntimeError("enact-hub serve did not answer /healthz at {}:\n{}".format(url, f.read()))


@pytest.fixture(scope="session")
def demo(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """The demo dataset served from a fresh database, with an admin token."""
    root = tmp_path_factory.mktemp("demo")
    server = serve(str(root / "demo.db"), str(root / "server.log"), ["--demo"])
    yield server
    server.stop()


@pytest.fixture(scope="session")
def admin(demo: Server) -> enact_hub.Hub:
    return enact_hub.Hub(demo.url, ADMIN_TOKEN)


@pytest.fixture(scope="session")
def submitter(demo: Server) -> enact_hub.Hub:
    """A hub client with a fresh submitter token (made over the admin API)."""
    response = requests.post(
        demo.url + "/api/v1/admin/tokens",
        json={"name": "python-tests", "role": "submitter"},
        headers={"Authorization": "Bearer " + ADMIN_TOKEN},
        timeout=30,
    )
    assert response.status_code == 201, response.text
    return enact_hub.Hub(demo.url, response.json()["token"])


@pytest.fixture(scope="session")
def public_demo(demo: Server) -> str:
    """The demo dataset's name, its answers made public (so its archive carries ground truth)."""
    response = requests.put(
        demo.url + "/api/v1/admin/datasets/demo/answers",
        json={"answers": "public"},
        headers={"Authorization": "Bearer " + ADMIN_TOKEN},
        timeout=30,
    )
    assert response.status_code in (200, 204), response.text
    return "demo"
