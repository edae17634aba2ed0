"""Settings of the registration: one frozen config per mode, and the data's local fits."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum
from typing import ClassVar

import numpy as np

from recognition.surfaces.registration.result import RegistrationMode

__all__ = [
    "ALIGNED_SEARCH",
    "THOROUGH_SEARCH",
    "ClosedFormConfig",
    "DataGeometryConfig",
    "FastConfig",
    "FastSearchConfig",
    "IcpConfig",
    "Optimizer",
    "RegistrationConfig",
    "ThesisConfig",
]


@dataclass(frozen=True)
class DataGeometryConfig:
    """How the data's normal and principal curvatures at p are estimated (4.1)-(4.6).

    Each data curve is fitted near p by a polynomial in its sampling plane
    (:func:`~recognition.surfaces.local_geometry.local_surface_geometry`).

    Attributes
    ----------
    fit_half_length_m : float
        Half length of the arc around p that each fit covers, metres (model units for
        unit-free surfaces).
    fit_spacings : float or None
        The arc covers at least this many point spacings either side of p (sparse data:
        the thesis's real data are 1.2 mm apart); None: ``fit_half_length_m`` alone.
    fit_degree : int
        Degree of the polynomial.
    fit_max_turn : float or None
        Largest angle (radians) a data curve may turn over the fit's arc: on tightly
        curved data the arc shrinks to ``fit_max_turn / kappa``, where a polynomial y(x)
        still follows the curve closely. None keeps the arc.
    normal_max_turn : float or None
        Where a data curve turns by more than this (radians) over the fit's arc, the
        normal comes from fits over the arc of this turn (``normal_max_turn / kappa``)
        and the curvatures from the fits over the whole arc, at that normal. On tightly
        curved data a fit over the whole arc tilts the normal: over the synthetic fast
        benchmark's instances at n = 21, d = 1.2 mm, 3 of 100 data normals lay more than
        10 degrees from the model's (at most 27), 1 with this at 0.4 rad (at most 10.7);
        the median error stays 0.7 degrees. None: the whole arc for both.
    at_common_point : bool
        Fit at the point where all three curves meet
        (:func:`~recognition.surfaces.registration.data.common_point`); False: at the
        pairwise closest points of the curves (:attr:`DataCurves.intersection`).
    """

    fit_half_length_m: float = 3.0e-3
    fit_spacings: float | None = 3.2
    fit_degree: int = 3
    fit_max_turn: float | None = None
    normal_max_turn: float | None = None
    at_common_point: bool = True


@dataclass(frozen=True)
class FastSearchConfig:
    """How densely one pass of the fast mode searches a model.

    Attributes
    ----------
    tolerance_scale : float
        Multiplies the table-lookup tolerance of :class:`FastConfig`; ``inf``: every
        vertex is a candidate (curvature estimates fail on sharp creases).
    candidate_spacing_m : float
        Candidate vertices are thinned to one per cubic cell of this side (the vertex
        nearest the data in (k1, k2)), metres.
    aligned_anisotropy : float
        k1 - k2 (1/m) above which, for both the data and a candidate, phi is searched
        only near the alignment of their principal directions; ``inf``: always scan.
    aligned_window_rad, aligned_step_rad : float
        Half width and step of that window around both alignments (phi and phi + pi).
    scan_step_rad : float
        Step of the full scan of phi over [0, 2 pi).
    prescreen_fractions : tuple of float
        Prescreening points: on each of the six arms (p to a curve's end), the data
        points at these fractions of the arm's length.
    prescreen_keep : float
        Fraction of the poses (of a model, phi set and normal orientation) kept after
        prescreening, but at least ``n_screened``.
    arm_fractions : tuple of float
        Screening points, as ``prescreen_fractions``.
    n_screened : int
        Poses per model kept after screening; each takes ``screen_iterations``
        Gauss-Newton steps on the screening points.
    n_coarse, coarse_per_arm, coarse_iterations
        Distinct poses per model kept next, refined on ``coarse_per_arm`` points per arm.
    n_final, final_iterations
        Distinct poses per model refined on every data point.
    candidate_budget : int or None
        Candidate-map rows screened across the whole database, at most: of the rows within
        the lookup tolerance, those whose ring descriptors (:mod:`~recognition.surfaces.
        rings`) and curvatures are nearest the data's; None: every row within the
        tolerance. Bounds the screening's cost whatever the database's size.
    screened_budget : int or None
        Screened poses kept across the database, at most (the best by the screening
        score, no more than ``n_screened`` of a model); None: ``n_screened`` per model.
    coarse_models, final_models : int or None
        Models that go on to the coarse and to the final stage, at most: those of least
        RMS residual after the stage before (the others pruned); None: no limit.
    """

    tolerance_scale: float = 1.0
    candidate_spacing_m: float = 2.5e-3
    aligned_anisotropy: float = 20.0
    aligned_window_rad: float = float(np.deg2rad(24.0))
    aligned_step_rad: float = float(np.deg2rad(8.0))
    scan_step_rad: float = float(np.deg2rad(10.0))
    prescreen_fractions: tuple[float, ...] = (2 / 3,)
    prescreen_keep: float = 0.1
    arm_fractions: tuple[float, ...] = (1 / 3, 2 / 3, 1.0)
    n_screened: int = 128
    screen_iterations: int = 4
    n_coarse: int = 48
    coarse_per_arm: int = 8
    coarse_iterations: int = 4
    n_final: int = 4
    final_iterations: int = 25
    candidate_budget: int | None = 20_000
    screened_budget: int | None = 1536
    coarse_models: int | None = 16
    final_models: int | None = 10


#: The first denser pass run when no model fits well enough (see FastConfig.fallbacks):
#: every vertex a candidate, phi near the alignment of the principal directions where
#: both are clearly anisotropic.
ALIGNED_SEARCH = FastSearchConfig(
    tolerance_scale=float("inf"),
    candidate_spacing_m=2.0e-3,
    n_screened=384,
    n_coarse=96,
    n_final=8,
    candidate_budget=60_000,
    screened_budget=4608,
)

#: The last pass: every vertex, phi scanned all round (principal directions mislead on
#: creases), more poses kept at each stage.
THOROUGH_SEARCH = FastSearchConfig(
    tolerance_scale=float("inf"),
    candidate_spacing_m=2.0e-3,
    aligned_anisotropy=float("inf"),
    prescreen_keep=0.3,
    n_screened=1000,
    n_coarse=150,
    n_final=12,
    candidate_budget=150_000,
    screened_budget=12_000,
)


@dataclass(frozen=True)
class FastConfig:
    """Settings of the fast mode (the default registration of mesh models).

    Attributes
    ----------
    delta : float
        Table-lookup tolerance of Eq. (4.7), 1/m (thesis: 0.03 1/mm = 30 1/m).
    relative_delta : float
        The tolerance grows by this fraction of the data's largest |k|; the estimates of
        both data and model disagree more where the curvature is high.
    geometry : DataGeometryConfig
        The data's local geometry at p, at the scale of the models' paraboloid fits
        (4.14); the normal from the arc over which a data curve turns by at most 0.4 rad
        (:attr:`DataGeometryConfig.normal_max_turn`).
    search : FastSearchConfig
        The first pass.
    fallbacks : tuple of FastSearchConfig
        Denser passes over the models not rejected at table lookup (by default over
        their whole surface, since curvature estimates fail on sharp creases), run in
        turn while the best error so far exceeds what the data's noise explains
        (:func:`~recognition.surfaces.registration.data.acceptable_error_m`); empty:
        never.
    accept_sigmas, accept_floor_m
        A fit is good enough when its mean error is within ``accept_sigmas`` standard
        deviations of the mean distance that the data's effective noise alone gives,
        plus ``accept_floor_m``. The noise is measured across the surface
        (:func:`~recognition.surfaces.registration.data.data_noise_m`), so that a
        sensor's error along the surface does not make a poor fit acceptable.
    model_mismatch_m : float
        How far the object may differ from its model (a scan's error, wear), RMS metres;
        it adds to the noise in the acceptance test and the outlier threshold.
    outlier_sigmas, outlier_floor_m
        A data point farther than ``outlier_sigmas`` effective noise levels (at least
        ``outlier_floor_m``) from a model is an outlier on it: the registration error
        (4.8) counts it at that threshold, the pose's last polish leaves it out, and the
        registration reports it
        (:func:`~recognition.surfaces.registration.data.outlier_threshold_m`).
    fit_noise_factor, fit_floor_m
        The curve fits at p are trusted when they explain each curve near p, and pass
        by p, to within ``fit_noise_factor`` times the data's noise plus ``fit_floor_m``
        (:func:`~recognition.surfaces.registration.data.data_fit_residual_m`); otherwise
        (p on a crease) candidates are not restricted by curvature.
    screen_prune_ratio : float or None
        A model whose best screened RMS residual (after the first Gauss-Newton steps on
        the screening points) exceeds this multiple of the best model's stops there, its
        screened poses scored as they are; None: never. Over 110 synthetic instances on
        22 models the true model's was at most 3.8 times the best; 8 stops about 13 of
        22 models before the coarse stage.
    prune_ratio : float or None
        A model whose best coarse RMS residual exceeds this multiple of the best
        model's stops before the final stage; None: never.
    polish_ratio, polish_margin_m, polish_iterations, polish_poses
        Models whose distance-field error is within ``polish_ratio`` times the best plus
        ``polish_margin_m`` are polished on exact closest points (at most
        ``polish_iterations`` steps of
        :func:`~recognition.surfaces.registration.exact.refine_exact`) and get exact
        errors; so are those of their first ``polish_poses`` distinct poses whose field
        errors are within ``polish_margin_m`` of their best (the field cannot tell them
        apart), the least exact error winning.
    equivalent_log_ratio, equivalent_floor_m
        Two distinct poses of a model are equivalent (equally good answers: a symmetric
        part, a flat face, a sphere) when the data are at most ``exp(equivalent_log_ratio)``
        times likelier at the better under Gaussian noise of the effective level, or
        their errors differ by at most ``equivalent_floor_m``
        (:class:`~recognition.surfaces.registration.ambiguity.Resolution`).
    free_motion_m : float
        The pose is free along a direction (a flat face, a cylinder's axis) when moving
        it this far along it is not resolved in the same sense, metres; the
        registration reports how many such directions it has.
    """

    mode: ClassVar[RegistrationMode] = RegistrationMode.FAST

    delta: float = 30.0
    relative_delta: float = 0.3
    geometry: DataGeometryConfig = field(
        default_factory=lambda: DataGeometryConfig(normal_max_turn=0.4)
    )
    search: FastSearchConfig = field(default_factory=FastSearchConfig)
    fallbacks: tuple[FastSearchConfig, ...] = (ALIGNED_SEARCH, THOROUGH_SEARCH)
    accept_sigmas: float = 4.0
    accept_floor_m: float = 5.0e-6
    model_mismatch_m: float = 0.0
    outlier_sigmas: float = 5.0
    outlier_floor_m: float = 0.1e-3
    fit_noise_factor: float = 5.0
    fit_floor_m: float = 5.0e-6
    screen_prune_ratio: float | None = 8.0
    prune_ratio: float | None = 4.0
    polish_ratio: float = 1.5
    polish_margin_m: float = 0.01e-3
    polish_iterations: int = 3
    polish_poses: int = 4
    equivalent_log_ratio: float = 3.0
    equivalent_floor_m: float = 1.0e-6
    free_motion_m: float = 1.0e-3


@dataclass(frozen=True)
class ThesisConfig:
    """Settings of the thesis's registration on meshes (Sections 4.3.3.1-4.3.3.2).

    Attributes
    ----------
    delta : float
        Table-lookup tolerance of Eq. (4.7), 1/m.
    geometry : DataGeometryConfig
    phi_step_deg : float
        Rotation step of the scan of phi (thesis: 10 degrees).
    max_candidates : int
        Candidates searched, nearest in (k1, k2) first.
    exact_top : int
        In a recognition, the models of least error whose error is then computed
        exactly (the best also polished).
    """

    mode: ClassVar[RegistrationMode] = RegistrationMode.THESIS

    delta: float = 30.0
    geometry: DataGeometryConfig = field(default_factory=DataGeometryConfig)
    phi_step_deg: float = 10.0
    max_candidates: int = 20
    exact_top: int = 3


@dataclass(frozen=True)
class IcpConfig:
    """Settings of the ICP baseline: multi-start point-to-plane ICP on mesh models.

    Attributes
    ----------
    delta : float
        Table-lookup tolerance of Eq. (4.7), 1/m.
    geometry : DataGeometryConfig
    phi_starts : int
        Starting rotations per candidate.
    max_candidates : int
        Candidates (nearest in (k1, k2) first) started from.
    iterations : int
        ICP iterations at most per start.
    exact_top : int
        As :attr:`ThesisConfig.exact_top`.
    """

    mode: ClassVar[RegistrationMode] = RegistrationMode.ICP

    delta: float = 30.0
    geometry: DataGeometryConfig = field(default_factory=DataGeometryConfig)
    phi_starts: int = 8
    max_candidates: int = 25
    iterations: int = 8
    exact_top: int = 3


class Optimizer(StrEnum):
    """Local search from a candidate point of a closed-form model."""

    LEVENBERG_MARQUARDT = "levenberg_marquardt"
    """Levenberg-Marquardt on the residuals f / |grad f| over (u, v, phi) (default)."""
    STEEPEST_DESCENT = "steepest_descent"
    """The thesis's steepest descent on E(u, v, phi) (4.11), backtracking line search."""


@dataclass(frozen=True)
class ClosedFormConfig:
    """Settings of the registration onto closed-form models (thesis 4.1.2, 4.2.2).

    Attributes
    ----------
    delta : float
        Table lookup tolerance of (4.7), 1 / model units (``inf``: no rejection). The
        default is the thesis's free-form tolerance 0.03 1/mm = 30 1/m; the unit-free
        Table 4.1 surfaces need their own (0.1 in the reproduction).
    geometry : DataGeometryConfig
        The data's local geometry at p (default: over 6 mm, degree 4, at most half a
        radian of turn, at the curves' pairwise closest points).
    max_candidates : int
        Candidate points kept after thinning the lookup result; phi is initialised at
        each (4.2.2.1).
    local_searches : int
        Local searches, from the candidates of least initial error E(u, v, phi_0).
    candidate_separation : float
        Smallest distance between two candidates, as a fraction of the data's radius
        (largest distance of a data point from p).
    phi_samples, bisection_steps : int
        Discretisation of [0, 2 pi) and bisection steps of the phi initialisation.
    optimizer : Optimizer
    rigid_refinement : bool
        Follow the best (u, v, phi) search by a six-degree-of-freedom refinement.
    max_iterations : int
        Per local search (the steepest descent gets 20 times as many).
    tolerance : float
        Relative decrease of the squared residuals (or of E) at which a search stops.
    """

    mode: ClassVar[RegistrationMode] = RegistrationMode.CLOSED_FORM

    delta: float = 30.0
    geometry: DataGeometryConfig = field(
        default_factory=lambda: DataGeometryConfig(
            fit_half_length_m=6.0e-3,
            fit_spacings=None,
            fit_degree=4,
            fit_max_turn=0.5,
            at_common_point=False,
        )
    )
    max_candidates: int = 24
    local_searches: int = 6
    candidate_separation: float = 0.15
    phi_samples: int = 72
    bisection_steps: int = 24
    optimizer: Optimizer = Optimizer.LEVENBERG_MARQUARDT
    rigid_refinement: bool = True
    max_iterations: int = 100
    tolerance: float = 1e-10


#: The settings of any registration mode.
RegistrationConfig = FastConfig | ThesisConfig | IcpConfig | ClosedFormConfig
