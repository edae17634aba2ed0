"""Damped least squares (Levenberg-Marquardt) over a batch of independent problems.

One solver serves every least-squares fit of the library: the fast mode's pose searches
on distance fields (hundreds of poses at once), the exact polish of a pose on closest
points, the closed-form registration over (u, v, phi) and over a rigid motion, and the
cubic-spline fit of Chapter 3. A problem is a state (a tuple of arrays, each with the
batch on its first axis) that the caller knows how to move (``retract``), to score
(``cost``) and to linearise (``linearize``: residuals r and their Jacobian J with
respect to the step; or ``normal_equations``: J^T J and J^T r at once, for callers that
assemble them faster than the batched products). Each iteration solves, for every problem
still running,

    (J^T J + lambda D) step = -J^T r

with D the identity scaled by trace(J^T J) / n (:attr:`Damping.TRACE`) or Marquardt's
diagonal of J^T J (:attr:`Damping.DIAGONAL`), and keeps the step when it lowers the
cost; lambda shrinks after a kept step and grows after a rejected one. A problem stops
when a kept step lowers its cost by less than ``rtol`` of it, when a kept step is
smaller than ``step_tol`` (as the caller measures steps), when its cost is at most
``atol`` (zero by default), when
lambda exceeds ``max_damping`` (no damping lowers the cost) or after
``max_iterations``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "Damping",
    "LeastSquaresConfig",
    "LeastSquaresResult",
    "LeastSquaresStatus",
    "LinearSolve",
    "State",
    "damped_least_squares",
]

Array = NDArray[np.float64]
State = tuple[np.ndarray, ...]
"""A batch of problem states: arrays whose first axis is the batch."""


class Damping(StrEnum):
    """How lambda scales the damping term."""

    TRACE = "trace"
    """lambda (trace(J^T J) / n + ``trace_floor``) I: one scale for all parameters."""
    DIAGONAL = "diagonal"
    """lambda diag(J^T J) (Marquardt): independent of the parameters' units."""


class LinearSolve(StrEnum):
    """How the damped normal equations are solved."""

    LU = "lu"
    """LU factorisation (the matrix must be regular)."""
    LEAST_NORM = "least_norm"
    """Least-norm solution from the symmetric eigendecomposition; directions whose
    eigenvalue is below ``least_norm_cutoff`` of the largest (exact symmetries of a model)
    take no step."""


class LeastSquaresStatus(StrEnum):
    """Why one problem of the batch stopped."""

    CONVERGED = "converged"
    """A kept step lowered the cost by less than ``rtol``, or moved less than
    ``step_tol``, or the cost is at most ``atol``."""
    STALLED = "stalled"
    """lambda exceeded ``max_damping``: no step near the state lowers the cost."""
    MAX_ITERATIONS = "max_iterations"
    """The iteration limit came first."""


@dataclass(frozen=True)
class LeastSquaresConfig:
    """Settings of :func:`damped_least_squares`.

    Attributes
    ----------
    max_iterations : int
        Iterations at most (an iteration is one trial step, or with ``retry`` one kept
        step with its rejected trials).
    damping : Damping
    initial_damping : float
        lambda at the start.
    shrink, grow : float
        lambda is multiplied by ``shrink`` after a kept step (but stays at least
        ``min_damping``) and by ``grow`` after a rejected one.
    min_damping, max_damping : float
        Bounds of lambda; a problem whose lambda exceeds ``max_damping`` stops.
    trace_floor : float
        Added to trace(J^T J) / n in :attr:`Damping.TRACE` (keeps a zero Jacobian damped).
    rtol : float
        A kept step that lowers the cost by less than this fraction of it ends the
        problem (0: never).
    step_tol : float
        A kept step whose size (``step_size``) is below this ends the problem (0: never).
    atol : float
        A problem whose cost is at or below this has converged (0: only a zero cost).
    any_at_atol : bool
        The batch holds alternative starts of one problem: all stop as soon as one
        reaches ``atol``.
    retry : bool
        A rejected step is tried again with a larger lambda within the same iteration,
        until one is kept or lambda exceeds ``max_damping``.
    extend : bool
        A kept step is doubled, up to 1024 times its length, while that lowers the cost
        further (large residuals make J^T J overestimate the cost's curvature).
    solve : LinearSolve
    least_norm_cutoff : float
        :attr:`LinearSolve.LEAST_NORM`: eigenvalues below this fraction of the largest
        count as zero.
    """

    max_iterations: int = 100
    damping: Damping = Damping.TRACE
    initial_damping: float = 1e-3
    shrink: float = 0.3
    grow: float = 10.0
    min_damping: float = 0.0
    max_damping: float = 1e6
    trace_floor: float = 1e-12
    rtol: float = 1e-4
    step_tol: float = 0.0
    atol: float = 0.0
    any_at_atol: bool = False
    retry: bool = False
    extend: bool = False
    solve: LinearSolve = LinearSolve.LU
    least_norm_cutoff: float = 1e-10


@dataclass(frozen=True)
class LeastSquaresResult:
    """The end of :func:`damped_least_squares` for every problem of the batch.

    Attributes
    ----------
    state : tuple of arrays
        The final states, batch first.
    cost : (B,) float
    iterations : (B,) int
        Iterations each problem ran.
    status : tuple of LeastSquaresStatus
        Per problem.
    trace : (T + 1, B) float
        ``monitor`` (default: the cost) at the start and after each of the T iterations
        the batch ran; a problem that stopped keeps its last value.
    """

    state: State
    cost: Array
    iterations: NDArray[np.int64]
    status: tuple[LeastSquaresStatus, ...]
    trace: Array


def _take(state: State, rows: NDArray[np.intp]) -> State:
    """The ``rows`` (sorted, distinct) of every array; all of them: the state itself (not
    a copy: the solver writes only into states it made)."""
    if rows.size == len(state[0]):
        return state
    return tuple(a[rows] for a in state)


def _put(state: State, rows: NDArray[np.intp], values: State) -> None:
    for a, v in zip(state, values, strict=True):
        a[rows] = v


def _damped(H: Array, lam: Array, config: LeastSquaresConfig) -> Array:
    n = H.shape[-1]
    eye = np.eye(n)
    if config.damping is Damping.TRACE:
        scale = np.trace(H, axis1=1, axis2=2)[:, None, None] / n + config.trace_floor
        return H + (lam[:, None, None] * scale) * eye
    D = np.einsum("bii->bi", H)
    return H + lam[:, None, None] * (D[:, :, None] * eye)


def _solve(M: Array, rhs: Array, config: LeastSquaresConfig) -> Array:
    """Solutions x of M x = rhs for a batch (B, n, n), (B, n)."""
    if config.solve is LinearSolve.LU:
        return np.asarray(np.linalg.solve(M, rhs[..., None])[..., 0], dtype=np.float64)
    w, V = np.linalg.eigh(M)
    out = np.empty_like(rhs)
    for b in range(len(M)):  # the kept directions differ from problem to problem
        keep = w[b] > config.least_norm_cutoff * max(w[b, -1], 1e-300)
        Vk = V[b][:, keep]
        out[b] = Vk @ ((Vk.T @ rhs[b]) / w[b][keep])
    return out


def _steps(
    M: Array,
    g: Array,
    state: State,
    config: LeastSquaresConfig,
    held: Callable[[State, Array], NDArray[np.bool_]] | None,
) -> Array:
    """The damped Gauss-Newton steps; components ``held`` at a bound are kept fixed."""
    step = _solve(M, -g, config)
    if held is None:
        return step
    fixed = np.asarray(held(state, step), bool)
    for b in np.flatnonzero(fixed.any(axis=1)):
        free = ~fixed[b]
        step[b] = 0.0
        if free.any():
            sub = M[b][np.ix_(free, free)][None]
            step[b, free] = _solve(sub, -g[b, free][None], config)[0]
    return step


def damped_least_squares(
    state: State,
    *,
    cost: Callable[[State], Array],
    linearize: Callable[[State], tuple[Array, Array]] | None = None,
    normal_equations: Callable[[State], tuple[Array, Array]] | None = None,
    retract: Callable[[State, Array], State],
    config: LeastSquaresConfig = LeastSquaresConfig(),
    step_size: Callable[[State, Array], Array] | None = None,
    held: Callable[[State, Array], NDArray[np.bool_]] | None = None,
    monitor: Callable[[State], Array] | None = None,
) -> LeastSquaresResult:
    """Minimise each problem's cost by damped Gauss-Newton steps (module docstring).

    Parameters
    ----------
    state : tuple of arrays
        The starting states, batch first (B problems). Not modified.
    cost : callable
        ``cost(state) -> (B,)``: what a kept step must lower (usually the mean or sum
        of the squared residuals; any cost the linearisation approximates).
    linearize : callable, optional
        ``linearize(state) -> (r (B, m), J (B, m, n))``: residuals and their Jacobian
        with respect to the step.
    normal_equations : callable, optional
        ``normal_equations(state) -> (J^T J (B, n, n), J^T r (B, n))``: instead of
        ``linearize`` (exactly one of the two is given).
    retract : callable
        ``retract(state, step (B, n)) -> state``: the states moved by the steps.
    config : LeastSquaresConfig
    step_size : callable, optional
        ``step_size(state, step) -> (B,)`` compared with ``config.step_tol`` (default:
        the Euclidean norm of the step).
    held : callable, optional
        ``held(state, step) -> (B, n) bool``: step components to hold at zero (a
        parameter on a bound that the step would take out of its domain).
    monitor : callable, optional
        ``monitor(state) -> (B,)`` recorded in the trace (default: the cost).
    """
    if (linearize is None) == (normal_equations is None):
        raise ValueError("give exactly one of linearize and normal_equations")
    state = tuple(np.array(a, copy=True) for a in state)
    B = len(state[0])
    current = np.array(cost(state), dtype=float)
    lam = np.full(B, float(config.initial_damping))
    iterations = np.zeros(B, dtype=np.int64)
    status = [LeastSquaresStatus.MAX_ITERATIONS] * B
    measured = current if monitor is None else np.array(monitor(state), dtype=float)
    trace = [measured.copy()]
    active = np.flatnonzero(current > config.atol)
    for b in np.flatnonzero(~(current > config.atol)):
        status[b] = LeastSquaresStatus.CONVERGED
    size = step_size or (lambda _s, step: np.linalg.norm(step, axis=1))
    for _ in range(config.max_iterations):
        if active.size == 0:
            break
        iterations[active] += 1
        here = _take(state, active)
        if normal_equations is not None:
            H, g = normal_equations(here)
        else:
            assert linearize is not None
            r, J = linearize(here)
            JT = np.swapaxes(J, 1, 2)
            H = JT @ J
            g = (JT @ r[..., None])[..., 0]
        # trial steps; with retry, rejected ones again with more damping
        trying = np.arange(active.size)
        kept = np.zeros(active.size, bool)
        steps = np.zeros((active.size, H.shape[-1]))
        new_state: State | None = None  # the moved states, made on the first kept step
        new_cost = current[active].copy()
        while trying.size:
            rows = active[trying]
            sub = _take(here, trying)
            step = _steps(_damped(H[trying], lam[rows], config), g[trying], sub, config, held)
            moved = retract(sub, step)
            moved_cost = np.asarray(cost(moved), dtype=float)
            better = moved_cost < current[rows]
            good = trying[better]
            kept[good] = True
            steps[good] = step[better]
            if new_state is None and good.size == active.size:
                new_state = moved  # every step kept at once
            elif good.size:
                if new_state is None:
                    new_state = tuple(np.array(a, copy=True) for a in here)
                _put(new_state, good, _take(moved, np.flatnonzero(better)))
            new_cost[good] = moved_cost[better]
            lam[rows[~better]] *= config.grow
            if not config.retry:
                break
            trying = trying[~better]
            trying = trying[lam[active[trying]] <= config.max_damping]
        if config.extend and new_state is not None:
            extending = np.flatnonzero(kept)
            scale = 1.0
            while extending.size and scale < 1024:
                far = retract(_take(here, extending), 2 * scale * steps[extending])
                far_cost = np.asarray(cost(far), dtype=float)
                better = far_cost < new_cost[extending]
                _put(new_state, extending[better], _take(far, np.flatnonzero(better)))
                new_cost[extending[better]] = far_cost[better]
                extending = extending[better]
                scale *= 2
        good = np.flatnonzero(kept)
        rows = active[good]
        decrease = current[rows] - new_cost[good]
        stop = np.zeros(active.size, bool)
        converged = (
            (decrease < config.rtol * current[rows])
            | (size(_take(here, good), steps[good]) < config.step_tol)
            | (new_cost[good] <= config.atol)
        )
        if new_state is not None:
            if rows.size == B:
                state = new_state  # every problem moved
            else:
                _put(state, rows, _take(new_state, good))
        current[rows] = new_cost[good]
        lam[rows] = np.maximum(lam[rows] * config.shrink, config.min_damping)
        stop[good[converged]] = True
        for b in rows[converged]:
            status[b] = LeastSquaresStatus.CONVERGED
        stalled = lam[active] > config.max_damping
        for b in active[stalled & ~stop]:
            status[b] = LeastSquaresStatus.STALLED
        stop |= stalled
        if monitor is None:
            measured = current.copy()
        else:
            measured = measured.copy()
            measured[active] = monitor(_take(state, active))
        trace.append(measured.copy())
        active = active[~stop]
        if config.any_at_atol and np.any(current <= config.atol):
            active = active[:0]
    return LeastSquaresResult(state, current, iterations, tuple(status), np.array(trace))
