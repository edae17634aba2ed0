"""Waiting for a pool's results with Ctrl-C held until it is safe to raise."""

import os
import signal
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import pytest

from recognition.pools import completed, process_pool, usable_cores, worker_share


def test_completed_gives_every_future_once_as_it_completes():
    with ThreadPoolExecutor(3) as pool:
        futures = [pool.submit(time.sleep, delay) for delay in (0.3, 0.0, 0.15)]
        order = list(completed(futures))
    assert order == [futures[1], futures[2], futures[0]]


def test_a_ctrl_c_while_waiting_is_raised_between_waits_and_the_handler_restored():
    before = signal.getsignal(signal.SIGINT)
    for _ in range(10):  # a signal that interrupts a wait must not stretch the next one
        release = threading.Event()
        with ThreadPoolExecutor(1) as pool:
            future = pool.submit(release.wait, 5.0)
            timer = threading.Timer(0.2, os.kill, (os.getpid(), signal.SIGINT))
            timer.start()
            start = time.monotonic()
            with pytest.raises(KeyboardInterrupt):
                list(completed([future]))
            waited = time.monotonic() - start
            release.set()
        assert 0.15 < waited < 2.0  # raised soon after the signal, not when the work ended
        assert signal.getsignal(signal.SIGINT) is before


def _blas_threads() -> list[int]:
    from threadpoolctl import threadpool_info

    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


def test_a_pool_worker_uses_its_share_of_the_cores():
    with process_pool(2) as pool:
        threads = pool.submit(_blas_threads).result()
    assert threads and all(n == worker_share(2) for n in threads)
    assert worker_share(2) == max(1, usable_cores() // 2) and usable_cores() >= 1
    assert worker_share(10**6) == 1  # never none


def _managers_alive() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if type(t).__name__ == "_ExecutorManagerThread"]


def test_leaving_a_pool_by_an_exception_ends_its_workers_and_then_its_manager_thread():
    # the interpreter's exit writes to the manager's wake-up pipe unless it has ended
    before = set(_managers_alive())
    with pytest.raises(RuntimeError), process_pool(2) as pool:
        started = pool.submit(os.getpid).result()
        pool.submit(time.sleep, 30.0)
        raise RuntimeError
    assert started != os.getpid()
    assert not set(_managers_alive()) - before
