"""The recognition tree of thesis Fig. 3.4: class, shape parameters and contact parameters.

Every class hypothesis is initialised from the thesis's invariants and then refined:

1. **Initialisation (thesis).** Parabola: I_p (3.10). Ellipse/hyperbola: I_c1, I_c2 by
   the regression form of (3.17)/(3.23), sign of I_c1. Cubical and semi-cubical
   parabola: the slope quartics (3.31) and (3.34) at two points, slope propagation (3.29),
   then I_cp1/I_cp2 (3.27-3.28) or I_scp1/I_scp2 (3.32-3.33) at every point. Cubic
   spline: one contact and its parameter t fix (a, b, c) in closed form (errata item 7);
   (lambda1, t1) is searched on a grid and scored by consistency at the other contacts.
   Contact parameters t from Section 3.3.1 with the corrections of errata item 5.
2. **Refinement.** A least-squares fit of the exact canonical signature: unknowns are
   the shape parameters, the rotation psi between data and canonical frame (when tangent
   rotations are given) and each contact's parameter t_i; residuals are
   ``kappa_i - sigma kappa(t_i)`` and ``kappa_s,i - kappa_s(t_i)`` (divided by the
   measured magnitude plus its median over the points) and
   ``sin(phi_i + psi - theta(t_i))``. The reduced RMS
   residual (divided by the degrees of freedom left) is the class's consistency
   measure, comparable across classes.
3. **Decision.** If no class has a residual of at most ``tolerance`` the curve is
   ``unclassified``. Otherwise the tree takes the simplest class (parabola; then the
   two-parameter classes; then the cubic spline) whose residual is within
   ``complexity_factor`` of the best, or below ``tolerance / complexity_factor`` (fits
   that good are all exact to within the estimation error): the classes are nested
   (a parabola is a conic and a spline; a semi-cubical parabola is a spline with
   c = 0), so a more complex class must fit clearly better to be preferred.

``tolerance`` must exceed the relative error of the kappa, kappa_s estimates: about
1e-4 for exact samples and finite differences, 1e-2-5e-2 for noisy tactile samples and
:func:`~recognition.curves.estimation.local_fit_geometry` (see README and
``scripts/reproduce_thesis.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import least_squares

from recognition.curves import invariants as inv
from recognition.curves.estimation import LocalGeometry, local_fit_geometry
from recognition.curves.families import (
    N_PARAMETERS,
    CurveKind,
    canonical_derivatives,
    curvature,
    curvature_derivative,
    tangent_angle,
)
from recognition.errors import DegenerateGeometry, InvalidCurveData, NoRealSolution

__all__ = [
    "DEFAULT_TOLERANCE",
    "ClassFit",
    "CurveRecognition",
    "canonical_parameters",
    "fit_class",
    "recognize_curve",
    "recognize_points",
]

#: Default consistency tolerance (reduced relative residual) of :func:`recognize_curve`.
DEFAULT_TOLERANCE = 0.02
#: A more complex class must fit this many times better to be preferred.
COMPLEXITY_FACTOR = 3.0
#: Estimates whose |kappa| is below this fraction of the largest are left out of the
#: conic invariants, which divide by kappa (inflections are not conic points).
SMALL_KAPPA_FRACTION = 1e-3

PARAMETER_NAMES = {1: ("a",), 2: ("a", "b"), 3: ("a", "b", "c")}
CLASS_ORDER = (
    CurveKind.PARABOLA,
    CurveKind.ELLIPSE,
    CurveKind.HYPERBOLA,
    CurveKind.CUBICAL_PARABOLA,
    CurveKind.SEMICUBICAL_PARABOLA,
    CurveKind.CUBIC_SPLINE,
)
NEEDS_SLOPE = {CurveKind.CUBICAL_PARABOLA, CurveKind.SEMICUBICAL_PARABOLA, CurveKind.CUBIC_SPLINE}


@dataclass(frozen=True)
class ClassFit:
    """One class hypothesis tested by the tree.

    Attributes
    ----------
    kind : CurveKind
    params : tuple of float
        Canonical shape parameters (empty when the class was rejected outright).
    residual : float
        Reduced relative residual of the refined fit; ``inf`` when rejected.
    t : (m,) float
        Contact parameter of each estimate in the canonical form.
    psi : float or None
        Rotation (radians) taking data tangent angles to canonical ones, when known.
    orientation : int
        +1 when the data traverse the canonical curve with increasing t, else -1.
    invariants : dict of str to ndarray
        The thesis's invariant values evaluated on the data for this class.
    message : str
        Why the class was rejected, if it was.
    per_point : (m,) float or None
        Each point's residual norm in the final fit (of the points used).
    outliers : tuple of int
        Points left out as estimation outliers (their t is NaN).
    """

    kind: CurveKind
    params: tuple[float, ...]
    residual: float
    t: np.ndarray
    psi: float | None
    orientation: int
    invariants: dict[str, np.ndarray] = field(default_factory=dict)
    message: str = ""
    per_point: np.ndarray | None = None
    outliers: tuple[int, ...] = ()

    @property
    def parameters(self) -> dict[str, float]:
        """Shape parameters by name."""
        return dict(zip(PARAMETER_NAMES.get(len(self.params), ()), self.params, strict=True))


@dataclass(frozen=True)
class CurveRecognition:
    """Result of the recognition tree.

    Attributes
    ----------
    kind : CurveKind
        The recognised class, or ``CurveKind.UNCLASSIFIED``.
    parameters : dict of str to float
        Shape parameters of the canonical form (empty when unclassified).
    contact_parameters : (m,) float
        Parameter t of each contact on the canonical curve (Section 3.3.1).
    invariants : dict of str to ndarray
        Invariant values of the recognised class, e.g. ``{"I_p": ...}``.
    spread : dict of str to float
        Relative spread (std / |mean|) of each invariant.
    residual : float
        Consistency residual of the recognised class (``inf`` if unclassified).
    candidates : tuple of ClassFit
        Every hypothesis tested, in tree order.
    tolerance : float
    """

    kind: CurveKind
    parameters: dict[str, float]
    contact_parameters: np.ndarray
    invariants: dict[str, np.ndarray]
    spread: dict[str, float]
    residual: float
    candidates: tuple[ClassFit, ...]
    tolerance: float

    @property
    def fit(self) -> ClassFit | None:
        """The winning hypothesis, or None if unclassified."""
        return next((c for c in self.candidates if c.kind is self.kind), None)


# --- residual model ---------------------------------------------------------------------


@dataclass(frozen=True)
class _Data:
    kappa: np.ndarray
    kappa_s: np.ndarray
    phi: np.ndarray | None  # tangent angles relative to the first estimate
    kappa_scale: np.ndarray  # per-point scale of kappa residuals
    kappa_s_scale: np.ndarray  # per-point scale of kappa_s residuals

    @property
    def m(self) -> int:
        return self.kappa.size

    def subset(self, keep) -> _Data:
        """The points ``keep``, tangent angles again relative to the first of them."""
        return _Data(
            self.kappa[keep],
            self.kappa_s[keep],
            None if self.phi is None else self.phi[keep] - self.phi[keep][0],
            self.kappa_scale[keep],
            self.kappa_s_scale[keep],
        )


def _make_data(kappa, kappa_s, dphi) -> _Data:
    kappa = np.asarray(kappa, dtype=float).ravel()
    kappa_s = np.asarray(kappa_s, dtype=float).ravel()
    if kappa.shape != kappa_s.shape:
        raise InvalidCurveData(
            f"kappa and kappa_s must have the same length, got {kappa.size} and {kappa_s.size}"
        )
    if kappa.size < 3:
        raise InvalidCurveData(f"expected kappa, kappa_s at three or more points, got {kappa.size}")
    if not (np.all(np.isfinite(kappa)) and np.all(np.isfinite(kappa_s))):
        raise InvalidCurveData("kappa and kappa_s must be finite; got NaN or infinity")
    if dphi is not None:
        dphi = np.asarray(dphi, dtype=float).ravel()
        if dphi.shape != kappa.shape or not np.all(np.isfinite(dphi)):
            raise InvalidCurveData(
                f"dphi must hold {kappa.size} finite tangent rotations (radians), "
                f"got shape {dphi.shape}"
            )
        dphi = dphi - dphi[0]
    kappa_ref = float(np.median(np.abs(kappa)))
    if not np.any(kappa != 0):
        raise DegenerateGeometry(
            "kappa is zero at every point: a straight segment has no curvature invariants"
        )
    # residuals are relative where the values are large and relative to the typical
    # magnitude where they are small: estimation errors grow with |kappa| and |kappa_s|
    kappa_scale = np.abs(kappa) + max(kappa_ref, 1e-300)
    kappa_s_scale = np.abs(kappa_s) + float(np.median(np.abs(kappa_s))) + kappa_ref**2
    return _Data(kappa, kappa_s, dphi, kappa_scale, kappa_s_scale)


def _residuals(kind, params, t, psi, sigma, data: _Data) -> np.ndarray:
    """Relative residuals of a batch of hypotheses.

    ``params`` is a tuple of (B,) arrays, ``t`` (B, m), ``psi`` and ``sigma`` (B,).
    Returns (B, 2m) or (B, 3m): kappa, kappa_s and (with tangent angles) slope blocks.
    """
    with np.errstate(all="ignore"):
        d = canonical_derivatives(kind, params, t)
        k, ks = curvature(d), curvature_derivative(d)
        parts = [
            (sigma[:, None] * k - data.kappa) / data.kappa_scale,
            (ks - data.kappa_s) / data.kappa_s_scale,
        ]
        if data.phi is not None:
            parts.append(np.sin(data.phi + psi[:, None] - tangent_angle(d)))
        r = np.concatenate(parts, axis=1)
    return np.where(np.isfinite(r), r, 1e6)


@dataclass(frozen=True)
class _Guess:
    """An initial hypothesis: shape, contact parameters, rotation and orientation."""

    params: tuple[float, ...]
    t: np.ndarray
    psi: float
    sigma: float
    invariants: dict[str, np.ndarray]


def _reduced_rms(r: np.ndarray, n_unknowns: int) -> np.ndarray:
    """RMS residual per degree of freedom left, (B, n_res) -> (B,)."""
    return np.sqrt(np.sum(r**2, axis=-1) / max(r.shape[-1] - n_unknowns, 1))


def _least_squares(kind, n_p: int, x0: np.ndarray, sigma: float, data: _Data):
    """Minimise the residuals over x = (params, [psi], t_1..t_m); returns (x, residuals).

    The Jacobian is a central difference, taken for all columns in one batched
    evaluation: column by column for the shape parameters and psi, and for all t_i at
    once (residual i depends on t_i only).
    """
    use_psi = data.phi is not None
    head = n_p + (1 if use_psi else 0)
    m = data.m
    n_blocks = 3 if use_psi else 2
    sigma = np.array([sigma])

    def batch(X):
        B = X.shape[0]
        params = tuple(X[:, j] for j in range(n_p))
        psi = X[:, n_p] if use_psi else np.zeros(B)
        return _residuals(kind, params, X[:, head:], psi, np.repeat(sigma, B), data)

    def fun(x):
        return batch(x[None])[0]

    def jac(x):
        h = 1e-6 * np.maximum(1.0, np.abs(x))
        X = np.repeat(x[None], 2 * head + 2, axis=0)
        for j in range(head):
            X[2 * j, j] += h[j]
            X[2 * j + 1, j] -= h[j]
        X[-2, head:] += h[head:]
        X[-1, head:] -= h[head:]
        F = batch(X)
        J = np.zeros((n_blocks * m, x.size))
        J[:, :head] = ((F[0 : 2 * head : 2] - F[1 : 2 * head : 2]) / (2 * h[:head, None])).T
        diag = (F[-2] - F[-1]) / np.tile(2 * h[head:], n_blocks)
        J[np.arange(n_blocks * m), head + np.tile(np.arange(m), n_blocks)] = diag
        return J

    with np.errstate(all="ignore"):
        sol = least_squares(fun, x0, jac=jac, method="lm", x_scale="jac", max_nfev=100)
    return sol.x, sol.fun


#: A point whose residual exceeds this multiple of the median is an estimation outlier.
OUTLIER_FACTOR = 5.0
#: At most this fraction of the points is left out as outliers.
MAX_OUTLIER_FRACTION = 0.1
#: With at least this many points, one outlier may be left out even below 10 points.
MIN_POINTS_FOR_OUTLIERS = 6


def _refine(kind, guess: _Guess, data: _Data) -> ClassFit:
    """Least-squares refinement of (params, psi, t_i) from an initial guess."""
    n_p = len(guess.params)
    use_psi = data.phi is not None
    head = n_p + (1 if use_psi else 0)
    x0 = np.concatenate([guess.params, [guess.psi] if use_psi else [], guess.t])
    x, r = _least_squares(kind, n_p, x0, guess.sigma, data)
    params, t, sigma = _canonical(kind, tuple(float(v) for v in x[:n_p]), x[head:], guess.sigma)
    return ClassFit(
        kind,
        params,
        float(_reduced_rms(r, x0.size)),
        t.copy(),
        float(np.mod(x[n_p], 2 * np.pi)) if use_psi else None,
        int(sigma),
        guess.invariants,
        per_point=np.sqrt(np.sum(r.reshape(-1, data.m) ** 2, axis=0)),
    )


#: Number of best-scoring initial guesses of a class that are refined.
N_REFINED = 2


def _refine_best(
    kind, guesses: list[_Guess], data: _Data, message: str, n_refined: int = N_REFINED
) -> ClassFit:
    """Score every initial guess in one batch and refine the best ``n_refined``."""
    guesses = [g for g in guesses if all(np.isfinite(g.params)) and np.all(np.isfinite(g.t))]
    if not guesses:
        return _rejected(kind, message)
    params = tuple(np.array([g.params[j] for g in guesses]) for j in range(len(guesses[0].params)))
    r = _residuals(
        kind,
        params,
        np.stack([g.t for g in guesses]),
        np.array([g.psi for g in guesses]),
        np.array([g.sigma for g in guesses]),
        data,
    )
    order = np.argsort(_reduced_rms(r, 0))[:n_refined]
    return _best([_refine(kind, guesses[i], data) for i in order])


def _canonical(kind, params, t, sigma):
    """Report equivalent shapes one way: (a, b) positive for conics, a > 0 for x = t^2 classes.

    ``x = t^2, y = a t^3 + b t^2 + c t`` with ``t -> -t`` is the same curve with
    (-a, b, -c), traversed the other way; for the semi-cubical parabola (-a, b).
    """
    p = list(params)
    if kind in (CurveKind.PARABOLA, CurveKind.ELLIPSE, CurveKind.HYPERBOLA):
        p = [abs(v) for v in p]
    elif kind in (CurveKind.SEMICUBICAL_PARABOLA, CurveKind.CUBIC_SPLINE) and p[0] < 0:
        p[0] = -p[0]
        if kind is CurveKind.CUBIC_SPLINE:
            p[2] = -p[2]
        t, sigma = -t, -sigma
    return tuple(p), t, sigma


def canonical_parameters(kind: CurveKind | str, params) -> tuple[float, ...]:
    """The representative of a shape's equivalent parameter sets that the tree reports."""
    kind = CurveKind(kind)
    return _canonical(kind, tuple(float(v) for v in params), np.zeros(0), 1.0)[0]


def _rejected(kind, message) -> ClassFit:
    return ClassFit(kind, (), float("inf"), np.array([]), None, 1, {}, message)


def _psi_guess(data: _Data, kind, params, t):
    if data.phi is None:
        return 0.0
    theta = tangent_angle(canonical_derivatives(kind, params, t))
    z = np.exp(2j * (theta - data.phi))  # mod pi: orientation is carried by sigma
    return float(np.angle(z.mean()) / 2.0)


def _best(fits):
    return min(fits, key=lambda f: f.residual)


# --- class hypotheses -------------------------------------------------------------------


def _guess(data, kind, params, t, sigma, invariants) -> _Guess:
    params = tuple(float(v) for v in params)
    return _Guess(
        params, np.asarray(t, float), _psi_guess(data, kind, params, t), float(sigma), invariants
    )


def _fit_parabola(data: _Data) -> ClassFit:
    i_p = inv.parabola_invariant(data.kappa, data.kappa_s)
    a = float(inv.parabola_parameter(np.median(i_p)))
    t = data.kappa_s / (3.0 * data.kappa**2)  # Section 3.3.1
    sigma = -np.sign(np.mean(data.kappa)) or 1.0  # canonical kappa < 0 (3.5)
    guess = _guess(data, CurveKind.PARABOLA, (a,), t, sigma, {"I_p": i_p})
    return _refine(CurveKind.PARABOLA, guess, data)


def _conic_contact_parameters(kind, a, b, kappa, kappa_s):
    """Contact parameters on an ellipse or hyperbola, Section 3.3.1 with errata item 5."""
    base = np.cbrt((a * b / np.abs(kappa)) ** 2) - b * b
    if kind is CurveKind.ELLIPSE:
        denom = a * a - b * b
        if abs(denom) < 1e-12 * a * a:  # a circle: any t
            return np.zeros_like(kappa)
        t0 = np.arcsin(np.sqrt(np.clip(base / denom, 0.0, 1.0)))
        t = np.where(kappa_s * denom <= 0, t0, np.pi - t0)
        # contacts are known modulo pi (central symmetry); keep them on one branch
        return np.unwrap(t, period=np.pi)
    return np.sign(kappa_s) * np.arcsinh(np.sqrt(np.clip(base / (a * a + b * b), 0.0, None)))


def _fit_conic(data: _Data) -> list[ClassFit]:
    """Ellipse and hyperbola from the regression form of I_c1, I_c2, Eqs. (3.17)-(3.24)."""
    kinds = (CurveKind.ELLIPSE, CurveKind.HYPERBOLA)
    if np.any(np.sign(data.kappa) != np.sign(data.kappa[0])):
        return [_rejected(k, "kappa changes sign: a conic has no inflection") for k in kinds]
    keep = np.abs(data.kappa) >= SMALL_KAPPA_FRACTION * np.abs(data.kappa).max()
    try:
        i_c1, i_c2, _ = inv.conic_invariants_regression(data.kappa[keep], data.kappa_s[keep])
    except DegenerateGeometry as exc:
        if np.ptp(data.kappa) > 1e-6 * np.abs(data.kappa).max():
            return [_rejected(k, str(exc)) for k in kinds]
        # constant curvature: a circle, the ellipse with a = b
        r = float(1.0 / np.abs(data.kappa).mean())
        sigma = np.sign(data.kappa[0])
        t = sigma * (
            np.concatenate([[0.0], np.cumsum(np.diff(data.phi))])
            if data.phi is not None
            else np.zeros(data.m)
        )
        guess = _guess(data, CurveKind.ELLIPSE, (r, r), t, sigma, {})
        return [
            _refine(CurveKind.ELLIPSE, guess, data),
            _rejected(CurveKind.HYPERBOLA, "constant curvature is a circle"),
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
            fits.append(_rejected(kind, str(exc)))
            continue
        t = _conic_contact_parameters(kind, a, b, data.kappa, data.kappa_s)
        fits.append(_refine(kind, _guess(data, kind, (a, b), t, sigma, invariants), data))
    return fits


def _quartic_slopes(kind, data: _Data, sign: float) -> np.ndarray:
    """Candidate slopes at the first estimate from the quartic at several pairs of points."""
    quartic = (
        inv.cubical_parabola_slope_quartic
        if kind is CurveKind.CUBICAL_PARABOLA
        else inv.semicubical_parabola_slope_quartic
    )
    k, ks, phi = sign * data.kappa, data.kappa_s, data.phi
    roots = []
    for j in sorted({data.m // 3, data.m // 2, data.m - 1} - {0}):
        with np.errstate(all="ignore"):
            coefficients = quartic(k[0], ks[0], k[j], ks[j], np.tan(phi[j] - phi[0]))
        try:
            roots.extend(inv.real_slopes(coefficients))
        except NoRealSolution:
            continue
    return np.unique(np.round(roots, 12))


def _fit_cubical_parabola(data: _Data) -> ClassFit:
    kind = CurveKind.CUBICAL_PARABOLA
    guesses = []
    for lam1 in _quartic_slopes(kind, data, 1.0):
        lam = inv.propagate_slope(lam1, data.phi)
        with np.errstate(all="ignore"):
            i1 = inv.cubical_parabola_invariant_1(lam, data.kappa, data.kappa_s)
            i2 = inv.cubical_parabola_invariant_2(lam, data.kappa, data.kappa_s)
            a, b = float(np.nanmedian(i1)), float(np.nanmedian(i2))
            # Section 3.3.1: t = +-sqrt((lam - b) / (3a)), sign(t) = sign(kappa / a)
            t = np.sign(data.kappa / a) * np.sqrt(np.clip((lam - b) / (3.0 * a), 0.0, None))
        invariants = {"I_cp1": i1, "I_cp2": i2}
        guesses += [_guess(data, kind, (a, b), t, s, invariants) for s in (1.0, -1.0)]
    return _refine_best(kind, guesses, data, "no real slope solves the quartic (3.31)")


def _fit_semicubical_parabola(data: _Data) -> ClassFit:
    kind = CurveKind.SEMICUBICAL_PARABOLA
    guesses = []
    for sign in (1.0, -1.0):  # errata item 4: traversal towards +x or -x
        for lam1 in _quartic_slopes(kind, data, sign):
            lam = inv.propagate_slope(lam1, data.phi)
            with np.errstate(all="ignore"):
                i1 = inv.semicubical_parabola_invariant_1(lam, sign * data.kappa, data.kappa_s)
                i2 = inv.semicubical_parabola_invariant_2(lam, sign * data.kappa, data.kappa_s)
                a, b = float(np.nanmedian(i1)), float(np.nanmedian(i2))
                t = 2.0 * (lam - b) / (3.0 * a)  # Section 3.3.1
            sigma = sign * (np.sign(np.median(t)) or 1.0)
            guesses.append(_guess(data, kind, (a, b), t, sigma, {"I_scp1": i1, "I_scp2": i2}))
    return _refine_best(kind, guesses, data, "no real slope solves the semi-cubical quartic")


def _spline_contact_geometry(a, b, c, t):
    """Exact kappa, kappa_s (increasing t) of x = t^2, y = a t^3 + b t^2 + c t, Eqs. (3.1)-(3.2)."""
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


def _spline_guesses(data: _Data, n_psi: int = 120, n_t: int = 32) -> list[_Guess]:
    """Initial spline shapes: closed form at one contact, scored at the others.

    For each rotation psi (slopes lam_i = tan(phi_i + psi)), orientation and t_j on a
    log grid, (a, b, c) follow from a reference contact j (errata item 7); every other
    contact's t solves the slope equation (3.39) and its exact kappa, kappa_s are
    compared with the measured ones. References are the contacts at a quarter, half and
    three quarters of the data and the two of largest |kappa| (a contact near an
    inflection is ill-conditioned); in each band of psi the best cell is kept.
    """
    psi = np.linspace(0.0, np.pi, n_psi, endpoint=False)
    lam = np.tan(data.phi[None, :] + psi[:, None])  # (P, m)
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
                        _Guess(
                            tuple(float(v) for v in params),
                            t,
                            float(psi[p]),
                            float(sigma),
                            {"g": g},
                        )
                    )
    return guesses


def _fit_cubic_spline(data: _Data) -> ClassFit:
    return _refine_best(
        CurveKind.CUBIC_SPLINE,
        _spline_guesses(data),
        data,
        "no spline shape is consistent with the contacts",
        SPLINE_REFINED,
    )


def fit_class(kind: CurveKind | str, kappa, kappa_s, dphi=None) -> ClassFit:
    """Test one class hypothesis on kappa, kappa_s (and tangent rotations ``dphi``)."""
    kind = CurveKind(kind)
    data = _make_data(kappa, kappa_s, dphi)
    return _fit_one(kind, data)


def _fit_one(kind, data: _Data) -> ClassFit:
    """Fit one class; then leave out estimation outliers and fit again from scratch.

    Estimates of kappa_s are least reliable where the curvature changes fastest (a few
    points near a cusp or a sharp bend). After a first fit, at most
    ``MAX_OUTLIER_FRACTION`` of the points (one point from ``MIN_POINTS_FOR_OUTLIERS``
    points up) whose residual exceeds ``OUTLIER_FACTOR`` times the median are left out
    and the class is fitted again, initialisation included, on the rest. Their contact
    parameters are NaN and their indices are in ``ClassFit.outliers``.
    """
    fit = _fit_class_once(kind, data)
    if not np.isfinite(fit.residual) or fit.per_point is None:
        return fit
    per_point = fit.per_point
    n_out = max(int(MAX_OUTLIER_FRACTION * data.m), 1 if data.m >= MIN_POINTS_FOR_OUTLIERS else 0)
    worst = np.argsort(-per_point)[:n_out]
    outliers = np.sort(worst[per_point[worst] > OUTLIER_FACTOR * np.median(per_point)])
    if outliers.size == 0:
        return fit
    keep = np.setdiff1d(np.arange(data.m), outliers)
    again = _fit_class_once(kind, data.subset(keep))
    if not again.residual < fit.residual:
        return fit
    t = np.full(data.m, np.nan)
    t[keep] = again.t
    return replace(again, t=t, outliers=tuple(int(i) for i in outliers))


def _fit_class_once(kind, data: _Data) -> ClassFit:
    if kind in NEEDS_SLOPE and data.phi is None:
        return _rejected(kind, "needs the tangent rotations dphi")
    if kind is CurveKind.PARABOLA:
        return _fit_parabola(data)
    if kind in (CurveKind.ELLIPSE, CurveKind.HYPERBOLA):
        return next(f for f in _fit_conic(data) if f.kind is kind)
    if kind is CurveKind.CUBICAL_PARABOLA:
        return _fit_cubical_parabola(data)
    if kind is CurveKind.SEMICUBICAL_PARABOLA:
        return _fit_semicubical_parabola(data)
    if kind is CurveKind.CUBIC_SPLINE:
        return _fit_cubic_spline(data)
    raise InvalidCurveData(f"{kind} is not a class of the recognition tree")


def _relative_spread(values) -> float:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size < 2:
        return float("nan")
    return float(np.std(v) / max(abs(np.mean(v)), 1e-300))


def recognize_curve(
    kappa,
    kappa_s,
    dphi=None,
    *,
    tolerance: float = DEFAULT_TOLERANCE,
    complexity_factor: float = COMPLEXITY_FACTOR,
) -> CurveRecognition:
    """Recognise a curve from its local geometry at m >= 3 points (thesis Fig. 3.4).

    Parameters
    ----------
    kappa, kappa_s : (m,) float
        Curvature and its arc-length derivative at m points, in order of traversal.
    dphi : (m,) float, optional
        Tangent rotation of each point from the first (radians), e.g. the jaw rotation
        of Section 3.2.2.1 or :attr:`LocalGeometry.dphi`. Without it only the conics can
        be recognised.
    tolerance : float
        Largest reduced relative residual of a consistent class; must exceed the
        relative estimation error of kappa and kappa_s.
    complexity_factor : float
        How much better a more complex class must fit to be preferred.
    """
    if not tolerance > 0:
        raise InvalidCurveData(f"tolerance must be positive, got {tolerance}")
    data = _make_data(kappa, kappa_s, dphi)
    if data.phi is not None and np.ptp(data.phi) < 1e-9:
        raise DegenerateGeometry(
            "the tangent does not turn: a straight segment has no curvature invariants"
        )
    fits = [_fit_one(k, data) for k in CLASS_ORDER]

    chosen = None
    best = _best(fits)
    if best.residual <= tolerance:
        good_enough = max(complexity_factor * best.residual, tolerance / complexity_factor)
        for level in (1, 2, 3):
            at_level = [f for f in fits if N_PARAMETERS[f.kind] == level]
            if at_level and _best(at_level).residual <= good_enough:
                chosen = _best(at_level)
                break
    if chosen is None:
        return CurveRecognition(
            CurveKind.UNCLASSIFIED,
            {},
            np.array([]),
            {},
            {},
            float("inf"),
            tuple(fits),
            tolerance,
        )
    invariants = dict(chosen.invariants)
    if chosen.kind is CurveKind.PARABOLA:
        invariants = {"I_p": invariants["I_p"]}
    return CurveRecognition(
        chosen.kind,
        chosen.parameters,
        chosen.t,
        invariants,
        {name: _relative_spread(v) for name, v in invariants.items()},
        chosen.residual,
        tuple(fits),
        tolerance,
    )


def recognize_points(
    points,
    *,
    n_estimates: int = 25,
    tolerance: float = DEFAULT_TOLERANCE,
    estimator=local_fit_geometry,
    **estimator_options,
) -> tuple[CurveRecognition, LocalGeometry]:
    """Estimate local geometry from ordered tactile points and run the recognition tree.

    ``n_estimates`` evenly spaced estimates (of all the estimator returns) are passed to
    :func:`recognize_curve` together with their tangent rotations.
    Returns the recognition and the estimates used.
    """
    geometry = estimator(points, **estimator_options)
    if len(geometry) < 3:
        raise InvalidCurveData("the estimator returned fewer than three estimates")
    pick = np.unique(np.linspace(0, len(geometry) - 1, min(n_estimates, len(geometry))).round())
    used = geometry.subset(pick.astype(int))
    turn = abs(used.dphi[-1])
    if np.all(np.abs(used.kappa) * (used.s[-1] - used.s[0]) < 1e-6) and turn < 1e-6:
        raise DegenerateGeometry(
            "the points lie on a straight segment (kappa = 0): no curvature invariants exist"
        )
    return recognize_curve(used.kappa, used.kappa_s, used.dphi, tolerance=tolerance), used
