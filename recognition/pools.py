"""Process pools that stop at once on Ctrl-C (the workers ignore SIGINT, the parent ends
them) and share the machine's cores among their workers.

Each worker's native thread pools (BLAS, OpenMP) are limited to its share of the cores
(:func:`worker_share`): left alone, every worker's BLAS starts as many threads as
the machine has cores, and the workers' threads then contend for them. Measured with two
workers on two cores (the synthetic benchmark with touches, noise 0.05 mm): a touch's
planning and update took 0.55 s (mean) with a BLAS thread per core in each worker and
0.37 s with one.

A ``KeyboardInterrupt`` that lands inside the standard library's pool code can land after
a lock is taken but before the ``with`` block that releases it is entered (CPython does
not release it then): the pool's manager thread then waits on that lock for ever and the
interpreter never exits. Fresh-clone runs hung so after "interrupted" twice: once with
the manager thread waiting on the work-id queue's lock (taken in ``submit``), once on a
future's condition (``as_completed`` takes every future's). Where the main thread calls
into that code (``submit``, waiting for results with :func:`completed`), Ctrl-C is held
and raised as the call returns.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import queue
import signal
import threading
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from typing import Any

from threadpoolctl import threadpool_limits

__all__ = ["completed", "limit_native_threads", "process_pool", "usable_cores", "worker_share"]

#: While waiting for a result, a held Ctrl-C is raised within this many seconds.
_POLL_S = 0.1


def limit_native_threads(threads: int) -> None:
    """Limit this process's native thread pools (BLAS, OpenMP) to ``threads`` threads."""
    threadpool_limits(limits=max(1, threads))


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity where the platform tells it,
    else the machine's), at least one."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return os.cpu_count() or 1


def worker_share(workers: int) -> int:
    """The threads of one of ``workers`` processes that run at once: the usable cores
    over ``workers``, at least one."""
    return max(1, usable_cores() // max(workers, 1))


def _worker_start(
    workers: int, initializer: Callable[..., object] | None, initargs: tuple[Any, ...]
) -> None:
    """A worker's start: Ctrl-C is the parent's to handle, the native thread pools are
    limited to the worker's share of the cores, then ``initializer(*initargs)``."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    limit_native_threads(worker_share(workers))
    if initializer is not None:
        initializer(*initargs)


@contextlib.contextmanager
def _interrupts_held() -> Iterator[list[int]]:
    """In the main thread, Ctrl-C inside the block is recorded in the yielded list, not
    raised where it lands, and raised as ``KeyboardInterrupt`` when the block ends
    (elsewhere nothing changes)."""
    held: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield held
        return
    previous = signal.signal(signal.SIGINT, lambda number, _frame: held.append(number))
    try:
        yield held
    finally:
        signal.signal(signal.SIGINT, previous)
    if held:
        raise KeyboardInterrupt


class _Pool(ProcessPoolExecutor):
    """A process pool whose ``submit`` (``map`` calls it) defers Ctrl-C to its end
    (module docstring)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Any:
        with _interrupts_held():
            return super().submit(fn, *args, **kwargs)


def completed(futures: Iterable[Future[Any]]) -> Iterator[Future[Any]]:
    """The ``futures`` as they complete, as :func:`concurrent.futures.as_completed` gives
    them, but with Ctrl-C held while waiting and raised between waits (within
    ``_POLL_S``; module docstring).

    The wait is a :class:`queue.Queue`'s: a :class:`queue.SimpleQueue`'s ``get`` with a
    timeout that a signal interrupts waits on past its timeout until an item comes (24 of
    80 Ctrl-Cs held so on Python 3.11.7 were raised only when the work ended)."""
    done: queue.Queue[Future[Any]] = queue.Queue()
    with _interrupts_held():
        pending = list(futures)
        for future in pending:
            future.add_done_callback(done.put)
    for _ in pending:
        with _interrupts_held() as held:
            while True:
                try:
                    future = done.get(timeout=_POLL_S)
                    break
                except queue.Empty:
                    if held:
                        break
        yield future


@contextlib.contextmanager
def process_pool(
    workers: int,
    initializer: Callable[..., object] | None = None,
    initargs: tuple[Any, ...] = (),
) -> Iterator[ProcessPoolExecutor]:
    """A :class:`~concurrent.futures.ProcessPoolExecutor` of ``workers`` processes whose
    workers ignore SIGINT (a Ctrl-C at a terminal reaches the whole process group: only
    the parent reports it) and use their share of the cores (:func:`worker_share`).

    Leaving the block normally waits for the work submitted; leaving it by an exception
    (Ctrl-C's ``KeyboardInterrupt`` included) cancels what has not started and terminates
    the workers at once instead of waiting for their jobs.
    """
    before = set(multiprocessing.active_children())
    pool = _Pool(workers, initializer=_worker_start, initargs=(workers, initializer, initargs))
    try:
        yield pool
    except BaseException:
        # the pool forgets its manager thread on the first shutdown: keep it to wait for
        manager = getattr(pool, "_executor_manager_thread", None)
        pool.shutdown(wait=False, cancel_futures=True)
        started = set(multiprocessing.active_children()) - before
        for process in started:
            process.terminate()
        for process in started:
            process.join(timeout=5)
        # the manager thread sees its workers gone, closes its wake-up pipe and ends: wait
        # for it, so that it does not close the pipe while the interpreter's exit writes
        # to it (an "OSError: Bad file descriptor" traceback after the one-line message)
        if manager is not None:
            manager.join(timeout=5)
        raise
    pool.shutdown(wait=True)
