"""Signed distance fields of recipe nodes.

Negative inside, positive outside, in recipe units. :func:`evaluate` takes (n, 3)
points; the primitive functions take (3, n) arrays, one coordinate per row, which keeps
the arithmetic on contiguous rows. The primitives are exact
(round cones, half-spaces) or close approximations near the surface (ellipsoid,
superellipsoid, spiral shell): the zero level set is the shape, and the value is a
distance estimate good enough to tell near from far.

:func:`evaluate` takes ``exact_within``: a primitive is evaluated exactly only at
points within that distance of its bounding box; elsewhere the distance to the box (a
lower bound, at least ``exact_within``) stands in. The field keeps its sign everywhere,
and equals the fully evaluated field wherever its magnitude is below
``exact_within - blend_margin(node)`` (a far primitive can reach the result through a
chain of smooth blends; :func:`blend_margin` bounds how far).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from recognition.rigid import rotation_about
from tactile_sim.objects.recipe import (
    Ellipsoid,
    HalfSpace,
    Intersect,
    Mirror,
    Node,
    SpiralShell,
    Subtract,
    Superellipsoid,
    Tube,
    Union,
    Vec3,
)

__all__ = [
    "blend_margin",
    "evaluate",
    "node_bounds",
    "rotation_matrix",
    "sd_ellipsoid",
    "sd_round_cones",
    "sd_superellipsoid",
    "smooth_max",
    "smooth_min",
    "tube_segments",
]

#: Guards divisions at the centre of a primitive.
_TINY = 1e-12


def rotation_matrix(rotation_deg: tuple[float, float, float]) -> np.ndarray:
    """(3, 3) rotation ``Rz @ Ry @ Rx`` from extrinsic x, y, z angles in degrees."""
    ax, ay, az = np.radians(rotation_deg)
    return rotation_about(2, az) @ rotation_about(1, ay) @ rotation_about(0, ax)


def _to_local(xyz: np.ndarray, center: Vec3, rotation_deg: Vec3) -> np.ndarray:
    """(3, n) points expressed in a primitive's local frame (``R^T (p - c)``)."""
    c = np.asarray(center, dtype=float)
    d0, d1, d2 = xyz[0] - c[0], xyz[1] - c[1], xyz[2] - c[2]
    if not any(rotation_deg):
        return np.stack([d0, d1, d2])
    R = rotation_matrix(rotation_deg)
    return np.stack([R[0, j] * d0 + R[1, j] * d1 + R[2, j] * d2 for j in range(3)])


def _norm(v: np.ndarray) -> np.ndarray:
    """Euclidean norm of (3, n) vectors, (n,)."""
    return np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


def _distance_to(xyz: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Distances (n,) from (3, n) points to one point."""
    d = xyz[0] - centre[0]
    total = d * d
    for i in (1, 2):
        d = xyz[i] - centre[i]
        total += d * d
    return np.sqrt(total)


def smooth_min(a: np.ndarray, b: np.ndarray, k: float) -> np.ndarray:
    """Polynomial smooth minimum over a blend width ``k`` (plain minimum for k = 0)."""
    if k <= 0:
        return np.minimum(a, b)
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b + (a - b) * h - k * h * (1.0 - h)


def smooth_max(a: np.ndarray, b: np.ndarray, k: float) -> np.ndarray:
    """Polynomial smooth maximum over a blend width ``k`` (plain maximum for k = 0)."""
    return -smooth_min(-a, -b, k)


def sd_ellipsoid(local: np.ndarray, radii: ArrayLike) -> np.ndarray:
    """Approximate signed distance to an axis-aligned ellipsoid centred at the origin.

    Parameters
    ----------
    local : (3, n) float
        Points in the ellipsoid's frame, one coordinate per row.
    radii : (3,) float
        Semi-axes.

    Returns
    -------
    (n,) float
        ``k0 (k0 - 1) / k1`` with ``k0 = |p / r|``, ``k1 = |p / r^2|``: exact on the
        surface to first order, a distance estimate elsewhere.
    """
    r = np.asarray(radii, dtype=float)
    q0, q1, q2 = local[0] / r[0], local[1] / r[1], local[2] / r[2]
    k0 = np.sqrt(q0 * q0 + q1 * q1 + q2 * q2)
    q0 /= r[0]
    q1 /= r[1]
    q2 /= r[2]
    k1 = np.sqrt(q0 * q0 + q1 * q1 + q2 * q2)
    return np.where(k1 > _TINY, k0 * (k0 - 1.0) / np.maximum(k1, _TINY), -r.min())


def sd_superellipsoid(local: np.ndarray, radii: ArrayLike, exponents: ArrayLike) -> np.ndarray:
    """Radial distance estimate to an axis-aligned superellipsoid centred at the origin.

    Parameters
    ----------
    local : (3, n) float
        Points in the superellipsoid's frame, one coordinate per row.
    radii : (3,) float
        Semi-axes.
    exponents : (2,) float
        ``(e1, e2)`` squareness along z and in the xy plane.

    Returns
    -------
    (n,) float
        ``|p| (1 - F^(-e1/2))`` with ``F`` the inside-outside function: the distance
        from ``p`` to the surface along the ray from the centre.
    """
    e1, e2 = exponents
    r = np.asarray(radii, dtype=float)
    q = [np.abs(local[i]) / r[i] + _TINY for i in range(3)]
    xy = (q[0] ** (2.0 / e2) + q[1] ** (2.0 / e2)) ** (e2 / e1)
    F = xy + q[2] ** (2.0 / e1)
    return _norm(local) * (1.0 - F ** (-e1 / 2.0))


def _catmull_rom(
    points: np.ndarray, values: np.ndarray, subdivisions: int
) -> tuple[np.ndarray, np.ndarray]:
    """Centripetal Catmull-Rom spline through ``points``, ``values`` interpolated linearly.

    Returns ``(samples, sampled_values)`` of shapes ``(s, 3)`` and ``(s,)``, including
    every control point.
    """
    P = np.vstack([2 * points[0] - points[1], points, 2 * points[-1] - points[-2]])
    out_p, out_v = [points[:1]], [values[:1]]
    u = np.arange(1, subdivisions + 1) / subdivisions
    for i in range(len(points) - 1):
        p0, p1, p2, p3 = P[i], P[i + 1], P[i + 2], P[i + 3]
        t0 = 0.0
        t1 = t0 + np.linalg.norm(p1 - p0) ** 0.5 + _TINY
        t2 = t1 + np.linalg.norm(p2 - p1) ** 0.5 + _TINY
        t3 = t2 + np.linalg.norm(p3 - p2) ** 0.5 + _TINY
        t = (t1 + u * (t2 - t1))[:, None]
        a1 = (t1 - t) / (t1 - t0) * p0 + (t - t0) / (t1 - t0) * p1
        a2 = (t2 - t) / (t2 - t1) * p1 + (t - t1) / (t2 - t1) * p2
        a3 = (t3 - t) / (t3 - t2) * p2 + (t - t2) / (t3 - t2) * p3
        b1 = (t2 - t) / (t2 - t0) * a1 + (t - t0) / (t2 - t0) * a2
        b2 = (t3 - t) / (t3 - t1) * a2 + (t - t1) / (t3 - t1) * a3
        out_p.append((t2 - t) / (t2 - t1) * b1 + (t - t1) / (t2 - t1) * b2)
        out_v.append(values[i] + u * (values[i + 1] - values[i]))
    return np.vstack(out_p), np.concatenate(out_v)


def tube_segments(tube: Tube) -> tuple[np.ndarray, np.ndarray]:
    """Centreline samples ``(m, 3)`` and radii ``(m,)`` of a tube's round-cone chain."""
    points = np.asarray(tube.points, dtype=float)
    radii = np.asarray(tube.radii, dtype=float)
    if tube.smooth and len(points) > 2:
        return _catmull_rom(points, radii, tube.subdivisions)
    return points, radii


def sd_round_cones(xyz: np.ndarray, a: ArrayLike, b: ArrayLike, ra: float, rb: float) -> np.ndarray:
    """Exact signed distance to the round cone joining spheres (a, ra) and (b, rb).

    Parameters
    ----------
    xyz : (3, n) float
        Points, one coordinate per row.
    a, b : (3,) float
        Sphere centres.
    ra, rb : float
        Sphere radii.

    Returns
    -------
    (n,) float
        Signed distance to the convex hull of the two spheres (to the larger sphere
        when it contains the other).
    """
    a = np.asarray(a, dtype=float)
    ba = np.asarray(b, dtype=float) - a
    l2 = float(ba @ ba)
    rr = ra - rb
    a2 = l2 - rr * rr
    pa = xyz - a[:, None]
    if a2 <= _TINY:
        big, r = (np.zeros(3), ra) if ra >= rb else (ba, rb)
        return _norm(pa - big[:, None]) - r
    il2 = 1.0 / l2
    y = ba[0] * pa[0] + ba[1] * pa[1] + ba[2] * pa[2]
    z = y - l2
    w = pa * l2 - ba[:, None] * y
    x2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2]
    y2 = y * y * l2
    z2 = z * z * l2
    k = np.sign(rr) * rr * rr * x2
    side_b = np.sign(z) * a2 * z2 > k
    side_a = np.sign(y) * a2 * y2 < k
    d_b = np.sqrt(x2 + z2) * il2 - rb
    d_a = np.sqrt(x2 + y2) * il2 - ra
    d_mid = (np.sqrt(x2 * a2 * il2) + y * rr) * il2 - ra
    return np.where(side_b, d_b, np.where(side_a, d_a, d_mid))


def _sd_spiral_shell(local: np.ndarray, shell: SpiralShell) -> np.ndarray:
    """Distance estimate to a spiral shell in its local frame (see :class:`SpiralShell`).

    Each point is compared with the tube cross-section at its own polar angle on every
    whorl (and with the aperture end), treating the cross-section as an ellipsoid with
    half-widths (radial, tangential, axial) = ``tube_ratio * radius * (1, 1,
    tube_aspect)``; the minimum over whorls is returned. Angles before the apex are
    clamped to it, which closes the apex with an ellipsoidal cap.
    """
    b = np.log(shell.growth_per_turn) / (2.0 * np.pi)
    theta_start = -2.0 * np.pi * shell.turns
    r_end = shell.aperture_radius
    x, y, z = local

    def whorl_distance(theta: np.ndarray) -> np.ndarray:
        radius = r_end * np.exp(b * theta)
        c, s = np.cos(theta), np.sin(theta)
        vx, vy = x - radius * c, y - radius * s
        vz = (z - shell.spire * (r_end - radius)) / shell.tube_aspect
        radial = vx * c + vy * s
        tangential = vy * c - vx * s
        half = shell.tube_ratio * radius
        k0 = np.sqrt(radial * radial + tangential * tangential + vz * vz) / half
        vz = vz / shell.tube_aspect
        k1 = np.sqrt(radial * radial + tangential * tangential + vz * vz) / (half * half)
        return np.where(k1 > _TINY, k0 * (k0 - 1.0) / np.maximum(k1, _TINY), -half)

    # Polar angle on the outermost whorl, in (-2 pi, 0].
    phi = -np.mod(-np.arctan2(y, x), 2.0 * np.pi)
    best = whorl_distance(np.zeros_like(x))
    for turn in range(int(np.ceil(shell.turns)) + 1):
        best = np.minimum(best, whorl_distance(np.maximum(phi - 2.0 * np.pi * turn, theta_start)))
    return best


def blend_margin(node: Node) -> float:
    """How far (recipe units) a primitive's value can reach the result through blends.

    A polynomial smooth minimum of width ``k`` lowers its result by at most ``k / 4``
    below the smaller argument and blends only arguments closer than ``k``: along a
    chain of ``n`` blends a value can influence results up to ``1.25 k n`` smaller.
    Nested operations add up. Sharp operations (``k = 0``) contribute nothing.
    """
    if isinstance(node, Union | Intersect):
        inner = max(blend_margin(c) for c in node.children)
        return 1.25 * node.k * len(node.children) + inner
    if isinstance(node, Subtract):
        inner = max(blend_margin(c) for c in (node.base, *node.cuts))
        return 1.25 * node.k * (1 + len(node.cuts)) + inner
    if isinstance(node, Mirror):
        return blend_margin(node.child)
    return 0.0


def _box_distance(xyz: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Distance from (3, n) points to an axis-aligned box (0 inside)."""
    total = np.zeros(xyz.shape[1])
    for i in range(3):
        q = np.maximum(np.maximum(lo[i] - xyz[i], xyz[i] - hi[i]), 0.0)
        total += q * q
    return np.sqrt(total)


def _in_box(xyz: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Indices of the (3, n) points inside an axis-aligned box."""
    x, y, z = xyz
    return np.flatnonzero(
        (x >= lo[0]) & (x <= hi[0]) & (y >= lo[1]) & (y <= hi[1]) & (z >= lo[2]) & (z <= hi[2])
    )


def _rotated_box_bounds(
    center: Vec3, rotation_deg: Vec3, lo_local: np.ndarray, hi_local: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    corners = np.array(
        [
            [x, y, z]
            for x in (lo_local[0], hi_local[0])
            for y in (lo_local[1], hi_local[1])
            for z in (lo_local[2], hi_local[2])
        ]
    )
    world = corners @ rotation_matrix(rotation_deg).T + np.asarray(center)
    return world.min(axis=0), world.max(axis=0)


def node_bounds(node: Node) -> tuple[np.ndarray, np.ndarray] | None:
    """Axis-aligned box ``(lo, hi)`` containing the node's solid; None if unbounded."""
    if isinstance(node, Ellipsoid | Superellipsoid):
        r = np.asarray(node.radii, dtype=float)
        return _rotated_box_bounds(node.center, node.rotation_deg, -r, r)
    if isinstance(node, Tube):
        pts, radii = tube_segments(node)
        return (pts - radii[:, None]).min(axis=0), (pts + radii[:, None]).max(axis=0)
    if isinstance(node, SpiralShell):
        half = node.tube_ratio * node.aperture_radius
        reach = node.aperture_radius + half
        half_z = half * node.tube_aspect
        rise = node.spire * node.aperture_radius
        lo = np.array([-reach, -reach, min(-half_z, rise - half_z)])
        hi = np.array([reach, reach, max(half_z, rise + half_z)])
        return _rotated_box_bounds(node.center, node.rotation_deg, lo, hi)
    if isinstance(node, HalfSpace):
        return None
    if isinstance(node, Union):
        boxes = [node_bounds(c) for c in node.children]
        if any(box is None for box in boxes):
            return None
        pad = node.k / 4.0
        return (
            np.min([box[0] for box in boxes], axis=0) - pad,
            np.max([box[1] for box in boxes], axis=0) + pad,
        )
    if isinstance(node, Subtract):
        return node_bounds(node.base)
    if isinstance(node, Intersect):
        boxes = [box for box in (node_bounds(c) for c in node.children) if box is not None]
        if not boxes:
            return None
        return np.max([box[0] for box in boxes], axis=0), np.min([box[1] for box in boxes], axis=0)
    if isinstance(node, Mirror):
        box = node_bounds(node.child)
        if box is None:
            return None
        lo, hi = box[0].copy(), box[1].copy()
        extent = max(abs(lo[node.axis]), abs(hi[node.axis]))
        lo[node.axis], hi[node.axis] = -extent, extent
        return lo, hi
    raise TypeError(f"not a recipe node: {type(node).__name__}")


def _leaf_exact(node: Node, xyz: np.ndarray) -> np.ndarray:
    local = _to_local(xyz, node.center, node.rotation_deg)
    if isinstance(node, Ellipsoid):
        return sd_ellipsoid(local, node.radii)
    if isinstance(node, Superellipsoid):
        return sd_superellipsoid(local, node.radii, node.exponents)
    if isinstance(node, SpiralShell):
        return _sd_spiral_shell(local, node)
    raise TypeError(f"not a leaf: {type(node).__name__}")


def _sd_tube(tube: Tube, xyz: np.ndarray, exact_within: float) -> np.ndarray:
    """Hard union of a tube's round cones, evaluating each cone only where it can win.

    The sample spheres give an upper bound ``U`` of the distance (each sphere lies in
    the tube); a cone of length ``l`` and largest radius ``r`` is at least
    ``min(|p - a|, |p - b|) - l - r`` away. A cone is evaluated only at points where
    that lower bound is at most ``min(U, exact_within)``; other cones cannot be the
    minimum there, or only where the tube is farther than ``exact_within``.
    """
    pts, radii = tube_segments(tube)
    upper = np.full(xyz.shape[1], np.inf)
    for centre, radius in zip(pts, radii, strict=True):
        np.minimum(upper, _distance_to(xyz, centre) - radius, out=upper)
    threshold = np.minimum(upper, exact_within)
    out = np.full(xyz.shape[1], np.inf)
    dist_a = _distance_to(xyz, pts[0])
    for i in range(len(pts) - 1):
        dist_b = _distance_to(xyz, pts[i + 1])
        reach = np.linalg.norm(pts[i + 1] - pts[i]) + max(radii[i], radii[i + 1])
        idx = np.flatnonzero(np.minimum(dist_a, dist_b) - reach <= threshold)
        if idx.size:
            d = sd_round_cones(xyz[:, idx], pts[i], pts[i + 1], radii[i], radii[i + 1])
            out[idx] = np.minimum(out[idx], d)
        dist_a = dist_b
    if np.isfinite(exact_within):
        lo = (pts - radii[:, None]).min(axis=0)
        hi = (pts + radii[:, None]).max(axis=0)
        np.minimum(out, np.maximum(_box_distance(xyz, lo, hi), exact_within), out=out)
    return out


def _evaluate(node: Node, xyz: np.ndarray, exact_within: float) -> np.ndarray:
    if isinstance(node, Union):
        out = _evaluate(node.children[0], xyz, exact_within)
        for child in node.children[1:]:
            out = smooth_min(out, _evaluate(child, xyz, exact_within), node.k)
        return out
    if isinstance(node, Subtract):
        out = _evaluate(node.base, xyz, exact_within)
        for cut in node.cuts:
            out = smooth_max(out, -_evaluate(cut, xyz, exact_within), node.k)
        return out
    if isinstance(node, Intersect):
        out = _evaluate(node.children[0], xyz, exact_within)
        for child in node.children[1:]:
            out = smooth_max(out, _evaluate(child, xyz, exact_within), node.k)
        return out
    if isinstance(node, Mirror):
        folded = xyz.copy()
        folded[node.axis] = np.abs(folded[node.axis])
        return _evaluate(node.child, folded, exact_within)
    if isinstance(node, HalfSpace):
        n = np.asarray(node.normal, dtype=float)
        n = n / np.linalg.norm(n)
        return n[0] * xyz[0] + n[1] * xyz[1] + n[2] * xyz[2] - node.offset
    if isinstance(node, Tube):
        return _sd_tube(node, xyz, exact_within)
    if not np.isfinite(exact_within):
        return _leaf_exact(node, xyz)
    lo, hi = node_bounds(node)
    out = np.maximum(_box_distance(xyz, lo, hi), exact_within)
    idx = _in_box(xyz, lo - exact_within, hi + exact_within)
    if idx.size:
        out[idx] = _leaf_exact(node, xyz[:, idx])
    return out


def evaluate(node: Node, points: np.ndarray, exact_within: float = np.inf) -> np.ndarray:
    """Signed distance of ``node`` at ``points``.

    Parameters
    ----------
    node : recipe node
    points : (n, 3) float, recipe units
    exact_within : float, recipe units
        Primitives are evaluated exactly within this distance of their bounding boxes
        and replaced by the box distance farther away (see the module docstring).

    Returns
    -------
    (n,) float, recipe units
    """
    xyz = np.ascontiguousarray(np.asarray(points, dtype=float).T)
    return _evaluate(node, xyz, exact_within)
