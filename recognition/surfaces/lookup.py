"""The lookup table of principal curvatures, thesis Eq. (4.7), for every kind of model."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

__all__ = ["CurvatureTable"]


@dataclass(frozen=True, eq=False)
class CurvatureTable:
    """Principal curvatures at sampled sites of a model with a (k1, k2) range query (4.7).

    A site is whatever the model samples: a mesh vertex (Section 4.3.2) or a grid point
    (u, v) of a closed-form surface (Section 4.2.1).

    Attributes
    ----------
    site : (m,) int
        The model's index of each row: a vertex of a mesh model, a grid point of a
        closed-form model.
    k1, k2 : (m,) float
        Principal curvatures, k1 >= k2, 1 / model units (1/m for meshes).
    d1 : (m, 3) float or None
        Unit principal direction of k1 at each site (mesh tables).
    """

    site: NDArray[np.int64]
    k1: NDArray[np.float64]
    k2: NDArray[np.float64]
    d1: NDArray[np.float64] | None = None
    _tree: cKDTree | None = field(default=None, init=False, repr=False)

    def __len__(self) -> int:
        return int(self.site.size)

    def query(self, k1: float, k2: float, delta: float) -> NDArray[np.int64]:
        """Rows with sqrt((k1 - k1_i)^2 + (k2 - k2_i)^2) < delta, thesis Eq. (4.7).

        Parameters
        ----------
        k1, k2 : float
            The data's principal curvatures.
        delta : float
            Tolerance, same units; ``inf`` returns every row.

        Returns
        -------
        (r,) int
            Row indices, nearest in (k1, k2) first; rows at equal distance in a fixed
            order (the KD-tree's).
        """
        if np.isinf(delta):
            rows = np.arange(len(self))
        else:
            if self._tree is None:  # at the first query: the fast mode's maps never need one
                object.__setattr__(self, "_tree", cKDTree(np.column_stack([self.k1, self.k2])))
            assert self._tree is not None
            rows = np.asarray(self._tree.query_ball_point([k1, k2], r=delta), dtype=np.int64)
        dist = np.hypot(self.k1[rows] - k1, self.k2[rows] - k2)
        keep = dist < delta
        rows, dist = rows[keep], dist[keep]
        return rows[np.argsort(dist, kind="stable")]
