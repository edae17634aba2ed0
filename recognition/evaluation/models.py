"""The model sets a benchmark recognises against: a ModelDatabase or the Fig. 4.15 closed forms.

A worker is handed a :data:`DatabaseHandle` (small, picklable) and loads the
:data:`Database` from it once (:func:`load_database`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

from recognition.surfaces import closed_form as cf
from recognition.surfaces.database import ModelDatabase

__all__ = [
    "CLOSED_FORM_METHOD",
    "ClosedFormModels",
    "Database",
    "DatabaseHandle",
    "load_database",
]

#: Method name of the registration onto closed-form models (thesis Section 4.2.2).
CLOSED_FORM_METHOD = "closed-form"


@dataclass(frozen=True)
class ClosedFormModels:
    """The closed-form models of the four solids of thesis Fig. 4.15, as a database.

    Built (tables of Section 4.2.1) in every worker that needs them.

    Attributes
    ----------
    half_length_m : float, metres
        The cylinders are tabulated over |z| <= this.
    n_u, n_v : int
        Lookup-table grid.
    """

    half_length_m: float = 0.05
    n_u: int = 200
    n_v: int = 100

    @property
    def names(self) -> list[str]:
        """The solids' names, in the order of Fig. 4.15."""
        return [s.name for s in cf.fig_4_15_solids(self.half_length_m)]

    def load(self) -> tuple[cf.ClosedFormModel, ...]:
        """The models with their lookup tables (built once per process)."""
        return _closed_form_models(self)


@functools.lru_cache(maxsize=2)
def _closed_form_models(spec: ClosedFormModels) -> tuple[cf.ClosedFormModel, ...]:
    return tuple(
        cf.ClosedFormModel.build(s, spec.n_u, spec.n_v)
        for s in cf.fig_4_15_solids(spec.half_length_m)
    )


#: A loaded model set: a mesh database or the closed-form models.
Database = ModelDatabase | tuple[cf.ClosedFormModel, ...]

#: What a worker loads a :data:`Database` from: a ModelDatabase directory or the
#: closed-form models' settings.
DatabaseHandle = Path | str | ClosedFormModels


def load_database(handle: DatabaseHandle) -> Database:
    """The model set named by ``handle``."""
    if isinstance(handle, ClosedFormModels):
        return handle.load()
    return ModelDatabase.load(handle)
