"""The data's own geometry and noise: where the curves meet, (4.1)-(4.6) there, their scatter."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import gammaincinv

from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.local_geometry import LocalSurfaceGeometry, local_surface_geometry
from recognition.surfaces.registration.config import DataGeometryConfig, FastConfig

__all__ = [
    "acceptable_error_m",
    "common_point",
    "data_fit_residual_m",
    "data_geometry",
    "data_noise_m",
    "effective_noise_m",
    "median_spacing",
    "outlier_threshold_m",
    "plane_scatter_m",
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
    ``fit_max_turn / kappa``, where a polynomial y(x) still follows the curve closely; if
    it turns by more than ``normal_max_turn``, the normal alone comes from fits over
    ``normal_max_turn / kappa`` (oriented as the whole arc's) and the curvatures from the
    whole arc's fits at that normal (:meth:`LocalSurfaceGeometry.with_normal`).
    """
    half = _fit_half_length(curves, config)
    point = common_point(curves) if config.at_common_point else None
    geometry = local_surface_geometry(
        curves, half_length_m=half, degree=config.fit_degree, point=point
    )
    shorter = _arc_turning(geometry, half, config.fit_max_turn)
    if shorter is not None:
        half = shorter
        geometry = local_surface_geometry(
            curves, half_length_m=half, degree=config.fit_degree, point=point
        )
    shorter = _arc_turning(geometry, half, config.normal_max_turn)
    if shorter is not None:
        short = local_surface_geometry(
            curves, half_length_m=shorter, degree=config.fit_degree, point=point
        )
        normal = short.normal if short.normal @ geometry.normal >= 0 else -short.normal
        geometry = geometry.with_normal(normal)
    return geometry


def _arc_turning(
    geometry: LocalSurfaceGeometry, half: float, max_turn: float | None
) -> float | None:
    """The half length of arc over which the most curved of ``geometry``'s data curves
    (fitted over ``half``) turns by ``max_turn`` radians, when shorter than ``half``;
    None: it is not, or no limit."""
    if max_turn is None:
        return None
    kappa = max(f.curvature for f in geometry.frames)
    return max_turn / kappa if kappa * half > max_turn else None


def _fit_half_length(curves: DataCurves, config: DataGeometryConfig) -> float:
    if config.fit_spacings is None:
        return config.fit_half_length_m
    return max(config.fit_half_length_m, config.fit_spacings * median_spacing(curves))


def plane_scatter_m(curves: DataCurves) -> float:
    """RMS distance of the data points from their curves' least-squares planes, metres.

    Every data curve lies in its sampling plane; with isotropic noise of standard
    deviation sigma, the residuals of a least-squares plane have a mean square of
    sigma^2 (n - 3) / n, and this is sigma. A sensor's error along the surface (a contact
    point displaced sideways, out of the sampling plane, where the surface slopes across
    it) counts here too, though it moves the point along the surface, not off it.
    """
    total, dof = 0.0, 0
    for c in curves.curves:
        centred = c - c.mean(axis=0)
        normal = np.linalg.svd(centred, full_matrices=False)[2][-1]
        residual = centred @ normal
        total += float(residual @ residual)
        dof += max(len(c) - 3, 1)
    return float(np.sqrt(total / dof))


#: Points per window and degree of the local fits of :func:`data_noise_m`.
NOISE_WINDOW, NOISE_DEGREE = 7, 4


def data_noise_m(curves: DataCurves) -> float:
    """Standard deviation of the data's noise across the surface, metres.

    Each curve, in its sampling plane, is fitted by a polynomial of degree
    ``NOISE_DEGREE`` over every window of ``NOISE_WINDOW`` consecutive points (along the
    window's chord); the residuals, per degree of freedom left, estimate the noise that
    moves points off the curve within its plane: off the surface, where the plane holds
    the surface normal. Unlike :func:`plane_scatter_m`, a point displaced along the
    surface, across the plane, does not count. The estimate is the median over the
    windows (scaled by the chi-square median, so that it is sigma for Gaussian noise):
    a gross outlier spoils the few windows that hold it, not the estimate. On noise-free
    data the result is the fits' own error (about a micrometre at the thesis's spacings on
    curvature radii of a few millimetres and more).
    """
    variances = []
    for c in curves.curves:
        w = min(NOISE_WINDOW, len(c))
        if w < NOISE_DEGREE + 2:
            continue
        centred = c - c.mean(axis=0)
        basis = np.linalg.svd(centred, full_matrices=False)[2][:2]  # the plane's axes
        xy = centred @ basis.T  # (n, 2)
        windows = np.lib.stride_tricks.sliding_window_view(xy, (w, 2))[:, 0]  # (k, w, 2)
        chord = windows[:, -1] - windows[:, 0]
        ex = chord / np.maximum(np.linalg.norm(chord, axis=1, keepdims=True), 1e-300)
        ey = np.stack([-ex[:, 1], ex[:, 0]], axis=1)
        rel = windows - windows.mean(axis=1, keepdims=True)
        x = np.einsum("kwi,ki->kw", rel, ex)
        y = np.einsum("kwi,ki->kw", rel, ey)
        x = x / np.maximum(np.abs(x).max(axis=1, keepdims=True), 1e-300)
        A = x[..., None] ** np.arange(NOISE_DEGREE + 1)  # (k, w, degree + 1)
        AT = np.swapaxes(A, 1, 2)
        coef = np.linalg.solve(AT @ A + 1e-12 * np.eye(NOISE_DEGREE + 1), AT @ y[..., None])
        residual = y - (A @ coef)[..., 0]
        dof = w - NOISE_DEGREE - 1
        chi2_median = 2.0 * float(gammaincinv(dof / 2.0, 0.5))  # of chi-square, dof degrees
        variances.append(np.sum(residual * residual, axis=1) / chi2_median)
    if not variances:
        return plane_scatter_m(curves)
    return float(np.sqrt(np.median(np.concatenate(variances))))


def effective_noise_m(noise_m: float, config: FastConfig = FastConfig()) -> float:
    """The error a data point has on its own model: sensor noise and model mismatch,
    sqrt(noise^2 + ``model_mismatch_m``^2), metres."""
    return float(np.hypot(noise_m, config.model_mismatch_m))


def outlier_threshold_m(noise_m: float, config: FastConfig = FastConfig()) -> float:
    """Distance from the model beyond which a data point is an outlier, metres:
    ``outlier_sigmas`` effective noise levels (:func:`effective_noise_m`), at least
    ``outlier_floor_m``."""
    return max(config.outlier_sigmas * effective_noise_m(noise_m, config), config.outlier_floor_m)


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

    For points displaced by Gaussian errors of standard deviation sigma (the effective
    noise, :func:`effective_noise_m`: the noise across the surface of
    :func:`data_noise_m` and the model mismatch), the mean distance to the surface they
    were sampled on is sqrt(2/pi) sigma, with a relative standard deviation of
    sqrt(pi/2 - 1 / 2) / sqrt(n) over n points once the error of the noise estimate
    itself is included; the limit lies ``accept_sigmas`` such deviations above, plus
    ``accept_floor_m``.
    """
    spread = np.sqrt(np.pi / 2 - 0.5) / np.sqrt(max(n_points, 1))
    mean = np.sqrt(2 / np.pi) * effective_noise_m(noise_m, config)
    return float(mean * (1 + config.accept_sigmas * spread) + config.accept_floor_m)
