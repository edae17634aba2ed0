"""Differential and semi-differential invariants of thesis Section 3.2, and shape recovery.

All functions are vectorised over numpy arrays. Conventions fixed here (see
``THESIS_ERRATA.md``):

* ``kappa^(2/3)`` means ``|kappa|^(2/3) = cbrt(kappa^2)``; printed literally it is NaN
  wherever kappa < 0.
* The cubic-class formulas (3.27)-(3.44) hold for traversal towards +x in the
  canonical frame; callers try both signs of kappa.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from recognition.curves.families import CurveKind
from recognition.errors import DegenerateGeometry, InvalidCurveData, NoRealSolution

__all__ = [
    "CubicSplineGFit",
    "CubicSplineGSolution",
    "abs_two_thirds",
    "conic_invariant_1",
    "conic_invariant_2",
    "conic_invariants_regression",
    "contact_parameter",
    "cubic_spline_c",
    "cubic_spline_from_contact",
    "cubic_spline_residual",
    "cubical_parabola_invariant_1",
    "cubical_parabola_invariant_2",
    "cubical_parabola_slope_quartic",
    "ellipse_parameters",
    "fit_cubic_spline_g",
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


# --- Cubic spline: least-squares fit of g (Section 3.2.2.3) -----------------------------

#: Two local solutions closer than this (relative in a, absolute in b and slope angle)
#: are the same solution.
SOLUTION_MERGE_TOL = 1e-6
#: Largest ``sum_i g_i^2`` (g is dimensionless) of a solution that counts as g = 0 on
#: exact data; noisy estimates need a larger value.
ZERO_COST_TOL = 1e-20
#: |g| is capped at this value (and NaN replaced by it) during the search.
RESIDUAL_CAP = 1e6


@dataclass(frozen=True)
class CubicSplineGSolution:
    """One local minimum of ``sum_i g(a, b, lambda_i)^2`` (Section 3.2.2.3).

    Attributes
    ----------
    a, b : float
        Shape parameters of the spline (3.35), ``a > 0`` (g depends on a^2 only).
    lambda1 : float
        Slope at the first contact in the canonical frame.
    slopes : (m,) float
        Slope at every contact, from lambda1 by (3.29).
    cost : float
        ``sum_i g(a, b, lambda_i)^2`` at the solution.
    c : (m,) float
        Third shape parameter from each contact by the formula after (3.44).
    """

    a: float
    b: float
    lambda1: float
    slopes: np.ndarray
    cost: float
    c: np.ndarray

    @property
    def c_spread(self) -> float:
        """Relative spread std(c) / |mean(c)| of the per-contact c; 0 on the true shape."""
        return float(np.std(self.c) / max(abs(np.mean(self.c)), 1e-300))


@dataclass(frozen=True)
class CubicSplineGFit:
    """Every distinct local solution of the thesis's g least-squares problem.

    Attributes
    ----------
    solutions : tuple of CubicSplineGSolution
        Distinct local minima, in order of increasing cost.
    n_starts : int
        Number of seeded starting points tried.
    """

    solutions: tuple[CubicSplineGSolution, ...]
    n_starts: int

    def zero_cost(self, tol: float = ZERO_COST_TOL) -> tuple[CubicSplineGSolution, ...]:
        """The solutions with ``cost <= tol``: g vanishes at every contact."""
        return tuple(s for s in self.solutions if s.cost <= tol)

    def most_consistent(self, tol: float = ZERO_COST_TOL) -> CubicSplineGSolution:
        """The zero-cost solution whose c agrees best across contacts (errata item 7).

        Raises :class:`NoRealSolution` when no solution has zero cost.
        """
        candidates = self.zero_cost(tol)
        if not candidates:
            raise NoRealSolution(
                "no (a, b, lambda1) makes g vanish at every contact: the contacts are not on "
                "one cubic spline (3.35) traversed towards +x"
            )
        return min(candidates, key=lambda s: s.c_spread)


def _batched_levenberg_marquardt(residuals, X0, *, max_iterations=200, step_tol=1e-13):
    """Minimise ``sum(residuals(x)^2)`` from every row of ``X0`` at once.

    ``residuals`` maps (S, n) to (S, m). The Jacobian is a central difference; each start
    keeps its own damping. Returns the final points (S, n) and costs (S,).
    """
    X = np.array(X0, dtype=float)
    S, n = X.shape
    r = residuals(X)
    cost = np.sum(r * r, axis=1)
    damping = np.full(S, 1e-3)
    active = np.ones(S, dtype=bool)
    eye = np.eye(n)
    for _ in range(max_iterations):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        x = X[idx]
        h = 1e-7 * np.maximum(1.0, np.abs(x))
        shifted = np.concatenate(
            [x[:, None, :] + h[:, None, :] * eye, x[:, None, :] - h[:, None, :] * eye], axis=1
        )  # (s, 2n, n)
        F = residuals(shifted.reshape(-1, n)).reshape(idx.size, 2 * n, -1)
        J = ((F[:, :n] - F[:, n:]) / (2.0 * h[:, :, None])).transpose(0, 2, 1)  # (s, m, n)
        JtJ = np.einsum("smi,smj->sij", J, J)
        Jtr = np.einsum("smi,sm->si", J, r[idx])
        diag = np.einsum("sii->si", JtJ)
        A = JtJ + damping[idx, None, None] * diag[:, :, None] * eye
        with np.errstate(all="ignore"):
            step = -np.einsum("sij,sj->si", np.linalg.pinv(A), Jtr)
        step = np.where(np.isfinite(step), step, 0.0)
        trial = x + step
        r_trial = residuals(trial)
        cost_trial = np.sum(r_trial * r_trial, axis=1)
        better = cost_trial < cost[idx]
        X[idx[better]] = trial[better]
        r[idx[better]] = r_trial[better]
        cost[idx[better]] = cost_trial[better]
        damping[idx] = np.where(better, damping[idx] / 3.0, damping[idx] * 4.0)
        small = np.max(np.abs(step) / np.maximum(1.0, np.abs(x)), axis=1) < step_tol
        active[idx] = ~(small | (damping[idx] > 1e12) | (cost[idx] == 0.0))
    return X, cost


def fit_cubic_spline_g(
    kappa,
    kappa_s,
    dphi,
    *,
    rng: np.random.Generator,
    n_starts: int = 64,
) -> CubicSplineGFit:
    """Least-squares estimate of (a, b, lambda1) of a cubic spline, Section 3.2.2.3.

    Minimises ``sum_i g(a, b, lambda_i)^2`` where g is (3.44) divided by ``81 M a^4``
    (:func:`cubic_spline_residual`) and ``lambda_i = tan(arctan(lambda1) + dphi_i)`` by
    (3.29). The unknowns are ``(log a, b, arctan(lambda1))``; ``n_starts`` local
    Levenberg-Marquardt solves start from seeded random points with ``a`` spread over
    two decades around ``sqrt(median |kappa|)`` (a has the unit length^(-1/2)),
    ``b`` in [-3, 3] and the slope angle uniform. Every distinct local minimum is
    returned with its cost and with c at each contact (formula after (3.44),
    :func:`cubic_spline_c`).

    g = 0 at three contacts does not fix the shape (THESIS_ERRATA item 7): with three
    contacts there are often two or more zero-cost solutions with a > 0, and only the
    true one gives the same c at every contact (use
    :meth:`CubicSplineGFit.most_consistent`). With more contacts the problem is
    overdetermined and spurious zeros are rare. The search can miss the true solution
    when its basin is narrow or the contacts are ill-conditioned (two contacts close
    together, or near an inflection); more starts help with the former only. One contact
    and its parameter t fix the shape in closed form (:func:`cubic_spline_from_contact`).

    The formulas hold for traversal towards +x in the canonical frame; for the other
    direction pass ``-kappa`` (errata item 4).

    Parameters
    ----------
    kappa, kappa_s : (m,) float
        Curvature and its arc-length derivative at m >= 3 contacts.
    dphi : (m,) float
        Tangent rotation of each contact from the first (radians).
    rng : numpy.random.Generator
        Source of the starting points.
    n_starts : int
        Number of starting points.
    """
    kappa, kappa_s, dphi = (np.asarray(v, dtype=float).ravel() for v in (kappa, kappa_s, dphi))
    m = kappa.size
    if m < 3 or kappa_s.shape != (m,) or dphi.shape != (m,):
        raise InvalidCurveData(
            f"expected kappa, kappa_s and dphi at the same m >= 3 contacts, got sizes "
            f"{kappa.size}, {kappa_s.size}, {dphi.size}"
        )
    if not (
        np.all(np.isfinite(kappa)) and np.all(np.isfinite(kappa_s)) and np.all(np.isfinite(dphi))
    ):
        raise InvalidCurveData("kappa, kappa_s and dphi must be finite; got NaN or infinity")
    if np.any(kappa == 0):
        raise DegenerateGeometry("g divides by kappa^2: every contact needs kappa != 0")
    if n_starts < 1:
        raise InvalidCurveData(f"n_starts must be >= 1, got {n_starts}")
    dphi = dphi - dphi[0]

    def residuals(X):  # (S, 3) -> (S, m)
        with np.errstate(all="ignore"):
            g = cubic_spline_residual(
                np.exp(X[:, :1]), X[:, 1:2], np.tan(X[:, 2:3] + dphi), kappa, kappa_s
            )
        return np.clip(np.where(np.isfinite(g), g, RESIDUAL_CAP), -RESIDUAL_CAP, RESIDUAL_CAP)

    log_a0 = 0.5 * np.log(np.median(np.abs(kappa)))
    starts = np.column_stack(
        [
            log_a0 + rng.uniform(np.log(0.1), np.log(10.0), n_starts),
            rng.uniform(-3.0, 3.0, n_starts),
            rng.uniform(-np.pi / 2, np.pi / 2, n_starts),
        ]
    )
    X, cost = _batched_levenberg_marquardt(residuals, starts)
    X[:, 2] = np.mod(X[:, 2] + np.pi / 2, np.pi) - np.pi / 2
    keep = np.isfinite(cost) & (np.abs(X[:, 0]) < 700.0)
    found: list[tuple[float, float, float, float]] = []
    for i in np.flatnonzero(keep)[np.argsort(cost[keep], kind="stable")]:
        a, b, angle = float(np.exp(X[i, 0])), float(X[i, 1]), float(X[i, 2])
        duplicate = any(
            abs(a - fa) <= SOLUTION_MERGE_TOL * fa
            and abs(b - fb) <= SOLUTION_MERGE_TOL * max(1.0, abs(fb))
            and abs(np.sin(angle - fangle)) <= SOLUTION_MERGE_TOL
            for fa, fb, fangle, _ in found
        )
        if not duplicate:
            found.append((a, b, angle, float(cost[i])))
    solutions = []
    for a, b, angle, c_cost in found:
        slopes = np.tan(angle + dphi)
        with np.errstate(all="ignore"):
            c = cubic_spline_c(a, b, slopes, kappa, kappa_s)
        solutions.append(CubicSplineGSolution(a, b, float(np.tan(angle)), slopes, c_cost, c))
    return CubicSplineGFit(tuple(solutions), int(n_starts))


# --- Contact parameters (Section 3.3.1) -------------------------------------------------

#: An ellipse with |a^2 - b^2| below this fraction of a^2 is a circle.
DEGENERATE_CIRCLE_TOL = 1e-12


def contact_parameter(kind, params, kappa, kappa_s, lam=None):
    """Parameter t of each contact on the canonical curve, thesis Section 3.3.1.

    With the corrections of THESIS_ERRATA item 5:

    * parabola: ``t = kappa_s / (3 kappa^2)``;
    * ellipse: ``t0 = arcsin(sqrt(((ab/|kappa|)^(2/3) - b^2) / (a^2 - b^2)))`` is right
      only in the first quadrant; ``t = t0`` if ``kappa_s (a^2 - b^2) <= 0``, else
      ``pi - t0``. t is determined modulo pi (the ellipse is centrally symmetric) and is
      returned in [0, pi]. A circle (a = b) has no distinguished contact: DegenerateGeometry;
    * hyperbola: the printed arsinh gives |t|; ``t = sign(kappa_s) arsinh(sqrt(
      ((ab/|kappa|)^(2/3) - b^2) / (a^2 + b^2)))``;
    * cubical parabola: ``t = sign(kappa / a) sqrt((lam - b) / (3a))`` for traversal
      towards +x (the printed "+-");
    * semi-cubical parabola: ``t = 2 (lam - b) / (3a)``;
    * cubic spline: ``t = -(M ((b - lam)^2 - 3ac) + 3 (b - lam)) / (6a)`` with
      ``M = (kappa_s + 3 kappa^2 lam) / ((1 + lam^2) kappa^2)``.

    Only the cubical parabola depends on the direction of traversal (through the sign
    of kappa; reversal gives -t, the same point after the rotation by pi that maps the
    curve onto itself); the others use |kappa| or kappa^2, which reversal leaves
    unchanged, as it does kappa_s. The semi-cubical and spline formulas hold on both
    branches t > 0 and t < 0.

    Parameters
    ----------
    kind : CurveKind or str
    params : sequence of float
        Canonical shape parameters: (a,), (a, b) or (a, b, c).
    kappa, kappa_s : (m,) float
        Curvature and its arc-length derivative at each contact.
    lam : (m,) float, optional
        Slope ``dy/dx`` at each contact in the canonical frame; required by the three
        cubic classes.

    Returns
    -------
    (m,) float
    """
    kind = CurveKind(kind)
    kappa = np.asarray(kappa, dtype=float)
    kappa_s = np.asarray(kappa_s, dtype=float)
    if kind in (CurveKind.CUBICAL_PARABOLA, CurveKind.SEMICUBICAL_PARABOLA, CurveKind.CUBIC_SPLINE):
        if lam is None:
            raise InvalidCurveData(f"the contact parameter of a {kind} needs the slopes lam")
        lam = np.asarray(lam, dtype=float)
    expected = {
        CurveKind.PARABOLA: 1,
        CurveKind.ELLIPSE: 2,
        CurveKind.HYPERBOLA: 2,
        CurveKind.CUBICAL_PARABOLA: 2,
        CurveKind.SEMICUBICAL_PARABOLA: 2,
        CurveKind.CUBIC_SPLINE: 3,
    }
    if kind not in expected:
        raise InvalidCurveData(f"{kind} has no contact parameter formula (Section 3.3.1)")
    if len(params) != expected[kind]:
        raise InvalidCurveData(
            f"{kind} takes {expected[kind]} shape parameter(s), got {len(params)}"
        )
    p = tuple(float(v) for v in params)
    if kind is CurveKind.PARABOLA:
        return kappa_s / (3.0 * kappa**2)
    if kind in (CurveKind.ELLIPSE, CurveKind.HYPERBOLA):
        a, b = abs(p[0]), abs(p[1])
        base = np.cbrt((a * b / np.abs(kappa)) ** 2) - b * b
        if kind is CurveKind.HYPERBOLA:
            return np.sign(kappa_s) * np.arcsinh(np.sqrt(np.clip(base / (a * a + b * b), 0, None)))
        denom = a * a - b * b
        if abs(denom) <= DEGENERATE_CIRCLE_TOL * a * a:
            raise DegenerateGeometry("a circle (a = b) has no distinguished contact parameter")
        t0 = np.arcsin(np.sqrt(np.clip(base / denom, 0.0, 1.0)))
        return np.where(kappa_s * denom <= 0, t0, np.pi - t0)
    a, b = p[0], p[1]
    if kind is CurveKind.CUBICAL_PARABOLA:
        return np.sign(kappa / a) * np.sqrt(np.clip((lam - b) / (3.0 * a), 0.0, None))
    if kind is CurveKind.SEMICUBICAL_PARABOLA:
        return 2.0 * (lam - b) / (3.0 * a)
    c = p[2]
    _, M = _spline_L_M(lam, kappa, kappa_s)
    e = b - lam
    return -(M * (e * e - 3.0 * a * c) + 3.0 * e) / (6.0 * a)
