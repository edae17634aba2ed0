"""Recognition benchmarks (thesis 4.3.4, 4.4; Tables 4.5-4.7): sources, runner, records, reports.

An instance is named by an :class:`InstanceSpec` and made by a source
(:class:`InstanceSource`: :class:`SyntheticSource` samples curves on the models
themselves; ``tactile_sim.evaluation.SimulatedSource`` has the simulated robot probe the
objects). A :class:`Job` is one instance and one registration config per method;
:func:`run` runs jobs here, in a local process pool or on Ray
(:mod:`recognition.evaluation.ray_backend`), appends one :class:`Record` per instance and
method to a JSONL file as they finish, and resumes where a killed run stopped.
:func:`summarize` gives the figures per method; :mod:`.reports` and :mod:`.figures`
write the Markdown tables and PNG figures.

Importing this package imports neither ray nor matplotlib; they are imported when used.
"""

from recognition.evaluation.instances import Instance, InstanceSource, InstanceSpec
from recognition.evaluation.jobs import Job, run_instance, run_job, settings_key
from recognition.evaluation.models import (
    CLOSED_FORM_METHOD,
    ClosedFormModels,
    Database,
    DatabaseHandle,
    load_database,
)
from recognition.evaluation.records import (
    TIMING_FIELDS,
    Record,
    ReferenceRecord,
    comparable,
    read_results,
)
from recognition.evaluation.runner import BACKENDS, run
from recognition.evaluation.summary import MethodSummary, summarize, summary_json
from recognition.evaluation.synthetic_source import SyntheticSource, instance_specs, make_curves

__all__ = [
    "BACKENDS",
    "CLOSED_FORM_METHOD",
    "TIMING_FIELDS",
    "ClosedFormModels",
    "Database",
    "DatabaseHandle",
    "Instance",
    "InstanceSource",
    "InstanceSpec",
    "Job",
    "MethodSummary",
    "Record",
    "ReferenceRecord",
    "SyntheticSource",
    "comparable",
    "instance_specs",
    "load_database",
    "make_curves",
    "read_results",
    "run",
    "run_instance",
    "run_job",
    "settings_key",
    "summarize",
    "summary_json",
]
