"""The one front door of registration: a config names the mode, the model its kind.

``register(model, curves, config)`` registers data curves on one model;
``register_all(models, curves, config)`` on several (the fast mode searches all of them
in one batch); ``recognize(models, curves, config)`` ranks them (thesis Eq. (4.9)).
The config's class chooses the method: :class:`FastConfig` (default), :class:`ThesisConfig`
and :class:`IcpConfig` on mesh models, :class:`ClosedFormConfig` on closed-form models.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from typing import Any

from numpy.typing import ArrayLike

from recognition.errors import InvalidCurveData, InvalidModel
from recognition.surfaces.closed_form.model import ClosedFormModel
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.distance import FieldStack
from recognition.surfaces.local_geometry import LocalSurfaceGeometry
from recognition.surfaces.mesh_model import MeshModel
from recognition.surfaces.registration.candidates import CandidateIndex
from recognition.surfaces.registration.closed_form import register_closed_form
from recognition.surfaces.registration.config import (
    ClosedFormConfig,
    FastConfig,
    IcpConfig,
    RegistrationConfig,
    ThesisConfig,
)
from recognition.surfaces.registration.data import data_geometry
from recognition.surfaces.registration.exact import with_exact_error
from recognition.surfaces.registration.fast import register_fast
from recognition.surfaces.registration.icp import register_icp
from recognition.surfaces.registration.ranking import Recognition, rank
from recognition.surfaces.registration.result import Registration, RegistrationMode
from recognition.surfaces.registration.thesis import register_thesis

__all__ = [
    "CONFIGS",
    "Model",
    "config_for",
    "recognize",
    "register",
    "register_all",
    "registration_mode",
]

Model = MeshModel | ClosedFormModel
"""A model of either kind."""

#: The config class of every mode.
CONFIGS: dict[RegistrationMode, type[RegistrationConfig]] = {
    RegistrationMode.FAST: FastConfig,
    RegistrationMode.THESIS: ThesisConfig,
    RegistrationMode.ICP: IcpConfig,
    RegistrationMode.CLOSED_FORM: ClosedFormConfig,
}


def registration_mode(mode: RegistrationMode | str) -> RegistrationMode:
    """The mode named ``mode``, or :class:`~recognition.errors.InvalidCurveData`."""
    try:
        return RegistrationMode(mode)
    except ValueError:
        raise InvalidCurveData(
            f"unknown registration mode {mode!r}; expected one of "
            f"{', '.join(m.value for m in RegistrationMode)}"
        ) from None


def config_for(mode: RegistrationMode | str, **fields: Any) -> RegistrationConfig:
    """The default config of ``mode`` with ``fields`` set (e.g. ``delta=30.0``)."""
    return CONFIGS[registration_mode(mode)](**fields)


def _check_kinds(models: Sequence[Model], config: RegistrationConfig) -> None:
    kind = ClosedFormModel if isinstance(config, ClosedFormConfig) else MeshModel
    for model in models:
        if not isinstance(model, kind):
            raise InvalidModel(
                f"{getattr(model, 'name', model)!r} is a {type(model).__name__}; the "
                f"{config.mode.value} mode registers {kind.__name__}s"
            )


def register_all(
    models: Sequence[Model],
    curves: DataCurves,
    config: RegistrationConfig = FastConfig(),
    *,
    geometry: LocalSurfaceGeometry | None = None,
    stack: FieldStack | None = None,
    which_field: ArrayLike | None = None,
    index: CandidateIndex | None = None,
    threads: int = 1,
    contact: ArrayLike | None = None,
    noise_m: float | None = None,
) -> list[Registration]:
    """Register data curves on each of ``models``: one registration per model, in order.

    Parameters
    ----------
    models : sequence of MeshModel or ClosedFormModel
    curves : DataCurves
        Data curves in any frame, metres.
    config : FastConfig, ThesisConfig, IcpConfig or ClosedFormConfig
        The mode and its settings.
    geometry : LocalSurfaceGeometry, optional
        The data's local geometry, if already computed (it does not depend on the model;
        default :func:`~recognition.surfaces.registration.data.data_geometry`).
    stack, which_field, index
        Fast mode: the models' distance fields in one stack, each model's index in it and
        the candidate maps of the stack's models in one table (built here if not given).
    threads : int
        Thesis, ICP and closed-form modes: models registered concurrently (numpy
        releases the GIL in the heavy array work); results do not depend on it.
    contact : (k, 3) float, optional
        Fast mode: further contact points in the curves' frame (verification touches)
        that choose the poses with the curves (:func:`register_fast`).
    noise_m : float, optional
        Fast mode: the data's noise across the surface, if already estimated (default
        :func:`~recognition.surfaces.registration.data.data_noise_m`).

    Returns
    -------
    list of Registration
        Fast mode: errors exact (poses polished on closest points) for the models that
        can win, the others read off the distance fields.
    """
    models = list(models)
    _check_kinds(models, config)
    geometry = geometry or data_geometry(curves, config.geometry)
    if isinstance(config, FastConfig):
        meshes = [m for m in models if isinstance(m, MeshModel)]
        return register_fast(
            meshes,
            curves,
            geometry,
            config,
            stack=stack,
            which_field=which_field,
            index=index,
            contact=contact,
            noise_m=noise_m,
        )

    def one(model: Model) -> Registration:
        if isinstance(config, ThesisConfig) and isinstance(model, MeshModel):
            return register_thesis(model, curves, geometry, config)
        if isinstance(config, IcpConfig) and isinstance(model, MeshModel):
            return register_icp(model, curves, geometry, config)
        assert isinstance(config, ClosedFormConfig) and isinstance(model, ClosedFormModel)
        return register_closed_form(model, curves, geometry, config)

    if threads > 1 and len(models) > 1:
        with ThreadPoolExecutor(threads) as pool:
            return list(pool.map(one, models))
    return [one(model) for model in models]


def register(
    model: Model,
    curves: DataCurves,
    config: RegistrationConfig = FastConfig(),
    *,
    geometry: LocalSurfaceGeometry | None = None,
    exact: bool = True,
) -> Registration:
    """Register data curves on one model (see :func:`register_all`).

    ``exact`` (fast mode): polish the pose and compute the error on exact closest points
    (else the error is read off the distance field). ``time_s`` is the whole time, local
    geometry included.
    """
    start = time.perf_counter()
    geometry = geometry or data_geometry(curves, config.geometry)
    result = register_all([model], curves, config, geometry=geometry)[0]
    if exact and isinstance(config, FastConfig) and isinstance(model, MeshModel):
        result = with_exact_error(result, model, curves, refine=True, point=geometry.point)
    return replace(result, time_s=time.perf_counter() - start)


def recognize(
    models: Sequence[Model],
    curves: DataCurves,
    config: RegistrationConfig = FastConfig(),
    *,
    max_error_m: float = float("inf"),
    threads: int = 1,
) -> Recognition:
    """Register the curves on every model and rank them, thesis Eq. (4.9).

    For a database of mesh models, :meth:`~recognition.surfaces.database.ModelDatabase.
    recognize` does the same with the models' distance fields prepared once.
    """
    start = time.perf_counter()
    models = list(models)
    if not models:
        raise InvalidCurveData("recognition needs at least one model")
    names = [m.name for m in models]
    if len(set(names)) != len(names):
        raise InvalidModel(f"model names must be unique, got {names}")
    geometry = data_geometry(curves, config.geometry)
    found = register_all(models, curves, config, geometry=geometry, threads=threads)
    return rank(
        dict(zip(names, found, strict=True)),
        geometry,
        time.perf_counter() - start,
        max_error_m,
    )
