"""Convex hulls of point sets, and the checks made on meshes before they are split."""

from __future__ import annotations

from typing import Any

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import ConvexHull

from tactile_sim.errors import InvalidMesh

__all__ = [
    "convex_hull_part",
    "is_closed_manifold",
    "is_convex",
    "mesh_arrays",
]


_CONVEX_VOLUME_TOLERANCE = 1e-6
"""A mesh whose volume is within this fraction of its convex hull's counts as convex."""


def mesh_arrays(mesh: Any) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Returns the checked (n, 3) float64 vertices and (m, 3) int64 faces of a mesh or a
    (vertices, faces) pair.

    Raises
    ------
    InvalidMesh
        Too few vertices or faces, non-finite vertices or face indices out of range.
    """
    if isinstance(mesh, tuple):
        vertices, faces = mesh
    else:
        vertices, faces = mesh.vertices, mesh.faces
    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or len(vertices) < 4:
        raise InvalidMesh(f"vertices must be (n >= 4, 3), got shape {vertices.shape}")
    if not np.all(np.isfinite(vertices)):
        raise InvalidMesh("vertices hold NaN or infinite values")
    if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) < 4:
        raise InvalidMesh(f"faces must be (m >= 4, 3), got shape {faces.shape}")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise InvalidMesh(f"face indices must lie in [0, {len(vertices) - 1}]")
    return vertices, faces


def convex_hull_part(points: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Returns the convex hull of points as (vertices (k, 3), outward faces (m, 3)).

    Parameters
    ----------
    points : (n, 3) float, metres
        At least four points spanning three dimensions.
    """
    points = np.asarray(points, dtype=np.float64)
    try:
        hull = ConvexHull(points)
    except Exception as error:  # scipy raises QhullError (not exported on every version)
        raise InvalidMesh(f"cannot build a convex hull of {len(points)} points: {error}") from error
    used = hull.vertices
    remap = np.full(len(points), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    faces = remap[hull.simplices]
    vertices = points[used]
    # Orient every triangle outward: its normal must agree with the facet's plane normal.
    a, b, c = vertices[faces[:, 0]], vertices[faces[:, 1]], vertices[faces[:, 2]]
    flip = np.einsum("ij,ij->i", np.cross(b - a, c - a), hull.equations[:, :3]) < 0
    faces[flip] = faces[flip][:, ::-1]
    return vertices, faces


def is_convex(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> bool:
    """Returns True if the closed mesh's volume equals its convex hull's (within a tolerance)."""
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False, validate=False)
    try:
        hull_volume = ConvexHull(vertices).volume
    except Exception:
        return False
    volume = abs(float(mesh.volume))
    return hull_volume > 0 and volume >= (1.0 - _CONVEX_VOLUME_TOLERANCE) * hull_volume


def is_closed_manifold(faces: NDArray[np.int64]) -> bool:
    """Returns True if every edge of the triangles is shared by exactly two of them."""
    edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(np.all(counts == 2))
