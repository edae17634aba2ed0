"""The thesis's registration on a triangle mesh (Sections 4.3.3.1-4.3.3.2).

The data curves are superposed at a candidate vertex v (p on v, the data normal on v's
normal (4.13), turned by phi about it); the three fitted sampling planes, moved with
them, are intersected with the mesh and each section is resampled with the data's point
spacing, p's counterpart in the middle. The superposition error is the mean distance
between corresponding points (4.15). phi is scanned in 10-degree steps; then a greedy
walk moves to the best unvisited 1-ring neighbour while the error decreases, re-scanning
phi one step either side; the smallest error over the candidates is the registration
error (4.16).
"""

from __future__ import annotations

import time

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from recognition.errors import RecognitionError
from recognition.rigid import pose_matrix, rotation_about
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.local_geometry import LocalSurfaceGeometry
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.registration.config import ThesisConfig
from recognition.surfaces.registration.result import (
    Registration,
    RegistrationMode,
    RegistrationStatus,
    rejected,
)
from recognition.surfaces.registration.superposition import (
    candidate_rows,
    hypotheses,
    model_frames,
)
from recognition.surfaces.sections import local_submesh, plane_section_polyline, resample_around

__all__ = ["correspondence_error", "register_thesis"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
Layout = list[tuple[Array, float, int]]
"""Per data curve: its plane normal, mean point spacing and the index of its point nearest p."""


def _curve_layout(curves: DataCurves) -> Layout:
    """Per curve: plane normal, mean spacing, and the index of the point nearest p."""
    layout = []
    for i, c in enumerate(curves.curves):
        spacing = float(np.mean(np.linalg.norm(np.diff(c, axis=0), axis=1)))
        middle = int(np.argmin(np.linalg.norm(c - curves.intersection, axis=1)))
        layout.append((curves.plane_normal(i), spacing, middle))
    return layout


def correspondence_error(
    curves: DataCurves,
    layout: Layout,
    R: Array,
    t: Array,
    anchor: Array,
    local_mesh: tuple[Array, IntArray],
) -> float:
    """Mean distance between data points and their plane-section counterparts, Eq. (4.15).

    ``R`` (3, 3), ``t`` (3,) move the data onto the model with p on ``anchor`` (3,) (a
    model vertex); ``local_mesh`` (vertices (m, 3), faces (f, 3)) is the part of the model
    around the anchor; lengths in metres, the result too. Infinite when a section through
    the anchor is too short for the data curve.
    """
    total, count = 0.0, 0
    for curve, (normal, spacing, middle) in zip(curves.curves, layout, strict=True):
        moved = curve @ R.T + t
        try:
            section = plane_section_polyline(*local_mesh, anchor, R @ normal)
            # resample with the anchor at the data's p index, in the data's direction
            n = len(curve)
            ahead, behind = n - 1 - middle, middle
            half = max(ahead, behind)
            samples = resample_around(section, anchor, 2 * half + 1, spacing)
        except RecognitionError:
            return float("inf")
        forward = samples[half - behind : half + ahead + 1]
        backward = samples[::-1][half - behind : half + ahead + 1]
        e_f = np.linalg.norm(moved - forward, axis=1)
        e_b = np.linalg.norm(moved - backward, axis=1)
        e = e_f if e_f.sum() <= e_b.sum() else e_b
        total += float(e.sum())
        count += n
    return total / count


def register_thesis(
    model: MeshModel,
    curves: DataCurves,
    geometry: LocalSurfaceGeometry,
    config: ThesisConfig = ThesisConfig(),
) -> Registration:
    """Thesis-mode registration of the curves on one mesh model, thesis Eq. (4.16) (module
    docstring).

    ``geometry`` is the data's local geometry at p
    (:func:`~recognition.surfaces.registration.data.data_geometry`).
    """
    start = time.perf_counter()
    layout = _curve_layout(curves)
    # faces near enough to hold every section: half a curve's length, with a margin
    extent = max(len(c) for c in curves.curves) * max(s for _, s, _ in layout)
    radius = 0.6 * extent + 2e-3
    step = np.deg2rad(config.phi_step_deg)
    phis = np.arange(0.0, 2 * np.pi - 1e-9, step)
    adjacency = model.mesh.vertex_neighbors
    centres = cKDTree(model.mesh.triangles_center)
    local_cache: dict[int, tuple[Array, IntArray]] = {}
    best = None
    candidates_all = []
    evaluations = 0
    for hyp in hypotheses(geometry):
        rows = candidate_rows(model, hyp, config.delta)[: config.max_candidates]
        candidates_all.append(model.table.site[rows])

        def pose(
            vertex: int, phi: float, d1: Array, hyp: LocalSurfaceGeometry = hyp
        ) -> tuple[Array, Array]:
            n = model.normals[vertex]
            t1 = d1 - n * (d1 @ n)
            t1 /= np.linalg.norm(t1)
            frame = np.column_stack([t1, np.cross(n, t1), n])
            R = frame @ rotation_about(2, np.array(phi)) @ hyp.frame.T
            return R, model.vertices[vertex] - R @ hyp.point

        def error_at(vertex: int, phi: float, d1: Array) -> tuple[float, Array, Array]:
            nonlocal evaluations
            evaluations += 1
            R, t = pose(vertex, phi, d1)
            x = model.vertices[vertex]
            local = local_cache.get(vertex)
            if local is None:
                faces = np.asarray(centres.query_ball_point(x, radius), dtype=np.int64)
                local = local_submesh(model.vertices, model.faces, faces)
                local_cache[vertex] = local
            return correspondence_error(curves, layout, R, t, x, local), R, t

        frames = model_frames(model, rows)
        for row, frame in zip(rows, frames, strict=True):
            v = int(model.table.site[row])
            d1 = frame[:, 0]
            scan = [(error_at(v, phi, d1), phi) for phi in phis]
            (e, R, t), phi = min(scan, key=lambda item: item[0][0])
            if not np.isfinite(e):
                continue
            visited = {v}
            while True:  # greedy 1-ring walk (Section 4.3.3.2), phi re-scanned +-1 step
                ring = [u for u in adjacency[v] if u not in visited]
                visited.update(ring)
                moves = [
                    (error_at(u, ph, d1), u, ph)
                    for u in ring
                    for ph in (phi - step, phi, phi + step)
                ]
                if not moves:
                    break
                (e_u, R_u, t_u), u, ph = min(moves, key=lambda item: item[0][0])
                if not e_u < e:
                    break
                e, R, t, v, phi = e_u, R_u, t_u, u, ph
            if best is None or e < best[0]:
                best = (e, R, t)
    candidates = np.concatenate(candidates_all) if candidates_all else np.zeros(0, np.int64)
    if best is None:
        return rejected(model.name, RegistrationMode.THESIS, start, candidates)
    e, R, t = best
    return Registration(
        model.name,
        float(e),
        pose_matrix(R, t),
        R @ geometry.point + t,
        candidates,
        evaluations,
        RegistrationStatus.CONVERGED,
        time.perf_counter() - start,
        RegistrationMode.THESIS,
    )
