"""Model-based recognition of curves and surfaces from tactile data.

Pure geometry (numpy/scipy): Chapter 3 of the thesis lives in
:mod:`recognition.curves`.
"""

from recognition.errors import (
    DegenerateGeometry,
    InvalidCurveData,
    NoRealSolution,
    RecognitionError,
)

__all__ = [
    "DegenerateGeometry",
    "InvalidCurveData",
    "NoRealSolution",
    "RecognitionError",
]
