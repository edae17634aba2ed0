"""Accuracy and speed of the simulated probe: sensed points against the meshes, wall times.

:func:`sensing_accuracy` probes objects and measures every sensed point against the
surface MuJoCo touched and against the object's mesh, and MuJoCo's contact points
against the mesh (:class:`~recognition.surfaces.distance.MeshDistance`: exact point-triangle
distances; not
``trimesh.proximity``, which is wrong at this scale). :func:`session_timing` measures
the wall time of warm probing sessions, :func:`probe_script_seconds` that of
``scripts/probe.py`` as a user runs it; :func:`collision_report` the collision parts.
"""

from __future__ import annotations

import json
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
    "ERRORS",
    "SCRIPT_PARTS",
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


#: The errors of a sensed point the sensing report keeps apart: across the surfaces
#: (sensor, geometry, total) and along them (lateral).
ERRORS = ("sensor", "geometry", "total", "lateral")


def _stats_mm(values_m: NDArray[np.float64]) -> dict[str, float]:
    return {
        "mean_mm": float(values_m.mean()) * 1e3,
        "p95_mm": float(np.percentile(values_m, 95)) * 1e3,
        "max_mm": float(values_m.max()) * 1e3,
    }


@dataclass(frozen=True)
class ObjectAccuracy:
    """Sensed-point errors on one object over several sessions, kept apart by cause.

    Attributes
    ----------
    name : str
    seeds : tuple of int
        Session seeds.
    sensor_m : (n,) float, metres
        Sensor error: distance of every sensed point from the surface the tip touched
        (the collider's tangent plane at MuJoCo's contact point, whose normal points to
        the tip's centre).
    geometry_m : (n,) float, metres
        Geometry error: distance of those contact points from the object's mesh.
    total_m : (n,) float, metres
        Distance of every sensed point from the object's mesh.
    lateral_m : (n,) float, metres
        How far each sensed point lies from MuJoCo's contact point along the surface
        (a displacement along the surface, which moves the point on it, not off it).
    contacts_missing : int
        Readings at which MuJoCo reported no tip contact (the contact point is then the
        mesh point nearest the tip centre).
    truncated_sweeps : int
        Sweeps that lost points (edges, steep surfaces).
    stylus_contacts : int
        Readings during which the shaft or housing touched something.
    session_seconds : tuple of float, seconds
        Wall time of each session's probing (scene build excluded).
    """

    name: str
    seeds: tuple[int, ...]
    sensor_m: NDArray[np.float64]
    geometry_m: NDArray[np.float64]
    total_m: NDArray[np.float64]
    lateral_m: NDArray[np.float64]
    contacts_missing: int
    truncated_sweeps: int
    stylus_contacts: int
    session_seconds: tuple[float, ...]

    def summary(self) -> dict[str, Any]:
        """Returns the figures in millimetres, JSON-ready."""
        return {
            "n_points": len(self.total_m),
            **{
                f"{which}_{k}": v
                for which in ERRORS
                for k, v in _stats_mm(getattr(self, f"{which}_m")).items()
            },
            "contacts_missing": self.contacts_missing,
            "truncated_sweeps": self.truncated_sweeps,
            "stylus_contacts": self.stylus_contacts,
            "session_seconds": list(self.session_seconds),
        }


@dataclass(frozen=True)
class AccuracyResult:
    """Sensed points against the colliders and the meshes, pooled over objects.

    Attributes
    ----------
    objects : tuple of ObjectAccuracy
    """

    objects: tuple[ObjectAccuracy, ...]

    @property
    def n_points(self) -> int:
        """Sensed points over all objects."""
        return sum(len(o.total_m) for o in self.objects)

    def pooled_m(self, which: str) -> NDArray[np.float64]:
        """One error (``"sensor"``, ``"geometry"`` or ``"total"``) of every point, metres."""
        return np.concatenate([getattr(o, f"{which}_m") for o in self.objects])

    def summary(self) -> dict[str, Any]:
        """Returns the figures in millimetres, JSON-ready: pooled, then per object."""
        return {
            "n_points": self.n_points,
            **{
                f"{which}_{k}": v
                for which in ERRORS
                for k, v in _stats_mm(self.pooled_m(which)).items()
            },
            "contacts_missing": sum(o.contacts_missing for o in self.objects),
            "objects": {o.name: o.summary() for o in self.objects},
        }


def sensing_accuracy(
    objects: Sequence[str] = tuple(object_names()),
    *,
    sessions_per_object: int = 3,
    seed: int = 0,
    config: ProbingConfig | None = None,
    sensor: SensorConfig | None = None,
    progress: bool = True,
) -> AccuracyResult:
    """Probes objects (3 sweeps x 21 points at 1.2 mm per session) and measures every
    sensed point against the surface MuJoCo touched and against the object's mesh.

    The errors are kept apart (:class:`ObjectAccuracy`): the sensor's (sensed point to
    the surface the tip touched), the collider's (MuJoCo's contact point to mesh), their
    sum (sensed point to mesh), and the sensed point's offset along the surface, each
    over the probed regions only. Each object is placed once
    (random pose from ``seed``); each session draws its own point p, plane yaw and
    noise.

    Parameters
    ----------
    objects : sequence of str
        Catalog or solid names (default: the ten catalog objects).
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
        sensor_m, geometry_m, total_m, lateral_m = [], [], [], []
        seconds, seeds = [], []
        truncated = stylus = missing = 0
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
                contacts = sweep.true_contact_points_in_world
                normal = sweep.true_tip_centres_in_world - contacts
                normal /= np.linalg.norm(normal, axis=1, keepdims=True)
                offset = sweep.points_in_world - contacts
                across = np.einsum("ij,ij->i", offset, normal)
                sensor_m.append(np.abs(across))
                lateral_m.append(np.linalg.norm(offset - across[:, None] * normal, axis=1))
                geometry_m.append(probe_scene.closest_points_in_world(contacts)[1])
                total_m.append(probe_scene.closest_points_in_world(sweep.points_in_world)[1])
                missing += int(np.count_nonzero(~sweep.contact_found))
                truncated += int(sweep.truncated)
                stylus += int(np.count_nonzero(sweep.stylus_contacts))
        per_object.append(
            ObjectAccuracy(
                name=name,
                seeds=tuple(seeds),
                sensor_m=np.concatenate(sensor_m),
                geometry_m=np.concatenate(geometry_m),
                total_m=np.concatenate(total_m),
                lateral_m=np.concatenate(lateral_m),
                contacts_missing=missing,
                truncated_sweeps=truncated,
                stylus_contacts=stylus,
                session_seconds=tuple(seconds),
            )
        )
    return AccuracyResult(objects=tuple(per_object))


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


#: The parts of a ``scripts/probe.py`` run that :func:`probe_script_seconds` reports:
#: (label, key).
SCRIPT_PARTS = (
    ("start-up and imports", "startup"),
    ("object", "object"),
    ("database load", "database"),
    ("probing", "probing"),
    ("recognition", "recognition"),
    ("total", "wall"),
)


def probe_script_seconds(
    name: str = "cat", *, runs: int = 4, seed: int = 0
) -> list[dict[str, float]]:
    """Returns the wall times of ``runs`` runs of ``scripts/probe.py --object name``, each a
    fresh process as a user starts it (seeds ``seed``, ``seed + 1``, ...; the first run
    warms the caches), seconds: ``wall`` and its parts (:data:`SCRIPT_PARTS`, from the
    run's ``--json`` summary; ``startup`` is the wall time outside the script's own).

    Raises
    ------
    SimulationError
        A run failed (its last error output is in the message).
    """
    command = [sys.executable, str(PROBE_SCRIPT), "--object", name, "--rerun", "save"]
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(runs):
            summary_path = Path(tmp) / f"run{k}.json"
            start = time.perf_counter()
            done = subprocess.run(
                [*command, "--seed", str(seed + k), "--out", tmp, "--json", str(summary_path)],
                capture_output=True,
                text=True,
            )
            wall = time.perf_counter() - start
            if done.returncode != 0:
                raise SimulationError(f"probe.py failed: {done.stderr.strip()[-300:]}")
            timings = json.loads(summary_path.read_text())["timings_s"]
            out.append(
                {
                    "wall": wall,
                    "startup": wall - timings["total"],
                    **{k: timings[k] for k in ("object", "database", "probing", "recognition")},
                }
            )
    return out


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
