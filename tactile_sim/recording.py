"""Probing sessions and their recognition as rerun recordings: saved, spawned or served."""

from __future__ import annotations

import contextlib
import math
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.parse
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tactile_sim.errors import InvalidRecording, PortInUse, RecordingError
from tactile_sim.trajectory import Trajectory, VisualGeom

__all__ = [
    "CURVE_NAMES",
    "MODES",
    "RecordingSummary",
    "WebViewer",
    "check_display",
    "check_ports",
    "log_probe_run",
    "open_native_viewer",
    "probe_blueprint",
    "read_recording",
    "record_probe_run",
    "recording_overhead",
    "serve_recording",
]

MODES = ("save", "spawn", "serve")
"""What :func:`record_probe_run` does with a recording."""

CURVE_NAMES = ("alpha", "beta", "gamma")
"""Names of the three data curves (thesis Section 4.3), in sweep order."""

APPLICATION_ID = "tactile_sim"

_CURVE_COLORS = np.array([[230, 60, 50, 255], [40, 170, 70, 255], [50, 110, 230, 255]], np.uint8)
_TIP_COLOR = (250, 200, 30, 255)
_CONTACT_COLOR = (255, 255, 255, 255)
_CANDIDATE_COLOR = (255, 140, 0, 255)
_SURFACE_COLOR = (150, 150, 150, 255)
_POINT_RADIUS_M = 0.3e-3
_SURFACE_POINTS = 3000
"""Vertices drawn per database model (a subsample; candidates are drawn in full)."""
_MODEL_SPACING_M = 0.12
_MODELS_PER_ROW = 5


@dataclass(frozen=True)
class RecordingSummary:
    """What a recording file holds.

    Attributes
    ----------
    path : Path
    application_id : str
    rows : dict of str to int
        Rows logged on a timeline, per entity path (leading "/" dropped).
    static : frozenset of str
        Entity paths with static data.
    has_blueprint : bool
        The file stores a blueprint.
    """

    path: Path
    application_id: str
    rows: dict[str, int]
    static: frozenset[str]
    has_blueprint: bool

    @property
    def entities(self) -> frozenset[str]:
        """Returns every entity path with data."""
        return frozenset(self.rows) | self.static


def read_recording(path: str | Path) -> RecordingSummary:
    """Reads a recording file back (``rerun.chunk.RrdReader``) and summarises it.

    Raises
    ------
    InvalidRecording
        The file is missing, not an .rrd file, truncated (no footer, or a chunk cut
        short) or holds no recording.
    """
    from rerun.chunk import RrdReader

    path = Path(path)
    if not path.is_file():
        raise InvalidRecording(f"no recording at {path}: the file does not exist")
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            reader = RrdReader(path)
            recordings = reader.recordings()
            blueprints = reader.blueprints()
            if not recordings:
                raise InvalidRecording(f"{path} holds no recording (an empty or blueprint file)")
            rows: dict[str, int] = {}
            static: set[str] = set()
            for chunk in reader.stream():
                entity = chunk.entity_path.lstrip("/")
                if chunk.is_static:
                    static.add(entity)
                else:
                    rows[entity] = rows.get(entity, 0) + chunk.num_rows
    except (RuntimeError, ValueError, OSError) as error:
        if isinstance(error, InvalidRecording):
            raise
        reason = str(error).splitlines()[0].split(f"{path}: ", 1)[-1]
        raise InvalidRecording(f"{path} is truncated or not an .rrd recording: {reason}") from error
    if any("footer" in str(w.message) for w in caught):
        raise InvalidRecording(
            f"{path} is truncated: it has no footer (the writer did not finish; record it again)"
        )
    return RecordingSummary(
        path=path,
        application_id=str(recordings[0].application_id),
        rows=rows,
        static=frozenset(static),
        has_blueprint=bool(blueprints),
    )


# Entity paths ------------------------------------------------------------------------------


def _body_path(body: str) -> str:
    """Entity path of a MuJoCo body: the table, the object or a part of the robot."""
    if body == "world":
        return "world/table"
    if body.endswith("/object"):
        return "world/object"
    return f"world/robot/{body}"


def _geom_path(geom: VisualGeom) -> str:
    short = geom.name.rsplit("/", 1)[-1]
    return f"{_body_path(geom.body)}/{short}"


def _xyzw(quat_wxyz: NDArray[np.float64]) -> NDArray[np.float64]:
    """MuJoCo's (..., 4) wxyz quaternions as rerun's xyzw."""
    return np.concatenate([quat_wxyz[..., 1:], quat_wxyz[..., :1]], axis=-1)


def _rgba8(rgba: Sequence[float]) -> NDArray[np.uint8]:
    return np.clip(np.round(np.asarray(rgba) * 255.0), 0, 255).astype(np.uint8)


# Logging -----------------------------------------------------------------------------------


def _vertex_normals(vertices: NDArray, faces: NDArray) -> NDArray[np.float32]:
    """Area-weighted unit vertex normals of a triangle mesh, (n, 3)."""
    v = vertices.astype(np.float64)
    tri = v[faces]
    face_normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normals = np.zeros_like(v)
    for corner in range(3):
        for axis in range(3):
            normals[:, axis] += np.bincount(
                faces[:, corner], weights=face_normals[:, axis], minlength=len(v)
            )
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return (normals / np.where(length > 0, length, 1.0)).astype(np.float32)


def _geom_archetype(geom: VisualGeom) -> Any:
    """The rerun archetype drawing a geom in its own frame (None for planes)."""
    import rerun as rr

    color = _rgba8(geom.rgba)
    size = geom.size
    if geom.shape == "box":
        return rr.Boxes3D(half_sizes=[size], colors=[color], fill_mode="solid")
    if geom.shape == "sphere":
        return rr.Ellipsoids3D(half_sizes=[[size[0]] * 3], colors=[color], fill_mode="solid")
    if geom.shape == "ellipsoid":
        return rr.Ellipsoids3D(half_sizes=[size], colors=[color], fill_mode="solid")
    if geom.shape == "cylinder":
        return rr.Cylinders3D(
            lengths=[2.0 * size[1]], radii=[size[0]], colors=[color], fill_mode="solid"
        )
    if geom.shape == "capsule":
        return rr.Capsules3D(
            lengths=[2.0 * size[1]],
            radii=[size[0]],
            translations=[[0.0, 0.0, -size[1]]],
            colors=[color],
            fill_mode="solid",
        )
    if geom.shape == "mesh" and geom.vertices is not None and geom.faces is not None:
        return rr.Mesh3D(
            vertex_positions=geom.vertices,
            triangle_indices=geom.faces,
            vertex_normals=_vertex_normals(geom.vertices, geom.faces),
            albedo_factor=color,
        )
    return None


def _time_columns(steps: NDArray[np.int64], times_s: NDArray[np.float64]) -> list:
    import rerun as rr

    return [
        rr.TimeColumn("step", sequence=np.asarray(steps, dtype=np.int64)),
        rr.TimeColumn("sim_time", duration=np.asarray(times_s, dtype=np.float64)),
    ]


def _log_scene(rec, trajectory: Trajectory) -> None:
    """Static things: the table, the object, the robot's geoms and its fixed base."""
    import rerun as rr

    for name, position, quat in zip(
        trajectory.static_body_names,
        trajectory.static_body_positions_in_world,
        trajectory.static_body_quats_wxyz_in_world,
        strict=True,
    ):
        if name != "world":
            rec.log(
                _body_path(name),
                rr.Transform3D(translation=position, quaternion=_xyzw(quat)),
                static=True,
            )
    for geom in trajectory.geoms:
        archetype = _geom_archetype(geom)
        if archetype is None:
            continue
        rec.log(
            _geom_path(geom),
            rr.Transform3D(
                translation=geom.position_in_body, quaternion=_xyzw(geom.quat_wxyz_in_body)
            ),
            archetype,
            static=True,
        )


def _log_motion(rec, trajectory: Trajectory) -> None:
    """Per-sample body poses, the tip, the stylus deflection and the tip force."""
    import rerun as rr

    indexes = _time_columns(trajectory.steps, trajectory.times_s)
    quats = _xyzw(trajectory.body_quats_wxyz_in_world)
    for b, name in enumerate(trajectory.body_names):
        rec.send_columns(
            _body_path(name),
            indexes=indexes,
            columns=rr.Transform3D.columns(
                translation=trajectory.body_positions_in_world[:, b], quaternion=quats[:, b]
            ),
        )
    rec.log(
        "world/probe/tip",
        rr.Points3D.from_fields(radii=[0.2e-3], colors=[_TIP_COLOR]),
        static=True,
    )
    rec.send_columns(
        "world/probe/tip",
        indexes=indexes,
        columns=rr.Points3D.columns(positions=trajectory.tip_centres_in_world),
    )
    rec.log("sensors/deflection", rr.SeriesLines(names=["x (rad)", "y (rad)"]), static=True)
    rec.send_columns(
        "sensors/deflection",
        indexes=indexes,
        columns=rr.Scalars.columns(scalars=trajectory.deflection_rad),
    )
    force = trajectory.tip_force_n
    rec.log("sensors/force", rr.SeriesLines(names=["axial (N)", "lateral (N)"]), static=True)
    rec.send_columns(
        "sensors/force",
        indexes=indexes,
        columns=rr.Scalars.columns(
            scalars=np.column_stack([force[:, 2], np.hypot(force[:, 0], force[:, 1])])
        ),
    )


def _log_readings(rec, session, timestep_s: float | None) -> None:
    """The sensed points, true contacts and normals at their reading times; the curves."""
    import rerun as rr

    sweeps = session.sweeps
    times = [np.asarray(s.reading_times_s, dtype=np.float64) for s in sweeps]
    timed = all(len(t) == s.n_points for t, s in zip(times, sweeps, strict=True))
    points = np.concatenate([s.points_in_world for s in sweeps])
    contacts = np.concatenate([s.true_contact_points_in_world for s in sweeps])
    normals = np.concatenate([s.normals_in_world for s in sweeps])
    colors = np.concatenate(
        [np.repeat(_CURVE_COLORS[k : k + 1], s.n_points, axis=0) for k, s in enumerate(sweeps)]
    )
    if timed:
        t = np.concatenate(times)
        order = np.argsort(t, kind="stable")
        t, points, contacts, normals, colors = (
            a[order] for a in (t, points, contacts, normals, colors)
        )
        if timestep_s is not None:
            indexes = _time_columns(np.round(t / timestep_s).astype(np.int64), t)
        else:
            indexes = [rr.TimeColumn("sim_time", duration=t)]
        rec.send_columns(
            "world/probe/sensed",
            indexes=indexes,
            columns=rr.Points3D.columns(positions=points, colors=colors),
        )
        rec.send_columns(
            "world/probe/contacts",
            indexes=indexes,
            columns=rr.Points3D.columns(positions=contacts),
        )
        rec.send_columns(
            "world/probe/normals",
            indexes=indexes,
            columns=rr.Arrows3D.columns(origins=points, vectors=2e-3 * normals, colors=colors),
        )
    else:
        rec.log("world/probe/sensed", rr.Points3D(points, colors=colors), static=True)
        rec.log("world/probe/contacts", rr.Points3D(contacts), static=True)
    rec.log("world/probe/sensed", rr.Points3D.from_fields(radii=[_POINT_RADIUS_M]), static=True)
    rec.log(
        "world/probe/contacts",
        rr.Points3D.from_fields(radii=[0.15e-3], colors=[_CONTACT_COLOR]),
        static=True,
    )
    for k, curve in enumerate(session.curves.curves):
        path = f"world/curves/{CURVE_NAMES[k] if k < len(CURVE_NAMES) else k}"
        parts = [
            rr.LineStrips3D([curve], colors=[_CURVE_COLORS[k % 3]], radii=[0.1e-3]),
            rr.Points3D(curve, colors=[_CURVE_COLORS[k % 3]], radii=[_POINT_RADIUS_M]),
        ]
        if timed:
            _set_time(rec, float(np.max(times[k])), timestep_s)
            rec.log(path, *parts)
        else:
            rec.log(path, *parts, static=True)
    rec.log(
        "world/curves/p",
        rr.Points3D([session.curves.intersection], radii=[0.5e-3], labels=["p"]),
        static=True,
    )


def _set_time(rec, time_s: float, timestep_s: float | None) -> None:
    rec.set_time("sim_time", duration=time_s)
    if timestep_s is not None:
        rec.set_time("step", sequence=round(time_s / timestep_s))


def _ranking_markdown(session, result) -> str:
    lines = [
        f"# {session.object_name}, seed {session.seed}",
        "",
        f"Recognised as **{result.name}**" if result.name else "No model fits the curves.",
        "",
        "| rank | model | error (mm) | candidates |",
        "|---:|---|---:|---:|",
    ]
    for rank, (name, error) in enumerate(result.ranking, start=1):
        shown = f"{error * 1e3:.4f}" if math.isfinite(error) else "rejected"
        count = len(result.registrations[name].candidates) if name in result.registrations else 0
        lines.append(f"| {rank} | {name} | {shown} | {count} |")
    return "\n".join(lines)


def _log_recognition(rec, session, result, database) -> None:
    """The ranking, candidate locations on every model and the curves on the best one."""
    import rerun as rr

    rec.log(
        "recognition/ranking",
        rr.TextDocument(_ranking_markdown(session, result), media_type="text/markdown"),
        static=True,
    )
    verdict = (
        f"recognised {session.object_name} as {result.name}"
        if result.name
        else f"no model fits the curves of {session.object_name}"
    )
    level = "INFO" if result.name == session.object_name else "WARN"
    rec.log("log", rr.TextLog(verdict, level=level))
    if database is None:
        return
    ranks = {name: rank for rank, (name, _) in enumerate(result.ranking, start=1)}
    errors = dict(result.ranking)
    for i, name in enumerate(sorted(result.registrations, key=lambda n: ranks.get(n, 0))):
        model = database[name]
        registration = result.registrations[name]
        vertices = np.asarray(model.vertices)
        path = f"recognition/models/{name}"
        offset = [
            (i % _MODELS_PER_ROW) * _MODEL_SPACING_M,
            -(i // _MODELS_PER_ROW) * _MODEL_SPACING_M,
            0.0,
        ]
        rec.log(path, rr.Transform3D(translation=offset), static=True)
        shown = np.arange(len(vertices))
        if len(vertices) > _SURFACE_POINTS:
            shown = np.sort(np.random.default_rng(0).choice(shown, _SURFACE_POINTS, replace=False))
        rec.log(
            f"{path}/surface",
            rr.Points3D(vertices[shown], colors=[_SURFACE_COLOR], radii=[0.25e-3]),
            static=True,
        )
        candidates = vertices[np.asarray(registration.candidates, dtype=np.int64)]
        rec.log(
            f"{path}/candidates",
            rr.Points3D(candidates, colors=[_CANDIDATE_COLOR], radii=[0.6e-3]),
            static=True,
        )
        error = errors.get(name, math.inf)
        label = f"{ranks.get(name, '-')}. {name}: " + (
            f"{error * 1e3:.3f} mm" if math.isfinite(error) else "rejected"
        )
        top = vertices.mean(axis=0)
        top[2] = vertices[:, 2].max() + 0.01
        rec.log(f"{path}/label", rr.Points3D([top], labels=[label], radii=[0.1e-3]), static=True)
    best = result.best
    if best is None or not np.all(np.isfinite(best.T_model_from_data)):
        return
    T = best.T_model_from_data
    path = f"recognition/models/{best.model}"
    for k, curve in enumerate(session.curves.curves):
        registered = curve @ T[:3, :3].T + T[:3, 3]
        rec.log(
            f"{path}/curves/{CURVE_NAMES[k] if k < len(CURVE_NAMES) else k}",
            rr.LineStrips3D([registered], colors=[_CURVE_COLORS[k % 3]], radii=[0.15e-3]),
            rr.Points3D(registered, colors=[_CURVE_COLORS[k % 3]], radii=[_POINT_RADIUS_M]),
            static=True,
        )
    if np.all(np.isfinite(best.location)):
        rec.log(
            f"{path}/location",
            rr.Points3D([best.location], radii=[0.8e-3], labels=["p"]),
            static=True,
        )


def log_probe_run(rec, session, result=None, database=None) -> None:
    """Logs a probing session (and its recognition) to a rerun recording stream.

    Parameters
    ----------
    rec : rerun.RecordingStream
    session : tactile_sim.probing.ProbeSession
        With ``trajectory`` (``probe_object(..., trajectory_hz=...)``) the scene, the
        robot's motion and the stylus signals are logged; without it only the readings,
        the curves and the recognition.
    result : recognition.Recognition or None
    database : recognition.ModelDatabase or None
        The database ``result`` came from: candidate locations and the registered curves
        are drawn on its models.
    """
    import rerun as rr

    trajectory: Trajectory | None = session.trajectory
    timestep = None if trajectory is None else trajectory.timestep_s
    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    if trajectory is not None:
        _log_scene(rec, trajectory)
        _log_motion(rec, trajectory)
    _log_readings(rec, session, timestep)
    for k, sweep in enumerate(session.sweeps):
        for side in sweep.sides:
            if side.message and len(sweep.reading_times_s):
                _set_time(rec, float(np.max(sweep.reading_times_s)), timestep)
                rec.log("log", rr.TextLog(f"sweep {k}: {side.message}", level="WARN"))
    _set_time(rec, float(session.sim_seconds), timestep)
    rec.log(
        "log",
        rr.TextLog(
            f"probed {session.object_name} (seed {session.seed}): "
            f"{sum(s.n_points for s in session.sweeps)} points in {session.sim_seconds:.2f} s "
            f"simulated, {session.wall_seconds:.2f} s wall",
            level="INFO",
        ),
    )
    if result is not None:
        _log_recognition(rec, session, result, database)


def probe_blueprint(target_in_world: Sequence[float] | None = None):
    """Returns the recording's first view: the 3D scene, the stylus signals, the log, and
    the recognition (models with candidates, ranking).

    Parameters
    ----------
    target_in_world : (3,) float or None, metres
        Where the 3D camera looks (the probed point); None: rerun's default framing.
    """
    import rerun.blueprint as rrb

    history = [
        rrb.VisibleTimeRange(
            timeline,
            start=rrb.TimeRangeBoundary.infinite(),
            end=rrb.TimeRangeBoundary.cursor_relative(),
        )
        for timeline in ("step", "sim_time")
    ]
    eye = None
    if target_in_world is not None:
        target = np.asarray(target_in_world, dtype=np.float64)
        eye = rrb.EyeControls3D(position=target + np.array([0.07, -0.10, 0.08]), look_target=target)
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(
                origin="world", name="probing", time_ranges=history, eye_controls=eye
            ),
            rrb.Vertical(
                rrb.TimeSeriesView(origin="sensors/deflection", name="stylus deflection"),
                rrb.TimeSeriesView(origin="sensors/force", name="tip force"),
                rrb.Tabs(
                    rrb.Spatial3DView(origin="recognition/models", name="recognition"),
                    rrb.TextDocumentView(origin="recognition/ranking", name="ranking"),
                    rrb.TextLogView(origin="log", name="log"),
                ),
            ),
            column_shares=[3, 2],
        ),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(timeline="sim_time"),
    )


def record_probe_run(
    session,
    result=None,
    database=None,
    *,
    mode: str = "save",
    path: str | Path | None = None,
    application_id: str = APPLICATION_ID,
) -> str | None:
    """Records a probing session and its recognition; returns what to tell the user.

    Parameters
    ----------
    session : tactile_sim.probing.ProbeSession
    result : recognition.Recognition or None
    database : recognition.ModelDatabase or None
    mode : {"save", "spawn", "serve"}
        "save" writes ``path``; "spawn" also streams to a native viewer it starts;
        "serve" writes ``path`` for :func:`serve_recording` to serve to a browser.
    path : str, Path or None
        The .rrd file (required for "save" and "serve"; optional for "spawn").
    application_id : str
        Groups recordings in the viewer.

    Returns
    -------
    str or None
        The .rrd path written, or a line about the spawned viewer.

    Raises
    ------
    RecordingError
        The file cannot be written, or ("spawn") there is no display for the viewer.
    """
    import rerun as rr

    if mode not in MODES:
        raise ValueError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
    if path is None and mode != "spawn":
        raise ValueError(f"mode {mode!r} needs a path for the .rrd file")
    recording_id = f"{session.object_name}-seed{session.seed}-{time.time_ns():x}"
    rec = rr.RecordingStream(application_id, recording_id=recording_id)
    blueprint = probe_blueprint(session.curves.intersection)
    if path is not None:
        path = Path(path)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise RecordingError(f"cannot create {path.parent}: {error}") from error
    try:
        if mode == "spawn":
            check_display()
            rr.spawn(connect=False, executable_path=_rerun_executable(), recording=rec)
            sinks = [rr.GrpcSink()] + ([rr.FileSink(str(path))] if path else [])
            rec.set_sinks(*sinks, default_blueprint=blueprint)
        else:
            rec.save(path, default_blueprint=blueprint)
        log_probe_run(rec, session, result, database)
    finally:
        rec.disconnect()
    if path is not None and not path.is_file():
        raise RecordingError(f"rerun did not write {path}")
    if mode == "spawn":
        return "streamed to the native viewer" + (f"; saved {path}" if path else "")
    return str(path)


# Viewers -------------------------------------------------------------------------------------


def _rerun_executable() -> str:
    """The rerun command-line viewer shipped with rerun-sdk."""
    import rerun_cli

    bundled = Path(rerun_cli.__file__).parent / "rerun"
    if bundled.is_file():
        return str(bundled)
    found = shutil.which("rerun")
    if found is None:
        raise RecordingError("the rerun viewer executable is missing: reinstall rerun-sdk")
    return found


def _port_free(host: str, port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind((host, port))
        except OSError:
            return False
    return True


def _free_port(host: str, avoid: Sequence[int] = ()) -> int:
    while True:
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
            s.bind((host, 0))
            port = int(s.getsockname()[1])
        if port not in avoid:
            return port


def check_ports(web_port: int = 9090, grpc_port: int = 9876, host: str = "127.0.0.1") -> None:
    """Checks that the web viewer's ports are free on ``host``.

    Raises
    ------
    PortInUse
        A port is taken; the message names the option to pass and a free port.
    """
    if web_port == grpc_port:
        raise ValueError(f"the web and gRPC ports must differ, both are {web_port}")
    if not _port_free(host, web_port):
        raise PortInUse(web_port, "--web-port", _free_port(host, (grpc_port,)))
    if not _port_free(host, grpc_port):
        raise PortInUse(grpc_port, "--grpc-port", _free_port(host, (web_port,)))


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt


class WebViewer:
    """A running web viewer (``rerun --serve-web``) serving one recording on one host.

    Use as a context manager, or call :meth:`close`.

    Attributes
    ----------
    url : str
        Open this in a browser: the viewer page, connected to the recording's server.
    process : subprocess.Popen
    """

    def __init__(self, process: subprocess.Popen, url: str) -> None:
        self.process = process
        self.url = url

    def wait(self) -> int:
        """Blocks until the server stops (Ctrl-C or SIGTERM stop it); returns its exit
        status (0 when stopped here)."""
        main = threading.current_thread() is threading.main_thread()
        previous = signal.signal(signal.SIGTERM, _interrupt) if main else None
        try:
            return self.process.wait()
        except KeyboardInterrupt:
            return 0
        finally:
            self.close()
            if main:
                signal.signal(signal.SIGTERM, previous)

    def close(self) -> None:
        """Stops the server."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()

    def __enter__(self) -> WebViewer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def serve_recording(
    path: str | Path,
    *,
    web_port: int = 9090,
    grpc_port: int = 9876,
    host: str = "127.0.0.1",
    timeout_s: float = 30.0,
) -> WebViewer:
    """Serves a recording to browsers: the web viewer over HTTP, the data over gRPC.

    Both servers bind ``host`` only (loopback by default).

    Parameters
    ----------
    path : str or Path
        The .rrd file; checked first (:func:`read_recording`).
    web_port, grpc_port : int
        HTTP port of the viewer page, gRPC port of the data.
    host : str
        Address both servers bind.
    timeout_s : float, seconds
        How long to wait for the servers to come up.

    Raises
    ------
    InvalidRecording
        The file is missing, truncated or not a recording.
    PortInUse
        A port is taken; the message names a free one.
    RecordingError
        The viewer did not start.
    """
    path = Path(path)
    read_recording(path)
    check_ports(web_port, grpc_port, host)
    log = tempfile.TemporaryFile()
    process = subprocess.Popen(
        [
            _rerun_executable(),
            "--serve-web",
            "--bind",
            host,
            "--web-viewer-port",
            str(web_port),
            "--port",
            str(grpc_port),
            str(path),
        ],
        stdout=log,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
    )
    viewer = WebViewer(process, _viewer_url(host, web_port, grpc_port))
    deadline = time.monotonic() + timeout_s
    while not (_listening(host, web_port) and _listening(host, grpc_port)):
        if process.poll() is not None or time.monotonic() > deadline:
            viewer.close()
            log.seek(0)
            tail = log.read().decode(errors="replace").strip().splitlines()[-3:]
            raise RecordingError(
                f"the web viewer did not start on {host}:{web_port}: " + " / ".join(tail)
            )
        time.sleep(0.1)
    return viewer


def _listening(host: str, port: int) -> bool:
    with contextlib.suppress(OSError), socket.create_connection((host, port), timeout=0.5):
        return True
    return False


def _viewer_url(host: str, web_port: int, grpc_port: int) -> str:
    source = urllib.parse.quote(f"rerun+http://{host}:{grpc_port}/proxy", safe="")
    return f"http://{host}:{web_port}/?url={source}"


def check_display() -> None:
    """Checks that the native viewer has a display to open a window on.

    Raises
    ------
    RecordingError
        Linux without DISPLAY or WAYLAND_DISPLAY; the message names the web viewer instead.
    """
    if sys.platform.startswith("linux") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    ):
        raise RecordingError(
            "no display for the native viewer (DISPLAY is not set): use the web viewer "
            "(scripts/probe.py --rerun serve, scripts/replay.py FILE --web)"
        )


def open_native_viewer(path: str | Path) -> int:
    """Opens a recording in the native viewer and waits until it is closed.

    Raises
    ------
    InvalidRecording
        The file is missing, truncated or not a recording.
    RecordingError
        The viewer failed (e.g. no display); the message says what to do instead.
    """
    path = Path(path)
    read_recording(path)
    check_display()
    status = subprocess.call([_rerun_executable(), "--bind", "127.0.0.1", str(path)])
    if status not in (0, 130):
        raise RecordingError(
            f"the native viewer exited with status {status} (no display? serve the "
            "recording to a browser instead: --web)"
        )
    return status


# Overhead ----------------------------------------------------------------------------------


def recording_overhead(
    obj: str = "cat",
    seeds: Sequence[int] = (0, 1, 2),
    *,
    n_points: int = 21,
    trajectory_hz: float = 200.0,
    database=None,
    directory: str | Path | None = None,
) -> dict:
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
