"""Benchmark jobs on Ray actors, each holding the database (imports ray when called)."""

from __future__ import annotations

import os
import socket
import threading
from collections.abc import Callable
from typing import Any

from recognition.errors import BackendUnavailable
from recognition.evaluation.jobs import Job
from recognition.evaluation.models import DatabaseHandle
from recognition.evaluation.records import Record
from recognition.evaluation.workers import worker_init, worker_run
from recognition.pools import limit_native_threads

__all__ = ["RAY_CONNECT_TIMEOUT_S", "RAY_INIT_TIMEOUT_S", "check_ray_address", "run_on_ray"]

#: How long an existing cluster's address is given to answer, seconds.
RAY_CONNECT_TIMEOUT_S = 5.0
#: How long joining an existing cluster may take, seconds (Ray itself retries for minutes).
RAY_INIT_TIMEOUT_S = 20.0

#: What an HTTP/2 client sends first; a gRPC server (Ray's GCS, Ray Client) answers with
#: a SETTINGS frame.
_HTTP2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n"
_HTTP2_SETTINGS = 0x4


class _Worker:
    """A Ray actor holding the database."""

    def __init__(self, handle: DatabaseHandle) -> None:
        limit_native_threads(1)  # the actor reserves one CPU (run_on_ray)
        worker_init(handle)

    def run(self, job: Job) -> list[Record]:
        return worker_run(job)


def check_ray_address(address: str | None, timeout_s: float = RAY_CONNECT_TIMEOUT_S) -> None:
    """Checks that a Ray cluster answers at ``address`` (``host:port`` of its head, or
    ``ray://host:port``) within ``timeout_s``: something accepts a connection there and
    speaks gRPC. Ray's own connect retries for minutes, deaf to Ctrl-C, when nothing
    answers. None, ``"local"`` and ``"auto"`` without ``RAY_ADDRESS`` are left to Ray.

    Raises
    ------
    BackendUnavailable
        The address is malformed, nothing answers there, or what answers is not gRPC.
    """
    if address == "auto":
        address = os.environ.get("RAY_ADDRESS") or None
    if address is None or address == "local":
        return
    target = address.removeprefix("ray://")
    host, _, port = target.rpartition(":")
    host = host.strip("[]")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise BackendUnavailable(
            f"Ray address {address!r} is not host:port (e.g. 10.0.0.5:6379, "
            "ray://10.0.0.5:10001 or auto)"
        )
    try:
        with socket.create_connection((host, int(port)), timeout=timeout_s) as connection:
            connection.settimeout(timeout_s)
            connection.sendall(_HTTP2_PREFACE)
            frame = connection.recv(9)
    except OSError as exc:
        if isinstance(exc, TimeoutError):
            reason = f"no answer within {timeout_s:g} s"
        else:
            reason = (exc.strerror or str(exc)).lower()
        raise BackendUnavailable(
            f"no Ray cluster at {address} ({reason}); expected the head's address "
            "(ray start --head prints it)"
        ) from exc
    if len(frame) < 4 or frame[3] != _HTTP2_SETTINGS:
        raise BackendUnavailable(
            f"what answers at {address} is not a Ray cluster (no gRPC); expected the "
            "head's address (ray start --head prints it)"
        )


def _join(address: str, timeout_s: float) -> None:
    """``ray.init(address=...)``, given ``timeout_s``: it runs in a thread, so that Ctrl-C
    is heard and a cluster that does not take the driver is reported in time.

    Raises
    ------
    BackendUnavailable
        Ray failed, or did not finish in time (it goes on trying in the background until
        this process ends).
    """
    import ray

    outcome: list[BaseException | None] = []

    def join() -> None:
        try:
            ray.init(address=address, log_to_driver=False)
            outcome.append(None)
        except BaseException as exc:  # reported by the caller's thread
            outcome.append(exc)

    thread = threading.Thread(target=join, name="ray-init", daemon=True)
    thread.start()
    thread.join(timeout_s)
    if not outcome:
        raise BackendUnavailable(
            f"the Ray cluster at {address} did not take this driver within {timeout_s:g} s; "
            "expected the head's address (ray start --head prints it)"
        )
    error = outcome[0]
    if error is not None:
        reason = (str(error).strip().splitlines() or [type(error).__name__])[0]
        raise BackendUnavailable(f"cannot join the Ray cluster at {address}: {reason}") from error


def run_on_ray(
    handle: DatabaseHandle,
    todo: list[Job],
    record: Callable[[Job, list[Record]], None],
    workers: int,
    address: str | None,
) -> None:
    """Run ``todo`` on ``workers`` Ray actors; ``record`` gets each job's records.

    A local instance (no ``address``) listens on 127.0.0.1 only, unless the environment
    says otherwise (Ray reads ``RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER`` when imported). An
    ``address`` is checked first (:func:`check_ray_address`).

    Raises
    ------
    BackendUnavailable
        No Ray cluster answers at ``address``.
    """
    if address is None:
        os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")
    else:
        check_ray_address(address)
    import ray

    if not ray.is_initialized():
        if address:
            _join(address, RAY_INIT_TIMEOUT_S)
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
            # a bounded wait: Ctrl-C is seen at once
            ready, _ = ray.wait(list(pending), num_returns=1, timeout=0.5)
            if not ready:
                continue
            actor, job = pending.pop(ready[0])
            record(job, ray.get(ready[0]))
            if queue:
                nxt = queue.pop(0)
                pending[actor.run.remote(nxt)] = (actor, nxt)
    finally:
        for actor in actors:
            ray.kill(actor)
