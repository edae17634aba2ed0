"""Curvature estimators of thesis Section 3.4 on exact samples, and their input checks.

Samples are taken at equal arc-length spacing h from circles and ellipses, whose exact
kappa and kappa_s are known (Eqs. (3.11)-(3.12)). Tolerances are stated per test from
the estimator's truncation error; the observed errors are 5-20 times smaller.
"""

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from recognition.curves.estimation import (
    LocalGeometry,
    finite_difference_geometry,
    local_fit_geometry,
)
from recognition.curves.families import CanonicalCurve, CurveKind
from recognition.curves.sampling import SampledCurve
from recognition.curves.sampling import sample_by_arc_length as sample
from recognition.errors import InvalidCurveData
from recognition.rigid import apply_pose, random_planar_motion

#: The most accurate local fit on exact data (used by the recognition tests too).
EXACT_FIT = {"window": 11, "degree": 6, "kappa_window": None}


def circle(r: float) -> CanonicalCurve:
    return CanonicalCurve(CurveKind.ELLIPSE, (r, r))


def exact_at(
    sampled: SampledCurve, geometry: LocalGeometry
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = sampled.t[geometry.index]
    return sampled.curve.kappa(t), sampled.curve.kappa_s(t), sampled.curve.phi(t)


def relative_errors(sampled: SampledCurve, geometry: LocalGeometry) -> tuple[float, float]:
    """max |kappa error| / max |kappa| and max |kappa_s error| / (max |kappa_s| + max kappa^2)."""
    kappa, kappa_s, _ = exact_at(sampled, geometry)
    kappa_scale = np.abs(kappa).max()
    kappa_s_scale = np.abs(kappa_s).max() + kappa_scale**2
    return (
        np.abs(geometry.kappa - kappa).max() / kappa_scale,
        np.abs(geometry.kappa_s - kappa_s).max() / kappa_s_scale,
    )


# --- finite differences (Section 3.4) ----------------------------------------------------


@pytest.mark.parametrize("r", [0.02, 1.0, 30.0])
@pytest.mark.parametrize("with_phi", [True, False])
def test_finite_differences_on_a_circle_have_the_exact_chord_bias(r: float, with_phi: bool) -> None:
    """On a circle phi(s) is linear, so the only error is arc length taken as the chord:
    kappa_est = (1/r) (h/2r) / sin(h/2r) exactly, and kappa_s = 0 (rounding only)."""
    h = 0.02 * r
    sampled = sample(circle(r), 0.3, 2.8, h)
    phi = circle(r).phi(sampled.t) if with_phi else None
    geometry = finite_difference_geometry(sampled.points, phi=phi)
    half = h / (2 * r)
    np.testing.assert_allclose(geometry.kappa, (1 / r) * half / np.sin(half), rtol=1e-9)
    assert np.abs(geometry.kappa_s).max() <= 1e-6 / r**2
    assert len(geometry) == sampled.t.size - (2 if with_phi else 4)


def test_finite_differences_converge_at_second_order_on_an_ellipse() -> None:
    """Central differences on phi(s): halving h divides the error by about 4."""
    curve = CanonicalCurve(CurveKind.ELLIPSE, (2.0, 1.0))
    errors = []
    for h in (0.02, 0.01):
        sampled = sample(curve, 0.2, 2.4, h)
        geometry = finite_difference_geometry(sampled.points, phi=curve.phi(sampled.t))
        errors.append(relative_errors(sampled, geometry))
    (k1, s1), (k2, s2) = errors
    assert k1 < 1e-3 and s1 < 2e-3  # h = 0.02 on curvature radii 0.25-4
    assert 3.5 < k1 / k2 < 4.5
    assert 3.5 < s1 / s2 < 4.5


def test_finite_differences_reject_bad_phi() -> None:
    sampled = sample(circle(1.0), 0.0, 1.0, 0.05)
    with pytest.raises(InvalidCurveData, match="phi must be"):
        finite_difference_geometry(sampled.points, phi=np.zeros(3))
    with pytest.raises(InvalidCurveData, match="at least 5 points"):
        finite_difference_geometry(sampled.points[:4])


# --- local fits (Section 3.4.2) ----------------------------------------------------------


@pytest.mark.parametrize("r", [0.02, 1.0, 30.0])
def test_local_fit_on_circles_is_exact(r: float) -> None:
    """Degree-6 fits over 11 points at h = r/100: kappa to 1e-8 relative, kappa_s ~ 0;
    positions, tangent angles and arc length match the exact circle."""
    h = r / 100
    sampled = sample(circle(r), 0.3, 2.8, h)
    geometry = local_fit_geometry(sampled.points, **EXACT_FIT)
    _, _, phi = exact_at(sampled, geometry)
    np.testing.assert_allclose(geometry.kappa, 1 / r, rtol=1e-8)
    assert np.abs(geometry.kappa_s).max() <= 1e-7 / r**2
    np.testing.assert_allclose(geometry.position, sampled.points[geometry.index], atol=1e-10 * r)
    assert np.abs(np.sin(geometry.phi - phi)).max() <= 1e-10
    np.testing.assert_allclose(np.diff(geometry.s), h, rtol=1e-8)


def test_local_fit_on_an_ellipse_matches_exact_kappa_and_kappa_s() -> None:
    """Degree-6 fits over 11 points at h = 0.01: truncation error O(h^5) in kappa and
    O(h^4) in kappa_s (observed 4e-9 and 5e-6 relative)."""
    curve = CanonicalCurve(CurveKind.ELLIPSE, (2.0, 1.0))
    sampled = sample(curve, 0.2, 2.4, 0.01)
    kappa_error, kappa_s_error = relative_errors(
        sampled, local_fit_geometry(sampled.points, **EXACT_FIT)
    )
    assert kappa_error < 1e-7
    assert kappa_s_error < 5e-5


def test_thesis_estimator_has_second_order_fit_bias() -> None:
    """The thesis's quadratic fits (degree 2, kappa(s) over 15 estimates): on a circle the
    quadratic cannot follow the arc, kappa is off by O((window h / r)^2) (about 1.2e-3 at
    h/r = 0.01) and halving h divides the error by 4."""
    errors = []
    for h in (0.02, 0.01):
        sampled = sample(circle(1.0), 0.0, 3.0, h)
        geometry = local_fit_geometry(sampled.points, window=15, degree=2, kappa_window=15)
        errors.append(np.abs(geometry.kappa - 1.0).max())
        assert np.abs(geometry.kappa_s).max() < 1e-9
    assert errors[1] < 2e-3
    assert 3.5 < errors[0] / errors[1] < 4.5


def test_estimates_are_invariant_under_rigid_motion_and_odd_under_reversal() -> None:
    """kappa, kappa_s and s do not depend on the frame; phi turns with it. Reversing the
    traversal flips kappa and leaves kappa_s unchanged."""
    rng = np.random.default_rng(40)
    curve = CanonicalCurve(CurveKind.ELLIPSE, (1.5, 0.8))
    points = sample(curve, 0.0, 2.5, 0.01).points
    for estimator in (local_fit_geometry, finite_difference_geometry):
        base = estimator(points)
        for _ in range(3):
            T = random_planar_motion(rng, translation_scale=10.0)
            moved = estimator(apply_pose(T, points))
            scale = np.abs(base.kappa).max()
            np.testing.assert_allclose(moved.kappa, base.kappa, atol=1e-8 * scale)
            np.testing.assert_allclose(moved.kappa_s, base.kappa_s, atol=1e-6 * scale**2)
            np.testing.assert_allclose(moved.s, base.s, atol=1e-9)
            turn = np.arctan2(T[1, 0], T[0, 0])
            assert np.abs(np.sin(moved.phi - base.phi - turn)).max() < 1e-9
        reverse = estimator(points[::-1])
        np.testing.assert_allclose(reverse.kappa[::-1], -base.kappa, atol=1e-8 * scale)
        np.testing.assert_allclose(reverse.kappa_s[::-1], base.kappa_s, atol=1e-6 * scale**2)


# --- the local fit's error model --------------------------------------------------------

#: The thesis's joystick-like data (Table 3.4): a point every 0.05 cm, noise 0.003 cm,
#: fits over 21 points and kappa(s) over 21 estimates.
JOYSTICK = {"window": 21, "degree": 3, "kappa_window": 21}


@pytest.mark.parametrize("options", [JOYSTICK, {"window": 21, "degree": 4, "kappa_window": None}])
def test_error_model_matches_the_scatter_of_noisy_estimates(options: dict[str, Any]) -> None:
    """Over 200 noise draws on the ellipse of Table 3.4: the noise part of the standard
    errors the estimator gives matches the scatter of kappa, kappa_s and phi within 20 %
    (the spread of a standard deviation from 200 draws is 5 %), and the whole standard
    error (noise and truncation, the latter with its safety factor TRUNCATION_FACTOR)
    covers the RMS error about the truth without exceeding it more than 2.2 times. The
    truth is taken at the estimate's nominal point: its along-curve jitter adds to phi."""
    curve = CanonicalCurve(CurveKind.ELLIPSE, (2.5, 1.75))
    clean = sample(curve, 0.3, 2.6, 0.05)
    rng = np.random.default_rng(42)
    estimates, errors, predicted, noise = [], [], [], []
    for _ in range(200):
        points = clean.points + rng.normal(scale=0.003, size=clean.points.shape)
        g = local_fit_geometry(points, **options)
        kappa, kappa_s, phi = exact_at(clean, g)
        estimates.append([g.kappa, g.kappa_s, g.phi])
        errors.append([g.kappa - kappa, g.kappa_s - kappa_s, np.sin(g.phi - phi)])
        se = g.sensitivity.standard_errors()
        predicted.append(se)
        noise.append(np.sqrt(se**2 - g.sensitivity.bias_variance.T))
    spread = np.std(estimates, axis=0) / np.mean(noise, axis=0)  # (3, m)
    assert np.all((spread > 0.8) & (spread < 1.2)), np.round(spread.min(axis=1), 2)
    rmse = np.sqrt(np.mean(np.square(errors), axis=0)) / np.mean(predicted, axis=0)
    assert np.all((rmse > 1 / 2.2) & (rmse < 1.1)), np.round(rmse.min(axis=1), 2)


def test_error_model_covers_the_truncation_error_of_exact_samples() -> None:
    """Exact samples: the error is the fits' truncation; 99 % of the estimates lie
    within 3 standard errors of the truth (kappa and kappa_s; phi is exact to rounding)."""
    rng = np.random.default_rng(43)
    z = []
    for kind, params, (t0, t1) in [
        (CurveKind.ELLIPSE, (2.0, 1.0), (0.2, 2.4)),
        (CurveKind.CUBIC_SPLINE, (0.9, -1.1, 0.8), (0.3, 1.7)),
        (CurveKind.HYPERBOLA, (1.2, 0.9), (-1.0, 0.5)),
    ]:
        T = random_planar_motion(rng)
        sampled = sample(CanonicalCurve(kind, params), t0, t1, 0.01, T_data_from_canonical=T)
        g = local_fit_geometry(sampled.points, **EXACT_FIT)
        kappa, kappa_s, _ = exact_at(sampled, g)
        se = g.sensitivity.standard_errors()
        z.append(np.abs(np.stack([g.kappa - kappa, g.kappa_s - kappa_s]) / se[:2]))
    assert np.percentile(np.concatenate(z, axis=1), 99) < 3.0


def test_error_model_covariance_is_symmetric_and_subsets_agree() -> None:
    """Estimates sharing input points have correlated noise; a subset's covariance is the
    corresponding block, and its diagonal the squared standard errors."""
    curve = CanonicalCurve(CurveKind.ELLIPSE, (2.5, 1.75))
    points = sample(curve, 0.3, 2.6, 0.05).points
    points = points + np.random.default_rng(44).normal(scale=0.003, size=points.shape)
    g = local_fit_geometry(points, **JOYSTICK)
    pick = np.array([0, 3, 10, 20])
    cov = g.subset(pick).sensitivity.covariance()
    full = g.sensitivity.covariance()
    rows = np.concatenate([pick + q * len(g) for q in range(3)])
    np.testing.assert_allclose(cov, full[np.ix_(rows, rows)], rtol=1e-12, atol=0)
    np.testing.assert_allclose(cov, cov.T)
    se = g.subset(pick).sensitivity.standard_errors()
    np.testing.assert_allclose(np.sqrt(np.diag(cov)), se.ravel(), rtol=1e-12)
    noise = cov - np.diag(g.subset(pick).sensitivity.bias_variance.T.ravel())
    corr = noise[0, 1] / np.sqrt(noise[0, 0] * noise[1, 1])  # kappa at estimates 0 and 3
    assert corr > 0.2  # independent estimates would give 0


# --- input checks ------------------------------------------------------------------------


@pytest.fixture
def points() -> np.ndarray:
    return sample(circle(1.0), 0.0, 1.5, 0.02).points


@pytest.mark.parametrize("estimator", [local_fit_geometry, finite_difference_geometry])
def test_wrong_shape_is_rejected(
    points: np.ndarray, estimator: Callable[..., LocalGeometry]
) -> None:
    with pytest.raises(InvalidCurveData, match=r"shape \(n, 2\)"):
        estimator(np.column_stack([points, points[:, 0]]))
    with pytest.raises(InvalidCurveData, match=r"shape \(n, 2\)"):
        estimator(points.ravel())


def test_fewer_points_than_the_window_are_rejected(points: np.ndarray) -> None:
    with pytest.raises(InvalidCurveData, match="at least 11 points"):
        local_fit_geometry(points[:10], **EXACT_FIT)
    # the thesis's estimator needs window + kappa_window - 1 points
    with pytest.raises(InvalidCurveData, match="at least 29 points"):
        local_fit_geometry(points[:28], window=15, degree=2, kappa_window=15)


@pytest.mark.parametrize("estimator", [local_fit_geometry, finite_difference_geometry])
def test_nan_is_rejected(points: np.ndarray, estimator: Callable[..., LocalGeometry]) -> None:
    bad = points.copy()
    bad[7, 1] = np.nan
    with pytest.raises(InvalidCurveData, match="point 7 is not finite"):
        estimator(bad)


@pytest.mark.parametrize("estimator", [local_fit_geometry, finite_difference_geometry])
def test_repeated_points_are_rejected(
    points: np.ndarray, estimator: Callable[..., LocalGeometry]
) -> None:
    bad = np.insert(points, 20, points[20], axis=0)
    with pytest.raises(InvalidCurveData, match="points 20 and 21 repeat"):
        estimator(bad)
    with pytest.raises(InvalidCurveData, match="all identical"):
        estimator(np.ones((30, 2)))


@pytest.mark.parametrize("estimator", [local_fit_geometry, finite_difference_geometry])
def test_unordered_points_are_rejected(
    points: np.ndarray, estimator: Callable[..., LocalGeometry]
) -> None:
    shuffled = points[np.random.default_rng(41).permutation(len(points))]
    with pytest.raises(InvalidCurveData, match="not ordered"):
        estimator(shuffled)
    swapped = points.copy()
    swapped[[10, 11]] = swapped[[11, 10]]  # one local swap: backtracking
    with pytest.raises(InvalidCurveData, match="not ordered"):
        estimator(swapped)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"window": 10}, "window must be odd"),
        ({"window": 5, "degree": 6}, "window must be odd and at least degree"),
        ({"kappa_window": 8}, "kappa_window must be odd"),
        ({"degree": 2, "kappa_window": None}, "needs degree >= 3"),
        ({"step": 0}, "step must be"),
    ],
)
def test_bad_options_are_rejected(
    points: np.ndarray, options: dict[str, Any], message: str
) -> None:
    with pytest.raises(InvalidCurveData, match=message):
        local_fit_geometry(points, **options)
