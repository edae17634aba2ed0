"""Superposition of the data on a mesh model: p on a vertex, N on its normal, turned by phi.

The starting poses of every mode on mesh models (thesis Sections 4.1.2.2 and 4.3.3.1): a
candidate vertex of the table lookup (4.7) takes the data's common point p, the data
normal is aligned with the vertex normal (4.13) and the curves are turned by phi about
it, the data's principal direction d1 starting on the vertex's.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from recognition.rigid import rotation_about
from recognition.surfaces.local_geometry import LocalSurfaceGeometry
from recognition.surfaces.mesh_model import MeshModel

__all__ = ["candidate_rows", "frames", "hypotheses", "model_frames", "superposition_poses"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


def hypotheses(geometry: LocalSurfaceGeometry) -> list[LocalSurfaceGeometry]:
    """The data's local geometry, and its flip when the normal's sign is unknown."""
    return [geometry] if geometry.oriented else [geometry, geometry.flipped()]


def candidate_rows(model: MeshModel, geometry: LocalSurfaceGeometry, delta: float) -> IntArray:
    """Rows of the model's table within ``delta`` of the data's (k1, k2), nearest first
    (thesis Eq. (4.7))."""
    return model.table.query(geometry.k1, geometry.k2, delta)


def frames(normals: Array, directions: Array) -> Array:
    """(k, 3, 3) right-handed frames whose columns are (t1, n x t1, n), t1 the direction
    made tangent (any tangent where it is parallel to the normal)."""
    t1 = directions - normals * np.einsum("ij,ij->i", directions, normals)[:, None]
    bad = np.linalg.norm(t1, axis=1) < 1e-9
    if bad.any():
        helper = np.where(np.abs(normals[bad, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
        t1[bad] = np.cross(normals[bad], helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    return np.stack([t1, np.cross(normals, t1), normals], axis=-1)


def model_frames(model: MeshModel, rows: IntArray) -> Array:
    """(k, 3, 3) frames (d1, d2, n) at table rows: principal direction and normal."""
    table = model.table
    assert table.d1 is not None  # mesh tables carry principal directions
    return frames(model.normals[table.site[rows]], table.d1[rows])


def superposition_poses(
    model: MeshModel, rows: IntArray, geometry: LocalSurfaceGeometry, phis: Array
) -> tuple[Array, Array]:
    """Poses (R, t) putting p on each table row's vertex, N on its normal (4.13), turned by
    phi (thesis Section 4.3.3.1).

    Returns R (k, f, 3, 3), t (k, f, 3) mapping data-frame points to the model frame.
    """
    F = model_frames(model, rows)  # (k, 3, 3)
    R = F[:, None] @ rotation_about(2, phis)[None] @ geometry.frame.T[None, None]
    x = model.vertices[model.table.site[rows]]
    t = x[:, None, :] - np.einsum("kfij,j->kfi", R, geometry.point)
    return R, t
