"""Reduction of general polynomial parametrisations to the canonical forms of Section 3.2.

A curve given by polynomials ``x(t), y(t)`` is rotated, translated and reparametrised
(``u = u_scale t + u_offset``) into the canonical form of its class. Each reduction
returns the canonical shape parameters and the rigid motion that places the canonical
curve on the given one:

    (x(t), y(t)) = R q(u) + translation,   u = u_scale t + u_offset,

where ``q`` is the canonical curve of :class:`~recognition.curves.families.CanonicalCurve`
and ``[R | translation]`` is ``T_data_from_canonical``.

The thesis rotates "by theta" as ``x' = x cos(theta) + y sin(theta)``,
``y' = -x sin(theta) + y cos(theta)`` (Section 3.2.1.1), i.e. ``p' = R(theta)^T p``;
the same convention is used here, so ``R = R(theta)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from recognition.curves.families import CanonicalCurve, CurveKind
from recognition.errors import DegenerateGeometry, InvalidCurveData
from recognition.rigid import apply_pose, pose_matrix, rotation_2d

__all__ = [
    "CanonicalReduction",
    "reduce_cubic_spline",
    "reduce_cubical_parabola",
    "reduce_parabola",
    "reduce_semicubical_parabola",
]

#: Relative size below which a determinant or leading coefficient counts as zero.
DEGENERACY_TOL = 1e-12


@dataclass(frozen=True)
class CanonicalReduction:
    """A polynomial curve in canonical form.

    Attributes
    ----------
    curve : CanonicalCurve
        Class and canonical shape parameters.
    theta : float
        Rotation angle (radians) of the thesis's reduction, ``p' = R(theta)^T p``.
    T_data_from_canonical : (3, 3) float
        Homogeneous rigid motion taking canonical points to the given curve.
    u_scale, u_offset : float
        Canonical parameter of the point with original parameter t:
        ``u = u_scale t + u_offset``.
    """

    curve: CanonicalCurve
    theta: float
    T_data_from_canonical: np.ndarray
    u_scale: float
    u_offset: float

    @property
    def kind(self) -> CurveKind:
        """Class of the curve."""
        return self.curve.kind

    @property
    def params(self) -> tuple[float, ...]:
        """Canonical shape parameters."""
        return self.curve.params

    def canonical_parameter(self, t: ArrayLike) -> np.ndarray:
        """Canonical parameter u of the points with original parameter ``t``, same shape."""
        return self.u_scale * np.asarray(t, dtype=float) + self.u_offset

    def points(self, t: ArrayLike) -> np.ndarray:
        """(n, 2) points of the given curve at original parameters ``t``, via the canonical form."""
        q = self.curve.points(self.canonical_parameter(np.atleast_1d(t)))
        return apply_pose(self.T_data_from_canonical, q)


def _check_finite(*coefficients: float) -> None:
    """Raise :class:`InvalidCurveData` unless every coefficient is a finite scalar."""
    values = np.asarray(coefficients, dtype=float)
    if values.shape != (len(coefficients),) or not np.all(np.isfinite(values)):
        raise InvalidCurveData(
            f"expected finite scalar polynomial coefficients, got {list(coefficients)}"
        )


def _rotated(
    theta: float, x_coefficients: ArrayLike, y_coefficients: ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients of x' = x cos + y sin and y' = -x sin + y cos (same degree order)."""
    c, s = np.cos(theta), np.sin(theta)
    x = np.asarray(x_coefficients, dtype=float)
    y = np.asarray(y_coefficients, dtype=float)
    return c * x + s * y, -s * x + c * y


def _reduction(
    kind: CurveKind,
    params: tuple[float, ...],
    theta: float,
    origin_rotated: ArrayLike,
    u_scale: float,
    u_offset: float,
) -> CanonicalReduction:
    """The reduction whose rotation is R(theta) and whose canonical origin sits at
    ``R(theta) origin_rotated`` (the origin in the rotated frame)."""
    R = rotation_2d(theta)
    return CanonicalReduction(
        CanonicalCurve(kind, tuple(float(p) for p in params)),
        float(theta),
        pose_matrix(R, R @ np.asarray(origin_rotated, dtype=float)),
        float(u_scale),
        float(u_offset),
    )


def reduce_parabola(
    a2: float, a1: float, a0: float, b2: float, b1: float, b0: float
) -> CanonicalReduction:
    """Parabola ``x = a2 t^2 + a1 t + a0, y = b2 t^2 + b1 t + b0``, thesis Eq. (3.4), in
    canonical form.

    Thesis Section 3.2.1.1: rotate by ``theta`` with ``tan(theta) = b2 / a2`` so that y
    loses its ``t^2`` term, then reparametrise and translate to ``x = a u^2, y = 2 a u``
    (``y^2 = 4 a x``). With ``A2 = a2 cos(theta) + b2 sin(theta)`` and
    ``B1 = -a1 sin(theta) + b1 cos(theta)``, the rotated curve is
    ``x' = A2 t^2 + A1 t + A0, y' = B1 t + B0``, so
    ``x' - x'_vertex = A2 / B1^2 (y' - y'_vertex)^2`` and

        a = (-a1 sin(theta) + b1 cos(theta))^2 / (4 (a2 cos(theta) + b2 sin(theta))).

    The printed formula lacks the factor 4 (THESIS_ERRATA item 6). ``theta`` is taken as
    ``atan2(b2, a2)``, which makes ``A2 = hypot(a2, b2) > 0`` and hence ``a > 0``
    (``arctan(b2 / a2)`` may differ by pi and give the mirror parabola ``a < 0``). The
    canonical parameter is ``u = (2 A2 t + A1) / B1``.

    Raises
    ------
    InvalidCurveData
        If a coefficient is not a finite number (likewise for every reduction here).
    DegenerateGeometry
        If ``a2 b1 - a1 b2 = 0``: the points lie on a straight line.
    """
    _check_finite(a2, a1, a0, b2, b1, b0)
    det = a2 * b1 - a1 * b2
    if not abs(det) > DEGENERACY_TOL * np.hypot(a2, b2) * np.hypot(a1, b1):
        raise DegenerateGeometry(
            "a2 b1 - a1 b2 = 0: the parametrisation (3.4) traces a straight line, "
            "expected a parabola"
        )
    theta = float(np.arctan2(b2, a2))
    (A0, A1, A2), (B0, B1, _) = _rotated(theta, (a0, a1, a2), (b0, b1, b2))
    a = B1**2 / (4.0 * A2)
    t_vertex = -A1 / (2.0 * A2)
    vertex = (A0 - A1**2 / (4.0 * A2), B1 * t_vertex + B0)
    u_scale = 2.0 * A2 / B1
    return _reduction(CurveKind.PARABOLA, (a,), theta, vertex, u_scale, A1 / B1)


def reduce_cubical_parabola(
    a3: float, a1: float, a0: float, b3: float, b1: float, b0: float
) -> CanonicalReduction:
    """Cubical parabola ``x = a3 t^3 + a1 t + a0, y = b3 t^3 + b1 t + b0`` in canonical form.

    Thesis Section 3.2.2.1: rotate by ``theta = arctan(-a3 / b3)``, which cancels the
    ``t^3`` term of ``x' = x cos(theta) + y sin(theta)``; with ``u = x' - a0'`` the curve
    is ``x = u, y = a u^3 + b u`` where

        a = (-a3 sin(theta) + b3 cos(theta)) / (a1 cos(theta) + b1 sin(theta))^3,
        b = (-a1 sin(theta) + b1 cos(theta)) / (a1 cos(theta) + b1 sin(theta)).

    The printed rotation and formulas hold as printed. ``theta`` is computed as
    ``atan2(-a3, b3)`` (defined also for ``b3 = 0``); ``arctan(-a3 / b3)`` differs from
    it by 0 or pi, which flips the signs of numerator and denominator together and
    leaves (a, b) unchanged. The canonical parameter is
    ``u = (a1 cos(theta) + b1 sin(theta)) t``.

    Raises
    ------
    DegenerateGeometry
        If ``a3 b1 - a1 b3 = 0`` (the condition of Section 3.2.2.1).
    """
    _check_finite(a3, a1, a0, b3, b1, b0)
    det = a3 * b1 - a1 * b3
    if not abs(det) > DEGENERACY_TOL * np.hypot(a3, b3) * np.hypot(a1, b1):
        raise DegenerateGeometry(
            "a3 b1 - a1 b3 = 0: expected a cubical parabola with a3 b1 - a1 b3 != 0 "
            "(Section 3.2.2.1)"
        )
    theta = float(np.arctan2(-a3, b3))
    (A0, A1, _), (B0, B1, B3) = _rotated(theta, (a0, a1, a3), (b0, b1, b3))
    return _reduction(CurveKind.CUBICAL_PARABOLA, (B3 / A1**3, B1 / A1), theta, (A0, B0), A1, 0.0)


def reduce_cubic_spline(
    a3: float, a2: float, a1: float, a0: float, b3: float, b2: float, b1: float, b0: float
) -> CanonicalReduction:
    """Cubic spline segment, thesis Eq. (3.25), in the canonical form of thesis Eq. (3.35),
    ``x = u^2``.

    Thesis Section 3.2.2.3 states that "proper rotation, translation, and
    reparametrization" give ``x = u^2, y = a u^3 + b u^2 + c u``; the steps are:

    1. rotate by ``theta = atan2(-a3, b3)`` (plus pi if needed) so that
       ``x' = A2 t^2 + A1 t + A0`` has no cubic term and ``A2 > 0``;
    2. shift ``tau = t - t_v``, ``t_v = -A1 / (2 A2)``, so that ``x' - x'(t_v) = A2 tau^2``
       and ``y' - y'(t_v) = B3 tau^3 + C2 tau^2 + C1 tau`` with
       ``C2 = 3 B3 t_v + B2``, ``C1 = 3 B3 t_v^2 + 2 B2 t_v + B1``;
    3. scale ``u = sigma sqrt(A2) tau``, giving ``a = sigma B3 / A2^(3/2)``,
       ``b = C2 / A2``, ``c = sigma C1 / sqrt(A2)``.

    ``(a, b, c)`` and ``(-a, b, -c)`` are the same curve (``u -> -u``); ``sigma`` is
    chosen so that ``a > 0``. The kind is :attr:`CurveKind.CUBIC_SPLINE`, or
    :attr:`CurveKind.SEMICUBICAL_PARABOLA` (parameters (a, b)) when ``c = 0`` exactly
    (use :func:`reduce_semicubical_parabola` for that class).

    Raises
    ------
    DegenerateGeometry
        If ``a3 = b3 = 0`` (a parabola: the rotation is not determined) or if the rotated
        x is linear in t (a cubical parabola after a shift of t).
    """
    _check_finite(a3, a2, a1, a0, b3, b2, b1, b0)
    if np.hypot(a3, b3) == 0.0:
        raise DegenerateGeometry(
            "a3 = b3 = 0: a quadratic parametrisation is a parabola, expected a cubic"
        )
    theta = float(np.arctan2(-a3, b3))
    x_rot, _ = _rotated(theta, (a0, a1, a2, a3), (b0, b1, b2, b3))
    if x_rot[2] < 0.0:
        theta = float(np.angle(np.exp(1j * (theta + np.pi))))
    (A0, A1, A2, _), (B0, B1, B2, B3) = _rotated(theta, (a0, a1, a2, a3), (b0, b1, b2, b3))
    if not A2 > DEGENERACY_TOL * np.hypot(a2, b2):
        raise DegenerateGeometry(
            "the rotated x(t) is linear: the curve is a cubical parabola, not of form (3.35)"
        )
    t_v = -A1 / (2.0 * A2)
    C2 = 3.0 * B3 * t_v + B2
    C1 = (3.0 * B3 * t_v + 2.0 * B2) * t_v + B1
    sigma = 1.0 if B3 >= 0.0 else -1.0
    root = np.sqrt(A2)
    a, b, c = sigma * B3 / A2**1.5, C2 / A2, sigma * C1 / root
    origin = (A0 + (A1 + A2 * t_v) * t_v, B0 + (B1 + (B2 + B3 * t_v) * t_v) * t_v)
    u_scale = sigma * root
    params: tuple[float, ...]
    if c == 0.0:
        kind, params = CurveKind.SEMICUBICAL_PARABOLA, (a, b)
    else:
        kind, params = CurveKind.CUBIC_SPLINE, (a, b, c)
    return _reduction(kind, params, theta, origin, u_scale, -u_scale * t_v)


def reduce_semicubical_parabola(
    a3: float, a2: float, a0: float, b3: float, b2: float, b0: float
) -> CanonicalReduction:
    """Semi-cubical parabola ``x = a3 t^3 + a2 t^2 + a0, y = b3 t^3 + b2 t^2 + b0``.

    Thesis Section 3.2.2.2 gives the canonical form ``x = u^2, y = a u^3 + b u^2`` without
    the reduction; it is the case ``a1 = b1 = 0`` of :func:`reduce_cubic_spline`, where
    no shift of t is needed and c = 0: ``a = |B3| / A2^(3/2)``, ``b = B2 / A2``.

    Raises
    ------
    DegenerateGeometry
        If ``a3 b2 - a2 b3 = 0`` (the condition of Section 3.2.2.2).
    """
    _check_finite(a3, a2, a0, b3, b2, b0)
    det = a3 * b2 - a2 * b3
    if not abs(det) > DEGENERACY_TOL * np.hypot(a3, b3) * np.hypot(a2, b2):
        raise DegenerateGeometry(
            "a3 b2 - a2 b3 = 0: expected a semi-cubical parabola with a3 b2 - a2 b3 != 0 "
            "(Section 3.2.2.2)"
        )
    return reduce_cubic_spline(a3, a2, 0.0, a0, b3, b2, 0.0, b0)
