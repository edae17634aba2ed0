"""Model-based recognition of curves and surfaces from tactile data.

Pure geometry (numpy/scipy/trimesh): Chapter 3 of the thesis lives in
:mod:`recognition.curves`, Chapter 4 in :mod:`recognition.surfaces`.

    from recognition import DataCurves, ModelDatabase, Recognition

A recognition keeps the (model, pose) hypotheses that fit near the best with their
posterior (``Recognition.belief``, ``.hypotheses``, ``.confidence``); ``verify`` touches
where they disagree until the answer is sure (``TouchLimits``, ``ModelDatabase.plan_touch``).

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
from recognition.surfaces.active_touch import Contact, NoReading, TouchStep, Verification, verify
from recognition.surfaces.belief import Belief, BeliefConfig
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.database import DATABASE_FORMAT, ModelDatabase
from recognition.surfaces.hypothesis import Hypothesis
from recognition.surfaces.mesh_model import MeshModelConfig
from recognition.surfaces.noise_model import NoiseModel
from recognition.surfaces.registration import (
    ClosedFormConfig,
    FastConfig,
    IcpConfig,
    Recognition,
    RegistrationConfig,
    ThesisConfig,
    config_for,
)
from recognition.surfaces.touch_planning import TouchLimits, TouchPlan

__all__ = [
    "DATABASE_FORMAT",
    "Belief",
    "BeliefConfig",
    "ClosedFormConfig",
    "Contact",
    "DataCurves",
    "DegenerateGeometry",
    "FastConfig",
    "Hypothesis",
    "IcpConfig",
    "InvalidArgument",
    "InvalidCurveData",
    "InvalidModel",
    "MeshModelConfig",
    "ModelDatabase",
    "NoReading",
    "NoRealSolution",
    "NoiseModel",
    "Recognition",
    "RecognitionError",
    "RegistrationConfig",
    "ThesisConfig",
    "TouchLimits",
    "TouchPlan",
    "TouchStep",
    "Verification",
    "config_for",
    "verify",
]
