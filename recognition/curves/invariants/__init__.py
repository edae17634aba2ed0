"""Differential and semi-differential invariants of thesis Section 3.2, and shape recovery.

All functions are vectorised over numpy arrays. Conventions fixed here (see
``THESIS_ERRATA.md``):

* ``kappa^(2/3)`` means ``|kappa|^(2/3) = cbrt(kappa^2)``; printed literally it is NaN
  wherever kappa < 0.
* The cubic-class formulas (3.27)-(3.44) hold for traversal towards +x in the
  canonical frame; callers try both signs of kappa.

The parts: :mod:`.conics` (Section 3.2.1), :mod:`.cubics` (the cubical and semi-cubical
parabolas, Sections 3.2.2.1-3.2.2.2), :mod:`.spline` (closed forms of the cubic spline,
Section 3.2.2.3), :mod:`.spline_fit` (the least-squares fit of g over the contacts) and
:mod:`.contact` (contact parameters, Section 3.3.1).
"""

from recognition.curves.invariants.conics import (
    abs_two_thirds,
    conic_invariant_1,
    conic_invariant_2,
    conic_invariants_regression,
    ellipse_parameters,
    hyperbola_parameters,
    parabola_invariant,
    parabola_parameter,
)
from recognition.curves.invariants.contact import contact_parameter
from recognition.curves.invariants.cubics import (
    cubical_parabola_invariant_1,
    cubical_parabola_invariant_2,
    cubical_parabola_slope_quartic,
    propagate_slope,
    real_slopes,
    semicubical_parabola_invariant_1,
    semicubical_parabola_invariant_2,
    semicubical_parabola_slope_quartic,
)
from recognition.curves.invariants.spline import (
    cubic_spline_c,
    cubic_spline_from_contact,
    cubic_spline_l_m,
    cubic_spline_residual,
)
from recognition.curves.invariants.spline_fit import (
    CubicSplineGFit,
    CubicSplineGSolution,
    fit_cubic_spline_g,
)

__all__ = [
    "CubicSplineGFit",
    "CubicSplineGSolution",
    "abs_two_thirds",
    "conic_invariant_1",
    "conic_invariant_2",
    "conic_invariants_regression",
    "contact_parameter",
    "cubic_spline_c",
    "cubic_spline_from_contact",
    "cubic_spline_l_m",
    "cubic_spline_residual",
    "cubical_parabola_invariant_1",
    "cubical_parabola_invariant_2",
    "cubical_parabola_slope_quartic",
    "ellipse_parameters",
    "fit_cubic_spline_g",
    "hyperbola_parameters",
    "parabola_invariant",
    "parabola_parameter",
    "propagate_slope",
    "real_slopes",
    "semicubical_parabola_invariant_1",
    "semicubical_parabola_invariant_2",
    "semicubical_parabola_slope_quartic",
]
