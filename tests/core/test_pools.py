"""Waiting for a pool's results with Ctrl-C held until it is safe to raise."""

import os
import signal
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import pytest

from recognition.pools import completed


def test_completed_gives_every_future_once_as_it_completes():
    with ThreadPoolExecutor(3) as pool:
        futures = [pool.submit(time.sleep, delay) for delay in (0.3, 0.0, 0.15)]
        order = list(completed(futures))
    assert order == [futures[1], futures[2], futures[0]]


def test_a_ctrl_c_while_waiting_is_raised_between_waits_and_the_handler_restored():
    before = signal.getsignal(signal.SIGINT)
    release = threading.Event()
    with ThreadPoolExecutor(1) as pool:
        future = pool.submit(release.wait, 10.0)
        timer = threading.Timer(0.2, os.kill, (os.getpid(), signal.SIGINT))
        timer.start()
        start = time.monotonic()
        with pytest.raises(KeyboardInterrupt):
            list(completed([future]))
        waited = time.monotonic() - start
        release.set()
    assert 0.15 < waited < 2.0  # raised soon after the signal, not when the work ended
    assert signal.getsignal(signal.SIGINT) is before
