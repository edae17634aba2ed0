"""recognize_points on the thesis's joystick-like data (Section 3.4.2, Table 3.4): random
curves of every class and of none from ``tests/testing_curves.py``, an arc whose tangent
turns by 2.5 rad scaled to 6 cm, sampled every 0.05 cm with 0.003 cm noise
(:func:`testing_curves.joystick_samples`), the noise estimated by recognize_points
itself from its local fits over 21 points (the thesis's settings, as
:class:`JoystickExperiment`); every class fitted to the points themselves and tested by
its sum of squared distances and by the part of it in the residuals' smoothest modes
along the curve that the fit cannot follow.

Where the data cannot tell: an arc is *separable* when every other class that could be
preferred to its own (a member's classes of at most as many parameters; for a curve of
no class, every class) stays, fitted to the same arc without noise, farther from it than
the test can miss: an RMS distance of at least sqrt(2 q / n) noise standard deviations,
q the margin a class must beat (for a member chi2(1) at the significance, by which a
class with one parameter more must fit better; for a non-member the chi2(n - 6)
quantile's excess over its mean, by which a fit is refused). Measured on 100 curves per
kind (seed 11): parabola, ellipse, hyperbola and cubical parabola 100 of 100;
semi-cubical parabola 59 (89 of its 100 arcs are within 0.42 noise sd of a parabola or
an ellipse arc, so no test of the sum of squares tells them apart; 36 are called a
parabola, which a class of one more parameter must beat by the test's margin); cubic
spline 90 (87 of the 87 separable); quartic 99 (98 of 98); sinusoid 75 left
unclassified, all 46 separable among them (the other 54 lie within 0.89 noise sd of a
cubic spline, closer than the sum of squares can see; 25 are called a cubical
parabola): all 642 separable arcs decided right.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
from scipy.special import chdtri
from testing_curves import MEMBER_KINDS, NON_MEMBER_KINDS, joystick_samples, random_curve

from recognition.curves import CurveKind, recognize_points
from recognition.curves.families import N_PARAMETERS, TREE_CLASSES
from recognition.curves.recognition import DEFAULT_SIGNIFICANCE
from recognition.curves.recognition.point_fit import fit_classes
from recognition.errors import RecognitionError

#: Curves per kind, and the least share decided right over all of them (measured on
#: these 12: 100 % where every arc is separable, 9 for the spline, 10 sinusoids); the
#: semi-cubical parabola is held to the separable arcs only.
N_CURVES = 12
MIN_RATE = {"cubic_spline": 9 / 12, "semicubical_parabola": 0.0, "sinusoid": 9 / 12}
#: Separable arcs decided wrong, at most (measured: none of 642 over 100 curves per kind).
MAX_SEPARABLE_MISSES = 1
#: The thesis's local fits (JoystickExperiment).
ESTIMATOR = {"window": 21, "degree": 3, "kappa_window": 21}
NOISE = 0.003


def _separation(kind: str, clean: np.ndarray) -> tuple[float, float]:
    """The least RMS distance (in noise sd) of the noise-free arc from a class that
    could be preferred to the right answer, and the threshold of separable."""
    n = clean.shape[0]
    fits = fit_classes(clean)
    if kind in MEMBER_KINDS:
        own = N_PARAMETERS[CurveKind(kind)]
        rivals = [k for k in TREE_CLASSES if k.value != kind and N_PARAMETERS[k] <= own]
        margin = chdtri(1, DEFAULT_SIGNIFICANCE)
    else:
        rivals = list(TREE_CLASSES)
        margin = chdtri(n - 6, DEFAULT_SIGNIFICANCE) - (n - 6)
    distances = [
        np.inf if fits[k] is None else np.sqrt(fits[k].sum_of_squares / n) / NOISE  # type: ignore[union-attr]
        for k in rivals
    ]
    return min(distances, default=np.inf), float(np.sqrt(2.0 * margin / n))


@pytest.mark.slow
@pytest.mark.parametrize("kind", MEMBER_KINDS + NON_MEMBER_KINDS)
def test_joystick_like_data_of_random_curves(kind: str) -> None:
    rng = np.random.default_rng(11)
    right = kind if kind in MEMBER_KINDS else CurveKind.UNCLASSIFIED.value
    decided, separable = [], []
    for _ in range(N_CURVES):
        curve = random_curve(kind, rng)
        twin = copy.deepcopy(rng)
        points = joystick_samples(curve, rng)
        distance, threshold = _separation(kind, joystick_samples(curve, twin, noise=0.0))
        try:
            result, _ = recognize_points(points, **ESTIMATOR)
            name = result.kind.value
        except RecognitionError as exc:
            name = type(exc).__name__
        decided.append(name)
        separable.append(distance >= threshold)
    hits = [name == right for name in decided]
    assert np.mean(hits) >= MIN_RATE.get(kind, 11 / 12), decided
    misses = [not h for h, s in zip(hits, separable, strict=True) if s]
    assert sum(misses) <= MAX_SEPARABLE_MISSES, (decided, separable)


#: Curves per kind of the measurement of what the data allow (the 100 of the docstring).
N_LIMIT = 100


@pytest.mark.slow
def test_no_decision_tells_the_semicubical_arcs_from_parabolas_at_95_percent() -> None:
    """What the joystick-like arcs of the semi-cubical parabola allow any decision by the
    fits: the likelihood ratio of the parabola against the best class of two parameters,
    Delta = (S_parabola - min S_two) / sigma^2 (sums of squared distances, the true noise
    sigma), is the statistic a threshold c decides by (parabola below it). Measured on
    the docstring's 100 arcs of each (seed 11): only 92 semi-cubical arcs fit the
    semi-cubical parabola better than every other class of two parameters; the best
    threshold is right on 78 % of either kind at once (c = 1.85), a parabola right
    97 % of the time (c = 4) leaves 72 % of the semi-cubical arcs, and the test's margin
    (c = 10.83) 61 %. No decision reaches 95 % on both."""
    two = [k for k in TREE_CLASSES if N_PARAMETERS[k] == 2]
    delta, own = {}, {}
    for kind in (CurveKind.PARABOLA, CurveKind.SEMICUBICAL_PARABOLA):
        rng = np.random.default_rng(11)
        rows = []
        for _ in range(N_LIMIT):
            fits = fit_classes(joystick_samples(random_curve(kind.value, rng), rng))
            s = {k: np.inf if f is None else f.sum_of_squares / NOISE**2 for k, f in fits.items()}
            best_two = min(two, key=s.__getitem__)
            rows.append((s[CurveKind.PARABOLA] - s[best_two], best_two))
        delta[kind] = np.array([d for d, _ in rows])
        own[kind] = np.array([b is CurveKind.SEMICUBICAL_PARABOLA for _, b in rows])
    parabola, semicubical = delta[CurveKind.PARABOLA], delta[CurveKind.SEMICUBICAL_PARABOLA]
    found = own[CurveKind.SEMICUBICAL_PARABOLA]
    thresholds = np.unique(np.concatenate([parabola, semicubical, [np.inf]]))
    both = [min(np.mean(parabola < c), np.mean((semicubical >= c) & found)) for c in thresholds]
    assert found.mean() < 0.95, found.mean()
    assert 0.6 < max(both) < 0.95, max(both)
