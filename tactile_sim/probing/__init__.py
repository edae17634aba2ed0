"""Probing objects with the simulated robot: sessions of three sweeps, and outline traces.

``probe_object("cat", seed=0) -> ProbeSession`` places the object on the table
(:mod:`~tactile_sim.probing.placement`), compiles the scene
(:mod:`~tactile_sim.probing.probe_scene`), plans three sampling planes through a point p
(:mod:`~tactile_sim.probing.plan`) and drives the rig (:mod:`~tactile_sim.probing.rig`)
through one sweep along each (:mod:`~tactile_sim.probing.sweep`); the session
(:mod:`~tactile_sim.probing.session`) holds the three data curves, and the ground truth
apart. :func:`trace_contour` (:mod:`~tactile_sim.probing.contour`) traces an outline in a
horizontal plane instead. The controller's parameters are one :class:`ProbingConfig`
(:mod:`~tactile_sim.probing.config`).
"""

from tactile_sim.errors import SweepTruncated
from tactile_sim.probing.config import ProbingConfig
from tactile_sim.probing.contour import ContourTrace, trace_contour
from tactile_sim.probing.placement import (
    PlacementConfig,
    ProbeTarget,
    displaced_target,
    mesh_target,
    random_pose,
    resolve_object,
    resting_pose,
    table_pose,
)
from tactile_sim.probing.plan import SamplingPlane, choose_point, sampling_planes
from tactile_sim.probing.probe_scene import ProbeScene, build_probe_scene
from tactile_sim.probing.session import (
    MAX_CURVE_LENGTH_M,
    MAX_SPACING_M,
    MIN_CURVE_POINTS,
    PLANE_ANGLE_RANGE_DEG,
    GroundTruth,
    ProbeSession,
    check_sweep,
    probe_object,
)
from tactile_sim.probing.sweep import StopReason, SweepResult, SweepSide

__all__ = [
    "MAX_CURVE_LENGTH_M",
    "MAX_SPACING_M",
    "MIN_CURVE_POINTS",
    "PLANE_ANGLE_RANGE_DEG",
    "ContourTrace",
    "GroundTruth",
    "PlacementConfig",
    "ProbeScene",
    "ProbeSession",
    "ProbeTarget",
    "ProbingConfig",
    "SamplingPlane",
    "StopReason",
    "SweepResult",
    "SweepSide",
    "SweepTruncated",
    "build_probe_scene",
    "check_sweep",
    "choose_point",
    "displaced_target",
    "mesh_target",
    "probe_object",
    "random_pose",
    "resolve_object",
    "resting_pose",
    "sampling_planes",
    "table_pose",
    "trace_contour",
]
