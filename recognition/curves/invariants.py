"""Differential and semi-differential invariants of thesis Section 3.2, and shape recovery.

All functions are vectorised over numpy arrays. Conventions fixed here (see
``THESIS_ERRATA.md``):

* ``kappa^(2/3)`` means ``|kappa|^(2/3) = cbrt(kappa^2)``; printed literally it is NaN
  wherever kappa < 0.
* The cubic-class formulas (3.27)-(3.44) hold for traversal towards +x in the
  canonical frame; callers try both signs of kappa.
"""

from __future__ import annotations

import numpy as np

from recognition.errors import DegenerateGeometry, NoRealSolution

__all__ = [
    "abs_two_thirds",
    "conic_invariant_1",
    "conic_invariant_2",
    "conic_invariants_regression",
    "cubic_spline_c",
    "cubic_spline_from_contact",
    "cubic_spline_residual",
    "cubical_parabola_invariant_1",
    "cubical_parabola_invariant_2",
    "cubical_parabola_slope_quartic",
    "ellipse_parameters",
    "hyperbola_parameters",
    "parabola_invariant",
    "parabola_parameter",
    "propagate_slope",
    "real_slopes",
    "semicubical_parabola_invariant_1",
    "semicubical_parabola_invariant_2",
    "semicubical_parabola_slope_quartic",
]


def abs_two_thirds(x):
    """|x|^(2/3), the reading of the thesis's ``kappa^(2/3)`` (errata item 1)."""
    x = np.asarray(x, dtype=float)
    return np.cbrt(x * x)


# --- Conics (Section 3.2.1) -------------------------------------------------------------


def parabola_invariant(kappa, kappa_s):
    """I_p = |kappa|^(2/3) (kappa_s^2 / (9 kappa^4) + 1), thesis Eq. (3.10).

    Equal to ``(2a)^(-2/3)`` at every point of the parabola ``y^2 = 4 a x`` (3.9); for
    an ellipse or hyperbola it is the left side of (3.17) / (3.23).
    """
    kappa = np.asarray(kappa, dtype=float)
    kappa_s = np.asarray(kappa_s, dtype=float)
    return abs_two_thirds(kappa) * (kappa_s**2 / (9.0 * kappa**4) + 1.0)


def parabola_parameter(i_p):
    """Shape parameter a of ``y^2 = 4 a x`` from I_p = (2a)^(-2/3), thesis Eq. (3.9)."""
    i_p = np.asarray(i_p, dtype=float)
    return 0.5 * i_p**-1.5


def conic_invariant_1(kappa1, kappa_s1, kappa2, kappa_s2):
    """I_c1 from two points, thesis Eq. (3.19) (and (3.24)).

    Equals ``1/(ab)^(2/3)`` on an ellipse, ``-1/(ab)^(2/3)`` on a hyperbola and 0 on a
    parabola. Defined when ``|kappa1| != |kappa2|`` (errata item 1).
    """
    u1, u2 = abs_two_thirds(kappa1), abs_two_thirds(kappa2)
    ip1, ip2 = parabola_invariant(kappa1, kappa_s1), parabola_invariant(kappa2, kappa_s2)
    return u1 * u2 / (u1 - u2) * (ip1 - ip2)


def conic_invariant_2(kappa1, kappa_s1, kappa2, kappa_s2):
    """I_c2 from two points, thesis Eq. (3.20).

    Equals ``(a^2 + b^2)/(ab)^(4/3)`` on an ellipse, ``(a^2 - b^2)/(ab)^(4/3)`` on a
    hyperbola and ``(2a)^(-2/3)`` on a parabola. The printed step just before (3.20)
    misplaces a bracket (errata item 2); (3.20) itself is right.
    """
    u1, u2 = abs_two_thirds(kappa1), abs_two_thirds(kappa2)
    ip1, ip2 = parabola_invariant(kappa1, kappa_s1), parabola_invariant(kappa2, kappa_s2)
    return (u1 * ip1 - u2 * ip2) / (u1 - u2)


def conic_invariants_regression(kappa, kappa_s):
    """I_c1, I_c2 from any number of points by one linear least-squares fit.

    Eqs. (3.17) and (3.23) say that on every conic ``I_p = I_c2 - I_c1 |kappa|^(-2/3)``:
    I_p is an affine function of ``w = |kappa|^(-2/3)`` whose slope is ``-I_c1`` and
    whose intercept is ``I_c2``. The two-point invariants (3.19)-(3.20) are exactly the
    slope and intercept through two points; the fit uses every point at once and its
    residual measures how far the data are from any conic.

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


def ellipse_parameters(i_c1, i_c2):
    """Semi-axes (a, b), a >= b, of an ellipse from I_c1 > 0 and I_c2 (Section 3.2.1.2).

    mu1 = ab = I_c1^(-3/2) and mu2 = a^2 + b^2 = I_c2 mu1^(4/3); a discriminant that
    noise makes slightly negative is clamped to 0 (a circle).
    """
    if not i_c1 > 0:
        raise DegenerateGeometry(f"an ellipse needs I_c1 > 0, got {i_c1:.6g}")
    mu1 = i_c1**-1.5
    mu2 = i_c2 * mu1 ** (4.0 / 3.0)
    root = np.sqrt(max(mu2**2 - 4.0 * mu1**2, 0.0))
    return float(np.sqrt((mu2 + root) / 2.0)), float(np.sqrt(max(mu2 - root, 0.0) / 2.0))


def hyperbola_parameters(i_c1, i_c2):
    """(a, b) of ``x^2/a^2 - y^2/b^2 = 1`` from I_c1 < 0 and I_c2 (Section 3.2.1.3).

    mu1 = ab = (-I_c1)^(-3/2) and mu2 = a^2 - b^2 = I_c2 mu1^(4/3).
    """
    if not i_c1 < 0:
        raise DegenerateGeometry(f"a hyperbola needs I_c1 < 0, got {i_c1:.6g}")
    mu1 = (-i_c1) ** -1.5
    mu2 = i_c2 * mu1 ** (4.0 / 3.0)
    root = np.sqrt(mu2**2 + 4.0 * mu1**2)
    return float(np.sqrt((root + mu2) / 2.0)), float(np.sqrt((root - mu2) / 2.0))


# --- Slopes (Section 3.2.2.1) -----------------------------------------------------------


def propagate_slope(lambda1, delta_phi):
    """Slope after the tangent turns by ``delta_phi``, thesis Eq. (3.29).

    lambda2 = (lambda1 + delta) / (1 - lambda1 delta) with delta = tan(delta_phi),
    evaluated as tan(arctan(lambda1) + delta_phi), which is the same and stays finite
    when ``1 - lambda1 delta`` is small.
    """
    return np.tan(np.arctan(lambda1) + np.asarray(delta_phi, dtype=float))


def real_slopes(coefficients, *, imaginary_tol: float = 1e-7) -> np.ndarray:
    """Real roots of a slope quartic ``d4 l^4 + d3 l^3 + d2 l^2 + d1 l + d0``.

    ``coefficients`` is ``(d0, d1, d2, d3, d4)``. Both printed quartics factor as
    ``(1 + l^2)(e2 l^2 + e1 l + e0)`` (errata item 3), so at most two roots are real.
    Raises :class:`NoRealSolution` when none is.
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


def cubical_parabola_invariant_1(lam, kappa, kappa_s):
    """I_cp1 = (kappa_s + 3 lam kappa^2)(1 + lam^2)^2 / 6 = a, thesis Eq. (3.27)."""
    lam, kappa, kappa_s = (np.asarray(v, dtype=float) for v in (lam, kappa, kappa_s))
    return (kappa_s + 3.0 * lam * kappa**2) * (1.0 + lam**2) ** 2 / 6.0


def cubical_parabola_invariant_2(lam, kappa, kappa_s):
    """I_cp2 = lam - kappa^2 (1 + lam^2) / (2 (kappa_s + 3 lam kappa^2)) = b, Eq. (3.28)."""
    lam, kappa, kappa_s = (np.asarray(v, dtype=float) for v in (lam, kappa, kappa_s))
    return lam - kappa**2 * (1.0 + lam**2) / (2.0 * (kappa_s + 3.0 * lam * kappa**2))


def cubical_parabola_slope_quartic(kappa1, kappa_s1, kappa2, kappa_s2, delta12):
    """Coefficients (d0, ..., d4) of the slope quartic (3.31), as printed.

    From I_cp2 at two points (3.30) with lambda2 eliminated by (3.29);
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


def semicubical_parabola_invariant_1(lam, kappa, kappa_s):
    """I_scp1 = sqrt(-8 kappa^3 (1 + lam^2)^(5/2) / (9 (kappa_s + 3 lam kappa^2))) = a, (3.32).

    The radicand is negative on the ``t < 0`` branch traversed with increasing t
    (errata item 4); its absolute value is used, which gives a there too.
    """
    lam, kappa, kappa_s = (np.asarray(v, dtype=float) for v in (lam, kappa, kappa_s))
    radicand = -8.0 * kappa**3 * (1.0 + lam**2) ** 2.5 / (9.0 * (kappa_s + 3.0 * lam * kappa**2))
    return np.sqrt(np.abs(radicand))


def semicubical_parabola_invariant_2(lam, kappa, kappa_s):
    """I_scp2 = lam + kappa^2 (1 + lam^2) / (kappa_s + 3 lam kappa^2) = b, Eq. (3.33)."""
    lam, kappa, kappa_s = (np.asarray(v, dtype=float) for v in (lam, kappa, kappa_s))
    return lam + kappa**2 * (1.0 + lam**2) / (kappa_s + 3.0 * lam * kappa**2)


def semicubical_parabola_slope_quartic(kappa1, kappa_s1, kappa2, kappa_s2, delta12):
    """Coefficients (d0, ..., d4) of the semi-cubical slope quartic (Section 3.2.2.2).

    From I_scp2 at two points (3.34) with lambda2 eliminated by (3.29).
    """
    k1, k2 = kappa1**2, kappa2**2
    s1, s2, d = kappa_s1, kappa_s2, delta12
    d0 = k1 * (s2 + 3 * k2 * d) - s1 * (s2 * d + k2 * (1 + 4 * d**2))
    d1 = d * (s1 * (s2 * d - 3 * k2) - 5 * k1 * (s2 + 3 * k2 * d))
    d2 = k1 * (s2 * (1 + 4 * d**2) - 9 * k2 * d) - s1 * (s2 * d + k2 * (1 + 4 * d**2))
    d3 = d1
    d4 = 4 * k1 * d * (s2 * d - 3 * k2)
    return np.array([d0, d1, d2, d3, d4], dtype=float)


# --- Cubic spline (Section 3.2.2.3) -----------------------------------------------------


def _spline_L_M(lam, kappa, kappa_s):
    """L = 2 (1 + lam^2)^(3/2) kappa and M = (kappa_s + 3 kappa^2 lam) / ((1 + lam^2) kappa^2)."""
    lam, kappa, kappa_s = (np.asarray(v, dtype=float) for v in (lam, kappa, kappa_s))
    one = 1.0 + lam**2
    return 2.0 * one**1.5 * kappa, (kappa_s + 3.0 * kappa**2 * lam) / (one * kappa**2)


def cubic_spline_residual(a, b, lam, kappa, kappa_s):
    """g(a, b, lambda): the resultant (3.44) divided by 81 M a^4.

    g = 1 + 18 L (1 + 3 M (b - lam)) / (81 M a^2) + L^2 (b - lam)(M (b - lam) + 3)^2
    / (81 M a^4); zero at every contact of the spline ``x = t^2, y = a t^3 + b t^2 + c t``
    when lam is the slope there.
    """
    L, M = _spline_L_M(lam, kappa, kappa_s)
    e = b - np.asarray(lam, dtype=float)
    a2 = np.asarray(a, dtype=float) ** 2
    return (
        1.0
        + 18.0 * L * (1.0 + 3.0 * M * e) / (81.0 * M * a2)
        + L**2 * e * (M * e + 3.0) ** 2 / (81.0 * M * a2**2)
    )


def cubic_spline_c(a, b, lam, kappa, kappa_s):
    """Third shape parameter c of the spline (3.35), formula after (3.44)."""
    L, M = _spline_L_M(lam, kappa, kappa_s)
    e = b - np.asarray(lam, dtype=float)
    a = np.asarray(a, dtype=float)
    num = ((2.0 * e * L + 9.0 * a**2) * (M * e + 3.0) - 18.0 * a**2) * e
    return num / (3.0 * a * (2.0 * L + 2.0 * M * e * L + 9.0 * a**2 * M))


def cubic_spline_from_contact(lam, kappa, kappa_s, t):
    """Shape (a, b, c) of the spline (3.35) from one contact and its parameter t.

    Substituting ``b - lam = L t^2 - 3 a t`` (3.42) and ``c = 3 a t^2 - 2 L t^3`` (3.40)
    into (3.41) leaves ``(b - lam)^2 - 3ac = L^2 t^4`` and hence (errata item 7)
    ``a = L t (M L t^2 + 3) / 3``, ``b = lam + L t^2 - 3 a t``, ``c = 3 a t^2 - 2 L t^3``.
    Valid for traversal towards +x (t > 0 with increasing t).
    """
    L, M = _spline_L_M(lam, kappa, kappa_s)
    t = np.asarray(t, dtype=float)
    a = L * t * (M * L * t**2 + 3.0) / 3.0
    b = np.asarray(lam, dtype=float) + L * t**2 - 3.0 * a * t
    c = 3.0 * a * t**2 - 2.0 * L * t**3
    return a, b, c
