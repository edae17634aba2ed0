"""Tables 3.4 and 3.5 of the thesis from points sensed by the simulated robot (Section 3.4.2).

:func:`reproduce_thesis` reproduces any of the thesis's tables
(:func:`recognition.reproduction.reproduce.reproduce`), those two from the robot's
traced outlines when asked to.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from recognition.reproduction import chapter3
from recognition.reproduction.reproduce import ReproductionConfig, TableMaker, reproduce
from recognition.reproduction.tables import TableResult
from tactile_sim.collision import load_solid
from tactile_sim.evaluation.outlines import TraceConfig, spline_segment_bearings, trace_outlines

__all__ = [
    "SIM_TABLES",
    "TABLE_3_4_SIM_TOLERANCE_PERCENT",
    "ThesisTablesConfig",
    "reproduce_thesis",
    "table_3_4_sim",
    "table_3_5_sim",
]

#: Tables with a simulated-robot source.
SIM_TABLES = ("3.4", "3.5")
#: Largest relative error (%) of a and b accepted for Table 3.4 from simulated points.
TABLE_3_4_SIM_TOLERANCE_PERCENT = 2.0


@dataclass(frozen=True)
class ThesisTablesConfig:
    """Which tables, from which points.

    Attributes
    ----------
    reproduction : ReproductionConfig
        The tables, their JSON and figures.
    source : {"synthetic", "sim"}
        Where the tactile points of Tables 3.4 and 3.5 come from: sampled on the closed
        form with joystick-like noise, or sensed by the simulated robot tracing the
        extruded outline (thesis Section 3.4.2).
    sim_trials : int
        With ``source="sim"``: independent experiments of Table 3.4 (two traced arcs each).
    """

    reproduction: ReproductionConfig = field(default_factory=ReproductionConfig)
    source: str = "synthetic"
    sim_trials: int = 10


def table_3_4_sim(joystick: chapter3.JoystickExperiment, trials: int, seed: int) -> TableResult:
    """Table 3.4 from the simulated robot tracing the extruded ellipse (a = 25 mm,
    b = 17.5 mm) in a horizontal plane: per trial two arcs of ``joystick.arc_length`` cm
    at ``joystick.spacing`` cm from random start bearings, each with its own object pose
    and sensor noise."""
    trace = TraceConfig(
        object_name="planar_ellipse",
        trials=trials,
        arcs_per_trial=joystick.n_arcs,
        arc_length_m=joystick.arc_length * 1e-2,
        spacing_m=joystick.spacing * 1e-2,
        seed=seed,
    )
    traces = trace_outlines(trace)
    accuracy = traces.accuracy()
    result = chapter3.table_3_4_from_points(
        traces.arcs_in_world(),
        joystick,
        description=(
            f"points sensed by the simulated robot tracing the extruded ellipse: "
            f"{trace.arcs_per_trial} arcs of {trace.arc_length_m * 1e2:g} cm per trial, "
            f"a point every {trace.spacing_m * 1e3:g} mm (in-plane distance of the sensed "
            f"points to the ellipse: mean {accuracy['distance_to_outline_mean_mm']:.3f} mm, "
            f"max {accuracy['distance_to_outline_max_mm']:.3f} mm)"
        ),
    )
    errors = result.measured["mean_relative_error_percent"]
    result.measured["source"] = "sim"
    result.measured["sensing"] = accuracy
    result.measured["within_tolerance"] = bool(
        max(errors.values()) <= TABLE_3_4_SIM_TOLERANCE_PERCENT
    )
    result.measured["tolerance_percent"] = TABLE_3_4_SIM_TOLERANCE_PERCENT
    result.settings["trace"] = {
        "object_name": trace.object_name,
        "trials": trace.trials,
        "arcs_per_trial": trace.arcs_per_trial,
        "arc_length_m": trace.arc_length_m,
        "spacing_m": trace.spacing_m,
        "seed": trace.seed,
        "start_bearings": "random per arc",
    }
    return replace(
        result,
        markdown=result.markdown + f"\n\nSimulated probe: {accuracy['points']} points in "
        f"{accuracy['wall_seconds']:.1f} s of tracing; a and b within "
        f"{TABLE_3_4_SIM_TOLERANCE_PERCENT:g} %: {result.measured['within_tolerance']}.",
    )


def table_3_5_sim(seed: int) -> TableResult:
    """Table 3.5 analogue from the simulated robot tracing each of the five segments of
    the extruded closed cubic spline (Fig. 3.8) in a horizontal plane, a point every
    0.5 mm from 3 mm before the segment's first knot to 3 mm past its last."""
    coefficients = np.asarray(load_solid("planar_spline").parameters["spline_coefficients_m"])
    segments, distances, seconds = [], [], 0.0
    for k, (bearing, length) in enumerate(spline_segment_bearings()):
        traces = trace_outlines(
            TraceConfig(
                object_name="planar_spline",
                trials=1,
                arcs_per_trial=1,
                arc_length_m=length,
                spacing_m=0.5e-3,
                start_angles_rad=(bearing,),
                seed=seed + k,
            )
        )
        arc = traces.trials[0][0]
        on_segment = np.floor(arc.outline_parameter) == k
        segments.append((arc.points_in_world, on_segment, coefficients[k]))
        distances.append(arc.distance_to_outline_m)
        seconds += arc.wall_seconds
    d = np.concatenate(distances)
    # the estimator of Table 3.4's joystick data: the default one (11 points, degree 6)
    # is tuned for noise-free samples
    estimator = chapter3.CurveExperiment(window=21, degree=3, kappa_window=21, seed=seed)
    result = chapter3.table_3_5_from_points(
        segments,
        estimator,
        description=(
            "points sensed by the simulated robot tracing each segment of the extruded "
            f"spline every 0.5 mm (in-plane distance to the spline: mean "
            f"{d.mean() * 1e3:.3f} mm, max {d.max() * 1e3:.3f} mm)"
        ),
    )
    result.measured["source"] = "sim"
    result.measured["sensing"] = {
        "points": int(d.size),
        "distance_to_outline_mean_mm": float(d.mean() * 1e3),
        "distance_to_outline_max_mm": float(d.max() * 1e3),
        "wall_seconds": seconds,
    }
    return result


def reproduce_thesis(
    config: ThesisTablesConfig, *, echo: Callable[[str], object] = print
) -> list[TableResult]:
    """The configured tables (:func:`~recognition.reproduction.reproduce.reproduce`);
    with ``source="sim"``, Tables 3.4 and 3.5 from the simulated robot's points."""
    makers: dict[str, TableMaker] = {}
    if config.source == "sim":
        seed = config.reproduction.seed
        joystick = chapter3.JoystickExperiment(seed=seed)
        makers = {
            "3.4": lambda: table_3_4_sim(joystick, config.sim_trials, seed),
            "3.5": lambda: table_3_5_sim(seed),
        }
    return reproduce(config.reproduction, makers=makers, echo=echo)
