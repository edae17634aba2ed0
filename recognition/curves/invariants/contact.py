"""Parameter t of each contact on the canonical curve, thesis Section 3.3.1."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from recognition.curves.families import N_PARAMETERS, SLOPE_CLASSES, TREE_CLASSES, CurveKind
from recognition.curves.invariants.spline import cubic_spline_l_m
from recognition.errors import DegenerateGeometry, InvalidCurveData

__all__ = ["DEGENERATE_CIRCLE_TOL", "contact_parameter"]

#: An ellipse with |a^2 - b^2| below this fraction of a^2 is a circle.
DEGENERATE_CIRCLE_TOL = 1e-12


def contact_parameter(
    kind: CurveKind | str,
    params: Sequence[float],
    kappa: ArrayLike,
    kappa_s: ArrayLike,
    lam: ArrayLike | None = None,
) -> np.ndarray:
    """Parameter t of each contact on the canonical curve, thesis Section 3.3.1.

    The formulas invert thesis Eqs. (3.5)-(3.6) (parabola), (3.16) (ellipse and its
    hyperbolic counterpart), (3.26) (cubical parabola), the semi-cubical slope and (3.41)
    (cubic spline), with the corrections of THESIS_ERRATA item 5:

    * parabola: ``t = kappa_s / (3 kappa^2)``;
    * ellipse: ``t0 = arcsin(sqrt(((ab/|kappa|)^(2/3) - b^2) / (a^2 - b^2)))`` is right
      only in the first quadrant; ``t = t0`` if ``kappa_s (a^2 - b^2) <= 0``, else
      ``pi - t0``. t is determined modulo pi (the ellipse is centrally symmetric) and is
      returned in [0, pi]. A circle (a = b) has no distinguished contact: DegenerateGeometry;
    * hyperbola: the printed arsinh gives |t|; ``t = sign(kappa_s) arsinh(sqrt(
      ((ab/|kappa|)^(2/3) - b^2) / (a^2 + b^2)))``;
    * cubical parabola: ``t = sign(kappa / a) sqrt((lam - b) / (3a))`` for traversal
      towards +x (the printed "+-");
    * semi-cubical parabola: ``t = 2 (lam - b) / (3a)``;
    * cubic spline: ``t = -(M ((b - lam)^2 - 3ac) + 3 (b - lam)) / (6a)`` with
      ``M = (kappa_s + 3 kappa^2 lam) / ((1 + lam^2) kappa^2)``.

    Only the cubical parabola depends on the direction of traversal (through the sign
    of kappa; reversal gives -t, the same point after the rotation by pi that maps the
    curve onto itself); the others use |kappa| or kappa^2, which reversal leaves
    unchanged, as it does kappa_s. The semi-cubical and spline formulas hold on both
    branches t > 0 and t < 0.

    Parameters
    ----------
    kind : CurveKind or str
    params : sequence of float
        Canonical shape parameters: (a,), (a, b) or (a, b, c).
    kappa, kappa_s : (m,) float
        Curvature and its arc-length derivative at each contact.
    lam : (m,) float, optional
        Slope ``dy/dx`` at each contact in the canonical frame; required by the three
        cubic classes.

    Returns
    -------
    (m,) float
    """
    kind = CurveKind(kind)
    kappa = np.asarray(kappa, dtype=float)
    kappa_s = np.asarray(kappa_s, dtype=float)
    if kind in SLOPE_CLASSES:
        if lam is None:
            raise InvalidCurveData(f"the contact parameter of a {kind} needs the slopes lam")
    if kind not in TREE_CLASSES:
        raise InvalidCurveData(f"{kind} has no contact parameter formula (Section 3.3.1)")
    expected = N_PARAMETERS[kind]
    if len(params) != expected:
        raise InvalidCurveData(f"{kind} takes {expected} shape parameter(s), got {len(params)}")
    p = tuple(float(v) for v in params)
    if kind is CurveKind.PARABOLA:
        return kappa_s / (3.0 * kappa**2)
    if kind in (CurveKind.ELLIPSE, CurveKind.HYPERBOLA):
        a, b = abs(p[0]), abs(p[1])
        base = np.cbrt((a * b / np.abs(kappa)) ** 2) - b * b
        if kind is CurveKind.HYPERBOLA:
            return np.sign(kappa_s) * np.arcsinh(np.sqrt(np.clip(base / (a * a + b * b), 0, None)))
        denom = a * a - b * b
        if abs(denom) <= DEGENERATE_CIRCLE_TOL * a * a:
            raise DegenerateGeometry("a circle (a = b) has no distinguished contact parameter")
        t0 = np.arcsin(np.sqrt(np.clip(base / denom, 0.0, 1.0)))
        return np.where(kappa_s * denom <= 0, t0, np.pi - t0)
    a, b = p[0], p[1]
    slopes = np.asarray(lam, dtype=float)
    if kind is CurveKind.CUBICAL_PARABOLA:
        return np.sign(kappa / a) * np.sqrt(np.clip((slopes - b) / (3.0 * a), 0.0, None))
    if kind is CurveKind.SEMICUBICAL_PARABOLA:
        return 2.0 * (slopes - b) / (3.0 * a)
    c = p[2]
    _, M = cubic_spline_l_m(slopes, kappa, kappa_s)
    e = b - slopes
    return -(M * (e * e - 3.0 * a * c) + 3.0 * e) / (6.0 * a)
