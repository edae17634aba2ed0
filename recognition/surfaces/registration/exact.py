"""Exact registration errors: closest points on the model's triangles, and the pose polish."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from recognition.least_squares import LeastSquaresConfig, State, damped_least_squares
from recognition.rigid import cross, pose_matrix
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.registration.result import Registration

__all__ = ["exact_distances_m", "exact_error_m", "polish", "refine_exact", "with_exact_error"]

Array = NDArray[np.float64]
PoseState = tuple[Array, Array, Array, Array, Array, NDArray[np.int64]]
"""R, t, the moved points, their distances, closest points and faces: one pose."""


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


def _refine_poses(
    model: MeshModel,
    points: Array,
    R: Array,
    t: Array,
    iterations: int,
    tolerance: float,
    threshold_m: float,
) -> tuple[Array, Array, Array]:
    """:func:`refine_exact` for k poses at once: R (k, 3, 3), t (k, 3) -> R, t and the
    exact distances (k, n) at the results; one closest-point query per step for all."""
    reach = float(np.max(np.linalg.norm(points - points.mean(axis=0), axis=1)))
    n = len(points)

    def evaluate(R: Array, t: Array) -> PoseState:
        X = np.einsum("nj,kij->kni", points, R) + t[:, None, :]
        distance, q, face = model.distance.closest(X.reshape(-1, 3))
        k = len(R)
        return R, t, X, distance.reshape(k, n), q.reshape(k, n, 3), face.reshape(k, n)

    def cost(state: State) -> Array:
        return np.asarray(np.mean(np.minimum(state[3], threshold_m) ** 2, axis=1))

    def linearize(state: State) -> tuple[Array, Array]:
        X, distance, q, face = state[2], state[3], state[4], state[5]
        normals = model.distance.face_normals[face]
        r = np.einsum("kij,kij->ki", X - q, normals)
        c = X.mean(axis=1, keepdims=True)
        J = np.concatenate([cross(X - c, normals), normals], axis=2)
        outliers = distance > threshold_m
        return np.where(outliers, 0.0, r), np.where(outliers[..., None], 0.0, J)

    def retract(state: State, step: Array) -> State:
        R, t, X = state[0], state[1], state[2]
        c = X.mean(axis=1)
        dR = Rotation.from_rotvec(step[:, :3]).as_matrix()
        moved_t = np.einsum("kij,kj->ki", dR, t - c) + c + step[:, 3:]
        return evaluate(dR @ R, moved_t)

    def step_size(_state: State, step: Array) -> Array:
        return np.linalg.norm(step[:, :3], axis=1) * reach + np.linalg.norm(step[:, 3:], axis=1)

    result = damped_least_squares(
        evaluate(np.asarray(R, float), np.asarray(t, float)),
        cost=cost,
        linearize=linearize,
        retract=retract,
        step_size=step_size,
        config=LeastSquaresConfig(
            max_iterations=iterations,
            initial_damping=1e-6,
            shrink=0.1,
            grow=100.0,
            max_damping=1e6,
            trace_floor=1e-300,
            rtol=tolerance,
            step_tol=1e-7,
        ),
    )
    R_out, t_out, _, distance, _, _ = result.state
    return R_out, t_out, distance


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
    R_out, t_out, distance = _refine_poses(
        model,
        np.asarray(points, float),
        np.asarray(R, float)[None],
        np.asarray(t, float)[None],
        iterations,
        tolerance,
        threshold_m,
    )
    return R_out[0], t_out[0], float(np.mean(np.minimum(distance[0], threshold_m)))


def polish(
    registration: Registration,
    model: MeshModel,
    curves: DataCurves,
    *,
    point: Array | None = None,
    iterations: int = 12,
    threshold_m: float | None = None,
    poses: Array | None = None,
) -> Registration:
    """``registration`` polished on exact closest points, with its exact error (4.8).

    The poses ``poses`` ((k, 4, 4) T_model_from_data; default the registration's own)
    are refined together by at most ``iterations`` steps of :func:`refine_exact` and the
    one of least exact error is kept; ``poses`` and ``pose_errors_m`` then list the
    polished poses first, best first. ``point`` ((3,), metres: the data's p, data frame)
    moves with the pose. Points farther than ``threshold_m`` (default: the
    registration's ``outlier_threshold_m``) count at it and are reported as outliers.
    The time taken is added to ``time_s``.
    """
    if registration.error_is_exact or not np.isfinite(registration.error_m):
        return registration
    start = time.perf_counter()
    threshold = registration.outlier_threshold_m if threshold_m is None else threshold_m
    starts = registration.T_model_from_data[None] if poses is None else np.asarray(poses)
    R, t, distance = _refine_poses(
        model,
        np.asarray(curves.points, float),
        starts[:, :3, :3],
        starts[:, :3, 3],
        iterations,
        1e-4,
        threshold,
    )
    errors = np.mean(np.minimum(distance, threshold), axis=1)
    order = np.argsort(errors, kind="stable")
    polished = pose_matrix(R[order], t[order])
    best = order[0]
    location = registration.location if point is None else R[best] @ point + t[best]
    rest = slice(len(starts), None)
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
        time_s=registration.time_s + time.perf_counter() - start,
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
