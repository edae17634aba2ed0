"""The compiled probing scene with one object, and queries on the object's original mesh.

The experimenter's plan and the ground truth query the mesh (closest points, first ray
hits, face normals) with libigl AABB trees, built on first use; the sensor never does.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.rigid import apply_pose
from tactile_sim import scene
from tactile_sim.probing.placement import (
    MOUNT_IN_WORLD,
    ObjectLike,
    ProbeTarget,
    random_pose,
    resolve_object,
)

if TYPE_CHECKING:
    from dm_control import mjcf

__all__ = [
    "ProbeScene",
    "build_probe_scene",
]


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
    tip_contact : bool
        The tip meets the object's own mesh through the tip's contact box
        (:mod:`tactile_sim.probing.tip_contact`); False: the object's convex parts.
    """

    physics: mjcf.Physics
    target: ProbeTarget
    T_world_from_object: NDArray[np.float64]
    build_seconds: float
    tip_contact: bool = True
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
        return apply_pose(T, closest), np.sqrt(squared)


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
        Object pose; None draws one with :func:`random_pose` from ``seed``.
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
        position_in_mount=T[:3, 3] - MOUNT_IN_WORLD,
        quat_wxyz_in_mount=quat,
        tip_collides=not tip_contact,
    )
    if tip_contact:
        scene.add_tip_contact(model)
    physics = scene.build_physics(model)
    return ProbeScene(
        physics=physics,
        target=target,
        T_world_from_object=T,
        build_seconds=time.perf_counter() - start,
        tip_contact=tip_contact,
    )


def _mjcf_name(name: str) -> str:
    """A valid MJCF model name for an object name."""
    cleaned = "".join(c if c.isalnum() or c in "_-" else "_" for c in name)
    return cleaned if cleaned[:1].isalpha() else f"object_{cleaned}"
