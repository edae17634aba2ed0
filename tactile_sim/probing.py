"""Probing sessions: place an object, plan three sampling planes, run the sweep controller.

The sweep controller is a touch-probe cycle in one sampling plane. For every point it

1. predicts where the next contact lies: one spacing on from where the last approach met
   the surface, along the in-plane tangent that the last sensed normal gives (turned by
   half the turn of the normal between the last two points);
2. moves the undeflected tip to a start point ``standoff_m`` outside that prediction,
   aimed off the plane by what the last point drifted (so that the contact lands in it);
3. approaches along the in-plane normal at ``approach_speed_m_s`` until the first touch
   (a small deflection or axial force), backs off ``backoff_m`` from the impact, and
   presses again at ``press_speed_m_s`` until the set point: a deflection of
   ``deflection_trigger_rad`` (a sloped surface tilts the stylus) or an axial force of
   ``axial_force_trigger_n`` (a level one loads it along its rigid axis), steadily for a
   few timesteps so that an impact spike does not count;
4. holds the arm there, lets the stylus settle for ``dwell_s`` and reads the sensors,
   averaged over ``reading_average_s`` (:mod:`tactile_sim.sensor` turns the reading and
   the slide of the press into the sensed contact point and normal).

The first point of the first sweep is touched twice: the second approach line is moved
by the horizontal miss of the first, so that the three curves meet at the planned p.

No contact within ``search_m`` beyond the prediction means the surface fell away (an
edge): that side of the sweep is truncated, reported, and the other side of p is
extended instead when it can be. A surface turning steeper than ``max_tilt_deg`` ends a
side the same way, as does a point the arm cannot reach (the reason names the limit). A
sweep left with fewer than five points makes :func:`probe_object` choose another p (when
it chose p itself) or raise :class:`SweepTruncated`.

A session (:func:`probe_object`) traces three vertical sampling planes through one
point p on the upward-facing surface, ``plane_angle_deg`` apart, n points per curve with
p in the middle; :func:`trace_contour` traces an object's outline in a horizontal plane
(the planar experiments of thesis Section 3.4.2). Choosing p and the first approach uses
the object's mesh, as an experimenter would; the sensed points come from the sensor
readings only, and the ground truth (object pose, p on the model, true contact points)
is kept apart in :class:`GroundTruth`.
"""

from __future__ import annotations

import enum
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from recognition import DataCurves
from recognition.rigid import pose_matrix, rotation_about
from tactile_sim import scene
from tactile_sim.collision import (
    ConvexParts,
    Solid,
    convex_decomposition,
    load_solid,
    object_parts,
    solid_names,
)
from tactile_sim.errors import SimulationError, SweepTruncated, UnknownObject, UnreachablePoint
from tactile_sim.kinematics import COBRA600, inverse_kinematics, probe_tip_position
from tactile_sim.objects import ObjectModel, load_object, object_names
from tactile_sim.sensor import (
    ContactEstimate,
    GroundTruthReader,
    SensorConfig,
    SensorReader,
    SensorReading,
    estimate_contact,
    sweep_contacts,
)
from tactile_sim.trajectory import Trajectory, TrajectoryRecorder

__all__ = [
    "ContourTrace",
    "GroundTruth",
    "PlacementConfig",
    "ProbeScene",
    "ProbeSession",
    "ProbeTarget",
    "ProbingConfig",
    "SamplingPlane",
    "StopReason",
    "SweepResult",
    "SweepSide",
    "SweepTruncated",
    "build_probe_scene",
    "choose_point",
    "probe_object",
    "random_pose",
    "resolve_object",
    "sampling_planes",
    "trace_contour",
]


@dataclass(frozen=True)
class ProbingConfig:
    """The sweep controller's set points, speeds and limits.

    Attributes
    ----------
    approach_speed_m_s : float, m/s
        Speed of the guarded approach towards the surface, until the first touch.
    press_speed_m_s : float, m/s
        Speed of the press after the first touch, until the set point.
    move_speed_m_s : float, m/s
        Peak speed of the short moves between points.
    travel_speed_m_s : float, m/s
        Peak speed of the travel moves between sweep sides and sweeps.
    standoff_m : float, metres
        The approach starts this far outside the predicted surface.
    search_m : float, metres
        The approach gives up (lost contact) this far beyond the predicted surface.
    first_clearance_m, first_search_m : float, metres
        The same for the first point of a sweep, where the surface is known only from
        the experimenter's plan (p on the model).
    clearance_m : float, metres
        Height above the highest point touched so far for travel moves.
    touch_deflection_rad, touch_axial_force_n : float, radians, newtons
        First-touch thresholds of the approach (well above the noise).
    touch_settle_s : float, seconds
        Pause between the first touch and the press.
    backoff_m : float, metres
        The arm backs off this far from the touch (where its momentum carried it) before
        the press.
    press_travel_m : float, metres
        Longest press beyond the first touch.
    press_persist_steps : int
        The set point must hold for this many consecutive timesteps (an impact spike
        of the axial force on a slope does not count).
    press_retries : int
        Presses that still end below the sensor's ``min_normal_force_n`` continue this
        many times, each at a lower speed.
    deflection_trigger_rad : float, radians
        Deflection set point of the press: the stylus tilts this much (0.002 rad moves
        the tip 0.24 mm; a lateral force of 5 mN).
    axial_force_trigger_n : float, newtons
        Axial force set point of the press (a level surface does not tilt the stylus;
        0.1 N sinks the tip about 1 um into the surface).
    settle_s : float, seconds
        Wait after a move before an approach (the stylus swings when the arm accelerates).
    dwell_s : float, seconds
        Wait between the trigger and the reading.
    reading_average_s : float, seconds
        A reading is the mean of the sensor's samples (one per timestep) over this time.
    axial_average_steps : int
        The axial-force thresholds apply to the mean of this many samples (the stiff tip
        contact may switch on and off from one timestep to the next).
    ramp_s : float, seconds
        The approach reaches its speed over this time (a jerk tilts the stylus).
    max_tilt_deg : float, degrees
        A side of a vertical sweep ends where the in-plane normal tilts more than this
        from vertical (the stylus would touch with its shaft).
    extend_on_loss : bool
        When one side of p is truncated, sample the missing points on the other side.
    max_replans : int
        When p was chosen automatically and a sweep still ends with fewer than five
        points, choose another p, at most this many times.
    tool_yaw_rad : float, radians
        Yaw of the flange (and of the deflection axes) during probing.
    """

    approach_speed_m_s: float = 0.006
    press_speed_m_s: float = 0.002
    move_speed_m_s: float = 0.04
    travel_speed_m_s: float = 0.05
    standoff_m: float = 0.3e-3
    search_m: float = 1.5e-3
    first_clearance_m: float = 1.5e-3
    first_search_m: float = 3.0e-3
    clearance_m: float = 3.0e-3
    touch_deflection_rad: float = 5e-4
    touch_axial_force_n: float = 0.01
    touch_settle_s: float = 0.03
    backoff_m: float = 20e-6
    press_travel_m: float = 0.6e-3
    press_persist_steps: int = 4
    press_retries: int = 2
    deflection_trigger_rad: float = 2e-3
    axial_force_trigger_n: float = 0.1
    settle_s: float = 0.03
    dwell_s: float = 0.03
    reading_average_s: float = 0.01
    axial_average_steps: int = 8
    ramp_s: float = 0.01
    max_tilt_deg: float = 75.0
    extend_on_loss: bool = True
    max_replans: int = 3
    tool_yaw_rad: float = 0.0


@dataclass(frozen=True)
class PlacementConfig:
    """Random placement of an object on the table (:func:`random_pose`).

    Attributes
    ----------
    max_offset_m : float, metres
        The object's origin lies uniformly in a disk of this radius around the mount.
    yaw_range_rad : (2,) float, radians
        Rotation about the vertical axis, uniform in this range.
    """

    max_offset_m: float = 0.02
    yaw_range_rad: tuple[float, float] = (-math.pi, math.pi)


_MIN_CURVE_POINTS = 5
"""Fewest points a data curve may have (``recognition.DataCurves`` asks for five)."""


class StopReason(enum.Enum):
    """Why one side of a sweep ended."""

    COMPLETE = "complete"
    LOST_CONTACT = "lost_contact"
    TOO_STEEP = "too_steep"
    UNREACHABLE = "unreachable"
    BLOCKED = "blocked"


@dataclass(frozen=True)
class SamplingPlane:
    """A sampling plane in the world frame.

    Attributes
    ----------
    origin_in_world : (3,) float, metres
        A point of the plane: p (for an outline trace, its first planned point).
    normal_in_world : (3,) float
        Unit plane normal.
    up_in_world : (3,) float
        Unit in-plane direction the first approach comes from (it approaches along
        minus this); vertical planes: +z.
    forward_in_world : (3,) float
        Unit in-plane direction of the "+" side: ``cross(normal, up)``.
    """

    origin_in_world: NDArray[np.float64]
    normal_in_world: NDArray[np.float64]
    up_in_world: NDArray[np.float64]
    forward_in_world: NDArray[np.float64]

    @classmethod
    def through(cls, origin: ArrayLike, forward: ArrayLike, up: ArrayLike) -> SamplingPlane:
        """Returns the plane through ``origin`` spanned by ``forward`` and ``up``."""
        up = np.asarray(up, dtype=np.float64)
        up = up / np.linalg.norm(up)
        forward = np.asarray(forward, dtype=np.float64)
        forward = forward - (forward @ up) * up
        forward = forward / np.linalg.norm(forward)
        return cls(
            origin_in_world=np.asarray(origin, dtype=np.float64),
            normal_in_world=np.cross(up, forward),
            up_in_world=up,
            forward_in_world=forward,
        )

    def distance(self, points: ArrayLike) -> NDArray[np.float64]:
        """Returns the signed distances of points (..., 3) to the plane, metres."""
        return (np.asarray(points) - self.origin_in_world) @ self.normal_in_world


@dataclass(frozen=True)
class SweepSide:
    """One side of a sweep, from p outward.

    Attributes
    ----------
    direction : int
        +1 (along ``forward_in_world``) or -1.
    requested : int
        Points asked for on this side (p excluded).
    acquired : int
        Points sensed.
    stop : StopReason
    message : str
        What stopped it, in words ("" when complete).
    """

    direction: int
    requested: int
    acquired: int
    stop: StopReason
    message: str = ""


@dataclass(frozen=True)
class SweepResult:
    """One sweep: the sensed curve through p in one sampling plane.

    Attributes
    ----------
    plane : SamplingPlane
    points_in_world : (n, 3) float, metres
        Sensed contact points, ordered along ``forward_in_world``.
    normals_in_world : (n, 3) float
        Sensed outward normals.
    tip_centres_in_world : (n, 3) float, metres
        Tip centres from the readings.
    p_index : int
        Index of the point sensed at p.
    sides : tuple of SweepSide
        What happened on each side of p, in the order they ran.
    true_tip_centres_in_world : (n, 3) float, metres
        Ground truth: the simulator's tip centres at the readings.
    true_contact_points_in_world : (n, 3) float, metres
        Ground truth: closest points of the original mesh to the true tip centres.
    stylus_contacts : (n,) int
        Ground truth: contacts of the shaft or housing at each reading (should be 0).
    reading_times_s : (n,) float, seconds
        Simulated time of each point's reading.
    """

    plane: SamplingPlane
    points_in_world: NDArray[np.float64]
    normals_in_world: NDArray[np.float64]
    tip_centres_in_world: NDArray[np.float64]
    p_index: int
    sides: tuple[SweepSide, ...]
    true_tip_centres_in_world: NDArray[np.float64]
    true_contact_points_in_world: NDArray[np.float64]
    stylus_contacts: NDArray[np.int64]
    reading_times_s: NDArray[np.float64] = field(default_factory=lambda: np.empty(0))

    @property
    def truncated(self) -> bool:
        """Returns True if a side stopped early."""
        return any(side.stop is not StopReason.COMPLETE for side in self.sides)

    @property
    def n_points(self) -> int:
        """Returns the number of sensed points."""
        return len(self.points_in_world)


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
        Per curve, closest points of the original mesh to the true tip centres.
    true_tip_centres_in_world : tuple of (n_i, 3) float
        Per curve, the simulator's tip centres at the readings.
    """

    T_world_from_object: NDArray[np.float64]
    point_in_object: NDArray[np.float64]
    point_in_world: NDArray[np.float64]
    normal_in_object: NDArray[np.float64]
    true_contact_points_in_world: tuple[NDArray[np.float64], ...]
    true_tip_centres_in_world: tuple[NDArray[np.float64], ...]


@dataclass(frozen=True)
class ProbeSession:
    """The result of probing one object: three data curves and the ground truth apart.

    Attributes
    ----------
    object_name : str
    curves : DataCurves
        The three sensed curves, world frame, with ``approach`` the direction in which
        the probe approached p (into the object).
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
        return self.sweep.points_in_world @ T[:3, :3].T + T[:3, 3]


# Objects and placement ---------------------------------------------------------------------


@dataclass(frozen=True)
class ProbeTarget:
    """An object to probe.

    Attributes
    ----------
    name : str
    mesh : trimesh.Trimesh
        The original surface, model frame, metres (drawn, and the ground truth).
    parts : ConvexParts
        Its convex collision parts.
    """

    name: str
    mesh: trimesh.Trimesh
    parts: ConvexParts


def resolve_object(obj: Any, *, progress: bool = True) -> ProbeTarget:
    """Returns the name, mesh and collision parts of a catalog name, solid name,
    ObjectModel, Solid or trimesh mesh.

    Raises
    ------
    UnknownObject
        A name that is neither a catalog object nor a solid; lists the known names.
    """
    if isinstance(obj, str):
        if obj in object_names():
            obj = load_object(obj)
        elif obj in solid_names():
            obj = load_solid(obj)
        else:
            raise UnknownObject(obj, (*object_names(), *solid_names()))
    if isinstance(obj, ObjectModel | Solid):
        name, mesh = obj.name, obj.mesh
    elif isinstance(obj, trimesh.Trimesh):
        name, mesh = "object", obj
    else:
        raise TypeError(
            "object must be a catalog or solid name, an ObjectModel, a Solid or a "
            f"trimesh.Trimesh, got {type(obj).__name__}"
        )
    if isinstance(obj, ObjectModel):
        parts = object_parts(obj, progress=progress)
    else:
        convex = True if isinstance(obj, Solid) and obj.convex else None
        parts = convex_decomposition(mesh, name=name, progress=progress, convex=convex)
    return ProbeTarget(name=name, mesh=mesh, parts=parts)


def random_pose(
    rng: np.random.Generator, config: PlacementConfig | None = None
) -> NDArray[np.float64]:
    """Returns a random T_world_from_object: upright on the table near the object mount.

    Parameters
    ----------
    rng : numpy.random.Generator
    config : PlacementConfig or None
        None: the defaults.
    """
    config = config or PlacementConfig()
    yaw = rng.uniform(*config.yaw_range_rad)
    radius = config.max_offset_m * math.sqrt(rng.uniform())
    angle = rng.uniform(-math.pi, math.pi)
    offset = np.array([radius * math.cos(angle), radius * math.sin(angle), 0.0])
    return pose_matrix(rotation_about(2, yaw), _MOUNT_IN_WORLD + offset)


_MOUNT_IN_WORLD = np.array([0.40, 0.0, 0.0])
"""The scene's ``object_mount`` site (``scenes/scene.xml``), axes parallel to the world's."""


@dataclass
class ProbeScene:
    """A compiled scene with one object, ready for sweeps.

    Attributes
    ----------
    physics : dm_control.mjcf.Physics
    target : ProbeTarget
        The object (name, mesh, collision parts).
    T_world_from_object : (4, 4) float
    build_seconds : float, seconds
    """

    physics: Any
    target: ProbeTarget
    T_world_from_object: NDArray[np.float64]
    build_seconds: float
    _tree: Any = field(default=None, repr=False)
    _ray_tree: Any = field(default=None, repr=False)
    _face_normals: Any = field(default=None, repr=False)

    def mesh_tree(self) -> tuple[Any, NDArray[np.float64], NDArray[np.int64]]:
        """Returns a libigl AABB tree of the original mesh (model frame), its vertices (n, 3)
        metres and faces (m, 3), built on first use."""
        if self._tree is None:
            import igl

            vertices = np.ascontiguousarray(self.target.mesh.vertices, dtype=np.float64)
            faces = np.ascontiguousarray(self.target.mesh.faces, dtype=np.int64)
            tree = igl.AABB()
            tree.init(vertices, faces)
            self._tree = (tree, vertices, faces)
        return self._tree

    def face_normals_in_world(self) -> NDArray[np.float64]:
        """Returns the original mesh's unit face normals in the world frame, (m, 3)."""
        if self._face_normals is None:
            R = self.T_world_from_object[:3, :3]
            self._face_normals = np.asarray(self.target.mesh.face_normals) @ R.T
        return self._face_normals

    def first_hits_in_object(
        self, origins_in_object: ArrayLike, directions_in_object: ArrayLike
    ) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
        """Returns the face hit first by each ray (-1: none) and the distance along it,
        metres, for (k, 3) origins and unit directions in the model frame.

        libigl's ray-triangle test has absolute tolerances that miss sub-millimetre
        triangles in metres: the rays are cast on a copy in millimetres.
        """
        if self._ray_tree is None:
            import igl

            _, vertices, faces = self.mesh_tree()
            vertices_mm = vertices * 1e3
            tree = igl.AABB()
            tree.init(vertices_mm, faces)
            self._ray_tree = (tree, vertices_mm, faces)
        tree, vertices_mm, faces = self._ray_tree
        origins = np.ascontiguousarray(origins_in_object, dtype=np.float64).reshape(-1, 3) * 1e3
        directions = np.ascontiguousarray(directions_in_object, dtype=np.float64).reshape(-1, 3)
        hit_faces, distance_mm, _ = tree.intersect_ray_first(
            vertices_mm, faces, origins, directions
        )
        return np.asarray(hit_faces, dtype=np.int64), np.asarray(distance_mm) * 1e-3

    def closest_points_in_world(
        self, points_in_world: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Returns the closest points of the original mesh (world frame) and their
        distances (metres) for (k, 3) world points; libigl AABB, exact point-triangle
        distances."""
        tree, vertices, faces = self.mesh_tree()
        T = self.T_world_from_object
        points = np.asarray(points_in_world, dtype=np.float64).reshape(-1, 3)
        in_object = (points - T[:3, 3]) @ T[:3, :3]
        squared, _, closest = tree.squared_distance(vertices, faces, in_object)
        return closest @ T[:3, :3].T + T[:3, 3], np.sqrt(squared)


def build_probe_scene(
    obj: Any, T_world_from_object: ArrayLike | None = None, *, seed: int = 0, progress=True
) -> ProbeScene:
    """Returns the compiled probing scene with an object placed on the table.

    Parameters
    ----------
    obj : str, ObjectModel, Solid or trimesh.Trimesh
        See :func:`resolve_object`.
    T_world_from_object : (4, 4) float or None
        Object pose; None draws one with :func:`random_pose` from ``seed``.
    seed : int
        Seed of the random pose.
    progress : bool
        Announce cold builds (meshes, hulls) with progress bars.
    """
    start = time.perf_counter()
    target = resolve_object(obj, progress=progress)
    if T_world_from_object is None:
        T = random_pose(np.random.default_rng([seed, 1]))
    else:
        T = np.asarray(T_world_from_object, dtype=np.float64)
        if T.shape != (4, 4) or not np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-6):
            raise ValueError("T_world_from_object must be a (4, 4) rigid transform")
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(T[:3, :3]).reshape(9))
    model = scene.scene_model()
    scene.attach_object(
        model,
        _mjcf_name(target.name),
        [(v, f) for v, f in target.parts.parts],
        visual_mesh=target.mesh,
        position_in_mount=T[:3, 3] - _MOUNT_IN_WORLD,
        quat_wxyz_in_mount=quat,
    )
    physics = scene.build_physics(model)
    return ProbeScene(
        physics=physics,
        target=target,
        T_world_from_object=T,
        build_seconds=time.perf_counter() - start,
    )


def _mjcf_name(name: str) -> str:
    """A valid MJCF model name for an object name."""
    cleaned = "".join(c if c.isalnum() or c in "_-" else "_" for c in name)
    return cleaned if cleaned[:1].isalpha() else f"object_{cleaned}"


# Planning --------------------------------------------------------------------------------


def sampling_planes(
    point_in_world: ArrayLike, first_yaw_rad: float, plane_angle_rad: float, count: int = 3
) -> tuple[SamplingPlane, ...]:
    """Returns ``count`` vertical sampling planes through a point, ``plane_angle_rad`` apart.

    Plane k contains the vertical through the point and the horizontal direction at yaw
    ``first_yaw_rad + k * plane_angle_rad`` (its "+" side).
    """
    planes = []
    for k in range(count):
        yaw = first_yaw_rad + k * plane_angle_rad
        forward = np.array([math.cos(yaw), math.sin(yaw), 0.0])
        planes.append(SamplingPlane.through(point_in_world, forward, (0.0, 0.0, 1.0)))
    return tuple(planes)


def choose_point(
    probe_scene: ProbeScene,
    rng: np.random.Generator,
    *,
    plane_angle_rad: float,
    first_yaw_rad: float,
    half_length_m: float,
    max_slope_deg: float = 35.0,
    max_sweep_slope_deg: float = 60.0,
    candidates: int = 400,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Returns a point p (world frame) on the upward-facing surface and its outward normal.

    Candidates are drawn by area on faces within ``max_slope_deg`` of level; the first
    whose three planned sweeps see, along vertical rays every 0.5 mm out to
    ``half_length_m`` on both sides, a surface no steeper than ``max_sweep_slope_deg``
    and without steps is returned (the best one found when none is clean).

    Raises
    ------
    UnreachablePoint
        No candidate is within reach; names the limit one of them breaks.
    """
    mesh = probe_scene.target.mesh
    T = probe_scene.T_world_from_object
    _, vertices, faces = probe_scene.mesh_tree()
    normals = probe_scene.face_normals_in_world()
    areas = np.asarray(mesh.area_faces)
    level = normals[:, 2] >= math.cos(math.radians(max_slope_deg))
    if not level.any():
        raise SimulationError(
            f"{probe_scene.target.name}: no face within {max_slope_deg} deg of level to probe"
        )
    weights = np.where(level, areas, 0.0)
    faces_drawn = rng.choice(len(faces), size=candidates, p=weights / weights.sum())
    u, v = rng.random((2, candidates))
    swap = u + v > 1.0
    u[swap], v[swap] = 1.0 - u[swap], 1.0 - v[swap]
    tri = vertices[faces[faces_drawn]]
    points_in_object = (
        tri[:, 0] + u[:, None] * (tri[:, 1] - tri[:, 0]) + v[:, None] * (tri[:, 2] - tri[:, 0])
    )
    points = points_in_object @ T[:3, :3].T + T[:3, 3]
    origins = points + COBRA600.probe.tip_radius_m * normals[faces_drawn]
    top = float((vertices @ T[:3, :3].T + T[:3, 3])[:, 2].max()) + 0.01
    # Vertical rays along the three planned sweeps of the candidates, cast in batches
    # until a clean one turns up.
    offsets = np.arange(-half_length_m, half_length_m + 1e-9, 5e-4)
    yaws = first_yaw_rad + plane_angle_rad * np.arange(3)
    forwards = np.column_stack([np.cos(yaws), np.sin(yaws), np.zeros(3)])  # (3, 3)
    down = T[:3, :3].T @ [0.0, 0.0, -1.0]
    cos_limit = math.cos(math.radians(max_sweep_slope_deg))
    score = np.full(candidates, -1.0)
    for batch in np.array_split(np.arange(candidates), max(1, candidates // 50)):
        starts = (
            origins[batch, None, None, :] + offsets[None, None, :, None] * forwards[None, :, None]
        )
        starts[..., 2] = top
        shape = starts.shape[:3]  # (candidates, 3 planes, offsets)
        in_object = (starts.reshape(-1, 3) - T[:3, 3]) @ T[:3, :3]
        hit_faces, hit_t = probe_scene.first_hits_in_object(
            in_object, np.tile(down, (len(in_object), 1))
        )
        hit_faces, hit_t = hit_faces.reshape(shape), hit_t.reshape(shape)
        hit = hit_faces >= 0
        steep = np.where(hit, normals[hit_faces, 2], 0.0) < cos_limit
        heights = np.where(hit, top - np.nan_to_num(hit_t), 0.0)
        steps = np.abs(np.diff(heights, axis=2)).max(axis=(1, 2))
        clean = hit.all(axis=(1, 2)) & ~steep.any(axis=(1, 2)) & (steps < 1.5e-3)
        # Clean candidates first, then those with the fewest steep or missing samples.
        score[batch] = clean * 2.0 + (1.0 - (steep | ~hit).mean(axis=(1, 2)))
        if clean.any():
            break
    unreachable: UnreachablePoint | None = None
    for i in np.argsort(-score, kind="stable"):
        if score[i] < 0:
            break
        try:
            inverse_kinematics(origins[i] + np.array([0.0, 0.0, 0.02]), robot=COBRA600)
        except UnreachablePoint as error:
            unreachable = error
            continue
        return points[i], normals[faces_drawn[i]]
    assert unreachable is not None
    raise UnreachablePoint(
        f"{probe_scene.target.name}: no upward-facing point within the robot's reach; "
        f"e.g. {unreachable}",
        unreachable.limit,
    )


# The controller ----------------------------------------------------------------------------


class _Rig:
    """Drives the arm through joint-space moves and guarded approaches; reads the sensor."""

    def __init__(
        self,
        probe_scene: ProbeScene,
        config: ProbingConfig,
        sensor: SensorConfig,
        rng: np.random.Generator,
        recorder: TrajectoryRecorder | None = None,
    ) -> None:
        physics = probe_scene.physics
        self.physics = physics
        self.model, self.data = physics.model.ptr, physics.data.ptr
        # Steps like mujoco.mj_step(model, data[, nstep]); the recorder samples on the way.
        self._step = mujoco.mj_step if recorder is None else recorder.step
        self.config = config
        self.sensor = sensor
        self.reader = SensorReader(physics, sensor.noise, rng)
        self.dt = float(self.model.opt.timestep)
        actuators = [physics.model.name2id(j, "actuator") for j in scene.ARM_JOINTS]
        first = actuators[0]
        # A slice is faster than an index array in the per-step loops.
        self.actuators = (
            slice(first, first + 4) if actuators == list(range(first, first + 4)) else actuators
        )
        self.q_command = scene.arm_joints(physics)
        self.last_touch_centre = np.zeros(3)
        self.first_contact: NDArray[np.float64] | None = None

    # Low level.
    def _set_ctrl(self, q: NDArray[np.float64]) -> None:
        self.data.ctrl[self.actuators] = q
        self.q_command = q

    def _check(self) -> None:
        scene.raise_on_warnings(self.physics)

    def ik(self, tip_in_world: NDArray[np.float64]) -> NDArray[np.float64]:
        return inverse_kinematics(
            tip_in_world,
            tool_yaw_rad=self.config.tool_yaw_rad,
            robot=self.sensor.robot,
            joints_reference=self.q_command,
        )

    def teleport(self, tip_in_world: NDArray[np.float64]) -> None:
        """Puts the arm at rest with the undeflected tip at a point (no contact there)."""
        q = self.ik(tip_in_world)
        scene.set_arm_joints(self.physics, q)
        self.q_command = q

    def settle(self, seconds: float) -> None:
        n = max(1, round(seconds / self.dt))
        self._step(self.model, self.data, n)
        self._check()

    def move(self, tip_in_world: NDArray[np.float64], speed: float) -> None:
        """Minimum-jerk joint-space move of the undeflected tip to a point."""
        distance = float(np.linalg.norm(np.asarray(tip_in_world) - self.commanded_tip()))
        self._smooth_to(self.ik(tip_in_world), max(1.875 * distance / speed, 0.01))

    def _smooth_to(self, q1: NDArray[np.float64], duration: float) -> None:
        """Minimum-jerk joint-space move of the command to ``q1`` in ``duration`` seconds."""
        q0 = self.q_command.copy()
        n = max(1, round(duration / self.dt))
        tau = np.arange(1, n + 1) / n
        profile = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
        path = q0 + profile[:, None] * (q1 - q0)
        model, data, actuators, step = self.model, self.data, self.actuators, self._step
        for q in path:
            data.ctrl[actuators] = q
            step(model, data)
        self.q_command = np.array(q1, dtype=np.float64)
        self._check()

    def commanded_tip(self) -> NDArray[np.float64]:
        """Returns where the commanded joints put the undeflected tip centre, world."""
        return probe_tip_position(self.q_command, self.sensor.robot)

    def _guarded_line(
        self,
        target: NDArray[np.float64],
        travel: float,
        speed: float,
        deflection_rad: float,
        axial_force_n: float,
        persist_steps: int,
        lead: bool,
    ) -> NDArray[np.float64] | None:
        """Moves the command in a straight joint-space line towards the undeflected tip
        position ``target`` (``travel`` metres away) at ``speed`` after a ramp, until the
        deflection or the axial force reaches its threshold for ``persist_steps`` steps in
        a row. Then holds the arm where the encoders put it when the streak began (they lag
        the state by one step; ``lead`` adds the command increment, holding the arm where
        it was then rather than one step before); returns the triggering reading (7
        values, see SensorReader.raw), or None after the whole travel. The first reading
        with evidence of contact (the touch thresholds) is kept in ``first_contact``."""
        q0 = self.q_command.copy()
        q1 = self.ik(target)
        # Distance covered after each step: a linear speed ramp, then constant speed.
        n_ramp = max(1, round(self.config.ramp_s / self.dt))
        n_total = n_ramp // 2 + math.ceil(travel / (speed * self.dt))
        steps = np.arange(1, n_total + 1)
        covered = np.where(
            steps <= n_ramp,
            0.5 * speed * self.dt * steps**2 / n_ramp,
            speed * self.dt * (steps - 0.5 * n_ramp),
        )
        path = q0 + np.minimum(covered / travel, 1.0)[:, None] * (q1 - q0)
        model, data, actuators, raw = self.model, self.data, self.actuators, self.reader.raw
        step = self._step
        count = 0
        streak_start = q0
        previous = q0
        # The stiff tip contact can chatter (on and off every step) while the stylus, with
        # its inertia, does not: the axial force is judged on a short running mean.
        recent_axial = [0.0] * self.config.axial_average_steps
        touch_deflection, touch_force = (
            self.config.touch_deflection_rad,
            self.config.touch_axial_force_n,
        )
        self.first_contact = None
        for i, q in enumerate(path):
            data.ctrl[actuators] = q
            step(model, data)
            values = raw()
            recent_axial[i % len(recent_axial)] = values[6]
            axial = sum(recent_axial) / len(recent_axial)
            deflection = math.hypot(values[4], values[5])
            if self.first_contact is None and (
                deflection >= touch_deflection or values[6] >= touch_force
            ):
                self.first_contact = values
            if deflection >= deflection_rad or axial >= axial_force_n:
                if count == 0:
                    streak_start = values[:4] + (q - previous) if lead else values[:4].copy()
                count += 1
                if count >= persist_steps:
                    # Hold where the condition first held (a stiff contact would otherwise
                    # build force while the streak is confirmed).
                    self._set_ctrl(streak_start)
                    self._check()
                    return values
            else:
                count = 0
            previous = q
        self.q_command = q1
        self._check()
        return None

    def approach(
        self, start: NDArray[np.float64], direction: NDArray[np.float64], travel: float
    ) -> ContactEstimate | None:
        """Guarded approach from ``start`` along ``direction``; returns the sensed contact,
        or None when nothing was touched within ``travel`` metres.

        Two phases: at ``approach_speed_m_s`` until the first touch, then, from where the
        arm stopped, a press at ``press_speed_m_s`` until the deflection or the axial
        force reaches its set point (steadily, not in an impact spike). The arm holds
        there, the stylus settles for ``dwell_s``, the sensors are read.
        """
        config = self.config
        touched = self._guarded_line(
            start + travel * direction,
            travel,
            config.approach_speed_m_s,
            config.touch_deflection_rad,
            config.touch_axial_force_n,
            1,
            lead=False,
        )
        if touched is None:
            return None
        # Back off from the impact (the arm overshoots the touch point), then press slowly.
        touch_tip = self.commanded_tip()
        here = touch_tip - config.backoff_m * direction
        self._smooth_to(self.ik(here), 2.0 * config.ramp_s)
        self.settle(config.touch_settle_s)
        touch_centre = probe_tip_position(touched[:4], self.sensor.robot, touched[4:6])
        travel = config.backoff_m + config.press_travel_m
        for attempt in range(1 + config.press_retries):
            start_tip = self.commanded_tip()
            pressed = self._guarded_line(
                start_tip + travel * direction,
                travel,
                config.press_speed_m_s / (1 + attempt),
                config.deflection_trigger_rad,
                config.axial_force_trigger_n,
                config.press_persist_steps,
                lead=False,
            )
            if pressed is None:
                self._set_ctrl(self.q_command)
            if attempt == 0 and self.first_contact is not None:
                # The slide starts where the slow press met the surface again.
                values = self.first_contact
                touch_centre = probe_tip_position(values[:4], self.sensor.robot, values[4:6])
            self.last_touch_centre = touch_centre
            self.settle(config.dwell_s)
            estimate = estimate_contact(
                self._averaged_reading(),
                self.sensor,
                fallback_normal=-direction,
                slid_from_in_world=touch_centre,
            )
            # An impact spike can stop the press before the set point: press on, slower.
            if estimate.normal_from_force or pressed is None:
                break
            travel = config.press_travel_m
        return estimate

    def _averaged_reading(self) -> SensorReading:
        """Returns the mean of the readings over the next ``reading_average_s`` (the sensor
        samples every timestep; the mean smooths contact chatter and noise)."""
        n = max(1, round(self.config.reading_average_s / self.dt))
        total = np.zeros(7)
        for _ in range(n):
            self._step(self.model, self.data)
            total += self.reader.raw()
        self._check()
        mean = total / n
        return SensorReading(
            time_s=float(self.data.time),
            joints=mean[:4],
            deflection_rad=mean[4:6],
            axial_force_n=float(mean[6]),
        )


@dataclass
class _Sample:
    """One sensed point: the estimate, the press's slide (sensed), and the ground truth."""

    estimate: ContactEstimate
    slide: NDArray[np.float64]
    true_tip: NDArray[np.float64]
    stylus_contacts: int


def _in_plane(vector: NDArray[np.float64], plane: SamplingPlane) -> NDArray[np.float64] | None:
    """Unit projection of a vector into the plane, None if it is (nearly) normal to it."""
    projected = vector - (vector @ plane.normal_in_world) * plane.normal_in_world
    norm = float(np.linalg.norm(projected))
    return None if norm < 1e-6 else projected / norm


def _rotate_in_plane(vector, plane: SamplingPlane, angle: float) -> NDArray[np.float64]:
    """Rotates an in-plane vector about the plane normal by ``angle`` radians."""
    n = plane.normal_in_world
    return vector * math.cos(angle) + np.cross(n, vector) * math.sin(angle)


def _signed_angle(a, b, plane: SamplingPlane) -> float:
    """Signed angle from in-plane vector a to b about the plane normal."""
    return math.atan2(float(np.cross(a, b) @ plane.normal_in_world), float(a @ b))


class _SweepRunner:
    """Runs the touch-probe cycle along one sampling plane."""

    def __init__(self, rig: _Rig, config: ProbingConfig, spacing_m: float, max_tilt_deg):
        self.rig = rig
        self.config = config
        self.spacing = spacing_m
        self.max_tilt = None if max_tilt_deg is None else math.radians(max_tilt_deg)
        self.highest_z = -math.inf
        self.truth = GroundTruthReader(rig.physics)

    def _sample(self, estimate: ContactEstimate) -> _Sample:
        truth = self.truth.read()
        self.highest_z = max(self.highest_z, float(estimate.tip_centre_in_world[2]))
        slide = estimate.tip_centre_in_world - self.rig.last_touch_centre
        return _Sample(estimate, slide, truth.tip_centre_in_world, truth.stylus_contacts)

    def first(
        self,
        plane: SamplingPlane,
        line_point: NDArray[np.float64],
        clearance: float,
        search: float,
        from_current: bool = False,
    ) -> _Sample:
        """Approaches along -up the line through ``line_point`` (where the tip centre
        should touch), from ``clearance`` outside it."""
        start = line_point + clearance * plane.up_in_world
        self.highest_z = max(self.highest_z, float(start[2]))
        if from_current:
            self.travel_to(start)
        else:
            self.rig.teleport(start)
            self.rig.settle(self.config.settle_s)
        estimate = self.rig.approach(start, -plane.up_in_world, clearance + search)
        if estimate is None:
            raise SimulationError(
                f"no surface found within {(clearance + search) * 1e3:.1f} mm of the planned "
                f"point {np.round(plane.origin_in_world, 4).tolist()} m (the tip centre was "
                f"to touch at {np.round(line_point, 4).tolist()} m)"
            )
        return self._sample(estimate)

    def side(
        self, plane: SamplingPlane, history: list[_Sample], direction: int, count: int
    ) -> tuple[list[_Sample], SweepSide]:
        """Samples up to ``count`` points from the last of ``history`` in ``direction``."""
        config, rig = self.config, self.rig
        samples: list[_Sample] = []
        last = history[-1]
        up = _in_plane(last.estimate.normal_in_world, plane)
        if up is None:
            up = plane.up_in_world
        tangent = direction * np.cross(plane.normal_in_world, up)
        turn = 0.0  # change of the normal's direction per point, radians
        if len(history) >= 2:
            previous = _in_plane(history[-2].estimate.normal_in_world, plane)
            if previous is not None:
                turn = _signed_angle(previous, up, plane)
        e = plane.normal_in_world
        radius = rig.sensor.robot.probe.tip_radius_m
        for _ in range(count):
            # Where the last approach line met the surface: the sensed tip centre less the
            # slide of the press (readings before and after it).
            line = last.estimate.tip_centre_in_world - last.slide
            # Predict along the chord: half the expected turn of the tangent.
            chord = _rotate_in_plane(tangent, plane, 0.5 * turn)
            predicted = line + self.spacing * chord
            predicted_up = _rotate_in_plane(up, plane, turn)
            start = predicted + config.standoff_m * predicted_up
            # Aim the approach line off the plane so that the contact lands in it: the tip
            # will slide about as it did last time, and the contact lies a tip radius from
            # the centre along the normal.
            aim = radius * float(last.estimate.normal_in_world @ e) - float(last.slide @ e)
            start = start + (aim - plane.distance(start)) * e
            try:
                rig.move(start, config.move_speed_m_s)
                rig.settle(config.settle_s)
                estimate = rig.approach(start, -predicted_up, config.standoff_m + config.search_m)
            except UnreachablePoint as error:
                return samples, SweepSide(
                    direction, count, len(samples), StopReason.UNREACHABLE, str(error)
                )
            if estimate is None:
                return samples, SweepSide(
                    direction,
                    count,
                    len(samples),
                    StopReason.LOST_CONTACT,
                    f"lost contact after {len(samples)} of {count} points on the "
                    f"{'+' if direction > 0 else '-'} side: no surface within "
                    f"{config.search_m * 1e3:.1f} mm beyond the predicted point (an edge)",
                )
            sample = self._sample(estimate)
            new_up = _in_plane(estimate.normal_in_world, plane)
            if new_up is None:
                new_up = predicted_up
            tilt = _signed_angle(plane.up_in_world, new_up, plane)
            if self.max_tilt is not None and abs(tilt) > self.max_tilt:
                return samples, SweepSide(
                    direction,
                    count,
                    len(samples),
                    StopReason.TOO_STEEP,
                    f"surface too steep after {len(samples)} of {count} points on the "
                    f"{'+' if direction > 0 else '-'} side: normal {math.degrees(tilt):.0f} deg"
                    f" from vertical, limit {math.degrees(self.max_tilt):.0f} deg",
                )
            turn = _signed_angle(up, new_up, plane)
            tangent = _rotate_in_plane(tangent, plane, turn)
            up = new_up
            samples.append(sample)
            last = sample
        return samples, SweepSide(direction, count, len(samples), StopReason.COMPLETE)

    def _travel_height(self) -> float:
        return self.highest_z + self.config.clearance_m

    def retreat(self) -> None:
        """Moves straight up from the current point to the travel height."""
        here = self.rig.commanded_tip()
        up = here.copy()
        up[2] = max(self._travel_height(), here[2] + self.config.clearance_m)
        self.rig.move(up, self.config.travel_speed_m_s)

    def travel_to(self, target: NDArray[np.float64]) -> None:
        """Moves at the travel height over ``target``, then down to it, and settles."""
        here = self.rig.commanded_tip()
        height = max(self._travel_height(), here[2], target[2])
        if here[2] < height - 1e-6:
            self.rig.move(np.array([here[0], here[1], height]), self.config.travel_speed_m_s)
        self.rig.move(np.array([target[0], target[1], height]), self.config.travel_speed_m_s)
        self.rig.move(target, self.config.travel_speed_m_s)
        self.rig.settle(self.config.settle_s)


def _sweep_result(
    probe_scene: ProbeScene,
    plane: SamplingPlane,
    samples: list[_Sample],
    p_index: int,
    sides: Sequence[SweepSide],
    sensor: SensorConfig,
) -> SweepResult:
    """The sweep's points (refined with its path) and ground truth."""
    centres = np.array([s.estimate.tip_centre_in_world for s in samples])
    points, normals = sweep_contacts(
        centres, np.array([s.estimate.normal_in_world for s in samples]), sensor
    )
    true_tips = np.array([s.true_tip for s in samples])
    true_contacts, _ = probe_scene.closest_points_in_world(true_tips)
    return SweepResult(
        plane=plane,
        points_in_world=points,
        normals_in_world=normals,
        tip_centres_in_world=centres,
        p_index=p_index,
        sides=tuple(sides),
        true_tip_centres_in_world=true_tips,
        true_contact_points_in_world=true_contacts,
        stylus_contacts=np.array([s.stylus_contacts for s in samples], dtype=np.int64),
        reading_times_s=np.array([s.estimate.reading.time_s for s in samples]),
    )


def _sweep(
    runner: _SweepRunner,
    probe_scene: ProbeScene,
    plane: SamplingPlane,
    line_point: NDArray[np.float64],
    n_points: int,
    first: bool,
) -> SweepResult:
    """One full sweep through p (the plane origin) with p in the middle; the first
    approach comes down the line through ``line_point`` (corrected in place by the first
    sweep)."""
    config = runner.config
    p_sample = runner.first(
        plane,
        line_point,
        config.first_clearance_m,
        config.first_search_m,
        from_current=not first,
    )
    if first:
        # The press slides the tip off the planned point: touch again, the approach line
        # moved by the horizontal miss, so the sensed p lands on the planned one (the
        # later sweeps come down the corrected line directly).
        miss = plane.origin_in_world - p_sample.estimate.point_in_world
        miss[2] = 0.0
        line_point += miss
        runner.retreat()
        p_sample = runner.first(
            plane,
            line_point,
            config.first_clearance_m,
            config.first_search_m,
            from_current=True,
        )
    n_plus = (n_points - 1) // 2
    n_minus = n_points - 1 - n_plus
    plus, plus_side = runner.side(plane, [p_sample], +1, n_plus)
    missing = n_plus - len(plus)
    sides = [plus_side]
    minus: list[_Sample] = []
    if n_minus + (missing if config.extend_on_loss else 0) > 0:
        runner.retreat()
        # Back over p, then down to p's approach start for the other side.
        start = p_sample.estimate.tip_centre_in_world + config.standoff_m * plane.up_in_world
        runner.travel_to(start)
        count = n_minus + (missing if config.extend_on_loss else 0)
        minus, minus_side = runner.side(plane, [*plus[:1], p_sample], -1, count)
        sides.append(minus_side)
    samples = [*minus[::-1], p_sample, *plus]
    runner.retreat()
    return _sweep_result(probe_scene, plane, samples, len(minus), sides, runner.rig.sensor)


def probe_object(
    obj: Any,
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
    SimulationError
        MuJoCo became unstable, or no surface was found at p.
    """
    wall_start = time.perf_counter()
    config = config or ProbingConfig()
    sensor = sensor or SensorConfig()
    if n_points < 5:
        raise ValueError(f"n_points must be >= 5 (a data curve needs five), got {n_points}")
    if not 0 < spacing_m < 0.02:
        raise ValueError(f"spacing_m must lie in (0, 0.02) m, got {spacing_m}")
    if not 5.0 <= plane_angle_deg <= 85.0:
        raise ValueError(f"plane_angle_deg must lie in [5, 85] deg, got {plane_angle_deg}")
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
            p_world, normal_world = _snap_point(probe_scene, point)
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
        rig = _Rig(probe_scene, config, sensor, rng, recorder)
        runner = _SweepRunner(rig, config, spacing_m, config.max_tilt_deg)
        sweeps = tuple(
            _sweep(runner, probe_scene, plane, line_point, n_points, first=(k == 0))
            for k, plane in enumerate(planes)
        )
        if all(sweep.n_points >= _MIN_CURVE_POINTS for sweep in sweeps):
            break
    else:
        reasons = "; ".join(
            f"sweep {k}: {side.message}"
            for k, sweep in enumerate(sweeps)
            for side in sweep.sides
            if side.stop is not StopReason.COMPLETE
        )
        tried = f" ({attempts} points tried)" if attempts > 1 else ""
        raise SweepTruncated(
            f"{probe_scene.target.name}: a sweep through p kept fewer than "
            f"{_MIN_CURVE_POINTS} points{tried}: {reasons}"
        )
    curves = DataCurves(
        curves=tuple(s.points_in_world for s in sweeps), approach=np.array([0.0, 0.0, -1.0])
    )
    T_object_from_world = np.linalg.inv(T)
    truth = GroundTruth(
        T_world_from_object=T,
        point_in_object=T_object_from_world[:3, :3] @ p_world + T_object_from_world[:3, 3],
        point_in_world=p_world,
        normal_in_object=T_object_from_world[:3, :3] @ normal_world,
        true_contact_points_in_world=tuple(s.true_contact_points_in_world for s in sweeps),
        true_tip_centres_in_world=tuple(s.true_tip_centres_in_world for s in sweeps),
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
    )


def _snap_point(
    probe_scene: ProbeScene, point_in_object: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """p snapped onto the mesh (world frame) and the mesh's outward normal there."""
    p = np.asarray(point_in_object, dtype=np.float64)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ValueError(f"point must be a finite (3,) array in the model frame, got {p}")
    tree, vertices, faces = probe_scene.mesh_tree()
    _, face, closest = tree.squared_distance(vertices, faces, p[None])
    T = probe_scene.T_world_from_object
    normal = probe_scene.face_normals_in_world()[int(face[0])]
    if normal[2] < 0.2:
        raise ValueError(
            f"point {p.round(4).tolist()} m is not on the upward-facing surface: the normal "
            f"there is {normal.round(2).tolist()} in the world (z component must exceed 0.2)"
        )
    return T[:3, :3] @ closest[0] + T[:3, 3], normal


def trace_contour(
    obj: Any,
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
    vertices_world = np.asarray(probe_scene.target.mesh.vertices) @ T[:3, :3].T + T[:3, 3]
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
    rig = _Rig(probe_scene, config, sensor, rng)
    runner = _SweepRunner(rig, config, spacing_m, None)
    first = runner.first(
        plane, wall + radius * outward, config.first_clearance_m, config.first_search_m
    )
    samples, side = runner.side(plane, [first], +1, n_points - 1)
    samples = [first, *samples]
    sweep = _sweep_result(probe_scene, plane, samples, 0, (side,), sensor)
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
