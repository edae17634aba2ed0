"""Closed planar outlines and their prisms: the ellipse and the closed cubic spline."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "DEFAULT_SPLINE_KNOTS_M",
    "closed_spline_coefficients",
    "closed_spline_outline",
    "ellipse_outline",
    "extrude_outline",
]


def ellipse_outline(
    semi_axis_x_m: float, semi_axis_y_m: float, n_segments: int = 720
) -> NDArray[np.float64]:
    """Returns an ellipse as a closed polygon, (n_segments, 2) metres, counter-clockwise.

    Vertices lie on the ellipse at equal parameter steps (x = a cos t, y = b sin t).
    """
    t = np.linspace(0.0, 2.0 * math.pi, n_segments, endpoint=False)
    return np.column_stack([semi_axis_x_m * np.cos(t), semi_axis_y_m * np.sin(t)])


DEFAULT_SPLINE_KNOTS_M = (
    (0.030, 0.000),
    (0.006, 0.026),
    (-0.024, 0.017),
    (-0.022, -0.019),
    (0.009, -0.028),
)
"""Knots of the closed cubic spline of the planar experiment (thesis Fig. 3.8 shows a
closed spline of five segments; its knots are not published), metres, counter-clockwise."""


def closed_spline_coefficients(knots_m: ArrayLike = DEFAULT_SPLINE_KNOTS_M) -> NDArray[np.float64]:
    """Returns the segments of the periodic cubic spline through ``knots_m``.

    Segment i runs from knot i to knot i + 1 (the last back to the first) as
    ``x(t) = a3 t^3 + a2 t^2 + a1 t + a0``, ``y(t) = b3 t^3 + ...`` for t in [0, 1]
    (thesis Eq. (3.25)), with continuous position, tangent and curvature vector.

    Parameters
    ----------
    knots_m : (k, 2) float, metres
        At least three distinct knots, in order along the curve.

    Returns
    -------
    (k, 2, 4) float
        ``[i, 0] = (a3, a2, a1, a0)`` and ``[i, 1] = (b3, b2, b1, b0)``, metres.
    """
    from scipy.interpolate import CubicSpline

    knots = np.asarray(knots_m, dtype=np.float64)
    if knots.ndim != 2 or knots.shape[1] != 2 or len(knots) < 3:
        raise ValueError(f"knots_m must be (k >= 3, 2), got shape {knots.shape}")
    closed = np.vstack([knots, knots[:1]])
    spline = CubicSpline(np.arange(len(closed), dtype=np.float64), closed, bc_type="periodic")
    # spline.c: (4, k, 2), powers 3..0 of (t - t_i).
    return np.transpose(spline.c, (1, 2, 0)).copy()


def closed_spline_outline(
    knots_m: ArrayLike = DEFAULT_SPLINE_KNOTS_M, samples_per_segment: int = 200
) -> NDArray[np.float64]:
    """Returns the closed cubic spline through ``knots_m`` as a polygon, (n, 2) metres."""
    coefficients = closed_spline_coefficients(knots_m)
    t = np.linspace(0.0, 1.0, samples_per_segment, endpoint=False)
    powers = np.stack([t**3, t**2, t, np.ones_like(t)])  # (4, s)
    return np.concatenate([(segment @ powers).T for segment in coefficients])


def extrude_outline(
    outline_m: ArrayLike, height_m: float
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Returns the prism over a closed planar outline, from z = 0 to z = height_m.

    The caps are fans from the outline's centroid, so the outline must be star-shaped
    about its centroid (true for every convex outline).

    Parameters
    ----------
    outline_m : (n, 2) float, metres
        Closed polygon (last vertex not repeated), counter-clockwise seen from +z.
    height_m : float, metres

    Returns
    -------
    vertices : (2 n + 2, 3) float, metres
    faces : (4 n, 3) int, outward-wound
    """
    outline = np.asarray(outline_m, dtype=np.float64)
    n = len(outline)
    if outline.ndim != 2 or outline.shape[1] != 2 or n < 3 or not height_m > 0:
        raise ValueError("outline_m must be (n >= 3, 2) and height_m positive")
    x, y = outline.T
    if 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)) <= 0:
        raise ValueError("outline_m must run counter-clockwise (positive area)")
    centre = outline.mean(axis=0)
    rel = outline - centre
    nxt = np.roll(rel, -1, axis=0)
    if np.any(rel[:, 0] * nxt[:, 1] - rel[:, 1] * nxt[:, 0] <= 0):
        raise ValueError("outline_m must be star-shaped about its centroid")
    bottom = np.column_stack([outline, np.zeros(n)])
    top = np.column_stack([outline, np.full(n, height_m)])
    vertices = np.vstack([bottom, top, [[*centre, 0.0]], [[*centre, height_m]]])
    i = np.arange(n)
    j = (i + 1) % n
    side = np.concatenate([np.column_stack([i, j, n + j]), np.column_stack([i, n + j, n + i])])
    bottom_cap = np.column_stack([np.full(n, 2 * n), j, i])
    top_cap = np.column_stack([np.full(n, 2 * n + 1), n + i, n + j])
    return vertices, np.concatenate([side, bottom_cap, top_cap]).astype(np.int64)
