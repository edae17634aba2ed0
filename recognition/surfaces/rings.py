"""Ring descriptors: a surface's height over its tangent plane on rings about a point.

The thesis looks candidates up by the principal curvatures at p alone (Eq. (4.7)). Over a
database of many free-form models that lookup keeps a large share of every model's
surface (a tolerance of 0.03 1/mm admits 40 % of the candidates of 100 models). The
data curves say more: on a ring of radius rho about p (in the tangent plane), the six arms
of the curves give the surface's height h(theta) over the tangent plane at six angles.
Fitting h = a0 + a1 cos t + b1 sin t + a2 cos 2t + b2 sin 2t, the mean height a0 (the mean
curvature at scale rho: a0 ~ H rho^2 / 2) and the anisotropy |(a2, b2)| (the curvatures'
difference at that scale) do not depend on the turn about the normal, nor (to first order)
on a small error of the normal (the tilt terms a1, b1 absorb it). At a few radii they
make a multi-scale generalisation of (k1, k2), precomputed for every candidate vertex of
every model, so that one ranking over the whole database picks the candidates worth
screening (:func:`ring_scores`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.distance import DistanceField, FieldStack
from recognition.surfaces.local_geometry import LocalSurfaceGeometry

__all__ = [
    "RADII_M",
    "data_ring_descriptors",
    "model_ring_descriptors",
    "ring_invariants",
    "ring_scores",
    "ring_weights",
]

Array = NDArray[np.float64]
Array32 = NDArray[np.float32]

#: Ring radii, metres. The data's six arms sample a ring at six angles, so that their
#: harmonic fit folds the ring's fourth harmonic into the anisotropy and its sixth into
#: the mean height, more the wider the ring: on catalog and generated models the
#: six-angle estimate departs from the twelve-sample descriptor by a median of at most
#: 0.05 (mean height) and 0.18 (anisotropy) score scales at 3 mm, 0.19 and 1.1 at 6 mm,
#: 1.8 and 3.5 at 10 mm, where a ring misranks more candidates than it ranks when the
#: planes are 60 degrees apart (with planes 10-30 degrees apart it still helped a little:
#: ``docs/benchmarks/sweep_angle.md`` and the README).
RADII_M = (3.0e-3, 6.0e-3)
#: Samples per ring on a model.
RING_SAMPLES = 12
#: Newton steps that find the surface along the normal; a sample farther than
#: ``ON_SURFACE_M`` from the surface after them is undefined (the ring leaves the field's
#: band, or the surface folds back).
NEWTON_STEPS = 4
ON_SURFACE_M = 5.0e-5
#: A ring sample counts where the surface is within this angle of the tangent plane.
MAX_SLOPE_RAD = float(np.deg2rad(60.0))
#: Samples a model's ring needs (of ``RING_SAMPLES``); the data's need five arms.
MIN_RING_SAMPLES = 7
#: Score scales: a descriptor component may differ by ``SCALE_FLOOR_M`` plus
#: ``SCALE_RELATIVE`` of the data's mean height at that radius per standard unit; a ring
#: the data have and the model lacks costs ``MISSING_COST`` per component; no component
#: costs more than ``MAX_COST`` (an outlier among the data spoils one ring, not the score).
SCALE_FLOOR_M = 5.0e-5
SCALE_RELATIVE = 0.03
MISSING_COST = 9.0
MAX_COST = 25.0


def _harmonics(theta: Array) -> Array:
    """(..., 5) design matrix of h = a0 + a1 cos t + b1 sin t + a2 cos 2t + b2 sin 2t."""
    return np.stack(
        [np.ones_like(theta), np.cos(theta), np.sin(theta), np.cos(2 * theta), np.sin(2 * theta)],
        axis=-1,
    )


def ring_invariants(theta: Array, height: Array) -> Array:
    """(a0, |(a2, b2)|) of the least-squares harmonic fit of heights (k,) at angles (k,);
    NaN with fewer than five samples."""
    if len(theta) < 5:
        return np.full(2, np.nan)
    coef = np.linalg.lstsq(_harmonics(theta), height, rcond=None)[0]
    return np.array([coef[0], np.hypot(coef[3], coef[4])])


def model_ring_descriptors(
    field: DistanceField, points: Array, normals: Array, directions: Array
) -> Array32:
    """(m, len(RADII_M), 2) float32 ring invariants of a model at ``points`` (m, 3), with
    unit ``normals`` (m, 3) and tangent ``directions`` (m, 3), read off its distance field.

    Each ring sample is moved along the normal onto the surface (Newton on the field,
    from the height of the ring inside scaled as rho^2). A sample counts where it lies on
    the surface and the surface there is within ``MAX_SLOPE_RAD`` of the tangent plane
    (over a fold or an edge, the height over the plane is not the surface the data
    trace); the invariants are fitted to the samples that count, NaN where fewer than
    ``MIN_RING_SAMPLES`` do. The data's rings are measured alike
    (:func:`data_ring_descriptors`).
    """
    stack = FieldStack.of([field])
    theta: Array = np.linspace(0.0, 2 * np.pi, RING_SAMPLES, endpoint=False)
    t1 = directions - normals * np.einsum("ij,ij->i", directions, normals)[:, None]
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(normals, t1)
    out = np.empty((len(points), len(RADII_M), 2), np.float32)
    design = _harmonics(theta)  # (RING_SAMPLES, 5)
    for start in range(0, len(points), 4096):
        s = slice(start, start + 4096)
        ring = np.cos(theta)[:, None, None] * t1[s] + np.sin(theta)[:, None, None] * t2[s]
        ring = ring.transpose(1, 0, 2)  # (b, RING_SAMPLES, 3)
        n = np.broadcast_to(normals[s][:, None, :], ring.shape)
        which = np.zeros(len(ring), np.int64)
        h = np.zeros(ring.shape[:2])
        inside = RADII_M[0]
        for k, rho in enumerate(RADII_M):
            base = points[s][:, None, :] + rho * ring
            h = np.nan_to_num(h) * (rho / inside) ** 2
            for _ in range(NEWTON_STEPS):
                value, gradient = stack.value_and_gradient(base + h[..., None] * n, which)
                slope = np.einsum("bpi,bpi->bp", gradient, n)
                h -= value / np.maximum(slope, 0.3)
            value, gradient = stack.value_and_gradient(base + h[..., None] * n, which)
            gentle = np.einsum("bpi,bpi->bp", gradient, n) >= np.cos(MAX_SLOPE_RAD) * np.maximum(
                np.linalg.norm(gradient, axis=-1), 1e-12
            )
            on = (np.abs(value) <= ON_SURFACE_M) & gentle
            # least squares over the samples that count: (A' W A) c = A' W h
            weighted = design[None] * on[..., None]
            lhs = np.einsum("bpi,pj->bij", weighted, design) + 1e-9 * np.eye(5)
            rhs = np.einsum("bpi,bp->bi", weighted, np.where(on, h, 0.0))
            coef = np.linalg.solve(lhs, rhs[..., None])[..., 0]
            inv = np.stack([coef[:, 0], np.hypot(coef[:, 3], coef[:, 4])], axis=-1)
            inv[on.sum(axis=1) < MIN_RING_SAMPLES] = np.nan
            out[s, k] = inv
            h = np.where(on, h, np.nan)
            inside = rho
    return out


def data_ring_descriptors(curves: DataCurves, geometry: LocalSurfaceGeometry) -> Array:
    """(len(RADII_M), 2) ring invariants of the data about p in the frame of ``geometry``
    (d1, d2, N): on each arm of each curve, the point whose distance from p in the
    tangent plane first reaches the radius, interpolated, where the arm rises or falls
    there by less than ``MAX_SLOPE_RAD``; NaN at a radius fewer than five arms give."""
    p, frame = geometry.point, geometry.frame
    steep = np.tan(MAX_SLOPE_RAD)
    samples: list[list[tuple[float, float]]] = [[] for _ in RADII_M]
    for c in curves.curves:
        m = int(np.argmin(np.linalg.norm(c - p, axis=1)))
        for arm in (c[m:], c[m::-1]):
            q = (arm - p) @ frame
            r = np.hypot(q[:, 0], q[:, 1])
            for k, rho in enumerate(RADII_M):
                crossing = np.flatnonzero((r[:-1] < rho) & (r[1:] >= rho))
                if not crossing.size:
                    continue
                i = crossing[0]
                if abs(q[i + 1, 2] - q[i, 2]) > steep * (r[i + 1] - r[i]):
                    continue
                at = q[i] + (rho - r[i]) / (r[i + 1] - r[i]) * (q[i + 1] - q[i])
                samples[k].append((float(np.arctan2(at[1], at[0])), float(at[2])))
    out = np.full((len(RADII_M), 2), np.nan)
    for k, found in enumerate(samples):
        if found:
            theta, height = np.array(found).T
            out[k] = ring_invariants(theta, height)
    return out


def ring_weights(data: Array) -> Array:
    """(K,) the reciprocal scale of each radius' components in :func:`ring_scores`:
    1 / (``SCALE_FLOOR_M + SCALE_RELATIVE * |a0|``), 0 at radii the data do not reach."""
    reached = np.isfinite(data).all(axis=1)
    scale = SCALE_FLOOR_M + SCALE_RELATIVE * np.abs(np.nan_to_num(data[:, 0]))
    return np.where(reached, 1.0 / scale, 0.0)


def ring_scores(models: Array32, data: Array) -> Array:
    """(m,) squared standardised distance of models' ring descriptors (m, K, 2) from the
    data's (K, 2), over the radii the data reach: each component scaled by
    ``SCALE_FLOOR_M + SCALE_RELATIVE * |a0|`` (the data's mean height at that radius),
    ``MISSING_COST`` per component where the model's ring is undefined, at most
    ``MAX_COST`` per component."""
    from recognition.surfaces import field_kernels  # numba: imported when first needed

    return field_kernels.ring_scores(
        np.ascontiguousarray(models, np.float32),
        np.nan_to_num(np.asarray(data, np.float64)),
        ring_weights(np.asarray(data, np.float64)),
        MISSING_COST,
        MAX_COST,
    ).astype(np.float64)
