"""Results of the recognition tree: one class hypothesis and the tree's decision."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from recognition.curves.families import CurveKind

__all__ = [
    "PARAMETER_NAMES",
    "ClassFit",
    "CurveRecognition",
    "canonical_form",
    "canonical_parameters",
]

#: Names of the shape parameters of a canonical form, by their number.
PARAMETER_NAMES = {1: ("a",), 2: ("a", "b"), 3: ("a", "b", "c")}


@dataclass(frozen=True)
class ClassFit:
    """One class hypothesis tested by the tree.

    Attributes
    ----------
    kind : CurveKind
    params : tuple of float
        Canonical shape parameters (empty when the class was rejected outright).
    residual : float
        Reduced RMS of the standardised residuals of the refined fit (divided by the
        degrees of freedom left); ``inf`` when rejected.
    t : (m,) float
        Contact parameter of each estimate in the canonical form.
    psi : float or None
        Rotation (radians) taking data tangent angles to canonical ones, when known.
    orientation : int
        +1 when the data traverse the canonical curve with increasing t, else -1.
    invariants : dict of str to ndarray
        The thesis's invariant values evaluated on the data for this class.
    message : str
        Why the class was rejected, if it was.
    per_point : (m,) float or None
        Each point's residual norm in the final fit (of the points used).
    outliers : tuple of int
        Points left out as estimation outliers (their t is NaN).
    statistic : float
        Sum of the squared standardised residuals (chi-square statistic); ``inf`` when
        rejected.
    scale, dof : float
        For data of this class with errors as stated, ``statistic`` is distributed as
        ``scale * chi2(dof)`` (``scale`` 1 and ``dof`` residuals minus unknowns for
        independent errors).
    p_value : float
        Probability of a statistic at least this large for data of this class (a fit to
        points: the smaller of its two tests' doubled, :func:`recognize_points`); 0 when
        rejected, NaN when no degree of freedom is left.
    """

    kind: CurveKind
    params: tuple[float, ...]
    residual: float
    t: np.ndarray
    psi: float | None
    orientation: int
    invariants: dict[str, np.ndarray] = field(default_factory=dict)
    message: str = ""
    per_point: np.ndarray | None = None
    outliers: tuple[int, ...] = ()
    statistic: float = float("inf")
    scale: float = 1.0
    dof: float = float("nan")
    p_value: float = 0.0

    @property
    def parameters(self) -> dict[str, float]:
        """Shape parameters by name."""
        return dict(zip(PARAMETER_NAMES.get(len(self.params), ()), self.params, strict=True))


@dataclass(frozen=True)
class CurveRecognition:
    """Result of the recognition tree.

    Attributes
    ----------
    kind : CurveKind
        The recognised class, or ``CurveKind.UNCLASSIFIED``.
    parameters : dict of str to float
        Shape parameters of the canonical form (empty when unclassified).
    contact_parameters : (m,) float
        Parameter t of each contact on the canonical curve (Section 3.3.1).
    invariants : dict of str to ndarray
        Invariant values of the recognised class, e.g. ``{"I_p": ...}``.
    spread : dict of str to float
        Relative spread (std / |mean|) of each invariant.
    residual : float
        Consistency residual of the recognised class (``inf`` if unclassified).
    candidates : tuple of ClassFit
        Every hypothesis tested, in tree order.
    tolerance : float or None
        The reduced-residual tolerance of the decision, when one was given instead of
        the input uncertainty.
    statistic : float
        Chi-square statistic of the recognised class (``inf`` if unclassified).
    p_value : float
        Its p-value (:attr:`ClassFit.p_value`); 0 if unclassified.
    significance : float
        Significance of the consistency test: a class is consistent when its p-value is
        at least this.
    runner_up : ClassFit or None
        The next-best class: the best-fitting of the others (the best of all when
        unclassified).
    decided_by : str
        ``"invariants"``: the thesis's tree on local estimates (:func:`recognize_curve`);
        ``"points"``: every class fitted to the sampled points themselves
        (:func:`recognize_points`).
    noise : float or None
        ``"points"``: the points' noise (standard deviation per coordinate) the tests
        assumed.
    """

    kind: CurveKind
    parameters: dict[str, float]
    contact_parameters: np.ndarray
    invariants: dict[str, np.ndarray]
    spread: dict[str, float]
    residual: float
    candidates: tuple[ClassFit, ...]
    tolerance: float | None
    statistic: float = float("inf")
    p_value: float = 0.0
    significance: float = float("nan")
    runner_up: ClassFit | None = None
    decided_by: str = "invariants"
    noise: float | None = None

    @property
    def fit(self) -> ClassFit | None:
        """The winning hypothesis, or None if unclassified."""
        return next((c for c in self.candidates if c.kind is self.kind), None)


def canonical_form(
    kind: CurveKind, params: tuple[float, ...], t: np.ndarray, sigma: float, psi: float = 0.0
) -> tuple[tuple[float, ...], np.ndarray, float, float]:
    """Report equivalent shapes one way: (a, b) positive for conics with a >= b for the
    ellipse, a > 0 for the x = t^2 classes; returns shape, contacts, orientation and psi.

    ``x = t^2, y = a t^3 + b t^2 + c t`` with ``t -> -t`` is the same curve with
    (-a, b, -c), traversed the other way; for the semi-cubical parabola (-a, b). The
    ellipse (a cos t, b sin t) with a < b is (b cos t', a sin t') in a frame turned by
    -pi/2, with t' = t - pi/2 (and psi less pi/2).
    """
    p = list(params)
    if kind in (CurveKind.PARABOLA, CurveKind.ELLIPSE, CurveKind.HYPERBOLA):
        p = [abs(v) for v in p]
        if kind is CurveKind.ELLIPSE and p[1] > p[0]:
            p = [p[1], p[0]]
            t, psi = t - np.pi / 2, psi - np.pi / 2
    elif kind in (CurveKind.SEMICUBICAL_PARABOLA, CurveKind.CUBIC_SPLINE) and p[0] < 0:
        p[0] = -p[0]
        if kind is CurveKind.CUBIC_SPLINE:
            p[2] = -p[2]
        t, sigma = -t, -sigma
    return tuple(p), t, sigma, psi


def canonical_parameters(kind: CurveKind | str, params: Sequence[float]) -> tuple[float, ...]:
    """The representative of a shape's equivalent parameter sets that the tree reports."""
    kind = CurveKind(kind)
    return canonical_form(kind, tuple(float(v) for v in params), np.zeros(0), 1.0)[0]
