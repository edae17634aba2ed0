"""Initial hypotheses of each class from the thesis's invariants, refined by the signature fit.

Parabola: I_p (3.10). Ellipse/hyperbola: I_c1, I_c2 by the regression form of
(3.17)/(3.23), sign of I_c1. Cubical and semi-cubical parabola: the slope quartics (3.31)
and (3.34) at two points, slope propagation (3.29), then I_cp1/I_cp2 (3.27)-(3.28) or
I_scp1/I_scp2 (3.32)-(3.33) at every point. Cubic spline (3.35): every spline through
two contacts, by elimination (:mod:`.spline_solve`), and on imprecise data also the best
cells of a table of its shapes up to similarity (:mod:`.spline_search`). Contact parameters t from
Section 3.3.1 with the corrections of errata item 5.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from recognition.curves import invariants as inv
from recognition.curves.families import SLOPE_CLASSES, CurveKind
from recognition.curves.recognition.angle_search import angle_starts
from recognition.curves.recognition.results import ClassFit
from recognition.curves.recognition.signature_fit import (
    SIGNATURE_SOLVER,
    ContactData,
    Guess,
    initial_guess,
    precise,
    refine_best,
    rejected,
)
from recognition.curves.recognition.spline_search import spline_starts
from recognition.curves.recognition.spline_solve import spline_candidates
from recognition.errors import DegenerateGeometry, InvalidCurveData, NoRealSolution
from recognition.least_squares import LeastSquaresConfig

__all__ = [
    "PRECISE_SPLINE_SOLVER",
    "SMALL_KAPPA_FRACTION",
    "SPLINE_REFINED",
    "SPLINE_REFINED_PRECISE",
    "Test",
    "fit_conics",
    "fit_cubic_spline",
    "fit_cubical_parabola",
    "fit_hypothesis",
    "fit_parabola",
    "fit_semicubical_parabola",
]

#: Estimates whose |kappa| is below this fraction of the largest are left out of the
#: conic invariants, which divide by kappa (inflections are not conic points).
SMALL_KAPPA_FRACTION = 1e-3
#: Starting shapes of the cubic spline refined together; on precise data the splines
#: through two contacts are exact and the fewer best of them suffice.
SPLINE_REFINED = 12
SPLINE_REFINED_PRECISE = 3
#: On precise data those starts are exact for a spline, whose fit stops at once; the
#: iterations only measure how far a curve of no class is from every spline, and stop
#: when a step lowers the cost by less than 1e-3 of it, or after 25 iterations.
PRECISE_SPLINE_SOLVER = replace(SIGNATURE_SOLVER, rtol=1e-3, max_iterations=25)
#: Starts of a class from kappa and phi alone (:mod:`.angle_search`), added on imprecise
#: data, and the guesses of such a class refined.
ANGLE_STARTS = 6
ANGLE_REFINED = 6


def _with_angle_starts(
    kind: CurveKind, guesses: list[Guess], data: ContactData
) -> tuple[list[Guess], int]:
    """``guesses`` plus the kappa-phi starts of ``kind`` when the data are imprecise and
    have tangent angles, and the number of guesses to refine."""
    if data.phi is None or precise(data):
        return guesses, 2
    weight = (data.kappa / data.sigma_kappa) ** 2
    extra = [
        Guess(params, t, psi, sigma, {})
        for params, t, psi, sigma in angle_starts(kind, data.kappa, data.phi, weight, ANGLE_STARTS)
    ]
    return guesses + extra, ANGLE_REFINED


@dataclass(frozen=True)
class Test:
    """The consistency test the fits are made for: a class whose best initial guess is
    far beyond its acceptance statistic is not refined (:func:`refine_best`).

    Attributes
    ----------
    significance : float or None
        Significance of the chi-square test; None refines every class.
    tolerance : float or None
        The reduced-residual tolerance, in the tolerance mode.
    """

    significance: float | None = None
    tolerance: float | None = None


def _refine(
    kind: CurveKind,
    guesses: list[Guess],
    data: ContactData,
    message: str,
    test: Test,
    n_refined: int = 2,
    solver: LeastSquaresConfig = SIGNATURE_SOLVER,
) -> ClassFit:
    return refine_best(
        kind, guesses, data, message, n_refined, test.significance, test.tolerance, solver
    )


def fit_parabola(data: ContactData, test: Test = Test()) -> ClassFit:
    """The parabola from the median of I_p, thesis Eqs. (3.9)-(3.10), refined."""
    i_p = inv.parabola_invariant(data.kappa, data.kappa_s)
    a = float(inv.parabola_parameter(np.median(i_p)))
    t = inv.contact_parameter(CurveKind.PARABOLA, (a,), data.kappa, data.kappa_s)
    sigma = -np.sign(np.mean(data.kappa)) or 1.0  # canonical kappa < 0 (3.5)
    guess = initial_guess(data, CurveKind.PARABOLA, (a,), t, sigma, {"I_p": i_p})
    guesses, n = _with_angle_starts(CurveKind.PARABOLA, [guess], data)
    guesses = [Guess(g.params, g.t, g.psi, g.sigma, {"I_p": i_p}) for g in guesses]
    return _refine(CurveKind.PARABOLA, guesses, data, "I_p is not finite", test, n)


def _conic_contact_parameters(
    kind: CurveKind, a: float, b: float, kappa: np.ndarray, kappa_s: np.ndarray
) -> np.ndarray:
    """Contact parameters on an ellipse or hyperbola (thesis Section 3.3.1, errata item
    5); on an ellipse on one branch modulo pi, on a circle all 0 (any t fits)."""
    try:
        t = inv.contact_parameter(kind, (a, b), kappa, kappa_s)
    except DegenerateGeometry:  # a circle: any t
        return np.zeros_like(kappa)
    if kind is CurveKind.ELLIPSE:
        # contacts are known modulo pi (central symmetry); keep them on one branch
        return np.unwrap(t, period=np.pi)
    return t


def fit_conics(data: ContactData, test: Test = Test()) -> list[ClassFit]:
    """Ellipse and hyperbola from the regression form of I_c1, I_c2, thesis
    Eqs. (3.17)-(3.24) (and on imprecise data from kappa and phi), each refined; in that
    order."""
    kinds = (CurveKind.ELLIPSE, CurveKind.HYPERBOLA)
    significant = np.abs(data.kappa) > 3.0 * data.sigma_kappa
    signs = np.sign(data.kappa[significant])
    if np.any(signs > 0) and np.any(signs < 0):
        return [rejected(k, "kappa changes sign: a conic has no inflection") for k in kinds]
    keep = np.abs(data.kappa) >= SMALL_KAPPA_FRACTION * np.abs(data.kappa).max()
    invariants: dict[str, np.ndarray] = {}
    reason = ""
    try:
        i_c1, i_c2, _ = inv.conic_invariants_regression(data.kappa[keep], data.kappa_s[keep])
    except DegenerateGeometry as exc:
        if np.ptp(data.kappa) <= 1e-6 * np.abs(data.kappa).max():
            # constant curvature: a circle, the ellipse with a = b
            r = float(1.0 / np.abs(data.kappa).mean())
            sigma = np.sign(data.kappa[0])
            t = sigma * (
                np.concatenate([[0.0], np.cumsum(np.diff(data.phi))])
                if data.phi is not None
                else np.zeros(data.m)
            )
            guess = initial_guess(data, CurveKind.ELLIPSE, (r, r), t, sigma, {})
            return [
                _refine(CurveKind.ELLIPSE, [guess], data, "not a circle", test),
                rejected(CurveKind.HYPERBOLA, "constant curvature is a circle"),
            ]
        i_c1 = i_c2 = float("nan")
        reason = str(exc)
    else:
        k1, ks1 = data.kappa[:-1], data.kappa_s[:-1]
        k2, ks2 = data.kappa[1:], data.kappa_s[1:]
        invariants = {
            "I_c1": inv.conic_invariant_1(k1, ks1, k2, ks2),
            "I_c2": inv.conic_invariant_2(k1, ks1, k2, ks2),
        }
    fits = []
    for kind in kinds:
        guesses: list[Guess] = []
        why = reason
        if not why:
            try:
                if kind is CurveKind.ELLIPSE:
                    a, b = inv.ellipse_parameters(i_c1, i_c2)
                    sigma = np.sign(np.mean(data.kappa))  # canonical kappa > 0 (3.11)
                else:
                    a, b = inv.hyperbola_parameters(i_c1, i_c2)
                    sigma = -np.sign(np.mean(data.kappa))  # canonical kappa < 0 (3.21)
                t = _conic_contact_parameters(kind, a, b, data.kappa, data.kappa_s)
                guesses.append(initial_guess(data, kind, (a, b), t, sigma, invariants))
            except DegenerateGeometry as exc:
                why = str(exc)
        guesses, n = _with_angle_starts(kind, guesses, data)
        if not guesses:
            fits.append(rejected(kind, why))
            continue
        guesses = [Guess(g.params, g.t, g.psi, g.sigma, invariants) for g in guesses]
        fits.append(_refine(kind, guesses, data, "the conic invariants are not finite", test, n))
    return fits


def _quartic_slopes(kind: CurveKind, data: ContactData, sign: float) -> np.ndarray:
    """Candidate slopes at the first estimate from the quartic at several pairs of points,
    thesis Eq. (3.31) or its semi-cubical counterpart."""
    quartic = (
        inv.cubical_parabola_slope_quartic
        if kind is CurveKind.CUBICAL_PARABOLA
        else inv.semicubical_parabola_slope_quartic
    )
    k, ks, phi = sign * data.kappa, data.kappa_s, data.measured_phi
    roots: list[float] = []
    for j in sorted({data.m // 3, data.m // 2, data.m - 1} - {0}):
        coefficients = quartic(k[0], ks[0], k[j], ks[j], np.tan(phi[j] - phi[0]))
        if not np.all(np.isfinite(coefficients)):
            continue
        try:
            roots.extend(inv.real_slopes(coefficients))
        except NoRealSolution:
            continue
    return np.unique(np.round(roots, 12))


def fit_cubical_parabola(data: ContactData, test: Test = Test()) -> ClassFit:
    """The cubical parabola from the slope quartic (3.31), slope propagation (3.29) and
    the medians of I_cp1, I_cp2, thesis Eqs. (3.27)-(3.28), refined."""
    kind = CurveKind.CUBICAL_PARABOLA
    guesses = []
    for lam1 in _quartic_slopes(kind, data, 1.0):
        lam = inv.propagate_slope(lam1, data.measured_phi)
        i1 = inv.cubical_parabola_invariant_1(lam, data.kappa, data.kappa_s)
        i2 = inv.cubical_parabola_invariant_2(lam, data.kappa, data.kappa_s)
        a, b = float(np.nanmedian(i1)), float(np.nanmedian(i2))
        # Section 3.3.1: t = +-sqrt((lam - b) / (3a)), sign(t) = sign(kappa / a)
        t = inv.contact_parameter(kind, (a, b), data.kappa, data.kappa_s, lam)
        invariants = {"I_cp1": i1, "I_cp2": i2}
        guesses += [initial_guess(data, kind, (a, b), t, s, invariants) for s in (1.0, -1.0)]
    guesses, n = _with_angle_starts(kind, guesses, data)
    return _refine(kind, guesses, data, "no real slope solves the quartic (3.31)", test, n)


def fit_semicubical_parabola(data: ContactData, test: Test = Test()) -> ClassFit:
    """The semi-cubical parabola from its slope quartic (after (3.34)), slope propagation
    (3.29) and the medians of I_scp1, I_scp2, thesis Eqs. (3.32)-(3.33), refined."""
    kind = CurveKind.SEMICUBICAL_PARABOLA
    guesses = []
    for sign in (1.0, -1.0):  # errata item 4: traversal towards +x or -x
        for lam1 in _quartic_slopes(kind, data, sign):
            lam = inv.propagate_slope(lam1, data.measured_phi)
            i1 = inv.semicubical_parabola_invariant_1(lam, sign * data.kappa, data.kappa_s)
            i2 = inv.semicubical_parabola_invariant_2(lam, sign * data.kappa, data.kappa_s)
            a, b = float(np.nanmedian(i1)), float(np.nanmedian(i2))
            t = inv.contact_parameter(kind, (a, b), sign * data.kappa, data.kappa_s, lam)
            sigma = sign * (np.sign(np.median(t)) or 1.0)
            guesses.append(
                initial_guess(data, kind, (a, b), t, sigma, {"I_scp1": i1, "I_scp2": i2})
            )
    guesses, n = _with_angle_starts(kind, guesses, data)
    message = "no real slope solves the semi-cubical quartic"
    return _refine(kind, guesses, data, message, test, n)


def _spline_pairs(m: int) -> list[tuple[int, int]]:
    """Pairs of contacts that fix the spline's candidates: the first and the last; on
    more contacts also the first and the middle, the middle and the last."""
    pairs = [(0, m - 1)]
    if m > 3:
        pairs += [(0, m // 2), (m // 2, m - 1)]
    return pairs


def fit_cubic_spline(data: ContactData, test: Test = Test()) -> ClassFit:
    """The cubic spline (3.35) from every spline through two contacts
    (:func:`~.spline_solve.spline_candidates`, by elimination) and, on imprecise data,
    the best cells of the table of its shapes up to similarity
    (:func:`~.spline_search.spline_starts`), refined together; g of thesis Eq. (3.44) at
    the solution is reported as its invariant."""
    kind = CurveKind.CUBIC_SPLINE
    phi = data.measured_phi
    guesses = []
    for pair in _spline_pairs(data.m):
        found = spline_candidates(data.kappa, data.kappa_s, phi, pair)
        for params, t, psi, sigma in zip(
            found.params, found.t, found.psi, found.sigma, strict=True
        ):
            guesses.append(Guess(tuple(float(v) for v in params), t, float(psi), float(sigma), {}))
    n_refined, gate, solver = SPLINE_REFINED_PRECISE, test, PRECISE_SPLINE_SOLVER
    if not precise(data):
        n_refined, gate, solver = SPLINE_REFINED, Test(), SIGNATURE_SOLVER
        starts = spline_starts(data.kappa, data.kappa_s, phi, SPLINE_REFINED)
        for params, t, psi, sigma in zip(
            starts.params, starts.t, starts.psi, starts.sigma, strict=True
        ):
            guesses.append(Guess(tuple(float(v) for v in params), t, float(psi), float(sigma), {}))
    # on imprecise data the starts are approximate: every one is refined, whatever the test
    message = "no spline shape is consistent with the contacts"
    fit = _refine(kind, guesses, data, message, gate, n_refined, solver)
    if fit.params and fit.psi is not None:
        a, b, _ = fit.params
        lam = np.tan(data.measured_phi + fit.psi)
        # the closed forms hold for traversal towards +x: increasing t where t > 0
        kappa = fit.orientation * np.sign(fit.t) * data.kappa
        g = inv.cubic_spline_residual(a, b, lam, kappa, data.kappa_s)
        fit = replace(fit, invariants={"g": g})
    return fit


def fit_hypothesis(kind: CurveKind, data: ContactData, test: Test = Test()) -> ClassFit:
    """Test one class on the data: its initial hypotheses, refined; rejected without
    tangent rotations when the class needs them."""
    if kind in SLOPE_CLASSES and data.phi is None:
        return rejected(kind, "needs the tangent rotations dphi")
    with np.errstate(all="ignore"):
        if kind is CurveKind.PARABOLA:
            return fit_parabola(data, test)
        if kind in (CurveKind.ELLIPSE, CurveKind.HYPERBOLA):
            return next(f for f in fit_conics(data, test) if f.kind is kind)
        if kind is CurveKind.CUBICAL_PARABOLA:
            return fit_cubical_parabola(data, test)
        if kind is CurveKind.SEMICUBICAL_PARABOLA:
            return fit_semicubical_parabola(data, test)
        if kind is CurveKind.CUBIC_SPLINE:
            return fit_cubic_spline(data, test)
    raise InvalidCurveData(f"{kind} is not a class of the recognition tree")
