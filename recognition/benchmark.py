"""Recognition benchmark over a model database (thesis Section 4.3.4, Tables 4.6-4.7).

Instances are drawn per model: well-separated vertices (no two within ``separation_m``),
three sampling planes containing the vertex normal ``plane_angle_deg`` apart, ``n_points``
per curve at ``spacing_m``, Gaussian noise, a random rigid motion. An instance is fully
determined by (model, index, settings, seed), so any worker can regenerate it; results
are appended to a JSONL file as they finish and a restarted run skips what is done.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from recognition.errors import RecognitionError
from recognition.surfaces.database import ModelDatabase
from recognition.surfaces.registration import RegistrationConfig
from recognition.synthetic import mesh_data_curves

__all__ = [
    "InstanceSpec",
    "SyntheticSource",
    "instance_specs",
    "read_results",
    "run_instance",
    "summarize",
]


@dataclass(frozen=True)
class SyntheticSource:
    """How synthetic instances are made (thesis Section 4.3.4 defaults).

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

    @property
    def length_m(self) -> float:
        return (self.n_points - 1) * self.spacing_m


@dataclass(frozen=True)
class InstanceSpec:
    """One recognition instance: the model, the vertex and its own seed."""

    model: str
    index: int
    vertex: int
    seed: int

    @property
    def key(self) -> str:
        return f"{self.model}/{self.index}"


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


def run_instance(
    database: ModelDatabase,
    spec: InstanceSpec,
    source: SyntheticSource,
    method: str,
    registration: RegistrationConfig,
) -> dict:
    """Recognise one instance with one method; a JSON-ready record."""
    synthetic = make_curves(database, spec, source)
    database.registration = registration
    result = database.recognize(synthetic.curves, mode=method)
    truth = result.registrations[spec.model]
    located = truth.location if np.all(np.isfinite(truth.location)) else None
    return {
        "instance": spec.key,
        "model": spec.model,
        "vertex": spec.vertex,
        "method": method,
        "recognized": result.name,
        "success": result.name == spec.model,
        "localization_error_mm": (
            float(np.linalg.norm(located - synthetic.point_in_model) * 1e3)
            if located is not None
            else None
        ),
        "time_s": result.time_s,
        "errors_mm": {n: (e * 1e3 if np.isfinite(e) else None) for n, e in result.ranking},
        "times_s": result.timings_s,
        "candidates": {n: len(r.candidates) for n, r in result.registrations.items()},
        "k1": result.geometry.k1,
        "k2": result.geometry.k2,
    }


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


def summarize(records: Iterable[dict]) -> dict[str, dict]:
    """Per method: success rate, median/p90 time, median localisation error, instances."""
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
    return out


# --- execution backends ---------------------------------------------------------------

_WORKER_DB: ModelDatabase | None = None


def _worker_init(database_dir: str) -> None:
    global _WORKER_DB
    _WORKER_DB = ModelDatabase.load(database_dir)


def _worker_run(args) -> dict:
    spec, source, method, registration = args
    return run_instance(_WORKER_DB, spec, source, method, registration)


def settings_key(source: SyntheticSource, registration: RegistrationConfig, extra=()) -> str:
    """Short hash of everything a result depends on (used to resume safely)."""
    payload = json.dumps([asdict(source), asdict(registration), list(extra)], sort_keys=True)
    return hashlib.sha256(payload.encode()).hexdigest()[:12]


def run(
    database_dir: Path,
    jobs: list[tuple[InstanceSpec, SyntheticSource, str, RegistrationConfig]],
    results_path: Path,
    *,
    workers: int = 1,
    backend: str = "local",
    progress: bool = True,
    ray_address: str | None = None,
    on_record: Callable[[dict], None] | None = None,
) -> list[dict]:
    """Run jobs not yet in ``results_path`` and append their records to it as they finish.

    Records carry a ``settings`` hash; a job counts as done when a record with the same
    instance, method and settings exists.
    """
    results_path = Path(results_path)
    results_path.parent.mkdir(parents=True, exist_ok=True)
    done = {(r["instance"], r["method"], r.get("settings")) for r in read_results(results_path)}

    def tag(job):
        spec, source, method, registration = job
        return (spec.key, method, settings_key(source, registration))

    todo = [job for job in jobs if tag(job) not in done]
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(
            total=len(jobs), initial=len(jobs) - len(todo), unit="instance", desc="benchmark"
        )
    new = []

    def record(job, rec):
        rec["settings"] = tag(job)[2]
        with results_path.open("a") as f:
            f.write(json.dumps(rec) + "\n")
            f.flush()
            os.fsync(f.fileno())
        new.append(rec)
        if on_record:
            on_record(rec)
        if bar:
            bar.update(1)

    if backend == "ray":
        _run_ray(database_dir, todo, record, workers, ray_address)
    elif workers <= 1:
        _worker_init(str(database_dir))
        for job in todo:
            record(job, _worker_run(job))
    else:
        from concurrent.futures import ProcessPoolExecutor, as_completed

        with ProcessPoolExecutor(
            workers, initializer=_worker_init, initargs=(str(database_dir),)
        ) as pool:
            futures = {pool.submit(_worker_run, job): job for job in todo}
            for future in as_completed(futures):
                record(futures[future], future.result())
    if bar:
        bar.close()
    return read_results(results_path)


def _run_ray(database_dir, todo, record, workers, address) -> None:
    import ray

    if not ray.is_initialized():
        ray.init(
            address=address,
            num_cpus=None if address else workers,
            include_dashboard=False,
            log_to_driver=False,
        )

    @ray.remote
    class Worker:
        def __init__(self, directory):
            _worker_init(directory)

        def run(self, job):
            return _worker_run(job)

    actors = [Worker.remote(str(database_dir)) for _ in range(max(workers, 1))]
    pending = {}
    queue = list(todo)
    for actor in actors:
        if queue:
            job = queue.pop(0)
            pending[actor.run.remote(job)] = (actor, job)
    while pending:
        ready, _ = ray.wait(list(pending), num_returns=1)
        actor, job = pending.pop(ready[0])
        record(job, ray.get(ready[0]))
        if queue:
            nxt = queue.pop(0)
            pending[actor.run.remote(nxt)] = (actor, nxt)
