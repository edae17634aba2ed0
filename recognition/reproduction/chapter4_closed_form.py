"""Fig. 4.5, Tables 4.2, 4.3 and 4.5 and Figs. 4.3 and 4.7 of the thesis (closed forms).

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
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from recognition.reproduction.tables import TableResult, markdown_table, save_figure
from recognition.rigid import random_rigid_motion
from recognition.surfaces import closed_form as cf
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.registration import (
    ClosedFormConfig,
    ClosedFormRegistration,
    Optimizer,
    data_geometry,
    recognize,
    register,
)
from recognition.synthetic import (
    implicit_data_curves,
    sampling_plane_normals,
)

__all__ = [
    "SolidExperiment",
    "SurfaceExperiment",
    "fig_4_5",
    "figures",
    "noisy_data_curves",
    "surface_instances",
    "table_4_2",
    "table_4_3",
    "table_4_5",
    "tilted_plane_normals",
]

#: Surface names in the thesis's column order (Tables 4.2 and 4.3).
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

    def data_curves(self, surface: cf.ClosedFormSurface, u: float, v: float, rng):
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
        return ClosedFormConfig(delta=self.delta_per_m, max_candidates=self.max_candidates)

    def describe(self) -> str:
        return (
            f"n = {self.n_points}, d = {self.spacing_m * 1e3:g} mm, uniform noise within "
            f"+-{self.noise_m * 1e3:g} mm"
        )


def _rng(*key: int) -> np.random.Generator:
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
):
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


def _instance(job) -> dict:
    """One recognition test: data from surface ``i`` at a random p, onto all four models."""
    i, k, experiment = job
    models = _models(experiment.grid)
    surface = models[i].surface
    rng = _rng(experiment.seed, 42, i, k)
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


_INSTANCES: dict = {}


def surface_instances(
    experiment: SurfaceExperiment = SurfaceExperiment(), workers: int | None = None
) -> tuple[dict, ...]:
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
            with ProcessPoolExecutor(workers) as pool:
                records = list(pool.map(_instance, jobs))
        _INSTANCES[experiment] = tuple(records)
    return _INSTANCES[experiment]


TABLE_4_2_THESIS = {
    "min_distance": {
        "ellipsoid": 0.0169,
        "elliptic_paraboloid": 0.0148,
        "monkey_saddle": 0.0053,
        "crossed_trough": 0.0171,
    },
    "max_distance": {
        "ellipsoid": 0.0408,
        "elliptic_paraboloid": 0.0448,
        "monkey_saddle": 0.0433,
        "crossed_trough": 0.0396,
    },
    "avg_distance": {
        "ellipsoid": 0.0288,
        "elliptic_paraboloid": 0.0297,
        "monkey_saddle": 0.0234,
        "crossed_trough": 0.0265,
    },
}


def table_4_2(
    experiment: SurfaceExperiment = SurfaceExperiment(), workers: int | None = None
) -> TableResult:
    """Table 4.2: |p - p*| of ten registrations on each surface (onto its own model)."""
    records = surface_instances(experiment, workers)
    measured: dict = {"min_distance": {}, "max_distance": {}, "avg_distance": {}}
    extra: dict = {"raw_avg_distance": {}, "at_symmetric_copy": {}, "avg_error": {}}
    for name in SURFACES:
        rs = [r for r in records if r["surface"] == name]
        d = np.array([r["distance"] for r in rs])
        raw = np.array([r["raw_distance"] for r in rs])
        measured["min_distance"][name] = float(d.min())
        measured["max_distance"][name] = float(d.max())
        measured["avg_distance"][name] = float(d.mean())
        extra["raw_avg_distance"][name] = float(raw.mean())
        extra["at_symmetric_copy"][name] = int(np.sum(raw > d + 1e-12))
        extra["avg_error"][name] = float(np.mean([r["error"] for r in rs]))
    measured.update(extra)
    measured["distances"] = {
        name: [r["distance"] for r in records if r["surface"] == name] for name in SURFACES
    }
    header = ["", *SURFACES]
    rows = []
    for key in ("min_distance", "max_distance", "avg_distance"):
        rows.append([f"thesis {key[:3]}", *(TABLE_4_2_THESIS[key][n] for n in SURFACES)])
        rows.append([key[:3], *(measured[key][n] for n in SURFACES)])
    rows.append(
        ["estimate at a symmetric copy", *(extra["at_symmetric_copy"][n] for n in SURFACES)]
    )
    rows.append(["avg registration error", *(extra["avg_error"][n] for n in SURFACES)])
    text = (
        f"**Table 4.2** |p - p*| over {experiment.instances} registrations per surface, "
        f"modulo each surface's rigid symmetries; {experiment.describe()}.\n\n"
        + markdown_table(header, rows, digits=3)
    )
    return TableResult("4.2", TABLE_4_2_THESIS, measured, asdict(experiment), text)


TABLE_4_3_THESIS = {
    "decided_at_lookup": {
        "ellipsoid": 2,
        "elliptic_paraboloid": 1,
        "monkey_saddle": 9,
        "crossed_trough": 0,
    },
    "decided_by_local_search": {
        "ellipsoid": 8,
        "elliptic_paraboloid": 9,
        "monkey_saddle": 1,
        "crossed_trough": 10,
    },
    "successes": {
        "ellipsoid": 10,
        "elliptic_paraboloid": 10,
        "monkey_saddle": 10,
        "crossed_trough": 10,
    },
    "tests": {
        "ellipsoid": 10,
        "elliptic_paraboloid": 10,
        "monkey_saddle": 10,
        "crossed_trough": 10,
    },
    "wrong_model_error_excess_percent": 180.0,
}


def table_4_3(
    experiment: SurfaceExperiment = SurfaceExperiment(), workers: int | None = None
) -> TableResult:
    """Table 4.3: recognition among the four surfaces, ten tests on each.

    A success is decided at table lookup when every wrong model had no candidate point,
    otherwise by local search (registration errors compared).
    """
    records = surface_instances(experiment, workers)
    measured: dict = {
        "successes": {},
        "tests": {},
        "decided_at_lookup": {},
        "decided_by_local_search": {},
    }
    excess = []
    for name in SURFACES:
        rs = [r for r in records if r["surface"] == name]
        ok = [r for r in rs if r["recognized"] == name]
        measured["successes"][name] = len(ok)
        measured["tests"][name] = len(rs)
        measured["decided_at_lookup"][name] = sum(r["decided_at_lookup"] for r in ok)
        measured["decided_by_local_search"][name] = sum(not r["decided_at_lookup"] for r in ok)
        for r in rs:
            errors = dict(r["ranking"])
            own = errors[name]
            wrong = [e for n, e in errors.items() if n != name and np.isfinite(e)]
            excess += [100 * (e - own) / own for e in wrong]
    measured["total_successes"] = sum(measured["successes"].values())
    measured["total_tests"] = sum(measured["tests"].values())
    measured["wrong_model_error_excess_percent"] = float(np.mean(excess)) if excess else None
    measured["min_wrong_model_error_excess_percent"] = float(np.min(excess)) if excess else None
    header = ["successes", *SURFACES]
    rows = [
        ["thesis table lookup", *(TABLE_4_3_THESIS["decided_at_lookup"][n] for n in SURFACES)],
        ["table lookup", *(measured["decided_at_lookup"][n] for n in SURFACES)],
        [
            "thesis local search",
            *(TABLE_4_3_THESIS["decided_by_local_search"][n] for n in SURFACES),
        ],
        ["local search", *(measured["decided_by_local_search"][n] for n in SURFACES)],
        [
            "successes / tests",
            *(f"{measured['successes'][n]}/{measured['tests'][n]}" for n in SURFACES),
        ],
    ]
    text = (
        f"**Table 4.3** recognition tests: {measured['total_successes']}/"
        f"{measured['total_tests']} (thesis 40/40); wrong models' registration errors exceed "
        f"the right model's by {measured['wrong_model_error_excess_percent']:.0f} % on "
        f"average (thesis 180 %); {experiment.describe()}.\n\n" + markdown_table(header, rows)
    )
    return TableResult("4.3", TABLE_4_3_THESIS, measured, asdict(experiment), text)


# --- Fig. 4.5: the worked example --------------------------------------------------------

FIG_4_5_THESIS = {
    "point_uv": [1.21, 0.43],
    "normal": [0.1611, 0.5764, 0.8011],
    "k1": 0.9548,
    "k2": 0.6370,
    "true_k1": 0.9074,
    "true_k2": 0.6519,
    "candidates_uv": [[1.26, 0.4], [1.41, 0.4], [0.63, 0.5]],
    "candidate_errors": [0.000888, 0.000961, 0.001654],
    "local_minima_uv": [[1.26, 0.44], [1.27, 0.44], [1.17, 0.44]],
    "local_minima_errors": [0.000662, 0.000666, 0.000686],
    "estimate_uv": [1.26, 0.44],
}


def _fig_4_5_data(experiment: SurfaceExperiment):
    surface = cf.elliptic_paraboloid(1.5, 1.1)
    rng = _rng(experiment.seed, 45)
    u, v = 1.21, 0.43
    curves, point, T_true, clean = experiment.data_curves(surface, u, v, rng)
    return surface, curves, point, T_true, clean


def fig_4_5(experiment: SurfaceExperiment = SurfaceExperiment()) -> TableResult:
    """The worked example of Section 4.2.3.1 (Fig. 4.5): elliptic paraboloid a = 1.5,
    b = 1.1, p at (u, v) = (1.21, 0.43), 61 points per curve, noise within +-0.001.

    Reports the estimated normal and principal curvatures against the true ones, the
    candidate points, the superposition error at each after the phi initialisation and
    after the local search, and the estimated location.
    """
    surface, curves, point, T_true, _ = _fig_4_5_data(experiment)
    model = cf.ClosedFormModel.build(surface, *experiment.grid)
    config = experiment.config()
    geometry = data_geometry(curves, config.geometry)
    normal_in_model = T_true[:3, :3] @ geometry.normal
    true_normal = surface.normal(1.21, 0.43)
    k_true = [float(k) for k in surface.principal_curvatures(1.21, 0.43)]
    registration = register(model, curves, config, geometry=geometry)
    assert isinstance(registration, ClosedFormRegistration)
    X = cf.local_coordinates(geometry, curves.points)
    lookup = cf.candidate_rows(
        model,
        geometry.k1,
        geometry.k2,
        config.delta,
        config.candidate_separation * np.max(np.linalg.norm(X, axis=1)),
        config.max_candidates,
        surface.symmetries,
    )
    initial = [cf.initial_phi(surface, X, u, v)[1] for u, v in registration.candidates]
    measured = {
        "normal": normal_in_model.tolist(),
        "true_normal": true_normal.tolist(),
        "normal_error_deg": float(
            np.degrees(np.arccos(np.clip(normal_in_model @ true_normal, -1.0, 1.0)))
        ),
        "k1": geometry.k1,
        "k2": geometry.k2,
        "true_k1": k_true[0],
        "true_k2": k_true[1],
        "k1_error_percent": 100 * abs(geometry.k1 - k_true[0]) / k_true[0],
        "k2_error_percent": 100 * abs(geometry.k2 - k_true[1]) / k_true[1],
        "lookup_candidates": len(lookup),
        "candidates_uv": registration.candidates.tolist(),
        "candidate_errors": [float(e) for e in initial],
        "local_minima_uv": [s.solution[:2].tolist() for s in registration.searches],
        "local_minima_errors": [float(s.cost) for s in registration.searches],
        "estimate_uv": [registration.u, registration.v],
        "estimate_uv_nearest_symmetric_copy": list(
            surface.closest_parameters(
                surface.symmetric_image(point, registration.location), 1.21, 0.43
            )
        ),
        "registration_error": registration.error_m,
        "distance": surface.symmetric_distance(point, registration.location),
        "pose_rotation_error_deg": float(
            np.degrees(
                Rotation.from_matrix(
                    registration.T_model_from_data[:3, :3] @ T_true[:3, :3].T
                ).magnitude()
            )
        ),
    }
    rows = [
        ["normal (outward)", FIG_4_5_THESIS["normal"], measured["normal"], measured["true_normal"]],
        ["k1", FIG_4_5_THESIS["k1"], measured["k1"], measured["true_k1"]],
        ["k2", FIG_4_5_THESIS["k2"], measured["k2"], measured["true_k2"]],
        ["candidates (searched)", "3 (3)", f"{len(lookup)} ({len(initial)})", "-"],
        ["best E after local search", 0.000662, registration.error_m, "-"],
        [
            "p* (u, v), symmetric copy nearest p",
            FIG_4_5_THESIS["estimate_uv"],
            measured["estimate_uv_nearest_symmetric_copy"],
            [1.21, 0.43],
        ],
    ]
    rows = [[r[0], *(_fmt(x) for x in r[1:])] for r in rows]
    text = (
        "**Fig. 4.5** worked example on the elliptic paraboloid a = 1.5, b = 1.1 at (u, v) = "
        f"(1.21, 0.43): k1 error {measured['k1_error_percent']:.2f} %, k2 error "
        f"{measured['k2_error_percent']:.2f} % (thesis 5.2 %, 2.3 %), normal error "
        f"{measured['normal_error_deg']:.3f} deg, |p - p*| = {measured['distance']:.4f}; "
        f"{experiment.describe()}. The thesis's normal points into the bowl, ours out of "
        "the solid above it.\n\n" + markdown_table(["", "thesis", "measured", "true"], rows)
    )
    return TableResult("fig4.5", FIG_4_5_THESIS, measured, asdict(experiment), text)


def _fmt(x):
    if isinstance(x, list | tuple):
        return "(" + ", ".join(f"{float(v):.4g}" for v in x) + ")"
    return x


# --- Table 4.5 analogue ------------------------------------------------------------------

TABLE_4_5_THESIS = {
    "min_error_mm": {
        "cylinder_1": {
            "cylinder_1": 0.033,
            "cylinder_2": 0.182,
            "elliptic_cylinder": 0.230,
            "sphere": 0.271,
        },
        "cylinder_2": {
            "cylinder_1": 0.155,
            "cylinder_2": 0.072,
            "elliptic_cylinder": 0.224,
            "sphere": 0.306,
        },
        "elliptic_cylinder": {
            "cylinder_1": 0.446,
            "cylinder_2": 0.195,
            "elliptic_cylinder": 0.156,
            "sphere": 0.929,
        },
        "sphere": {
            "cylinder_1": 0.296,
            "cylinder_2": 1.056,
            "elliptic_cylinder": 0.254,
            "sphere": 0.055,
        },
    },
    "diagonal_minimum_in_every_column": True,
}

#: A variant with curves ten times longer (d = 0.5 mm) and 30 um noise, the sensed-point
#: accuracy of the simulated probe.
LONG_CURVES = SolidExperiment(spacing_m=0.5e-3, noise_m=30e-6)


def _solid_matrix(experiment: SolidExperiment):
    """errors[object][model] in mm: data from each solid registered onto every model."""
    solids = cf.fig_4_15_solids()
    models = [cf.ClosedFormModel.build(s) for s in solids]
    config = experiment.config()
    matrix: dict = {}
    for j, solid in enumerate(solids):
        rng = _rng(experiment.seed, 415, j)
        u = rng.uniform(0, 2 * np.pi)
        v = rng.uniform(0.5, np.pi - 0.5) if solid.name == "sphere" else rng.uniform(-0.01, 0.01)
        curves, *_ = noisy_data_curves(
            solid,
            u,
            v,
            rng,
            n_points=experiment.n_points,
            spacing=experiment.spacing_m,
            noise=experiment.noise_m,
            plane_normals=sampling_plane_normals(solid.normal(u, v), rng.normal(size=3)),
        )
        recognition = recognize(models, curves, config)
        matrix[solid.name] = {
            name: 1e3 * r.error_m for name, r in recognition.registrations.items()
        }
    names = [s.name for s in solids]
    diagonal = all(min(matrix[o], key=matrix[o].get) == o for o in names)
    return matrix, diagonal


def table_4_5(
    experiment: SolidExperiment = SolidExperiment(), long_curves: SolidExperiment = LONG_CURVES
) -> TableResult:
    """Table 4.5 analogue: minimum registration error (4.9) of data from each Fig. 4.15
    solid onto each model, in mm (columns: objects, rows: models).

    With the thesis's n = 41 and d = 0.05 mm the curves are 2 mm long: the elliptic
    cylinder then holds patches matching either circular cylinder to about 1e-5 mm, so
    the diagonal is smallest only for nearly noise-free data. ``long_curves`` repeats the
    table with d = 0.5 mm and +-30 um noise.
    """
    matrix, diagonal = _solid_matrix(experiment)
    long_matrix, long_diagonal = _solid_matrix(long_curves)
    names = list(matrix)
    measured = {
        "min_error_mm": matrix,
        "diagonal_minimum_in_every_column": diagonal,
        "long_curves": {
            "min_error_mm": long_matrix,
            "diagonal_minimum_in_every_column": long_diagonal,
            "settings": asdict(long_curves),
        },
    }

    def rows(m, thesis=None):
        out = []
        for model in names:
            row = [model]
            for obj in names:
                cell = f"{m[obj][model]:.3g}"
                if thesis is not None:
                    cell += f" ({thesis[obj][model]:.3f})"
                row.append(f"**{cell}**" if obj == model else cell)
            out.append(row)
        return out

    header = ["model \\ object", *names]
    text = (
        f"**Table 4.5** minimum registration error (mm) of synthetic data from each object "
        f"onto each model, thesis in brackets; {experiment.describe()}; diagonal smallest in "
        f"every column: {diagonal}.\n\n"
        + markdown_table(header, rows(matrix, TABLE_4_5_THESIS["min_error_mm"]))
        + f"\n\nWith {long_curves.describe()}: diagonal smallest in every column: "
        f"{long_diagonal}.\n\n" + markdown_table(header, rows(long_matrix))
    )
    settings = asdict(experiment)
    settings["models"] = {s.name: dict(s.parameters) for s in cf.fig_4_15_solids()}
    settings["note"] = cf.fig_4_15_solids()[0].note
    return TableResult("4.5", TABLE_4_5_THESIS, measured, settings, text)


# --- figures -----------------------------------------------------------------------------


def figures(
    out_dir: Path,
    experiment: SurfaceExperiment = SurfaceExperiment(),
    workers: int | None = None,
) -> list[Path]:
    """Figs. 4.3 (E against phi), 4.5 (worked example) and 4.7 (true vs estimated p)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []

    # Fig. 4.3: curves from the ellipsoid at (1.02, 0.69), placed at (0.31, 0.63)
    ellipsoid = cf.ellipsoid(1.0, 0.8, 0.5)
    rng = _rng(experiment.seed, 43)
    curves, *_ = experiment.data_curves(ellipsoid, 1.02, 0.69, rng)
    geometry = data_geometry(curves, experiment.config().geometry)
    X = cf.local_coordinates(geometry, curves.points)
    phi = np.linspace(0, 2 * np.pi, 721)
    fig, ax = plt.subplots(figsize=(7, 4))
    for (u, v), label in (((0.31, 0.63), "placed at (0.31, 0.63)"), ((1.02, 0.69), "at p")):
        ax.plot(phi, cf.superposition_error(ellipsoid, X, u, v, phi), label=label)
        best, e = cf.initial_phi(ellipsoid, X, u, v)
        ax.plot([best], [e], "o", color="k", ms=4)
    ax.set(xlabel="phi (rad)", ylabel="E (4.11)", title="Fig. 4.3: E against phi (ellipsoid)")
    ax.legend()
    paths.append(save_figure(fig, out_dir / "fig4_3_error_vs_phi.png"))

    # Fig. 4.5: data curves at their true place and as registered
    surface, curves, _, T_true, _ = _fig_4_5_data(experiment)
    model = cf.ClosedFormModel.build(surface, *experiment.grid)
    registration = register(model, curves, experiment.config())
    fig = plt.figure(figsize=(7, 6))
    ax = fig.add_subplot(projection="3d")
    uu, vv = np.meshgrid(np.linspace(0, 2 * np.pi, 60), np.linspace(0, 1, 30))
    P = surface.sigma(uu, vv)
    ax.plot_surface(P[..., 0], P[..., 1], P[..., 2], color="0.8", alpha=0.5, linewidth=0)
    for c in curves.curves:
        true = c @ T_true[:3, :3].T + T_true[:3, 3]
        reg = c @ registration.T_model_from_data[:3, :3].T + registration.T_model_from_data[:3, 3]
        ax.plot(*true.T, "k-", lw=3)
        ax.plot(*reg.T, "--", color="tab:red", lw=1.5)
    ax.set(title="Fig. 4.5: data curves at p (black) and registered (red, dashed)")
    paths.append(save_figure(fig, out_dir / "fig4_5_worked_example.png"))

    # Fig. 4.7: true p (dots) and estimates p* (crosses), symmetric copy nearest p
    records = surface_instances(experiment, workers)
    fig = plt.figure(figsize=(11, 10))
    for i, s in enumerate(cf.table_4_1_surfaces()):
        ax = fig.add_subplot(2, 2, i + 1, projection="3d")
        (u0, u1), (v0, v1) = s.domain
        uu, vv = np.meshgrid(np.linspace(u0, u1, 50), np.linspace(v0, v1, 40))
        P = s.sigma(uu, vv)
        ax.plot_wireframe(P[..., 0], P[..., 1], P[..., 2], color="0.7", lw=0.3)
        for r in (r for r in records if r["surface"] == s.name):
            p, est = np.array(r["point"]), np.array(r["location"])
            est = s.symmetric_image(p, est)
            ax.plot(*p, "o", color="tab:blue", ms=5)
            ax.plot(*est, "x", color="tab:red", ms=7)
        ax.set(title=f"({'abcd'[i]}) {s.name.replace('_', ' ')}")
    fig.suptitle("Fig. 4.7: true p (dots) and estimated p* (crosses)")
    paths.append(save_figure(fig, out_dir / "fig4_7_registration_instances.png"))
    return paths


def default_experiment(**overrides) -> SurfaceExperiment:
    """The documented default settings, with ``overrides`` applied."""
    return replace(SurfaceExperiment(), **overrides)
