"""The ICP baseline: what a practitioner would write instead of the thesis's registration.

Multi-start point-to-plane ICP on the model's vertices and normals (KD-tree
correspondences, a Gauss-Newton step per iteration) from the same table candidates
(4.7) and a few phi, the best start by RMS residual; its error is then the exact mean
distance (4.8).
"""

from __future__ import annotations

import time

import numpy as np
from scipy.spatial.transform import Rotation

from recognition.rigid import pose_matrix
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.local_geometry import LocalSurfaceGeometry
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.registration.config import IcpConfig
from recognition.surfaces.registration.result import (
    Registration,
    RegistrationMode,
    RegistrationStatus,
    rejected,
)
from recognition.surfaces.registration.superposition import (
    candidate_rows,
    hypotheses,
    superposition_poses,
)

__all__ = ["register_icp"]


def register_icp(
    model: MeshModel,
    curves: DataCurves,
    geometry: LocalSurfaceGeometry,
    config: IcpConfig = IcpConfig(),
) -> Registration:
    """Multi-start point-to-plane ICP on vertices and normals (KD-tree correspondences).

    ``geometry`` is the data's local geometry at p
    (:func:`~recognition.surfaces.registration.data.data_geometry`).
    """
    start = time.perf_counter()
    points = curves.points
    phis = np.linspace(0, 2 * np.pi, config.phi_starts, endpoint=False)
    best, all_rows, total_iterations = None, [], 0
    for hyp in hypotheses(geometry):
        rows = candidate_rows(model, hyp, config.delta)[: config.max_candidates]
        all_rows.append(model.table.site[rows])
        if rows.size == 0:
            continue
        R, t = superposition_poses(model, rows, hyp, phis)
        for Rs, ts in zip(R.reshape(-1, 3, 3), t.reshape(-1, 3), strict=True):
            trace: list[float] = []
            for _ in range(config.iterations):
                X = points @ Rs.T + ts
                _, nearest = model.tree.query(X)
                y, n = model.vertices[nearest], model.normals[nearest]
                r = np.einsum("ij,ij->i", X - y, n)
                trace.append(float(np.sqrt(np.mean(r * r))))
                c = X.mean(axis=0)
                J = np.concatenate([np.cross(X - c, n), n], axis=1)
                step = np.linalg.lstsq(J, -r, rcond=None)[0]
                dR = Rotation.from_rotvec(step[:3]).as_matrix()
                Rs, ts = dR @ Rs, dR @ (ts - c) + c + step[3:]
                total_iterations += 1
                if np.linalg.norm(step) < 1e-8:
                    break
            X = points @ Rs.T + ts
            _, nearest = model.tree.query(X)
            r = np.einsum("ij,ij->i", X - model.vertices[nearest], model.normals[nearest])
            rms = float(np.sqrt(np.mean(r * r)))
            if best is None or rms < best[0]:
                best = (rms, Rs, ts, tuple(trace))
    candidates = np.concatenate(all_rows) if all_rows else np.zeros(0, np.int64)
    if best is None:
        return rejected(model.name, RegistrationMode.ICP, start, candidates)
    _, R, t, best_trace = best
    error = float(np.mean(model.distance.closest(points @ R.T + t)[0]))
    return Registration(
        model.name,
        error,
        pose_matrix(R, t),
        R @ geometry.point + t,
        candidates,
        total_iterations,
        RegistrationStatus.CONVERGED,
        time.perf_counter() - start,
        RegistrationMode.ICP,
        best_trace,
    )
