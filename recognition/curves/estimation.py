"""Curvature and its arc-length derivative from ordered planar tactile points (thesis 3.4).

Two estimators:

* :func:`finite_difference_geometry`: the central differences of Section 3.4 on the
  tangent angle phi(s); accurate on exact data, fragile under noise (Fig. 3.6).
* :func:`local_fit_geometry`: the robust estimator of Section 3.4.2, generalised. A
  polynomial ``v = y(u)`` is fitted over a sliding window of ``window`` points in the
  window's own chord frame (the thesis fits ``y = y(x)`` in world coordinates, which
  fails where the curve is vertical); kappa, phi and the position at the window's middle
  point come from the fit. Arc length between estimates is integrated on the fit by
  Simpson's rule. kappa_s comes from a quadratic fit of kappa(s) over a sliding window of
  ``kappa_window`` estimates (thesis) or, with ``kappa_window=None``, from the third
  derivative of the first fit (needs ``degree >= 3``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import ArrayLike

from recognition.errors import InvalidCurveData

__all__ = [
    "LocalGeometry",
    "finite_difference_geometry",
    "local_fit_geometry",
    "validate_points",
]

#: A step shorter than this fraction of the median step counts as a repeated point.
REPEATED_POINT_TOL = 1e-6
#: A step longer than this multiple of the median step counts as a jump (unordered data).
JUMP_FACTOR = 8.0


@dataclass(frozen=True)
class LocalGeometry:
    """Local geometry estimated at ``m`` points of a sampled curve.

    Attributes
    ----------
    index : (m,) int
        Index of the input point each estimate belongs to.
    position : (m, 2) float
        Estimated curve point (denoised), same unit as the input.
    s : (m,) float
        Arc length from the first estimate.
    phi : (m,) float
        Tangent angle in radians, unwrapped, for the direction of traversal.
    kappa : (m,) float
        Signed curvature (positive when turning left), 1/unit.
    kappa_s : (m,) float
        d kappa / d s, 1/unit^2.
    """

    index: np.ndarray
    position: np.ndarray
    s: np.ndarray
    phi: np.ndarray
    kappa: np.ndarray
    kappa_s: np.ndarray

    def __len__(self) -> int:
        """Number of estimates m."""
        return self.kappa.size

    @property
    def dphi(self) -> np.ndarray:
        """Tangent rotation from the first estimate, phi - phi[0] (the thesis's Delta phi)."""
        return self.phi - self.phi[0]

    def subset(self, indices: ArrayLike) -> LocalGeometry:
        """The estimates at ``indices`` (positions into this object, not input indices)."""
        idx = np.asarray(indices)
        return LocalGeometry(
            self.index[idx],
            self.position[idx],
            self.s[idx],
            self.phi[idx],
            self.kappa[idx],
            self.kappa_s[idx],
        )


def validate_points(points: ArrayLike, min_points: int) -> np.ndarray:
    """Check ordered planar tactile points and return them as an (n, 2) float array.

    Raises :class:`InvalidCurveData` for a wrong shape, fewer than ``min_points``
    points, non-finite values, repeated points (a step shorter than
    ``REPEATED_POINT_TOL`` times the median step) or unordered points (a step longer than
    ``JUMP_FACTOR`` times the median step, or a reversal of direction between steps).
    """
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2:
        raise InvalidCurveData(f"expected planar points of shape (n, 2), got {p.shape}")
    if p.shape[0] < min_points:
        raise InvalidCurveData(
            f"expected at least {min_points} points for this estimator, got {p.shape[0]}"
        )
    if not np.all(np.isfinite(p)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(p), axis=1))[0])
        raise InvalidCurveData(f"point {bad} is not finite ({p[bad]}); expected finite values")
    steps = np.diff(p, axis=0)
    length = np.hypot(steps[:, 0], steps[:, 1])
    median = np.median(length)
    if not median > 0:
        raise InvalidCurveData("the points are all the same; expected distinct ordered points")
    short = np.flatnonzero(length <= REPEATED_POINT_TOL * median)
    if short.size:
        i = int(short[0])
        raise InvalidCurveData(
            f"points {i} and {i + 1} repeat; expected distinct points ordered along the curve"
        )
    jumps = np.flatnonzero(length > JUMP_FACTOR * median)
    cos_turn = np.einsum("ij,ij->i", steps[:-1], steps[1:]) / (length[:-1] * length[1:])
    reversals = np.flatnonzero(cos_turn < 0.0)
    if jumps.size or reversals.size:
        i = int(np.concatenate([jumps, reversals]).min())
        raise InvalidCurveData(
            f"points are not ordered along the curve near point {i}: expected consecutive "
            f"points about {median:.3g} apart with no backtracking"
        )
    return p


def _central_difference_weights(h0: np.ndarray, h1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Weights of f(s - h0), f(s), f(s + h1) for the first and second derivative at s."""
    first = np.stack([-h1 / (h0 * (h0 + h1)), (h1 - h0) / (h0 * h1), h0 / (h1 * (h0 + h1))])
    second = np.stack([2 / (h0 * (h0 + h1)), -2 / (h0 * h1), 2 / (h1 * (h0 + h1))])
    return first, second


def finite_difference_geometry(points: ArrayLike, phi: ArrayLike | None = None) -> LocalGeometry:
    """kappa and kappa_s by the central differences of thesis Section 3.4.

    ``kappa ~ (phi(s + ds) - phi(s - ds)) / (2 ds)`` and
    ``kappa_s ~ (phi(s + ds) - 2 phi(s) + phi(s - ds)) / ds^2``, in their non-uniform
    three-point form. Arc length is the sum of chords. When ``phi`` (the tangent angle
    at each point, as measured by the rotation of a jaw) is not given, it is taken from
    the central chord ``p[i+1] - p[i-1]``.

    Parameters
    ----------
    points : (n, 2) float
        Ordered points, n >= 5 (n >= 3 with ``phi``).
    phi : (n,) float, optional
        Tangent angle at each point, radians.
    """
    p = validate_points(points, 3 if phi is not None else 5)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
    index = np.arange(p.shape[0])
    if phi is None:
        chord = p[2:] - p[:-2]
        angles = np.arctan2(chord[:, 1], chord[:, 0])
        s, index = s[1:-1], index[1:-1]
    else:
        angles = np.asarray(phi, dtype=float)
        if angles.shape != (p.shape[0],) or not np.all(np.isfinite(angles)):
            raise InvalidCurveData(f"phi must be {p.shape[0]} finite angles, got {angles.shape}")
    angles = np.unwrap(angles)
    h0, h1 = np.diff(s)[:-1], np.diff(s)[1:]
    w1, w2 = _central_difference_weights(h0, h1)
    stencil = np.stack([angles[:-2], angles[1:-1], angles[2:]])
    kappa = np.sum(w1 * stencil, axis=0)
    kappa_s = np.sum(w2 * stencil, axis=0)
    return LocalGeometry(index[1:-1], p[index[1:-1]], s[1:-1] - s[1], angles[1:-1], kappa, kappa_s)


def _fit_windows(
    p: np.ndarray, window: int, degree: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Least-squares polynomial fits v = y(u) over every window in its chord frame.

    Returns origin (m, 2), x axis (m, 2), y axis (m, 2), half chord scale (m,) and the
    coefficients (m, degree + 1) of y in the scaled abscissa u / scale.
    """
    W = sliding_window_view(p, window, axis=0).transpose(0, 2, 1)  # (m, window, 2)
    h = window // 2
    origin = W[:, h]
    chord = W[:, -1] - W[:, 0]
    scale = 0.5 * np.hypot(chord[:, 0], chord[:, 1])
    ex = chord / (2.0 * scale[:, None])
    ey = np.stack([-ex[:, 1], ex[:, 0]], axis=1)
    rel = W - origin[:, None]
    u = np.einsum("mwk,mk->mw", rel, ex) / scale[:, None]
    v = np.einsum("mwk,mk->mw", rel, ey)
    V = u[..., None] ** np.arange(degree + 1)  # (m, window, degree + 1)
    Q, R = np.linalg.qr(V)
    coef = np.linalg.solve(R, np.einsum("mwd,mw->md", Q, v)[..., None])[..., 0]
    return origin, ex, ey, scale, coef


def _simpson_arc_length(
    coef: np.ndarray, scale: np.ndarray, u1: np.ndarray, panels: int = 4
) -> np.ndarray:
    """Arc length of v = y(u) from u = 0 to u1 (unscaled) by composite Simpson's rule."""
    x = np.linspace(0.0, 1.0, 2 * panels + 1)[None, :] * (u1 / scale)[:, None]  # scaled u
    dcoef = coef[:, 1:] * np.arange(1, coef.shape[1])
    slope = (x[..., None] ** np.arange(dcoef.shape[1]) * dcoef[:, None, :]).sum(-1) / scale[:, None]
    f = np.sqrt(1.0 + slope**2)
    w = np.ones(2 * panels + 1)
    w[1:-1:2], w[2:-1:2] = 4.0, 2.0
    return (f * w).sum(axis=1) * (u1 / (6.0 * panels))


def local_fit_geometry(
    points: ArrayLike,
    *,
    window: int = 15,
    degree: int = 3,
    kappa_window: int | None = 15,
    step: int = 1,
) -> LocalGeometry:
    """kappa and kappa_s by local fitting, thesis Section 3.4.2 (generalised).

    Parameters
    ----------
    points : (n, 2) float
        Ordered tactile points along the curve.
    window : int
        Odd number of points of each first-stage fit (the thesis's n).
    degree : int
        Degree of the first-stage polynomial; the thesis uses 2.
    kappa_window : int or None
        Odd number of curvature estimates in each second-stage quadratic fit of
        kappa(s) (the thesis's m). ``None`` takes kappa_s from the first-stage
        polynomial's third derivative instead (needs ``degree >= 3``).
    step : int
        Shift between consecutive first-stage windows (the thesis's l).

    The defaults (cubic first stage over 15 points, quadratic kappa(s) over 15
    estimates) gave the lowest shape-parameter errors over the test curves of
    ``scripts/reproduce_thesis.py`` at 100-200 points per unit length; ``degree=2``
    with ``kappa_window`` is the thesis's estimator.
    """
    if window % 2 == 0 or window < degree + 2:
        raise InvalidCurveData(f"window must be odd and at least degree + 2, got {window}")
    if kappa_window is None and degree < 3:
        raise InvalidCurveData("kappa_window=None needs degree >= 3 to differentiate kappa")
    if kappa_window is not None and (kappa_window % 2 == 0 or kappa_window < 3):
        raise InvalidCurveData(f"kappa_window must be odd and >= 3, got {kappa_window}")
    if step < 1:
        raise InvalidCurveData(f"step must be >= 1, got {step}")
    n_estimates = 1 if kappa_window is None else kappa_window
    p = validate_points(points, window + (n_estimates - 1) * step)

    origin, ex, ey, scale, coef = _fit_windows(p, window, degree)
    origin, ex, ey, scale, coef = (
        origin[::step],
        ex[::step],
        ey[::step],
        scale[::step],
        coef[::step],
    )
    index = np.arange(window // 2, p.shape[0] - window // 2)[::step]

    c = np.zeros((coef.shape[0], 4))
    c[:, : min(4, degree + 1)] = coef[:, :4]
    y0, y1, y2, y3 = c[:, 0], c[:, 1] / scale, 2 * c[:, 2] / scale**2, 6 * c[:, 3] / scale**3
    g = 1.0 + y1**2
    kappa = y2 / g**1.5
    position = origin + y0[:, None] * ey
    phi = np.unwrap(np.arctan2(ex[:, 1], ex[:, 0]) + np.arctan(y1))

    # arc length between consecutive estimates along the earlier window's fit
    u_next = np.einsum("mk,mk->m", position[1:] - origin[:-1], ex[:-1])
    ds = _simpson_arc_length(coef[:-1], scale[:-1], u_next)
    s = np.concatenate([[0.0], np.cumsum(ds)])

    if kappa_window is None:
        kappa_s = (y3 / g**1.5 - 3.0 * y1 * y2**2 / g**2.5) / np.sqrt(g)
        return LocalGeometry(index, position, s, phi, kappa, kappa_s)

    h = kappa_window // 2
    S = sliding_window_view(s, kappa_window)
    K = sliding_window_view(kappa, kappa_window)
    centre = S[:, h : h + 1]
    ds_scale = (S[:, -1] - S[:, 0])[:, None] / 2.0
    x = (S - centre) / ds_scale
    V = x[..., None] ** np.arange(3)
    Q, R = np.linalg.qr(V)
    b = np.linalg.solve(R, np.einsum("mwd,mw->md", Q, K)[..., None])[..., 0]
    kappa_s = b[:, 1] / ds_scale[:, 0]
    sl = slice(h, kappa.size - h)
    return LocalGeometry(index[sl], position[sl], s[sl] - s[h], phi[sl], kappa[sl], kappa_s)
