"""The object to probe and its place on the table: mesh and collision parts, a random pose.

:func:`resolve_object` turns a catalog name, a solid name or a mesh into a
:class:`ProbeTarget` (the original surface and its convex collision parts);
:func:`random_pose` draws an upright pose near the scene's object mount.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import trimesh
from numpy.typing import NDArray

from recognition.rigid import pose_matrix, rotation_about
from recognition.surfaces.mesh_files import read_mesh
from recognition.surfaces.mesh_repair import MeshReport, prepare_mesh
from tactile_sim.collision import (
    ConvexParts,
    Solid,
    convex_decomposition,
    load_solid,
    object_parts,
    solid_names,
)
from tactile_sim.collision.tiling import surface_tiles
from tactile_sim.errors import UnknownObject
from tactile_sim.objects import ObjectModel, load_object, object_names
from tactile_sim.objects.mismatch import DisplacementField, displaced_mesh
from tactile_sim.objects.visual import visual_mesh

__all__ = [
    "MOUNT_IN_WORLD",
    "ObjectLike",
    "PlacementConfig",
    "ProbeTarget",
    "displaced_target",
    "mesh_target",
    "random_pose",
    "resolve_object",
    "resting_pose",
    "table_pose",
]


MOUNT_IN_WORLD = np.array([0.40, 0.0, 0.0])
"""The scene's ``object_mount`` site (``scenes/scene.xml``), axes parallel to the world's."""


@dataclass(frozen=True)
class ProbeTarget:
    """An object to probe.

    Attributes
    ----------
    name : str
    mesh : trimesh.Trimesh
        The object's surface, model frame, metres: what the tip touches, and the ground
        truth.
    parts : ConvexParts
        Convex collision parts (what holds it on the table).
    drawn : trimesh.Trimesh or None
        The mesh drawn (default: a simplified copy of ``mesh``).
    model_error_rms_m : float
        How far ``mesh`` lies from the object's model (RMS, metres): 0 unless displaced
        (:func:`displaced_target`).
    upright : bool
        The model frame stands the object on its base at z = 0 (the catalog's objects and
        solids); False (a mesh file): it rests in one of its stable poses
        (:func:`table_pose`).
    """

    name: str
    mesh: trimesh.Trimesh
    parts: ConvexParts
    drawn: trimesh.Trimesh | None = None
    model_error_rms_m: float = 0.0
    upright: bool = True

    @property
    def drawn_mesh(self) -> trimesh.Trimesh:
        """The mesh the scene draws: ``drawn``, else a simplified copy of ``mesh``."""
        return self.drawn if self.drawn is not None else visual_mesh(self.mesh)


ObjectLike = str | ObjectModel | Solid | trimesh.Trimesh | ProbeTarget
"""What can be probed: a catalog or solid name, a catalog object, a solid, a mesh in
metres (model frame, base on z = 0), or a resolved :class:`ProbeTarget`."""


def mesh_target(
    path: str | Path, units: str = "m", *, name: str | None = None
) -> tuple[ProbeTarget, MeshReport]:
    """Returns a mesh file as an object to probe, and what was repaired to make it a model.

    The file is read (:func:`~recognition.surfaces.mesh_files.read_mesh`: OBJ, PLY, STL,
    OFF, GLB, glTF in ``units``) and made a model (holes kept, pieces kept,
    :func:`~recognition.surfaces.mesh_repair.prepare_mesh`); the tip meets that surface
    itself, and convex tiles of it (:func:`~tactile_sim.collision.tiling.surface_tiles`,
    a fraction of a second) keep the probe's body off it. The object is named after the
    file unless ``name`` is given.

    Raises
    ------
    RecognitionError
        The file cannot be read or the mesh cannot be a model (the message says why).
    """
    path = Path(path)
    label = name or path.stem
    mesh, report = prepare_mesh(read_mesh(path, units), label)
    return ProbeTarget(label, mesh, surface_tiles(mesh), upright=False), report


def resting_pose(mesh: trimesh.Trimesh, rng: np.random.Generator) -> NDArray[np.float64]:
    """Returns a pose (4, 4) in which ``mesh`` rests stably on the plane z = 0, drawn from
    its stable poses by their probability (trimesh's quasi-static estimate on the convex
    hull, whatever the mesh's holes and pieces)."""
    poses, probabilities = trimesh.poses.compute_stable_poses(mesh, n_samples=1)
    return np.asarray(poses[rng.choice(len(poses), p=probabilities / probabilities.sum())])


def displaced_target(target: ProbeTarget, field: DisplacementField) -> ProbeTarget:
    """Returns ``target`` with its surface displaced along the normals by ``field`` (an
    object that differs from its model, :mod:`tactile_sim.objects.mismatch`); the collision
    parts, which only hold it on the table, stay. ``model_error_rms_m`` is the achieved
    RMS distance from the original surface."""
    if field.rms_m == 0:
        return target
    mesh, achieved = displaced_mesh(target.mesh, field)
    drawn, _ = displaced_mesh(visual_mesh(target.mesh), field, scale_from=target.mesh)
    return replace(target, mesh=mesh, drawn=drawn, model_error_rms_m=achieved)


def resolve_object(obj: ObjectLike, *, progress: bool = True) -> ProbeTarget:
    """Returns the name, mesh and collision parts of a catalog name, solid name,
    ObjectModel, Solid or trimesh mesh (a ProbeTarget as it is).

    Raises
    ------
    UnknownObject
        A name that is neither a catalog object nor a solid; lists the known names.
    """
    if isinstance(obj, ProbeTarget):
        return obj
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
            "object must be a catalog or solid name, an ObjectModel, a Solid, a "
            f"trimesh.Trimesh or a ProbeTarget, got {type(obj).__name__}"
        )
    if isinstance(obj, ObjectModel):
        parts = object_parts(obj, progress=progress)
    else:
        convex = True if isinstance(obj, Solid) and obj.convex else None
        parts = convex_decomposition(mesh, name=name, progress=progress, convex=convex)
    return ProbeTarget(name=name, mesh=mesh, parts=parts)


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


def table_pose(target: ProbeTarget, seed: int) -> NDArray[np.float64]:
    """Returns the object's seeded pose on the table: :func:`random_pose` (generator
    ``[seed, 1]``), after :func:`resting_pose` (generator ``[seed, 3]``) unless the model
    stands upright as modelled."""
    T = random_pose(np.random.default_rng([seed, 1]))
    if target.upright:
        return T
    return T @ resting_pose(target.mesh, np.random.default_rng([seed, 3]))


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
    return pose_matrix(rotation_about(2, yaw), MOUNT_IN_WORLD + offset)
