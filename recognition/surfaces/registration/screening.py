"""The fast search's first stage: every model's candidate poses scored on the distance
fields, in one batch across the models.

At each candidate vertex the data are superposed (p on the vertex, N on its normal,
Section 4.1.2.2) at rotations phi about the normal, and each (candidate, phi) pose is
scored by the mean distance of a few data points read off the model's field at the
nearest voxel: first on the prescreening points, then the best of each model again on
the screening points. The candidates of all models go through each step together (the
rotation patterns are the data's, the same for every model), so that the cost grows with
the number of candidates, which the budgets bound, not with the number of models.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from recognition.rigid import rotation_about
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.distance import FieldStack
from recognition.surfaces.local_geometry import LocalSurfaceGeometry
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.registration.candidates import CandidateIndex, smallest
from recognition.surfaces.registration.config import FastConfig, FastSearchConfig
from recognition.surfaces.registration.superposition import frames, hypotheses
from recognition.surfaces.rings import data_ring_descriptors

__all__ = ["Poses", "Screened", "arm_indices", "screen"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class Poses:
    """A model's poses at one stage of the search: R (k, 3, 3), t (k, 3), and their RMS
    residual (k,) once refined."""

    R: Array
    t: Array
    rms: Array | None = None


@dataclass(frozen=True)
class Screened:
    """One model's outcome of the screen.

    Attributes
    ----------
    poses : Poses or None
        Its best screened poses (None: none left).
    candidates : (c,) int
        The candidate vertices.
    matched : bool
        Whether it had candidates within the lookup tolerance (False: rejected at table
        lookup).
    """

    poses: Poses | None
    candidates: IntArray
    matched: bool


def arm_indices(curves: DataCurves, point: Array, fractions: Sequence[float] | Array) -> IntArray:
    """Indices into ``curves.points`` of the points at ``fractions`` of each arm's length.

    An arm runs from the point of a curve nearest p to one of its ends; the result holds,
    per curve and fraction, the index on the forward arm then on the backward arm. A curve
    that p ends (a sweep truncated on one side) has one arm only: both samples of a
    fraction f then lie on it, at f and f / 2.
    """
    idx, offset = [], 0
    for c in curves.curves:
        m = int(np.argmin(np.linalg.norm(c - point, axis=1)))
        n = len(c)
        ahead, behind = n - 1 - m, m
        for f in fractions:
            if ahead == 0 or behind == 0:
                arm, sign = (ahead, 1) if ahead > 0 else (behind, -1)
                for g in (f, f / 2):
                    idx.append(offset + m + sign * max(1, round(g * arm)))
                continue
            idx.append(offset + min(n - 1, m + max(1, round(f * ahead))))
            idx.append(offset + max(0, m - max(1, round(f * behind))))
        offset += n
    return np.array(idx, dtype=np.int64)


@dataclass(frozen=True)
class _Candidates:
    """The candidates of all models for one data hypothesis, grouped by model (rows of
    model ``w`` are ``slice(start[w], start[w + 1])``).

    site : (C,) vertex; normal, d1, origin : (C, 3) its normal, principal direction and
    position; anisotropy : (C,) k1 - k2; owner : (C,) the model's index."""

    site: IntArray
    normal: Array
    d1: Array
    origin: Array
    anisotropy: Array
    owner: IntArray
    start: IntArray


def _thinned(
    models: Sequence[MeshModel],
    chosen: Sequence[IntArray],
    hyp: LocalSurfaceGeometry,
    spacing: float,
) -> _Candidates:
    """Of each model's candidate map rows ``chosen``, the one nearest the data's (k1, k2)
    in each cubic cell of side ``spacing`` (metres), so that candidates cover every
    matching region about evenly; in the order of (model, cell)."""
    parts: list[tuple[NDArray[Any], ...]] = []
    for w, (model, rows) in enumerate(zip(models, chosen, strict=True)):
        if rows.size == 0:
            continue
        pool = model.candidate_curvatures
        assert pool.d1 is not None  # the candidate map carries principal directions
        cell = model.cell_keys(spacing)[pool.site[rows]]
        order = np.lexsort((np.hypot(pool.k1[rows] - hyp.k1, pool.k2[rows] - hyp.k2), cell))
        first = np.ones(order.size, bool)
        first[1:] = cell[order[1:]] != cell[order[:-1]]
        rows = rows[order[first]]
        site = pool.site[rows]
        parts.append(
            (
                np.full(rows.size, w),
                site,
                model.normals[site],
                pool.d1[rows],
                model.vertices[site],
                pool.k1[rows] - pool.k2[rows],
            )
        )
    if not parts:
        empty = np.zeros((0, 3))
        return _Candidates(
            np.zeros(0, np.int64), empty, empty, empty, np.zeros(0), np.zeros(0, np.int64),
            np.zeros(len(models) + 1, np.int64),
        )  # fmt: skip
    owner, site, normal, d1, origin, anisotropy = (
        np.concatenate(x) for x in zip(*parts, strict=True)
    )
    start = np.searchsorted(owner, np.arange(len(models) + 1))
    return _Candidates(site, normal, d1, origin, anisotropy, owner, start)


def screen(
    models: Sequence[MeshModel],
    stack: FieldStack,
    which_field: IntArray,
    curves: DataCurves,
    geometry: LocalSurfaceGeometry,
    config: FastConfig,
    search: FastSearchConfig,
    log: Array,
    index: CandidateIndex,
    contact: Array,
) -> list[Screened]:
    """Candidate poses of every model, scored on the screening points.

    The candidates come from all the models at once (:meth:`CandidateIndex.select`,
    within the ``candidate_budget``), one per cell. Every pose is first scored on the
    prescreening points; the best ``prescreen_keep`` of each model's (at least
    ``n_screened``) are scored again on the screening points. Returns, per model, its best
    ``n_screened`` poses (with a ``screened_budget``, only those among the best of all
    models), the candidate vertices, and whether it had candidates within the lookup
    tolerance. ``log`` (per model, seconds) receives the time, shared by candidate count.
    ``contact`` (k, 3), further contact points of the data (verification touches; may be
    empty), joins both the prescreening and the screening points.
    """
    n = len(models)
    points = np.concatenate(
        [curves.points[arm_indices(curves, geometry.point, search.arm_fractions)], contact]
    )
    pre_points = np.concatenate(
        [curves.points[arm_indices(curves, geometry.point, search.prescreen_fractions)], contact]
    )
    best_R: list[list[Array]] = [[] for _ in models]
    best_t: list[list[Array]] = [[] for _ in models]
    best_s: list[list[Array]] = [[] for _ in models]
    candidates: list[list[IntArray]] = [[] for _ in models]
    matched = np.zeros(n, bool)
    half = np.arange(
        -search.aligned_window_rad, search.aligned_window_rad + 1e-9, search.aligned_step_rad
    )
    aligned_phis = np.concatenate([half, np.pi + half])
    scan_phis = np.arange(0.0, 2 * np.pi - 1e-9, search.scan_step_rad)
    for hyp in hypotheses(geometry):
        start_time = time.perf_counter()
        tolerance = search.tolerance_scale * (
            config.delta + config.relative_delta * max(abs(hyp.k1), abs(hyp.k2))
        )
        local = (points - hyp.point) @ hyp.frame  # (P, 3) in the data's (d1, d2, N) frame
        pre_local = (pre_points - hyp.point) @ hyp.frame
        chosen, within = index.select(
            hyp,
            data_ring_descriptors(curves, hyp),
            tolerance,
            search.candidate_budget,
            which_field,
        )
        matched |= within
        cand = _thinned(models, chosen, hyp, search.candidate_spacing_m)
        for w in range(n):
            candidates[w].append(cand.site[cand.start[w] : cand.start[w + 1]])
        aligned = (hyp.k1 - hyp.k2 >= search.aligned_anisotropy) & (
            cand.anisotropy >= search.aligned_anisotropy
        )
        for mask, phis in ((aligned, aligned_phis), (~aligned, scan_phis)):
            sel = np.flatnonzero(mask)
            if not sel.size:
                continue
            owner = cand.owner[sel]
            F = frames(cand.normal[sel], cand.d1[sel])
            turns = rotation_about(2, phis)
            which = which_field[owner]
            origins = cand.origin[sel]
            pre_patterns = np.einsum("fij,pj->fpi", turns, pre_local)  # (phi, P, 3)
            pre = np.abs(stack.nearest_in_frames(which, F, origins, pre_patterns)).mean(axis=-1)
            bounds = np.searchsorted(owner, np.arange(n + 1))
            picked = []
            for m in np.flatnonzero(np.diff(bounds)):
                a, b = bounds[m], bounds[m + 1]
                block = pre[a:b].ravel()
                count = max(search.n_screened, int(np.ceil(search.prescreen_keep * block.size)))
                picked.append(a * len(phis) + smallest(block, count))
            c, f = np.divmod(np.concatenate(picked), len(phis))
            patterns = np.einsum("fij,pj->fpi", turns, local)
            score = np.abs(
                stack.nearest_in_frames(which[c], F[c], origins[c], patterns[f], paired=True)
            ).mean(axis=-1)
            ends = np.searchsorted(owner[c], np.arange(n + 1))
            for m in np.flatnonzero(np.diff(ends)):
                a, b = ends[m], ends[m + 1]
                keep = a + smallest(score[a:b], search.n_screened)
                R = F[c[keep]] @ turns[f[keep]] @ hyp.frame.T
                best_R[m].append(R)
                best_t[m].append(origins[c[keep]] - R @ hyp.point)
                best_s[m].append(score[keep])
        log += (time.perf_counter() - start_time) * (
            np.diff(cand.start) / max(cand.site.size, 1) if cand.site.size else 1.0 / n
        )
    scores = [np.concatenate(x) if x else np.zeros(0) for x in best_s]
    cutoff = np.inf
    if search.screened_budget is not None:
        ranked = np.concatenate(
            [np.sort(x, kind="stable")[: search.n_screened] for x in scores] or [np.zeros(0)]
        )
        if ranked.size > search.screened_budget:
            cutoff = np.partition(ranked, search.screened_budget - 1)[search.screened_budget - 1]
    out = []
    for w in range(n):
        cands = np.concatenate(candidates[w]) if candidates[w] else np.zeros(0, np.int64)
        keep = np.argsort(scores[w], kind="stable")[: search.n_screened]
        keep = keep[scores[w][keep] <= cutoff]
        if not keep.size:
            out.append(Screened(None, cands, bool(matched[w])))
            continue
        R, t = (np.concatenate(x) for x in (best_R[w], best_t[w]))
        out.append(Screened(Poses(R[keep], t[keep]), cands, bool(matched[w])))
    return out
