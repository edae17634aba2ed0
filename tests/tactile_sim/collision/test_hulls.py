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
