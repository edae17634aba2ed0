"""Recording a probing session: a .rrd file saved, or streamed to a native viewer it starts."""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING

from tactile_sim.errors import RecordingError
from tactile_sim.recording.blueprint import probe_blueprint
from tactile_sim.recording.log import log_probe_run
from tactile_sim.recording.viewer import check_display, rerun_executable

if TYPE_CHECKING:
    from recognition import ModelDatabase, Recognition
    from tactile_sim.probing import ProbeSession
    from tactile_sim.probing.touches import TouchSession

__all__ = [
    "APPLICATION_ID",
    "MODES",
    "record_probe_run",
]


MODES = ("save", "spawn", "serve")
"""What :func:`record_probe_run` does with a recording."""

APPLICATION_ID = "tactile_sim"
"""Groups the recordings in the viewer."""


def record_probe_run(
    session: ProbeSession,
    result: Recognition | None = None,
    database: ModelDatabase | None = None,
    *,
    touches: TouchSession | None = None,
    mode: str = "save",
    path: str | Path | None = None,
    application_id: str = APPLICATION_ID,
) -> str | None:
    """Records a probing session and its recognition; returns what to tell the user.

    Parameters
    ----------
    session : tactile_sim.probing.ProbeSession
    result : recognition.Recognition or None
    database : recognition.ModelDatabase or None
    touches : TouchSession or None
        The verification touches after the sweeps.
    mode : {"save", "spawn", "serve"}
        "save" writes ``path``; "spawn" also streams to a native viewer it starts;
        "serve" writes ``path`` for :func:`serve_recording` to serve to a browser.
    path : str, Path or None
        The .rrd file (required for "save" and "serve"; optional for "spawn").
    application_id : str
        Groups recordings in the viewer.

    Returns
    -------
    str or None
        The .rrd path written, or a line about the spawned viewer.

    Raises
    ------
    RecordingError
        The file cannot be written, or ("spawn") there is no display for the viewer.
    """
    import rerun as rr

    if mode not in MODES:
        raise ValueError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
    if path is None and mode != "spawn":
        raise ValueError(f"mode {mode!r} needs a path for the .rrd file")
    recording_id = f"{session.object_name}-seed{session.seed}-{time.time_ns():x}"
    rec = rr.RecordingStream(application_id, recording_id=recording_id)
    blueprint = probe_blueprint(session.curves.intersection)
    if path is not None:
        path = Path(path)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise RecordingError(f"cannot create {path.parent}: {error}") from error
    try:
        if mode == "spawn":
            check_display()
            rr.spawn(connect=False, executable_path=rerun_executable(), recording=rec)
            sinks = [rr.GrpcSink()] + ([rr.FileSink(str(path))] if path else [])
            rec.set_sinks(*sinks, default_blueprint=blueprint)
        else:
            rec.save(path, default_blueprint=blueprint)
        log_probe_run(rec, session, result, database, touches)
    finally:
        rec.disconnect()
    if path is not None and not path.is_file():
        raise RecordingError(f"rerun did not write {path}")
    if mode == "spawn":
        return "streamed to the native viewer" + (f"; saved {path}" if path else "")
    return str(path)
