"""Bad input at the library's boundary: one typed error that says what was wrong.

Each case calls a public entry point with input a user may well pass by mistake and
checks the error's class (always one of :mod:`recognition.errors`) and a fragment of its
message. Property-based tests then throw generated input at ``DataCurves`` and
``ModelDatabase.recognize``: nothing but the library's typed errors may escape.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from testing_meshes import blob

from recognition import (
    DataCurves,
    InvalidArgument,
    InvalidCurveData,
    ModelDatabase,
    RecognitionError,
)


def _bowl(angle: float, n: int = 21, scale: float = 1.0) -> np.ndarray:
    """A curve through the origin on z = -(x^2 + y^2) / 0.04, metres (times ``scale``)."""
    t = np.linspace(-5e-3, 5e-3, n)[:, None]
    d = np.array([np.cos(angle), np.sin(angle), 0.0])
    return scale * (t * d + np.column_stack([0 * t, 0 * t, -(t**2) / 0.04]))


def _three(**kwargs: float) -> list[np.ndarray]:
    return [_bowl(a, **kwargs) for a in (0.0, np.pi / 3, 2 * np.pi / 3)]  # type: ignore[arg-type]


def _shuffled() -> list[np.ndarray]:
    curves = _three()
    curves[1] = curves[1][np.random.default_rng(0).permutation(21)]
    return curves


def _zigzag() -> np.ndarray:
    """Five points stepping back and forth between two places (hypothesis found it)."""
    a, b = [0.015625, 0.015625, 0.015625], [0.0, 0.015625, 0.015625]
    return np.array([a, b, a, b, a])


def _mm_curves() -> list[np.ndarray]:
    """Curves in millimetres (one 0.05 mm off the others), passed as metres."""
    curves = _three(scale=1e3)
    curves[2] = curves[2] + 0.05
    return curves


CURVE_CASES = [
    ("none", lambda: DataCurves(None), "sequence of (n, 3) point arrays"),  # type: ignore[arg-type]
    ("text", lambda: DataCurves("abc"), "sequence of (n, 3) point arrays"),  # type: ignore[arg-type]
    ("ragged", lambda: DataCurves([[[0, 0, 0], [1, 2]], *_three()[1:]]), "ragged"),
    ("strings", lambda: DataCurves([np.full((6, 3), "x"), *_three()[1:]]), "holds text"),
    (
        "complex",
        lambda: DataCurves([_three()[0] * (1 + 1j), *_three()[1:]]),
        "holds complex numbers",
    ),
    ("booleans", lambda: DataCurves([np.ones((6, 3), bool), *_three()[1:]]), "booleans"),
    ("one curve", lambda: DataCurves(_three()[:1]), "expected three data curves"),
    ("flat array", lambda: DataCurves([np.zeros(9), *_three()[1:]]), "must be an (n, 3)"),
    ("four points", lambda: DataCurves([_three()[0][:4], *_three()[1:]]), "at least 5"),
    ("nan", lambda: DataCurves([_three()[0] * np.nan, *_three()[1:]]), "NaN or infinite"),
    ("huge", lambda: DataCurves([_three()[0] + 1e300, *_three()[1:]]), "within 1000 m"),
    ("repeated", lambda: DataCurves([np.zeros((6, 3)), *_three()[1:]]), "repeats a point"),
    ("unordered", lambda: DataCurves(_shuffled()), "not in order"),
    ("back and forth", lambda: DataCurves([_zigzag()] * 3), "repeats a point"),
    ("millimetres", lambda: DataCurves(_mm_curves()), "look like millimetres"),
    ("apart", lambda: DataCurves([_three()[0] + 0.01, *_three()[1:]]), "do not meet"),
    ("approach nan", lambda: DataCurves(_three(), approach=[np.nan, 0, 1]), "approach"),
    ("approach text", lambda: DataCurves(_three(), approach="down"), "holds text"),
    ("zero approach", lambda: DataCurves(_three(), approach=[0, 0, 0]), "non-zero"),
    ("tolerance nan", lambda: DataCurves(_three(), meet_tolerance_m=np.nan), "positive"),
    ("tolerance text", lambda: DataCurves(_three(), meet_tolerance_m="1"), "a number"),  # type: ignore[arg-type]
    ("normals short", lambda: DataCurves(_three(), normals=[np.ones((21, 3))]), "one normal"),
    ("normals text", lambda: DataCurves(_three(), normals="up"), "one (n_i, 3) array"),  # type: ignore[arg-type]
    (
        "normals shape",
        lambda: DataCurves(_three(), normals=[np.ones((20, 3))] * 3),
        "the curve's shape",
    ),
]


@pytest.mark.parametrize(("case", "make", "fragment"), CURVE_CASES, ids=[c[0] for c in CURVE_CASES])
def test_bad_curves_are_one_typed_error(case, make, fragment: str) -> None:
    with pytest.raises(RecognitionError, match=re.escape(fragment)) as caught:
        make()
    assert isinstance(caught.value, InvalidCurveData)


@pytest.fixture(scope="module")
def database() -> ModelDatabase:
    return ModelDatabase.from_meshes({"blob": blob()})


def _good() -> DataCurves:
    return DataCurves(_three(), approach=[0.0, 0.0, -1.0])


RECOGNIZE_CASES = [
    ("tuple", lambda db: db.recognize(tuple(_three())), InvalidCurveData, "recognition.DataCurves"),
    ("unknown model", lambda db: db.recognize(_good(), models=["nope"]), InvalidArgument, "nope"),
    ("no models", lambda db: db.recognize(_good(), models=[]), InvalidArgument, "non-empty"),
    ("a name", lambda db: db.recognize(_good(), models="blob"), InvalidArgument, "list"),
    (
        "nan error",
        lambda db: db.recognize(_good(), max_error_m=np.nan),
        InvalidArgument,
        "positive",
    ),
    ("negative", lambda db: db.recognize(_good(), max_error_m=-1.0), InvalidArgument, "positive"),
    ("text error", lambda db: db.recognize(_good(), max_error_m="1"), InvalidArgument, "number"),
    ("bad mode", lambda db: db.recognize(_good(), mode="warp"), RecognitionError, "warp"),
]


@pytest.mark.parametrize(
    ("case", "call", "error", "fragment"), RECOGNIZE_CASES, ids=[c[0] for c in RECOGNIZE_CASES]
)
def test_bad_recognize_arguments_are_one_typed_error(database, case, call, error, fragment) -> None:
    with pytest.raises(error, match=re.escape(fragment)):
        call(database)


# --- property-based: only typed errors escape ------------------------------------------

_coordinates = st.floats(allow_nan=True, allow_infinity=True, width=64)
_curve = hnp.arrays(
    np.float64, st.tuples(st.integers(0, 12), st.sampled_from([2, 3, 4])), elements=_coordinates
)
_near = hnp.arrays(
    np.float64,
    st.tuples(st.integers(5, 12), st.just(3)),
    elements=st.floats(-0.02, 0.02, allow_nan=False, width=64),
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(curves=st.lists(st.one_of(_curve, _near), min_size=0, max_size=4))
def test_generated_curves_raise_only_typed_errors(curves) -> None:
    try:
        DataCurves(curves)
    except RecognitionError:
        pass


def _jittered_bowls(draw_noise: float, angles: list[float], n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(int(draw_noise * 1e9) % 2**32)
    return [_bowl(a, n=n) + rng.normal(scale=draw_noise, size=(n, 3)) for a in angles]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    noise=st.floats(0.0, 2e-3),
    angles=st.lists(st.floats(0.0, np.pi), min_size=3, max_size=4),
    n=st.integers(5, 30),
)
def test_generated_sessions_are_recognised_or_refused_with_typed_errors(
    database, noise, angles, n
) -> None:
    try:
        result = database.recognize(DataCurves(_jittered_bowls(noise, angles, n)))
    except RecognitionError:
        return
    assert result.name in (None, "blob")
    assert all(np.isnan(e) or e >= 0 for _, e in result.ranking)


@pytest.mark.slow
@settings(max_examples=2000, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(curves=st.lists(st.one_of(_curve, _near), min_size=0, max_size=4))
def test_many_generated_curves_raise_only_typed_errors(curves) -> None:
    try:
        DataCurves(curves)
    except RecognitionError:
        pass
