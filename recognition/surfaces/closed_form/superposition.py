"""The superposition error E(u, v, phi) of data curves on a closed-form model, thesis Eq. (4.11).

Registration (thesis Section 4.2.2) places the data's common point p on sigma(u, v),
aligns the data normal with the model normal there and turns the curves by phi about it;
E is the mean first-order distance f / |grad f| of the moved points to the surface.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.errors import DegenerateGeometry
from recognition.rigid import cross, rotation_about, rotation_about_derivative, skew
from recognition.surfaces.closed_form.surface import ClosedFormSurface, _given, outward_normal
from recognition.surfaces.local_geometry import LocalSurfaceGeometry

__all__ = [
    "initial_phi",
    "local_coordinates",
    "model_frame",
    "point_distance_residuals",
    "pose_from_parameters",
    "rigid_motion_residuals",
    "superposition_error",
    "superposition_error_gradient",
    "superposition_residuals",
]

Array = NDArray[np.float64]


def _rz(phi: ArrayLike) -> tuple[Array, Array]:
    """Rotations about z by phi and their derivatives, (..., 3, 3) each."""
    return rotation_about(2, phi), rotation_about_derivative(2, phi)


def _normalised(w: Array, w_u: Array, w_v: Array) -> tuple[Array, Array, Array]:
    """w / |w| and its derivatives given those of w (vectors along the last axis)."""
    norm = np.linalg.norm(w)
    e = w / norm
    return e, (w_u - e * (e @ w_u)) / norm, (w_v - e * (e @ w_v)) / norm


def model_frame(
    surface: ClosedFormSurface, u: float, v: float
) -> tuple[Array, Array, Array, Array, Array, Array]:
    """The model's local frame (d1, d2, n) at sigma(u, v) and its parameter derivatives.

    d1 = sigma_u / |sigma_u|, n the outward normal (4.10), d2 = n x d1, so that
    d1 x d2 = n (thesis Section 4.2.2).

    Returns
    -------
    point : (3,) float
        sigma(u, v).
    F, F_u, F_v : (3, 3) float
        Columns (d1, d2, n) and their derivatives with respect to u and v.
    s_u, s_v : (3,) float
        sigma_u, sigma_v.
    """
    d = surface.sigma_derivatives(float(u), float(v))
    w = cross(d.su, d.sv)
    if not np.linalg.norm(w) > 0 or not np.linalg.norm(d.su) > 0:
        raise DegenerateGeometry(f"{surface.name}: singular parameter point ({u:g}, {v:g})")
    sign = float(outward_normal(surface, d, w)[1][0])
    n, n_u, n_v = _normalised(
        sign * w,
        sign * (cross(d.suu, d.sv) + cross(d.su, d.suv)),
        sign * (cross(d.suv, d.sv) + cross(d.su, d.svv)),
    )
    d1, d1_u, d1_v = _normalised(d.su, d.suu, d.suv)
    d2 = cross(n, d1)
    d2_u = cross(n_u, d1) + cross(n, d1_u)
    d2_v = cross(n_v, d1) + cross(n, d1_v)
    F = np.column_stack([d1, d2, n])
    F_u = np.column_stack([d1_u, d2_u, n_u])
    F_v = np.column_stack([d1_v, d2_v, n_v])
    return d.point, F, F_u, F_v, d.su, d.sv


def local_coordinates(geometry: LocalSurfaceGeometry, points: ArrayLike) -> Array:
    """Data points in the local frame (t1, t2, N) at p, thesis Section 4.2.2.

    Returns
    -------
    (n, 3) float
        ``(t1 t2 N)^T (x_i - p)`` with (t1, t2, N) = (d1, d2, N) of ``geometry``.
    """
    return (np.asarray(points, float) - geometry.point) @ geometry.frame


def pose_from_parameters(
    surface: ClosedFormSurface, geometry: LocalSurfaceGeometry, u: float, v: float, phi: float
) -> Array:
    """T_model_from_data (4, 4) that puts p on sigma(u, v) turned by phi (Section 4.2.2)."""
    q, F, *_ = model_frame(surface, u, v)
    R = F @ _rz(phi)[0] @ geometry.frame.T
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = q - R @ geometry.point
    return T


def point_distance_residuals(surface: ClosedFormSurface, points: Array) -> tuple[Array, Array]:
    """First-order signed distances f / |grad f| (4.11) and their gradients.

    Returns
    -------
    r : (n,) float
        Signed distance estimates, model units (positive outside).
    dr : (n, 3) float
        d r / d point = grad f / |grad f| - f H grad f / |grad f|^3.
    """
    f, g_, H_ = surface.implicit_terms(points, 2)
    g, H = _given(g_), _given(H_)
    norm = np.linalg.norm(g, axis=1)
    norm = np.maximum(norm, 1e-300)
    r = f / norm
    Hg = (H @ g[:, :, None])[:, :, 0]
    dr = g / norm[:, None] - (f / norm**3)[:, None] * Hg
    return r, dr


def superposition_residuals(
    surface: ClosedFormSurface, local_points: Array, u: float, v: float, phi: float
) -> tuple[Array, Array]:
    """Residuals f / |grad f| of the transformed data points and their Jacobian.

    Parameters
    ----------
    surface : ClosedFormSurface
    local_points : (n, 3) float
        Data points in the local frame at p (:func:`local_coordinates`).
    u, v, phi : float
        Location of p on the model and the turn about the normal, radians for phi.

    Returns
    -------
    r : (n,) float
        Signed first-order distances of the points x''_i to the surface.
    J : (n, 3) float
        d r / d (u, v, phi).
    """
    q, F, F_u, F_v, s_u, s_v = model_frame(surface, u, v)
    Rz, dRz = _rz(float(phi))
    a = local_points @ Rz.T
    y = a @ F.T + q
    r, dr = point_distance_residuals(surface, y)
    dy_du = a @ F_u.T + s_u
    dy_dv = a @ F_v.T + s_v
    dy_dphi = local_points @ (F @ dRz).T
    J = np.column_stack([np.sum(dr * dy_du, 1), np.sum(dr * dy_dv, 1), np.sum(dr * dy_dphi, 1)])
    return r, J


def _phi_terms(
    surface: ClosedFormSurface, local_points: Array, u: float, v: float
) -> Callable[[ArrayLike], tuple[Array, Array]]:
    """``phi (m,) -> (E (m,), E_phi (m,))`` at a fixed (u, v), Eq. (4.11)."""
    q, F, *_ = model_frame(surface, u, v)
    n = local_points.shape[0]

    def terms(phi: ArrayLike) -> tuple[Array, Array]:
        phi = np.atleast_1d(np.asarray(phi, float))
        Rz, dRz = _rz(phi)  # (m, 3, 3)
        FR = F @ Rz
        y = local_points @ FR.transpose(0, 2, 1) + q
        dy = local_points @ (F @ dRz).transpose(0, 2, 1)
        r, dr = point_distance_residuals(surface, y.reshape(-1, 3))
        r = r.reshape(phi.size, n)
        slope = np.sum(dr.reshape(phi.size, n, 3) * dy, axis=2)
        return np.abs(r).mean(axis=1), np.sum(np.sign(r) * slope, axis=1) / n

    return terms


def superposition_error(
    surface: ClosedFormSurface, local_points: Array, u: float, v: float, phi: ArrayLike
) -> float | Array:
    """Superposition error E(u, v, phi), thesis Eq. (4.11).

    ``local_points`` (n, 3) are the data points in the local frame at p
    (:func:`local_coordinates`), model units; ``phi`` (radians) may be an array: E
    (model units) is then evaluated for every angle, same shape.
    """
    phi_arr = np.asarray(phi, float)
    E = _phi_terms(surface, local_points, u, v)(phi_arr.reshape(-1))[0]
    return float(E[0]) if phi_arr.ndim == 0 else E.reshape(phi_arr.shape)


def superposition_error_gradient(
    surface: ClosedFormSurface, local_points: Array, u: float, v: float, phi: float
) -> tuple[float, Array]:
    """E (4.11) and its gradient (E_u, E_v, E_phi) (Section 4.2.2.1).

    Returns
    -------
    E : float
    gradient : (3,) float
        Where a residual is exactly zero its |.| contributes 0 (a subgradient).
    """
    r, J = superposition_residuals(surface, local_points, u, v, phi)
    return float(np.abs(r).mean()), np.sign(r) @ J / r.size


def initial_phi(
    surface: ClosedFormSurface,
    local_points: Array,
    u: float,
    v: float,
    samples: int = 72,
    bisection_steps: int = 24,
) -> tuple[float, float]:
    """phi minimising E(u, v, .) (4.11) by discretisation, bracketing and bisection, thesis
    Section 4.2.2.1.

    [0, 2 pi) is sampled at ``samples`` angles; every discrete local minimum brackets a
    minimum between its neighbours, in which the sign change of E_phi is bisected (all
    brackets at once). The best of these minima is returned.

    Returns
    -------
    phi : float
        Radians in [0, 2 pi).
    E : float
        E(u, v, phi).
    """
    terms = _phi_terms(surface, local_points, u, v)
    step = 2 * np.pi / samples
    grid = step * np.arange(samples)
    E, _ = terms(grid)
    minima = np.flatnonzero((E <= np.roll(E, 1)) & (E <= np.roll(E, -1)))
    lo, hi = grid[minima] - step, grid[minima] + step
    for _ in range(bisection_steps):
        mid = 0.5 * (lo + hi)
        down = terms(mid)[1] < 0
        lo, hi = np.where(down, mid, lo), np.where(down, hi, mid)
    phi = np.concatenate([grid[minima], 0.5 * (lo + hi)])
    E_phi, _ = terms(phi)
    best = int(np.argmin(E_phi))
    return float(np.mod(phi[best], 2 * np.pi)), float(E_phi[best])


def rigid_motion_residuals(
    surface: ClosedFormSurface, local_points: Array, R: ArrayLike, c: Array
) -> tuple[Array, Array]:
    """Residuals f / |grad f| of the points ``R x_i + c`` and their Jacobian.

    Parameters
    ----------
    local_points : (n, 3) float
        Data points in the local frame at p.
    R : (3, 3) float
        Rotation from the local frame to the model frame.
    c : (3,) float
        Where p lands, model frame.

    Returns
    -------
    r : (n,) float
    J : (n, 6) float
        d r / d (omega, dc) for the update ``R <- exp([omega]x) R``, ``c <- c + dc``.
    """
    a = local_points @ np.asarray(R, float).T
    r, dr = point_distance_residuals(surface, a + c)
    return r, np.concatenate([np.einsum("ni,nij->nj", dr, -skew(a)), dr], axis=1)
