"""Chapter 4: surfaces from three data curves: local geometry, models and registration."""

from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.local_geometry import (
    CurveFrame,
    LocalSurfaceGeometry,
    local_surface_geometry,
)

__all__ = [
    "CurveFrame",
    "DataCurves",
    "LocalSurfaceGeometry",
    "local_surface_geometry",
]
