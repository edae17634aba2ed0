"""The thesis's printed Chapter 3 values, the shapes behind them and their true invariants."""

from __future__ import annotations

import numpy as np

from recognition.curves.families import CurveKind

__all__ = [
    "CLASSES",
    "TABLE_3_1_SHAPES",
    "TABLE_3_1_THESIS",
    "TABLE_3_2_SPLINE",
    "TABLE_3_2_THESIS",
    "TABLE_3_3_THESIS",
    "TABLE_3_4_THESIS",
    "TABLE_3_5_THESIS",
    "true_invariants",
]


#: The six classes of the tree, in the column order of Table 3.3.
CLASSES = (
    CurveKind.ELLIPSE,
    CurveKind.HYPERBOLA,
    CurveKind.PARABOLA,
    CurveKind.CUBICAL_PARABOLA,
    CurveKind.SEMICUBICAL_PARABOLA,
    CurveKind.CUBIC_SPLINE,
)


#: Shapes matching Table 3.1's "real" row (THESIS_ERRATA item 8) and parameter intervals.
TABLE_3_1_SHAPES: dict[CurveKind, tuple[tuple[float, ...], tuple[float, float]]] = {
    CurveKind.PARABOLA: ((4.852,), (-1.5, 1.5)),
    CurveKind.ELLIPSE: ((5.450, 2.293), (0.0, 2 * np.pi)),
    CurveKind.HYPERBOLA: ((3.131, 2.305), (-1.5, 1.5)),
    CurveKind.CUBICAL_PARABOLA: ((6.9963, 2.6127), (-0.5, 0.5)),
    CurveKind.SEMICUBICAL_PARABOLA: ((1.3730, 6.5107), (0.2, 1.5)),
}
#: Table 3.1 as printed: min, max and mean of each invariant over 100 points (pairs).
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


def true_invariants() -> dict[str, float]:
    """The true values of Table 3.1's invariants on :data:`TABLE_3_1_SHAPES`, thesis
    Eqs. (3.9), (3.19)-(3.20), (3.24), (3.27)-(3.28) and (3.32)-(3.33)."""
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


#: The cubic spline segment of Tables 3.2 and 3.5 (Fig. 3.8) and its parameter interval.
TABLE_3_2_SPLINE: tuple[tuple[float, float, float], tuple[float, float]] = (
    (1.10734, 1.67996, -0.401898),
    (0.3, 1.5),
)
#: Table 3.2 as printed: each invariant's summary over 100 values on the other classes.

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

#: Table 3.3 as printed: relative errors (%) of the recovered shapes, per class.
TABLE_3_3_THESIS: dict[str, dict[str, float]] = {
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

#: Table 3.4 as printed: I_c1, I_c2, a, b of the joystick ellipse (cm).
TABLE_3_4_THESIS = {
    "real": {"I_c1": 0.373836, "I_c2": 1.30145, "a": 2.5, "b": 1.75},
    "min": {"I_c1": 0.350559, "I_c2": 1.26074, "a": 2.38636, "b": 1.62636},
    "max": {"I_c1": 0.404903, "I_c2": 1.36736, "a": 2.67234, "b": 1.83549},
    "mean": {"I_c1": 0.377728, "I_c2": 1.31825, "a": 2.51127, "b": 1.71959},
}

#: Table 3.5 as printed: the spline segment's shape from two groups of three estimates.
TABLE_3_5_THESIS = {
    "real": {"a": 1.10734, "b": 1.67996, "c": -0.401898},
    "test 1": {"a": 1.07246, "b": 1.57648, "c": -0.39233},
    "test 2": {"a": 1.06594, "b": 1.55496, "c": -0.44884},
}
