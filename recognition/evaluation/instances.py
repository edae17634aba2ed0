"""Benchmark instances: the spec that names one, the data a source makes of it, the source protocol.

An instance is named by an :class:`InstanceSpec` (model, index, seed) and made from it
by a *source*, a frozen dataclass of settings (hashed, with the registration settings,
into the ``settings`` of every record) with

- ``specs(database) -> list[InstanceSpec]``: the instances of the benchmark;
- ``instance(database, spec) -> Instance``: the data curves and the ground truth of one,
  regenerated from the spec alone (so any worker can make it).

:class:`~recognition.evaluation.synthetic_source.SyntheticSource` samples curves on the
models themselves (thesis Section 4.3.4); ``tactile_sim.evaluation.SimulatedSource`` has
the simulated robot probe the objects (Section 4.4).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

from recognition.evaluation.models import Database
from recognition.surfaces.data_curves import DataCurves

if TYPE_CHECKING:
    from recognition.surfaces.active_touch import Contact
    from recognition.surfaces.touch_planning import TouchLimits, TouchPlan

__all__ = ["Instance", "InstanceSource", "InstanceSpec"]


@dataclass(frozen=True)
class InstanceSpec:
    """One recognition instance: the model (object), its index and its own seed.

    Attributes
    ----------
    model : str
        The true model's name.
    index : int
        Instance number of this model.
    vertex : int or None
        The model vertex the curves meet at (synthetic instances); None when the source
        chooses the point itself (simulated probing).
    seed : int
        Seeds everything random in making the instance.
    """

    model: str
    index: int
    vertex: int | None
    seed: int

    @property
    def key(self) -> str:
        """The instance's name in records: ``model/index``."""
        return f"{self.model}/{self.index}"


@dataclass(frozen=True)
class Instance:
    """The data of one instance, as a source makes it.

    Attributes
    ----------
    curves : DataCurves or None
        The three data curves, metres; None when the instance could not be made (then
        ``info["error"]`` says why, and the instance counts as a failure).
    point_in_model : (3,) float or None, metres
        The true common point p in the model frame (None: no localisation error).
    info : Mapping[str, Any]
        JSON-ready facts about the instance, copied into every record (``*_mm``, ``*_s``).
    reference_curves : DataCurves or None
        The same instance without measurement error (e.g. the simulator's true contact
        points); recognised too, as a diagnosis, when given.
    touch : callable or None
        ``touch(plan) -> Contact`` (or its point (3,)) in the curves' frame, or None
        (nothing met along the planned approach): further contact for verification
        touches (:func:`recognition.verify`); None: the source cannot touch.
    touch_limits : TouchLimits or None
        The touches ``touch`` can make.
    T_model_from_data : (4, 4) float or None
        The true pose, model from the curves' frame (the ground truth of the diagnosis of
        a wrong answer, :mod:`~recognition.evaluation.diagnosis`); None: not known.
    """

    curves: DataCurves | None
    point_in_model: NDArray[np.float64] | None = None
    info: Mapping[str, Any] = field(default_factory=dict)
    reference_curves: DataCurves | None = None
    touch: Callable[[TouchPlan], Contact | NDArray[np.float64] | None] | None = None
    touch_limits: TouchLimits | None = None
    T_model_from_data: NDArray[np.float64] | None = None


class InstanceSource(Protocol):
    """What the runner needs of a source of instances (a frozen dataclass)."""

    def specs(self, database: Database) -> list[InstanceSpec]:
        """The instances of the benchmark, in order."""
        ...

    def instance(self, database: Database, spec: InstanceSpec) -> Instance:
        """The data of the instance ``spec`` (from the spec alone)."""
        ...
