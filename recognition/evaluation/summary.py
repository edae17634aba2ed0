"""The summary of benchmark records per method: success rate, times, localisation error."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from recognition.evaluation.records import Record

__all__ = ["MethodSummary", "summarize", "summary_json"]


@dataclass(frozen=True)
class MethodSummary:
    """The records of one method, summarised.

    Attributes
    ----------
    method : str
    instances : int
        Records (instances) of the method.
    success_rate : float
        Fraction recognised as their true model.
    median_time_s, p90_time_s : float, seconds
        Recognition time: median and 90th percentile.
    median_localization_error_mm : float or None
        Median distance of the estimate of p from the true p (None: no estimate).
    reference_success_rate : float or None
        Success rate of the same instances' reference curves (None: no references).
    """

    method: str
    instances: int
    success_rate: float
    median_time_s: float
    p90_time_s: float
    median_localization_error_mm: float | None
    reference_success_rate: float | None = None

    def to_json(self) -> dict[str, Any]:
        """The summary as a JSON object (``reference_success_rate`` only when known)."""
        out: dict[str, Any] = {
            "method": self.method,
            "instances": self.instances,
            "success_rate": self.success_rate,
            "median_time_s": self.median_time_s,
            "p90_time_s": self.p90_time_s,
            "median_localization_error_mm": self.median_localization_error_mm,
        }
        if self.reference_success_rate is not None:
            out["reference_success_rate"] = self.reference_success_rate
        return out


def summarize(records: Iterable[Record]) -> dict[str, MethodSummary]:
    """Per method (in order of first appearance): success rate, median/p90 time, median
    localisation error, instances.

    Records of instances that carry a reference recognition also give
    ``reference_success_rate`` (the same instances without measurement error).
    """
    by_method: dict[str, list[Record]] = {}
    for r in records:
        by_method.setdefault(r.method, []).append(r)
    out = {}
    for method, rs in by_method.items():
        times = np.array([r.time_s for r in rs])
        loc = np.array([r.localization_error_mm for r in rs if r.localization_error_mm is not None])
        references = [r.reference.success for r in rs if r.reference is not None]
        out[method] = MethodSummary(
            method=method,
            instances=len(rs),
            success_rate=float(np.mean([r.success for r in rs])),
            median_time_s=float(np.median(times)),
            p90_time_s=float(np.percentile(times, 90)),
            median_localization_error_mm=float(np.median(loc)) if loc.size else None,
            reference_success_rate=float(np.mean(references)) if references else None,
        )
    return out


def summary_json(summary: dict[str, MethodSummary]) -> dict[str, dict[str, Any]]:
    """A summary per method as JSON objects."""
    return {method: s.to_json() for method, s in summary.items()}
