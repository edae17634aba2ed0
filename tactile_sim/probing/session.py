"""Probing sessions: three sweeps through one point p of an object -> three data curves.

A session (:func:`probe_object`) traces three vertical sampling planes through one point
p on the upward-facing surface, ``plane_angle_deg`` apart, n points per curve with p in
the middle. Choosing p and the first approach uses the object's mesh, as an experimenter
would; the sensed points come from the sensor readings only, and the ground truth (object
pose, p on the model, true contact points) is kept apart in :class:`GroundTruth`. A sweep
left with fewer than five points makes :func:`probe_object` choose another p (when it
chose p itself) or raise :class:`~tactile_sim.errors.SweepTruncated`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition import DataCurves, RecognitionError
from recognition.rigid import apply_pose
from recognition.surfaces.registration import common_point
from tactile_sim.errors import InvalidSettings, SweepTruncated, UnusableCurves
from tactile_sim.kinematics import inverse_kinematics
from tactile_sim.probing.config import ProbingConfig
from tactile_sim.probing.placement import ObjectLike
from tactile_sim.probing.plan import choose_point, sampling_planes, snap_point
from tactile_sim.probing.probe_scene import ProbeScene, build_probe_scene
from tactile_sim.probing.rig import Rig
from tactile_sim.probing.sweep import StopReason, SweepResult, SweepRunner, run_sweep
from tactile_sim.sensor import SensorConfig
from tactile_sim.trajectory import Trajectory, TrajectoryRecorder

__all__ = [
    "MAX_CURVE_LENGTH_M",
    "MAX_SPACING_M",
    "MIN_CURVE_POINTS",
    "PLANE_ANGLE_RANGE_DEG",
    "GroundTruth",
    "ProbeSession",
    "check_sweep",
    "probe_object",
]


MIN_CURVE_POINTS = 5
"""Fewest points a data curve may have (``recognition.DataCurves`` asks for five)."""

MAX_SPACING_M = 0.02
"""Point spacing along a sweep must be below this, metres."""

MAX_CURVE_LENGTH_M = 0.1
"""Longest sweep, (n_points - 1) * spacing, metres: the largest catalog object is under
0.1 m."""

PLANE_ANGLE_RANGE_DEG = (5.0, 85.0)
"""Smallest and largest angle between neighbouring sampling planes, degrees."""


def data_point_in_object(
    curves: DataCurves, T_world_from_object: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Returns where the common point p of world-frame curves (what recognition locates,
    :func:`recognition.surfaces.registration.common_point`) lies on the object, model
    frame, metres, by the pose ``T_world_from_object``."""
    return apply_pose(np.linalg.inv(T_world_from_object), common_point(curves)[None])[0]


@dataclass(frozen=True)
class GroundTruth:
    """What the simulator knows and the sensor does not (evaluation only).

    Attributes
    ----------
    T_world_from_object : (4, 4) float
        Object pose on the table, metres.
    point_in_object : (3,) float, metres
        p on the model, model frame.
    point_in_world : (3,) float, metres
        p in the world frame.
    normal_in_object : (3,) float
        The model's outward normal at p, model frame.
    true_contact_points_in_world : tuple of (n_i, 3) float
        Per curve, where MuJoCo's contact met the surface the tip touched at each
        reading.
    mesh_points_in_world : tuple of (n_i, 3) float
        Per curve, the points of the object's mesh nearest the true tip centres.
    true_tip_centres_in_world : tuple of (n_i, 3) float
        Per curve, the simulator's tip centres at the readings.
    data_point_in_object : (3,) float, metres
        Where the sensed curves' common point p lies on the object
        (:func:`data_point_in_object`): the localisation's reference.
    model_error_rms_m : float
        How far the probed surface lies from the object's model (RMS, metres; 0 unless
        the object was displaced on purpose, :func:`~tactile_sim.probing.displaced_target`).
    """

    T_world_from_object: NDArray[np.float64]
    point_in_object: NDArray[np.float64]
    point_in_world: NDArray[np.float64]
    normal_in_object: NDArray[np.float64]
    true_contact_points_in_world: tuple[NDArray[np.float64], ...]
    mesh_points_in_world: tuple[NDArray[np.float64], ...]
    true_tip_centres_in_world: tuple[NDArray[np.float64], ...]
    data_point_in_object: NDArray[np.float64]
    model_error_rms_m: float = 0.0


@dataclass(frozen=True)
class ProbeSession:
    """The result of probing one object: three data curves and the ground truth apart.

    Attributes
    ----------
    object_name : str
    curves : DataCurves
        The three sensed curves, world frame, with ``approach`` the direction in which
        the probe approached p (into the object) and the sensed contact normals.
    sweeps : tuple of SweepResult
        Per-sweep details (planes, normals, truncations).
    ground_truth : GroundTruth
    seed : int
    plane_angle_deg : float, degrees
    spacing_m : float, metres
    n_points : int
        Points requested per curve.
    wall_seconds : float, seconds
        Wall time of the session (scene build included).
    build_seconds : float, seconds
        Wall time spent loading the object and compiling the scene (0 when a built scene
        was passed in).
    sim_seconds : float, seconds
        Simulated time.
    trajectory : Trajectory or None
        The rig's state sampled during the session (``probe_object(..., trajectory_hz=...)``);
        None when it was not recorded.
    runner : SweepRunner or None
        The rig, still in the scene where the sweeps left it: further touches
        (:func:`tactile_sim.probing.touches.touch_until_sure`) continue from there.
    """

    object_name: str
    curves: DataCurves
    sweeps: tuple[SweepResult, ...]
    ground_truth: GroundTruth
    seed: int
    plane_angle_deg: float
    spacing_m: float
    n_points: int
    wall_seconds: float
    build_seconds: float
    sim_seconds: float
    trajectory: Trajectory | None = None
    runner: SweepRunner | None = field(default=None, repr=False, compare=False)

    @property
    def truncated(self) -> bool:
        """Returns True if any sweep lost points."""
        return any(s.truncated for s in self.sweeps)

    @property
    def messages(self) -> tuple[str, ...]:
        """Returns the reasons of every truncated sweep side."""
        return tuple(
            f"sweep {i}: {side.message}"
            for i, s in enumerate(self.sweeps)
            for side in s.sides
            if side.stop is not StopReason.COMPLETE
        )


def check_sweep(n_points: int, spacing_m: float, plane_angle_deg: float) -> None:
    """Checks a session's sweep settings: at least :data:`MIN_CURVE_POINTS` points, a
    spacing in (0, :data:`MAX_SPACING_M`), a sweep no longer than
    :data:`MAX_CURVE_LENGTH_M` and a plane angle in :data:`PLANE_ANGLE_RANGE_DEG`.

    Raises
    ------
    InvalidSettings
        The setting out of range, and its range.
    """
    if n_points < MIN_CURVE_POINTS:
        raise InvalidSettings(f"n_points must be >= 5 (a data curve needs five), got {n_points}")
    if not 0 < spacing_m < MAX_SPACING_M:
        raise InvalidSettings(f"spacing_m must lie in (0, {MAX_SPACING_M:g}) m, got {spacing_m}")
    if not (n_points - 1) * spacing_m <= MAX_CURVE_LENGTH_M:
        raise InvalidSettings(
            f"a sweep of {n_points} points {spacing_m:g} m apart is longer than "
            f"{MAX_CURVE_LENGTH_M:g} m"
        )
    low, high = PLANE_ANGLE_RANGE_DEG
    if not low <= plane_angle_deg <= high:
        raise InvalidSettings(
            f"plane_angle_deg must lie in [{low:g}, {high:g}] deg, got {plane_angle_deg}"
        )


def probe_object(
    obj: ObjectLike,
    *,
    seed: int,
    point: ArrayLike | None = None,
    plane_angle_deg: float = 60.0,
    n_points: int = 21,
    spacing_m: float = 1.2e-3,
    T_world_from_object: ArrayLike | None = None,
    first_plane_yaw_rad: float | None = None,
    config: ProbingConfig | None = None,
    sensor: SensorConfig | None = None,
    probe_scene: ProbeScene | None = None,
    progress: bool = True,
    trajectory_hz: float | None = None,
) -> ProbeSession:
    """Probes an object along three sampling planes through one point; returns the curves.

    Parameters
    ----------
    obj : str, ObjectModel, Solid or trimesh.Trimesh
        A catalog name (``object_names()``), a solid name (``solid_names()``) or a mesh
        in metres (model frame, base on z = 0).
    seed : int
        Seeds everything random: the pose (when not given), p (when not given), the
        first plane's yaw (when not given) and the sensor noise.
    point : (3,) float or None, metres
        p in the model frame (snapped to the mesh); None picks a point on the
        upward-facing surface where the three sweeps fit.
    plane_angle_deg : float, degrees
        Angle between neighbouring sampling planes (thesis: 60).
    n_points : int
        Points per curve, p included (thesis: 21); p is the middle one when no side is
        truncated.
    spacing_m : float, metres
        Distance between neighbouring points along the curve (thesis: 1.2 mm).
    T_world_from_object : (4, 4) float or None
        Object pose on the table; None draws a random one (:func:`random_pose`).
    first_plane_yaw_rad : float or None, radians
        Yaw of the first plane's "+" direction; None draws it.
    config : ProbingConfig or None
        Controller parameters; None: the defaults.
    sensor : SensorConfig or None
        Sensor model (noise); None: the defaults.
    probe_scene : ProbeScene or None
        A scene already built for this object (:func:`build_probe_scene`), reused as is
        (its pose wins over ``T_world_from_object``); None builds one.
    progress : bool
        Announce cold builds (meshes, hulls) with progress bars.
    trajectory_hz : float or None, 1/s
        Sample the rig's state (body poses, tip, deflection, force) at this rate of
        simulated time into ``ProbeSession.trajectory``, e.g. for a recording
        (:mod:`tactile_sim.recording`); None records nothing.

    Returns
    -------
    ProbeSession

    Raises
    ------
    UnknownObject
        ``obj`` is an unknown name; the message lists the known ones.
    UnreachablePoint
        p (or the start of its approach) is outside the robot's workspace; the message
        names the limit.
    SweepTruncated
        A sweep kept fewer than five points (for an automatic p, after replanning).
    UnusableCurves
        The sensed curves are no data curves (for an automatic p, after replanning).
    SimulationError
        MuJoCo became unstable, or no surface was found at p.
    """
    wall_start = time.perf_counter()
    config = config or ProbingConfig()
    sensor = sensor or SensorConfig()
    check_sweep(n_points, spacing_m, plane_angle_deg)
    rng = np.random.default_rng(seed)
    build_seconds = 0.0
    if probe_scene is None:
        probe_scene = build_probe_scene(obj, T_world_from_object, seed=seed, progress=progress)
        build_seconds = probe_scene.build_seconds
    T = probe_scene.T_world_from_object
    plane_angle = math.radians(plane_angle_deg)
    yaw = rng.uniform(-math.pi, math.pi) if first_plane_yaw_rad is None else first_plane_yaw_rad
    half_length = (n_points // 2) * spacing_m + 1e-3
    radius = sensor.robot.probe.tip_radius_m
    attempts = 1 + config.max_replans if point is None else 1
    for attempt in range(attempts):
        if point is None:
            p_world, normal_world = choose_point(
                probe_scene,
                np.random.default_rng([seed, 2] if attempt == 0 else [seed, 2, attempt]),
                plane_angle_rad=plane_angle,
                first_yaw_rad=yaw,
                half_length_m=half_length,
            )
        else:
            p_world, normal_world = snap_point(probe_scene, point)
        origin = p_world + radius * normal_world
        # Bad input first: p must be reachable with the approach clearance above it.
        inverse_kinematics(
            origin + np.array([0.0, 0.0, config.first_clearance_m]), robot=sensor.robot
        )
        planes = sampling_planes(p_world, yaw, plane_angle)
        line_point = origin.copy()
        probe_scene.physics.reset()
        recorder = None
        if trajectory_hz is not None:
            recorder = TrajectoryRecorder(probe_scene.physics, trajectory_hz)
        rig = Rig(probe_scene, config, sensor, rng, recorder)
        runner = SweepRunner(rig, config, spacing_m, config.max_tilt_deg)
        sweeps = tuple(
            run_sweep(runner, probe_scene, plane, line_point, n_points, first=(k == 0))
            for k, plane in enumerate(planes)
        )
        unusable = None
        if all(sweep.n_points >= MIN_CURVE_POINTS for sweep in sweeps):
            try:
                curves = DataCurves(
                    curves=tuple(s.points_in_world for s in sweeps),
                    approach=np.array([0.0, 0.0, -1.0]),
                    normals=tuple(s.normals_in_world for s in sweeps),
                )
                break
            except RecognitionError as exc:  # e.g. parallel tangents at p: plan again
                unusable = str(exc)
    else:
        tried = f" ({attempts} points tried)" if attempts > 1 else ""
        if unusable is not None:
            raise UnusableCurves(
                f"{probe_scene.target.name}: the sensed curves are unusable{tried}: {unusable}"
            )
        reasons = "; ".join(
            f"sweep {k}: {side.message}"
            for k, sweep in enumerate(sweeps)
            for side in sweep.sides
            if side.stop is not StopReason.COMPLETE
        )
        raise SweepTruncated(
            f"{probe_scene.target.name}: a sweep through p kept fewer than "
            f"{MIN_CURVE_POINTS} points{tried}: {reasons}"
        )
    T_object_from_world = np.linalg.inv(T)
    truth = GroundTruth(
        T_world_from_object=T,
        point_in_object=T_object_from_world[:3, :3] @ p_world + T_object_from_world[:3, 3],
        point_in_world=p_world,
        normal_in_object=T_object_from_world[:3, :3] @ normal_world,
        true_contact_points_in_world=tuple(s.true_contact_points_in_world for s in sweeps),
        mesh_points_in_world=tuple(s.mesh_points_in_world for s in sweeps),
        true_tip_centres_in_world=tuple(s.true_tip_centres_in_world for s in sweeps),
        data_point_in_object=data_point_in_object(curves, T),
        model_error_rms_m=probe_scene.target.model_error_rms_m,
    )
    return ProbeSession(
        object_name=probe_scene.target.name,
        curves=curves,
        sweeps=sweeps,
        ground_truth=truth,
        seed=seed,
        plane_angle_deg=plane_angle_deg,
        spacing_m=spacing_m,
        n_points=n_points,
        wall_seconds=time.perf_counter() - wall_start,
        build_seconds=build_seconds,
        sim_seconds=float(probe_scene.physics.data.time),
        trajectory=None if recorder is None else recorder.trajectory(),
        runner=runner,
    )
