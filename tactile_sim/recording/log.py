"""Logging a probing session and its recognition to a rerun recording stream.

Entity paths mirror the physical tree: ``world/table``, ``world/object``,
``world/robot/<body>``, ``world/probe/{tip,sensed,contacts,normals}``,
``world/curves/{alpha,beta,gamma,p}``; the verification touches to
``world/touches/<k>/{approach,contact}`` and the hypotheses they tell apart, as ghost
models at their poses, to ``world/hypotheses/<rank>``; the stylus signals go to
``sensors/deflection`` and ``sensors/force``, the recognition to
``recognition/{ranking,models/<name>}`` and the messages to ``log``. Static things are
logged once; the rest on the timelines ``step`` and ``sim_time``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.rigid import apply_pose

if TYPE_CHECKING:
    import rerun as rr

    from recognition import Belief, ModelDatabase, Recognition
    from tactile_sim.probing import ProbeSession
    from tactile_sim.probing.touches import TouchSession
    from tactile_sim.trajectory import Trajectory, VisualGeom

__all__ = [
    "CURVE_NAMES",
    "log_probe_run",
]


CURVE_NAMES = ("alpha", "beta", "gamma")
"""Names of the three data curves (thesis Section 4.3), in sweep order."""

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
_GHOSTS = 3
"""Hypotheses drawn as ghost models at their poses, most probable first."""
_GHOST_POINTS = 2000
_GHOST_COLORS = np.array([[80, 220, 120, 90], [230, 120, 220, 70], [120, 200, 240, 60]], np.uint8)
_APPROACH_COLOR = (255, 90, 30, 255)


def _body_path(body: str) -> str:
    """Entity path of a MuJoCo body: the table, the object or a part of the robot."""
    if body == "world":
        return "world/table"
    if body.endswith("/object"):
        return "world/object"
    return f"world/robot/{body}"


def _geom_path(geom: VisualGeom) -> str:
    """Entity path of a drawn geom, below its body's."""
    short = geom.name.rsplit("/", 1)[-1]
    return f"{_body_path(geom.body)}/{short}"


def _xyzw(quat_wxyz: NDArray[np.float64]) -> NDArray[np.float64]:
    """MuJoCo's (..., 4) wxyz quaternions as rerun's xyzw."""
    return np.concatenate([quat_wxyz[..., 1:], quat_wxyz[..., :1]], axis=-1)


def _rgba8(rgba: ArrayLike) -> NDArray[np.uint8]:
    """Colour in [0, 1] as 8-bit RGBA."""
    return np.clip(np.round(np.asarray(rgba) * 255.0), 0, 255).astype(np.uint8)


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
    """The ``step`` and ``sim_time`` columns of samples at those steps and times."""
    import rerun as rr

    return [
        rr.TimeColumn("step", sequence=np.asarray(steps, dtype=np.int64)),
        rr.TimeColumn("sim_time", duration=np.asarray(times_s, dtype=np.float64)),
    ]


def _log_scene(rec: rr.RecordingStream, trajectory: Trajectory) -> None:
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


def _log_motion(rec: rr.RecordingStream, trajectory: Trajectory) -> None:
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


def _log_readings(rec: rr.RecordingStream, session: ProbeSession, timestep_s: float | None) -> None:
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


def _set_time(rec: rr.RecordingStream, time_s: float, timestep_s: float | None) -> None:
    """Sets the stream's ``sim_time`` (and ``step``, when the timestep is known)."""
    rec.set_time("sim_time", duration=time_s)
    if timestep_s is not None:
        rec.set_time("step", sequence=round(time_s / timestep_s))


def _ranking_markdown(session: ProbeSession, result: Recognition) -> str:
    """The recognition's ranking as a Markdown table."""
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


def _log_recognition(
    rec: rr.RecordingStream,
    session: ProbeSession,
    result: Recognition,
    database: ModelDatabase | None,
) -> None:
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
        registered = apply_pose(T, curve)
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


def _log_hypotheses(
    rec: rr.RecordingStream, belief: Belief, database: ModelDatabase, title: str
) -> None:
    """The belief's most probable hypotheses as ghost models placed in the world (the
    curves' frame) by their poses, labelled with their posterior."""
    import rerun as rr

    hypotheses = belief.hypotheses[:_GHOSTS]
    for rank in range(_GHOSTS):
        path = f"world/hypotheses/{rank}"
        if rank >= len(hypotheses):
            rec.log(path, rr.Clear(recursive=True))
            continue
        h = hypotheses[rank]
        vertices = np.asarray(database[h.model].vertices)
        shown = np.random.default_rng(rank).choice(
            len(vertices), min(_GHOST_POINTS, len(vertices)), replace=False
        )
        T = np.linalg.inv(h.T_model_from_data)  # world from model
        rec.log(
            path,
            rr.Points3D(
                apply_pose(T, vertices[np.sort(shown)]),
                colors=[_GHOST_COLORS[rank]],
                radii=[0.2e-3],
            ),
        )
        rec.log(
            f"{path}/label",
            rr.Points3D(
                [apply_pose(T, h.location[None])[0]],
                labels=[f"{h.model} {h.posterior:.2f}"],
                radii=[0.5e-3],
            ),
        )
    rec.log(
        "log",
        rr.TextLog(
            f"{title}: confidence {belief.confidence:.3f}; "
            + ", ".join(f"{h.model} {h.posterior:.2f}" for h in hypotheses),
            level="INFO",
        ),
    )


def _log_touches(
    rec: rr.RecordingStream,
    touches: TouchSession,
    database: ModelDatabase | None,
    timestep_s: float | None,
) -> None:
    """Each planned touch (its approach as an arrow), its sensed contact and the
    hypotheses before and after it."""
    import rerun as rr

    belief = touches.recognition.belief
    if database is not None and belief is not None:
        _log_hypotheses(rec, belief, database, "after the sweeps")
    for k, (touch, step) in enumerate(
        zip(touches.touches, touches.verification.steps, strict=True), start=1
    ):
        _set_time(rec, touch.sim_time_s, timestep_s)
        plan = touch.plan
        path = f"world/touches/{k}"
        rec.log(
            f"{path}/approach",
            rr.Arrows3D(
                origins=[plan.start],
                vectors=[plan.travel_m * plan.direction],
                colors=[_APPROACH_COLOR],
                radii=[0.15e-3],
            ),
            static=True,
        )
        if touch.point_in_world is not None:
            rec.log(
                f"{path}/contact",
                rr.Points3D(
                    [touch.point_in_world],
                    colors=[_CONTACT_COLOR],
                    radii=[0.6e-3],
                    labels=[f"touch {k}" + (" (not used)" if touch.no_reading else "")],
                ),
                static=True,
            )
        met = "contact" if touch.point_in_world is not None else "no contact"
        if touch.no_reading is not None:
            met = "no reading: the shaft touched"
        if database is not None:
            _log_hypotheses(rec, step.belief, database, f"touch {k} ({met})")


def log_probe_run(
    rec: rr.RecordingStream,
    session: ProbeSession,
    result: Recognition | None = None,
    database: ModelDatabase | None = None,
    touches: TouchSession | None = None,
) -> None:
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
    touches : TouchSession or None
        The verification touches after the sweeps (their approaches, contacts, and the
        hypotheses as ghost models after the sweeps and after each touch).
    """
    import rerun as rr

    trajectory: Trajectory | None = session.trajectory
    if touches is not None and touches.trajectory is not None:
        trajectory = touches.trajectory
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
    if touches is not None:
        _log_touches(rec, touches, database, timestep)
