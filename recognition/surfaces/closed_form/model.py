"""A closed-form model: a surface with its lookup table of principal curvatures (4.2.1, 4.7)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from recognition.errors import InvalidModel
from recognition.surfaces.closed_form.surface import ClosedFormSurface, principal_curvatures
from recognition.surfaces.lookup import CurvatureTable

__all__ = ["ClosedFormModel", "candidate_rows"]

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class ClosedFormModel:
    """A closed-form surface with its lookup table: one entry of a model database.

    The table samples the parameter domain on a uniform grid of cell centres (so that
    singular edges such as poles are avoided); row i of :attr:`table` is grid point i.

    Attributes
    ----------
    surface : ClosedFormSurface
    table : CurvatureTable
        Principal curvatures at the grid points (thesis Section 4.2.1, Eq. (4.7)).
    u, v : (m,) float
        Parameters of the grid points.
    points : (m, 3) float
        sigma(u, v), model units.
    shape : (int, int)
        Grid size (n_u, n_v).
    """

    surface: ClosedFormSurface
    table: CurvatureTable
    u: Array
    v: Array
    points: Array
    shape: tuple[int, int]

    @classmethod
    def build(cls, surface: ClosedFormSurface, n_u: int = 200, n_v: int = 100) -> ClosedFormModel:
        """The model of ``surface`` with its table (4.7) on an ``n_u`` x ``n_v`` grid (thesis
        Section 4.2.1)."""
        if n_u < 2 or n_v < 2:
            raise InvalidModel(f"a lookup table needs at least a 2 x 2 grid, got {n_u} x {n_v}")
        (u0, u1), (v0, v1) = surface.domain
        u = u0 + (np.arange(n_u) + 0.5) * (u1 - u0) / n_u
        v = v0 + (np.arange(n_v) + 0.5) * (v1 - v0) / n_v
        uu, vv = (g.ravel() for g in np.meshgrid(u, v, indexing="ij"))
        k1, k2 = principal_curvatures(surface, uu, vv)
        table = CurvatureTable(np.arange(uu.size), k1, k2)
        return cls(surface, table, uu, vv, surface.sigma(uu, vv), (n_u, n_v))

    @property
    def name(self) -> str:
        """The surface's name."""
        return self.surface.name


def candidate_rows(
    model: ClosedFormModel,
    k1: float,
    k2: float,
    delta: float,
    separation: float,
    max_candidates: int,
    symmetries: Sequence[Array] = (),
) -> NDArray[np.int64]:
    """Candidate points of the table lookup (4.7), thinned out in space.

    Rows within ``delta`` of (k1, k2) are visited nearest first; a row is kept unless a
    kept row, or its image under one of the surface's ``symmetries`` (which would give
    the same registration), lies within ``separation`` (model units), until
    ``max_candidates`` are kept.
    """
    rows = model.table.query(k1, k2, delta)
    maps = [np.eye(3), *symmetries]
    kept: list[Array] = []
    out: list[int] = []
    for r in rows:
        q = model.points[r]
        if kept and np.min(np.linalg.norm(np.concatenate(kept) - q, axis=1)) < separation:
            continue
        kept.append(np.array([S @ q for S in maps]))
        out.append(int(r))
        if len(out) == max_candidates:
            break
    return np.array(out, dtype=np.int64)
