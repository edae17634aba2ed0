"""Registration of three data curves on mesh models (thesis Sections 4.1.2, 4.3.3).

Three modes behind :func:`register` (one model) and
:meth:`recognition.surfaces.database.ModelDatabase.recognize` (all models):

``fast`` (default)
    The data's normal and curvatures are estimated at the point where all three curves
    meet, at the scale of the models' fits (:func:`data_geometry`). Table lookup (4.7) in
    a curvature map of one vertex per 1 mm cell, thinned to one candidate per 2.5 mm
    cell; where the curve fits at p do not explain the data (p on a crease), candidates
    come from the whole surface. At each candidate the data are superposed (p on the
    vertex, N on its normal, Section 4.1.2.2) at rotations phi about the normal: a window
    around the alignment of the principal directions where both data and model are
    clearly anisotropic, a full scan elsewhere. Every (candidate, phi) pose of every model
    is screened in one vectorised batch on the models' narrow-band signed distance fields
    with a few points per arm of the data; the best poses of each model slide into their
    basins by batched Gauss-Newton over all six degrees of freedom on ever more points,
    near-duplicates dropped between stages. A model whose coarse fit is far worse than
    the best model's stops there. The reported error is the mean point-to-surface
    distance (4.8), exact (closest points on the triangles, pose polished) for the models
    that can win. When even the best model fits worse than the data's own noise
    explains, the models not rejected at table lookup are searched again over their whole
    surface (:attr:`RegistrationConfig.fallback`).
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
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from enum import StrEnum

import numpy as np
from scipy.spatial.transform import Rotation

from recognition.errors import InvalidCurveData
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.distance import FieldStack
from recognition.surfaces.local_geometry import (
    LocalSurfaceGeometry,
    local_surface_geometry,
)
from recognition.surfaces.mesh_model import MeshModel

__all__ = [
    "FastSearchConfig",
    "Registration",
    "RegistrationConfig",
    "RegistrationMode",
    "RegistrationStatus",
    "acceptable_error_m",
    "common_point",
    "data_fit_residual_m",
    "data_geometry",
    "data_noise_m",
    "refine_exact",
    "register",
    "register_fast",
    "registration_mode",
]


#: Poses closer than this (p's image, metres) and ...
DISTINCT_RADIUS_M = 0.5e-3
#: ... turned less than this from a better pose are near-duplicates (fast mode).
DISTINCT_ANGLE_RAD = float(np.deg2rad(3.0))


class RegistrationMode(StrEnum):
    FAST = "fast"
    THESIS = "thesis"
    ICP = "icp-baseline"


class RegistrationStatus(StrEnum):
    CONVERGED = "converged"
    MAX_ITERATIONS = "max_iterations"
    NO_CANDIDATES = "no_candidates"  # rejected at table lookup
    PRUNED = "pruned"  # fast mode: stopped after the coarse stage, far worse than the best


@dataclass(frozen=True)
class FastSearchConfig:
    """How densely one pass of the fast mode searches a model.

    Attributes
    ----------
    tolerance_scale : float
        Multiplies the table-lookup tolerance of :class:`RegistrationConfig`; ``inf``:
        every vertex is a candidate (curvature estimates fail on sharp creases).
    candidate_spacing_m : float
        Candidate vertices are thinned to one per cubic cell of this side (the vertex
        nearest the data in (k1, k2)), metres.
    aligned_anisotropy : float
        k1 - k2 (1/m) above which, for both the data and a candidate, phi is searched
        only near the alignment of their principal directions; ``inf``: always scan.
    aligned_window_rad, aligned_step_rad : float
        Half width and step of that window around both alignments (phi and phi + pi).
    scan_step_rad : float
        Step of the full scan of phi over [0, 2 pi).
    prescreen_fractions : tuple of float
        Prescreening points: on each of the six arms (p to a curve's end), the data
        points at these fractions of the arm's length.
    prescreen_keep : float
        Fraction of the poses (of a model, phi set and normal orientation) kept after
        prescreening, but at least ``n_screened``.
    arm_fractions : tuple of float
        Screening points, as ``prescreen_fractions``.
    n_screened : int
        Poses per model kept after screening; each takes ``screen_iterations``
        Gauss-Newton steps on the screening points.
    n_coarse, coarse_per_arm, coarse_iterations
        Distinct poses per model kept next, refined on ``coarse_per_arm`` points per arm.
    n_final, final_iterations
        Distinct poses per model refined on every data point.
    """

    tolerance_scale: float = 1.0
    candidate_spacing_m: float = 2.5e-3
    aligned_anisotropy: float = 20.0
    aligned_window_rad: float = float(np.deg2rad(24.0))
    aligned_step_rad: float = float(np.deg2rad(8.0))
    scan_step_rad: float = float(np.deg2rad(10.0))
    prescreen_fractions: tuple[float, ...] = (2 / 3,)
    prescreen_keep: float = 0.1
    arm_fractions: tuple[float, ...] = (1 / 3, 2 / 3, 1.0)
    n_screened: int = 128
    screen_iterations: int = 4
    n_coarse: int = 48
    coarse_per_arm: int = 8
    coarse_iterations: int = 4
    n_final: int = 4
    final_iterations: int = 25


#: The denser pass run when no model fits well enough (see RegistrationConfig.fallback).
THOROUGH_SEARCH = FastSearchConfig(
    tolerance_scale=float("inf"),
    candidate_spacing_m=2.0e-3,
    aligned_anisotropy=float("inf"),
    n_screened=384,
    n_coarse=96,
    n_final=8,
)


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
    fit_half_length_m, fit_spacings, fit_degree
        The data's local geometry (4.1)-(4.6): each curve is fitted by a polynomial of
        ``fit_degree`` over the arc within max(``fit_half_length_m``, ``fit_spacings``
        point spacings) of p, the scale of the models' paraboloid fits (4.14).
    search : FastSearchConfig
        Fast mode: the first pass.
    fallback : FastSearchConfig or None
        Fast mode: a denser pass over the models not rejected at table lookup (by default
        over their whole surface, since curvature estimates fail on sharp creases), run
        when the best error of the first pass exceeds :func:`acceptable_error_m`; None:
        never.
    accept_sigmas, accept_floor_m
        A fit is good enough when its mean error is within ``accept_sigmas`` standard
        deviations of the mean distance that the data's noise alone gives, plus
        ``accept_floor_m`` (:func:`acceptable_error_m`).
    accept_noise_cap_m
        The noise the acceptance test assumes is at most this. The noise is estimated
        from the data's scatter about their sampling planes, which also counts a
        sensor's error along the surface (a contact point displaced sideways, on a
        surface that slopes across the sampling plane): it can be many times the error
        across the surface, which alone sets the registration error. Above the cap the
        fallback search runs, since the first pass also relies on the normal and
        curvatures at p that such data give poorly.
    fit_noise_factor, fit_floor_m
        The curve fits at p are trusted when they explain each curve near p, and pass
        by p, to within ``fit_noise_factor`` times the data's noise plus ``fit_floor_m``
        (:func:`data_fit_residual_m`); otherwise (p on a crease) the fast mode does not
        restrict its candidates by curvature.
    prune_ratio : float or None
        Fast mode: a model whose best coarse RMS residual exceeds this multiple of the
        best model's stops before the final stage; None: never.
    polish_ratio, polish_margin_m, polish_iterations
        Models whose distance-field error is within ``polish_ratio`` times the best plus
        ``polish_margin_m`` are polished on exact closest points (at most
        ``polish_iterations`` steps of :func:`refine_exact`) and get exact errors.
    thesis_phi_step_deg : float
        Rotation step of the thesis mode (thesis: 10 degrees).
    thesis_max_candidates : int
        Candidates searched in thesis mode, nearest in (k1, k2) first.
    icp_phi : int
        Starting rotations per candidate for the ICP baseline.
    icp_max_candidates : int
        Candidates (nearest in (k1, k2) first) started by the ICP baseline.
    icp_iterations : int
        ICP iterations at most per start.
    """

    delta: float = 30.0
    relative_delta: float = 0.3
    fit_half_length_m: float = 3.0e-3
    fit_spacings: float = 3.2
    fit_degree: int = 3
    search: FastSearchConfig = FastSearchConfig()
    fallback: FastSearchConfig | None = THOROUGH_SEARCH
    accept_sigmas: float = 4.0
    accept_floor_m: float = 5.0e-6
    accept_noise_cap_m: float = 0.05e-3
    fit_noise_factor: float = 5.0
    fit_floor_m: float = 5.0e-6
    prune_ratio: float | None = 4.0
    polish_ratio: float = 1.5
    polish_margin_m: float = 0.01e-3
    polish_iterations: int = 3
    thesis_phi_step_deg: float = 10.0
    thesis_max_candidates: int = 20
    icp_phi: int = 8
    icp_max_candidates: int = 25
    icp_iterations: int = 8


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
        Wall time; in a search of several models at once, this model's share of the
        batched work (in proportion to the point evaluations made for it).
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
        self,
        model: MeshModel,
        curves: DataCurves,
        refine: bool = False,
        point=None,
        iterations: int = 12,
    ) -> Registration:
        """This registration with its error computed exactly (if it was not).

        With ``refine``, the pose is first polished on exact closest points by at most
        ``iterations`` steps of :func:`refine_exact`; ``point`` (the data's p) then moves
        with it.
        The time taken is added to ``time_s``.
        """
        if self.error_is_exact or not np.isfinite(self.error_m):
            return self
        start = time.perf_counter()
        R, t = self.T_model_from_data[:3, :3], self.T_model_from_data[:3, 3]
        if refine:
            R, t, error = refine_exact(model, curves.points, R, t, iterations)
            location = self.location if point is None else R @ point + t
            return replace(
                self,
                error_m=error,
                error_is_exact=True,
                T_model_from_data=_pose_matrix(R, t),
                location=location,
                time_s=self.time_s + time.perf_counter() - start,
            )
        error = float(np.mean(model.distance.closest(curves.points @ R.T + t)[0]))
        return replace(
            self,
            error_m=error,
            error_is_exact=True,
            time_s=self.time_s + time.perf_counter() - start,
        )


def _rejected(model, mode, start, candidates=None, elapsed=None) -> Registration:
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
        time.perf_counter() - start if elapsed is None else elapsed,
        mode,
    )


# --- the data's local geometry and noise ----------------------------------------------


def _median_spacing(curves: DataCurves) -> float:
    steps = [np.linalg.norm(np.diff(c, axis=0), axis=1) for c in curves.curves]
    return float(np.median(np.concatenate(steps)))


def _distances_to_polyline(points: np.ndarray, polyline: np.ndarray) -> np.ndarray:
    """(n,) distance from each point (n, 3) to a polyline (m, 3)."""
    a, ab = polyline[:-1], np.diff(polyline, axis=0)
    rel = points[:, None, :] - a[None]
    s = np.clip(np.einsum("nmi,mi->nm", rel, ab) / np.einsum("mi,mi->m", ab, ab), 0.0, 1.0)
    return np.min(np.linalg.norm(rel - s[..., None] * ab[None], axis=-1), axis=1)


def common_point(curves: DataCurves) -> np.ndarray:
    """The point where all the data curves meet (p of thesis Fig. 4.1), (3,) metres.

    Of the points of every curve, the one whose largest distance to the other curves is
    least; then the mean of the points of the curves nearest it. Unlike the pairwise
    closest points (:attr:`DataCurves.intersection`), a place where only two curves come
    close (sampling planes a few degrees apart over a strongly curved surface) is not
    taken for p.
    """
    best = None
    for i, c in enumerate(curves.curves):
        others = [_distances_to_polyline(c, o) for j, o in enumerate(curves.curves) if j != i]
        worst = np.max(others, axis=0)
        k = int(np.argmin(worst))
        if best is None or worst[k] < best[0]:
            best = (worst[k], c[k])
    p = best[1]
    for _ in range(2):
        nearest = []
        for c in curves.curves:
            a, ab = c[:-1], np.diff(c, axis=0)
            s = np.clip(np.einsum("mi,mi->m", p - a, ab) / np.einsum("mi,mi->m", ab, ab), 0, 1)
            q = a + s[:, None] * ab
            nearest.append(q[np.argmin(np.linalg.norm(q - p, axis=1))])
        p = np.mean(nearest, axis=0)
    return p


def data_geometry(
    curves: DataCurves, config: RegistrationConfig = RegistrationConfig()
) -> LocalSurfaceGeometry:
    """Normal and principal curvatures at p (thesis Eqs. (4.1)-(4.6)) at the models' scale.

    As :func:`~recognition.surfaces.local_geometry.local_surface_geometry`, at the point
    where all curves meet (:func:`common_point`), each curve fitted over the arc within
    max(``fit_half_length_m``, ``fit_spacings`` x the point spacing) of p by a
    polynomial of degree ``fit_degree``: about the neighbourhood of the models'
    paraboloid fits (4.14), and at least three points either side of p when the points
    are sparse (the thesis's real data: 1.2 mm apart).
    """
    half_length = max(config.fit_half_length_m, config.fit_spacings * _median_spacing(curves))
    return local_surface_geometry(
        curves, half_length_m=half_length, degree=config.fit_degree, point=common_point(curves)
    )


def data_noise_m(curves: DataCurves) -> float:
    """Standard deviation of the data's noise, from the residuals of each curve's plane.

    Every data curve lies in its sampling plane; with isotropic noise of standard
    deviation sigma, the residuals of a least-squares plane have a mean square of
    sigma^2 (n - 3) / n.
    """
    total, dof = 0.0, 0
    for c in curves.curves:
        centred = c - c.mean(axis=0)
        normal = np.linalg.svd(centred, full_matrices=False)[2][-1]
        residual = centred @ normal
        total += float(residual @ residual)
        dof += max(len(c) - 3, 1)
    return float(np.sqrt(total / dof))


def data_fit_residual_m(
    curves: DataCurves, config: RegistrationConfig = RegistrationConfig(), point=None
):
    """How far the data's local fits at p (default :func:`common_point`) miss the data, m.

    Each curve is fitted near p as in :func:`data_geometry` (a plane, then a polynomial
    in it along the local chord); the result is the largest, over the curves, of the fit's
    RMS residual (per degree of freedom) and of its distance from p.
    """
    p = common_point(curves) if point is None else np.asarray(point, float)
    half_length = max(config.fit_half_length_m, config.fit_spacings * _median_spacing(curves))
    degree = config.fit_degree
    worst = 0.0
    for curve in curves.curves:
        centred = curve - curve.mean(axis=0)
        normal = np.linalg.svd(centred, full_matrices=False)[2][-1]
        distance = np.linalg.norm(curve - p, axis=1)
        near = np.flatnonzero(distance <= half_length)
        if near.size < degree + 2:
            near = np.sort(np.argsort(distance)[: degree + 2])
        local = curve[near[0] : near[-1] + 1]
        chord = local[-1] - local[0]
        chord -= normal * (chord @ normal)
        ex = chord / np.linalg.norm(chord)
        ey = np.cross(normal, ex)
        x, y = (local - p) @ ex, (local - p) @ ey
        scale = max(np.abs(x).max(), 1e-12)
        coef = np.polynomial.polynomial.polyfit(x / scale, y, degree)
        residual = y - np.polynomial.polynomial.polyval(x / scale, coef)
        rms = np.sqrt(residual @ residual / max(len(residual) - degree - 1, 1))
        worst = max(worst, float(rms), float(abs(coef[0])))
    return worst


def acceptable_error_m(
    noise_m: float, n_points: int, config: RegistrationConfig = RegistrationConfig()
) -> float:
    """Largest mean registration error (4.8) that the data's noise explains, metres.

    For points displaced by Gaussian noise of standard deviation sigma, the mean distance
    to the surface they were sampled on is sqrt(2/pi) sigma, with a relative standard
    deviation of sqrt(pi/2 - 1 / 2) / sqrt(n) over n points once the error of the noise
    estimate itself (:func:`data_noise_m`) is included; the limit lies
    ``accept_sigmas`` such deviations above, plus ``accept_floor_m``. The noise is
    taken as at most ``accept_noise_cap_m``.
    """
    spread = np.sqrt(np.pi / 2 - 0.5) / np.sqrt(max(n_points, 1))
    mean = np.sqrt(2 / np.pi) * min(noise_m, config.accept_noise_cap_m)
    return float(mean * (1 + config.accept_sigmas * spread) + config.accept_floor_m)


# --- shared helpers -------------------------------------------------------------------


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
    """(k, 3, 3) frames (d1, d2, n) at table rows: principal direction and normal."""
    table = model.table
    return _frames(model.normals[table.vertex[rows]], table.d1[rows])


def _frames(normals: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """(k, 3, 3) right-handed frames whose columns are (t1, n x t1, n), t1 the direction
    made tangent (any tangent where it is parallel to the normal)."""
    t1 = directions - normals * np.einsum("ij,ij->i", directions, normals)[:, None]
    bad = np.linalg.norm(t1, axis=1) < 1e-9
    if bad.any():
        helper = np.where(np.abs(normals[bad, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
        t1[bad] = np.cross(normals[bad], helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    return np.stack([t1, np.cross(normals, t1), normals], axis=-1)


def _rot_z(phi: np.ndarray) -> np.ndarray:
    c, s = np.cos(phi), np.sin(phi)
    R = np.zeros((*np.shape(phi), 3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 1, 0], R[..., 1, 1] = c, -s, s, c
    R[..., 2, 2] = 1.0
    return R


def _superposition_poses(model, rows, geometry, phis):
    """Poses (R, t) putting p on each table row's vertex, N on its normal, turned by phi.

    Returns R (k, f, 3, 3), t (k, f, 3) mapping data-frame points to the model frame.
    """
    frames = _model_frames(model, rows)  # (k, 3, 3)
    R = frames[:, None] @ _rot_z(phis)[None] @ geometry.frame.T[None, None]
    x = model.vertices[model.table.vertex[rows]]
    t = x[:, None, :] - np.einsum("kfij,j->kfi", R, geometry.point)
    return R, t


def _pose_matrix(R, t) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T


def _rotations(w: np.ndarray) -> np.ndarray:
    """(B, 3, 3) rotation matrices of rotation vectors w (B, 3) (Rodrigues' formula)."""
    theta = np.linalg.norm(w, axis=1)
    k = w / np.maximum(theta, 1e-300)[:, None]
    K = np.zeros((len(w), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = k[:, 2], -k[:, 1], k[:, 0]
    s, c = np.sin(theta)[:, None, None], (1 - np.cos(theta))[:, None, None]
    return np.eye(3) + s * K + c * (K @ K)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.empty(np.broadcast_shapes(a.shape, b.shape), dtype=np.result_type(a, b))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


# --- fast mode --------------------------------------------------------------------------


def _gauss_newton(stack: FieldStack, which, points, R, t, iterations, tolerance=1e-4):
    """Batched Levenberg-damped Gauss-Newton of poses on signed distance fields.

    Minimises sum_i sdf(R q_i + t)^2 for each of the B starts in its own field
    ``which`` (B,); R (B, 3, 3), t (B, 3), points (P, 3). A start stops once a step
    lowers its cost by less than the fraction ``tolerance`` (or its damping exceeds
    1e6); at most ``iterations`` steps. Returns R, t, the RMS residual per start and the
    best RMS after each step.
    """
    R, t, which = R.copy(), t.copy(), np.asarray(which)
    lam = np.full(len(R), 1e-3)
    pts_T = np.ascontiguousarray(points.T)
    X = (R @ pts_T).transpose(0, 2, 1) + t[:, None, :]
    r, g = stack.value_and_gradient(X, which)
    cost = np.mean(r * r, axis=1)
    trace = [float(np.sqrt(cost.min()))]
    eye = np.eye(6)
    active = np.arange(len(R))
    for _ in range(iterations):
        Xa, ra, ga = X[active], r[active], g[active]
        c = Xa.mean(axis=1)
        J = np.concatenate([_cross(Xa - c[:, None, :], ga), ga], axis=-1)  # (A, P, 6)
        JT = J.transpose(0, 2, 1)
        H = JT @ J
        b = -(JT @ ra[..., None])
        scale = np.trace(H, axis1=1, axis2=2)[:, None, None] / 6 + 1e-12
        step = np.linalg.solve(H + (lam[active, None, None] * scale) * eye, b)[..., 0]
        dR = _rotations(step[:, :3])
        R_new = dR @ R[active]
        t_new = (dR @ (t[active] - c)[..., None])[..., 0] + c + step[:, 3:]
        X_new = (R_new @ pts_T).transpose(0, 2, 1) + t_new[:, None, :]
        r_new, g_new = stack.value_and_gradient(X_new, which[active])
        cost_new = np.mean(r_new * r_new, axis=1)
        better = cost_new < cost[active]
        moved = active[better]
        R[moved], t[moved], X[moved] = R_new[better], t_new[better], X_new[better]
        r[moved], g[moved] = r_new[better], g_new[better]
        improvement = (cost[active] - cost_new) / np.maximum(cost[active], 1e-300)
        cost[moved] = cost_new[better]
        lam[active] = np.where(better, lam[active] * 0.3, lam[active] * 10.0)
        trace.append(float(np.sqrt(cost.min())))
        done = (better & (improvement < tolerance)) | (lam[active] > 1e6)
        active = active[~done]
        if active.size == 0:
            break
    return R, t, np.sqrt(cost), tuple(trace)


def refine_exact(
    model: MeshModel, points: np.ndarray, R, t, iterations: int = 12, tolerance: float = 1e-4
):
    """Levenberg-Marquardt on exact closest points: the last six-DOF polish of a pose.

    Each step linearises the distances as point-to-plane residuals on the closest
    triangles and is kept only if it lowers the mean squared exact distance (so the pose
    never gets worse, also along the flat directions of nearly symmetric surfaces).
    Stops when a kept step lowers the mean squared distance by less than the fraction
    ``tolerance`` or moves no data point by more than 0.1 micrometre, or after
    ``iterations`` steps. Returns R, t and the mean exact distance (4.8) at the result.
    """
    points = np.asarray(points, float)
    reach = float(np.max(np.linalg.norm(points - points.mean(axis=0), axis=1)))
    X = points @ R.T + t
    distance, q, face = model.distance.closest(X)
    cost = float(np.mean(distance**2))
    lam = 1e-6
    for _ in range(iterations):
        n = model.distance.face_normals[face]
        r = np.einsum("ij,ij->i", X - q, n)
        c = X.mean(axis=0)
        J = np.concatenate([np.cross(X - c, n), n], axis=1)
        H = J.T @ J
        damping = lam * (np.trace(H) / 6 + 1e-300)
        step = np.linalg.solve(H + damping * np.eye(6), -(J.T @ r))
        dR = Rotation.from_rotvec(step[:3]).as_matrix()
        R_new, t_new = dR @ R, dR @ (t - c) + c + step[3:]
        X_new = points @ R_new.T + t_new
        d_new, q_new, f_new = model.distance.closest(X_new)
        cost_new = float(np.mean(d_new**2))
        if cost_new < cost:
            small = cost - cost_new < tolerance * cost
            R, t, X, distance, q, face, cost = R_new, t_new, X_new, d_new, q_new, f_new, cost_new
            lam *= 0.1
            if small or np.linalg.norm(step[:3]) * reach + np.linalg.norm(step[3:]) < 1e-7:
                break
        else:
            lam *= 100.0
            if lam > 1e6:
                break
    return R, t, float(np.mean(distance))


def _dense_candidates(model, geometry, delta, spacing):
    """Rows of the candidate map within delta of the data's (k1, k2), one per cell.

    Rows of :attr:`MeshModel.candidate_curvatures` whose curvature is within ``delta``
    (1/m; ``inf``: every row) of the data's (4.7); in each cubic cell of side
    ``spacing`` the row nearest in (k1, k2) is kept, so candidates cover every matching
    region about evenly.
    """
    pool = model.candidate_curvatures
    rows = pool.query(geometry.k1, geometry.k2, delta) if np.isfinite(delta) else None
    if rows is None:
        rows = np.arange(len(pool))
    if rows.size == 0:
        return rows
    dist = np.hypot(pool.k1[rows] - geometry.k1, pool.k2[rows] - geometry.k2)
    cell = model.cell_keys(spacing)[pool.vertex[rows]]
    order = np.lexsort((dist, cell))
    first = np.ones(order.size, bool)
    first[1:] = cell[order[1:]] != cell[order[:-1]]
    return rows[order[first]]


def _arm_indices(curves: DataCurves, point: np.ndarray, fractions) -> np.ndarray:
    """Indices into ``curves.points`` of the points at ``fractions`` of each arm's length.

    An arm runs from the point of a curve nearest p to one of its ends; the result holds,
    per curve and fraction, the index on the forward arm then on the backward arm.
    """
    idx, offset = [], 0
    for c in curves.curves:
        m = int(np.argmin(np.linalg.norm(c - point, axis=1)))
        n = len(c)
        for f in fractions:
            idx.append(offset + min(n - 1, m + max(1, round(f * (n - 1 - m)))))
            idx.append(offset + max(0, m - max(1, round(f * m))))
        offset += n
    return np.array(idx, dtype=np.int64)


def _distinct(R, t, rms, point, n_keep, radius=DISTINCT_RADIUS_M, angle=DISTINCT_ANGLE_RAD):
    """Indices of the ``n_keep`` best poses (least ``rms``), skipping any pose that puts p
    within ``radius`` of a better kept pose while rotated less than ``angle`` from it."""
    order = np.argsort(rms, kind="stable")
    R, location = R[order], R[order] @ point + t[order]
    near = np.linalg.norm(location[:, None] - location[None], axis=-1) < radius
    cos_limit = 1 + 2 * np.cos(angle)
    same = near & (np.einsum("aij,bij->ab", R, R) > cos_limit)
    alive = np.ones(len(order), bool)
    kept = []
    for i in range(len(order)):
        if alive[i]:
            kept.append(i)
            if len(kept) == n_keep:
                break
            alive &= ~same[i]
    return order[np.array(kept, dtype=np.int64)]


def _smallest(values: np.ndarray, count: int) -> np.ndarray:
    """Indices of the ``count`` smallest values (all if fewer), in no particular order."""
    if count >= values.size:
        return np.arange(values.size)
    return np.argpartition(values, count - 1)[:count]


def _screen(models, stack, which_field, curves, geometry, config, search, log):
    """Stage 1: candidate poses of every model, scored on the screening points.

    Every pose is first scored on the prescreening points; the best ``prescreen_keep``
    of them (at least ``n_screened``) are scored again on the screening points. Returns,
    per model, the best ``n_screened`` poses (R, t) and the candidate vertices.
    """
    points = curves.points[_arm_indices(curves, geometry.point, search.arm_fractions)]
    pre_points = curves.points[_arm_indices(curves, geometry.point, search.prescreen_fractions)]
    best_R = [[] for _ in models]
    best_t = [[] for _ in models]
    best_s = [[] for _ in models]
    candidates = [[] for _ in models]
    half = np.arange(
        -search.aligned_window_rad, search.aligned_window_rad + 1e-9, search.aligned_step_rad
    )
    aligned_phis = np.concatenate([half, np.pi + half])
    scan_phis = np.arange(0.0, 2 * np.pi - 1e-9, search.scan_step_rad)
    for hyp in _hypotheses(geometry):
        tolerance = search.tolerance_scale * (
            config.delta + config.relative_delta * max(abs(hyp.k1), abs(hyp.k2))
        )
        local = (points - hyp.point) @ hyp.frame  # (P, 3) in the data's (d1, d2, N) frame
        pre_local = (pre_points - hyp.point) @ hyp.frame
        data_anisotropic = hyp.k1 - hyp.k2 >= search.aligned_anisotropy
        for w, model in enumerate(models):
            start = time.perf_counter()
            pool = model.candidate_curvatures
            rows = _dense_candidates(model, hyp, tolerance, search.candidate_spacing_m)
            candidates[w].append(pool.vertex[rows])
            if rows.size == 0:
                log[w] += time.perf_counter() - start
                continue
            aligned = data_anisotropic & (
                pool.k1[rows] - pool.k2[rows] >= search.aligned_anisotropy
            )
            for mask, phis in ((aligned, aligned_phis), (~aligned, scan_phis)):
                if not mask.any():
                    continue
                v = pool.vertex[rows[mask]]
                frames = _frames(model.normals[v], pool.d1[rows[mask]])
                turns = _rot_z(phis)
                patterns = np.einsum("fij,pj->fpi", turns, local)  # (F, P, 3)
                pre_patterns = np.einsum("fij,pj->fpi", turns, pre_local)
                which = np.full(len(v), which_field[w])
                origins = model.vertices[v]
                pre = np.abs(stack.nearest_in_frames(which, frames, origins, pre_patterns))
                pre = pre.mean(axis=-1).ravel()
                count = max(search.n_screened, int(np.ceil(search.prescreen_keep * pre.size)))
                c, f = np.divmod(_smallest(pre, count), len(phis))
                score = np.abs(
                    stack.nearest_in_frames(
                        which[c], frames[c], origins[c], patterns[f], paired=True
                    )
                ).mean(axis=-1)
                keep = _smallest(score, search.n_screened)
                c, f, score = c[keep], f[keep], score[keep]
                R = frames[c] @ turns[f] @ hyp.frame.T
                best_R[w].append(R)
                best_t[w].append(origins[c] - R @ hyp.point)
                best_s[w].append(score)
            log[w] += time.perf_counter() - start
    out = []
    for w in range(len(models)):
        cands = np.concatenate(candidates[w]) if candidates[w] else np.zeros(0, np.int64)
        if not best_R[w]:
            out.append((None, None, cands))
            continue
        R, t, s = (np.concatenate(x) for x in (best_R[w], best_t[w], best_s[w]))
        keep = np.argsort(s, kind="stable")[: search.n_screened]
        out.append((R[keep], t[keep], cands))
    return out


def _search(models, stack, curves, geometry, config, search, which_field) -> list[Registration]:
    """One pass of the fast search over ``models`` (fields ``which_field`` in ``stack``).

    Returns one registration per model, its error read off the distance field.
    """
    n = len(models)
    seconds = np.zeros(n)
    iterations = np.zeros(n, dtype=np.int64)
    points = curves.points
    screen_idx = _arm_indices(curves, geometry.point, search.arm_fractions)
    fractions = np.arange(1, search.coarse_per_arm + 1) / search.coarse_per_arm
    coarse_idx = np.unique(_arm_indices(curves, geometry.point, fractions))
    screened = _screen(models, stack, which_field, curves, geometry, config, search, seconds)

    def batched(poses, stage_points, steps):
        """Gauss-Newton of every model's poses in one batch; time shared by pose count."""
        live = [w for w in range(n) if poses[w] is not None]
        if not live:
            return poses
        start = time.perf_counter()
        owner = np.concatenate([np.full(len(poses[w][0]), w) for w in live])
        R, t, rms, trace = _gauss_newton(
            stack,
            which_field[owner],
            stage_points,
            np.concatenate([poses[w][0] for w in live]),
            np.concatenate([poses[w][1] for w in live]),
            steps,
        )
        counts = np.bincount(owner, minlength=n)
        seconds[:] += (time.perf_counter() - start) * counts / counts.sum()
        iterations[live] += len(trace) - 1
        out = list(poses)
        for w in live:
            sel = owner == w
            out[w] = (R[sel], t[sel], rms[sel])
        return out

    def distinct(poses, n_keep):
        out = []
        for w, p in enumerate(poses):
            if p is None:
                out.append(None)
                continue
            start = time.perf_counter()
            keep = _distinct(*p, geometry.point, n_keep)
            out.append((p[0][keep], p[1][keep]))
            seconds[w] += time.perf_counter() - start
        return out

    poses = [None if R is None else (R, t) for R, t, _ in screened]
    poses = batched(poses, points[screen_idx], search.screen_iterations)
    poses = batched(distinct(poses, search.n_coarse), points[coarse_idx], search.coarse_iterations)
    status = [RegistrationStatus.CONVERGED] * n
    live = [w for w in range(n) if poses[w] is not None]
    if config.prune_ratio is not None and live:
        best = min(float(poses[w][2].min()) for w in live)
        for w in live:
            if float(poses[w][2].min()) > config.prune_ratio * best:
                status[w] = RegistrationStatus.PRUNED
    final = [
        p if s is RegistrationStatus.CONVERGED else None for p, s in zip(poses, status, strict=True)
    ]
    final = batched(distinct(final, search.n_final), points, search.final_iterations)
    out = []
    for w, model in enumerate(models):
        candidates = screened[w][2]
        source = final[w] if final[w] is not None else poses[w]
        if source is None:
            out.append(_rejected(model.name, RegistrationMode.FAST, 0.0, candidates, seconds[w]))
            continue
        start = time.perf_counter()
        b = int(np.argmin(source[2]))
        R, t = source[0][b], source[1][b]
        error = float(_field_errors(stack, which_field[[w]], points, R[None], t[None])[0])
        out.append(
            Registration(
                model.name,
                error,
                _pose_matrix(R, t),
                R @ geometry.point + t,
                candidates,
                int(iterations[w]),
                status[w],
                seconds[w] + time.perf_counter() - start,
                RegistrationMode.FAST,
                error_is_exact=False,
            )
        )
    return out


def _field_errors(stack, which_field, points, R, t) -> np.ndarray:
    """Mean |sdf| of the data points at poses R (B, 3, 3), t (B, 3) in fields (B,)."""
    X = (R @ points.T).transpose(0, 2, 1) + t[:, None, :]
    return np.mean(np.abs(stack(X, which_field)), axis=1)


def register_fast(
    models: Sequence[MeshModel],
    curves: DataCurves,
    geometry: LocalSurfaceGeometry,
    config: RegistrationConfig = RegistrationConfig(),
    *,
    stack: FieldStack | None = None,
    which_field: np.ndarray | None = None,
    noise_m: float | None = None,
) -> list[Registration]:
    """Fast-mode registration of the curves on several models at once (module docstring).

    Parameters
    ----------
    models : sequence of MeshModel
    curves : DataCurves
    geometry : LocalSurfaceGeometry
        The data's local geometry (:func:`data_geometry`).
    config : RegistrationConfig
    stack : FieldStack, optional
        The models' distance fields (built here if not given).
    which_field : (len(models),) int, optional
        Index of each model's field in ``stack`` (default: 0, 1, ...).
    noise_m : float, optional
        The data's noise (default :func:`data_noise_m`), for the fallback test.

    Returns
    -------
    list of Registration
        One per model, in order. Errors are exact (poses polished on closest points) for
        the models that can win; the others are read off the distance fields.
    """
    models = list(models)
    if stack is None:
        stack = FieldStack.of([m.distance_field for m in models])
    which_field = np.arange(len(models)) if which_field is None else np.asarray(which_field)
    noise = data_noise_m(curves) if noise_m is None else noise_m
    trusted = data_fit_residual_m(curves, config, geometry.point) <= (
        config.fit_noise_factor * noise + config.fit_floor_m
    )
    search = config.search
    if not trusted:
        search = replace(search, tolerance_scale=np.inf, aligned_anisotropy=np.inf)
    first = _search(models, stack, curves, geometry, config, search, which_field)
    registrations = _polish(models, curves, geometry, first, config)
    if config.fallback is None:
        return registrations
    if min(r.error_m for r in registrations) <= acceptable_error_m(
        noise, len(curves.points), config
    ):
        return registrations
    # models rejected at table lookup stay rejected: the fallback searches the others
    kept = [
        w for w, r in enumerate(registrations) if r.status is not RegistrationStatus.NO_CANDIDATES
    ]
    second = _search(
        [models[w] for w in kept],
        stack,
        curves,
        geometry,
        config,
        config.fallback,
        which_field[kept],
    )
    merged = list(registrations)
    for w, b in zip(kept, second, strict=True):
        a = registrations[w]
        better = b if b.error_m < a.error_m else a
        merged[w] = replace(
            better,
            candidates=np.union1d(a.candidates, b.candidates),
            iterations=a.iterations + b.iterations,
            time_s=a.time_s + b.time_s,
        )
    return _polish(models, curves, geometry, merged, config)


def _polish(models, curves, geometry, registrations, config):
    """Exact errors, poses polished on closest points, for the models that can win."""
    field_errors = [r.error_m for r in registrations if not r.error_is_exact]
    exact_errors = [r.error_m for r in registrations if r.error_is_exact]
    best = min(field_errors + exact_errors, default=float("inf"))
    if not np.isfinite(best):
        return registrations
    limit = config.polish_ratio * best + config.polish_margin_m
    out = list(registrations)
    for w, reg in enumerate(registrations):
        if not reg.error_is_exact and reg.error_m <= limit:
            out[w] = reg.with_exact_error(
                models[w], curves, True, geometry.point, config.polish_iterations
            )
    return out


# --- ICP baseline -----------------------------------------------------------------------


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
            for _ in range(config.icp_iterations):
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


def registration_mode(mode: RegistrationMode | str) -> RegistrationMode:
    """The mode named ``mode``, or :class:`~recognition.errors.InvalidCurveData`."""
    try:
        return RegistrationMode(mode)
    except ValueError:
        raise InvalidCurveData(
            f"unknown registration mode {mode!r}; expected one of "
            f"{', '.join(m.value for m in RegistrationMode)}"
        ) from None


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
        The data's local geometry, if already computed (it does not depend on the model;
        default :func:`data_geometry`).
    exact : bool
        Fast mode: polish the pose and compute the error on exact closest points (else
        the error is read off the distance field).
    """
    start = time.perf_counter()
    mode = registration_mode(mode)
    geometry = geometry or data_geometry(curves, config)
    if mode is RegistrationMode.FAST:
        result = register_fast([model], curves, geometry, config)[0]
        if exact:
            result = result.with_exact_error(model, curves, refine=True, point=geometry.point)
        return replace(result, time_s=time.perf_counter() - start)
    if mode is RegistrationMode.ICP:
        return _register_icp(model, curves, geometry, config, start)
    from recognition.surfaces.thesis_registration import register_thesis

    return register_thesis(model, curves, geometry, config, start)
