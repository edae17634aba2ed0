"""The recognition tree of thesis Fig. 3.4: class, shape parameters and contact parameters.

Every class hypothesis is initialised from the thesis's invariants and then refined:

1. **Initialisation (thesis)**, :mod:`.hypotheses`. Parabola: I_p (3.10).
   Ellipse/hyperbola: I_c1, I_c2 by the regression form of (3.17)/(3.23), sign of I_c1.
   Cubical and semi-cubical parabola: the slope quartics (3.31) and (3.34) at two
   points, slope propagation (3.29), then I_cp1/I_cp2 (3.27-3.28) or I_scp1/I_scp2
   (3.32-3.33) at every point. Cubic spline: one contact and its parameter t fix
   (a, b, c) in closed form (errata item 7); (lambda1, t1) is searched on a grid and
   scored by consistency at the other contacts. Contact parameters t from Section 3.3.1
   with the corrections of errata item 5.
2. **Refinement**, :mod:`.signature_fit`. A least-squares fit of the exact canonical
   signature: unknowns are the shape parameters, the rotation psi between data and
   canonical frame (when tangent rotations are given) and each contact's parameter t_i;
   residuals are ``kappa_i - sigma kappa(t_i)`` and ``kappa_s,i - kappa_s(t_i)``
   (divided by the measured magnitude plus its median over the points) and
   ``sin(phi_i + psi - theta(t_i))``. The reduced RMS residual (divided by the degrees
   of freedom left) is the class's consistency measure, comparable across classes.
3. **Decision**, :mod:`.tree`. If no class has a residual of at most ``tolerance`` the
   curve is ``unclassified``. Otherwise the tree takes the simplest class (parabola; then
   the two-parameter classes; then the cubic spline) whose residual is within
   ``complexity_factor`` of the best, or below ``tolerance / complexity_factor`` (fits
   that good are all exact to within the estimation error): the classes are nested
   (a parabola is a conic and a spline; a semi-cubical parabola is a spline with
   c = 0), so a more complex class must fit clearly better to be preferred.

``tolerance`` must exceed the relative error of the kappa, kappa_s estimates: about
1e-4 for exact samples and finite differences, 1e-2-5e-2 for noisy tactile samples and
:func:`~recognition.curves.estimation.local_fit_geometry` (see README and
``scripts/reproduce_thesis.py``). The results are :class:`ClassFit` (one hypothesis) and
:class:`CurveRecognition` (the decision), in :mod:`.results`.
"""

from recognition.curves.recognition.results import (
    ClassFit,
    CurveRecognition,
    canonical_parameters,
)
from recognition.curves.recognition.tree import (
    COMPLEXITY_FACTOR,
    DEFAULT_TOLERANCE,
    estimated_uncertainty,
    fit_class,
    recognize_curve,
    recognize_points,
)
from recognition.curves.recognition.uncertainty import (
    DEFAULT_SIGNIFICANCE,
    EXACT_PRECISION,
    InputUncertainty,
    consistency_test,
)

__all__ = [
    "COMPLEXITY_FACTOR",
    "DEFAULT_SIGNIFICANCE",
    "DEFAULT_TOLERANCE",
    "EXACT_PRECISION",
    "ClassFit",
    "CurveRecognition",
    "InputUncertainty",
    "canonical_parameters",
    "consistency_test",
    "estimated_uncertainty",
    "fit_class",
    "recognize_curve",
    "recognize_points",
]
