"""Recognition benchmark over the 10-model database or your own meshes (thesis 4.3.4).

python scripts/benchmark.py                               # all three methods
python scripts/benchmark.py --method fast --json out.json
python scripts/benchmark.py --sweep delta                 # Fig. 4.11 (also length, angle)
python scripts/benchmark.py --mesh-dir my_meshes --units mm
python scripts/benchmark.py --backend ray --ray-address auto --workers 8
python scripts/benchmark.py --source sim --json out.json   # simulated robot: Tables 4.5-4.7
python scripts/benchmark.py --source sim --experiment catalog --sessions 1 --method fast
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import platform
import shlex
import sys
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np

from recognition import benchmark as bench
from recognition.errors import RecognitionError
from recognition.reproduction.chapter4_closed_form import TABLE_4_5_THESIS, SolidExperiment
from recognition.reproduction.tables import markdown_table
from recognition.surfaces.database import ModelDatabase
from recognition.surfaces.registration import RegistrationConfig, config_for
from tactile_sim.errors import SimulationError

ROOT = Path(__file__).resolve().parents[1]
METHODS = ("fast", "thesis", "icp-baseline")
SOURCES = ("synthetic", "sim")
EXPERIMENTS = ("catalog", "solids", "sensing")
SENSING_OBJECTS = ("cat", "dog", "bird")
"""Objects of the sensing experiment unless ``--object`` names others."""
SWEEPS = {
    "delta": ("delta_per_mm", [0.01, 0.02, 0.03, 0.04, 0.05], "Fig. 4.11"),
    "length": ("length_mm", [6.0, 12.0, 18.0, 24.0, 30.0], "Fig. 4.12"),
    # three planes phi apart: at 90 degrees the first and the third coincide
    "angle": ("plane_angle_deg", [10.0, 20.0, 30.0, 45.0, 60.0, 75.0, 85.0], "Fig. 4.13"),
}
# What the thesis reports of each sweep (Section 4.3.4; its figures print no values).
SWEEP_THESIS = {
    "delta": "success rate and recognition time both rise with the tolerance (more candidates)",
    "length": "success rate and recognition time both rise with the length of the curves",
    "angle": "success rate rises with the angle between the planes; time hardly changes",
}


@dataclass(frozen=True)
class Config:
    """Benchmark settings (thesis Section 4.3.4 defaults).

    Attributes
    ----------
    methods : tuple of str
        Registration modes compared in one run.
    per_model : int
        Instances per model.
    n_points, spacing_mm, plane_angle_deg, noise_mm
        Data curves: points per curve, their spacing, the angle between sampling
        planes and the noise (mm).
    delta_per_mm : float
        Table-lookup tolerance (thesis: 0.03 1/mm).
    thesis_instances : int
        Instances run in thesis mode (it takes about a minute each); 0 for all.
    workers : int
    backend : {"local", "ray"}
    ray_address : str or None
    mesh_dir : Path or None
        Benchmark these meshes (OBJ/PLY/STL) instead of the catalog.
    units : {"m", "mm"}
        Units of the meshes in ``mesh_dir``.
    sweep : str or None
        "delta", "length" or "angle": success and time against that parameter.
    results : Path or None
        JSONL file of per-instance records (resumable); default under runs/benchmark/.
    json_path : Path or None
        Summary per method as JSON.
    out_dir : Path
        Where the Markdown summary and figures go.
    tag : str
        Suffix of the summary's file name (``<database><tag>.md``).
    seed : int
    source : {"synthetic", "sim"}
        Curves sampled on the models themselves (Section 4.3.4) or probed by the
        simulated robot (Section 4.4: Tables 4.5-4.7).
    experiments : tuple of str
        With ``source="sim"``: "catalog" (Tables 4.6-4.7: the ten objects, 3 x 21 points
        at 1.2 mm, recognised against the catalog database) and/or "solids" (Table 4.5:
        the four solids of Fig. 4.15, n = 41 at 0.05 mm, against their closed forms)
        and/or "sensing" (the sensed points against the original meshes over
        ``sessions`` sessions of each of three objects, and warm wall times of a session
        and of ``scripts/probe.py``).
    sessions : int
        With ``source="sim"``: probing sessions (seeds) per object.
    objects : tuple of str or None
        With ``source="sim"``: probe only these objects.
    sim_curves : {"sensed", "true_contacts"}
        With ``source="sim"``: recognise the sensed points (the experiment) or the
        simulator's true contact points (no sensor error); the other set is recognised
        as the instance's reference either way.
    sim_spacing_mm : float or None
        With ``source="sim"``: point spacing of every experiment instead of its own
        (1.2 mm on the catalog, 0.05 mm on the solids).
    arguments : tuple of str
        The command-line arguments these settings came from (shown in the reports).
    """

    methods: tuple[str, ...] = METHODS
    per_model: int = 10
    n_points: int = 81
    spacing_mm: float = 0.3
    plane_angle_deg: float = 60.0
    noise_mm: float = 0.02
    delta_per_mm: float = 0.03
    thesis_instances: int = 20
    workers: int = field(default_factory=lambda: os.cpu_count() or 1)
    backend: str = "local"
    ray_address: str | None = None
    mesh_dir: Path | None = None
    units: str = "m"
    sweep: str | None = None
    results: Path | None = None
    json_path: Path | None = None
    out_dir: Path = ROOT / "docs" / "benchmarks"
    tag: str = ""
    seed: int = 0
    source: str = "synthetic"
    experiments: tuple[str, ...] = EXPERIMENTS
    sessions: int = 3
    objects: tuple[str, ...] | None = None
    sim_curves: str = "sensed"
    sim_spacing_mm: float | None = None
    arguments: tuple[str, ...] = ()

    def synthetic_source(self, **overrides) -> bench.SyntheticSource:
        return bench.SyntheticSource(
            per_model=self.per_model,
            n_points=overrides.get("n_points", self.n_points),
            spacing_m=self.spacing_mm * 1e-3,
            plane_angle_deg=overrides.get("plane_angle_deg", self.plane_angle_deg),
            noise_std_m=self.noise_mm * 1e-3,
            seed=self.seed,
        )

    def registration(self, method: str = "fast", **overrides) -> RegistrationConfig:
        return config_for(method, delta=overrides.get("delta_per_mm", self.delta_per_mm) * 1e3)


def load_database(config: Config) -> tuple[ModelDatabase, str]:
    """The catalog's database, or one built (and cached) from ``config.mesh_dir``."""
    if config.mesh_dir is None:
        from tactile_sim.objects.database import catalog_database

        return catalog_database(), "catalog"
    import trimesh

    files = sorted(
        p for p in Path(config.mesh_dir).iterdir() if p.suffix.lower() in (".obj", ".ply", ".stl")
    )
    if not files:
        raise RecognitionError(f"no OBJ, PLY or STL files in {config.mesh_dir}")
    scale = {"m": 1.0, "mm": 1e-3}[config.units]
    digest = hashlib.sha256()
    for p in files:
        digest.update(p.name.encode())
        digest.update(p.read_bytes())
    digest.update(str(scale).encode())
    directory = ROOT / "runs" / "mesh_databases" / digest.hexdigest()[:16]
    try:
        return ModelDatabase.load(directory), Path(config.mesh_dir).name
    except RecognitionError:
        pass
    meshes = {}
    for p in files:
        mesh = trimesh.load(p, force="mesh")
        mesh.apply_scale(scale)
        meshes[p.stem] = mesh
    print(f"building a database of {len(meshes)} meshes from {config.mesh_dir}", flush=True)
    ModelDatabase.from_meshes(meshes, progress=True).save(directory)
    return ModelDatabase.load(directory), Path(config.mesh_dir).name


def _jobs(database, config, methods, source, overrides=None, limit_thesis=True):
    specs = bench.instance_specs(database, source)
    jobs = []
    for method in methods:
        chosen = specs
        if method == "thesis" and limit_thesis and config.thesis_instances:
            # spread over the models: instance 0 of each, then 1, ...
            chosen = sorted(specs, key=lambda s: (s.index, s.model))[: config.thesis_instances]
        registration = config.registration(method, **(overrides or {}))
        jobs += [bench.Job(spec, source, (registration,)) for spec in chosen]
    return jobs


def _run(config: Config, database, jobs, path) -> list[dict]:
    """The jobs' records (resumed from ``path``) on the configured workers and backend."""
    return bench.run(
        database,
        jobs,
        path,
        workers=config.workers,
        backend=config.backend,
        ray_address=config.ray_address,
    )


def _results_path(config, name, source, registration, tag=""):
    key = bench.settings_key(source, registration)
    return config.results or ROOT / "runs" / "benchmark" / f"{name}{tag}_{key}.jsonl"


def _command(config: Config) -> str:
    return f"`{shlex.join(['python', 'scripts/benchmark.py', *config.arguments])}`"


def machine() -> str:
    return f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"


def run(config: Config) -> dict:
    """Run the benchmark (or a sweep); write records, summary JSON and Markdown."""
    if config.source == "sim":
        return run_sim(config)
    database, name = load_database(config)
    directory = database.directory
    started = time.strftime("%Y-%m-%d %H:%M")
    if config.sweep:
        return _run_sweep(config, database, name, directory, started)
    source, registration = config.synthetic_source(), config.registration()
    path = _results_path(config, name, source, registration)
    jobs = _jobs(database, config, config.methods, source)
    records = _run(config, directory, jobs, path)
    records = [r for r in records if r["method"] in config.methods]
    summary = bench.summarize(records)
    if config.json_path:
        _write_json(config.json_path, summary)
    text = _markdown(config, database, name, records, summary, started, path)
    out = Path(config.out_dir) / f"{name}{config.tag}.md"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    print(text)
    return summary


def run_sim(config: Config) -> dict:
    """The simulated robot experiments (thesis Section 4.4); returns the summary per method.

    "catalog": every catalog object probed ``sessions`` times, recognised against the
    catalog database with ``methods`` (Tables 4.6-4.7 analogue). "solids": the four
    solids of Fig. 4.15 probed ``sessions`` times, recognised against their closed-form
    models (Table 4.5 analogue, method ``closed-form``).
    """
    from tactile_sim.errors import UnknownObject
    from tactile_sim.experiments import FIG_4_15_SOLIDS, catalog_experiment, solids_experiment
    from tactile_sim.objects import object_names

    known = (*object_names(), *FIG_4_15_SOLIDS)
    for name in config.objects or ():
        if name not in known:
            raise UnknownObject(name, known)
    started = time.strftime("%Y-%m-%d %H:%M")
    summary: dict = {}
    for experiment in config.experiments:
        if experiment == "sensing":
            summary["sensing"] = run_sensing(config, started)
            continue
        make = catalog_experiment if experiment == "catalog" else solids_experiment
        source = make(
            sessions_per_object=config.sessions, curves=config.sim_curves, seed=config.seed
        )
        if config.sim_spacing_mm is not None:
            source = replace(source, spacing_m=config.sim_spacing_mm * 1e-3)
        if config.objects is not None:
            kept = tuple(o for o in source.objects if o in config.objects)
            if not kept:
                continue
            source = replace(source, objects=kept)
        if experiment == "catalog":
            from tactile_sim.objects.database import catalog_database

            database = catalog_database()
            handle, names = database.directory, database.names
            registration = config.registration()
            configs = {m: config.registration(m) for m in config.methods}
        else:
            database = handle = bench.ClosedFormModels()
            names = database.names
            registration = SolidExperiment().config()
            configs = {registration.mode.value: registration}
        specs = source.specs(database)
        thesis_keys = {
            s.key
            for s in sorted(specs, key=lambda s: (s.index, s.model))[
                : config.thesis_instances or len(specs)
            ]
        }
        jobs = [
            bench.Job(
                spec,
                source,
                tuple(c for m, c in configs.items() if m != "thesis" or spec.key in thesis_keys),
            )
            for spec in specs
        ]
        name = f"sim_{experiment}"
        path = _results_path(config, name, source, registration, config.tag)
        records = _run(config, handle, jobs, path)
        wanted = {(j.spec.key, m) for j in jobs for m in j.methods}
        keys = {m: bench.settings_key(source, c) for m, c in configs.items()}
        records = [
            r
            for r in records
            if (r["instance"], r["method"]) in wanted and r.get("settings") == keys[r["method"]]
        ]
        found = bench.summarize(records)
        summary |= found
        out = Path(config.out_dir)
        out.mkdir(parents=True, exist_ok=True)
        figure = out / f"{name}{config.tag}.png"
        if experiment == "catalog":
            text = _sim_catalog_markdown(config, source, names, records, found, started, path)
            _sim_catalog_figure(records, names, figure)
        else:
            text = _sim_solids_markdown(config, source, names, records, found, started, path)
            _sim_solids_figure(records, names, figure)
        text += f"\n![{name}]({figure.name})\n"
        (out / f"{name}{config.tag}.md").write_text(text)
        print(text)
    if config.json_path:
        _write_json(config.json_path, summary)
    return summary


def run_sensing(config: Config, started: str) -> dict:
    """Sensed points against the original meshes; warm wall times of a session and of
    ``scripts/probe.py`` (a fresh process, as a user runs it; the first run warms the
    caches). Writes ``sim_sensing<tag>.md``; returns the figures (millimetres, seconds)."""
    import subprocess
    import tempfile

    from tactile_sim.accuracy import sensing_accuracy, session_timing

    objects = config.objects or SENSING_OBJECTS
    accuracy = sensing_accuracy(objects, sessions_per_object=config.sessions, seed=config.seed)
    timing = session_timing(objects[0], repeats=3, seed=config.seed)
    command = [sys.executable, str(ROOT / "scripts" / "probe.py"), "--object", objects[0]]
    walls = []
    with tempfile.TemporaryDirectory() as out:
        for k in range(4):
            start = time.perf_counter()
            done = subprocess.run(
                [*command, "--seed", str(config.seed + k), "--out", out],
                capture_output=True,
                text=True,
            )
            if done.returncode != 0:
                raise SimulationError(f"probe.py failed: {done.stderr.strip()[-300:]}")
            walls.append(time.perf_counter() - start)
    figures = accuracy.summary() | {
        "session_object": objects[0],
        "session_build_s": list(timing.build_seconds),
        "session_probe_s": list(timing.probe_seconds),
        "session_total_s": list(timing.session_seconds),
        "session_sim_s": list(timing.sim_seconds),
        "probe_script_cold_or_first_s": walls[0],
        "probe_script_warm_s": walls[1:],
    }
    rows = [
        [
            name,
            o["n_points"],
            o["distance_to_mesh_mean_mm"],
            o["distance_to_mesh_p95_mm"],
            o["distance_to_mesh_max_mm"],
            o["truncated_sweeps"],
            o["stylus_contacts"],
        ]
        for name, o in figures["objects"].items()
    ]
    rows.append(
        [
            "all",
            figures["n_points"],
            figures["distance_to_mesh_mean_mm"],
            figures["distance_to_mesh_p95_mm"],
            figures["distance_to_mesh_max_mm"],
            "",
            "",
        ]
    )
    text = "\n".join(
        [
            "# Simulated sensing: accuracy and speed",
            "",
            f"Command: {_command(config)}  ",
            f"Date: {started}; machine: {machine()}.  ",
            f"{len(objects)} objects x {config.sessions} sessions (3 sweeps x 21 points at "
            "1.2 mm, random pose, p and plane yaw per seed; seeds from "
            f"--seed {config.seed}). Distances to the original mesh by libigl's AABB "
            "(exact point-triangle).",
            "",
            "## Sensed points against the original mesh (mm)",
            "",
            markdown_table(
                ["object", "points", "mean", "p95", "max", "truncated sweeps", "shaft contacts"],
                rows,
                digits=3,
            ),
            "",
            f"Distance to the true contact point (the mesh point closest to the simulated tip "
            f"centre): mean {figures['error_to_true_contact_mean_mm']:.3f} mm, p95 "
            f"{figures['error_to_true_contact_p95_mm']:.3f} mm.",
            "",
            "## Wall time (s)",
            "",
            markdown_table(
                ["what", "runs", "min", "median", "max"],
                [
                    [label, len(v), min(v), float(np.median(v)), max(v)]
                    for label, v in (
                        (f"session on {objects[0]}: scene build", timing.build_seconds),
                        (f"session on {objects[0]}: three sweeps", timing.probe_seconds),
                        (f"session on {objects[0]}: probe_object total", timing.session_seconds),
                        (f"`scripts/probe.py --object {objects[0]}`, warm", walls[1:]),
                    )
                ],
                digits=3,
            ),
            "",
            f"Simulated time per session: {float(np.median(timing.sim_seconds)):.1f} s. "
            f"The first `scripts/probe.py` run took {walls[0]:.2f} s (caches already warm "
            "unless this was a fresh checkout).",
            "",
        ]
    )
    out = Path(config.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"sim_sensing{config.tag}.md").write_text(text)
    print(text)
    return figures


def _header(config, title, source, started, path) -> list[str]:
    return [
        f"# {title}",
        "",
        f"Command: {_command(config)}  ",
        f"Date: {started}; machine: {machine()}; workers: {config.workers} ({config.backend}).  ",
        f"Probing: {len(source.objects)} objects x {source.sessions_per_object} sessions "
        f"(seeds from --seed {source.seed}); {source.n_points} points per curve at "
        f"d = {source.spacing_m * 1e3:g} mm, planes {source.plane_angle_deg:g} deg apart; "
        f"recognised from the {source.curves.replace('_', ' ')} points, and from the "
        f"{'true contact' if source.curves == 'sensed' else 'sensed'} points of the same "
        f"session as the reference. Records: `{_shown(path)}`.",
        "",
    ]


def _summary_table(summary) -> str:
    return markdown_table(
        [
            "method",
            "instances",
            "success %",
            "reference success %",
            "median time s",
            "p90 time s",
            "median localisation error mm",
        ],
        [
            [
                m,
                s["instances"],
                100 * s["success_rate"],
                100 * s["reference_success_rate"] if "reference_success_rate" in s else None,
                s["median_time_s"],
                s["p90_time_s"],
                s["median_localization_error_mm"],
            ]
            for m, s in summary.items()
        ],
        digits=4,
    )


def _matrix(first: dict, names: list[str], field: str, bold_min: bool, thesis=None) -> str:
    """Rows: models, columns: objects (thesis layout); the column minimum in bold."""
    columns = [o for o in names if o in first]
    rows = []
    for m in names:
        row = [m]
        for o in columns:
            value = first[o][field].get(m)
            cell = "-" if value is None else f"{value:.3g}"
            if thesis is not None:
                cell += f" ({thesis[o][m]:.3f})"
            finite = {k: v for k, v in first[o][field].items() if v is not None}
            if bold_min and value is not None and m == min(finite, key=finite.get):
                cell = f"**{cell}**"
            row.append(cell)
        rows.append(row)
    return markdown_table(["model \\ object", *columns], rows)


def _instance_rows(records, method) -> list[list]:
    rows = []
    for r in sorted(
        (r for r in records if r["method"] == method), key=lambda r: (r["model"], r["index"])
    ):
        errors = {k: v for k, v in r.get("errors_mm", {}).items() if v is not None}
        own = errors.get(r["model"])
        others = [v for k, v in errors.items() if k != r["model"]]
        ref = r.get("reference", {})
        rows.append(
            [
                r["instance"],
                r["seed"],
                str(r["recognized"]),
                own,
                (min(others) - own) if own is not None and others else None,
                r["localization_error_mm"],
                str(ref.get("recognized")) if ref else "-",
                ref.get("localization_error_mm") if ref else None,
                r.get("sensed_error_mean_mm"),
                r.get("sensed_error_max_mm"),
                (
                    f"{r['spacing_mean_mm']:.3f} +- {r['spacing_std_mm']:.3f}"
                    if "spacing_mean_mm" in r
                    else "-"
                ),
                len(r.get("truncated", [])) if "error" not in r else r["error"],
                r.get("probe_time_s"),
                r["time_s"],
            ]
        )
    return rows


_INSTANCE_HEADER = [
    "instance",
    "seed",
    "recognised",
    "own error mm",
    "margin mm",
    "localisation error mm",
    "recognised (reference)",
    "localisation error (reference) mm",
    "sensed error mean mm",
    "sensed error max mm",
    "spacing mm",
    "truncated sides",
    "probing s",
    "recognition s",
]


def _confusion(records, method, names) -> str:
    confusion: dict = {}
    for r in records:
        if r["method"] == method:
            row = confusion.setdefault(r["model"], {})
            row[str(r["recognized"])] = row.get(str(r["recognized"]), 0) + 1
    labels = [*names, "None"]
    return markdown_table(
        ["object", *labels],
        [[o, *[confusion.get(o, {}).get(c, 0) for c in labels]] for o in names if o in confusion],
    )


def _sim_catalog_markdown(config, source, names, records, summary, started, path) -> str:
    lines = _header(
        config,
        "Simulated robot experiment on the catalog: Tables 4.6 and 4.7 analogue",
        source,
        started,
        path,
    )
    lines += [
        f"Lookup tolerance delta = {config.delta_per_mm} 1/mm; thesis mode on the first "
        f"{config.thesis_instances or 'all'} instances. 'reference': the same sessions "
        "recognised from the other point set (see above).",
        "",
        "## Summary",
        "",
        _summary_table(summary),
    ]
    method = "fast" if "fast" in summary else next(iter(summary), None)
    if method is None:
        return "\n".join(lines) + "\n"
    first = {
        r["model"]: r
        for r in records
        if r["method"] == method and r["index"] == 0 and r.get("errors_mm")
    }
    lines += [
        "",
        f"## Table 4.6 analogue: registration errors (mm), {method}, session 0 of each "
        "object (columns: object, rows: model; '-' rejected at table lookup; column "
        "minimum in bold)",
        "",
        _matrix(first, names, "errors_mm", bold_min=True),
        "",
        f"## Table 4.7 analogue: registration times (s), {method}, same sessions",
        "",
        _matrix(first, names, "times_s", bold_min=False),
        "",
        "Recognition time (all models, local geometry included): "
        + ", ".join(f"{o} {first[o]['time_s']:.3g} s" for o in names if o in first)
        + ".",
        "",
        f"## Confusion ({method}, all sessions; rows: object, columns: recognised)",
        "",
        _confusion(records, method, names),
        "",
        f"## Sessions ({method})",
        "",
        markdown_table(_INSTANCE_HEADER, _instance_rows(records, method), digits=3),
    ]
    return "\n".join(lines) + "\n"


def _sim_solids_markdown(config, source, names, records, summary, started, path) -> str:
    experiment = SolidExperiment()
    lines = _header(
        config,
        "Simulated robot experiment on the Fig. 4.15 solids: Table 4.5 analogue",
        source,
        started,
        path,
    )
    method = bench.CLOSED_FORM_METHOD
    lines += [
        f"Registration onto the four closed-form models (thesis Section 4.2.2), table "
        f"lookup tolerance {experiment.delta_per_m} 1/m, {experiment.max_candidates} "
        "candidates. The thesis's values are in brackets.",
        "",
        "## Summary",
        "",
        _summary_table(summary),
    ]
    first = {
        r["model"]: r
        for r in records
        if r["method"] == method and r["index"] == 0 and r.get("errors_mm")
    }
    diagonal = [
        o for o in first if min(_finite(first[o]["errors_mm"]), key=first[o]["errors_mm"].get) == o
    ]
    lines += [
        "",
        "## Table 4.5 analogue: minimum registration error (mm), session 0 of each solid "
        "(columns: object, rows: model; column minimum in bold)",
        "",
        _matrix(first, names, "errors_mm", bold_min=True, thesis=TABLE_4_5_THESIS["min_error_mm"]),
        "",
        f"Columns whose minimum is on the diagonal: {len(diagonal)} / {len(first)}.",
    ]
    if source.sessions_per_object > 1:
        lines += [
            "",
            "## Every session: registration errors (mm)",
            "",
            markdown_table(
                ["instance", *names, "recognised"],
                [
                    [r["instance"], *[r["errors_mm"].get(m) for m in names], str(r["recognized"])]
                    for r in sorted(records, key=lambda r: (r["model"], r["index"]))
                    if r["method"] == method
                ],
                digits=3,
            ),
        ]
    lines += [
        "",
        "## Confusion (all sessions; rows: object, columns: recognised)",
        "",
        _confusion(records, method, names),
        "",
        "## Sessions",
        "",
        markdown_table(_INSTANCE_HEADER, _instance_rows(records, method), digits=3),
    ]
    return "\n".join(lines) + "\n"


def _finite(errors: dict) -> dict:
    return {k: v for k, v in errors.items() if v is not None}


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _error_image(ax, first, names, title):
    columns = [o for o in names if o in first]
    matrix = np.array(
        [[first[o]["errors_mm"].get(m) or np.nan for o in columns] for m in names], dtype=float
    )
    image = ax.imshow(np.log10(matrix), cmap="viridis")
    ax.set_xticks(range(len(columns)), columns, rotation=60, ha="right")
    ax.set_yticks(range(len(names)), names)
    for j, o in enumerate(columns):
        finite = _finite(first[o]["errors_mm"])
        if finite:
            i = names.index(min(finite, key=finite.get))
            ax.add_patch(_plt_rectangle(j, i))
    ax.set(xlabel="object", ylabel="model", title=title)
    return image


def _plt_rectangle(j, i):
    from matplotlib.patches import Rectangle

    return Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, edgecolor="red", linewidth=2)


def _sim_catalog_figure(records, names, path: Path) -> None:
    plt = _pyplot()
    method = "fast" if any(r["method"] == "fast" for r in records) else records[0]["method"]
    rs = sorted(
        (r for r in records if r["method"] == method), key=lambda r: (r["model"], r["index"])
    )
    first = {r["model"]: r for r in rs if r["index"] == 0 and r.get("errors_mm")}
    fig, ax = plt.subplots(1, 2, figsize=(12, 5))
    image = _error_image(ax[0], first, names, f"log10 registration error mm ({method}, session 0)")
    fig.colorbar(image, ax=ax[0], shrink=0.8)
    x = np.arange(len(rs))
    sensed = [r["localization_error_mm"] or np.nan for r in rs]
    reference = [(r.get("reference") or {}).get("localization_error_mm") or np.nan for r in rs]
    ax[1].semilogy(x, sensed, "o", label=f"{rs[0].get('curves', 'data')} points" if rs else "")
    ax[1].semilogy(x, reference, "x", label="reference points")
    for k, r in enumerate(rs):
        if not r["success"]:
            ax[1].axvline(k, color="red", alpha=0.3)
    ax[1].set_xticks(x, [r["instance"] for r in rs], rotation=90, fontsize=7)
    ax[1].set(ylabel="localisation error mm", title="localisation error per session")
    ax[1].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _sim_solids_figure(records, names, path: Path) -> None:
    plt = _pyplot()
    method = bench.CLOSED_FORM_METHOD
    first = {
        r["model"]: r
        for r in records
        if r["method"] == method and r["index"] == 0 and r.get("errors_mm")
    }
    fig, ax = plt.subplots(figsize=(6, 5))
    image = _error_image(ax, first, names, "log10 minimum registration error mm (session 0)")
    fig.colorbar(image, ax=ax, shrink=0.8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _shown(path: Path) -> Path:
    path = Path(path).resolve()
    return path.relative_to(ROOT) if path.is_relative_to(ROOT) else path


def _write_json(path: Path, payload) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(payload, indent=2))
    tmp.replace(path)


def _markdown(config, database, name, records, summary, started, path) -> str:
    lines = [
        f"# Recognition benchmark: {name}",
        "",
        f"Command: {_command(config)}  ",
        f"Date: {started}; machine: {machine()}; workers: {config.workers} ({config.backend}).  ",
        f"Instances: {config.per_model} per model, n = {config.n_points} points per curve at "
        f"d = {config.spacing_mm} mm (l = {(config.n_points - 1) * config.spacing_mm:g} mm), "
        f"planes {config.plane_angle_deg:g} deg apart, noise sigma {config.noise_mm} mm, "
        f"delta = {config.delta_per_mm} 1/mm. Thesis mode on the first "
        f"{config.thesis_instances or 'all'} instances. Records: `{_shown(path)}`.",
        "",
        "## Summary",
        "",
        markdown_table(
            [
                "method",
                "instances",
                "success %",
                "median time s",
                "p90 time s",
                "median localisation error mm",
            ],
            [
                [
                    m,
                    s["instances"],
                    100 * s["success_rate"],
                    s["median_time_s"],
                    s["p90_time_s"],
                    s["median_localization_error_mm"],
                ]
                for m, s in summary.items()
            ],
            digits=4,
        ),
    ]
    if "fast" in summary:
        for other in ("icp-baseline", "thesis"):
            if other in summary:
                both = {r["instance"] for r in records if r["method"] == other}
                fast_t = [
                    r["time_s"] for r in records if r["method"] == "fast" and r["instance"] in both
                ]
                other_t = [r["time_s"] for r in records if r["method"] == other]
                lines += [
                    "",
                    f"fast vs {other} on the same {len(both)} instances: median time "
                    f"{np.median(fast_t):.3g} s vs {np.median(other_t):.3g} s "
                    f"({np.median(other_t) / np.median(fast_t):.1f}x).",
                ]
    names = database.names
    first = {
        r["model"]: r for r in records if r["method"] == "fast" and r["instance"].endswith("/0")
    }
    if first:
        lines += [
            "",
            "## Registration errors (mm), Table 4.6 analogue (fast, instance 0 of "
            "each object; columns: object, rows: model; '-' rejected at table lookup)",
            "",
        ]
        rows = [
            [m, *[first[o]["errors_mm"].get(m) if o in first else None for o in names]]
            for m in names
        ]
        lines.append(markdown_table(["model \\ object", *names], rows, digits=3))
        lines += ["", "## Registration times (s), Table 4.7 analogue (same instances)", ""]
        rows = [
            [m, *[first[o]["times_s"].get(m) if o in first else None for o in names]] for m in names
        ]
        rows.append(["recognition", *[first[o]["time_s"] if o in first else None for o in names]])
        lines.append(markdown_table(["model \\ object", *names], rows, digits=3))
    lines += ["", "## Model tables, Table 4.4 analogue", ""]
    rows = []
    for m in names:
        model = database[m]
        t = model.timings
        rows.append(
            [
                m,
                len(model.vertices),
                len(model.faces),
                " x ".join(f"{x * 1e3:.1f}" for x in np.ptp(model.vertices, axis=0)),
                len(model.table),
                t.get("sampling_s"),
                t.get("curvatures_s"),
                (t.get("sampling_s") or 0) + (t.get("curvatures_s") or 0),
                t.get("vertex_curvatures_s"),
                t.get("distance_field_s"),
            ]
        )
    lines.append(
        markdown_table(
            [
                "model",
                "vertices",
                "triangles",
                "dimension mm",
                "sample vertices",
                "sampling s",
                "curvatures s",
                "table s",
                "vertex curvature map s",
                "distance field s",
            ],
            rows,
            digits=3,
        )
    )
    confusion = {}
    for r in records:
        if r["method"] == "fast":
            confusion.setdefault(r["model"], {}).setdefault(str(r["recognized"]), 0)
            confusion[r["model"]][str(r["recognized"])] += 1
    if confusion:
        labels = [*names, "None"]
        lines += ["", "## Confusion (fast, all instances; rows: object, columns: recognised)", ""]
        lines.append(
            markdown_table(
                ["object", *labels],
                [[o, *[confusion.get(o, {}).get(c, 0) for c in labels]] for o in names],
            )
        )
    return "\n".join(lines) + "\n"


def _run_sweep(config, database, name, directory, started) -> dict:
    parameter, values, figure = SWEEPS[config.sweep]
    results = {}
    for value in values:
        overrides = {}
        if parameter == "length_mm":
            overrides["n_points"] = round(value / config.spacing_mm) + 1
        else:
            overrides[parameter] = value
        source, registration = (
            config.synthetic_source(**overrides),
            config.registration(**overrides),
        )
        path = _results_path(config, name, source, registration, f"_sweep_{config.sweep}")
        jobs = _jobs(database, config, ("fast",), source, overrides)
        records = _run(config, directory, jobs, path)
        results[value] = bench.summarize(r for r in records if r["method"] == "fast")["fast"]
    payload = {
        "parameter": parameter,
        "figure": figure,
        "date": started,
        "machine": machine(),
        "points": [{"value": v, **s} for v, s in results.items()],
    }
    out = Path(config.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    _write_json(out / f"sweep_{config.sweep}.json", payload)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(9, 3.5))
    xs = list(results)
    ax[0].plot(xs, [100 * results[v]["success_rate"] for v in xs], "o-")
    ax[0].set(xlabel=parameter, ylabel="success %", ylim=(0, 105), title=f"{figure}: success rate")
    ax[1].plot(xs, [results[v]["median_time_s"] for v in xs], "o-")
    ax[1].set(xlabel=parameter, ylabel="median recognition time s", title="time")
    fig.tight_layout()
    fig.savefig(out / f"sweep_{config.sweep}.png", dpi=110)
    plt.close(fig)
    table = markdown_table(
        [parameter, "instances", "success %", "median time s", "p90 time s", "median loc. err. mm"],
        [
            [
                v,
                r["instances"],
                100 * r["success_rate"],
                r["median_time_s"],
                r["p90_time_s"],
                r["median_localization_error_mm"],
            ]
            for v, r in results.items()
        ],
    )
    text = "\n".join(
        [
            f"# Sweep of {parameter}, thesis {figure} ({name}, fast mode)",
            "",
            f"Command: {_command(config)}  ",
            f"Date: {started}; machine: {machine()}; workers: {config.workers} "
            f"({config.backend}).  ",
            f"Instances: {config.per_model} per model; unless swept, n = {config.n_points} "
            f"points per curve at d = {config.spacing_mm} mm, planes "
            f"{config.plane_angle_deg:g} deg apart, noise sigma {config.noise_mm} mm, "
            f"delta = {config.delta_per_mm} 1/mm. Values: `sweep_{config.sweep}.json`.",
            "",
            f"![{figure}](sweep_{config.sweep}.png)",
            "",
            table,
            "",
            f"Thesis ({figure}): {SWEEP_THESIS[config.sweep]}.",
            "",
        ]
    )
    (out / f"sweep_{config.sweep}.md").write_text(text)
    print(text)
    return payload


def parse_args(argv=None) -> Config:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--method",
        action="append",
        choices=METHODS,
        help="registration mode (repeatable; default all three)",
    )
    p.add_argument("--per-model", type=int, default=10)
    p.add_argument("--n-points", type=int, default=81)
    p.add_argument("--spacing-mm", type=float, default=0.3)
    p.add_argument("--plane-angle", type=float, default=60.0)
    p.add_argument("--noise-mm", type=float, default=0.02)
    p.add_argument("--delta", type=float, default=0.03, help="lookup tolerance, 1/mm")
    p.add_argument("--thesis-instances", type=int, default=20)
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    p.add_argument("--backend", choices=("local", "ray"), default="local")
    p.add_argument("--ray-address", default=None, help="existing Ray cluster (e.g. auto)")
    p.add_argument("--mesh-dir", type=Path)
    p.add_argument("--units", choices=("m", "mm"), default="m")
    p.add_argument("--sweep", choices=tuple(SWEEPS))
    p.add_argument("--results", type=Path, help="JSONL of per-instance records")
    p.add_argument("--json", type=Path, dest="json_path", help="summary per method")
    p.add_argument("--out-dir", type=Path, default=ROOT / "docs" / "benchmarks")
    p.add_argument("--tag", default="", help="suffix of the summary file name")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--source", choices=SOURCES, default="synthetic", help="synthetic curves or the robot"
    )
    p.add_argument(
        "--experiment",
        action="append",
        choices=EXPERIMENTS,
        help="with --source sim: catalog (Tables 4.6-4.7), solids (Table 4.5) and/or "
        "sensing (sensed points against the meshes, wall times)",
    )
    p.add_argument("--sessions", type=int, default=3, help="with --source sim: seeds per object")
    p.add_argument("--object", action="append", help="with --source sim: probe only these")
    p.add_argument(
        "--sim-curves",
        choices=("sensed", "true_contacts"),
        default="sensed",
        help="with --source sim: recognise the sensed or the true contact points",
    )
    p.add_argument(
        "--sim-spacing-mm",
        type=float,
        help="with --source sim: point spacing instead of the experiment's own",
    )
    a = p.parse_args(argv)
    if a.sim_spacing_mm is not None and not 0 < a.sim_spacing_mm < 20:
        p.error("--sim-spacing-mm must lie in (0, 20)")
    if a.sessions < 1:
        p.error("--sessions must be at least 1")
    if a.source == "sim" and (a.mesh_dir is not None or a.sweep is not None):
        p.error("--mesh-dir and --sweep apply to --source synthetic only")
    for name in ("per_model", "n_points", "workers"):
        if getattr(a, name) < 1:
            p.error(f"--{name.replace('_', '-')} must be at least 1")
    if a.spacing_mm <= 0 or a.delta <= 0 or a.noise_mm < 0:
        p.error("--spacing-mm and --delta must be positive, --noise-mm not negative")
    if a.mesh_dir is not None and not a.mesh_dir.is_dir():
        p.error(f"--mesh-dir {a.mesh_dir} is not a directory")
    return Config(
        methods=tuple(a.method) if a.method else METHODS,
        per_model=a.per_model,
        n_points=a.n_points,
        spacing_mm=a.spacing_mm,
        plane_angle_deg=a.plane_angle,
        noise_mm=a.noise_mm,
        delta_per_mm=a.delta,
        thesis_instances=a.thesis_instances,
        workers=a.workers,
        backend=a.backend,
        ray_address=a.ray_address,
        mesh_dir=a.mesh_dir,
        units=a.units,
        sweep=a.sweep,
        results=a.results,
        json_path=a.json_path,
        out_dir=a.out_dir,
        tag=a.tag,
        seed=a.seed,
        source=a.source,
        experiments=tuple(a.experiment) if a.experiment else EXPERIMENTS,
        sessions=a.sessions,
        objects=tuple(a.object) if a.object else None,
        sim_curves=a.sim_curves,
        sim_spacing_mm=a.sim_spacing_mm,
        arguments=tuple(sys.argv[1:] if argv is None else argv),
    )


def main(argv=None) -> int:
    config = parse_args(argv)
    try:
        run(config)
    except (RecognitionError, SimulationError, OSError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
