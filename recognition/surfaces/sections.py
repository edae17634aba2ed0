"""Plane sections of a triangle mesh, ordered and resampled at equal arc length.

The sampling planes of synthetic data (thesis Section 4.3.4) and of the thesis's
superposition on meshes (Eq. (4.15)) cut the mesh through a point; each section is an
ordered polyline, resampled with that point in the middle.
"""

from __future__ import annotations

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from recognition.errors import DegenerateGeometry

__all__ = ["local_submesh", "mesh_plane_section", "plane_section_polyline", "resample_around"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


def resample_around(polyline: Array, point: Array, n_points: int, spacing: float) -> Array:
    """``n_points`` at arc-length ``spacing`` along a polyline, ``point`` in the middle.

    The polyline is ordered; ``point`` is projected onto it. Raises
    :class:`DegenerateGeometry` when the polyline ends before the samples do.

    Parameters
    ----------
    polyline : (m, 3) float
        Ordered points, metres (or the surface's units).
    point : (3,) float
        The point that becomes the middle sample, same units.
    n_points : int
        Number of samples.
    spacing : float
        Arc length between consecutive samples, same units.

    Returns
    -------
    (n_points, 3) float
        The samples, in the polyline's order.
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
    vertices: Array, faces: IntArray, point: Array, plane_normal: ArrayLike
) -> Array:
    """The plane section through ``point`` of a triangle set, as an ordered polyline.

    Each section point lies on a mesh edge crossed by the plane and is keyed by that
    edge, so the segments of neighbouring triangles join exactly. The component of the
    section nearest ``point`` is walked both ways from the segment nearest it; a closed
    section is returned as an open loop. Signed distances are taken for every vertex
    given: pass a compact local mesh (see :func:`local_submesh`) when cutting a small
    region of a large one.

    Parameters
    ----------
    vertices : (n, 3) float
        Vertex positions, metres.
    faces : (f, 3) int
        Triangles, indices into ``vertices``.
    point : (3,) float
        A point of the plane, metres.
    plane_normal : (3,) float
        Unit normal of the plane.

    Returns
    -------
    (m, 3) float
        The section's points, metres, in walking order.
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

    def walk(node: int) -> list[int]:
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


def local_submesh(vertices: Array, faces: IntArray, face_ids: IntArray) -> tuple[Array, IntArray]:
    """The faces ``face_ids`` as a compact mesh: (local vertices, reindexed faces).

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (f, 3) int
    face_ids : (k,) int
        The faces to keep.

    Returns
    -------
    vertices : (m, 3) float
        The vertices the kept faces use, in index order.
    faces : (k, 3) int
        The kept faces, indexing the returned vertices.
    """
    used, inverse = np.unique(faces[face_ids], return_inverse=True)
    return vertices[used], inverse.reshape(-1, 3)


def mesh_plane_section(
    mesh: trimesh.Trimesh,
    point: Array,
    plane_normal: ArrayLike,
    radius: float | None = None,
    local_faces: IntArray | None = None,
) -> Array:
    """The connected plane section of ``mesh`` through ``point``, as an ordered polyline.

    Only faces within ``radius`` of ``point`` (or the given ``local_faces``) are
    intersected (a closed section is then cut into an open arc through the point).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The surface, metres.
    point : (3,) float
        A point of the plane, metres.
    plane_normal : (3,) float
        Unit normal of the plane.
    radius : float, optional
        Faces whose centre lies within this distance of ``point`` are cut, metres.
    local_faces : (k,) int, optional
        The faces to cut (instead of ``radius``).

    Returns
    -------
    (m, 3) float
        The section's points, metres, in walking order.
    """
    vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    if local_faces is None and radius is not None:
        local_faces = np.flatnonzero(
            np.linalg.norm(mesh.triangles_center - point, axis=1) <= radius
        )
    if local_faces is not None:
        vertices, faces = local_submesh(vertices, faces, local_faces)
    return plane_section_polyline(vertices, faces, point, plane_normal)
