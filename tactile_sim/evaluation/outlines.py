"""Outline traces of the extruded planar solids (thesis Section 3.4.2: Table 3.4, Fig. 3.8).

:func:`trace_outlines` traces an extruded outline (the ellipse of Table 3.4, the closed
cubic spline of Fig. 3.8) in a horizontal plane (:func:`trace_contour`) and measures the
sensed points against the true outline.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tactile_sim.collision import closed_spline_outline, ellipse_outline, load_solid
from tactile_sim.errors import UnknownObject
from tactile_sim.evaluation.sessions import session_seed
from tactile_sim.probing import ProbingConfig, random_pose, trace_contour
from tactile_sim.sensor import SensorConfig

__all__ = [
    "OutlineTrace",
    "OutlineTraces",
    "TraceConfig",
    "outline_distance",
    "spline_segment_bearings",
    "trace_outlines",
]


@dataclass(frozen=True)
class TraceConfig:
    """Outline traces of an extruded solid in a horizontal plane (thesis Section 3.4.2).

    Attributes
    ----------
    object_name : str
        ``"planar_ellipse"`` (Table 3.4) or ``"planar_spline"`` (Fig. 3.8).
    trials : int
        Independent experiments.
    arcs_per_trial : int
        Arcs traced per experiment (thesis: two parts of the ellipse).
    arc_length_m : float, metres
        Length of each arc (the trace walks ``arc_length_m / spacing_m`` steps).
    spacing_m : float, metres
        Distance between neighbouring points.
    start_angles_rad : tuple of float or None, radians
        Bearing of every arc's first point from the object's axis, in the object frame
        (one per arc of a trial, reused by every trial); None draws them.
    probing : ProbingConfig
    sensor : SensorConfig
    seed : int
        Arc ``j`` of trial ``i`` is traced with :func:`session_seed` (seed, "trial i", j):
        the object's pose, the start bearing (when drawn) and the noise.
    """

    object_name: str = "planar_ellipse"
    trials: int = 10
    arcs_per_trial: int = 2
    arc_length_m: float = 0.06
    spacing_m: float = 0.5e-3
    start_angles_rad: tuple[float, ...] | None = None
    probing: ProbingConfig = field(default_factory=ProbingConfig)
    sensor: SensorConfig = field(default_factory=SensorConfig)
    seed: int = 0

    def __post_init__(self) -> None:
        if self.object_name not in ("planar_ellipse", "planar_spline"):
            raise UnknownObject(self.object_name, ("planar_ellipse", "planar_spline"))
        if self.trials < 1 or self.arcs_per_trial < 1:
            raise ValueError("trials and arcs_per_trial must be at least 1")
        if not 0 < self.spacing_m < self.arc_length_m:
            raise ValueError("spacing_m must be positive and shorter than arc_length_m")
        if self.start_angles_rad is not None and len(self.start_angles_rad) != self.arcs_per_trial:
            raise ValueError("start_angles_rad needs one bearing per arc of a trial")

    @property
    def n_points(self) -> int:
        """Returns the points per arc."""
        return round(self.arc_length_m / self.spacing_m) + 1


@dataclass(frozen=True)
class OutlineTrace:
    """One traced arc.

    Attributes
    ----------
    seed : int
    points_in_world : (n, 2) float, metres
        The sensed outline points (x, y) in the world frame, as the robot reports them.
    points_in_object : (n, 2) float, metres
        The same in the object frame (ground truth pose applied; evaluation only).
    distance_to_outline_m : (n,) float, metres
        In-plane distance of every sensed point to the true outline.
    outline_parameter : (n,) float
        Where on the outline each sensed point lies (its nearest outline point): the
        ellipse's angle t in [0, 2 pi) of (a cos t, b sin t); for the closed spline,
        segment index plus the segment's parameter t in [0, 1) (Eq. (3.25)).
    height_span_m : float, metres
        Spread of the sensed points' heights (the plane is horizontal).
    wall_seconds : float, seconds
    truncated : str
        Why the trace stopped early ("" when complete).
    """

    seed: int
    points_in_world: NDArray[np.float64]
    points_in_object: NDArray[np.float64]
    distance_to_outline_m: NDArray[np.float64]
    outline_parameter: NDArray[np.float64]
    height_span_m: float
    wall_seconds: float
    truncated: str = ""


@dataclass(frozen=True)
class OutlineTraces:
    """Every trial's traced arcs and the outline they came from.

    Attributes
    ----------
    config : TraceConfig
    trials : tuple of tuple of OutlineTrace
        ``trials[i][j]``: arc j of trial i.
    parameters : dict
        The solid's closed-form parameters in metres (``semi_axes_m``, or
        ``spline_coefficients_m`` (k, 2, 4) with ``knots_m``), object frame.
    """

    config: TraceConfig
    trials: tuple[tuple[OutlineTrace, ...], ...]
    parameters: dict

    def arcs_in_world(self) -> list[list[NDArray[np.float64]]]:
        """Returns the sensed points per trial and arc, (n, 2) metres, world frame."""
        return [[arc.points_in_world for arc in trial] for trial in self.trials]

    def accuracy(self) -> dict[str, float]:
        """Returns the sensed points' in-plane distance to the true outline, in mm."""
        d = np.concatenate([arc.distance_to_outline_m for t in self.trials for arc in t])
        return {
            "points": int(d.size),
            "distance_to_outline_mean_mm": float(d.mean() * 1e3),
            "distance_to_outline_p95_mm": float(np.percentile(d, 95) * 1e3),
            "distance_to_outline_max_mm": float(d.max() * 1e3),
            "height_span_max_mm": float(
                max(arc.height_span_m for t in self.trials for arc in t) * 1e3
            ),
            "wall_seconds": float(sum(arc.wall_seconds for t in self.trials for arc in t)),
        }


_ELLIPSE_SAMPLES = 200_000
_SPLINE_SAMPLES_PER_SEGMENT = 40_000


def _dense_outline(
    object_name: str, parameters: Mapping[str, Any]
) -> tuple[np.ndarray, np.ndarray]:
    """The true outline, object frame, densely enough that the nearest vertex gives the
    distance to within a micrometre: (m, 2) metres, and each vertex's outline parameter
    (see :attr:`OutlineTrace.outline_parameter`), (m,)."""
    if object_name == "planar_ellipse":
        a, b = parameters["semi_axes_m"]
        outline = ellipse_outline(a, b, n_segments=_ELLIPSE_SAMPLES)
        return outline, np.arange(len(outline)) * (2 * math.pi / _ELLIPSE_SAMPLES)
    outline = closed_spline_outline(
        parameters["knots_m"], samples_per_segment=_SPLINE_SAMPLES_PER_SEGMENT
    )
    return outline, np.arange(len(outline)) / _SPLINE_SAMPLES_PER_SEGMENT


def outline_distance(
    points: NDArray[np.float64], outline: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Returns the distance of points (n, 2) to a dense closed outline (m, 2), metres, and
    the index of each point's nearest outline vertex."""
    from scipy.spatial import cKDTree

    distance, index = cKDTree(outline).query(np.asarray(points)[:, :2])
    return distance, index


def spline_segment_bearings(margin_m: float = 3e-3) -> tuple[tuple[float, float], ...]:
    """Returns, per segment of the closed spline, the bearing (object frame, radians) of a
    point ``margin_m`` before its first knot and the arc length to trace from there to
    ``margin_m`` past its last knot, metres (a trace over one segment, with room for the
    local fits at its ends)."""
    parameters = load_solid("planar_spline").parameters
    outline, parameter = _dense_outline("planar_spline", parameters)
    steps = np.linalg.norm(np.diff(outline, axis=0, append=outline[:1]), axis=1)
    s = np.concatenate([[0.0], np.cumsum(steps)])[:-1]
    perimeter = float(steps.sum())
    out = []
    for k in range(len(parameters["knots_m"])):
        start = s[int(np.searchsorted(parameter, k))]
        end = (
            s[int(np.searchsorted(parameter, k + 1))]
            if k + 1 < len(parameters["knots_m"])
            else perimeter
        )
        begin = (start - margin_m) % perimeter
        x, y = outline[int(np.searchsorted(s, begin)) % len(outline)]
        out.append((math.atan2(float(y), float(x)), float(end - start + 2 * margin_m)))
    return tuple(out)


def trace_outlines(config: TraceConfig = TraceConfig(), *, progress: bool = False) -> OutlineTraces:
    """Traces ``config.trials`` x ``config.arcs_per_trial`` arcs of an extruded outline.

    Every arc is one :func:`trace_contour` run (its own scene, pose and noise), half way
    up the prism, counter-clockwise seen from above.

    Raises
    ------
    SimulationError
        A trace failed (no wall found, unstable simulation).
    """
    solid = load_solid(config.object_name)
    parameters = dict(solid.parameters)
    outline, outline_parameter = _dense_outline(config.object_name, parameters)
    trials = []
    for i in range(config.trials):
        arcs = []
        for j in range(config.arcs_per_trial):
            seed = session_seed(config.seed, f"trial {i}", j)
            rng = np.random.default_rng([seed, 1])
            bearing = (
                config.start_angles_rad[j]
                if config.start_angles_rad is not None
                else rng.uniform(-math.pi, math.pi)
            )
            T = random_pose(rng)
            yaw = math.atan2(T[1, 0], T[0, 0])
            trace = trace_contour(
                solid,
                seed=seed,
                n_points=config.n_points,
                spacing_m=config.spacing_m,
                start_angle_rad=bearing + yaw,
                T_world_from_object=T,
                config=config.probing,
                sensor=config.sensor,
                progress=progress,
            )
            in_object = trace.points_in_object
            distance, nearest = outline_distance(in_object, outline)
            side = trace.sweep.sides[0]
            arcs.append(
                OutlineTrace(
                    seed=seed,
                    points_in_world=trace.points_in_world[:, :2].copy(),
                    points_in_object=in_object[:, :2].copy(),
                    distance_to_outline_m=distance,
                    outline_parameter=outline_parameter[nearest],
                    height_span_m=float(np.ptp(trace.points_in_world[:, 2])),
                    wall_seconds=trace.wall_seconds,
                    truncated=side.message,
                )
            )
        trials.append(tuple(arcs))
    return OutlineTraces(config, tuple(trials), parameters)
