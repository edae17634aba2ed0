"""The compiled probing scene with one object, and queries on the object's original mesh.

The experimenter's plan, the tip's contact and the ground truth query the mesh (closest
points and first ray hits by :class:`~recognition.surfaces.distance.MeshDistance`, built
on first use; face normals); the sensor never does.
"""

from __future__ import annotations

import hashlib
import time
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.rigid import apply_pose
from recognition.surfaces.distance import MeshDistance
from tactile_sim import scene
from tactile_sim.objects.cache import generated_dir, read_npz, write_npz_atomic
from tactile_sim.probing.placement import (
    MOUNT_IN_WORLD,
    ObjectLike,
    ProbeTarget,
    resolve_object,
    table_pose,
)

__all__ = [
    "ProbeScene",
    "build_probe_scene",
]


@dataclass
class ProbeScene:
    """A compiled scene with one object, ready for sweeps.

    Attributes
    ----------
    physics : dm_control.mujoco.Physics
        The compiled scene (:func:`tactile_sim.scene.physics_of`).
    target : ProbeTarget
        The object (name, mesh, collision parts).
    T_world_from_object : (4, 4) float
    build_seconds : float, seconds
    tip_contact : bool
        The tip meets the object's own mesh through the tip's contact box
        (:mod:`tactile_sim.probing.tip_contact`); False: the object's convex parts.
    """

    physics: Any
    target: ProbeTarget
    T_world_from_object: NDArray[np.float64]
    build_seconds: float
    tip_contact: bool = True
    _mesh_distance: MeshDistance | None = field(default=None, repr=False)
    _face_normals: Any = field(default=None, repr=False)

    @property
    def mesh_distance(self) -> MeshDistance:
        """Exact closest points on the original mesh (model frame; built on first use)."""
        if self._mesh_distance is None:
            self._mesh_distance = MeshDistance(self.target.mesh.vertices, self.target.mesh.faces)
        return self._mesh_distance

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
        metres, for (k, 3) origins and unit directions in the model frame."""
        return self.mesh_distance.first_hits(origins_in_object, directions_in_object)

    def sphere_rests_in_world(
        self, starts_in_world: ArrayLike, radius_m: float, floor_z_m: float = 0.0
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
        """Returns where a sphere of radius ``radius_m`` lowered vertically from each start
        (k, 3) first touches the original mesh: its centre (k, 3) and the unit contact
        normal (k, 3), world frame, and whether it touched before its centre came down to
        ``floor_z_m + radius_m`` (the table). Sphere tracing on exact distances: every
        step lowers the sphere by its clearance, so it never passes through the surface;
        it starts two radii above where a vertical ray from the start meets the mesh, if
        it is clear of the mesh there, else at the start (which must be clear).
        """
        centres = np.array(starts_in_world, dtype=np.float64).reshape(-1, 3)
        lowest = floor_z_m + radius_m
        T = self.T_world_from_object
        down = np.tile(T[:3, :3].T @ [0.0, 0.0, -1.0], (len(centres), 1))
        hit_faces, hit_t = self.first_hits_in_object((centres - T[:3, 3]) @ T[:3, :3], down)
        # start two radii above the ray's hit where the sphere is clear of the mesh there
        # (every point between the start and the hit is outside; on slopes steeper than
        # 60 degrees the sphere would cut the surface there: start from the start)
        hit = np.flatnonzero(hit_faces >= 0)
        lower = centres[hit].copy()
        lower[:, 2] = np.minimum(lower[:, 2], lower[:, 2] - hit_t[hit] + 2 * radius_m)
        clear = self.closest_points_in_world(lower)[1] >= radius_m
        centres[hit[clear]] = lower[clear]
        active = np.ones(len(centres), bool)
        closest = np.zeros_like(centres)
        for _ in range(200):
            if not active.any():
                break
            q, d = self.closest_points_in_world(centres[active])
            closest[active] = q
            clearance = d - radius_m
            done = clearance < 1e-6
            rows = np.flatnonzero(active)
            centres[rows[~done], 2] -= clearance[~done]
            low = centres[rows, 2] <= lowest
            centres[rows[low], 2] = lowest
            active[rows[done | low]] = False
        normals = centres - closest
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
        touched = centres[:, 2] > lowest + 1e-9
        return centres, normals, touched

    def closest_points_in_world(
        self, points_in_world: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Returns the closest points of the original mesh (world frame) and their
        distances (metres) for (k, 3) world points; exact point-triangle distances."""
        T = self.T_world_from_object
        points = np.asarray(points_in_world, dtype=np.float64).reshape(-1, 3)
        distance, closest, _ = self.mesh_distance.closest((points - T[:3, 3]) @ T[:3, :3])
        return apply_pose(T, closest), distance


def build_probe_scene(
    obj: ObjectLike,
    T_world_from_object: ArrayLike | None = None,
    *,
    seed: int = 0,
    progress: bool = True,
    tip_contact: bool = True,
) -> ProbeScene:
    """Returns the compiled probing scene with an object placed on the table.

    Parameters
    ----------
    obj : str, ObjectModel, Solid or trimesh.Trimesh
        See :func:`resolve_object`.
    T_world_from_object : (4, 4) float or None
        Object pose; None draws one with :func:`table_pose` from ``seed``.
    seed : int
        Seed of the random pose.
    progress : bool
        Announce cold builds (meshes, hulls) with progress bars.
    tip_contact : bool
        The tip meets the object's own mesh (:mod:`tactile_sim.probing.tip_contact`);
        False: the tip collides with the object's convex parts, as the rest of the probe.
    """
    start = time.perf_counter()
    target = resolve_object(obj, progress=progress)
    if T_world_from_object is None:
        T = table_pose(target, seed)
    else:
        T = np.asarray(T_world_from_object, dtype=np.float64)
        if T.shape != (4, 4) or not np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-6):
            raise ValueError("T_world_from_object must be a (4, 4) rigid transform")
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(T[:3, :3]).reshape(9))
    name = _mjcf_name(target.name)
    physics = scene.physics_of(_compiled_scene(target, name, tip_contact))
    # The object is welded to the world: its pose is its body's place under the mount.
    model = physics.model.ptr
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"{name}/object")
    mount_pos, mount_quat = model.body_pos[body].copy(), model.body_quat[body].copy()
    offset = np.zeros(3)
    mujoco.mju_rotVecQuat(offset, T[:3, 3] - MOUNT_IN_WORLD, mount_quat)
    model.body_pos[body] = mount_pos + offset
    mujoco.mju_mulQuat(model.body_quat[body], mount_quat, quat)
    scene.step(physics, 0)
    return ProbeScene(
        physics=physics,
        target=target,
        T_world_from_object=T,
        build_seconds=time.perf_counter() - start,
        tip_contact=tip_contact,
    )


#: Version of the compiled-scene cache entries; another version is compiled again.
SCENE_CACHE_FORMAT = 1


def _compiled_scene(target: ProbeTarget, name: str, tip_contact: bool) -> mujoco.MjModel:
    """The compiled scene with the object at the mount in its model pose, from the cache
    (keyed by the scene files, MuJoCo's version, the object's parts and drawn mesh), else
    compiled and cached (about 0.5 s; checksummed, written atomically)."""
    drawn = target.drawn_mesh
    digest = hashlib.sha256(
        repr((SCENE_CACHE_FORMAT, mujoco.__version__, name, tip_contact)).encode()
    )
    for path in sorted(scene.SCENES_DIR.glob("*.xml")):
        digest.update(path.read_bytes())
    for vertices, faces in (*target.parts.parts, (drawn.vertices, drawn.faces)):
        digest.update(np.ascontiguousarray(vertices, dtype=np.float64).tobytes())
        digest.update(np.ascontiguousarray(faces, dtype=np.int64).tobytes())
    key = digest.hexdigest()[:24]
    path = generated_dir("scenes") / f"{name}-{key}.npz"
    cached = read_npz(path, ("mjb",))
    if cached is not None:
        return mujoco.MjModel.from_binary_path(
            "scene.mjb", assets={"scene.mjb": cached[0]["mjb"].tobytes()}
        )
    mjcf_model = scene.scene_model()
    scene.attach_object(
        mjcf_model,
        name,
        [(v, f) for v, f in target.parts.parts],
        visual_mesh=drawn,
        tip_collides=not tip_contact,
    )
    if tip_contact:
        scene.add_tip_contact(mjcf_model)
    model = scene.build_physics(mjcf_model).model.ptr
    buffer = np.empty(mujoco.mj_sizeModel(model), dtype=np.uint8)
    mujoco.mj_saveModel(model, None, buffer)
    write_npz_atomic(path, {"mjb": buffer}, {"key": key})
    return model


def _mjcf_name(name: str) -> str:
    """A valid MJCF model name for an object name."""
    cleaned = "".join(c if c.isalnum() or c in "_-" else "_" for c in name)
    return cleaned if cleaned[:1].isalpha() else f"object_{cleaned}"
