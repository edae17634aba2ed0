"""Least-squares fit of the exact canonical signature to the estimates of one class.

Unknowns are the shape parameters, the rotation psi between data and canonical frame
(when tangent rotations are given) and each contact's parameter t_i; residuals are
``kappa_i - sigma kappa(t_i)``, ``kappa_s,i - kappa_s(t_i)`` and
``sin(phi_i + psi - theta(t_i))``, each divided by the standard uncertainty of its datum,
with kappa and kappa_s of the canonical form by thesis Eqs. (3.1)-(3.2). Many starting
hypotheses of a class are refined at once by damped Gauss-Newton steps
(:func:`recognition.least_squares.damped_least_squares`). The fit's chi-square statistic
and p-value (:func:`~recognition.curves.recognition.uncertainty.consistency_test`) say
whether the class is consistent with the data; its reduced RMS residual (divided by the
degrees of freedom left) is the measure of the ``tolerance`` mode.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import chdtri

from recognition.curves.families import (
    N_PARAMETERS,
    CurveKind,
    canonical_derivatives,
    derivative_terms,
)
from recognition.curves.recognition.results import ClassFit, canonical_form
from recognition.curves.recognition.uncertainty import (
    InputUncertainty,
    consistency_test,
    magnitude_scales,
)
from recognition.errors import DegenerateGeometry, InvalidCurveData
from recognition.least_squares import Damping, LeastSquaresConfig, damped_least_squares

__all__ = [
    "GATE_RELATIVE",
    "KEPT_AFTER_SCREENING",
    "MAX_KAPPA",
    "MAX_KAPPA_S",
    "MAX_ROUNDS",
    "N_REFINED",
    "PRECISE_DATA",
    "PROGRESS",
    "REFINE_GATE",
    "SCREENING_SOLVER",
    "SIGNATURE_SOLVER",
    "ContactData",
    "Guess",
    "acceptance_statistic",
    "best_fit",
    "contact_data",
    "initial_guess",
    "precise",
    "psi_guess",
    "reduced_rms",
    "refine",
    "refine_best",
    "rejected",
    "signature_residuals",
]

#: Largest |kappa| (1/length) and |kappa_s| (1/length^2) accepted: the invariants raise
#: kappa to the fourth power and kappa_s to the second.
MAX_KAPPA = 1e60
MAX_KAPPA_S = 1e120
#: A chi-square statistic this small is zero to every test (residuals of 1e-2 standard
#: uncertainties): the fit of a class stops when one of its starts gets there.
STATISTIC_FLOOR = 1e-4


@dataclass(frozen=True)
class ContactData:
    """Checked estimates at m contacts and the standard uncertainty of each.

    Attributes
    ----------
    kappa, kappa_s : (m,) float
        Curvature (1/length) and its arc-length derivative (1/length^2).
    phi : (m,) float or None
        Tangent angles (radians) relative to the first estimate, when measured.
    sigma_kappa, sigma_kappa_s, sigma_phi : (m,) float
        Standard uncertainty of each datum (the residuals are divided by them).
    correlation : (3m, 3m) float or None
        Correlation of the errors (kappa, kappa_s, phi blocks); independent when None.
    cost_floor : float
        A fit whose sum of squared residuals is at most this has converged: with standard
        uncertainties, ``STATISTIC_FLOOR`` (no test tells it from zero); else 0.
    """

    kappa: np.ndarray
    kappa_s: np.ndarray
    phi: np.ndarray | None
    sigma_kappa: np.ndarray
    sigma_kappa_s: np.ndarray
    sigma_phi: np.ndarray
    correlation: np.ndarray | None = None
    cost_floor: float = 0.0

    @property
    def m(self) -> int:
        """Number of contacts."""
        return self.kappa.size

    @property
    def measured_phi(self) -> np.ndarray:
        """The tangent angles; :class:`InvalidCurveData` when they were not given."""
        if self.phi is None:
            raise InvalidCurveData("this hypothesis needs the tangent rotations dphi")
        return self.phi

    @property
    def residual_correlation(self) -> np.ndarray | None:
        """Correlation of the residual vector (2m or 3m entries), if known."""
        if self.correlation is None:
            return None
        n = 3 * self.m if self.phi is not None else 2 * self.m
        return self.correlation[:n, :n]

    def subset(self, keep: np.ndarray) -> ContactData:
        """The points ``keep``, tangent angles again relative to the first of them."""
        corr = None
        if self.correlation is not None:
            rows = np.concatenate([keep + k * self.m for k in range(3)])
            corr = self.correlation[np.ix_(rows, rows)]
        return ContactData(
            self.kappa[keep],
            self.kappa_s[keep],
            None if self.phi is None else self.phi[keep] - self.phi[keep][0],
            self.sigma_kappa[keep],
            self.sigma_kappa_s[keep],
            self.sigma_phi[keep],
            corr,
            self.cost_floor,
        )


def _contact_array(value: ArrayLike, name: str, unit: str) -> np.ndarray:
    """One input of the tree as a finite (m,) float array, or InvalidCurveData."""
    try:
        raw = np.asarray(value)
    except (ValueError, TypeError) as exc:
        raise InvalidCurveData(
            f"{name} must be a flat sequence of numbers ({unit}), one per contact; "
            f"got a ragged or unreadable value ({exc})"
        ) from None
    if raw.dtype.kind not in "iuf":
        raise InvalidCurveData(
            f"{name} must hold real numbers ({unit}), one per contact; got dtype {raw.dtype}"
        )
    if raw.ndim != 1:
        raise InvalidCurveData(
            f"{name} must be one-dimensional, one value per contact (m,); got shape {raw.shape}"
        )
    values = raw.astype(float)
    if not np.all(np.isfinite(values)):
        bad = int(np.flatnonzero(~np.isfinite(values))[0])
        raise InvalidCurveData(
            f"{name} must be finite; got {values[bad]} at contact {bad} (NaN or infinity)"
        )
    return values


def contact_data(
    kappa: ArrayLike,
    kappa_s: ArrayLike,
    dphi: ArrayLike | None,
    uncertainty: InputUncertainty | None = None,
) -> ContactData:
    """Check kappa, kappa_s (and the tangent rotations ``dphi``) at m >= 3 contacts.

    Without ``uncertainty`` each residual is relative to :func:`magnitude_scales` and the
    slope residual is taken as is (the ``tolerance`` mode's measure).

    Raises :class:`InvalidCurveData` for non-numeric, ragged, multi-dimensional,
    mismatched, too few, non-finite or out-of-range values and
    :class:`DegenerateGeometry` when kappa is zero everywhere.
    """
    kappa = _contact_array(kappa, "kappa", "1/length")
    kappa_s = _contact_array(kappa_s, "kappa_s", "1/length^2")
    if kappa.shape != kappa_s.shape:
        raise InvalidCurveData(
            f"kappa and kappa_s must have the same length, got {kappa.size} and {kappa_s.size}"
        )
    if kappa.size < 3:
        raise InvalidCurveData(f"expected kappa, kappa_s at three or more points, got {kappa.size}")
    for name, values, limit in (("kappa", kappa, MAX_KAPPA), ("kappa_s", kappa_s, MAX_KAPPA_S)):
        big = np.flatnonzero(np.abs(values) > limit)
        if big.size:
            raise InvalidCurveData(
                f"{name} = {values[big[0]]:.3g} at contact {int(big[0])} is out of range; "
                f"expected |{name}| <= {limit:.0e} (change the length unit)"
            )
    phi: np.ndarray | None = None
    if dphi is not None:
        try:
            phi = _contact_array(dphi, "dphi", "radians")
        except InvalidCurveData as exc:
            raise InvalidCurveData(
                f"dphi must hold {kappa.size} tangent rotations: {exc}"
            ) from None
        if phi.shape != kappa.shape:
            raise InvalidCurveData(
                f"dphi must hold {kappa.size} finite tangent rotations (radians), "
                f"got shape {phi.shape}"
            )
        phi = phi - phi[0]
    if not np.any(kappa != 0):
        raise DegenerateGeometry(
            "kappa is zero at every point: a straight segment has no curvature invariants"
        )
    if uncertainty is None:
        sk, sks = magnitude_scales(kappa, kappa_s)
        return ContactData(kappa, kappa_s, phi, sk, sks, np.ones_like(kappa))
    sk, sks, sphi = uncertainty.standard_deviations(kappa, kappa_s)
    corr = None if uncertainty.correlation is None else np.asarray(uncertainty.correlation, float)
    return ContactData(kappa, kappa_s, phi, sk, sks, sphi, corr, STATISTIC_FLOOR)


def signature_residuals(
    kind: CurveKind,
    params: tuple[np.ndarray, ...],
    t: np.ndarray,
    psi: np.ndarray,
    sigma: np.ndarray,
    data: ContactData,
) -> np.ndarray:
    """Standardised residuals of a batch of hypotheses against the canonical signature,
    thesis Eqs. (3.1)-(3.2).

    ``params`` is a tuple of (B,) arrays, ``t`` (B, m), ``psi`` and ``sigma`` (B,).
    Returns (B, 2m) or (B, 3m): kappa, kappa_s and (with tangent angles) slope blocks,
    each divided by the data's standard uncertainty; non-finite values become 1e6.
    """
    with np.errstate(all="ignore"):
        _, (x1, y1), (x2, y2), (x3, y3) = derivative_terms(kind, params, t)
        speed2 = x1 * x1 + y1 * y1
        speed = np.sqrt(speed2)
        cross = x1 * y2 - x2 * y1
        k = cross / (speed2 * speed)
        dk = (x1 * y3 - x3 * y1) / (speed2 * speed) - 3.0 * cross * (x1 * x2 + y1 * y2) / (
            speed2 * speed2 * speed
        )
        parts = [
            (sigma[:, None] * k - data.kappa) / data.sigma_kappa,
            (dk / speed - data.kappa_s) / data.sigma_kappa_s,
        ]
        if data.phi is not None:
            angle = data.phi + psi[:, None]
            parts.append((np.sin(angle) * x1 - np.cos(angle) * y1) / speed / data.sigma_phi)
        r = np.concatenate(parts, axis=1)
    return np.where(np.isfinite(r), r, 1e6)


@dataclass(frozen=True)
class Guess:
    """An initial hypothesis: shape, contact parameters, rotation and orientation."""

    params: tuple[float, ...]
    t: np.ndarray
    psi: float
    sigma: float
    invariants: dict[str, np.ndarray]


def reduced_rms(r: np.ndarray, n_unknowns: int) -> np.ndarray:
    """RMS residual per degree of freedom left, (B, n_res) -> (B,)."""
    return np.sqrt(np.sum(r**2, axis=-1) / max(r.shape[-1] - n_unknowns, 1))


#: Damped Gauss-Newton settings of the signature fits: Marquardt's diagonal damping, a
#: rejected step retried with more damping in the same iteration, until a step lowers
#: the cost by less than 1e-6 of it or moves no unknown by more than 1e-13 of its size,
#: or 80 iterations.
SIGNATURE_SOLVER = LeastSquaresConfig(
    max_iterations=80,
    damping=Damping.DIAGONAL,
    initial_damping=1e-3,
    shrink=0.1,
    grow=3.0,
    max_damping=1e12,
    rtol=1e-6,
    step_tol=1e-13,
    retry=True,
)
#: Many starts of one class are first refined together for a few iterations; the best
#: KEPT_AFTER_SCREENING of them are then refined to convergence.
SCREENING_SOLVER = replace(SIGNATURE_SOLVER, max_iterations=10)
KEPT_AFTER_SCREENING = 3
#: They continue in rounds of SCREENING_SOLVER iterations while a round lowers the cost
#: below PROGRESS times its value, for MAX_ROUNDS rounds at most.
PROGRESS = 0.95
MAX_ROUNDS = 40
#: Central-difference step of the Jacobian, relative to max(1, |x|).
JACOBIAN_STEP = 1e-7
#: Added to the normal equations, relative to their largest diagonal entry: keeps an
#: unknown the residuals do not depend on (e.g. psi on a circle) from making them singular.
DIAGONAL_FLOOR = 1e-14


class _Problem:
    """The residuals of one class on the data as functions of the stacked unknowns
    ``x = (params, [psi], t_1..t_m)`` of a batch, and their Jacobian."""

    def __init__(self, kind: CurveKind, data: ContactData) -> None:
        self.kind = kind
        self.data = data
        self.n_p = N_PARAMETERS[kind]
        self.use_psi = data.phi is not None
        self.head = self.n_p + (1 if self.use_psi else 0)
        self.blocks = 3 if self.use_psi else 2

    def residuals(self, X: np.ndarray, sigma: np.ndarray) -> np.ndarray:
        params = tuple(X[:, j] for j in range(self.n_p))
        psi = X[:, self.n_p] if self.use_psi else np.zeros(X.shape[0])
        return signature_residuals(self.kind, params, X[:, self.head :], psi, sigma, self.data)

    def linearize(self, X: np.ndarray, sigma: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residuals (B, n) and central-difference Jacobian (B, n, k) in one batched call:
        column by column for the shape and psi, all t_i at once (residual i depends on
        t_i only)."""
        B, k = X.shape
        m, head = self.data.m, self.head
        h = JACOBIAN_STEP * np.maximum(1.0, np.abs(X))
        steps = np.zeros((2 * head + 3, B, k))
        for j in range(head):
            steps[1 + 2 * j, :, j] = h[:, j]
            steps[2 + 2 * j, :, j] = -h[:, j]
        steps[-2, :, head:] = h[:, head:]
        steps[-1, :, head:] = -h[:, head:]
        F = self.residuals((X[None] + steps).reshape(-1, k), np.tile(sigma, 2 * head + 3))
        F = F.reshape(2 * head + 3, B, -1)
        J = np.zeros((B, F.shape[2], k))
        for j in range(head):
            J[:, :, j] = (F[1 + 2 * j] - F[2 + 2 * j]) / (2.0 * h[:, j, None])
        rows = np.arange(self.blocks * m)
        cols = head + np.tile(np.arange(m), self.blocks)
        J[:, rows, cols] = (F[-2] - F[-1]) / (2.0 * np.tile(h[:, head:], self.blocks))
        return F[0], J

    def solve(
        self, X0: np.ndarray, sigma: np.ndarray, config: LeastSquaresConfig = SIGNATURE_SOLVER
    ) -> tuple[np.ndarray, np.ndarray]:
        """Refine every row of ``X0`` at once; returns the solutions and their residuals."""
        k = X0.shape[1]

        def cost(state: tuple[np.ndarray, ...]) -> np.ndarray:
            r = self.residuals(state[0], state[1])
            return np.sum(r * r, axis=1)

        def linearize(state: tuple[np.ndarray, ...]) -> tuple[np.ndarray, np.ndarray]:
            r, J = self.linearize(state[0], state[1])
            floor = DIAGONAL_FLOOR * np.max(np.sum(J * J, axis=1), axis=1) + 1e-300
            J = np.concatenate([J, np.sqrt(floor)[:, None, None] * np.eye(k)], axis=1)
            return np.concatenate([r, np.zeros((r.shape[0], k))], axis=1), J

        def step_size(state: tuple[np.ndarray, ...], step: np.ndarray) -> np.ndarray:
            return np.max(np.abs(step) / np.maximum(1.0, np.abs(state[0])), axis=1)

        with np.errstate(all="ignore"):
            result = damped_least_squares(
                (X0, sigma),
                cost=cost,
                linearize=linearize,
                retract=lambda state, step: (state[0] + step, state[1]),
                config=replace(config, atol=self.data.cost_floor, any_at_atol=True),
                step_size=step_size,
            )
        X = result.state[0]
        return X, self.residuals(X, sigma)


def _class_fit(
    problem: _Problem,
    x: np.ndarray,
    r: np.ndarray,
    sigma: float,
    invariants: dict[str, np.ndarray],
) -> ClassFit:
    """The ClassFit of one refined solution: canonical shape, statistics, per-point residual."""
    kind, data = problem.kind, problem.data
    n_p, head = problem.n_p, problem.head
    psi = float(x[n_p]) if problem.use_psi else 0.0
    params, t, orientation, psi = canonical_form(
        kind, tuple(float(v) for v in x[:n_p]), x[head:], sigma, psi
    )
    _, J = problem.linearize(x[None], np.array([sigma]))
    with np.errstate(all="ignore"):
        statistic, scale, dof, p_value = consistency_test(r, J[0], data.residual_correlation)
    return ClassFit(
        kind,
        params,
        float(reduced_rms(r, x.size)),
        t.copy(),
        float(np.mod(psi, 2 * np.pi)) if problem.use_psi else None,
        int(orientation),
        invariants,
        per_point=np.sqrt(np.sum(r.reshape(-1, data.m) ** 2, axis=0)),
        statistic=statistic,
        scale=scale,
        dof=dof,
        p_value=p_value,
    )


def _stack(guesses: Sequence[Guess], use_psi: bool) -> tuple[np.ndarray, np.ndarray]:
    X = np.array([np.concatenate([g.params, [g.psi] if use_psi else [], g.t]) for g in guesses])
    return X, np.array([g.sigma for g in guesses], dtype=float)


def refine(kind: CurveKind, guess: Guess, data: ContactData) -> ClassFit:
    """Least-squares refinement of (params, psi, t_i) from an initial guess."""
    problem = _Problem(kind, data)
    X0, sigma = _stack([guess], problem.use_psi)
    X, R = problem.solve(X0, sigma)
    return _class_fit(problem, X[0], R[0], float(sigma[0]), guess.invariants)


#: Number of best-scoring initial guesses of a class that are refined.
N_REFINED = 2
#: A class whose best initial guess has a chi-square statistic above REFINE_GATE times
#: its acceptance statistic and an RMS residual relative to the values' magnitudes
#: (:func:`~recognition.curves.recognition.uncertainty.magnitude_scales`) above
#: GATE_RELATIVE is not refined: such a guess is far from the data by any measure, and no
#: fit from one reached consistency in the tests. Only precise data are gated (every
#: uncertainty below PRECISE_DATA relative to its magnitude): their initial guesses are
#: exact for the data's own class.
REFINE_GATE = 1e6
GATE_RELATIVE = 0.01
PRECISE_DATA = 1e-6


def acceptance_statistic(
    n_residuals: int, n_unknowns: int, significance: float, tolerance: float | None = None
) -> float:
    """The largest statistic of a consistent fit with independent errors: the
    ``1 - significance`` quantile of chi-square with the degrees of freedom left, or
    ``tolerance^2`` per degree of freedom (the reduced RMS residual at most ``tolerance``)."""
    dof = max(n_residuals - n_unknowns, 1)
    if tolerance is not None:
        return float(tolerance * tolerance * dof)
    return float(chdtri(dof, significance))


def precise(data: ContactData) -> bool:
    """Whether every uncertainty is below PRECISE_DATA relative to its magnitude."""
    scale_k, scale_ks = magnitude_scales(data.kappa, data.kappa_s)
    relative = np.concatenate(
        [data.sigma_kappa / scale_k, data.sigma_kappa_s / scale_ks, data.sigma_phi]
    )
    return bool(np.all(relative <= PRECISE_DATA))


def _relative_rms(r: np.ndarray, data: ContactData) -> float:
    """RMS of standardised residuals ``r`` re-expressed relative to the values' magnitudes."""
    scale_k, scale_ks = magnitude_scales(data.kappa, data.kappa_s)
    scales = np.concatenate(
        [scale_k / data.sigma_kappa, scale_ks / data.sigma_kappa_s, 1.0 / data.sigma_phi]
    )
    return float(np.sqrt(np.mean((r / scales[: r.size]) ** 2)))


def refine_best(
    kind: CurveKind,
    guesses: list[Guess],
    data: ContactData,
    message: str,
    n_refined: int = N_REFINED,
    significance: float | None = None,
    tolerance: float | None = None,
    solver: LeastSquaresConfig = SIGNATURE_SOLVER,
) -> ClassFit:
    """Score every initial guess in one batch and refine the best ``n_refined`` together
    (with ``solver``; many guesses are screened first, :func:`_screen_and_refine`).

    With ``significance`` (and ``tolerance`` in the tolerance mode), a class whose best
    guess scores above ``REFINE_GATE`` times the :func:`acceptance_statistic` and is
    further than ``GATE_RELATIVE`` from the data is reported unrefined, with the
    statistic of that guess.
    """
    guesses = [g for g in guesses if all(np.isfinite(g.params)) and np.all(np.isfinite(g.t))]
    if not guesses:
        return rejected(kind, message)
    problem = _Problem(kind, data)
    X, sigma = _stack(guesses, problem.use_psi)
    R = problem.residuals(X, sigma)
    score = np.sum(R * R, axis=1)
    order = np.argsort(score, kind="stable")[:n_refined]
    gate = (
        None
        if significance is None or not precise(data)
        else REFINE_GATE * acceptance_statistic(R.shape[1], X.shape[1], significance, tolerance)
    )
    best = order[0]
    if (
        gate is not None
        and not score[best] <= gate
        and _relative_rms(R[best], data) > GATE_RELATIVE
    ):
        fit = _class_fit(problem, X[best], R[best], float(sigma[best]), guesses[best].invariants)
        return replace(fit, message="inconsistent already at the initial guess; not refined")
    X, sigma = X[order], sigma[order]
    if order.size <= KEPT_AFTER_SCREENING:
        X, R = problem.solve(X, sigma, solver)
    else:
        X, R, order = _screen_and_refine(problem, X, sigma, order)
        sigma = np.array([guesses[i].sigma for i in order], dtype=float)
    cost = np.sum(R * R, axis=1)
    best = int(np.argmin(cost))
    invariants = guesses[order[best]].invariants
    return _class_fit(problem, X[best], R[best], float(sigma[best]), invariants)


def _screen_and_refine(
    problem: _Problem, X: np.ndarray, sigma: np.ndarray, order: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Many starts: ``SCREENING_SOLVER`` iterations for all, then the best
    ``KEPT_AFTER_SCREENING`` continue in rounds of as many iterations while a round lowers
    their cost below ``PROGRESS`` times what it was (up to ``MAX_ROUNDS`` rounds)."""
    X, R = problem.solve(X, sigma, SCREENING_SOLVER)
    cost = np.sum(R * R, axis=1)
    kept = np.argsort(cost, kind="stable")[:KEPT_AFTER_SCREENING]
    X, R, sigma, order, cost = X[kept], R[kept], sigma[kept], order[kept], cost[kept]
    active = np.ones(kept.size, dtype=bool)
    for _ in range(MAX_ROUNDS):
        if not active.any():
            break
        rows = np.flatnonzero(active)
        X_new, R_new = problem.solve(X[rows], sigma[rows], SCREENING_SOLVER)
        cost_new = np.sum(R_new * R_new, axis=1)
        better = cost_new < cost[rows]
        X[rows[better]], R[rows[better]] = X_new[better], R_new[better]
        active[rows] = better & (cost_new < PROGRESS * cost[rows]) & (cost_new > 0)
        cost[rows[better]] = cost_new[better]
    return X, R, order


def rejected(kind: CurveKind, message: str) -> ClassFit:
    """A hypothesis rejected outright: no parameters, infinite residual, ``message`` why."""
    return ClassFit(kind, (), float("inf"), np.array([]), None, 1, {}, message)


def psi_guess(data: ContactData, kind: CurveKind, params: tuple[float, ...], t: ArrayLike) -> float:
    """Rotation (radians, modulo pi) taking the data's tangent angles to those of the
    canonical curve at ``t``; 0 without tangent angles."""
    if data.phi is None:
        return 0.0
    d = canonical_derivatives(kind, params, t)
    theta = np.arctan2(d[1, 1], d[1, 0])
    z = np.exp(2j * (theta - data.phi))  # mod pi: orientation is carried by sigma
    return float(np.angle(z.mean()) / 2.0)


def best_fit(fits: Sequence[ClassFit]) -> ClassFit:
    """The hypothesis of smallest residual."""
    return min(fits, key=lambda f: f.residual)


def initial_guess(
    data: ContactData,
    kind: CurveKind,
    params: Sequence[float],
    t: ArrayLike,
    sigma: float,
    invariants: dict[str, np.ndarray],
) -> Guess:
    """A :class:`Guess` of shape ``params``, contacts ``t`` and orientation ``sigma``, its
    rotation from the tangent angles (:func:`psi_guess`)."""
    shape = tuple(float(v) for v in params)
    with np.errstate(all="ignore"):
        psi = psi_guess(data, kind, shape, t)
    return Guess(shape, np.asarray(t, float), psi, float(sigma), invariants)
