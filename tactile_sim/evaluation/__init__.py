"""The simulated robot in the evaluation layer: instance source, experiments, benchmark runs.

:class:`SimulatedSource` makes recognition-benchmark instances by probing (thesis
Section 4.4); :func:`trace_outlines` traces the planar solids of Section 3.4.2 (Tables
3.4 and 3.5: :func:`reproduce_thesis`); :func:`sensing_accuracy` and
:func:`session_timing` measure the simulated probe; :func:`run` runs a benchmark from a
:class:`BenchmarkConfig` (synthetic curves, sweeps, or the robot's experiments), on top of
:mod:`recognition.evaluation`; :func:`probe_run` is one probing run end to end
(``scripts/probe.py``).

Importing this package loads neither matplotlib nor ray (MuJoCo comes with
:mod:`tactile_sim.probing`).
"""

from tactile_sim.evaluation.accuracy import (
    AccuracyResult,
    ObjectAccuracy,
    TimingResult,
    collision_report,
    probe_script_seconds,
    sensing_accuracy,
    session_timing,
)
from tactile_sim.evaluation.benchmark import (
    plan_jobs,
    run,
    run_sensing,
    run_sim,
    run_sweep,
    run_synthetic,
)
from tactile_sim.evaluation.benchmark_config import (
    EXPERIMENTS,
    METHODS,
    SENSING_OBJECTS,
    SOURCES,
    SWEEPS,
    BenchmarkConfig,
    MeshSettings,
    MethodSettings,
    ReportSettings,
    RunSettings,
    SimSettings,
    Sweep,
    SyntheticSettings,
)
from tactile_sim.evaluation.databases import benchmark_database
from tactile_sim.evaluation.outlines import (
    OutlineTrace,
    OutlineTraces,
    TraceConfig,
    outline_distance,
    spline_segment_bearings,
    trace_outlines,
)
from tactile_sim.evaluation.probe_run import RERUN_MODES, ProbeRunConfig, pose_error, probe_run
from tactile_sim.evaluation.sessions import (
    FIG_4_15_SOLIDS,
    SimulatedSource,
    catalog_experiment,
    session_seed,
    solids_experiment,
)
from tactile_sim.evaluation.thesis_tables import (
    SIM_TABLES,
    TABLE_3_4_SIM_TOLERANCE_PERCENT,
    ThesisTablesConfig,
    reproduce_thesis,
    table_3_4_sim,
    table_3_5_sim,
)

__all__ = [
    "EXPERIMENTS",
    "FIG_4_15_SOLIDS",
    "METHODS",
    "RERUN_MODES",
    "SENSING_OBJECTS",
    "SIM_TABLES",
    "SOURCES",
    "SWEEPS",
    "TABLE_3_4_SIM_TOLERANCE_PERCENT",
    "AccuracyResult",
    "BenchmarkConfig",
    "MeshSettings",
    "MethodSettings",
    "ObjectAccuracy",
    "OutlineTrace",
    "OutlineTraces",
    "ProbeRunConfig",
    "ReportSettings",
    "RunSettings",
    "SimSettings",
    "SimulatedSource",
    "Sweep",
    "SyntheticSettings",
    "ThesisTablesConfig",
    "TimingResult",
    "TraceConfig",
    "benchmark_database",
    "catalog_experiment",
    "collision_report",
    "outline_distance",
    "plan_jobs",
    "pose_error",
    "probe_run",
    "probe_script_seconds",
    "reproduce_thesis",
    "run",
    "run_sensing",
    "run_sim",
    "run_sweep",
    "run_synthetic",
    "sensing_accuracy",
    "session_seed",
    "session_timing",
    "solids_experiment",
    "spline_segment_bearings",
    "table_3_4_sim",
    "table_3_5_sim",
    "trace_outlines",
]
