"""Chapter 3: recognition of planar algebraic curves by differential invariants."""

from recognition.curves import invariants, reduction
from recognition.curves.estimation import (
    EstimateSensitivity,
    LocalGeometry,
    finite_difference_geometry,
    local_fit_geometry,
)
from recognition.curves.families import CanonicalCurve, CurveKind
from recognition.curves.recognition import (
    ClassFit,
    CurveRecognition,
    InputUncertainty,
    recognize_curve,
    recognize_points,
)
from recognition.curves.sampling import (
    SampledCurve,
    random_curve,
    sample_by_arc_length,
)

__all__ = [
    "CanonicalCurve",
    "ClassFit",
    "CurveKind",
    "CurveRecognition",
    "EstimateSensitivity",
    "InputUncertainty",
    "LocalGeometry",
    "SampledCurve",
    "finite_difference_geometry",
    "invariants",
    "local_fit_geometry",
    "random_curve",
    "recognize_curve",
    "recognize_points",
    "reduction",
    "sample_by_arc_length",
]
