"""How a verification touch weighs a hypothesis against "none of these" (log ratios, nats).

Each touch counts as the hypothesis predicted it before it was made
(:func:`predicted_evidence`): at its pose then, with the uncertainty of that pose. Scored
after a refit to all the contact instead, a hypothesis that slid along a shallow valley
to meet a touch it had missed by millimetres would lose little (the leave-one-out
leverage linearises at the refitted pose).

The contact point (:func:`point_evidence`): its residual whitened given all the contact
before it, z_i (Sigma's Cholesky factor L; L_ii its conditional noise), spread wider by
q_i = g_i^T C g_i, g_i the whitened residual's change under a small motion of the pose
and C that motion's Laplace covariance; against the uniform spread along the touch's
approach (length w_i) that "none of these" predicts:

    log [N(z_i / sqrt(1 + q_i)) / (L_ii sqrt(1 + q_i))] - log (1 / w_i).

A sensed contact normal n_s (:func:`normal_evidence`): against the normal n the
hypothesis predicts where it puts the contact. Its deviation d = theta B u (theta the
angle between them, u the unit direction of n_s's tilt away from n, B (2, 3) an
orthonormal basis of n's tangent plane) is N(0, C),

    C = sigma_n^2 I + B [n]x Sigma_w [n]x^T B^T,

sigma_n the sensor's and the mismatch's spread (:meth:`NoiseModel.normal_sigma_rad`),
Sigma_w the covariance of the hypothesis's turn (a turn w tilts n by w x n). "None of
these" spreads a normal uniformly over the hemisphere facing the probe, 1 / (2 pi) per
steradian; for small angles the tangent-plane density is per steradian, so the ratio is

    -d^T C^-1 d / 2 - log det(C) / 2.

A touch that met nothing (:func:`miss_evidence`): a surface the ray would have crossed is
a contact the pose predicted that did not happen.

Every squared whitened deviation is counted by Huber's loss (:func:`huber`): a single
contact that no noise explains (a slip, a sharp edge) does not decide alone.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.errors import InvalidArgument
from recognition.rigid import cross, point_to_plane_jacobian, posed
from recognition.surfaces.distance import MeshDistance
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.noise_model import NoiseModel, huber
from recognition.surfaces.registration.exact import smooth_normals

__all__ = [
    "evidence_bounds",
    "miss_evidence",
    "normal_evidence",
    "point_evidence",
    "predicted_evidence",
    "sensed_normals",
]

Array = NDArray[np.float64]


def point_evidence(
    whitened: Array, pose_variance: Array, spread: Array, windows: Array, huber_k: float
) -> Array:
    """Log ratio of the touches' contact points (module docstring): ``whitened`` (..., k)
    the touches' whitened residuals z_i at the predicting pose, ``pose_variance`` (..., k)
    q_i the variance its uncertainty adds to them, ``spread`` (k,) L_ii and ``windows``
    (k,) the approaches' lengths w_i (metres); summed over the touches, (...)."""
    wide = 1.0 + np.maximum(pose_variance, 0.0)
    terms = -huber(whitened / np.sqrt(wide), huber_k) - 0.5 * np.log(wide)
    return np.sum(terms - np.log(np.sqrt(2.0 * np.pi) * spread / windows), axis=-1)


def normal_evidence(
    predicted: Array, sensed: Array, turn_covariance: Array, sigma_rad: float, huber_k: float
) -> Array:
    """Log ratio of the touches' sensed normals (module docstring): ``predicted`` and
    ``sensed`` (..., k, 3) unit normals in one frame (rows of NaN in ``sensed``: no normal
    sensed), ``turn_covariance`` (..., 3, 3) the hypothesis's turn in that frame,
    radians^2; summed over the touches, (...)."""
    known = np.all(np.isfinite(sensed), axis=-1)
    n, s = predicted, np.where(known[..., None], sensed, predicted)
    # an orthonormal basis e1, e2 = n x e1 of each n's tangent plane
    e1 = cross(n, np.eye(3)[np.argmin(np.abs(n), axis=-1)])
    e1 /= np.sqrt(np.sum(e1 * e1, axis=-1))[..., None]
    e2 = cross(n, e1)
    tilt = np.stack([np.sum(e1 * s, axis=-1), np.sum(e2 * s, axis=-1)], axis=-1)
    size = np.sqrt(np.sum(tilt * tilt, axis=-1))[..., None]
    # the tilt's direction; any one for a normal sensed opposite the predicted
    along = np.where(size > 1e-15, tilt / np.maximum(size, 1e-300), [1.0, 0.0])
    d = np.arccos(np.clip(np.sum(n * s, axis=-1), -1.0, 1.0))[..., None] * along
    M = np.stack([-e2, e1], axis=-2)  # B [n]x (..., k, 2, 3): a turn w tilts n by w x n
    C = sigma_rad**2 * np.eye(2) + M @ turn_covariance[..., None, :, :] @ np.swapaxes(M, -1, -2)
    a, b, c = C[..., 0, 0], C[..., 0, 1] + C[..., 1, 0], C[..., 1, 1]
    det = a * c - C[..., 0, 1] * C[..., 1, 0]
    z2 = (d[..., 0] ** 2 * c - d[..., 0] * d[..., 1] * b + d[..., 1] ** 2 * a) / det
    terms = -huber(np.sqrt(np.maximum(z2, 0.0)), huber_k) - 0.5 * np.log(det)  # d^T C^-1 d
    return np.sum(np.where(known, terms, 0.0), axis=-1)


def evidence_bounds(spread: Array, windows: Array, normals: Array, sigma_rad: float) -> Array:
    """The most each of k touches can add to a hypothesis's log ratio (module docstring),
    (k,): its point predicted exactly, -log(sqrt(2 pi) L_ii / w_i) (``spread`` (k,) L_ii,
    ``windows`` (k,) w_i), and a sensed normal (rows of NaN in ``normals`` (k, 3): none)
    as predicted, -log det(C) / 2 <= -2 log ``sigma_rad`` (C >= sigma_n^2 I)."""
    sensed = np.all(np.isfinite(normals), axis=1)
    return -np.log(np.sqrt(2.0 * np.pi) * spread / windows) - 2.0 * np.log(sigma_rad) * sensed


def predicted_evidence(
    model: MeshModel,
    T_model_from_data: Array,
    pivot: Array,
    pose_covariance: Array,
    points: Array,
    whitening_rows: Array,
    windows: Array,
    normals: Array,
    noise: NoiseModel,
    sensor_m: float,
) -> Array:
    """Log ratios (m,) against "none of these" of the last k of the contact ``points``
    (n, 3), the touches, as m hypotheses of one model predicted them before they were
    made (module docstring): ``model`` at ``T_model_from_data`` (m, 4, 4) with the
    Laplace covariances ``pose_covariance`` (m, 6, 6) of a turn about ``pivot`` (m, 3)
    and a shift (model frame); ``whitening_rows`` (k, n) the touches' rows of the inverse
    Cholesky factor of Sigma over all the points; ``windows`` (k,) the approaches' lengths
    and ``normals`` (k, 3) the sensed normals (rows of NaN: none), data frame; ``noise``
    and ``sensor_m`` as the belief's."""
    k, m = len(whitening_rows), len(T_model_from_data)
    if k == 0 or m == 0:
        return np.zeros(m)
    R, t = T_model_from_data[:, :3, :3], T_model_from_data[:, :3, 3]
    moved = posed(R, t, points)
    flat, closest, face = model.distance.signed_closest(moved.reshape(-1, 3))
    signed = flat.reshape(m, -1)
    surface = smooth_normals(model, closest, face).reshape(moved.shape)
    # the contact before the touches counts at most the outlier level, as in the fit;
    # the touches as they are (a miss by millimetres is no outlier of the sensor)
    level = noise.outlier_level_m(sensor_m)
    residuals = np.concatenate([np.clip(signed[:, :-k], -level, level), signed[:, -k:]], axis=1)
    J = whitening_rows @ point_to_plane_jacobian(moved, surface, pivot[:, None, :])
    spread = 1.0 / whitening_rows[np.arange(k), len(points) - k + np.arange(k)]
    score = point_evidence(
        residuals @ whitening_rows.T,
        np.einsum("mij,mjl,mil->mi", J, pose_covariance, J),
        spread,
        windows,
        noise.huber_k,
    )
    return score + normal_evidence(
        surface[:, len(points) - k :],
        np.einsum("kj,mij->mki", normals, R),
        pose_covariance[:, :3, :3],
        noise.normal_sigma_rad(),
        noise.huber_k,
    )


def miss_evidence(
    distance: MeshDistance,
    R: Array,
    t: Array,
    misses: Sequence[tuple[Array, Array, float]],
    sigma_m: float,
    huber_k: float,
) -> float:
    """Log ratio of the touches that met nothing, ``misses`` (start, unit direction,
    travel in metres; data frame), under the pose R, t of the model whose distances
    ``distance`` gives: a ray that the posed surface crosses within the travel costs
    Huber's loss of its deepest point inside, in noise levels ``sigma_m`` (a surface the
    ray just grazes costs little, one it runs deep into costs much). A ray that meets no
    face, or first enters the surface beyond its travel (it starts outside), is clear of
    it and is not sampled."""
    penalty = 0.0
    for start, direction, travel in misses:
        steps = np.arange(0.0, travel + 0.5 * RAY_SAMPLE_M, RAY_SAMPLE_M)
        towards = R @ direction
        face, hit = distance.first_hits(R @ start + t, towards)
        entering = face[0] >= 0 and float(distance.normals_of(face)[0] @ towards) < 0
        if face[0] < 0 or (entering and hit[0] > steps[-1]):
            continue
        deepest = _deepest(distance, (start + steps[:, None] * direction) @ R.T + t, steps)
        if deepest < 0:
            penalty -= float(huber(np.array([deepest / sigma_m]), huber_k)[0])
    return penalty


#: :func:`miss_evidence` samples a ray that meets the surface every this many metres, on
#: the exact mesh (the pair search reads the distance fields more coarsely,
#: :data:`~recognition.surfaces.registration.contact_pairs.MISS_STEP_M`).
RAY_SAMPLE_M = 0.1e-3
#: :func:`_deepest` reads every this many samples of a ray first.
COARSE_EVERY = 10


def _deepest(distance: MeshDistance, ray: Array, steps: Array) -> float:
    """The least signed distance of the ray's points (k, 3) at arc lengths ``steps`` (k,)
    when it is negative (else some value >= 0), reading only the points that can be
    inside: every ``COARSE_EVERY``-th first, then those no read point clears (a point at
    distance d > 0 has none of the surface within d, so a point within d - e of it lies
    at least e outside)."""
    coarse = np.arange(0, len(steps), COARSE_EVERY)
    read = distance.signed(ray[coarse])
    before = np.minimum(np.arange(len(steps)) // COARSE_EVERY, len(coarse) - 1)
    after = np.minimum(before + 1, len(coarse) - 1)
    clear = np.maximum(
        read[before] - np.abs(steps - steps[coarse[before]]),
        read[after] - np.abs(steps - steps[coarse[after]]),
    )
    unread = np.flatnonzero(clear <= 0)
    unread = unread[unread % COARSE_EVERY != 0]
    if not unread.size:
        return float(read.min())
    return float(min(read.min(), distance.signed(ray[unread]).min()))


def sensed_normals(normals: ArrayLike | None, count: int) -> Array:
    """``normals`` (count, 3) of as many contacts made unit, rows of NaN (none sensed)
    kept; None: none sensed at all. Raises InvalidArgument on anything else."""
    if normals is None:
        return np.full((count, 3), np.nan)
    out = np.asarray(normals, dtype=np.float64)
    if out.shape != (count, 3):
        raise InvalidArgument(
            f"normals must be one (3,) vector per contact point ({count}, 3), got shape {out.shape}"
        )
    size = np.linalg.norm(out, axis=1)
    given = np.all(np.isfinite(out), axis=1)
    if not np.all(given | np.all(np.isnan(out), axis=1)) or np.any(size[given] < 1e-9):
        raise InvalidArgument("each normal must be a finite non-zero vector, or a row of NaN")
    out = out.copy()
    out[given] /= size[given, None]
    return out
