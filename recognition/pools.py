"""Process pools that stop at once on Ctrl-C: the workers ignore SIGINT, the parent ends them."""

from __future__ import annotations

import contextlib
import multiprocessing
import signal
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from typing import Any

__all__ = ["process_pool"]


def _ignore_interrupts(
    initializer: Callable[..., object] | None, initargs: tuple[Any, ...]
) -> None:
    """A worker's start: Ctrl-C is the parent's to handle, then ``initializer(*initargs)``."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if initializer is not None:
        initializer(*initargs)


class _Pool(ProcessPoolExecutor):
    """A process pool whose ``submit`` (``map`` calls it) defers Ctrl-C to its end.

    A ``KeyboardInterrupt`` raised inside ``submit`` can land after a queue's lock is
    taken but before the ``with`` block that releases it is entered (CPython does not
    release it then): the pool's manager thread then waits on that lock for ever and the
    interpreter never exits. A fresh-clone run hung so once after "interrupted", its
    manager thread waiting on the work-id queue's lock; 24 interrupted runs under load
    did not reproduce it. In the main thread the interrupt is now held while the call is
    queued and raised as it returns.
    """

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Any:
        if threading.current_thread() is not threading.main_thread():
            return super().submit(fn, *args, **kwargs)
        held: list[int] = []
        previous = signal.signal(signal.SIGINT, lambda number, _frame: held.append(number))
        try:
            return super().submit(fn, *args, **kwargs)
        finally:
            signal.signal(signal.SIGINT, previous)
            if held:
                raise KeyboardInterrupt


@contextlib.contextmanager
def process_pool(
    workers: int,
    initializer: Callable[..., object] | None = None,
    initargs: tuple[Any, ...] = (),
) -> Iterator[ProcessPoolExecutor]:
    """A :class:`~concurrent.futures.ProcessPoolExecutor` of ``workers`` processes whose
    workers ignore SIGINT (a Ctrl-C at a terminal reaches the whole process group: only
    the parent reports it).

    Leaving the block normally waits for the work submitted; leaving it by an exception
    (Ctrl-C's ``KeyboardInterrupt`` included) cancels what has not started and terminates
    the workers at once instead of waiting for their jobs.
    """
    before = set(multiprocessing.active_children())
    pool = _Pool(workers, initializer=_ignore_interrupts, initargs=(initializer, initargs))
    try:
        yield pool
    except BaseException:
        pool.shutdown(wait=False, cancel_futures=True)
        started = set(multiprocessing.active_children()) - before
        for process in started:
            process.terminate()
        for process in started:
            process.join(timeout=5)
        # the pool's manager thread sees its workers gone and ends: wait for it, so that
        # it does not close its wake-up pipe while the interpreter's exit writes to it
        # (an "OSError: Bad file descriptor" traceback after the one-line message)
        pool.shutdown(wait=True)
        raise
    pool.shutdown(wait=True)
