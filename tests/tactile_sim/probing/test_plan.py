"""The plan: sampling planes, and p chosen or snapped onto the mesh."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tactile_sim.probing import ProbeScene, probe_object, sampling_planes


def test_sampling_planes_are_vertical_and_plane_angle_apart() -> None:
    planes = sampling_planes([0.4, 0.0, 0.05], 0.3, math.radians(60))
    assert len(planes) == 3
    for k, plane in enumerate(planes):
        np.testing.assert_allclose(plane.up_in_world, [0.0, 0.0, 1.0])
        assert plane.normal_in_world[2] == pytest.approx(0.0)
        yaw = math.atan2(plane.forward_in_world[1], plane.forward_in_world[0])
        assert yaw == pytest.approx(0.3 + k * math.radians(60))
        assert plane.distance([[0.4, 0.0, 0.05]])[0] == pytest.approx(0.0)


def test_given_point_is_snapped_to_the_model_and_probed(sphere_scene: ProbeScene) -> None:
    point = np.array([0.005, -0.004, 0.07])  # above the sphere, model frame
    session = probe_object("sphere", seed=1, n_points=5, point=point, probe_scene=sphere_scene)
    p = session.ground_truth.point_in_object
    assert np.linalg.norm(p - [0.0, 0.0, 0.033]) == pytest.approx(0.033, abs=10e-6)
    assert np.linalg.norm(session.curves.intersection - session.ground_truth.point_in_world) < (
        0.05e-3
    )


def test_point_on_the_underside_is_rejected(sphere_scene: ProbeScene) -> None:
    with pytest.raises(ValueError, match="upward-facing"):
        probe_object("sphere", seed=1, point=(0.0, 0.0, -0.01), probe_scene=sphere_scene)
