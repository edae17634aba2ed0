"""What recording costs."""

from __future__ import annotations

import pytest

from tactile_sim.recording import recording_overhead


def test_recording_overhead_reports_times_and_sizes() -> None:
    report = recording_overhead("sphere", seeds=(1,), n_points=7)
    (run,) = report["runs"]
    assert run["plain_s"] > 0 and run["sampled_s"] > 0 and run["logging_s"] > 0
    assert run["rrd_bytes"] > 10_000 and run["samples"] > 100
    assert report["total"]["overhead"] == pytest.approx(run["overhead"])
