"""The state of a benchmark worker process or actor: its database, loaded once."""

from __future__ import annotations

from recognition.evaluation.jobs import Job, run_job
from recognition.evaluation.models import Database, DatabaseHandle, load_database
from recognition.evaluation.records import Record

__all__ = ["worker_init", "worker_run"]

_WORKER_DB: Database | None = None


def worker_init(handle: DatabaseHandle) -> None:
    """Load the database this worker recognises against."""
    global _WORKER_DB
    _WORKER_DB = load_database(handle)


def worker_run(job: Job) -> list[Record]:
    """The job's records, against the database of :func:`worker_init`."""
    if _WORKER_DB is None:
        raise RuntimeError("worker_init was not called in this worker")
    return run_job(_WORKER_DB, job)
