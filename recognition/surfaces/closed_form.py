"""Closed-form surface models: lookup tables and registration of data curves (thesis 4.2).

A :class:`ClosedFormSurface` has a parametric form sigma(u, v) (for the lookup table of
principal curvatures, Section 4.2.1) and an implicit form f = 0 (for the point-to-surface
distance of the superposition error (4.11)), each with analytic derivatives.

Conventions as in :mod:`recognition.surfaces.local_geometry`: f > 0 outside the object
and the normal is the outward one (the normalised gradient of f); a normal curvature is
positive where the surface bends away from that normal (a sphere of radius r has
k1 = k2 = 1/r); k1 >= k2. Open patches (paraboloid, monkey saddle, crossed trough) are
the boundary of the solid above the graph, so their outside is the side below it.

Registration (Section 4.2.2) places the data's common point p on sigma(u, v), aligns the
data normal with the model normal there and turns the curves by phi about it. The
superposition error E(u, v, phi) (4.11) is minimised from every candidate point of the
table lookup (4.7): phi is initialised by discretisation, bracketing and bisection
(4.2.2.1), then either by the thesis's steepest descent or (default) by Levenberg-
Marquardt on the residuals f / |grad f|, optionally followed by a Levenberg-Marquardt
refinement of all six degrees of freedom of the rigid motion.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from types import MappingProxyType

import numpy as np
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from recognition.errors import DegenerateGeometry, InvalidCurveData, InvalidModel
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.local_geometry import LocalSurfaceGeometry, local_surface_geometry

__all__ = [
    "ClosedFormModel",
    "ClosedFormRecognition",
    "ClosedFormSurface",
    "CurvatureLookup",
    "LocalSearch",
    "Optimizer",
    "Registration",
    "RegistrationConfig",
    "SearchStatus",
    "SigmaDerivatives",
    "candidate_rows",
    "circular_cylinder",
    "crossed_trough",
    "curvature_lookup",
    "data_geometry",
    "ellipsoid",
    "elliptic_cylinder",
    "elliptic_paraboloid",
    "fig_4_15_solids",
    "implicit_principal_curvatures",
    "initial_phi",
    "levenberg_marquardt",
    "local_coordinates",
    "model_frame",
    "monkey_saddle",
    "point_distance_residuals",
    "pose_from_parameters",
    "principal_curvatures",
    "recognize",
    "refine_rigid_motion",
    "register",
    "rigid_motion_residuals",
    "sphere",
    "steepest_descent",
    "superposition_error",
    "superposition_error_gradient",
    "superposition_residuals",
    "table_4_1_surfaces",
]

#: Fraction of a non-periodic parameter interval kept clear at each end when a search is
#: kept inside the domain (the ends may be singular: the poles of a sphere or an ellipsoid).
EDGE_MARGIN = 1.0e-6


# --- surfaces -----------------------------------------------------------------------------


@dataclass(frozen=True)
class SigmaDerivatives:
    """sigma(u, v) and its partial derivatives up to second order.

    Attributes
    ----------
    point, su, sv, suu, suv, svv : (..., 3) float
        sigma and its derivatives, model units per parameter unit (squared).
    """

    point: np.ndarray
    su: np.ndarray
    sv: np.ndarray
    suu: np.ndarray
    suv: np.ndarray
    svv: np.ndarray


@dataclass(frozen=True, eq=False)
class ClosedFormSurface:
    """A surface with a parametric and an implicit form and their analytic derivatives.

    Attributes
    ----------
    name : str
    parameters : Mapping[str, float]
        The family's shape parameters (e.g. ``a``, ``b``, ``c``), model units.
    domain : ((u_min, u_max), (v_min, v_max))
        Parameter domain of sigma covered by the lookup table.
    periodic : (bool, bool)
        Whether u, v wrap around their interval.
    sigma_terms : callable
        ``(u, v) -> SigmaDerivatives`` for broadcastable arrays u, v.
    implicit_terms : callable
        ``(points (n, 3), order) -> (f (n,), grad f (n, 3), Hessian of f (n, 3, 3))``,
        the derivatives above ``order`` left out (None); f > 0 outside.
    note : str
        How the closed form relates to the physical object (e.g. an infinite cylinder).
    symmetries : tuple of (3, 3) float
        Rotations about the origin, other than the identity, that map the solid onto
        itself: data registered at p or at S p are indistinguishable (continuous
        symmetries of spheres and cylinders are not listed).
    """

    name: str
    parameters: Mapping[str, float]
    domain: tuple[tuple[float, float], tuple[float, float]]
    periodic: tuple[bool, bool]
    sigma_terms: Callable[[np.ndarray, np.ndarray], SigmaDerivatives] = field(repr=False)
    implicit_terms: Callable[[np.ndarray, int], tuple] = field(repr=False)
    note: str = ""
    symmetries: tuple[np.ndarray, ...] = field(default=(), repr=False)

    def sigma(self, u, v) -> np.ndarray:
        """sigma(u, v), (..., 3)."""
        return self.sigma_terms(np.asarray(u, float), np.asarray(v, float)).point

    def sigma_derivatives(self, u, v) -> SigmaDerivatives:
        """sigma and its first and second partial derivatives at (u, v)."""
        return self.sigma_terms(np.asarray(u, float), np.asarray(v, float))

    def implicit(self, points) -> np.ndarray:
        """f at (n, 3) points, (n,); the surface is f = 0, f > 0 outside."""
        return self.implicit_terms(np.atleast_2d(np.asarray(points, float)), 0)[0]

    def gradient(self, points) -> np.ndarray:
        """grad f at (n, 3) points, (n, 3)."""
        return self.implicit_terms(np.atleast_2d(np.asarray(points, float)), 1)[1]

    def hessian(self, points) -> np.ndarray:
        """Hessian of f at (n, 3) points, (n, 3, 3)."""
        return self.implicit_terms(np.atleast_2d(np.asarray(points, float)), 2)[2]

    def normal(self, u, v) -> np.ndarray:
        """Outward unit normal (4.10) at sigma(u, v), (..., 3)."""
        d = self.sigma_derivatives(u, v)
        return _outward(self, d, _cross(d.su, d.sv))[0]

    def principal_curvatures(self, u, v):
        """(k1, k2) at sigma(u, v) from the fundamental forms; see :func:`principal_curvatures`."""
        return principal_curvatures(self, u, v)

    def contain(self, u, v):
        """(u, v) wrapped into the domain where periodic, clipped to it otherwise."""
        out = []
        for x, (lo, hi), periodic in zip((u, v), self.domain, self.periodic, strict=True):
            if periodic:
                x = lo + np.mod(x - lo, hi - lo)
            else:
                margin = EDGE_MARGIN * (hi - lo)
                x = np.clip(x, lo + margin, hi - margin)
            out.append(x)
        return out[0], out[1]

    def closest_parameters(self, point, u0: float, v0: float) -> tuple[float, float]:
        """(u, v) of the point of sigma nearest ``point``, by Gauss-Newton from (u0, v0)."""
        return _project(self, np.asarray(point, float), u0, v0)

    def symmetric_image(self, point, estimate) -> np.ndarray:
        """The image S estimate (S a symmetry or the identity) nearest ``point``, (3,)."""
        point, estimate = np.asarray(point, float), np.asarray(estimate, float)
        images = [estimate] + [S @ estimate for S in self.symmetries]
        return min(images, key=lambda q: float(np.linalg.norm(q - point)))

    def symmetric_distance(self, point, estimate) -> float:
        """min over the symmetries S (and the identity) of |S estimate - point|."""
        point = np.asarray(point, float)
        return float(np.linalg.norm(self.symmetric_image(point, estimate) - point))


def _positive(name: str, **values: float) -> dict[str, float]:
    for key, value in values.items():
        if not (np.isfinite(value) and value > 0):
            raise InvalidModel(f"{name}: parameter {key} must be finite and > 0, got {value}")
    return {k: float(v) for k, v in values.items()}


def _stack(*columns):
    shapes = {np.shape(c) for c in columns}
    if shapes == {()}:
        return np.array([float(c) for c in columns])
    if len(shapes) > 1:
        columns = np.broadcast_arrays(*columns)
    return np.stack(columns, axis=-1)


def _cross(a, b):
    """Cross product along the last axis (faster than numpy.cross for small arrays)."""
    if a.ndim == 1 and b.ndim == 1:
        a0, a1, a2 = a.tolist()
        b0, b1, b2 = b.tolist()
        return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def _rotations_about(axis: int, count: int) -> tuple[np.ndarray, ...]:
    """The ``count - 1`` non-trivial rotations by multiples of 2 pi / count about an axis."""
    return tuple(
        Rotation.from_rotvec(2 * np.pi * k / count * np.eye(3)[axis]).as_matrix()
        for k in range(1, count)
    )


def _quadric_terms(scales: np.ndarray, offset: float, linear_z: float = 0.0):
    """f = sum_i s_i x_i^2 - offset - linear_z z, with its gradient and Hessian."""

    hessian = np.diag(2.0 * scales)

    def terms(points, order=2):
        f = (points * points) @ scales - offset
        if linear_z:
            f -= linear_z * points[:, 2]
        if order < 1:
            return f, None, None
        g = 2.0 * points * scales
        g[:, 2] -= linear_z
        if order < 2:
            return f, g, None
        return f, g, np.broadcast_to(hessian, (points.shape[0], 3, 3))

    return terms


def ellipsoid(a: float = 1.0, b: float = 0.8, c: float = 0.5, name: str = "ellipsoid"):
    """x^2/a^2 + y^2/b^2 + z^2/c^2 = 1 (thesis Table 4.1).

    sigma = (a cos u sin v, b sin u sin v, c cos v), (u, v) in [0, 2 pi] x [0, pi].
    """
    p = _positive(name, a=a, b=b, c=c)
    a, b, c = p["a"], p["b"], p["c"]

    def sigma_terms(u, v):
        cu, su_, cv, sv_ = np.cos(u), np.sin(u), np.cos(v), np.sin(v)
        z = np.zeros(np.broadcast_shapes(np.shape(u), np.shape(v)))
        return SigmaDerivatives(
            _stack(a * cu * sv_, b * su_ * sv_, c * cv + z),
            _stack(-a * su_ * sv_, b * cu * sv_, z),
            _stack(a * cu * cv, b * su_ * cv, -c * sv_ + z),
            _stack(-a * cu * sv_, -b * su_ * sv_, z),
            _stack(-a * su_ * cv, b * cu * cv, z),
            _stack(-a * cu * sv_, -b * su_ * sv_, -c * cv + z),
        )

    return ClosedFormSurface(
        name,
        MappingProxyType(p),
        ((0.0, 2 * np.pi), (0.0, np.pi)),
        (True, False),
        sigma_terms,
        _quadric_terms(np.array([1 / a**2, 1 / b**2, 1 / c**2]), 1.0),
        symmetries=tuple(np.diag(d) for d in ((1, -1, -1), (-1, 1, -1), (-1, -1, 1))),
    )


def sphere(radius: float, name: str = "sphere"):
    """Sphere of radius ``radius`` about the origin (an ellipsoid with a = b = c)."""
    _positive(name, radius=radius)
    s = ellipsoid(radius, radius, radius, name)
    return replace(s, parameters=MappingProxyType({"radius": float(radius)}), symmetries=())


def elliptic_paraboloid(a: float = 1.5, b: float = 1.1, name: str = "elliptic_paraboloid"):
    """x^2/a^2 + y^2/b^2 = z (thesis Table 4.1); f = x^2/a^2 + y^2/b^2 - z.

    sigma = (a v cos u, b v sin u, v^2), (u, v) in [0, 2 pi] x [-1, 1] (every point is
    covered twice: (u, v) and (u + pi, -v)).
    """
    p = _positive(name, a=a, b=b)
    a, b = p["a"], p["b"]

    def sigma_terms(u, v):
        cu, su_ = np.cos(u), np.sin(u)
        z = np.zeros(np.broadcast_shapes(np.shape(u), np.shape(v)))
        return SigmaDerivatives(
            _stack(a * v * cu, b * v * su_, v**2 + z),
            _stack(-a * v * su_, b * v * cu, z),
            _stack(a * cu + 0 * v, b * su_ + 0 * v, 2 * v + z),
            _stack(-a * v * cu, -b * v * su_, z),
            _stack(-a * su_ + 0 * v, b * cu + 0 * v, z),
            _stack(z, z, 2.0 + z),
        )

    return ClosedFormSurface(
        name,
        MappingProxyType(p),
        ((0.0, 2 * np.pi), (-1.0, 1.0)),
        (True, False),
        sigma_terms,
        _quadric_terms(np.array([1 / a**2, 1 / b**2, 0.0]), 0.0, linear_z=1.0),
        symmetries=_rotations_about(2, 2),
    )


def _graph_surface(name: str, height, rotations: int) -> ClosedFormSurface:
    """The graph z = h(x, y) over [-1, 1]^2: sigma = (u, v, h(u, v)), f = h(x, y) - z.

    ``height(x, y)`` returns h and its partial derivatives (h, h_x, h_y, h_xx, h_xy,
    h_yy); the surface is symmetric under ``rotations`` turns about the z axis.
    """

    def sigma_terms(u, v):
        z = np.zeros(np.broadcast_shapes(np.shape(u), np.shape(v)))
        one = 1.0 + z
        h, hu, hv, huu, huv, hvv = height(u, v)
        return SigmaDerivatives(
            _stack(u + z, v + z, h + z),
            _stack(one, z, hu + z),
            _stack(z, one, hv + z),
            _stack(z, z, huu + z),
            _stack(z, z, huv + z),
            _stack(z, z, hvv + z),
        )

    def implicit_terms(points, order=2):
        x, y, zc = points.T
        h, hx, hy, hxx, hxy, hyy = height(x, y)
        f = h - zc
        if order < 1:
            return f, None, None
        g = np.empty_like(points)
        g[:, 0], g[:, 1], g[:, 2] = hx, hy, -1.0
        if order < 2:
            return f, g, None
        H = np.zeros((points.shape[0], 3, 3))
        H[:, 0, 0], H[:, 1, 1] = hxx, hyy
        H[:, 0, 1] = H[:, 1, 0] = hxy
        return f, g, H

    return ClosedFormSurface(
        name,
        MappingProxyType({}),
        ((-1.0, 1.0), (-1.0, 1.0)),
        (False, False),
        sigma_terms,
        implicit_terms,
        symmetries=_rotations_about(2, rotations),
    )


def monkey_saddle(name: str = "monkey_saddle"):
    """x^3 - 3 x y^2 = z (thesis Table 4.1); f = x^3 - 3 x y^2 - z.

    sigma = (u, v, u^3 - 3 u v^2), (u, v) in [-1, 1] x [-1, 1].
    """

    def height(x, y):
        return x**3 - 3 * x * y**2, 3 * x**2 - 3 * y**2, -6 * x * y, 6 * x, -6 * y, -6 * x

    return _graph_surface(name, height, rotations=3)


def crossed_trough(name: str = "crossed_trough"):
    """x^2 y^2 = z (thesis Table 4.1); f = x^2 y^2 - z.

    sigma = (u, v, u^2 v^2), (u, v) in [-1, 1] x [-1, 1].
    """

    def height(x, y):
        return x**2 * y**2, 2 * x * y**2, 2 * x**2 * y, 2 * y**2, 4 * x * y, 2 * x**2

    return _graph_surface(name, height, rotations=4)


def elliptic_cylinder(a: float, b: float, half_length: float, name: str = "elliptic_cylinder"):
    """x^2/a^2 + y^2/b^2 = 1 about the z axis; sigma = (a cos u, b sin u, v).

    The implicit form is the infinite cylinder; the table covers |v| <= ``half_length``.
    Registration ignores the end faces: the model is the lateral surface only.
    """
    p = _positive(name, a=a, b=b, half_length=half_length)
    a, b = p["a"], p["b"]

    def sigma_terms(u, v):
        cu, su_ = np.cos(u), np.sin(u)
        z = np.zeros(np.broadcast_shapes(np.shape(u), np.shape(v)))
        return SigmaDerivatives(
            _stack(a * cu + z, b * su_ + z, v + z),
            _stack(-a * su_ + z, b * cu + z, z),
            _stack(z, z, 1.0 + z),
            _stack(-a * cu + z, -b * su_ + z, z),
            _stack(z, z, z),
            _stack(z, z, z),
        )

    return ClosedFormSurface(
        name,
        MappingProxyType(p),
        ((0.0, 2 * np.pi), (-half_length, half_length)),
        (True, False),
        sigma_terms,
        _quadric_terms(np.array([1 / a**2, 1 / b**2, 0.0]), 1.0),
        note="infinite cylinder in implicit form (no end faces); table over |z| <= half_length",
        symmetries=tuple(np.diag(d) for d in ((1, -1, -1), (-1, 1, -1), (-1, -1, 1))),
    )


def circular_cylinder(radius: float, half_length: float, name: str = "cylinder"):
    """Circular cylinder of radius ``radius`` about the z axis (see :func:`elliptic_cylinder`)."""
    s = elliptic_cylinder(radius, radius, half_length, name)
    return replace(
        s,
        parameters=MappingProxyType({"radius": float(radius), "half_length": float(half_length)}),
    )


def table_4_1_surfaces() -> tuple[ClosedFormSurface, ...]:
    """The four surfaces of thesis Table 4.1 / Figs. 4.5-4.6 with the thesis's parameters."""
    return (
        ellipsoid(1.0, 0.8, 0.5),
        elliptic_paraboloid(1.5, 1.1),
        monkey_saddle(),
        crossed_trough(),
    )


def fig_4_15_solids(half_length_m: float = 0.05) -> tuple[ClosedFormSurface, ...]:
    """The four algebraic objects of thesis Fig. 4.15, in metres.

    Two circular cylinders of diameter 50.4 mm and 94 mm, an elliptic cylinder of
    semi-axes 50.8 mm x 31.75 mm, a sphere of radius 33 mm. Cylinders are infinite in
    implicit form and tabulated over |z| <= ``half_length_m``.
    """
    return (
        circular_cylinder(0.0252, half_length_m, "cylinder_1"),
        circular_cylinder(0.047, half_length_m, "cylinder_2"),
        elliptic_cylinder(0.0508, 0.03175, half_length_m, "elliptic_cylinder"),
        sphere(0.033, "sphere"),
    )


# --- curvatures -------------------------------------------------------------------------


def _outward(surface: ClosedFormSurface, d: SigmaDerivatives, w: np.ndarray):
    """Unit vector of ``w`` signed to agree with grad f at sigma, and the sign (..., 1)."""
    g = surface.implicit_terms(d.point.reshape(-1, 3), 1)[1].reshape(d.point.shape)
    sign = np.where(np.sum(w * g, axis=-1, keepdims=True) < 0, -1.0, 1.0)
    norm = np.linalg.norm(w, axis=-1, keepdims=True)
    if np.any(norm <= 0):
        raise DegenerateGeometry(
            f"{surface.name}: sigma_u x sigma_v vanishes (singular parameter point)"
        )
    return sign * w / norm, sign


def principal_curvatures(surface: ClosedFormSurface, u, v):
    """Principal curvatures from the fundamental forms, thesis Section 4.2.1.

    The eigenvalues of F_I^-1 F_II with n the outward normal (4.10), negated so that a
    convex surface has positive curvatures.

    Parameters
    ----------
    surface : ClosedFormSurface
    u, v : array_like
        Parameters (broadcast together), away from singular points of sigma.

    Returns
    -------
    k1, k2 : (...) float
        k1 >= k2, 1 / model units.
    """
    d = surface.sigma_derivatives(u, v)
    n, _ = _outward(surface, d, _cross(d.su, d.sv))
    E = np.sum(d.su * d.su, -1)
    F = np.sum(d.su * d.sv, -1)
    G = np.sum(d.sv * d.sv, -1)
    L = -np.sum(d.suu * n, -1)
    M = -np.sum(d.suv * n, -1)
    N = -np.sum(d.svv * n, -1)
    det = E * G - F * F
    mean = (L * G - 2 * M * F + N * E) / (2 * det)
    gauss = (L * N - M * M) / det
    root = np.sqrt(np.maximum(mean * mean - gauss, 0.0))
    return mean + root, mean - root


def implicit_principal_curvatures(surface: ClosedFormSurface, points):
    """Principal curvatures of f = 0 at surface points from grad f and its Hessian.

    The shape operator is the Hessian of f restricted to the tangent plane, divided by
    |grad f| (positive for a convex surface with f > 0 outside); an independent check of
    :func:`principal_curvatures`.

    Returns
    -------
    k1, k2 : (n,) float
    """
    _, g, H = surface.implicit_terms(np.atleast_2d(np.asarray(points, float)), 2)
    norm = np.linalg.norm(g, axis=1)
    n = g / norm[:, None]
    P = np.eye(3) - n[:, :, None] * n[:, None, :]
    S = P @ H @ P / norm[:, None, None]
    # S n = 0, so the characteristic polynomial is t (t^2 - trace t + m2): the principal
    # curvatures are the roots of the quadratic, m2 the sum of the 2 x 2 principal minors
    trace = np.trace(S, axis1=1, axis2=2)
    m2 = 0.5 * (trace**2 - np.trace(S @ S, axis1=1, axis2=2))
    root = np.sqrt(np.maximum(trace**2 / 4 - m2, 0.0))
    return trace / 2 + root, trace / 2 - root


# --- lookup table (4.7) -----------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class CurvatureLookup:
    """Principal curvatures on a uniform (u, v) grid with a (k1, k2) range query (4.7).

    Attributes
    ----------
    u, v : (m,) float
        Grid parameters (cell centres, so singular edges such as poles are avoided).
    points : (m, 3) float
        sigma(u, v), model units.
    k1, k2 : (m,) float
        Principal curvatures, 1 / model units.
    shape : (int, int)
        Grid size (n_u, n_v).
    """

    u: np.ndarray
    v: np.ndarray
    points: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    shape: tuple[int, int]
    _tree: cKDTree = field(init=False, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "_tree", cKDTree(np.column_stack([self.k1, self.k2])))

    def __len__(self) -> int:
        return self.u.size

    def query(self, k1: float, k2: float, delta: float) -> np.ndarray:
        """Rows with sqrt((k1 - k1_i)^2 + (k2 - k2_i)^2) < delta, thesis Eq. (4.7).

        Returns
        -------
        (r,) int
            Row indices, nearest in (k1, k2) first.
        """
        if np.isinf(delta):
            rows = np.arange(len(self))
        else:
            rows = np.asarray(self._tree.query_ball_point([k1, k2], r=delta), dtype=np.int64)
        dist = np.hypot(self.k1[rows] - k1, self.k2[rows] - k2)
        keep = dist < delta
        rows, dist = rows[keep], dist[keep]
        return rows[np.argsort(dist, kind="stable")]


def curvature_lookup(surface: ClosedFormSurface, n_u: int = 200, n_v: int = 100):
    """The lookup table of ``surface`` on an ``n_u`` x ``n_v`` grid of cell centres (4.2.1)."""
    if n_u < 2 or n_v < 2:
        raise InvalidModel(f"a lookup table needs at least a 2 x 2 grid, got {n_u} x {n_v}")
    (u0, u1), (v0, v1) = surface.domain
    u = u0 + (np.arange(n_u) + 0.5) * (u1 - u0) / n_u
    v = v0 + (np.arange(n_v) + 0.5) * (v1 - v0) / n_v
    uu, vv = (g.ravel() for g in np.meshgrid(u, v, indexing="ij"))
    k1, k2 = principal_curvatures(surface, uu, vv)
    return CurvatureLookup(uu, vv, surface.sigma(uu, vv), k1, k2, (n_u, n_v))


@dataclass(frozen=True, eq=False)
class ClosedFormModel:
    """A closed-form surface with its lookup table: one entry of a model database."""

    surface: ClosedFormSurface
    table: CurvatureLookup

    @classmethod
    def build(cls, surface: ClosedFormSurface, n_u: int = 200, n_v: int = 100):
        return cls(surface, curvature_lookup(surface, n_u, n_v))

    @property
    def name(self) -> str:
        return self.surface.name


def candidate_rows(
    table: CurvatureLookup,
    k1: float,
    k2: float,
    delta: float,
    separation: float,
    max_candidates: int,
    symmetries: Sequence[np.ndarray] = (),
) -> np.ndarray:
    """Candidate points of the table lookup (4.7), thinned out in space.

    Rows within ``delta`` of (k1, k2) are visited nearest first; a row is kept unless a
    kept row, or its image under one of the surface's ``symmetries`` (which would give
    the same registration), lies within ``separation`` (model units), until
    ``max_candidates`` are kept.
    """
    rows = table.query(k1, k2, delta)
    maps = [np.eye(3), *symmetries]
    kept: list[np.ndarray] = []
    out: list[int] = []
    for r in rows:
        q = table.points[r]
        if kept and np.min(np.linalg.norm(np.concatenate(kept) - q, axis=1)) < separation:
            continue
        kept.append(np.array([S @ q for S in maps]))
        out.append(int(r))
        if len(out) == max_candidates:
            break
    return np.array(out, dtype=np.int64)


# --- superposition error (4.11) -----------------------------------------------------------


def _normalised(w, w_u, w_v):
    """w / |w| and its derivatives given those of w (vectors along the last axis)."""
    norm = np.linalg.norm(w)
    e = w / norm
    return e, (w_u - e * (e @ w_u)) / norm, (w_v - e * (e @ w_v)) / norm


def model_frame(surface: ClosedFormSurface, u: float, v: float):
    """The model's local frame (d1, d2, n) at sigma(u, v) and its parameter derivatives.

    d1 = sigma_u / |sigma_u|, n the outward normal (4.10), d2 = n x d1, so that
    d1 x d2 = n (thesis Section 4.2.2).

    Returns
    -------
    point : (3,) float
        sigma(u, v).
    F, F_u, F_v : (3, 3) float
        Columns (d1, d2, n) and their derivatives with respect to u and v.
    s_u, s_v : (3,) float
        sigma_u, sigma_v.
    """
    d = surface.sigma_derivatives(float(u), float(v))
    w = _cross(d.su, d.sv)
    if not np.linalg.norm(w) > 0 or not np.linalg.norm(d.su) > 0:
        raise DegenerateGeometry(f"{surface.name}: singular parameter point ({u:g}, {v:g})")
    _, sign = _outward(surface, d, w)
    sign = float(sign[0])
    n, n_u, n_v = _normalised(
        sign * w,
        sign * (_cross(d.suu, d.sv) + _cross(d.su, d.suv)),
        sign * (_cross(d.suv, d.sv) + _cross(d.su, d.svv)),
    )
    d1, d1_u, d1_v = _normalised(d.su, d.suu, d.suv)
    d2 = _cross(n, d1)
    d2_u = _cross(n_u, d1) + _cross(n, d1_u)
    d2_v = _cross(n_v, d1) + _cross(n, d1_v)
    F = np.column_stack([d1, d2, n])
    F_u = np.column_stack([d1_u, d2_u, n_u])
    F_v = np.column_stack([d1_v, d2_v, n_v])
    return d.point, F, F_u, F_v, d.su, d.sv


def _rz(phi):
    c, s = np.cos(phi), np.sin(phi)
    R = np.zeros((*np.shape(phi), 3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 1, 0], R[..., 1, 1], R[..., 2, 2] = c, -s, s, c, 1.0
    dR = np.zeros_like(R)
    dR[..., 0, 0], dR[..., 0, 1], dR[..., 1, 0], dR[..., 1, 1] = -s, -c, c, -s
    return R, dR


def local_coordinates(geometry: LocalSurfaceGeometry, points: np.ndarray) -> np.ndarray:
    """Data points in the local frame (t1, t2, N) at p, thesis Section 4.2.2.

    Returns
    -------
    (n, 3) float
        ``(t1 t2 N)^T (x_i - p)`` with (t1, t2, N) = (d1, d2, N) of ``geometry``.
    """
    return (np.asarray(points, float) - geometry.point) @ geometry.frame


def pose_from_parameters(
    surface: ClosedFormSurface, geometry: LocalSurfaceGeometry, u: float, v: float, phi: float
) -> np.ndarray:
    """T_model_from_data (4, 4) that puts p on sigma(u, v) turned by phi (Section 4.2.2)."""
    q, F, *_ = model_frame(surface, u, v)
    R = F @ _rz(phi)[0] @ geometry.frame.T
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = q - R @ geometry.point
    return T


def point_distance_residuals(surface: ClosedFormSurface, points: np.ndarray):
    """First-order signed distances f / |grad f| (4.11) and their gradients.

    Returns
    -------
    r : (n,) float
        Signed distance estimates, model units (positive outside).
    dr : (n, 3) float
        d r / d point = grad f / |grad f| - f H grad f / |grad f|^3.
    """
    f, g, H = surface.implicit_terms(points, 2)
    norm = np.linalg.norm(g, axis=1)
    norm = np.maximum(norm, 1e-300)
    r = f / norm
    Hg = (H @ g[:, :, None])[:, :, 0]
    dr = g / norm[:, None] - (f / norm**3)[:, None] * Hg
    return r, dr


def superposition_residuals(
    surface: ClosedFormSurface, local_points: np.ndarray, u: float, v: float, phi: float
):
    """Residuals f / |grad f| of the transformed data points and their Jacobian.

    Parameters
    ----------
    surface : ClosedFormSurface
    local_points : (n, 3) float
        Data points in the local frame at p (:func:`local_coordinates`).
    u, v, phi : float
        Location of p on the model and the turn about the normal, radians for phi.

    Returns
    -------
    r : (n,) float
        Signed first-order distances of the points x''_i to the surface.
    J : (n, 3) float
        d r / d (u, v, phi).
    """
    q, F, F_u, F_v, s_u, s_v = model_frame(surface, u, v)
    Rz, dRz = _rz(float(phi))
    a = local_points @ Rz.T
    y = a @ F.T + q
    r, dr = point_distance_residuals(surface, y)
    dy_du = a @ F_u.T + s_u
    dy_dv = a @ F_v.T + s_v
    dy_dphi = local_points @ (F @ dRz).T
    J = np.column_stack([np.sum(dr * dy_du, 1), np.sum(dr * dy_dv, 1), np.sum(dr * dy_dphi, 1)])
    return r, J


def _phi_terms(surface: ClosedFormSurface, local_points: np.ndarray, u: float, v: float):
    """``phi (m,) -> (E (m,), E_phi (m,))`` at a fixed (u, v), Eq. (4.11)."""
    q, F, *_ = model_frame(surface, u, v)
    n = local_points.shape[0]

    def terms(phi):
        phi = np.atleast_1d(np.asarray(phi, float))
        Rz, dRz = _rz(phi)  # (m, 3, 3)
        FR = F @ Rz
        y = local_points @ FR.transpose(0, 2, 1) + q
        dy = local_points @ (F @ dRz).transpose(0, 2, 1)
        r, dr = point_distance_residuals(surface, y.reshape(-1, 3))
        r = r.reshape(phi.size, n)
        slope = np.sum(dr.reshape(phi.size, n, 3) * dy, axis=2)
        return np.abs(r).mean(axis=1), np.sum(np.sign(r) * slope, axis=1) / n

    return terms


def superposition_error(
    surface: ClosedFormSurface, local_points: np.ndarray, u: float, v: float, phi
):
    """Superposition error E(u, v, phi), thesis Eq. (4.11).

    ``phi`` may be an array: E is then evaluated for every angle, same shape.
    """
    phi_arr = np.asarray(phi, float)
    E = _phi_terms(surface, local_points, u, v)(phi_arr.reshape(-1))[0]
    return float(E[0]) if phi_arr.ndim == 0 else E.reshape(phi_arr.shape)


def superposition_error_gradient(
    surface: ClosedFormSurface, local_points: np.ndarray, u: float, v: float, phi: float
):
    """E (4.11) and its gradient (E_u, E_v, E_phi) (Section 4.2.2.1).

    Returns
    -------
    E : float
    gradient : (3,) float
        Where a residual is exactly zero its |.| contributes 0 (a subgradient).
    """
    r, J = superposition_residuals(surface, local_points, u, v, phi)
    return float(np.abs(r).mean()), np.sign(r) @ J / r.size


def initial_phi(
    surface: ClosedFormSurface,
    local_points: np.ndarray,
    u: float,
    v: float,
    samples: int = 72,
    bisection_steps: int = 24,
):
    """phi minimising E(u, v, .) by discretisation, bracketing and bisection (4.2.2.1).

    [0, 2 pi) is sampled at ``samples`` angles; every discrete local minimum brackets a
    minimum between its neighbours, in which the sign change of E_phi is bisected (all
    brackets at once). The best of these minima is returned.

    Returns
    -------
    phi : float
        Radians in [0, 2 pi).
    E : float
        E(u, v, phi).
    """
    terms = _phi_terms(surface, local_points, u, v)
    step = 2 * np.pi / samples
    grid = step * np.arange(samples)
    E, _ = terms(grid)
    minima = np.flatnonzero((E <= np.roll(E, 1)) & (E <= np.roll(E, -1)))
    lo, hi = grid[minima] - step, grid[minima] + step
    for _ in range(bisection_steps):
        mid = 0.5 * (lo + hi)
        down = terms(mid)[1] < 0
        lo, hi = np.where(down, mid, lo), np.where(down, hi, mid)
    phi = np.concatenate([grid[minima], 0.5 * (lo + hi)])
    E_phi, _ = terms(phi)
    best = int(np.argmin(E_phi))
    return float(np.mod(phi[best], 2 * np.pi)), float(E_phi[best])


# --- local search -------------------------------------------------------------------------


class SearchStatus(enum.Enum):
    """How a local search or a registration ended."""

    CONVERGED = "converged"
    """The step or the decrease of the cost fell below the tolerance."""
    NO_PROGRESS = "no_progress"
    """No step along the search direction decreased the cost any further."""
    MAX_ITERATIONS = "max_iterations"
    """The iteration limit was reached first."""
    REJECTED_AT_LOOKUP = "rejected_at_lookup"
    """The table lookup (4.7) found no candidate point: the model was not searched."""


class Optimizer(enum.Enum):
    """Local search from a candidate point."""

    LEVENBERG_MARQUARDT = "levenberg_marquardt"
    """Levenberg-Marquardt on the residuals f / |grad f| over (u, v, phi) (default)."""
    STEEPEST_DESCENT = "steepest_descent"
    """The thesis's steepest descent on E(u, v, phi) (4.11), backtracking line search."""


@dataclass(frozen=True)
class LocalSearch:
    """Result of one local search (over (u, v, phi), or over a rigid motion).

    Attributes
    ----------
    solution : (k,) float
        Final parameters: (u, v, phi), or a rigid-motion increment for 6 DOF.
    cost : float
        E (4.11) at the solution, model units.
    iterations : int
    status : SearchStatus
    trace : (iterations + 1,) float
        E after every iteration, starting point first.
    """

    solution: np.ndarray
    cost: float
    iterations: int
    status: SearchStatus
    trace: np.ndarray


def _wrap(surface, x):
    u, v = surface.contain(x[0], x[1])
    return np.array([u, v, np.mod(x[2], 2 * np.pi)])


def _solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Least-norm solution of the symmetric system A x = b, ignoring directions whose
    eigenvalue is below 1e-10 of the largest (exact symmetries of the model)."""
    w, V = np.linalg.eigh(A)
    keep = w > 1e-10 * max(w[-1], 1e-300)
    return V[:, keep] @ ((V[:, keep].T @ b) / w[keep])


def _lm_loop(fun, x0, retract, blocked, max_iterations, tolerance):
    """Levenberg-Marquardt with Marquardt's diagonal scaling.

    ``fun(x) -> (r, J)``; ``retract(x, step) -> x_new``; ``blocked(x, step) -> mask`` of
    components that sit on a bound and would leave it (they are held fixed: an active
    set). Stops when the relative decrease of sum r^2 falls below ``tolerance``, when the
    step is negligible, or when no damping gives a decrease.
    """
    x = x0
    r, J = fun(x)
    cost = r @ r
    trace = [float(np.abs(r).mean())]
    lam = 1e-3
    status = SearchStatus.MAX_ITERATIONS
    it = 0
    for _ in range(max_iterations):
        it += 1
        A, g = J.T @ J, J.T @ r
        D = np.diag(A).copy()
        accepted = False
        step = np.zeros_like(g)
        while lam < 1e12:
            step = -_solve(A + lam * np.diag(D), g)
            held = blocked(x, step)
            if np.any(held):
                free = ~held
                step = np.zeros_like(g)
                if np.any(free):
                    Af = A[np.ix_(free, free)] + lam * np.diag(D[free])
                    step[free] = -_solve(Af, g[free])
            x_new = retract(x, step)
            r_new, J_new = fun(x_new)
            cost_new = r_new @ r_new
            if cost_new < cost:
                accepted = True
                break
            lam *= 10
        if not accepted:
            status = SearchStatus.CONVERGED
            trace.append(trace[-1])
            break
        # large residuals (a wrong model) make J^T J overestimate the curvature of the
        # cost and the steps too short: extend an accepted step while the cost decreases
        scale = 1.0
        while scale < 1024:
            x_far = retract(x, 2 * scale * step)
            r_far, J_far = fun(x_far)
            cost_far = r_far @ r_far
            if not cost_far < cost_new:
                break
            x_new, r_new, J_new, cost_new, scale = x_far, r_far, J_far, cost_far, 2 * scale
        decrease = cost - cost_new
        x, r, J, cost = x_new, r_new, J_new, cost_new
        trace.append(float(np.abs(r).mean()))
        lam = max(lam / 10, 1e-12)
        if decrease <= tolerance * cost or np.linalg.norm(step) <= 1e-12:
            status = SearchStatus.CONVERGED
            break
    return x, it, status, np.array(trace)


def levenberg_marquardt(
    surface: ClosedFormSurface,
    local_points: np.ndarray,
    x0,
    max_iterations: int = 100,
    tolerance: float = 1e-10,
) -> LocalSearch:
    """Minimise sum r_i^2 over (u, v, phi), r_i = f / |grad f| of (4.11), by Levenberg-Marquardt.

    Marquardt's diagonal scaling makes the step independent of the units of u, v and
    phi; (u, v) stay in the domain (wrapped where periodic; a parameter on an edge of
    the domain is held there while the step would take it out). ``cost`` is E (4.11)
    at the end; ``tolerance`` is the relative decrease of sum r_i^2 at which it stops.
    """
    (u0, u1), (v0, v1) = surface.domain
    margin = EDGE_MARGIN * np.array([u1 - u0, v1 - v0])
    lo = np.array([u0, v0]) + margin
    hi = np.array([u1, v1]) - margin
    bounded = ~np.array(surface.periodic)

    def blocked(x, step):
        out = np.zeros(3, bool)
        out[:2] = bounded & (((x[:2] <= lo) & (step[:2] < 0)) | ((x[:2] >= hi) & (step[:2] > 0)))
        return out

    x, it, status, trace = _lm_loop(
        lambda x: superposition_residuals(surface, local_points, *x),
        _wrap(surface, np.asarray(x0, float)),
        lambda x, step: _wrap(surface, x + step),
        blocked,
        max_iterations,
        tolerance,
    )
    return LocalSearch(x, float(trace[-1]), it, status, trace)


def _line_minimum(fun, f0: float, t0: float, iterations: int = 40):
    """Minimise ``fun(t)`` over t > 0 by bracketing from ``t0`` and golden-section search.

    Returns (t, f(t)); t = 0 if no tried step decreases f below ``f0``.
    """
    a, fa = 0.0, f0
    b, fb = t0, fun(t0)
    while fb >= fa and b > 1e-12 * t0:  # shrink until the first step decreases f
        b *= 0.25
        fb = fun(b)
    if fb >= fa:
        return 0.0, f0
    c, fc = 2.0 * b, fun(2.0 * b)
    while fc < fb:  # grow until f increases: [a, c] brackets a minimum at b
        a, b, fb = b, c, fc
        c, fc = 2.0 * c, fun(2.0 * c)
    golden = 0.5 * (np.sqrt(5.0) - 1.0)
    x1, x2 = c - golden * (c - a), a + golden * (c - a)
    f1, f2 = fun(x1), fun(x2)
    for _ in range(iterations):
        if f1 < f2:
            c, x2, f2 = x2, x1, f1
            x1 = c - golden * (c - a)
            f1 = fun(x1)
        else:
            a, x1, f1 = x1, x2, f2
            x2 = a + golden * (c - a)
            f2 = fun(x2)
        if c - a <= 1e-6 * (c + a):
            break
    best = min(((fb, b), (f1, x1), (f2, x2)))
    return best[1], best[0]


def steepest_descent(
    surface: ClosedFormSurface,
    local_points: np.ndarray,
    x0,
    max_iterations: int = 2000,
    tolerance: float = 1e-10,
) -> LocalSearch:
    """The thesis's steepest descent on E(u, v, phi) (4.11), Section 4.2.2.2.

    Each iteration minimises E along -grad E (bracketing and golden-section search) and
    the search stops when no step along it decreases E ("until no further minimization
    is possible") or E decreases by less than ``tolerance`` relative.
    """
    x = _wrap(surface, np.asarray(x0, float))
    E, grad = superposition_error_gradient(surface, local_points, *x)
    trace = [E]
    t = 1e-2 / max(np.linalg.norm(grad), 1e-300)
    status = SearchStatus.MAX_ITERATIONS
    it = 0
    for _ in range(max_iterations):
        it += 1
        if not np.linalg.norm(grad) > 0:
            status = SearchStatus.CONVERGED
            trace.append(E)
            break
        t, E_new = _line_minimum(
            lambda step, x=x, d=-grad: superposition_error(
                surface, local_points, *_wrap(surface, x + step * d)
            ),
            E,
            t,
        )
        if t == 0.0:
            status = SearchStatus.CONVERGED
            trace.append(E)
            break
        decrease = E - E_new
        x = _wrap(surface, x - t * grad)
        E, grad = superposition_error_gradient(surface, local_points, *x)
        trace.append(E)
        if decrease <= tolerance * E:
            status = SearchStatus.CONVERGED
            break
    return LocalSearch(x, trace[-1], it, status, np.array(trace))


def _skew(w):
    out = np.zeros((*w.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -w[..., 2], w[..., 1]
    out[..., 1, 0], out[..., 1, 2] = w[..., 2], -w[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -w[..., 1], w[..., 0]
    return out


def rigid_motion_residuals(
    surface: ClosedFormSurface, local_points: np.ndarray, R: np.ndarray, c: np.ndarray
):
    """Residuals f / |grad f| of the points ``R x_i + c`` and their Jacobian.

    Parameters
    ----------
    local_points : (n, 3) float
        Data points in the local frame at p.
    R : (3, 3) float
        Rotation from the local frame to the model frame.
    c : (3,) float
        Where p lands, model frame.

    Returns
    -------
    r : (n,) float
    J : (n, 6) float
        d r / d (omega, dc) for the update ``R <- exp([omega]x) R``, ``c <- c + dc``.
    """
    a = local_points @ np.asarray(R, float).T
    r, dr = point_distance_residuals(surface, a + c)
    return r, np.concatenate([np.einsum("ni,nij->nj", dr, -_skew(a)), dr], axis=1)


def refine_rigid_motion(
    surface: ClosedFormSurface,
    local_points: np.ndarray,
    R0: np.ndarray,
    c0: np.ndarray,
    max_iterations: int = 50,
    tolerance: float = 1e-10,
):
    """Levenberg-Marquardt over all six degrees of freedom of the data's rigid motion.

    The data points in the local frame at p are placed at ``y_i = R x_i + c``; the
    increment (omega, dc) updates ``R <- exp([omega]x) R``, ``c <- c + dc`` (rotation
    about the placed p, which keeps the problem well conditioned).

    Returns
    -------
    R : (3, 3) float
    c : (3,) float
        Where p lands, model frame.
    search : LocalSearch
        ``solution`` is the total increment (rotation vector, translation).
    """

    def residuals(x):
        return rigid_motion_residuals(surface, local_points, x[0], x[1])

    def retract(x, step):
        R, c, total = x
        return Rotation.from_rotvec(step[:3]).as_matrix() @ R, c + step[3:], total + step

    (R, c, total), it, status, trace = _lm_loop(
        residuals,
        (np.array(R0, float), np.array(c0, float), np.zeros(6)),
        retract,
        lambda x, step: np.zeros(6, bool),
        max_iterations,
        tolerance,
    )
    return R, c, LocalSearch(total, float(trace[-1]), it, status, trace)


def _project(surface: ClosedFormSurface, q: np.ndarray, u: float, v: float, iterations=30):
    """(u, v) of the point of sigma nearest q, by Gauss-Newton from (u, v)."""
    x = np.array(surface.contain(u, v), float)
    for _ in range(iterations):
        d = surface.sigma_derivatives(*x)
        J = np.column_stack([d.su, d.sv])
        step, *_ = np.linalg.lstsq(J, q - d.point, rcond=None)
        x = np.array(surface.contain(*(x + step)), float)
        if np.linalg.norm(step) < 1e-13 * (1 + np.linalg.norm(x)):
            break
    return float(x[0]), float(x[1])


# --- registration and recognition ---------------------------------------------------------


@dataclass(frozen=True)
class RegistrationConfig:
    """Settings of the registration of data curves onto a closed-form model (4.1.2, 4.2.2).

    Attributes
    ----------
    delta : float
        Table lookup tolerance of (4.7), 1 / model units (``inf``: no rejection). The
        default is the thesis's free-form tolerance 0.03 1/mm = 30 1/m; the unit-free
        Table 4.1 surfaces need their own (0.1 in the reproduction).
    max_candidates : int
        Candidate points kept after thinning the lookup result; phi is initialised at
        each (4.2.2.1).
    local_searches : int
        Local searches, from the candidates of least initial error E(u, v, phi_0).
    candidate_separation : float
        Smallest distance between two candidates, as a fraction of the data's radius
        (largest distance of a data point from p).
    phi_samples, bisection_steps : int
        Discretisation of [0, 2 pi) and bisection steps of the phi initialisation.
    optimizer : Optimizer
    rigid_refinement : bool
        Follow the best (u, v, phi) search by a six-degree-of-freedom refinement.
    max_iterations : int
        Per local search (the steepest descent gets 20 times as many).
    tolerance : float
        Relative decrease of the squared residuals (or of E) at which a search stops.
    fit_half_length, fit_degree
        :func:`~recognition.surfaces.local_geometry.local_surface_geometry` settings;
        the half length is in the data's units (default 6 mm for data in metres).
    fit_max_turn : float or None
        Largest angle (radians) a data curve may turn over the fit window: on tightly
        curved data the window shrinks to ``fit_max_turn / kappa`` (see
        :func:`data_geometry`). None keeps ``fit_half_length``.
    """

    delta: float = 30.0
    max_candidates: int = 24
    local_searches: int = 6
    candidate_separation: float = 0.15
    phi_samples: int = 72
    bisection_steps: int = 24
    optimizer: Optimizer = Optimizer.LEVENBERG_MARQUARDT
    rigid_refinement: bool = True
    max_iterations: int = 100
    tolerance: float = 1e-10
    fit_half_length: float = 6.0e-3
    fit_degree: int = 4
    fit_max_turn: float | None = 0.5


@dataclass(frozen=True)
class Registration:
    """Registration of data curves onto one model (thesis Eq. (4.12)).

    Attributes
    ----------
    model : str
    error : float
        Registration error: E (4.11) at the best local minimum, model units; ``inf`` if
        the table lookup found no candidate.
    u, v, phi : float
        Location of p on the model and the turn about the normal (radians); NaN if rejected.
    T_model_from_data : (4, 4) float
        Rigid motion taking the data onto the model (NaN if rejected).
    location : (3,) float
        Estimate p* of p on the model, sigma(u, v).
    iterations : int
        Iterations of the winning local search (plus the rigid refinement).
    status : SearchStatus
    candidates : (m, 2) float
        (u, v) of the candidate points searched from (the ``local_searches`` of least
        initial error among those of the table lookup), least initial error first.
    searches : tuple of LocalSearch
        One per candidate, in the order of ``candidates``.
    normal_flipped : bool
        True when the winning data normal is the opposite of the estimated one (only
        tried when the data carry no approach direction).
    """

    model: str
    error: float
    u: float
    v: float
    phi: float
    T_model_from_data: np.ndarray
    location: np.ndarray
    iterations: int
    status: SearchStatus
    candidates: np.ndarray = field(repr=False)
    searches: tuple[LocalSearch, ...] = field(repr=False)
    normal_flipped: bool = False

    @property
    def rejected(self) -> bool:
        return self.status is SearchStatus.REJECTED_AT_LOOKUP


def _rejected(model: str) -> Registration:
    nan = float("nan")
    return Registration(
        model,
        float("inf"),
        nan,
        nan,
        nan,
        np.full((4, 4), nan),
        np.full(3, nan),
        0,
        SearchStatus.REJECTED_AT_LOOKUP,
        np.zeros((0, 2)),
        (),
    )


def _register_oriented(
    geometry: LocalSurfaceGeometry,
    points: np.ndarray,
    model: ClosedFormModel,
    config: RegistrationConfig,
) -> Registration:
    surface, table = model.surface, model.table
    X = local_coordinates(geometry, points)
    radius = float(np.max(np.linalg.norm(X, axis=1)))
    rows = candidate_rows(
        table,
        geometry.k1,
        geometry.k2,
        config.delta,
        config.candidate_separation * radius,
        config.max_candidates,
        surface.symmetries,
    )
    if rows.size == 0:
        return _rejected(surface.name)
    starts = []
    for row in rows:
        u0, v0 = float(table.u[row]), float(table.v[row])
        phi0, E0 = initial_phi(surface, X, u0, v0, config.phi_samples, config.bisection_steps)
        starts.append((E0, u0, v0, phi0))
    starts.sort(key=lambda start: start[0])
    starts = starts[: config.local_searches]
    searches = []
    for _, u0, v0, phi0 in starts:
        if config.optimizer is Optimizer.LEVENBERG_MARQUARDT:
            s = levenberg_marquardt(
                surface, X, (u0, v0, phi0), config.max_iterations, config.tolerance
            )
        else:
            s = steepest_descent(
                surface, X, (u0, v0, phi0), 20 * config.max_iterations, config.tolerance
            )
        searches.append(s)
    best = min(searches, key=lambda s: s.cost)
    u, v, phi = (float(x) for x in best.solution)
    T = pose_from_parameters(surface, geometry, u, v, phi)
    error, iterations, status = best.cost, best.iterations, best.status
    if config.rigid_refinement:
        _, F, *_ = model_frame(surface, u, v)
        R0 = F @ _rz(phi)[0]
        R, c, rigid = refine_rigid_motion(
            surface, X, R0, surface.sigma(u, v), config.max_iterations, config.tolerance
        )
        u_r, v_r = _project(surface, c, u, v)
        on_patch = np.linalg.norm(surface.sigma(u_r, v_r) - c) <= 0.05 * radius
        if rigid.cost <= error and on_patch:
            u, v = u_r, v_r
            _, F, *_ = model_frame(surface, u, v)
            M = F.T @ R
            phi = float(np.mod(np.arctan2(M[1, 0], M[0, 0]), 2 * np.pi))
            T = np.eye(4)
            T[:3, :3] = R @ geometry.frame.T
            T[:3, 3] = c - T[:3, :3] @ geometry.point
            error, iterations, status = rigid.cost, iterations + rigid.iterations, rigid.status
    return Registration(
        surface.name,
        float(error),
        u,
        v,
        phi,
        T,
        surface.sigma(u, v),
        iterations,
        status,
        np.array([start[1:3] for start in starts]),
        tuple(searches),
    )


def data_geometry(
    curves: DataCurves, config: RegistrationConfig = RegistrationConfig()
) -> LocalSurfaceGeometry:
    """Normal (4.1) and principal curvatures (4.2)-(4.6) at the curves' common point.

    :func:`~recognition.surfaces.local_geometry.local_surface_geometry` over
    ``config.fit_half_length``; if a data curve turns by more than ``config.fit_max_turn``
    over that window (curvature kappa), the fit is repeated over ``fit_max_turn / kappa``,
    where a polynomial y(x) still follows the curve closely.
    """
    half = config.fit_half_length
    geometry = local_surface_geometry(curves, half_length_m=half, degree=config.fit_degree)
    if config.fit_max_turn is not None:
        kappa = max(f.curvature for f in geometry.frames)
        if kappa * half > config.fit_max_turn:
            geometry = local_surface_geometry(
                curves, half_length_m=config.fit_max_turn / kappa, degree=config.fit_degree
            )
    return geometry


def register(
    curves: DataCurves,
    model: ClosedFormModel,
    config: RegistrationConfig = RegistrationConfig(),
    geometry: LocalSurfaceGeometry | None = None,
) -> Registration:
    """Register data curves onto a closed-form model, thesis Section 4.2.2.2.

    Estimates the normal and principal curvatures at p (4.1)-(4.6) (unless ``geometry``
    is given), looks up candidate points (4.7), initialises phi at each, runs the local
    search and keeps the least error (4.12). Without an approach direction in the data
    both orientations of the normal are tried.
    """
    if geometry is None:
        geometry = data_geometry(curves, config)
    points = curves.points
    result = _register_oriented(geometry, points, model, config)
    if not geometry.oriented:
        other = _register_oriented(geometry.flipped(), points, model, config)
        if other.error < result.error:
            result = replace(other, normal_flipped=True)
    return result


@dataclass(frozen=True)
class ClosedFormRecognition:
    """Recognition over a set of closed-form models, thesis Eq. (4.9).

    Attributes
    ----------
    name : str or None
        The model of least registration error; None if every model was rejected.
    ranking : tuple of (str, float)
        (model, registration error) ascending; rejected models have ``inf``.
    registrations : Mapping[str, Registration]
    """

    name: str | None
    ranking: tuple[tuple[str, float], ...]
    registrations: Mapping[str, Registration] = field(repr=False)

    @property
    def best(self) -> Registration | None:
        return None if self.name is None else self.registrations[self.name]

    @property
    def pose(self) -> np.ndarray | None:
        """T_model_from_data (4, 4) on the recognised model."""
        return None if self.best is None else self.best.T_model_from_data

    @property
    def location(self) -> np.ndarray | None:
        """Estimate of p on the recognised model, (3,)."""
        return None if self.best is None else self.best.location

    @property
    def decided_at_lookup(self) -> bool:
        """True when every other model was rejected at table lookup."""
        return self.name is not None and all(
            r.rejected for n, r in self.registrations.items() if n != self.name
        )


def recognize(
    curves: DataCurves,
    models: Sequence[ClosedFormModel],
    config: RegistrationConfig = RegistrationConfig(),
) -> ClosedFormRecognition:
    """Register the curves onto every model and pick the least error, thesis Eq. (4.9)."""
    if len(models) == 0:
        raise InvalidCurveData("recognition needs at least one model")
    names = [m.name for m in models]
    if len(set(names)) != len(names):
        raise InvalidModel(f"model names must be unique, got {names}")
    geometry = data_geometry(curves, config)
    registrations = {m.name: register(curves, m, config, geometry) for m in models}
    ranking = tuple(sorted(((n, r.error) for n, r in registrations.items()), key=lambda t: t[1]))
    name = ranking[0][0] if np.isfinite(ranking[0][1]) else None
    return ClosedFormRecognition(name, ranking, MappingProxyType(registrations))
