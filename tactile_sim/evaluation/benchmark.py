"""The benchmark runs: synthetic (thesis 4.3.4) and its sweeps, the robot experiments (4.4).

:func:`run` takes a :class:`~tactile_sim.evaluation.benchmark_config.BenchmarkConfig`:
synthetic curves on the catalog's models (or a directory of meshes), a sweep of one
setting (Figs. 4.11-4.13), or the simulated robot's experiments (:func:`run_sim`:
Tables 4.5-4.7 analogues, :func:`run_sensing`: the sensed points' accuracy and wall
times). Records stream to JSONL files (resumable), reports to Markdown and PNG, the
summary optionally to JSON.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from recognition import ModelDatabase, RegistrationConfig
from recognition.errors import InvalidCurveData
from recognition.evaluation import (
    ClosedFormModels,
    DatabaseHandle,
    InstanceSpec,
    Job,
    MethodSummary,
    Record,
    SyntheticSource,
    instance_specs,
    read_results,
    settings_key,
    summarize,
    summary_json,
)
from recognition.evaluation import run as run_jobs
from recognition.evaluation.calibration import (
    reliability,
    reliability_figure,
    touch_summary,
    touches_section,
)
from recognition.evaluation.figures import catalog_sessions_figure, solids_figure, sweep_figure
from recognition.evaluation.reports import RunInfo, catalog_report, machine, sweep_report
from recognition.files import write_json_atomic
from recognition.reproduction.chapter4_closed_form import SolidExperiment
from tactile_sim.errors import UnknownObject
from tactile_sim.evaluation.accuracy import (
    probe_script_seconds,
    sensing_accuracy,
    session_timing,
)
from tactile_sim.evaluation.benchmark_config import (
    RUNS_DIR,
    SENSING_OBJECTS,
    SWEEPS,
    TIMED_OBJECT,
    BenchmarkConfig,
    Sweep,
)
from tactile_sim.evaluation.databases import benchmark_database, mesh_files
from tactile_sim.evaluation.reports import catalog_sessions_report, sensing_report, solids_report
from tactile_sim.evaluation.scaling import database_footprint, footprint_table, sized_specs
from tactile_sim.evaluation.sessions import (
    FIG_4_15_SOLIDS,
    SimulatedSource,
    catalog_experiment,
    solids_experiment,
)

__all__ = [
    "check_config",
    "plan_jobs",
    "run",
    "run_sensing",
    "run_sim",
    "run_sweep",
    "run_synthetic",
]

Echo = Callable[[str], object]


def plan_jobs(
    specs: Sequence[InstanceSpec],
    source: Any,
    configs: Mapping[str, RegistrationConfig],
    thesis_instances: int,
    touches: int = 0,
    models: DatabaseHandle | None = None,
) -> list[Job]:
    """One job per instance with the registration of every method; thesis mode (about a
    minute an instance) only on the first ``thesis_instances`` (0: all), spread over the
    models: instance 0 of each, then 1, ...; at most ``touches`` verification touches
    after the curves; the records keyed by ``models`` (:func:`_models_key`), so that a
    results file shared by several databases resumes each one's records only."""
    first = sorted(specs, key=lambda s: (s.index, s.model))[: thesis_instances or len(specs)]
    thesis_keys = {s.key for s in first}
    jobs = []
    for spec in specs:
        chosen = tuple(c for m, c in configs.items() if m != "thesis" or spec.key in thesis_keys)
        if chosen:
            jobs.append(Job(spec, source, chosen, touches, _models_key(models)))
    return jobs


def _records(
    config: BenchmarkConfig, handle: DatabaseHandle, jobs: Sequence[Job], path: Path
) -> list[Record]:
    """The jobs' records (resumed from ``path``) on the configured workers and backend;
    records of other instances, methods or settings in ``path`` are left out."""
    records = run_jobs(
        handle,
        jobs,
        path,
        workers=config.run.workers,
        backend=config.run.backend,
        ray_address=config.run.ray_address,
        progress=config.run.progress,
    )
    wanted = {(j.spec.key, c.mode.value, j.settings(c)) for j in jobs for c in j.configs}
    return [r for r in records if (r.instance, r.method, r.settings) in wanted]


def _directory(database: ModelDatabase) -> Path:
    """Where the workers load ``database`` from."""
    if database.directory is None:
        raise ValueError("the benchmark's workers load the database from disk: save it first")
    return database.directory


def _results_path(
    config: BenchmarkConfig,
    name: str,
    source: Any,
    registration: RegistrationConfig,
    tag: str,
    handle: DatabaseHandle,
) -> Path:
    """The records file of a run: keyed by the source, the registration and the models
    (a database's folder is named by a hash of its content and settings), never by a
    folder's name alone."""
    if config.run.results is not None:
        return config.run.results
    key = settings_key(source, registration, (_models_key(handle),))
    return Path(config.run.records_dir) / f"{name}{tag}_{key}.jsonl"


def _models_key(handle: DatabaseHandle | None) -> str:
    """What names the models of a run: a database folder's name (a hash of its content
    and settings), the closed-form models' repr; empty for None."""
    if handle is None:
        return ""
    return handle.name if isinstance(handle, Path) else repr(handle)


def _shown(path: Path) -> str:
    """``path`` as a report shows it: from the project's root when inside it."""
    path = Path(path).resolve()
    root = RUNS_DIR.parent
    return str(path.relative_to(root) if path.is_relative_to(root) else path)


def _run_info(config: BenchmarkConfig, started: str) -> RunInfo:
    return RunInfo(config.report.command, started, config.run.workers, config.run.backend)


def _write_report(config: BenchmarkConfig, file_name: str, text: str, echo: Echo) -> None:
    out = Path(config.report.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / file_name).write_text(text)
    echo(text)


def _calibration(config: BenchmarkConfig, stem: str, records: Sequence[Record]) -> str:
    """The belief's reliability (after the curves and after the touches) as
    ``<stem>_reliability`` .json and .png beside the report; returns the report's
    section ("" when no record carries a confidence)."""
    answers = [r for r in records if r.confidence is not None]
    if not answers:
        return ""
    out = Path(config.report.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    payload: dict[str, Any] = {
        "command": config.report.command,
        "after_curves": reliability(answers),
    }
    if any(r.touches is not None for r in answers):
        payload["after_touches"] = reliability(answers, after_touches=True)
        payload["touches"] = touch_summary(answers)
    write_json_atomic(out / f"{stem}_reliability.json", payload)
    figure = out / f"{stem}_reliability.png"
    reliability_figure(answers, figure)
    return "\n" + touches_section(answers, figure.name)


def check_config(config: BenchmarkConfig) -> None:
    """Checks a run's settings before any work: makes every instance source the run uses
    (they check their settings) and reads the records file given (``config.run.results``).

    Raises
    ------
    RecognitionError
        Synthetic settings that make no instance (e.g. sampling planes that coincide), or
        a records file with a line that is not a record (``InvalidRecords``).
    SimulationError
        Simulated sessions' settings out of range (``InvalidSettings``, e.g. sweeps longer
        than the largest object).
    """
    if config.source == "sim":
        for experiment in config.sim.experiments:
            if experiment != "sensing":
                _sim_source(config, experiment)
    elif config.sweep and config.sweep != "database-size":
        _sweep_points(config)
    else:
        config.synthetic.source()
    if config.run.results is not None:
        read_results(config.run.results)


def run(config: BenchmarkConfig, *, echo: Echo = print) -> dict[str, Any]:
    """Run the benchmark of ``config``; write records, reports and the summary JSON.

    Returns
    -------
    dict
        The JSON summary: per method (and ``sensing``), or a sweep's points.
    """
    check_config(config)
    if config.source == "sim":
        return run_sim(config, echo=echo)
    started = time.strftime("%Y-%m-%d %H:%M")
    if config.sweep == "database-size":
        return run_size_sweep(config, started, echo=echo)
    database, name = benchmark_database(config.meshes, config.synthetic.database_size)
    if config.sweep:
        return run_sweep(config, database, name, started, echo=echo)
    return run_synthetic(config, database, name, started, echo=echo)


def run_synthetic(
    config: BenchmarkConfig, database: ModelDatabase, name: str, started: str, *, echo: Echo = print
) -> dict[str, Any]:
    """Synthetic instances on ``database`` recognised with every method (thesis 4.3.4);
    writes ``<name><tag>.md``; returns the summary per method."""
    syn, methods = config.synthetic, config.methods
    source = syn.source()
    path = _results_path(config, name, source, methods.config(), "", _directory(database))
    specs = (
        instance_specs(database, source)
        if syn.database_size is None
        else sized_specs(database, source, syn.per_generated)
    )
    jobs = plan_jobs(
        specs,
        source,
        methods.configs(),
        methods.thesis_instances,
        methods.touches,
        _directory(database),
    )
    records = _records(config, _directory(database), jobs, path)
    summary = summarize(records)
    payload = summary_json(summary)
    if config.report.json_path:
        write_json_atomic(config.report.json_path, payload)
    each = "model"
    if syn.database_size is not None:
        each = f"catalog model and {syn.per_generated} per generated model"
    settings = (
        f"Instances: {syn.per_model} per {each}, n = {syn.n_points} points per curve at "
        f"d = {syn.spacing_mm} mm (l = {(syn.n_points - 1) * syn.spacing_mm:g} mm), "
        f"planes {syn.plane_angle_deg:g} deg apart, noise sigma {syn.noise_mm} mm, "
        f"delta = {methods.delta_per_mm} 1/mm. Thesis mode on the first "
        f"{methods.thesis_instances or 'all'} instances. Records: `{_shown(path)}`."
    )
    text = catalog_report(name, _run_info(config, started), settings, database, records, summary)
    text += _calibration(config, f"{name}{config.report.tag}", records)
    _write_report(config, f"{name}{config.report.tag}.md", text, echo)
    return payload


def run_sweep(
    config: BenchmarkConfig, database: ModelDatabase, name: str, started: str, *, echo: Echo = print
) -> dict[str, Any]:
    """Fast-mode success and time against one setting (``config.sweep``: thesis Figs.
    4.11-4.13); writes ``sweep_<name>`` .json, .png and .md; returns the JSON payload."""
    if config.sweep is None:
        raise ValueError("run_sweep needs config.sweep")
    sweep = SWEEPS[config.sweep]
    syn, methods = config.synthetic, config.methods
    results: dict[float, MethodSummary] = {}
    for value, source, registration in _sweep_points(config):
        path = _results_path(
            config, name, source, registration, f"_sweep_{config.sweep}", _directory(database)
        )
        jobs = plan_jobs(
            instance_specs(database, source),
            source,
            {"fast": registration},
            methods.thesis_instances,
            models=_directory(database),
        )
        records = _records(config, _directory(database), jobs, path)
        results[value] = summarize(records)["fast"]
    stem = f"sweep_{config.sweep}"
    settings = (
        f"Instances: {syn.per_model} per model; unless swept, n = {syn.n_points} "
        f"points per curve at d = {syn.spacing_mm} mm, planes "
        f"{syn.plane_angle_deg:g} deg apart, noise sigma {syn.noise_mm} mm, "
        f"delta = {methods.delta_per_mm} 1/mm. Values: `{stem}.json`."
    )
    return _write_sweep(config, sweep, stem, name, started, results, settings, echo=echo)


def _write_sweep(
    config: BenchmarkConfig,
    sweep: Sweep,
    stem: str,
    name: str,
    started: str,
    results: Mapping[float, MethodSummary],
    settings: str,
    *,
    extras: Mapping[float, dict[str, Any]] | None = None,
    appendix: str = "",
    echo: Echo = print,
) -> dict[str, Any]:
    """Writes a sweep's ``<stem>`` .json (each point with its ``extras``), .png and .md
    (``appendix`` after the table); returns the JSON payload."""
    payload = {
        "parameter": sweep.parameter,
        "figure": sweep.figure,
        "date": started,
        "machine": machine(),
        "points": [
            {"value": v, **s.to_json(), **(extras or {}).get(v, {})} for v, s in results.items()
        ],
    }
    out = Path(config.report.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out / f"{stem}.json", payload)
    sweep_figure(results, sweep.parameter, sweep.figure, out / f"{stem}.png")
    text = sweep_report(
        sweep.parameter,
        sweep.figure,
        name,
        _run_info(config, started),
        settings,
        results,
        f"{stem}.png",
        sweep.thesis,
    )
    _write_report(config, f"{stem}.md", text + appendix, echo)
    return payload


def run_size_sweep(config: BenchmarkConfig, started: str, *, echo: Echo = print) -> dict[str, Any]:
    """Fast-mode success, time and memory against the database's size (the catalog's
    models, then generated ones): ``per_model`` instances on each catalog model and
    ``per_generated`` on each generated one, the same instances at every size; writes
    ``sweep_database_size<tag>`` .json, .png and .md; returns the JSON payload."""
    sweep = SWEEPS["database-size"]
    syn, methods = config.synthetic, config.methods
    source = syn.source()
    registration = methods.config("fast")
    results: dict[float, MethodSummary] = {}
    footprints: dict[int, dict[str, Any]] = {}
    for value in sweep.values:
        size = int(value)
        database, name = benchmark_database(config.meshes, size)
        handle = _directory(database)
        path = _results_path(config, name, source, registration, "_sweep", handle)
        specs = sized_specs(database, source, syn.per_generated)
        jobs = plan_jobs(
            specs, source, {"fast": registration}, methods.thesis_instances, models=handle
        )
        results[value] = summarize(_records(config, handle, jobs, path))["fast"]
        footprints[size] = database_footprint(handle)
        del database
    stem = f"sweep_database_size{config.report.tag}"
    settings = (
        f"Instances: {syn.per_model} per catalog model and {syn.per_generated} per generated "
        f"model (the same at every size), n = {syn.n_points} points per curve at d = "
        f"{syn.spacing_mm} mm, planes {syn.plane_angle_deg:g} deg apart, noise sigma "
        f"{syn.noise_mm} mm, delta = {methods.delta_per_mm} 1/mm. Values: `{stem}.json`."
    )
    return _write_sweep(
        config,
        sweep,
        stem,
        "catalog and generated models",
        started,
        results,
        settings,
        extras={float(n): {"footprint": f} for n, f in footprints.items()},
        appendix="\n## Load time, memory and build time\n\n" + footprint_table(footprints) + "\n",
        echo=echo,
    )


def _sweep_points(
    config: BenchmarkConfig,
) -> list[tuple[float, SyntheticSource, RegistrationConfig]]:
    """Each value of the configured sweep, with the instance source and the registration
    it is run with."""
    if config.sweep is None:
        raise ValueError("a sweep's points need config.sweep")
    sweep = SWEEPS[config.sweep]
    syn, methods = config.synthetic, config.methods
    points = []
    for value in sweep.values:
        n_points = plane_angle_deg = delta_per_mm = None
        if sweep.parameter == "length_mm":
            n_points = round(value / syn.spacing_mm) + 1
        elif sweep.parameter == "plane_angle_deg":
            plane_angle_deg = value
        else:
            delta_per_mm = value
        try:
            source = syn.source(n_points=n_points, plane_angle_deg=plane_angle_deg)
        except InvalidCurveData as exc:
            raise InvalidCurveData(f"the {config.sweep} sweep at {value:g}: {exc}") from exc
        points.append((value, source, methods.config("fast", delta_per_mm)))
    return points


def _sim_source(config: BenchmarkConfig, experiment: str) -> SimulatedSource | None:
    """The experiment's probing settings with the configured overrides (None: none of
    its objects is to be probed)."""
    sim = config.sim
    make = catalog_experiment if experiment == "catalog" else solids_experiment
    source = make(
        sessions_per_object=sim.sessions,
        first_session=sim.first_session,
        curves=sim.curves,
        seed=sim.seed,
        model_error_m=sim.model_error_mm * 1e-3,
    )
    if sim.spacing_mm is not None:
        source = replace(source, spacing_m=sim.spacing_mm * 1e-3)
    meshes = config.meshes
    if experiment == "catalog" and meshes.mesh_dir is not None:
        files = tuple((p.stem, str(p)) for p in mesh_files(Path(meshes.mesh_dir)))
        names = tuple(n for n, _ in files)
        others = source.objects if meshes.with_catalog else ()
        source = replace(source, objects=(*others, *names), meshes=files, units=meshes.units)
    if sim.objects is not None:
        kept = tuple(o for o in source.objects if o in sim.objects)
        if not kept:
            return None
        source = replace(source, objects=kept)
    return source


def run_sim(config: BenchmarkConfig, *, echo: Echo = print) -> dict[str, Any]:
    """The simulated robot experiments (thesis Section 4.4); returns the summary per method
    (and ``sensing``).

    "catalog": every catalog object probed ``sessions`` times, recognised against the
    catalog database with every method (Tables 4.6-4.7 analogue). "solids": the four
    solids of Fig. 4.15 probed ``sessions`` times, recognised against their closed-form
    models (Table 4.5 analogue, method ``closed-form``). "sensing": :func:`run_sensing`.
    """
    from tactile_sim.objects import object_names

    mesh_names = (
        tuple(p.stem for p in mesh_files(Path(config.meshes.mesh_dir)))
        if config.meshes.mesh_dir is not None
        else ()
    )
    known = (*object_names(), *FIG_4_15_SOLIDS, *mesh_names)
    for name in config.sim.objects or ():
        if name not in known:
            raise UnknownObject(name, known)
    started = time.strftime("%Y-%m-%d %H:%M")
    summary: dict[str, Any] = {}
    tag = config.report.tag
    for experiment in config.sim.experiments:
        if experiment == "sensing":
            summary["sensing"] = run_sensing(config, started, echo=echo)
            continue
        source = _sim_source(config, experiment)
        if source is None:
            continue
        handle: DatabaseHandle
        if experiment == "catalog":
            database, _ = benchmark_database(config.meshes)
            handle, names = _directory(database), database.names
            registration = config.methods.config()
            configs = config.methods.configs()
        else:
            models = ClosedFormModels()
            handle, names = models, models.names
            registration = SolidExperiment().config()
            configs = {registration.mode.value: registration}
        name = f"sim_{experiment}"
        path = _results_path(config, name, source, registration, tag, handle)
        jobs = plan_jobs(
            source.specs(None),
            source,
            configs,
            config.methods.thesis_instances,
            config.methods.touches if experiment == "catalog" else 0,
            handle,
        )
        records = _records(config, handle, jobs, path)
        found = summarize(records)
        summary |= summary_json(found)
        out = Path(config.report.out_dir)
        out.mkdir(parents=True, exist_ok=True)
        figure = out / f"{name}{tag}.png"
        run_info = _run_info(config, started)
        if experiment == "catalog":
            text = catalog_sessions_report(
                run_info,
                source,
                names,
                records,
                found,
                _shown(path),
                delta_per_mm=config.methods.delta_per_mm,
                thesis_instances=config.methods.thesis_instances,
            )
            catalog_sessions_figure(records, names, figure)
        else:
            text = solids_report(
                run_info, source, names, records, found, _shown(path), SolidExperiment()
            )
            solids_figure(records, names, figure)
        text += f"\n![{name}]({figure.name})\n"
        text += _calibration(config, f"{name}{tag}", records)
        _write_report(config, f"{name}{tag}.md", text, echo)
    if config.report.json_path:
        write_json_atomic(config.report.json_path, summary)
    return summary


def run_sensing(config: BenchmarkConfig, started: str, *, echo: Echo = print) -> dict[str, Any]:
    """Sensed points against the original meshes; warm wall times of a session and of
    ``scripts/probe.py`` (a fresh process, as a user runs it; the first run warms the
    caches). Writes ``sim_sensing<tag>.md``; returns the figures (millimetres, seconds)."""
    sim = config.sim
    objects = sim.objects or SENSING_OBJECTS
    accuracy = sensing_accuracy(objects, sessions_per_object=sim.sessions, seed=sim.seed)
    timed = TIMED_OBJECT if TIMED_OBJECT in objects else objects[0]
    timing = session_timing(timed, repeats=3, seed=sim.seed)
    walls = probe_script_seconds(timed, runs=4, seed=sim.seed)
    figures = accuracy.summary() | {
        "session_object": timed,
        "session_build_s": list(timing.build_seconds),
        "session_probe_s": list(timing.probe_seconds),
        "session_total_s": list(timing.session_seconds),
        "session_sim_s": list(timing.sim_seconds),
        "probe_script_cold_or_first_s": walls[0],
        "probe_script_warm_s": walls[1:],
    }
    text = sensing_report(
        _run_info(config, started), objects, sim.sessions, sim.seed, accuracy, timing, walls
    )
    _write_report(config, f"sim_sensing{config.report.tag}.md", text, echo)
    return figures
