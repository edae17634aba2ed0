"""Test session set-up: pytest-xdist's workers share the machine's cores (as the
benchmark's do, :func:`recognition.pools.worker_share`)."""

import os

from recognition.pools import limit_native_threads, worker_share


def pytest_configure(config):
    workers = os.environ.get("PYTEST_XDIST_WORKER_COUNT")
    if workers:
        limit_native_threads(worker_share(int(workers)))
