"""The recognition tree of thesis Fig. 3.4: every class hypothesis, then the decision."""

from __future__ import annotations

import numbers
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import orth
from scipy.special import chdtrc, chdtri, fdtrc

from recognition.curves.estimation import LocalGeometry, local_fit_geometry
from recognition.curves.families import N_PARAMETERS, TREE_CLASSES, CurveKind
from recognition.curves.recognition.hypotheses import Test, fit_conics, fit_hypothesis
from recognition.curves.recognition.point_fit import PointFit, fit_classes
from recognition.curves.recognition.results import ClassFit, CurveRecognition, canonical_form
from recognition.curves.recognition.signature_fit import (
    ContactData,
    best_fit,
    contact_data,
    rejected,
)
from recognition.curves.recognition.uncertainty import (
    DEFAULT_SIGNIFICANCE,
    EXACT_PRECISION,
    InputUncertainty,
    magnitude_scales,
)
from recognition.errors import DegenerateGeometry, InvalidCurveData

__all__ = [
    "COMPLEXITY_FACTOR",
    "DEFAULT_SIGNIFICANCE",
    "DEFAULT_TOLERANCE",
    "ESTIMATE_PRECISION",
    "MAX_OUTLIER_FRACTION",
    "MIN_POINTS_FOR_OUTLIERS",
    "OUTLIER_FACTOR",
    "SMOOTH_MODES",
    "estimated_uncertainty",
    "fit_class",
    "recognize_curve",
    "recognize_points",
    "smooth_statistic",
]

#: The reduced relative residual of a consistent class in the ``tolerance`` mode as it
#: was the default before the input uncertainty: suits noisy tactile estimates only.
DEFAULT_TOLERANCE = 0.02
#: Tolerance mode: a more complex class must fit this many times better to be preferred.
COMPLEXITY_FACTOR = 3.0
#: Relative floor added to the uncertainty the estimator's error model gives its
#: estimates (their rounding: noise-free degree-6 fits over 11 points leave relative
#: errors of kappa up to about 5e-11, which a floor of 1e-12 understated, refusing 2-7 of
#: 100 noise-free parabolas), and radians for the angles.
ESTIMATE_PRECISION = 1e-10

#: Points decided by their fits: the residuals' smoothest modes along the curve (the
#: polynomials of arc length up to degree 3), beyond what the fit's unknowns change,
#: tested apart (:func:`smooth_statistic`).
SMOOTH_MODES = 4
#: Directions of those modes whose part beyond the fit's changes is shorter than this
#: fraction of the longest are left out.
SMOOTH_RANK_TOLERANCE = 1e-3

#: A point whose residual exceeds this multiple of the median is an estimation outlier.
OUTLIER_FACTOR = 5.0
#: At most this fraction of the points is left out as outliers.
MAX_OUTLIER_FRACTION = 0.1
#: With at least this many points, one outlier may be left out even below 10 points.
MIN_POINTS_FOR_OUTLIERS = 6


def fit_class(
    kind: CurveKind | str,
    kappa: ArrayLike,
    kappa_s: ArrayLike,
    dphi: ArrayLike | None = None,
    *,
    uncertainty: InputUncertainty | None = None,
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
    uncertainty : InputUncertainty, optional
        Standard uncertainty of the inputs; without it the residuals are relative (the
        tolerance mode's measure) and the statistic is the sum of their squares.
    """
    kind = CurveKind(kind)
    data = contact_data(kappa, kappa_s, dphi, uncertainty)
    return _fit_with_outliers(kind, data, Test())


def _fit_with_outliers(kind: CurveKind, data: ContactData, test: Test) -> ClassFit:
    """Fit one class; then leave out estimation outliers and fit again from scratch.

    Estimates of kappa_s are least reliable where the curvature changes fastest (a few
    points near a cusp or a sharp bend). After a first fit, at most
    ``MAX_OUTLIER_FRACTION`` of the points (one point from ``MIN_POINTS_FOR_OUTLIERS``
    points up) whose residual exceeds ``OUTLIER_FACTOR`` times the median are left out
    and the class is fitted again, initialisation included, on the rest. Their contact
    parameters are NaN and their indices are in ``ClassFit.outliers``.
    """
    return _with_outliers(fit_hypothesis(kind, data, test), data, test)


def _with_outliers(fit: ClassFit, data: ContactData, test: Test) -> ClassFit:
    if not np.isfinite(fit.residual) or fit.per_point is None:
        return fit
    per_point = fit.per_point
    n_out = max(int(MAX_OUTLIER_FRACTION * data.m), 1 if data.m >= MIN_POINTS_FOR_OUTLIERS else 0)
    worst = np.argsort(-per_point)[:n_out]
    outliers = np.sort(worst[per_point[worst] > OUTLIER_FACTOR * np.median(per_point)])
    if outliers.size == 0:
        return fit
    keep = np.setdiff1d(np.arange(data.m), outliers)
    again = fit_hypothesis(fit.kind, data.subset(keep), test)
    if not again.residual < fit.residual:
        return fit
    t = np.full(data.m, np.nan)
    t[keep] = again.t
    return replace(again, t=t, outliers=tuple(int(i) for i in outliers))


def _decided(fits: Sequence[ClassFit], test: Test, complexity_factor: float) -> ClassFit | None:
    """The class the fits so far decide for, if no class with one more parameter could
    displace it: in the tolerance mode a residual below ``tolerance / complexity_factor``;
    else a consistent class whose statistic is below the likelihood-ratio margin of one
    more parameter (:func:`_choose_by_test`), which no fit could overcome."""
    if test.tolerance is not None:
        good = [f for f in fits if f.residual <= test.tolerance / complexity_factor]
        return min(good, key=lambda f: f.residual) if good else None
    if test.significance is None:
        return None
    chosen = _choose_by_test(fits, test.significance)
    if chosen is not None and chosen.statistic <= chosen.scale * chdtri(1, test.significance):
        return chosen
    return None


def _not_fitted(kind: CurveKind, decided: ClassFit) -> ClassFit:
    """The record of a class left unfitted because ``decided`` fits too well."""
    message = (
        f"not fitted: the {decided.kind} fits too well for a {kind} to fit significantly better"
    )
    return replace(rejected(kind, message), statistic=float("nan"), p_value=float("nan"))


def _all_fits(data: ContactData, test: Test, complexity_factor: float) -> list[ClassFit]:
    """Every class of the tree fitted, outliers left out, in tree order.

    The classes are fitted by number of parameters (the parabola and the conics first;
    then the cubical and semi-cubical parabolas; then the cubic spline). A level is left
    unfitted when the classes before it already decide (:func:`_decided`): no fit of more
    parameters could change the decision.
    """
    fits: dict[CurveKind, ClassFit] = {}
    with np.errstate(all="ignore"):
        conics = fit_conics(data, test)
    for fit in conics:
        fits[fit.kind] = _with_outliers(fit, data, test)
    fits[CurveKind.PARABOLA] = _fit_with_outliers(CurveKind.PARABOLA, data, test)
    later = (
        (CurveKind.CUBICAL_PARABOLA, CurveKind.SEMICUBICAL_PARABOLA),
        (CurveKind.CUBIC_SPLINE,),
    )
    for kinds in later:
        decided = _decided(list(fits.values()), test, complexity_factor)
        for kind in kinds:
            if decided is None:
                fits[kind] = _fit_with_outliers(kind, data, test)
            else:
                fits[kind] = _not_fitted(kind, decided)
    return [fits[kind] for kind in TREE_CLASSES]


def _relative_spread(values: ArrayLike) -> float:
    """std / |mean| of the finite values; NaN for fewer than two."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size < 2:
        return float("nan")
    return float(np.std(v) / max(abs(np.mean(v)), 1e-300))


def _standing(fit: ClassFit) -> tuple[float, float]:
    """Sort key of how well a class fits: p-value, then reduced statistic (lower first)."""
    p = fit.p_value if np.isfinite(fit.p_value) else 0.0
    reduced = fit.statistic / fit.dof if fit.dof > 0 else float("inf")
    return (-p, reduced if np.isfinite(reduced) else float("inf"))


def _fitted_better(fit: ClassFit) -> float:
    """Sort key of point fits of one level (as many unknowns each): the sum of squared
    distances, the likelihood's order (noise in the points counts alike in every fit)."""
    return fit.statistic if np.isfinite(fit.statistic) else float("inf")


def _choose_by_test(
    fits: Sequence[ClassFit],
    significance: float,
    better: Callable[[ClassFit], Any] = _standing,
) -> ClassFit | None:
    """The class the chi-square tests support, or None.

    The consistent classes are those with p-value >= ``significance``. The simplest
    level with a consistent class gives the first choice (the best-fitting there, least
    by ``better``); a consistent class of a higher level replaces it when its statistic
    is lower by more than the ``1 - significance`` quantile of chi-square with the
    difference in parameters as degrees of freedom (a likelihood-ratio test: the classes
    are nested, a parabola is a conic and a spline, a semi-cubical parabola a spline with
    c = 0).
    """
    consistent = [f for f in fits if np.isfinite(f.p_value) and f.p_value >= significance]
    if not consistent:
        return None
    levels = sorted({N_PARAMETERS[f.kind] for f in consistent})
    chosen = min((f for f in consistent if N_PARAMETERS[f.kind] == levels[0]), key=better)
    for level in levels[1:]:
        candidate = min((f for f in consistent if N_PARAMETERS[f.kind] == level), key=better)
        extra = N_PARAMETERS[candidate.kind] - N_PARAMETERS[chosen.kind]
        margin = max(chosen.scale, candidate.scale) * chdtri(extra, significance)
        if chosen.statistic - candidate.statistic > margin:
            chosen = candidate
    return chosen


def _choose_by_tolerance(
    fits: Sequence[ClassFit], tolerance: float, complexity_factor: float
) -> ClassFit | None:
    """The class of the tolerance mode: the simplest (parabola; then the two-parameter
    classes; then the cubic spline) whose reduced residual is within
    ``complexity_factor`` of the best, or below ``tolerance / complexity_factor``."""
    best = best_fit(fits)
    if not best.residual <= tolerance:
        return None
    good_enough = max(complexity_factor * best.residual, tolerance / complexity_factor)
    for level in (1, 2, 3):
        at_level = [f for f in fits if N_PARAMETERS[f.kind] == level]
        if at_level and best_fit(at_level).residual <= good_enough:
            return best_fit(at_level)
    return None


def _check_significance(significance: float) -> None:
    """Raise :class:`InvalidCurveData` unless ``significance`` lies in (0, 1)."""
    if not (isinstance(significance, numbers.Real) and 0 < significance < 1):
        raise InvalidCurveData(f"significance must lie in (0, 1), got {significance}")


def _decision(
    chosen: ClassFit | None,
    fits: Sequence[ClassFit],
    significance: float,
    *,
    tolerance: float | None = None,
    decided_by: str = "invariants",
    noise: float | None = None,
) -> CurveRecognition:
    """The recognition of the ``chosen`` class among ``fits`` (unclassified when None),
    with the next-best class as runner-up; the parabola reports its invariant I_p only."""
    others = sorted((f for f in fits if f is not chosen), key=_standing)
    runner_up = others[0] if others else None
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
            float("inf"),
            0.0,
            significance,
            runner_up,
            decided_by,
            noise,
        )
    invariants = dict(chosen.invariants)
    if chosen.kind is CurveKind.PARABOLA and invariants:
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
        chosen.statistic,
        chosen.p_value,
        significance,
        runner_up,
        decided_by,
        noise,
    )


def recognize_curve(
    kappa: ArrayLike,
    kappa_s: ArrayLike,
    dphi: ArrayLike | None = None,
    *,
    uncertainty: InputUncertainty | None = None,
    significance: float = DEFAULT_SIGNIFICANCE,
    tolerance: float | None = None,
    complexity_factor: float = COMPLEXITY_FACTOR,
) -> CurveRecognition:
    """Recognise a curve from its local geometry at m >= 3 points (thesis Fig. 3.4).

    Every class of the tree is fitted to the data (:mod:`.hypotheses`,
    :mod:`.signature_fit`); a class is consistent when the chi-square statistic of its
    fit, the residuals divided by the inputs' standard uncertainty, has a p-value of at
    least ``significance`` (:mod:`.uncertainty`). The simplest consistent class is
    recognised unless a more complex consistent one fits significantly better;
    :attr:`CurveRecognition.runner_up` is the next-best class and
    :attr:`CurveRecognition.p_value` how well the recognised one fits.

    Parameters
    ----------
    kappa, kappa_s : (m,) float
        Curvature (1/length) and its arc-length derivative (1/length^2) at m points, in
        order of traversal.
    dphi : (m,) float, optional
        Tangent rotation of each point from the first (radians), e.g. the jaw rotation
        of Section 3.2.2.1 or :attr:`LocalGeometry.dphi`. Without it only the conics can
        be recognised.
    uncertainty : InputUncertainty, optional
        Standard uncertainty of the inputs (absolute or relative, for kappa, kappa_s and
        the tangent angles, optionally correlated). Default: the values are exact to
        rounding, ``InputUncertainty.relative(EXACT_PRECISION)``.
    significance : float
        Probability that data of a class, with errors as stated, are found inconsistent
        with it (the test's false-rejection rate); the rate at which curves of no class
        are accepted depends on how far they are from every class and is measured in
        ``docs/results/chapter3.md``.
    tolerance : float, optional
        Instead of the uncertainty: the largest reduced relative residual of a
        consistent class (the decision before the input uncertainty; 0.02 was its
        default), with ``complexity_factor``.
    complexity_factor : float
        Tolerance mode: how much better a more complex class must fit to be preferred.
    """
    if tolerance is not None:
        if uncertainty is not None:
            raise InvalidCurveData("give either the input uncertainty or a tolerance, not both")
        if not (isinstance(tolerance, numbers.Real) and tolerance > 0):
            raise InvalidCurveData(f"tolerance must be positive, got {tolerance}")
        if not (isinstance(complexity_factor, numbers.Real) and complexity_factor >= 1):
            raise InvalidCurveData(f"complexity_factor must be >= 1, got {complexity_factor}")
    _check_significance(significance)
    if uncertainty is None and tolerance is None:
        uncertainty = InputUncertainty.relative(EXACT_PRECISION)
    if uncertainty is not None and not isinstance(uncertainty, InputUncertainty):
        raise InvalidCurveData(
            f"uncertainty must be an InputUncertainty, got {type(uncertainty).__name__}"
        )
    data = contact_data(kappa, kappa_s, dphi, uncertainty)
    if data.phi is not None and np.ptp(data.phi) < 1e-9:
        raise DegenerateGeometry(
            "the tangent does not turn: a straight segment has no curvature invariants"
        )
    test = Test(significance, None) if tolerance is None else Test(None, tolerance)
    fits = _all_fits(data, test, complexity_factor)
    if tolerance is None:
        chosen = _choose_by_test(fits, significance)
    else:
        chosen = _choose_by_tolerance(fits, tolerance, complexity_factor)
    return _decision(chosen, fits, significance, tolerance=tolerance)


def estimated_uncertainty(geometry: LocalGeometry) -> InputUncertainty:
    """The uncertainty of an estimator's kappa, kappa_s and tangent angles from its own
    error model (:attr:`LocalGeometry.sensitivity`: the noise of the local fits'
    residuals propagated, and their truncation error), with the floor
    ``ESTIMATE_PRECISION``."""
    if geometry.sensitivity is None:
        raise InvalidCurveData(
            "the estimator gives no error model of its estimates (LocalGeometry.sensitivity "
            "is None); pass uncertainty= or tolerance= to recognize_points"
        )
    cov = geometry.sensitivity.covariance()
    scale_k, scale_ks = magnitude_scales(geometry.kappa, geometry.kappa_s)
    floor = ESTIMATE_PRECISION * np.concatenate([scale_k, scale_ks, np.ones(len(geometry))])
    return InputUncertainty.from_covariance(cov + np.diag(floor**2))


def _tail(statistic: float, dof: float, noise_dof: float) -> float:
    """P(X >= statistic) for X the sum of ``dof`` squared standard normals over the noise
    variance: chi-square with a known noise (``noise_dof`` infinite), else ``dof`` times
    F(dof, noise_dof), the noise estimated on ``noise_dof`` degrees of freedom."""
    if np.isinf(noise_dof):
        return float(chdtrc(dof, statistic))
    return float(fdtrc(dof, noise_dof, statistic / dof))


def smooth_statistic(
    points: np.ndarray, residuals: np.ndarray, modes: int, fitted: np.ndarray | None = None
) -> tuple[float, int]:
    """Squared length of the signed ``residuals`` (n,) of a fit to ordered ``points``
    (n, 2) projected on the ``modes`` lowest-degree polynomials of arc length along the
    points (orthonormal over the points; Neyman's smooth test), and its degrees of freedom.

    ``fitted`` (n, r), an orthonormal basis of the changes of the residuals that the fit's
    unknowns make, is first taken out of those modes: the fit absorbs the noise there (a
    rigid motion and a shape parameter change a curve's distances smoothly), so that the
    remaining modes hold noise alone (chi-square with as many degrees of freedom as they
    span) and a curve of another shape leaves its misfit, smooth along the curve, in them.
    """
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    x = 2.0 * s / max(s[-1], 1e-300) - 1.0
    basis, _ = np.linalg.qr(np.polynomial.legendre.legvander(x, modes - 1))
    if fitted is not None and fitted.size:
        basis = orth(basis - fitted @ (fitted.T @ basis), rcond=SMOOTH_RANK_TOLERANCE)
    return float(np.sum((basis.T @ residuals) ** 2)), basis.shape[1]


def _point_class_fit(
    fit: PointFit | None,
    kind: CurveKind,
    used: LocalGeometry,
    points: np.ndarray,
    noise: float,
    noise_dof: float,
) -> ClassFit:
    """A class fitted to the points as a :class:`ClassFit`: its statistic is the sum of
    squared distances over the noise variance, tested by chi-square (the noise known,
    ``noise_dof`` infinite) or F (the noise estimated on ``noise_dof`` degrees of
    freedom); so is the part of it in the residuals' ``SMOOTH_MODES`` smoothest modes
    along the curve beyond the fit's own changes, on as many degrees of freedom as those
    span (:func:`smooth_statistic`), where a wrong class leaves its misfit.
    The p-value is the smaller of the two tests' doubled (Bonferroni): a class is refused
    when either refuses it at half the significance."""
    if fit is None:
        return rejected(kind, "no least-squares fit to the points converged")
    dof = fit.distances.size - fit.n_unknowns
    statistic = fit.sum_of_squares / noise**2
    if dof <= 0:
        p_value = float("nan")
    else:
        smooth, modes = smooth_statistic(points, fit.distances, SMOOTH_MODES, fit.fitted)
        p_smooth = _tail(smooth / noise**2, modes, noise_dof) if modes else 1.0
        p_value = min(1.0, 2.0 * min(_tail(statistic, dof, noise_dof), p_smooth))
    u = fit.u[used.index]
    theta = fit.reduction.theta
    orientation = 1 if np.median(np.diff(fit.u)) >= 0 else -1
    params, t, orientation_f, psi = canonical_form(
        kind, fit.reduction.params, u, float(orientation), -theta
    )
    return ClassFit(
        kind,
        params,
        float(np.sqrt(statistic / dof)) if dof > 0 else float("inf"),
        t,
        psi,
        int(orientation_f),
        per_point=np.abs(fit.distances),
        statistic=float(statistic),
        dof=float(dof),
        p_value=p_value,
    )


def _recognize_by_points(
    points: np.ndarray, used: LocalGeometry, noise: float, noise_dof: float, significance: float
) -> CurveRecognition:
    """Every class fitted to the points themselves (:mod:`.point_fit`), decided as the
    tree decides (:func:`_choose_by_test`)."""
    fitted = fit_classes(points)
    fits = [
        _point_class_fit(fitted[kind], kind, used, points, noise, noise_dof)
        for kind in TREE_CLASSES
    ]
    chosen = _choose_by_test(fits, significance, _fitted_better)
    return _decision(chosen, fits, significance, decided_by="points", noise=noise)


def _estimated_noise(geometry: LocalGeometry) -> tuple[float, float]:
    """The points' noise (standard deviation per coordinate) from the estimator's error
    model, and the degrees of freedom of that estimate."""
    if geometry.sensitivity is None:
        raise InvalidCurveData(
            "the estimator gives no error model (LocalGeometry.sensitivity is None): pass "
            "noise= (the points' standard deviation per coordinate) to recognize_points"
        )
    variance = geometry.sensitivity.point_variance
    return float(np.sqrt(np.mean(variance))), float(geometry.sensitivity.variance_dof)


def recognize_points(
    points: ArrayLike,
    *,
    n_estimates: int = 25,
    uncertainty: InputUncertainty | None = None,
    significance: float = DEFAULT_SIGNIFICANCE,
    tolerance: float | None = None,
    decide_by: str | None = None,
    noise: float | None = None,
    estimator: Callable[..., LocalGeometry] = local_fit_geometry,
    **estimator_options: Any,
) -> tuple[CurveRecognition, LocalGeometry]:
    """Recognise the class of a sampled curve from ordered tactile points.

    Two decisions (``decide_by``):

    - ``"points"`` (the default unless ``uncertainty`` or ``tolerance`` is given): every
      class of the tree is fitted to the points themselves by orthogonal distance
      regression (:mod:`.point_fit`) and tested by its sum of squared distances over the
      points' noise: an F test with the noise estimated by the estimator's error model
      (its local check fits' residuals), a chi-square test when ``noise`` is given. The
      class is chosen among the consistent ones as the tree chooses (the simplest unless
      a more complex one fits significantly better). Contact parameters are those of the
      points the estimates belong to.
    - ``"invariants"``: the thesis's tree (Fig. 3.4) on ``n_estimates`` evenly spaced
      local estimates, :func:`recognize_curve` with their tangent rotations and the
      uncertainty the estimator's own error model gives them
      (:func:`estimated_uncertainty`), unless ``uncertainty`` or ``tolerance`` is given.

    Parameters
    ----------
    points : (n, 2) float
        Ordered tactile points along the curve (any length unit).
    n_estimates : int
        Estimates used, at least 3.
    uncertainty, significance, tolerance
        See :func:`recognize_curve` (``significance`` serves both decisions).
    decide_by : {"points", "invariants"}, optional
    noise : float, optional
        ``"points"``: the points' known noise (standard deviation per coordinate, the
        points' unit) instead of the estimate.
    estimator : callable
        ``estimator(points, **estimator_options) -> LocalGeometry``.

    Returns
    -------
    CurveRecognition
    LocalGeometry
        The estimates used.
    """
    if isinstance(n_estimates, bool) or not isinstance(n_estimates, numbers.Integral):
        raise InvalidCurveData(f"n_estimates must be an integer >= 3, got {n_estimates!r}")
    if n_estimates < 3:
        raise InvalidCurveData(f"n_estimates must be at least 3, got {n_estimates}")
    if decide_by is None:
        decide_by = "points" if uncertainty is None and tolerance is None else "invariants"
    if decide_by not in ("points", "invariants"):
        raise InvalidCurveData(f"decide_by must be 'points' or 'invariants', got {decide_by!r}")
    if decide_by == "points" and (uncertainty is not None or tolerance is not None):
        raise InvalidCurveData(
            "uncertainty= and tolerance= concern the invariants: give decide_by='invariants'"
        )
    if noise is not None and not (
        isinstance(noise, numbers.Real) and np.isfinite(noise) and noise > 0
    ):
        raise InvalidCurveData(f"noise must be a positive number, got {noise!r}")
    _check_significance(significance)
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
    if decide_by == "points":
        if noise is None:
            sigma, noise_dof = _estimated_noise(geometry)
        else:
            sigma, noise_dof = float(noise), float("inf")
        p = np.asarray(points, dtype=float)
        return _recognize_by_points(p, used, sigma, noise_dof, significance), used
    if uncertainty is None and tolerance is None:
        uncertainty = estimated_uncertainty(used)
    result = recognize_curve(
        used.kappa,
        used.kappa_s,
        used.dphi,
        uncertainty=uncertainty,
        significance=significance,
        tolerance=tolerance,
    )
    return result, used
