"""Poses from oriented contact: two surface points with their normals fix a pose.

The curves give their common point p with the surface normal there; a verification
touch gives its contact point with the normal the sensor felt. Two oriented points
(x1, n1), (x2, n2) a distance D apart carry four features that no rigid motion changes
(the point pair features of Drost et al., CVPR 2010, with the dihedral's sign so that a
mirror image does not match):

    d = (x2 - x1) / D,   f = (n1 . d,  n2 . d,  n1 . n2,  (n1 x d) . n2),

and, unless n1 is parallel to d, a frame: e1 = d, e2 = the part of n1 across d
(normalised), e3 = e1 x e2. A pair of model vertices (a, b) whose distance and features
match the data's proposes the pose that maps the data's frame onto the model's, the
pair's midpoint onto the model pair's. Where p's curvatures fit many places of a model
(a nearly spherical body, a flat face), the curves alone leave its pose free, but a touch
away from p names the few places and turns that fit both: this is how a broader search
(:meth:`~recognition.surfaces.database.ModelDatabase.broaden`) finds poses that the
curvature lookup at p never proposed. A touch that met nothing counts too: a pose that
puts the surface across its approach cannot be the truth (:func:`contact_costs`).

The model side is sampled at one vertex per cubic cell of ``PAIR_SPACING_M``; the
tolerances cover that sampling (a vertex lies up to a cell's diagonal from the true point,
its normal turned by the surface's curvature over that distance) and the data's own
errors. The poses are coarse (a cell off): they are starts, to be refined on the fields.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from recognition.rigid import pose_matrix
from recognition.surfaces.distance import FieldStack
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.registration.ambiguity import distinct_poses
from recognition.surfaces.registration.fast import fit_on_fields

__all__ = [
    "DISTANCE_TOLERANCE_M",
    "FEATURE_TOLERANCE",
    "MISS_STEP_M",
    "PAIR_SPACING_M",
    "contact_costs",
    "pair_features",
    "pair_poses",
    "pair_search",
]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Model vertices are sampled one per cubic cell of this side, metres.
PAIR_SPACING_M = 4.0e-3
#: A model pair matches when its distance is within this of the data pair's, metres.
DISTANCE_TOLERANCE_M = 3.0e-3
#: ... and each of its four features (cosines) within this of the data pair's.
FEATURE_TOLERANCE = 0.25
#: At most this many pair poses of a model are scored (a seeded draw beyond), each on the
#: touches and at most ``SCORE_POINTS`` of the curves' points ...
MAX_SCORED = 20_000
SCORE_POINTS = 12
#: ... the best this many refined on the model's field (the defaults of ``pair_search``) ...
N_REFINED = 16
#: ... and this many distinct ones returned.
N_KEPT = 8
#: A touch that met nothing is read along its approach every this many metres.
MISS_STEP_M = 1.0e-3
#: Gauss-Newton steps of the refinement.
ITERATIONS = 10
#: Anchor vertices processed together (bounds the memory of the distance block).
_CHUNK = 512


def pair_features(x1: Array, n1: Array, x2: Array, n2: Array) -> tuple[Array, Array, Array]:
    """Distances (k,), features (k, 4) and frames (k, 3, 3) (columns e1, e2, e3) of the
    oriented point pairs (x1, n1), (x2, n2), each (k, 3) (module docstring); a frame is
    NaN where n1 is parallel to the pair's direction."""
    v = x2 - x1
    D = np.linalg.norm(v, axis=-1)
    d = v / np.maximum(D, 1e-12)[..., None]
    along = np.sum(n1 * d, axis=-1)
    features = np.stack(
        [
            along,
            np.sum(n2 * d, axis=-1),
            np.sum(n1 * n2, axis=-1),
            np.sum(np.cross(n1, d) * n2, axis=-1),
        ],
        axis=-1,
    )
    across = n1 - along[..., None] * d
    size = np.linalg.norm(across, axis=-1)
    e2 = across / np.where(size > 1e-6, size, np.nan)[..., None]
    frames = np.stack([d, e2, np.cross(d, e2)], axis=-1)
    return D, features, frames


def pair_poses(
    model: MeshModel,
    point: Array,
    normal: Array,
    contact: Array,
    contact_normal: Array,
    *,
    distance_tolerance_m: float = DISTANCE_TOLERANCE_M,
    feature_tolerance: float = FEATURE_TOLERANCE,
) -> tuple[Array, Array]:
    """The poses (R (K, 3, 3), t (K, 3), T_model_from_data) that map the data's oriented
    pair, ``point`` with its outward unit ``normal`` and ``contact`` with its outward
    unit ``contact_normal`` (each (3,), data frame), onto a matching pair of the model's
    sampled vertices (module docstring). Empty when the data's normal at ``point`` is
    parallel to the pair's direction or nothing matches."""
    one = [
        np.asarray(a, dtype=np.float64).reshape(1, 3)
        for a in (point, normal, contact, contact_normal)
    ]
    D, features, frame = pair_features(*one)
    if not np.all(np.isfinite(frame)):
        return np.zeros((0, 3, 3)), np.zeros((0, 3))
    middle = 0.5 * (one[0][0] + one[2][0])
    sample = model.one_per_cell(PAIR_SPACING_M)
    X, N = model.vertices[sample], model.normals[sample]
    squares = np.sum(X * X, axis=1)
    low, high = max(D[0] - distance_tolerance_m, 0.0) ** 2, (D[0] + distance_tolerance_m) ** 2
    rotations, translations = [], []
    for start in range(0, len(X), _CHUNK):
        a = np.arange(start, min(start + _CHUNK, len(X)))
        gap = squares[a, None] + squares[None, :] - 2.0 * (X[a] @ X.T)  # squared distances
        turn = N[a] @ N.T  # n_a . n_b, the third feature
        near = (gap >= low) & (gap <= high) & (np.abs(turn - features[0, 2]) <= feature_tolerance)
        ia, ib = np.nonzero(near)
        if not len(ia):
            continue
        ia = a[ia]
        _, f, F = pair_features(X[ia], N[ia], X[ib], N[ib])
        keep = np.all(np.abs(f - features[0]) <= feature_tolerance, axis=1)
        keep &= np.all(np.isfinite(F), axis=(1, 2))
        if not keep.any():
            continue
        R = F[keep] @ frame[0].T
        rotations.append(R)
        translations.append(0.5 * (X[ia[keep]] + X[ib[keep]]) - R @ middle)
    if not rotations:
        return np.zeros((0, 3, 3)), np.zeros((0, 3))
    return np.concatenate(rotations), np.concatenate(translations)


def contact_costs(
    stack: FieldStack,
    field: int,
    points: Array,
    misses: Sequence[tuple[Array, Array, float]],
    R: Array,
    t: Array,
    threshold_m: float,
) -> Array:
    """The cost of each pose R (B, 3, 3), t (B, 3) (model from data) of the model whose
    field is ``field`` of ``stack``: the mean, over the ``points`` (n, 3) and the
    ``misses`` (start, unit direction, travel in metres: touches that met nothing, data
    frame), of a point's squared distance from the surface and a miss's squared depth
    to which the posed surface reaches across its approach (read every ``MISS_STEP_M``;
    0 when it stays clear), each counted at most ``threshold_m`` squared. (B,)"""
    which = np.full(len(R), field)
    values = stack(points @ R.transpose(0, 2, 1) + t[:, None, :], which)
    squares = [np.minimum(values * values, threshold_m**2)]
    if len(misses):
        rays = [
            np.asarray(start, float) + np.arange(0.0, travel, MISS_STEP_M)[:, None] * direction
            for start, direction, travel in misses
        ]
        along = stack(np.concatenate(rays) @ R.transpose(0, 2, 1) + t[:, None, :], which)
        starts = np.cumsum([0] + [len(r) for r in rays[:-1]])
        depth = np.maximum(-np.minimum.reduceat(along, starts, axis=1), 0.0)
        squares.append(np.minimum(depth * depth, threshold_m**2))
    return np.mean(np.concatenate(squares, axis=1), axis=1)


def pair_search(
    models: Sequence[MeshModel],
    stack: FieldStack,
    which_field: IntArray,
    curve_points: Array,
    point: Array,
    normal: Array,
    touches: Array,
    touch_normals: Array,
    threshold_m: float,
    seed: int = 0,
    misses: Sequence[tuple[Array, Array, float]] = (),
    refined: int = N_REFINED,
    kept: int = N_KEPT,
) -> list[tuple[str, Array, float]]:
    """Poses of ``models`` (fields ``which_field`` of ``stack``) that fit the curves'
    points (n, 3) and the ``touches`` (k, 3), started from every model pair matching p
    (``point``, outward ``normal``) and a touch with its sensed outward normal
    (``touch_normals`` (k, 3); rows with NaN are not paired): scored on the fields at the
    touches and ``SCORE_POINTS`` of the curves' points (each point's squared distance
    counted at most ``threshold_m`` squared, and each of the ``misses`` as well,
    :func:`contact_costs`), the best ``refined`` of each model refined by Gauss-Newton
    on all the points (the touches never clipped), at most ``kept`` distinct ones kept.
    Returns (model name, T_model_from_data (4, 4), mean distance of the curves' points
    from the model, each counted at most ``threshold_m``). Same arguments and seed, same
    poses."""
    rng = np.random.default_rng(seed)
    paired = np.flatnonzero(np.all(np.isfinite(touch_normals), axis=1))
    data = np.concatenate([curve_points, touches])
    few = np.unique(np.linspace(0, len(curve_points) - 1, SCORE_POINTS).round().astype(np.int64))
    scoring = np.concatenate([curve_points[few], touches])
    out: list[tuple[str, Array, float]] = []
    for model, field in zip(models, which_field, strict=True):
        found = [pair_poses(model, point, normal, touches[j], touch_normals[j]) for j in paired]
        R = np.concatenate([f[0] for f in found] or [np.zeros((0, 3, 3))])
        t = np.concatenate([f[1] for f in found] or [np.zeros((0, 3))])
        if not len(R):
            continue
        if len(R) > MAX_SCORED:
            pick = np.sort(rng.choice(len(R), size=MAX_SCORED, replace=False))
            R, t = R[pick], t[pick]
        cost = contact_costs(stack, field, scoring, misses, R, t, threshold_m)
        best = np.argsort(cost, kind="stable")[:refined]
        R, t, _, _ = fit_on_fields(
            stack,
            np.full(len(best), field),
            data,
            R[best],
            t[best],
            ITERATIONS,
            clip_m=threshold_m,
            unclipped=len(touches),
        )
        placed = curve_points @ R.transpose(0, 2, 1) + t[:, None, :]
        errors = np.mean(
            np.minimum(np.abs(stack(placed, np.full(len(R), field))), threshold_m), axis=1
        )
        for k in distinct_poses(R, t, errors, point, kept):
            out.append((model.name, pose_matrix(R[k], t[k]), float(errors[k])))
    return out
