"""The recognition tree of thesis Fig. 3.4: every class hypothesis, then the decision."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from recognition.curves.estimation import LocalGeometry, local_fit_geometry
from recognition.curves.families import N_PARAMETERS, TREE_CLASSES, CurveKind
from recognition.curves.recognition.hypotheses import fit_hypothesis
from recognition.curves.recognition.results import ClassFit, CurveRecognition
from recognition.curves.recognition.signature_fit import ContactData, best_fit, contact_data
from recognition.errors import DegenerateGeometry, InvalidCurveData

__all__ = [
    "COMPLEXITY_FACTOR",
    "DEFAULT_TOLERANCE",
    "MAX_OUTLIER_FRACTION",
    "MIN_POINTS_FOR_OUTLIERS",
    "OUTLIER_FACTOR",
    "fit_class",
    "recognize_curve",
    "recognize_points",
]

#: Default consistency tolerance (reduced relative residual) of :func:`recognize_curve`.
DEFAULT_TOLERANCE = 0.02
#: A more complex class must fit this many times better to be preferred.
COMPLEXITY_FACTOR = 3.0


#: A point whose residual exceeds this multiple of the median is an estimation outlier.
OUTLIER_FACTOR = 5.0
#: At most this fraction of the points is left out as outliers.
MAX_OUTLIER_FRACTION = 0.1
#: With at least this many points, one outlier may be left out even below 10 points.
MIN_POINTS_FOR_OUTLIERS = 6


def fit_class(
    kind: CurveKind | str, kappa: ArrayLike, kappa_s: ArrayLike, dphi: ArrayLike | None = None
) -> ClassFit:
    """Test one class hypothesis on kappa, kappa_s (and tangent rotations ``dphi``).

    Parameters
    ----------
    kind : CurveKind or str
        A class of the tree.
    kappa, kappa_s : (m,) float
        Curvature (1/length) and its arc-length derivative (1/length^2) at m >= 3 points.
    dphi : (m,) float, optional
        Tangent rotation of each point from the first (radians); the cubic classes need it.
    """
    kind = CurveKind(kind)
    data = contact_data(kappa, kappa_s, dphi)
    return _fit_with_outliers(kind, data)


def _fit_with_outliers(kind: CurveKind, data: ContactData) -> ClassFit:
    """Fit one class; then leave out estimation outliers and fit again from scratch.

    Estimates of kappa_s are least reliable where the curvature changes fastest (a few
    points near a cusp or a sharp bend). After a first fit, at most
    ``MAX_OUTLIER_FRACTION`` of the points (one point from ``MIN_POINTS_FOR_OUTLIERS``
    points up) whose residual exceeds ``OUTLIER_FACTOR`` times the median are left out
    and the class is fitted again, initialisation included, on the rest. Their contact
    parameters are NaN and their indices are in ``ClassFit.outliers``.
    """
    fit = fit_hypothesis(kind, data)
    if not np.isfinite(fit.residual) or fit.per_point is None:
        return fit
    per_point = fit.per_point
    n_out = max(int(MAX_OUTLIER_FRACTION * data.m), 1 if data.m >= MIN_POINTS_FOR_OUTLIERS else 0)
    worst = np.argsort(-per_point)[:n_out]
    outliers = np.sort(worst[per_point[worst] > OUTLIER_FACTOR * np.median(per_point)])
    if outliers.size == 0:
        return fit
    keep = np.setdiff1d(np.arange(data.m), outliers)
    again = fit_hypothesis(kind, data.subset(keep))
    if not again.residual < fit.residual:
        return fit
    t = np.full(data.m, np.nan)
    t[keep] = again.t
    return replace(again, t=t, outliers=tuple(int(i) for i in outliers))


def _relative_spread(values: ArrayLike) -> float:
    """std / |mean| of the finite values; NaN for fewer than two."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size < 2:
        return float("nan")
    return float(np.std(v) / max(abs(np.mean(v)), 1e-300))


def recognize_curve(
    kappa: ArrayLike,
    kappa_s: ArrayLike,
    dphi: ArrayLike | None = None,
    *,
    tolerance: float = DEFAULT_TOLERANCE,
    complexity_factor: float = COMPLEXITY_FACTOR,
) -> CurveRecognition:
    """Recognise a curve from its local geometry at m >= 3 points (thesis Fig. 3.4).

    Parameters
    ----------
    kappa, kappa_s : (m,) float
        Curvature and its arc-length derivative at m points, in order of traversal.
    dphi : (m,) float, optional
        Tangent rotation of each point from the first (radians), e.g. the jaw rotation
        of Section 3.2.2.1 or :attr:`LocalGeometry.dphi`. Without it only the conics can
        be recognised.
    tolerance : float
        Largest reduced relative residual of a consistent class; must exceed the
        relative estimation error of kappa and kappa_s.
    complexity_factor : float
        How much better a more complex class must fit to be preferred.
    """
    if not tolerance > 0:
        raise InvalidCurveData(f"tolerance must be positive, got {tolerance}")
    data = contact_data(kappa, kappa_s, dphi)
    if data.phi is not None and np.ptp(data.phi) < 1e-9:
        raise DegenerateGeometry(
            "the tangent does not turn: a straight segment has no curvature invariants"
        )
    fits = [_fit_with_outliers(k, data) for k in TREE_CLASSES]

    chosen: ClassFit | None = None
    best = best_fit(fits)
    if best.residual <= tolerance:
        good_enough = max(complexity_factor * best.residual, tolerance / complexity_factor)
        for level in (1, 2, 3):
            at_level = [f for f in fits if N_PARAMETERS[f.kind] == level]
            if at_level and best_fit(at_level).residual <= good_enough:
                chosen = best_fit(at_level)
                break
    if chosen is None:
        return CurveRecognition(
            CurveKind.UNCLASSIFIED,
            {},
            np.array([]),
            {},
            {},
            float("inf"),
            tuple(fits),
            tolerance,
        )
    invariants = dict(chosen.invariants)
    if chosen.kind is CurveKind.PARABOLA:
        invariants = {"I_p": invariants["I_p"]}
    return CurveRecognition(
        chosen.kind,
        chosen.parameters,
        chosen.t,
        invariants,
        {name: _relative_spread(v) for name, v in invariants.items()},
        chosen.residual,
        tuple(fits),
        tolerance,
    )


def recognize_points(
    points: ArrayLike,
    *,
    n_estimates: int = 25,
    tolerance: float = DEFAULT_TOLERANCE,
    estimator: Callable[..., LocalGeometry] = local_fit_geometry,
    **estimator_options: Any,
) -> tuple[CurveRecognition, LocalGeometry]:
    """Estimate local geometry from ordered tactile points and run the recognition tree
    (thesis Fig. 3.4).

    ``n_estimates`` evenly spaced estimates (of all the estimator returns) are passed to
    :func:`recognize_curve` together with their tangent rotations.

    Parameters
    ----------
    points : (n, 2) float
        Ordered tactile points along the curve (any length unit).
    n_estimates : int
    tolerance : float
        See :func:`recognize_curve`.
    estimator : callable
        ``estimator(points, **estimator_options) -> LocalGeometry``.

    Returns
    -------
    CurveRecognition
    LocalGeometry
        The estimates used.
    """
    geometry = estimator(points, **estimator_options)
    if len(geometry) < 3:
        raise InvalidCurveData("the estimator returned fewer than three estimates")
    pick = np.unique(np.linspace(0, len(geometry) - 1, min(n_estimates, len(geometry))).round())
    used = geometry.subset(pick.astype(int))
    turn = abs(used.dphi[-1])
    if np.all(np.abs(used.kappa) * (used.s[-1] - used.s[0]) < 1e-6) and turn < 1e-6:
        raise DegenerateGeometry(
            "the points lie on a straight segment (kappa = 0): no curvature invariants exist"
        )
    return recognize_curve(used.kappa, used.kappa_s, used.dphi, tolerance=tolerance), used
