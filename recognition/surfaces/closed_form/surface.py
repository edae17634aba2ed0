"""Closed-form surfaces: sigma(u, v) and f = 0 with analytic derivatives, and their curvatures.

A :class:`ClosedFormSurface` has a parametric form sigma(u, v) (for the lookup table of
principal curvatures, thesis Section 4.2.1) and an implicit form f = 0 (for the
point-to-surface distance of the superposition error (4.11)), each with analytic
derivatives.

Conventions as in :mod:`recognition.surfaces.local_geometry`: f > 0 outside the object
and the normal is the outward one (the normalised gradient of f); a normal curvature is
positive where the surface bends away from that normal (a sphere of radius r has
k1 = k2 = 1/r); k1 >= k2. Open patches (paraboloid, monkey saddle, crossed trough) are
the boundary of the solid above the graph, so their outside is the side below it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.errors import DegenerateGeometry
from recognition.rigid import cross

__all__ = [
    "EDGE_MARGIN",
    "ClosedFormSurface",
    "ImplicitTerms",
    "SigmaDerivatives",
    "implicit_principal_curvatures",
    "outward_normal",
    "principal_curvatures",
    "stack_columns",
]

Array = NDArray[np.float64]
ImplicitTerms = tuple[Array, Array | None, Array | None]
"""f (n,), grad f (n, 3) and the Hessian of f (n, 3, 3); the orders not asked for are None."""
Parameter = float | NDArray[np.float64]
"""A surface parameter u or v: a number or an array of them."""


def _given(value: Array | None) -> Array:
    """A term of :data:`ImplicitTerms` that was asked for."""
    assert value is not None
    return value


#: Fraction of a non-periodic parameter interval kept clear at each end when a search is
#: kept inside the domain (the ends may be singular: the poles of a sphere or an ellipsoid).
EDGE_MARGIN = 1.0e-6


@dataclass(frozen=True)
class SigmaDerivatives:
    """sigma(u, v) and its partial derivatives up to second order.

    Attributes
    ----------
    point, su, sv, suu, suv, svv : (..., 3) float
        sigma and its derivatives, model units per parameter unit (squared).
    """

    point: Array
    su: Array
    sv: Array
    suu: Array
    suv: Array
    svv: Array


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
    sigma_terms: Callable[[Array, Array], SigmaDerivatives] = field(repr=False)
    implicit_terms: Callable[[Array, int], ImplicitTerms] = field(repr=False)
    note: str = ""
    symmetries: tuple[Array, ...] = field(default=(), repr=False)

    def sigma(self, u: ArrayLike, v: ArrayLike) -> Array:
        """sigma(u, v), (..., 3)."""
        return self.sigma_terms(np.asarray(u, float), np.asarray(v, float)).point

    def sigma_derivatives(self, u: ArrayLike, v: ArrayLike) -> SigmaDerivatives:
        """sigma and its first and second partial derivatives at (u, v)."""
        return self.sigma_terms(np.asarray(u, float), np.asarray(v, float))

    def implicit(self, points: ArrayLike) -> Array:
        """f at (n, 3) points, (n,); the surface is f = 0, f > 0 outside."""
        return self.implicit_terms(np.atleast_2d(np.asarray(points, float)), 0)[0]

    def gradient(self, points: ArrayLike) -> Array:
        """grad f at (n, 3) points, (n, 3)."""
        return _given(self.implicit_terms(np.atleast_2d(np.asarray(points, float)), 1)[1])

    def hessian(self, points: ArrayLike) -> Array:
        """Hessian of f at (n, 3) points, (n, 3, 3)."""
        return _given(self.implicit_terms(np.atleast_2d(np.asarray(points, float)), 2)[2])

    def normal(self, u: ArrayLike, v: ArrayLike) -> Array:
        """Outward unit normal (4.10) at sigma(u, v), (..., 3)."""
        d = self.sigma_derivatives(u, v)
        return outward_normal(self, d, cross(d.su, d.sv))[0]

    def principal_curvatures(self, u: ArrayLike, v: ArrayLike) -> tuple[Array, Array]:
        """(k1, k2) at sigma(u, v) from the fundamental forms; see :func:`principal_curvatures`."""
        return principal_curvatures(self, u, v)

    def contain(self, u: Parameter, v: Parameter) -> tuple[Parameter, Parameter]:
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

    def closest_parameters(self, point: ArrayLike, u0: float, v0: float) -> tuple[float, float]:
        """(u, v) of the point of sigma nearest ``point`` (3,), by Gauss-Newton from (u0, v0)."""
        return _project(self, np.asarray(point, float), u0, v0)

    def symmetric_image(self, point: ArrayLike, estimate: ArrayLike) -> Array:
        """The image S estimate (S a symmetry or the identity) nearest ``point``, (3,)."""
        point, estimate = np.asarray(point, float), np.asarray(estimate, float)
        images = [estimate] + [S @ estimate for S in self.symmetries]
        return min(images, key=lambda q: float(np.linalg.norm(q - point)))

    def symmetric_distance(self, point: ArrayLike, estimate: ArrayLike) -> float:
        """min over the symmetries S (and the identity) of |S estimate - point|."""
        point = np.asarray(point, float)
        return float(np.linalg.norm(self.symmetric_image(point, estimate) - point))


def stack_columns(*columns: Parameter) -> Array:
    """The columns stacked along a last axis (broadcast together; scalars give a vector)."""
    shapes = {np.shape(c) for c in columns}
    if shapes == {()}:
        return np.array([float(c) for c in columns])
    if len(shapes) > 1:
        columns = np.broadcast_arrays(*columns)
    return np.stack(columns, axis=-1)


def outward_normal(
    surface: ClosedFormSurface, d: SigmaDerivatives, w: Array
) -> tuple[Array, Array]:
    """Unit vector of ``w`` (..., 3) signed to agree with grad f at sigma, and the sign (..., 1):
    with w = sigma_u x sigma_v, the outward normal of thesis Eq. (4.10)."""
    g = surface.gradient(d.point.reshape(-1, 3)).reshape(d.point.shape)
    sign = np.where(np.sum(w * g, axis=-1, keepdims=True) < 0, -1.0, 1.0)
    norm = np.linalg.norm(w, axis=-1, keepdims=True)
    if np.any(norm <= 0):
        raise DegenerateGeometry(
            f"{surface.name}: sigma_u x sigma_v vanishes (singular parameter point)"
        )
    return sign * w / norm, sign


def principal_curvatures(
    surface: ClosedFormSurface, u: ArrayLike, v: ArrayLike
) -> tuple[Array, Array]:
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
    n, _ = outward_normal(surface, d, cross(d.su, d.sv))
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


def implicit_principal_curvatures(
    surface: ClosedFormSurface, points: ArrayLike
) -> tuple[Array, Array]:
    """Principal curvatures of f = 0 at surface points from grad f and its Hessian.

    The shape operator is the Hessian of f restricted to the tangent plane, divided by
    |grad f| (positive for a convex surface with f > 0 outside); an independent check of
    :func:`principal_curvatures`.

    Returns
    -------
    k1, k2 : (n,) float
    """
    _, g_, H_ = surface.implicit_terms(np.atleast_2d(np.asarray(points, float)), 2)
    g, H = _given(g_), _given(H_)
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


def _project(
    surface: ClosedFormSurface, q: Array, u: float, v: float, iterations: int = 30
) -> tuple[float, float]:
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
