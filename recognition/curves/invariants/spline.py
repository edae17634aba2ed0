"""Closed forms of the cubic spline (3.35) at a contact: g, c, the shape from one contact."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "cubic_spline_c",
    "cubic_spline_from_contact",
    "cubic_spline_l_m",
    "cubic_spline_residual",
]


def cubic_spline_l_m(
    lam: ArrayLike, kappa: ArrayLike, kappa_s: ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """L = 2 (1 + lam^2)^(3/2) kappa and M = (kappa_s + 3 kappa^2 lam) / ((1 + lam^2) kappa^2),
    the coefficients of thesis Eqs. (3.40)-(3.41)."""
    lam, kappa, kappa_s = (np.asarray(v, dtype=float) for v in (lam, kappa, kappa_s))
    one = 1.0 + lam**2
    return 2.0 * one**1.5 * kappa, (kappa_s + 3.0 * kappa**2 * lam) / (one * kappa**2)


def cubic_spline_residual(
    a: ArrayLike, b: ArrayLike, lam: ArrayLike, kappa: ArrayLike, kappa_s: ArrayLike
) -> np.ndarray:
    """g(a, b, lambda): the resultant, thesis Eq. (3.44), divided by 81 M a^4.

    g = 1 + 18 L (1 + 3 M (b - lam)) / (81 M a^2) + L^2 (b - lam)(M (b - lam) + 3)^2
    / (81 M a^4); zero at every contact of the spline ``x = t^2, y = a t^3 + b t^2 + c t``
    when lam is the slope there. Arguments broadcast.
    """
    L, M = cubic_spline_l_m(lam, kappa, kappa_s)
    e = b - np.asarray(lam, dtype=float)
    a2 = np.asarray(a, dtype=float) ** 2
    return (
        1.0
        + 18.0 * L * (1.0 + 3.0 * M * e) / (81.0 * M * a2)
        + L**2 * e * (M * e + 3.0) ** 2 / (81.0 * M * a2**2)
    )


def cubic_spline_c(
    a: ArrayLike, b: ArrayLike, lam: ArrayLike, kappa: ArrayLike, kappa_s: ArrayLike
) -> np.ndarray:
    """Third shape parameter c of the spline, thesis Eq. (3.35), by the formula after
    Eq. (3.44)."""
    L, M = cubic_spline_l_m(lam, kappa, kappa_s)
    e = b - np.asarray(lam, dtype=float)
    a = np.asarray(a, dtype=float)
    num = ((2.0 * e * L + 9.0 * a**2) * (M * e + 3.0) - 18.0 * a**2) * e
    return num / (3.0 * a * (2.0 * L + 2.0 * M * e * L + 9.0 * a**2 * M))


def cubic_spline_from_contact(
    lam: ArrayLike, kappa: ArrayLike, kappa_s: ArrayLike, t: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Shape (a, b, c) of the spline (3.35) from one contact and its parameter t, thesis
    Eqs. (3.40)-(3.42).

    Substituting ``b - lam = L t^2 - 3 a t`` (3.42) and ``c = 3 a t^2 - 2 L t^3`` (3.40)
    into (3.41) leaves ``(b - lam)^2 - 3ac = L^2 t^4`` and hence (errata item 7)
    ``a = L t (M L t^2 + 3) / 3``, ``b = lam + L t^2 - 3 a t``, ``c = 3 a t^2 - 2 L t^3``.
    Valid for traversal towards +x (t > 0 with increasing t). Arguments broadcast.
    """
    L, M = cubic_spline_l_m(lam, kappa, kappa_s)
    t = np.asarray(t, dtype=float)
    a = L * t * (M * L * t**2 + 3.0) / 3.0
    b = np.asarray(lam, dtype=float) + L * t**2 - 3.0 * a * t
    c = 3.0 * a * t**2 - 2.0 * L * t**3
    return a, b, c
