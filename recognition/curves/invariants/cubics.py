"""Cubical and semi-cubical parabola invariants and slope quartics, thesis Sections 3.2.2.1-2."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from recognition.errors import NoRealSolution

__all__ = [
    "cubical_parabola_invariant_1",
    "cubical_parabola_invariant_2",
    "cubical_parabola_slope_quartic",
    "propagate_slope",
    "real_slopes",
    "semicubical_parabola_invariant_1",
    "semicubical_parabola_invariant_2",
    "semicubical_parabola_slope_quartic",
]


def propagate_slope(lambda1: ArrayLike, delta_phi: ArrayLike) -> np.ndarray:
    """Slope after the tangent turns by ``delta_phi``, thesis Eq. (3.29).

    lambda2 = (lambda1 + delta) / (1 - lambda1 delta) with delta = tan(delta_phi),
    evaluated as tan(arctan(lambda1) + delta_phi), which is the same and stays finite
    when ``1 - lambda1 delta`` is small. Arguments broadcast; ``delta_phi`` in radians.
    """
    return np.tan(np.arctan(lambda1) + np.asarray(delta_phi, dtype=float))


def real_slopes(coefficients: ArrayLike, *, imaginary_tol: float = 1e-7) -> np.ndarray:
    """Real roots of a slope quartic ``d4 l^4 + d3 l^3 + d2 l^2 + d1 l + d0``, thesis
    Eq. (3.31).

    ``coefficients`` is ``(d0, d1, d2, d3, d4)``. Both printed quartics factor as
    ``(1 + l^2)(e2 l^2 + e1 l + e0)`` (errata item 3), so at most two roots are real.
    Returns them sorted; raises :class:`NoRealSolution` when none is.
    """
    d = np.asarray(coefficients, dtype=float)
    roots = np.roots(d[::-1]) if np.any(d) else np.array([])
    scale = np.maximum(1.0, np.abs(roots))
    real = np.sort(roots[np.abs(roots.imag) <= imaginary_tol * scale].real)
    if real.size == 0:
        raise NoRealSolution(
            "the slope quartic has no real root: the two points are not on a curve of the "
            "hypothesised class (expected a real slope lambda1)"
        )
    return real


# --- Cubical parabola (Section 3.2.2.1) -------------------------------------------------


def cubical_parabola_invariant_1(
    lam: ArrayLike, kappa: ArrayLike, kappa_s: ArrayLike
) -> np.ndarray:
    """I_cp1 = (kappa_s + 3 lam kappa^2)(1 + lam^2)^2 / 6 = a, thesis Eq. (3.27)."""
    lam, kappa, kappa_s = (np.asarray(v, dtype=float) for v in (lam, kappa, kappa_s))
    return (kappa_s + 3.0 * lam * kappa**2) * (1.0 + lam**2) ** 2 / 6.0


def cubical_parabola_invariant_2(
    lam: ArrayLike, kappa: ArrayLike, kappa_s: ArrayLike
) -> np.ndarray:
    """I_cp2 = lam - kappa^2 (1 + lam^2) / (2 (kappa_s + 3 lam kappa^2)) = b, thesis
    Eq. (3.28)."""
    lam, kappa, kappa_s = (np.asarray(v, dtype=float) for v in (lam, kappa, kappa_s))
    return lam - kappa**2 * (1.0 + lam**2) / (2.0 * (kappa_s + 3.0 * lam * kappa**2))


def cubical_parabola_slope_quartic(
    kappa1: float, kappa_s1: float, kappa2: float, kappa_s2: float, delta12: float
) -> np.ndarray:
    """Coefficients (d0, ..., d4) of the slope quartic, thesis Eq. (3.31), as printed.

    From I_cp2 at two points, thesis Eq. (3.30), with lambda2 eliminated by (3.29);
    ``delta12 = tan(phi2 - phi1)``.
    """
    k1, k2 = kappa1**2, kappa2**2
    s1, s2, d = kappa_s1, kappa_s2, delta12
    d0 = s1 * (k2 * (5 * d**2 - 1) + 2 * s2 * d) + k1 * (3 * k2 * d + s2)
    d1 = 2 * d * (s1 * (3 * k2 - s2 * d) + 2 * k1 * (3 * k2 * d + s2))
    d2 = s1 * (k2 * (5 * d**2 - 1) + 2 * s2 * d) + k1 * (18 * k2 * d - s2 * (5 * d**2 - 1))
    d3 = d1
    d4 = 5 * k1 * d * (3 * k2 - s2 * d)
    return np.array([d0, d1, d2, d3, d4], dtype=float)


# --- Semi-cubical parabola (Section 3.2.2.2) --------------------------------------------


def semicubical_parabola_invariant_1(
    lam: ArrayLike, kappa: ArrayLike, kappa_s: ArrayLike
) -> np.ndarray:
    """I_scp1 = sqrt(-8 kappa^3 (1 + lam^2)^(5/2) / (9 (kappa_s + 3 lam kappa^2))) = a,
    thesis Eq. (3.32).

    The radicand is negative on the ``t < 0`` branch traversed with increasing t
    (errata item 4); its absolute value is used, which gives a there too.
    """
    lam, kappa, kappa_s = (np.asarray(v, dtype=float) for v in (lam, kappa, kappa_s))
    radicand = -8.0 * kappa**3 * (1.0 + lam**2) ** 2.5 / (9.0 * (kappa_s + 3.0 * lam * kappa**2))
    return np.sqrt(np.abs(radicand))


def semicubical_parabola_invariant_2(
    lam: ArrayLike, kappa: ArrayLike, kappa_s: ArrayLike
) -> np.ndarray:
    """I_scp2 = lam + kappa^2 (1 + lam^2) / (kappa_s + 3 lam kappa^2) = b, thesis
    Eq. (3.33)."""
    lam, kappa, kappa_s = (np.asarray(v, dtype=float) for v in (lam, kappa, kappa_s))
    return lam + kappa**2 * (1.0 + lam**2) / (kappa_s + 3.0 * lam * kappa**2)


def semicubical_parabola_slope_quartic(
    kappa1: float, kappa_s1: float, kappa2: float, kappa_s2: float, delta12: float
) -> np.ndarray:
    """Coefficients (d0, ..., d4) of the semi-cubical slope quartic (thesis Section
    3.2.2.2, after Eq. (3.34)).

    From I_scp2 at two points, thesis Eq. (3.34), with lambda2 eliminated by (3.29).
    """
    k1, k2 = kappa1**2, kappa2**2
    s1, s2, d = kappa_s1, kappa_s2, delta12
    d0 = k1 * (s2 + 3 * k2 * d) - s1 * (s2 * d + k2 * (1 + 4 * d**2))
    d1 = d * (s1 * (s2 * d - 3 * k2) - 5 * k1 * (s2 + 3 * k2 * d))
    d2 = k1 * (s2 * (1 + 4 * d**2) - 9 * k2 * d) - s1 * (s2 * d + k2 * (1 + 4 * d**2))
    d3 = d1
    d4 = 4 * k1 * d * (s2 * d - 3 * k2)
    return np.array([d0, d1, d2, d3, d4], dtype=float)
