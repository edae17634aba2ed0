"""Compiled loop of the touch planner (:mod:`recognition.surfaces.touch_planning`): the
outcomes' mixtures of Gaussian overlaps, which its expected information gain sums.

Between a hundred outcomes (hypotheses, and their poses moved along their loose motions)
and three hundred candidate touches, the overlaps are millions of exponentials; as numpy
expressions they fill an (H, H, C) array. Here each pair is computed once (the overlap is
symmetric), skipped where it underflows to 0, and summed where it is made (numba,
compiled once and cached on disk).
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

__all__ = ["mixtures"]

Array = NDArray[np.float64]

#: exp(-x) is exactly 0 in double precision beyond this: such a pair adds nothing.
UNDERFLOW = 746.0


@numba.njit(cache=True, nogil=True)
def mixtures(depths: Array, weights: Array, scale: float) -> Array:  # pragma: no cover
    """sum_j weights_j exp(-scale (depths_ci - depths_cj)^2) for each candidate c and
    outcome i, (C, H), of ``depths`` (C, H) and ``weights`` (H,)."""
    n_touches, n_outcomes = depths.shape
    out = np.zeros((n_touches, n_outcomes))
    for c in range(n_touches):
        for i in range(n_outcomes):
            out[c, i] += weights[i]
            for j in range(i + 1, n_outcomes):
                gap = depths[c, i] - depths[c, j]
                exponent = scale * gap * gap
                if exponent < UNDERFLOW:
                    overlap = np.exp(-exponent)
                    out[c, i] += weights[j] * overlap
                    out[c, j] += weights[i] * overlap
    return out
