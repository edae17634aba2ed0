"""The experimenter's plan: the point p to probe and the vertical sampling planes through it.

p is chosen on the object's upward-facing surface where the three planned sweeps fit
(:func:`choose_point`), or a given point is snapped onto the mesh (:func:`snap_point`);
both read the original mesh, as an experimenter would, never the sensor.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.rigid import apply_pose
from tactile_sim.errors import SimulationError, UnreachablePoint
from tactile_sim.kinematics import COBRA600, inverse_kinematics
from tactile_sim.probing.probe_scene import ProbeScene

__all__ = [
    "SamplingPlane",
    "choose_point",
    "sampling_planes",
    "snap_point",
    "sweeps_fit",
]


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
    max_contact_tilt_deg: float = 60.0,
    candidates: int = 400,
    dry_runs_per_batch: int = 2,
    min_fit: float = 0.95,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Returns a point p (world frame) on the upward-facing surface and its outward normal.

    Candidates are drawn by area on faces within ``max_slope_deg`` of level; the first
    whose three planned sweeps see, along vertical rays every 1 mm out to
    ``half_length_m`` on both sides, a surface no steeper than ``max_sweep_slope_deg``
    and without steps, and where the tip lowered onto the planned points every 0.6 mm
    rests on a surface whose normal, seen in the sampling plane, is within
    ``max_contact_tilt_deg`` of vertical (:func:`sweeps_fit`: a narrow crest passes the
    first test and not this one; the stylus senses steep slopes poorly), is returned; the
    best one found when none is clean.

    Raises
    ------
    UnreachablePoint
        No candidate is within reach; names the limit one of them breaks.
    """
    mesh = probe_scene.target.mesh
    T = probe_scene.T_world_from_object
    vertices, faces = probe_scene.mesh_distance.vertices, probe_scene.mesh_distance.faces
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
    points = apply_pose(T, points_in_object)
    origins = points + COBRA600.probe.tip_radius_m * normals[faces_drawn]
    top = float(apply_pose(T, vertices)[:, 2].max()) + 0.01
    # Vertical rays along the three planned sweeps of the candidates, cast in batches
    # until a clean one turns up.
    offsets = np.arange(-half_length_m, half_length_m + 1e-9, 1e-3)
    yaws = first_yaw_rad + plane_angle_rad * np.arange(3)
    forwards = np.column_stack([np.cos(yaws), np.sin(yaws), np.zeros(3)])  # (3, 3)
    down = T[:3, :3].T @ [0.0, 0.0, -1.0]
    cos_limit = math.cos(math.radians(max_sweep_slope_deg))
    score = np.full(candidates, -1.0)
    unreachable: UnreachablePoint | None = None
    fallback: tuple[float, float, int] | None = None  # (score, fit, candidate)
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
        # The best few of this batch in order: the first reachable one whose contacts a
        # sweep can take is p.
        for i in batch[np.argsort(-score[batch], kind="stable")][:dry_runs_per_batch]:
            try:
                inverse_kinematics(origins[i] + np.array([0.0, 0.0, 0.02]), robot=COBRA600)
            except UnreachablePoint as error:
                unreachable = error
                continue
            fit = sweeps_fit(
                probe_scene, points[i], yaws, half_length_m, max_contact_tilt_deg, top_z_m=top
            )
            if fit >= min_fit and score[i] >= 2.0:
                return points[i], normals[faces_drawn[i]]
            if fallback is None or (fit, score[i]) > fallback[:2]:
                fallback = (fit, float(score[i]), int(i))
    if fallback is not None:
        return points[fallback[2]], normals[faces_drawn[fallback[2]]]
    assert unreachable is not None
    raise UnreachablePoint(
        f"{probe_scene.target.name}: no upward-facing point within the robot's reach; "
        f"e.g. {unreachable}",
        unreachable.limit,
    )


def sweeps_fit(
    probe_scene: ProbeScene,
    point_in_world: NDArray[np.float64],
    yaws_rad: NDArray[np.float64],
    half_length_m: float,
    max_slope_deg: float,
    *,
    spacing_m: float = 0.6e-3,
    max_turn_deg: float = 20.0,
    top_z_m: float | None = None,
) -> float:
    """Returns the fraction of planned tip contacts of three sweeps that a sweep can take.

    Along each sweep's horizontal direction (yaw), every ``spacing_m`` out to
    ``half_length_m`` on both sides of p, the tip (radius of the Cobra's probe) is lowered
    vertically onto the mesh (:meth:`ProbeScene.sphere_rests_in_world`); a contact counts
    when it is on the object, its normal, projected into the sampling plane, is within
    ``max_slope_deg`` of vertical, and the normal turns by less than ``max_turn_deg`` to
    its neighbours' (more is a crease or an edge, where the tip touches two sides at once
    or slips off).
    """
    radius = COBRA600.probe.tip_radius_m
    offsets = np.arange(-half_length_m, half_length_m + 1e-9, spacing_m)
    forwards = np.column_stack([np.cos(yaws_rad), np.sin(yaws_rad), np.zeros(len(yaws_rad))])
    starts = point_in_world + offsets[None, :, None] * forwards[:, None, :]
    top = float(point_in_world[2]) + 0.02 if top_z_m is None else top_z_m
    starts[..., 2] = top + radius
    _, contact_normals, touched = probe_scene.sphere_rests_in_world(starts.reshape(-1, 3), radius)
    plane_normals = np.column_stack([-forwards[:, 1], forwards[:, 0], np.zeros(len(yaws_rad))])
    across = np.einsum("pki,pi->pk", contact_normals.reshape(*starts.shape), plane_normals)
    in_plane = contact_normals.reshape(*starts.shape) - across[..., None] * plane_normals[:, None]
    length = np.linalg.norm(in_plane, axis=2)
    cos_tilt = in_plane[..., 2] / np.maximum(length, 1e-12)
    ok = touched.reshape(starts.shape[:2]) & (cos_tilt >= math.cos(math.radians(max_slope_deg)))
    normals = contact_normals.reshape(*starts.shape)
    smooth = np.einsum("pki,pki->pk", normals[:, 1:], normals[:, :-1]) >= math.cos(
        math.radians(max_turn_deg)
    )
    ok[:, 1:] &= smooth
    ok[:, :-1] &= smooth
    return float(ok.mean())


def snap_point(
    probe_scene: ProbeScene, point_in_object: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Returns p snapped onto the mesh (world frame, metres) and the mesh's outward normal
    there (world frame).

    Raises
    ------
    ValueError
        ``point_in_object`` is not a finite (3,) point, or the surface there does not face
        upward.
    """
    p = np.asarray(point_in_object, dtype=np.float64)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ValueError(f"point must be a finite (3,) array in the model frame, got {p}")
    _, closest, face = probe_scene.mesh_distance.closest(p[None])
    T = probe_scene.T_world_from_object
    normal = probe_scene.face_normals_in_world()[int(face[0])]
    if normal[2] < 0.2:
        raise ValueError(
            f"point {p.round(4).tolist()} m is not on the upward-facing surface: the normal "
            f"there is {normal.round(2).tolist()} in the world (z component must exceed 0.2)"
        )
    return T[:3, :3] @ closest[0] + T[:3, 3], normal
