"""Model-based recognition of curves and surfaces from tactile data.

Pure geometry (numpy/scipy/trimesh): Chapter 3 of the thesis lives in
:mod:`recognition.curves`, Chapter 4 in :mod:`recognition.surfaces`.

    from recognition import DataCurves, ModelDatabase, Recognition
"""

from recognition.errors import (
    DegenerateGeometry,
    InvalidCurveData,
    InvalidModel,
    NoRealSolution,
    RecognitionError,
)
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.database import ModelDatabase, Recognition

__all__ = [
    "DataCurves",
    "DegenerateGeometry",
    "InvalidCurveData",
    "InvalidModel",
    "ModelDatabase",
    "NoRealSolution",
    "Recognition",
    "RecognitionError",
]
