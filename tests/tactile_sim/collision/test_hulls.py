"""Convex hulls of point sets."""

from __future__ import annotations

import numpy as np
import trimesh

from tactile_sim.collision import convex_hull_part


def test_convex_hull_part_faces_point_outward() -> None:
    rng = np.random.default_rng(0)
    vertices, faces = convex_hull_part(rng.normal(size=(200, 3)))
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    assert mesh.is_watertight and mesh.volume > 0


def test_surface_tiles_cover_an_open_mesh_in_pieces_close_to_its_surface() -> None:
    from recognition.surfaces.distance import MeshDistance
    from tactile_sim.collision.tiling import TILE_THICKNESS_M, surface_tiles

    sphere = trimesh.creation.icosphere(4, radius=0.03)
    keep = sphere.triangles_center[:, 2] < 0.02
    cut = trimesh.Trimesh(sphere.vertices, sphere.faces[keep])
    eye = trimesh.creation.icosphere(2, radius=0.004).apply_translation([0.04, 0, 0])
    mesh = trimesh.util.concatenate([cut, eye])
    tiles = surface_tiles(mesh)
    assert tiles.source == "tiles" and tiles.n_parts > 50
    distance = MeshDistance(mesh.vertices, mesh.faces)
    for vertices, _ in tiles.parts:
        # every tile vertex lies on the surface or a tile thickness inside it
        assert distance.closest(vertices)[0].max() < TILE_THICKNESS_M + 1e-6
    # every vertex of the mesh is a corner of some tile
    corners = np.unique(np.concatenate([v for v, _ in tiles.parts]).round(9), axis=0)
    assert len(corners) >= len(mesh.vertices)
