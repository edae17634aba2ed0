"""Tests of the MJCF scenes and their assembly: compile, step without warnings, probe contact."""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest
from dm_control import mjcf
from numpy.typing import ArrayLike

from tactile_sim import scene
from tactile_sim.collision import convex_decomposition, load_solid, object_parts, solid_names
from tactile_sim.errors import InvalidMesh, SimulationError
from tactile_sim.kinematics import inverse_kinematics, probe_tip_pose
from tactile_sim.objects import load_object, object_names

SIMULATED_SECONDS = 1.0
CONTROL_NOISE = 0.01
"""Standard deviation of the control noise, as a fraction of each actuator's control range."""

SCENE_FILES = sorted(scene.SCENES_DIR.glob("*.xml"))


def box_mesh(size: ArrayLike, centre: ArrayLike = (0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of an axis-aligned box, outward-facing triangles, metres."""
    half = np.asarray(size, dtype=float) / 2.0
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    vertices = corners * half + np.asarray(centre, dtype=float)
    faces = np.array(
        [
            [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5],  # -x, +x
            [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],  # -y, +y
            [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],  # -z, +z
        ]
    )  # fmt: skip
    return vertices, faces


def assert_no_warnings(data: mujoco.MjData, where: str) -> None:
    counts = {
        name: data.warning[int(w)].number
        for name, w in mujoco.mjtWarning.__members__.items()
        if int(w) < len(data.warning) and data.warning[int(w)].number > 0
    }
    assert not counts, f"{where}: MuJoCo warnings {counts} at t = {data.time:.3f} s"
    for field in ("qpos", "qvel", "qacc"):
        assert np.isfinite(getattr(data, field)).all(), f"{where}: non-finite {field}"


def step_with_control_noise(model: mujoco.MjModel, data: mujoco.MjData, where: str) -> None:
    """Steps one simulated second with ctrl = rest pose + seeded noise (menagerie model_test).

    The rest pose holds each actuated joint at its initial position.
    """
    rng = np.random.default_rng(0)
    low, high = model.actuator_ctrlrange.T
    joint_qpos = data.qpos[model.jnt_qposadr[model.actuator_trnid[:, 0]]]
    rest = np.clip(joint_qpos, low, high)
    for _ in range(int(SIMULATED_SECONDS / model.opt.timestep)):
        data.ctrl[:] = np.clip(
            rest + CONTROL_NOISE * (high - low) * rng.standard_normal(model.nu), low, high
        )
        mujoco.mj_step(model, data)
        assert_no_warnings(data, where)


@pytest.mark.parametrize("path", SCENE_FILES, ids=lambda p: p.name)
def test_scene_file_compiles_and_steps_without_warnings(path: Path) -> None:
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    if model.njnt:
        data.qpos[:] = np.random.default_rng(1).uniform(-0.01, 0.01, model.nq) + model.qpos0
    step_with_control_noise(model, data, path.name)


@pytest.fixture(scope="module")
def box_physics() -> mjcf.Physics:
    """The assembled scene with a 60 x 60 x 40 mm box resting on the table at the mount."""
    return scene.load_scene([box_mesh((0.06, 0.06, 0.04), (0.0, 0.0, 0.02))])


def test_assembled_scene_with_object_steps_without_warnings(box_physics: mjcf.Physics) -> None:
    physics = box_physics
    model, data = physics.model.ptr, physics.data.ptr
    assert model.opt.timestep == pytest.approx(0.001)
    # Hover 5 mm above the box top, then add control noise around that pose.
    q = inverse_kinematics([0.4, 0.0, 0.045])
    scene.set_arm_joints(physics, q)
    rng = np.random.default_rng(0)
    low, high = model.actuator_ctrlrange.T
    for _ in range(int(SIMULATED_SECONDS / model.opt.timestep)):
        data.ctrl[:] = np.clip(
            q + CONTROL_NOISE * 0.05 * (high - low) * rng.standard_normal(4), low, high
        )
        scene.step(physics)
    assert_no_warnings(data, "scene with a box")
    assert scene.warning_counts(physics) == {}


def test_attached_object_pose_and_geoms(box_physics: mjcf.Physics) -> None:
    physics = box_physics
    mount = physics.named.data.site_xpos[scene.OBJECT_MOUNT_SITE]
    np.testing.assert_allclose(mount, [0.4, 0.0, 0.0])
    np.testing.assert_allclose(physics.named.data.xpos["object/object"], mount)
    model = physics.model
    collision = model.name2id("object/collision_0", "geom")
    assert model.geom_contype[collision] and model.geom_conaffinity[collision]
    # Without a visual mesh the collision parts are drawn (group 2) and still collide.
    assert model.geom_group[collision] == 2


def test_attach_object_places_visual_and_collision_geoms_at_the_pose() -> None:
    model = scene.scene_model()
    angle = 0.3
    quat = (math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2))
    body = scene.attach_object(
        model,
        "cube",
        [
            box_mesh((0.02, 0.02, 0.02), (0.0, 0.0, 0.01)),
            box_mesh((0.01, 0.01, 0.01), (0.0, 0.0, 0.025)),
        ],
        visual_mesh=box_mesh((0.02, 0.02, 0.03), (0.0, 0.0, 0.015)),
        position_in_mount=(0.05, -0.02, 0.0),
        quat_wxyz_in_mount=quat,
        maxhullvert=8,
    )
    physics = scene.build_physics(model)
    np.testing.assert_allclose(physics.bind(body).xpos, [0.45, -0.02, 0.0], atol=1e-12)
    np.testing.assert_allclose(physics.bind(body).xquat, quat, atol=1e-12)
    m = physics.model
    visual = m.name2id("cube/visual", "geom")
    assert m.geom_contype[visual] == 0 and m.geom_conaffinity[visual] == 0
    assert m.geom_group[visual] == 2
    for i in range(2):
        collision = m.name2id(f"cube/collision_{i}", "geom")
        assert m.geom_contype[collision] == 1 and m.geom_group[collision] == 3


def test_attach_object_rejects_bad_input() -> None:
    model = scene.scene_model()
    flat = (
        np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float) * 0.01,
        [[0, 1, 2], [1, 3, 2]],
    )
    with pytest.raises(InvalidMesh, match="collision part 1 is flat"):
        scene.attach_object(model, "a", [box_mesh((0.01, 0.01, 0.01)), flat])
    with pytest.raises(InvalidMesh, match="face indices"):
        scene.attach_object(model, "b", [(box_mesh((0.01, 0.01, 0.01))[0], [[0, 1, 8]])])
    with pytest.raises(InvalidMesh, match="at least one collision part"):
        scene.attach_object(model, "c", [])
    with pytest.raises(ValueError, match="object name"):
        scene.attach_object(model, "a/b", [box_mesh((0.01, 0.01, 0.01))])
    scene.attach_object(model, "d", [box_mesh((0.01, 0.01, 0.01))])
    with pytest.raises(ValueError, match="already holds"):
        scene.attach_object(model, "d", [box_mesh((0.01, 0.01, 0.01))])


def test_step_raises_on_instability() -> None:
    physics = scene.load_scene()
    physics.data.qvel[0] = np.inf
    with pytest.raises(SimulationError, match="mjWARN_BAD"):
        scene.step(physics)


def press(
    physics: mjcf.Physics,
    tip_start: ArrayLike,
    depth_m: float,
    speed_m_s: float = 0.005,
    hold_s: float = 0.3,
) -> np.ndarray:
    """Lowers the quill from a tip position by depth_m at speed_m_s, then holds; returns a log.

    The log has one row per step: touch (N), deflection_x, deflection_y (rad).
    """
    q = inverse_kinematics(tip_start)
    scene.set_arm_joints(physics, q)
    target = q.copy()
    dt = physics.model.opt.timestep
    n_move = round(depth_m / speed_m_s / dt)
    log = []
    for i in range(n_move + round(hold_s / dt)):
        target[2] = q[2] + depth_m * min(i + 1, n_move) / n_move
        physics.data.ctrl[:] = target
        scene.step(physics)
        log.append(
            [
                physics.named.data.sensordata[scene.TIP_TOUCH_SENSOR][0],
                *scene.probe_deflection(physics),
            ]
        )
    return np.array(log)


def test_probe_deflects_against_a_box_top_and_settles() -> None:
    # The box top slopes at 30 deg: pressing down makes the stylus tip slide and tilt the
    # stylus (a level top would only load the stylus along its axis).
    slope = math.radians(30.0)
    quat = (math.cos(slope / 2), math.sin(slope / 2), 0.0, 0.0)
    physics = scene.load_scene(
        [box_mesh((0.06, 0.06, 0.04), (0.0, 0.0, 0.02))], quat_wxyz_in_mount=quat
    )
    top_z = 0.04 / math.cos(slope)
    log = press(physics, [0.4, 0.0, top_z + 0.002], depth_m=0.005)
    touch, deflection = log[:, 0], log[:, 1:]
    assert touch[-1] > 0.05, "tip contact not sensed"
    assert math.degrees(np.abs(deflection[-1]).max()) > 1.0, "no measurable deflection"
    # Settled: the deflection moves by less than 0.01 deg over the last 100 ms.
    assert math.degrees(np.ptp(deflection[-100:], axis=0).max()) < 0.01
    # The contact is the tip's, and the tip sits on the slope within 20 um.
    tip_geom = physics.model.name2id(scene.PROBE_TIP_GEOM, "geom")
    contacts = physics.data.contact[: physics.data.ncon]
    assert any(tip_geom in (c.geom1, c.geom2) for c in contacts)
    assert all(-20e-6 < c.dist < 1e-6 for c in contacts)
    tip = physics.named.data.site_xpos[scene.PROBE_TIP_SITE]
    normal = np.array([0.0, -math.sin(slope), math.cos(slope)])
    height_above_top = normal @ (tip - np.array([0.4, 0.0, 0.0])) - 0.04 - 0.001
    assert abs(height_above_top) < 20e-6
    # The sensors and the kinematics agree on where the tip is.
    T_tip = probe_tip_pose(scene.arm_joints(physics), deflection=scene.probe_deflection(physics))
    np.testing.assert_allclose(T_tip[:3, 3], tip, atol=1e-9)


def test_released_stylus_returns_to_rest_within_100_ms() -> None:
    slope = math.radians(30.0)
    quat = (math.cos(slope / 2), math.sin(slope / 2), 0.0, 0.0)
    physics = scene.load_scene(
        [box_mesh((0.06, 0.06, 0.04), (0.0, 0.0, 0.02))], quat_wxyz_in_mount=quat
    )
    press(physics, [0.4, 0.0, 0.04 / math.cos(slope) + 0.002], depth_m=0.005, hold_s=0.1)
    assert np.abs(scene.probe_deflection(physics)).max() > math.radians(1.0)
    # Lift the probe 5 mm in one go: the stylus springs back.
    physics.data.ctrl[2] -= 0.005
    scene.step(physics, 100)
    assert physics.named.data.sensordata[scene.TIP_TOUCH_SENSOR][0] == 0.0
    assert math.degrees(np.abs(scene.probe_deflection(physics)).max()) < 0.05


@pytest.mark.slow
@pytest.mark.parametrize("name", [*object_names(), *solid_names()])
def test_object_scene_steps_one_second_with_control_noise_without_warnings(name: str) -> None:
    solid = name in solid_names()
    mesh = load_solid(name).mesh if solid else load_object(name).mesh
    if solid:
        parts = convex_decomposition(mesh, name=name, progress=False, convex=True)
    else:
        parts = object_parts(load_object(name), progress=False)
    physics = scene.load_scene(list(parts.parts), visual_mesh=mesh, name=name)
    model, data = physics.model.ptr, physics.data.ptr
    # Hover 3 mm above the object's top at the mount, then add seeded control noise.
    height = float(np.max(mesh.vertices[:, 2]))
    q = inverse_kinematics([0.4, 0.0, height + 0.003])
    scene.set_arm_joints(physics, q)
    rng = np.random.default_rng(0)
    low, high = model.actuator_ctrlrange.T
    for _ in range(int(SIMULATED_SECONDS / model.opt.timestep)):
        data.ctrl[:] = np.clip(
            q + CONTROL_NOISE * 0.05 * (high - low) * rng.standard_normal(model.nu), low, high
        )
        mujoco.mj_step(model, data)
    assert scene.warning_counts(physics) == {}, f"{name}: MuJoCo warned"
    for field in ("qpos", "qvel", "qacc"):
        assert np.isfinite(getattr(data, field)).all()
