"""The closed-form experiments of thesis Chapter 4: settings, noisy data curves, the 40 tests.

Every measurement starts from data curves traced on the true surface through a point p
(three sampling planes, points at equal arc length, noise, a random rigid motion to an
unknown data frame); normal, curvatures, candidates and pose are estimated from those
points, never taken from the closed form.

The Table 4.1 surfaces have no units (the thesis gives none; noise is "within +-0.001").
Their sampling: 61 points per curve every 0.015 (curves 0.9 long), three planes through
p 60 degrees apart about the normal, each tilted about its tangent at p by a random
angle within +-20 degrees ("three arbitrary planes"), uniform noise in [-0.001, 0.001]
per coordinate.

Locations are compared modulo the rigid symmetries of each surface (ellipsoid: the three
half-turns about its axes; paraboloid: the half-turn about z; monkey saddle: the turns
by 120 degrees; crossed trough: the quarter turns): data registered at p and at S p are
indistinguishable, and the thesis also pairs each p with "the closest cross" (Fig. 4.7).
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from recognition.pools import process_pool
from recognition.rigid import random_rigid_motion
from recognition.surfaces import closed_form as cf
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.registration import ClosedFormConfig, Optimizer, recognize
from recognition.synthetic import implicit_data_curves, sampling_plane_normals

__all__ = [
    "LONG_CURVES",
    "SAMPLE_DOMAINS",
    "SURFACES",
    "SolidExperiment",
    "SurfaceExperiment",
    "default_experiment",
    "fig_4_5_data",
    "noisy_data_curves",
    "seeded_rng",
    "surface_instances",
    "tilted_plane_normals",
]

#: What :func:`noisy_data_curves` returns: the curves (data frame), the true p (model
#: frame), T_model_from_data and the noise-free samples (model frame).
NoisyCurves = tuple[DataCurves, np.ndarray, np.ndarray, tuple[np.ndarray, ...]]

#: The Table 4.1 surfaces in the thesis's column order (Tables 4.2 and 4.3).
SURFACES = ("ellipsoid", "elliptic_paraboloid", "monkey_saddle", "crossed_trough")

#: Where the random points p of Tables 4.2-4.3 are drawn, in (u, v): the tabulated
#: domain less the parametrisation's singular points (poles, apex) and a 5 % rim.
SAMPLE_DOMAINS = {
    "ellipsoid": ((0.0, 2 * np.pi), (0.2, np.pi - 0.2)),
    "elliptic_paraboloid": ((0.0, 2 * np.pi), (0.1, 0.95)),
    "monkey_saddle": ((-0.95, 0.95), (-0.95, 0.95)),
    "crossed_trough": ((-0.95, 0.95), (-0.95, 0.95)),
}


@dataclass(frozen=True)
class SurfaceExperiment:
    """Sampling and registration settings for the Table 4.1 surfaces (no units).

    Attributes
    ----------
    n_points : int
        Points per data curve (thesis: 61).
    spacing : float
        Arc length between consecutive points.
    noise : float
        Half width of the uniform noise added to every coordinate (thesis: 0.001).
    plane_angle_deg : float
        Angle between consecutive sampling planes about the normal.
    plane_tilt_deg : float
        Each plane is tilted about its tangent at p by a random angle within +- this.
    instances : int
        Random points p per surface (thesis: 10).
    delta : float
        Table lookup tolerance (4.7).
    grid : (int, int)
        Lookup table size (n_u, n_v).
    fit_half_length, fit_degree, fit_max_turn
        Local fits of the data curves (:func:`recognition.surfaces.registration.data_geometry`).
    optimizer : str
        ``levenberg_marquardt`` (default) or ``steepest_descent`` (the thesis's).
    rigid_refinement : bool
        Refine all six degrees of freedom after the (u, v, phi) search.
    seed : int
    """

    n_points: int = 61
    spacing: float = 0.015
    noise: float = 1e-3
    plane_angle_deg: float = 60.0
    plane_tilt_deg: float = 20.0
    instances: int = 10
    delta: float = 0.1
    grid: tuple[int, int] = (200, 100)
    fit_half_length: float = 0.45
    fit_degree: int = 4
    fit_max_turn: float = 0.5
    optimizer: str = "levenberg_marquardt"
    rigid_refinement: bool = True
    seed: int = 0

    def config(self) -> ClosedFormConfig:
        """The registration settings of this experiment."""
        return ClosedFormConfig(
            delta=self.delta,
            optimizer=Optimizer(self.optimizer),
            rigid_refinement=self.rigid_refinement,
            geometry=replace(
                ClosedFormConfig().geometry,
                fit_half_length_m=self.fit_half_length,
                fit_degree=self.fit_degree,
                fit_max_turn=self.fit_max_turn,
            ),
        )

    def data_curves(
        self, surface: cf.ClosedFormSurface, u: float, v: float, rng: np.random.Generator
    ) -> NoisyCurves:
        """:func:`noisy_data_curves` through sigma(u, v) on this experiment's planes
        (:func:`tilted_plane_normals`), points and noise."""
        planes = tilted_plane_normals(
            surface.normal(u, v), rng, self.plane_angle_deg, self.plane_tilt_deg
        )
        return noisy_data_curves(
            surface,
            u,
            v,
            rng,
            n_points=self.n_points,
            spacing=self.spacing,
            noise=self.noise,
            plane_normals=planes,
        )

    def describe(self) -> str:
        """The settings in one line, for table captions."""
        return (
            f"{self.n_points} points per curve every {self.spacing:g}, uniform noise within "
            f"+-{self.noise:g}, planes {self.plane_angle_deg:g} deg apart tilted within "
            f"+-{self.plane_tilt_deg:g} deg; delta = {self.delta:g}; "
            f"{self.optimizer.replace('_', ' ')}"
            + (" + 6-DOF refinement" if self.rigid_refinement else "")
        )


@dataclass(frozen=True)
class SolidExperiment:
    """Sampling of the Fig. 4.15 solids (metres) for the Table 4.5 analogue.

    Attributes
    ----------
    n_points : int
        Points per curve (thesis: n = 41).
    spacing_m : float
        Arc length between points (thesis: d = 0.05 mm).
    noise_m : float
        Half width of uniform noise per coordinate.
    delta_per_m : float
        Table lookup tolerance, 1/m (``inf``: every model gets a finite error, as in the
        thesis's table).
    max_candidates : int
    seed : int
    """

    n_points: int = 41
    spacing_m: float = 0.05e-3
    noise_m: float = 0.0
    delta_per_m: float = float("inf")
    max_candidates: int = 4
    seed: int = 0

    def config(self) -> ClosedFormConfig:
        """The registration settings of this experiment."""
        return ClosedFormConfig(delta=self.delta_per_m, max_candidates=self.max_candidates)

    def describe(self) -> str:
        """The settings in one line, for table captions."""
        return (
            f"n = {self.n_points}, d = {self.spacing_m * 1e3:g} mm, uniform noise within "
            f"+-{self.noise_m * 1e3:g} mm"
        )


def seeded_rng(*key: int) -> np.random.Generator:
    """A generator seeded by the integers ``key`` (experiment seed, table, indices)."""
    return np.random.default_rng(np.random.SeedSequence(list(key)))


def tilted_plane_normals(
    normal: np.ndarray,
    rng: np.random.Generator,
    plane_angle_deg: float = 60.0,
    max_tilt_deg: float = 20.0,
) -> np.ndarray:
    """Three sampling planes through p: ``plane_angle_deg`` apart about the normal (random
    first direction), each tilted about its tangent at p by a uniform random angle within
    +- ``max_tilt_deg``.

    Returns
    -------
    (3, 3) float
        Unit plane normals.
    """
    planes = sampling_plane_normals(normal, rng.normal(size=3), np.deg2rad(plane_angle_deg))
    out = []
    for m in planes:
        tangent = np.cross(normal, m)
        tangent /= np.linalg.norm(tangent)
        angle = np.deg2rad(rng.uniform(-max_tilt_deg, max_tilt_deg))
        out.append(Rotation.from_rotvec(angle * tangent).apply(m))
    return np.array(out)


def noisy_data_curves(
    surface: cf.ClosedFormSurface,
    u: float,
    v: float,
    rng: np.random.Generator,
    *,
    n_points: int,
    spacing: float,
    noise: float,
    plane_normals: np.ndarray | None = None,
    translation_scale: float = 0.1,
) -> NoisyCurves:
    """Data curves through sigma(u, v) with uniform noise, in a random data frame.

    Returns
    -------
    curves : DataCurves
        In the data frame, with the approach direction.
    point : (3,) float
        The true p, model frame.
    T_model_from_data : (4, 4) float
    clean : tuple of (n, 3) float
        Noise-free samples, model frame.
    """
    point = surface.sigma(u, v)
    normal = surface.normal(u, v)
    synthetic = implicit_data_curves(
        surface,
        point,
        n_points=n_points,
        spacing=spacing,
        plane_normals=plane_normals,
        transform=False,
    )
    clean = synthetic.clean_curves_in_model
    T = random_rigid_motion(rng, translation_scale)
    R, t = T[:3, :3], T[:3, 3]
    noisy = [c + rng.uniform(-noise, noise, c.shape) for c in clean]
    curves = DataCurves(
        tuple(c @ R.T + t for c in noisy),
        meet_tolerance_m=max(1e-3, 20 * noise),
        approach=-(R @ normal),
    )
    return curves, point, np.linalg.inv(T), clean


# --- Tables 4.2 and 4.3: instances ----------------------------------------------------


@functools.lru_cache(maxsize=4)
def _models(grid: tuple[int, int]) -> tuple[cf.ClosedFormModel, ...]:
    return tuple(cf.ClosedFormModel.build(s, *grid) for s in cf.table_4_1_surfaces())


def _instance(job: tuple[int, int, SurfaceExperiment]) -> dict[str, Any]:
    """One recognition test: data from surface ``i`` at a random p, onto all four models."""
    i, k, experiment = job
    models = _models(experiment.grid)
    surface = models[i].surface
    rng = seeded_rng(experiment.seed, 42, i, k)
    (u0, u1), (v0, v1) = SAMPLE_DOMAINS[surface.name]
    u, v = rng.uniform(u0, u1), rng.uniform(v0, v1)
    curves, point, _, _ = experiment.data_curves(surface, u, v, rng)
    recognition = recognize(models, curves, experiment.config())
    own = recognition.registrations[surface.name]
    return {
        "surface": surface.name,
        "index": k,
        "u": float(u),
        "v": float(v),
        "point": point.tolist(),
        "recognized": recognition.name,
        "ranking": [(n, float(e)) for n, e in recognition.ranking],
        "decided_at_lookup": bool(recognition.decided_at_lookup),
        "location": own.location.tolist(),
        "distance": surface.symmetric_distance(point, own.location),
        "raw_distance": float(np.linalg.norm(own.location - point)),
        "error": float(own.error_m),
        "candidates": int(own.candidates.shape[0]),
        "iterations": int(own.iterations),
        "status": own.status.value,
    }


_INSTANCES: dict[SurfaceExperiment, tuple[dict[str, Any], ...]] = {}


def surface_instances(
    experiment: SurfaceExperiment = SurfaceExperiment(), workers: int | None = None
) -> tuple[dict[str, Any], ...]:
    """The 40 tests of Fig. 4.7 / Tables 4.2-4.3: ten random p on each Table 4.1 surface,
    each recognised against all four models. Seeded by (seed, surface, index), so any
    process count gives the same records; cached per experiment."""
    if experiment not in _INSTANCES:
        jobs = [
            (i, k, experiment) for i in range(len(SURFACES)) for k in range(experiment.instances)
        ]
        workers = workers or os.cpu_count() or 1
        if workers == 1:
            records = [_instance(job) for job in jobs]
        else:
            with process_pool(workers) as pool:
                records = list(pool.map(_instance, jobs))
        _INSTANCES[experiment] = tuple(records)
    return _INSTANCES[experiment]


def fig_4_5_data(
    experiment: SurfaceExperiment,
) -> tuple[cf.ClosedFormSurface, *NoisyCurves]:
    """The worked example's data (Section 4.2.3.1): the elliptic paraboloid a = 1.5,
    b = 1.1 and its noisy curves through (u, v) = (1.21, 0.43): the surface, the curves,
    the true p, T_model_from_data and the noise-free samples."""
    surface = cf.elliptic_paraboloid(1.5, 1.1)
    rng = seeded_rng(experiment.seed, 45)
    u, v = 1.21, 0.43
    curves, point, T_true, clean = experiment.data_curves(surface, u, v, rng)
    return surface, curves, point, T_true, clean


#: A variant with curves ten times longer (d = 0.5 mm) and 30 um noise, the sensed-point
#: accuracy of the simulated probe.
LONG_CURVES = SolidExperiment(spacing_m=0.5e-3, noise_m=30e-6)


def default_experiment(**overrides: Any) -> SurfaceExperiment:
    """The documented default settings, with ``overrides`` applied."""
    return replace(SurfaceExperiment(), **overrides)
