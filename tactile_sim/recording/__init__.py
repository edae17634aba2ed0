"""Probing sessions and their recognition as rerun recordings: saved, spawned or served.

:func:`record_probe_run` (:mod:`~tactile_sim.recording.record`) logs a session
(:mod:`~tactile_sim.recording.log`) with its first view
(:mod:`~tactile_sim.recording.blueprint`) to an .rrd file or a native viewer;
:func:`read_recording` (:mod:`~tactile_sim.recording.read`) reads a file back;
:func:`serve_recording` and :func:`open_native_viewer` (:mod:`~tactile_sim.recording.viewer`)
show one; :func:`recording_overhead` (:mod:`~tactile_sim.recording.overhead`) measures what
recording costs. Importing the package loads neither rerun nor MuJoCo.
"""

from tactile_sim.recording.blueprint import probe_blueprint
from tactile_sim.recording.log import CURVE_NAMES, log_probe_run
from tactile_sim.recording.overhead import recording_overhead
from tactile_sim.recording.read import RecordingSummary, read_recording
from tactile_sim.recording.record import APPLICATION_ID, MODES, record_probe_run
from tactile_sim.recording.viewer import (
    WebViewer,
    check_display,
    check_ports,
    open_native_viewer,
    serve_recording,
)

__all__ = [
    "APPLICATION_ID",
    "CURVE_NAMES",
    "MODES",
    "RecordingSummary",
    "WebViewer",
    "check_display",
    "check_ports",
    "log_probe_run",
    "open_native_viewer",
    "probe_blueprint",
    "read_recording",
    "record_probe_run",
    "recording_overhead",
    "serve_recording",
]
