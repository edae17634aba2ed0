"""Registration of three data curves on a mesh model (thesis Sections 4.1.2, 4.3.3).

Three modes behind :func:`register`:

``fast`` (default)
    Table lookup (4.7); every candidate vertex x every rotation phi about the normal
    (superposition of Section 4.1.2.2) is scored in one vectorised batch on the model's
    narrow-band signed distance field with a subset of the data points; the best poses
    are refined together by Gauss-Newton over all six degrees of freedom (p slides on
    the surface, the curves turn about and tilt off the normal) on every data point.
    The reported error is the mean exact point-to-surface distance (4.8).
``thesis``
    The thesis's method: superposition by intersecting the three sampling planes with
    the mesh and resampling at the data's spacing (4.15), phi in 10-degree steps, then
    a greedy walk over 1-ring neighbours while the error decreases (4.16).
``icp-baseline``
    What a practitioner would write instead: multi-start point-to-plane ICP on the
    model's vertices and normals (KD-tree correspondences) from the same table
    candidates and a few phi.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from enum import StrEnum

import numpy as np
from scipy.spatial.transform import Rotation

from recognition.errors import InvalidCurveData
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.local_geometry import LocalSurfaceGeometry, local_surface_geometry
from recognition.surfaces.mesh_model import MeshModel

__all__ = [
    "Registration",
    "RegistrationConfig",
    "RegistrationMode",
    "RegistrationStatus",
    "register",
]


class RegistrationMode(StrEnum):
    FAST = "fast"
    THESIS = "thesis"
    ICP = "icp-baseline"


class RegistrationStatus(StrEnum):
    CONVERGED = "converged"
    MAX_ITERATIONS = "max_iterations"
    NO_CANDIDATES = "no_candidates"  # rejected at table lookup


@dataclass(frozen=True)
class RegistrationConfig:
    """Settings of the registration.

    Attributes
    ----------
    delta : float
        Table-lookup tolerance of Eq. (4.7), 1/m (thesis: 0.03 1/mm = 30 1/m).
    relative_delta : float
        Fast mode: the tolerance grows by this fraction of the data's largest |k|; the
        estimates of both data and model disagree more where the curvature is high.
    n_phi : int
        Fast mode: rotations about the normal scored per candidate when the data are
        nearly umbilic (k1 - k2 <= ``anisotropy``); otherwise phi is scanned +-30 degrees
        around the two alignments of the principal directions.
    anisotropy : float
        k1 - k2 (1/m) above which principal directions are trusted.
    candidate_spacing_m : float
        Fast mode: candidate vertices are thinned to one per cell of this size.
    sparse_points, n_screened
        Fast mode stage 1: data points scored at every candidate pose (nearest voxel),
        and the best poses kept; stage 2 runs ``screen_iterations`` Gauss-Newton steps on
        them with the same points.
    n_refined_coarse, coarse_points
        Stage 3: the best poses after stage 2 and the data points they are refined on.
    n_refined, iterations
        Stage 4: the best poses after stage 3, refined on every data point.
    iterations : int
        Gauss-Newton / ICP iterations at most.
    thesis_phi_step_deg : float
        Rotation step of the thesis mode (thesis: 10 degrees).
    thesis_max_candidates : int
        Candidates searched in thesis mode, nearest in (k1, k2) first.
    icp_phi : int
        Starting rotations per candidate for the ICP baseline.
    icp_max_candidates : int
        Candidates (nearest in (k1, k2) first) started by the ICP baseline.
    """

    delta: float = 30.0
    relative_delta: float = 0.3
    n_phi: int = 24
    anisotropy: float = 15.0
    candidate_spacing_m: float = 4.0e-3
    sparse_points: int = 9
    n_screened: int = 384
    n_refined_coarse: int = 48
    coarse_points: int = 30
    screen_iterations: int = 3
    n_refined: int = 3
    iterations: int = 8
    thesis_phi_step_deg: float = 10.0
    thesis_max_candidates: int = 20
    icp_phi: int = 8
    icp_max_candidates: int = 25


@dataclass(frozen=True)
class Registration:
    """Result of registering data curves on one model.

    Attributes
    ----------
    model : str
    error_m : float
        Registration error: mean distance from the data points to the model (4.8),
        metres; ``inf`` when the model was rejected at table lookup.
    T_model_from_data : (4, 4) float
        Rigid transform taking data points onto the model.
    location : (3,) float
        The data curves' common point p mapped onto the model, model frame.
    candidates : (k,) int
        Candidate vertices of the table lookup.
    iterations : int
    status : RegistrationStatus
    time_s : float
    mode : RegistrationMode
    trace : tuple of float
        Error after each refinement step of the best start (diagnostics).
    error_is_exact : bool
        False when ``error_m`` was read off the distance field (within about 0.01 mm of
        the exact distance), see :meth:`with_exact_error`.
    """

    model: str
    error_m: float
    T_model_from_data: np.ndarray
    location: np.ndarray
    candidates: np.ndarray
    iterations: int
    status: RegistrationStatus
    time_s: float
    mode: RegistrationMode
    trace: tuple[float, ...] = field(default_factory=tuple)
    error_is_exact: bool = True

    def with_exact_error(
        self, model: MeshModel, curves: DataCurves, refine: bool = False, point=None
    ) -> Registration:
        """This registration with its error computed exactly (if it was not).

        With ``refine``, the pose is first polished by point-to-plane Gauss-Newton on exact
        closest points (:func:`refine_exact`); ``point`` (the data's p) then moves with it.
        """
        if self.error_is_exact or not np.isfinite(self.error_m):
            return self
        R, t = self.T_model_from_data[:3, :3], self.T_model_from_data[:3, 3]
        if refine:
            R, t, error = refine_exact(model, curves.points, R, t)
            location = self.location if point is None else R @ point + t
            return replace(
                self,
                error_m=error,
                error_is_exact=True,
                T_model_from_data=_pose_matrix(R, t),
                location=location,
            )
        error = float(np.mean(model.distance.closest(curves.points @ R.T + t)[0]))
        return replace(self, error_m=error, error_is_exact=True)


def _rejected(model, mode, start, candidates=None) -> Registration:
    nan = np.full(3, np.nan)
    candidates = np.zeros(0, np.int64) if candidates is None else candidates
    return Registration(
        model,
        float("inf"),
        np.full((4, 4), np.nan),
        nan,
        candidates,
        0,
        RegistrationStatus.NO_CANDIDATES,
        time.perf_counter() - start,
        mode,
    )


def _hypotheses(geometry: LocalSurfaceGeometry) -> list[LocalSurfaceGeometry]:
    """The data's local geometry, and its flip when the normal's sign is unknown."""
    return [geometry] if geometry.oriented else [geometry, geometry.flipped()]


def _candidates(model: MeshModel, geometry: LocalSurfaceGeometry, delta: float):
    """Table rows within delta of the data's (k1, k2), nearest first (4.7)."""
    table = model.table
    rows = table.query(geometry.k1, geometry.k2, delta)
    d = np.hypot(table.k1[rows] - geometry.k1, table.k2[rows] - geometry.k2)
    return rows[np.argsort(d, kind="stable")]


def _model_frames(model: MeshModel, rows: np.ndarray) -> np.ndarray:
    """(k, 3, 3) frames (d1, d2, n) at candidate vertices: principal direction and normal."""
    table = model.table
    v = table.vertex[rows]
    n = model.normals[v]
    t1 = table.d1[rows] - n * np.einsum("ij,ij->i", table.d1[rows], n)[:, None]
    bad = np.linalg.norm(t1, axis=1) < 1e-9
    if bad.any():
        helper = np.where(np.abs(n[bad, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
        t1[bad] = np.cross(n[bad], helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    return np.stack([t1, np.cross(n, t1), n], axis=-1)


def _rot_z(phi: np.ndarray) -> np.ndarray:
    c, s = np.cos(phi), np.sin(phi)
    R = np.zeros((*phi.shape, 3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 1, 0], R[..., 1, 1] = c, -s, s, c
    R[..., 2, 2] = 1.0
    return R


def _superposition_poses(model, rows, geometry, phis):
    """Poses (R, t) putting p on each candidate, N on its normal, turned by each phi.

    Returns R (k, f, 3, 3), t (k, f, 3) mapping data-frame points to the model frame.
    """
    frames = _model_frames(model, rows)  # (k, 3, 3)
    data_frame = geometry.frame  # columns d1, d2, N in data coordinates
    R = frames[:, None] @ _rot_z(phis)[None] @ data_frame.T[None, None]
    x = model.vertices[model.table.vertex[rows]]
    t = x[:, None, :] - np.einsum("kfij,j->kfi", R, geometry.point)
    return R, t


def _spread_subset(curves: DataCurves, count: int) -> np.ndarray:
    """Indices into ``curves.points`` of about ``count`` points spread along every curve."""
    idx, offset = [], 0
    per = max(count // len(curves.curves), 2)
    for c in curves.curves:
        idx.append(offset + np.unique(np.linspace(0, len(c) - 1, per).round().astype(int)))
        offset += len(c)
    return np.concatenate(idx)


def _gauss_newton(field, points, R, t, iterations):
    """Batched Gauss-Newton (Levenberg damping) of poses on the signed distance field.

    Minimises sum_i sdf(R q_i + t)^2 for each of the B starts; R (B, 3, 3), t (B, 3).
    Returns R, t, the RMS residual per start and the trace of the best start.
    """
    lam = np.full(len(R), 1e-3)
    pts_T = np.ascontiguousarray(points.T)
    X = (R @ pts_T).transpose(0, 2, 1) + t[:, None, :]
    r, g = field.value_and_gradient(X)
    cost = np.mean(r * r, axis=1)
    trace = [float(np.sqrt(cost.min()))]
    eye = np.eye(6)
    for _ in range(iterations):
        c = X.mean(axis=1, keepdims=True)
        J = np.concatenate([np.cross(X - c, g), g], axis=-1)  # (B, n, 6)
        JT = J.transpose(0, 2, 1)
        H = JT @ J
        b = -(JT @ r[..., None])
        scale = np.trace(H, axis1=1, axis2=2)[:, None, None] / 6 + 1e-12
        step = np.linalg.solve(H + (lam[:, None, None] * scale) * eye, b)[..., 0]
        dR = Rotation.from_rotvec(step[:, :3]).as_matrix()
        R_new = dR @ R
        t_new = (dR @ (t - c[:, 0])[..., None])[..., 0] + c[:, 0] + step[:, 3:]
        X_new = (R_new @ pts_T).transpose(0, 2, 1) + t_new[:, None, :]
        r_new, g_new = field.value_and_gradient(X_new)
        cost_new = np.mean(r_new * r_new, axis=1)
        better = cost_new < cost
        R = np.where(better[:, None, None], R_new, R)
        t = np.where(better[:, None], t_new, t)
        X = np.where(better[:, None, None], X_new, X)
        r = np.where(better[:, None], r_new, r)
        g = np.where(better[:, None, None], g_new, g)
        lam = np.where(better, lam * 0.3, lam * 10.0)
        improvement = (cost - np.minimum(cost, cost_new)) / np.maximum(cost, 1e-300)
        cost = np.minimum(cost, cost_new)
        trace.append(float(np.sqrt(cost.min())))
        if np.all((improvement < 1e-4) & better) or np.all(lam > 1e6):
            break
    return R, t, np.sqrt(cost), tuple(trace)


def refine_exact(model: MeshModel, points: np.ndarray, R, t, iterations: int = 10):
    """Point-to-plane Gauss-Newton on exact closest points (the last six-DOF polish).

    Returns R, t and the mean exact distance after refinement.
    """
    for _ in range(iterations):
        X = points @ R.T + t
        _, q, face = model.distance.closest(X)
        n = model.distance.face_normals[face]
        r = np.einsum("ij,ij->i", X - q, n)
        c = X.mean(axis=0)
        J = np.concatenate([np.cross(X - c, n), n], axis=1)
        step = np.linalg.lstsq(J, -r, rcond=None)[0]
        dR = Rotation.from_rotvec(step[:3]).as_matrix()
        R, t = dR @ R, dR @ (t - c) + c + step[3:]
        if np.linalg.norm(step) < 1e-10:
            break
    return R, t, float(np.mean(model.distance.closest(points @ R.T + t)[0]))


def _pose_matrix(R, t) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T


def _dense_candidates(model, geometry, delta, spacing):
    """Vertices whose curvature is within delta of the data's, one per ``spacing`` cell.

    From the per-vertex curvature map (thinned to a 1 mm pool); in each cubic cell of side
    ``spacing`` the vertex nearest in (k1, k2) is kept, so candidates cover every matching
    region about evenly.
    """
    pool = model.candidate_pool()
    rows = pool.query(geometry.k1, geometry.k2, delta)
    if rows.size == 0:
        return rows
    vertices = pool.vertex[rows]
    dist = np.hypot(pool.k1[rows] - geometry.k1, pool.k2[rows] - geometry.k2)
    cell = model.cell_keys(spacing)[vertices]
    order = np.lexsort((dist, cell))
    first = np.ones(order.size, bool)
    first[1:] = cell[order[1:]] != cell[order[:-1]]
    return vertices[order[first]]


def _phi_grid(geometry, config) -> np.ndarray:
    """Rotations about the normal to try: around the principal-direction alignments when
    the data are clearly anisotropic, a uniform scan otherwise."""
    if geometry.k1 - geometry.k2 > config.anisotropy:
        offsets = np.deg2rad(np.arange(-30, 31, 15))
        return np.concatenate([offsets, np.pi + offsets])
    return np.linspace(0, 2 * np.pi, config.n_phi, endpoint=False)


def _superpose(model, vertices, frames_d1, geometry, phis):
    """Poses putting p on each vertex, N on its normal, d1 on frames_d1 turned by phi."""
    n = model.normals[vertices]
    t1 = frames_d1 - n * np.einsum("ij,ij->i", frames_d1, n)[:, None]
    t1 /= np.maximum(np.linalg.norm(t1, axis=1, keepdims=True), 1e-300)
    frames = np.stack([t1, np.cross(n, t1), n], axis=-1)
    R = frames[:, None] @ (_rot_z(phis) @ geometry.frame.T)[None]
    t = model.vertices[vertices][:, None, :] - R @ geometry.point
    return R, t


def _register_fast(model, curves, geometry, config, start, exact=True) -> Registration:
    points = curves.points
    sparse = points[_spread_subset(curves, config.sparse_points)]
    coarse = points[_spread_subset(curves, config.coarse_points)]
    field = model.distance_field
    dense = model.vertex_curvatures
    starts_R, starts_t, all_candidates = [], [], []
    for hyp in _hypotheses(geometry):
        delta = config.delta + config.relative_delta * max(abs(hyp.k1), abs(hyp.k2))
        vertices = _dense_candidates(model, hyp, delta, config.candidate_spacing_m)
        all_candidates.append(vertices)
        if vertices.size == 0:
            continue
        phis = _phi_grid(hyp, config)
        R, t = _superpose(model, vertices, dense.d1[vertices], hyp, phis)
        # stage 1: a few points at every candidate pose
        X = (R.reshape(-1, 3, 3) @ sparse.T).transpose(0, 2, 1) + t.reshape(-1, 1, 3)
        score = np.mean(np.abs(field.nearest(X)), axis=-1)
        keep = np.argsort(score)[: config.n_screened]
        starts_R.append(R.reshape(-1, 3, 3)[keep])
        starts_t.append(t.reshape(-1, 3)[keep])
    # the best screened poses of both normal orientations compete from here on
    candidates = np.concatenate(all_candidates) if all_candidates else np.zeros(0, np.int64)
    if not starts_R:
        return _rejected(model.name, RegistrationMode.FAST, start, candidates)
    R, t = np.concatenate(starts_R), np.concatenate(starts_t)
    # stages 2-4: ever fewer starts, ever more points: each start slides into its basin
    # on a few points before the best ones are refined on more
    stages = (
        (config.n_screened, sparse, config.screen_iterations),
        (config.n_refined_coarse, coarse, config.screen_iterations),
        (config.n_refined, points, config.iterations),
    )
    rms = np.zeros(len(R))
    for n_keep, stage_points, iterations in stages:
        keep = np.argsort(rms, kind="stable")[:n_keep]
        R, t, rms, trace = _gauss_newton(field, stage_points, R[keep], t[keep], iterations)
    best = int(np.argmin(rms))
    R, t = R[best], t[best]
    if exact:
        R, t, error = refine_exact(model, points, R, t)
    else:
        error = float(np.mean(np.abs(field(points @ R.T + t))))
    return Registration(
        model.name,
        error,
        _pose_matrix(R, t),
        R @ geometry.point + t,
        candidates,
        len(trace) - 1,
        RegistrationStatus.CONVERGED,
        time.perf_counter() - start,
        RegistrationMode.FAST,
        trace,
        exact,
    )


def _register_icp(model, curves, geometry, config, start) -> Registration:
    """Multi-start point-to-plane ICP on vertices and normals (KD-tree correspondences)."""
    points = curves.points
    phis = np.linspace(0, 2 * np.pi, config.icp_phi, endpoint=False)
    best, all_rows, total_iterations = None, [], 0
    for hyp in _hypotheses(geometry):
        rows = _candidates(model, hyp, config.delta)[: config.icp_max_candidates]
        all_rows.append(model.table.vertex[rows])
        if rows.size == 0:
            continue
        R, t = _superposition_poses(model, rows, hyp, phis)
        for Rs, ts in zip(R.reshape(-1, 3, 3), t.reshape(-1, 3), strict=True):
            trace = []
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
        return _rejected(model.name, RegistrationMode.ICP, start, candidates)
    _, R, t, trace = best
    error = float(np.mean(model.distance.closest(points @ R.T + t)[0]))
    return Registration(
        model.name,
        error,
        _pose_matrix(R, t),
        R @ geometry.point + t,
        candidates,
        total_iterations,
        RegistrationStatus.CONVERGED,
        time.perf_counter() - start,
        RegistrationMode.ICP,
        trace,
    )


def register(
    model: MeshModel,
    curves: DataCurves,
    *,
    mode: RegistrationMode | str = RegistrationMode.FAST,
    config: RegistrationConfig = RegistrationConfig(),
    geometry: LocalSurfaceGeometry | None = None,
    exact: bool = True,
) -> Registration:
    """Register data curves on one mesh model.

    Parameters
    ----------
    model : MeshModel
    curves : DataCurves
        Data curves in any frame, metres.
    mode : {"fast", "thesis", "icp-baseline"}
    config : RegistrationConfig
    geometry : LocalSurfaceGeometry, optional
        The data's local geometry, if already computed (it does not depend on the model).
    exact : bool
        Fast mode: compute the final error exactly (else from the distance field).
    """
    start = time.perf_counter()
    try:
        mode = RegistrationMode(mode)
    except ValueError:
        raise InvalidCurveData(
            f"unknown registration mode {mode!r}; expected one of "
            f"{', '.join(m.value for m in RegistrationMode)}"
        ) from None
    geometry = geometry or local_surface_geometry(curves)
    if mode is RegistrationMode.FAST:
        return _register_fast(model, curves, geometry, config, start, exact)
    if mode is RegistrationMode.ICP:
        return _register_icp(model, curves, geometry, config, start)
    from recognition.surfaces.thesis_registration import register_thesis

    return register_thesis(model, curves, geometry, config, start)
