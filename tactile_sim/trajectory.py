"""The probing rig's state sampled during a session: body poses, tip path, stylus signals."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from dm_control import mjcf

__all__ = [
    "DEFAULT_RATE_HZ",
    "Trajectory",
    "TrajectoryRecorder",
    "VisualGeom",
    "visual_geoms",
]

DEFAULT_RATE_HZ = 200.0
"""Default sampling rate of a trajectory, per second of simulated time."""

_VISUAL_GROUPS = (0, 1, 2)
"""Geom groups MuJoCo draws by default; group 3 holds the collision geoms."""

_SHAPES = {
    mujoco.mjtGeom.mjGEOM_PLANE: "plane",
    mujoco.mjtGeom.mjGEOM_SPHERE: "sphere",
    mujoco.mjtGeom.mjGEOM_CAPSULE: "capsule",
    mujoco.mjtGeom.mjGEOM_ELLIPSOID: "ellipsoid",
    mujoco.mjtGeom.mjGEOM_CYLINDER: "cylinder",
    mujoco.mjtGeom.mjGEOM_BOX: "box",
    mujoco.mjtGeom.mjGEOM_MESH: "mesh",
}


@dataclass(frozen=True)
class VisualGeom:
    """One drawn geom of the compiled model, in its body's frame.

    Attributes
    ----------
    name : str
        MuJoCo geom name.
    body : str
        Name of the body that carries it ("world" for the table and the floor).
    shape : str
        "plane", "sphere", "capsule", "ellipsoid", "cylinder", "box" or "mesh".
    size : (3,) float, metres
        MuJoCo's ``geom_size``: half sizes of a box, (radius, half length) of a capsule
        or cylinder, the radius of a sphere, the semi-axes of an ellipsoid.
    position_in_body : (3,) float, metres
    quat_wxyz_in_body : (4,) float
    rgba : (4,) float
        Colour in [0, 1] (the material's when the geom has one).
    vertices : (n, 3) float or None, metres
        Mesh vertices in the geom frame (meshes only).
    faces : (m, 3) int or None
        Mesh triangles (meshes only).
    """

    name: str
    body: str
    shape: str
    size: NDArray[np.float64]
    position_in_body: NDArray[np.float64]
    quat_wxyz_in_body: NDArray[np.float64]
    rgba: NDArray[np.float64]
    vertices: NDArray[np.float32] | None = None
    faces: NDArray[np.int32] | None = None


def visual_geoms(model: mujoco.MjModel) -> tuple[VisualGeom, ...]:
    """Returns the drawn geoms (groups 0-2) of a compiled model, meshes included."""
    geoms = []
    for g in _visual_geom_ids(model):
        shape = _SHAPES[mujoco.mjtGeom(int(model.geom_type[g]))]
        material = int(model.geom_matid[g])
        rgba = model.mat_rgba[material] if material >= 0 else model.geom_rgba[g]
        vertices = faces = None
        mesh = int(model.geom_dataid[g])
        if shape == "mesh" and mesh >= 0:
            v0, nv = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
            f0, nf = int(model.mesh_faceadr[mesh]), int(model.mesh_facenum[mesh])
            vertices = np.array(model.mesh_vert[v0 : v0 + nv], dtype=np.float32)
            faces = np.array(model.mesh_face[f0 : f0 + nf], dtype=np.int32)
        body = int(model.geom_bodyid[g])
        geoms.append(
            VisualGeom(
                name=mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom_{g}",
                body=mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body) or f"body_{body}",
                shape=shape,
                size=np.array(model.geom_size[g], dtype=np.float64),
                position_in_body=np.array(model.geom_pos[g], dtype=np.float64),
                quat_wxyz_in_body=np.array(model.geom_quat[g], dtype=np.float64),
                rgba=np.array(rgba, dtype=np.float64),
                vertices=vertices,
                faces=faces,
            )
        )
    return tuple(geoms)


@dataclass(frozen=True)
class Trajectory:
    """The rig's state every few timesteps of a session, and what the scene draws.

    Attributes
    ----------
    timestep_s : float, seconds
        MuJoCo's timestep.
    steps : (k,) int
        Timestep index of each sample (0: the state after the reset).
    times_s : (k,) float, seconds
        Simulated time of each sample.
    body_names : tuple of str
        The bodies that move (carry a joint or sit below one) and are drawn, b of them.
    body_positions_in_world : (k, b, 3) float, metres
    body_quats_wxyz_in_world : (k, b, 4) float
    static_body_names : tuple of str
        The drawn bodies welded to the world (the world itself, the robot base, the
        object).
    static_body_positions_in_world : (s, 3) float, metres
    static_body_quats_wxyz_in_world : (s, 4) float
    tip_centres_in_world : (k, 3) float, metres
        Centre of the probe's tip sphere (site ``probe_tip``).
    deflection_rad : (k, 2) float, radians
        Stylus pivot angles (deflection_x, deflection_y), noise-free.
    tip_force_n : (k, 3) float, newtons
        Force of the stylus on the tip in the tip frame, noise-free (z along the stylus:
        the axial force).
    geoms : tuple of VisualGeom
        The drawn geoms of every body.
    """

    timestep_s: float
    steps: NDArray[np.int64]
    times_s: NDArray[np.float64]
    body_names: tuple[str, ...]
    body_positions_in_world: NDArray[np.float64]
    body_quats_wxyz_in_world: NDArray[np.float64]
    static_body_names: tuple[str, ...]
    static_body_positions_in_world: NDArray[np.float64]
    static_body_quats_wxyz_in_world: NDArray[np.float64]
    tip_centres_in_world: NDArray[np.float64]
    deflection_rad: NDArray[np.float64]
    tip_force_n: NDArray[np.float64]
    geoms: tuple[VisualGeom, ...]

    def __len__(self) -> int:
        return len(self.steps)

    @property
    def deflection_magnitude_rad(self) -> NDArray[np.float64]:
        """Returns the stylus tilt sqrt(dx^2 + dy^2) of each sample, (k,) radians."""
        return np.hypot(self.deflection_rad[:, 0], self.deflection_rad[:, 1])


class TrajectoryRecorder:
    """Steps MuJoCo like ``mujoco.mj_step`` and samples the rig every ``every_steps`` steps.

    Parameters
    ----------
    physics : dm_control.mjcf.Physics
        The probing scene (:mod:`tactile_sim.scene`), just reset.
    rate_hz : float, 1/s
        Samples per second of simulated time (rounded to a whole number of timesteps).
    """

    def __init__(self, physics: mjcf.Physics, rate_hz: float = DEFAULT_RATE_HZ) -> None:
        from tactile_sim import scene

        if not math.isfinite(rate_hz) or rate_hz <= 0:
            raise ValueError(f"rate_hz must be positive, got {rate_hz}")
        model, data = physics.model.ptr, physics.data.ptr
        self._model, self._data = model, data
        self.timestep_s = float(model.opt.timestep)
        self.every_steps = max(1, round(1.0 / (rate_hz * self.timestep_s)))
        self.geoms = visual_geoms(model)
        drawn = sorted({int(model.geom_bodyid[g]) for g in _visual_geom_ids(model)})
        self._moving = np.array([b for b in drawn if int(model.body_weldid[b]) != 0], dtype=int)
        self._static = np.array([b for b in drawn if int(model.body_weldid[b]) == 0], dtype=int)
        self._tip_site = physics.model.name2id(scene.PROBE_TIP_SITE, "site")
        joints = [physics.model.name2id(j, "joint") for j in scene.DEFLECTION_JOINTS]
        self._deflection_adr = np.array([int(model.jnt_qposadr[j]) for j in joints])
        force = physics.model.name2id(scene.TIP_FORCE_SENSOR, "sensor")
        adr = int(model.sensor_adr[force])
        self._force = slice(adr, adr + 3)
        self._countdown = self.every_steps
        self._xpos: list[NDArray[np.float64]] = []
        self._xquat: list[NDArray[np.float64]] = []
        self._tips: list[NDArray[np.float64]] = []
        self._qpos: list[NDArray[np.float64]] = []
        self._forces: list[NDArray[np.float64]] = []
        self._sample()

    def _sample(self) -> None:
        """Stores the current state (every ``every_steps`` steps, from step 0)."""
        data = self._data
        self._xpos.append(data.xpos.copy())
        self._xquat.append(data.xquat.copy())
        self._tips.append(data.site_xpos[self._tip_site].copy())
        self._qpos.append(data.qpos.copy())
        self._forces.append(data.sensordata[self._force].copy())

    def step(self, model: mujoco.MjModel, data: mujoco.MjData, nstep: int = 1) -> None:
        """Advances the simulation by ``nstep`` timesteps, sampling on the way."""
        if nstep < self._countdown:
            mujoco.mj_step(model, data, nstep)
            self._countdown -= nstep
            return
        while nstep > 0:
            n = min(nstep, self._countdown)
            mujoco.mj_step(model, data, n)
            nstep -= n
            self._countdown -= n
            if self._countdown == 0:
                self._sample()
                self._countdown = self.every_steps

    def trajectory(self) -> Trajectory:
        """Returns the samples taken so far."""
        model, data = self._model, self._data
        xpos, xquat = np.array(self._xpos), np.array(self._xquat)
        steps = self.every_steps * np.arange(len(self._xpos), dtype=np.int64)
        return Trajectory(
            timestep_s=self.timestep_s,
            steps=steps,
            times_s=steps * self.timestep_s,
            body_names=tuple(_body_name(model, b) for b in self._moving),
            body_positions_in_world=xpos[:, self._moving],
            body_quats_wxyz_in_world=xquat[:, self._moving],
            static_body_names=tuple(_body_name(model, b) for b in self._static),
            static_body_positions_in_world=np.array(data.xpos[self._static]),
            static_body_quats_wxyz_in_world=np.array(data.xquat[self._static]),
            tip_centres_in_world=np.array(self._tips),
            deflection_rad=np.array(self._qpos)[:, self._deflection_adr],
            tip_force_n=np.array(self._forces),
            geoms=self.geoms,
        )


def _visual_geom_ids(model: mujoco.MjModel) -> list[int]:
    """Ids of the geoms MuJoCo draws by default whose shape a recording can show."""
    return [
        g
        for g in range(model.ngeom)
        if int(model.geom_group[g]) in _VISUAL_GROUPS
        and mujoco.mjtGeom(int(model.geom_type[g])) in _SHAPES
    ]


def _body_name(model: mujoco.MjModel, body: int) -> str:
    return mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body) or f"body_{body}"
