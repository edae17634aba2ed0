"""Chapter 3 experiment settings and the sampled, estimated curves they produce."""

from __future__ import annotations

import itertools
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from recognition.curves import invariants as inv
from recognition.curves.estimation import LocalGeometry, local_fit_geometry
from recognition.curves.families import CanonicalCurve, CurveKind
from recognition.curves.recognition import (
    canonical_parameters,
    estimated_uncertainty,
    recognize_curve,
)
from recognition.curves.sampling import SampledCurve, random_curve, sample_by_arc_length
from recognition.pools import process_pool
from recognition.reproduction.chapter3.measures import relative_parameter_error
from recognition.reproduction.chapter3.reference import (
    CLASSES,
    TABLE_3_1_SHAPES,
    TABLE_3_2_SPLINE,
)
from recognition.rigid import random_planar_motion

__all__ = [
    "DEFAULT_CURVE_EXPERIMENT",
    "DEFAULT_JOYSTICK_EXPERIMENT",
    "SPLINE_SEGMENT_EXPERIMENT",
    "CurveExperiment",
    "JoystickExperiment",
    "classify_random_curves",
    "default_experiment",
    "ellipse_arc_estimates",
    "experiment_rng",
    "joystick_ellipse_estimates",
    "random_pairs",
    "sample_placed_curve",
    "shape_geometry",
]


@dataclass(frozen=True)
class CurveExperiment:
    """Sampling and estimation settings of the simulated experiments (Tables 3.1-3.3).

    Attributes
    ----------
    spacing : float
        Arc length between consecutive samples, in curve units (the curves are 1-10
        units across).
    noise_std : float
        Isotropic Gaussian noise per coordinate, curve units.
    window, degree, kappa_window
        :func:`~recognition.curves.estimation.local_fit_geometry` settings.
    n_estimates : int
        Estimates per curve passed to the recognition tree.
    tolerance : float or None
        Consistency tolerance of the recognition tree; None (the default): the tree's
        chi-square test with the uncertainty the estimator's own error model gives the
        estimates (:func:`~recognition.curves.recognition.tree.estimated_uncertainty`),
        the default of ``recognize_points(..., decide_by="invariants")``.
    seed : int
    """

    spacing: float = 0.01
    noise_std: float = 0.0
    window: int = 11
    degree: int = 6
    kappa_window: int | None = None
    n_estimates: int = 25
    tolerance: float | None = None
    seed: int = 0

    def estimate(self, points: ArrayLike) -> LocalGeometry:
        """kappa, kappa_s and phi of ordered points (n, 2) by this experiment's local fit."""
        return local_fit_geometry(
            points, window=self.window, degree=self.degree, kappa_window=self.kappa_window
        )

    def describe(self) -> str:
        """The settings in words, for the tables' captions."""
        return (
            f"points every {self.spacing:g} units of arc length, noise sigma "
            f"{self.noise_std:g}; local polynomial fit over {self.window} points, degree "
            f"{self.degree}"
            + (f", kappa_s from {self.kappa_window} kappa estimates" if self.kappa_window else "")
            + (
                "; the estimator's own uncertainty"
                if self.tolerance is None
                else f"; tolerance {self.tolerance:g}"
            )
        )


@dataclass(frozen=True)
class JoystickExperiment:
    """Noisy joystick-like samples of two arcs of an ellipse (Table 3.4, Fig. 3.7).

    Units are centimetres: the ellipse of Table 3.4 has a = 2.5, b = 1.75 (25 x 17.5 mm);
    0.05 spacing is 0.5 mm, 0.003 noise is 30 um, the sensed-point accuracy of the
    simulated probe.

    Attributes
    ----------
    a, b : float
        Semi-axes of the ellipse, cm.
    spacing, noise_std : float
        Arc length between samples and Gaussian noise per coordinate, cm.
    arc_length : float
        Length of each sampled arc, cm.
    n_arcs, estimates_per_arc : int
        Arcs per experiment and estimates kept on each.
    window, degree, kappa_window
        :func:`~recognition.curves.estimation.local_fit_geometry` settings.
    n_pairs : int
        Pairs of estimates of the pairwise invariants (3.19)-(3.20).
    trials : int
        Independent experiments of the recognition tree's estimate.
    seed : int
    """

    a: float = 2.5
    b: float = 1.75
    spacing: float = 0.05
    noise_std: float = 0.003
    arc_length: float = 6.0
    n_arcs: int = 2
    estimates_per_arc: int = 20
    window: int = 21
    degree: int = 3
    kappa_window: int | None = 21
    n_pairs: int = 80
    trials: int = 20
    seed: int = 0


#: The default settings of the simulated experiments (Tables 3.1-3.3).
DEFAULT_CURVE_EXPERIMENT = CurveExperiment()
#: Table 3.5's settings: the defaults with a point every 0.005 units of arc length.
SPLINE_SEGMENT_EXPERIMENT = CurveExperiment(spacing=0.005)
#: The default joystick experiment (Table 3.4, Fig. 3.7).
DEFAULT_JOYSTICK_EXPERIMENT = JoystickExperiment()


def default_experiment(**overrides: Any) -> CurveExperiment:
    """The documented default settings, with ``overrides`` applied."""
    return replace(CurveExperiment(), **overrides)


def experiment_rng(*key: int) -> np.random.Generator:
    """The generator of one measurement, seeded by the integers ``key``."""
    return np.random.default_rng(np.random.SeedSequence(list(key)))


def sample_placed_curve(
    curve: CanonicalCurve,
    t0: float,
    t1: float,
    experiment: CurveExperiment | JoystickExperiment,
    rng: np.random.Generator,
) -> SampledCurve:
    """Samples of ``curve`` from ``t0`` to ``t1`` at the experiment's spacing and noise,
    placed by a random planar motion drawn from ``rng``."""
    return sample_by_arc_length(
        curve,
        t0,
        t1,
        experiment.spacing,
        rng=rng,
        noise_std=experiment.noise_std,
        T_data_from_canonical=random_planar_motion(rng),
    )


def random_pairs(
    rng: np.random.Generator,
    n_points: int,
    n_pairs: int,
    kappa: np.ndarray | None = None,
    min_rel_diff: float = 0.05,
) -> np.ndarray:
    """Up to ``n_pairs`` distinct random index pairs (k, 2) of ``n_points`` points; with
    ``kappa``, |kappa|^(2/3) must differ by ``min_rel_diff`` (relative) within a pair."""
    pairs = np.array(list(itertools.combinations(range(n_points), 2)))
    pairs = pairs[rng.permutation(len(pairs))]
    if kappa is not None:
        u = inv.abs_two_thirds(kappa)
        diff = np.abs(u[pairs[:, 0]] - u[pairs[:, 1]]) / np.maximum(u[pairs[:, 0]], u[pairs[:, 1]])
        pairs = pairs[diff >= min_rel_diff]
    return pairs[:n_pairs]


def shape_geometry(kind: CurveKind, experiment: CurveExperiment, key: int) -> LocalGeometry:
    """Estimates along Table 3.1's shape of class ``kind`` (Table 3.2's spline for the
    cubic spline), sampled and placed with the generator of ``key``."""
    params, (t0, t1) = TABLE_3_1_SHAPES.get(kind) or TABLE_3_2_SPLINE
    rng = experiment_rng(experiment.seed, 31, key)
    sampled = sample_placed_curve(CanonicalCurve(kind, params), t0, t1, experiment, rng)
    return experiment.estimate(sampled.points)


def ellipse_arc_estimates(
    arcs: Iterable[ArrayLike], experiment: JoystickExperiment
) -> LocalGeometry:
    """kappa and kappa_s at ``estimates_per_arc`` points on each arc (thesis Section 3.4.2).

    Parameters
    ----------
    arcs : sequence of (n_i, 2) float
        Ordered points along arcs of one ellipse, in the experiment's units (cm), each
        arc in its own frame.
    experiment : JoystickExperiment
        The estimator's settings (``window``, ``degree``, ``kappa_window``).

    Returns
    -------
    LocalGeometry
        The estimates of all arcs concatenated, |kappa| (each arc may be traversed
        either way).
    """
    parts = []
    for points in arcs:
        g = local_fit_geometry(
            np.asarray(points, dtype=float),
            window=experiment.window,
            degree=experiment.degree,
            kappa_window=experiment.kappa_window,
        )
        idx = np.linspace(0, len(g) - 1, experiment.estimates_per_arc).round().astype(int)
        parts.append(g.subset(idx))
    cat = [np.concatenate([getattr(p, f) for p in parts]) for f in ("kappa", "kappa_s")]
    # each arc was placed by its own rigid motion: signs of kappa follow the traversal
    kappa = np.abs(cat[0])
    n = kappa.size
    return LocalGeometry(np.arange(n), np.zeros((n, 2)), np.zeros(n), np.zeros(n), kappa, cat[1])


def joystick_ellipse_estimates(experiment: JoystickExperiment, trial: int) -> LocalGeometry:
    """Estimates at ``estimates_per_arc`` points on each of ``n_arcs`` noisy ellipse arcs."""
    rng = experiment_rng(experiment.seed, 34, trial)
    curve = CanonicalCurve(CurveKind.ELLIPSE, (experiment.a, experiment.b))
    arcs = []
    for _ in range(experiment.n_arcs):
        t0 = rng.uniform(0.0, 2 * np.pi)
        # parameter span of the requested arc length, from the local speed
        span = experiment.arc_length / float(curve.speed(t0 + np.linspace(0, 1, 5)).mean())
        arcs.append(sample_placed_curve(curve, t0, t0 + span, experiment, rng).points)
    return ellipse_arc_estimates(arcs, experiment)


def _classify_one(job: tuple[CurveKind, int, CurveExperiment]) -> dict[str, Any]:
    """The record of random curve ``index`` of class ``kind`` (see classify_random_curves)."""
    kind, index, experiment = job
    rng = experiment_rng(experiment.seed, 33, list(CurveKind).index(kind), index)
    curve, t0, t1 = random_curve(kind, rng)
    sampled = sample_placed_curve(curve, t0, t1, experiment, rng)
    g = experiment.estimate(sampled.points)
    pick = np.unique(np.linspace(0, len(g) - 1, min(experiment.n_estimates, len(g))).round())
    g = g.subset(pick.astype(int))
    if experiment.tolerance is None:
        result = recognize_curve(g.kappa, g.kappa_s, g.dphi, uncertainty=estimated_uncertainty(g))
    else:
        result = recognize_curve(g.kappa, g.kappa_s, g.dphi, tolerance=experiment.tolerance)
    true = canonical_parameters(kind, curve.params) if kind in CLASSES else curve.params
    own = next((c for c in result.candidates if c.kind is kind), None)
    return {
        "kind": kind.value,
        "index": index,
        "true": list(true),
        "recognized": result.kind.value,
        "residual": result.residual,
        "own_class_params": list(own.params) if own else [],
        "own_class_error": relative_parameter_error(true, own.params) if own else float("inf"),
    }


def classify_random_curves(
    experiment: CurveExperiment = DEFAULT_CURVE_EXPERIMENT,
    n_curves: int = 100,
    kinds: Sequence[CurveKind | str] = (*CLASSES, CurveKind.QUARTIC),
    workers: int | None = None,
) -> list[dict[str, Any]]:
    """Sample ``n_curves`` random curves per class, estimate and run the recognition tree.

    Each record holds the true class and shape, the recognised class, and the shape
    recovered by the fit of the true class (for Table 3.3). Curves are seeded by
    (seed, class, index): the same settings give the same records in any process count.

    Parameters
    ----------
    experiment : CurveExperiment
    n_curves : int
        Curves per class.
    kinds : sequence of CurveKind
        The classes (a quartic belongs to none).
    workers : int, optional
        Worker processes (default: all cores).

    Returns
    -------
    list of dict
        Per curve: ``kind``, ``index``, ``true`` (shape), ``recognized`` (class),
        ``residual``, ``own_class_params`` and ``own_class_error`` (relative parameter
        error of the true class's fit).
    """
    jobs = [(CurveKind(k), i, experiment) for k in kinds for i in range(n_curves)]
    workers = workers or os.cpu_count() or 1
    if workers == 1:
        return [_classify_one(job) for job in jobs]
    with process_pool(workers) as pool:
        return list(pool.map(_classify_one, jobs, chunksize=4))
