"""The benchmark runner: what is not yet done, run here, in a process pool or on Ray, and resumed.

A job is one instance and the methods to recognise it with; records, one per instance
and method, are appended to a JSONL file as they finish and a restarted run skips what
is done.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path

from recognition.evaluation.jobs import Job, run_job
from recognition.evaluation.models import DatabaseHandle, load_database
from recognition.evaluation.ray_backend import run_on_ray
from recognition.evaluation.records import Record, read_results
from recognition.evaluation.workers import worker_init, worker_run
from recognition.pools import completed, process_pool

__all__ = ["BACKENDS", "run"]

#: Where jobs run: this process or a local process pool ("local"), or Ray actors.
BACKENDS = ("local", "ray")


def _drop_partial_line(path: Path) -> None:
    """Cut a last line left unfinished by a killed run, so that appends start a line."""
    if not path.exists():
        return
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        with path.open("r+b") as f:
            f.truncate(data.rfind(b"\n") + 1)


def _todo(jobs: Sequence[Job], done: set[tuple[str, str, str | None]]) -> tuple[list[Job], int]:
    """The jobs with only their methods not yet done, and the number of records wanted."""
    todo, total = [], 0
    for job in jobs:
        missing = tuple(
            c for c in job.configs if (job.spec.key, c.mode.value, job.settings(c)) not in done
        )
        total += len(job.configs)
        if missing:
            todo.append(replace(job, configs=missing))
    return todo, total


def run(
    database: DatabaseHandle,
    jobs: Sequence[Job],
    results_path: Path | str,
    *,
    workers: int = 1,
    backend: str = "local",
    progress: bool = True,
    ray_address: str | None = None,
    on_record: Callable[[Record], None] | None = None,
) -> list[Record]:
    """Run what is not yet in ``results_path``; append records to it as they finish.

    Parameters
    ----------
    database : path or ClosedFormModels
        A :class:`~recognition.surfaces.database.ModelDatabase` directory (every worker
        loads it) or the closed-form models.
    jobs : sequence of Job
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
    list of Record
        Every record in ``results_path`` (earlier runs' included).
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend must be 'local' or 'ray', got {backend!r}")
    results_path = Path(results_path)
    results_path.parent.mkdir(parents=True, exist_ok=True)
    _drop_partial_line(results_path)
    done = {(r.instance, r.method, r.settings) for r in read_results(results_path)}
    todo, total = _todo(jobs, done)
    bar = None
    if progress:
        from tqdm import tqdm

        pending = sum(len(job.configs) for job in todo)
        bar = tqdm(total=total, initial=total - pending, unit="record", desc="benchmark")

    def record(job: Job, records: list[Record]) -> None:
        stamped = [
            rec.with_settings(job.settings(config))
            for rec, config in zip(records, job.configs, strict=True)
        ]
        with results_path.open("a") as f:
            for rec in stamped:
                f.write(rec.dumps() + "\n")
            f.flush()
            os.fsync(f.fileno())
        for rec in stamped:
            if on_record:
                on_record(rec)
            if bar:
                bar.update(1)

    try:
        if backend == "ray":
            run_on_ray(database, todo, record, workers, ray_address)
        elif workers <= 1 or len(todo) <= 1:
            db = load_database(database)
            for job in todo:
                record(job, run_job(db, job))
        else:
            _run_pool(database, todo, record, workers)
    except KeyboardInterrupt:
        if bar:
            bar.leave = False  # the caller reports the interrupt on the bar's line
        raise
    finally:
        if bar:
            bar.close()
    return read_results(results_path)


def _run_pool(
    database: DatabaseHandle,
    todo: list[Job],
    record: Callable[[Job, list[Record]], None],
    workers: int,
) -> None:
    """``todo`` in a local pool of ``workers`` processes, each holding the database; an
    interrupt or an error ends the workers at once."""
    with process_pool(min(workers, len(todo)), worker_init, (database,)) as pool:
        futures = {pool.submit(worker_run, job): job for job in todo}
        for future in completed(futures):
            record(futures[future], future.result())
