"""Benchmark jobs on Ray actors, each holding the database (imports ray when called)."""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

from recognition.evaluation.jobs import Job
from recognition.evaluation.models import DatabaseHandle
from recognition.evaluation.records import Record
from recognition.evaluation.workers import worker_init, worker_run

__all__ = ["run_on_ray"]


class _Worker:
    """A Ray actor holding the database."""

    def __init__(self, handle: DatabaseHandle) -> None:
        worker_init(handle)

    def run(self, job: Job) -> list[Record]:
        return worker_run(job)


def run_on_ray(
    handle: DatabaseHandle,
    todo: list[Job],
    record: Callable[[Job, list[Record]], None],
    workers: int,
    address: str | None,
) -> None:
    """Run ``todo`` on ``workers`` Ray actors; ``record`` gets each job's records.

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

    worker = ray.remote(num_cpus=1)(_Worker)
    # ray's stubs do not type actor methods' .remote
    actors: list[Any] = [worker.remote(handle) for _ in range(max(1, min(workers, len(todo))))]
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
