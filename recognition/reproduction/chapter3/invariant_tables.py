"""Tables 3.1 and 3.2: the invariants on their own class and on the others."""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from recognition.curves import invariants as inv
from recognition.curves.estimation import LocalGeometry
from recognition.curves.families import CurveKind
from recognition.errors import RecognitionError
from recognition.reproduction.chapter3.experiments import (
    DEFAULT_CURVE_EXPERIMENT,
    CurveExperiment,
    experiment_rng,
    random_pairs,
    shape_geometry,
)
from recognition.reproduction.chapter3.measures import summary
from recognition.reproduction.chapter3.reference import (
    TABLE_3_1_SHAPES,
    TABLE_3_1_THESIS,
    TABLE_3_2_THESIS,
    true_invariants,
)
from recognition.reproduction.tables import TableResult, markdown_table

__all__ = [
    "table_3_1",
    "table_3_2",
]


def _pick_slope(
    kind: CurveKind, geometry: LocalGeometry, i: int, j: int, sign: float = 1.0
) -> tuple[float, float, float] | None:
    """Slope at point i by the thesis's quartic at the pair (i, j), thesis
    Eqs. (3.29)-(3.34).

    Both real roots satisfy the I_*2 equation the quartic came from; the one at which the
    first invariant (the shape parameter a) agrees at i and j is returned, with the
    slopes at i and j and the relative disagreement of a. None if the quartic has no
    real root.
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


def _cubic_invariants(kind: CurveKind, geometry: LocalGeometry, pairs: np.ndarray) -> np.ndarray:
    """(I_1, I_2) at the first point of each pair (k, 2), slope from the pair's quartic,
    thesis Eqs. (3.27)-(3.28) or (3.32)-(3.33); (k, 2), NaN where no slope is real."""
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
        picks = [(s, p) for s in signs if (p := _pick_slope(kind, geometry, i, j, s)) is not None]
        if not picks:
            out.append((np.nan, np.nan))
            continue
        s, (lam, _, _) = min(picks, key=lambda sp: sp[1][2])
        k, ks = s * geometry.kappa[i], geometry.kappa_s[i]
        out.append((float(first(lam, k, ks)), float(second(lam, k, ks))))
    return np.array(out)


def table_3_1(
    experiment: CurveExperiment = DEFAULT_CURVE_EXPERIMENT, n_values: int = 100
) -> TableResult:
    """Table 3.1: each invariant evaluated ``n_values`` times at random points of its shape.

    The invariants are those of thesis Eqs. (3.10), (3.19)-(3.20), (3.27)-(3.28) and
    (3.32)-(3.33), the cubic ones with the slope from the quartic (3.31) (or its
    semi-cubical counterpart) at a random pair of points.
    """
    values: dict[str, np.ndarray] = {}
    for key, kind in enumerate(TABLE_3_1_SHAPES):
        g = shape_geometry(kind, experiment, key)
        rng = experiment_rng(experiment.seed, 311, key)
        if kind is CurveKind.PARABOLA:
            idx = rng.choice(len(g), size=n_values, replace=False)
            values["I_p"] = inv.parabola_invariant(g.kappa[idx], g.kappa_s[idx])
        elif kind in (CurveKind.ELLIPSE, CurveKind.HYPERBOLA):
            i, j = random_pairs(rng, len(g), n_values, g.kappa).T
            args = (g.kappa[i], g.kappa_s[i], g.kappa[j], g.kappa_s[j])
            values[f"I_c1 {kind.value}"] = inv.conic_invariant_1(*args)
            values[f"I_c2 {kind.value}"] = inv.conic_invariant_2(*args)
        else:
            pairs = random_pairs(rng, len(g), n_values)
            v = _cubic_invariants(kind, g, pairs)
            prefix = "I_cp" if kind is CurveKind.CUBICAL_PARABOLA else "I_scp"
            values[prefix + "1"], values[prefix + "2"] = v[:, 0], v[:, 1]
    true = true_invariants()
    measured: dict[str, dict[str, float]] = {}
    for name, v in values.items():
        s = summary(v)
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


def table_3_2(
    experiment: CurveExperiment = DEFAULT_CURVE_EXPERIMENT, n_values: int = 100
) -> TableResult:
    """Table 3.2: invariants of one class evaluated on data from the others (and its own).

    I_c1 (thesis Eq. (3.19)), I_cp2 (3.28) and I_scp2 (3.33) on Table 3.1's ellipse,
    cubical and semi-cubical parabolas and Table 3.2's spline segment.
    """
    data_kinds = (
        CurveKind.ELLIPSE,
        CurveKind.CUBICAL_PARABOLA,
        CurveKind.SEMICUBICAL_PARABOLA,
        CurveKind.CUBIC_SPLINE,
    )
    geometry = {kind: shape_geometry(kind, experiment, 20 + n) for n, kind in enumerate(data_kinds)}
    measured: dict[str, dict[str, dict[str, float]]] = {}
    for name in ("I_c1", "I_cp2", "I_scp2"):
        measured[name] = {}
        for key, kind in enumerate(data_kinds):
            g = geometry[kind]
            rng = experiment_rng(experiment.seed, 321, key)
            if name == "I_c1":
                i, j = random_pairs(rng, len(g), n_values, g.kappa).T
                v = inv.conic_invariant_1(g.kappa[i], g.kappa_s[i], g.kappa[j], g.kappa_s[j])
            else:
                hyp = (
                    CurveKind.CUBICAL_PARABOLA
                    if name == "I_cp2"
                    else CurveKind.SEMICUBICAL_PARABOLA
                )
                v = _cubic_invariants(hyp, g, random_pairs(rng, len(g), n_values))[:, 1]
            s = summary(v)
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
