"""Tables 3.1-3.5, the recognition-rate matrix and Figs. 3.1-3.3 and 3.7 of the thesis.

Every measurement starts from points sampled along a curve (ordered, at a fixed arc
length spacing, optionally noisy, placed by a random rigid motion); kappa, kappa_s and
phi are estimated from those points, never taken from the closed forms.
"""

from __future__ import annotations

import itertools
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from recognition.curves import invariants as inv
from recognition.curves.estimation import LocalGeometry, local_fit_geometry
from recognition.curves.families import CanonicalCurve, CurveKind
from recognition.curves.recognition import (
    canonical_parameters,
    fit_class,
    recognize_curve,
)
from recognition.curves.sampling import random_curve, sample_by_arc_length
from recognition.errors import InvalidCurveData, RecognitionError
from recognition.reproduction.tables import TableResult, markdown_table, save_figure
from recognition.rigid import random_planar_motion

__all__ = [
    "CLASSES",
    "CurveExperiment",
    "JoystickExperiment",
    "classify_random_curves",
    "ellipse_arc_estimates",
    "figures",
    "recognition_rates",
    "table_3_1",
    "table_3_2",
    "table_3_3",
    "table_3_4",
    "table_3_4_from_points",
    "table_3_5",
    "table_3_5_from_points",
]

CLASSES = (
    CurveKind.ELLIPSE,
    CurveKind.HYPERBOLA,
    CurveKind.PARABOLA,
    CurveKind.CUBICAL_PARABOLA,
    CurveKind.SEMICUBICAL_PARABOLA,
    CurveKind.CUBIC_SPLINE,
)


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
    tolerance : float
        Consistency tolerance of the recognition tree.
    seed : int
    """

    spacing: float = 0.01
    noise_std: float = 0.0
    window: int = 11
    degree: int = 6
    kappa_window: int | None = None
    n_estimates: int = 25
    tolerance: float = 1e-4
    seed: int = 0

    def estimate(self, points) -> LocalGeometry:
        return local_fit_geometry(
            points, window=self.window, degree=self.degree, kappa_window=self.kappa_window
        )

    def describe(self) -> str:
        return (
            f"points every {self.spacing:g} units of arc length, noise sigma "
            f"{self.noise_std:g}; local polynomial fit over {self.window} points, degree "
            f"{self.degree}"
            + (f", kappa_s from {self.kappa_window} kappa estimates" if self.kappa_window else "")
            + f"; tolerance {self.tolerance:g}"
        )


@dataclass(frozen=True)
class JoystickExperiment:
    """Noisy joystick-like samples of two arcs of an ellipse (Table 3.4, Fig. 3.7).

    Units are centimetres: the ellipse of Table 3.4 has a = 2.5, b = 1.75 (25 x 17.5 mm);
    0.05 spacing is 0.5 mm, 0.003 noise is 30 um, the sensed-point accuracy of the
    simulated probe.
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


def _rng(*key: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(list(key)))


def _sample(curve, t0, t1, experiment, rng):
    return sample_by_arc_length(
        curve,
        t0,
        t1,
        experiment.spacing,
        rng=rng,
        noise_std=experiment.noise_std,
        T_data_from_canonical=random_planar_motion(rng),
    )


def _summary(values) -> dict[str, float]:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return {"min": float("nan"), "max": float("nan"), "mean": float("nan"), "n": 0}
    return {
        "min": float(v.min()),
        "max": float(v.max()),
        "mean": float(v.mean()),
        "stdev": float(v.std()),
        "n": int(v.size),
    }


def _random_pairs(rng, n_points: int, n_pairs: int, kappa=None, min_rel_diff: float = 0.05):
    """Distinct random index pairs; with ``kappa``, |kappa|^(2/3) must differ by min_rel_diff."""
    pairs = np.array(list(itertools.combinations(range(n_points), 2)))
    pairs = pairs[rng.permutation(len(pairs))]
    if kappa is not None:
        u = inv.abs_two_thirds(kappa)
        diff = np.abs(u[pairs[:, 0]] - u[pairs[:, 1]]) / np.maximum(u[pairs[:, 0]], u[pairs[:, 1]])
        pairs = pairs[diff >= min_rel_diff]
    return pairs[:n_pairs]


def _pick_slope(kind, geometry: LocalGeometry, i: int, j: int, sign: float = 1.0):
    """Slope at point i by the thesis's quartic at the pair (i, j), Eqs. (3.29)-(3.34).

    Both real roots satisfy the I_*2 equation the quartic came from; the one at which the
    first invariant (the shape parameter a) agrees at i and j is returned, with the
    slopes at i and j. None if the quartic has no real root.
    """
    k, ks, phi = sign * geometry.kappa, geometry.kappa_s, geometry.phi
    if kind is CurveKind.CUBICAL_PARABOLA:
        quartic, first = inv.cubical_parabola_slope_quartic, inv.cubical_parabola_invariant_1
    else:
        quartic, first = (
            inv.semicubical_parabola_slope_quartic,
            inv.semicubical_parabola_invariant_1,
        )
    delta = phi[j] - phi[i]
    try:
        roots = inv.real_slopes(quartic(k[i], ks[i], k[j], ks[j], np.tan(delta)))
    except RecognitionError:
        return None
    lam_j = inv.propagate_slope(roots, delta)
    ai, aj = first(roots, k[i], ks[i]), first(lam_j, k[j], ks[j])
    best = int(np.argmin(np.abs(ai - aj) / np.maximum(np.abs(ai) + np.abs(aj), 1e-300)))
    return roots[best], lam_j[best], abs(ai[best] - aj[best]) / max(abs(ai[best]), 1e-300)


def _cubic_invariants(kind, geometry, pairs):
    """(I_1, I_2) at the first point of each pair, slope from the pair's quartic."""
    first, second = {
        CurveKind.CUBICAL_PARABOLA: (
            inv.cubical_parabola_invariant_1,
            inv.cubical_parabola_invariant_2,
        ),
        CurveKind.SEMICUBICAL_PARABOLA: (
            inv.semicubical_parabola_invariant_1,
            inv.semicubical_parabola_invariant_2,
        ),
    }[kind]
    signs = (1.0,) if kind is CurveKind.CUBICAL_PARABOLA else (1.0, -1.0)  # errata item 4
    out = []
    for i, j in pairs:
        picks = [(s, _pick_slope(kind, geometry, i, j, s)) for s in signs]
        picks = [(s, p) for s, p in picks if p is not None]
        if not picks:
            out.append((np.nan, np.nan))
            continue
        s, (lam, _, _) = min(picks, key=lambda sp: sp[1][2])
        k, ks = s * geometry.kappa[i], geometry.kappa_s[i]
        out.append((float(first(lam, k, ks)), float(second(lam, k, ks))))
    return np.array(out)


# --- Table 3.1 --------------------------------------------------------------------------

#: Shapes matching Table 3.1's "real" row (THESIS_ERRATA item 8) and parameter intervals.
TABLE_3_1_SHAPES = {
    CurveKind.PARABOLA: ((4.852,), (-1.5, 1.5)),
    CurveKind.ELLIPSE: ((5.450, 2.293), (0.0, 2 * np.pi)),
    CurveKind.HYPERBOLA: ((3.131, 2.305), (-1.5, 1.5)),
    CurveKind.CUBICAL_PARABOLA: ((6.9963, 2.6127), (-0.5, 0.5)),
    CurveKind.SEMICUBICAL_PARABOLA: ((1.3730, 6.5107), (0.2, 1.5)),
}
TABLE_3_1_THESIS = {
    "I_p": {"real": 0.2198, "min": 0.2168, "max": 0.2230, "mean": 0.2198},
    "I_c1 ellipse": {"real": 0.1857, "min": 0.1801, "max": 0.1863, "mean": 0.1852},
    "I_c1 hyperbola": {"real": -0.2678, "min": -0.2729, "max": -0.2655, "mean": -0.2675},
    "I_c2 ellipse": {"real": 1.2055, "min": 1.1749, "max": 1.2083, "mean": 1.2035},
    "I_c2 hyperbola": {"real": 0.3222, "min": 0.2937, "max": 0.3615, "mean": 0.3210},
    "I_cp1": {"real": 6.9963, "min": 6.7687, "max": 7.0289, "mean": 6.9355},
    "I_cp2": {"real": 2.6127, "min": 1.7312, "max": 3.1684, "mean": 2.5022},
    "I_scp1": {"real": 1.3730, "min": 1.4111, "max": 1.4447, "mean": 1.4220},
    "I_scp2": {"real": 6.5107, "min": 6.3945, "max": 6.5834, "mean": 6.5154},
}


def _true_invariants() -> dict[str, float]:
    (a,) = TABLE_3_1_SHAPES[CurveKind.PARABOLA][0]
    ea, eb = TABLE_3_1_SHAPES[CurveKind.ELLIPSE][0]
    ha, hb = TABLE_3_1_SHAPES[CurveKind.HYPERBOLA][0]
    return {
        "I_p": (2 * a) ** (-2 / 3),
        "I_c1 ellipse": (ea * eb) ** (-2 / 3),
        "I_c1 hyperbola": -((ha * hb) ** (-2 / 3)),
        "I_c2 ellipse": (ea**2 + eb**2) / (ea * eb) ** (4 / 3),
        "I_c2 hyperbola": (ha**2 - hb**2) / (ha * hb) ** (4 / 3),
        "I_cp1": TABLE_3_1_SHAPES[CurveKind.CUBICAL_PARABOLA][0][0],
        "I_cp2": TABLE_3_1_SHAPES[CurveKind.CUBICAL_PARABOLA][0][1],
        "I_scp1": TABLE_3_1_SHAPES[CurveKind.SEMICUBICAL_PARABOLA][0][0],
        "I_scp2": TABLE_3_1_SHAPES[CurveKind.SEMICUBICAL_PARABOLA][0][1],
    }


def _shape_geometry(kind, experiment: CurveExperiment, key: int) -> LocalGeometry:
    params, (t0, t1) = TABLE_3_1_SHAPES.get(kind) or TABLE_3_2_SPLINE
    rng = _rng(experiment.seed, 31, key)
    sampled = _sample(CanonicalCurve(kind, params), t0, t1, experiment, rng)
    return experiment.estimate(sampled.points)


def table_3_1(experiment: CurveExperiment = CurveExperiment(), n_values: int = 100) -> TableResult:
    """Table 3.1: each invariant evaluated ``n_values`` times at random points of its shape."""
    values: dict[str, np.ndarray] = {}
    for key, kind in enumerate(TABLE_3_1_SHAPES):
        g = _shape_geometry(kind, experiment, key)
        rng = _rng(experiment.seed, 311, key)
        if kind is CurveKind.PARABOLA:
            idx = rng.choice(len(g), size=n_values, replace=False)
            values["I_p"] = inv.parabola_invariant(g.kappa[idx], g.kappa_s[idx])
        elif kind in (CurveKind.ELLIPSE, CurveKind.HYPERBOLA):
            i, j = _random_pairs(rng, len(g), n_values, g.kappa).T
            args = (g.kappa[i], g.kappa_s[i], g.kappa[j], g.kappa_s[j])
            values[f"I_c1 {kind.value}"] = inv.conic_invariant_1(*args)
            values[f"I_c2 {kind.value}"] = inv.conic_invariant_2(*args)
        else:
            pairs = _random_pairs(rng, len(g), n_values)
            v = _cubic_invariants(kind, g, pairs)
            prefix = "I_cp" if kind is CurveKind.CUBICAL_PARABOLA else "I_scp"
            values[prefix + "1"], values[prefix + "2"] = v[:, 0], v[:, 1]
    true = _true_invariants()
    measured = {}
    for name, v in values.items():
        s = _summary(v)
        s["real"] = true[name]
        s["mean_relative_error_percent"] = 100 * abs(s["mean"] - true[name]) / abs(true[name])
        measured[name] = s
    header = [
        "invariant",
        "real",
        "thesis min",
        "thesis max",
        "thesis mean",
        "min",
        "max",
        "mean",
        "mean error %",
    ]
    rows = [
        [
            name,
            true[name],
            TABLE_3_1_THESIS[name]["min"],
            TABLE_3_1_THESIS[name]["max"],
            TABLE_3_1_THESIS[name]["mean"],
            m["min"],
            m["max"],
            m["mean"],
            m["mean_relative_error_percent"],
        ]
        for name, m in measured.items()
    ]
    text = (
        f"**Table 3.1** invariants at {n_values} random points (pairs) of one shape per "
        f"class; {experiment.describe()}.\n\n" + markdown_table(header, rows)
    )
    return TableResult("3.1", TABLE_3_1_THESIS, measured, asdict(experiment), text)


# --- Table 3.2 --------------------------------------------------------------------------

TABLE_3_2_SPLINE = ((1.10734, 1.67996, -0.401898), (0.3, 1.5))
TABLE_3_2_THESIS = {
    "I_c1": {
        "cubical_parabola": {"min": -6.38, "max": -0.04, "mean": -0.73, "stdev": 1.22},
        "semicubical_parabola": {"min": -22.84, "max": 28.37, "mean": 3.37, "stdev": 6.76},
        "cubic_spline": {"min": -45.24, "max": -4.94, "mean": -16.50, "stdev": 10.86},
    },
    "I_cp2": {
        "ellipse": {"min": -11.97, "max": 15.46, "mean": -0.04, "stdev": 2.53},
        "semicubical_parabola": {"min": 8.54, "max": 19.03, "mean": 13.76, "stdev": 3.07},
        "cubic_spline": {"min": 11.66, "max": 1721.04, "mean": 55.52, "stdev": 217.34},
    },
    "I_scp2": {
        "ellipse": {"min": -265.80, "max": 5.83, "mean": -3.22, "stdev": 26.75},
        "cubical_parabola": {"min": 7.80, "max": 65.22, "mean": 29.17, "stdev": 17.19},
        "cubic_spline": {"min": -150.68, "max": 1715.73, "mean": 38.97, "stdev": 182.24},
    },
}


def table_3_2(experiment: CurveExperiment = CurveExperiment(), n_values: int = 100) -> TableResult:
    """Table 3.2: invariants of one class evaluated on data from the others (and its own)."""
    data_kinds = (
        CurveKind.ELLIPSE,
        CurveKind.CUBICAL_PARABOLA,
        CurveKind.SEMICUBICAL_PARABOLA,
        CurveKind.CUBIC_SPLINE,
    )
    geometry = {
        kind: _shape_geometry(kind, experiment, 20 + n) for n, kind in enumerate(data_kinds)
    }
    measured: dict[str, dict] = {}
    for name in ("I_c1", "I_cp2", "I_scp2"):
        measured[name] = {}
        for key, kind in enumerate(data_kinds):
            g = geometry[kind]
            rng = _rng(experiment.seed, 321, key)
            if name == "I_c1":
                i, j = _random_pairs(rng, len(g), n_values, g.kappa).T
                v = inv.conic_invariant_1(g.kappa[i], g.kappa_s[i], g.kappa[j], g.kappa_s[j])
            else:
                hyp = (
                    CurveKind.CUBICAL_PARABOLA
                    if name == "I_cp2"
                    else CurveKind.SEMICUBICAL_PARABOLA
                )
                v = _cubic_invariants(hyp, g, _random_pairs(rng, len(g), n_values))[:, 1]
            s = _summary(v)
            s["relative_spread"] = s.get("stdev", np.nan) / max(abs(s["mean"]), 1e-300)
            measured[name][kind.value] = s
    header = [
        "invariant",
        "data",
        "thesis mean (stdev)",
        "min",
        "max",
        "mean",
        "stdev",
        "stdev/|mean|",
    ]
    rows = []
    for name, per in measured.items():
        for data_kind, s in per.items():
            t = TABLE_3_2_THESIS[name].get(data_kind)
            thesis = f"{t['mean']:g} ({t['stdev']:g})" if t else "own class"
            rows.append(
                [
                    name,
                    data_kind,
                    thesis,
                    s["min"],
                    s["max"],
                    s["mean"],
                    s.get("stdev"),
                    s["relative_spread"],
                ]
            )
    text = (
        "**Table 3.2** invariants evaluated on data of other classes (the own class for "
        f"contrast), {n_values} values each; {experiment.describe()}. An invariant holds "
        "only on its own class: there stdev/|mean| is small, elsewhere large.\n\n"
        + markdown_table(header, rows, digits=4)
    )
    return TableResult("3.2", TABLE_3_2_THESIS, measured, asdict(experiment), text)


# --- Table 3.3 and recognition rates ----------------------------------------------------

TABLE_3_3_THESIS = {
    "min_relative_error_percent": {
        "ellipse": 0.02,
        "hyperbola": 0.10,
        "parabola": 0.01,
        "cubical_parabola": 0.02,
        "semicubical_parabola": 0.04,
        "cubic_spline": 0.61,
    },
    "max_relative_error_percent": {
        "ellipse": 7.99,
        "hyperbola": 9.71,
        "parabola": 3.35,
        "cubical_parabola": 7.49,
        "semicubical_parabola": 8.09,
        "cubic_spline": 29.23,
    },
    "mean_relative_error_percent": {
        "ellipse": 0.40,
        "hyperbola": 1.15,
        "parabola": 0.36,
        "cubical_parabola": 0.83,
        "semicubical_parabola": 1.23,
        "cubic_spline": 11.27,
    },
    "curves": {
        "ellipse": 100,
        "hyperbola": 100,
        "parabola": 100,
        "cubical_parabola": 100,
        "semicubical_parabola": 100,
        "cubic_spline": 25,
    },
}


def relative_parameter_error(true, estimated) -> float:
    """sqrt(sum(((p - p_hat) / p)^2)), the error measure of Table 3.3."""
    true, estimated = np.asarray(true, float), np.asarray(estimated, float)
    if estimated.shape != true.shape:
        return float("inf")
    return float(np.sqrt(np.sum(((true - estimated) / true) ** 2)))


def _classify_one(job) -> dict:
    kind, index, experiment = job
    rng = _rng(experiment.seed, 33, list(CurveKind).index(kind), index)
    curve, t0, t1 = random_curve(kind, rng)
    sampled = _sample(curve, t0, t1, experiment, rng)
    g = experiment.estimate(sampled.points)
    pick = np.unique(np.linspace(0, len(g) - 1, min(experiment.n_estimates, len(g))).round())
    g = g.subset(pick.astype(int))
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
    experiment: CurveExperiment = CurveExperiment(),
    n_curves: int = 100,
    kinds=(*CLASSES, CurveKind.QUARTIC),
    workers: int | None = None,
) -> list[dict]:
    """Sample ``n_curves`` random curves per class, estimate and run the recognition tree.

    Each record holds the true class and shape, the recognised class, and the shape
    recovered by the fit of the true class (for Table 3.3). Curves are seeded by
    (seed, class, index): the same settings give the same records in any process count.
    """
    jobs = [(CurveKind(k), i, experiment) for k in kinds for i in range(n_curves)]
    workers = workers or os.cpu_count() or 1
    if workers == 1:
        return [_classify_one(job) for job in jobs]
    with ProcessPoolExecutor(workers) as pool:
        return list(pool.map(_classify_one, jobs, chunksize=4))


def table_3_3(records: list[dict], experiment: CurveExperiment) -> TableResult:
    """Table 3.3: relative error of the recovered shape parameters, per class."""
    measured: dict[str, dict] = {
        "min_relative_error_percent": {},
        "max_relative_error_percent": {},
        "mean_relative_error_percent": {},
        "curves": {},
    }
    for kind in CLASSES:
        errors = [100 * r["own_class_error"] for r in records if r["kind"] == kind.value]
        s = _summary(errors)
        measured["min_relative_error_percent"][kind.value] = s["min"]
        measured["max_relative_error_percent"][kind.value] = s["max"]
        measured["mean_relative_error_percent"][kind.value] = s["mean"]
        measured["curves"][kind.value] = len(errors)
    header = ["", *[k.value for k in CLASSES]]
    rows = []
    for stat in ("min", "max", "mean"):
        key = f"{stat}_relative_error_percent"
        rows.append([f"thesis {stat} %", *[TABLE_3_3_THESIS[key][k.value] for k in CLASSES]])
        rows.append([f"{stat} %", *[measured[key][k.value] for k in CLASSES]])
    rows.append(["curves", *[measured["curves"][k.value] for k in CLASSES]])
    text = (
        "**Table 3.3** relative error sqrt(sum(((p - p_hat)/p)^2)) of the recovered shape "
        f"parameters over random curves of each class; {experiment.describe()}.\n\n"
        + markdown_table(header, rows, digits=3)
    )
    return TableResult("3.3", TABLE_3_3_THESIS, measured, asdict(experiment), text)


def recognition_rates(records: list[dict], experiment: CurveExperiment) -> TableResult:
    """Confusion matrix of the recognition tree over random curves of every class."""
    labels = [*(k.value for k in CLASSES), CurveKind.UNCLASSIFIED.value]
    truths = list(dict.fromkeys(r["kind"] for r in records))
    matrix = {t: dict.fromkeys(labels, 0) for t in truths}
    for r in records:
        matrix[r["kind"]][r["recognized"]] += 1
    rate = {}
    for t in truths:
        expected = t if t in labels else CurveKind.UNCLASSIFIED.value
        rate[t] = matrix[t][expected] / max(sum(matrix[t].values()), 1)
    header = ["true \\ recognised", *labels, "correct %"]
    rows = [[t, *matrix[t].values(), 100 * rate[t]] for t in truths]
    text = (
        "**Recognition rates** of the tree (Fig. 3.4) from sampled points; a quartic "
        f"belongs to no class and should be unclassified; {experiment.describe()}.\n\n"
        + markdown_table(header, rows, digits=4)
    )
    measured = {"confusion": matrix, "correct_rate": rate}
    return TableResult("recognition", {}, measured, asdict(experiment), text)


# --- Table 3.4 --------------------------------------------------------------------------

TABLE_3_4_THESIS = {
    "real": {"I_c1": 0.373836, "I_c2": 1.30145, "a": 2.5, "b": 1.75},
    "min": {"I_c1": 0.350559, "I_c2": 1.26074, "a": 2.38636, "b": 1.62636},
    "max": {"I_c1": 0.404903, "I_c2": 1.36736, "a": 2.67234, "b": 1.83549},
    "mean": {"I_c1": 0.377728, "I_c2": 1.31825, "a": 2.51127, "b": 1.71959},
}


def ellipse_arc_estimates(arcs, experiment: JoystickExperiment) -> LocalGeometry:
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
    rng = _rng(experiment.seed, 34, trial)
    curve = CanonicalCurve(CurveKind.ELLIPSE, (experiment.a, experiment.b))
    arcs = []
    for _ in range(experiment.n_arcs):
        t0 = rng.uniform(0.0, 2 * np.pi)
        # parameter span of the requested arc length, from the local speed
        span = experiment.arc_length / float(curve.speed(t0 + np.linspace(0, 1, 5)).mean())
        arcs.append(_sample(curve, t0, t0 + span, experiment, rng).points)
    return ellipse_arc_estimates(arcs, experiment)


def table_3_4(experiment: JoystickExperiment = JoystickExperiment()) -> TableResult:
    """Table 3.4: I_c1, I_c2, a, b of an ellipse from noisy joystick-like samples.

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
    trial_arcs_m, experiment: JoystickExperiment = JoystickExperiment(), *, description: str = ""
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
    estimates: list[LocalGeometry], experiment: JoystickExperiment, description: str, settings
) -> TableResult:
    g = estimates[0]
    rng = _rng(experiment.seed, 341)
    i, j = _random_pairs(rng, len(g), experiment.n_pairs, g.kappa).T
    args = (g.kappa[i], g.kappa_s[i], g.kappa[j], g.kappa_s[j])
    c1, c2 = inv.conic_invariant_1(*args), inv.conic_invariant_2(*args)
    ab = []
    for x, y in zip(c1, c2, strict=True):
        try:
            ab.append(inv.ellipse_parameters(x, y))
        except RecognitionError:
            ab.append((np.nan, np.nan))
    ab = np.array(ab)
    pairwise = {
        "I_c1": _summary(c1),
        "I_c2": _summary(c2),
        "a": _summary(ab[:, 0]),
        "b": _summary(ab[:, 1]),
    }
    fits = []
    for gt in estimates:
        fit = fit_class(CurveKind.ELLIPSE, gt.kappa, gt.kappa_s)
        i_c1, i_c2, _ = inv.conic_invariants_regression(gt.kappa, gt.kappa_s)
        fits.append((*fit.params, i_c1, i_c2))
    fits = np.array(fits)
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
    measured = {"pairwise": pairwise, "tree": tree, "mean_relative_error_percent": rel}
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


# --- Table 3.5 --------------------------------------------------------------------------

TABLE_3_5_THESIS = {
    "real": {"a": 1.10734, "b": 1.67996, "c": -0.401898},
    "test 1": {"a": 1.07246, "b": 1.57648, "c": -0.39233},
    "test 2": {"a": 1.06594, "b": 1.55496, "c": -0.44884},
}


def table_3_5(experiment: CurveExperiment = CurveExperiment(spacing=0.005)) -> TableResult:
    """Table 3.5: the cubic spline segment from three of eight estimates (and from all 8).

    The segment x = t^2, y = a t^3 + b t^2 + c t, t in [0.3, 1.5], is sampled with
    ``experiment``; estimates are taken at eight evenly spaced points. Its shape is
    carried by kappa_s, which is tiny along most of the segment: joystick-level noise
    leaves nothing to recover, so the default samples are noise-free. Three contacts do
    not always fix a spline (THESIS_ERRATA item 7).
    """
    params, (t0, t1) = TABLE_3_2_SPLINE
    curve = CanonicalCurve(CurveKind.CUBIC_SPLINE, params)
    rng = _rng(experiment.seed, 35)
    g = experiment.estimate(_sample(curve, t0, t1, experiment, rng).points)
    g = g.subset(np.linspace(0, len(g) - 1, 8).round().astype(int))
    groups = {"test 1": [0, 3, 7], "test 2": [1, 4, 6], "all eight": list(range(8))}
    measured = {}
    for name, idx in groups.items():
        fit = fit_class(CurveKind.CUBIC_SPLINE, g.kappa[idx], g.kappa_s[idx], g.dphi[idx])
        measured[name] = dict(zip("abc", fit.params, strict=True)) if fit.params else {}
        measured[name]["relative_error_percent"] = 100 * relative_parameter_error(
            params, fit.params
        )
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
        f"(estimates {groups['test 1']} and {groups['test 2']}) and from all eight; "
        f"{experiment.describe()}.\n\n" + markdown_table(header, rows)
    )
    return TableResult("3.5", TABLE_3_5_THESIS, measured, asdict(experiment), text)


def table_3_5_from_points(
    segments, experiment: CurveExperiment = CurveExperiment(spacing=0.005), *, description=""
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
    from recognition.curves.reduction import reduce_cubic_spline

    groups = {"test 1": [0, 3, 7], "test 2": [1, 4, 6], "all eight": list(range(8))}
    measured: dict = {}
    rows = []
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
        entry = {"real": dict(zip("abc", params, strict=True))}
        rows.append([f"segment {k} real", *params, 0.0])
        for name, idx in groups.items():
            fit = fit_class(CurveKind.CUBIC_SPLINE, g.kappa[idx], g.kappa_s[idx], g.dphi[idx])
            entry[name] = dict(zip("abc", fit.params, strict=True)) if fit.params else {}
            entry[name]["relative_error_percent"] = 100 * relative_parameter_error(
                params, fit.params
            )
            e = entry[name]
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


# --- figures ----------------------------------------------------------------------------


def _signature(curve: CanonicalCurve, t):
    return curve.kappa(t), curve.kappa_s(t)


def figures(out_dir: Path, joystick: JoystickExperiment = JoystickExperiment()) -> list[Path]:
    """Figs. 3.1-3.3 (curves and signature curves) and 3.7 (estimates vs signature)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []

    # Fig. 3.1: y = 0.6 x^3 + 0.4 x and its signature curve
    curve = CanonicalCurve(CurveKind.CUBICAL_PARABOLA, (0.6, 0.4))
    t = np.linspace(-1.5, 1.5, 600)
    fig, ax = plt.subplots(1, 2, figsize=(9, 4))
    p = curve.points(t)
    ax[0].plot(p[:, 0], p[:, 1])
    ax[0].set(title="(a) y = 0.6 x^3 + 0.4 x", xlabel="x", ylabel="y", aspect="equal")
    ax[1].plot(*_signature(curve, t))
    ax[1].set(title="(b) signature curve", xlabel="kappa", ylabel="kappa_s")
    paths.append(save_figure(fig, out_dir / "fig3_1_cubical_parabola_signature.png"))

    # Fig. 3.2: three parabolas, signatures, I_p along each
    fig, ax = plt.subplots(1, 3, figsize=(13, 4))
    t = np.linspace(-2.0, 2.0, 400)
    for a in (0.5, 1.0, 2.0):
        c = CanonicalCurve(CurveKind.PARABOLA, (a,))
        p = c.points(t)
        k, ks = _signature(c, t)
        ax[0].plot(p[:, 0], p[:, 1], label=f"a = {a}")
        ax[1].plot(k, ks)
        ax[2].plot(
            t, inv.parabola_invariant(k, ks), label=f"(2a)^(-2/3) = {(2 * a) ** (-2 / 3):.3f}"
        )
    ax[0].set(title="(a) y^2 = 4 a x", xlabel="x", ylabel="y")
    ax[0].legend()
    ax[1].set(title="(b) signature curves", xlabel="kappa", ylabel="kappa_s")
    ax[2].set(title="(c) I_p along each curve", xlabel="t", ylabel="I_p")
    ax[2].legend()
    paths.append(save_figure(fig, out_dir / "fig3_2_parabolas.png"))

    # Fig. 3.3: two ellipses and a circle, signatures, (I_c1, I_c2)
    fig, ax = plt.subplots(1, 3, figsize=(13, 4))
    t = np.linspace(0, 2 * np.pi, 500)
    for a, b in ((2.0, 1.0), (1.6, 1.25), (1.1, 1.1)):
        c = CanonicalCurve(CurveKind.ELLIPSE, (a, b))
        p = c.points(t)
        k, ks = _signature(c, t)
        ax[0].plot(p[:, 0], p[:, 1], label=f"a = {a}, b = {b}")
        ax[1].plot(k, ks, "o" if a == b else "-", ms=4)
        ic1, ic2 = (a * b) ** (-2 / 3), (a * a + b * b) / (a * b) ** (4 / 3)
        if a != b:  # evaluated at random pairs: one point in the (I_c1, I_c2) plane
            i, j = np.random.default_rng(0).integers(0, t.size, (2, 30))
            keep = np.abs(np.abs(k[i]) - np.abs(k[j])) > 1e-3
            i, j = i[keep], j[keep]
            args = (k[i], ks[i], k[j], ks[j])
            ax[2].plot(inv.conic_invariant_1(*args), inv.conic_invariant_2(*args), "x")
        else:
            ax[2].plot([ic1], [ic2], "o")
    ax[0].set(title="(a) ellipses x^2/a^2 + y^2/b^2 = 1", aspect="equal")
    ax[0].legend(fontsize=8)
    ax[1].set(title="(b) signature curves", xlabel="kappa", ylabel="kappa_s")
    ax[2].set(title="(c) (I_c1, I_c2) from pairs of points", xlabel="I_c1", ylabel="I_c2")
    paths.append(save_figure(fig, out_dir / "fig3_3_ellipses.png"))

    # Fig. 3.7: estimates from joystick-like samples against the signature curve
    g = joystick_ellipse_estimates(joystick, 0)
    c = CanonicalCurve(CurveKind.ELLIPSE, (joystick.a, joystick.b))
    k, ks = _signature(c, t)
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    p = c.points(t)
    ax[0].plot(p[:, 0], p[:, 1])
    ax[0].set(title=f"(a) ellipse a = {joystick.a}, b = {joystick.b}", aspect="equal")
    ax[1].plot(k, ks, label="signature curve")
    ax[1].plot(g.kappa, g.kappa_s, "o", ms=4, label="estimates from noisy samples")
    ax[1].set(title="(b) estimates vs signature", xlabel="kappa", ylabel="kappa_s")
    ax[1].legend()
    paths.append(save_figure(fig, out_dir / "fig3_7_estimates_vs_signature.png"))
    return paths


def default_experiment(**overrides) -> CurveExperiment:
    """The documented default settings, with ``overrides`` applied."""
    return replace(CurveExperiment(), **overrides)
