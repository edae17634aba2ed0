"""Synthetic data curves: sampling planes through a surface point (thesis 4.2.3, 4.3.4).

Three planes containing the surface normal at p, ``plane_angle`` apart (or any given
planes through p), are intersected with a surface: a triangle mesh (exact plane-mesh
section) or an implicit surface ``f = 0`` (traced by predictor-corrector steps). Each
section is resampled at equal arc-length spacing with p as its middle point, noise is
added, and the curves are moved to an unknown data frame by a random rigid motion. The
ground truth is kept apart.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
import trimesh
from scipy.spatial.transform import Rotation

from recognition.errors import DegenerateGeometry, InvalidCurveData
from recognition.surfaces.data_curves import DataCurves

__all__ = [
    "ImplicitSurface",
    "SyntheticCurves",
    "implicit_data_curves",
    "local_submesh",
    "mesh_data_curves",
    "mesh_plane_section",
    "plane_section_polyline",
    "random_rigid_transform",
    "resample_around",
    "sampling_plane_normals",
]


class ImplicitSurface(Protocol):
    """What :func:`implicit_data_curves` needs of a closed-form surface."""

    def implicit(self, points: np.ndarray) -> np.ndarray:
        """f(x) at (n, 3) points; the surface is f = 0."""

    def gradient(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) gradient of f."""


@dataclass(frozen=True)
class SyntheticCurves:
    """Data curves with their ground truth.

    Attributes
    ----------
    curves : DataCurves
        Noisy curves in the data frame, with the approach direction.
    point_in_model : (3,) float
        The true common point p on the model.
    normal_in_model : (3,) float
        The model's outward unit normal at p.
    T_model_from_data : (4, 4) float
        The rigid motion from the data frame to the model frame.
    clean_curves_in_model : tuple of (n_i, 3) float
        The noise-free samples, model frame.
    plane_normals_in_model : (k, 3) float
        Normals of the sampling planes, model frame.
    """

    curves: DataCurves
    point_in_model: np.ndarray
    normal_in_model: np.ndarray
    T_model_from_data: np.ndarray
    clean_curves_in_model: tuple[np.ndarray, ...]
    plane_normals_in_model: np.ndarray


def random_rigid_transform(rng: np.random.Generator, translation_scale_m: float = 0.1):
    """A uniformly random rotation and a Gaussian translation, as a 4x4 matrix."""
    T = np.eye(4)
    T[:3, :3] = Rotation.random(random_state=rng).as_matrix()
    T[:3, 3] = rng.normal(scale=translation_scale_m, size=3)
    return T


def _unit(v):
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v)
    if not n > 0:
        raise InvalidCurveData(f"expected a non-zero vector, got {v}")
    return v / n


def sampling_plane_normals(
    normal, first_direction=None, plane_angle_rad: float = np.pi / 3, count: int = 3
) -> np.ndarray:
    """Normals of ``count`` planes that contain ``normal``, ``plane_angle_rad`` apart.

    The first plane contains ``first_direction`` (any tangent if omitted); plane k is
    the first rotated by ``k * plane_angle_rad`` about the surface normal. Planes that
    coincide (e.g. three planes 90 degrees apart: the first and the third) raise
    :class:`InvalidCurveData`.
    """
    angles = plane_angle_rad * np.arange(count)
    gap = np.abs(np.sin(angles[:, None] - angles[None, :])) + np.eye(count)
    if count > 1 and gap.min() < 1e-6:
        i, j = sorted(np.unravel_index(np.argmin(gap), gap.shape))
        raise InvalidCurveData(
            f"sampling planes {i} and {j} coincide at a plane angle of "
            f"{np.degrees(plane_angle_rad):g} degrees; expected distinct planes (for three "
            "planes, an angle strictly between 0 and 90 degrees, or between 90 and 180)"
        )
    n = _unit(normal)
    if first_direction is None:
        first_direction = np.eye(3)[np.argmin(np.abs(n))]
    t = np.asarray(first_direction, float) - n * (np.asarray(first_direction, float) @ n)
    t = _unit(t)
    b = np.cross(n, t)
    directions = np.cos(angles)[:, None] * t + np.sin(angles)[:, None] * b
    return np.cross(directions, n)  # plane normal = in-plane tangent x surface normal


def resample_around(polyline: np.ndarray, point: np.ndarray, n_points: int, spacing: float):
    """``n_points`` at arc-length ``spacing`` along a polyline, ``point`` in the middle.

    The polyline is ordered; ``point`` is projected onto it. Raises
    :class:`DegenerateGeometry` when the polyline ends before the samples do.
    """
    seg = np.diff(polyline, axis=0)
    seg_len = np.linalg.norm(seg, axis=1)
    s_nodes = np.concatenate([[0.0], np.cumsum(seg_len)])
    # projection of point onto every segment
    w = np.clip(
        np.einsum("ij,ij->i", point - polyline[:-1], seg) / np.maximum(seg_len**2, 1e-300), 0, 1
    )
    proj = polyline[:-1] + w[:, None] * seg
    k = int(np.argmin(np.linalg.norm(proj - point, axis=1)))
    s0 = s_nodes[k] + w[k] * seg_len[k]
    half = (n_points - 1) / 2.0
    s = s0 + spacing * (np.arange(n_points) - half)
    if s[0] < -1e-12 or s[-1] > s_nodes[-1] + 1e-12:
        raise DegenerateGeometry(
            f"the section through p is too short: {n_points} points at {spacing * 1e3:.3g} mm "
            f"need {spacing * (n_points - 1) * 1e3:.3g} mm centred on p, the section offers "
            f"{s0 * 1e3:.3g} mm before and {(s_nodes[-1] - s0) * 1e3:.3g} mm after"
        )
    return np.column_stack([np.interp(s, s_nodes, polyline[:, i]) for i in range(3)])


def plane_section_polyline(
    vertices: np.ndarray, faces: np.ndarray, point: np.ndarray, plane_normal: np.ndarray
) -> np.ndarray:
    """The plane section through ``point`` of a triangle set, as an ordered polyline.

    Each section point lies on a mesh edge crossed by the plane and is keyed by that
    edge, so the segments of neighbouring triangles join exactly. The component of the
    section nearest ``point`` is walked both ways from the segment nearest it; a closed
    section is returned as an open loop. Signed distances are taken for every vertex
    given: pass a compact local mesh (see :func:`local_submesh`) when cutting a small
    region of a large one.
    """
    n = np.asarray(plane_normal, float)
    d = vertices @ n - point @ n
    tri_d = d[faces]
    above = tri_d > 0
    crossing = above.any(axis=1) & ~above.all(axis=1)
    if not crossing.any():
        raise DegenerateGeometry("the sampling plane does not cut the mesh near p")
    f, fd = faces[crossing], tri_d[crossing]
    ft = vertices[f]
    # the two edges of each crossing triangle whose endpoints lie on opposite sides
    i0 = np.array([0, 1, 2])
    i1 = np.array([1, 2, 0])
    cut = (fd[:, i0] > 0) != (fd[:, i1] > 0)  # (m, 3)
    keep = cut.sum(axis=1) == 2
    f, fd, ft, cut = f[keep], fd[keep], ft[keep], cut[keep]
    sel = np.argsort(~cut, axis=1, kind="stable")[:, :2]  # (m, 2) edge slots
    a_idx, b_idx = i0[sel], i1[sel]
    rows = np.arange(len(f))[:, None]
    va, vb = f[rows, a_idx], f[rows, b_idx]
    da, db = fd[rows, a_idx], fd[rows, b_idx]
    pa, pb = ft[rows, a_idx], ft[rows, b_idx]
    s = (da / (da - db))[..., None]
    pts = pa + s * (pb - pa)  # (m, 2, 3)
    key = np.minimum(va, vb) * len(vertices) + np.maximum(va, vb)
    nodes, inverse = np.unique(key.ravel(), return_inverse=True)
    seg = inverse.reshape(-1, 2)
    position = np.zeros((len(nodes), 3))
    position[seg.ravel()] = pts.reshape(-1, 3)
    # the (at most two) segments at each node
    link = np.full((len(nodes), 2), -1, np.int64)
    flat_node = seg.ravel()
    order = np.argsort(flat_node, kind="stable")
    owner = (np.arange(flat_node.size) // 2)[order]
    node_sorted = flat_node[order]
    slot = np.arange(node_sorted.size) - np.searchsorted(node_sorted, node_sorted)
    ok = slot < 2
    link[node_sorted[ok], slot[ok]] = owner[ok]
    mid = 0.5 * (position[seg[:, 0]] + position[seg[:, 1]])
    first = int(np.argmin(np.linalg.norm(mid - point, axis=1)))
    used = np.zeros(len(seg), bool)
    used[first] = True
    link_l, seg_l = link.tolist(), seg.tolist()

    def walk(node):
        path = [node]
        while True:
            s0, s1 = link_l[node]
            nxt = s0 if s0 >= 0 and not used[s0] else (s1 if s1 >= 0 and not used[s1] else -1)
            if nxt < 0:
                return path
            used[nxt] = True
            a, b = seg_l[nxt]
            node = b if a == node else a
            path.append(node)

    a, b = seg_l[first]
    forward = walk(b)
    backward = walk(a)
    return position[backward[::-1] + forward]


def local_submesh(vertices: np.ndarray, faces: np.ndarray, face_ids: np.ndarray):
    """The faces ``face_ids`` as a compact mesh: (local vertices, reindexed faces)."""
    used, inverse = np.unique(faces[face_ids], return_inverse=True)
    return vertices[used], inverse.reshape(-1, 3)


def mesh_plane_section(
    mesh: trimesh.Trimesh,
    point: np.ndarray,
    plane_normal: np.ndarray,
    radius: float | None = None,
    local_faces: np.ndarray | None = None,
) -> np.ndarray:
    """The connected plane section of ``mesh`` through ``point``, as an ordered polyline.

    Only faces within ``radius`` of ``point`` (or the given ``local_faces``) are
    intersected (a closed section is then cut into an open arc through the point).
    """
    vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    if local_faces is None and radius is not None:
        local_faces = np.flatnonzero(
            np.linalg.norm(mesh.triangles_center - point, axis=1) <= radius
        )
    if local_faces is not None:
        vertices, faces = local_submesh(vertices, faces, local_faces)
    return plane_section_polyline(vertices, faces, point, plane_normal)


def _finish(
    clean_in_model, point, normal, planes, noise_std_m, rng, transform, translation_scale_m
) -> SyntheticCurves:
    if noise_std_m > 0 and rng is None:
        raise InvalidCurveData("noise_std_m > 0 needs an explicit numpy.random.Generator")
    if transform and rng is None:
        raise InvalidCurveData("a random transform needs an explicit numpy.random.Generator")
    T_data_from_model = random_rigid_transform(rng, translation_scale_m) if transform else np.eye(4)
    noisy = [
        c + (rng.normal(scale=noise_std_m, size=c.shape) if noise_std_m > 0 else 0.0)
        for c in clean_in_model
    ]
    R, t = T_data_from_model[:3, :3], T_data_from_model[:3, 3]
    data = DataCurves(tuple(c @ R.T + t for c in noisy), approach=-(R @ normal))
    return SyntheticCurves(
        data,
        np.asarray(point, float),
        np.asarray(normal, float),
        np.linalg.inv(T_data_from_model),
        tuple(clean_in_model),
        np.asarray(planes, float),
    )


def mesh_data_curves(
    mesh: trimesh.Trimesh,
    point,
    *,
    normal=None,
    n_points: int = 81,
    spacing_m: float = 0.3e-3,
    plane_angle_deg: float = 60.0,
    first_direction=None,
    plane_normals=None,
    noise_std_m: float = 0.02e-3,
    rng: np.random.Generator | None = None,
    transform: bool = True,
    translation_scale_m: float = 0.1,
) -> SyntheticCurves:
    """Three data curves through ``point`` on a triangle mesh (thesis Section 4.3.4).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Watertight model in metres.
    point : (3,) float or int
        A point on the surface, or a vertex index.
    normal : (3,) float, optional
        Outward normal at ``point`` (default: the area-weighted vertex normal (4.13) of the
        nearest vertex).
    n_points, spacing_m
        Points per curve and their arc-length spacing (p is the middle point).
    plane_angle_deg : float
        Angle between consecutive sampling planes, which all contain the normal.
    first_direction : (3,) float, optional
        A tangent direction in the first plane (random if ``rng`` is given).
    plane_normals : (k, 3) float, optional
        Arbitrary sampling planes through ``point`` instead.
    noise_std_m : float
        Isotropic Gaussian noise per coordinate.
    rng : numpy.random.Generator
        Needed for noise, a random first direction and the random transform.
    transform : bool
        Move the curves to a random data frame.
    """
    if np.ndim(point) == 0:
        vertex = int(point)
        point = mesh.vertices[vertex]
    else:
        point = np.asarray(point, float)
        vertex = int(mesh.kdtree.query(point)[1])
    if normal is None:
        normal = mesh.vertex_normals[vertex]
    normal = _unit(normal)
    if plane_normals is None:
        if first_direction is None and rng is not None:
            first_direction = rng.normal(size=3)
        plane_normals = sampling_plane_normals(normal, first_direction, np.deg2rad(plane_angle_deg))
    radius = 0.75 * spacing_m * (n_points - 1) + 5e-3
    clean = []
    for m in plane_normals:
        polyline = mesh_plane_section(mesh, point, _unit(m), radius=radius)
        clean.append(resample_around(polyline, point, n_points, spacing_m))
    return _finish(
        clean, point, normal, plane_normals, noise_std_m, rng, transform, translation_scale_m
    )


def _trace_implicit(surface, point, plane_normal, length, step):
    """Points of {f = 0} ∩ plane from ``point`` over arc ``length`` (predictor-corrector)."""

    def project(q):
        for _ in range(20):
            g = surface.gradient(q[None])[0]
            g = g - plane_normal * (g @ plane_normal)
            f = surface.implicit(q[None])[0]
            dq = f * g / (g @ g)
            q = q - dq
            if np.linalg.norm(dq) < 1e-14 * max(1.0, np.linalg.norm(q)):
                break
        return q

    branches = []
    for sign in (1.0, -1.0):
        q = project(np.asarray(point, float))
        pts = [q]
        travelled = 0.0
        while travelled < length:
            g = surface.gradient(q[None])[0]
            t = np.cross(plane_normal, g)
            t = sign * t / np.linalg.norm(t)
            q_new = project(q + step * t)
            travelled += np.linalg.norm(q_new - q)
            pts.append(q_new)
            q = q_new
        branches.append(np.array(pts))
    return np.concatenate([branches[1][::-1], branches[0][1:]])


def implicit_data_curves(
    surface: ImplicitSurface,
    point,
    *,
    n_points: int = 61,
    spacing: float = 0.01,
    plane_angle_deg: float = 60.0,
    first_direction=None,
    plane_normals=None,
    noise_std: float = 0.0,
    rng: np.random.Generator | None = None,
    transform: bool = True,
    translation_scale: float = 0.1,
) -> SyntheticCurves:
    """Data curves through ``point`` on an implicit surface ``f = 0`` (thesis Section 4.2.3).

    Same parameters as :func:`mesh_data_curves` (in the surface's units); the outward
    normal is the normalised gradient of f at ``point``. The curves are traced with steps
    of ``spacing / 8`` and resampled at ``spacing``.
    """
    point = np.asarray(point, float)
    normal = _unit(surface.gradient(point[None])[0])
    if plane_normals is None:
        if first_direction is None and rng is not None:
            first_direction = rng.normal(size=3)
        plane_normals = sampling_plane_normals(normal, first_direction, np.deg2rad(plane_angle_deg))
    half = spacing * (n_points - 1) / 2.0
    clean = []
    for m in plane_normals:
        m = _unit(m)
        polyline = _trace_implicit(surface, point, m, 1.05 * half + spacing, spacing / 8.0)
        clean.append(resample_around(polyline, point, n_points, spacing))
    return _finish(
        clean, point, normal, plane_normals, noise_std, rng, transform, translation_scale
    )
