"""Settings of a benchmark run, one small frozen config per part (thesis Section 4.3.4 defaults).

:class:`BenchmarkConfig` gathers them: the synthetic instances
(:class:`SyntheticSettings`), the registration per method (:class:`MethodSettings`), the
meshes benchmarked instead of the catalog (:class:`MeshSettings`), where and how jobs run
(:class:`RunSettings`), where the reports go (:class:`ReportSettings`) and the simulated
robot's experiments (:class:`SimSettings`).
"""

from __future__ import annotations

import os
import shlex
from dataclasses import dataclass, field, replace
from pathlib import Path

from recognition import FastConfig, RegistrationConfig, config_for
from recognition.evaluation import SyntheticSource
from tactile_sim.objects import OBJECT_NAMES

__all__ = [
    "EXPERIMENTS",
    "METHODS",
    "RUNS_DIR",
    "SENSING_OBJECTS",
    "SOURCES",
    "SWEEPS",
    "TIMED_OBJECT",
    "BenchmarkConfig",
    "MeshSettings",
    "MethodSettings",
    "ReportSettings",
    "RunSettings",
    "SimSettings",
    "Sweep",
    "SyntheticSettings",
]

#: The project's run directory (records, caches and reports of runs; not committed).
RUNS_DIR = Path(__file__).resolve().parents[2] / "runs"
METHODS = ("fast", "thesis", "icp-baseline")
SOURCES = ("synthetic", "sim")
EXPERIMENTS = ("catalog", "solids", "sensing")
#: Objects of the sensing experiment unless :attr:`SimSettings.objects` names others: the
#: ten catalog objects.
SENSING_OBJECTS = OBJECT_NAMES
#: The object whose sessions and ``scripts/probe.py`` runs the sensing experiment times
#: (the demo's), when it is among the objects.
TIMED_OBJECT = "cat"


@dataclass(frozen=True)
class Sweep:
    """A sweep of one setting (thesis Figs. 4.11-4.13).

    Attributes
    ----------
    parameter : str
        ``delta_per_mm``, ``length_mm`` or ``plane_angle_deg``.
    values : tuple of float
    figure : str
        The thesis figure.
    thesis : str
        What the thesis reports of it (Section 4.3.4; its figures print no values).
    """

    parameter: str
    values: tuple[float, ...]
    figure: str
    thesis: str


#: The sweeps by name.
SWEEPS = {
    "delta": Sweep(
        "delta_per_mm",
        (0.01, 0.02, 0.03, 0.04, 0.05),
        "Fig. 4.11",
        "success rate and recognition time both rise with the tolerance (more candidates)",
    ),
    "length": Sweep(
        "length_mm",
        (6.0, 12.0, 18.0, 24.0, 30.0),
        "Fig. 4.12",
        "success rate and recognition time both rise with the length of the curves",
    ),
    # three planes phi apart: at 90 degrees the first and the third coincide
    "angle": Sweep(
        "plane_angle_deg",
        (10.0, 20.0, 30.0, 45.0, 60.0, 75.0, 85.0),
        "Fig. 4.13",
        "success rate rises with the angle between the planes; time hardly changes",
    ),
    # the catalog's models, then generated ones (tactile_sim.objects.generated)
    "database-size": Sweep(
        "database_size",
        (10.0, 25.0, 50.0, 100.0),
        "Table 4.7",
        "each model is searched in turn, 3.4-19.3 s per recognition against 10 models: the "
        "time grows in proportion to the number of models",
    ),
}


@dataclass(frozen=True)
class SyntheticSettings:
    """Synthetic instances, as the user gives them (millimetres).

    Attributes
    ----------
    per_model : int
        Instances per model.
    n_points : int
        Points per curve.
    spacing_mm : float
        Arc length between points.
    plane_angle_deg : float
        Angle between sampling planes.
    noise_mm : float
        Gaussian noise per coordinate.
    seed : int
    per_generated : int
        Instances per generated model (:func:`~tactile_sim.objects.database.
        sized_database`), in a database of ``database_size`` models or the database-size
        sweep.
    database_size : int or None
        Recognise against the catalog's models and generated ones, this many in all
        (None: the catalog, or ``MeshSettings.mesh_dir``).
    """

    per_model: int = 10
    n_points: int = 81
    spacing_mm: float = 0.3
    plane_angle_deg: float = 60.0
    noise_mm: float = 0.02
    seed: int = 0
    per_generated: int = 2
    database_size: int | None = None

    def source(
        self, *, n_points: int | None = None, plane_angle_deg: float | None = None
    ) -> SyntheticSource:
        """The instance source of these settings (``n_points`` or ``plane_angle_deg``
        replaced in a sweep)."""
        return SyntheticSource(
            per_model=self.per_model,
            n_points=self.n_points if n_points is None else n_points,
            spacing_m=self.spacing_mm * 1e-3,
            plane_angle_deg=self.plane_angle_deg if plane_angle_deg is None else plane_angle_deg,
            noise_std_m=self.noise_mm * 1e-3,
            seed=self.seed,
        )


@dataclass(frozen=True)
class MethodSettings:
    """The registration methods compared, and their settings.

    Attributes
    ----------
    methods : tuple of str
        Registration modes compared in one run.
    delta_per_mm : float
        Table-lookup tolerance (thesis: 0.03 1/mm).
    thesis_instances : int
        Instances run in thesis mode (it takes about a minute each); 0 for all.
    model_mismatch_mm : float
        How far the fast mode takes the objects to differ from their models (RMS, mm:
        :attr:`recognition.FastConfig.model_mismatch_m`): the experimenter's knowledge
        of the model's accuracy, as of the sensor's noise.
    touches : int
        Verification touches after the curves, at most, until the answer's confidence
        reaches 0.99 (fast mode; :func:`recognition.verify`); 0: none.
    """

    methods: tuple[str, ...] = METHODS
    delta_per_mm: float = 0.03
    thesis_instances: int = 20
    model_mismatch_mm: float = 0.0
    touches: int = 0

    def config(self, method: str = "fast", delta_per_mm: float | None = None) -> RegistrationConfig:
        """The registration of ``method`` (``delta_per_mm`` replaced in a sweep)."""
        delta = self.delta_per_mm if delta_per_mm is None else delta_per_mm
        config = config_for(method, delta=delta * 1e3)
        if isinstance(config, FastConfig) and self.model_mismatch_mm:
            config = replace(config, model_mismatch_m=self.model_mismatch_mm * 1e-3)
        return config

    def configs(self) -> dict[str, RegistrationConfig]:
        """The registration per method, in the order of ``methods``."""
        return {m: self.config(m) for m in self.methods}


@dataclass(frozen=True)
class MeshSettings:
    """The meshes benchmarked instead of the catalog.

    Attributes
    ----------
    mesh_dir : Path or None
        A directory of mesh files (OBJ, PLY, STL, OFF, GLB, glTF: one model each, named by
        the file); None: the catalog.
    units : {"m", "mm", "cm", "in"}
        Units of the meshes.
    with_catalog : bool
        Recognise against the catalog's models as well as the folder's.
    cache_dir : Path
        Where the databases built from mesh directories are kept (one per content hash).
    """

    mesh_dir: Path | None = None
    units: str = "m"
    cache_dir: Path = RUNS_DIR / "mesh_databases"
    with_catalog: bool = False


@dataclass(frozen=True)
class RunSettings:
    """Where and how the jobs run.

    Attributes
    ----------
    workers : int
        Processes (local) or actors (Ray).
    backend : {"local", "ray"}
    ray_address : str or None
        An existing Ray cluster.
    results : Path or None
        JSONL file of records (resumable); None: one per run under ``records_dir``.
    records_dir : Path
    progress : bool
        Progress bars.
    """

    workers: int = field(default_factory=lambda: os.cpu_count() or 1)
    backend: str = "local"
    ray_address: str | None = None
    results: Path | None = None
    records_dir: Path = RUNS_DIR / "benchmark"
    progress: bool = True


@dataclass(frozen=True)
class ReportSettings:
    """Where the reports go and what they say of the command.

    Attributes
    ----------
    out_dir : Path
        Markdown reports and figures (``docs/benchmarks`` for the committed ones).
    json_path : Path or None
        The summary per method as JSON.
    tag : str
        Suffix of the reports' file names (``<name><tag>.md``).
    arguments : tuple of str
        The command-line arguments of the run (shown in the reports).
    """

    out_dir: Path = RUNS_DIR / "benchmark"
    json_path: Path | None = None
    tag: str = ""
    arguments: tuple[str, ...] = ()

    @property
    def command(self) -> str:
        """The command of the run, as Markdown."""
        return f"`{shlex.join(['python', 'scripts/benchmark.py', *self.arguments])}`"


@dataclass(frozen=True)
class SimSettings:
    """The simulated robot's experiments (thesis Section 4.4).

    Attributes
    ----------
    experiments : tuple of str
        "catalog" (Tables 4.6-4.7: the ten objects, 3 x 21 points at 1.2 mm, recognised
        against the catalog database) and/or "solids" (Table 4.5: the four solids of
        Fig. 4.15, n = 41 at 0.05 mm, against their closed forms) and/or "sensing" (the
        sensed points against the original meshes over ``sessions`` sessions of each of
        three objects, and warm wall times of a session and of ``scripts/probe.py``).
    sessions : int
        Probing sessions (seeds) per object.
    first_session : int
        Index of each object's first session (later sessions without the earlier ones).
    objects : tuple of str or None
        Probe only these objects.
    curves : {"sensed", "true_contacts"}
        Recognise the sensed points (the experiment) or the simulator's true contact
        points (no sensor error); the other set is recognised as the instance's reference
        either way.
    spacing_mm : float or None
        Point spacing of every experiment instead of its own (1.2 mm on the catalog,
        0.05 mm on the solids).
    seed : int
    model_error_mm : float
        RMS (mm) of the smooth random displacement of every probed object from its
        model (:func:`~tactile_sim.probing.displaced_target`); 0: none.
    """

    experiments: tuple[str, ...] = EXPERIMENTS
    sessions: int = 3
    first_session: int = 0
    objects: tuple[str, ...] | None = None
    curves: str = "sensed"
    spacing_mm: float | None = None
    seed: int = 0
    model_error_mm: float = 0.0


@dataclass(frozen=True)
class BenchmarkConfig:
    """A benchmark run: what is recognised, how, and where it is written.

    Attributes
    ----------
    source : {"synthetic", "sim"}
        Curves sampled on the models themselves (Section 4.3.4) or probed by the
        simulated robot (Section 4.4: Tables 4.5-4.7).
    synthetic : SyntheticSettings
    methods : MethodSettings
    meshes : MeshSettings
    run : RunSettings
    report : ReportSettings
    sim : SimSettings
    sweep : str or None
        With ``source="synthetic"``: "delta", "length" or "angle" (:data:`SWEEPS`):
        success and time against that parameter, fast mode.
    """

    source: str = "synthetic"
    synthetic: SyntheticSettings = field(default_factory=SyntheticSettings)
    methods: MethodSettings = field(default_factory=MethodSettings)
    meshes: MeshSettings = field(default_factory=MeshSettings)
    run: RunSettings = field(default_factory=RunSettings)
    report: ReportSettings = field(default_factory=ReportSettings)
    sim: SimSettings = field(default_factory=SimSettings)
    sweep: str | None = None
