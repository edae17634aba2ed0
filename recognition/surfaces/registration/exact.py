"""Exact registration errors: closest points on the model's triangles, and the pose polish."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.rigid import pose_matrix
from recognition.surfaces.closest_fit import refine_poses
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.registration.ambiguity import Resolution, distinct_poses
from recognition.surfaces.registration.result import Registration

__all__ = [
    "exact_distances_m",
    "exact_error_m",
    "polish",
    "refine_exact",
    "smooth_normals",
    "with_exact_error",
]

Array = NDArray[np.float64]


def exact_distances_m(model: MeshModel, points: ArrayLike, R: ArrayLike, t: ArrayLike) -> Array:
    """Exact distances (n,) from the points moved by (R, t) to the model, metres.

    ``points`` (n, 3) and ``t`` (3,) in metres, ``R`` (3, 3).
    """
    moved = np.asarray(points, float) @ np.asarray(R).T + np.asarray(t)
    return np.asarray(model.distance.closest(moved)[0], dtype=np.float64)


def exact_error_m(
    model: MeshModel,
    points: ArrayLike,
    R: ArrayLike,
    t: ArrayLike,
    threshold_m: float = float("inf"),
) -> float:
    """Mean exact distance from the points moved by (R, t) to the model, thesis Eq. (4.8),
    each point counted at most ``threshold_m`` (an outlier); metres.

    ``points`` (n, 3) and ``t`` (3,) in metres, ``R`` (3, 3).
    """
    return float(np.mean(np.minimum(exact_distances_m(model, points, R, t), threshold_m)))


def refine_exact(
    model: MeshModel,
    points: ArrayLike,
    R: ArrayLike,
    t: ArrayLike,
    iterations: int = 12,
    tolerance: float = 1e-4,
    threshold_m: float = float("inf"),
) -> tuple[Array, Array, float]:
    """Levenberg-Marquardt on exact closest points: the last six-DOF polish of a pose.

    Each step linearises the distances as point-to-plane residuals on the closest
    triangles and is kept only if it lowers the mean squared exact distance (so the pose
    never gets worse, also along the flat directions of nearly symmetric surfaces).
    Points farther than ``threshold_m`` (outliers) count at the threshold and do not
    pull the pose (a truncated quadratic). Stops when a kept step lowers the cost by less
    than the fraction ``tolerance`` or moves no data point by more than 0.1 micrometre,
    or after ``iterations`` steps. Returns R (3, 3), t (3,) and the mean exact distance
    (4.8) at the result (outliers at the threshold), metres; ``points`` (n, 3) and ``t``
    in metres, ``R`` (3, 3).
    """
    R_out, t_out, signed, _, _ = refine_poses(
        model.distance,
        np.asarray(points, float),
        np.asarray(R, float)[None],
        np.asarray(t, float)[None],
        iterations,
        tolerance,
        threshold_m,
    )
    return R_out[0], t_out[0], float(np.mean(np.minimum(np.abs(signed[0]), threshold_m)))


def polish(
    registration: Registration,
    model: MeshModel,
    curves: DataCurves,
    *,
    point: Array | None = None,
    iterations: int = 12,
    threshold_m: float | None = None,
    poses: Array | None = None,
    resolution: Resolution | None = None,
) -> Registration:
    """``registration`` polished on exact closest points, with its exact error (4.8).

    The poses ``poses`` ((k, 4, 4) T_model_from_data; default the registration's own)
    are refined together by at most ``iterations`` steps of :func:`refine_exact` and the
    one of least exact error is kept; ``poses`` and ``pose_errors_m`` then list the
    distinct polished poses first (:func:`distinct_poses`: those that came to the same
    answer appear once), best first. ``point`` ((3,), metres: the data's p, data frame;
    default the data's centroid) moves with the pose. With the data's ``resolution``,
    the model's symmetric images of the poses (:attr:`MeshModel.symmetries`) are polished
    with them, the polished poses it cannot tell from the best are ``equivalent_poses``
    and the directions it leaves the best free along are ``free_motions``. Points farther than
    ``threshold_m`` (default: the registration's ``outlier_threshold_m``) count at it and
    are reported as outliers. The time taken is added to ``time_s``.
    """
    if registration.error_is_exact or not np.isfinite(registration.error_m):
        return registration
    start = time.perf_counter()
    threshold = registration.outlier_threshold_m if threshold_m is None else threshold_m
    starts = registration.T_model_from_data[None] if poses is None else np.asarray(poses)
    rest = slice(len(starts), None)  # the registration's poses not polished
    if resolution is not None and len(model.symmetries):
        # the model's symmetric images of each pose fit the data as well: polished with it
        images = np.einsum("sij,kjl->skil", model.symmetries, starts).reshape(-1, 4, 4)
        starts = np.concatenate([starts, images])
    R, t, signed, _, _ = refine_poses(
        model.distance,
        np.asarray(curves.points, float),
        starts[:, :3, :3],
        starts[:, :3, 3],
        iterations,
        1e-4,
        threshold,
    )
    distance = np.abs(signed)
    errors = np.mean(np.minimum(distance, threshold), axis=1)
    p = np.asarray(curves.points, float).mean(axis=0) if point is None else point
    order = distinct_poses(R, t, errors, p, len(errors))
    polished = pose_matrix(R[order], t[order])
    best = order[0]
    location = registration.location if point is None else R[best] @ point + t[best]
    equivalent, free = 1, 0
    if resolution is not None:
        limit = resolution.equivalent_error_m(float(errors[best]))
        equivalent = int(np.sum(errors[order] <= limit))
        fit = _inliers_at(model, np.asarray(curves.points, float), R[best], t[best], threshold)
        free = resolution.free_motions(*fit) if fit is not None else 0
    return replace(
        registration,
        error_m=float(errors[best]),
        error_is_exact=True,
        T_model_from_data=polished[0],
        location=location,
        outliers=np.flatnonzero(distance[best] > threshold),
        outlier_threshold_m=threshold,
        poses=np.concatenate([polished, registration.poses[rest].reshape(-1, 4, 4)]),
        pose_errors_m=np.concatenate([errors[order], registration.pose_errors_m[rest]]),
        equivalent_poses=equivalent,
        free_motions=free,
        time_s=registration.time_s + time.perf_counter() - start,
    )


def _inliers_at(
    model: MeshModel, points: Array, R: Array, t: Array, threshold_m: float
) -> tuple[Array, Array] | None:
    """The data points within ``threshold_m`` of the model at the pose (R, t), moved, and
    the model's normals at their closest points, interpolated from its vertex normals
    (a faceted sphere stays free to turn); None when fewer than six."""
    moved = points @ R.T + t
    distance, q, face = model.distance.closest(moved)
    inliers = distance <= threshold_m
    if inliers.sum() < 6:
        return None
    return moved[inliers], smooth_normals(model, q[inliers], face[inliers])


def smooth_normals(model: MeshModel, points: Array, faces: NDArray[np.int64]) -> Array:
    """Unit normals (k, 3) at ``points`` (k, 3) on ``faces`` (k,) of the model,
    interpolated from its vertex normals (on a faceted sphere they point at the centre,
    so that a turn about it stays free)."""
    from recognition.surfaces.mesh_kernels import interpolated_normals  # numba: when needed

    return interpolated_normals(
        model.vertices,
        np.ascontiguousarray(model.faces, dtype=np.int64),
        model.normals,
        np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3),
        np.ascontiguousarray(faces, dtype=np.int64).reshape(-1),
    )


def with_exact_error(
    registration: Registration,
    model: MeshModel,
    curves: DataCurves,
    refine: bool = False,
    point: Array | None = None,
    iterations: int = 12,
    threshold_m: float | None = None,
) -> Registration:
    """``registration`` with its error computed exactly (if it was not).

    With ``refine``, the pose is first polished (:func:`polish`); ``point`` ((3,),
    metres: the data's p, data frame) then moves with it. Points farther than
    ``threshold_m`` (default: the registration's ``outlier_threshold_m``) count at it and
    are reported as outliers. The time taken is added to ``time_s``.
    """
    if refine:
        return polish(
            registration,
            model,
            curves,
            point=point,
            iterations=iterations,
            threshold_m=threshold_m,
        )
    if registration.error_is_exact or not np.isfinite(registration.error_m):
        return registration
    start = time.perf_counter()
    threshold = registration.outlier_threshold_m if threshold_m is None else threshold_m
    T = registration.T_model_from_data
    distances = exact_distances_m(model, curves.points, T[:3, :3], T[:3, 3])
    return replace(
        registration,
        error_m=float(np.mean(np.minimum(distances, threshold))),
        error_is_exact=True,
        outliers=np.flatnonzero(distances > threshold),
        outlier_threshold_m=threshold,
        time_s=registration.time_s + time.perf_counter() - start,
    )
