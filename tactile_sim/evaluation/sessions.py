"""The thesis's robot experiments on the simulated robot (Sections 3.4.2 and 4.4).

:class:`SimulatedSource` makes recognition-benchmark instances by probing an object with
the simulated Cobra 600 (three sweeps through one point, :func:`probe_object`): each
instance is regenerated from its seed alone, so any worker of
:func:`recognition.benchmark.run` can make it. Its specs and instances have the fields
that ``recognition.benchmark`` reads (:class:`SessionSpec`, :class:`ProbedInstance`), so
that tactile_sim imports nothing of ``recognition`` but ``DataCurves``.
:func:`catalog_experiment` is the Table 4.6 / 4.7 setting (the ten catalog objects,
3 x 21 points at 1.2 mm, planes 60 degrees apart), :func:`solids_experiment` the Table
4.5 one (the four solids of Fig. 4.15, n = 41, d = 0.05 mm).

:func:`trace_outlines` traces an extruded outline (the ellipse of Table 3.4, the closed
cubic spline of Fig. 3.8) in a horizontal plane (:func:`trace_contour`) and measures the
sensed points against the true outline.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from recognition.surfaces import DataCurves
from tactile_sim.collision import closed_spline_outline, ellipse_outline, load_solid, solid_names
from tactile_sim.errors import SimulationError, UnknownObject
from tactile_sim.objects import object_names
from tactile_sim.probing import ProbingConfig, probe_object, random_pose, trace_contour
from tactile_sim.sensor import SensorConfig

__all__ = [
    "FIG_4_15_SOLIDS",
    "OutlineTrace",
    "OutlineTraces",
    "ProbedInstance",
    "SessionSpec",
    "SimulatedSource",
    "TraceConfig",
    "catalog_experiment",
    "outline_distance",
    "session_seed",
    "solids_experiment",
    "spline_segment_bearings",
    "trace_outlines",
]

#: The four algebraic objects of thesis Fig. 4.15 (the Table 4.5 columns).
FIG_4_15_SOLIDS = ("cylinder_1", "cylinder_2", "elliptic_cylinder", "sphere")

_CURVES = ("sensed", "true_contacts")


def session_seed(base_seed: int, name: str, index: int) -> int:
    """Returns the seed of session ``index`` of object ``name``: a hash of the three."""
    digest = hashlib.sha256(repr(("session", base_seed, name, index)).encode()).digest()
    return int.from_bytes(digest[:4], "little") >> 1


@dataclass(frozen=True)
class SessionSpec:
    """One probing session of a benchmark (a ``recognition.benchmark.InstanceSpec``).

    Attributes
    ----------
    model : str
        The probed object's name.
    index : int
        Session number of this object.
    vertex : None
        Sessions choose their point p themselves.
    seed : int
        The session's seed (:func:`session_seed`).
    """

    model: str
    index: int
    vertex: None
    seed: int

    @property
    def key(self) -> str:
        return f"{self.model}/{self.index}"


@dataclass(frozen=True)
class ProbedInstance:
    """A probing session as a benchmark instance (a ``recognition.benchmark.Instance``).

    Attributes
    ----------
    curves : DataCurves or None
        The data curves (world frame), None when the session failed.
    point_in_model : (3,) float or None, metres
        The true p, object frame.
    info : dict
        JSON-ready facts of the session (``error`` when it failed).
    reference_curves : DataCurves or None
        The other point set of the session (true contact points or sensed points).
    """

    curves: DataCurves | None
    point_in_model: NDArray[np.float64] | None = None
    info: dict = field(default_factory=dict)
    reference_curves: DataCurves | None = None


@dataclass(frozen=True)
class SimulatedSource:
    """Benchmark instances probed by the simulated robot (thesis Section 4.4.1).

    Instance ``k`` of object ``name`` is one :func:`probe_object` session with the seed
    :func:`session_seed` (seed, name, k): that seed draws the object's pose on the table,
    the point p, the first plane's yaw and the sensor noise.

    Attributes
    ----------
    objects : tuple of str
        Catalog or solid names.
    sessions_per_object : int
        Sessions (instances) per object.
    n_points : int
        Points per curve, p included (thesis: 21 on the free-form objects, 41 on the
        solids).
    spacing_m : float, metres
        Distance between neighbouring points (thesis: 1.2 mm; 0.05 mm on the solids).
    plane_angle_deg : float, degrees
        Angle between neighbouring sampling planes (thesis: 60).
    curves : {"sensed", "true_contacts"}
        What an instance's data curves are: the sensed points (the experiment), or the
        simulator's true contact points of the same session (no sensor error: a
        diagnosis). The other one is the instance's reference.
    probing : ProbingConfig
        Sweep controller.
    sensor : SensorConfig
        Sensor model (noise).
    seed : int
    """

    objects: tuple[str, ...] = field(default_factory=object_names)
    sessions_per_object: int = 3
    n_points: int = 21
    spacing_m: float = 1.2e-3
    plane_angle_deg: float = 60.0
    curves: str = "sensed"
    probing: ProbingConfig = field(default_factory=ProbingConfig)
    sensor: SensorConfig = field(default_factory=SensorConfig)
    seed: int = 0

    def __post_init__(self) -> None:
        known = (*object_names(), *solid_names())
        for name in self.objects:
            if name not in known:
                raise UnknownObject(name, known)
        if self.curves not in _CURVES:
            raise ValueError(f"curves must be one of {_CURVES}, got {self.curves!r}")
        if self.sessions_per_object < 1:
            raise ValueError(f"sessions_per_object must be >= 1, got {self.sessions_per_object}")

    def specs(self, database=None) -> list[SessionSpec]:
        """Returns the instance specs: ``sessions_per_object`` per object, in order.

        ``database`` is not used: the objects are probed wherever the seed puts p.
        """
        return [
            SessionSpec(name, k, None, session_seed(self.seed, name, k))
            for name in self.objects
            for k in range(self.sessions_per_object)
        ]

    def instance(self, database, spec: SessionSpec) -> ProbedInstance:
        """Probes the spec's object with the spec's seed; returns a benchmark instance.

        The instance's ``info`` holds the session's facts: probing wall and simulated
        time, points per curve, truncated sweep sides, the sensed points' distance to
        the true contact points (mean and max, mm) and their spacing. A session that
        fails (a sweep left with too few points, an unreachable point, an unstable
        simulation) gives an instance without curves whose ``info["error"]`` says why.
        """
        try:
            session = probe_object(
                spec.model,
                seed=spec.seed,
                n_points=self.n_points,
                spacing_m=self.spacing_m,
                plane_angle_deg=self.plane_angle_deg,
                config=self.probing,
                sensor=self.sensor,
                progress=False,
            )
        except UnknownObject:
            raise
        except SimulationError as exc:
            return ProbedInstance(None, None, {"error": f"{type(exc).__name__}: {exc}"})
        truth = session.ground_truth
        true_curves = DataCurves(
            curves=truth.true_contact_points_in_world, approach=session.curves.approach
        )
        sensed_error = np.concatenate(
            [
                np.linalg.norm(s.points_in_world - s.true_contact_points_in_world, axis=1)
                for s in session.sweeps
            ]
        )
        steps = np.concatenate(
            [np.linalg.norm(np.diff(s.points_in_world, axis=0), axis=1) for s in session.sweeps]
        )
        info = {
            "curves": self.curves,
            "points_per_curve": [len(c) for c in session.curves.curves],
            "truncated": list(session.messages),
            "probe_time_s": session.wall_seconds,
            "sim_time_s": session.sim_seconds,
            "sensed_error_mean_mm": float(sensed_error.mean() * 1e3),
            "sensed_error_max_mm": float(sensed_error.max() * 1e3),
            "spacing_mean_mm": float(steps.mean() * 1e3),
            "spacing_std_mm": float(steps.std() * 1e3),
        }
        if self.curves == "sensed":
            curves, reference = session.curves, true_curves
        else:
            curves, reference = true_curves, session.curves
        return ProbedInstance(curves, np.asarray(truth.point_in_object), info, reference)


def catalog_experiment(**overrides) -> SimulatedSource:
    """Returns the Table 4.6 / 4.7 setting: the ten catalog objects, 3 x 21 points at
    1.2 mm, planes 60 degrees apart (``overrides`` replace fields)."""
    return SimulatedSource(**{"objects": object_names(), **overrides})


def solids_experiment(**overrides) -> SimulatedSource:
    """Returns the Table 4.5 setting: the four solids of Fig. 4.15, n = 41 points at
    d = 0.05 mm (``overrides`` replace fields)."""
    settings = {"objects": FIG_4_15_SOLIDS, "n_points": 41, "spacing_m": 0.05e-3}
    return SimulatedSource(**{**settings, **overrides})


# --- planar experiments (Section 3.4.2) -----------------------------------------------------


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


def _dense_outline(object_name: str, parameters) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The true outline, object frame, densely enough that the nearest vertex gives the
    distance to within a micrometre: (m, 2) metres, and each vertex's outline parameter
    (see :attr:`OutlineTrace.outline_parameter`), (m,)."""
    if object_name == "planar_ellipse":
        outline = ellipse_outline(*parameters["semi_axes_m"], n_segments=_ELLIPSE_SAMPLES)
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
