"""One probing run end to end: probe an object, recognise it, measure it against the truth, save.

What ``scripts/probe.py`` (and ``make demo``) runs: the simulated robot probes a catalog
object (:func:`~tactile_sim.probing.probe_object`), the catalog database recognises the
curves, the estimate is compared with the ground truth, and the curves (.npz) and the
recording (.rrd) are saved.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from recognition.errors import InvalidArgument
from recognition.files import write_json_atomic
from recognition.rigid import rotation_angle
from recognition.surfaces.mesh_repair import MeshReport
from tactile_sim.collision.parts import safe_name
from tactile_sim.evaluation.benchmark_config import RUNS_DIR
from tactile_sim.recording.viewer import GRPC_PORT, WEB_PORT

if TYPE_CHECKING:
    from recognition import ModelDatabase
    from tactile_sim.probing import ProbeTarget

__all__ = ["RERUN_MODES", "ProbeRunConfig", "pose_error", "probe_run"]

#: What is done with the recording: saved, shown in a native viewer, served to a browser,
#: or not made.
RERUN_MODES = ("save", "spawn", "serve", "off")


@dataclass(frozen=True)
class ProbeRunConfig:
    """What to probe and where to put the results.

    Attributes
    ----------
    object_name : str
        A catalog object (``tactile_sim.objects.object_names()``); ignored with ``mesh``.
    mesh : Path or None
        Probe this mesh file instead (:func:`~tactile_sim.probing.mesh_target`: any of
        OBJ, PLY, STL, OFF, GLB, glTF, open or in pieces), resting on the table in one of
        its stable poses (drawn from ``seed``).
    units : str
        Units of ``mesh`` ("m", "mm", "cm" or "in").
    database : Path or None
        Recognise against this saved database (``ModelDatabase.save``); default: the
        catalog's, with ``mesh`` the catalog's models and the mesh's (built once, cached
        by the mesh's content).
    seed : int
        Seeds the object's pose, the probed point, the planes and the sensor noise.
    n_points, spacing_mm, plane_angle_deg
        Points per curve, their spacing and the angle between sampling planes
        (thesis Section 4.4.3: 21, 1.2 mm, 60 degrees).
    out : Path or None
        Directory for the curves (.npz) and the recording; default runs/.
    rerun : str
        "save" (an .rrd file), "spawn" (open the viewer), "serve" (web viewer on
        127.0.0.1) or "off".
    web_port, grpc_port : int
        Ports of the web viewer ("serve"): HTTP for the page, gRPC for the data.
    trajectory_hz : float
        Rate (per second of simulated time) at which the recording samples the robot.
    model_error_mm : float
        RMS (mm) of a smooth random displacement of the probed object from its model
        along the normals, seeded by ``seed`` (:func:`~tactile_sim.probing.displaced_target`):
        the object differs from the database's model as a real one from its scan, and
        recognition is told so (:attr:`recognition.FastConfig.model_mismatch_m`). 0: none.
    model_error_correlation_mm : float
        Correlation length of that displacement, mm.
    json_path : Path or None
        Where to write the summary as JSON too (written atomically).
    touches : int
        Verification touches after the sweeps, at most
        (:func:`~tactile_sim.probing.touches.touch_until_sure`): the robot touches where
        the hypotheses disagree until the answer's confidence reaches 0.99. 0: the
        thesis's three curves alone.
    """

    object_name: str = "cat"
    mesh: Path | None = None
    units: str = "m"
    database: Path | None = None
    seed: int = 0
    n_points: int = 21
    spacing_mm: float = 1.2
    plane_angle_deg: float = 60.0
    out: Path | None = None
    rerun: str = "save"
    web_port: int = WEB_PORT
    grpc_port: int = GRPC_PORT
    trajectory_hz: float = 200.0
    model_error_mm: float = 0.0
    model_error_correlation_mm: float = 5.0
    json_path: Path | None = None
    touches: int = 5

    @property
    def out_dir(self) -> Path:
        """Where the run's files go."""
        return Path(self.out) if self.out else RUNS_DIR


def pose_error(
    T_estimated: np.ndarray, T_true: np.ndarray, points: np.ndarray
) -> tuple[float, float]:
    """Returns the rotation error (degrees) between two 4x4 poses and the mean distance
    (metres) between where they put ``points`` (n, 3): the data on the model."""
    angle = np.degrees(rotation_angle(T_estimated[:3, :3] @ T_true[:3, :3].T))
    moved = points @ (T_estimated[:3, :3] - T_true[:3, :3]).T + (T_estimated - T_true)[:3, 3]
    return float(angle), float(np.linalg.norm(moved, axis=1).mean())


def probe_run(config: ProbeRunConfig) -> dict[str, Any]:
    """Probe, recognise, compare with the ground truth, save curves and recording.

    Returns
    -------
    dict
        JSON-ready: ``object``, ``seed``, ``recognized``, ``correct``, ``ranking_mm``
        (None: rejected at table lookup), ``margin_mm``, ``truncated_sweeps``,
        ``timings_s`` (the object's meshes, displaced by the model error if any, the
        database load, probing with its scene build, recognition, total),
        ``outliers`` (indices of the points recognition rejected), ``model_error_mm``
        (requested and achieved RMS, correlation; with a model error),
        ``location_error_mm`` (from where the data's p lies on the object),
        ``pose_error_deg``, ``pose_error_mm`` (when the true model located p),
        ``curves_file`` and ``recording`` (unless off).

    Raises
    ------
    UnknownObject
        ``object_name`` is not a catalog object.
    SimulationError
        ``model_error_mm`` or its correlation length is negative or not finite.
    PortInUse, RecordingError
        The viewer cannot be served or shown (checked before probing).
    """
    from recognition import FastConfig
    from tactile_sim.errors import UnknownObject
    from tactile_sim.objects import object_names
    from tactile_sim.objects.mismatch import DisplacementField
    from tactile_sim.probing import displaced_target, probe_object

    if config.mesh is None and config.object_name not in object_names():
        raise UnknownObject(config.object_name, object_names())
    displacement = DisplacementField(
        config.model_error_mm * 1e-3, config.model_error_correlation_mm * 1e-3, config.seed
    )
    if config.rerun == "serve":
        from tactile_sim.recording import check_ports

        check_ports(config.web_port, config.grpc_port)
    elif config.rerun == "spawn":
        from tactile_sim.recording import check_display

        check_display()
    start = time.perf_counter()
    target, report = _target(config)
    target = displaced_target(target, displacement)
    name = target.name
    prepared = time.perf_counter()
    database = _database(config, target, report)
    loaded = time.perf_counter()
    session = probe_object(
        target,
        seed=config.seed,
        n_points=config.n_points,
        spacing_m=config.spacing_mm * 1e-3,
        plane_angle_deg=config.plane_angle_deg,
        trajectory_hz=None if config.rerun == "off" else config.trajectory_hz,
    )
    probed = time.perf_counter()
    registration = database.registration
    if isinstance(registration, FastConfig):
        registration = replace(registration, model_mismatch_m=displacement.rms_m)
    result = database.recognize(session.curves, registration)
    recognized = time.perf_counter()
    touched = None
    if config.touches > 0:
        from tactile_sim.probing.touches import touch_until_sure

        touched = touch_until_sure(
            session, database, max_touches=config.touches, recognition=result
        )
    finished = time.perf_counter()

    truth = session.ground_truth
    T_object_from_world = np.linalg.inv(truth.T_world_from_object)
    summary: dict[str, Any] = {
        "object": name,
        "seed": config.seed,
        "recognized": result.name,
        "correct": result.name == name,
        "ranking_mm": [(n, e * 1e3 if np.isfinite(e) else None) for n, e in result.ranking],
        "margin_mm": result.margin_m * 1e3,
        "truncated_sweeps": list(session.messages),
        "timings_s": {
            "object": prepared - start,
            "database": loaded - prepared,
            "probing": probed - loaded,
            "scene_build": session.build_seconds,
            "recognition": recognized - probed,
            "touches": finished - recognized,
            "total": finished - start,
        },
        "outliers": [int(i) for i in result.outliers],
        "confidence": result.confidence,
        "belief_best": None
        if result.belief is None or result.belief.best is None
        else result.belief.best.model,
    }
    if config.model_error_mm > 0:
        summary["model_error_mm"] = {
            "requested_rms": config.model_error_mm,
            "achieved_rms": truth.model_error_rms_m * 1e3,
            "correlation": config.model_error_correlation_mm,
        }
    if report is not None:
        summary["mesh_repairs"] = list(report.notes)
    own = result.registrations.get(name)
    if own is not None and np.all(np.isfinite(own.location)):
        summary["location_error_mm"] = float(
            np.linalg.norm(own.location - truth.data_point_in_object) * 1e3
        )
        data = np.concatenate(session.curves.curves)
        angle, shift = pose_error(own.T_model_from_data, T_object_from_world, data)
        summary["pose_error_deg"], summary["pose_error_mm"] = angle, shift * 1e3
    if touched is not None:
        summary["touches"] = _touch_summary(touched, name, truth.data_point_in_object)

    out = config.out_dir
    out.mkdir(parents=True, exist_ok=True)
    stem = f"{time.strftime('%Y%m%d-%H%M%S')}_{safe_name(name)}_seed{config.seed}"
    session.curves.save(out / f"{stem}_curves.npz")
    summary["curves_file"] = str(out / f"{stem}_curves.npz")
    if config.rerun != "off":
        from tactile_sim.recording import record_probe_run

        summary["recording"] = record_probe_run(
            session,
            result,
            database,
            touches=touched,
            mode=config.rerun,
            path=out / f"{stem}.rrd",
        )
    if config.json_path is not None:
        write_json_atomic(Path(config.json_path), summary)
    return summary


def _touch_summary(touched: Any, name: str, point_in_object: np.ndarray) -> dict[str, Any]:
    """JSON-ready: each touch's confidence and best model, the answer after the touches
    (its model, confidence, location error on the object when it names it) and times."""
    belief = touched.verification.belief
    best = belief.best
    out: dict[str, Any] = {
        "made": [
            {
                "confidence": t.confidence,
                "best": t.best_model,
                "contact": t.point_in_world is not None and t.no_reading is None,
                "no_reading": t.no_reading,
                "recognition_time_s": t.recognition_time_s,
                "robot_time_s": t.robot_time_s,
            }
            for t in touched.touches
        ],
        "stop": touched.verification.stop,
        "recognized": None if best is None else best.model,
        "correct": best is not None and best.model == name,
        "confidence": belief.confidence,
    }
    if best is not None and best.model == name:
        out["location_error_mm"] = best.location_error_m(point_in_object) * 1e3
    return out


def _target(config: ProbeRunConfig) -> tuple[ProbeTarget, MeshReport | None]:
    """The object to probe and, for a mesh file, what was repaired to make it a model."""
    from tactile_sim.objects import object_names
    from tactile_sim.probing import mesh_target, resolve_object

    if config.mesh is None:
        return resolve_object(config.object_name), None
    target, report = mesh_target(config.mesh, config.units)
    if config.database is None and target.name in object_names():
        raise InvalidArgument(
            f"a catalog object is called {target.name!r}: rename {config.mesh} to probe it "
            "against the catalog"
        )
    return target, report


def _database(
    config: ProbeRunConfig, target: ProbeTarget, report: MeshReport | None
) -> ModelDatabase:
    """The database to recognise against: the given one, the catalog's, or the catalog's
    with the probed mesh's model (built once, cached by its content)."""
    from recognition import ModelDatabase
    from recognition.surfaces.mesh_model import MeshModel
    from tactile_sim.objects.cache import generated_dir
    from tactile_sim.objects.database import cached_database, catalog_database

    if config.database is not None:
        return ModelDatabase.load(config.database)
    catalog = catalog_database()
    if report is None:
        return catalog
    model = MeshModel(target.name, target.mesh, validate=False, report=report)
    assert catalog.directory is not None
    key = f"{catalog.directory.name}-{model.hash[:16]}"

    def build() -> ModelDatabase:
        return ModelDatabase({**catalog.models, target.name: model}).prepare()

    directory = generated_dir("database") / f"with-{safe_name(target.name)}-{key}"
    return cached_database(directory, build, f"the catalog's database with {target.name!r}")
