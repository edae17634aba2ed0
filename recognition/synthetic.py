"""Synthetic data curves: sampling planes through a surface point (thesis 4.2.3, 4.3.4).

Three planes containing the surface normal at p, ``plane_angle`` apart (or any given
planes through p), are intersected with a surface: a triangle mesh (exact plane-mesh
section) or an implicit surface ``f = 0`` (traced by predictor-corrector steps). Each
section is resampled at equal arc-length spacing with p as its middle point, noise is
added, and the curves are moved to an unknown data frame by a random rigid motion. The
ground truth is kept apart.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from recognition.errors import InvalidCurveData
from recognition.rigid import random_rigid_motion
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.distance import MeshDistance
from recognition.surfaces.sections import mesh_plane_section, resample_around

__all__ = [
    "ImplicitSurface",
    "SyntheticCurves",
    "implicit_data_curves",
    "mesh_data_curves",
    "ray_contact",
    "sampling_plane_normals",
    "sensed_normal",
]

Array = NDArray[np.float64]


class ImplicitSurface(Protocol):
    """What :func:`implicit_data_curves` needs of a closed-form surface."""

    def implicit(self, points: Array) -> Array:
        """f(x) at (n, 3) points, (n,); the surface is f = 0."""

    def gradient(self, points: Array) -> Array:
        """(n, 3) gradient of f at (n, 3) points."""


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
    point_in_model: Array
    normal_in_model: Array
    T_model_from_data: Array
    clean_curves_in_model: tuple[Array, ...]
    plane_normals_in_model: Array


def _unit(v: ArrayLike) -> Array:
    """``v`` scaled to unit length (:class:`InvalidCurveData` for a zero vector)."""
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v)
    if not n > 0:
        raise InvalidCurveData(f"expected a non-zero vector, got {v}")
    return v / n


def sampling_plane_normals(
    normal: ArrayLike,
    first_direction: ArrayLike | None = None,
    plane_angle_rad: float = np.pi / 3,
    count: int = 3,
) -> Array:
    """Normals of ``count`` planes that contain ``normal``, ``plane_angle_rad`` apart.

    The first plane contains ``first_direction`` (any tangent if omitted); plane k is
    the first rotated by ``k * plane_angle_rad`` about the surface normal. Planes that
    coincide (e.g. three planes 90 degrees apart: the first and the third) raise
    :class:`InvalidCurveData`.

    Parameters
    ----------
    normal : (3,) float
        The surface normal (any length but zero).
    first_direction : (3,) float, optional
        A direction in the first plane (its component along ``normal`` is dropped).
    plane_angle_rad : float
        Angle between consecutive planes about the normal, radians.
    count : int
        Number of planes.

    Returns
    -------
    (count, 3) float
        Unit normals of the planes.
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


def _finish(
    clean_in_model: Sequence[Array],
    point: ArrayLike,
    normal: Array,
    planes: ArrayLike,
    noise_std_m: float,
    rng: np.random.Generator | None,
    transform: bool,
    translation_scale_m: float,
) -> SyntheticCurves:
    """Noise, the random data frame and the ground truth around clean model-frame curves."""
    if noise_std_m > 0 and rng is None:
        raise InvalidCurveData("noise_std_m > 0 needs an explicit numpy.random.Generator")
    if transform and rng is None:
        raise InvalidCurveData("a random transform needs an explicit numpy.random.Generator")
    if transform:
        assert rng is not None  # checked above
        T_data_from_model = random_rigid_motion(rng, translation_scale_m)
    else:
        T_data_from_model = np.eye(4)
    if noise_std_m > 0:
        assert rng is not None  # checked above
        noisy = [c + rng.normal(scale=noise_std_m, size=c.shape) for c in clean_in_model]
    else:
        noisy = [c + 0.0 for c in clean_in_model]
    R, t = T_data_from_model[:3, :3], T_data_from_model[:3, 3]
    data = DataCurves(tuple(c @ R.T + t for c in noisy), approach=-(R @ normal))
    return SyntheticCurves(
        data,
        np.asarray(point, float),
        np.asarray(normal, float),
        np.asarray(np.linalg.inv(T_data_from_model), dtype=np.float64),
        tuple(clean_in_model),
        np.asarray(planes, float),
    )


def mesh_data_curves(
    mesh: trimesh.Trimesh,
    point: ArrayLike,
    *,
    normal: ArrayLike | None = None,
    n_points: int = 81,
    spacing_m: float = 0.3e-3,
    plane_angle_deg: float = 60.0,
    first_direction: ArrayLike | None = None,
    plane_normals: ArrayLike | None = None,
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
        vertex = int(np.asarray(point))
        p: Array = mesh.vertices[vertex]
    else:
        p = np.asarray(point, float)
        vertex = int(mesh.kdtree.query(p)[1])
    unit_normal = _unit(mesh.vertex_normals[vertex] if normal is None else normal)
    if plane_normals is None:
        if first_direction is None and rng is not None:
            first_direction = rng.normal(size=3)
        planes = sampling_plane_normals(unit_normal, first_direction, np.deg2rad(plane_angle_deg))
    else:
        planes = np.asarray(plane_normals, float)
    radius = 0.75 * spacing_m * (n_points - 1) + 5e-3
    clean = []
    for m in planes:
        polyline = mesh_plane_section(mesh, p, _unit(m), radius=radius)
        clean.append(resample_around(polyline, p, n_points, spacing_m))
    return _finish(clean, p, unit_normal, planes, noise_std_m, rng, transform, translation_scale_m)


def _trace_implicit(
    surface: ImplicitSurface, point: ArrayLike, plane_normal: Array, length: float, step: float
) -> Array:
    """Points of {f = 0} ∩ plane from ``point`` over arc ``length`` (predictor-corrector)."""

    def project(q: Array) -> Array:
        """``q`` moved onto {f = 0} within the plane by Newton steps along grad f."""
        for _ in range(20):
            g = surface.gradient(q[None])[0]
            g = g - plane_normal * (g @ plane_normal)
            f = surface.implicit(q[None])[0]
            dq = f * g / (g @ g)
            q = q - dq
            if np.linalg.norm(dq) < 1e-14 * max(1.0, float(np.linalg.norm(q))):
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
            travelled += float(np.linalg.norm(q_new - q))
            pts.append(q_new)
            q = q_new
        branches.append(np.array(pts))
    return np.concatenate([branches[1][::-1], branches[0][1:]])


def implicit_data_curves(
    surface: ImplicitSurface,
    point: ArrayLike,
    *,
    n_points: int = 61,
    spacing: float = 0.01,
    plane_angle_deg: float = 60.0,
    first_direction: ArrayLike | None = None,
    plane_normals: ArrayLike | None = None,
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
    p = np.asarray(point, float)
    normal = _unit(surface.gradient(p[None])[0])
    if plane_normals is None:
        if first_direction is None and rng is not None:
            first_direction = rng.normal(size=3)
        planes = sampling_plane_normals(normal, first_direction, np.deg2rad(plane_angle_deg))
    else:
        planes = np.asarray(plane_normals, float)
    half = spacing * (n_points - 1) / 2.0
    clean = []
    for m in planes:
        m = _unit(m)
        polyline = _trace_implicit(surface, p, m, 1.05 * half + spacing, spacing / 8.0)
        clean.append(resample_around(polyline, p, n_points, spacing))
    return _finish(clean, p, normal, planes, noise_std, rng, transform, translation_scale)


def ray_contact(
    distance: MeshDistance,
    T_model_from_data: ArrayLike,
    start: ArrayLike,
    direction: ArrayLike,
    travel_m: float,
    *,
    noise_m: float = 0.0,
    rng: np.random.Generator | None = None,
    step_m: float = 0.1e-3,
    way_in: ArrayLike | None = None,
) -> Array | None:
    """A touch on a known mesh: where a probe moving along ``direction`` through
    ``start`` (data frame) first enters the mesh at the pose ``T_model_from_data``, at
    most ``travel_m`` beyond ``start``, with isotropic Gaussian noise of ``noise_m`` per
    axis (drawn from ``rng``); None when it meets nothing. The probe comes to ``start``
    in a straight line from ``start + way_in`` (default: ``travel_m`` behind it along
    ``direction``; a sensor lowered from above: a long way along its axis): a start
    inside the mesh (the surface nearer than predicted) gives the point where the probe
    met the surface on its way. The entry is bracketed on samples ``step_m`` apart and
    bisected to 1e-9 m.
    """
    T = np.asarray(T_model_from_data, dtype=np.float64)
    a = np.asarray(start, dtype=np.float64)
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    back = -travel_m * d if way_in is None else np.asarray(way_in, dtype=np.float64)

    low, high = distance.vertices.min(axis=0) - step_m, distance.vertices.max(axis=0) + step_m

    def signed(X: Array) -> Array:
        # exact distances within the mesh's bounding box only: outside lies outside
        Y = X @ T[:3, :3].T + T[:3, 3]
        near = np.all((Y >= low) & (Y <= high), axis=1)
        out = np.full(len(Y), np.inf)
        out[near] = distance.signed(Y[near])
        return out

    come = np.linspace(1.0, 0.0, max(int(np.ceil(np.linalg.norm(back) / step_m)), 1) + 1)
    go = np.arange(step_m, travel_m + step_m / 2, step_m)
    path = np.concatenate([a + come[:, None] * back, a + go[:, None] * d])
    inside = signed(path) <= 0
    entries = np.flatnonzero(inside[1:] & ~inside[:-1]) + 1
    if not entries.size:
        return None
    first = int(entries[0])
    lo, hi = path[first - 1], path[first]
    while np.linalg.norm(hi - lo) > 1e-9:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if signed(mid[None])[0] <= 0 else (mid, hi)
    point = hi
    if noise_m > 0:
        if rng is None:
            raise InvalidCurveData("ray_contact with noise needs a random generator (rng)")
        point = point + rng.normal(0.0, noise_m, 3)
    return point


def sensed_normal(
    distance: MeshDistance,
    T_model_from_data: ArrayLike,
    point: ArrayLike,
    *,
    noise_rad: float = 0.0,
    rng: np.random.Generator | None = None,
) -> Array:
    """The outward unit normal a sensor reports at a contact ``point`` (data frame) on a
    known mesh at the pose ``T_model_from_data``: the normal of the face nearest it, in
    the data frame, tilted by Gaussian noise of ``noise_rad`` per component across it
    (drawn from ``rng``)."""
    T = np.asarray(T_model_from_data, dtype=np.float64)
    q = T[:3, :3] @ np.asarray(point, dtype=np.float64) + T[:3, 3]
    _, _, face = distance.closest(q[None])
    normal = T[:3, :3].T @ distance.normals_of(face)[0]
    if noise_rad > 0:
        if rng is None:
            raise InvalidCurveData("sensed_normal with noise needs a random generator (rng)")
        helper = np.eye(3)[int(np.argmin(np.abs(normal)))]
        e1 = np.cross(normal, helper)
        e1 /= np.linalg.norm(e1)
        tilt = rng.normal(0.0, noise_rad, 2)
        normal = normal + tilt[0] * e1 + tilt[1] * np.cross(normal, e1)
    return np.asarray(normal / np.linalg.norm(normal), dtype=np.float64)
