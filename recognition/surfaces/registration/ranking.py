"""Recognition: the registrations on every model ranked by error, thesis Eq. (4.9)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from recognition.surfaces.local_geometry import LocalSurfaceGeometry
from recognition.surfaces.registration.result import Registration

if TYPE_CHECKING:
    from recognition.surfaces.belief import Belief
    from recognition.surfaces.hypothesis import Hypothesis

__all__ = ["Recognition", "rank"]


@dataclass(frozen=True)
class Recognition:
    """Result of recognising data curves against a set of models (thesis Eq. (4.9)).

    Attributes
    ----------
    name : str or None
        Best model, or None when every model was rejected or fits worse than the
        largest error accepted (``max_error_m`` of :func:`rank`).
    ranking : list of (str, float)
        (model, registration error in metres), ascending; rejected models: inf.
    pose : (4, 4) float
        T_model_from_data of the best model (NaN when ``name`` is None).
    location : (3,) float
        The curves' common point p on the best model, model frame (NaN when ``name`` is
        None).
    margin_m : float
        Second-best error minus best error, metres (inf if only one model fits).
    registrations : dict of str to Registration
    timings_s : dict of str to float
        Registration time per model (fast mode: each model's share of the batched
        search, in proportion to the point evaluations made for it).
    time_s : float
        Total time, local geometry included.
    geometry : LocalSurfaceGeometry
        The data's normal and principal curvatures at p.
    belief : Belief or None
        The distinct (model, pose) hypotheses that fit near the best and their posterior
        (:mod:`recognition.surfaces.belief`; mesh databases).
    """

    name: str | None
    ranking: list[tuple[str, float]]
    pose: NDArray[np.float64]
    location: NDArray[np.float64]
    margin_m: float
    registrations: dict[str, Registration]
    timings_s: dict[str, float]
    time_s: float
    geometry: LocalSurfaceGeometry = field(repr=False)
    belief: Belief | None = field(default=None, repr=False)

    @property
    def hypotheses(self) -> tuple[Hypothesis, ...]:
        """The belief's hypotheses, most probable first (empty without a belief)."""
        return () if self.belief is None else self.belief.hypotheses

    @property
    def confidence(self) -> float:
        """The belief's confidence that its best hypothesis is right: its model, with p
        within 1 mm (:attr:`Belief.confidence`; NaN without a belief)."""
        return float("nan") if self.belief is None else self.belief.confidence

    @property
    def best(self) -> Registration | None:
        """The best model's registration (even when it fits worse than the threshold)."""
        return self.registrations.get(self.ranking[0][0]) if self.ranking else None

    @property
    def outliers(self) -> NDArray[np.int64]:
        """Indices (into the curves' points) of the data points the best model's
        registration rejected as outliers (empty when no model was named)."""
        best = self.best
        if self.name is None or best is None:
            return np.zeros(0, np.int64)
        return best.outliers

    @property
    def decided_at_lookup(self) -> bool:
        """True when every other model was rejected at table lookup (4.7)."""
        return self.name is not None and all(
            r.rejected for n, r in self.registrations.items() if n != self.name
        )


def rank(
    registrations: Mapping[str, Registration],
    geometry: LocalSurfaceGeometry,
    time_s: float,
    max_error_m: float = float("inf"),
) -> Recognition:
    """The recognition that ``registrations`` (one per model) give: least error first (4.9).

    The best model is named only when its error is finite and at most ``max_error_m``.
    """
    registrations = dict(registrations)
    ranking = sorted(((n, r.error_m) for n, r in registrations.items()), key=lambda item: item[1])
    best_name, best_error = ranking[0]
    second = ranking[1][1] if len(ranking) > 1 else float("inf")
    fits = bool(np.isfinite(best_error) and best_error <= max_error_m)
    best = registrations[best_name]
    return Recognition(
        best_name if fits else None,
        ranking,
        best.T_model_from_data if fits else np.full((4, 4), np.nan),
        best.location if fits else np.full(3, np.nan),
        float(second - best_error) if np.isfinite(best_error) else float("inf"),
        registrations,
        {n: r.time_s for n, r in registrations.items()},
        time_s,
        geometry,
    )
