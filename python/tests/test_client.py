"""The `enact_hub` package against a real server: reading, downloading, submitting, errors."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any, Dict, List

import pytest

import enact_hub
from enact_hub import Hub, HubError

from conftest import Server, import_or_skip, serve

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def binary_version() -> str:
    out = subprocess.run([enact_hub.find_enact_hub_bin(), "--version"], capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_the_package_version_is_the_binarys_and_the_servers(demo: Server) -> None:
    line = binary_version()
    match = re.fullmatch(r"enact-hub (\S+) \(commit (\S+), schema sqlite (\d+), postgres (\d+)\)", line)
    assert match, line
    assert enact_hub.__version__ == match.group(1)
    served = Hub(demo.url).version()
    assert served["version"] == enact_hub.__version__
    assert served["commit"] == match.group(2)
    database = served["database"]
    assert database["backend"] == "sqlite"
    assert database["applied"] == database["expected"] == int(match.group(3))


def test_python_dash_m_runs_the_same_binary() -> None:
    out = subprocess.run([sys.executable, "-m", "enact_hub", "--version"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == binary_version()


def test_datasets_are_listed_with_their_counts(demo: Server) -> None:
    datasets = {d.name: d for d in Hub(demo.url).datasets()}
    demo_set = datasets["demo"]
    assert demo_set.items > 0
    assert demo_set.forward + demo_set.inverse == demo_set.items
    assert sum(sum(c.values()) for c in demo_set.by_step_length.values()) == demo_set.items
    assert set(demo_set.by_step_length["forward"]) == set(range(3, 11))
    assert Hub(demo.url).dataset("demo") == demo_set


def test_items_come_with_their_frames_as_png_bytes(demo: Server) -> None:
    items = list(Hub(demo.url).items("demo", direction="inverse", step_length=4, limit=3))
    assert len(items) == 3
    for item in items:
        assert item.direction == "inverse" and item.step_length == 4
        assert item.question and item.actions
        assert [image.position for image in item.images] == sorted(image.position for image in item.images)
        for image in item.images:
            assert isinstance(image.data, bytes) and image.data.startswith(PNG_SIGNATURE)
            assert image.label


def test_items_without_frames_and_as_pil_images(demo: Server) -> None:
    hub = Hub(demo.url)
    bare = next(hub.items("demo", frames="none"))
    assert all(image.data is None for image in bare.images)
    pil = import_or_skip("PIL.Image")
    item = next(hub.items("demo", frames="pil"))
    assert item.id == bare.id
    assert all(isinstance(image.data, pil.Image) and image.data.size[0] > 0 for image in item.images)
    with pytest.raises(ValueError, match="frames must be"):
        next(hub.items("demo", frames="jpeg"))


def test_a_bad_filter_raises_the_hubs_message(demo: Server) -> None:
    with pytest.raises(HubError) as caught:
        next(Hub(demo.url).items("demo", step_length=42))
    assert caught.value.status == 400
    assert caught.value.message == 'step_length: "42" is not a whole number from 3 to 10'
    assert caught.value.code == "bad_value_whole_number"
    with pytest.raises(HubError) as missing:
        Hub(demo.url).dataset("no-such-dataset")
    assert missing.value.status == 404
    # A typed reason: its code and what it names, for a program to act on.
    assert missing.value.code == "no_dataset"
    assert missing.value.details == {"dataset": "no-such-dataset"}


def all_items(hub: Hub, dataset: str) -> List[Dict[str, Any]]:
    return [
        {k: v for k, v in item.raw.items() if k != "dataset"}
        for item in hub.items(dataset, frames="none")
    ]


def test_a_download_imports_back_to_the_same_items(demo: Server, public_demo: str, tmp_path: Path) -> None:
    folder = tmp_path / "demo-copy"
    download = Hub(demo.url).download(public_demo, folder)
    assert download.ground_truth
    assert download.path == str(folder)
    records = (folder / "QA" / "enact_ordering.jsonl").read_text(encoding="utf-8").splitlines()
    assert len(records) == Hub(demo.url).dataset(public_demo).items
    assert download.files > len(records)  # the JSONL and every image

    db = str(tmp_path / "copy.db")
    imported = subprocess.run(
        [enact_hub.find_enact_hub_bin(), "import", str(folder), "--db", db],
        capture_output=True,
        text=True,
    )
    assert imported.returncode == 0, imported.stderr
    copy = serve(db, str(tmp_path / "copy.log"))
    try:
        assert all_items(Hub(copy.url), "demo-copy") == all_items(Hub(demo.url), public_demo)
    finally:
        copy.stop()


def ground_truth(demo: Server, dataset: str, tmp_path: Path) -> List[Dict[str, Any]]:
    folder = tmp_path / "truth"
    Hub(demo.url).download(dataset, folder)
    lines = (folder / "QA" / "enact_ordering.jsonl").read_text(encoding="utf-8").splitlines()
    return [json.loads(line) for line in lines]


def test_a_submission_returns_typed_scores(
    demo: Server, public_demo: str, submitter: Hub, tmp_path: Path
) -> None:
    records = ground_truth(demo, public_demo, tmp_path)
    right = records[: len(records) // 2]
    answers = {r["id"]: r["gt_answer"] for r in right}
    # One answer as a model would write it: prose around the order.
    first = right[0]
    answers[first["id"]] = "The order is {}.".format(first["gt_answer"])
    submission = submitter.submit(public_demo, "python-client", answers, description="half right", notes="pytest")
    assert submission.model == "python-client"
    assert submission.dataset == public_demo
    scores = submission.scores
    assert scores.coverage.dataset_items == len(records)
    assert scores.coverage.answered == len(right)
    assert scores.coverage.missing == len(records) - len(right)
    assert scores.coverage.unparseable == 0
    assert scores.overall is not None
    assert scores.overall.count == len(records)
    assert scores.overall.task_accuracy == pytest.approx(len(right) / len(records))
    assert set(scores.overall.per_step) == set(range(3, 11))
    assert scores.task_accuracy_interval is not None
    assert 0 <= scores.task_accuracy_interval.low <= scores.task_accuracy_interval.high <= 1

    again = submitter.submission(submission.id)
    assert again.scores == scores
    assert again.items is not None and len(again.items) == len(records)

    board = submitter.leaderboard(public_demo, all=True, model="python-client")
    assert any(row.get("submission") == submission.id or row.get("id") == submission.id for row in board["rows"]), board

    analysis = submitter.errors(submission.id)
    assert isinstance(analysis, dict) and analysis


def test_a_refused_submission_carries_the_hubs_problems(demo: Server, submitter: Hub) -> None:
    with pytest.raises(HubError) as caught:
        submitter.submit("demo", "python-client", [("not-an-item", "[1, 2]"), ("also-not", "[2, 1]")])
    error = caught.value
    assert error.status == 422
    assert error.problems and {p["line"] for p in error.problems} == {1, 2}
    assert "not-an-item" in str(error)
    assert error.body is not None and error.body["error"] == error.message
    assert error.code == "rejected" and error.details == {}


def test_a_bad_token_raises_the_hubs_message(demo: Server) -> None:
    hub = Hub(demo.url, "ehub_000000000000_nope")
    with pytest.raises(HubError) as caught:
        hub.submit("demo", "python-client", {})
    assert caught.value.status == 401
    assert caught.value.message == "the API token is unknown or has been revoked"
    assert caught.value.code == "token_unknown"
    assert str(caught.value).startswith("posting the submission: HTTP 401: ")
    with pytest.raises(HubError, match="needs a token"):
        Hub(demo.url).errors(1)


def test_an_unknown_study_raises_not_found(demo: Server) -> None:
    with pytest.raises(HubError) as caught:
        Hub(demo.url).study_report("no-such-study", "python-client")
    assert caught.value.status == 404


class FakeChat(BaseHTTPRequestHandler):
    """An OpenAI-compatible chat endpoint that answers every item "[1, 2, 3]"."""

    requests_seen = 0

    def do_POST(self) -> None:  # noqa: N802 (http.server's name)
        length = int(self.headers.get("Content-Length", "0"))
        json.loads(self.rfile.read(length) or b"{}")
        type(self).requests_seen += 1
        body = json.dumps(
            {
                "id": "chatcmpl-test",
                "object": "chat.completion",
                "choices": [{"index": 0, "message": {"role": "assistant", "content": "[1, 2, 3]"}, "finish_reason": "stop"}],
                "usage": {"prompt_tokens": 10, "completion_tokens": 5, "total_tokens": 15},
            }
        ).encode()
        self.send_response(200)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, *args: Any) -> None:
        pass


def test_run_drives_the_binarys_run_command(demo: Server, submitter: Hub, tmp_path: Path) -> None:
    fake = ThreadingHTTPServer(("127.0.0.1", 0), FakeChat)
    thread = threading.Thread(target=fake.serve_forever, daemon=True)
    thread.start()
    cache = tmp_path / "run-cache.jsonl"
    endpoint = "http://127.0.0.1:{}/v1".format(fake.server_address[1])
    try:
        result = submitter.run(
            "demo", endpoint=endpoint, model="fake-vlm", limit=4, concurrency=2, submit_as="python-run", cache=str(cache)
        )
        # The same run again: everything is in the cache, nothing is asked, the same submission.
        again = submitter.run(
            "demo", endpoint=endpoint, model="fake-vlm", limit=4, concurrency=2, submit_as="python-run", cache=str(cache)
        )
    finally:
        fake.shutdown()
    assert FakeChat.requests_seen == 4
    progress = result.report["progress"]
    assert (progress["total"], progress["answered"], progress["failed"]) == (4, 4, 0)
    assert progress["usage"] == {"prompt_tokens": 40, "completion_tokens": 20}
    assert again.report["progress"]["asked_now"] == 0
    assert again.report["submission"] == result.report["submission"]
    lines = cache.read_text().splitlines()
    assert len(lines) == 1 + 4
    assert json.loads(lines[0])["model"] == "fake-vlm"
    assert submitter.token and submitter.token not in cache.read_text()
    submission = submitter.submission(result.report["submission"])
    assert submission.model == "python-run"
    version = submitter.version()
    assert submission.scored_by == "{}+{}".format(version["version"], version["commit"])
    board = submitter.leaderboard("demo", all=True, model="python-run")
    assert board["rows"], board


def test_download_refuses_a_path_outside_the_folder() -> None:
    from enact_hub.client import _inside

    root = os.path.abspath("somewhere")
    assert _inside(root, "QA/images/a.png", "x") == os.path.join(root, "QA", "images", "a.png")
    for bad in ["../escape", "/etc/passwd", "QA/../../escape", "..\\escape"]:
        with pytest.raises(HubError, match="outside the folder"):
            _inside(root, bad, "x")

