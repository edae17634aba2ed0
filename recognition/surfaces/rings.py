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

Six samples cannot tell the ring's higher harmonics from the fitted ones: at six equally
spaced angles the fourth harmonic is the second and the sixth a constant. A model's ring,
sampled at twelve angles, also stores the RMS of each of its harmonics 3 to 6 (in the
residual of the fit); the data's sample angles give how much of each every invariant
takes (:func:`alias_gains`, over the harmonic's unknown phase), and the score counts that
as noise.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.distance import DistanceField, FieldStack
from recognition.surfaces.local_geometry import LocalSurfaceGeometry

__all__ = [
    "RADII_M",
    "alias_gains",
    "check_ring_shapes",
    "data_ring_descriptors",
    "model_ring_descriptors",
    "ring_invariants",
    "ring_scores",
    "ring_weights",
]

Array = NDArray[np.float64]
Array32 = NDArray[np.float32]

#: Ring radii, metres. Over wider rings the data's six samples alias more of the ring's
#: higher harmonics (on catalog and generated models the six-angle estimate departs from
#: the twelve-sample fit by a median of at most 0.05 (mean height) and 0.18 (anisotropy)
#: base score scales at 3 mm, 0.19 and 1.1 at 6 mm, 1.8 and 3.5 at 10 mm). The score
#: counts the aliasing (:func:`alias_gains`), and still a 10 mm ring misranks more than
#: it ranks: over the 280 instances of 100 models at n = 21, d = 1.2 mm it recognises 258
#: against 265 without it (README, "Many models").
RADII_M = (3.0e-3, 6.0e-3)
#: Samples per ring on a model.
RING_SAMPLES = 12
#: The harmonics above the fit's that a model's ring resolves (twelve samples).
ALIAS_HARMONICS = (3, 4, 5, 6)
#: Values per ring of a model: a0, |(a2, b2)|, the RMS of each of ``ALIAS_HARMONICS``.
DESCRIPTOR_SIZE = 2 + len(ALIAS_HARMONICS)
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


def alias_gains(theta: Array) -> Array:
    """(2, len(ALIAS_HARMONICS)) how much of each of a ring's harmonics 3 to 6 the
    harmonic fit at angles ``theta`` (k,) takes into a0 (row 0) and into |(a2, b2)|
    (row 1): standard deviations per unit RMS of the harmonic, over its phase. A harmonic
    k of RMS R and phase psi gives heights sqrt(2) R cos(k theta + psi), and the fit's
    coefficients are P h with P the fit's pseudo-inverse, so a0 takes R |P_0 . z| with
    z = exp(i k theta), and the anisotropy, along (a2, b2) in mean square over that
    direction, R ((|P_3 . z|^2 + |P_4 . z|^2) / 2)^(1/2). At six equally spaced angles a0
    takes the sixth harmonic whole and the anisotropy the fourth; NaN with fewer than five
    angles."""
    if len(theta) < 5:
        return np.full((2, len(ALIAS_HARMONICS)), np.nan)
    pinv = np.linalg.pinv(_harmonics(theta))  # (5, k)
    z = np.exp(1j * np.outer(ALIAS_HARMONICS, theta))  # (h, k)
    leak = np.abs(z @ pinv.T)  # (h, 5)
    return np.stack([leak[:, 0], np.sqrt(0.5 * (leak[:, 3] ** 2 + leak[:, 4] ** 2))])


def model_ring_descriptors(
    field: DistanceField, points: Array, normals: Array, directions: Array
) -> Array32:
    """(m, len(RADII_M), DESCRIPTOR_SIZE) float32 ring descriptors of a model at
    ``points`` (m, 3), with unit ``normals`` (m, 3) and tangent ``directions`` (m, 3), read
    off its distance field: the invariants (a0, |(a2, b2)|), then the RMS of each of the
    ring's harmonics ``ALIAS_HARMONICS`` (which six data samples alias), from the harmonic
    fit's residual.

    Each ring sample is moved along the normal onto the surface (Newton on the field,
    from the height of the ring inside scaled as rho^2). A sample counts where it lies on
    the surface and the surface there is within ``MAX_SLOPE_RAD`` of the tangent plane
    (over a fold or an edge, the height over the plane is not the surface the data
    trace); the invariants are fitted to the samples that count, NaN where fewer than
    ``MIN_RING_SAMPLES`` do; a harmonic's RMS is its Fourier amplitude in the residual
    over them. Where samples are missing this is a rough estimate (the five-term fit
    takes up part of the harmonics, and the rest spreads over the others), so that a
    partial ring gets less room than it should. The data's rings are measured alike
    (:func:`data_ring_descriptors`).
    """
    stack = FieldStack.of([field])
    theta: Array = np.linspace(0.0, 2 * np.pi, RING_SAMPLES, endpoint=False)
    t1 = directions - normals * np.einsum("ij,ij->i", directions, normals)[:, None]
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(normals, t1)
    out = np.empty((len(points), len(RADII_M), DESCRIPTOR_SIZE), np.float32)
    waves = np.exp(-1j * np.outer(theta, ALIAS_HARMONICS))  # (RING_SAMPLES, h)
    # a harmonic's |sum of residual * exp(-i k theta)| / count is half its amplitude, so
    # sqrt(2) times it is its RMS; the Nyquist harmonic's is its RMS at the samples
    # (twelve samples see cos 6 theta alone)
    per_amplitude = np.where(2 * np.array(ALIAS_HARMONICS) == RING_SAMPLES, 1.0, np.sqrt(2.0))
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
            count = on.sum(axis=1)
            residual = np.where(on, h - coef @ design.T, 0.0)
            amplitude = np.abs(residual @ waves) / np.maximum(count, 1)[:, None]
            inv = np.concatenate(
                [
                    coef[:, :1],
                    np.hypot(coef[:, 3], coef[:, 4])[:, None],
                    amplitude * per_amplitude,
                ],
                axis=1,
            )
            inv[count < MIN_RING_SAMPLES] = np.nan
            out[s, k] = inv
            h = np.where(on, h, np.nan)
            inside = rho
    return out


def data_ring_descriptors(curves: DataCurves, geometry: LocalSurfaceGeometry) -> Array:
    """(len(RADII_M), 2 + 2 len(ALIAS_HARMONICS)) ring descriptors of the data about p in
    the frame of ``geometry`` (d1, d2, N): the invariants (a0, |(a2, b2)|), then their
    :func:`alias_gains` (a0's, then the anisotropy's). A ring's samples are, on each arm
    of each curve, the point whose distance from p in the tangent plane first reaches the
    radius, interpolated, where the arm rises or falls there by less than
    ``MAX_SLOPE_RAD``; NaN at a radius fewer than five arms give."""
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
    out = np.full((len(RADII_M), 2 + 2 * len(ALIAS_HARMONICS)), np.nan)
    for k, found in enumerate(samples):
        if found:
            theta, height = np.array(found).T
            out[k] = np.concatenate([ring_invariants(theta, height), *alias_gains(theta)])
    return out


def check_ring_shapes(models: Array32, data: Array) -> None:
    """Assert that models' descriptors (..., K, 2 + h) and the data's (K, 2 + 2 h) agree
    (the compiled score reads them unchecked)."""
    k, size = models.shape[-2:]
    assert data.shape == (k, 2 + 2 * (size - 2)), (models.shape, data.shape)


def ring_weights(data: Array) -> Array:
    """(K,) the reciprocal base scale of each radius' components in :func:`ring_scores`:
    1 / (``SCALE_FLOOR_M + SCALE_RELATIVE * |a0|``), 0 at radii the data do not reach."""
    reached = np.isfinite(data).all(axis=1)
    scale = SCALE_FLOOR_M + SCALE_RELATIVE * np.abs(np.nan_to_num(data[:, 0]))
    return np.where(reached, 1.0 / scale, 0.0)


def ring_scores(models: Array32, data: Array) -> Array:
    """(m,) squared standardised distance of models' ring descriptors (m, K,
    DESCRIPTOR_SIZE) from the data's (:func:`data_ring_descriptors`), over the radii the
    data reach: each invariant's difference over the root sum of squares of the base
    scale ``SCALE_FLOOR_M + SCALE_RELATIVE * |a0|`` (the data's mean height at that
    radius) and of the model's harmonics' RMS times the data's gains for them (what the
    data's fit aliases); ``MISSING_COST`` per component where the model's ring is
    undefined, at most ``MAX_COST`` per component. The room a ring's harmonics give is
    not charged for (the score ranks candidates for screening; charging it as a Gaussian
    likelihood would, with log(1 + leak^2) per component, recognised 255 of the 280
    instances of 100 models at n = 21, d = 1.2 mm against 265)."""
    from recognition.surfaces import field_kernels  # numba: imported when first needed

    check_ring_shapes(models, data)
    return field_kernels.ring_scores(
        np.ascontiguousarray(models, np.float32),
        np.nan_to_num(np.asarray(data, np.float64)),
        ring_weights(np.asarray(data, np.float64)),
        MISSING_COST,
        MAX_COST,
    ).astype(np.float64)
