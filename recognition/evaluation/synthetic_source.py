"""Benchmark instances sampled on the models themselves (thesis Section 4.3.4)."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

from recognition.errors import InvalidCurveData, RecognitionError
from recognition.evaluation.instances import Instance, InstanceSpec
from recognition.surfaces.active_touch import Contact
from recognition.surfaces.database import ModelDatabase
from recognition.surfaces.noise_model import NoiseModel
from recognition.surfaces.touch_planning import TouchLimits, TouchPlan
from recognition.synthetic import (
    SyntheticCurves,
    mesh_data_curves,
    ray_contact,
    sampling_plane_normals,
    sensed_normal,
)

__all__ = ["SyntheticSource", "instance_specs", "make_curves"]


@dataclass(frozen=True)
class SyntheticSource:
    """How synthetic instances are made (thesis Section 4.3.4 defaults).

    Instances are drawn per model: well-separated vertices (no two within
    ``separation_m``), three sampling planes containing the vertex normal
    ``plane_angle_deg`` apart, ``n_points`` per curve at ``spacing_m``, Gaussian noise, a
    random rigid motion.

    Attributes
    ----------
    per_model : int
        Instances per model (thesis: 10).
    n_points : int
        Points per curve (thesis: 81).
    spacing_m : float
        Arc length between points (thesis: 0.3 mm), so l = (n - 1) d = 24 mm.
    plane_angle_deg : float
        Angle between consecutive sampling planes (thesis: 60).
    noise_std_m : float
        Gaussian noise per coordinate.
    separation_m : float
        Smallest distance between two instance vertices of one model.
    seed : int
    normal_noise_rad : float or None
        A verification touch also senses the surface normal, tilted by Gaussian noise of
        this much per component (default: the simulated robot's,
        :attr:`~recognition.surfaces.noise_model.NoiseModel.normal_sd_rad`); None: touches
        sense no normal.
    """

    per_model: int = 10
    n_points: int = 81
    spacing_m: float = 0.3e-3
    plane_angle_deg: float = 60.0
    noise_std_m: float = 0.02e-3
    separation_m: float = 10e-3
    seed: int = 0
    normal_noise_rad: float | None = NoiseModel.normal_sd_rad

    def __post_init__(self) -> None:
        # planes that coincide would make every instance invalid: say so once, here
        sampling_plane_normals([0.0, 0.0, 1.0], plane_angle_rad=np.deg2rad(self.plane_angle_deg))
        if self.n_points < 5 or not self.spacing_m > 0 or self.per_model < 1:
            raise InvalidCurveData(
                f"expected at least 5 points per curve, a positive spacing and at least one "
                f"instance per model; got n_points={self.n_points}, "
                f"spacing_m={self.spacing_m}, per_model={self.per_model}"
            )

    @property
    def length_m(self) -> float:
        """Length of every curve, l = (n - 1) d, metres."""
        return (self.n_points - 1) * self.spacing_m

    def specs(self, database: ModelDatabase) -> list[InstanceSpec]:
        """See :func:`instance_specs`."""
        return instance_specs(database, self)

    def instance(self, database: ModelDatabase, spec: InstanceSpec) -> Instance:
        """The sampled curves (noisy, moved) and p on the model; a touch is a ray cast
        along the planned approach onto the true model at the true pose, with the same
        noise (:func:`~recognition.synthetic.ray_contact`), approaching within 80 degrees
        of the curves' approach direction, and senses the normal there
        (:func:`~recognition.synthetic.sensed_normal`, ``normal_noise_rad``). The sensor
        is lowered to the approach's start from above the object along the curves'
        approach: where the object is nearer than planned, it meets it on the way."""
        synthetic = make_curves(database, spec, self)
        model = database[spec.model]
        rng = _rng("touches", spec.key, spec.seed)
        normal_rng = _rng("touch normals", spec.key, spec.seed)
        assert synthetic.curves.approach is not None  # sampled curves carry it
        limits = TouchLimits(up=-synthetic.curves.approach, max_tilt_rad=np.deg2rad(80.0))
        above = 2.0 * model.extent_m

        def touch(plan: TouchPlan) -> Contact | None:
            point = ray_contact(
                model.distance,
                synthetic.T_model_from_data,
                plan.start,
                plan.direction,
                plan.travel_m,
                noise_m=self.noise_std_m,
                rng=rng,
                way_in=above * limits.up,
            )
            if point is None or self.normal_noise_rad is None:
                return None if point is None else Contact(point)
            normal = sensed_normal(
                model.distance,
                synthetic.T_model_from_data,
                point,
                noise_rad=self.normal_noise_rad,
                rng=normal_rng,
            )
            return Contact(point, normal)

        return Instance(
            synthetic.curves,
            np.asarray(synthetic.point_in_model),
            touch=touch,
            touch_limits=limits,
            T_model_from_data=np.asarray(synthetic.T_model_from_data),
        )


def _rng(*key: object) -> np.random.Generator:
    digest = hashlib.sha256(repr(key).encode()).digest()
    return np.random.default_rng(int.from_bytes(digest[:8], "little"))


def instance_specs(database: ModelDatabase, source: SyntheticSource) -> list[InstanceSpec]:
    """``per_model`` well-separated vertices per model whose three curves can be sampled.

    Vertices are drawn in a seeded order; one is taken when it is at least
    ``separation_m`` from those already taken and its three sections are long enough.
    """
    specs = []
    for name, model in database.models.items():
        rng = _rng("vertices", name, source.seed)
        order = rng.permutation(len(model.vertices))
        chosen: list[int] = []
        for v in order:
            if len(chosen) == source.per_model:
                break
            x = model.vertices[v]
            if chosen and np.min(np.linalg.norm(model.vertices[chosen] - x, axis=1)) < (
                source.separation_m
            ):
                continue
            spec = InstanceSpec(name, len(chosen), int(v), int(rng.integers(2**31)))
            try:
                make_curves(database, spec, source)
            except RecognitionError:
                continue
            chosen.append(int(v))
            specs.append(spec)
    return specs


def make_curves(
    database: ModelDatabase, spec: InstanceSpec, source: SyntheticSource
) -> SyntheticCurves:
    """The instance's data curves and ground truth."""
    if spec.vertex is None:
        raise InvalidCurveData(f"synthetic instance {spec.key} names no vertex")
    model = database[spec.model]
    return mesh_data_curves(
        model.mesh,
        spec.vertex,
        normal=model.normals[spec.vertex],
        n_points=source.n_points,
        spacing_m=source.spacing_m,
        plane_angle_deg=source.plane_angle_deg,
        noise_std_m=source.noise_std_m,
        rng=np.random.default_rng(spec.seed),
    )
