"""Exact distances to a catalog object's or solid's own mesh (the evaluation's yardstick),
and how the exact-distance structure compares with libigl's AABB tree."""

from __future__ import annotations

import functools
import subprocess
import sys
import time
import timeit
from collections.abc import Sequence
from typing import Any

import numpy as np

from recognition.surfaces.distance import MeshDistance
from tactile_sim.evaluation.scaling import RSS_MB_SOURCE
from tactile_sim.probing import resolve_object

__all__ = ["OFFSETS_MM", "compare_with_libigl", "comparison_table", "mesh_distance"]

#: Standard deviations of the query points' offsets from the surface, mm.
OFFSETS_MM = (0.02, 0.2, 1.0, 3.0)


@functools.lru_cache(maxsize=4)
def mesh_distance(name: str) -> MeshDistance:
    """Returns exact closest points on the mesh of the catalog object or solid ``name``
    (model frame), kept for the next call."""
    mesh = resolve_object(name, progress=False).mesh
    return MeshDistance(mesh.vertices, mesh.faces)


#: Run in a fresh interpreter: the growth of resident memory (Linux) while libigl builds
#: the AABB tree of one object's mesh (an allocator's freed pages would hide it here).
_TREE_BYTES = (
    RSS_MB_SOURCE
    + """
import sys, igl, numpy as np
from tactile_sim.probing import resolve_object
mesh = resolve_object(sys.argv[1], progress=False).mesh
v = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
f = np.ascontiguousarray(mesh.faces, dtype=np.int64)
before = rss_mb()
tree = igl.AABB()
tree.init(v, f)
print(round((rss_mb() - before) * 2**20))
"""
)


def _tree_bytes(name: str) -> int:
    """Resident memory that libigl's AABB tree of ``name``'s mesh takes, bytes."""
    out = subprocess.run(
        [sys.executable, "-c", _TREE_BYTES, name], capture_output=True, text=True, check=True
    )
    return int(out.stdout.split()[-1])


def compare_with_libigl(
    names: Sequence[str], queries: int = 20_000, seed: int = 0
) -> list[dict[str, Any]]:
    """Exact closest points by :class:`MeshDistance` (a grid of cell lists) and by
    libigl's AABB tree on the meshes of ``names``: build time and memory, query speed at
    several distances from the surface, and the largest difference of their distances.

    Per mesh: ``queries`` points, vertices moved by Gaussian offsets of each standard
    deviation in ``OFFSETS_MM``. Memory: the grid's arrays; the tree's, as the growth of
    a fresh process's resident memory while it is built (its own allocator does not say).
    """
    rng = np.random.default_rng(seed)
    return [_compare_one(name, queries, rng) for name in names]


def _compare_one(name: str, queries: int, rng: np.random.Generator) -> dict[str, Any]:
    """:func:`compare_with_libigl` on one mesh."""
    import igl

    mesh = resolve_object(name, progress=False).mesh
    vertices = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
    faces = np.ascontiguousarray(mesh.faces, dtype=np.int64)
    MeshDistance(vertices, faces).closest(vertices[:1])  # compiled code loaded
    grid = MeshDistance(vertices, faces)
    start = time.perf_counter()
    grid.closest(vertices[:1])
    grid_build = time.perf_counter() - start
    grid_bytes = grid.grid.nbytes
    start = time.perf_counter()
    tree = igl.AABB()
    tree.init(vertices, faces)
    tree_build = time.perf_counter() - start
    tree_bytes = _tree_bytes(name)
    row: dict[str, Any] = {
        "object": name,
        "faces": len(faces),
        "grid_build_s": grid_build,
        "tree_build_s": tree_build,
        "grid_bytes_per_face": grid_bytes / len(faces),
        "tree_bytes_per_face": tree_bytes / len(faces),
        "largest_difference_m": 0.0,
    }
    at = vertices[rng.integers(len(vertices), size=queries)]
    for offset_mm in OFFSETS_MM:
        points = at + rng.normal(scale=offset_mm * 1e-3, size=at.shape)
        ours = grid.closest(points)[0]
        theirs = np.sqrt(tree.squared_distance(vertices, faces, points)[0])
        row["largest_difference_m"] = max(
            row["largest_difference_m"], float(np.max(np.abs(ours - theirs)))
        )
        # the best of three calls
        row[f"grid_points_per_s_{offset_mm:g}mm"] = queries / min(
            timeit.repeat(lambda p=points: grid.closest(p), number=1, repeat=3)
        )
        row[f"tree_points_per_s_{offset_mm:g}mm"] = queries / min(
            timeit.repeat(
                lambda p=points: tree.squared_distance(vertices, faces, p), number=1, repeat=3
            )
        )
    return row


def comparison_table(rows: Sequence[dict[str, Any]]) -> list[str]:
    """The Markdown table of :func:`compare_with_libigl`'s rows (speeds in thousands of
    points per second, grid / libigl)."""
    head = ["object", "faces", "build ms (grid / libigl)", "bytes per face (grid / libigl)"]
    head += [f"k points/s at {o:g} mm" for o in OFFSETS_MM] + ["largest difference m"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [
            r["object"],
            str(r["faces"]),
            f"{r['grid_build_s'] * 1e3:.0f} / {r['tree_build_s'] * 1e3:.0f}",
            f"{r['grid_bytes_per_face']:.0f} / {r['tree_bytes_per_face']:.0f}",
        ]
        for o in OFFSETS_MM:
            grid, tree = r[f"grid_points_per_s_{o:g}mm"], r[f"tree_points_per_s_{o:g}mm"]
            cells.append(f"{grid / 1e3:.0f} / {tree / 1e3:.0f}")
        cells.append(f"{r['largest_difference_m']:.1e}")
        lines.append("| " + " | ".join(cells) + " |")
    return lines
