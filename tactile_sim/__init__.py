"""MuJoCo simulation of a SCARA robot probing objects with a compliant joystick sensor.

Importing the package loads neither MuJoCo nor dm_control; the submodules that need
them import them. :mod:`tactile_sim.objects` holds the catalog of the thesis's ten
free-form objects, :mod:`tactile_sim.collision` their convex collision parts and the
closed-form solids; :mod:`tactile_sim.scene`, :mod:`tactile_sim.kinematics` and
:mod:`tactile_sim.sensor` the robot, its probe and what the probe measures;
:mod:`tactile_sim.probing` the probing sessions, :mod:`tactile_sim.recording` their rerun
recordings. Every exception is in :mod:`tactile_sim.errors`.
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
    UnusableCurves,
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
    "UnusableCurves",
    "WorkspaceLimit",
]
