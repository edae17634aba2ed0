"""MuJoCo simulation of a SCARA robot probing objects with a compliant joystick sensor.

Importing the package loads neither MuJoCo nor dm_control; the submodules that need
them import them. :mod:`tactile_sim.objects` holds the catalog of the thesis's ten
free-form objects.
"""

from tactile_sim.errors import (
    AssetError,
    InvalidMesh,
    InvalidRecording,
    PortInUse,
    RecordingError,
    SimulationError,
    SimulationUnstable,
    SweepTruncated,
    UnknownObject,
    UnreachablePoint,
    WorkspaceLimit,
)

__all__ = [
    "AssetError",
    "InvalidMesh",
    "InvalidRecording",
    "PortInUse",
    "RecordingError",
    "SimulationError",
    "SimulationUnstable",
    "SweepTruncated",
    "UnknownObject",
    "UnreachablePoint",
    "WorkspaceLimit",
]
