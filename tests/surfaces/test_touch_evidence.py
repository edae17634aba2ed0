"""How a touch's sensed normal and a missed touch weigh a hypothesis against "none"."""

import numpy as np
import pytest

from recognition import InvalidArgument
from recognition.surfaces.noise_model import NoiseModel, huber
from recognition.surfaces.touch_evidence import normal_evidence, sensed_normals

SIGMA = np.deg2rad(2.0)
UP = np.array([[0.0, 0.0, 1.0]])


def _tilted(angle_rad: float) -> np.ndarray:
    return np.array([[np.sin(angle_rad), 0.0, np.cos(angle_rad)]])


@pytest.mark.parametrize("sigmas", [0.0, 1.0, 3.0, 8.0])
def test_a_sensed_normal_scores_its_tilt_from_the_predicted_one_against_a_uniform_hemisphere(
    sigmas,
):
    # N(0, s^2 I) in the tangent plane over 1 / (2 pi) per steradian: -huber(z) - log s^2
    score = normal_evidence(UP, _tilted(sigmas * SIGMA), np.zeros((3, 3)), SIGMA, 3.0)
    expected = -huber(np.array([sigmas]), 3.0)[0] - np.log(SIGMA**2)
    assert score == pytest.approx(expected, rel=1e-9, abs=1e-9)


def test_an_uncertain_turn_widens_what_the_normal_may_tilt():
    # a turn about x or y of standard deviation tau tilts the normal z by as much
    tau = np.deg2rad(3.0)
    turn = np.diag([tau**2, tau**2, 1.0])  # a turn about z does not tilt it
    score = normal_evidence(UP, _tilted(2 * SIGMA), turn, SIGMA, 3.0)
    wide = SIGMA**2 + tau**2
    assert score == pytest.approx(-0.5 * (2 * SIGMA) ** 2 / wide - np.log(wide), rel=1e-9)


def test_no_sensed_normal_counts_nothing_and_an_opposite_one_counts_much():
    assert normal_evidence(UP, np.full((1, 3), np.nan), np.zeros((3, 3)), SIGMA, 3.0) == 0.0
    opposite = normal_evidence(UP, -UP, np.zeros((3, 3)), SIGMA, 3.0)
    assert opposite == pytest.approx(-(3.0 * np.pi / SIGMA - 4.5) - np.log(SIGMA**2))


def test_the_normals_of_several_touches_and_hypotheses_score_as_each_alone():
    rng = np.random.default_rng(2)
    predicted = rng.normal(size=(4, 5, 3))
    predicted /= np.linalg.norm(predicted, axis=-1, keepdims=True)
    sensed = predicted + 0.05 * rng.normal(size=(4, 5, 3))
    sensed /= np.linalg.norm(sensed, axis=-1, keepdims=True)
    sensed[:, [1, 3]] = np.nan  # not sensed
    A = rng.normal(size=(4, 3, 3)) * 0.02
    turn = A @ np.swapaxes(A, 1, 2)
    together = normal_evidence(predicted, sensed, turn, SIGMA, 3.0)
    for h in range(4):
        alone = sum(
            normal_evidence(predicted[h, [i]], sensed[h, [i]], turn[h], SIGMA, 3.0)
            for i in (0, 2, 4)
        )
        assert together[h] == pytest.approx(alone, rel=1e-12)
        assert normal_evidence(predicted[h, [1]], sensed[h, [1]], turn[h], SIGMA, 3.0) == 0.0


def test_the_model_mismatch_adds_its_slope_to_the_sensors_normal_noise():
    noise = NoiseModel(normal_sd_rad=0.03, model_mismatch_m=0.1e-3, correlation_m=5e-3)
    assert noise.normal_sigma_rad() == pytest.approx(np.hypot(0.03, np.sqrt(3) * 0.1 / 5))


def test_sensed_normals_are_made_unit_and_bad_ones_refused():
    out = sensed_normals([[0.0, 0.0, 2.0], [np.nan] * 3], 2)
    np.testing.assert_array_equal(out[0], [0.0, 0.0, 1.0])
    assert np.all(np.isnan(out[1]))
    assert np.all(np.isnan(sensed_normals(None, 3))) and sensed_normals(None, 3).shape == (3, 3)
    for bad in ([[0.0, 0.0, 0.0]], [[np.nan, 0.0, 1.0]], [[np.inf, 0.0, 1.0]], [[0.0, 1.0]]):
        with pytest.raises(InvalidArgument, match="normal"):
            sensed_normals(bad, 1)
    with pytest.raises(InvalidArgument, match="normal_sd_rad"):
        NoiseModel(normal_sd_rad=0.0)


def test_a_missed_touch_reads_only_the_ray_points_that_can_be_inside():
    """The deepest point of a missed touch's ray inside the posed model is the least
    signed distance over all its points whenever that is negative, and not negative when
    no point is inside, though most points are never read (rays through, grazing and
    clear of a blob, at random poses)."""
    from testing_meshes import blob

    from recognition.surfaces.mesh_model import MeshModel
    from recognition.surfaces.touch_evidence import _deepest

    distance = MeshModel("blob", blob()).distance
    rng = np.random.default_rng(4)
    inside = outside = 0
    for _ in range(60):
        start = rng.normal(size=3) * 0.05
        aim = rng.normal(size=3) * 0.02
        direction = (aim - start) / np.linalg.norm(aim - start)
        steps = np.arange(0.0, 0.08 + 0.05e-3, 0.1e-3)
        ray = start + steps[:, None] * direction
        every = float(distance.signed(ray).min())
        deepest = _deepest(distance, ray, steps)
        if every < 0:
            inside += 1
            assert deepest == every
        else:
            outside += 1
            assert deepest >= 0
    assert inside >= 10 and outside >= 10


def test_a_missed_touch_costs_what_every_point_of_its_ray_says():
    """A missed touch's cost is Huber's loss of the deepest of all its ray's points inside
    the posed model (none inside: nothing), though a ray clear of the surface is cast, not
    sampled (rays from outside and inside a blob at random poses, through it, grazing it
    and clear of it)."""
    from scipy.spatial.transform import Rotation
    from testing_meshes import blob

    from recognition.surfaces.mesh_model import MeshModel
    from recognition.surfaces.touch_evidence import RAY_SAMPLE_M, miss_evidence

    distance = MeshModel("blob", blob()).distance
    rng = np.random.default_rng(7)
    sigma, k = 0.1e-3, 3.0
    costly = free = 0
    for _ in range(80):
        R = Rotation.from_rotvec(rng.normal(size=3)).as_matrix()
        t = rng.normal(size=3) * 0.005
        start = rng.normal(size=3) * 0.04
        aim = rng.normal(size=3) * 0.02
        direction = (aim - start) / np.linalg.norm(aim - start)
        travel = rng.uniform(0.005, 0.06)
        steps = np.arange(0.0, travel + 0.5 * RAY_SAMPLE_M, RAY_SAMPLE_M)
        every = float(distance.signed((start + steps[:, None] * direction) @ R.T + t).min())
        expected = -huber(np.array([every / sigma]), k)[0] if every < 0 else 0.0
        cost = miss_evidence(distance, R, t, [(start, direction, travel)], sigma, k)
        assert cost == pytest.approx(expected, rel=1e-12, abs=0.0)
        costly += cost < 0
        free += cost == 0
    assert costly >= 10 and free >= 10
