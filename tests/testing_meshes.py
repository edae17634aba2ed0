"""Small test meshes with known geometry (metres)."""

from __future__ import annotations

import itertools

import numpy as np
import trimesh


def sphere(radius: float = 0.03, subdivisions: int = 5) -> trimesh.Trimesh:
    return trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)


def torus(major: float = 0.04, minor: float = 0.015, sections=(300, 120)) -> trimesh.Trimesh:
    return trimesh.creation.torus(
        major_radius=major,
        minor_radius=minor,
        major_sections=sections[0],
        minor_sections=sections[1],
    )


def cylinder(
    radius: float = 0.02, height: float = 0.08, n_theta: int = 240, n_z: int = 160, n_cap: int = 30
) -> trimesh.Trimesh:
    """A closed cylinder: a regular grid on its side (vertices exactly on it), flat caps."""
    theta = np.linspace(0, 2 * np.pi, n_theta, endpoint=False)
    z = np.linspace(-height / 2, height / 2, n_z)
    side = np.stack(
        np.broadcast_arrays(radius * np.cos(theta)[None], radius * np.sin(theta)[None], z[:, None]),
        axis=-1,
    ).reshape(-1, 3)
    idx = np.arange(n_z * n_theta).reshape(n_z, n_theta)
    a, b = idx[:-1], np.roll(idx[:-1], -1, axis=1)
    c, d = idx[1:], np.roll(idx[1:], -1, axis=1)
    faces = [np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)]
    vertices = [side]
    for ring_index, zc, flip in ((0, -height / 2, True), (n_z - 1, height / 2, False)):
        # concentric rings down to a centre vertex
        rings = [idx[ring_index]]
        for k in range(n_cap - 1, 0, -1):
            rk = radius * k / n_cap
            start = sum(len(x) for x in vertices)
            ring = np.stack([rk * np.cos(theta), rk * np.sin(theta), np.full(n_theta, zc)], -1)
            vertices.append(ring)
            rings.append(start + np.arange(n_theta))
        centre = sum(len(x) for x in vertices)
        vertices.append(np.array([[0.0, 0.0, zc]]))
        for outer, inner in itertools.pairwise(rings):
            o2, i2 = np.roll(outer, -1), np.roll(inner, -1)
            tri = np.concatenate([np.stack([outer, o2, i2], -1), np.stack([outer, i2, inner], -1)])
            faces.append(tri[:, ::-1] if not flip else tri)
        inner = rings[-1]
        fan = np.stack([inner, np.roll(inner, -1), np.full(n_theta, centre)], -1)
        faces.append(fan[:, ::-1] if not flip else fan)
    mesh = trimesh.Trimesh(np.concatenate(vertices), np.concatenate(faces), process=False)
    trimesh.repair.fix_winding(mesh)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def blob(subdivisions: int = 5, scale: float = 0.03) -> trimesh.Trimesh:
    """An ellipsoid with smooth bumps: no symmetry, curvature varying everywhere."""
    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    v = m.vertices
    x, y, z = v.T
    r = 1.0 + 0.12 * np.sin(2 * x + 1.0) * np.cos(3 * y) + 0.08 * z**3 + 0.05 * x * y
    v = v * r[:, None] * np.array([1.0, 0.8, 0.65]) * scale
    return trimesh.Trimesh(v, m.faces, process=False)


def ellipsoid(axes=(0.035, 0.025, 0.018), subdivisions: int = 5) -> trimesh.Trimesh:
    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    return trimesh.Trimesh(m.vertices * np.array(axes), m.faces, process=False)
