"""The damped least-squares solver on problems with known minima."""

import numpy as np
import pytest

from recognition.least_squares import (
    Damping,
    LeastSquaresConfig,
    LeastSquaresStatus,
    LinearSolve,
    damped_least_squares,
)

# Rosenbrock's function as residuals: r = (10 (y - x^2), 1 - x), minimum 0 at (1, 1).


def _cost(state):
    (x,) = state
    r = np.stack([10 * (x[:, 1] - x[:, 0] ** 2), 1 - x[:, 0]], axis=1)
    return np.sum(r * r, axis=1)


def _linearize(state):
    (x,) = state
    r = np.stack([10 * (x[:, 1] - x[:, 0] ** 2), 1 - x[:, 0]], axis=1)
    J = np.zeros((len(x), 2, 2))
    J[:, 0, 0], J[:, 0, 1], J[:, 1, 0] = -20 * x[:, 0], 10.0, -1.0
    return r, J


def _retract(state, step):
    return (state[0] + step,)


def _solve(starts, **overrides):
    config = LeastSquaresConfig(
        **{"max_iterations": 200, "rtol": 0.0, "step_tol": 1e-14, **overrides}
    )
    return damped_least_squares(
        (np.array(starts, float),),
        cost=_cost,
        linearize=_linearize,
        retract=_retract,
        config=config,
    )


@pytest.mark.parametrize(
    "overrides",
    [
        {},
        {"damping": Damping.DIAGONAL, "solve": LinearSolve.LEAST_NORM, "shrink": 0.1},
        {"retry": True, "extend": True, "damping": Damping.DIAGONAL},
    ],
)
def test_every_start_of_a_batch_reaches_the_minimum(overrides):
    starts = [[-1.2, 1.0], [2.0, -1.0], [0.0, 0.0], [1.0, 1.0]]
    result = _solve(starts, **overrides)
    np.testing.assert_allclose(result.state[0], np.ones((4, 2)), atol=1e-7)
    assert np.all(result.cost < 1e-14)
    assert all(s is LeastSquaresStatus.CONVERGED for s in result.status)
    # the trace never rises and ends at the cost
    assert np.all(np.diff(result.trace, axis=0) <= 0)
    np.testing.assert_array_equal(result.trace[-1], result.cost)
    assert result.iterations[3] == 0  # started at the minimum


def test_a_batch_solves_each_problem_as_if_alone():
    starts = [[-1.2, 1.0], [2.0, -1.0], [0.3, 0.8]]
    together = _solve(starts)
    for i, start in enumerate(starts):
        alone = _solve([start])
        np.testing.assert_array_equal(alone.state[0][0], together.state[0][i])
        assert alone.iterations[0] == together.iterations[i]


def test_limits_and_stalls_are_reported():
    short = _solve([[-1.2, 1.0]], max_iterations=3)
    assert short.status[0] is LeastSquaresStatus.MAX_ITERATIONS
    assert short.iterations[0] == 3 and short.trace.shape == (4, 1)

    def never_better(state):  # every trial step is rejected
        return _cost(state) + 100.0 * np.any(state[0] != 0.5, axis=1)

    stalled = damped_least_squares(
        (np.array([[0.5, 0.5]]),),
        cost=never_better,
        linearize=_linearize,
        retract=_retract,
        config=LeastSquaresConfig(retry=True, max_damping=1e6),
    )
    assert stalled.status[0] is LeastSquaresStatus.STALLED
    np.testing.assert_array_equal(stalled.state[0], [[0.5, 0.5]])


def test_held_components_stay_on_their_bound():
    # x is bounded above by 0.5: the minimum on that bound is at y = 0.25
    def held(state, step):
        out = np.zeros(step.shape, bool)
        out[:, 0] = (state[0][:, 0] >= 0.5) & (step[:, 0] > 0)
        return out

    def retract(state, step):
        x = state[0] + step
        x[:, 0] = np.minimum(x[:, 0], 0.5)
        return (x,)

    result = damped_least_squares(
        (np.array([[0.5, 2.0]]),),
        cost=_cost,
        linearize=_linearize,
        retract=retract,
        held=held,
        config=LeastSquaresConfig(max_iterations=100, rtol=0.0, step_tol=1e-14, retry=True),
    )
    np.testing.assert_allclose(result.state[0][0], [0.5, 0.25], atol=1e-9)


def _normal_equations(state):
    r, J = _linearize(state)
    JT = np.swapaxes(J, 1, 2)
    return JT @ J, (JT @ r[..., None])[..., 0]


def test_normal_equations_stand_for_the_linearisation():
    starts = np.array([[-1.2, 1.0], [2.0, -1.0], [0.0, 0.0]])
    config = LeastSquaresConfig(max_iterations=200, rtol=0.0, step_tol=1e-14)
    by_jacobian = _solve(starts)
    by_normal = damped_least_squares(
        (starts,), cost=_cost, normal_equations=_normal_equations, retract=_retract, config=config
    )
    np.testing.assert_allclose(by_normal.state[0], by_jacobian.state[0], atol=1e-12)
    np.testing.assert_array_equal(by_normal.iterations, by_jacobian.iterations)
    for given in ({}, {"linearize": _linearize, "normal_equations": _normal_equations}):
        with pytest.raises(ValueError, match="exactly one"):
            damped_least_squares((starts,), cost=_cost, retract=_retract, **given)


def test_a_kept_batch_is_never_written_through_to_the_caller():
    # every step of every problem kept: the solver hands its own arrays on, never the input
    starts = np.array([[-1.2, 1.0], [2.0, -1.0]])
    before = starts.copy()
    result = _solve(starts)
    np.testing.assert_array_equal(starts, before)
    assert not np.shares_memory(result.state[0], starts)
