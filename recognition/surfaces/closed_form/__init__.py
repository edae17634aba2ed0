"""Closed-form surface models (thesis Section 4.2): surfaces, lookup tables, (4.11), local searches.

Registration onto these models is :func:`recognition.surfaces.registration.register` with
a :class:`~recognition.surfaces.registration.ClosedFormConfig`.
"""

from recognition.surfaces.closed_form.families import (
    circular_cylinder,
    crossed_trough,
    ellipsoid,
    elliptic_cylinder,
    elliptic_paraboloid,
    fig_4_15_solids,
    monkey_saddle,
    sphere,
    table_4_1_surfaces,
)
from recognition.surfaces.closed_form.model import ClosedFormModel, candidate_rows
from recognition.surfaces.closed_form.search import (
    LocalSearch,
    levenberg_marquardt,
    refine_rigid_motion,
    steepest_descent,
)
from recognition.surfaces.closed_form.superposition import (
    initial_phi,
    local_coordinates,
    model_frame,
    point_distance_residuals,
    pose_from_parameters,
    rigid_motion_residuals,
    superposition_error,
    superposition_error_gradient,
    superposition_residuals,
)
from recognition.surfaces.closed_form.surface import (
    EDGE_MARGIN,
    ClosedFormSurface,
    SigmaDerivatives,
    implicit_principal_curvatures,
    principal_curvatures,
)

__all__ = [
    "EDGE_MARGIN",
    "ClosedFormModel",
    "ClosedFormSurface",
    "LocalSearch",
    "SigmaDerivatives",
    "candidate_rows",
    "circular_cylinder",
    "crossed_trough",
    "ellipsoid",
    "elliptic_cylinder",
    "elliptic_paraboloid",
    "fig_4_15_solids",
    "implicit_principal_curvatures",
    "initial_phi",
    "levenberg_marquardt",
    "local_coordinates",
    "model_frame",
    "monkey_saddle",
    "point_distance_residuals",
    "pose_from_parameters",
    "principal_curvatures",
    "refine_rigid_motion",
    "rigid_motion_residuals",
    "sphere",
    "steepest_descent",
    "superposition_error",
    "superposition_error_gradient",
    "superposition_residuals",
    "table_4_1_surfaces",
]
