"""How far the exposed surface of a union of convex parts lies from the original mesh."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import ConvexHull

from recognition.surfaces.distance import MeshDistance
from tactile_sim.collision.hulls import mesh_arrays

__all__ = [
    "HullAccuracy",
    "hull_surface_deviation",
]


_SHARED_FACE_TOLERANCE_M = 1e-5
"""A sampled point this close to (or inside) another part is not on the union's surface
(CoACD's cut faces shared by two parts match to a few micrometres)."""


@dataclass(frozen=True)
class HullAccuracy:
    """How far the exposed surface of a union of convex parts lies from the original mesh.

    Attributes
    ----------
    n_samples : int
        Points sampled on the parts' surfaces that are not inside another part.
    mean_m, p95_m, max_m : float, metres
        Mean, 95th percentile and maximum distance of those points to the original mesh.
    """

    n_samples: int
    mean_m: float
    p95_m: float
    max_m: float


def hull_surface_deviation(
    parts: Sequence[tuple[ArrayLike, ArrayLike]],
    mesh: Any,
    n_samples: int = 50_000,
    seed: int = 0,
) -> HullAccuracy:
    """Returns how far the exposed surface of a union of convex parts lies from a mesh.

    Points are sampled uniformly (by area) on every part's hull; those strictly inside
    another part are dropped (they are not on the union's surface, which is what a probe
    can touch); the rest are measured against the mesh by exact point-triangle distances
    (:class:`~recognition.surfaces.distance.MeshDistance`; ``trimesh.proximity`` is not
    reliable at this scale).

    Parameters
    ----------
    parts : sequence of ((n_i, 3) float, (m_i, 3) int)
        Convex parts, metres.
    mesh : trimesh.Trimesh or ((n, 3) float, (m, 3) int)
        The original surface, same frame.
    n_samples : int
        Points sampled over all parts before the interior ones are dropped.
    seed : int
        Sampling seed.
    """
    rng = np.random.default_rng(seed)
    hulls = []
    for vertices, _ in parts:
        hull = ConvexHull(np.asarray(vertices, dtype=np.float64))
        hulls.append((hull.points[hull.simplices], hull.equations))
    areas = [
        0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
        for t, _ in hulls
    ]
    total = sum(float(a.sum()) for a in areas)
    exposed = []
    for i, ((triangles, _), area) in enumerate(zip(hulls, areas, strict=True)):
        k = max(1, round(n_samples * float(area.sum()) / total))
        index = rng.choice(len(triangles), size=k, p=area / area.sum())
        u, v = rng.random((2, k))
        swap = u + v > 1.0
        u[swap], v[swap] = 1.0 - u[swap], 1.0 - v[swap]
        t = triangles[index]
        points = t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])
        # Inside or on another part (cut faces shared by two parts are not exposed).
        inside = np.zeros(k, dtype=bool)
        for j, (_, equations) in enumerate(hulls):
            if j != i:
                offsets = points @ equations[:, :3].T + equations[:, 3]
                inside |= np.all(offsets < _SHARED_FACE_TOLERANCE_M, axis=1)
        exposed.append(points[~inside])
    points = np.concatenate(exposed)
    distance = MeshDistance(*mesh_arrays(mesh)).closest(points)[0]
    return HullAccuracy(
        n_samples=len(points),
        mean_m=float(distance.mean()),
        p95_m=float(np.percentile(distance, 95)),
        max_m=float(distance.max()),
    )
