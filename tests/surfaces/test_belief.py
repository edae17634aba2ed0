"""The belief over (model, pose), touch planning and the verification loop."""

from dataclasses import replace

import numpy as np
import pytest
from testing_meshes import blob, ellipsoid, sphere

from recognition import (
    BeliefConfig,
    Contact,
    InvalidArgument,
    ModelDatabase,
    NoiseModel,
    NoReading,
    TouchLimits,
    verify,
)
from recognition.evaluation.diagnosis import cause, surface_apart, touch_could_tell, truth_fit
from recognition.rigid import pose_matrix, rotation_about
from recognition.surfaces.active_touch import LOST_WITHIN_M
from recognition.surfaces.belief import Belief
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.noise_model import huber
from recognition.surfaces.registration import ALIGNED_SEARCH, FastConfig, data_geometry
from recognition.surfaces.registration.contact_pairs import N_KEPT, N_REFINED
from recognition.surfaces.registration.exact import smooth_normals
from recognition.surfaces.registration.fast import register_fast
from recognition.surfaces.touch_planning import (
    MAX_NONE_WEIGHT,
    information_gain,
    predicted_depths,
    without_edges,
)
from recognition.synthetic import mesh_data_curves, ray_contact, sensed_normal


@pytest.fixture(scope="module")
def database():
    scaled = ellipsoid()
    scaled.apply_scale(1.04)
    return ModelDatabase(
        {
            "blob": MeshModel("blob", blob()),
            "ellipsoid": MeshModel("ellipsoid", ellipsoid()),
            "larger_ellipsoid": MeshModel("larger_ellipsoid", scaled),
            "sphere": MeshModel("sphere", sphere()),
        }
    ).prepare()


def _curves(model, vertex, seed, noise=0.0, n_points=41, spacing_m=0.4e-3):
    return mesh_data_curves(
        model.mesh,
        vertex,
        normal=model.normals[vertex],
        n_points=n_points,
        spacing_m=spacing_m,
        noise_std_m=noise,
        rng=np.random.default_rng(seed),
    )


def _limits(synthetic):
    return TouchLimits(up=-synthetic.curves.approach, max_tilt_rad=np.deg2rad(80.0))


def test_distinct_data_give_one_sure_answer_with_posteriors_summing_to_one(database):
    model = database["blob"]
    synthetic = _curves(model, 2500, seed=1, noise=0.005e-3)
    result = database.recognize(synthetic.curves)
    assert result.name == "blob"
    assert result.hypotheses[0].model == "blob"
    assert result.confidence >= 0.99
    assert sum(h.posterior for h in result.hypotheses) == pytest.approx(1.0)
    np.testing.assert_allclose(result.hypotheses[0].location, synthetic.point_in_model, atol=0.1e-3)


def test_a_sphere_leaves_p_free_so_the_answer_is_not_sure(database):
    model = database["sphere"]
    synthetic = _curves(model, 300, seed=2, noise=0.005e-3)
    result = database.recognize(synthetic.curves, models=["sphere"])
    assert result.name == "sphere"
    # a turn about the centre moves p freely: the location is unknown far beyond 1 mm
    assert result.hypotheses[0].location_sd_m > 1e-3
    assert result.confidence < 0.5


def _the_ellipsoids_top(database):
    """The ellipsoid's top, where it and the 4 % larger one look alike: the model, curves
    of 11 points there and their recognition against the two (not sure)."""
    model = database["ellipsoid"]
    vertex = int(np.argmax(model.vertices[:, 2]))
    synthetic = _curves(model, vertex, seed=3, noise=0.002e-3, n_points=11, spacing_m=0.3e-3)
    result = database.recognize(
        synthetic.curves,
        models=["ellipsoid", "larger_ellipsoid"],
        noise=NoiseModel(model_mismatch_m=0.02e-3),
    )
    return model, synthetic, result


def test_touches_tell_two_similar_models_apart(database):
    model, synthetic, result = _the_ellipsoids_top(database)
    assert result.confidence < 0.99
    rng = np.random.default_rng(0)

    def touch(plan):
        return ray_contact(
            model.distance,
            synthetic.T_model_from_data,
            plan.start,
            plan.direction,
            plan.travel_m,
            noise_m=0.002e-3,
            rng=rng,
        )

    done = verify(database, result.belief, touch, _limits(synthetic), max_touches=5)
    assert done.belief.best.model == "ellipsoid"
    assert done.belief.confidence >= 0.99
    assert 1 <= len(done.steps) <= 5
    assert done.stop == "sure"
    # sure after a touch only once a broader search with all the touches found no rival
    assert done.belief.broadened == done.belief.touches
    # the ellipsoid's mirror images are the same answer
    images = done.belief.best.location_images
    assert len(images) > 1
    assert np.linalg.norm(images - synthetic.point_in_model, axis=1).min() < 1e-3


def _blob_and_a_vertex_8_mm_from_p(database):
    """The blob, its belief after well-determined curves, a vertex 8 mm from their p and
    the transform of the model frame into the data frame."""
    model = database["blob"]
    synthetic = _curves(model, 2500, seed=1, noise=0.005e-3)
    before = database.recognize(synthetic.curves, models=["blob"]).belief
    p = synthetic.point_in_model
    v = int(np.argmin(np.abs(np.linalg.norm(model.vertices - p, axis=1) - 8e-3)))
    return model, before, v, np.linalg.inv(synthetic.T_model_from_data)


@pytest.mark.parametrize("off_m", [0.0, 0.015e-3])
def test_a_touch_counts_by_the_density_its_hypothesis_predicted_for_it(database, off_m):
    # a touch 8 mm from p, on the blob or 15 um outside it, under a well-determined pose:
    # it moves the hypothesis against "none of these" (uniform along the approach) by
    # log(window / (sqrt(2 pi) s)) - z^2 / (2 (1 + q)) - log(1 + q) / 2, z = (r - mu) / s,
    # r the touch's residual at the pose before the touch, mu and s its mean and spread
    # given the curves' residuals, q the variance the pose's uncertainty adds to z
    model, before, v, data_from_model = _blob_and_a_vertex_8_mm_from_p(database)
    touched = model.vertices[v] + off_m * model.normals[v]
    touched = data_from_model[:3, :3] @ touched + data_from_model[:3, 3]
    after = database.update(before, touched[None])
    points = np.vstack([before.points, touched])
    T = before.best.T_model_from_data
    r = model.distance.signed(points @ T[:3, :3].T + T[:3, 3])
    sigma = before.noise.covariance(points, before.sensor_m)
    n = len(before.points)
    mu = sigma[n, :n] @ np.linalg.solve(sigma[:n, :n], r[:n])
    s = np.sqrt(sigma[n, n] - sigma[n, :n] @ np.linalg.solve(sigma[:n, :n], sigma[:n, n]))
    h = before.best
    weights = -np.linalg.solve(sigma[:n, :n], sigma[:n, n])  # z = (r_n + weights . r_o) / s
    moved = points @ T[:3, :3].T + T[:3, 3]
    _, near, faces = model.distance.closest(moved)
    normals = smooth_normals(model, near, faces)
    J = np.concatenate([np.cross(moved - h.pivot, normals), normals], axis=1)
    g = (J[n] + weights @ J[:n]) / s
    q = g @ h.pose_covariance @ g
    z = (r[n] - mu) / s
    expected = np.log(BeliefConfig().touch_window_m / (np.sqrt(2 * np.pi) * s))
    expected -= 0.5 * z**2 / (1 + q) + 0.5 * np.log(1 + q)
    assert after.best.touch_evidence == pytest.approx(expected, abs=0.02)
    assert abs(r[n] - off_m) < 2e-6  # the pose predicted the surface there
    # the refit to the touch moves the curves' own fit little
    gain = after.best.log_likelihood - before.best.log_likelihood
    assert gain == pytest.approx(expected, abs=0.5)
    # an approach twice as long made the contact half as likely under "none of these"
    longer = database.update(before, touched[None], windows=[2 * BeliefConfig().touch_window_m])
    assert longer.best.log_likelihood - after.best.log_likelihood == pytest.approx(np.log(2))


@pytest.mark.parametrize("tilt_deg", [0.0, 15.0])
def test_a_touchs_sensed_normal_counts_by_how_far_it_tilts_from_the_hypothesis(database, tilt_deg):
    # the same touch with the blob's own normal there gains -log s_n^2 on the touch
    # without one; tilted 15 degrees (7.5 s_n) it loses Huber's loss of the tilt on that
    model, before, v, data_from_model = _blob_and_a_vertex_8_mm_from_p(database)
    touched = data_from_model[:3, :3] @ model.vertices[v] + data_from_model[:3, 3]
    normal = model.normals[v]
    side = np.cross(normal, [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    tilt = np.deg2rad(tilt_deg)
    sensed = data_from_model[:3, :3] @ (np.cos(tilt) * normal + np.sin(tilt) * side)
    bare = database.update(before, touched[None])
    with_normal = database.update(before, touched[None], normals=sensed[None])
    s = before.noise.normal_sigma_rad()
    expected = -huber(np.array([tilt / s]), before.noise.huber_k)[0] - np.log(s**2)
    gain = with_normal.best.log_likelihood - bare.best.log_likelihood
    assert gain == pytest.approx(expected, abs=0.1)
    np.testing.assert_allclose(with_normal.normals, sensed[None], atol=1e-12)
    assert np.all(np.isnan(bare.normals))


def test_verification_takes_the_touchs_normal_when_the_sensor_gives_one(database):
    model, synthetic, result = _the_ellipsoids_top(database)
    data_from_model = np.linalg.inv(synthetic.T_model_from_data)

    def touch(plan):
        point = ray_contact(
            model.distance, synthetic.T_model_from_data, plan.start, plan.direction, 0.02
        )
        if point is None:
            return None
        T = synthetic.T_model_from_data
        _, _, face = model.distance.closest((T[:3, :3] @ point + T[:3, 3])[None])
        return Contact(point, data_from_model[:3, :3] @ model.mesh.face_normals[face[0]])

    done = verify(database, result.belief, touch, _limits(synthetic), max_touches=5)
    assert done.belief.best.model == "ellipsoid" and done.stop == "sure"
    made = [step for step in done.steps if step.contact is not None]
    assert made and all(step.normal is not None for step in made)
    assert np.all(np.isfinite(done.belief.normals)) and len(done.belief.normals) == len(made)


def test_a_touch_with_no_reading_leaves_the_belief_and_is_not_planned_again(database):
    model, synthetic, result = _the_ellipsoids_top(database)
    calls = []

    def touch(plan):
        calls.append(plan)
        if len(calls) == 1:
            return NoReading("the shaft touched")
        return ray_contact(
            model.distance, synthetic.T_model_from_data, plan.start, plan.direction, 0.02
        )

    limits = _limits(synthetic)
    done = verify(database, result.belief, touch, limits, max_touches=3)
    first = done.steps[0]
    assert first.no_reading == "the shaft touched" and first.contact is None
    assert first.belief is result.belief  # nothing was learnt from it
    assert len(done.steps) == len(calls) >= 2
    later = np.array([step.plan.point for step in done.steps[1:]])
    assert np.linalg.norm(later - first.plan.point, axis=1).min() >= limits.min_separation_m
    # the same belief, seed and avoided point plan the same touch again
    again = database.plan_touch(result.belief, limits, seed=1, avoid=first.plan.point[None])
    np.testing.assert_array_equal(again.point, done.steps[1].plan.point)


def test_after_a_touch_that_met_nothing_the_next_is_planned_near_the_contact_made(database):
    model, synthetic, result = _the_ellipsoids_top(database)
    calls = []

    def touch(plan):  # the first meets nothing, the others the true surface
        calls.append(plan)
        if len(calls) == 1:
            return None
        return ray_contact(
            model.distance, synthetic.T_model_from_data, plan.start, plan.direction, 0.02
        )

    limits = _limits(synthetic)
    done = verify(database, result.belief, touch, limits, max_touches=2, confidence=1.0)
    assert len(done.steps) == 2 and done.steps[0].contact is None
    near = np.linalg.norm(result.belief.points - done.steps[1].plan.point, axis=1).min()
    assert near <= LOST_WITHIN_M
    # planned on the same belief with and without the rule: it is what keeps a touch near
    free = database.plan_touch(result.belief, limits, seed=3)
    close = database.plan_touch(result.belief, limits, seed=3, within_m=LOST_WITHIN_M)
    assert np.linalg.norm(result.belief.points - close.point, axis=1).min() <= LOST_WITHIN_M
    assert np.linalg.norm(result.belief.points - free.point, axis=1).min() > LOST_WITHIN_M


def test_a_last_touch_that_nothing_explains_has_a_broader_search_after_it(database):
    synthetic = _curves(
        database["blob"], 2500, seed=2, noise=0.002e-3, n_points=21, spacing_m=0.6e-3
    )
    result = database.recognize(synthetic.curves, models=["blob"])

    def touch(plan):  # 3 mm beyond where the hypotheses put the surface
        return plan.start + (plan.depths_m[0] + 3e-3) * plan.direction

    limits = _limits(synthetic)
    done = verify(database, result.belief, touch, limits, max_touches=1, confidence=1.0)
    assert len(done.steps) == 1 and done.steps[0].belief.unexplained >= 0.5
    assert done.steps[0].belief.broadened is None
    assert done.belief.broadened == 1 and done.broaden_s > 0  # searched again after it
    untouched = verify(database, result.belief, touch, limits, max_touches=0, confidence=1.0)
    assert untouched.belief is result.belief  # no touch, no search


def test_a_last_touch_that_leaves_the_belief_unsure_has_a_broader_search_after_it(database):
    synthetic = _curves(
        database["blob"], 2500, seed=2, noise=0.002e-3, n_points=21, spacing_m=0.6e-3
    )
    result = database.recognize(synthetic.curves, models=["blob"])
    limits = _limits(synthetic)
    done = verify(
        database, result.belief, lambda plan: plan.point, limits, max_touches=1, confidence=1.0
    )
    assert done.steps[0].belief.unexplained < 0.5  # the touch met the predicted surface
    assert done.steps[0].confidence < 1.0  # and left the belief short of sure
    assert done.steps[0].belief.broadened is None
    assert done.belief.broadened == 1  # not sure after it: searched again


def test_a_search_whose_answer_may_end_the_touches_keeps_every_pair_pose_it_refines(
    database, monkeypatch
):
    synthetic = _curves(
        database["blob"], 2500, seed=2, noise=0.002e-3, n_points=21, spacing_m=0.6e-3
    )
    result = database.recognize(synthetic.curves, models=["blob"])
    import recognition.surfaces.database as database_module

    seen = []
    real = database_module.pair_search
    monkeypatch.setattr(
        database_module,
        "pair_search",
        lambda *args, **kw: seen.append(kw) or real(*args, **kw),
    )

    def touch(plan):  # the predicted contact, with the normal the sensor felt
        return Contact(plan.point, -plan.direction)

    done = verify(database, result.belief, touch, _limits(synthetic), max_touches=1, confidence=1.0)
    assert done.belief.broadened == 1 and len(seen) == 1  # the one search after the touch
    assert seen[0]["refined"] == seen[0]["kept"] == database_module.FINAL_REFINED
    # a broader search during the touches keeps the search's own numbers
    database.broaden(done.steps[0].belief)
    assert len(seen) == 2 and (seen[1]["refined"], seen[1]["kept"]) == (N_REFINED, N_KEPT)
    # the search after the touch that makes the belief sure is as thorough as the last
    sure_at = done.steps[0].confidence
    assert result.belief.confidence < sure_at
    seen.clear()
    verify(database, result.belief, touch, _limits(synthetic), max_touches=1, confidence=sure_at)
    assert len(seen) == 1 and seen[0]["refined"] == database_module.FINAL_REFINED


def test_a_belief_a_search_made_sure_is_tested_by_a_touch(database, monkeypatch):
    synthetic = _curves(database["blob"], 2500, seed=1, noise=0.005e-3)
    sure = database.recognize(synthetic.curves, models=["blob"]).belief
    limits = _limits(synthetic)
    assert sure.confidence >= 0.99
    # sure, nothing tells its hypotheses apart; doubted, a touch tests the answer
    assert database.plan_touch(sure, limits, seed=1) is None
    doubted = database.plan_touch(sure, limits, seed=1, doubt=MAX_NONE_WEIGHT)
    assert doubted is not None and doubted.information_nats > 0.1
    # a belief that nothing explains, which the broader search before the first touch
    # makes sure
    lost = replace(
        sure,
        hypotheses=tuple(replace(h, posterior=0.01 * h.posterior) for h in sure.hypotheses),
        unexplained=0.99,
    )
    assert lost.confidence < 0.5
    monkeypatch.setattr(
        type(database), "broaden", lambda self, belief, **_: belief if belief.touches else sure
    )
    done = verify(database, lost, lambda plan: plan.point, limits, max_touches=3)
    assert len(done.steps) == 1  # one touch, the one that tests the search's answer
    assert done.stop == "sure" and done.steps[0].confidence >= 0.99


def test_none_of_these_spreads_a_touch_over_the_planned_approach():
    assert BeliefConfig().touch_window_m == TouchLimits(up=np.array([0.0, 0.0, 1.0])).depth_m


def test_a_sure_belief_makes_no_touch(database):
    synthetic = _curves(database["blob"], 2500, seed=1, noise=0.005e-3)
    result = database.recognize(synthetic.curves)

    def touch(plan):
        raise AssertionError("no touch expected")

    done = verify(database, result.belief, touch, _limits(synthetic))
    assert done.steps == () and done.stop == "sure"


def test_a_gross_outlier_is_reported_and_does_not_change_the_answer(database):
    synthetic = _curves(database["blob"], 2500, seed=4, noise=0.005e-3)
    curves = [c.copy() for c in synthetic.curves.curves]
    curves[1][5] += 0.02 * synthetic.curves.approach
    moved = type(synthetic.curves)(tuple(curves), approach=synthetic.curves.approach)
    result = database.recognize(moved)
    assert result.hypotheses[0].model == "blob"
    index = len(curves[0]) + 5
    assert index in result.hypotheses[0].outliers
    images = result.hypotheses[0].location_images  # the blob's symmetric images
    assert np.linalg.norm(images - synthetic.point_in_model, axis=1).min() < 0.1e-3


def test_information_gain_is_log_two_for_two_far_apart_outcomes_and_zero_for_one():
    depths = np.array([[1e-3, 1e-3], [1e-3, 3e-3]])
    gain = information_gain(depths, np.array([0.5, 0.5]), 1e-5)
    np.testing.assert_allclose(gain, [0.0, np.log(2)], atol=1e-9)
    # a predicted miss is an outcome of its own
    miss = information_gain(np.array([[2e-3], [np.nan]]), np.array([0.5, 0.5]), 1e-5)
    np.testing.assert_allclose(miss, [np.log(2)], atol=1e-9)


def test_information_gain_sums_the_overlaps_of_every_pair_of_outcomes():
    # against the sum written out over all (H + 1) x (H + 1) pairs, "none of these" the last
    rng = np.random.default_rng(8)
    sigma, window, none = 0.05e-3, 12e-3, 0.2
    for H, C in ((1, 5), (7, 40), (60, 30)):
        depths = rng.uniform(0, 12e-3, (H, C)) * rng.choice([1.0, 0.01], (H, C))
        depths[rng.random((H, C)) < 0.1] = np.nan
        weights = rng.random(H)
        d = np.where(np.isnan(depths), 1.0, depths)
        overlap = np.ones((H + 1, H + 1, C))
        overlap[:H, :H] = np.exp(-((d[:, None] - d[None]) ** 2) / (8 * sigma**2))
        met = np.where(np.isnan(depths), 0.0, np.sqrt(sigma * np.sqrt(8 * np.pi) / window))
        overlap[:H, H] = overlap[H, :H] = met
        w = np.append(weights, none) / (weights.sum() + none)
        expected = -(w @ np.log(np.einsum("j,ijc->ic", w, overlap)))
        got = information_gain(depths, weights, sigma, none, window)
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-14)
        alone = -(w[:H] / w[:H].sum()) @ np.log(
            np.einsum("j,ijc->ic", w[:H] / w[:H].sum(), overlap[:H, :H])
        )
        np.testing.assert_allclose(
            information_gain(depths, weights, sigma), alone, rtol=1e-12, atol=1e-14
        )


def test_touches_a_likely_hypothesis_predicts_to_miss_are_made_only_when_nothing_else_tells():
    # two equally likely hypotheses; touch 0: both meet the surface 1 mm apart, touch 1:
    # the first meets it, the second predicts nothing there
    depths = np.array([[4.0e-3, 4.0e-3], [5.0e-3, np.nan]])
    weights = np.array([0.5, 0.5])
    gain = information_gain(depths, weights, 0.05e-3)
    assert gain[1] > 0.6 and gain[0] > 0.6
    assert without_edges(gain, depths, weights)[1] == -np.inf  # the contact either way
    apart = np.array([[4.0e-3, 4.0e-3], [4.0e-3, np.nan]])  # only the edge tells them apart
    alone = without_edges(information_gain(apart, weights, 0.05e-3), apart, weights)
    assert np.argmax(alone) == 1 and alone[1] > 0.6


def test_none_of_these_is_an_outcome_spread_over_the_approach():
    # one hypothesis against "none of these": a touch tests it even with nothing to split
    sigma, window = 2e-5, 10e-3
    across = np.sqrt(sigma * np.sqrt(8 * np.pi) / window)  # Bhattacharyya: Gaussian, uniform
    gain = information_gain(np.array([[4e-3]]), np.array([0.5]), sigma, 0.5, window)
    np.testing.assert_allclose(gain, [-np.log(0.5 * (1 + across))], rtol=1e-12)
    assert information_gain(np.array([[4e-3]]), np.array([1.0]), sigma) == pytest.approx(0)
    # a predicted miss shares nothing with a contact along the approach
    miss = information_gain(np.array([[np.nan]]), np.array([0.5]), sigma, 0.5, window)
    np.testing.assert_allclose(miss, [np.log(2)], atol=1e-9)


def test_contact_points_choose_the_poses_of_the_search(database):
    model = database["blob"]
    # short, noisy curves leave the blob's pose loose: the best fit lies 30 mm away
    synthetic = _curves(model, 2500, seed=2, noise=0.02e-3, n_points=9, spacing_m=0.6e-3)
    p = synthetic.point_in_model
    distance = np.linalg.norm(model.vertices - p, axis=1)
    touched = model.vertices[[int(np.argmin(np.abs(distance - r))) for r in (10e-3, 14e-3)]]
    into_data = np.linalg.inv(synthetic.T_model_from_data)
    contact = touched @ into_data[:3, :3].T + into_data[:3, 3]
    config = replace(FastConfig(), search=ALIGNED_SEARCH, fallbacks=())
    geometry = data_geometry(synthetic.curves, config.geometry)

    def touch_residuals_m(found):
        T = found.poses[0]
        return np.abs(database.field_stack((contact @ T[:3, :3].T + T[:3, 3])[None], [0])[0])

    alone = register_fast([model], synthetic.curves, geometry, config)[0]
    assert touch_residuals_m(alone).max() > 0.5e-3
    touched_too = register_fast([model], synthetic.curves, geometry, config, contact=contact)[0]
    assert touch_residuals_m(touched_too).max() < 0.15e-3


def test_a_broader_search_runs_once_per_touch(database):
    synthetic = _curves(database["blob"], 2500, seed=2, noise=0.02e-3, n_points=9, spacing_m=0.6e-3)
    belief = database.recognize(synthetic.curves, models=["blob"]).belief
    broad = database.broaden(belief)
    assert belief.broadened is None and broad.broadened == 0
    assert database.broaden(broad) is broad  # no new touch: nothing to search again
    touched = database.update(broad, broad.point[None])  # a touch at p, where the curves meet
    assert touched.broadened == 0 and database.broaden(touched).broadened == 1
    # a touch that met nothing rules poses out: it too is searched with again
    away = broad.point + 0.05 * np.array([0.0, 0.0, 1.0])
    missed = database.update(database.broaden(touched), misses=[(away, [0.0, 0.0, 1.0], 0.01)])
    assert missed.touches == 2 and missed.broadened == 1
    assert database.broaden(missed).broadened == 2


def test_a_broader_search_counts_outliers_as_the_recognition_did(database, monkeypatch):
    """Told the object differs from its model, recognition clips points at a level that
    mismatch allows; the broader search after touches uses the same level, not the
    database's (which would clip the true pose's points as outliers)."""
    synthetic = _curves(database["blob"], 2500, seed=2, noise=0.02e-3, n_points=9, spacing_m=0.6e-3)
    told = FastConfig(model_mismatch_m=0.1e-3)
    belief = database.recognize(synthetic.curves, told, models=["blob"]).belief
    assert belief.noise.model_mismatch_m == told.model_mismatch_m
    import recognition.surfaces.database as database_module

    seen = []
    real = database_module.register_all
    monkeypatch.setattr(
        database_module,
        "register_all",
        lambda models, curves, config, **kw: (
            seen.append(config) or real(models, curves, config, **kw)
        ),
    )
    database.broaden(belief)
    assert seen and seen[0].model_mismatch_m == told.model_mismatch_m


def test_predicted_depth_along_a_ray_to_the_sphere_centre(database):
    stack = database.field_stack
    which = np.array([database.names.index("sphere")])
    start = np.array([[0.0, 0.0, 0.035]])
    depth = predicted_depths(stack, which, np.eye(4)[None], start, np.array([[0, 0, -1.0]]), 0.01)
    assert depth[0, 0] == pytest.approx(0.005, abs=0.05e-3)
    away = predicted_depths(stack, which, np.eye(4)[None], start, np.array([[0, 0, 1.0]]), 0.01)
    assert np.isnan(away[0, 0])


def test_ray_contact_meets_the_mesh_where_the_ray_does(database):
    model = database["sphere"]
    hit = ray_contact(model.distance, np.eye(4), [0.0, 0.0, 0.04], [0.0, 0.0, -1.0], 0.02)
    assert np.linalg.norm(hit) == pytest.approx(0.03, abs=0.02e-3)
    assert ray_contact(model.distance, np.eye(4), [0, 0, 0.04], [0, 0, 1.0], 0.02) is None


def test_ray_contact_from_a_start_inside_meets_the_mesh_on_the_way_in(database):
    """The approach's start lies inside the sphere (r = 30 mm): the probe met the surface
    on its way there, along the approach (by default) or lowered from above."""
    model = database["sphere"]
    start, across = [0.02, 0.0, 0.0], [-1.0, 0.0, 0.0]
    along = ray_contact(model.distance, np.eye(4), start, across, 0.02)
    assert along == pytest.approx([0.03, 0.0, 0.0], abs=0.02e-3)
    lowered = ray_contact(model.distance, np.eye(4), start, across, 0.02, way_in=[0, 0, 0.1])
    assert lowered == pytest.approx([0.02, 0.0, np.sqrt(0.03**2 - 0.02**2)], abs=0.02e-3)


def test_a_synthetic_touch_senses_the_meshs_normal_with_the_stated_noise(database):
    model = database["sphere"]
    T = np.eye(4)
    T[:3, 3] = [0.01, 0.0, 0.0]  # data frame shifted from the model's
    point = np.array([-0.01, 0.0, 0.03])  # the sphere's top in the data frame
    exact = sensed_normal(model.distance, T, point)
    assert np.degrees(np.arccos(exact @ [0.0, 0.0, 1.0])) < 2.0  # a facet of the test sphere
    rng = np.random.default_rng(0)
    sigma = np.deg2rad(2.0)
    tilts = [
        np.arccos(
            np.clip(
                sensed_normal(model.distance, T, point, noise_rad=sigma, rng=rng) @ exact, -1, 1
            )
        )
        for _ in range(2000)
    ]
    # two components of sigma each: an RMS tilt of sigma sqrt(2)
    assert np.sqrt(np.mean(np.square(tilts))) == pytest.approx(sigma * np.sqrt(2), rel=0.05)


def test_bad_arguments_are_refused_with_typed_errors(database):
    synthetic = _curves(database["blob"], 2500, seed=1)
    result = database.recognize(synthetic.curves)
    with pytest.raises(InvalidArgument, match="max_touches"):
        verify(database, result.belief, lambda plan: None, _limits(synthetic), max_touches=-1)
    with pytest.raises(InvalidArgument, match="up"):
        TouchLimits(up=np.zeros(3))
    with pytest.raises(InvalidArgument, match="finite"):
        database.update(result.belief, np.full((1, 3), np.nan))
    with pytest.raises(InvalidArgument, match="windows"):
        database.update(result.belief, synthetic.curves.intersection[None], windows=[0.0])
    with pytest.raises(InvalidArgument, match="windows"):
        database.update(result.belief, synthetic.curves.intersection[None], windows=[1e-3, 2e-3])
    with pytest.raises(InvalidArgument, match="normals"):
        database.update(result.belief, synthetic.curves.intersection[None], normals=np.ones(3))
    with pytest.raises(InvalidArgument, match="model_mismatch_m"):
        NoiseModel(model_mismatch_m=-1.0)


def _loose_blob_and_two_touches(database):
    """Short noisy curves on the blob, which leave its pose loose: their belief and two
    touches on the blob 12 and 20 mm from p (data frame)."""
    model = database["blob"]
    synthetic = _curves(model, 2500, seed=1, noise=0.05e-3, n_points=11, spacing_m=1.2e-3)
    found = database.recognize(synthetic.curves, models=["blob"]).belief
    p = synthetic.point_in_model
    data_from_model = np.linalg.inv(synthetic.T_model_from_data)
    distance = np.linalg.norm(model.vertices - p, axis=1)
    above = 1e3 * (model.vertices[:, 2] < p[2])
    v = [int(np.argmin(np.abs(distance - d) + above)) for d in (12e-3, 20e-3)]
    touched = model.vertices[v] @ data_from_model[:3, :3].T + data_from_model[:3, 3]
    return found, touched


def test_a_pose_added_after_touches_counts_them_as_a_hypothesis_that_made_them(database):
    # short noisy curves leave the blob's pose loose; two touches pin it. A pose added
    # after them (a broader search's) predicts each touch in turn, the second at the pose
    # the first pinned: exactly as a hypothesis that was there when they were made (no
    # valleys explored, so that one pose is followed), and more than the pose the curves
    # alone leave loose predicts them
    found, touched = _loose_blob_and_two_touches(database)
    start = [("blob", found.best.T_model_from_data)]
    config = replace(found.config, explore_hypotheses=0)
    before = replace(found, hypotheses=(), config=config).with_poses(database.models, start)
    made = database.update(database.update(before, touched[:1]), touched[1:])
    added = replace(made, hypotheses=()).with_poses(database.models, start)
    assert len(made.hypotheses) == len(added.hypotheses) == 1
    assert added.best.touch_evidence == pytest.approx(made.best.touch_evidence, abs=1e-6)
    assert added.best.log_likelihood == pytest.approx(made.best.log_likelihood, abs=1e-6)
    loose = replace(made, hypotheses=())._predicted(
        before.hypotheses, database.models, made._whitening(), 0
    )
    assert loose[0] < made.best.touch_evidence - 0.1


def test_the_diagnosis_tells_a_missed_truth_from_data_that_favour_the_answer(database):
    # curves on the blob searched on the sphere alone: the answer (the sphere) is wrong
    # and the true pose, scored as a broader search's pose would be, fits far better (the
    # search missed it); the right answer against itself is a tie
    model = database["blob"]
    synthetic = _curves(model, 2500, seed=1, noise=0.005e-3)
    truth = (model.name, synthetic.T_model_from_data, synthetic.point_in_model)
    wrong = database.recognize(synthetic.curves, models=["sphere"]).belief
    fit = truth_fit(database.models, wrong, *truth)
    assert fit is not None and fit["log_ratio"] > 100 and fit["error_mm"] < 0.1
    assert cause(fit) == "search"
    # the sphere stands apart from the blob on most of its surface: a touch would tell
    assert fit["apart"] > 0.5 and touch_could_tell(fit)
    right = database.recognize(synthetic.curves, models=["blob"]).belief
    fit = truth_fit(database.models, right, *truth)
    assert fit is not None and abs(fit["log_ratio"]) < 1 and cause(fit) == "tie"


def test_a_pose_stands_apart_from_the_truth_where_a_touch_would_tell(database):
    # a sphere turned about its centre is the same surface (apart nowhere); the blob
    # turned as much, or shifted by 1 mm, stands apart on much of it; the same pose nowhere
    def turned(model, degrees):
        centre = np.asarray(model.mesh.centroid)
        R = rotation_about(2, np.deg2rad(degrees))
        return pose_matrix(R, centre - R @ centre)

    sphere, blob = database["sphere"], database["blob"]
    truth = np.eye(4)
    assert surface_apart(sphere, turned(sphere, 40.0), sphere, truth, 0.15e-3) < 0.01
    assert surface_apart(blob, truth, blob, truth, 0.15e-3) == 0.0
    assert surface_apart(blob, turned(blob, 40.0), blob, truth, 0.15e-3) > 0.5
    shifted = pose_matrix(np.eye(3), [1e-3, 0.0, 0.0])
    assert surface_apart(blob, shifted, blob, truth, 0.15e-3) > 0.3


def test_a_pose_found_along_a_valley_after_touches_counts_them_as_it_predicted_them(
    database, monkeypatch
):
    # a pose that the valley exploration finds after touches counts each touch as it
    # would have predicted it in turn (as a broader search's pose does), not as the
    # hypothesis whose valley it lies along predicted it: short noisy curves leave the
    # blob's pose loose, and a pose started 7 mm along that valley ends 6 mm away, 5 mm
    # off the second touch, which the pose the touches pinned meets
    found, touched = _loose_blob_and_two_touches(database)
    # no valleys explored at the first touch, every pose kept: the one start below is
    # all the exploration there is
    found = replace(found, config=replace(found.config, explore_hypotheses=0, min_posterior=0))
    once = database.update(found, touched[:1])
    _, second = once.loose_motions(once.best)[1]
    start = once.best.moved(-7e-3 * second)
    monkeypatch.setattr(Belief, "_explored", lambda belief, found: [("blob", start, 0.0)])
    after = database.update(once, touched[1:])
    # the same steps by hand: refined on all the contact, each touch predicted in turn
    fresh = replace(after, hypotheses=())
    whitening = fresh._whitening()
    minimum = fresh._fitted([("blob", start, 0.0)], database.models, whitening)[0]
    ((name, T, evidence),) = fresh._in_turn(
        [("blob", minimum.T_model_from_data, 0.0)], database.models
    )
    expected = fresh._fitted([(name, T, evidence)], database.models, whitening)[0]
    assert np.linalg.norm(expected.location - after.best.location) > 1e-3
    (valley,) = [h for h in after.hypotheses if np.allclose(h.location, expected.location)]
    assert valley.touch_evidence == pytest.approx(evidence, abs=1e-9)
    assert valley.touch_evidence < after.best.touch_evidence - 10.0


def test_a_hypothesis_a_touch_moves_beyond_its_uncertainty_counts_the_touches_again(database):
    # a hypothesis whose refinement moves p farther than its own uncertainty explains has
    # come to another place: the touches it predicted from where it was do not speak for
    # it there, and they count again as it would have predicted each in turn. A pose
    # 5 mm along the loose blob's valley, marked as certain to 0.1 mm, comes back to the
    # place the touches pin; still allowed to move that far, it keeps what it predicted
    found, touched = _loose_blob_and_two_touches(database)
    config = replace(found.config, explore_hypotheses=0)
    once = database.update(replace(found, config=config), touched[:1])
    best = once.best
    _, loose = once.loose_motions(best)[0]
    away = replace(best, T_model_from_data=best.moved(5e-3 * loose))
    sure = replace(away, location_covariance=np.eye(3) * (0.1e-3) ** 2)
    moved = database.update(replace(once, hypotheses=(sure,)), touched[1:])
    kept = database.update(
        replace(once, hypotheses=(sure,), config=replace(config, drift_sds=1e9)), touched[1:]
    )
    assert len(moved.hypotheses) == len(kept.hypotheses) == 1
    start = away.T_model_from_data
    assert np.linalg.norm(moved.best.location - (start[:3, :3] @ once.point + start[:3, 3])) > 1e-3
    # the same steps by hand: the refined pose, each touch predicted in turn from there
    fresh = replace(moved, hypotheses=())
    ((_, _, evidence),) = fresh._in_turn(
        [("blob", kept.best.T_model_from_data, 0.0)], database.models
    )
    assert moved.best.touch_evidence == pytest.approx(evidence, abs=1e-9)
    assert kept.best.touch_evidence != pytest.approx(evidence, abs=1e-3)


def test_no_pose_predicts_a_touch_better_than_its_bound(database):
    # a touch adds at most -log(sqrt(2 pi) L_ii / w_i) for its point and -2 log sigma_n
    # for its sensed normal to a hypothesis's log ratio against "none of these": the
    # poses along the loose blob's valley, near and far, predict it no better
    found, touched = _loose_blob_and_two_touches(database)
    model = database["blob"]
    T = found.best.T_model_from_data
    _, _, face = model.distance.signed_closest(touched[:1] @ T[:3, :3].T + T[:3, 3])
    normal = model.distance.normals_of(face) @ T[:3, :3]  # data frame
    once = database.update(found, touched[:1], normals=normal)
    bound = once._touch_bounds()
    assert bound.shape == (1,) and np.isfinite(bound[0])
    _, loose = found.loose_motions(found.best)[0]
    posed = [
        replace(found.best, T_model_from_data=found.best.moved(s * loose))
        for s in (-6e-3, -2e-3, -0.5e-3, 0.0, 0.5e-3, 2e-3, 6e-3)
    ]
    scores = once._predicted(posed, database.models, once._whitening(), 0)
    assert max(scores) <= bound[0]
    assert max(scores) > bound[0] - 10.0  # and the best comes near it


def test_poses_that_cannot_win_are_left_out_before_all_their_touches_are_counted(
    database, monkeypatch
):
    # poses added after touches keep the evidence that counting all their touches gives,
    # unless it leaves them below the posterior floor of the likeliest hypothesis's
    # log-likelihood; those are left out, and as soon as the touches still to count,
    # each predicted as well as it can be (the bounds), cannot lift them over it: with
    # the floor beyond every bound, no pose is even fitted. Poses along the loose blob's
    # valley and turned about p
    found, touched = _loose_blob_and_two_touches(database)
    made = database.update(database.update(found, touched[:1]), touched[1:])
    best = made.best
    _, loose = made.loose_motions(best)[0]
    p = best.location
    poses = [("blob", best.moved(s * loose), 0.0) for s in (-3e-3, 3e-3)]
    for angle in np.deg2rad([20.0, 45.0, 90.0]):
        turn = pose_matrix(rotation_about(0, angle), p - rotation_about(0, angle) @ p)
        poses.append(("blob", turn @ best.T_model_from_data, 0.0))
    every = made._in_turn(poses, database.models)
    evidence = sorted(e for _, _, e in every)
    gap = -np.log(made.config.min_posterior)
    for floor in (evidence[0] - 1.0, 0.5 * (evidence[1] + evidence[2]), evidence[-1] + 1.0):
        kept = made._in_turn(poses, database.models, floor + gap)
        expected = [(name, T, e) for name, T, e in every if e >= floor]
        assert len(kept) == len(expected)
        for (_, T, e), (_, T_all, e_all) in zip(kept, expected, strict=True):
            np.testing.assert_array_equal(T, T_all)
            assert e == e_all
    fitted = []
    monkeypatch.setattr(Belief, "_fitted", lambda *args: fitted.append(args) or [])
    assert made._in_turn(poses, database.models, made._touch_bounds().sum() + gap + 1e-6) == []
    assert not fitted
