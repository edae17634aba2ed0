"""Poses the data cannot tell apart: equivalent poses, free motions, model symmetries."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from recognition import ModelDatabase
from recognition.rigid import rotation_angle
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.registration.ambiguity import Resolution, distinct_poses
from recognition.synthetic import mesh_data_curves
from tests.testing_meshes import blob, sphere


def _plane_points(n: int = 63) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(0)
    points = np.c_[rng.uniform(-0.01, 0.01, (n, 2)), np.zeros(n)]
    return points, np.tile([0.0, 0.0, 1.0], (n, 1))


def test_free_motions_of_a_plane_a_cylinder_and_a_sphere() -> None:
    resolution = Resolution(sigma_m=0.02e-3, n_points=63)
    points, normals = _plane_points()
    assert resolution.free_motions(points, normals) == 3  # two slides and a turn
    rng = np.random.default_rng(1)
    angle, z = rng.uniform(-0.5, 0.5, 63), rng.uniform(-0.01, 0.01, 63)
    on_cylinder = np.c_[0.02 * np.cos(angle), 0.02 * np.sin(angle), z]
    radial = np.c_[np.cos(angle), np.sin(angle), np.zeros(63)]
    assert resolution.free_motions(on_cylinder, radial) == 2  # along and about its axis
    direction = rng.normal(size=(63, 3)) * [0.3, 0.3, 1.0]
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    direction[:, 2] = np.abs(direction[:, 2])
    assert resolution.free_motions(0.02 * direction, direction) == 3  # turns about the centre
    curved = np.c_[points[:, :2], 30 * points[:, 0] ** 2 + 50 * points[:, 1] ** 2]
    gradient = np.c_[-60 * points[:, 0], -100 * points[:, 1], np.ones(63)]
    gradient /= np.linalg.norm(gradient, axis=1, keepdims=True)
    assert resolution.free_motions(curved, gradient) == 0  # an elliptic paraboloid fixes it


def test_equivalent_errors_follow_the_noise_and_the_count_of_points() -> None:
    loose = Resolution(sigma_m=0.05e-3, n_points=20).equivalent_error_m(0.04e-3)
    tight = Resolution(sigma_m=0.01e-3, n_points=200).equivalent_error_m(0.04e-3)
    assert loose > tight > 0.04e-3
    exact = Resolution(sigma_m=0.0, n_points=63, floor_m=1e-6).equivalent_error_m(0.0)
    assert exact == pytest.approx(1e-6)


def test_distinct_poses_drop_near_duplicates() -> None:
    R = np.repeat(np.eye(3)[None], 3, axis=0)
    t = np.array([[0.0, 0, 0], [0.1e-3, 0, 0], [5e-3, 0, 0]])
    kept = distinct_poses(R, t, np.array([2.0, 1.0, 3.0]), np.zeros(3), 3)
    assert kept.tolist() == [1, 2]


def test_a_hexagonal_prism_has_its_twelve_symmetries_and_a_blob_none() -> None:
    prism = trimesh.creation.cylinder(radius=0.03, height=0.02, sections=6)
    turns = MeshModel("prism", prism).symmetries
    angles = np.sort(np.degrees(rotation_angle(turns[:, :3, :3])))
    assert len(turns) == 11  # 5 turns about the axis, 6 flips
    assert np.allclose(angles[:5], [60, 60, 120, 120, 180], atol=0.5)
    assert len(MeshModel("blob", blob()).symmetries) == 0


def test_curves_on_a_sphere_report_their_pose_free() -> None:
    models = {"sphere": MeshModel("sphere", sphere()), "blob": MeshModel("blob", blob())}
    database = ModelDatabase(models).prepare()
    model = models["sphere"]
    curves = mesh_data_curves(
        model.mesh,
        100,
        normal=model.normals[100],
        noise_std_m=0.01e-3,
        rng=np.random.default_rng(0),
    ).curves
    result = database.recognize(curves)
    own = result.registrations["sphere"]
    assert result.name == "sphere" and own.free_motions == 3 and own.ambiguous
    assert own.error_m < 0.02e-3


def test_distinct_poses_keeps_the_best_of_each_group_in_order() -> None:
    # the greedy choice, whatever the ties: each kept pose is the least error among the
    # poses no better kept pose stands for (p within the radius, turned less than the
    # angle), and the kept ones stand for one another never
    from scipy.spatial.transform import Rotation

    from recognition.surfaces.registration.ambiguity import DISTINCT_ANGLE_RAD, DISTINCT_RADIUS_M

    rng = np.random.default_rng(3)
    for trial in range(40):
        k = int(rng.integers(1, 400))
        base = Rotation.random(4, random_state=trial).as_matrix()
        R = (
            base[rng.integers(0, 4, k)]
            @ Rotation.from_rotvec(rng.normal(size=(k, 3)) * 0.1).as_matrix()
        )
        t = rng.normal(size=(k, 3)) * 2e-3
        errors = np.round(rng.random(k), 1)  # many ties
        point = rng.normal(size=3) * 0.01
        location = R @ point + t
        same = (np.linalg.norm(location[:, None] - location[None], axis=-1) < DISTINCT_RADIUS_M) & (
            np.einsum("aij,bij->ab", R, R) > 1 + 2 * np.cos(DISTINCT_ANGLE_RAD)
        )
        n_keep = int(rng.integers(1, 30))
        kept = distinct_poses(R, t, errors, point, n_keep)
        alive = np.ones(k, bool)
        for i in kept:
            assert alive[i] and errors[i] == errors[alive].min()
            assert i == np.flatnonzero(alive & (errors == errors[i]))[0]  # ties: first given
            alive &= ~same[i]
        assert len(kept) == n_keep or not alive.any()


def test_distinct_poses_with_no_radius_or_angle_keeps_every_pose() -> None:
    R = np.tile(np.eye(3), (3, 1, 1))
    t = np.zeros((3, 3))
    for radius, angle in ((0.0, 0.1), (1.0, 0.0)):
        kept = distinct_poses(R, t, np.array([2.0, 1.0, 3.0]), np.zeros(3), 3, radius, angle)
        np.testing.assert_array_equal(kept, [1, 0, 2])
