"""Canonical curve families of Chapter 3 with exact local geometry.

Each family is a planar curve ``alpha(t) = (x(t), y(t))`` in the canonical form the
thesis reduces it to (Sections 3.2.1-3.2.2). Curvature and its arc-length derivative
are evaluated exactly from the parametric derivatives by thesis Eqs. (3.1)-(3.2), for
traversal in the direction of increasing ``t``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum

import numpy as np
from numpy.typing import ArrayLike

from recognition.errors import InvalidCurveData

__all__ = [
    "N_PARAMETERS",
    "SLOPE_CLASSES",
    "TREE_CLASSES",
    "CanonicalCurve",
    "CurveKind",
    "canonical_derivatives",
    "curvature",
    "curvature_derivative",
    "tangent_angle",
]


class CurveKind(StrEnum):
    """Curve classes of the recognition tree (thesis Fig. 3.4)."""

    PARABOLA = "parabola"
    ELLIPSE = "ellipse"
    HYPERBOLA = "hyperbola"
    CUBICAL_PARABOLA = "cubical_parabola"
    SEMICUBICAL_PARABOLA = "semicubical_parabola"
    CUBIC_SPLINE = "cubic_spline"
    QUARTIC = "quartic"  # a curve of no class, for negative tests
    UNCLASSIFIED = "unclassified"


#: The classes of the recognition tree, in the order it tests them (simplest first).
TREE_CLASSES = (
    CurveKind.PARABOLA,
    CurveKind.ELLIPSE,
    CurveKind.HYPERBOLA,
    CurveKind.CUBICAL_PARABOLA,
    CurveKind.SEMICUBICAL_PARABOLA,
    CurveKind.CUBIC_SPLINE,
)
#: The cubic classes of the tree, whose invariants need the slope at each contact.
SLOPE_CLASSES = (
    CurveKind.CUBICAL_PARABOLA,
    CurveKind.SEMICUBICAL_PARABOLA,
    CurveKind.CUBIC_SPLINE,
)

#: Number of shape parameters of each canonical form.
N_PARAMETERS: dict[CurveKind, int] = {
    CurveKind.PARABOLA: 1,
    CurveKind.ELLIPSE: 2,
    CurveKind.HYPERBOLA: 2,
    CurveKind.CUBICAL_PARABOLA: 2,
    CurveKind.SEMICUBICAL_PARABOLA: 2,
    CurveKind.CUBIC_SPLINE: 3,
    CurveKind.QUARTIC: 3,
}


def _polynomial_coefficients(
    kind: CurveKind, params: Sequence[ArrayLike]
) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients (lowest degree first, last axis) of x(t) and y(t), polynomial classes.

    Each parameter may be a scalar or an array of a common shape S; the result has
    shape S + (degree + 1,).
    """
    p = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in params))
    zero, one = np.zeros_like(p[0]), np.ones_like(p[0])
    x: tuple[np.ndarray, ...]
    y: tuple[np.ndarray, ...]
    if kind is CurveKind.PARABOLA:  # x = a t^2, y = 2 a t (Section 3.2.1.1)
        (a,) = p
        x, y = (zero, zero, a), (zero, 2.0 * a)
    elif kind is CurveKind.CUBICAL_PARABOLA:  # x = t, y = a t^3 + b t (Section 3.2.2.1)
        a, b = p
        x, y = (zero, one), (zero, b, zero, a)
    elif kind is CurveKind.SEMICUBICAL_PARABOLA:  # x = t^2, y = a t^3 + b t^2 (3.2.2.2)
        a, b = p
        x, y = (zero, zero, one), (zero, zero, b, a)
    elif kind is CurveKind.CUBIC_SPLINE:  # x = t^2, y = a t^3 + b t^2 + c t, Eq. (3.35)
        a, b, c = p
        x, y = (zero, zero, one), (zero, c, b, a)
    elif kind is CurveKind.QUARTIC:  # x = t, y = a t^4 + b t^2 + c t: in no class
        a, b, c = p
        x, y = (zero, one), (zero, c, b, zero, a)
    else:
        raise ValueError(f"{kind} is not a polynomial class")
    return np.stack(x, axis=-1), np.stack(y, axis=-1)


def canonical_derivatives(
    kind: CurveKind | str, params: Sequence[ArrayLike], t: ArrayLike
) -> np.ndarray:
    """Position and first three derivatives of a canonical curve.

    Parameters
    ----------
    kind : CurveKind
    params : sequence of float or of arrays
        Shape parameters (a,), (a, b) or (a, b, c) of the canonical form. For a batch,
        each parameter is an array of shape S and ``t`` has shape S + (n,).
    t : (..., n) float
        Curve parameter values.

    Returns
    -------
    (4, 2, ..., n) float
        ``[k, :, ..., i]`` is the k-th derivative of (x, y) at ``t[..., i]``.
    """
    kind = CurveKind(kind)
    t = np.asarray(t, dtype=float)
    if kind in (CurveKind.ELLIPSE, CurveKind.HYPERBOLA):
        a, b = (np.asarray(v, dtype=float)[..., None] for v in params)
        if kind is CurveKind.ELLIPSE:  # (a cos t, b sin t)
            c, s = np.cos(t), np.sin(t)
            xs, ys = (c, -s, -c, s), (s, c, -s, -c)
        else:  # (a cosh t, b sinh t)
            c, s = np.cosh(t), np.sinh(t)
            xs, ys = (c, s, c, s), (s, c, s, c)
        return np.stack(
            [np.stack(np.broadcast_arrays(a * x, b * y)) for x, y in zip(xs, ys, strict=True)]
        )
    cx, cy = _polynomial_coefficients(kind, params)
    degree = max(cx.shape[-1], cy.shape[-1]) - 1
    C = np.zeros((4, 2, *cx.shape[:-1], degree + 1))
    C[0, 0, ..., : cx.shape[-1]], C[0, 1, ..., : cy.shape[-1]] = cx, cy
    powers = np.arange(1, degree + 1)
    for k in range(1, 4):  # coefficient j of the derivative is (j + 1) c_(j + 1)
        C[k, :, ..., :-1] = C[k - 1, :, ..., 1:] * powers
    T = t[..., None] ** np.arange(degree + 1)  # (..., n, degree + 1)
    return np.einsum("kx...d,...nd->kx...n", C, T)


def curvature(d: np.ndarray) -> np.ndarray:
    """Signed curvature from parametric derivatives, thesis Eq. (3.1).

    ``d`` is the (4, 2, n) array of :func:`canonical_derivatives`.
    """
    (x1, y1), (x2, y2) = d[1], d[2]
    return (x1 * y2 - x2 * y1) / np.hypot(x1, y1) ** 3


def curvature_derivative(d: np.ndarray) -> np.ndarray:
    """Derivative of curvature with respect to arc length, thesis Eq. (3.2).

    kappa_s = kappa'(t) / |alpha'(t)|, with kappa'(t) from differentiating (3.1).
    """
    (x1, y1), (x2, y2), (x3, y3) = d[1], d[2], d[3]
    speed2 = x1 * x1 + y1 * y1
    speed = np.sqrt(speed2)
    cross = x1 * y2 - x2 * y1
    dkappa_dt = (x1 * y3 - x3 * y1) / speed**3 - 3.0 * cross * (x1 * x2 + y1 * y2) / speed**5
    return dkappa_dt / speed


def tangent_angle(d: np.ndarray) -> np.ndarray:
    """Tangent angle phi (radians, in (-pi, pi]) of the direction of increasing t."""
    return np.arctan2(d[1, 1], d[1, 0])


@dataclass(frozen=True)
class CanonicalCurve:
    """A curve of one class in its canonical form (thesis Sections 3.2.1-3.2.2; the cubic
    spline is thesis Eq. (3.35)).

    Attributes
    ----------
    kind : CurveKind
    params : tuple of float
        Shape parameters, e.g. (a, b) for an ellipse ``x^2/a^2 + y^2/b^2 = 1``.
    """

    kind: CurveKind
    params: tuple[float, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "kind", CurveKind(self.kind))
        if self.kind is CurveKind.UNCLASSIFIED:
            raise InvalidCurveData("an unclassified curve has no canonical form")
        expected = N_PARAMETERS[self.kind]
        if len(self.params) != expected:
            raise InvalidCurveData(
                f"{self.kind} takes {expected} shape parameter(s), got {len(self.params)}"
            )
        object.__setattr__(self, "params", tuple(float(p) for p in self.params))

    def derivatives(self, t: ArrayLike) -> np.ndarray:
        """(4, 2, n) position and derivatives at ``t``; see :func:`canonical_derivatives`."""
        return canonical_derivatives(self.kind, self.params, np.atleast_1d(t))

    def points(self, t: ArrayLike) -> np.ndarray:
        """(n, 2) points alpha(t)."""
        return self.derivatives(t)[0].T

    def kappa(self, t: ArrayLike) -> np.ndarray:
        """Signed curvature at ``t``, Eq. (3.1)."""
        return curvature(self.derivatives(t))

    def kappa_s(self, t: ArrayLike) -> np.ndarray:
        """Arc-length derivative of curvature at ``t``, Eq. (3.2)."""
        return curvature_derivative(self.derivatives(t))

    def phi(self, t: ArrayLike) -> np.ndarray:
        """Tangent angle at ``t`` (radians)."""
        return tangent_angle(self.derivatives(t))

    def speed(self, t: ArrayLike) -> np.ndarray:
        """|alpha'(t)|."""
        d = self.derivatives(t)
        return np.hypot(d[1, 0], d[1, 1])

    def arc_length(self, t0: float, t1: float, n: int = 4001) -> float:
        """Arc length from ``t0`` to ``t1`` (composite Simpson rule on |alpha'|)."""
        from scipy.integrate import simpson

        t = np.linspace(t0, t1, n | 1)
        return float(simpson(self.speed(t), x=t))
