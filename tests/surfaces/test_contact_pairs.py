"""Poses from two oriented contact points (point pair features)."""

import numpy as np
import pytest
from testing_meshes import blob

from recognition.rigid import pose_matrix, rotation_from_vector
from recognition.surfaces.distance import FieldStack
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.registration.contact_pairs import (
    N_KEPT,
    PAIR_SPACING_M,
    contact_costs,
    pair_features,
    pair_poses,
    pair_search,
)


@pytest.fixture(scope="module")
def model() -> MeshModel:
    return MeshModel("blob", blob())


def _truth(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return pose_matrix(rotation_from_vector(rng.normal(size=(1, 3)))[0], rng.normal(0, 0.05, 3))


def _oriented_pair(model: MeshModel, T: np.ndarray, i: int, j: int):
    """Vertices i and j with their normals, moved into a data frame by T^-1."""
    Ti = np.linalg.inv(T)
    place = lambda v: Ti[:3, :3] @ v + Ti[:3, 3]  # noqa: E731
    turn = lambda n: Ti[:3, :3] @ n  # noqa: E731
    return (
        place(model.vertices[i]),
        turn(model.normals[i]),
        place(model.vertices[j]),
        turn(model.normals[j]),
    )


def test_the_features_do_not_change_under_a_rigid_motion_and_tell_a_mirror_image():
    rng = np.random.default_rng(1)
    x1, x2 = rng.normal(size=(2, 3))
    n1, n2 = (v / np.linalg.norm(v) for v in rng.normal(size=(2, 3)))
    D, f, F = pair_features(x1[None], n1[None], x2[None], n2[None])
    R = rotation_from_vector(rng.normal(size=(1, 3)))[0]
    t = rng.normal(size=3)
    D2, f2, F2 = pair_features(
        (R @ x1 + t)[None], (R @ n1)[None], (R @ x2 + t)[None], (R @ n2)[None]
    )
    assert D2 == pytest.approx(D) and f2 == pytest.approx(f)
    assert F2[0] == pytest.approx(R @ F[0])  # the frame turns with the pair
    mirror = np.diag([1.0, 1.0, -1.0])
    _, fm, _ = pair_features(
        (mirror @ x1)[None], (mirror @ n1)[None], (mirror @ x2)[None], (mirror @ n2)[None]
    )
    assert fm[0, :3] == pytest.approx(f[0, :3]) and fm[0, 3] == pytest.approx(-f[0, 3])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_pair_of_surface_points_proposes_the_true_pose(model, seed):
    T = _truth(seed)
    rng = np.random.default_rng(seed)
    i = int(rng.integers(len(model.vertices)))
    far = np.linalg.norm(model.vertices - model.vertices[i], axis=1)
    j = int(rng.choice(np.flatnonzero((far > 0.015) & (far < 0.04))))
    p, n, c, m = _oriented_pair(model, T, i, j)
    R, t = pair_poses(model, p, n, c, m)
    assert len(R)
    # within about a sampling cell of the truth at both points, the turn a few degrees
    at_p = np.linalg.norm(R @ p + t - model.vertices[i], axis=1)
    at_c = np.linalg.norm(R @ c + t - model.vertices[j], axis=1)
    k = int(np.argmin(at_p + at_c))
    assert at_p[k] < 1.5 * PAIR_SPACING_M and at_c[k] < 1.5 * PAIR_SPACING_M
    cosine = (np.trace(R[k].T @ T[:3, :3]) - 1) / 2
    assert np.degrees(np.arccos(min(cosine, 1.0))) < 15.0


def test_no_pose_when_the_normal_at_p_points_along_the_pair(model):
    p, c = np.zeros(3), np.array([0.0, 0.0, 0.02])
    R, t = pair_poses(model, p, np.array([0.0, 0.0, 1.0]), c, np.array([1.0, 0.0, 0.0]))
    assert R.shape == (0, 3, 3) and t.shape == (0, 3)


def test_the_search_refines_pair_poses_onto_the_surface(model):
    # curves' points around vertex i and a touch at j: the search returns a pose that
    # puts them all on the surface, near the truth
    T = _truth(5)
    Ti = np.linalg.inv(T)
    i = 0
    near = np.linalg.norm(model.vertices - model.vertices[i], axis=1)
    patch = np.flatnonzero(near < 0.006)[::5]
    j = int(np.flatnonzero((near > 0.02) & (near < 0.03))[0])
    curve_points = model.vertices[patch] @ Ti[:3, :3].T + Ti[:3, 3]
    p, n, c, m = _oriented_pair(model, T, i, j)
    stack = FieldStack.of([model.distance_field])
    args = ([model], stack, np.array([0]), curve_points, p, n, c[None], m[None], 0.1e-3)
    found = pair_search(*args)
    again = pair_search(*args)
    assert found and len(found) == len(again)  # same arguments, same poses
    assert all(np.array_equal(a[1], b[1]) for a, b in zip(found, again, strict=True))
    name, pose, error = found[0]
    assert name == "blob" and error < 0.02e-3
    assert np.linalg.norm(pose[:3, :3] @ p + pose[:3, 3] - model.vertices[i]) < 0.5e-3
    # refining more of the scored poses keeps more distinct ones, at most as many as asked,
    # and the best of them fits at least as well (the first refined are the same)
    wide = pair_search(*args, refined=64, kept=64)
    assert len(found) == N_KEPT < len(wide) <= 64
    assert min(e for _, _, e in wide) <= error + 1e-12
    assert len(pair_search(*args, refined=64, kept=2)) == 2


def test_a_touch_that_met_nothing_costs_a_pose_that_puts_the_surface_across_it(model):
    T = _truth(3)
    Ti = np.linalg.inv(T)
    stack = FieldStack.of([model.distance_field])
    points = model.vertices[::997] @ Ti[:3, :3].T + Ti[:3, 3]  # on the surface at T
    R, t = T[None, :3, :3], T[None, :3, 3]
    threshold = 0.1e-3
    alone = contact_costs(stack, 0, points, [], R, t, threshold)
    assert alone[0] < 0.01 * threshold**2
    # a ray from outside straight through the body, and one that passes it by
    normal = Ti[:3, :3] @ model.normals[0]
    outside = Ti[:3, :3] @ (model.vertices[0] + 0.01 * model.normals[0]) + Ti[:3, 3]
    through = (outside, -normal, 0.02)
    past = (outside, normal, 0.02)
    crossed = contact_costs(stack, 0, points, [through], R, t, threshold)
    cleared = contact_costs(stack, 0, points, [past], R, t, threshold)
    # the crossing counts as one point a full threshold off, among len(points) + 1
    assert crossed[0] == pytest.approx((alone[0] * len(points) + threshold**2) / (len(points) + 1))
    assert cleared[0] == pytest.approx(alone[0] * len(points) / (len(points) + 1))
