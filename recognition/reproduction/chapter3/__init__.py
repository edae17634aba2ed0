"""Tables 3.1-3.5, the recognition-rate matrix and Figs. 3.1-3.3 and 3.7 of the thesis.

Every measurement starts from points sampled along a curve (ordered, at a fixed arc
length spacing, optionally noisy, placed by a random rigid motion); kappa, kappa_s and
phi are estimated from those points, never taken from the closed forms.

The parts: :mod:`.reference` (the thesis's printed values and true invariants),
:mod:`.experiments` (settings, sampling and estimation, the random-curve records),
:mod:`.measures`, the table builders :mod:`.invariant_tables` (3.1, 3.2),
:mod:`.random_curve_tables` (3.3, recognition rates) and :mod:`.shape_tables` (3.4, 3.5),
and :mod:`.signature_figures` (matplotlib, imported only when a figure is drawn).
"""

from recognition.reproduction.chapter3.experiments import (
    CurveExperiment,
    JoystickExperiment,
    classify_random_curves,
    default_experiment,
    ellipse_arc_estimates,
    joystick_ellipse_estimates,
)
from recognition.reproduction.chapter3.invariant_tables import table_3_1, table_3_2
from recognition.reproduction.chapter3.measures import relative_parameter_error
from recognition.reproduction.chapter3.random_curve_tables import recognition_rates, table_3_3
from recognition.reproduction.chapter3.reference import (
    CLASSES,
    TABLE_3_1_SHAPES,
    TABLE_3_1_THESIS,
    TABLE_3_2_SPLINE,
    TABLE_3_2_THESIS,
    TABLE_3_3_THESIS,
    TABLE_3_4_THESIS,
    TABLE_3_5_THESIS,
)
from recognition.reproduction.chapter3.shape_tables import (
    table_3_4,
    table_3_4_from_points,
    table_3_5,
    table_3_5_from_points,
)
from recognition.reproduction.chapter3.signature_figures import figures
from recognition.reproduction.tables import TableResult

__all__ = [
    "CLASSES",
    "TABLE_3_1_SHAPES",
    "TABLE_3_1_THESIS",
    "TABLE_3_2_SPLINE",
    "TABLE_3_2_THESIS",
    "TABLE_3_3_THESIS",
    "TABLE_3_4_THESIS",
    "TABLE_3_5_THESIS",
    "CurveExperiment",
    "JoystickExperiment",
    "TableResult",
    "classify_random_curves",
    "default_experiment",
    "ellipse_arc_estimates",
    "figures",
    "joystick_ellipse_estimates",
    "recognition_rates",
    "relative_parameter_error",
    "table_3_1",
    "table_3_2",
    "table_3_3",
    "table_3_4",
    "table_3_4_from_points",
    "table_3_5",
    "table_3_5_from_points",
]
