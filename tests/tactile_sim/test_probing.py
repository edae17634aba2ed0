"""Probing sessions: planning, the sweep controller, reproducibility and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from recognition.surfaces import DataCurves
from tactile_sim import probing
from tactile_sim.collision import load_solid
from tactile_sim.errors import SimulationError, UnknownObject, UnreachablePoint, WorkspaceLimit
from tactile_sim.probing import StopReason


def pose(x: float = 0.40, y: float = 0.0, yaw: float = 0.0) -> np.ndarray:
    """T_world_from_object: upright at (x, y) on the table, turned by ``yaw``."""
    T = np.eye(4)
    T[:2, :2] = [[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]
    T[:2, 3] = (x, y)
    return T


@pytest.fixture(scope="module")
def sphere_scene():
    return probing.build_probe_scene("sphere", pose(), progress=False)


def test_sampling_planes_are_vertical_and_plane_angle_apart():
    planes = probing.sampling_planes([0.4, 0.0, 0.05], 0.3, math.radians(60))
    assert len(planes) == 3
    for k, plane in enumerate(planes):
        np.testing.assert_allclose(plane.up_in_world, [0.0, 0.0, 1.0])
        assert plane.normal_in_world[2] == pytest.approx(0.0)
        yaw = math.atan2(plane.forward_in_world[1], plane.forward_in_world[0])
        assert yaw == pytest.approx(0.3 + k * math.radians(60))
        assert plane.distance([[0.4, 0.0, 0.05]])[0] == pytest.approx(0.0)


def test_random_pose_is_upright_and_near_the_mount():
    rng = np.random.default_rng(4)
    for _ in range(20):
        T = probing.random_pose(rng)
        np.testing.assert_allclose(T[:3, 2], [0.0, 0.0, 1.0], atol=1e-12)
        assert T[2, 3] == 0.0
        assert np.hypot(T[0, 3] - 0.40, T[1, 3]) <= 0.02 + 1e-12


def test_random_pose_turns_by_the_drawn_yaw_exactly():
    for seed in range(50):
        T = probing.random_pose(np.random.default_rng(seed))
        yaw = np.random.default_rng(seed).uniform(-math.pi, math.pi)
        c, s = math.cos(yaw), math.sin(yaw)
        assert np.array_equal(T[:3, :3], [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_session_on_the_sphere(sphere_scene):
    session = probing.probe_object(
        "sphere", seed=11, n_points=9, probe_scene=sphere_scene, first_plane_yaw_rad=0.2
    )
    assert isinstance(session.curves, DataCurves)
    assert [len(c) for c in session.curves.curves] == [9, 9, 9]
    assert not session.truncated and session.messages == ()
    np.testing.assert_allclose(session.curves.approach, [0.0, 0.0, -1.0])
    truth = session.ground_truth
    # The three curves meet at the planned p (the first sweep re-aims its approach).
    assert np.linalg.norm(session.curves.intersection - truth.point_in_world) < 0.05e-3
    centre = truth.T_world_from_object[:3, 3] + [0.0, 0.0, 0.033]
    for sweep in session.sweeps:
        assert sweep.p_index == 4
        # Points on the sphere (icosphere facets lie up to 9.4 um inside it).
        radial = np.linalg.norm(sweep.points_in_world - centre, axis=1) - 0.033
        assert np.all(np.abs(radial) < 20e-6)
        # Neighbouring points one spacing apart, near the sampling plane.
        steps = np.linalg.norm(np.diff(sweep.points_in_world, axis=0), axis=1)
        np.testing.assert_allclose(steps, 1.2e-3, atol=0.15e-3)
        assert np.all(np.abs(sweep.plane.distance(sweep.points_in_world)) < 0.25e-3)
        # Ground truth is kept apart and agrees.
        error = np.linalg.norm(sweep.points_in_world - sweep.true_contact_points_in_world, axis=1)
        # (friction leaves up to tip radius x sin(friction angle) = 0.1 mm along the
        # surface where the tip barely slid).
        assert error.mean() < 0.04e-3 and error.max() < 0.15e-3


def test_same_seed_same_session_other_seed_other_session(sphere_scene):
    kwargs = {"n_points": 5, "probe_scene": sphere_scene}
    first = probing.probe_object("sphere", seed=5, **kwargs)
    again = probing.probe_object("sphere", seed=5, **kwargs)
    other = probing.probe_object("sphere", seed=6, **kwargs)
    for a, b in zip(first.curves.curves, again.curves.curves, strict=True):
        np.testing.assert_array_equal(a, b)
    assert not np.allclose(first.curves.points, other.curves.points)


def test_given_point_is_snapped_to_the_model_and_probed(sphere_scene):
    point = np.array([0.005, -0.004, 0.07])  # above the sphere, model frame
    session = probing.probe_object(
        "sphere", seed=1, n_points=5, point=point, probe_scene=sphere_scene
    )
    p = session.ground_truth.point_in_object
    assert np.linalg.norm(p - [0.0, 0.0, 0.033]) == pytest.approx(0.033, abs=10e-6)
    assert np.linalg.norm(session.curves.intersection - session.ground_truth.point_in_world) < (
        0.05e-3
    )


def test_point_on_the_underside_is_rejected(sphere_scene):
    with pytest.raises(ValueError, match="upward-facing"):
        probing.probe_object("sphere", seed=1, point=(0.0, 0.0, -0.01), probe_scene=sphere_scene)


def test_unknown_object_lists_catalog_and_solids():
    with pytest.raises(UnknownObject, match=r"known objects: pear.*elephant.*sphere"):
        probing.probe_object("teapot", seed=0)


def test_unreachable_point_names_the_limit():
    far = pose(x=0.72)  # beyond the arm's reach of 0.60 m
    with pytest.raises(UnreachablePoint, match="radius too large") as error:
        probing.probe_object("sphere", seed=0, T_world_from_object=far, progress=False)
    assert error.value.limit is WorkspaceLimit.RADIUS_TOO_LARGE


def test_sweep_over_an_edge_is_truncated_and_reported():
    # A 40 mm cube; p 3 mm from its +x edge, the first plane along x: the + side of that
    # sweep runs off the top after about two points and the - side makes up for it.
    cube = trimesh.creation.box(extents=(0.04, 0.04, 0.04))
    cube.apply_translation((0.0, 0.0, 0.02))
    session = probing.probe_object(
        cube,
        seed=2,
        n_points=9,
        point=(0.017, 0.0, 0.04),
        first_plane_yaw_rad=0.0,
        T_world_from_object=pose(),
        progress=False,
    )
    sweep = session.sweeps[0]
    assert sweep.truncated and session.truncated
    plus, minus = sweep.sides
    assert plus.stop in (StopReason.LOST_CONTACT, StopReason.TOO_STEEP)
    assert plus.acquired < plus.requested
    assert minus.stop is StopReason.COMPLETE and minus.requested > 4
    assert sweep.n_points == 9 and sweep.p_index == 9 - 1 - plus.acquired
    assert any(
        "sweep 0" in m and ("lost contact" in m or "too steep" in m) for m in session.messages
    )
    # Every sensed point is on the cube (on its top, or on the edge the tip rolled onto).
    q = np.abs(sweep.points_in_world - [0.40, 0.0, 0.02]) - 0.02
    distance = np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0)
    # Friction tilts the sensed normal at an edge, where neither correction applies.
    assert np.all(np.abs(distance[:-2]) < 10e-6) and np.all(np.abs(distance) < 0.15e-3)


def test_outline_of_the_planar_ellipse():
    trace = probing.trace_contour(
        "planar_ellipse", seed=0, n_points=12, start_angle_rad=0.4, T_world_from_object=pose()
    )
    points = trace.points_in_object
    assert len(points) == 12 and not trace.sweep.truncated
    # On the ellipse x^2/a^2 + y^2/b^2 = 1 (a = 25 mm, b = 17.5 mm), in the plane.
    a, b = load_solid("planar_ellipse").parameters["semi_axes_m"]
    level = (points[:, 0] / a) ** 2 + (points[:, 1] / b) ** 2
    # The level-set value changes by about 2 d / b per distance d off the curve.
    np.testing.assert_allclose(level, 1.0, atol=2 * 20e-6 / b)
    # Heights scatter along the wall with the axial force noise (it tilts the sensed
    # normal, which moves the point along the surface, not off it).
    np.testing.assert_allclose(points[:, 2], points[0, 2], atol=0.4e-3)
    # Counter-clockwise seen from above.
    angles = np.unwrap(np.arctan2(points[:, 1] / b, points[:, 0] / a))
    assert np.all(np.diff(angles) > 0)


def test_instability_raises_simulation_error(sphere_scene):
    broken = probing.build_probe_scene("sphere", pose(), progress=False)
    broken.physics.model.opt.timestep = 0.5  # far beyond the servos' stability limit
    with pytest.raises(SimulationError):
        probing.probe_object("sphere", seed=0, n_points=5, probe_scene=broken)


def test_bad_parameters_are_rejected(sphere_scene):
    with pytest.raises(ValueError, match="n_points"):
        probing.probe_object("sphere", seed=0, n_points=3, probe_scene=sphere_scene)
    with pytest.raises(ValueError, match="plane_angle_deg"):
        probing.probe_object("sphere", seed=0, plane_angle_deg=0.0, probe_scene=sphere_scene)
    with pytest.raises(ValueError, match="rigid"):
        probing.build_probe_scene("sphere", np.diag([2.0, 1.0, 1.0, 1.0]), progress=False)


def test_sweeps_that_keep_too_few_points_raise_sweep_truncated():
    # A rib 3 mm wide: every plane through its top crosses it in a few millimetres.
    rib = trimesh.creation.box(extents=(0.003, 0.04, 0.02))
    rib.apply_translation((0.0, 0.0, 0.01))
    with pytest.raises(probing.SweepTruncated, match=r"fewer than 5 points.*sweep 0"):
        probing.probe_object(
            rib,
            seed=0,
            n_points=9,
            point=(0.0, 0.0, 0.02),
            first_plane_yaw_rad=0.0,
            T_world_from_object=pose(),
            progress=False,
        )
