"""What recording costs: session wall time without and with it, and the .rrd size."""

from __future__ import annotations

import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tactile_sim.recording.record import record_probe_run

if TYPE_CHECKING:
    from recognition import ModelDatabase

__all__ = [
    "recording_overhead",
]


def recording_overhead(
    obj: str = "cat",
    seeds: Sequence[int] = (0, 1, 2),
    *,
    n_points: int = 21,
    trajectory_hz: float = 200.0,
    database: ModelDatabase | None = None,
    directory: str | Path | None = None,
) -> dict[str, Any]:
    """Measures what recording costs: session wall time without and with it, .rrd size.

    Each seed runs the same session twice, each on a freshly built scene (the build is
    part of a session's wall time): once plain and once with the trajectory sampled,
    then recorded to an .rrd file (:func:`record_probe_run`, with the recognition when
    ``database`` is given; recognising is not counted). The first recording in a process
    includes rerun's one-time set-up.

    Parameters
    ----------
    obj : str
        Object to probe.
    seeds : sequence of int
    n_points : int
        Points per curve.
    trajectory_hz : float, 1/s
    database : recognition.ModelDatabase or None
        Recognise each session with it and record the result.
    directory : str, Path or None
        Where the .rrd files go; None: a temporary directory, removed afterwards.

    Returns
    -------
    dict
        Per seed and in total: ``plain_s`` (session wall time without recording),
        ``sampled_s`` (with the trajectory sampled), ``logging_s`` (writing the .rrd),
        ``overhead`` ((sampled + logging - plain) / plain), ``rrd_bytes``, ``samples``.
    """
    import rerun  # noqa: F401  (imported once, outside the timings)

    from tactile_sim.probing import probe_object

    runs = []
    with tempfile.TemporaryDirectory() as scratch:
        out = Path(directory) if directory is not None else Path(scratch)
        for k, seed in enumerate(seeds):
            walls: dict[float | None, float] = {}
            # Alternate which run goes first (a warm cache must not favour one).
            for hz in (None, trajectory_hz) if k % 2 == 0 else (trajectory_hz, None):
                start = time.perf_counter()
                session = probe_object(
                    obj, seed=seed, n_points=n_points, progress=False, trajectory_hz=hz
                )
                walls[hz] = time.perf_counter() - start
                if hz is not None:
                    recorded = session
            result = database.recognize(recorded.curves) if database is not None else None
            path = out / f"{recorded.object_name}_seed{seed}.rrd"
            start = time.perf_counter()
            record_probe_run(recorded, result, database, mode="save", path=path)
            logging = time.perf_counter() - start
            plain, sampled = walls[None], walls[trajectory_hz]
            runs.append(
                {
                    "seed": seed,
                    "plain_s": plain,
                    "sampled_s": sampled,
                    "logging_s": logging,
                    "overhead": (sampled + logging - plain) / plain,
                    "rrd_bytes": path.stat().st_size,
                    "samples": len(recorded.trajectory),
                    "sim_s": recorded.sim_seconds,
                }
            )
    total = {
        key: float(sum(run[key] for run in runs))
        for key in ("plain_s", "sampled_s", "logging_s", "rrd_bytes", "samples", "sim_s")
    }
    total["overhead"] = (total["sampled_s"] + total["logging_s"] - total["plain_s"]) / total[
        "plain_s"
    ]
    return {
        "object": obj,
        "n_points": n_points,
        "trajectory_hz": trajectory_hz,
        "runs": runs,
        "total": total,
    }
