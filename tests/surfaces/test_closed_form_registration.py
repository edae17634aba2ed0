"""Registration of three data curves onto closed-form models and recognition (4.1.2-4.2.2).

Data are traced on the true surface (noise-free unless stated) and moved to a random
data frame; the pose found must map them back, modulo the surface's rigid symmetries.
"""

from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import minimize

from recognition.errors import InvalidCurveData, InvalidModel
from recognition.least_squares import LeastSquaresStatus
from recognition.reproduction.chapter4_closed_form import noisy_data_curves
from recognition.surfaces import closed_form as cf
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.registration import (
    ClosedFormConfig,
    Optimizer,
    RegistrationStatus,
    data_geometry,
    recognize,
    register,
)
from recognition.synthetic import implicit_data_curves

#: Unit-free Table 4.1 settings: 61 points every 0.015, fits over at most 0.45 (fewer
#: candidates than the default, for speed).


def config(fit_half_length: float = 0.45, **fields) -> ClosedFormConfig:
    """Closed-form settings with the data's fits over ``fit_half_length``."""
    geometry = replace(ClosedFormConfig().geometry, fit_half_length_m=fit_half_length)
    return ClosedFormConfig(geometry=geometry, **fields)


CONFIG = config(delta=0.1, max_candidates=8, local_searches=3)
POINTS = {
    "ellipsoid": (1.02, 0.69),
    "elliptic_paraboloid": (1.21, 0.43),
    "monkey_saddle": (0.4, -0.55),
    "crossed_trough": (0.6, 0.35),
}


@pytest.fixture(scope="module")
def models():
    return {s.name: cf.ClosedFormModel.build(s, 120, 60) for s in cf.table_4_1_surfaces()}


def clean_curves(surface, u, v, seed):
    rng = np.random.default_rng(seed)
    return implicit_data_curves(surface, surface.sigma(u, v), spacing=0.015, rng=rng)


def pose_error(surface, T_est, T_true):
    """Smallest |S T_est - T_true| (Frobenius) over S in the symmetries and the identity."""
    out = []
    for S in (np.eye(3), *surface.symmetries):
        M = np.eye(4)
        M[:3, :3] = S
        out.append(np.linalg.norm(M @ T_est - T_true))
    return min(out)


@pytest.mark.parametrize("name", list(POINTS))
def test_noise_free_registration_recovers_the_pose(models, name):
    model = models[name]
    synthetic = clean_curves(model.surface, *POINTS[name], seed=1)
    result = register(model, synthetic.curves, CONFIG)
    assert result.status is RegistrationStatus.CONVERGED
    assert result.error_m < 1e-7
    assert model.surface.symmetric_distance(synthetic.point_in_model, result.location) < 1e-6
    assert pose_error(model.surface, result.T_model_from_data, synthetic.T_model_from_data) < 1e-5
    assert len(result.searches) == result.candidates.shape[0] >= 1


def test_registration_is_unchanged_by_a_rigid_motion_of_the_data(models):
    model = models["elliptic_paraboloid"]
    rng = np.random.default_rng(2)
    curves, *_ = noisy_data_curves(
        model.surface, 1.21, 0.43, rng, n_points=61, spacing=0.015, noise=1e-3
    )
    motion = np.eye(4)
    motion[:3, :3] = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    motion[:3, :3] *= np.sign(np.linalg.det(motion[:3, :3]))
    motion[:3, 3] = rng.normal(size=3)
    a = register(model, curves, CONFIG)
    b = register(model, curves.transformed(motion), CONFIG)
    assert b.error_m == pytest.approx(a.error_m, rel=1e-6)
    np.testing.assert_allclose(b.location, a.location, atol=1e-7)
    np.testing.assert_allclose(b.T_model_from_data @ motion, a.T_model_from_data, atol=1e-6)
    assert (b.u, b.v) == pytest.approx((a.u, a.v), abs=1e-6)


def test_noisy_worked_example_is_located_within_the_noise(models):
    model = models["elliptic_paraboloid"]
    rng = np.random.default_rng(3)
    curves, point, T_true, _ = noisy_data_curves(
        model.surface, 1.21, 0.43, rng, n_points=61, spacing=0.015, noise=1e-3
    )
    result = register(model, curves, CONFIG)
    # uniform noise within +-0.001 per coordinate: mean |distance| about 0.0005
    assert 3e-4 < result.error_m < 7e-4
    assert model.surface.symmetric_distance(point, result.location) < 0.01
    assert pose_error(model.surface, result.T_model_from_data, T_true) < 0.05


def test_without_an_approach_direction_both_normals_are_tried(models):
    model = models["ellipsoid"]
    synthetic = clean_curves(model.surface, 1.02, 0.69, seed=4)
    unoriented = DataCurves(synthetic.curves.curves)
    oriented = register(model, synthetic.curves, CONFIG)
    either = register(model, unoriented, CONFIG)
    assert either.error_m == pytest.approx(oriented.error_m, abs=1e-9)
    np.testing.assert_allclose(either.T_model_from_data, oriented.T_model_from_data, atol=1e-6)
    # unoriented data take the side from which the surface looks convex on average; on
    # the crossed trough at (0.9, 0.9) (mean curvature < 0 seen from outside) that is the
    # inside, and the registration reports that it flipped the estimate
    trough = models["crossed_trough"]
    for (u, v), flipped in (((0.6, 0.35), False), ((0.9, 0.9), True)):
        data = clean_curves(trough.surface, u, v, seed=5)
        unoriented = DataCurves(data.curves.curves)
        result = register(trough, unoriented, CONFIG)
        assert result.error_m < 1e-8
        assert result.normal_flipped is flipped
        assert trough.surface.symmetric_distance(data.point_in_model, result.location) < 1e-6
        estimate = (
            data.T_model_from_data[:3, :3] @ data_geometry(unoriented, CONFIG.geometry).normal
        )
        assert bool(estimate @ data.normal_in_model < 0) is flipped


@pytest.mark.slow
def test_steepest_descent_and_levenberg_marquardt_reach_the_minimum_of_e(models):
    """With p and N pinned (3 DOF), E keeps a floor set by the normal's estimate; both
    searches reach it: steepest descent minimises E itself, LM the squared residuals."""
    model = models["crossed_trough"]
    synthetic = clean_curves(model.surface, 0.6, 0.35, seed=6)
    geometry = data_geometry(synthetic.curves, CONFIG.geometry)
    X = cf.local_coordinates(geometry, synthetic.curves.points)
    x0 = (0.5, 0.45, cf.initial_phi(model.surface, X, 0.5, 0.45)[0])
    sd = cf.steepest_descent(model.surface, X, x0, max_iterations=500)
    lm = cf.levenberg_marquardt(model.surface, X, x0)
    reference = minimize(
        lambda x: cf.superposition_error(model.surface, X, *x),
        lm.solution,
        method="Nelder-Mead",
        options={"xatol": 1e-10, "fatol": 1e-14, "maxiter": 4000},
    )
    assert np.all(np.diff(sd.trace) <= 0)
    assert sd.status is LeastSquaresStatus.CONVERGED
    assert lm.status is LeastSquaresStatus.CONVERGED
    assert reference.fun <= sd.cost <= 1.05 * reference.fun
    assert reference.fun <= lm.cost <= 1.25 * reference.fun
    assert lm.iterations < sd.iterations
    np.testing.assert_allclose(sd.solution[:2], [0.6, 0.35], atol=0.01)
    np.testing.assert_allclose(lm.solution[:2], [0.6, 0.35], atol=0.01)


def test_thesis_optimizer_through_the_registration_config(models):
    model = models["ellipsoid"]
    synthetic = clean_curves(model.surface, 1.02, 0.69, seed=7)
    thesis = config(
        delta=0.1,
        max_candidates=1,
        max_iterations=2,  # 40 steepest-descent iterations
        optimizer=Optimizer.STEEPEST_DESCENT,
        rigid_refinement=False,
    )
    sd = register(model, synthetic.curves, thesis)
    assert all(np.all(np.diff(s.trace) <= 0) for s in sd.searches)
    assert sd.error_m < 0.8 * min(s.trace[0] for s in sd.searches)
    assert model.surface.symmetric_distance(synthetic.point_in_model, sd.location) < 0.05
    # the six-degree-of-freedom refinement removes the error of the estimated normal
    lm6 = register(
        model,
        synthetic.curves,
        replace(
            thesis,
            optimizer=Optimizer.LEVENBERG_MARQUARDT,
            rigid_refinement=True,
            max_iterations=100,
        ),
    )
    assert lm6.error_m < 1e-8 < 1e-4 < sd.error_m


def test_search_stays_in_the_domain_when_the_optimum_lies_outside(models):
    model = models["crossed_trough"]
    synthetic = clean_curves(model.surface, 1.2, 0.5, seed=8)  # beyond u = 1
    geometry = data_geometry(synthetic.curves, CONFIG.geometry)
    X = cf.local_coordinates(geometry, synthetic.curves.points)
    x0 = (0.8, 0.5, cf.initial_phi(model.surface, X, 0.8, 0.5)[0])
    lm = cf.levenberg_marquardt(model.surface, X, x0)
    assert lm.solution[0] == pytest.approx(1.0, abs=1e-5)
    assert lm.status in (LeastSquaresStatus.CONVERGED, LeastSquaresStatus.STALLED)
    assert lm.iterations < 50


def test_recognition_of_crossed_trough_data(models):
    """The thesis's example (4.2.3.2): no candidates on the ellipsoid and the paraboloid."""
    rng = np.random.default_rng(9)
    trough = models["crossed_trough"].surface
    curves, point, _, _ = noisy_data_curves(
        trough, 0.6, 0.35, rng, n_points=61, spacing=0.015, noise=1e-3
    )
    result = recognize(list(models.values()), curves, CONFIG)
    assert result.name == "crossed_trough"
    errors = dict(result.ranking)
    assert errors["ellipsoid"] == np.inf and errors["elliptic_paraboloid"] == np.inf
    assert result.registrations["ellipsoid"].rejected
    assert (
        np.isfinite(errors["monkey_saddle"]) and errors["monkey_saddle"] > errors["crossed_trough"]
    )
    assert [e for _, e in result.ranking] == sorted(errors.values())
    assert not result.decided_at_lookup
    assert trough.symmetric_distance(point, result.location) < 0.02
    np.testing.assert_array_equal(result.pose, result.best.T_model_from_data)


def test_no_model_fits_when_every_lookup_is_empty(models):
    synthetic = clean_curves(models["ellipsoid"].surface, 1.02, 0.69, seed=10)
    result = recognize(list(models.values()), synthetic.curves, config(delta=1e-9))
    assert result.name is None
    assert np.all(np.isnan(result.pose)) and np.all(np.isnan(result.location))
    assert all(e == np.inf for _, e in result.ranking)
    rejected = result.registrations["ellipsoid"]
    assert rejected.status is RegistrationStatus.NO_CANDIDATES
    assert np.all(np.isnan(rejected.T_model_from_data))


def test_recognition_input_errors(models):
    synthetic = clean_curves(models["ellipsoid"].surface, 1.02, 0.69, seed=11)
    with pytest.raises(InvalidCurveData, match="at least one model"):
        recognize([], synthetic.curves, CONFIG)
    m = models["ellipsoid"]
    with pytest.raises(InvalidModel, match="unique"):
        recognize([m, m], synthetic.curves, CONFIG)


def test_fig_4_15_solids_recognise_themselves_from_noise_free_short_curves():
    solids = cf.fig_4_15_solids()
    models = [cf.ClosedFormModel.build(s, 90, 20) for s in solids]
    settings = ClosedFormConfig(delta=np.inf, max_candidates=3)
    rng = np.random.default_rng(12)
    for solid in solids[::3]:  # cylinder 1 and the sphere
        u, v = 0.8, (1.1 if solid.name == "sphere" else 0.0)
        synthetic = implicit_data_curves(
            solid, solid.sigma(u, v), n_points=41, spacing=0.05e-3, rng=rng
        )
        result = recognize(models, synthetic.curves, settings)
        assert result.name == solid.name
        assert result.ranking[0][1] < 1e-10 < result.ranking[1][1]
