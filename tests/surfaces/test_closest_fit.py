"""Poses refined on a mesh's exact closest points."""

import numpy as np
from testing_meshes import blob

from recognition.rigid import pose_matrix, posed, rotation_from_vector
from recognition.surfaces.closest_fit import refine_poses
from recognition.surfaces.mesh_model import MeshModel


def test_refined_poses_come_with_what_the_surface_says_at_them():
    # points on the surface at a known pose, started from poses a little off: the
    # refinement returns, at its results, the same signed distances, closest points and
    # faces as a query there, and brings the poses back onto the surface
    model = MeshModel("blob", blob())
    rng = np.random.default_rng(3)
    truth = pose_matrix(rotation_from_vector(rng.normal(0, 0.3, (1, 3)))[0], rng.normal(0, 0.01, 3))
    into_data = np.linalg.inv(truth)
    points = model.vertices[::199] @ into_data[:3, :3].T + into_data[:3, 3]
    R0 = rotation_from_vector(rng.normal(0, 0.01, (4, 3))) @ truth[:3, :3]
    t0 = truth[:3, 3] + rng.normal(0, 0.3e-3, (4, 3))
    R, t, signed, closest, face = refine_poses(model.distance, points, R0, t0, 20, 1e-8, 2e-3)
    queried, at, on = model.distance.signed_closest(posed(R, t, points).reshape(-1, 3))
    assert np.array_equal(signed, queried.reshape(signed.shape))
    assert np.array_equal(closest, at.reshape(closest.shape))
    assert np.array_equal(face, on.reshape(face.shape))
    assert np.any(signed < 0) and np.any(signed > 0)  # the sign is the side of the surface
    assert np.abs(signed).max() < 0.02e-3
