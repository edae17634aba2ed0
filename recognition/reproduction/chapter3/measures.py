"""The measures the Chapter 3 tables report: value summaries and the relative parameter error."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "relative_parameter_error",
    "summary",
]


def summary(values: ArrayLike) -> dict[str, float]:
    """min, max, mean, stdev and count ``n`` of the finite values (NaN and n = 0 when
    there are none)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return {"min": float("nan"), "max": float("nan"), "mean": float("nan"), "n": 0}
    return {
        "min": float(v.min()),
        "max": float(v.max()),
        "mean": float(v.mean()),
        "stdev": float(v.std()),
        "n": int(v.size),
    }


def relative_parameter_error(true: Sequence[float], estimated: Sequence[float]) -> float:
    """sqrt(sum(((p - p_hat) / p)^2)), the error measure of Table 3.3; inf when the
    numbers of parameters differ."""
    p, p_hat = np.asarray(true, float), np.asarray(estimated, float)
    if p_hat.shape != p.shape:
        return float("inf")
    return float(np.sqrt(np.sum(((p - p_hat) / p) ** 2)))
