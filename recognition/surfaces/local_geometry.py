"""Surface normal and principal curvatures at the common point of the data curves (4.1.1).

Conventions: the surface normal points out of the object; a normal curvature is
positive where the surface bends away from the normal (a convex surface, e.g. a sphere of
radius r, has k1 = k2 = 1/r). ``k1 >= k2``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.errors import DegenerateGeometry
from recognition.surfaces.data_curves import DataCurves

__all__ = [
    "CurveFrame",
    "LocalSurfaceGeometry",
    "curve_frame_at",
    "local_surface_geometry",
    "normal_curvature",
    "principal_curvatures_from_normal_curvatures",
    "principal_curvatures_thesis",
    "surface_normal",
]

Array = NDArray[np.float64]

#: Default half length (metres) of the arc around p used by the curve fits.
FIT_HALF_LENGTH_M = 4.5e-3
#: Default degree of the polynomial fitted to each data curve around p.
FIT_DEGREE = 4

#: The plane and polynomial fits leave out points whose residual exceeds ``TRIM_SIGMAS``
#: robust standard deviations and ``TRIM_FLOOR_M`` (a gross outlier), refitting at most
#: ``TRIM_PASSES`` times.
TRIM_SIGMAS, TRIM_FLOOR_M, TRIM_PASSES = 6.0, 0.02e-3, 2


@dataclass(frozen=True)
class CurveFrame:
    """Local geometry of one data curve at p (thesis Fig. 4.2).

    Attributes
    ----------
    point : (3,) float
        The fitted curve's point nearest p.
    tangent : (3,) float
        Unit tangent T, in the direction of the curve's point order.
    normal : (3,) float
        Unit principal normal N_c, towards the centre of curvature.
    curvature : float
        Curvature kappa >= 0, 1/m.
    plane_normal : (3,) float
        Unit normal of the sampling plane.
    """

    point: Array
    tangent: Array
    normal: Array
    curvature: float
    plane_normal: Array


@dataclass(frozen=True)
class LocalSurfaceGeometry:
    """Normal and principal curvatures at the data curves' common point.

    Attributes
    ----------
    point : (3,) float
        The common point p.
    normal : (3,) float
        Unit surface normal N (outward if the data carry an approach direction).
    k1, k2 : float
        Principal curvatures, k1 >= k2, 1/m (convex positive).
    d1, d2 : (3,) float
        Unit principal directions (tangent to the surface).
    frames : tuple of CurveFrame
    normal_curvatures : (k,) float
        Normal curvature along each curve's tangent, Euler's theorem (4.2)-(4.4).
    oriented : bool
        True when the normal's sign came from the data's approach direction.
    """

    point: Array
    normal: Array
    k1: float
    k2: float
    d1: Array
    d2: Array
    frames: tuple[CurveFrame, ...]
    normal_curvatures: Array
    oriented: bool

    def with_normal(self, normal: ArrayLike) -> LocalSurfaceGeometry:
        """The principal curvatures of the same curve fits about another ``normal`` (e.g.
        one estimated over a shorter arc); its sign is kept."""
        unit = np.asarray(normal, dtype=float)
        return _at_normal(self.point, unit / np.linalg.norm(unit), self.frames, self.oriented)

    def flipped(self) -> LocalSurfaceGeometry:
        """The same geometry seen with the opposite normal: (k1, k2) -> (-k2, -k1)."""
        return LocalSurfaceGeometry(
            self.point,
            -self.normal,
            -self.k2,
            -self.k1,
            self.d2,
            self.d1,
            self.frames,
            -self.normal_curvatures,
            self.oriented,
        )

    @property
    def frame(self) -> Array:
        """(3, 3) rotation whose columns are (d1, d2, N): the local frame at p."""
        return np.column_stack([self.d1, self.d2, self.normal])


def _gross(residuals: Array) -> NDArray[np.bool_]:
    """Residuals too large for the rest to explain: beyond ``TRIM_SIGMAS`` robust
    standard deviations (1.4826 times the median absolute residual) and ``TRIM_FLOOR_M``."""
    a = np.abs(residuals)
    return np.asarray(a > max(TRIM_SIGMAS * 1.4826 * float(np.median(a)), TRIM_FLOOR_M))


def _plane_fit(points: Array) -> tuple[Array, Array]:
    """Centroid (3,) and the (3, 3) right singular vectors of the centred points, after
    leaving out points grossly off the plane of the others (:func:`_gross`)."""
    keep = np.ones(len(points), bool)
    for _ in range(TRIM_PASSES + 1):
        centroid = points[keep].mean(axis=0)
        _, _, vt = np.linalg.svd(points[keep] - centroid, full_matrices=False)
        gross = _gross((points - centroid) @ vt[2])
        if not (gross & keep).any() or np.count_nonzero(keep & ~gross) < 3:
            break
        keep &= ~gross
    return centroid, vt  # rows: two in-plane directions, then the plane normal


def curve_frame_at(
    curve: Array,
    p: Array,
    *,
    half_length_m: float = FIT_HALF_LENGTH_M,
    degree: int = FIT_DEGREE,
) -> CurveFrame:
    """Tangent, normal and curvature of a data curve at p (thesis Section 4.1.1.1).

    A plane is fitted to the whole curve; in that plane a polynomial ``y = f(x)`` (the
    thesis uses a quadratic) is fitted over the points within ``half_length_m`` of p,
    in a frame whose x axis is the local chord; tangent, normal and curvature come from
    its derivatives at the abscissa of p. Both fits leave out gross outliers (residuals
    beyond ``TRIM_SIGMAS`` robust standard deviations and ``TRIM_FLOOR_M``).

    Parameters
    ----------
    curve : (n, 3) float
        Ordered points of the data curve, metres.
    p : (3,) float
        The common point of the data curves, metres.
    half_length_m : float
        Points within this distance of p are fitted, metres.
    degree : int
        Degree of the fitted polynomial.
    """
    _, vt = _plane_fit(curve)
    plane_normal = vt[2]
    near = np.linalg.norm(curve - p, axis=1) <= half_length_m
    if np.count_nonzero(near) < degree + 2:
        order = np.argsort(np.linalg.norm(curve - p, axis=1))
        near = np.zeros(curve.shape[0], bool)
        near[order[: degree + 2]] = True
    idx = np.flatnonzero(near)
    local = curve[idx[0] : idx[-1] + 1]
    if local.shape[0] < degree + 2:
        raise DegenerateGeometry(
            f"a data curve has {local.shape[0]} points near p; the fit needs {degree + 2}"
        )
    chord = local[-1] - local[0]
    chord -= plane_normal * (chord @ plane_normal)
    ex = chord / np.linalg.norm(chord)
    ey = np.cross(plane_normal, ex)
    rel = local - p
    x, y = rel @ ex, rel @ ey
    scale = max(np.abs(x).max(), 1e-12)
    keep = np.ones(len(x), bool)
    for _ in range(TRIM_PASSES + 1):
        coef = np.polynomial.polynomial.polyfit(x[keep] / scale, y[keep], degree)
        gross = _gross(y - np.polynomial.polynomial.polyval(x / scale, coef))
        if not (gross & keep).any() or np.count_nonzero(keep & ~gross) < degree + 2:
            break
        keep &= ~gross
    y0 = coef[0]
    y1 = coef[1] / scale
    y2 = 2.0 * coef[2] / scale**2
    g = np.sqrt(1.0 + y1 * y1)
    tangent = (ex + y1 * ey) / g
    kappa_signed = y2 / g**3  # positive: bends towards +ey
    in_plane_normal = (-y1 * ex + ey) / g
    normal = np.sign(kappa_signed or 1.0) * in_plane_normal
    return CurveFrame(p + y0 * ey, tangent, normal, float(abs(kappa_signed)), plane_normal)


def surface_normal(tangents: ArrayLike) -> Array:
    """Unit N minimising sum_i (N . T_i)^2, thesis Eq. (4.1) (sign arbitrary).

    The minimiser is the eigenvector of ``sum_i T_i T_i^T`` of least eigenvalue.

    Parameters
    ----------
    tangents : (k, 3) float
        Unit tangents T_i of the data curves at p.

    Returns
    -------
    (3,) float
        The unit normal N.
    """
    T = np.asarray(tangents, dtype=float)
    _, v = np.linalg.eigh(T.T @ T)
    return v[:, 0]


def normal_curvature(frame: CurveFrame, normal: Array) -> float:
    """Normal curvature along a curve's tangent: -kappa (N_c . N), Meusnier's theorem: the
    left-hand sides of thesis Eqs. (4.2)-(4.4).

    The thesis writes kappa (N_c . N) with N on the side the curve bends towards; with the
    outward normal the sign flips so that convex surfaces have positive curvature.
    ``normal`` is the (3,) unit surface normal; the result is in 1/m.
    """
    return float(-frame.curvature * (frame.normal @ normal))


def principal_curvatures_thesis(
    kn_alpha: float, kn_beta: float, kn_gamma: float, theta1: float, theta2: float
) -> tuple[float, float, float]:
    """k1, k2 and theta from three normal curvatures, thesis Eqs. (4.2)-(4.6).

    ``theta1``, ``theta2`` are the angles from T_alpha to T_beta and T_gamma in the
    tangent plane; theta is the angle from T_alpha to the first principal direction
    (angles in radians, curvatures in 1/m). Returns ``(k1, k2, theta)`` in the thesis's
    order (k1 is the curvature along theta, not necessarily the larger one).
    """
    ratio = ((kn_alpha - kn_beta) * np.sin(theta2)) / ((kn_alpha - kn_gamma) * np.sin(theta1))
    theta = (np.arctan(np.sin(theta1 - theta2) / (ratio - np.cos(theta1 - theta2))) - theta2) / 2
    c0, s0 = np.cos(theta) ** 2, np.sin(theta) ** 2
    c1, s1 = np.cos(theta + theta1) ** 2, np.sin(theta + theta1) ** 2
    denom = c0 * s1 - c1 * s0
    k1 = (kn_alpha * s1 - kn_beta * s0) / denom
    k2 = (kn_beta * c0 - kn_alpha * c1) / denom
    return float(k1), float(k2), float(theta)


def principal_curvatures_from_normal_curvatures(
    normal_curvatures: ArrayLike, angles: ArrayLike
) -> tuple[float, float, float, float]:
    """Second fundamental form from k >= 3 normal curvatures by least squares (Euler).

    ``kn_i = L cos^2(a_i) + 2 M sin(a_i) cos(a_i) + N sin^2(a_i)`` for tangent directions
    at angles ``a_i`` in the tangent plane. With three curves this is the exact solve of
    (4.2)-(4.4); with more it is their least-squares solution.

    Parameters
    ----------
    normal_curvatures : (k,) float
        Normal curvatures kn_i, 1/m.
    angles : (k,) float
        Angles a_i of the tangent directions in the tangent plane, radians.

    Returns
    -------
    k1, k2 : float
        Eigenvalues of [[L, M], [M, N]], k1 >= k2, 1/m.
    angle1 : float
        Angle of the k1 direction, radians.
    condition : float
        Condition number of the linear system (large: directions too close together).
    """
    a = np.asarray(angles, dtype=float)
    A = np.column_stack([np.cos(a) ** 2, 2 * np.sin(a) * np.cos(a), np.sin(a) ** 2])
    (L, M, N), *_ = np.linalg.lstsq(A, np.asarray(normal_curvatures, float), rcond=None)
    w, v = np.linalg.eigh(np.array([[L, M], [M, N]]))
    condition = float(np.linalg.cond(A))
    return float(w[1]), float(w[0]), float(np.arctan2(v[1, 1], v[0, 1])), condition


def _measured_normals_at(curves: DataCurves, p: Array) -> Array | None:
    """The sensor's normals (k, 3) at the point of each curve nearest p, or None."""
    if curves.normals is None:
        return None
    rows = [
        n[int(np.argmin(np.linalg.norm(c - p, axis=1)))]
        for c, n in zip(curves.curves, curves.normals, strict=True)
    ]
    return np.array(rows)


def local_surface_geometry(
    curves: DataCurves,
    *,
    half_length_m: float = FIT_HALF_LENGTH_M,
    degree: int = FIT_DEGREE,
    point: ArrayLike | None = None,
) -> LocalSurfaceGeometry:
    """Normal (4.1) and principal curvatures (4.2)-(4.6) at the curves' common point.

    ``point`` ((3,), metres; default ``curves.intersection``) is where the curves are
    fitted and the geometry evaluated.

    When the curves carry the sensor's normals, those of the points nearest p join the
    tangents in (4.1): N minimises sum_i (N . T_i)^2 + sum_j (1 - (N . n_j)^2), each
    measured normal n_j counting as much as one tangent, and they orient N outward.
    Otherwise, with ``curves.approach`` the normal points against the approach (out of
    the object); else it is oriented so that the mean normal curvature is positive (the
    data are taken as seen from outside a locally convex surface) and ``oriented`` is
    False.
    """
    p = curves.intersection if point is None else np.asarray(point, dtype=float)
    frames = tuple(
        curve_frame_at(c, p, half_length_m=half_length_m, degree=degree) for c in curves.curves
    )
    tangents = np.array([f.tangent for f in frames])
    measured = _measured_normals_at(curves, p)
    if measured is None:
        normal = surface_normal(tangents)
    else:
        M = tangents.T @ tangents + len(measured) * np.eye(3) - measured.T @ measured
        normal = np.linalg.eigh(M)[1][:, 0]
        normal = normal if normal @ measured.sum(axis=0) >= 0 else -normal
    approach = curves.approach
    oriented = approach is not None or measured is not None
    if approach is not None and measured is None:
        normal = -normal if normal @ approach > 0 else normal
    if not oriented and np.mean([normal_curvature(f, normal) for f in frames]) < 0:
        normal = -normal
    return _at_normal(p, normal, frames, oriented)


def _at_normal(
    p: Array, normal: Array, frames: tuple[CurveFrame, ...], oriented: bool
) -> LocalSurfaceGeometry:
    """The principal curvatures (4.2)-(4.6) at p of the curves' ``frames`` about the unit
    ``normal``."""
    tangents = np.array([f.tangent for f in frames])
    kn = np.array([normal_curvature(f, normal) for f in frames])
    # tangent-plane basis: e1 along the first curve's projected tangent
    e1 = tangents[0] - normal * (tangents[0] @ normal)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(normal, e1)
    angles = np.arctan2(tangents @ e2, tangents @ e1)
    if np.min(np.abs(np.sin(angles[:, None] - angles[None, :])) + np.eye(len(angles))) < 1e-3:
        raise DegenerateGeometry("two data curves have the same tangent direction at p")
    k1, k2, angle1, _ = principal_curvatures_from_normal_curvatures(kn, angles)
    d1 = np.cos(angle1) * e1 + np.sin(angle1) * e2
    d2 = np.cross(normal, d1)
    return LocalSurfaceGeometry(p, normal, k1, k2, d1, d2, frames, kn, oriented)
