"""How a verification touch weighs a hypothesis against "none of these" (log ratios, nats).

A touch's contact point (:func:`point_evidence`): by how well the hypothesis predicted it,
its residual given all the other contact (leave-one-out: a pose refitted to the touch
would otherwise explain any touch at all). Whitened residual z_i over sqrt(1 - h_ii),
h_ii the touch's leverage on the pose fit; density N(0, L_ii^2 / (1 - h_ii)), L_ii its
conditional noise; against the uniform spread along the touch's approach (length w_i)
that "none of these" predicts:

    log [N(z_i / sqrt(1 - h_ii)) / (L_ii sqrt(1 - h_ii)^-1)] - log (1 / w_i).

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
from recognition.surfaces.distance import MeshDistance
from recognition.surfaces.noise_model import huber

__all__ = ["miss_evidence", "normal_evidence", "point_evidence", "sensed_normals"]

Array = NDArray[np.float64]


def point_evidence(
    whitened: Array, leverage: Array, spread: Array, windows: Array, huber_k: float
) -> float:
    """Log ratio of the touches' contact points (module docstring): ``whitened`` (k,) the
    touches' whitened residuals z_i, ``leverage`` (k,) h_ii, ``spread`` (k,) L_ii and
    ``windows`` (k,) the approaches' lengths w_i (metres)."""
    if len(whitened) == 0:
        return 0.0
    keep = np.clip(1.0 - leverage, 1e-12, 1.0)
    return float(
        np.sum(
            -huber(whitened / np.sqrt(keep), huber_k)
            + 0.5 * np.log(keep)
            - np.log(np.sqrt(2.0 * np.pi) * spread / windows)
        )
    )


def normal_evidence(
    predicted: Array, sensed: Array, turn_covariance: Array, sigma_rad: float, huber_k: float
) -> float:
    """Log ratio of the touches' sensed normals (module docstring): ``predicted`` and
    ``sensed`` (k, 3) unit normals in one frame (rows of NaN in ``sensed``: no normal
    sensed), ``turn_covariance`` (3, 3) the hypothesis's turn in that frame, radians^2."""
    known = np.all(np.isfinite(sensed), axis=1)
    total = 0.0
    for n, s in zip(predicted[known], sensed[known], strict=True):
        # an orthonormal basis of n's tangent plane
        helper = np.eye(3)[int(np.argmin(np.abs(n)))]
        e1 = np.cross(n, helper)
        e1 /= np.linalg.norm(e1)
        B = np.stack([e1, np.cross(n, e1)])
        cosine = float(np.clip(n @ s, -1.0, 1.0))
        tilt = B @ s
        size = float(np.linalg.norm(tilt))
        # the tilt's direction; any one for a normal sensed opposite the predicted
        d = np.arccos(cosine) * (tilt / size if size > 1e-15 else np.array([1.0, 0.0]))
        skew = np.array([[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]])
        M = B @ skew
        C = sigma_rad**2 * np.eye(2) + M @ turn_covariance @ M.T
        z = float(np.sqrt(d @ np.linalg.solve(C, d)))
        total += -float(huber(np.array([z]), huber_k)[0]) - 0.5 * float(np.log(np.linalg.det(C)))
    return total


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
    ray just grazes costs little, one it runs deep into costs much)."""
    penalty = 0.0
    for start, direction, travel in misses:
        steps = np.arange(0.0, travel + 0.05e-3, 0.1e-3)
        ray = start + steps[:, None] * direction
        deepest = float(distance.signed(ray @ R.T + t).min())
        if deepest < 0:
            penalty -= float(huber(np.array([deepest / sigma_m]), huber_k)[0])
    return penalty


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
