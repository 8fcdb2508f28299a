"""What the client returns: the hub's JSON read into typed records.

Each record keeps the JSON it was read from in ``raw``, so a field this version of the package
does not name yet is still at hand.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional

__all__ = [
    "Action",
    "Coverage",
    "Dataset",
    "Download",
    "Image",
    "Interval",
    "Item",
    "Performance",
    "RunResult",
    "Scores",
    "Submission",
]


@dataclass
class Dataset:
    """A dataset and its item counts."""

    name: str
    created_at: str
    items: int
    forward: int
    inverse: int
    tasks: int
    #: ``direction -> step length (L) -> number of items``.
    by_step_length: Dict[str, Dict[int, int]]
    raw: Dict[str, Any] = field(repr=False)

    @classmethod
    def from_json(cls, body: Dict[str, Any]) -> "Dataset":
        by_step = {
            direction: {int(length): int(count) for length, count in counts.items()}
            for direction, counts in (body.get("by_step_length") or {}).items()
        }
        return cls(
            name=body["name"],
            created_at=body["created_at"],
            items=body["items"],
            forward=body["forward"],
            inverse=body["inverse"],
            tasks=body["tasks"],
            by_step_length=by_step,
            raw=body,
        )


@dataclass
class Action:
    """One action text of an item; ``label`` is the number an answer orders."""

    label: int
    text: str


@dataclass
class Image:
    """One image of an item, in the order the model is shown them.

    ``data`` is the PNG's bytes, a ``PIL.Image.Image`` (``frames="pil"``), or None when frames
    were not fetched (``frames="none"``).
    """

    position: int
    label: str
    url: str
    data: Any = field(default=None, repr=False)


@dataclass
class Item:
    """An item as a model sees it: never its ground truth."""

    id: str
    dataset: str
    type: str
    #: ``"forward"`` (order the future images) or ``"inverse"`` (order the action texts).
    direction: str
    #: L, the number of images (3 to 10).
    step_length: int
    task_name: str
    question: str
    actions: List[Action]
    images: List[Image]
    raw: Dict[str, Any] = field(repr=False)

    @classmethod
    def from_json(cls, body: Dict[str, Any]) -> "Item":
        return cls(
            id=body["id"],
            dataset=body["dataset"],
            type=body["type"],
            direction=body["direction"],
            step_length=body["step_length"],
            task_name=body["task_name"],
            question=body["question"],
            actions=[Action(label=a["label"], text=a["text"]) for a in body["actions"]],
            images=[Image(position=i["position"], label=i["label"], url=i["url"]) for i in body["images"]],
            raw=body,
        )


@dataclass
class Performance:
    """Task and pairwise accuracy (fractions in [0, 1]) over a group of items, with the same by
    step length L."""

    count: int
    task_accuracy: float
    #: None when no item of the group has one (exact-only scoring).
    pairwise_accuracy: Optional[float]
    pairwise_count: int
    per_step: Dict[int, "Performance"]

    @classmethod
    def from_json(cls, body: Optional[Dict[str, Any]]) -> Optional["Performance"]:
        if body is None:
            return None
        per_step = {}
        for length, step in (body.get("per_step") or {}).items():
            per_step[int(length)] = cls(
                count=step["count"],
                task_accuracy=step["task_accuracy"],
                pairwise_accuracy=step.get("pairwise_accuracy"),
                pairwise_count=step["pairwise_count"],
                per_step={},
            )
        return cls(
            count=body["count"],
            task_accuracy=body["task_accuracy"],
            pairwise_accuracy=body.get("pairwise_accuracy"),
            pairwise_count=body["pairwise_count"],
            per_step=per_step,
        )


@dataclass
class Coverage:
    """How much of the dataset a submission answered."""

    dataset_items: int
    answered: int
    missing: int
    unparseable: int
    #: answered / dataset_items.
    coverage: float
    #: unparseable / answered.
    parse_failure_rate: float


@dataclass
class Interval:
    """A bootstrap confidence interval."""

    low: float
    high: float


@dataclass
class Scores:
    """A submission's scores under the hub's strict policy: every dataset item counts."""

    overall: Optional[Performance]
    forward: Optional[Performance]
    inverse: Optional[Performance]
    coverage: Coverage
    #: The confidence level of the intervals (e.g. 0.95).
    confidence_level: float
    task_accuracy_interval: Optional[Interval]
    pairwise_accuracy_interval: Optional[Interval]
    raw: Dict[str, Any] = field(repr=False)

    @classmethod
    def from_json(cls, body: Dict[str, Any]) -> "Scores":
        report = body.get("report") or {}
        coverage = body["coverage"]
        confidence = body.get("confidence") or {}

        def interval(value: Optional[Dict[str, Any]]) -> Optional[Interval]:
            return None if value is None else Interval(low=value["low"], high=value["high"])

        return cls(
            overall=Performance.from_json(report.get("overall")),
            forward=Performance.from_json(report.get("forward_world_modeling")),
            inverse=Performance.from_json(report.get("inverse_world_modeling")),
            coverage=Coverage(
                dataset_items=coverage["dataset_items"],
                answered=coverage["answered"],
                missing=coverage["missing"],
                unparseable=coverage["unparseable"],
                coverage=coverage["coverage"],
                parse_failure_rate=coverage["parse_failure_rate"],
            ),
            confidence_level=confidence.get("level", 0.0),
            task_accuracy_interval=interval(confidence.get("task_accuracy")),
            pairwise_accuracy_interval=interval(confidence.get("pairwise_accuracy")),
            raw=body,
        )


@dataclass
class Submission:
    """A stored submission and its scores."""

    id: int
    dataset: str
    account: str
    model: str
    status: str
    visibility: str
    created_at: str
    scores: Scores
    #: The enact-hub build that computed the scores (``version+commit``; empty when older).
    scored_by: str
    #: Per-item verdicts, when the dataset's answers are public and you may read them.
    items: Optional[List[Dict[str, Any]]]
    raw: Dict[str, Any] = field(repr=False)

    @classmethod
    def from_json(cls, body: Dict[str, Any]) -> "Submission":
        return cls(
            id=body["id"],
            dataset=body["dataset"],
            account=body["account"],
            model=body["model"],
            status=body["status"],
            visibility=body["visibility"],
            created_at=body["created_at"],
            scores=Scores.from_json(body["scores"]),
            scored_by=body.get("scored_by", ""),
            items=body.get("items"),
            raw=body,
        )


@dataclass
class Download:
    """A dataset written to a folder in ENACT's release layout."""

    path: str
    files: int
    bytes: int
    #: Whether the records carry ground truth (the dataset's answers are public).
    ground_truth: bool


@dataclass
class RunResult:
    """What ``enact-hub run --json`` reported, and its progress log (standard error)."""

    report: Dict[str, Any]
    log: str = field(repr=False)
