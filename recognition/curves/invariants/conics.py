"""Invariants of the parabola, ellipse and hyperbola and their shapes, thesis Section 3.2.1."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from recognition.errors import DegenerateGeometry

__all__ = [
    "abs_two_thirds",
    "conic_invariant_1",
    "conic_invariant_2",
    "conic_invariants_regression",
    "ellipse_parameters",
    "hyperbola_parameters",
    "parabola_invariant",
    "parabola_parameter",
]


def abs_two_thirds(x: ArrayLike) -> np.ndarray:
    """|x|^(2/3), the reading of the thesis's ``kappa^(2/3)`` (errata item 1)."""
    x = np.asarray(x, dtype=float)
    return np.cbrt(x * x)


def parabola_invariant(kappa: ArrayLike, kappa_s: ArrayLike) -> np.ndarray:
    """I_p = |kappa|^(2/3) (kappa_s^2 / (9 kappa^4) + 1), thesis Eq. (3.10).

    Equal to ``(2a)^(-2/3)`` at every point of the parabola ``y^2 = 4 a x`` (3.9); for
    an ellipse or hyperbola it is the left side of (3.17) / (3.23).

    Parameters
    ----------
    kappa : (...) float, 1/length
    kappa_s : (...) float, 1/length^2

    Returns
    -------
    (...) float, length^(-2/3)
    """
    kappa = np.asarray(kappa, dtype=float)
    kappa_s = np.asarray(kappa_s, dtype=float)
    return abs_two_thirds(kappa) * (kappa_s**2 / (9.0 * kappa**4) + 1.0)


def parabola_parameter(i_p: ArrayLike) -> np.ndarray:
    """Shape parameter a of ``y^2 = 4 a x`` from I_p = (2a)^(-2/3), thesis Eq. (3.9)."""
    i_p = np.asarray(i_p, dtype=float)
    return 0.5 * i_p**-1.5


def conic_invariant_1(
    kappa1: ArrayLike, kappa_s1: ArrayLike, kappa2: ArrayLike, kappa_s2: ArrayLike
) -> np.ndarray:
    """I_c1 from two points, thesis Eq. (3.19) (and (3.24)).

    Equals ``1/(ab)^(2/3)`` on an ellipse, ``-1/(ab)^(2/3)`` on a hyperbola and 0 on a
    parabola. Defined when ``|kappa1| != |kappa2|`` (errata item 1). Arguments broadcast.
    """
    u1, u2 = abs_two_thirds(kappa1), abs_two_thirds(kappa2)
    ip1, ip2 = parabola_invariant(kappa1, kappa_s1), parabola_invariant(kappa2, kappa_s2)
    return u1 * u2 / (u1 - u2) * (ip1 - ip2)


def conic_invariant_2(
    kappa1: ArrayLike, kappa_s1: ArrayLike, kappa2: ArrayLike, kappa_s2: ArrayLike
) -> np.ndarray:
    """I_c2 from two points, thesis Eq. (3.20).

    Equals ``(a^2 + b^2)/(ab)^(4/3)`` on an ellipse, ``(a^2 - b^2)/(ab)^(4/3)`` on a
    hyperbola and ``(2a)^(-2/3)`` on a parabola. The printed step just before (3.20)
    misplaces a bracket (errata item 2); (3.20) itself is right. Arguments broadcast.
    """
    u1, u2 = abs_two_thirds(kappa1), abs_two_thirds(kappa2)
    ip1, ip2 = parabola_invariant(kappa1, kappa_s1), parabola_invariant(kappa2, kappa_s2)
    return (u1 * ip1 - u2 * ip2) / (u1 - u2)


def conic_invariants_regression(kappa: ArrayLike, kappa_s: ArrayLike) -> tuple[float, float, float]:
    """I_c1, I_c2 from any number of points by one linear least-squares fit, thesis
    Eqs. (3.17) and (3.23).

    Eqs. (3.17) and (3.23) say that on every conic ``I_p = I_c2 - I_c1 |kappa|^(-2/3)``:
    I_p is an affine function of ``w = |kappa|^(-2/3)`` whose slope is ``-I_c1`` and
    whose intercept is ``I_c2``. The two-point invariants (3.19)-(3.20) are exactly the
    slope and intercept through two points; the fit uses every point at once and its
    residual measures how far the data are from any conic.

    Parameters
    ----------
    kappa, kappa_s : (m,) float
        Curvature and its arc-length derivative at m >= 3 points.

    Returns
    -------
    i_c1, i_c2 : float
    relative_residual : float
        RMS of the fit residual divided by the mean of I_p (dimensionless).
    """
    kappa = np.asarray(kappa, dtype=float)
    w = 1.0 / abs_two_thirds(kappa)
    i_p = parabola_invariant(kappa, kappa_s)
    if kappa.size < 3 or np.ptp(w) <= 1e-9 * np.abs(w).max():
        raise DegenerateGeometry(
            "the conic invariants need at least three points with different |kappa|"
        )
    A = np.column_stack([np.ones_like(w), -w])
    (i_c2, i_c1), *_ = np.linalg.lstsq(A, i_p, rcond=None)
    residual = i_p - A @ np.array([i_c2, i_c1])
    return float(i_c1), float(i_c2), float(np.sqrt(np.mean(residual**2)) / np.mean(i_p))


def ellipse_parameters(i_c1: float, i_c2: float) -> tuple[float, float]:
    """Semi-axes (a, b), a >= b, of an ellipse from I_c1 > 0 and I_c2 (thesis Section
    3.2.1.2, inverting Eqs. (3.19)-(3.20)).

    mu1 = ab = I_c1^(-3/2) and mu2 = a^2 + b^2 = I_c2 mu1^(4/3); a discriminant that
    noise makes slightly negative is clamped to 0 (a circle).
    """
    if not i_c1 > 0:
        raise DegenerateGeometry(f"an ellipse needs I_c1 > 0, got {i_c1:.6g}")
    mu1 = i_c1**-1.5
    mu2 = i_c2 * mu1 ** (4.0 / 3.0)
    root = np.sqrt(max(mu2**2 - 4.0 * mu1**2, 0.0))
    return float(np.sqrt((mu2 + root) / 2.0)), float(np.sqrt(max(mu2 - root, 0.0) / 2.0))


def hyperbola_parameters(i_c1: float, i_c2: float) -> tuple[float, float]:
    """(a, b) of ``x^2/a^2 - y^2/b^2 = 1`` from I_c1 < 0 and I_c2 (thesis Section
    3.2.1.3, inverting Eq. (3.24) and the I_c2 that follows it).

    mu1 = ab = (-I_c1)^(-3/2) and mu2 = a^2 - b^2 = I_c2 mu1^(4/3).
    """
    if not i_c1 < 0:
        raise DegenerateGeometry(f"a hyperbola needs I_c1 < 0, got {i_c1:.6g}")
    mu1 = (-i_c1) ** -1.5
    mu2 = i_c2 * mu1 ** (4.0 / 3.0)
    root = np.sqrt(mu2**2 + 4.0 * mu1**2)
    return float(np.sqrt((root + mu2) / 2.0)), float(np.sqrt((root - mu2) / 2.0))
