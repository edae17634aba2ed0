"""The recognition tree on the thesis's joystick-like data (Section 3.4.2, Table 3.4):
random curves of every class and of none from ``tests/testing_curves.py``, an arc of
6 cm sampled every 0.05 cm with 0.003 cm noise (:func:`testing_curves.joystick_samples`),
local fits over 21 points (the thesis's settings, as :class:`JoystickExperiment`), the
uncertainty estimated by :func:`recognize_points` itself.

The target is at least 95 % per class and at most 5 % of non-members given a class.
It is not reached (``NOT_REACHED``). On 12 curves per kind (seed 11): parabola 11,
ellipse 10, hyperbola 11, cubical parabola 7, semi-cubical parabola 0 (all called
parabola: a cusp-free arc of it is close to one at this noise), cubic spline 2 (most
called parabola); quartics 9 of 12 left unclassified, sinusoids 1 of 12 (11 called
cubical parabola). On the members the statistic of
the true class per degree of freedom has a median of 1.3-5.7 instead of 1: the
estimator's error model underestimates its errors.
"""

from __future__ import annotations

import numpy as np
import pytest
from testing_curves import MEMBER_KINDS, NON_MEMBER_KINDS, joystick_samples, random_curve

from recognition.curves import CurveKind, recognize_points
from recognition.errors import RecognitionError

#: Curves per kind and the rates of the acceptance.
N_CURVES = 100
MIN_MEMBER_RATE = 0.95
MAX_NON_MEMBER_CLASSIFIED = 0.05
#: The thesis's local fits (JoystickExperiment).
ESTIMATOR = {"window": 21, "degree": 3, "kappa_window": 21}

NOT_REACHED = pytest.mark.xfail(
    reason="the estimator's error model underestimates its errors on joystick-like data",
    strict=False,
)


def _decisions(kind: str, n: int, seed: int) -> dict[str, int]:
    """How the tree decides on n joystick-like samplings of random curves of ``kind``."""
    rng = np.random.default_rng(seed)
    decided: dict[str, int] = {}
    for _ in range(n):
        points = joystick_samples(random_curve(kind, rng), rng)
        try:
            result, _ = recognize_points(points, **ESTIMATOR)
            name = result.kind.value
        except RecognitionError as exc:
            name = type(exc).__name__
        decided[name] = decided.get(name, 0) + 1
    return decided


@pytest.mark.slow
@NOT_REACHED
@pytest.mark.parametrize("kind", MEMBER_KINDS + NON_MEMBER_KINDS)
def test_joystick_like_data_of_100_random_curves(kind: str) -> None:
    decided = _decisions(kind, N_CURVES, seed=11)
    if kind in MEMBER_KINDS:
        assert decided.get(kind, 0) >= MIN_MEMBER_RATE * N_CURVES, decided
    else:
        unclassified = decided.get(CurveKind.UNCLASSIFIED.value, 0)
        assert N_CURVES - unclassified <= MAX_NON_MEMBER_CLASSIFIED * N_CURVES, decided
