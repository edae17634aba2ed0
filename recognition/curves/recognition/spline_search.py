"""Starting shapes of the cubic spline (3.35) from a table of its shapes up to similarity.

Scaling a curve by s turns the spline ``x = t^2, y = a t^3 + b t^2 + c t`` into the one
with ``(a s^(-1/2), b, c s^(1/2))`` (and t into ``t s^(1/2)``): up to a rigid motion and
a scale every spline is ``x = t^2, y = t^3 + b t^2 + p t`` with ``p = ac`` (a > 0, as the
tree reports it; the mirror image has -b). Along that curve three quantities do not
depend on the motion, the scale or the direction of traversal: ``q = kappa_s / kappa^2``
at a point, the ratio of the curvatures at two points and the tangent's turn between
them (thesis Eqs. (3.1)-(3.2) and (3.29)). The table holds kappa, kappa_s and the
tangent angle on a grid of shapes and of t; a contact's q picks the points of each tabled
shape where it can lie, the other contacts' curvature ratios and turns score the shape,
and the best cells (local minima over the grid) are the starts of the least-squares fit.

The grid follows the shapes' geometry. ``y' = 3t^2 + 2bt + p`` turns at the inflection
``t = -b/3``, and for large |b| the visible piece there is close to a cubical parabola
whose slope parameter is ``(p - b^2/3) / |b|`` up to a constant: so b runs over sinh of a
uniform grid (up to ``sinh(B_EXTENT)``), ``p = b^2/3 + r w`` with r on an arctan-uniform
grid and ``w = sqrt(1 + b^2/9)``, and t over ``-b/3 + w tan(u)`` with u uniform.

Unlike the closed form of one contact and its parameter (THESIS_ERRATA item 7), which
maps a small error in the rotation to a large one in the shape near the vertex, the
table's errors are bounded by its cell size in shape space.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from recognition.curves.recognition.angle_search import local_minima

__all__ = [
    "B_EXTENT",
    "PARAMETER_GRID",
    "ROOTS_PER_SHAPE",
    "SEARCH_CONTACTS",
    "SHAPE_GRID",
    "SplineShapeTable",
    "SplineStarts",
    "spline_shape_table",
    "spline_starts",
]

#: Values of b and of r (module docstring) in the table.
SHAPE_GRID = 48
#: The table's b runs over sinh of a uniform grid on [-B_EXTENT, B_EXTENT].
B_EXTENT = 9.0
#: Values of the curve parameter t of the table.
PARAMETER_GRID = 128
#: Points of one tabled shape kept where a contact's q can lie.
ROOTS_PER_SHAPE = 6
#: Contacts used to score the tabled shapes (evenly spread over the data).
SEARCH_CONTACTS = 5


def _arctan_grid(n: int) -> np.ndarray:
    """n values tan(u), u uniform in (-pi/2, pi/2) at cell centres."""
    return np.asarray(np.tan((np.arange(n) + 0.5) / n * np.pi - np.pi / 2))


@dataclass(frozen=True)
class SplineShapeTable:
    """kappa, kappa_s and the tangent angle of ``x = t^2, y = t^3 + b t^2 + p t``.

    Attributes
    ----------
    b : (nb,) float
        The tabled values of b.
    p : (nb, nr) float
        The tabled values of p for each b.
    t : (nb, nt) float
        The tabled curve parameters for each b.
    kappa, kappa_s : (nb, np, nt) float
        Curvature and its arc-length derivative for increasing t, thesis Eqs. (3.1)-(3.2).
    theta : (nb, np, nt) float
        Tangent angle of increasing t, unwrapped along t.
    q_angle : (nb, np, nt) float32
        arctan(kappa_s / kappa^2), the scale-free value a contact is matched to.
    smooth : (nb * np * nt - 1,) bool
        Whether q_angle is continuous between each tabled point and the next in the
        flattened table (it jumps by pi where kappa passes through zero; False from the
        last t of one shape to the first of the next).
    """

    b: np.ndarray
    p: np.ndarray
    t: np.ndarray
    kappa: np.ndarray
    kappa_s: np.ndarray
    theta: np.ndarray
    q_angle: np.ndarray
    smooth: np.ndarray


@lru_cache(maxsize=2)
def spline_shape_table(n_shape: int = SHAPE_GRID, n_t: int = PARAMETER_GRID) -> SplineShapeTable:
    """The table of spline shapes up to similarity (module docstring), thesis Eqs.
    (3.35)-(3.37); built once per size."""
    b = np.sinh(np.linspace(-B_EXTENT, B_EXTENT, n_shape))
    width = np.sqrt(1.0 + b * b / 9.0)
    p = b[:, None] ** 2 / 3.0 + _arctan_grid(n_shape)[None, :] * width[:, None]
    t = -b[:, None] / 3.0 + _arctan_grid(n_t)[None, :] * width[:, None]
    B, P, T = b[:, None, None], p[:, :, None], t[:, None, :]
    x1, y1 = 2.0 * T, (3.0 * T + 2.0 * B) * T + P
    y2, y3 = 6.0 * T + 2.0 * B, 6.0
    speed2 = x1 * x1 + y1 * y1
    speed = np.sqrt(speed2)
    cross = x1 * y2 - 2.0 * y1
    kappa = cross / (speed2 * speed)
    dk = x1 * y3 / (speed2 * speed) - 3.0 * cross * (2.0 * x1 + y1 * y2) / (speed2 * speed2 * speed)
    kappa_s = dk / speed
    theta = np.unwrap(np.arctan2(y1, x1), axis=2)
    q_angle = np.arctan2(kappa_s, kappa * kappa).astype(np.float32)
    smooth = np.zeros(q_angle.shape, dtype=bool)
    smooth[..., :-1] = np.abs(np.diff(q_angle, axis=2)) < np.float32(np.pi / 2)
    smooth = smooth.reshape(-1)[:-1]
    return SplineShapeTable(b, p, t, kappa, kappa_s, theta, q_angle, smooth)


@dataclass(frozen=True)
class SplineStarts:
    """Starting hypotheses of the spline fit.

    Attributes
    ----------
    params : (S, 3) float
        (a, b, c) of each start.
    t : (S, m) float
        Contact parameters.
    psi : (S,) float
        Rotation taking the data's tangent angles to the canonical ones (mod pi).
    sigma : (S,) float
        +1 when the data traverse the spline with increasing t, else -1.
    score : (S,) float
        The table's consistency score of each start (lower is better).
    """

    params: np.ndarray
    t: np.ndarray
    psi: np.ndarray
    sigma: np.ndarray
    score: np.ndarray


@dataclass(frozen=True)
class _Roots:
    """The points of the tabled shapes where a contact's q can lie, as flat lists sorted
    by shape (``shape = ib * np + ip``)."""

    shape: np.ndarray
    t: np.ndarray
    kappa: np.ndarray
    theta: np.ndarray


def _roots_on_table(table: SplineShapeTable, kappa: float, kappa_s: float, n_roots: int) -> _Roots:
    """Points of every tabled shape where ``kappa_s / kappa^2`` equals the contact's
    (at most ``n_roots`` per shape): t, kappa and theta there, linearly interpolated."""
    level = np.float32(np.arctan2(kappa_s, kappa * kappa))
    q = table.q_angle.reshape(-1)
    below = q < level
    # a sign change of q, not the jump of arctan(q) through an inflection
    flat = np.flatnonzero((below[1:] != below[:-1]) & table.smooth)
    n_t = table.t.shape[1]
    shape, it = np.divmod(flat, n_t)
    ib = shape // table.p.shape[1]
    slot = np.arange(shape.size) - np.searchsorted(shape, shape, side="left")
    keep = slot < n_roots
    flat, shape, it = flat[keep], shape[keep], it[keep]
    d0 = q[flat].astype(float) - float(level)
    d1 = q[flat + 1].astype(float) - float(level)
    w = d0 / (d0 - d1)
    t0, t1 = table.t[ib, it], table.t[ib, it + 1]
    values = []
    for grid in (table.kappa.reshape(-1), table.theta.reshape(-1)):
        v0, v1 = grid[flat], grid[flat + 1]
        values.append(v0 + w * (v1 - v0))
    return _Roots(shape, t0 + w * (t1 - t0), values[0], values[1])


def _pairs(left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (i, j) with ``left[i] == right[j]`` of two sorted integer arrays."""
    lo = np.searchsorted(right, left, side="left")
    count = np.searchsorted(right, left, side="right") - lo
    i = np.repeat(np.arange(left.size), count)
    start = np.repeat(lo - np.cumsum(count) + count, count)
    return i, start + np.arange(i.size)


def _wrap(angle: np.ndarray) -> np.ndarray:
    """Angles in [-pi, pi]."""
    return np.asarray(angle - (2.0 * np.pi) * np.rint(angle / (2.0 * np.pi)))


def spline_starts(
    kappa: np.ndarray,
    kappa_s: np.ndarray,
    phi: np.ndarray,
    n_starts: int,
    table: SplineShapeTable | None = None,
) -> SplineStarts:
    """The ``n_starts`` best starting shapes of the cubic spline for the contacts.

    Parameters
    ----------
    kappa, kappa_s : (m,) float
        Curvature and its arc-length derivative at m >= 3 contacts.
    phi : (m,) float
        Tangent angle of each contact relative to the first, radians.
    n_starts : int
        Starts returned at most (the best-scoring local minima of the table).
    table : SplineShapeTable, optional
        Default :func:`spline_shape_table`.
    """
    table = table or spline_shape_table()
    m = kappa.size
    n_shapes = table.p.size
    used = np.unique(np.linspace(0, m - 1, min(m, SEARCH_CONTACTS)).round().astype(int))
    ref = int(used[np.argmax(np.abs(kappa[used]))])
    others = [int(i) for i in used if i != ref]
    roots = {i: _roots_on_table(table, kappa[i], kappa_s[i], ROOTS_PER_SHAPE) for i in used}
    base = roots[ref]
    total = np.zeros(base.shape.size)
    partner = {}
    for i in others:
        r = roots[i]
        a, b = _pairs(base.shape, r.shape)
        # ratio of |kappa| as an angle, the turn from the reference, the sign of kappa
        e = np.abs(
            np.arctan2(np.abs(r.kappa[b]), np.abs(base.kappa[a]))
            - np.arctan2(abs(kappa[i]), abs(kappa[ref]))
        )
        e += np.abs(_wrap(r.theta[b] - base.theta[a] - (phi[i] - phi[ref])))
        if kappa[i] * kappa[ref] != 0:
            e += np.sign(r.kappa[b] * base.kappa[a]) != np.sign(kappa[i] * kappa[ref])
        best = np.full(base.shape.size, np.inf)
        np.minimum.at(best, a, e)
        # the partner of each reference root: its pair of least error
        hit = e <= best[a]
        choice = np.full(base.shape.size, -1)
        choice[a[hit]] = b[hit]
        partner[i] = choice
        total += best
    score = np.full(n_shapes, np.inf)
    np.minimum.at(score, base.shape, total)
    on_best = np.isfinite(total) & (total <= score[base.shape])
    root_of = np.full(n_shapes, -1)
    root_of[base.shape[on_best]] = np.flatnonzero(on_best)
    grid = score.reshape(table.p.shape)
    ib, ip = local_minima(grid)
    order = np.argsort(grid[ib, ip], kind="stable")[:n_starts]
    ib, ip = ib[order], ip[order]
    if ib.size == 0:
        empty = np.zeros((0, m))
        return SplineStarts(np.zeros((0, 3)), empty, np.zeros(0), np.zeros(0), np.zeros(0))
    j = root_of[ib * table.p.shape[1] + ip]
    picks = {ref: j, **{i: partner[i][j] for i in others}}
    t_used = np.stack([roots[i].t[picks[i]] for i in used], axis=1)
    k_used = np.stack([roots[i].kappa[picks[i]] for i in used], axis=1)
    th_used = np.stack([roots[i].theta[picks[i]] for i in used], axis=1)
    with np.errstate(all="ignore"):
        log_ratio = np.log(np.abs(k_used / kappa[used]))
        ok = np.isfinite(log_ratio)
        scale = np.exp(np.sum(np.where(ok, log_ratio, 0.0), 1) / np.maximum(ok.sum(1), 1))
    ref_col = int(np.flatnonzero(used == ref)[0])
    sigma = np.sign(k_used[:, ref_col] * kappa[ref])
    sigma = np.where(sigma == 0, 1.0, sigma)
    psi = 0.5 * np.angle(np.mean(np.exp(2j * (th_used - phi[used])), axis=1))
    root = np.sqrt(scale)
    params = np.column_stack([1.0 / root, table.b[ib], table.p[ib, ip] * root])
    t = np.stack([np.interp(np.arange(m), used, row) for row in t_used]).reshape(-1, m)
    return SplineStarts(params, t * root[:, None], psi, sigma, grid[ib, ip])
