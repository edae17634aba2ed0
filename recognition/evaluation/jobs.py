"""A benchmark job (one instance, one registration config per method) and the records it gives."""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from recognition.errors import DegenerateGeometry, InvalidCurveData, InvalidModel
from recognition.evaluation.diagnosis import truth_fit
from recognition.evaluation.instances import Instance, InstanceSource, InstanceSpec
from recognition.evaluation.models import Database
from recognition.evaluation.records import RIGHT_WITHIN_MM, Record, ReferenceRecord
from recognition.evaluation.synthetic_source import SyntheticSource
from recognition.surfaces.active_touch import verify
from recognition.surfaces.belief import Belief
from recognition.surfaces.data_curves import DataCurves
from recognition.surfaces.database import ModelDatabase
from recognition.surfaces.registration import (
    ClosedFormConfig,
    Recognition,
    RegistrationConfig,
    recognize,
)

__all__ = ["Job", "run_instance", "run_job", "settings_key"]


@dataclass(frozen=True)
class Job:
    """One instance and the methods to recognise it with.

    Attributes
    ----------
    spec : InstanceSpec
    source : InstanceSource
        Makes the instance from ``spec`` (a frozen dataclass).
    configs : tuple of RegistrationConfig
        One per method (the config's class names it), each method at most once.
    touches : int
        Verification touches after the curves, at most (fast mode, sources that can
        touch; :func:`recognition.verify`); 0: none.
    models : str
        The models the instance is recognised against (a database folder's name, which
        hashes its content); part of the records' settings, so that a record made
        against other models is never resumed as this job's. Empty: not recorded.
    """

    spec: InstanceSpec
    source: InstanceSource
    configs: tuple[RegistrationConfig, ...]
    touches: int = 0
    models: str = ""

    def __post_init__(self) -> None:
        if len(set(self.methods)) != len(self.methods):
            raise ValueError(f"a job runs each method once, got {list(self.methods)}")

    @property
    def methods(self) -> tuple[str, ...]:
        """The methods' names, in the order of ``configs``."""
        return tuple(c.mode.value for c in self.configs)

    def settings(self, config: RegistrationConfig) -> str:
        """The settings key of the records made with ``config`` (the touches and the
        models too, when set)."""
        extra: tuple[str | int, ...] = ("touches", self.touches) if self.touches else ()
        if self.models:
            extra += ("models", self.models)
        return settings_key(self.source, config, extra)


def _source_payload(source: Any) -> dict[str, Any]:
    payload = asdict(source)
    if not isinstance(source, SyntheticSource):
        payload["source"] = f"{type(source).__module__}.{type(source).__qualname__}"
    return payload


def settings_key(source: Any, registration: RegistrationConfig, extra: tuple = ()) -> str:
    """Short hash of everything a result depends on (used to resume safely).

    The source's fields (and, for sources other than :class:`SyntheticSource`, its
    class), the registration settings and ``extra``.
    """
    payload = json.dumps(
        [_source_payload(source), asdict(registration), list(extra)], sort_keys=True, default=str
    )
    return hashlib.sha256(payload.encode()).hexdigest()[:12]


# --- recognition of one instance --------------------------------------------------------


def _mm(value: float) -> float | None:
    return float(value) * 1e3 if np.isfinite(value) else None


def _located_error_mm(
    location: ArrayLike | None, point_in_model: NDArray[np.float64] | None
) -> float | None:
    if point_in_model is None or location is None or not np.all(np.isfinite(location)):
        return None
    return float(np.linalg.norm(np.asarray(location) - point_in_model) * 1e3)


@dataclass(frozen=True)
class _Recognised:
    """The recognition fields of a record, and the true model's estimate of p."""

    recognized: str | None
    success: bool
    time_s: float
    errors_mm: dict[str, float | None]
    times_s: dict[str, float]
    candidates: dict[str, int] | None = None
    k1: float | None = None
    k2: float | None = None
    error: str | None = None
    location: NDArray[np.float64] | None = None
    result: Recognition | None = None


def _answer_error_mm(
    belief: Belief | None, true_model: str, point_in_model: NDArray[np.float64] | None
) -> float | None:
    """How far the belief's best hypothesis puts p from the truth, mm, up to the model's
    symmetries (None: it names another model, or no truth)."""
    best = None if belief is None else belief.best
    if best is None or best.model != true_model or point_in_model is None:
        return None
    return best.location_error_m(point_in_model) * 1e3


def _touched(
    database: Database,
    result: Recognition | None,
    instance: Instance,
    true_model: str,
    touches: int,
    seed: int,
) -> dict[str, Any] | None:
    """The verification touches' record (None when none can be made)."""
    if (
        touches <= 0
        or result is None
        or result.belief is None
        or instance.touch is None
        or instance.touch_limits is None
        or not isinstance(database, ModelDatabase)
    ):
        return None
    done = verify(
        database,
        result.belief,
        instance.touch,
        instance.touch_limits,
        max_touches=touches,
        seed=seed,
    )
    best = done.belief.best
    return {
        "made": len(done.steps),
        "no_readings": sum(step.no_reading is not None for step in done.steps),
        "stop": done.stop,
        "recognized": None if best is None else best.model,
        "success": best is not None and best.model == true_model,
        "confidence": done.belief.confidence,
        "answer_error_mm": _answer_error_mm(done.belief, true_model, instance.point_in_model),
        "confidences": [step.confidence for step in done.steps],
        "recognition_times_s": [step.recognition_time_s for step in done.steps],
        "truth_fit": _truth_fit(database, done.belief, instance, true_model),
    }


def _truth_fit(
    database: Database, belief: Belief | None, instance: Instance, true_model: str
) -> dict[str, Any] | None:
    """How the true pose fits the belief's contact against a wrong answer
    (:func:`~recognition.evaluation.diagnosis.truth_fit`); None for a right answer, or
    without a belief or the true pose."""
    if (
        belief is None
        or instance.T_model_from_data is None
        or instance.point_in_model is None
        or not isinstance(database, ModelDatabase)
    ):
        return None
    error = _answer_error_mm(belief, true_model, instance.point_in_model)
    if error is not None and error <= RIGHT_WITHIN_MM:
        return None
    return truth_fit(
        database.models, belief, true_model, instance.T_model_from_data, instance.point_in_model
    )


def _recognize(
    database: Database, curves: DataCurves, true_model: str, config: RegistrationConfig
) -> _Recognised:
    """Recognition of ``curves`` with one method.

    Curves whose local geometry cannot be computed (e.g. two sampling planes that
    coincide) are not recognised: the result says why (``error``) and counts as a failure.
    """
    start = time.perf_counter()
    try:
        result, location = _recognition(database, curves, true_model, config)
    except (InvalidCurveData, DegenerateGeometry) as exc:
        return _Recognised(
            recognized=None,
            success=False,
            time_s=time.perf_counter() - start,
            errors_mm={},
            times_s={},
            error=f"{type(exc).__name__}: {exc}",
        )
    return _Recognised(
        recognized=result.name,
        success=result.name == true_model,
        time_s=result.time_s,
        errors_mm={n: _mm(e) for n, e in result.ranking},
        times_s=result.timings_s,
        candidates={n: len(r.candidates) for n, r in result.registrations.items()},
        k1=float(result.geometry.k1),
        k2=float(result.geometry.k2),
        location=location,
        result=result,
    )


def _recognition(
    database: Database, curves: DataCurves, true_model: str, config: RegistrationConfig
) -> tuple[Recognition, NDArray[np.float64] | None]:
    """The recognition (thesis Eq. (4.9)) and the true model's estimate of p (model frame,
    or None)."""
    if isinstance(database, ModelDatabase):
        if isinstance(config, ClosedFormConfig):
            raise InvalidModel("a mesh database is registered with a mesh mode, not closed-form")
        result = database.recognize(curves, config)
        truth = result.registrations.get(true_model)
        return result, (None if truth is None else truth.location)
    # The solids are symmetric (thesis Section 4.4.2): no location is compared.
    return recognize(database, curves, config), None


def run_job(database: Database, job: Job) -> list[Record]:
    """Make the job's instance once and recognise it with each of its methods.

    Returns
    -------
    list of Record
        One per method, in the order of ``job.configs`` (``settings`` not yet set).
    """
    spec = job.spec
    start = time.perf_counter()
    instance = job.source.instance(database, spec)
    made_s = time.perf_counter() - start
    base: dict[str, Any] = {
        "instance": spec.key,
        "model": spec.model,
        "index": spec.index,
        "vertex": spec.vertex,
        "seed": spec.seed,
        "info": dict(instance.info),
        "instance_time_s": made_s,
    }
    records = []
    for config in job.configs:
        method = config.mode.value
        if instance.curves is None:
            records.append(
                Record(**base, method=method, recognized=None, success=False, time_s=0.0)
            )
            continue
        found = _recognize(database, instance.curves, spec.model, config)
        belief = None if found.result is None else found.result.belief
        reference = None
        if instance.reference_curves is not None:
            ref = _recognize(database, instance.reference_curves, spec.model, config)
            reference = ReferenceRecord(
                recognized=ref.recognized,
                success=ref.success,
                errors_mm=ref.errors_mm,
                localization_error_mm=_located_error_mm(ref.location, instance.point_in_model),
                error=ref.error,
            )
        records.append(
            Record(
                **base,
                method=method,
                recognized=found.recognized,
                success=found.success,
                time_s=found.time_s,
                errors_mm=found.errors_mm,
                times_s=found.times_s,
                candidates=found.candidates,
                k1=found.k1,
                k2=found.k2,
                error=found.error,
                localization_error_mm=_located_error_mm(found.location, instance.point_in_model),
                reference=reference,
                confidence=None if belief is None else belief.confidence,
                answer_error_mm=_answer_error_mm(belief, spec.model, instance.point_in_model),
                touches=_touched(
                    database, found.result, instance, spec.model, job.touches, spec.seed
                ),
                truth_fit=_truth_fit(database, belief, instance, spec.model),
            )
        )
    return records


def run_instance(
    database: Database,
    spec: InstanceSpec,
    source: InstanceSource,
    config: RegistrationConfig,
) -> Record:
    """Recognise one instance with one method."""
    return run_job(database, Job(spec, source, (config,)))[0]
