"""Initial hypotheses of each class from the thesis's invariants, refined by the signature fit.

Parabola: I_p (3.10). Ellipse/hyperbola: I_c1, I_c2 by the regression form of
(3.17)/(3.23), sign of I_c1. Cubical and semi-cubical parabola: the slope quartics (3.31)
and (3.34) at two points, slope propagation (3.29), then I_cp1/I_cp2 (3.27)-(3.28) or
I_scp1/I_scp2 (3.32)-(3.33) at every point. Cubic spline: one contact and its parameter t
fix (a, b, c) in closed form (errata item 7); (lambda1, t1) is searched on a grid and
scored by consistency at the other contacts. Contact parameters t from Section 3.3.1
with the corrections of errata item 5.
"""

from __future__ import annotations

import numpy as np

from recognition.curves import invariants as inv
from recognition.curves.families import SLOPE_CLASSES, CurveKind
from recognition.curves.recognition.results import ClassFit
from recognition.curves.recognition.signature_fit import (
    ContactData,
    Guess,
    initial_guess,
    refine,
    refine_best,
    rejected,
)
from recognition.errors import DegenerateGeometry, InvalidCurveData, NoRealSolution

__all__ = [
    "SMALL_KAPPA_FRACTION",
    "SPLINE_PSI_BANDS",
    "SPLINE_REFINED",
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


def fit_parabola(data: ContactData) -> ClassFit:
    """The parabola from the median of I_p, thesis Eqs. (3.9)-(3.10), refined."""
    i_p = inv.parabola_invariant(data.kappa, data.kappa_s)
    a = float(inv.parabola_parameter(np.median(i_p)))
    t = inv.contact_parameter(CurveKind.PARABOLA, (a,), data.kappa, data.kappa_s)
    sigma = -np.sign(np.mean(data.kappa)) or 1.0  # canonical kappa < 0 (3.5)
    guess = initial_guess(data, CurveKind.PARABOLA, (a,), t, sigma, {"I_p": i_p})
    return refine(CurveKind.PARABOLA, guess, data)


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


def fit_conics(data: ContactData) -> list[ClassFit]:
    """Ellipse and hyperbola from the regression form of I_c1, I_c2, thesis
    Eqs. (3.17)-(3.24), each refined; in that order."""
    kinds = (CurveKind.ELLIPSE, CurveKind.HYPERBOLA)
    if np.any(np.sign(data.kappa) != np.sign(data.kappa[0])):
        return [rejected(k, "kappa changes sign: a conic has no inflection") for k in kinds]
    keep = np.abs(data.kappa) >= SMALL_KAPPA_FRACTION * np.abs(data.kappa).max()
    try:
        i_c1, i_c2, _ = inv.conic_invariants_regression(data.kappa[keep], data.kappa_s[keep])
    except DegenerateGeometry as exc:
        if np.ptp(data.kappa) > 1e-6 * np.abs(data.kappa).max():
            return [rejected(k, str(exc)) for k in kinds]
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
            refine(CurveKind.ELLIPSE, guess, data),
            rejected(CurveKind.HYPERBOLA, "constant curvature is a circle"),
        ]
    k1, ks1 = data.kappa[:-1], data.kappa_s[:-1]
    k2, ks2 = data.kappa[1:], data.kappa_s[1:]
    with np.errstate(all="ignore"):
        invariants = {
            "I_c1": inv.conic_invariant_1(k1, ks1, k2, ks2),
            "I_c2": inv.conic_invariant_2(k1, ks1, k2, ks2),
        }
    fits = []
    for kind in kinds:
        try:
            if kind is CurveKind.ELLIPSE:
                a, b = inv.ellipse_parameters(i_c1, i_c2)
                sigma = np.sign(np.mean(data.kappa))  # canonical kappa > 0 (3.11)
            else:
                a, b = inv.hyperbola_parameters(i_c1, i_c2)
                sigma = -np.sign(np.mean(data.kappa))  # canonical kappa < 0 (3.21)
        except DegenerateGeometry as exc:
            fits.append(rejected(kind, str(exc)))
            continue
        t = _conic_contact_parameters(kind, a, b, data.kappa, data.kappa_s)
        fits.append(refine(kind, initial_guess(data, kind, (a, b), t, sigma, invariants), data))
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
        with np.errstate(all="ignore"):
            coefficients = quartic(k[0], ks[0], k[j], ks[j], np.tan(phi[j] - phi[0]))
        try:
            roots.extend(inv.real_slopes(coefficients))
        except NoRealSolution:
            continue
    return np.unique(np.round(roots, 12))


def fit_cubical_parabola(data: ContactData) -> ClassFit:
    """The cubical parabola from the slope quartic (3.31), slope propagation (3.29) and
    the medians of I_cp1, I_cp2, thesis Eqs. (3.27)-(3.28), refined."""
    kind = CurveKind.CUBICAL_PARABOLA
    guesses = []
    for lam1 in _quartic_slopes(kind, data, 1.0):
        lam = inv.propagate_slope(lam1, data.measured_phi)
        with np.errstate(all="ignore"):
            i1 = inv.cubical_parabola_invariant_1(lam, data.kappa, data.kappa_s)
            i2 = inv.cubical_parabola_invariant_2(lam, data.kappa, data.kappa_s)
            a, b = float(np.nanmedian(i1)), float(np.nanmedian(i2))
            # Section 3.3.1: t = +-sqrt((lam - b) / (3a)), sign(t) = sign(kappa / a)
            t = inv.contact_parameter(kind, (a, b), data.kappa, data.kappa_s, lam)
        invariants = {"I_cp1": i1, "I_cp2": i2}
        guesses += [initial_guess(data, kind, (a, b), t, s, invariants) for s in (1.0, -1.0)]
    return refine_best(kind, guesses, data, "no real slope solves the quartic (3.31)")


def fit_semicubical_parabola(data: ContactData) -> ClassFit:
    """The semi-cubical parabola from its slope quartic (after (3.34)), slope propagation
    (3.29) and the medians of I_scp1, I_scp2, thesis Eqs. (3.32)-(3.33), refined."""
    kind = CurveKind.SEMICUBICAL_PARABOLA
    guesses = []
    for sign in (1.0, -1.0):  # errata item 4: traversal towards +x or -x
        for lam1 in _quartic_slopes(kind, data, sign):
            lam = inv.propagate_slope(lam1, data.measured_phi)
            with np.errstate(all="ignore"):
                i1 = inv.semicubical_parabola_invariant_1(lam, sign * data.kappa, data.kappa_s)
                i2 = inv.semicubical_parabola_invariant_2(lam, sign * data.kappa, data.kappa_s)
                a, b = float(np.nanmedian(i1)), float(np.nanmedian(i2))
                t = inv.contact_parameter(kind, (a, b), sign * data.kappa, data.kappa_s, lam)
            sigma = sign * (np.sign(np.median(t)) or 1.0)
            guesses.append(
                initial_guess(data, kind, (a, b), t, sigma, {"I_scp1": i1, "I_scp2": i2})
            )
    return refine_best(kind, guesses, data, "no real slope solves the semi-cubical quartic")


def _spline_contact_geometry(
    a: np.ndarray, b: np.ndarray, c: np.ndarray, t: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Exact kappa, kappa_s (increasing t) of x = t^2, y = a t^3 + b t^2 + c t, thesis
    Eqs. (3.1)-(3.2); arguments broadcast."""
    x1, y1 = 2 * t, (3 * a * t + 2 * b) * t + c
    x2, y2 = 2.0, 6 * a * t + 2 * b
    y3 = 6 * a
    sp2 = x1 * x1 + y1 * y1
    cross = x1 * y2 - x2 * y1
    k = cross / sp2**1.5
    dk = x1 * y3 / sp2**1.5 - 3 * cross * (x1 * x2 + y1 * y2) / sp2**2.5
    return k, dk / np.sqrt(sp2)


#: Bands of psi in each of which the spline grid search keeps its best cell.
SPLINE_PSI_BANDS = 6
#: Initial spline guesses refined by least squares.
SPLINE_REFINED = 4


def _spline_guesses(data: ContactData, n_psi: int = 120, n_t: int = 32) -> list[Guess]:
    """Initial spline shapes: closed form at one contact, scored at the others.

    For each rotation psi (slopes lam_i = tan(phi_i + psi)), orientation and t_j on a
    log grid, (a, b, c) follow from a reference contact j (errata item 7); every other
    contact's t solves the slope equation, thesis Eq. (3.39), and its exact kappa, kappa_s are
    compared with the measured ones. References are the contacts at a quarter, half and
    three quarters of the data and the two of largest |kappa| (a contact near an
    inflection is ill-conditioned); in each band of psi the best cell is kept.
    """
    psi = np.linspace(0.0, np.pi, n_psi, endpoint=False)
    lam = np.tan(data.measured_phi[None, :] + psi[:, None])  # (P, m)
    u = np.geomspace(0.03, 6.0, n_t)
    refs = {
        data.m // 4,
        data.m // 2,
        (3 * data.m) // 4,
        *np.argsort(-np.abs(data.kappa))[:2].tolist(),
    }
    guesses = []
    for j in sorted(refs):
        for sign in (1.0, -1.0):
            for t_sign in (1.0, -1.0):
                L = 2.0 * (1.0 + lam[:, j : j + 1] ** 2) ** 1.5 * np.abs(data.kappa[j])
                tj = t_sign * u[None, :] / np.sqrt(L)  # (P, T)
                with np.errstate(all="ignore"):
                    a, b, c = inv.cubic_spline_from_contact(
                        lam[:, j : j + 1], sign * data.kappa[j], data.kappa_s[j], tj
                    )
                    A, B, C = (
                        3.0 * a[..., None],
                        2.0 * (b[..., None] - lam[:, None, :]),
                        c[..., None],
                    )
                    disc = np.sqrt(np.clip(B * B - 4 * A * C, 0.0, None))
                    sigma_inc = sign * t_sign  # traversal sense relative to increasing t
                    roots = np.stack(((-B + disc) / (2 * A), (-B - disc) / (2 * A)))
                    k, ks = _spline_contact_geometry(a[..., None], b[..., None], C, roots)
                    e = (
                        np.abs(sigma_inc * k - data.kappa) / data.kappa_scale
                        + np.abs(ks - data.kappa_s) / data.kappa_s_scale
                    )
                    e = np.where(np.isfinite(e), e, np.inf)
                    total = np.sum(e.min(axis=0), axis=-1)
                # the best cell in each band of psi: distinct basins, not one basin twice
                bands = total.reshape(SPLINE_PSI_BANDS, -1)
                for band, flat in enumerate(np.argmin(bands, axis=1)):
                    if not np.isfinite(bands[band, flat]):
                        continue
                    p, q = np.unravel_index(band * bands.shape[1] + flat, total.shape)
                    # each contact's parameter: the root of (3.39) that fits it best
                    t = roots[np.argmin(e[:, p, q], axis=0), p, q, np.arange(data.m)]
                    params = (a[p, q], b[p, q], c[p, q])
                    sigma = sigma_inc
                    if params[0] < 0:  # t -> -t gives the same curve with (-a, b, -c)
                        params, t, sigma = (-params[0], params[1], -params[2]), -t, -sigma
                    with np.errstate(all="ignore"):
                        g = inv.cubic_spline_residual(
                            a[p, q], b[p, q], lam[p], sign * data.kappa, data.kappa_s
                        )
                    guesses.append(
                        Guess(
                            tuple(float(v) for v in params),
                            t,
                            float(psi[p]),
                            float(sigma),
                            {"g": g},
                        )
                    )
    return guesses


def fit_cubic_spline(data: ContactData) -> ClassFit:
    """The cubic spline (3.35) from the closed form at one contact (errata item 7),
    searched over the rotation and the contact's parameter, refined."""
    return refine_best(
        CurveKind.CUBIC_SPLINE,
        _spline_guesses(data),
        data,
        "no spline shape is consistent with the contacts",
        SPLINE_REFINED,
    )


def fit_hypothesis(kind: CurveKind, data: ContactData) -> ClassFit:
    """Test one class on the data: its initial hypotheses, refined; rejected without
    tangent rotations when the class needs them."""
    if kind in SLOPE_CLASSES and data.phi is None:
        return rejected(kind, "needs the tangent rotations dphi")
    if kind is CurveKind.PARABOLA:
        return fit_parabola(data)
    if kind in (CurveKind.ELLIPSE, CurveKind.HYPERBOLA):
        return next(f for f in fit_conics(data) if f.kind is kind)
    if kind is CurveKind.CUBICAL_PARABOLA:
        return fit_cubical_parabola(data)
    if kind is CurveKind.SEMICUBICAL_PARABOLA:
        return fit_semicubical_parabola(data)
    if kind is CurveKind.CUBIC_SPLINE:
        return fit_cubic_spline(data)
    raise InvalidCurveData(f"{kind} is not a class of the recognition tree")
