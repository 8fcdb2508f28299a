"""Checking a hub's signed statement offline: the Python side of ``enact-hub verify``.

Every scored submission on an enact-hub server has a statement
(``GET /api/v1/submissions/{id}/statement``): a DSSE envelope whose payload (JSON) says what
the hub computed for which answers, signed with the hub's Ed25519 key over DSSE's
pre-authentication encoding. The hub lists its public keys at ``GET /api/v1/keys``::

    from enact_hub import Hub
    from enact_hub.verify import verify

    hub = Hub("https://hub.example.org", token="ehub_...")
    envelope = hub.statement(42)
    checked = verify(envelope, hub.keys(), answers="answers.jsonl")
    print(checked.statement["dataset"]["name"], checked.statement["scores"]["report"]["overall"])

The signature is checked with the ``cryptography`` package's Ed25519; nothing here is
hand-written cryptography. Every refusal raises :class:`StatementError` with what was wrong and
where (the same reasons ``enact-hub verify`` gives).
"""

from __future__ import annotations

import base64
import binascii
import hashlib
import json
import os
import struct
from dataclasses import dataclass
from typing import Any, Dict, Iterable, Mapping, Optional, Tuple, Union

from cryptography.exceptions import InvalidSignature
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey

__all__ = [
    "PAYLOAD_TYPE",
    "StatementError",
    "Verified",
    "answers_sha256",
    "pae",
    "verdicts_sha256",
    "verify",
]

#: The DSSE payload type of an enact-hub statement.
PAYLOAD_TYPE = "application/vnd.enact-hub.statement+json"

#: The payload format this module reads (its ``statement`` field).
STATEMENT_FORMAT = "enact-hub.statement/1"


class StatementError(ValueError):
    """A statement that does not check out: a malformed envelope or keys list (naming the
    field), an unknown key id, a bad signature, or answers that are not the ones it was made
    for."""


@dataclass
class Verified:
    """A statement whose signature verified.

    Attributes:
        statement: the payload: ``hub``, ``submission``, ``dataset`` (with ``items_sha256``),
            ``answers_sha256``, ``verdicts`` (``count``, ``sha256``), ``metric_version``,
            ``policy``, ``provenance``, ``scores`` and ``made_at``.
        keyid: the id of the key that signed it.
        key: that key as the keys list gave it (``retired_at`` set if it was rotated away).
        answers_checked: whether answers were given and matched ``answers_sha256``.
    """

    statement: Dict[str, Any]
    keyid: str
    key: Dict[str, Any]
    answers_checked: bool


def pae(payload_type: str, body: bytes) -> bytes:
    """DSSE's pre-authentication encoding: ``DSSEv1 SP LEN(type) SP type SP LEN(body) SP body``,
    lengths in ASCII decimal bytes."""
    kind = payload_type.encode("utf-8")
    return b"DSSEv1 %d %s %d %s" % (len(kind), kind, len(body), body)


def answers_sha256(answers: bytes) -> str:
    """The statement's ``answers_sha256`` of answers exactly as uploaded."""
    return hashlib.sha256(answers).hexdigest()


def verdicts_sha256(items: Iterable[Mapping[str, Any]]) -> str:
    """The statement's ``verdicts.sha256``, computed again from the per-item verdicts the
    submission API lists (``Hub.submission(id).items``' JSON, when a dataset's answers are
    public): one line per item sorted by item id,
    ``id TAB outcome TAB exact TAB semantic TAB task TAB pairwise LF``, flags ``1``/``0``,
    ``pairwise`` the value's IEEE 754 bits as 16 hex digits (big-endian) or ``-``."""
    lines = []
    for item in items:
        pairwise = item.get("pairwise_accuracy")
        lines.append(
            "\t".join(
                [
                    str(item["id"]),
                    str(item["outcome"]),
                    "1" if item.get("exact_match") else "0",
                    "1" if item.get("semantic_match") else "0",
                    "1" if item.get("task_accuracy") else "0",
                    "-" if pairwise is None else struct.pack(">d", float(pairwise)).hex(),
                ]
            )
            + "\n"
        )
    lines.sort(key=lambda line: line.split("\t", 1)[0].encode("utf-8"))
    return hashlib.sha256("".join(lines).encode("utf-8")).hexdigest()


def _field(obj: Mapping[str, Any], path: str, name: str) -> str:
    if name not in obj:
        raise StatementError("malformed {}: `{}{}` is missing".format(_what(path), path, name))
    value = obj[name]
    if not isinstance(value, str):
        raise StatementError(
            "malformed {}: `{}{}` must be a string, not {}".format(_what(path), path, name, type(value).__name__)
        )
    return value


def _what(path: str) -> str:
    return "keys list" if path.startswith("keys[") else "envelope"


def _unbase64(text: str, field: str, what: str) -> bytes:
    """Standard base64 with padding, in its one canonical spelling (as the hub reads it)."""
    try:
        raw = base64.b64decode(text, validate=True)
    except (binascii.Error, ValueError) as error:
        raise StatementError(
            "malformed {}: `{}` is not base64 (standard alphabet, padded): {}".format(what, field, error)
        ) from None
    if base64.b64encode(raw).decode("ascii") != text:
        raise StatementError("malformed {}: `{}` is not base64 in its canonical form".format(what, field))
    return raw


def _envelope(envelope: Union[Mapping[str, Any], str, bytes]) -> Mapping[str, Any]:
    if isinstance(envelope, (str, bytes)):
        try:
            envelope = json.loads(envelope)
        except ValueError as error:
            raise StatementError("malformed envelope: not JSON: {}".format(error)) from None
    if not isinstance(envelope, Mapping):
        raise StatementError("malformed envelope: the envelope must be a JSON object")
    return envelope


def _trusted_keys(keys: Mapping[str, Any]) -> Dict[str, Tuple[Ed25519PublicKey, Dict[str, Any]]]:
    """The keys list's keys by id, each checked: algorithm, 32 bytes, its own id."""
    if not isinstance(keys, Mapping):
        raise StatementError("malformed keys list: the keys list must be a JSON object")
    listed = keys.get("keys")
    if listed is None:
        raise StatementError("malformed keys list: `keys` is missing")
    if not isinstance(listed, list):
        raise StatementError("malformed keys list: `keys` must be an array")
    trusted: Dict[str, Tuple[Ed25519PublicKey, Dict[str, Any]]] = {}
    for i, key in enumerate(listed):
        at = "keys[{}]".format(i)
        if not isinstance(key, Mapping):
            raise StatementError("malformed keys list: `{}` must be an object".format(at))
        keyid = _field(key, at + ".", "keyid")
        algorithm = _field(key, at + ".", "algorithm")
        if algorithm != "ed25519":
            raise StatementError(
                "malformed keys list: `{}.algorithm` is {!r}; only 'ed25519' is known".format(at, algorithm)
            )
        raw = _unbase64(_field(key, at + ".", "public_key"), at + ".public_key", "keys list")
        if len(raw) != 32:
            raise StatementError(
                "malformed keys list: `{}.public_key` holds {} bytes; an Ed25519 public key is 32".format(at, len(raw))
            )
        own = hashlib.sha256(raw).hexdigest()[:16]
        if keyid != own:
            raise StatementError(
                "malformed keys list: `{}.keyid` is {!r} but its public key's id is {!r}".format(at, keyid, own)
            )
        trusted[keyid] = (Ed25519PublicKey.from_public_bytes(raw), dict(key))
    return trusted


def _answers_bytes(answers: Union[bytes, str, "os.PathLike[str]"]) -> Tuple[bytes, str]:
    if isinstance(answers, (bytes, bytearray, memoryview)):
        return bytes(answers), "the answers given"
    path = os.fspath(answers)
    with open(path, "rb") as f:
        return f.read(), path


def verify(
    envelope: Union[Mapping[str, Any], str, bytes],
    keys: Optional[Mapping[str, Any]] = None,
    *,
    hub: Any = None,
    answers: Union[bytes, str, "os.PathLike[str]", None] = None,
) -> Verified:
    """Checks a statement's signature against a hub's public keys, and optionally that
    ``answers`` are the ones it was made for.

    Args:
        envelope: the DSSE envelope as served (a dict, or its JSON text).
        keys: the keys list in the ``GET /api/v1/keys`` format (a dict), e.g. saved when the
            statement was fetched; or give ``hub`` instead.
        hub: a :class:`enact_hub.Hub` (or a hub's base URL) to fetch the keys from.
        answers: the answers' bytes, or the path of the answers file; checked against the
            statement's ``answers_sha256``.

    Returns:
        :class:`Verified`, holding the statement's payload.

    Raises:
        StatementError: a malformed envelope or keys list, an unknown key id, a bad signature
            (a changed payload or signature), or answers that differ.
    """
    if keys is None:
        if hub is None:
            raise TypeError("verify needs keys (the GET /api/v1/keys list) or hub")
        if isinstance(hub, str):
            from .client import Hub

            hub = Hub(hub)
        keys = hub.keys()
    trusted = _trusted_keys(keys)
    envelope = _envelope(envelope)
    payload_type = _field(envelope, "", "payloadType")
    payload = _unbase64(_field(envelope, "", "payload"), "payload", "envelope")
    if "signatures" not in envelope:
        raise StatementError("malformed envelope: `signatures` is missing")
    signatures = envelope["signatures"]
    if not isinstance(signatures, list):
        raise StatementError("malformed envelope: `signatures` must be an array")
    if not signatures:
        raise StatementError("malformed envelope: `signatures` is empty")
    signed = pae(payload_type, payload)
    good: Optional[str] = None
    for i, signature in enumerate(signatures):
        path = "signatures[{}].".format(i)
        if not isinstance(signature, Mapping):
            raise StatementError("malformed envelope: `signatures[{}]` must be an object".format(i))
        keyid = _field(signature, path, "keyid")
        sig = _field(signature, path, "sig")
        if keyid not in trusted:
            continue
        raw = _unbase64(sig, path + "sig", "envelope")
        if len(raw) != 64:
            raise StatementError(
                "malformed envelope: `{}sig` holds {} bytes; an Ed25519 signature is 64".format(path, len(raw))
            )
        try:
            trusted[keyid][0].verify(raw, signed)
        except InvalidSignature:
            raise StatementError(
                "bad signature: signatures[{}] by key {} does not verify over the payload (the payload "
                "or the signature was changed, or it was signed by another key)".format(i, keyid)
            ) from None
        good = good or keyid
    if good is None:
        named = ", ".join(str(s.get("keyid")) for s in signatures if isinstance(s, Mapping))
        raise StatementError(
            "unknown key id {}: the keys given list {}".format(named, ", ".join(trusted) or "no key")
        )
    if payload_type != PAYLOAD_TYPE:
        raise StatementError(
            "malformed payload: `payloadType` is {!r}, not {!r}: not an enact-hub statement".format(
                payload_type, PAYLOAD_TYPE
            )
        )
    try:
        statement = json.loads(payload)
    except ValueError as error:
        raise StatementError("malformed payload: not JSON: {}".format(error)) from None
    if not isinstance(statement, dict) or statement.get("statement") != STATEMENT_FORMAT:
        raise StatementError(
            "malformed payload: `statement` is not {!r}".format(STATEMENT_FORMAT)
        )
    checked = False
    if answers is not None:
        data, name = _answers_bytes(answers)
        actual = answers_sha256(data)
        expected = statement.get("answers_sha256")
        if actual != expected:
            raise StatementError(
                "answers differ: {} has SHA-256 {}, the statement names {}".format(name, actual, expected)
            )
        checked = True
    return Verified(statement=statement, keyid=good, key=trusted[good][1], answers_checked=checked)
