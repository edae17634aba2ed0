"""Tests of the Cobra 600 kinematics against MuJoCo and against themselves."""

from __future__ import annotations

import math

import numpy as np
import pytest
from dm_control import mjcf

from recognition.rigid import rotation_about
from tactile_sim import scene
from tactile_sim.errors import SimulationError, UnreachablePoint, WorkspaceLimit
from tactile_sim.kinematics import (
    COBRA600,
    Cobra600Geometry,
    ElbowBranch,
    flange_pose,
    inverse_kinematics,
    joint_limit_violation,
    probe_tip_pose,
    probe_tip_position,
    reach_radii,
)

POSITION_ATOL_M = 1e-9
ROTATION_ATOL = 1e-9


def random_joints(
    rng: np.random.Generator, n: int, robot: Cobra600Geometry = COBRA600
) -> np.ndarray:
    """(n, 4) joint vectors drawn uniformly within the joint limits."""
    lim = robot.limits
    lows = [lim.shoulder_rad[0], lim.elbow_rad[0], lim.quill_m[0], lim.roll_rad[0]]
    highs = [lim.shoulder_rad[1], lim.elbow_rad[1], lim.quill_m[1], lim.roll_rad[1]]
    return rng.uniform(lows, highs, size=(n, 4))


def tool_yaw(T_world_from_flange: np.ndarray) -> float:
    """Yaw of the flange x axis about the world z axis, radians."""
    return math.atan2(T_world_from_flange[1, 0], T_world_from_flange[0, 0])


@pytest.fixture(scope="module")
def physics() -> mjcf.Physics:
    return scene.load_scene()


def test_joint_limits_match_the_model(physics: mjcf.Physics) -> None:
    lim = COBRA600.limits
    expected = [lim.shoulder_rad, lim.elbow_rad, lim.quill_m, lim.roll_rad]
    for joint, (lo, hi) in zip(scene.ARM_JOINTS, expected, strict=True):
        np.testing.assert_allclose(physics.named.model.jnt_range[joint], [lo, hi], atol=1e-4)
        np.testing.assert_allclose(
            physics.named.model.actuator_ctrlrange[joint], [lo, hi], atol=1e-4
        )


def test_forward_kinematics_matches_mujoco_sites(physics: mjcf.Physics) -> None:
    rng = np.random.default_rng(0)
    joints = random_joints(rng, 50)
    deflections = rng.uniform(-0.3, 0.3, size=(50, 2))
    T_flange_expected = flange_pose(joints)
    T_tip_expected = probe_tip_pose(joints, deflection=deflections)
    for q, deflection, T_flange, T_tip in zip(
        joints, deflections, T_flange_expected, T_tip_expected, strict=True
    ):
        joint_names = scene.ARM_JOINTS + scene.DEFLECTION_JOINTS
        for joint, value in zip(joint_names, [*q, *deflection], strict=True):
            physics.named.data.qpos[joint] = value
        physics.forward()
        np.testing.assert_allclose(
            physics.named.data.site_xpos[scene.FLANGE_SITE], T_flange[:3, 3], atol=POSITION_ATOL_M
        )
        np.testing.assert_allclose(
            physics.named.data.site_xmat[scene.FLANGE_SITE].reshape(3, 3),
            T_flange[:3, :3],
            atol=ROTATION_ATOL,
        )
        np.testing.assert_allclose(
            physics.named.data.site_xpos[scene.PROBE_TIP_SITE], T_tip[:3, 3], atol=POSITION_ATOL_M
        )
        np.testing.assert_allclose(
            physics.named.data.site_xmat[scene.PROBE_TIP_SITE].reshape(3, 3),
            T_tip[:3, :3],
            atol=ROTATION_ATOL,
        )


def test_forward_kinematics_is_vectorised() -> None:
    rng = np.random.default_rng(1)
    joints = random_joints(rng, 7).reshape(7, 1, 4)
    T = probe_tip_pose(joints, deflection=rng.uniform(-0.2, 0.2, size=(7, 1, 2)))
    assert T.shape == (7, 1, 4, 4)
    np.testing.assert_allclose(
        T[..., :3, :3] @ np.swapaxes(T[..., :3, :3], -1, -2),
        np.broadcast_to(np.eye(3), (7, 1, 3, 3)),
        atol=1e-12,
    )


@pytest.mark.parametrize(
    "robot",
    [COBRA600, Cobra600Geometry(base_position_in_world=(0.1, -0.2, 0.05), base_yaw_rad=0.7)],
    ids=["scene", "moved_base"],
)
def test_inverse_kinematics_round_trip_on_both_branches(robot: Cobra600Geometry) -> None:
    rng = np.random.default_rng(2)
    solved = {ElbowBranch.RIGHTY: 0, ElbowBranch.LEFTY: 0}
    for q in random_joints(rng, 200, robot):
        target = probe_tip_position(q, robot)
        yaw = tool_yaw(flange_pose(q, robot))
        own = ElbowBranch.RIGHTY if q[1] >= 0 else ElbowBranch.LEFTY
        for branch in ElbowBranch:
            try:
                q_ik = inverse_kinematics(target, yaw, robot, branch=branch)
            except UnreachablePoint as error:
                assert branch is not own, f"own branch of {q} failed: {error}"
                assert error.limit is WorkspaceLimit.SHOULDER
                continue
            solved[branch] += 1
            assert (q_ik[1] >= 0) == (branch is ElbowBranch.RIGHTY)
            assert joint_limit_violation(q_ik, robot) is None
            np.testing.assert_allclose(probe_tip_position(q_ik, robot), target, atol=1e-9)
            assert math.isclose(
                math.remainder(tool_yaw(flange_pose(q_ik, robot)) - yaw, 2 * math.pi),
                0.0,
                abs_tol=1e-9,
            )
            if branch is own:
                np.testing.assert_allclose(q_ik[:3], q[:3], atol=1e-9)
        q_near = inverse_kinematics(target, yaw, robot, joints_reference=q)
        np.testing.assert_allclose(q_near, q, atol=1e-9)
    assert min(solved.values()) > 50


def test_inverse_kinematics_prefers_righty_without_reference() -> None:
    q = inverse_kinematics([0.4, 0.0, 0.1])
    assert q[1] > 0
    q = inverse_kinematics([0.4, 0.0, 0.1], joints_reference=[0.5, -1.0, 0.1, 0.0])
    assert q[1] < 0


@pytest.mark.parametrize(
    ("point", "limit", "words"),
    [
        ((0.65, 0.0, 0.1), WorkspaceLimit.RADIUS_TOO_LARGE, "radius too large"),
        ((0.05, 0.1, 0.1), WorkspaceLimit.RADIUS_TOO_SMALL, "radius too small"),
        ((0.4, 0.0, 0.25), WorkspaceLimit.QUILL, "quill stroke"),
        ((0.4, 0.0, -0.01), WorkspaceLimit.QUILL, "quill stroke"),
        ((-0.4, 0.0, 0.1), WorkspaceLimit.SHOULDER, "shoulder limit"),
    ],
    ids=["far", "near", "high", "low", "behind"],
)
def test_unreachable_points_name_the_limit(
    point: tuple[float, float, float], limit: WorkspaceLimit, words: str
) -> None:
    with pytest.raises(UnreachablePoint, match=words) as raised:
        inverse_kinematics(point)
    assert raised.value.limit is limit
    assert isinstance(raised.value, SimulationError)
    assert isinstance(raised.value, ValueError)


def test_unreachable_branch_names_branch_and_joint() -> None:
    # 74 degrees left of the x axis, 0.35 m out: the lefty branch needs the shoulder at 122 deg.
    point = 0.35 * np.array([math.cos(1.3), math.sin(1.3), 0.0]) + [0.0, 0.0, 0.1]
    inverse_kinematics(point, branch=ElbowBranch.RIGHTY)
    with pytest.raises(UnreachablePoint, match=r"lefty elbow branch needs shoulder = .* deg"):
        inverse_kinematics(point, branch=ElbowBranch.LEFTY)


def test_reach_radii_follow_the_elbow_limit() -> None:
    r_min, r_max = reach_radii()
    assert r_max == pytest.approx(0.6)
    expected = math.sqrt(0.325**2 + 0.275**2 + 2 * 0.325 * 0.275 * math.cos(math.radians(150)))
    assert r_min == pytest.approx(expected)
    q = inverse_kinematics([r_min + 1e-6, 0.0, 0.1])
    assert abs(q[1]) == pytest.approx(math.radians(150), abs=1e-3)


def test_joint_limit_violation_names_each_joint() -> None:
    assert joint_limit_violation([0.0, 0.0, 0.1, 0.0]) is None
    cases = [
        ([2.0, 0.0, 0.1, 0.0], WorkspaceLimit.SHOULDER, "shoulder limit"),
        ([0.0, 2.7, 0.1, 0.0], WorkspaceLimit.ELBOW, "elbow limit"),
        ([0.0, 0.0, 0.25, 0.0], WorkspaceLimit.QUILL, "quill limit"),
        ([0.0, 0.0, 0.1, 7.0], WorkspaceLimit.ROLL, "roll limit"),
    ]
    for joints, limit, words in cases:
        error = joint_limit_violation(joints)
        assert error is not None and error.limit is limit and words in str(error)


def test_bad_input_shapes_raise_value_error() -> None:
    with pytest.raises(ValueError, match="shape"):
        flange_pose([0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="tip_position_in_world"):
        inverse_kinematics([0.4, 0.0])
    with pytest.raises(ValueError, match="deflection"):
        probe_tip_pose([0.0, 0.0, 0.0, 0.0], deflection=[0.1])


def test_rotations_are_bit_identical_to_the_explicit_matrices() -> None:
    rng = np.random.default_rng(3)
    angles = rng.uniform(-7.0, 7.0, 2000)
    c, s, zero, one = np.cos(angles), np.sin(angles), np.zeros(2000), np.ones(2000)
    explicit = {
        0: [[one, zero, zero], [zero, c, -s], [zero, s, c]],
        1: [[c, zero, s], [zero, one, zero], [-s, zero, c]],
        2: [[c, -s, zero], [s, c, zero], [zero, zero, one]],
    }
    for axis, rows in explicit.items():
        assert np.array_equal(rotation_about(axis, angles), np.moveaxis(np.array(rows), -1, 0))
    # The flange: a turn by the yaw about z, then half a turn about x.
    joints = np.column_stack([angles, rng.uniform(-2.5, 2.5, 2000), np.zeros(2000), zero])
    yaw = joints[:, 0] + joints[:, 1]
    cy, sy = np.cos(yaw), np.sin(yaw)
    flange = np.moveaxis(np.array([[cy, sy, zero], [sy, -cy, zero], [zero, zero, -one]]), -1, 0)
    assert np.array_equal(flange_pose(joints)[:, :3, :3], flange)
