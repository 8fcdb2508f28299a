"""A typed client for an enact-hub server's JSON API (``/api/v1``)."""

from __future__ import annotations

import io
import json
import os
import posixpath
import random
import subprocess
import tarfile
import time
import uuid
from typing import (
    Any,
    Dict,
    Iterable,
    Iterator,
    List,
    Mapping,
    Optional,
    Sequence,
    Tuple,
    Union,
)

import requests

from . import __version__
from ._binary import find_enact_hub_bin
from .errors import HubError
from .types import (
    Dataset,
    Download,
    Item,
    RunResult,
    Submission,
)

__all__ = ["Hub", "Answer"]

#: An answer as a model gave it: its raw text (the hub parses it as ENACT does) or a list of
#: action labels in order.
Answer = Union[str, Sequence[int]]

_RETRIED_STATUSES = {429, 500, 502, 503, 504}


class Hub:
    """One enact-hub server, reached over its JSON API.

    Args:
        url: the server's base URL, e.g. ``http://127.0.0.1:8080``.
        token: an API token (``ehub_...``) from the hub's admin; needed to submit and to read
            submissions, not to read datasets.
        timeout: seconds each request may take (a submission gets at least 300).
        max_retries: how often a read (and a submission, under one idempotency key) is tried
            again after a connection error, a 429 or a 5xx, with exponential backoff that honours
            ``Retry-After``.
        session: a ``requests.Session`` to send through (one is made otherwise).

    Every failure raises :class:`HubError` with the hub's own message.
    """

    def __init__(
        self,
        url: str,
        token: Optional[str] = None,
        *,
        timeout: float = 60.0,
        max_retries: int = 3,
        retry_delay: float = 1.0,
        session: Optional[requests.Session] = None,
    ) -> None:
        self.url = url.rstrip("/")
        self.token = token
        self.timeout = timeout
        self.max_retries = max_retries
        self.retry_delay = retry_delay
        self.session = session or requests.Session()
        self.session.headers["User-Agent"] = "enact-hub-python/{}".format(__version__)

    # -- reading datasets ------------------------------------------------------------------

    def version(self) -> Dict[str, Any]:
        """The server's version, git commit and database schema (``GET /api/v1/version``)."""
        return self._get_json("/api/v1/version", "reading the hub's version")

    def datasets(self) -> List[Dataset]:
        """Every dataset on the hub with its item counts."""
        body = self._get_json("/api/v1/datasets", "listing datasets")
        return [Dataset.from_json(d) for d in body["datasets"]]

    def dataset(self, name: str) -> Dataset:
        """One dataset by name."""
        return Dataset.from_json(
            self._get_json("/api/v1/datasets/{}".format(_segment(name)), "reading dataset '{}'".format(name))
        )

    def items(
        self,
        dataset: str,
        *,
        direction: Optional[str] = None,
        step_length: Optional[int] = None,
        task: Optional[str] = None,
        limit: Optional[int] = None,
        frames: str = "bytes",
        page_size: int = 500,
    ) -> Iterator[Item]:
        """The items of ``dataset`` in import order, one request per page and per item.

        Args:
            direction: ``"forward"`` or ``"inverse"`` only.
            step_length: only items of L images (3 to 10).
            task: only items of this ENACT task.
            limit: stop after this many items.
            frames: ``"bytes"`` (each image's PNG in ``Image.data``), ``"pil"`` (a
                ``PIL.Image.Image``; needs the ``pil`` extra: ``pip install enact-hub[pil]``)
                or ``"none"`` (URLs only, nothing downloaded).
        """
        if frames not in ("bytes", "pil", "none"):
            raise ValueError("frames must be 'bytes', 'pil' or 'none', not {!r}".format(frames))
        if frames == "pil":
            _pil()  # fail before the first request when Pillow is missing
        params: Dict[str, Any] = {"per_page": page_size}
        if direction is not None:
            params["direction"] = direction
        if step_length is not None:
            params["step_length"] = step_length
        if task is not None:
            params["task"] = task
        path: Optional[str] = "/api/v1/datasets/{}/items".format(_segment(dataset))
        count = 0
        while path is not None:
            page = self._get_json(path, "listing items of dataset '{}'".format(dataset), params=params)
            params = {}  # `next` carries the query
            for entry in page["items"]:
                if limit is not None and count >= limit:
                    return
                body = self._get_json(entry["url"], "reading item '{}'".format(entry["id"]))
                item = Item.from_json(body)
                if frames != "none":
                    for image in item.images:
                        png = self._get("GET", image.url, "reading frame {}".format(image.url)).content
                        image.data = _pil().open(io.BytesIO(png)) if frames == "pil" else png
                count += 1
                yield item
            path = page.get("next")

    def download(self, dataset: str, directory: Union[str, "os.PathLike[str]"]) -> Download:
        """Writes ``dataset`` into ``directory`` in ENACT's release layout
        (``QA/enact_ordering.jsonl`` and ``QA/images/...``), streamed from the hub's archive.

        The folder reads back with ``enact-hub import DIRECTORY`` when the dataset's answers are
        public; otherwise ground truth is left out of every record (``Download.ground_truth``
        is False) and the importer refuses it. Only regular files and folders inside
        ``directory`` are written: an entry naming any other place raises :class:`HubError`.
        """
        target = os.path.abspath(os.fspath(directory))
        os.makedirs(target, exist_ok=True)
        what = "downloading dataset '{}'".format(dataset)
        response = self._get("GET", "/api/v1/datasets/{}/archive".format(_segment(dataset)), what, stream=True)
        files = 0
        size = 0
        try:
            with tarfile.open(fileobj=response.raw, mode="r|") as archive:
                for member in archive:
                    path = _inside(target, member.name, what)
                    if member.isdir():
                        os.makedirs(path, exist_ok=True)
                    elif member.isfile():
                        os.makedirs(os.path.dirname(path), exist_ok=True)
                        source = archive.extractfile(member)
                        if source is None:
                            raise HubError("{}: entry {!r} has no data".format(what, member.name))
                        with open(path, "wb") as out:
                            while True:
                                chunk = source.read(1 << 20)
                                if not chunk:
                                    break
                                out.write(chunk)
                                size += len(chunk)
                        files += 1
                    else:
                        raise HubError("{}: entry {!r} is not a file or a folder".format(what, member.name))
        except (tarfile.TarError, requests.RequestException) as error:
            raise HubError("{}: the archive could not be read: {}".format(what, error)) from error
        finally:
            response.close()
        truth = response.headers.get("X-Enact-Ground-Truth", "") == "included"
        return Download(path=target, files=files, bytes=size, ground_truth=truth)

    # -- submissions -----------------------------------------------------------------------

    def submit(
        self,
        dataset: str,
        model: str,
        answers: Union[Mapping[str, Answer], Iterable[Tuple[str, Answer]]],
        *,
        idempotency_key: Optional[str] = None,
        **metadata: str,
    ) -> Submission:
        """Submits ``answers`` (item id -> answer) as ``model`` and returns the scores.

        Items without an answer count as unanswered (they score 0). ``metadata`` may hold
        ``description``, ``url``, ``prompt_version`` and ``notes``. The submission is sent
        with an idempotency key (a fresh one unless given), so retrying after a lost
        connection or a 5xx never stores it twice.
        """
        unknown = set(metadata) - {"description", "url", "prompt_version", "notes"}
        if unknown:
            raise TypeError("unknown submission metadata: {}".format(", ".join(sorted(unknown))))
        pairs = answers.items() if isinstance(answers, Mapping) else answers
        lines = []
        for item_id, answer in pairs:
            value = answer if isinstance(answer, str) else list(answer)
            lines.append(json.dumps({"id": item_id, "answer": value}, ensure_ascii=False))
        body = ("\n".join(lines) + "\n").encode("utf-8") if lines else b""
        params = dict(metadata, model=model)
        key = idempotency_key or uuid.uuid4().hex
        response = self._get(
            "POST",
            "/api/v1/datasets/{}/submissions".format(_segment(dataset)),
            "posting the submission",
            params=params,
            data=body,
            headers={"Content-Type": "application/x-ndjson", "Idempotency-Key": key},
            timeout=max(self.timeout, 300.0),
            auth=True,
        )
        return Submission.from_json(_json(response, "posting the submission"))

    def submission(self, submission: int) -> Submission:
        """A stored submission (your own, or any with an admin token)."""
        return Submission.from_json(
            self._get_json("/api/v1/submissions/{}".format(int(submission)), "reading submission {}".format(submission), auth=True)
        )

    def statement(self, submission: int) -> Dict[str, Any]:
        """The submission's signed statement: a DSSE envelope (``payloadType``, ``payload``,
        ``signatures``) to check with :func:`enact_hub.verify.verify` against :meth:`keys`."""
        return self._get_json(
            "/api/v1/submissions/{}/statement".format(int(submission)),
            "reading the statement of submission {}".format(submission),
            auth=True,
        )

    def keys(self) -> Dict[str, Any]:
        """The hub's public signing keys (``{"keys": [{"keyid", "algorithm", "public_key",
        "created_at", "retired_at"?}]}``), old ones included."""
        return self._get_json("/api/v1/keys", "reading the hub's signing keys")

    def leaderboard(self, dataset: str, **filters: Any) -> Dict[str, Any]:
        """A dataset's leaderboard as the hub serves it (rows ranked, with ``next``/``prev``).

        ``filters`` are the route's query parameters: ``sort`` (e.g. ``"overall_pa"``),
        ``page``, ``per_page``, ``all`` (True: every published submission), ``model``,
        ``account``.
        """
        params = {k: _query_value(v) for k, v in filters.items() if v is not None}
        return self._get_json(
            "/api/v1/datasets/{}/leaderboard".format(_segment(dataset)),
            "reading the leaderboard of '{}'".format(dataset),
            params=params,
        )

    def errors(self, submission: int) -> Dict[str, Any]:
        """The paper's error analysis of one submission (structural and semantic error
        classes, handedness, accepted-but-incomplete answers)."""
        return self._get_json(
            "/api/v1/submissions/{}/errors".format(int(submission)),
            "reading the error analysis of submission {}".format(submission),
            auth=True,
        )

    # -- studies ---------------------------------------------------------------------------

    def study(self, study: str) -> Dict[str, Any]:
        """An ablation study: its baseline, variants and their alignments."""
        return self._get_json("/api/v1/studies/{}".format(_segment(study)), "reading study '{}'".format(study))

    def study_report(self, study: str, model: str, **options: Any) -> Dict[str, Any]:
        """A study report for ``model``: Δ and p per variant and direction (``options``:
        ``by_step_length=True``, ``account=...``)."""
        params = {k: _query_value(v) for k, v in options.items() if v is not None}
        params["model"] = model
        return self._get_json(
            "/api/v1/studies/{}/report".format(_segment(study)),
            "reading the report of study '{}'".format(study),
            params=params,
        )

    # -- model runs ------------------------------------------------------------------------

    def run(
        self,
        dataset: str,
        *,
        endpoint: str,
        model: str,
        api_key_env: Optional[str] = None,
        concurrency: Optional[int] = None,
        max_retries: Optional[int] = None,
        timeout: Optional[float] = None,
        temperature: Optional[float] = None,
        max_tokens: Optional[int] = None,
        limit: Optional[int] = None,
        submit_as: Optional[str] = None,
        submit: bool = True,
        price_input: Optional[float] = None,
        price_output: Optional[float] = None,
        cache: Optional[str] = None,
        extra_args: Sequence[str] = (),
        binary: Optional[str] = None,
    ) -> RunResult:
        """Asks a model every item of ``dataset`` through the ``enact-hub run`` command (the
        binary's engine: resumable, rate-limit aware, costed) against this hub, and returns
        what it reports (``--json``).

        ``endpoint`` is an OpenAI-compatible chat-completions base URL; its key is read by the
        binary from the environment variable ``api_key_env``. Other arguments map to the
        command's flags of the same name; ``extra_args`` are passed as they are.

        The command runs in its remote-hub mode (``--hub``): items and frames are read from
        this hub, every reply is kept in the cache file ``cache`` (default: named after the
        run, in the working directory) as it arrives, and the answers are submitted with this
        client's token, which reaches the command through its environment (never its
        arguments). Calling ``run`` again with the same arguments goes on where an interrupted
        run stopped and never asks an answered item again. On the hub itself,
        ``POST /api/v1/admin/runs`` starts the same engine.

        Raises:
            HubError: when the command fails; its message is the command's error output.
        """
        if not self.token:
            raise HubError("run: a token is needed to submit (Hub(url, token=...))")
        args = [
            binary or find_enact_hub_bin(),
            "run",
            dataset,
            "--hub",
            self.url,
            "--endpoint",
            endpoint,
            "--model",
            model,
            "--json",
        ]
        flags = [
            ("--api-key-env", api_key_env),
            ("--concurrency", concurrency),
            ("--max-retries", max_retries),
            ("--timeout", timeout),
            ("--temperature", temperature),
            ("--max-tokens", max_tokens),
            ("--limit", limit),
            ("--submit-as", submit_as),
            ("--price-input", price_input),
            ("--price-output", price_output),
            ("--cache", cache),
        ]
        for flag, value in flags:
            if value is not None:
                args += [flag, str(value)]
        if not submit:
            args.append("--no-submit")
        args += list(extra_args)
        # The token goes through the environment: arguments are visible to every user's `ps`.
        env = dict(os.environ, ENACT_HUB_TOKEN=self.token)
        finished = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        if finished.returncode != 0:
            message = finished.stderr.strip() or "exit status {}".format(finished.returncode)
            raise HubError("enact-hub run {}: {}".format(dataset, message))
        try:
            report = json.loads(finished.stdout)
        except ValueError as error:
            raise HubError("enact-hub run {}: its --json output is not JSON: {}".format(dataset, error)) from error
        return RunResult(report=report, log=finished.stderr)

    # -- HTTP ------------------------------------------------------------------------------

    def _get_json(self, path: str, what: str, *, params: Optional[Mapping[str, Any]] = None, auth: bool = False) -> Any:
        return _json(self._get("GET", path, what, params=params, auth=auth), what)

    def _get(
        self,
        method: str,
        path: str,
        what: str,
        *,
        auth: bool = False,
        timeout: Optional[float] = None,
        **kwargs: Any,
    ) -> requests.Response:
        """Sends a request, retrying connection errors, 429 and 5xx; a 4xx raises at once."""
        url = path if path.startswith(("http://", "https://")) else self.url + path
        headers = dict(kwargs.pop("headers", None) or {})
        if auth:
            if not self.token:
                raise HubError("{}: this needs a token (Hub(url, token=...))".format(what))
            headers["Authorization"] = "Bearer " + self.token
        for attempt in range(self.max_retries + 1):
            response: Optional[requests.Response] = None
            try:
                response = self.session.request(
                    method, url, headers=headers, timeout=timeout or self.timeout, **kwargs
                )
            except requests.RequestException as error:
                failure = HubError("{} failed: {}".format(what, error))
            else:
                if response.status_code < 400:
                    return response
                failure = HubError.from_response(what, response)
                if response.status_code not in _RETRIED_STATUSES:
                    raise failure
                if response.status_code == 429 and response.headers.get("Retry-After") is None:
                    # A quota that waiting will not restore.
                    raise failure
            if attempt == self.max_retries:
                raise failure
            time.sleep(retry_delay(response, attempt, self.retry_delay))
        raise HubError(what + ": no attempt was made")


def _json(response: requests.Response, what: str) -> Any:
    try:
        return response.json()
    except ValueError as error:
        raise HubError("{}: the answer is not JSON: {}".format(what, response.text[:300])) from error


def retry_delay(response: Optional[requests.Response], attempt: int, base: float) -> float:
    """Seconds before the next attempt: ``Retry-After`` when given, else exponential with
    jitter."""
    if response is not None:
        header = response.headers.get("Retry-After")
        if header is not None:
            try:
                return min(float(header), 300.0)
            except ValueError:
                pass
    return base * (2**attempt) * (0.5 + random.random() / 2)


def _segment(name: str) -> str:
    """``name`` as one URL path segment."""
    return requests.utils.quote(name, safe="")


def _query_value(value: Any) -> Any:
    return ("true" if value else "false") if isinstance(value, bool) else value


def _inside(root: str, name: str, what: str) -> str:
    """The path under ``root`` an archive entry names; refuses one that leaves it."""
    clean = posixpath.normpath(name)
    if posixpath.isabs(clean) or clean == ".." or clean.startswith("../") or "\\" in clean:
        raise HubError("{}: the archive names a path outside the folder: {!r}".format(what, name))
    return os.path.join(root, *clean.split("/"))


def _pil() -> Any:
    try:
        from PIL import Image
    except ImportError as error:
        raise ImportError("frames='pil' needs Pillow: pip install 'enact-hub[pil]'") from error
    return Image

