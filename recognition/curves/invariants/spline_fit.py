"""Least-squares fit of the cubic spline's g over the contacts, thesis Section 3.2.2.3."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from recognition.curves.invariants.spline import cubic_spline_c, cubic_spline_residual
from recognition.errors import DegenerateGeometry, InvalidCurveData, NoRealSolution
from recognition.least_squares import (
    Damping,
    LeastSquaresConfig,
    LinearSolve,
    damped_least_squares,
)

__all__ = [
    "G_FIT_SOLVER",
    "JACOBIAN_STEP",
    "RESIDUAL_CAP",
    "SOLUTION_MERGE_TOL",
    "ZERO_COST_TOL",
    "CubicSplineGFit",
    "CubicSplineGSolution",
    "fit_cubic_spline_g",
]

#: Two local solutions closer than this (relative in a, absolute in b and slope angle)
#: are the same solution.
SOLUTION_MERGE_TOL = 1e-6
#: Largest ``sum_i g_i^2`` (g is dimensionless) of a solution that counts as g = 0 on
#: exact data; noisy estimates need a larger value.
ZERO_COST_TOL = 1e-20
#: |g| is capped at this value (and NaN replaced by it) during the search.
RESIDUAL_CAP = 1e6
#: Central-difference step of the Jacobian, relative to max(1, |x|).
JACOBIAN_STEP = 1e-7
#: The local solves: Marquardt's diagonal damping (the unknowns log a, b and the slope
#: angle have different scales), least-norm steps, to a relative step of 1e-13.
G_FIT_SOLVER = LeastSquaresConfig(
    max_iterations=200,
    damping=Damping.DIAGONAL,
    initial_damping=1e-3,
    shrink=1.0 / 3.0,
    grow=4.0,
    max_damping=1e12,
    rtol=0.0,
    step_tol=1e-13,
    solve=LinearSolve.LEAST_NORM,
    least_norm_cutoff=1e-15,  # as numpy.linalg.pinv: the fit's directions differ in scale
)


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


def _linearize(
    residuals: Callable[[np.ndarray], np.ndarray], x: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Residuals (S, m) at the rows of ``x`` (S, n) and their central-difference Jacobian
    (S, m, n), from one batched evaluation of ``residuals``."""
    S, n = x.shape
    h = JACOBIAN_STEP * np.maximum(1.0, np.abs(x))
    eye = np.eye(n)
    points = np.concatenate(
        [x[:, None, :], x[:, None, :] + h[:, None, :] * eye, x[:, None, :] - h[:, None, :] * eye],
        axis=1,
    )  # (S, 2n + 1, n)
    F = residuals(points.reshape(-1, n)).reshape(S, 2 * n + 1, -1)
    J = ((F[:, 1 : n + 1] - F[:, n + 1 :]) / (2.0 * h[:, :, None])).transpose(0, 2, 1)
    return F[:, 0], J


def _relative_step(state: tuple[np.ndarray, ...], step: np.ndarray) -> np.ndarray:
    """Largest step component relative to max(1, |x|), (S,)."""
    return np.max(np.abs(step) / np.maximum(1.0, np.abs(state[0])), axis=1)


def _solve_from_starts(
    residuals: Callable[[np.ndarray], np.ndarray], starts: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Minimise ``sum(residuals(x)^2)`` from every row of ``starts`` (S, n) at once;
    returns the final points (S, n) and costs (S,)."""

    def cost(state: tuple[np.ndarray, ...]) -> np.ndarray:
        r = residuals(state[0])
        return np.sum(r * r, axis=1)

    with np.errstate(all="ignore"):
        result = damped_least_squares(
            (starts,),
            cost=cost,
            linearize=lambda state: _linearize(residuals, state[0]),
            retract=lambda state, step: (state[0] + step,),
            config=G_FIT_SOLVER,
            step_size=_relative_step,
        )
    return result.state[0], result.cost


def fit_cubic_spline_g(
    kappa: ArrayLike,
    kappa_s: ArrayLike,
    dphi: ArrayLike,
    *,
    rng: np.random.Generator,
    n_starts: int = 64,
) -> CubicSplineGFit:
    """Least-squares estimate of (a, b, lambda1) of a cubic spline, thesis Eqs. (3.44)
    and (3.29) (Section 3.2.2.3).

    Minimises ``sum_i g(a, b, lambda_i)^2`` where g is (3.44) divided by ``81 M a^4``
    (:func:`cubic_spline_residual`) and ``lambda_i = tan(arctan(lambda1) + dphi_i)`` by
    (3.29). The unknowns are ``(log a, b, arctan(lambda1))``; ``n_starts`` local
    Levenberg-Marquardt solves (:func:`recognition.least_squares.damped_least_squares`,
    settings :data:`G_FIT_SOLVER`) start from seeded random points with ``a`` spread over
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
    kappa, kappa_s = (np.asarray(v, dtype=float).ravel() for v in (kappa, kappa_s))
    turn = np.asarray(dphi, dtype=float).ravel()
    m = kappa.size
    if m < 3 or kappa_s.shape != (m,) or turn.shape != (m,):
        raise InvalidCurveData(
            f"expected kappa, kappa_s and dphi at the same m >= 3 contacts, got sizes "
            f"{kappa.size}, {kappa_s.size}, {turn.size}"
        )
    if not (
        np.all(np.isfinite(kappa)) and np.all(np.isfinite(kappa_s)) and np.all(np.isfinite(turn))
    ):
        raise InvalidCurveData("kappa, kappa_s and dphi must be finite; got NaN or infinity")
    if np.any(kappa == 0):
        raise DegenerateGeometry("g divides by kappa^2: every contact needs kappa != 0")
    if n_starts < 1:
        raise InvalidCurveData(f"n_starts must be >= 1, got {n_starts}")
    turn = turn - turn[0]

    def residuals(X: np.ndarray) -> np.ndarray:  # (S, 3) -> (S, m)
        with np.errstate(all="ignore"):
            g = cubic_spline_residual(
                np.exp(X[:, :1]), X[:, 1:2], np.tan(X[:, 2:3] + turn), kappa, kappa_s
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
    X, cost = _solve_from_starts(residuals, starts)
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
        slopes = np.tan(angle + turn)
        with np.errstate(all="ignore"):
            c = cubic_spline_c(a, b, slopes, kappa, kappa_s)
        solutions.append(CubicSplineGSolution(a, b, float(np.tan(angle)), slopes, c_cost, c))
    return CubicSplineGFit(tuple(solutions), int(n_starts))
