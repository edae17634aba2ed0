"""Probing sessions: the sweep controller on a sphere and a cube, reproducibility, bad input."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from recognition import DataCurves, NoReading, TouchPlan
from recognition.rigid import pose_matrix
from tactile_sim.errors import (
    SimulationError,
    SweepTruncated,
    UnreachablePoint,
    UnusableCurves,
    WorkspaceLimit,
)
from tactile_sim.probing import (
    ProbeScene,
    ProbeSession,
    StopReason,
    build_probe_scene,
    probe_object,
)
from tactile_sim.probing.placement import MOUNT_IN_WORLD
from tactile_sim.probing.touches import RobotToucher, shaft_reading

AT_MOUNT = pose_matrix(np.eye(3), MOUNT_IN_WORLD)
"""T_world_from_object: upright on the object mount, axes parallel to the world's."""


def test_session_on_the_sphere(sphere_scene: ProbeScene) -> None:
    session = probe_object(
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
        # MuJoCo's contacts lie on the mesh where the tip touched it (the tip's contact
        # box is tangent to the mesh there), and next to the mesh points nearest the tips.
        touched = sweep.true_contact_points_in_world
        _, off_mesh = sphere_scene.closest_points_in_world(touched)
        assert off_mesh.max() < 2e-6
        gap = np.linalg.norm(touched - sweep.mesh_points_in_world, axis=1)
        assert gap.max() < 20e-6
        # The sensed normals (the joystick's deflection: a few degrees off where the
        # sweep sets off or turns) travel with the curves.
        outward = (sweep.points_in_world - centre) / 0.033
        off = np.degrees(np.arccos(np.einsum("ij,ij->i", sweep.normals_in_world, outward)))
        assert np.median(off) < 1.5 and off.max() < 8.0
    for curve_normals, sweep in zip(session.curves.normals, session.sweeps, strict=True):
        np.testing.assert_allclose(curve_normals, sweep.normals_in_world, atol=1e-12)


def test_same_seed_same_session_other_seed_other_session(sphere_scene: ProbeScene) -> None:
    kwargs = {"n_points": 5, "probe_scene": sphere_scene}
    first = probe_object("sphere", seed=5, **kwargs)
    again = probe_object("sphere", seed=5, **kwargs)
    other = probe_object("sphere", seed=6, **kwargs)
    for a, b in zip(first.curves.curves, again.curves.curves, strict=True):
        np.testing.assert_array_equal(a, b)
    assert not np.allclose(first.curves.points, other.curves.points)


def test_unreachable_point_names_the_limit() -> None:
    far = pose_matrix(np.eye(3), (0.72, 0.0, 0.0))  # beyond the arm's reach of 0.60 m
    with pytest.raises(UnreachablePoint, match="radius too large") as error:
        probe_object("sphere", seed=0, T_world_from_object=far, progress=False)
    assert error.value.limit is WorkspaceLimit.RADIUS_TOO_LARGE


def test_sweep_over_an_edge_is_truncated_and_reported() -> None:
    # A 40 mm cube; p 3 mm from its +x edge, the first plane along x: the + side of that
    # sweep runs off the top after about two points and the - side makes up for it.
    cube = trimesh.creation.box(extents=(0.04, 0.04, 0.04))
    cube.apply_translation((0.0, 0.0, 0.02))
    session = probe_object(
        cube,
        seed=2,
        n_points=9,
        point=(0.017, 0.0, 0.04),
        first_plane_yaw_rad=0.0,
        T_world_from_object=AT_MOUNT,
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


def test_instability_raises_simulation_error(sphere_scene: ProbeScene) -> None:
    broken = build_probe_scene("sphere", AT_MOUNT, progress=False)
    broken.physics.model.opt.timestep = 0.5  # far beyond the servos' stability limit
    with pytest.raises(SimulationError):
        probe_object("sphere", seed=0, n_points=5, probe_scene=broken)


def test_bad_parameters_are_rejected(sphere_scene: ProbeScene) -> None:
    with pytest.raises(ValueError, match="n_points"):
        probe_object("sphere", seed=0, n_points=3, probe_scene=sphere_scene)
    with pytest.raises(ValueError, match="plane_angle_deg"):
        probe_object("sphere", seed=0, plane_angle_deg=0.0, probe_scene=sphere_scene)
    with pytest.raises(ValueError, match="rigid"):
        build_probe_scene("sphere", np.diag([2.0, 1.0, 1.0, 1.0]), progress=False)


def test_sweeps_that_keep_too_few_points_raise_sweep_truncated() -> None:
    # A rib 3 mm wide: every plane through its top crosses it in a few millimetres.
    rib = trimesh.creation.box(extents=(0.003, 0.04, 0.02))
    rib.apply_translation((0.0, 0.0, 0.01))
    with pytest.raises(SweepTruncated, match=r"fewer than 5 points.*sweep 0"):
        probe_object(
            rib,
            seed=0,
            n_points=9,
            point=(0.0, 0.0, 0.02),
            first_plane_yaw_rad=0.0,
            T_world_from_object=AT_MOUNT,
            progress=False,
        )


def test_curves_recognition_cannot_use_are_replanned_or_named() -> None:
    # At 0.05 mm spacing on the sphere, here the sensed curves 0 and 2 run parallel at p:
    # an automatic p is planned again; a given one is refused, saying why.
    seed, settings = 1080427897, {"n_points": 41, "spacing_m": 0.05e-3, "progress": False}
    session = probe_object("sphere", seed=seed, **settings)
    assert isinstance(session.curves, DataCurves)
    p = [0.0023077185884982643, -0.016780459432061995, 0.0613177107253435]
    with pytest.raises(UnusableCurves, match="parallel tangents"):
        probe_object("sphere", seed=seed, point=p, **settings)


def _sphere_session(sphere_scene: ProbeScene) -> tuple[ProbeSession, np.ndarray]:
    """A short session on the sphere (radius 33 mm) and the sphere's centre, world frame."""
    session = probe_object(
        "sphere", seed=11, n_points=9, probe_scene=sphere_scene, first_plane_yaw_rad=0.2
    )
    return session, session.ground_truth.T_world_from_object[:3, 3] + [0.0, 0.0, 0.033]


def test_a_robot_touch_off_the_surface_normal_reports_a_point_on_the_surface_and_its_normal(
    sphere_scene: ProbeScene,
) -> None:
    session, centre = _sphere_session(sphere_scene)
    outward = np.array([np.sin(0.5), 0.0, np.cos(0.5)])  # 29 degrees from the top
    point = centre + 0.033 * outward
    tilt = 0.21  # the approach runs 12 degrees off the inward normal
    direction = -np.array([np.sin(0.5 + tilt), 0.0, np.cos(0.5 + tilt)])
    plan = TouchPlan(point, direction, point - 4e-3 * direction, 10e-3, 1.0, np.zeros(1))
    contact = RobotToucher(session)(plan)
    assert contact is not None and contact.normal is not None
    _, off_mesh = sphere_scene.closest_points_in_world(contact.point[None])
    # a tip radius ahead along the approach would lie r (1 - cos 12 deg) = 22 um off
    assert off_mesh[0] < 5e-6
    # the sphere's normal there, not the approach's 12 degrees off
    radial = (contact.point - centre) / np.linalg.norm(contact.point - centre)
    assert np.degrees(np.arccos(np.clip(contact.normal @ radial, -1.0, 1.0))) < 2.0


def test_a_touch_under_an_overhang_meets_the_shaft_first_and_gives_no_reading(
    sphere_scene: ProbeScene,
) -> None:
    session, centre = _sphere_session(sphere_scene)
    below = np.radians(110.0)  # 20 degrees below the equator: the sphere overhangs the tip
    outward = np.array([np.sin(below), 0.0, np.cos(below)])
    point = centre + 0.033 * outward
    plan = TouchPlan(point, -outward, point + 4e-3 * outward, 10e-3, 1.0, np.zeros(1))
    toucher = RobotToucher(session)
    reading = toucher(plan)
    assert isinstance(reading, NoReading) and "shaft" in reading.reason
    assert toucher.made[-1][2] is None  # MuJoCo: the tip touched nothing


@pytest.mark.parametrize(("tilt_deg", "shaft"), [(0, False), (60, False), (78, False), (85, True)])
def test_a_reading_is_the_shafts_when_its_force_runs_across_the_stylus(tilt_deg, shaft) -> None:
    tilt = np.radians(tilt_deg)
    assert (shaft_reading(np.array([np.sin(tilt), 0.0, np.cos(tilt)])) is not None) is shaft
