"""Local searches on a closed-form model: over (u, v, phi) and over a rigid motion (4.2.2.2).

From a candidate point, E(u, v, phi) (4.11) is minimised either by the thesis's steepest
descent or (default) by Levenberg-Marquardt on the residuals f / |grad f|, optionally
followed by a Levenberg-Marquardt refinement of all six degrees of freedom of the rigid
motion.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from recognition.least_squares import (
    Damping,
    LeastSquaresConfig,
    LeastSquaresStatus,
    LinearSolve,
    State,
    damped_least_squares,
)
from recognition.surfaces.closed_form.superposition import (
    rigid_motion_residuals,
    superposition_error,
    superposition_error_gradient,
    superposition_residuals,
)
from recognition.surfaces.closed_form.surface import EDGE_MARGIN, ClosedFormSurface

__all__ = ["LocalSearch", "levenberg_marquardt", "refine_rigid_motion", "steepest_descent"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class LocalSearch:
    """Result of one local search (over (u, v, phi), or over a rigid motion).

    Attributes
    ----------
    solution : (k,) float
        Final parameters: (u, v, phi), or a rigid-motion increment for 6 DOF.
    cost : float
        E (4.11) at the solution, model units.
    iterations : int
    status : LeastSquaresStatus
        ``STALLED``: no step near the solution lowers the cost (a minimum).
    trace : (iterations + 1,) float
        E after every iteration, starting point first.
    """

    solution: Array
    cost: float
    iterations: int
    status: LeastSquaresStatus
    trace: Array


def _lm_config(max_iterations: int, tolerance: float) -> LeastSquaresConfig:
    """Levenberg-Marquardt with Marquardt's diagonal scaling, for unit-free parameters:
    a rejected step is retried with more damping, a kept one extended while it helps
    (large residuals, e.g. a wrong model, make J^T J overestimate the cost's curvature)."""
    return LeastSquaresConfig(
        max_iterations=max_iterations,
        damping=Damping.DIAGONAL,
        initial_damping=1e-3,
        shrink=0.1,
        grow=10.0,
        min_damping=1e-12,
        max_damping=1e12,
        rtol=tolerance,
        step_tol=1e-12,
        retry=True,
        extend=True,
        solve=LinearSolve.LEAST_NORM,
    )


def _sum_of_squares(state: State) -> Array:
    r = state[-2][0]
    return np.array([r @ r])


def _mean_distance(state: State) -> Array:
    return np.array([np.abs(state[-2][0]).mean()])


def _linearization(state: State) -> tuple[Array, Array]:
    return state[-2], state[-1]


def _wrap(surface: ClosedFormSurface, x: Array) -> Array:
    u, v = surface.contain(x[0], x[1])
    return np.array([u, v, np.mod(x[2], 2 * np.pi)])


def levenberg_marquardt(
    surface: ClosedFormSurface,
    local_points: Array,
    x0: ArrayLike,
    max_iterations: int = 100,
    tolerance: float = 1e-10,
) -> LocalSearch:
    """Minimise sum r_i^2 over (u, v, phi), r_i = f / |grad f| of (4.11), by Levenberg-Marquardt.

    Marquardt's diagonal scaling makes the step independent of the units of u, v and
    phi; (u, v) stay in the domain (wrapped where periodic; a parameter on an edge of
    the domain is held there while the step would take it out). ``cost`` is E (4.11)
    at the end; ``tolerance`` is the relative decrease of sum r_i^2 at which it stops.
    ``local_points`` (n, 3) are the data points in the local frame at p, model units;
    ``x0`` (3,) is the start (u, v, phi), phi in radians.
    """
    (u0, u1), (v0, v1) = surface.domain
    margin = EDGE_MARGIN * np.array([u1 - u0, v1 - v0])
    lo = np.array([u0, v0]) + margin
    hi = np.array([u1, v1]) - margin
    bounded = ~np.array(surface.periodic)

    def evaluate(x: Array) -> State:
        r, J = superposition_residuals(surface, local_points, *x)
        return x[None], r[None], J[None]

    def retract(state: State, step: Array) -> State:
        return evaluate(_wrap(surface, state[0][0] + step[0]))

    def held(state: State, step: Array) -> NDArray[np.bool_]:
        x = state[0][0]
        out = np.zeros(3, bool)
        out[:2] = bounded & (
            ((x[:2] <= lo) & (step[0, :2] < 0)) | ((x[:2] >= hi) & (step[0, :2] > 0))
        )
        return out[None]

    result = damped_least_squares(
        evaluate(_wrap(surface, np.asarray(x0, float))),
        cost=_sum_of_squares,
        linearize=_linearization,
        retract=retract,
        held=held,
        monitor=_mean_distance,
        config=_lm_config(max_iterations, tolerance),
    )
    trace = result.trace[:, 0]
    return LocalSearch(
        result.state[0][0], float(trace[-1]), int(result.iterations[0]), result.status[0], trace
    )


def _line_minimum(
    fun: Callable[[float], float], f0: float, t0: float, iterations: int = 40
) -> tuple[float, float]:
    """Minimise ``fun(t)`` over t > 0 by bracketing from ``t0`` and golden-section search.

    Returns (t, f(t)); t = 0 if no tried step decreases f below ``f0``.
    """
    a, fa = 0.0, f0
    b, fb = t0, fun(t0)
    while fb >= fa and b > 1e-12 * t0:  # shrink until the first step decreases f
        b *= 0.25
        fb = fun(b)
    if fb >= fa:
        return 0.0, f0
    c, fc = 2.0 * b, fun(2.0 * b)
    while fc < fb:  # grow until f increases: [a, c] brackets a minimum at b
        a, b, fb = b, c, fc
        c, fc = 2.0 * c, fun(2.0 * c)
    golden = 0.5 * (np.sqrt(5.0) - 1.0)
    x1, x2 = c - golden * (c - a), a + golden * (c - a)
    f1, f2 = fun(x1), fun(x2)
    for _ in range(iterations):
        if f1 < f2:
            c, x2, f2 = x2, x1, f1
            x1 = c - golden * (c - a)
            f1 = fun(x1)
        else:
            a, x1, f1 = x1, x2, f2
            x2 = a + golden * (c - a)
            f2 = fun(x2)
        if c - a <= 1e-6 * (c + a):
            break
    best = min(((fb, b), (f1, x1), (f2, x2)))
    return best[1], best[0]


def steepest_descent(
    surface: ClosedFormSurface,
    local_points: Array,
    x0: ArrayLike,
    max_iterations: int = 2000,
    tolerance: float = 1e-10,
) -> LocalSearch:
    """The thesis's steepest descent on E(u, v, phi) (4.11), Section 4.2.2.2.

    Each iteration minimises E along -grad E (bracketing and golden-section search) and
    the search stops when no step along it decreases E ("until no further minimization
    is possible") or E decreases by less than ``tolerance`` relative.
    ``local_points`` (n, 3) are the data points in the local frame at p, model units;
    ``x0`` (3,) is the start (u, v, phi), phi in radians.
    """
    x = _wrap(surface, np.asarray(x0, float))
    E, grad = superposition_error_gradient(surface, local_points, *x)
    trace = [E]
    t = 1e-2 / max(float(np.linalg.norm(grad)), 1e-300)
    status = LeastSquaresStatus.MAX_ITERATIONS
    it = 0
    for _ in range(max_iterations):
        it += 1
        if not np.linalg.norm(grad) > 0:
            status = LeastSquaresStatus.CONVERGED
            trace.append(E)
            break

        def along(step: float, x: Array = x, d: Array = -grad) -> float:
            return float(superposition_error(surface, local_points, *_wrap(surface, x + step * d)))

        t, E_new = _line_minimum(
            along,
            E,
            t,
        )
        if t == 0.0:
            status = LeastSquaresStatus.CONVERGED
            trace.append(E)
            break
        decrease = E - E_new
        x = _wrap(surface, x - t * grad)
        E, grad = superposition_error_gradient(surface, local_points, *x)
        trace.append(E)
        if decrease <= tolerance * E:
            status = LeastSquaresStatus.CONVERGED
            break
    return LocalSearch(x, trace[-1], it, status, np.array(trace))


def refine_rigid_motion(
    surface: ClosedFormSurface,
    local_points: Array,
    R0: ArrayLike,
    c0: ArrayLike,
    max_iterations: int = 50,
    tolerance: float = 1e-10,
) -> tuple[Array, Array, LocalSearch]:
    """Levenberg-Marquardt over all six degrees of freedom of the data's rigid motion.

    The data points in the local frame at p are placed at ``y_i = R x_i + c``; the
    increment (omega, dc) updates ``R <- exp([omega]x) R``, ``c <- c + dc`` (rotation
    about the placed p, which keeps the problem well conditioned).

    Returns
    -------
    R : (3, 3) float
    c : (3,) float
        Where p lands, model frame.
    search : LocalSearch
        ``solution`` is the total increment (rotation vector, translation).
    """

    def evaluate(R: Array, c: Array, total: Array) -> State:
        r, J = rigid_motion_residuals(surface, local_points, R, c)
        return R[None], c[None], total[None], r[None], J[None]

    def retract(state: State, step: Array) -> State:
        R, c, total = state[0][0], state[1][0], state[2][0]
        dR = Rotation.from_rotvec(step[0, :3]).as_matrix()
        return evaluate(dR @ R, c + step[0, 3:], total + step[0])

    result = damped_least_squares(
        evaluate(np.array(R0, float), np.array(c0, float), np.zeros(6)),
        cost=_sum_of_squares,
        linearize=_linearization,
        retract=retract,
        monitor=_mean_distance,
        config=_lm_config(max_iterations, tolerance),
    )
    R, c, total = (a[0] for a in result.state[:3])
    trace = result.trace[:, 0]
    search = LocalSearch(
        total, float(trace[-1]), int(result.iterations[0]), result.status[0], trace
    )
    return R, c, search
