"""Tables 3.4 and 3.5: an ellipse and a cubic spline segment recovered from tactile points."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from recognition.curves import invariants as inv
from recognition.curves.estimation import LocalGeometry
from recognition.curves.families import CanonicalCurve, CurveKind
from recognition.curves.recognition import fit_class
from recognition.curves.reduction import reduce_cubic_spline
from recognition.errors import InvalidCurveData, RecognitionError
from recognition.reproduction.chapter3.experiments import (
    DEFAULT_JOYSTICK_EXPERIMENT,
    SPLINE_SEGMENT_EXPERIMENT,
    CurveExperiment,
    JoystickExperiment,
    ellipse_arc_estimates,
    experiment_rng,
    joystick_ellipse_estimates,
    random_pairs,
    sample_placed_curve,
)
from recognition.reproduction.chapter3.measures import relative_parameter_error, summary
from recognition.reproduction.chapter3.reference import (
    TABLE_3_2_SPLINE,
    TABLE_3_4_THESIS,
    TABLE_3_5_THESIS,
)
from recognition.reproduction.tables import TableResult, markdown_table

__all__ = [
    "table_3_4",
    "table_3_4_from_points",
    "table_3_5",
    "table_3_5_from_points",
]


def table_3_4(experiment: JoystickExperiment = DEFAULT_JOYSTICK_EXPERIMENT) -> TableResult:
    """Table 3.4: I_c1, I_c2, a, b of an ellipse from noisy joystick-like samples, thesis
    Eqs. (3.19)-(3.20).

    The thesis's summary is over pairs of estimates of one experiment; that is measured
    on trial 0. The recognition tree's estimate (one least-squares fit over all the
    estimates) is averaged over ``trials`` independent experiments.
    """
    estimates = [joystick_ellipse_estimates(experiment, t) for t in range(experiment.trials)]
    description = (
        f"joystick-like samples: {experiment.n_arcs} arcs of {experiment.arc_length} cm, "
        f"points every {experiment.spacing} cm with noise sigma {experiment.noise_std} cm"
    )
    return _table_3_4(estimates, experiment, description, asdict(experiment))


def table_3_4_from_points(
    trial_arcs_m: Sequence[Sequence[np.ndarray]],
    experiment: JoystickExperiment = DEFAULT_JOYSTICK_EXPERIMENT,
    *,
    description: str = "",
) -> TableResult:
    """Table 3.4 from measured tactile points (e.g. the simulated probe's).

    Parameters
    ----------
    trial_arcs_m : sequence of sequence of (n, 2) float, metres
        Per independent experiment (trial), the ordered points of each traced arc of the
        ellipse with a = ``experiment.a``, b = ``experiment.b`` (cm), in any frame.
    experiment : JoystickExperiment
        The estimator's settings and the true a, b; its sampling fields are not used.
    description : str
        How the points were measured (for the Markdown).

    Returns
    -------
    TableResult
        As :func:`table_3_4`: pairwise invariants (3.19)-(3.20) of trial 0, and the
        recognition tree's (a, b) over all trials; ``measured["source"]`` is "points".
    """
    if len(trial_arcs_m) == 0:
        raise InvalidCurveData("table_3_4_from_points needs at least one trial of arcs")
    estimates = [
        ellipse_arc_estimates([100.0 * np.asarray(arc) for arc in arcs], experiment)
        for arcs in trial_arcs_m
    ]
    settings = asdict(experiment)
    settings["trials"] = len(estimates)
    for name in ("spacing", "noise_std", "arc_length", "n_arcs"):
        settings.pop(name)
    settings["arcs_per_trial"] = [len(arcs) for arcs in trial_arcs_m]
    settings["points_per_arc"] = [[len(arc) for arc in arcs] for arcs in trial_arcs_m]
    result = _table_3_4(estimates, experiment, description or "measured tactile points", settings)
    result.measured["source"] = "points"
    return result


def _table_3_4(
    estimates: list[LocalGeometry],
    experiment: JoystickExperiment,
    description: str,
    settings: dict[str, Any],
) -> TableResult:
    """Table 3.4 from the estimates of each trial: pairwise invariants (3.19)-(3.20) and
    (a, b) of trial 0, the recognition tree's ellipse over all trials."""
    g = estimates[0]
    rng = experiment_rng(experiment.seed, 341)
    i, j = random_pairs(rng, len(g), experiment.n_pairs, g.kappa).T
    args = (g.kappa[i], g.kappa_s[i], g.kappa[j], g.kappa_s[j])
    c1, c2 = inv.conic_invariant_1(*args), inv.conic_invariant_2(*args)
    semi_axes = []
    for x, y in zip(c1, c2, strict=True):
        try:
            semi_axes.append(inv.ellipse_parameters(x, y))
        except RecognitionError:
            semi_axes.append((np.nan, np.nan))
    ab = np.array(semi_axes)
    pairwise = {
        "I_c1": summary(c1),
        "I_c2": summary(c2),
        "a": summary(ab[:, 0]),
        "b": summary(ab[:, 1]),
    }
    per_trial = []
    for gt in estimates:
        fit = fit_class(CurveKind.ELLIPSE, gt.kappa, gt.kappa_s)
        i_c1, i_c2, _ = inv.conic_invariants_regression(gt.kappa, gt.kappa_s)
        per_trial.append((*fit.params, i_c1, i_c2))
    fits = np.array(per_trial)
    trials = len(estimates)
    tree = {
        "a_mean": float(fits[:, 0].mean()),
        "b_mean": float(fits[:, 1].mean()),
        "a_stdev": float(fits[:, 0].std()),
        "b_stdev": float(fits[:, 1].std()),
        "I_c1_mean": float(fits[:, 2].mean()),
        "I_c2_mean": float(fits[:, 3].mean()),
        "trials": trials,
    }
    rel = {
        "a": 100 * abs(tree["a_mean"] - experiment.a) / experiment.a,
        "b": 100 * abs(tree["b_mean"] - experiment.b) / experiment.b,
    }
    measured: dict[str, Any] = {
        "pairwise": pairwise,
        "tree": tree,
        "mean_relative_error_percent": rel,
    }
    header = ["", "I_c1", "I_c2", "a", "b"]
    rows = [["real", *TABLE_3_4_THESIS["real"].values()]]
    for stat in ("min", "max", "mean"):
        rows.append([f"thesis {stat}", *TABLE_3_4_THESIS[stat].values()])
        rows.append([f"pairs {stat}", *(pairwise[k][stat] for k in ("I_c1", "I_c2", "a", "b"))])
    rows.append(
        [
            f"tree, mean of {trials}",
            tree["I_c1_mean"],
            tree["I_c2_mean"],
            tree["a_mean"],
            tree["b_mean"],
        ]
    )
    rows.append(["tree, stdev", None, None, tree["a_stdev"], tree["b_stdev"]])
    text = (
        f"**Table 3.4** ellipse a = {experiment.a}, b = {experiment.b} (cm) from {description}; "
        f"fit over {experiment.window} points (degree {experiment.degree}), kappa_s over "
        f"{experiment.kappa_window} estimates; {experiment.estimates_per_arc} estimates per "
        f"arc. 'pairs' summarises {experiment.n_pairs} pairwise invariants (3.19)-(3.20) of "
        "one experiment, as the thesis does; 'tree' is the recognition tree's least-squares "
        f"shape over all estimates, averaged over {trials} experiments; a and b within "
        f"{rel['a']:.2f} % and {rel['b']:.2f} % of the true values.\n\n"
        + markdown_table(header, rows)
    )
    return TableResult("3.4", TABLE_3_4_THESIS, measured, settings, text)


#: Table 3.5's groups of the eight estimates: the thesis's two tests and all eight.
SPLINE_GROUPS = {"test 1": [0, 3, 7], "test 2": [1, 4, 6], "all eight": list(range(8))}


def _spline_fits(g: LocalGeometry, params: Sequence[float]) -> dict[str, dict[str, float]]:
    """The spline class (3.35) fitted to each group of :data:`SPLINE_GROUPS` of the eight
    estimates ``g``: its (a, b, c) and relative parameter error (%) against ``params``."""
    measured: dict[str, dict[str, float]] = {}
    for name, idx in SPLINE_GROUPS.items():
        fit = fit_class(CurveKind.CUBIC_SPLINE, g.kappa[idx], g.kappa_s[idx], g.dphi[idx])
        measured[name] = dict(zip("abc", fit.params, strict=True)) if fit.params else {}
        measured[name]["relative_error_percent"] = 100 * relative_parameter_error(
            params, fit.params
        )
    return measured


def table_3_5(experiment: CurveExperiment = SPLINE_SEGMENT_EXPERIMENT) -> TableResult:
    """Table 3.5: the cubic spline segment from three of eight estimates (and from all 8).

    The segment x = t^2, y = a t^3 + b t^2 + c t, t in [0.3, 1.5], is sampled with
    ``experiment``; estimates are taken at eight evenly spaced points. Its shape is
    carried by kappa_s, which is tiny along most of the segment: joystick-level noise
    leaves nothing to recover, so the default samples are noise-free. Three contacts do
    not always fix a spline (THESIS_ERRATA item 7).
    """
    params, (t0, t1) = TABLE_3_2_SPLINE
    curve = CanonicalCurve(CurveKind.CUBIC_SPLINE, params)
    rng = experiment_rng(experiment.seed, 35)
    g = experiment.estimate(sample_placed_curve(curve, t0, t1, experiment, rng).points)
    g = g.subset(np.linspace(0, len(g) - 1, 8).round().astype(int))
    measured = _spline_fits(g, params)
    header = ["", "a", "b", "c", "relative error %"]
    rows = [["real", *params, 0.0]]
    for name in ("test 1", "test 2"):
        t = TABLE_3_5_THESIS[name]
        rows.append(
            [
                f"thesis {name}",
                t["a"],
                t["b"],
                t["c"],
                100 * relative_parameter_error(params, list(t.values())),
            ]
        )
    for name, m in measured.items():
        rows.append([name, m.get("a"), m.get("b"), m.get("c"), m["relative_error_percent"]])
    text = (
        "**Table 3.5** cubic spline segment (t in [0.3, 1.5]) from three of eight estimates "
        f"(estimates {SPLINE_GROUPS['test 1']} and {SPLINE_GROUPS['test 2']}) and from all eight; "
        f"{experiment.describe()}.\n\n" + markdown_table(header, rows)
    )
    return TableResult("3.5", TABLE_3_5_THESIS, measured, asdict(experiment), text)


def table_3_5_from_points(
    segments: Sequence[tuple[ArrayLike, ArrayLike, ArrayLike]],
    experiment: CurveExperiment = SPLINE_SEGMENT_EXPERIMENT,
    *,
    description: str = "",
) -> TableResult:
    """Table 3.5 analogue from measured points of a closed cubic spline, segment by segment.

    For each traced segment, kappa, kappa_s and the tangent rotation are estimated along
    the whole trace (units: cm) and eight estimates evenly spaced over the points whose
    fit windows lie on the segment are kept (kappa_s jumps at the knots); the spline
    class (3.35) is fitted to estimates 0, 3, 7 ("test 1"), 1, 4, 6 ("test 2") and all
    eight, as in :func:`table_3_5`. The truth is
    the segment's polynomials (3.25) reduced to the form (3.35).

    Parameters
    ----------
    segments : sequence of (points_m, on_segment, coefficients_m)
        ``points_m`` (n, 2) float, metres: the ordered traced points (any frame);
        ``on_segment`` (n,) bool: which of them lie on the segment; ``coefficients_m``
        (2, 4) float, metres: ``x(t)`` and ``y(t)`` of the segment, powers 3..0, in the
        frame of ``points_m`` up to a rigid motion.
    experiment : CurveExperiment
        Estimator settings (``window``, ``degree``, ``kappa_window``).
    description : str
        How the points were measured (for the Markdown).
    """
    measured: dict[str, Any] = {}
    rows: list[list[Any]] = []
    for k, (points_m, on_segment, coefficients_m) in enumerate(segments):
        truth = reduce_cubic_spline(*(100.0 * np.asarray(coefficients_m)).reshape(-1))
        params = truth.curve.params
        g = experiment.estimate(100.0 * np.asarray(points_m, dtype=float))
        # estimates whose fit windows lie on the segment: kappa_s jumps at the knots
        half = experiment.window // 2 + (experiment.kappa_window or 1) // 2
        inside = np.convolve(np.asarray(on_segment, float), np.ones(2 * half + 1), "same")
        on = np.flatnonzero(inside[g.index] > 2 * half + 0.5)
        if on.size < 8:
            raise InvalidCurveData(f"segment {k}: {on.size} estimates on it, need 8")
        g = g.subset(on[np.linspace(0, on.size - 1, 8).round().astype(int)])
        fits = _spline_fits(g, params)
        entry = {"real": dict(zip("abc", params, strict=True)), **fits}
        rows.append([f"segment {k} real", *params, 0.0])
        for name, e in fits.items():
            rows.append(
                [
                    f"segment {k} {name}",
                    e.get("a"),
                    e.get("b"),
                    e.get("c"),
                    e["relative_error_percent"],
                ]
            )
        measured[f"segment {k}"] = entry
    text = (
        "**Table 3.5** analogue: segments of the closed cubic spline from three of eight "
        f"estimates (0, 3, 7 and 1, 4, 6) and from all eight, {description or 'measured points'}"
        f"; shape (3.35) in cm; local polynomial fit over {experiment.window} points, "
        f"degree {experiment.degree}"
        + (
            f", kappa_s from {experiment.kappa_window} kappa estimates"
            if experiment.kappa_window
            else ""
        )
        + ".\n\n"
        + markdown_table(["", "a", "b", "c", "relative error %"], rows)
    )
    settings = {k: v for k, v in asdict(experiment).items() if k not in ("spacing", "noise_std")}
    return TableResult("3.5", TABLE_3_5_THESIS, measured, settings, text)
