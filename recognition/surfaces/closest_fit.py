"""Rigid poses fitted on a mesh's exact closest points (the polish of every registration,
and the symmetry search of a model)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from recognition.least_squares import LeastSquaresConfig, State, damped_least_squares
from recognition.rigid import point_to_plane_jacobian, posed
from recognition.surfaces.distance import MeshDistance, signed_by_side

__all__ = ["refine_poses"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
PoseState = tuple[Array, Array, Array, Array, Array, Array, IntArray]
"""R, t, the moved points, their distances, closest points, the unit normals of the
faces they lie on and those faces."""


def refine_poses(
    distance_to: MeshDistance,
    points: Array,
    R: Array,
    t: Array,
    iterations: int,
    tolerance: float,
    threshold_m: float,
    whitening: Array | None = None,
    huber_k: float = np.inf,
) -> tuple[Array, Array, Array, Array, IntArray]:
    """Poses R (k, 3, 3), t (k, 3) of the points (n, 3) refined on exact closest points
    of a mesh: Levenberg-Marquardt on point-to-plane residuals, each point counted at most
    ``threshold_m``; one closest-point query per step for all poses. Returns R, t and, at
    the results, the exact signed distances (k, n) (positive outside, as
    :meth:`MeshDistance.signed_closest`), the closest points (k, n, 3) and their faces
    (k, n) (see :func:`~recognition.surfaces.registration.exact.refine_exact`).

    With ``whitening`` W (n, n) (the inverse of a Cholesky factor of the residuals'
    covariance), the signed residuals r (a point beyond the threshold at it) are fitted
    in the sense of generalised least squares: |W r|^2 (correlated errors), each whitened
    residual counted by Huber's loss beyond ``huber_k`` (iteratively reweighted)."""
    reach = float(np.max(np.linalg.norm(points - points.mean(axis=0), axis=1)))
    n = len(points)

    def evaluate(R: Array, t: Array) -> PoseState:
        X = posed(R, t, points)
        distance, q, face = distance_to.closest(X.reshape(-1, 3))
        k = len(R)
        normals = distance_to.normals_of(face).reshape(k, n, 3)
        return R, t, X, distance.reshape(k, n), q.reshape(k, n, 3), normals, face.reshape(k, n)

    def signed(state: State) -> Array:
        """Point-to-plane residuals (k, n), at most the threshold in size."""
        X, q, normals = state[2], state[4], state[5]
        r = np.einsum("kij,kij->ki", X - q, normals)
        return np.clip(r, -threshold_m, threshold_m)

    def cost(state: State) -> Array:
        if whitening is not None:
            z = np.abs(signed(state) @ whitening.T)
            loss = np.where(z <= huber_k, z * z, 2 * huber_k * z - huber_k**2)
            return np.asarray(np.mean(loss, axis=1))
        return np.asarray(np.mean(np.minimum(state[3], threshold_m) ** 2, axis=1))

    def linearize(state: State) -> tuple[Array, Array]:
        X, distance, q, normals = state[2], state[3], state[4], state[5]
        r = np.einsum("kij,kij->ki", X - q, normals)
        c = X.mean(axis=1, keepdims=True)
        J = point_to_plane_jacobian(X, normals, c)
        outliers = distance > threshold_m
        if whitening is not None:
            z = np.clip(r, -threshold_m, threshold_m) @ whitening.T
            Jz = np.matmul(whitening, np.where(outliers[..., None], 0.0, J))
            weight = np.sqrt(np.minimum(1.0, huber_k / np.maximum(np.abs(z), 1e-300)))
            return weight * z, weight[..., None] * Jz
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
    R_out, t_out, X, distance, q, normals, face = result.state
    return R_out, t_out, signed_by_side(X, q, normals, distance), q, face
