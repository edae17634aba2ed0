"""Exact distances to a catalog object's or solid's own mesh (the evaluation's yardstick)."""

from __future__ import annotations

import functools

from recognition.surfaces.distance import MeshDistance
from tactile_sim.probing import resolve_object

__all__ = ["mesh_distance"]


@functools.lru_cache(maxsize=4)
def mesh_distance(name: str) -> MeshDistance:
    """Returns exact closest points on the mesh of the catalog object or solid ``name``
    (model frame), kept for the next call."""
    mesh = resolve_object(name, progress=False).mesh
    return MeshDistance(mesh.vertices, mesh.faces)
