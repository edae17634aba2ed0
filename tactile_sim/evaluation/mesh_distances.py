"""Distances from points to a catalog object's or solid's own mesh (the evaluation's yardstick)."""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.surfaces.distance import MeshDistance
from tactile_sim.probing import resolve_object

__all__ = ["mesh_distances_m"]


@functools.lru_cache(maxsize=4)
def _distance(name: str) -> MeshDistance:
    mesh = resolve_object(name, progress=False).mesh
    return MeshDistance(mesh.vertices, mesh.faces)


def mesh_distances_m(name: str, points_in_object: ArrayLike) -> NDArray[np.float64]:
    """Returns the exact distances (k,) metres of points (k, 3) in the object frame,
    metres, from the mesh of the catalog object or solid ``name`` (libigl AABB tree)."""
    return _distance(name).closest(points_in_object)[0]
