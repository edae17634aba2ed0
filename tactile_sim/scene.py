"""The probing scene (robot, joystick probe, table, one object), built with dm_control.mjcf."""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tactile_sim.errors import InvalidMesh, SimulationError, SimulationUnstable

# dm_control picks its OpenGL backend at import; without a display the default (GLFW) warns.
# EGL renders headless here; an explicit MUJOCO_GL from the user always wins.
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco
from dm_control import mjcf
from dm_control import mujoco as dm_mujoco

__all__ = [
    "ARM_JOINTS",
    "BODY_CONTACT",
    "DEFLECTION_JOINTS",
    "FLANGE_SITE",
    "OBJECT_MOUNT_SITE",
    "PROBE_PATH",
    "PROBE_TIP_GEOM",
    "PROBE_TIP_SITE",
    "ROBOT_PATH",
    "SCENES_DIR",
    "SCENE_PATH",
    "TIP_CONTACT",
    "TIP_CONTACT_BODY",
    "TIP_FORCE_SENSOR",
    "TIP_TOUCH_SENSOR",
    "MeshLike",
    "SimulationUnstable",
    "add_tip_contact",
    "arm_joints",
    "attach_object",
    "build_physics",
    "load_scene",
    "physics_of",
    "probe_deflection",
    "raise_on_warnings",
    "scene_model",
    "set_arm_joints",
    "step",
    "warning_counts",
]

SCENES_DIR = Path(__file__).resolve().parent.parent / "scenes"
SCENE_PATH = SCENES_DIR / "scene.xml"
ROBOT_PATH = SCENES_DIR / "cobra600.xml"
PROBE_PATH = SCENES_DIR / "joystick_probe.xml"

_PROBE = "joystick_probe"
FLANGE_SITE = "flange"
OBJECT_MOUNT_SITE = "object_mount"
ARM_JOINTS = ("shoulder", "elbow", "quill", "roll")
DEFLECTION_JOINTS = (f"{_PROBE}/deflection_x", f"{_PROBE}/deflection_y")
PROBE_TIP_SITE = f"{_PROBE}/probe_tip"
PROBE_TIP_GEOM = f"{_PROBE}/tip"
TIP_TOUCH_SENSOR = f"{_PROBE}/tip_touch"
TIP_FORCE_SENSOR = f"{_PROBE}/tip_force"
TIP_CONTACT_BODY = "tip_contact"
"""The mocap body whose box stands for the object under the tip (:func:`add_tip_contact`)."""

BODY_CONTACT = 1
"""Contype/conaffinity bit of the probe's housing and shaft, the table, the object's parts."""
TIP_CONTACT = 2
"""Contype/conaffinity bit of the probe's tip, the table and the tip's contact box."""
TIP_CONTACT_HALF_SIZE_M = (3e-3, 3e-3, 1e-3)
"""Half sizes of the tip's contact box: its top face reaches 3 mm around the contact."""

_NAME_PATTERN = re.compile(r"^[A-Za-z][A-Za-z0-9_\-]*$")
_FLAT_PART_TOLERANCE_M = 1e-7
"""A collision part thinner than this in every direction is flat: MuJoCo cannot hull it."""


class _HasVerticesFaces(Protocol):
    """Anything with vertex and face arrays, e.g. ``trimesh.Trimesh``."""

    @property
    def vertices(self) -> ArrayLike: ...

    @property
    def faces(self) -> ArrayLike: ...


MeshLike = _HasVerticesFaces | tuple[ArrayLike, ArrayLike]
"""A triangle mesh: an object with ``vertices`` (n, 3) metres and ``faces`` (m, 3) indices,
or a ``(vertices, faces)`` pair."""


def scene_model() -> mjcf.RootElement:
    """Returns the probing scene (scene.xml, with the joystick probe on the robot's flange)."""
    model = mjcf.from_path(str(SCENE_PATH))
    probe = mjcf.from_path(str(PROBE_PATH))
    flange = model.find("site", FLANGE_SITE)
    if flange is None:
        raise SimulationError(f"{SCENE_PATH} has no site {FLANGE_SITE!r} to attach the probe to")
    flange.attach(probe)
    return model


def _mesh_arrays(mesh: MeshLike, label: str) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Checked (n, 3) float vertices and (m, 3) int faces of a mesh-like input."""
    if isinstance(mesh, tuple):
        if len(mesh) != 2:
            raise InvalidMesh(f"{label}: expected a (vertices, faces) pair, got {len(mesh)} items")
        vertices, faces = mesh
    else:
        vertices, faces = mesh.vertices, mesh.faces
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or len(vertices) < 4:
        raise InvalidMesh(f"{label}: vertices must be (n >= 4, 3), got shape {vertices.shape}")
    if not np.all(np.isfinite(vertices)):
        raise InvalidMesh(f"{label}: vertices hold NaN or infinite values")
    if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
        raise InvalidMesh(f"{label}: faces must be (m >= 1, 3), got shape {faces.shape}")
    if not np.issubdtype(faces.dtype, np.integer):
        raise InvalidMesh(f"{label}: faces must be integer indices, got {faces.dtype}")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise InvalidMesh(
            f"{label}: face indices must lie in [0, {len(vertices) - 1}], "
            f"got [{faces.min()}, {faces.max()}]"
        )
    return vertices, faces.astype(np.int64)


def _msh_asset(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> mjcf.Asset:
    """Mesh in MuJoCo's binary .msh format, loaded fast: float32 vertices (rounding below
    0.01 um within 1 m of the origin), int32 faces."""
    header = np.array([len(vertices), 0, 0, len(faces)], dtype="<i4")
    contents = header.tobytes() + vertices.astype("<f4").tobytes() + faces.astype("<i4").tobytes()
    return mjcf.Asset(contents=contents, extension=".msh")


def attach_object(
    model: mjcf.RootElement,
    name: str,
    collision_parts: Sequence[MeshLike],
    visual_mesh: MeshLike | None = None,
    position_in_mount: ArrayLike = (0.0, 0.0, 0.0),
    quat_wxyz_in_mount: ArrayLike = (1.0, 0.0, 0.0, 0.0),
    maxhullvert: int | None = None,
    rgba: tuple[float, float, float, float] = (0.8, 0.72, 0.6, 1.0),
    tip_collides: bool = True,
) -> mjcf.Element:
    """Attaches a fixed object at the scene's object mount; returns the object's body.

    The object body holds one colliding mesh geom per convex part (MuJoCo collides each as
    its convex hull; group 3, hidden by default) and one visual mesh geom that does not
    collide (group 2). Compiled names carry the prefix ``f"{name}/"``: the body is
    ``f"{name}/object"``, its geoms ``f"{name}/collision_{i}"`` and ``f"{name}/visual"``.
    The parts collide with the probe's housing and shaft, and with its tip unless
    ``tip_collides`` is False (the tip then meets the object through
    :func:`add_tip_contact`).

    Parameters
    ----------
    model : mjcf.RootElement
        The scene (``scene_model()``), modified in place.
    name : str
        Object name: a letter, then letters, digits, ``_`` or ``-``; unique in the scene.
    collision_parts : sequence of MeshLike
        Convex parts (e.g. CoACD hulls) in the object frame, metres. Each part must span
        three dimensions.
    visual_mesh : MeshLike or None
        Mesh drawn for the object, object frame, metres; None draws the collision parts.
    position_in_mount : (3,) float, metres
        Object frame origin in the ``object_mount`` frame (on the table top at
        (0.40, 0, 0) in the world, axes parallel to the world's).
    quat_wxyz_in_mount : (4,) float
        Object frame orientation in the mount frame, wxyz; normalised here.
    maxhullvert : int or None
        Cap on each collision hull's vertex count (> 3); None keeps every vertex.
    rgba : (4,) float
        Colour of the visual mesh.
    tip_collides : bool
        Whether the convex parts collide with the probe's tip too.

    Returns
    -------
    mjcf.Element
        The object's body; ``physics.bind(body).xpos``/``.xquat`` give its world pose.
    """
    if not isinstance(name, str) or not _NAME_PATTERN.match(name):
        raise ValueError(
            f"object name must be a letter followed by letters, digits, '_' or '-', got {name!r}"
        )
    if len(collision_parts) == 0:
        raise InvalidMesh(f"object {name!r} needs at least one collision part")
    if maxhullvert is not None and maxhullvert < 4:
        raise ValueError(f"maxhullvert must be at least 4 (or None), got {maxhullvert}")
    position = np.asarray(position_in_mount, dtype=np.float64)
    quat = np.asarray(quat_wxyz_in_mount, dtype=np.float64)
    if position.shape != (3,) or not np.all(np.isfinite(position)):
        raise ValueError(f"position_in_mount must be a finite (3,) array, got {position}")
    norm = float(np.linalg.norm(quat)) if quat.shape == (4,) else 0.0
    if not np.isfinite(norm) or norm < 1e-9:
        raise ValueError(f"quat_wxyz_in_mount must be a non-zero (4,) array, got {quat}")

    mount = model.find("site", OBJECT_MOUNT_SITE)
    if mount is None:
        raise SimulationError(f"the scene has no site {OBJECT_MOUNT_SITE!r} to attach objects to")

    if model.namescope.has_identifier("namescope", name):
        raise ValueError(f"the scene already holds a model named {name!r}")

    obj = mjcf.RootElement(model=name)
    body = obj.worldbody.add("body", name="object", pos=position, quat=quat / norm)
    hull_options = {} if maxhullvert is None else {"maxhullvert": maxhullvert}
    for i, part in enumerate(collision_parts):
        vertices, faces = _mesh_arrays(part, f"object {name!r} collision part {i}")
        centred = vertices - vertices.mean(axis=0)
        thickness = np.linalg.svd(centred, compute_uv=False)[-1] / np.sqrt(len(vertices))
        if thickness < _FLAT_PART_TOLERANCE_M:
            raise InvalidMesh(
                f"object {name!r} collision part {i} is flat (rms thickness {thickness:.2e} m "
                f"< {_FLAT_PART_TOLERANCE_M:.0e} m): MuJoCo cannot build its convex hull"
            )
        obj.asset.add(
            "mesh", name=f"collision_{i}", file=_msh_asset(vertices, faces), **hull_options
        )
        body.add(
            "geom",
            name=f"collision_{i}",
            type="mesh",
            mesh=f"collision_{i}",
            group=3,
            density=0,
            rgba=(0.2, 0.6, 0.9, 0.5),
            contype=BODY_CONTACT,
            conaffinity=BODY_CONTACT | (TIP_CONTACT if tip_collides else 0),
        )
    if visual_mesh is not None:
        vertices, faces = _mesh_arrays(visual_mesh, f"object {name!r} visual mesh")
        obj.asset.add("mesh", name="visual", file=_msh_asset(vertices, faces))
        body.add(
            "geom",
            name="visual",
            type="mesh",
            mesh="visual",
            group=2,
            contype=0,
            conaffinity=0,
            density=0,
            rgba=rgba,
        )
    else:
        for geom in body.find_all("geom"):
            geom.group = 2
            geom.rgba = rgba
    mount.attach(obj)
    return body


def add_tip_contact(model: mjcf.RootElement) -> mjcf.Element:
    """Adds the tip's contact box: a mocap body that stands for the object under the tip.

    Its box geom collides with the probe's tip only (bit :data:`TIP_CONTACT`; group 4,
    hidden); :mod:`tactile_sim.probing.tip_contact` keeps its top face tangent to the
    object's mesh at the point nearest the tip centre. It waits far below the table until
    then. Returns the mocap body (compiled name :data:`TIP_CONTACT_BODY`).
    """
    body = model.worldbody.add("body", name=TIP_CONTACT_BODY, mocap=True, pos=(0.0, 0.0, -1.0))
    body.add(
        "geom",
        name=TIP_CONTACT_BODY,
        type="box",
        size=TIP_CONTACT_HALF_SIZE_M,
        contype=TIP_CONTACT,
        conaffinity=TIP_CONTACT,
        group=4,
        rgba=(0.2, 0.9, 0.3, 0.4),
    )
    return body


def physics_of(model: mujoco.MjModel) -> dm_mujoco.Physics:
    """Returns dm_control's physics of a compiled model (e.g. one read from a cache)."""
    return dm_mujoco.Physics.from_model(dm_mujoco.wrapper.MjModel(model))


def build_physics(model: mjcf.RootElement) -> mjcf.Physics:
    """Returns the compiled physics of a scene model, forward-evaluated and warning-free.

    Raises
    ------
    SimulationError
        MuJoCo cannot compile the model (the message carries MuJoCo's).
    SimulationUnstable
        The initial state already raises a MuJoCo warning.
    """
    try:
        physics = mjcf.Physics.from_mjcf_model(model)
    except ValueError as error:
        raise SimulationError(f"MuJoCo could not compile the scene: {error}") from error
    step(physics, 0)
    return physics


def load_scene(
    collision_parts: Sequence[MeshLike] | None = None,
    visual_mesh: MeshLike | None = None,
    position_in_mount: ArrayLike = (0.0, 0.0, 0.0),
    quat_wxyz_in_mount: ArrayLike = (1.0, 0.0, 0.0, 0.0),
    name: str = "object",
    maxhullvert: int | None = None,
) -> mjcf.Physics:
    """Returns the physics of the probing scene with an optional object (see attach_object)."""
    model = scene_model()
    if collision_parts is not None:
        attach_object(
            model,
            name,
            collision_parts,
            visual_mesh,
            position_in_mount,
            quat_wxyz_in_mount,
            maxhullvert=maxhullvert,
        )
    return build_physics(model)


def warning_counts(physics: mjcf.Physics) -> dict[str, int]:
    """Returns MuJoCo's warning counts since the last reset, by warning name, non-zero only."""
    counts = np.asarray(physics.data.warning.number)
    return {
        name: int(counts[int(warning)])
        for name, warning in mujoco.mjtWarning.__members__.items()
        if int(warning) < len(counts) and counts[int(warning)] > 0
    }


def raise_on_warnings(physics: mjcf.Physics) -> None:
    """Raises SimulationUnstable if MuJoCo warned since the last reset or the state holds NaN."""
    data = physics.data.ptr
    if data.warning.number.any():
        details = ", ".join(f"{name} x{count}" for name, count in warning_counts(physics).items())
        raise SimulationUnstable(
            f"MuJoCo warned at t = {data.time:.4f} s: {details} "
            "(diverging state, or a buffer too small for the contacts)"
        )
    for field in ("qpos", "qvel", "qacc"):
        if not np.isfinite(getattr(data, field)).all():
            raise SimulationUnstable(
                f"non-finite {field} at t = {data.time:.4f} s: the simulation diverged"
            )


def step(physics: mjcf.Physics, nstep: int = 1) -> None:
    """Advances the simulation by ``nstep`` timesteps (0: forward only), raising on instability.

    Steps like dm_control's ``Physics.step`` (finish the step begun by ``mj_step1``, then
    ``mj_step1`` again, so positions and sensors match the new state), without its Python
    overhead; every MuJoCo warning counts, not only diverging states.

    Raises
    ------
    SimulationUnstable
        MuJoCo warned (e.g. bad accelerations and a reset) or the state is not finite.
    """
    if nstep < 0:
        raise ValueError(f"nstep must be >= 0, got {nstep}")
    model, data = physics.model.ptr, physics.data.ptr
    if nstep == 0:
        mujoco.mj_forward(model, data)
    else:
        mujoco.mj_step2(model, data)
        if nstep > 1:
            mujoco.mj_step(model, data, nstep - 1)
        mujoco.mj_step1(model, data)
    raise_on_warnings(physics)


def arm_joints(physics: mjcf.Physics) -> NDArray[np.float64]:
    """Returns the arm's joint vector (shoulder rad, elbow rad, quill m, roll rad), (4,)."""
    return np.array([physics.named.data.qpos[joint][0] for joint in ARM_JOINTS])


def probe_deflection(physics: mjcf.Physics) -> NDArray[np.float64]:
    """Returns the probe pivot angles (deflection_x, deflection_y), (2,) radians."""
    return np.array([physics.named.data.qpos[joint][0] for joint in DEFLECTION_JOINTS])


def set_arm_joints(physics: mjcf.Physics, joints: ArrayLike) -> None:
    """Sets the arm's joint positions and servo targets to ``joints`` (4,), at rest, forward.

    The probe's pivot is reset to rest as well.
    """
    q = np.asarray(joints, dtype=np.float64)
    if q.shape != (4,) or not np.all(np.isfinite(q)):
        raise ValueError(f"joints must be a finite (4,) array, got {q}")
    for joint, value in zip(ARM_JOINTS, q, strict=True):
        physics.named.data.qpos[joint] = value
        physics.named.data.ctrl[joint] = value
    for joint in DEFLECTION_JOINTS:
        physics.named.data.qpos[joint] = 0.0
    physics.data.qvel[:] = 0.0
    physics.data.act[:] = 0.0
    step(physics, 0)
