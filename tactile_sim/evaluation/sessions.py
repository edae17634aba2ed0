"""The robot as a benchmark instance source: probing sessions of thesis Section 4.4.

:class:`SimulatedSource` makes recognition-benchmark instances by probing an object with
the simulated Cobra 600 (three sweeps through one point, :func:`probe_object`): each
instance is regenerated from its seed alone (:func:`session_seed`), so any worker of
:func:`recognition.evaluation.run` can make it. :func:`catalog_experiment` is the
Table 4.6 / 4.7 setting (the ten catalog objects, 3 x 21 points at 1.2 mm, planes 60
degrees apart), :func:`solids_experiment` the Table 4.5 one (the four solids of
Fig. 4.15, n = 41, d = 0.05 mm).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from recognition import DataCurves, RecognitionError
from recognition.evaluation import Instance, InstanceSpec
from recognition.rigid import apply_pose
from recognition.surfaces.distance import MeshDistance
from tactile_sim.collision import solid_names
from tactile_sim.errors import InvalidSettings, SimulationError, UnknownObject
from tactile_sim.evaluation.mesh_distances import mesh_distance
from tactile_sim.objects import object_names
from tactile_sim.objects.mismatch import DisplacementField
from tactile_sim.probing import (
    ProbingConfig,
    check_sweep,
    displaced_target,
    mesh_target,
    probe_object,
    resolve_object,
)
from tactile_sim.probing.session import data_point_in_object
from tactile_sim.probing.touches import RobotToucher
from tactile_sim.sensor import SensorConfig

__all__ = [
    "FIG_4_15_SOLIDS",
    "SimulatedSource",
    "catalog_experiment",
    "session_seed",
    "solids_experiment",
]

#: The four algebraic objects of thesis Fig. 4.15 (the Table 4.5 columns).
FIG_4_15_SOLIDS = ("cylinder_1", "cylinder_2", "elliptic_cylinder", "sphere")

_CURVES = ("sensed", "true_contacts")


def session_seed(base_seed: int, name: str, index: int) -> int:
    """Returns the seed of session ``index`` of object ``name``: a hash of the three."""
    digest = hashlib.sha256(repr(("session", base_seed, name, index)).encode()).digest()
    return int.from_bytes(digest[:4], "little") >> 1


@dataclass(frozen=True)
class SimulatedSource:
    """Benchmark instances probed by the simulated robot (thesis Section 4.4.1).

    Instance ``k`` of object ``name`` is one :func:`probe_object` session with the seed
    :func:`session_seed` (seed, name, k): that seed draws the object's pose on the table,
    the point p, the first plane's yaw and the sensor noise.

    Attributes
    ----------
    objects : tuple of str
        Catalog or solid names.
    sessions_per_object : int
        Sessions (instances) per object.
    first_session : int
        Index of each object's first session (sessions ``first_session`` to
        ``first_session + sessions_per_object - 1``: later sessions of the same
        experiment, without the earlier ones).
    n_points : int
        Points per curve, p included (thesis: 21 on the free-form objects, 41 on the
        solids).
    spacing_m : float, metres
        Distance between neighbouring points (thesis: 1.2 mm; 0.05 mm on the solids).
    plane_angle_deg : float, degrees
        Angle between neighbouring sampling planes (thesis: 60).
    curves : {"sensed", "true_contacts"}
        What an instance's data curves are: the sensed points (the experiment), or the
        simulator's true contact points of the same session (no sensor error: a
        diagnosis). The other one is the instance's reference.
    probing : ProbingConfig
        Sweep controller.
    sensor : SensorConfig
        Sensor model (noise).
    seed : int
    model_error_m : float, metres
        RMS of the smooth random displacement of each probed object from its model
        (:func:`~tactile_sim.probing.displaced_target`; seeded per session); 0: the
        object is its model.
    model_error_correlation_m : float, metres
        Correlation length of that displacement.
    meshes : tuple of (name, path) pairs
        Mesh files that may be probed as objects of these names
        (:func:`~tactile_sim.probing.mesh_target`; resting in a seeded stable pose).
    units : str
        Units of the mesh files.
    """

    objects: tuple[str, ...] = field(default_factory=object_names)
    sessions_per_object: int = 3
    first_session: int = 0
    n_points: int = 21
    spacing_m: float = 1.2e-3
    plane_angle_deg: float = 60.0
    curves: str = "sensed"
    probing: ProbingConfig = field(default_factory=ProbingConfig)
    sensor: SensorConfig = field(default_factory=SensorConfig)
    seed: int = 0
    model_error_m: float = 0.0
    model_error_correlation_m: float = 5e-3
    meshes: tuple[tuple[str, str], ...] = ()
    units: str = "m"

    def __post_init__(self) -> None:
        DisplacementField(self.model_error_m, self.model_error_correlation_m)  # valid?
        known = (*object_names(), *solid_names(), *(name for name, _ in self.meshes))
        for name in self.objects:
            if name not in known:
                raise UnknownObject(name, known)
        if self.curves not in _CURVES:
            raise InvalidSettings(f"curves must be one of {_CURVES}, got {self.curves!r}")
        check_sweep(self.n_points, self.spacing_m, self.plane_angle_deg)
        if self.sessions_per_object < 1 or self.first_session < 0:
            raise InvalidSettings(
                f"sessions_per_object must be >= 1 and first_session >= 0, got "
                f"{self.sessions_per_object} and {self.first_session}"
            )

    def specs(self, database: object = None) -> list[InstanceSpec]:
        """Returns the instance specs: ``sessions_per_object`` per object, in order.

        ``database`` is not used: the objects are probed wherever the seed puts p.
        """
        return [
            InstanceSpec(name, k, None, session_seed(self.seed, name, k))
            for name in self.objects
            for k in range(self.first_session, self.first_session + self.sessions_per_object)
        ]

    def instance(self, database: object, spec: InstanceSpec) -> Instance:
        """Probes the spec's object with the spec's seed; returns a benchmark instance.

        The instance's ``info`` holds the session's facts: probing wall and simulated
        time, points per curve, truncated sweep sides, the errors of the points (mean
        and max, mm: the sensed points from the true contact points, where MuJoCo's
        contact met the surface the tip touched; the true contact points from the
        probed object's mesh; the sensed points from that mesh), their spacing, and the
        achieved RMS distance of the probed object from its model (``model_error_m``). A session
        that fails (a sweep left with too few points, an unreachable point, an unstable
        simulation) gives an instance without curves whose ``info["error"]`` says why.

        The instance's true point is where the data's common point p (the point the
        recogniser locates, :func:`recognition.surfaces.registration.common_point`) lies
        on the object, by the object's true pose.
        """
        try:
            files = dict(self.meshes)
            if spec.model in files:
                target, _ = mesh_target(files[spec.model], self.units, name=spec.model)
            else:
                target = resolve_object(spec.model, progress=False)
            displacement = DisplacementField(
                self.model_error_m, self.model_error_correlation_m, spec.seed
            )
            target = displaced_target(target, displacement)
            session = probe_object(
                target,
                seed=spec.seed,
                n_points=self.n_points,
                spacing_m=self.spacing_m,
                plane_angle_deg=self.plane_angle_deg,
                config=self.probing,
                sensor=self.sensor,
                progress=False,
            )
        except UnknownObject:
            raise
        except SimulationError as exc:
            return Instance(None, None, {"error": f"{type(exc).__name__}: {exc}"})
        truth = session.ground_truth
        try:
            true_curves: DataCurves | None = DataCurves(
                curves=truth.true_contact_points_in_world, approach=session.curves.approach
            )
        except RecognitionError as exc:  # MuJoCo's contacts need not make data curves
            true_curves, reference_error = None, f"{type(exc).__name__}: {exc}"
        sensed_error = np.concatenate(
            [
                np.linalg.norm(s.points_in_world - s.true_contact_points_in_world, axis=1)
                for s in session.sweeps
            ]
        )
        surface = (
            mesh_distance(spec.model)
            if target.model_error_rms_m == 0 and spec.model not in dict(self.meshes)
            else MeshDistance(target.mesh.vertices, target.mesh.faces)
        )
        T_object_from_world = np.linalg.inv(truth.T_world_from_object)
        contacts = np.concatenate(truth.true_contact_points_in_world)
        contact_error = surface.closest(apply_pose(T_object_from_world, contacts))[0]
        sensed_off_mesh = surface.closest(apply_pose(T_object_from_world, session.curves.points))[0]
        steps = np.concatenate(
            [np.linalg.norm(np.diff(s.points_in_world, axis=0), axis=1) for s in session.sweeps]
        )
        info = {
            "curves": self.curves,
            "points_per_curve": [len(c) for c in session.curves.curves],
            "truncated": list(session.messages),
            "probe_time_s": session.wall_seconds,
            "sim_time_s": session.sim_seconds,
            "sensed_error_mean_mm": float(sensed_error.mean() * 1e3),
            "sensed_error_max_mm": float(sensed_error.max() * 1e3),
            "contact_vs_mesh_mean_mm": float(contact_error.mean() * 1e3),
            "contact_vs_mesh_max_mm": float(contact_error.max() * 1e3),
            "sensed_vs_mesh_mean_mm": float(sensed_off_mesh.mean() * 1e3),
            "sensed_vs_mesh_max_mm": float(sensed_off_mesh.max() * 1e3),
            "spacing_mean_mm": float(steps.mean() * 1e3),
            "spacing_std_mm": float(steps.std() * 1e3),
            "model_error_rms_mm": target.model_error_rms_m * 1e3,
        }
        if true_curves is None:
            info["reference_error"] = reference_error
            if self.curves != "sensed":
                return Instance(None, None, info | {"error": reference_error})
        if self.curves == "sensed":
            curves, reference = session.curves, true_curves
        else:
            assert true_curves is not None
            curves, reference = true_curves, session.curves
        point = data_point_in_object(curves, truth.T_world_from_object)
        toucher = RobotToucher(session)
        return Instance(
            curves, point, info, reference, toucher, toucher.limits, T_object_from_world
        )


def catalog_experiment(**overrides: Any) -> SimulatedSource:
    """Returns the Table 4.6 / 4.7 setting: the ten catalog objects, 3 x 21 points at
    1.2 mm, planes 60 degrees apart (``overrides`` replace fields)."""
    return SimulatedSource(**{"objects": object_names(), **overrides})


def solids_experiment(**overrides: Any) -> SimulatedSource:
    """Returns the Table 4.5 setting: the four solids of Fig. 4.15, n = 41 points at
    d = 0.05 mm (``overrides`` replace fields)."""
    settings = {"objects": FIG_4_15_SOLIDS, "n_points": 41, "spacing_m": 0.05e-3}
    return SimulatedSource(**{**settings, **overrides})
