"""Results of the recognition tree: one class hypothesis and the tree's decision."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from recognition.curves.families import CurveKind

__all__ = ["PARAMETER_NAMES", "ClassFit", "CurveRecognition"]

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
        Reduced relative residual of the refined fit; ``inf`` when rejected.
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
    tolerance : float
    """

    kind: CurveKind
    parameters: dict[str, float]
    contact_parameters: np.ndarray
    invariants: dict[str, np.ndarray]
    spread: dict[str, float]
    residual: float
    candidates: tuple[ClassFit, ...]
    tolerance: float

    @property
    def fit(self) -> ClassFit | None:
        """The winning hypothesis, or None if unclassified."""
        return next((c for c in self.candidates if c.kind is self.kind), None)
