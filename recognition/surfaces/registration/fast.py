"""The fast mode: every model's candidate poses screened in one batch on distance fields.

The data's normal and curvatures are estimated at the point where all three curves meet,
at the scale of the models' fits (:func:`~recognition.surfaces.registration.data.
data_geometry`). Table lookup (4.7) in a curvature map of one vertex per 1 mm cell, over
every model at once; of the rows it keeps, at most ``candidate_budget`` across the
database, those whose ring descriptors (the surface's height on rings about the vertex,
:mod:`~recognition.surfaces.rings`) best match the data's
(:class:`~recognition.surfaces.registration.candidates.CandidateIndex`); thinned to one
candidate per 2.5 mm cell. Where the curve fits at p do not explain the data (p on a
crease), candidates come from the whole surface. At each candidate the data
are superposed (p on the vertex, N on its normal, Section 4.1.2.2) at rotations phi about
the normal: a window around the alignment of the principal directions where both data
and model are clearly anisotropic, a full scan elsewhere. Every (candidate, phi) pose of
every model is screened in one vectorised batch on the models' narrow-band signed
distance fields with a few points per arm of the data; the best poses of each model (at
most ``screened_budget`` across the database) slide
into their basins by batched Gauss-Newton over all six degrees of freedom on ever more
points, near-duplicates dropped between stages; each stage's loss is a truncated
quadratic, so that a gross outlier does not pull the pose. A model whose screened or
coarse fit is far worse than the best model's stops there (most models of a database stop
after the first steps). The reported error is the mean
point-to-surface distance (4.8), each point counted at most the outlier threshold
(:func:`~recognition.surfaces.registration.data.outlier_threshold_m`), exact (closest
points on the triangles, pose polished) for the models that can win. When even the best
model fits worse than the data's own noise explains, the models not rejected at table
lookup are searched again over their whole surface, ever more densely
(:attr:`FastConfig.fallbacks`).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.least_squares import LeastSquaresConfig, State, damped_least_squares
from recognition.rigid import pose_matrix, rotation_from_vector
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.distance import FieldStack
from recognition.surfaces.local_geometry import LocalSurfaceGeometry
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.registration.ambiguity import Resolution, distinct_poses
from recognition.surfaces.registration.candidates import CandidateIndex
from recognition.surfaces.registration.config import FastConfig, FastSearchConfig
from recognition.surfaces.registration.data import (
    acceptable_error_m,
    data_fit_residual_m,
    data_noise_m,
    outlier_threshold_m,
)
from recognition.surfaces.registration.exact import polish
from recognition.surfaces.registration.result import (
    Registration,
    RegistrationMode,
    RegistrationStatus,
    rejected,
)
from recognition.surfaces.registration.screening import Poses, arm_indices, screen

__all__ = ["fit_on_fields", "register_fast"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


#: With a clip, a start's points count at most this many robust standard deviations of
#: its first residuals (and at least the clip).
CLIP_SIGMAS = 4.0


def fit_on_fields(
    stack: FieldStack,
    which: IntArray,
    points: Array,
    R: Array,
    t: Array,
    iterations: int,
    tolerance: float = 1e-4,
    clip_m: float | None = None,
    unclipped: int = 0,
) -> tuple[Array, Array, Array, tuple[float, ...]]:
    """Batched Levenberg-damped Gauss-Newton of poses on signed distance fields.

    Minimises sum_i sdf(R q_i + t)^2 for each of the B starts in its own field
    ``which`` (B,); R (B, 3, 3), t (B, 3), points (P, 3). With ``clip_m`` the loss is a
    truncated quadratic: a residual counts at most the larger of ``clip_m`` and
    ``CLIP_SIGMAS`` robust standard deviations (1.4826 times the median absolute
    residual) of the start's first residuals, and pulls the pose not at all beyond (an
    outlier); the last ``unclipped`` points are trusted and never clipped. A start
    stops once a step lowers its cost by less than the fraction ``tolerance`` (or its
    damping exceeds 1e6); at most ``iterations`` steps. The
    rotation turns about the centroid of the placed points. Returns R, t, the RMS
    residual per start (clipped residuals at the clip) and the best RMS after each step.
    """

    def evaluate(R: Array, t: Array, which: IntArray, clip: Array) -> State:
        X = points @ R.transpose(0, 2, 1) + t[:, None, :]  # (B, P, 3), C order
        r, g = stack.value_and_gradient(X, which)
        return R, t, which, X, r, g, clip

    def cost(state: State) -> Array:
        r, clip = state[4], state[6]
        return np.mean(np.minimum(r * r, clip**2), axis=1)

    from recognition.surfaces import field_kernels  # numba: imported when first needed

    def normal_equations(state: State) -> tuple[Array, Array]:
        return field_kernels.rigid_normal_equations(*state[3:7])

    def retract(state: State, step: Array) -> State:
        R, t, which, X = state[:4]
        c = X.mean(axis=1)
        dR = rotation_from_vector(step[:, :3])
        t_new = (dR @ (t - c)[..., None])[..., 0] + c + step[:, 3:]
        return evaluate(dR @ R, t_new, which, state[6])

    which = np.asarray(which)
    clip = np.full((len(R), len(points)), np.inf)
    state = evaluate(R, t, which, clip)
    if clip_m is not None:
        clipped = len(points) - unclipped
        spread = CLIP_SIGMAS * 1.4826 * np.median(np.abs(state[4][:, :clipped]), axis=1)
        clip[:, :clipped] = np.maximum(spread, clip_m)[:, None]
    result = damped_least_squares(
        state,
        cost=cost,
        normal_equations=normal_equations,
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


def _search(
    models: Sequence[MeshModel],
    stack: FieldStack,
    curves: DataCurves,
    geometry: LocalSurfaceGeometry,
    config: FastConfig,
    search: FastSearchConfig,
    which_field: IntArray,
    threshold_m: float,
    index: CandidateIndex,
    contact: Array,
) -> list[Registration]:
    """One pass of the fast search over ``models`` (fields ``which_field`` in ``stack``,
    candidates ranked by ``index``).

    Returns one registration per model, its error read off the distance field, each
    point's distance counted at most ``threshold_m`` (beyond it the point is an outlier).
    The ``contact`` points (k, 3) join the curves' at every stage of the search, so that
    they choose and move the poses, but not the error.
    """
    n = len(models)
    seconds = np.zeros(n)
    iterations = np.zeros(n, dtype=np.int64)
    points = curves.points
    screen_idx = arm_indices(curves, geometry.point, search.arm_fractions)
    fractions = np.arange(1, search.coarse_per_arm + 1) / search.coarse_per_arm
    coarse_idx = np.unique(arm_indices(curves, geometry.point, fractions))
    screened = screen(
        models, stack, which_field, curves, geometry, config, search, seconds, index, contact
    )

    def batched(
        poses: list[Poses | None], stage_points: Array, steps: int, clip_m: float | None = None
    ) -> list[Poses | None]:
        """Gauss-Newton of every model's poses in one batch; time shared by pose count."""
        live = [(w, p) for w, p in enumerate(poses) if p is not None]
        if not live:
            return poses
        start = time.perf_counter()
        owner = np.concatenate([np.full(len(p.R), w) for w, p in live])
        R, t, rms, trace = fit_on_fields(
            stack,
            which_field[owner],
            np.concatenate([stage_points, contact]),
            np.concatenate([p.R for _, p in live]),
            np.concatenate([p.t for _, p in live]),
            steps,
            clip_m=clip_m,
            unclipped=len(contact),
        )
        counts = np.bincount(owner, minlength=n)
        seconds[:] += (time.perf_counter() - start) * counts / counts.sum()
        iterations[[w for w, _ in live]] += len(trace) - 1
        out = list(poses)
        for w, _ in live:
            sel = owner == w
            out[w] = Poses(R[sel], t[sel], rms[sel])
        return out

    def distinct(poses: list[Poses | None], n_keep: int) -> list[Poses | None]:
        out: list[Poses | None] = []
        for w, p in enumerate(poses):
            if p is None:
                out.append(None)
                continue
            assert p.rms is not None  # refined poses
            start = time.perf_counter()
            keep = distinct_poses(p.R, p.t, p.rms, geometry.point, n_keep)
            out.append(Poses(p.R[keep], p.t[keep]))
            seconds[w] += time.perf_counter() - start
        return out

    status = [RegistrationStatus.CONVERGED] * n

    def prune(
        poses: list[Poses | None], ratio: float | None, most: int | None
    ) -> list[Poses | None]:
        """The poses of the models still running whose best RMS is within ``ratio`` of
        the best model's, at most the ``most`` best models (None for the others, now
        pruned)."""
        rms = {
            w: float(p.rms.min())
            for w, p in enumerate(poses)
            if p is not None and p.rms is not None and status[w] is RegistrationStatus.CONVERGED
        }
        if ratio is not None and rms:
            best = min(rms.values())
            for w, value in rms.items():
                if value > ratio * best:
                    status[w] = RegistrationStatus.PRUNED
        if most is not None:
            for w in sorted(rms, key=rms.__getitem__)[most:]:
                status[w] = RegistrationStatus.PRUNED
        return [
            p if s is RegistrationStatus.CONVERGED else None
            for p, s in zip(poses, status, strict=True)
        ]

    first = batched(
        [s.poses for s in screened], points[screen_idx], search.screen_iterations, threshold_m
    )
    coarse = batched(
        distinct(prune(first, config.screen_prune_ratio, search.coarse_models), search.n_coarse),
        points[coarse_idx],
        search.coarse_iterations,
        threshold_m,
    )
    final = batched(
        distinct(prune(coarse, config.prune_ratio, search.final_models), search.n_final),
        points,
        search.final_iterations,
        threshold_m,
    )
    # the best n_final poses of every model (a pruned model's from the stage it stopped
    # at) scored in one batch, the least RMS residual first
    ranked: dict[int, tuple[Array, Array]] = {}
    for w in range(n):
        source = next((p[w] for p in (final, coarse, first) if p[w] is not None), None)
        if source is not None and source.rms is not None:
            order = np.argsort(source.rms, kind="stable")[: search.n_final]
            ranked[w] = (source.R[order], source.t[order])
    start = time.perf_counter()
    live = list(ranked)
    R_all = np.concatenate([ranked[w][0] for w in live] or [np.zeros((0, 3, 3))])
    t_all = np.concatenate([ranked[w][1] for w in live] or [np.zeros((0, 3))])
    counts = np.array([len(ranked[w][0]) for w in live], dtype=np.int64)
    fields = np.repeat(which_field[live], counts) if live else np.zeros(0, np.int64)
    distances = _field_distances(stack, fields, points, R_all, t_all)
    bounds = np.cumsum(counts)
    scored = {w: np.arange(b - c, b) for w, b, c in zip(live, bounds, counts, strict=True)}
    seconds_per_pose = (time.perf_counter() - start) / max(int(bounds[-1]) if live else 0, 1)
    out = []
    for w, model in enumerate(models):
        candidates, matched = screened[w].candidates, screened[w].matched
        if w not in scored:
            # a model with candidates that the budgets left out is pruned, not rejected
            dropped = rejected(model.name, RegistrationMode.FAST, 0.0, candidates, seconds[w])
            if matched:
                dropped = replace(dropped, status=RegistrationStatus.PRUNED)
            out.append(dropped)
            continue
        rows = scored[w]
        errors = np.mean(np.minimum(distances[rows], threshold_m), axis=1)
        found = pose_matrix(R_all[rows], t_all[rows])
        out.append(
            Registration(
                model.name,
                float(errors[0]),
                found[0],
                found[0, :3, :3] @ geometry.point + found[0, :3, 3],
                candidates,
                int(iterations[w]),
                status[w],
                seconds[w] + seconds_per_pose * len(rows),
                RegistrationMode.FAST,
                error_is_exact=False,
                outliers=np.flatnonzero(distances[rows[0]] > threshold_m),
                outlier_threshold_m=threshold_m,
                poses=found,
                pose_errors_m=errors,
            )
        )
    return out


def _field_distances(
    stack: FieldStack, which_field: IntArray, points: Array, R: Array, t: Array
) -> Array:
    """|sdf| (B, P) of the data points at poses R (B, 3, 3), t (B, 3) in fields (B,)."""
    X = (R @ points.T).transpose(0, 2, 1) + t[:, None, :]
    return np.abs(stack(X, which_field))


def register_fast(
    models: Sequence[MeshModel],
    curves: DataCurves,
    geometry: LocalSurfaceGeometry,
    config: FastConfig = FastConfig(),
    *,
    stack: FieldStack | None = None,
    which_field: ArrayLike | None = None,
    noise_m: float | None = None,
    index: CandidateIndex | None = None,
    contact: ArrayLike | None = None,
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
        The data's noise across the surface (default :func:`data_noise_m`), for the
        fallback test and the outlier threshold.
    index : CandidateIndex, optional
        The models' candidate maps in one table, its owners the fields of ``stack``
        (built here if not given).
    contact : (k, 3) float, optional
        Further contact points in the curves' frame (verification touches): they join
        the curves' points in choosing and refining the poses (a pose that misses them
        is screened out), not in the errors, the polish or the fallback test.

    Returns
    -------
    list of Registration
        One per model, in order. Errors are exact (poses polished on closest points) for
        the models that can win; the others are read off the distance fields. Either way
        a point counts at most the outlier threshold
        (:func:`~recognition.surfaces.registration.data.outlier_threshold_m`).
    """
    models = list(models)
    if stack is None:
        stack = FieldStack.of([m.distance_field for m in models])
    which_field = np.arange(len(models)) if which_field is None else np.asarray(which_field)
    if index is None:
        index = CandidateIndex.of(models, which_field)
    noise = data_noise_m(curves) if noise_m is None else noise_m
    threshold = outlier_threshold_m(noise, config)
    trusted = data_fit_residual_m(curves, config.geometry, geometry.point) <= (
        config.fit_noise_factor * noise + config.fit_floor_m
    )
    search = config.search
    if not trusted:
        search = replace(search, tolerance_scale=np.inf, aligned_anisotropy=np.inf)
    extra = np.zeros((0, 3)) if contact is None else np.asarray(contact, float).reshape(-1, 3)
    first = _search(
        models, stack, curves, geometry, config, search, which_field, threshold, index, extra
    )
    registrations = _polish(models, curves, geometry, first, config, threshold, noise)
    acceptable = acceptable_error_m(noise, len(curves.points), config)
    for fallback in config.fallbacks:
        if min(r.error_m for r in registrations) <= acceptable:
            break
        # models rejected at table lookup stay rejected: the fallback searches the others
        kept = [
            w
            for w, r in enumerate(registrations)
            if r.status is not RegistrationStatus.NO_CANDIDATES
        ]
        if not kept:
            break
        found = _search(
            [models[w] for w in kept],
            stack,
            curves,
            geometry,
            config,
            fallback,
            which_field[kept],
            threshold,
            index,
            extra,
        )
        merged = list(registrations)
        for w, b in zip(kept, found, strict=True):
            a = registrations[w]
            better = b if b.error_m < a.error_m else a
            merged[w] = replace(
                better,
                candidates=np.union1d(a.candidates, b.candidates),
                iterations=a.iterations + b.iterations,
                time_s=a.time_s + b.time_s,
            )
        registrations = _polish(models, curves, geometry, merged, config, threshold, noise)
    return registrations


def _polish(
    models: Sequence[MeshModel],
    curves: DataCurves,
    geometry: LocalSurfaceGeometry,
    registrations: Sequence[Registration],
    config: FastConfig,
    threshold_m: float,
    noise_m: float,
) -> list[Registration]:
    """Exact errors, poses polished on closest points (outliers beyond ``threshold_m``
    left out), for the models that can win; their poses equivalent under the data's
    noise ``noise_m`` counted, and the directions it leaves free (:class:`Resolution`).

    A model is polished when its distance-field error is within ``polish_ratio`` times
    the best plus ``polish_margin_m``. So are those of its first ``polish_poses`` distinct
    poses whose field errors are within ``polish_margin_m`` of its best (the distance
    field cannot tell them apart: a pose second on the field may be first on the
    triangles). The least exact error is the registration's.
    """
    errors = [r.error_m for r in registrations]
    best = min(errors, default=float("inf"))
    if not np.isfinite(best):
        return list(registrations)
    limit = config.polish_ratio * best + config.polish_margin_m
    resolution = Resolution.of(noise_m, len(curves.points), config)
    out = list(registrations)
    for w, reg in enumerate(registrations):
        if reg.error_is_exact or reg.error_m > limit:
            continue
        close = reg.pose_errors_m[: config.polish_poses]
        within = np.cumprod(close <= min(limit, reg.error_m + config.polish_margin_m))
        count = max(1, int(within.sum()))  # poses come best first
        out[w] = polish(
            reg,
            models[w],
            curves,
            point=geometry.point,
            iterations=config.polish_iterations,
            threshold_m=threshold_m,
            poses=reg.poses[:count] if len(reg.poses) else None,
            resolution=resolution,
        )
    return out
