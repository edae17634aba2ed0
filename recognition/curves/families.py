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
    "derivative_terms",
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


def derivative_terms(
    kind: CurveKind | str, params: Sequence[ArrayLike], t: ArrayLike
) -> list[tuple[np.ndarray | float, np.ndarray | float]]:
    """(x, y) and their first three derivatives of a canonical curve, not broadcast.

    Each parameter may be a scalar or an array of shape S, ``t`` of shape S + (n,);
    entry k of the list is the pair (x^(k), y^(k)), each an array or a constant that
    broadcasts with ``t``. :func:`canonical_derivatives` stacks them.
    """
    kind = CurveKind(kind)
    t = np.asarray(t, dtype=float)
    p = [np.asarray(v, dtype=float)[..., None] for v in params]
    x: list[np.ndarray | float]
    y: list[np.ndarray | float]
    if kind in (CurveKind.ELLIPSE, CurveKind.HYPERBOLA):
        a, b = p
        if kind is CurveKind.ELLIPSE:  # (a cos t, b sin t)
            c, s = np.cos(t), np.sin(t)
            x, y = [a * c, -a * s, -a * c, a * s], [b * s, b * c, -b * s, -b * c]
        else:  # (a cosh t, b sinh t)
            c, s = np.cosh(t), np.sinh(t)
            x, y = [a * c, a * s, a * c, a * s], [b * s, b * c, b * s, b * c]
    elif kind is CurveKind.PARABOLA:  # x = a t^2, y = 2 a t (Section 3.2.1.1)
        (a,) = p
        x, y = [a * t * t, 2.0 * a * t, 2.0 * a, 0.0], [2.0 * a * t, 2.0 * a, 0.0, 0.0]
    elif kind is CurveKind.CUBICAL_PARABOLA:  # x = t, y = a t^3 + b t (Section 3.2.2.1)
        a, b = p
        x = [t, 1.0, 0.0, 0.0]
        y = [(a * t * t + b) * t, 3.0 * a * t * t + b, 6.0 * a * t, 6.0 * a]
    elif kind in (CurveKind.SEMICUBICAL_PARABOLA, CurveKind.CUBIC_SPLINE):
        # x = t^2, y = a t^3 + b t^2 + c t: Eq. (3.35); c = 0 for Section 3.2.2.2
        a, b = p[0], p[1]
        c = p[2] if kind is CurveKind.CUBIC_SPLINE else 0.0
        x = [t * t, 2.0 * t, 2.0, 0.0]
        y = [((a * t + b) * t + c) * t, (3.0 * a * t + 2.0 * b) * t + c, 6.0 * a * t + 2.0 * b]
        y.append(6.0 * a)
    elif kind is CurveKind.QUARTIC:  # x = t, y = a t^4 + b t^2 + c t: in no class
        a, b, c = p
        t2 = t * t
        x = [t, 1.0, 0.0, 0.0]
        y = [(a * t2 * t + b * t + c) * t, 4.0 * a * t2 * t + 2.0 * b * t + c]
        y += [12.0 * a * t2 + 2.0 * b, 24.0 * a * t]
    else:
        raise InvalidCurveData(f"{kind} has no canonical form")
    return list(zip(x, y, strict=True))


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
    terms = derivative_terms(kind, params, t)
    shape = np.broadcast_shapes(*(np.shape(v) for pair in terms for v in pair))
    return np.stack([np.stack([np.broadcast_to(v, shape) for v in pair]) for pair in terms])


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
