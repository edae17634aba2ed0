"""Compiled loops of the fast search: the stacked distance fields' lookups
(:class:`~recognition.surfaces.distance.FieldStack`), the normal equations of a pose's
residuals on them, the lookup (4.7) with the ring scores over a database's candidate
index (:class:`~recognition.surfaces.registration.candidates.CandidateIndex`: one pass over
a million rows instead of a dozen array passes), and the greedy choice of distinct poses
between the search's stages.

The fast mode screens tens of thousands of candidate poses per recognition and slides
thousands of them down the fields by Gauss-Newton (Section 4.2.2's search, batched): one
nearest-voxel read or one trilinear interpolation with its gradient per data point and
pose. Written as numpy expressions, each lookup makes some sixty passes over arrays of a
hundred thousand points; here each point is read and finished in one pass (numba, compiled
once and cached on disk). The arithmetic is that of the numpy expressions, in the same
order and precision (float32 values and frames, float64 positions): the interpolation
gives the same bits, and the nearest voxel is the same except that a coordinate exactly
half-way between two voxel centres goes to the upper one (``np.rint`` would round it to
even, at twice the cost).
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

__all__ = [
    "candidate_scores",
    "distinct_in_order",
    "interpolate",
    "nearest_in_frames",
    "rigid_normal_equations",
    "ring_scores",
]

Array = NDArray[np.float64]
Array32 = NDArray[np.float32]
IntArray = NDArray[np.int64]


@numba.njit(cache=True, nogil=True, inline="always")
def _voxel(g: np.float32, upper: np.float32) -> int:  # pragma: no cover - compiled
    """The nearest voxel index of grid coordinate g, clamped to [0, upper] (half-way: the
    upper one; not a number: 0)."""
    if not g >= 0:
        return 0
    return int(min(g, upper) + np.float32(0.5))


@numba.njit(cache=True, nogil=True)
def nearest_in_frames(
    values: Array32,
    offset: IntArray,
    shape: IntArray,
    origin: Array,
    voxel: Array,
    which: IntArray,
    frames: Array,
    origins: Array,
    local: Array,
    paired: bool,
) -> Array32:  # pragma: no cover - compiled
    """Value at the nearest voxel centre of ``origins[c] + frames[c] @ local[f, j]`` in
    field ``which[c]``, (C, F, P), or (C, 1, P) with ``paired`` (pattern c for frame c);
    positions off a grid read its nearest boundary voxel."""
    C, F, P = len(which), local.shape[0], local.shape[1]
    out = np.empty((C, 1 if paired else F, P), np.float32)
    scaled = np.empty((3, 3), np.float32)
    shift = np.empty(3, np.float32)
    upper = np.empty(3, np.float32)
    for c in range(C):
        w = which[c]
        for a in range(3):
            for b in range(3):
                scaled[a, b] = np.float32(frames[c, a, b] / voxel[w])
            shift[a] = np.float32((origins[c, a] - origin[w, a]) / voxel[w])
            upper[a] = np.float32(shape[w, a] - 1)
        s1, s2, base = shape[w, 1], shape[w, 2], offset[w]
        for f in range(out.shape[1]):
            pattern = c if paired else f
            for j in range(P):
                q0 = np.float32(local[pattern, j, 0])
                q1 = np.float32(local[pattern, j, 1])
                q2 = np.float32(local[pattern, j, 2])
                i0 = _voxel(
                    scaled[0, 0] * q0 + scaled[0, 1] * q1 + scaled[0, 2] * q2 + shift[0], upper[0]
                )
                i1 = _voxel(
                    scaled[1, 0] * q0 + scaled[1, 1] * q1 + scaled[1, 2] * q2 + shift[1], upper[1]
                )
                i2 = _voxel(
                    scaled[2, 0] * q0 + scaled[2, 1] * q1 + scaled[2, 2] * q2 + shift[2], upper[2]
                )
                out[c, f, j] = values[base + (i0 * s1 + i1) * s2 + i2]
    return out


@numba.njit(cache=True, nogil=True)
def interpolate(
    values: Array32,
    offset: IntArray,
    shape: IntArray,
    origin: Array,
    voxel: Array,
    band: Array,
    which: IntArray,
    points: Array,
    gradient: bool,
) -> tuple[Array, Array]:  # pragma: no cover - compiled
    """Trilinear value (B, P) at points (B, P, 3) in fields ``which`` (B,) and, with
    ``gradient``, its gradient (B, P, 3) (else an empty array); off a grid ``band`` and a
    zero gradient."""
    B, P = points.shape[0], points.shape[1]
    value = np.empty((B, P))
    grad = np.zeros((B, P, 3) if gradient else (0, 0, 3))
    for b in range(B):
        w = which[b]
        n0, n1, n2 = shape[w, 0], shape[w, 1], shape[w, 2]
        sz = n2
        sx = n1 * n2
        inv = np.float32(1.0 / voxel[w])
        for j in range(P):
            g0 = (points[b, j, 0] - origin[w, 0]) / voxel[w]
            g1 = (points[b, j, 1] - origin[w, 1]) / voxel[w]
            g2 = (points[b, j, 2] - origin[w, 2]) / voxel[w]
            inside = 0 <= g0 <= n0 - 1 and 0 <= g1 <= n1 - 1 and 0 <= g2 <= n2 - 1
            if not inside:  # (or not a number)
                value[b, j] = band[w]  # off the grid: the far value, no gradient
                continue
            g0 = min(g0, n0 - 1 - 1e-6)
            g1 = min(g1, n1 - 1 - 1e-6)
            g2 = min(g2, n2 - 1 - 1e-6)
            i0, i1, i2 = np.floor(g0), np.floor(g1), np.floor(g2)
            fx, fy, fz = np.float32(g0 - i0), np.float32(g1 - i1), np.float32(g2 - i2)
            flat = np.int64(i0) * sx + np.int64(i1) * sz + np.int64(i2) + offset[w]
            c000, c100 = values[flat], values[flat + sx]
            c010, c110 = values[flat + sz], values[flat + sx + sz]
            c001, c101 = values[flat + 1], values[flat + sx + 1]
            c011, c111 = values[flat + sz + 1], values[flat + sx + sz + 1]
            # along x, then y, then z, keeping the differences for the gradient
            a00, a10 = c100 - c000, c110 - c010
            a01, a11 = c101 - c001, c111 - c011
            c00, c10 = c000 + fx * a00, c010 + fx * a10
            c01, c11 = c001 + fx * a01, c011 + fx * a11
            b0, b1 = c10 - c00, c11 - c01
            c0, c1 = c00 + fy * b0, c01 + fy * b1
            value[b, j] = c0 + fz * (c1 - c0)
            if gradient:
                gx0 = a00 + fy * (a10 - a00)
                gx1 = a01 + fy * (a11 - a01)
                grad[b, j, 0] = (gx0 + fz * (gx1 - gx0)) * inv
                grad[b, j, 1] = (b0 + fz * (b1 - b0)) * inv
                grad[b, j, 2] = (c1 - c0) * inv
    return value, grad


@numba.njit(cache=True, nogil=True)
def rigid_normal_equations(
    X: Array, r: Array, g: Array, clip: Array
) -> tuple[Array, Array]:  # pragma: no cover - compiled
    """J^T J (B, 6, 6) and J^T r (B, 6) of residuals r (B, P) at points X (B, P, 3) with
    gradients g (B, P, 3) under a small rigid motion (rotation vector about the centroid
    of each pose's points, then translation): row i of J is ((x_i - c) x g_i, g_i). A
    residual beyond its ``clip`` (B, P) is left out (a truncated quadratic)."""
    B, P = r.shape
    H = np.zeros((B, 6, 6))
    b = np.zeros((B, 6))
    j = np.empty(6)
    for k in range(B):
        c0 = c1 = c2 = 0.0
        for i in range(P):
            c0 += X[k, i, 0]
            c1 += X[k, i, 1]
            c2 += X[k, i, 2]
        c0, c1, c2 = c0 / P, c1 / P, c2 / P
        for i in range(P):
            if not abs(r[k, i]) <= clip[k, i]:
                continue  # beyond the clip: no pull
            d0, d1, d2 = X[k, i, 0] - c0, X[k, i, 1] - c1, X[k, i, 2] - c2
            n0, n1, n2 = g[k, i, 0], g[k, i, 1], g[k, i, 2]
            j[0], j[1], j[2] = d1 * n2 - d2 * n1, d2 * n0 - d0 * n2, d0 * n1 - d1 * n0
            j[3], j[4], j[5] = n0, n1, n2
            for a in range(6):
                b[k, a] += j[a] * r[k, i]
                for e in range(a, 6):
                    H[k, a, e] += j[a] * j[e]
        for a in range(6):
            for e in range(a):
                H[k, a, e] = H[k, e, a]
    return H, b


@numba.njit(cache=True, nogil=True, inline="always")
def _ring_cost(
    rings: NDArray[np.float32], data: Array, inv_scale: Array, missing: float, cap: float
) -> np.float32:  # pragma: no cover - compiled
    """Ring score of one row's descriptors (K, 2 + h) against the data's (K, 2 + 2 h)
    (:func:`~recognition.surfaces.rings.ring_scores`); radii the data do not reach have
    ``inv_scale`` 0."""
    total = np.float32(0.0)
    h = rings.shape[1] - 2
    for k in range(rings.shape[0]):
        if inv_scale[k] == 0.0:
            continue
        for c in range(2):
            widened = np.float32(1.0)
            for j in range(h):
                leak = np.float32(rings[k, 2 + j] * data[k, 2 + c * h + j] * inv_scale[k])
                widened += leak * leak
            z = (rings[k, c] - np.float32(data[k, c])) * np.float32(inv_scale[k])
            z2 = z * z / widened
            if z2 != z2:
                total += np.float32(missing)
            else:
                total += min(z2, np.float32(cap))
    return total


@numba.njit(cache=True, nogil=True)
def ring_scores(
    rings: NDArray[np.float32], data: Array, inv_scale: Array, missing: float, cap: float
) -> Array32:  # pragma: no cover - compiled
    """Ring score (m,) of rows of descriptors (m, K, 2 + h)."""
    out = np.empty(rings.shape[0], np.float32)
    for i in range(rings.shape[0]):
        out[i] = _ring_cost(rings[i], data, inv_scale, missing, cap)
    return out


@numba.njit(cache=True, nogil=True)
def candidate_scores(
    owner: IntArray,
    k1: Array,
    k2: Array,
    rings: NDArray[np.float32],
    allowed: NDArray[np.bool_],
    data_k1: float,
    data_k2: float,
    tolerance: float,
    data: Array,
    inv_scale: Array,
    missing: float,
    cap: float,
) -> tuple[IntArray, Array32]:  # pragma: no cover - compiled
    """The rows (ascending) of allowed owners within ``tolerance`` of (data_k1, data_k2)
    (4.7), and their scores: the ring score plus the squared curvature distance in
    tolerances (0 for an infinite tolerance), in one pass over the index."""
    n = owner.shape[0]
    keep = np.empty(n, np.int64)
    score = np.empty(n, np.float32)
    bound = tolerance * tolerance
    m = 0
    for i in range(n):
        if not allowed[owner[i]]:
            continue
        a = np.float64(k1[i]) - data_k1
        b = np.float64(k2[i]) - data_k2
        d2 = a * a + b * b
        if not d2 < bound:
            continue
        keep[m] = i
        s = _ring_cost(rings[i], data, inv_scale, missing, cap)
        if bound < np.inf:
            s += np.float32(d2 / bound)
        score[m] = s
        m += 1
    return keep[:m], score[:m]


@numba.njit(cache=True, nogil=True)
def distinct_in_order(
    R: Array, location: Array, radius: float, cos_limit: float, n_keep: int
) -> IntArray:  # pragma: no cover - compiled
    """The greedy choice of :func:`~recognition.surfaces.registration.ambiguity.
    distinct_poses` over poses R (k, 3, 3) already in order, best first, that put p at
    ``location`` (k, 3): indices of at most ``n_keep``, each the best pose still alive,
    which then kills every later pose within ``radius`` of it whose trace of R_i^T R_j
    exceeds ``cos_limit`` (1 + 2 cos of the angle)."""
    k = R.shape[0]
    alive = np.ones(k, np.bool_)
    kept = np.empty(max(min(k, n_keep), 0), np.int64)
    count, i = 0, 0
    while count < n_keep:
        while i < k and not alive[i]:
            i += 1
        if i == k:
            break
        kept[count] = i
        count += 1
        alive[i] = False
        for b in range(i + 1, k):
            if not alive[b]:
                continue
            dx = location[b, 0] - location[i, 0]
            dy = location[b, 1] - location[i, 1]
            dz = location[b, 2] - location[i, 2]
            if not np.sqrt(dx * dx + dy * dy + dz * dz) < radius:
                continue
            trace = 0.0
            for r in range(3):
                for c in range(3):
                    trace += R[b, r, c] * R[i, r, c]
            if trace > cos_limit:
                alive[b] = False
    return kept[:count]
