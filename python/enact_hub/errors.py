"""The one exception the client raises."""

from __future__ import annotations

from typing import Any, Dict, List, Optional

import requests

__all__ = ["HubError"]


class HubError(Exception):
    """A request the hub refused or that did not reach it.

    Attributes:
        status: the HTTP status, or None when no answer came (a connection error).
        message: the hub's own message (its JSON ``error``), or the start of the body.
        code: the hub's stable name for the reason (its JSON ``code``: ``"no_item"``,
            ``"limit_reached"``, ...), to branch on; None when no JSON error came.
        details: what a typed reason names (``{"dataset": ..., "item": ...}``); empty when
            there is none.
        problems: the hub's ``problems`` list (e.g. one per refused line of a submission:
            ``{"line": 3, "message": "..."}``); empty when there is none.
        body: the hub's whole JSON error, when it sent one.
    """

    def __init__(
        self,
        text: str,
        *,
        status: Optional[int] = None,
        message: Optional[str] = None,
        problems: Optional[List[Dict[str, Any]]] = None,
        body: Optional[Dict[str, Any]] = None,
    ) -> None:
        super().__init__(text)
        self.status = status
        self.message = message if message is not None else text
        self.problems = problems or []
        self.body = body
        code = body.get("code") if body is not None else None
        self.code: Optional[str] = code if isinstance(code, str) else None
        details = body.get("details") if body is not None else None
        self.details: Dict[str, Any] = details if isinstance(details, dict) else {}

    @classmethod
    def from_response(cls, what: str, response: requests.Response) -> "HubError":
        """The error for a refused request: ``what: HTTP 401: <the hub's message>``, with up to
        ten of its problems on the following lines."""
        body: Optional[Dict[str, Any]] = None
        try:
            parsed = response.json()
            if isinstance(parsed, dict) and "error" in parsed:
                body = parsed
        except ValueError:
            pass
        if body is not None:
            message = str(body["error"])
            problems = [p for p in body.get("problems") or [] if isinstance(p, dict)]
        else:
            message = response.text[:500]
            problems = []
        text = "{}: HTTP {}: {}".format(what, response.status_code, message)
        for problem in problems[:10]:
            text += "\n  line {}: {}".format(problem.get("line"), problem.get("message"))
        return cls(text, status=response.status_code, message=message, problems=problems, body=body)
