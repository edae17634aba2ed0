"""The fast mode's candidates: the lookup (4.7) over every model of a database at once,
ranked by ring descriptors within a budget."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.surfaces.local_geometry import LocalSurfaceGeometry
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.rings import MAX_COST, MISSING_COST, check_ring_shapes, ring_weights

__all__ = ["CandidateIndex", "smallest"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


def smallest(values: NDArray[np.floating], count: int | float) -> NDArray[np.intp]:
    """Indices of the ``count`` smallest values (all if fewer), in no particular order."""
    if count >= values.size:
        return np.arange(values.size)
    return np.argpartition(values, int(count) - 1)[: int(count)]


@dataclass(frozen=True, eq=False)
class CandidateIndex:
    """Every model's candidate map (:attr:`MeshModel.candidate_curvatures`) in one table,
    its rows in ascending order of k1, so that a lookup (4.7) scans only the rows whose
    k1 lies within the tolerance (found by bisection), not the whole table.

    Attributes
    ----------
    owner : (R,) int
        The field (in the search's field stack) of each row's model.
    row : (R,) int
        The row in its model's candidate map.
    k1, k2 : (R,) float, 1/m
        ``k1`` ascending.
    rings : (R, K, DESCRIPTOR_SIZE) float32
        Ring descriptors (:mod:`~recognition.surfaces.rings`).
    """

    owner: IntArray
    row: IntArray
    k1: Array
    k2: Array
    rings: NDArray[np.float32]

    @classmethod
    def of(cls, models: Sequence[MeshModel], owners: ArrayLike | None = None) -> CandidateIndex:
        """The index of ``models``' candidate maps, owned by ``owners`` (their fields in
        the stack; default 0, 1, ...)."""
        maps = [m.candidate_curvatures for m in models]
        owners = np.arange(len(maps)) if owners is None else np.asarray(owners)
        k1 = np.concatenate([c.k1 for c in maps])
        order = np.argsort(k1, kind="stable")
        return cls(
            np.repeat(owners, [len(c) for c in maps])[order],
            np.concatenate([np.arange(len(c)) for c in maps])[order],
            k1[order],
            np.concatenate([c.k2 for c in maps])[order],
            np.concatenate([m.rings for m in models])[order],
        )

    def select(
        self,
        geometry: LocalSurfaceGeometry,
        data_rings: Array,
        tolerance: float,
        budget: int | None,
        fields: IntArray,
    ) -> tuple[list[IntArray], NDArray[np.bool_]]:
        """The candidate rows of each model of ``fields``, and whether it has any.

        The rows within ``tolerance`` (1/m; inf: every row) of the data's (k1, k2)
        (4.7); over ``budget`` of them (None: no limit) across all the models, those of
        least score: the ring score (:func:`~recognition.surfaces.rings.ring_scores`)
        plus the squared curvature distance in tolerances, in one compiled pass
        (:func:`~recognition.surfaces.field_kernels.candidate_scores`). A model without a
        row within the tolerance is rejected at table lookup; one whose rows the budget
        left out is not.
        """
        from recognition.surfaces import field_kernels  # numba: imported when first needed

        check_ring_shapes(self.rings, data_rings)
        allowed = np.zeros(int(self.owner.max()) + 1, bool)
        allowed[fields] = True
        lo, hi = 0, self.k1.size
        if np.isfinite(tolerance):
            window = [geometry.k1 - tolerance, geometry.k1 + tolerance]
            lo, hi = (int(i) for i in np.searchsorted(self.k1, window))
        keep, score = field_kernels.candidate_scores(
            self.owner[lo:hi],
            self.k1[lo:hi],
            self.k2[lo:hi],
            self.rings[lo:hi],
            allowed,
            float(geometry.k1),
            float(geometry.k2),
            float(tolerance),
            np.nan_to_num(data_rings),
            ring_weights(data_rings),
            MISSING_COST,
            MAX_COST,
        )
        keep += lo
        matched = np.bincount(self.owner[keep], minlength=len(allowed))[fields] > 0
        if budget is not None and keep.size > budget:
            keep = keep[smallest(score, budget)]
        keep = keep[np.lexsort((self.row[keep], self.owner[keep]))]  # by model, then row
        owner = self.owner[keep]
        starts = np.searchsorted(owner, fields, side="left")
        ends = np.searchsorted(owner, fields, side="right")
        return [self.row[keep[a:b]] for a, b in zip(starts, ends, strict=True)], matched
