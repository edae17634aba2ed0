"""The simulator's exceptions: one base class, and what crosses a process boundary."""

from __future__ import annotations

import inspect
import pickle

import tactile_sim.errors as errors
from tactile_sim.errors import SimulationError, UnreachablePoint, WorkspaceLimit


def test_every_exception_is_a_simulation_error() -> None:
    exceptions = [
        value
        for name, value in vars(errors).items()
        if inspect.isclass(value) and issubclass(value, BaseException) and name in errors.__all__
    ]
    assert len(exceptions) >= 9
    assert all(issubclass(e, SimulationError) for e in exceptions)


def test_unreachable_point_survives_pickling_with_its_limit() -> None:
    error = UnreachablePoint("point beyond the reach (radius too large)", WorkspaceLimit.QUILL)
    copy = pickle.loads(pickle.dumps(error))
    assert type(copy) is UnreachablePoint
    assert str(copy) == str(error) and copy.limit is WorkspaceLimit.QUILL
