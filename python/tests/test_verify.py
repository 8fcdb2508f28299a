"""Signed statements checked in Python (`enact_hub.verify`, Ed25519 from `cryptography`) against
a statement a real server made: it verifies, fails after one changed payload byte, and refuses
other answers."""

from __future__ import annotations

import base64
import copy
import hashlib
import json
from pathlib import Path
from typing import Any, Dict, Tuple

import pytest
import requests

from enact_hub import Hub
from enact_hub.verify import PAYLOAD_TYPE, StatementError, pae, verdicts_sha256, verify

from conftest import Server


def submitted(demo: Server, submitter: Hub) -> Tuple[int, bytes]:
    """Posts answers to a few demo items as exact bytes; the submission's id and the bytes."""
    ids = [item.id for item in Hub(demo.url).items("demo", frames="none", limit=4)]
    body = "".join(json.dumps({"id": i, "answer": "[1, 2]"}) + "\n" for i in ids).encode("utf-8")
    response = requests.post(
        demo.url + "/api/v1/datasets/demo/submissions",
        params={"model": "python-verify"},
        data=body,
        headers={"Authorization": "Bearer " + str(submitter.token), "Content-Type": "application/x-ndjson"},
        timeout=60,
    )
    assert response.status_code == 201, response.text
    return response.json()["id"], body


@pytest.fixture(scope="module")
def signed(demo: Server, submitter: Hub) -> Tuple[int, bytes, Dict[str, Any], Dict[str, Any]]:
    submission, body = submitted(demo, submitter)
    return submission, body, submitter.statement(submission), submitter.keys()


def test_pae_is_dsse_s_example() -> None:
    assert pae("http://example.com/HelloWorld", b"hello world") == b"DSSEv1 29 http://example.com/HelloWorld 11 hello world"


def test_a_statement_of_the_server_verifies_with_its_published_key(signed, submitter: Hub, tmp_path: Path) -> None:
    submission, body, envelope, keys = signed
    assert envelope["payloadType"] == PAYLOAD_TYPE
    checked = verify(envelope, keys)
    assert checked.keyid == envelope["signatures"][0]["keyid"]
    assert checked.key["algorithm"] == "ed25519"
    statement = checked.statement
    assert statement["submission"]["id"] == submission
    assert statement["dataset"]["name"] == "demo"
    assert statement["answers_sha256"] == hashlib.sha256(body).hexdigest()
    assert statement["provenance"] == "submitted"
    assert not checked.answers_checked
    # The answers, as bytes or as a file, and the keys fetched from the hub.
    assert verify(envelope, keys, answers=body).answers_checked
    path = tmp_path / "answers.jsonl"
    path.write_bytes(body)
    assert verify(json.dumps(envelope), hub=submitter, answers=str(path)).answers_checked


def test_one_changed_payload_byte_fails(signed) -> None:
    _, _, envelope, keys = signed
    payload = bytearray(base64.b64decode(envelope["payload"]))
    for position in (0, len(payload) // 2, len(payload) - 2):
        tampered = copy.deepcopy(envelope)
        changed = bytearray(payload)
        changed[position] ^= 0x01
        tampered["payload"] = base64.b64encode(bytes(changed)).decode("ascii")
        with pytest.raises(StatementError, match="^bad signature: "):
            verify(tampered, keys)
    tampered = copy.deepcopy(envelope)
    sig = bytearray(base64.b64decode(tampered["signatures"][0]["sig"]))
    sig[0] ^= 0x01
    tampered["signatures"][0]["sig"] = base64.b64encode(bytes(sig)).decode("ascii")
    with pytest.raises(StatementError, match="^bad signature: "):
        verify(tampered, keys)


def test_other_answers_are_refused(signed) -> None:
    _, body, envelope, keys = signed
    with pytest.raises(StatementError, match="^answers differ: "):
        verify(envelope, keys, answers=body + b"\n")


def test_unknown_keys_and_malformed_envelopes_name_what_is_wrong(signed) -> None:
    _, _, envelope, keys = signed
    with pytest.raises(StatementError, match="^unknown key id "):
        verify(envelope, {"keys": []})
    broken = dict(envelope)
    del broken["payload"]
    with pytest.raises(StatementError, match="`payload` is missing"):
        verify(broken, keys)
    lying = copy.deepcopy(keys)
    lying["keys"][0]["keyid"] = "0000000000000000"
    with pytest.raises(StatementError, match=r"`keys\[0\]\.keyid`"):
        verify(envelope, lying)


def test_the_verdicts_digest_is_computed_again_from_the_public_verdicts(
    demo: Server, public_demo: str, submitter: Hub
) -> None:
    submission, _ = submitted(demo, submitter)
    envelope = submitter.statement(submission)
    statement = verify(envelope, submitter.keys()).statement
    shown = requests.get(
        demo.url + "/api/v1/submissions/{}".format(submission),
        headers={"Authorization": "Bearer " + str(submitter.token)},
        timeout=60,
    ).json()
    assert statement["verdicts"]["count"] == len(shown["items"])
    assert statement["verdicts"]["sha256"] == verdicts_sha256(shown["items"])
    assert statement["scores"] == shown["scores"]
