"""Outline traces: an object's outline followed in a horizontal plane (thesis Section 3.4.2)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.rigid import apply_pose
from tactile_sim.errors import SimulationError
from tactile_sim.probing.config import ProbingConfig
from tactile_sim.probing.placement import ObjectLike
from tactile_sim.probing.plan import SamplingPlane
from tactile_sim.probing.probe_scene import ProbeScene, build_probe_scene
from tactile_sim.probing.rig import Rig
from tactile_sim.probing.sweep import SweepResult, SweepRunner, sweep_result
from tactile_sim.sensor import SensorConfig

__all__ = [
    "ContourTrace",
    "trace_contour",
]


@dataclass(frozen=True)
class ContourTrace:
    """An object's outline traced in a horizontal plane (thesis Section 3.4.2).

    Attributes
    ----------
    object_name : str
    sweep : SweepResult
        The trace (one side, counter-clockwise seen from above).
    T_world_from_object : (4, 4) float
        Ground truth: object pose.
    wall_seconds, sim_seconds : float, seconds
    """

    object_name: str
    sweep: SweepResult
    T_world_from_object: NDArray[np.float64]
    wall_seconds: float
    sim_seconds: float

    @property
    def points_in_world(self) -> NDArray[np.float64]:
        """Returns the sensed outline points, (n, 3) metres, world frame."""
        return self.sweep.points_in_world

    @property
    def points_in_object(self) -> NDArray[np.float64]:
        """Returns the sensed outline points in the object frame, (n, 3) metres."""
        T = np.linalg.inv(self.T_world_from_object)
        return apply_pose(T, self.sweep.points_in_world)


def trace_contour(
    obj: ObjectLike,
    *,
    seed: int,
    n_points: int = 40,
    spacing_m: float = 1.2e-3,
    height_m: float | None = None,
    start_angle_rad: float | None = None,
    T_world_from_object: ArrayLike | None = None,
    config: ProbingConfig | None = None,
    sensor: SensorConfig | None = None,
    progress: bool = True,
) -> ContourTrace:
    """Traces an object's outline in a horizontal plane, counter-clockwise from above.

    The probe approaches the side wall horizontally (the stylus deflects against it) at
    the bearing ``start_angle_rad`` from the object's vertical axis, then walks along the
    wall by ``spacing_m`` for ``n_points`` points in all (thesis Section 3.4.2).

    Parameters
    ----------
    obj : str, ObjectModel, Solid or trimesh.Trimesh
        E.g. ``"planar_ellipse"`` or ``"planar_spline"``.
    seed : int
        Seeds the pose (when not given), the start bearing (when not given) and noise.
    n_points : int
        Points to sense.
    spacing_m : float, metres
    height_m : float or None, metres
        Height of the plane above the table; None: half the object's height.
    start_angle_rad : float or None, radians
        Bearing (world yaw) of the first point seen from the object's axis.
    T_world_from_object : (4, 4) float or None
        Object pose; None draws a random one.
    config : ProbingConfig or None
        Controller parameters; None: the defaults.
    sensor : SensorConfig or None
        Sensor model; None: the defaults.
    progress : bool
        Announce cold builds.
    """
    wall_start = time.perf_counter()
    config = config or ProbingConfig()
    sensor = sensor or SensorConfig()
    rng = np.random.default_rng(seed)
    probe_scene = build_probe_scene(obj, T_world_from_object, seed=seed, progress=progress)
    T = probe_scene.T_world_from_object
    vertices_world = apply_pose(T, probe_scene.target.mesh.vertices)
    if height_m is None:
        height_m = 0.5 * float(vertices_world[:, 2].max() + vertices_world[:, 2].min())
    bearing = rng.uniform(-math.pi, math.pi) if start_angle_rad is None else start_angle_rad
    axis = T[:3, 3].copy()
    axis[2] = height_m
    outward = np.array([math.cos(bearing), math.sin(bearing), 0.0])
    # The experimenter's plan: where the wall is along that bearing (from the mesh).
    wall = _wall_along(probe_scene, axis, outward)
    if wall is None:
        raise SimulationError(f"no wall at bearing {bearing:.3f} rad, height {height_m} m")
    radius = sensor.robot.probe.tip_radius_m
    plane = SamplingPlane.through(wall, np.cross([0.0, 0.0, 1.0], outward), outward)
    probe_scene.physics.reset()
    rig = Rig(probe_scene, config, sensor, rng)
    runner = SweepRunner(rig, config, spacing_m, None)
    first = runner.first(
        plane, wall + radius * outward, config.first_clearance_m, config.first_search_m
    )
    samples, side = runner.side(plane, [first], +1, n_points - 1)
    samples = [first, *samples]
    sweep = sweep_result(probe_scene, plane, samples, 0, (side,), sensor)
    return ContourTrace(
        object_name=probe_scene.target.name,
        sweep=sweep,
        T_world_from_object=T,
        wall_seconds=time.perf_counter() - wall_start,
        sim_seconds=float(probe_scene.physics.data.time),
    )


def _wall_along(
    probe_scene: ProbeScene, axis_point: NDArray[np.float64], outward: NDArray[np.float64]
) -> NDArray[np.float64] | None:
    """The outermost mesh point hit by a horizontal ray from outside towards the axis."""
    T = probe_scene.T_world_from_object
    origin = axis_point + 0.5 * outward
    o = (origin - T[:3, 3]) @ T[:3, :3]
    d = T[:3, :3].T @ (-outward)
    face, t = probe_scene.first_hits_in_object(o[None], d[None])
    if face[0] < 0:
        return None
    return origin - float(t[0]) * outward
