"""The data's own geometry and noise: where the curves meet, (4.1)-(4.6) there, their scatter."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.local_geometry import LocalSurfaceGeometry, local_surface_geometry
from recognition.surfaces.registration.config import DataGeometryConfig, FastConfig

__all__ = [
    "acceptable_error_m",
    "common_point",
    "data_fit_residual_m",
    "data_geometry",
    "data_noise_m",
    "median_spacing",
]

Array = NDArray[np.float64]


def median_spacing(curves: DataCurves) -> float:
    """Median distance between consecutive points of the curves, metres."""
    steps = [np.linalg.norm(np.diff(c, axis=0), axis=1) for c in curves.curves]
    return float(np.median(np.concatenate(steps)))


def _distances_to_polyline(points: Array, polyline: Array) -> Array:
    """(n,) distance from each point (n, 3) to a polyline (m, 3)."""
    a, ab = polyline[:-1], np.diff(polyline, axis=0)
    rel = points[:, None, :] - a[None]
    s = np.clip(np.einsum("nmi,mi->nm", rel, ab) / np.einsum("mi,mi->m", ab, ab), 0.0, 1.0)
    return np.min(np.linalg.norm(rel - s[..., None] * ab[None], axis=-1), axis=1)


def common_point(curves: DataCurves) -> Array:
    """The point where all the data curves meet (p of thesis Fig. 4.1), (3,) metres.

    Of the points of every curve, the one whose largest distance to the other curves is
    least; then the mean of the points of the curves nearest it. Unlike the pairwise
    closest points (:attr:`DataCurves.intersection`), a place where only two curves come
    close (sampling planes a few degrees apart over a strongly curved surface) is not
    taken for p.
    """
    best: tuple[float, Array] | None = None
    for i, c in enumerate(curves.curves):
        others = [_distances_to_polyline(c, o) for j, o in enumerate(curves.curves) if j != i]
        worst = np.max(others, axis=0)
        k = int(np.argmin(worst))
        if best is None or worst[k] < best[0]:
            best = (float(worst[k]), c[k])
    assert best is not None
    p = best[1]
    for _ in range(2):
        nearest = []
        for c in curves.curves:
            a, ab = c[:-1], np.diff(c, axis=0)
            s = np.clip(np.einsum("mi,mi->m", p - a, ab) / np.einsum("mi,mi->m", ab, ab), 0, 1)
            q = a + s[:, None] * ab
            nearest.append(q[np.argmin(np.linalg.norm(q - p, axis=1))])
        p = np.mean(nearest, axis=0)
    return p


def data_geometry(
    curves: DataCurves, config: DataGeometryConfig = DataGeometryConfig()
) -> LocalSurfaceGeometry:
    """Normal (4.1) and principal curvatures (4.2)-(4.6) of the data at p.

    :func:`~recognition.surfaces.local_geometry.local_surface_geometry` at the point
    where all curves meet (:func:`common_point`; with ``at_common_point`` False, at the
    curves' pairwise closest points), each curve fitted over the arc within
    max(``fit_half_length_m``, ``fit_spacings`` x the point spacing) of p by a
    polynomial of degree ``fit_degree``: about the neighbourhood of the models'
    paraboloid fits (4.14), and at least three points either side of p when the points
    are sparse (the thesis's real data: 1.2 mm apart). If a data curve turns by more
    than ``fit_max_turn`` over that arc (curvature kappa), the fit is repeated over
    ``fit_max_turn / kappa``, where a polynomial y(x) still follows the curve closely.
    """
    half = _fit_half_length(curves, config)
    point = common_point(curves) if config.at_common_point else None
    geometry = local_surface_geometry(
        curves, half_length_m=half, degree=config.fit_degree, point=point
    )
    if config.fit_max_turn is not None:
        kappa = max(f.curvature for f in geometry.frames)
        if kappa * half > config.fit_max_turn:
            geometry = local_surface_geometry(
                curves,
                half_length_m=config.fit_max_turn / kappa,
                degree=config.fit_degree,
                point=point,
            )
    return geometry


def _fit_half_length(curves: DataCurves, config: DataGeometryConfig) -> float:
    if config.fit_spacings is None:
        return config.fit_half_length_m
    return max(config.fit_half_length_m, config.fit_spacings * median_spacing(curves))


def data_noise_m(curves: DataCurves) -> float:
    """Standard deviation of the data's noise, from the residuals of each curve's plane.

    Every data curve lies in its sampling plane; with isotropic noise of standard
    deviation sigma, the residuals of a least-squares plane have a mean square of
    sigma^2 (n - 3) / n.
    """
    total, dof = 0.0, 0
    for c in curves.curves:
        centred = c - c.mean(axis=0)
        normal = np.linalg.svd(centred, full_matrices=False)[2][-1]
        residual = centred @ normal
        total += float(residual @ residual)
        dof += max(len(c) - 3, 1)
    return float(np.sqrt(total / dof))


def data_fit_residual_m(
    curves: DataCurves,
    config: DataGeometryConfig = DataGeometryConfig(),
    point: ArrayLike | None = None,
) -> float:
    """How far the data's local fits at p (default :func:`common_point`) miss the data, m.

    Each curve is fitted near p as in :func:`data_geometry` (a plane, then a polynomial
    in it along the local chord); the result is the largest, over the curves, of the fit's
    RMS residual (per degree of freedom) and of its distance from p.
    """
    p = common_point(curves) if point is None else np.asarray(point, float)
    half_length = _fit_half_length(curves, config)
    degree = config.fit_degree
    worst = 0.0
    for curve in curves.curves:
        centred = curve - curve.mean(axis=0)
        normal = np.linalg.svd(centred, full_matrices=False)[2][-1]
        distance = np.linalg.norm(curve - p, axis=1)
        near = np.flatnonzero(distance <= half_length)
        if near.size < degree + 2:
            near = np.sort(np.argsort(distance)[: degree + 2])
        local = curve[near[0] : near[-1] + 1]
        chord = local[-1] - local[0]
        chord -= normal * (chord @ normal)
        ex = chord / np.linalg.norm(chord)
        ey = np.cross(normal, ex)
        x, y = (local - p) @ ex, (local - p) @ ey
        scale = max(np.abs(x).max(), 1e-12)
        coef = np.polynomial.polynomial.polyfit(x / scale, y, degree)
        residual = y - np.polynomial.polynomial.polyval(x / scale, coef)
        rms = np.sqrt(residual @ residual / max(len(residual) - degree - 1, 1))
        worst = max(worst, float(rms), float(abs(coef[0])))
    return worst


def acceptable_error_m(noise_m: float, n_points: int, config: FastConfig = FastConfig()) -> float:
    """Largest mean registration error (4.8) that the data's noise explains, metres.

    For points displaced by Gaussian noise of standard deviation sigma, the mean distance
    to the surface they were sampled on is sqrt(2/pi) sigma, with a relative standard
    deviation of sqrt(pi/2 - 1 / 2) / sqrt(n) over n points once the error of the noise
    estimate itself (:func:`data_noise_m`) is included; the limit lies
    ``accept_sigmas`` such deviations above, plus ``accept_floor_m``. The noise is
    taken as at most ``accept_noise_cap_m``.
    """
    spread = np.sqrt(np.pi / 2 - 0.5) / np.sqrt(max(n_points, 1))
    mean = np.sqrt(2 / np.pi) * min(noise_m, config.accept_noise_cap_m)
    return float(mean * (1 + config.accept_sigmas * spread) + config.accept_floor_m)
