"""Accuracy and speed of the simulated probe: sensed points against the meshes, wall times.

:func:`sensing_accuracy` probes objects and measures every sensed point against the
object's original mesh (libigl AABB: exact point-triangle distances; not
``trimesh.proximity``, which is wrong at this scale). :func:`session_timing` measures
the wall time of warm probing sessions, :func:`probe_script_seconds` that of
``scripts/probe.py`` as a user runs it; :func:`collision_report` the collision parts.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tactile_sim.collision import convex_decomposition, load_solid, object_parts, solid_names
from tactile_sim.errors import SimulationError
from tactile_sim.objects import load_object, object_names
from tactile_sim.probing import ProbingConfig, build_probe_scene, probe_object
from tactile_sim.sensor import SensorConfig

__all__ = [
    "AccuracyResult",
    "ObjectAccuracy",
    "TimingResult",
    "collision_report",
    "probe_script_seconds",
    "sensing_accuracy",
    "session_timing",
]


#: The script a user runs to probe one object (timed by :func:`probe_script_seconds`).
PROBE_SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "probe.py"


@dataclass(frozen=True)
class ObjectAccuracy:
    """Sensed-point errors on one object over several sessions.

    Attributes
    ----------
    name : str
    seeds : tuple of int
        Session seeds.
    distance_to_mesh_m : (n,) float, metres
        Distance of every sensed point to the original mesh.
    error_to_true_m : (n,) float, metres
        Distance of every sensed point to its true contact point (the mesh point closest
        to the simulator's tip centre).
    truncated_sweeps : int
        Sweeps that lost points (edges, steep surfaces).
    stylus_contacts : int
        Readings during which the shaft or housing touched something.
    session_seconds : tuple of float, seconds
        Wall time of each session's probing (scene build excluded).
    """

    name: str
    seeds: tuple[int, ...]
    distance_to_mesh_m: NDArray[np.float64]
    error_to_true_m: NDArray[np.float64]
    truncated_sweeps: int
    stylus_contacts: int
    session_seconds: tuple[float, ...]


@dataclass(frozen=True)
class AccuracyResult:
    """Sensed points against the original meshes, pooled over objects.

    Attributes
    ----------
    objects : tuple of ObjectAccuracy
    n_points : int
    mean_m, p95_m, max_m : float, metres
        Distance of the sensed points to the original mesh: mean, 95th percentile, max.
    error_to_true_mean_m, error_to_true_p95_m : float, metres
        Distance to the true contact points: mean and 95th percentile.
    """

    objects: tuple[ObjectAccuracy, ...]
    n_points: int
    mean_m: float
    p95_m: float
    max_m: float
    error_to_true_mean_m: float
    error_to_true_p95_m: float

    def summary(self) -> dict[str, Any]:
        """Returns the figures in millimetres, JSON-ready."""
        return {
            "n_points": self.n_points,
            "distance_to_mesh_mean_mm": self.mean_m * 1e3,
            "distance_to_mesh_p95_mm": self.p95_m * 1e3,
            "distance_to_mesh_max_mm": self.max_m * 1e3,
            "error_to_true_contact_mean_mm": self.error_to_true_mean_m * 1e3,
            "error_to_true_contact_p95_mm": self.error_to_true_p95_m * 1e3,
            "objects": {
                o.name: {
                    "n_points": len(o.distance_to_mesh_m),
                    "distance_to_mesh_mean_mm": float(o.distance_to_mesh_m.mean()) * 1e3,
                    "distance_to_mesh_p95_mm": float(np.percentile(o.distance_to_mesh_m, 95)) * 1e3,
                    "distance_to_mesh_max_mm": float(o.distance_to_mesh_m.max()) * 1e3,
                    "truncated_sweeps": o.truncated_sweeps,
                    "stylus_contacts": o.stylus_contacts,
                    "session_seconds": list(o.session_seconds),
                }
                for o in self.objects
            },
        }


def sensing_accuracy(
    objects: Sequence[str] = ("cat", "dog", "bird"),
    *,
    sessions_per_object: int = 3,
    seed: int = 0,
    config: ProbingConfig | None = None,
    sensor: SensorConfig | None = None,
    progress: bool = True,
) -> AccuracyResult:
    """Probes objects (3 sweeps x 21 points at 1.2 mm per session) and measures the
    sensed points against the original meshes.

    The defaults give 3 x 3 x 63 = 567 points. Each object is placed once (random pose
    from ``seed``); each session draws its own point p, plane yaw and noise.

    Parameters
    ----------
    objects : sequence of str
        Catalog or solid names.
    sessions_per_object : int
    seed : int
        Base seed; session k of object i uses ``seed + 1000 * i + k``.
    config : ProbingConfig or None
    sensor : SensorConfig or None
    progress : bool
        Announce cold builds.
    """
    per_object = []
    for i, name in enumerate(objects):
        probe_scene = build_probe_scene(name, seed=seed + 1000 * i, progress=progress)
        distances, errors, seconds, seeds = [], [], [], []
        truncated = stylus = 0
        for k in range(sessions_per_object):
            session_seed = seed + 1000 * i + k
            start = time.perf_counter()
            session = probe_object(
                name,
                seed=session_seed,
                probe_scene=probe_scene,
                config=config,
                sensor=sensor,
                progress=progress,
            )
            seconds.append(time.perf_counter() - start)
            seeds.append(session_seed)
            for sweep in session.sweeps:
                _, d = probe_scene.closest_points_in_world(sweep.points_in_world)
                distances.append(d)
                errors.append(
                    np.linalg.norm(
                        sweep.points_in_world - sweep.true_contact_points_in_world, axis=1
                    )
                )
                truncated += int(sweep.truncated)
                stylus += int(np.count_nonzero(sweep.stylus_contacts))
        per_object.append(
            ObjectAccuracy(
                name=name,
                seeds=tuple(seeds),
                distance_to_mesh_m=np.concatenate(distances),
                error_to_true_m=np.concatenate(errors),
                truncated_sweeps=truncated,
                stylus_contacts=stylus,
                session_seconds=tuple(seconds),
            )
        )
    distance = np.concatenate([o.distance_to_mesh_m for o in per_object])
    error = np.concatenate([o.error_to_true_m for o in per_object])
    return AccuracyResult(
        objects=tuple(per_object),
        n_points=len(distance),
        mean_m=float(distance.mean()),
        p95_m=float(np.percentile(distance, 95)),
        max_m=float(distance.max()),
        error_to_true_mean_m=float(error.mean()),
        error_to_true_p95_m=float(np.percentile(error, 95)),
    )


@dataclass(frozen=True)
class TimingResult:
    """Wall times of warm probing sessions of one object.

    Attributes
    ----------
    name : str
    build_seconds : tuple of float, seconds
        Scene builds (object and hulls from the caches, MuJoCo compile).
    probe_seconds : tuple of float, seconds
        The three sweeps.
    session_seconds : tuple of float, seconds
        ``probe_object`` end to end (build included), as a user calls it.
    sim_seconds : tuple of float, seconds
        Simulated time per session.
    n_points : tuple of int
        Points sensed per session.
    """

    name: str
    build_seconds: tuple[float, ...] = field(default_factory=tuple)
    probe_seconds: tuple[float, ...] = field(default_factory=tuple)
    session_seconds: tuple[float, ...] = field(default_factory=tuple)
    sim_seconds: tuple[float, ...] = field(default_factory=tuple)
    n_points: tuple[int, ...] = field(default_factory=tuple)


def session_timing(
    name: str = "cat",
    *,
    repeats: int = 3,
    seed: int = 0,
    config: ProbingConfig | None = None,
    sensor: SensorConfig | None = None,
) -> TimingResult:
    """Returns the wall times of ``repeats`` warm sessions (3 x 21 points at 1.2 mm).

    One call of ``probe_object`` first warms the caches (and imports); the timed calls
    then each build their own scene, as a user's call does.
    """
    probe_object(name, seed=seed, config=config, sensor=sensor)
    builds, probes, sessions, sims, points = [], [], [], [], []
    for k in range(repeats):
        start = time.perf_counter()
        session = probe_object(name, seed=seed + k, config=config, sensor=sensor)
        sessions.append(time.perf_counter() - start)
        builds.append(session.build_seconds)
        probes.append(session.wall_seconds - session.build_seconds)
        sims.append(session.sim_seconds)
        points.append(session.curves.n_points)
    return TimingResult(
        name=name,
        build_seconds=tuple(builds),
        probe_seconds=tuple(probes),
        session_seconds=tuple(sessions),
        sim_seconds=tuple(sims),
        n_points=tuple(points),
    )


def probe_script_seconds(name: str = "cat", *, runs: int = 4, seed: int = 0) -> list[float]:
    """Returns the wall times of ``runs`` runs of ``scripts/probe.py --object name``, each a
    fresh process as a user starts it (seeds ``seed``, ``seed + 1``, ...; the first run
    warms the caches), seconds.

    Raises
    ------
    SimulationError
        A run failed (its last error output is in the message).
    """
    command = [sys.executable, str(PROBE_SCRIPT), "--object", name]
    walls = []
    with tempfile.TemporaryDirectory() as out:
        for k in range(runs):
            start = time.perf_counter()
            done = subprocess.run(
                [*command, "--seed", str(seed + k), "--out", out],
                capture_output=True,
                text=True,
            )
            if done.returncode != 0:
                raise SimulationError(f"probe.py failed: {done.stderr.strip()[-300:]}")
            walls.append(time.perf_counter() - start)
    return walls


def collision_report(names: Sequence[str] | None = None) -> list[dict[str, Any]]:
    """Returns, per object, its collision parts as loaded (warm) and as built (cold).

    Each row: ``name``, ``source`` (shipped, cache, built, convex), ``parts``,
    ``vertices``, ``load_seconds`` (this call), ``build_seconds`` (the CoACD run that made
    them, stored with them), and the exposed-surface deviation from the original mesh
    measured at build time (``*_mm``; absent for convex objects, which are exact).

    Parameters
    ----------
    names : sequence of str or None
        Catalog or solid names; None: all of them.
    """
    rows = []
    for name in names if names is not None else (*object_names(), *solid_names()):
        start = time.perf_counter()
        if name in solid_names():
            parts = convex_decomposition(load_solid(name).mesh, name=name, convex=True)
        else:
            parts = object_parts(load_object(name))
        row: dict[str, Any] = {
            "name": name,
            "source": parts.source,
            "parts": parts.n_parts,
            "vertices": parts.n_vertices,
            "load_seconds": time.perf_counter() - start,
            "build_seconds": parts.build_seconds,
        }
        if parts.accuracy is not None:
            row |= {
                "deviation_mean_mm": parts.accuracy.mean_m * 1e3,
                "deviation_p95_mm": parts.accuracy.p95_m * 1e3,
                "deviation_max_mm": parts.accuracy.max_m * 1e3,
            }
        rows.append(row)
    return rows
