"""Recognition benchmark over a model database (thesis Sections 4.3.4 and 4.4, Tables 4.5-4.7).

An instance is named by an :class:`InstanceSpec` (model, index, seed) and made from it by
a *source*: any object with

- ``specs(database) -> list[InstanceSpec]``: the instances of the benchmark;
- ``instance(database, spec) -> Instance``: the data curves and the ground truth of one,
  regenerated from the spec alone (so any worker can make it);

and a frozen dataclass of settings (hashed, with the registration settings, into the
``settings`` of every record). Specs and instances need only the fields of
:class:`InstanceSpec` and :class:`Instance` (a source may use its own classes).
:class:`SyntheticSource` samples curves on the models themselves (Section 4.3.4);
``tactile_sim.experiments.SimulatedSource`` has the simulated robot probe the objects
(Section 4.4).

The database is a :class:`~recognition.surfaces.database.ModelDatabase` directory (the
methods ``fast``, ``thesis``, ``icp-baseline``) or :class:`ClosedFormModels` (the method
``closed-form``). A job is one instance and the methods to recognise it with; records,
one per instance and method, are appended to a JSONL file as they finish and a restarted
run skips what is done. Jobs run in this process, a local process pool or on Ray.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from recognition.errors import DegenerateGeometry, InvalidCurveData, RecognitionError
from recognition.surfaces import closed_form as cf
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.database import ModelDatabase
from recognition.surfaces.registration import RegistrationConfig, recognize
from recognition.synthetic import mesh_data_curves, sampling_plane_normals

__all__ = [
    "CLOSED_FORM_METHOD",
    "TIMING_FIELDS",
    "ClosedFormModels",
    "Instance",
    "InstanceSource",
    "InstanceSpec",
    "Job",
    "SyntheticSource",
    "comparable",
    "instance_specs",
    "make_curves",
    "read_results",
    "run",
    "run_instance",
    "run_job",
    "settings_key",
    "summarize",
]

#: Method name of the registration onto closed-form models (thesis Section 4.2.2).
CLOSED_FORM_METHOD = "closed-form"

#: Record fields that hold wall times (they differ between runs of the same instance).
TIMING_FIELDS = ("time_s", "times_s", "instance_time_s", "probe_time_s")


@dataclass(frozen=True)
class InstanceSpec:
    """One recognition instance: the model (object), its index and its own seed.

    Attributes
    ----------
    model : str
        The true model's name.
    index : int
        Instance number of this model.
    vertex : int or None
        The model vertex the curves meet at (synthetic instances); None when the source
        chooses the point itself (simulated probing).
    seed : int
        Seeds everything random in making the instance.
    """

    model: str
    index: int
    vertex: int | None
    seed: int

    @property
    def key(self) -> str:
        return f"{self.model}/{self.index}"


@dataclass(frozen=True)
class Instance:
    """The data of one instance, as a source makes it.

    Attributes
    ----------
    curves : DataCurves or None
        The three data curves, metres; None when the instance could not be made (then
        ``info["error"]`` says why, and the instance counts as a failure).
    point_in_model : (3,) float or None, metres
        The true common point p in the model frame (None: no localisation error).
    info : Mapping[str, Any]
        JSON-ready facts about the instance, copied into every record (``*_mm``, ``*_s``).
    reference_curves : DataCurves or None
        The same instance without measurement error (e.g. the simulator's true contact
        points); recognised too, as a diagnosis, when given.
    """

    curves: DataCurves | None
    point_in_model: np.ndarray | None = None
    info: Mapping[str, Any] = field(default_factory=dict)
    reference_curves: DataCurves | None = None


class InstanceSource(Protocol):
    """What the runner needs of a source of instances (a frozen dataclass)."""

    def specs(self, database) -> list[InstanceSpec]: ...

    def instance(self, database, spec: InstanceSpec) -> Instance: ...


@dataclass(frozen=True)
class SyntheticSource:
    """How synthetic instances are made (thesis Section 4.3.4 defaults).

    Instances are drawn per model: well-separated vertices (no two within
    ``separation_m``), three sampling planes containing the vertex normal
    ``plane_angle_deg`` apart, ``n_points`` per curve at ``spacing_m``, Gaussian noise, a
    random rigid motion.

    Attributes
    ----------
    per_model : int
        Instances per model (thesis: 10).
    n_points : int
        Points per curve (thesis: 81).
    spacing_m : float
        Arc length between points (thesis: 0.3 mm), so l = (n - 1) d = 24 mm.
    plane_angle_deg : float
        Angle between consecutive sampling planes (thesis: 60).
    noise_std_m : float
        Gaussian noise per coordinate.
    separation_m : float
        Smallest distance between two instance vertices of one model.
    seed : int
    """

    per_model: int = 10
    n_points: int = 81
    spacing_m: float = 0.3e-3
    plane_angle_deg: float = 60.0
    noise_std_m: float = 0.02e-3
    separation_m: float = 10e-3
    seed: int = 0

    def __post_init__(self) -> None:
        # planes that coincide would make every instance invalid: say so once, here
        sampling_plane_normals([0.0, 0.0, 1.0], plane_angle_rad=np.deg2rad(self.plane_angle_deg))
        if self.n_points < 5 or not self.spacing_m > 0 or self.per_model < 1:
            raise InvalidCurveData(
                f"expected at least 5 points per curve, a positive spacing and at least one "
                f"instance per model; got n_points={self.n_points}, "
                f"spacing_m={self.spacing_m}, per_model={self.per_model}"
            )

    @property
    def length_m(self) -> float:
        return (self.n_points - 1) * self.spacing_m

    def specs(self, database: ModelDatabase) -> list[InstanceSpec]:
        """See :func:`instance_specs`."""
        return instance_specs(database, self)

    def instance(self, database: ModelDatabase, spec: InstanceSpec) -> Instance:
        """The sampled curves (noisy, moved) and p on the model."""
        synthetic = make_curves(database, spec, self)
        return Instance(synthetic.curves, np.asarray(synthetic.point_in_model))


@dataclass(frozen=True)
class ClosedFormModels:
    """The closed-form models of the four solids of thesis Fig. 4.15, as a database.

    Built (tables of Section 4.2.1) in every worker that needs them.

    Attributes
    ----------
    half_length_m : float, metres
        The cylinders are tabulated over |z| <= this.
    n_u, n_v : int
        Lookup-table grid.
    """

    half_length_m: float = 0.05
    n_u: int = 200
    n_v: int = 100

    @property
    def names(self) -> list[str]:
        return [s.name for s in cf.fig_4_15_solids(self.half_length_m)]

    def load(self) -> tuple[cf.ClosedFormModel, ...]:
        return _closed_form_models(self)


@functools.lru_cache(maxsize=2)
def _closed_form_models(spec: ClosedFormModels) -> tuple[cf.ClosedFormModel, ...]:
    return tuple(
        cf.ClosedFormModel.build(s, spec.n_u, spec.n_v)
        for s in cf.fig_4_15_solids(spec.half_length_m)
    )


def _rng(*key) -> np.random.Generator:
    digest = hashlib.sha256(repr(key).encode()).digest()
    return np.random.default_rng(int.from_bytes(digest[:8], "little"))


def instance_specs(database: ModelDatabase, source: SyntheticSource) -> list[InstanceSpec]:
    """``per_model`` well-separated vertices per model whose three curves can be sampled.

    Vertices are drawn in a seeded order; one is taken when it is at least
    ``separation_m`` from those already taken and its three sections are long enough.
    """
    specs = []
    for name, model in database.models.items():
        rng = _rng("vertices", name, source.seed)
        order = rng.permutation(len(model.vertices))
        chosen: list[int] = []
        for v in order:
            if len(chosen) == source.per_model:
                break
            x = model.vertices[v]
            if chosen and np.min(np.linalg.norm(model.vertices[chosen] - x, axis=1)) < (
                source.separation_m
            ):
                continue
            spec = InstanceSpec(name, len(chosen), int(v), int(rng.integers(2**31)))
            try:
                make_curves(database, spec, source)
            except RecognitionError:
                continue
            chosen.append(int(v))
            specs.append(spec)
    return specs


def make_curves(database: ModelDatabase, spec: InstanceSpec, source: SyntheticSource):
    """The instance's data curves and ground truth (a ``SyntheticCurves``)."""
    model = database[spec.model]
    return mesh_data_curves(
        model.mesh,
        spec.vertex,
        normal=model.normals[spec.vertex],
        n_points=source.n_points,
        spacing_m=source.spacing_m,
        plane_angle_deg=source.plane_angle_deg,
        noise_std_m=source.noise_std_m,
        rng=np.random.default_rng(spec.seed),
    )


# --- recognition of one instance --------------------------------------------------------


def _mm(value: float) -> float | None:
    return float(value) * 1e3 if np.isfinite(value) else None


def _located_error_mm(location, point_in_model) -> float | None:
    if point_in_model is None or location is None or not np.all(np.isfinite(location)):
        return None
    return float(np.linalg.norm(np.asarray(location) - point_in_model) * 1e3)


def _recognize(database, curves: DataCurves, true_model: str, config: RegistrationConfig):
    """Recognition of ``curves`` with one method: the record's recognition fields, and the
    true model's estimate of p (model frame, or None).

    Curves whose local geometry cannot be computed (e.g. two sampling planes that
    coincide) are not recognised: the record says why (``error``) and counts as a failure.
    """
    start = time.perf_counter()
    try:
        return _recognize_or_raise(database, curves, true_model, config)
    except (InvalidCurveData, DegenerateGeometry) as exc:
        return {
            "recognized": None,
            "success": False,
            "time_s": time.perf_counter() - start,
            "errors_mm": {},
            "times_s": {},
            "error": f"{type(exc).__name__}: {exc}",
        }, None


def _recognize_or_raise(database, curves, true_model, config: RegistrationConfig):
    if isinstance(database, ModelDatabase):
        result = database.recognize(curves, config)
        truth = result.registrations.get(true_model)
        return {
            "recognized": result.name,
            "success": result.name == true_model,
            "time_s": result.time_s,
            "errors_mm": {n: _mm(e) for n, e in result.ranking},
            "times_s": result.timings_s,
            "candidates": {n: len(r.candidates) for n, r in result.registrations.items()},
            "k1": result.geometry.k1,
            "k2": result.geometry.k2,
        }, (None if truth is None else truth.location)
    # thesis Eq. (4.9) over the closed-form models
    result = recognize(database, curves, config)
    # The solids are symmetric (thesis Section 4.4.2): no location is compared.
    return {
        "recognized": result.name,
        "success": result.name == true_model,
        "time_s": result.time_s,
        "errors_mm": {n: _mm(e) for n, e in result.ranking},
        "times_s": result.timings_s,
        "candidates": {n: int(r.candidates.shape[0]) for n, r in result.registrations.items()},
        "k1": float(result.geometry.k1),
        "k2": float(result.geometry.k2),
    }, None


def run_job(database, job: Job) -> list[dict]:
    """Make the job's instance once and recognise it with each of its methods.

    Returns
    -------
    list of dict
        One JSON-ready record per method, in the order of ``job.methods``.
    """
    spec = job.spec
    start = time.perf_counter()
    instance = job.source.instance(database, spec)
    made_s = time.perf_counter() - start
    base = {
        "instance": spec.key,
        "model": spec.model,
        "index": spec.index,
        "vertex": spec.vertex,
        "seed": spec.seed,
        **dict(instance.info),
        "instance_time_s": made_s,
    }
    records = []
    for config in job.configs:
        record = {**base, "method": config.mode.value}
        if instance.curves is None:
            record |= {
                "recognized": None,
                "success": False,
                "time_s": 0.0,
                "errors_mm": {},
                "times_s": {},
                "localization_error_mm": None,
            }
            records.append(record)
            continue
        fields, location = _recognize(database, instance.curves, spec.model, config)
        record |= fields
        record["localization_error_mm"] = _located_error_mm(location, instance.point_in_model)
        if instance.reference_curves is not None:
            ref, ref_location = _recognize(database, instance.reference_curves, spec.model, config)
            record["reference"] = {
                "recognized": ref["recognized"],
                "success": ref["success"],
                "errors_mm": ref["errors_mm"],
                "localization_error_mm": _located_error_mm(ref_location, instance.point_in_model),
                **({"error": ref["error"]} if "error" in ref else {}),
            }
        records.append(record)
    return records


def run_instance(
    database,
    spec: InstanceSpec,
    source: InstanceSource,
    config: RegistrationConfig,
) -> dict:
    """Recognise one instance with one method; a JSON-ready record."""
    return run_job(database, Job(spec, source, (config,)))[0]


# --- records ----------------------------------------------------------------------------


def read_results(path: Path) -> list[dict]:
    """Records of a JSONL results file (a truncated last line is ignored)."""
    records = []
    if not Path(path).exists():
        return records
    for line in Path(path).read_text().splitlines():
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return records


def _drop_partial_line(path: Path) -> None:
    """Cut a last line left unfinished by a killed run, so that appends start a line."""
    if not path.exists():
        return
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        with path.open("r+b") as f:
            f.truncate(data.rfind(b"\n") + 1)


def comparable(record: dict) -> dict:
    """The record without its wall times: equal for equal instances, settings and code."""
    return {k: v for k, v in record.items() if k not in TIMING_FIELDS}


def summarize(records: Iterable[dict]) -> dict[str, dict]:
    """Per method: success rate, median/p90 time, median localisation error, instances.

    Records of instances that carry a reference recognition also give
    ``reference_success_rate`` (the same instances without measurement error).
    """
    by_method: dict[str, list[dict]] = {}
    for r in records:
        by_method.setdefault(r["method"], []).append(r)
    out = {}
    for method, rs in by_method.items():
        times = np.array([r["time_s"] for r in rs])
        loc = np.array(
            [r["localization_error_mm"] for r in rs if r["localization_error_mm"] is not None]
        )
        out[method] = {
            "method": method,
            "instances": len(rs),
            "success_rate": float(np.mean([r["success"] for r in rs])),
            "median_time_s": float(np.median(times)),
            "p90_time_s": float(np.percentile(times, 90)),
            "median_localization_error_mm": float(np.median(loc)) if loc.size else None,
        }
        references = [r["reference"]["success"] for r in rs if "reference" in r]
        if references:
            out[method]["reference_success_rate"] = float(np.mean(references))
    return out


# --- execution backends -----------------------------------------------------------------


@dataclass(frozen=True)
class Job:
    """One instance and the methods to recognise it with.

    Attributes
    ----------
    spec : InstanceSpec
    source : InstanceSource
        Makes the instance from ``spec``.
    configs : tuple of RegistrationConfig
        One per method (the config's class names it).
    """

    spec: InstanceSpec
    source: Any
    configs: tuple[RegistrationConfig, ...]

    @property
    def methods(self) -> tuple[str, ...]:
        return tuple(c.mode.value for c in self.configs)

    def settings(self, config: RegistrationConfig) -> str:
        """The settings key of the records made with ``config``."""
        return settings_key(self.source, config)


_WORKER_DB: Any = None


def _load_database(database):
    if isinstance(database, ClosedFormModels):
        return database.load()
    return ModelDatabase.load(database)


def _worker_init(database) -> None:
    global _WORKER_DB
    _WORKER_DB = _load_database(database)


def _worker_run(job: Job) -> list[dict]:
    return run_job(_WORKER_DB, job)


def _source_payload(source) -> dict:
    payload = asdict(source)
    if not isinstance(source, SyntheticSource):
        payload["source"] = f"{type(source).__module__}.{type(source).__qualname__}"
    return payload


def settings_key(source, registration, extra=()) -> str:
    """Short hash of everything a result depends on (used to resume safely).

    The source's fields (and, for sources other than :class:`SyntheticSource`, its
    class), the registration settings and ``extra``.
    """
    payload = json.dumps(
        [_source_payload(source), asdict(registration), list(extra)], sort_keys=True, default=str
    )
    return hashlib.sha256(payload.encode()).hexdigest()[:12]


def _as_job(job) -> Job:
    if isinstance(job, Job):
        return job
    spec, source, config = job
    return Job(spec, source, (config,))


def run(
    database,
    jobs: Sequence[Job | tuple],
    results_path: Path,
    *,
    workers: int = 1,
    backend: str = "local",
    progress: bool = True,
    ray_address: str | None = None,
    on_record: Callable[[dict], None] | None = None,
) -> list[dict]:
    """Run what is not yet in ``results_path``; append records to it as they finish.

    Parameters
    ----------
    database : path or ClosedFormModels
        A :class:`ModelDatabase` directory (every worker loads it) or the closed-form
        models.
    jobs : sequence of Job
        (Tuples ``(spec, source, config)`` are taken as one-method jobs.)
    results_path : Path
        JSONL file of records; created when missing. Every record carries a
        ``settings`` hash; an (instance, method) counts as done when a record with the
        same instance, method and settings is in the file, and a job runs only its
        methods that are not done.
    workers : int
        Processes (local) or actors (Ray); 1 runs in this process.
    backend : {"local", "ray"}
    progress : bool
        A tqdm progress bar over (instance, method) records.
    ray_address : str or None
        An existing Ray cluster (``"auto"``, ``"host:port"``); None starts a local one
        with ``workers`` CPUs unless Ray is already initialised.
    on_record : callable or None
        Called with every new record, after it is written.

    Returns
    -------
    list of dict
        Every record in ``results_path`` (earlier runs' included).
    """
    if backend not in ("local", "ray"):
        raise ValueError(f"backend must be 'local' or 'ray', got {backend!r}")
    results_path = Path(results_path)
    results_path.parent.mkdir(parents=True, exist_ok=True)
    _drop_partial_line(results_path)
    done = {(r["instance"], r["method"], r.get("settings")) for r in read_results(results_path)}
    todo, total = [], 0
    for job in map(_as_job, jobs):
        missing = tuple(
            c for c in job.configs if (job.spec.key, c.mode.value, job.settings(c)) not in done
        )
        total += len(job.configs)
        if missing:
            todo.append(Job(job.spec, job.source, missing))
    bar = None
    if progress:
        from tqdm import tqdm

        pending = sum(len(job.configs) for job in todo)
        bar = tqdm(total=total, initial=total - pending, unit="record", desc="benchmark")

    def record(job: Job, records: list[dict]) -> None:
        with results_path.open("a") as f:
            for rec, config in zip(records, job.configs, strict=True):
                rec["settings"] = job.settings(config)
                f.write(json.dumps(rec) + "\n")
            f.flush()
            os.fsync(f.fileno())
        for rec in records:
            if on_record:
                on_record(rec)
            if bar:
                bar.update(1)

    try:
        if backend == "ray":
            _run_ray(database, todo, record, workers, ray_address)
        elif workers <= 1 or len(todo) <= 1:
            db = _load_database(database)
            for job in todo:
                record(job, run_job(db, job))
        else:
            from concurrent.futures import ProcessPoolExecutor, as_completed

            with ProcessPoolExecutor(
                min(workers, len(todo)), initializer=_worker_init, initargs=(database,)
            ) as pool:
                futures = {pool.submit(_worker_run, job): job for job in todo}
                try:
                    for future in as_completed(futures):
                        record(futures[future], future.result())
                except BaseException:
                    for future in futures:
                        future.cancel()
                    raise
    finally:
        if bar:
            bar.close()
    return read_results(results_path)


def _run_ray(database, todo: list[Job], record, workers: int, address: str | None) -> None:
    """Jobs on Ray actors, each holding the database; ``workers`` actors.

    A local instance (no ``address``) listens on 127.0.0.1 only, unless the environment
    says otherwise (Ray reads ``RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER`` when imported).
    """
    if address is None:
        os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")
    import ray

    if not ray.is_initialized():
        if address:
            ray.init(address=address, log_to_driver=False)
        else:
            ray.init(num_cpus=max(workers, 1), include_dashboard=False, log_to_driver=False)
    if not todo:
        return

    @ray.remote(num_cpus=1)
    class Worker:
        def __init__(self, database):
            _worker_init(database)

        def run(self, job):
            return _worker_run(job)

    actors = [Worker.remote(database) for _ in range(max(1, min(workers, len(todo))))]
    pending = {}
    queue = list(todo)
    for actor in actors:
        if queue:
            job = queue.pop(0)
            pending[actor.run.remote(job)] = (actor, job)
    try:
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            actor, job = pending.pop(ready[0])
            record(job, ray.get(ready[0]))
            if queue:
                nxt = queue.pop(0)
                pending[actor.run.remote(nxt)] = (actor, nxt)
    finally:
        for actor in actors:
            ray.kill(actor)
