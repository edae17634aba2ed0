"""The object to probe and its place on the table: mesh and collision parts, a random pose.

:func:`resolve_object` turns a catalog name, a solid name or a mesh into a
:class:`ProbeTarget` (the original surface and its convex collision parts);
:func:`random_pose` draws an upright pose near the scene's object mount.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh
from numpy.typing import NDArray

from recognition.rigid import pose_matrix, rotation_about
from tactile_sim.collision import (
    ConvexParts,
    Solid,
    convex_decomposition,
    load_solid,
    object_parts,
    solid_names,
)
from tactile_sim.errors import UnknownObject
from tactile_sim.objects import ObjectModel, load_object, object_names

__all__ = [
    "MOUNT_IN_WORLD",
    "ObjectLike",
    "PlacementConfig",
    "ProbeTarget",
    "random_pose",
    "resolve_object",
]


ObjectLike = str | ObjectModel | Solid | trimesh.Trimesh
"""What can be probed: a catalog or solid name, a catalog object, a solid, or a mesh in
metres (model frame, base on z = 0)."""

MOUNT_IN_WORLD = np.array([0.40, 0.0, 0.0])
"""The scene's ``object_mount`` site (``scenes/scene.xml``), axes parallel to the world's."""


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


def resolve_object(obj: ObjectLike, *, progress: bool = True) -> ProbeTarget:
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
