"""Model-based recognition of curves and surfaces from tactile data.

Pure geometry (numpy/scipy/trimesh): Chapter 3 of the thesis lives in
:mod:`recognition.curves`, Chapter 4 in :mod:`recognition.surfaces`.

    from recognition import DataCurves, ModelDatabase, Recognition

The registration settings are one frozen config per mode (``FastConfig``,
``ThesisConfig``, ``IcpConfig``, ``ClosedFormConfig``; ``config_for(mode, **fields)``).
"""

from recognition.errors import (
    DegenerateGeometry,
    InvalidArgument,
    InvalidCurveData,
    InvalidModel,
    NoRealSolution,
    RecognitionError,
)
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.database import DATABASE_FORMAT, ModelDatabase
from recognition.surfaces.mesh_model import MeshModelConfig
from recognition.surfaces.registration import (
    ClosedFormConfig,
    FastConfig,
    IcpConfig,
    Recognition,
    RegistrationConfig,
    ThesisConfig,
    config_for,
)

__all__ = [
    "DATABASE_FORMAT",
    "ClosedFormConfig",
    "DataCurves",
    "DegenerateGeometry",
    "FastConfig",
    "IcpConfig",
    "InvalidArgument",
    "InvalidCurveData",
    "InvalidModel",
    "MeshModelConfig",
    "ModelDatabase",
    "NoRealSolution",
    "Recognition",
    "RecognitionError",
    "RegistrationConfig",
    "ThesisConfig",
    "config_for",
]
