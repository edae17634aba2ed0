"""Convex tiles of a surface: the body-only collider of an object the tip meets directly.

With the tip's own contact (:mod:`tactile_sim.probing.tip_contact`) the tip touches the
object's mesh itself; the convex parts only keep the probe's shaft and housing off the
object. For that a tiling of the surface is enough, and it takes a fraction of a second
where a convex decomposition takes minutes on a large or open mesh: the vertices are
binned into cubic cells, and each cell's part is the convex hull of its patch of surface
and the same patch moved a little inward along the normals (a slab, never flat, even on a
planar face). It works on open meshes and meshes in several pieces alike. A patch of
width w and curvature k bulges by about w^2 k / 8 beyond the surface: 0.2 mm for 4 mm
cells where k = 0.1 1/mm.
"""

from __future__ import annotations

import hashlib
import time

import numpy as np
import trimesh
from scipy.spatial import QhullError

from tactile_sim.collision.hulls import convex_hull_part
from tactile_sim.collision.parts import ConvexParts
from tactile_sim.errors import InvalidMesh

__all__ = ["TILE_SIZE_M", "TILE_THICKNESS_M", "surface_tiles"]

#: Side of the cubic cells the surface is cut into, metres.
TILE_SIZE_M = 4.0e-3
#: How far each tile reaches inward from the surface, metres.
TILE_THICKNESS_M = 0.5e-3


def surface_tiles(
    mesh: trimesh.Trimesh,
    cell_m: float = TILE_SIZE_M,
    thickness_m: float = TILE_THICKNESS_M,
) -> ConvexParts:
    """Returns convex tiles covering the surface of ``mesh`` (metres; normals outward).

    Raises
    ------
    InvalidMesh
        No cell holds a patch to tile (an empty or degenerate mesh).
    """
    start = time.perf_counter()
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    normals = np.asarray(mesh.vertex_normals, dtype=np.float64)
    # every triangle belongs to the cell of its centre; a tile holds its triangles' corners
    cells = np.floor((vertices[faces].mean(axis=1) - vertices.min(axis=0)) / cell_m)
    keys = np.unique(cells.astype(np.int64), axis=0, return_inverse=True)[1].ravel()
    order = np.argsort(keys, kind="stable")
    bounds = np.flatnonzero(np.diff(keys[order])) + 1
    parts = []
    for group in np.split(order, bounds):
        corners = np.unique(faces[group].ravel())
        patch = vertices[corners]
        slab = np.concatenate([patch, patch - thickness_m * normals[corners]])
        try:
            parts.append(convex_hull_part(slab))
        except (InvalidMesh, QhullError):
            continue  # a sliver of a cell: its neighbours cover it
    if not parts:
        raise InvalidMesh("the mesh has no patch of surface to tile")
    digest = hashlib.sha256(vertices.tobytes() + faces.tobytes())
    digest.update(f"tiles:{cell_m}:{thickness_m}".encode())
    return ConvexParts(
        parts=tuple(parts),
        key=digest.hexdigest(),
        source="tiles",
        build_seconds=time.perf_counter() - start,
    )
