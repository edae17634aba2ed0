"""Every class fitted to sampled points by orthogonal distance regression (point_fit), and
recognize_points deciding on those fits."""

import copy

import numpy as np
import pytest
from scipy.special import chdtrc, chdtri

from recognition.curves import (
    CanonicalCurve,
    CurveKind,
    recognize_points,
    sample_by_arc_length,
)
from recognition.curves.families import TREE_CLASSES
from recognition.curves.recognition import canonical_parameters
from recognition.curves.recognition import point_fit as pf
from recognition.curves.recognition.tree import SMOOTH_MODES, smooth_statistic
from recognition.errors import InvalidCurveData
from recognition.rigid import apply_pose, random_planar_motion

#: (shape parameters, parameter interval) of a piece of each class.
CASES = {
    CurveKind.PARABOLA: ((1.5,), (-0.8, 1.2)),
    CurveKind.ELLIPSE: ((2.5, 1.2), (0.3, 2.8)),
    CurveKind.HYPERBOLA: ((1.2, 0.9), (-1.0, 0.5)),
    CurveKind.CUBICAL_PARABOLA: ((1.4, -0.8), (-1.2, 0.9)),
    # speed at least a tenth of its largest throughout (the fit's limit near a cusp)
    CurveKind.SEMICUBICAL_PARABOLA: ((1.8, -0.9), (0.7, 1.7)),
    CurveKind.CUBIC_SPLINE: ((0.9, -1.1, 0.8), (0.3, 1.7)),
}


def _points(kind: CurveKind, seed: int, noise: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    params, (t0, t1) = CASES[kind]
    rng = np.random.default_rng(seed)
    T = random_planar_motion(rng, 3.0)
    sampled = sample_by_arc_length(CanonicalCurve(kind, params), t0, t1, 0.02)
    points = apply_pose(T, sampled.points) + noise * rng.normal(size=sampled.points.shape)
    return points[::-1] if seed % 2 else points, T


@pytest.mark.parametrize("kind", TREE_CLASSES)
def test_jacobian_of_the_distances_matches_finite_differences(kind: CurveKind) -> None:
    points, _ = _points(kind, 3, noise=0.01)
    centre = points.mean(axis=0)
    scale = float(np.sqrt(np.mean(np.sum((points - centre) ** 2, axis=1))))
    q = (points - centre) / scale
    if kind in pf._POLYNOMIAL:
        c, t = pf._corrected_polynomial(q, 3)
        c = c[:3] if kind is CurveKind.PARABOLA else c
        starts, u = (c.reshape(1, -1), t[None])
        if kind in (CurveKind.CUBICAL_PARABOLA, CurveKind.SEMICUBICAL_PARABOLA):
            starts, u = pf._special_point_starts(kind, q, t, c)
    else:
        starts, u = pf._conic_starts(kind, q)
    g = starts[:1]
    u = u[:1]
    for _ in range(10):
        u = pf._feet(kind, g, u, q)
    r, J = pf._residuals(kind, g, u, q)
    numeric = np.zeros_like(J)
    for k in range(g.shape[1]):
        h = 1e-6 * max(1.0, abs(g[0, k]))
        up, down = g.copy(), g.copy()
        up[0, k] += h
        down[0, k] -= h
        r_up = pf._residuals(kind, up, pf._feet(kind, up, u, q), q)[0]
        r_down = pf._residuals(kind, down, pf._feet(kind, down, u, q), q)[0]
        numeric[..., k] = (r_up - r_down) / (2 * h)
    # away from the distances' kink where a point lies on the curve
    off = r[0] > 1e-4
    assert off.sum() > 0.9 * off.size
    np.testing.assert_allclose(J[0, off], numeric[0, off], atol=1e-5 * np.abs(numeric).max())


@pytest.mark.parametrize("kind", TREE_CLASSES)
def test_fit_recovers_the_shape_and_the_motion_of_exact_points(kind: CurveKind) -> None:
    for seed in (0, 1):
        points, _ = _points(kind, seed)
        fit = pf.fit_classes(points)[kind]
        assert fit is not None
        assert np.sqrt(fit.sum_of_squares / len(points)) < 1e-7
        want = canonical_parameters(kind, CASES[kind][0])
        got = canonical_parameters(kind, fit.reduction.params)
        np.testing.assert_allclose(got, want, rtol=1e-6)
        # the fitted canonical curve at the feet is the data
        placed = fit.reduction.curve.points(fit.u)
        np.testing.assert_allclose(
            apply_pose(fit.reduction.T_data_from_canonical, placed), points, atol=1e-6
        )


@pytest.mark.parametrize("kind", TREE_CLASSES)
def test_recognize_points_decides_on_the_points_by_default(kind: CurveKind) -> None:
    points, _ = _points(kind, 4, noise=1e-4)
    result, _ = recognize_points(points, window=15, degree=3, kappa_window=15)
    assert result.decided_by == "points"
    assert result.kind is kind, [(c.kind.value, c.p_value) for c in result.candidates]
    assert result.p_value >= 1e-3
    assert 0.5e-4 < result.noise < 2e-4
    want = canonical_parameters(kind, CASES[kind][0])
    np.testing.assert_allclose(tuple(result.parameters.values()), want, rtol=0.05)
    # known noise: the chi-square test
    known, _ = recognize_points(points, window=15, degree=3, kappa_window=15, noise=1e-4)
    assert known.kind is kind and known.noise == 1e-4


def test_recognize_points_refuses_mixed_decisions() -> None:
    points, _ = _points(CurveKind.ELLIPSE, 0)
    with pytest.raises(InvalidCurveData, match="decide_by"):
        recognize_points(points, decide_by="points", tolerance=1e-4)
    with pytest.raises(InvalidCurveData, match="decide_by"):
        recognize_points(points, decide_by="pointz")
    with pytest.raises(InvalidCurveData, match="noise"):
        recognize_points(points, noise=-1.0)


def test_a_semicubical_arc_that_runs_up_to_its_cusp_is_fitted_exactly() -> None:
    """The joystick generator's 15th semi-cubical arc of seed 11 ends next to its cusp
    (where the speed falls to a tenth of its median): started from the chord length,
    its fit ended 61 noise variances from the noise-free points, worse than an ellipse's."""
    from testing_curves import joystick_samples, random_curve

    rng = np.random.default_rng(11)
    for _ in range(15):
        curve = random_curve("semicubical_parabola", rng)
        twin = copy.deepcopy(rng)  # the same arc without its noise
        joystick_samples(curve, rng)
    points = joystick_samples(curve, twin, noise=0.0)
    fits = pf.fit_classes(points)
    own = fits[CurveKind.SEMICUBICAL_PARABOLA]
    assert own is not None and np.sqrt(own.sum_of_squares / len(points)) < 1e-6
    assert fits[CurveKind.ELLIPSE].sum_of_squares > 1e3 * own.sum_of_squares


def test_a_smooth_misfit_within_the_sum_of_squares_refuses_the_class() -> None:
    # a parabola bent by a smooth wave along its normal (three quarters of a period over
    # the arc), 0.3 noise sd RMS: the sum of squared distances of the parabola's fit stays
    # within its chi-square test, but the misfit lies in the residuals' smoothest modes
    # along the curve that the fit cannot follow, which the smooth test counts apart
    # (signed residuals: their signs follow the wave)
    sigma = 1e-4
    curve = sample_by_arc_length(CanonicalCurve(CurveKind.PARABOLA, (1.5,)), -0.8, 1.2, 0.005)
    rng = np.random.default_rng(3)
    x = np.linspace(-1.0, 1.0, len(curve.points))
    wave = 0.3 * sigma * np.sqrt(2.0) * np.cos(1.5 * np.pi * x)
    tangent = np.gradient(curve.points, axis=0)
    normal = np.stack([-tangent[:, 1], tangent[:, 0]], axis=1)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    points = curve.points + wave[:, None] * normal + sigma * rng.normal(size=curve.points.shape)
    fit = pf.fit_classes(points)[CurveKind.PARABOLA]
    assert fit is not None
    assert abs(np.corrcoef(fit.distances, wave)[0, 1]) > 0.1
    dof = len(points) - fit.n_unknowns
    assert chdtrc(dof, fit.sum_of_squares / sigma**2) > 1e-2  # the sum of squares passes
    result, _ = recognize_points(points, window=15, degree=3, kappa_window=15, noise=sigma)
    (parabola,) = [c for c in result.candidates if c.kind is CurveKind.PARABOLA]
    assert parabola.p_value < result.significance
    assert result.kind is not CurveKind.PARABOLA
    # white noise alone, and the noise the fit leaves: the smooth modes beyond the fit's
    # changes hold chi-square of as many degrees of freedom
    white = sigma * rng.normal(size=len(points))
    statistic, modes = smooth_statistic(points, white, SMOOTH_MODES, fit.fitted)
    assert 1 <= modes <= SMOOTH_MODES
    assert statistic / sigma**2 < chdtri(modes, 1e-3)


@pytest.mark.parametrize("kind", [CurveKind.ELLIPSE, CurveKind.CUBIC_SPLINE])
def test_the_smooth_modes_beyond_a_members_fit_hold_chi_square_noise(kind: CurveKind) -> None:
    # noisy members fitted by their own class: the smooth statistic over the modes left
    # once the fit's changes are taken out, summed over the curves, is chi-square with
    # the modes' total; counted as SMOOTH_MODES each (the modes the fit absorbs counted
    # as noise), it would lie far below that
    sigma = 1e-3
    statistics, modes, plain = [], [], []
    for seed in range(25):
        points, _ = _points(kind, seed, noise=sigma)
        fit = pf.fit_classes(points)[kind]
        assert fit is not None
        statistic, m = smooth_statistic(points, fit.distances, SMOOTH_MODES, fit.fitted)
        statistics.append(statistic / sigma**2)
        modes.append(m)
        plain.append(smooth_statistic(points, fit.distances, SMOOTH_MODES)[0] / sigma**2)
    total, dof = sum(statistics), sum(modes)
    assert chdtri(dof, 1 - 1e-4) < total < chdtri(dof, 1e-4)
    assert sum(plain) < chdtri(SMOOTH_MODES * len(plain), 1 - 1e-4)
