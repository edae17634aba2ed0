"""Rigid motions: rotations, poses and their small helpers, in the plane and in space.

Conventions: a rotation acts on column vectors (``R @ x``); arrays of vectors keep the
coordinates on the last axis and are rotated as ``x @ R.T``; a pose is a (4, 4)
homogeneous matrix named after the frames it maps, ``T_model_from_data``, and a planar
pose a (3, 3) one. Every function here is vectorised over leading axes where that is
stated.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

__all__ = [
    "apply_pose",
    "cross",
    "point_to_plane_jacobian",
    "pose_matrix",
    "posed",
    "random_planar_motion",
    "random_rigid_motion",
    "rotation_2d",
    "rotation_about",
    "rotation_about_derivative",
    "rotation_angle",
    "rotation_from_vector",
    "skew",
]

Array = NDArray[np.float64]


def cross(a: ArrayLike, b: ArrayLike) -> Array:
    """Cross product along the last axis, broadcast (faster than ``numpy.cross`` on small
    arrays)."""
    a, b = np.asarray(a), np.asarray(b)
    if a.ndim == 1 and b.ndim == 1:
        a0, a1, a2 = a.tolist()
        b0, b1, b2 = b.tolist()
        return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def point_to_plane_jacobian(points: ArrayLike, normals: ArrayLike, pivot: ArrayLike) -> Array:
    """How far each point (..., n, 3) moves along its unit normal (..., n, 3) under a small
    turn (radians, about ``pivot``) and a shift (metres), per unit of each: (..., n, 6),
    the rows [(x - pivot) x n, n]."""
    normals = np.asarray(normals)
    return np.concatenate([cross(np.asarray(points) - pivot, normals), normals], axis=-1)


def skew(w: ArrayLike) -> Array:
    """The cross-product matrices [w]x of vectors w (..., 3): ``skew(w) @ x == w x x``."""
    w = np.asarray(w, dtype=float)
    out = np.zeros((*w.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -w[..., 2], w[..., 1]
    out[..., 1, 0], out[..., 1, 2] = w[..., 2], -w[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -w[..., 1], w[..., 0]
    return out


def rotation_from_vector(w: ArrayLike) -> Array:
    """Rotation matrices exp([w]x) of rotation vectors w (B, 3) -> (B, 3, 3), Rodrigues'
    formula (the angle is |w|, radians)."""
    w = np.asarray(w, dtype=float)
    theta = np.linalg.norm(w, axis=1)
    k = w / np.maximum(theta, 1e-300)[:, None]
    K = skew(k)
    s, c = np.sin(theta)[:, None, None], (1 - np.cos(theta))[:, None, None]
    return np.eye(3) + s * K + c * (K @ K)


def rotation_about(axis: int, angle: ArrayLike) -> Array:
    """Rotations about the x (0), y (1) or z (2) axis by ``angle`` (...) radians ->
    (..., 3, 3)."""
    c, s = np.cos(angle), np.sin(angle)
    R = np.zeros((*np.shape(angle), 3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R[..., axis, axis] = 1.0
    R[..., i, i] = c
    R[..., j, j] = c
    R[..., i, j] = -s
    R[..., j, i] = s
    return R


def rotation_about_derivative(axis: int, angle: ArrayLike) -> Array:
    """d/d(angle) of :func:`rotation_about`, (..., 3, 3)."""
    c, s = np.cos(angle), np.sin(angle)
    dR = np.zeros((*np.shape(angle), 3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    dR[..., i, i] = -s
    dR[..., j, j] = -s
    dR[..., i, j] = -c
    dR[..., j, i] = c
    return dR


def rotation_angle(R: ArrayLike) -> Array:
    """Angle of rotations R (..., 3, 3), radians in [0, pi]."""
    trace = np.trace(np.asarray(R, dtype=float), axis1=-2, axis2=-1)
    return np.arccos(np.clip((trace - 1) / 2, -1.0, 1.0))


def rotation_2d(theta: ArrayLike) -> Array:
    """Planar rotations by ``theta`` (...) radians -> (..., 2, 2)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([np.stack([c, -s], axis=-1), np.stack([s, c], axis=-1)], axis=-2)


def pose_matrix(R: ArrayLike, t: ArrayLike) -> Array:
    """The homogeneous pose of rotation R (..., d, d) and translation t (..., d),
    (..., d + 1, d + 1)."""
    R, t = np.asarray(R, dtype=float), np.asarray(t, dtype=float)
    d = t.shape[-1]
    T = np.zeros((*t.shape[:-1], d + 1, d + 1))
    T[..., :-1, :-1], T[..., :-1, -1], T[..., -1, -1] = R, t, 1.0
    return T


def apply_pose(T: ArrayLike, points: ArrayLike) -> Array:
    """Points (n, d) moved by the homogeneous pose T (d + 1, d + 1)."""
    T = np.asarray(T, dtype=float)
    return np.asarray(points, dtype=float) @ T[:-1, :-1].T + T[:-1, -1]


def posed(R: ArrayLike, t: ArrayLike, points: ArrayLike) -> Array:
    """Points (n, d) moved by each of k poses, rotations R (k, d, d) and translations
    t (k, d): (k, n, d)."""
    moved = np.einsum("nj,kij->kni", np.asarray(points, float), np.asarray(R, float))
    return np.asarray(moved + np.asarray(t, float)[:, None, :], dtype=np.float64)


def random_rigid_motion(rng: np.random.Generator, translation_scale: float = 0.1) -> Array:
    """A uniformly random rotation and a Gaussian translation (standard deviation
    ``translation_scale`` per axis), as a (4, 4) pose."""
    R = Rotation.random(random_state=rng).as_matrix()
    return pose_matrix(R, rng.normal(scale=translation_scale, size=3))


def random_planar_motion(rng: np.random.Generator, translation_scale: float = 1.0) -> Array:
    """A uniformly random planar rotation and a Gaussian translation, as a (3, 3) pose."""
    theta = rng.uniform(-np.pi, np.pi)
    c, s = np.cos(theta), np.sin(theta)
    T = np.eye(3)
    T[:2, :2] = [[c, -s], [s, c]]
    T[:2, 2] = rng.normal(scale=translation_scale, size=2)
    return T
