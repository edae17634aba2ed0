"""Registration of data curves onto a closed-form model, thesis Section 4.2.2.2.

The normal and principal curvatures at p (4.1)-(4.6) select candidate points of the
model's table (4.7); at each, phi is initialised by discretisation, bracketing and
bisection (4.2.2.1), and the best few starts are searched locally over (u, v, phi),
then (optionally) over all six degrees of freedom. The least E (4.11) is the
registration error (4.12). Without an approach direction in the data both orientations
of the normal are tried.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from recognition.least_squares import LeastSquaresStatus
from recognition.rigid import rotation_about
from recognition.surfaces.closed_form.model import ClosedFormModel, candidate_rows
from recognition.surfaces.closed_form.search import (
    levenberg_marquardt,
    refine_rigid_motion,
    steepest_descent,
)
from recognition.surfaces.closed_form.superposition import (
    initial_phi,
    local_coordinates,
    model_frame,
    pose_from_parameters,
)
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.local_geometry import LocalSurfaceGeometry
from recognition.surfaces.registration.config import ClosedFormConfig, Optimizer
from recognition.surfaces.registration.result import (
    ClosedFormRegistration,
    RegistrationMode,
    RegistrationStatus,
    rejected,
)

__all__ = ["register_closed_form"]

Array = NDArray[np.float64]


def _status(status: LeastSquaresStatus) -> RegistrationStatus:
    """A local search that stalled found no step that lowers E: it converged."""
    if status is LeastSquaresStatus.MAX_ITERATIONS:
        return RegistrationStatus.MAX_ITERATIONS
    return RegistrationStatus.CONVERGED


def _register_oriented(
    geometry: LocalSurfaceGeometry,
    points: Array,
    model: ClosedFormModel,
    config: ClosedFormConfig,
    start: float,
) -> ClosedFormRegistration:
    surface = model.surface
    X = local_coordinates(geometry, points)
    radius = float(np.max(np.linalg.norm(X, axis=1)))
    rows = candidate_rows(
        model,
        geometry.k1,
        geometry.k2,
        config.delta,
        config.candidate_separation * radius,
        config.max_candidates,
        surface.symmetries,
    )
    if rows.size == 0:
        out = rejected(surface.name, RegistrationMode.CLOSED_FORM, start, np.zeros((0, 2)))
        assert isinstance(out, ClosedFormRegistration)
        return out
    starts = []
    for row in rows:
        u0, v0 = float(model.u[row]), float(model.v[row])
        phi0, E0 = initial_phi(surface, X, u0, v0, config.phi_samples, config.bisection_steps)
        starts.append((E0, u0, v0, phi0))
    starts.sort(key=lambda start: start[0])
    starts = starts[: config.local_searches]
    searches = []
    for _, u0, v0, phi0 in starts:
        if config.optimizer is Optimizer.LEVENBERG_MARQUARDT:
            s = levenberg_marquardt(
                surface, X, (u0, v0, phi0), config.max_iterations, config.tolerance
            )
        else:
            s = steepest_descent(
                surface, X, (u0, v0, phi0), 20 * config.max_iterations, config.tolerance
            )
        searches.append(s)
    best = min(searches, key=lambda s: s.cost)
    u, v, phi = (float(x) for x in best.solution)
    T = pose_from_parameters(surface, geometry, u, v, phi)
    error, iterations, status = best.cost, best.iterations, _status(best.status)
    if config.rigid_refinement:
        _, F, *_ = model_frame(surface, u, v)
        R0 = F @ rotation_about(2, phi)
        R, c, rigid = refine_rigid_motion(
            surface, X, R0, surface.sigma(u, v), config.max_iterations, config.tolerance
        )
        u_r, v_r = surface.closest_parameters(c, u, v)
        on_patch = np.linalg.norm(surface.sigma(u_r, v_r) - c) <= 0.05 * radius
        if rigid.cost <= error and on_patch:
            u, v = u_r, v_r
            _, F, *_ = model_frame(surface, u, v)
            M = F.T @ R
            phi = float(np.mod(np.arctan2(M[1, 0], M[0, 0]), 2 * np.pi))
            T = np.eye(4)
            T[:3, :3] = R @ geometry.frame.T
            T[:3, 3] = c - T[:3, :3] @ geometry.point
            error = rigid.cost
            iterations, status = iterations + rigid.iterations, _status(rigid.status)
    return ClosedFormRegistration(
        surface.name,
        float(error),
        T,
        surface.sigma(u, v),
        np.array([start[1:3] for start in starts]),
        iterations,
        status,
        time.perf_counter() - start,
        RegistrationMode.CLOSED_FORM,
        u=u,
        v=v,
        phi=phi,
        searches=tuple(searches),
    )


def register_closed_form(
    model: ClosedFormModel,
    curves: DataCurves,
    geometry: LocalSurfaceGeometry,
    config: ClosedFormConfig = ClosedFormConfig(),
) -> ClosedFormRegistration:
    """Register data curves onto a closed-form model, thesis Eq. (4.12) (module docstring).

    ``geometry`` is the data's local geometry at p
    (:func:`~recognition.surfaces.registration.data.data_geometry` with
    ``config.geometry``).
    """
    start = time.perf_counter()
    points = curves.points
    result = _register_oriented(geometry, points, model, config, start)
    if not geometry.oriented:
        other = _register_oriented(geometry.flipped(), points, model, config, start)
        if other.error_m < result.error_m:
            result = replace(other, normal_flipped=True)
    return replace(result, time_s=time.perf_counter() - start)
