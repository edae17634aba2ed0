"""The fast mode: every model's candidate poses screened in one batch on distance fields.

The data's normal and curvatures are estimated at the point where all three curves meet,
at the scale of the models' fits (:func:`~recognition.surfaces.registration.data.
data_geometry`). Table lookup (4.7) in a curvature map of one vertex per 1 mm cell,
thinned to one candidate per 2.5 mm cell; where the curve fits at p do not explain the
data (p on a crease), candidates come from the whole surface. At each candidate the data
are superposed (p on the vertex, N on its normal, Section 4.1.2.2) at rotations phi about
the normal: a window around the alignment of the principal directions where both data
and model are clearly anisotropic, a full scan elsewhere. Every (candidate, phi) pose of
every model is screened in one vectorised batch on the models' narrow-band signed
distance fields with a few points per arm of the data; the best poses of each model slide
into their basins by batched Gauss-Newton over all six degrees of freedom on ever more
points, near-duplicates dropped between stages. A model whose coarse fit is far worse
than the best model's stops there. The reported error is the mean point-to-surface
distance (4.8), exact (closest points on the triangles, pose polished) for the models
that can win. When even the best model fits worse than the data's own noise explains,
the models not rejected at table lookup are searched again over their whole surface
(:attr:`FastConfig.fallback`).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.least_squares import LeastSquaresConfig, State, damped_least_squares
from recognition.rigid import cross, pose_matrix, rotation_about, rotation_from_vector
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.distance import FieldStack
from recognition.surfaces.local_geometry import LocalSurfaceGeometry
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.registration.config import FastConfig, FastSearchConfig
from recognition.surfaces.registration.data import (
    acceptable_error_m,
    data_fit_residual_m,
    data_noise_m,
)
from recognition.surfaces.registration.exact import with_exact_error
from recognition.surfaces.registration.result import (
    Registration,
    RegistrationMode,
    RegistrationStatus,
    rejected,
)
from recognition.surfaces.registration.superposition import frames, hypotheses

__all__ = ["DISTINCT_ANGLE_RAD", "DISTINCT_RADIUS_M", "register_fast"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class _Poses:
    """A model's poses at one stage of the search: R (k, 3, 3), t (k, 3), and their RMS
    residual (k,) once refined."""

    R: Array
    t: Array
    rms: Array | None = None


#: Poses closer than this (p's image, metres) and ...
DISTINCT_RADIUS_M = 0.5e-3
#: ... turned less than this from a better pose are near-duplicates.
DISTINCT_ANGLE_RAD = float(np.deg2rad(3.0))


def _gauss_newton(
    stack: FieldStack,
    which: IntArray,
    points: Array,
    R: Array,
    t: Array,
    iterations: int,
    tolerance: float = 1e-4,
) -> tuple[Array, Array, Array, tuple[float, ...]]:
    """Batched Levenberg-damped Gauss-Newton of poses on signed distance fields.

    Minimises sum_i sdf(R q_i + t)^2 for each of the B starts in its own field
    ``which`` (B,); R (B, 3, 3), t (B, 3), points (P, 3). A start stops once a step
    lowers its cost by less than the fraction ``tolerance`` (or its damping exceeds
    1e6); at most ``iterations`` steps. The rotation turns about the centroid of the
    placed points. Returns R, t, the RMS residual per start and the best RMS after each
    step.
    """
    pts_T = np.ascontiguousarray(points.T)

    def evaluate(R: Array, t: Array, which: IntArray) -> State:
        X = (R @ pts_T).transpose(0, 2, 1) + t[:, None, :]
        r, g = stack.value_and_gradient(X, which)
        return R, t, which, X, r, g

    def cost(state: State) -> Array:
        r = state[4]
        return np.mean(r * r, axis=1)

    def linearize(state: State) -> tuple[Array, Array]:
        X, r, g = state[3], state[4], state[5]
        c = X.mean(axis=1)
        return r, np.concatenate([cross(X - c[:, None, :], g), g], axis=-1)

    def retract(state: State, step: Array) -> State:
        R, t, which, X = state[:4]
        c = X.mean(axis=1)
        dR = rotation_from_vector(step[:, :3])
        t_new = (dR @ (t - c)[..., None])[..., 0] + c + step[:, 3:]
        return evaluate(dR @ R, t_new, which)

    result = damped_least_squares(
        evaluate(R, t, np.asarray(which)),
        cost=cost,
        linearize=linearize,
        retract=retract,
        config=LeastSquaresConfig(
            max_iterations=iterations,
            initial_damping=1e-3,
            shrink=0.3,
            grow=10.0,
            max_damping=1e6,
            trace_floor=1e-12,
            rtol=tolerance,
        ),
    )
    trace = tuple(float(np.sqrt(c.min())) for c in result.trace)
    return result.state[0], result.state[1], np.sqrt(result.cost), trace


def _dense_candidates(
    model: MeshModel, geometry: LocalSurfaceGeometry, delta: float, spacing: float
) -> NDArray[np.int64]:
    """Rows of the candidate map within delta of the data's (k1, k2), one per cell.

    Rows of :attr:`MeshModel.candidate_curvatures` whose curvature is within ``delta``
    (1/m; ``inf``: every row) of the data's (4.7); in each cubic cell of side
    ``spacing`` the row nearest in (k1, k2) is kept, so candidates cover every matching
    region about evenly.
    """
    pool = model.candidate_curvatures
    if np.isfinite(delta):
        rows = pool.query(geometry.k1, geometry.k2, delta)
    else:
        rows = np.arange(len(pool))
    if rows.size == 0:
        return rows
    dist = np.hypot(pool.k1[rows] - geometry.k1, pool.k2[rows] - geometry.k2)
    cell = model.cell_keys(spacing)[pool.site[rows]]
    order = np.lexsort((dist, cell))
    first = np.ones(order.size, bool)
    first[1:] = cell[order[1:]] != cell[order[:-1]]
    return rows[order[first]]


def _arm_indices(curves: DataCurves, point: Array, fractions: Sequence[float] | Array) -> IntArray:
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


def _distinct(
    R: Array,
    t: Array,
    rms: Array,
    point: Array,
    n_keep: int,
    radius: float = DISTINCT_RADIUS_M,
    angle: float = DISTINCT_ANGLE_RAD,
) -> NDArray[np.int64]:
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


def _smallest(values: Array, count: int) -> NDArray[np.intp]:
    """Indices of the ``count`` smallest values (all if fewer), in no particular order."""
    if count >= values.size:
        return np.arange(values.size)
    return np.argpartition(values, count - 1)[:count]


def _screen(
    models: Sequence[MeshModel],
    stack: FieldStack,
    which_field: IntArray,
    curves: DataCurves,
    geometry: LocalSurfaceGeometry,
    config: FastConfig,
    search: FastSearchConfig,
    log: Array,
) -> list[tuple[_Poses | None, NDArray[np.int64]]]:
    """Stage 1: candidate poses of every model, scored on the screening points.

    Every pose is first scored on the prescreening points; the best ``prescreen_keep``
    of them (at least ``n_screened``) are scored again on the screening points. Returns,
    per model, the best ``n_screened`` poses (None without candidates) and the candidate
    vertices.
    """
    points = curves.points[_arm_indices(curves, geometry.point, search.arm_fractions)]
    pre_points = curves.points[_arm_indices(curves, geometry.point, search.prescreen_fractions)]
    best_R: list[list[Array]] = [[] for _ in models]
    best_t: list[list[Array]] = [[] for _ in models]
    best_s: list[list[Array]] = [[] for _ in models]
    candidates: list[list[NDArray[np.int64]]] = [[] for _ in models]
    half = np.arange(
        -search.aligned_window_rad, search.aligned_window_rad + 1e-9, search.aligned_step_rad
    )
    aligned_phis = np.concatenate([half, np.pi + half])
    scan_phis = np.arange(0.0, 2 * np.pi - 1e-9, search.scan_step_rad)
    for hyp in hypotheses(geometry):
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
            candidates[w].append(pool.site[rows])
            if rows.size == 0:
                log[w] += time.perf_counter() - start
                continue
            aligned = data_anisotropic & (
                pool.k1[rows] - pool.k2[rows] >= search.aligned_anisotropy
            )
            for mask, phis in ((aligned, aligned_phis), (~aligned, scan_phis)):
                if not mask.any():
                    continue
                v = pool.site[rows[mask]]
                assert pool.d1 is not None  # the candidate map carries principal directions
                F = frames(model.normals[v], pool.d1[rows[mask]])
                turns = rotation_about(2, phis)
                patterns = np.einsum("fij,pj->fpi", turns, local)  # (F, P, 3)
                pre_patterns = np.einsum("fij,pj->fpi", turns, pre_local)
                which = np.full(len(v), which_field[w])
                origins = model.vertices[v]
                pre = np.abs(stack.nearest_in_frames(which, F, origins, pre_patterns))
                pre = pre.mean(axis=-1).ravel()
                count = max(search.n_screened, int(np.ceil(search.prescreen_keep * pre.size)))
                c, f = np.divmod(_smallest(pre, count), len(phis))
                score = np.abs(
                    stack.nearest_in_frames(which[c], F[c], origins[c], patterns[f], paired=True)
                ).mean(axis=-1)
                keep = _smallest(score, search.n_screened)
                c, f, score = c[keep], f[keep], score[keep]
                R = F[c] @ turns[f] @ hyp.frame.T
                best_R[w].append(R)
                best_t[w].append(origins[c] - R @ hyp.point)
                best_s[w].append(score)
            log[w] += time.perf_counter() - start
    out: list[tuple[_Poses | None, NDArray[np.int64]]] = []
    for w in range(len(models)):
        cands = np.concatenate(candidates[w]) if candidates[w] else np.zeros(0, np.int64)
        if not best_R[w]:
            out.append((None, cands))
            continue
        R, t, s = (np.concatenate(x) for x in (best_R[w], best_t[w], best_s[w]))
        keep = np.argsort(s, kind="stable")[: search.n_screened]
        out.append((_Poses(R[keep], t[keep]), cands))
    return out


def _search(
    models: Sequence[MeshModel],
    stack: FieldStack,
    curves: DataCurves,
    geometry: LocalSurfaceGeometry,
    config: FastConfig,
    search: FastSearchConfig,
    which_field: IntArray,
) -> list[Registration]:
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

    def batched(poses: list[_Poses | None], stage_points: Array, steps: int) -> list[_Poses | None]:
        """Gauss-Newton of every model's poses in one batch; time shared by pose count."""
        live = [(w, p) for w, p in enumerate(poses) if p is not None]
        if not live:
            return poses
        start = time.perf_counter()
        owner = np.concatenate([np.full(len(p.R), w) for w, p in live])
        R, t, rms, trace = _gauss_newton(
            stack,
            which_field[owner],
            stage_points,
            np.concatenate([p.R for _, p in live]),
            np.concatenate([p.t for _, p in live]),
            steps,
        )
        counts = np.bincount(owner, minlength=n)
        seconds[:] += (time.perf_counter() - start) * counts / counts.sum()
        iterations[[w for w, _ in live]] += len(trace) - 1
        out = list(poses)
        for w, _ in live:
            sel = owner == w
            out[w] = _Poses(R[sel], t[sel], rms[sel])
        return out

    def distinct(poses: list[_Poses | None], n_keep: int) -> list[_Poses | None]:
        out: list[_Poses | None] = []
        for w, p in enumerate(poses):
            if p is None:
                out.append(None)
                continue
            assert p.rms is not None  # refined poses
            start = time.perf_counter()
            keep = _distinct(p.R, p.t, p.rms, geometry.point, n_keep)
            out.append(_Poses(p.R[keep], p.t[keep]))
            seconds[w] += time.perf_counter() - start
        return out

    poses = batched([p for p, _ in screened], points[screen_idx], search.screen_iterations)
    poses = batched(distinct(poses, search.n_coarse), points[coarse_idx], search.coarse_iterations)
    status = [RegistrationStatus.CONVERGED] * n
    coarse_rms = {w: float(p.rms.min()) for w, p in enumerate(poses) if p and p.rms is not None}
    if config.prune_ratio is not None and coarse_rms:
        best = min(coarse_rms.values())
        for w, value in coarse_rms.items():
            if value > config.prune_ratio * best:
                status[w] = RegistrationStatus.PRUNED
    final = [
        p if s is RegistrationStatus.CONVERGED else None for p, s in zip(poses, status, strict=True)
    ]
    final = batched(distinct(final, search.n_final), points, search.final_iterations)
    out = []
    for w, model in enumerate(models):
        candidates = screened[w][1]
        source = final[w] if final[w] is not None else poses[w]
        if source is None or source.rms is None:
            out.append(rejected(model.name, RegistrationMode.FAST, 0.0, candidates, seconds[w]))
            continue
        start = time.perf_counter()
        b = int(np.argmin(source.rms))
        R, t = source.R[b], source.t[b]
        error = float(_field_errors(stack, which_field[[w]], points, R[None], t[None])[0])
        out.append(
            Registration(
                model.name,
                error,
                pose_matrix(R, t),
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


def _field_errors(
    stack: FieldStack, which_field: IntArray, points: Array, R: Array, t: Array
) -> Array:
    """Mean |sdf| of the data points at poses R (B, 3, 3), t (B, 3) in fields (B,)."""
    X = (R @ points.T).transpose(0, 2, 1) + t[:, None, :]
    return np.mean(np.abs(stack(X, which_field)), axis=1)


def register_fast(
    models: Sequence[MeshModel],
    curves: DataCurves,
    geometry: LocalSurfaceGeometry,
    config: FastConfig = FastConfig(),
    *,
    stack: FieldStack | None = None,
    which_field: ArrayLike | None = None,
    noise_m: float | None = None,
) -> list[Registration]:
    """Fast-mode registration of the curves on several models at once (module docstring).

    Parameters
    ----------
    models : sequence of MeshModel
    curves : DataCurves
    geometry : LocalSurfaceGeometry
        The data's local geometry (:func:`data_geometry`).
    config : FastConfig
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
    trusted = data_fit_residual_m(curves, config.geometry, geometry.point) <= (
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


def _polish(
    models: Sequence[MeshModel],
    curves: DataCurves,
    geometry: LocalSurfaceGeometry,
    registrations: Sequence[Registration],
    config: FastConfig,
) -> list[Registration]:
    """Exact errors, poses polished on closest points, for the models that can win."""
    field_errors = [r.error_m for r in registrations if not r.error_is_exact]
    exact_errors = [r.error_m for r in registrations if r.error_is_exact]
    best = min(field_errors + exact_errors, default=float("inf"))
    if not np.isfinite(best):
        return list(registrations)
    limit = config.polish_ratio * best + config.polish_margin_m
    out = list(registrations)
    for w, reg in enumerate(registrations):
        if not reg.error_is_exact and reg.error_m <= limit:
            out[w] = with_exact_error(
                reg, models[w], curves, True, geometry.point, config.polish_iterations
            )
    return out
