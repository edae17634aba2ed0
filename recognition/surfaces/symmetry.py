"""A model's rotational symmetries: the rigid motions that map its surface onto itself.

A gear turned by one tooth, or turned over, is the same gear: data curves fit it equally
well at every symmetric image of a pose, so the registration reports those images as
equivalent answers rather than one of them at random. The search tries turns by 2 pi / k
(k = 2 ... ``max_order``) about the principal axes of the surface through its centroid,
and half turns about axes in the plane normal to an axis of order 3 or more, or in a
principal plane whose two principal moments are equal (a gear's or a wheel's flips),
each polished on exact closest points
(:func:`~recognition.surfaces.closest_fit.refine_poses`); a motion is a symmetry when 99 %
of the surface, moved, lies within ``tolerance_m`` of itself.
"""

from __future__ import annotations

import numpy as np
import trimesh
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from recognition.rigid import pose_matrix, rotation_angle, rotation_from_vector
from recognition.surfaces.closest_fit import refine_poses
from recognition.surfaces.distance import MeshDistance

__all__ = ["rotational_symmetries"]

Array = NDArray[np.float64]

#: Relative difference below which two principal moments count as equal.
EQUAL_MOMENTS = 0.05
#: Axes tried in a plane of flips, over half a turn.
PLANE_AXES = 180
#: A polished candidate must still turn by its own angle within this, radians.
TURN_TOLERANCE_RAD = float(np.deg2rad(1.0))
#: Surface points a candidate is polished on (all samples check it).
FIT_POINTS = 400


def _principal_axes(mesh: trimesh.Trimesh) -> tuple[Array, Array, Array]:
    """The surface's area centroid (3,), second moments (3,) ascending and principal axes
    (3, 3) (columns), from the exact second moments of its triangles."""
    tri, area = mesh.triangles, mesh.area_faces
    centre = np.einsum("f,fi->i", area, tri.mean(axis=1)) / area.sum()
    x = tri - centre
    s = x.sum(axis=1)
    second = np.einsum("f,fki,fkj->ij", area, x, x) + np.einsum("f,fi,fj->ij", area, s, s)
    moments, axes = np.linalg.eigh(second / (12 * area.sum()))
    return centre, moments, axes


def _symmetric(
    distance: MeshDistance,
    points: Array,
    probe: Array,
    centre: Array,
    rotations: Array,
    tolerance_m: float,
) -> tuple[Array, NDArray[np.bool_]]:
    """The rotations (c, 3, 3) about ``centre``, polished on exact closest points, as
    motions (c, 4, 4), and which of them map the points within ``tolerance_m`` of the
    surface (99th percentile) still turning as asked (within ``TURN_TOLERANCE_RAD``)."""
    t0 = centre - rotations @ centre
    moved = np.einsum("kij,nj->kni", rotations, probe) + t0[:, None]
    near = distance.closest(moved.reshape(-1, 3))[0].reshape(len(rotations), -1)
    keep = np.flatnonzero(near.mean(axis=1) <= tolerance_m)
    motions = pose_matrix(rotations, t0)
    good = np.zeros(len(rotations), bool)
    if len(keep):
        fit = points[:: max(1, len(points) // FIT_POINTS)]
        R, t, *_ = refine_poses(distance, fit, rotations[keep], t0[keep], 6, 1e-5, np.inf)
        motions[keep] = pose_matrix(R, t)
        moved = np.einsum("kij,nj->kni", R, points) + t[:, None]
        d = distance.closest(moved.reshape(-1, 3))[0].reshape(len(keep), -1)
        # the polish may slide a turn to a symmetry of another order: kept as tried only
        asked = rotation_angle(rotations[keep])
        same = np.abs(rotation_angle(R) - asked) <= TURN_TOLERANCE_RAD
        good[keep] = (np.quantile(d, 0.99, axis=1) <= tolerance_m) & same
    return motions, good


def _flips(plane: Array) -> Array:
    """Half turns (PLANE_AXES, 3, 3) about the axes in the plane of the columns of
    ``plane`` (3, 2)."""
    angle = np.linspace(0.0, np.pi, PLANE_AXES, endpoint=False)
    axes = np.cos(angle)[:, None] * plane[:, 0] + np.sin(angle)[:, None] * plane[:, 1]
    return rotation_from_vector(axes * np.pi)


def rotational_symmetries(
    vertices: Array,
    faces: NDArray[np.int64],
    distance: MeshDistance,
    *,
    tolerance_m: float = 0.5e-3,
    max_order: int = 24,
    samples: int = 2000,
    seed: int = 0,
) -> Array:
    """The proper rigid motions (k, 4, 4) other than the identity that map the surface
    (vertices (n, 3), metres, and faces) onto itself: 99 % of ``samples`` seeded surface
    points within ``tolerance_m`` of it (a tessellation is symmetric only to within its
    chords); distinct, empty for an asymmetric surface.

    Turns by 2 pi / k (k = 2 ... ``max_order``) about each principal axis are tried; of
    one axis's turns only the highest order found is kept, with its powers (a surface of
    revolution yields the turns of order ``max_order``). Half turns are tried about axes
    in the plane normal to an axis of order 3 or more, or in a plane of equal moments.
    """
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    points = np.asarray(trimesh.sample.sample_surface(mesh, samples, seed=seed)[0], float)
    probe = points[:: max(1, samples // 100)]
    centre, moments, axes = _principal_axes(mesh)
    orders = np.arange(2, max_order + 1)
    turns = rotation_from_vector(
        (axes.T[:, None, :] * (2 * np.pi / orders)[None, :, None]).reshape(-1, 3)
    )
    motions, good = _symmetric(distance, points, probe, centre, turns, tolerance_m)
    good = good.reshape(3, len(orders))
    chosen = []
    planes = []
    for a in range(3):
        others = [b for b in range(3) if b != a]
        if good[a].any():
            k = int(np.flatnonzero(good[a])[-1])
            chosen.extend(_cyclic_group(motions.reshape(3, len(orders), 4, 4)[a, k], orders[k]))
        equal = abs(moments[others[0]] - moments[others[1]]) <= EQUAL_MOMENTS * moments[others[1]]
        if equal or (good[a].any() and orders[np.flatnonzero(good[a])[-1]] >= 3):
            planes.append(axes[:, others])
    for plane in planes:
        flips, found = _symmetric(distance, points, probe, centre, _flips(plane), tolerance_m)
        flips = flips[found]
        if len(flips):
            chosen.extend(flips[:: -(-len(flips) // max_order)])  # a continuum: max_order
    if not chosen:
        return np.zeros((0, 4, 4))
    return _distinct(np.array(chosen), probe, tolerance_m)


def _cyclic_group(T: Array, order: int) -> list[Array]:
    """The turns by 2 pi j / ``order`` (j = 1 ... order - 1) about the axis of the motion
    ``T`` (4, 4): exact powers of the ideal turn, free of the drift of T's own."""
    rotvec = Rotation.from_matrix(T[:3, :3]).as_rotvec()
    axis = rotvec / np.linalg.norm(rotvec)
    # a point of the axis: the least-squares solution of (I - R) x = t
    on_axis = np.linalg.lstsq(np.eye(3) - T[:3, :3], T[:3, 3], rcond=None)[0]
    R = rotation_from_vector(axis[None] * (2 * np.pi * np.arange(1, order) / order)[:, None])
    return list(pose_matrix(R, on_axis - R @ on_axis))


def _distinct(motions: Array, probe: Array, tolerance_m: float) -> Array:
    """The motions without duplicates and without the identity: two motions are the same
    when they move the probe points (m, 3) apart by less than ``tolerance_m`` (mean)."""
    images = np.einsum("kij,nj->kni", motions[:, :3, :3], probe) + motions[:, None, :3, 3]
    kept: list[int] = []
    kept_images = [probe]
    for i, image in enumerate(images):
        if all(np.linalg.norm(image - K, axis=1).mean() > tolerance_m for K in kept_images):
            kept.append(i)
            kept_images.append(image)
    return motions[kept].reshape(-1, 4, 4)
