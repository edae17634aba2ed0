"""Benchmark records: one per instance and method, typed, and their JSONL file.

A :class:`Record` is written as one JSON object per line, its keys in this order:
``instance``, ``model``, ``index``, ``vertex``, ``seed``, then the source's facts about
the instance (:attr:`Record.info`, e.g. ``probe_time_s``; a failed instance's ``error``),
then ``instance_time_s``, ``method``, ``recognized``, ``success``, ``time_s``,
``errors_mm``, ``times_s`` and, when known, ``candidates``, ``k1``, ``k2``, ``error``
(the recognition failed), ``localization_error_mm``, ``reference``, ``confidence`` and
``answer_error_mm``, ``touches``, ``truth_fit`` and ``settings``.
Reading a line back (:meth:`Record.from_json`) takes the keys between ``seed`` and
``instance_time_s`` as the source's facts.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from recognition.errors import InvalidRecords

__all__ = [
    "RIGHT_WITHIN_MM",
    "TIMING_FIELDS",
    "Record",
    "ReferenceRecord",
    "comparable",
    "read_results",
]

#: Record fields that hold wall times (they differ between runs of the same instance).
TIMING_FIELDS = ("time_s", "times_s", "instance_time_s", "probe_time_s")


@dataclass(frozen=True)
class ReferenceRecord:
    """The recognition of an instance's reference curves (no measurement error).

    Attributes
    ----------
    recognized : str or None
        The model the reference curves were recognised as.
    success : bool
        ``recognized`` is the true model.
    errors_mm : dict of str to float or None
        Registration error on each model, mm (None: rejected at table lookup).
    localization_error_mm : float or None
        Distance of the true model's estimate of p from the true p, mm.
    error : str or None
        Why the reference curves could not be recognised.
    """

    recognized: str | None
    success: bool
    errors_mm: Mapping[str, float | None]
    localization_error_mm: float | None
    error: str | None = None

    def to_json(self) -> dict[str, Any]:
        """The JSON object of this reference recognition."""
        out: dict[str, Any] = {
            "recognized": self.recognized,
            "success": self.success,
            "errors_mm": dict(self.errors_mm),
            "localization_error_mm": self.localization_error_mm,
        }
        if self.error is not None:
            out["error"] = self.error
        return out

    @classmethod
    def from_json(cls, payload: Mapping[str, Any]) -> ReferenceRecord:
        """The reference recognition of a JSON object written by :meth:`to_json`."""
        return cls(
            recognized=payload["recognized"],
            success=payload["success"],
            errors_mm=dict(payload["errors_mm"]),
            localization_error_mm=payload["localization_error_mm"],
            error=payload.get("error"),
        )


#: An answer is right when it names the true model and puts p within this of the truth, mm.
RIGHT_WITHIN_MM = 1.0

_BEFORE_INFO = ("instance", "model", "index", "vertex", "seed")
#: Keys every record's JSON object has.
_REQUIRED = (
    *_BEFORE_INFO,
    "instance_time_s",
    "method",
    "recognized",
    "success",
    "time_s",
    "errors_mm",
    "times_s",
    "localization_error_mm",
)


@dataclass(frozen=True)
class Record:
    """The recognition of one benchmark instance with one method.

    Attributes
    ----------
    instance : str
        ``model/index``.
    model : str
        The true model.
    index : int
        Instance number of this model.
    vertex : int or None
        The model vertex the curves meet at (synthetic instances).
    seed : int
        The instance's seed.
    info : Mapping[str, Any]
        The source's JSON-ready facts about the instance (``*_mm``, ``*_s``; ``error``
        when it could not be made).
    instance_time_s : float, seconds
        Wall time of making the instance.
    method : str
        Registration mode (``fast``, ``thesis``, ``icp-baseline``, ``closed-form``).
    recognized : str or None
        The model the curves were recognised as.
    success : bool
        ``recognized`` is the true model.
    time_s : float, seconds
        Recognition time against all models, local geometry included.
    errors_mm : dict of str to float or None
        Registration error on each model, mm, ascending (None: rejected at lookup).
    times_s : dict of str to float, seconds
        Registration time per model.
    candidates : dict of str to int or None
        Candidate points per model (None when the curves were not recognised).
    k1, k2 : float or None, 1/m
        The data's principal curvatures at p.
    error : str or None
        Why the curves could not be recognised (e.g. two sampling planes coincide).
    localization_error_mm : float or None
        Distance of the true model's estimate of p from the true p, mm.
    reference : ReferenceRecord or None
        The recognition of the instance's reference curves, when it has them.
    confidence : float or None
        Fast mode: the belief's confidence that its best hypothesis is right
        (:attr:`recognition.Recognition.confidence`), after the curves.
    answer_error_mm : float or None
        Distance of the best hypothesis's p from the true p, mm (up to the model's
        symmetries), when it names the true model.
    touches : mapping or None
        Verification touches (``--touches N``): ``made`` (count), ``stop``,
        ``recognized``, ``success``, ``confidence``, ``answer_error_mm`` after them,
        ``recognition_times_s`` (planning and update of each touch), and, when the answer
        after them is wrong, ``truth_fit``.
    truth_fit : mapping or None
        When the answer after the curves is wrong and the true pose is known: how the
        truth fits the curves against the answer (``log_ratio``, ``error_mm``;
        :func:`~recognition.evaluation.diagnosis.truth_fit`).
    settings : str or None
        Hash of the source and registration settings (set by the runner).
    """

    instance: str
    model: str
    index: int
    vertex: int | None
    seed: int
    info: Mapping[str, Any]
    instance_time_s: float
    method: str
    recognized: str | None
    success: bool
    time_s: float
    errors_mm: Mapping[str, float | None] = field(default_factory=dict)
    times_s: Mapping[str, float] = field(default_factory=dict)
    candidates: Mapping[str, int] | None = None
    k1: float | None = None
    k2: float | None = None
    error: str | None = None
    localization_error_mm: float | None = None
    reference: ReferenceRecord | None = None
    settings: str | None = None
    confidence: float | None = None
    answer_error_mm: float | None = None
    touches: Mapping[str, Any] | None = None
    truth_fit: Mapping[str, Any] | None = None

    def answered_right(
        self, after_touches: bool = False, radius_mm: float = RIGHT_WITHIN_MM
    ) -> bool:
        """The belief's answer names the true model and puts p within ``radius_mm`` of
        the truth (after the verification touches, when made and asked for)."""
        if after_touches and self.touches is not None:
            error = self.touches.get("answer_error_mm")
            return bool(self.touches.get("success")) and error is not None and error <= radius_mm
        return self.answer_error_mm is not None and self.answer_error_mm <= radius_mm

    def to_json(self) -> dict[str, Any]:
        """The record's JSON object (keys in the order of the module docstring)."""
        out: dict[str, Any] = {
            "instance": self.instance,
            "model": self.model,
            "index": self.index,
            "vertex": self.vertex,
            "seed": self.seed,
            **self.info,
            "instance_time_s": self.instance_time_s,
            "method": self.method,
            "recognized": self.recognized,
            "success": self.success,
            "time_s": self.time_s,
            "errors_mm": dict(self.errors_mm),
            "times_s": dict(self.times_s),
        }
        if self.candidates is not None:
            out["candidates"] = dict(self.candidates)
        if self.k1 is not None:
            out["k1"] = self.k1
        if self.k2 is not None:
            out["k2"] = self.k2
        if self.error is not None:
            out["error"] = self.error
        out["localization_error_mm"] = self.localization_error_mm
        if self.reference is not None:
            out["reference"] = self.reference.to_json()
        if self.confidence is not None:
            out["confidence"] = self.confidence
            out["answer_error_mm"] = self.answer_error_mm
        if self.touches is not None:
            out["touches"] = dict(self.touches)
        if self.truth_fit is not None:
            out["truth_fit"] = dict(self.truth_fit)
        if self.settings is not None:
            out["settings"] = self.settings
        return out

    @classmethod
    def from_json(cls, payload: Mapping[str, Any]) -> Record:
        """The record of a JSON object written by :meth:`to_json`."""
        keys = list(payload)
        start = keys.index("seed") + 1
        end = keys.index("instance_time_s")
        reference = payload.get("reference")
        candidates = payload.get("candidates")
        return cls(
            **{k: payload[k] for k in _BEFORE_INFO},
            info={k: payload[k] for k in keys[start:end]},
            instance_time_s=payload["instance_time_s"],
            method=payload["method"],
            recognized=payload["recognized"],
            success=payload["success"],
            time_s=payload["time_s"],
            errors_mm=dict(payload["errors_mm"]),
            times_s=dict(payload["times_s"]),
            candidates=None if candidates is None else dict(candidates),
            k1=payload.get("k1"),
            k2=payload.get("k2"),
            error=payload["error"] if "error" in keys[end:] else None,
            localization_error_mm=payload["localization_error_mm"],
            reference=None if reference is None else ReferenceRecord.from_json(reference),
            settings=payload.get("settings"),
            confidence=payload.get("confidence"),
            answer_error_mm=payload.get("answer_error_mm"),
            touches=None if payload.get("touches") is None else dict(payload["touches"]),
            truth_fit=None if payload.get("truth_fit") is None else dict(payload["truth_fit"]),
        )

    def with_settings(self, settings: str) -> Record:
        """The record with its settings hash set."""
        return replace(self, settings=settings)

    def dumps(self) -> str:
        """The record as one JSON line (no newline)."""
        return json.dumps(self.to_json())

    @property
    def instance_error(self) -> str | None:
        """Why the instance could not be made or its curves recognised (None: no error)."""
        return self.error if self.error is not None else self.info.get("error")


def read_results(path: Path | str) -> list[Record]:
    """Records of a JSONL results file (none if it does not exist; a last line cut short
    by a killed run, without its newline, is ignored).

    Raises
    ------
    InvalidRecords
        A line is not a record (not JSON, not a JSON object, keys missing, values of the
        wrong type) or the file is not text; the message names the file and the line.
    """
    path = Path(path)
    if not path.exists():
        return []
    try:
        text = path.read_bytes().decode()
    except UnicodeDecodeError as exc:
        raise InvalidRecords(
            f"{path} is not a records file: not UTF-8 text (byte {exc.start}); expected "
            "one JSON benchmark record per line"
        ) from exc
    lines = text.split("\n")
    records: list[Record] = []
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            records.append(_parse_record(line))
        except InvalidRecords as exc:
            if number == len(lines):  # no newline after it: cut short by a killed run
                break
            raise InvalidRecords(
                f"{path}, line {number}: {exc}; expected one JSON benchmark record per line "
                "(as scripts/benchmark.py writes them)"
            ) from exc
    return records


def _parse_record(line: str) -> Record:
    """The record of one JSONL line.

    Raises
    ------
    InvalidRecords
        The line is not a record; the message says why.
    """
    try:
        payload = json.loads(line)
    except json.JSONDecodeError as exc:
        raise InvalidRecords(f"not JSON ({exc.msg})") from exc
    if not isinstance(payload, dict):
        raise InvalidRecords(f"a JSON {type(payload).__name__}, not an object")
    missing = [k for k in _REQUIRED if k not in payload]
    if missing:
        raise InvalidRecords(f"keys missing: {', '.join(missing)}")
    try:
        return Record.from_json(payload)
    except (TypeError, ValueError, AttributeError, KeyError) as exc:
        raise InvalidRecords(f"a value of the wrong type ({exc})") from exc


def comparable(record: Record) -> dict[str, Any]:
    """The record's JSON object without its wall times: equal for equal instances,
    settings and code."""
    return {k: v for k, v in record.to_json().items() if k not in TIMING_FIELDS}
